"""Limit checking of joint trajectories: position, velocity, acceleration, jerk and T1 Cartesian speed."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .differences import derivatives
from .limits import JointLimits
from .trajectory import JointTrajectory

QUANTITIES = ("position", "velocity", "acceleration", "jerk")
STEP_QUANTITIES = ("step velocity", "step acceleration", "step jerk")  # forward differences, robot at rest around
JERKS = ("jerk", "step jerk")  # fail only when jerk is enforced
UNITS = {
    "position": "rad",
    "velocity": "rad/s",
    "acceleration": "rad/s^2",
    "jerk": "rad/s^3",
    "cartesian speed": "m/s",
    "step velocity": "rad/s",
    "step acceleration": "rad/s^2",
    "step jerk": "rad/s^3",
    "rest": "rad/s",
}
REL_TOL = 1e-9  # a value exactly at its limit passes (the file's decimals round either way)


@dataclass(frozen=True)
class Violation:
    """One limit exceeded: the first sample over the limit and the peak of that quantity."""

    joint: int  # 1..7, 0 for the Cartesian flange speed
    quantity: str
    t: float  # first time over the limit [s]
    value: float  # value at that time (SI units of the quantity)
    limit: float
    peak: float  # largest |value| over the whole trajectory
    t_peak: float  # [s]
    samples: int  # number of samples over the limit
    note: str = ""  # for "rest": "start" or "end"

    def describe(self) -> str:
        unit = UNITS[self.quantity]
        who = f"A{self.joint}" if self.joint else "flange"
        if self.quantity == "rest":
            return (
                f"{who} is not at rest at the {self.note}: it moves at {self.value:+.4g} {unit} there (a "
                f"file must start and end at rest: |step velocity| ≤ acceleration limit × step = {self.limit:.4g} "
                f"{unit}); the controller would have to jump to that speed or stop dead — plans from `lbr plan` "
                f"and `lbr retime` start and end at rest, or add rows that accelerate from and brake to rest"
            )
        return (
            f"{who} {self.quantity} {self.value:+.4g} {unit} at t = {self.t:.3f} s exceeds the limit "
            f"{self.limit:.4g} {unit} (peak {self.peak:.4g} {unit} at t = {self.t_peak:.3f} s, {self.samples} samples)"
        )


@dataclass(frozen=True)
class CheckReport:
    """Per-joint peaks and limits per quantity, violations, and whether the check passed."""

    peaks: dict[str, np.ndarray]  # quantity -> (7,) peak |value|
    limits: dict[str, np.ndarray]  # quantity -> (7,) applied limit
    violations: tuple[Violation, ...]
    jerk_enforced: bool
    margin: float
    cartesian_speed_peak: float | None = None  # [m/s], with --t1
    cartesian_speed_limit: float | None = None
    series: dict[str, np.ndarray] = field(default_factory=dict, repr=False)  # t, position, velocity, acceleration, jerk

    @property
    def failing(self) -> tuple[Violation, ...]:
        """Violations that fail the check (jerk only when enforced)."""
        return tuple(v for v in self.violations if v.quantity not in JERKS or self.jerk_enforced)

    @property
    def ok(self) -> bool:
        return not self.failing

    def ratios(self) -> dict[str, np.ndarray]:
        """Peak / limit per quantity and joint."""
        return {k: self.peaks[k] / self.limits[k] for k in self.peaks}

    def plan_figures(self, traj: JointTrajectory) -> dict:
        """The figures a planner reports about its joint path and this check of it."""
        return {
            "limits_ok": self.ok,
            "max_ratio": {k: float(v.max()) for k, v in self.ratios().items()},
            "violations": [v.describe() for v in self.failing],
            "duration_s": float(traj.duration),
            "samples": len(traj),
            "dt_s": float(traj.dt),
        }

    def to_dict(self) -> dict:
        d = {
            "limits_ok": self.ok,
            "margin": self.margin,
            "jerk_enforced": self.jerk_enforced,
            "peak_ratio": {k: [round(float(x), 6) for x in v] for k, v in self.ratios().items()},
            "max_ratio": {k: float(v.max()) for k, v in self.ratios().items()},
            "violations": [
                {
                    "joint": v.joint,
                    "quantity": v.quantity,
                    "t_s": v.t,
                    "value": v.value,
                    "limit": v.limit,
                    "peak": v.peak,
                    "t_peak_s": v.t_peak,
                    "samples": v.samples,
                    "fails": v.quantity not in JERKS or self.jerk_enforced,
                }
                for v in self.violations
            ],
        }
        if self.cartesian_speed_peak is not None:
            d["cartesian_speed_peak_m_s"] = self.cartesian_speed_peak
            d["cartesian_speed_limit_m_s"] = self.cartesian_speed_limit
        return d


def _violations(quantity: str, t: np.ndarray, x: np.ndarray, limit: np.ndarray, joint_base: int = 1) -> list[Violation]:
    out = []
    over = np.abs(x) > limit[None, :] * (1.0 + REL_TOL)
    for j in np.flatnonzero(over.any(axis=0)):
        idx = np.flatnonzero(over[:, j])
        k = int(idx[0])
        kp = int(np.argmax(np.abs(x[:, j])))
        out.append(
            Violation(
                joint=int(j) + joint_base,
                quantity=quantity,
                t=float(t[k]),
                value=float(x[k, j]),
                limit=float(limit[j]),
                peak=float(abs(x[kp, j])),
                t_peak=float(t[kp]),
                samples=int(idx.size),
            )
        )
    return out


def check_trajectory(
    traj: JointTrajectory,
    limits: JointLimits,
    margin: float = 0.0,
    *,
    jerk: bool = False,
    cartesian_positions: np.ndarray | None = None,
) -> CheckReport:
    """Check a joint trajectory against ``limits`` scaled by (1 − margin).

    Derivatives by central differences applied repeatedly. ``cartesian_positions`` (n, 3) [m] of the flange
    enables the T1 Cartesian speed check.
    """
    if not 0.0 <= margin < 1.0:
        raise ValueError("margin must be in [0, 1)")
    lim = limits.scaled(1.0 - margin)
    h = traj.dt if len(traj) > 1 else 1.0
    vel, acc, jrk = derivatives(traj.q, h, 3)
    values = {"position": traj.q, "velocity": vel, "acceleration": acc, "jerk": jrk}
    applied = {"position": lim.position, "velocity": lim.velocity, "acceleration": lim.acceleration, "jerk": lim.jerk}
    steps = step_differences(traj.q, h)
    for qname, x in zip(STEP_QUANTITIES, steps):
        values[qname] = x
    applied.update({"step velocity": lim.velocity, "step acceleration": lim.acceleration, "step jerk": lim.jerk})
    violations: list[Violation] = rest_violations(traj, lim)
    for qname in QUANTITIES:
        violations += _violations(qname, traj.t, values[qname], applied[qname])
    t_steps = _step_times(traj.t)
    for qname, x in zip(STEP_QUANTITIES, steps):
        violations += _violations(qname, t_steps[: len(x)], x, applied[qname])
    peaks = {k: np.abs(v).max(axis=0) for k, v in values.items()}
    cart_peak = cart_limit = None
    if cartesian_positions is not None:
        speed = np.linalg.norm(derivatives(cartesian_positions, h, 1)[0], axis=1)
        cart_limit = lim.t1_cartesian_speed
        cart_peak = float(speed.max())
        violations += _violations("cartesian speed", traj.t, speed[:, None], np.array([cart_limit]), joint_base=0)
    return CheckReport(
        peaks=peaks,
        limits=applied,
        violations=tuple(violations),
        jerk_enforced=jerk,
        margin=margin,
        cartesian_speed_peak=cart_peak,
        cartesian_speed_limit=cart_limit,
        series={"t": traj.t, "position": traj.q, "velocity": vel, "acceleration": acc, "jerk": jrk},
    )


def step_differences(q: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward differences as the controller executes the rows one step [s] ``h`` apart, with the robot at rest
    before the first row and after the last: velocity (n+1, 7) [rad/s], acceleration (n+2, 7) [rad/s²], jerk
    (n+3, 7) [rad/s³]."""
    padded = np.vstack([q[:1], q[:1], q[:1], q, q[-1:], q[-1:], q[-1:]])
    return (np.diff(padded[2:-2], axis=0) / h, np.diff(padded[1:-1], 2, axis=0) / (h * h),
            np.diff(padded, 3, axis=0) / (h * h * h))  # fmt: skip


def _step_times(t: np.ndarray) -> np.ndarray:
    """Times [s] to name the step differences by: the row where each step series entry ends (clipped to the file),
    padded for the longest (jerk) series."""
    n = len(t)
    return t[np.clip(np.arange(n + 3), 0, n - 1)]


def rest_violations(traj: JointTrajectory, limits: JointLimits) -> list[Violation]:
    """The file must start and end at rest: the first and last step's speed [rad/s] at most what the acceleration
    limit reaches from rest in one step (a_max · h)."""
    if len(traj) < 2:
        return []
    h = traj.dt
    tol = limits.acceleration * h * (1.0 + REL_TOL)
    out = []
    for where, v, t in (
        ("start", (traj.q[1] - traj.q[0]) / h, traj.t[0]),
        ("end", (traj.q[-1] - traj.q[-2]) / h, traj.t[-1]),
    ):
        for j in np.flatnonzero(np.abs(v) > tol):
            out.append(Violation(int(j) + 1, "rest", float(t), float(v[j]), float(limits.acceleration[j] * h),
                                 float(abs(v[j])), float(t), 1, note=where))  # fmt: skip
    return out


def step_ratios(traj: JointTrajectory, limits: JointLimits) -> dict[str, float]:
    """Peak |forward difference| / limit over all joints, the robot at rest before and after the file (see
    :func:`step_differences`): what the controller executes step by step [ratio, 1 = at the limit]."""
    if len(traj) < 2:
        return {"velocity": 0.0, "acceleration": 0.0}
    vel, acc, _ = step_differences(traj.q, traj.dt)
    return {
        "velocity": float((np.abs(vel) / limits.velocity).max()),
        "acceleration": float((np.abs(acc) / limits.acceleration).max()),
    }
