"""Probe (not a benchmark yet): the follower in lock step with BurstController under constant lateness and bursts, its
replies judged at the message time for replies in time and when applied for queued ones (combined); prints per case the
largest ratios and the count of replies over the limits. Run from a checkout: PYTHONPATH=. python benchmarks/probe_late_queue.py"""
import functools, sys, numpy as np
from lbrcli.bridge.testing import LockStepSource, follow_in_lock_step
from lbrcli.fri.testing.holding import BurstController, reference_histories, step_ratios, CA
from trajectories.limits import default_limits
sys.path.insert(0, '/work/main')
from tests.lbrcli.fri.test_motion_late import _bursts
lim = default_limits()

def combined(ctl, limits, dt=1e-3):
    e = [np.asarray(x) for x in ctl.executed]
    rows = sorted((k, s) for s, k in ctl.applied.items())
    at, ours, follows = [], [], []
    for j, (k, s) in enumerate(rows):
        queued = j > 0 and rows[j - 1] == (k - 1, s - 1) and k != ctl.histories[s][0]
        at.append(k if queued else ctl.histories[s][0])
        ours.append(queued or ctl.histories[s][1])
        follows.append(j > 0 and rows[j - 1][1] == s - 1 and (not queued or at[j - 1] == k - 1))
    last3 = [(e[k - 1], e[k - 2], e[k - 3]) if k >= 3 else None for k in at]
    hist = reference_histories(last3, ours, follows, dt, limits)
    by_seq = {s: h for (_, s), h in zip(rows, hist)}
    replies = [r for r in ctl.replies if r.state == CA and r.position is not None and r.seq in by_seq]
    r = step_ratios(np.array([x.position for x in replies]), [by_seq[x.seq] for x in replies], limits, dt)
    bad = int((np.nan_to_num(r).max(1) > 1 + 1e-6).sum())
    return tuple(round(float(np.nanmax(r[:, k])), 2) for k in range(3)), bad

cases = {}
for hold in (True, False):
    for seed in (0, 1):
        cases[f"bursts{seed} hold={hold}"] = dict(late=_bursts(seed), hold=hold)
    for L in (1, 2, 5):
        cases[f"const L={L} hold={hold}"] = dict(late={11 + i: L for i in range(600, 2000)}, hold=hold)
for name, kw in cases.items():
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=functools.partial(BurstController, **kw))
    m = run.follower.executed
    print(f"{name:22} t {run.t[-1]:.2f} brake {m.braking!s:5} combined (v,a,j), replies over: {combined(run.controller, lim)}", flush=True)
