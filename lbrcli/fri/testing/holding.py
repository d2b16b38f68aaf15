"""A second judge of the motion-safety core: a scripted controller that differs from our simulator, and the limits
of every command we send measured against what it executed.

:class:`BurstController` runs a script as :class:`~lbrcli.fri.testing.ScriptedController` does, but
- a period without a command *holds* the last set-point (``hold=True``; our simulator and the scripted controller
  extrapolate the velocity instead) — the robot's velocity steps to 0, the controller's own step;
- replies come late in bursts (``late``: script index → lateness in periods): the reply to a message of lateness L
  is applied L periods after its own, as it is (no carrying forward); when several are in, the newest wins and the
  older ones are dropped; a message reflects the newest reply applied;
- its measured positions carry noise (``noise`` [rad], seeded); FRI 1.15 also reports the exact commanded one.

:func:`reply_ratios` judges every reply applied (decoded from its datagram) against the history executed when the
message it answers was sent — or, where the controller applies our replies one after the other, late (they queue),
when it was applied: the last three positions, continued by our previous command where the controller applied it
in time; after a step of the controller's own (a hold, a bridge, a late reply) whose state leaves the acceleration
or velocity limit, the state it holds — that position, at rest after a hold, else at the velocity before the
step; acceleration 0.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from .scripted import CA, CW, IDLE, Cycle, ScriptedController


@dataclass
class BurstController(ScriptedController):
    """A lock-step controller that holds (or extrapolates) missing commands and applies late bursts of replies."""

    hold: bool = True  # a period without a command holds the set-point (False: extrapolates the last velocity)
    late: dict[int, int] = field(default_factory=dict)  # script index → periods its reply comes late
    carry: bool = False  # a late reply is carried forward by its lateness at the commands' velocity (our simulator)
    noise: float = 0.0  # [rad] standard deviation of the measured positions' noise
    seed: int = 0

    def __post_init__(self) -> None:
        super().__post_init__()
        self._rng = np.random.default_rng(self.seed)
        self.histories: dict[int, tuple[int, bool]] = {}  # message seq → (index into executed before it, ours)
        self._pending: list[tuple[int, int, tuple[float, ...] | None, int]] = []  # (due step, msg seq, q, client seq)
        self._applied_seq = -1  # the newest message whose reply was applied
        self._reflected = 0  # the client's sequence counter of the newest reply applied
        self._msg_step: dict[int, int] = {}  # message seq → the step its reply was meant for
        self._last_cmd: tuple[float, ...] | None = None  # the last reply applied, as sent
        self.applied: dict[int, int] = {}  # message seq → the index into executed its reply was applied at
        self.applied_q: dict[int, tuple[float, ...]] = {}  # message seq → the position its reply was applied as [rad]
        self.on_time: list[bool] = []  # per executed step: it applied the reply to the message just before, in time

    def _robot_step(self, c: Cycle, pos: tuple[float, ...] | None) -> None:
        if self.hold and c.state == CA and pos is None:
            self._vel = [0.0] * 7  # hold the set-point: no extrapolation
        super()._robot_step(c, pos)

    def _message(self, c: Cycle, seq: int, reflected: int) -> bytes:
        if self.noise and c.state >= CW:  # the measured position noisy (FRI 1.15's commanded one stays exact)
            noise, inner = self._rng.normal(0.0, self.noise, 7), c.mutate

            def noisy(m) -> None:
                v = m.monitorData.measuredJointPosition.value
                v[:] = [x + float(e) for x, e in zip(v, noise)]
                if inner is not None:
                    inner(m)

            c = replace(c, mutate=noisy)
        return super()._message(c, seq, reflected)

    def _run(self) -> None:
        seq = -1
        dest = ("127.0.0.1", self.client_port)
        for i, c in enumerate(self.script):
            self._i = i
            if self.on_cycle is not None:
                self.on_cycle(i)
            seq += 1 + c.seq_jump
            self.clock_ns += int(round((1 + c.seq_jump) * c.send_period * 1e6))
            if c.state == CA:
                for _ in range(c.seq_jump):  # the messages lost on the way: periods without a command
                    self._step(c, seq)
            self.histories[seq] = (len(self.executed), bool(self.on_time and self.on_time[-1]))
            self.sock.sendto(self._message(c, seq, self._reflected), dest)
            self.sent_seqs.append(seq)
            if c.state == IDLE:
                time.sleep(self.pace_s)
                continue
            cmd = self._await_reply(time.monotonic() + self.reply_timeout, seq)
            if cmd is None:
                self.unanswered.append(i)
                if not self.client_done.is_set():
                    continue
                return
            pos = self._record(i, c, seq, cmd)
            if c.state != CA:
                self._reflected = cmd.header.sequenceCounter
                self._robot_step(c, pos)
                self.on_time.append(False)
                continue
            if not c.drop_reply:
                self._pending.append((len(self.executed) + self.late.get(i, 0), seq, pos, cmd.header.sequenceCounter))
                self._msg_step[seq] = len(self.executed)
            self._step(c, seq)
            time.sleep(self.pace_s)

    def _step(self, c: Cycle, seq: int) -> None:
        """One COMMANDING_ACTIVE step: the newest reply due by now (older ones dropped), else a hold or bridge."""
        now = len(self.executed)
        due = [p for p in self._pending if p[0] <= now]
        self._pending = [p for p in self._pending if p[0] > now]
        best = max(due, key=lambda p: p[1]) if due else None
        if best is not None and best[1] > self._applied_seq:
            q = best[2]
            late = now - self._msg_step.get(best[1], now)
            if self.carry and q is not None and late > 0 and self._last_cmd is not None:  # as our simulator does
                gap = max(1, best[1] - self._applied_seq)
                q = tuple(a + late * (a - b) / gap for a, b in zip(q, self._last_cmd))
            self._last_cmd = best[2] if best[2] is not None else self._last_cmd
            self._applied_seq, self._reflected = best[1], best[3]
            self.applied[best[1]] = now
            if q is not None:
                self.applied_q[best[1]] = q
            self._robot_step(c, q)
            self.on_time.append(best[1] == seq and best[0] == now)
            return
        self._robot_step(c, None)
        self.on_time.append(False)


def _envelope(limits, dt: float):
    from trajectories.envelope import BrakingEnvelope

    return BrakingEnvelope.from_limits(limits, dt)


def reference_histories(last3: list, ours, follows, dt: float, limits) -> list[tuple | None]:
    """Per message i, the executed history [rad] (newest first) its reply is judged against. ``last3[i]``: the last
    three positions executed before the message was sent (newest first; None: unknown); ``ours[i]``: the step into
    the newest applied our reply to message i − 1 in time; ``follows[i]``: message i − 1 was judged (no gap). A step
    of the controller's own "left the limits" when a braking stop cannot start from the state it leaves (the braking
    envelope of ``limits``, as the safety core tests it)."""
    env = _envelope(limits, dt)
    out: list[tuple | None] = []
    prev: tuple | None = None
    for i, l3 in enumerate(last3):
        if not follows[i]:
            prev = None
        if l3 is None:
            out.append(None)
            prev = None
            continue
        x = l3[0]
        if ours[i] and prev is not None:  # the controller applied our previous command in time: the history goes on
            h = (x, prev[0], prev[1])
        else:
            h = (x, l3[1], prev[1] if prev is not None else l3[2])
            if env.state_ok(*h) >= 0:  # the controller's own step left the limits: it holds
                # a hold (no step) stops the robot; after a jump it goes on at the velocity before
                s = np.where(np.abs(x - h[1]) <= 1e-9, 0.0, h[1] - h[2])
                h = (x, x - s, x - 2.0 * s)
        out.append(h)
        prev = h
    return out


def step_ratios(commands: np.ndarray, hist: list[tuple | None], limits, dt: float = 1e-3) -> np.ndarray:
    """(n, 3): per command [rad] (row i answers message i), its velocity, acceleration and jerk as the next step after
    ``hist[i]`` over the limits (largest joint); NaN where no history is known."""
    out = np.full((len(commands), 3), np.nan)
    for i, h in enumerate(hist):
        if h is None or not np.all(np.isfinite(commands[i])):
            continue
        x, x1, x2 = h
        q = commands[i]
        d = (q - x, q - 2.0 * x + x1, q - 3.0 * x + 3.0 * x1 - x2)
        for k, lim in enumerate((limits.velocity, limits.acceleration, limits.jerk)):
            out[i, k] = float(np.max(np.abs(d[k]) / (lim * dt ** (k + 1))))
    return out


def _at_messages(ctl: BurstController, limits, dt: float) -> dict[int, tuple | None]:
    """Message seq → the history executed when it was sent (:func:`reference_histories`)."""
    e = [np.asarray(x) for x in ctl.executed]
    rows = [(s, *ctl.histories[s]) for s in sorted(ctl.histories)]
    last3 = [(e[k - 1], e[k - 2], e[k - 3]) if k >= 3 else None for _, k, _ in rows]
    follows = [j > 0 and rows[j - 1][0] == s - 1 for j, (s, _, _) in enumerate(rows)]
    hist = reference_histories(last3, [o for _, _, o in rows], follows, dt, limits)
    return {s: h for (s, _, _), h in zip(rows, hist)}


def _at_application(ctl: BurstController, limits, dt: float) -> dict[int, tuple | None]:
    """Message seq → for each reply applied, the history it is judged against (see :func:`reply_ratios`)."""
    e = [np.asarray(x) for x in ctl.executed]
    rows = sorted((k, s) for s, k in ctl.applied.items())  # (step applied at, message seq)
    at: list[int] = []
    ours, follows = [], []
    for j, (k, s) in enumerate(rows):
        queued = j > 0 and rows[j - 1] == (k - 1, s - 1) and k != ctl.histories[s][0]
        at.append(k if queued else ctl.histories[s][0])
        ours.append(queued or ctl.histories[s][1])
        follows.append(j > 0 and rows[j - 1][1] == s - 1 and (not queued or at[j - 1] == k - 1))
    last3 = [(e[k - 1], e[k - 2], e[k - 3]) if k >= 3 else None for k in at]
    return {s: h for (_, s), h in zip(rows, reference_histories(last3, ours, follows, dt, limits))}


def reply_ratios(ctl: BurstController, limits, dt: float = 1e-3) -> tuple[list[int], np.ndarray]:
    """(message seqs, (n, 3) ratios): each of our replies in COMMANDING_ACTIVE, its velocity, acceleration and jerk
    over their limits as the next step after the history it is judged against (:func:`step_ratios`; the controller's
    own positions, not the noisy ones it reported). A reply applied right after our reply to the message before, late
    (the controller's replies queue), is judged against what was executed before it was applied; any other against
    what was executed when its message was sent — the client cannot know that a controller will hold, bridge or drop
    the replies in flight (a judge at application only would blame the reply for the controller's own step; one at
    the message's time only passed a core whose queued commands moved the robot at 100× the acceleration limit). A
    reply applied is judged as the position it was applied as (``carry``: carried forward, not as sent)."""
    by_seq = _at_messages(ctl, limits, dt) | _at_application(ctl, limits, dt)
    replies = [r for r in ctl.replies if r.state == CA and r.position is not None and r.seq in by_seq]
    pos = np.array([ctl.applied_q.get(x.seq, x.position) for x in replies]).reshape(-1, 7)
    return [r.seq for r in replies], step_ratios(pos, [by_seq[x.seq] for x in replies], limits, dt)


def command_ratios(ctl: BurstController, limits, dt: float = 1e-3) -> tuple[float, float, float]:
    """The largest velocity, acceleration and jerk of our applied replies over their limits (:func:`reply_ratios`)."""
    r = reply_ratios(ctl, limits, dt)[1]
    return tuple(float(np.nanmax(r[:, k])) if np.isfinite(r[:, k]).any() else 0.0 for k in range(3))  # type: ignore[return-value]


AROUND_CHANGE = (-1, 4)  # the replies to messages around a change of lateness (script indices from the change)


def late_bursts(seed: int, start: int = 600, end: int = 2800, offset: int = 11) -> dict[int, int]:
    """Script index (``offset`` past the preamble) → lateness [periods]: bursts of 5–60 replies each 2–20 periods
    late, 100–400 replies apart (seeded)."""
    rng = np.random.default_rng(seed)
    late, k = {}, start
    while k < end:
        lateness, n = int(rng.integers(2, 21)), int(rng.integers(5, 60))
        late.update({offset + i: lateness for i in range(k, k + n)})
        k += n + int(rng.integers(100, 400))
    return late


def over_limits(ctl: BurstController, limits, late: dict[int, int], dt: float = 1e-3) -> tuple[list, list]:
    """(over, stray): the replies the controller applied that break a limit as the robot executed them
    (:func:`reply_ratios`), as (message seq, ratios); ``stray``: those not answering a message ``AROUND_CHANGE`` a
    change of lateness (the end widened by the lateness around it: the replies in flight then) — where no client can tell whether the controller held or will apply its replies late
    (entry), or will drop the ones in flight (exit). Replies the controller dropped never moved the robot."""
    index = {s: i for i, s in enumerate(ctl.sent_seqs)}
    seqs, r = reply_ratios(ctl, limits, dt)
    over = [(s, row) for s, row in zip(seqs, np.nan_to_num(r)) if row.max() > 1 + 1e-6 and s in ctl.applied]
    changes = [i for i in range(1, len(ctl.script)) if late.get(i, 0) != late.get(i - 1, 0)]
    lo, hi = AROUND_CHANGE
    span = [(c, hi + max(late.get(c, 0), late.get(c - 1, 0))) for c in changes]  # (and the replies then in flight)
    return over, [(s, row) for s, row in over if not any(lo <= index[s] - c < h for c, h in span)]


def executed_ratios(ctl, lim, late: dict[int, int], margin: int = 6, dt: float = 1e-3) -> np.ndarray:
    """(3,) the largest velocity, acceleration and jerk over their limits of the robot's executed motion, leaving out
    the steps from each change of lateness to ``margin`` after the lateness around it (the controller's own steps
    there: a hold or bridge, then the queue it applies or drops)."""
    e = np.array(ctl.executed)
    changes = [i for i in range(1, len(ctl.script)) if late.get(i, 0) != late.get(i - 1, 0)]
    skip = np.zeros(len(e), bool)
    for c in (c for c in changes if c < len(ctl.sent_seqs)):  # (a session that ended early: the changes sent)
        k = ctl.histories[ctl.sent_seqs[c]][0]
        skip[max(0, k - 3) : k + max(late.get(c, 0), late.get(c - 1, 0)) + margin] = True
    out = []
    for order, limit in ((1, lim.velocity), (2, lim.acceleration), (3, lim.jerk)):
        r = (np.abs(np.diff(e, order, axis=0)) / (limit * dt**order)).max(1)
        kept = r[~skip[order:]]
        out.append(kept.max() if kept.size else 0.0)
    return np.array(out)
