"""Limit checking of joint trajectories: position, velocity, acceleration, jerk and T1 Cartesian speed."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .differences import derivatives
from .limits import JointLimits
from .trajectory import JointTrajectory

QUANTITIES = ("position", "velocity", "acceleration", "jerk")
UNITS = {"position": "rad", "velocity": "rad/s", "acceleration": "rad/s^2", "jerk": "rad/s^3", "cartesian speed": "m/s"}


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

    def describe(self) -> str:
        unit = UNITS[self.quantity]
        who = f"A{self.joint}" if self.joint else "flange"
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
        return tuple(v for v in self.violations if v.quantity != "jerk" or self.jerk_enforced)

    @property
    def ok(self) -> bool:
        return not self.failing

    def ratios(self) -> dict[str, np.ndarray]:
        """Peak / limit per quantity and joint."""
        return {k: self.peaks[k] / self.limits[k] for k in self.peaks}

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
                    "fails": v.quantity != "jerk" or self.jerk_enforced,
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
    over = np.abs(x) > limit[None, :]
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
    violations: list[Violation] = []
    for qname in QUANTITIES:
        violations += _violations(qname, traj.t, values[qname], applied[qname])
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


def step_ratios(traj: JointTrajectory, limits: JointLimits) -> dict[str, float]:
    """Peak |forward difference| / limit over all joints: velocity (q[k+1] − q[k])/h and acceleration
    (q[k+1] − 2q[k] + q[k−1])/h², what the controller executes step by step [ratio, 1 = at the limit]."""
    if len(traj) < 3:
        return {"velocity": 0.0, "acceleration": 0.0}
    h = traj.dt
    vel = np.abs(np.diff(traj.q, axis=0)) / h
    acc = np.abs(np.diff(traj.q, 2, axis=0)) / (h * h)
    return {
        "velocity": float((vel / limits.velocity).max()),
        "acceleration": float((acc / limits.acceleration).max()),
    }
