"""Replies that stay late and queue: the bridge's follower in lock step with
:class:`~lbrcli.fri.testing.holding.BurstController` (a controller we did not write for this: it holds or
extrapolates a period without a command, applies late replies in order, newest wins), every reply judged as the
robot executed it (:func:`~lbrcli.fri.testing.holding.over_limits`): per case the replies over a limit, those not
around a change of lateness (where no client can foresee the controller: 0 is the goal), the largest acceleration and
jerk over their limits.

Run: `python benchmarks/run_all.py late_queue` (writes benchmarks/results/late_queue.json)."""

from __future__ import annotations

import functools

import numpy as np

from lbrcli.bridge.testing import LockStepSource, follow_in_lock_step
from lbrcli.fri.testing.holding import BurstController, executed_ratios, late_bursts, over_limits
from trajectories.limits import default_limits


def _cases(quick: bool) -> dict[str, dict]:
    out = {}
    for hold in (True, False):
        ctl = "holds" if hold else "extrapolates"
        for lateness in (1, 2, 5) if not quick else (2,):
            late = {11 + i: lateness for i in range(600, 2000)}
            out[f"{lateness} periods late for 1.4 s, controller {ctl}"] = dict(late=late, hold=hold)
        for seed in (0, 1) if not quick else (0,):
            out[f"bursts of 2-20 periods late (seed {seed}), controller {ctl}"] = dict(
                late=late_bursts(seed), hold=hold
            )
    late = {11 + i: 3 for i in range(600, 2000)}
    out["3 periods late for 1.4 s, FRI 2.7, noise 10 µrad"] = dict(late=late, hold=False, noise=1e-5, version="2.7")
    for lateness in (1, 3):  # a controller that carries a late reply forward at our commands' velocity (lbr sim)
        late = {11 + i: lateness for i in range(600, 2000)}
        out[f"{lateness} periods late for 1.4 s, controller carries late replies forward"] = dict(late=late, carry=True)
    return out


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    lim, rows = default_limits(), []
    for name, kw in _cases(quick).items():
        version = kw.pop("version", "1.15")
        ctl = functools.partial(BurstController, **kw)
        r = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl, version=version)
        over, stray = over_limits(r.controller, lim, kw["late"])
        worst = np.max([row for _, row in over], axis=0) if over else np.zeros(3)
        ex = executed_ratios(r.controller, lim, kw["late"])
        rows += [(f"{name}: executed away from a change: largest {w} / limit", round(float(x), 2), "×")
                 for w, x in zip(("velocity", "acceleration", "jerk"), ex)]  # fmt: skip
        rows += [(f"{name}: session length", round(float(r.t[-1]), 3), "s"),
                 (f"{name}: replies over a limit", len(over), ""),
                 (f"{name}: of them away from a change of lateness", len(stray), ""),
                 (f"{name}: largest acceleration / limit", round(float(worst[1]), 2), "×"),
                 (f"{name}: braking stop", float(r.follower.executed.braking), "")]  # fmt: skip
    return rows


if __name__ == "__main__":
    for row in run():
        print(*row)
