"""The catch move: after the ball is released, bring the cup under it and stop, chosen to catch across the band.

The move starts from the pivot's state at ``t_start`` (the swing-up's stop may still be under way) and is a
time-synchronised, jerk-limited ruckig move in the base y–z plane to a chosen position and velocity at ``t_catch``,
then a jerk-limited brake to rest (gentler than the bounds: the ball is in the cup by then). Each candidate is
judged by stepping the string model (``string_stepper``) for every member of the robustness band — string length,
ball mass and a timing error of the cup's motion after the release — from the state the swing-up left it in.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from trajectories.errors import PlanningError

from .catch_outcome import CatchOutcome, outcome
from .string_model import StringModel
from .string_sim import PivotMotion
from .string_stepper import StringStepper, step_path
from .swingup_plan import TaskBounds

BRAKE_FRACTION = 0.6  # the brake after the catch uses this share of the acceleration and jerk bounds


@dataclass(frozen=True)
class CatchMove:
    """From t_start [s], reach pivot displacement (y, z) [m] from the start pose with velocity (vy, vz) [m/s] at
    t_catch [s] (later if the bounds need longer), keep that velocity for ``coast`` [s], then brake to rest."""

    t_start: float
    t_catch: float
    y: float
    z: float
    vy: float
    vz: float
    coast: float = 0.0  # [s] the band's balls come in over a while and bounce: the cup does not brake under them


@dataclass(frozen=True)
class BandMember:
    """One case of the robustness band: string length [m], ball mass [kg], timing error of the cup after the release
    [s] (positive: late)."""

    length: float
    mass: float
    shift: float = 0.0

    def model(self, base: StringModel) -> StringModel:
        from dataclasses import replace

        return replace(base, length=self.length, ball=replace(base.ball, mass=self.mass))


def band_members(
    length: float,
    mass: float,
    dt: float,
    length_tol: float = 0.03,
    mass_tol: float = 0.2,
    n_length: int = 3,
    n_mass: int = 3,
    timing: bool = True,
) -> tuple[BandMember, ...]:
    """A grid over the band: n_length lengths across ±length_tol, n_mass masses across ±mass_tol, timing errors −dt, 0,
    +dt (one FRI period) — every combination."""
    lengths = length * (1.0 + length_tol * np.linspace(-1.0, 1.0, n_length)) if n_length > 1 else [length]
    masses = mass * (1.0 + mass_tol * np.linspace(-1.0, 1.0, n_mass)) if n_mass > 1 else [mass]
    shifts = (-dt, 0.0, dt) if timing else (0.0,)
    return tuple(BandMember(float(ln), float(m), s) for ln in lengths for m in masses for s in shifts)


def cup_path(
    swing_x: np.ndarray,
    swing_v: np.ndarray,
    swing_u: np.ndarray,
    dt: float,
    move: CatchMove,
    bounds_y: TaskBounds,
    bounds_z: TaskBounds,
    settle: float = 0.5,
) -> tuple[np.ndarray, float]:
    """The pivot's displacements (n, 2) [m] along base y and z, every dt [s] from 0: the swing-up (y only) up to
    t_start, the move, its coast at the target velocity, the brake, ``settle`` [s] at rest. Also the time [s] the
    move actually reaches its target."""
    from ruckig import ControlInterface, InputParameter, Result, Ruckig, Trajectory

    k = min(int(round(move.t_start / dt)), len(swing_x) - 1)
    vmax = [max(bounds_y.v_max, abs(swing_v[k]) + 1e-9), bounds_z.v_max]
    inp = InputParameter(2)
    inp.current_position = [float(swing_x[k]), 0.0]
    inp.current_velocity = [float(swing_v[k]), 0.0]
    inp.current_acceleration = [float(np.clip(swing_u[k], -bounds_y.a_max, bounds_y.a_max)), 0.0]
    inp.target_position = [move.y, move.z]
    inp.target_velocity = [
        float(np.clip(move.vy, -0.999 * vmax[0], 0.999 * vmax[0])),
        float(np.clip(move.vz, -0.999 * vmax[1], 0.999 * vmax[1])),
    ]
    inp.target_acceleration = [0.0, 0.0]
    inp.max_velocity = vmax
    inp.max_acceleration = [bounds_y.a_max, bounds_z.a_max]
    inp.max_jerk = [bounds_y.j_max, bounds_z.j_max]
    inp.minimum_duration = max(move.t_catch - k * dt, dt)
    go = Trajectory(2)
    if Ruckig(2).calculate(inp, go) not in (Result.Working, Result.Finished):
        raise PlanningError("ruckig could not plan the catch move")
    p, v, a = go.at_time(go.duration)
    brake = InputParameter(2)
    brake.control_interface = ControlInterface.Velocity
    brake.current_position, brake.current_velocity, brake.current_acceleration = list(p), list(v), list(a)
    brake.target_velocity = [0.0, 0.0]
    brake.target_acceleration = [0.0, 0.0]
    brake.max_velocity = [max(vmax[0], abs(v[0]) + 1e-9), max(vmax[1], abs(v[1]) + 1e-9)]
    brake.max_acceleration = [BRAKE_FRACTION * bounds_y.a_max, BRAKE_FRACTION * bounds_z.a_max]
    brake.max_jerk = [BRAKE_FRACTION * bounds_y.j_max, BRAKE_FRACTION * bounds_z.j_max]
    stop = Trajectory(2)
    if Ruckig(2).calculate(brake, stop) not in (Result.Working, Result.Finished):
        raise PlanningError("ruckig could not brake after the catch")
    d_go, coast, d_stop = go.duration, max(0.0, move.coast), stop.duration
    n = int(math.ceil((d_go + coast + d_stop) / dt - 1e-9)) + int(round(settle / dt))
    tail = np.empty((n, 2))
    for i in range(1, n + 1):
        tau = i * dt
        if tau <= d_go:
            tail[i - 1] = go.at_time(tau)[0]
        elif tau <= d_go + coast:  # at the target velocity, no acceleration (where the move ended)
            tail[i - 1] = (p[0] + v[0] * (tau - d_go), p[1] + v[1] * (tau - d_go))
        else:
            q = stop.at_time(min(tau - d_go - coast, d_stop))[0]
            tail[i - 1] = (q[0] + v[0] * coast, q[1] + v[1] * coast)
    head = np.column_stack([swing_x[: k + 1], np.zeros(k + 1)])
    return np.vstack([head, tail]), k * dt + d_go


def pivot_motion(t: np.ndarray, p0: np.ndarray, path: np.ndarray, axis=(0.0, 0.0, 1.0)) -> PivotMotion:
    """The anchor's motion for displacements (n, 2) along base y and z from p0 (3,) [m]."""
    pos = np.asarray(p0, dtype=float)[None, :] + np.column_stack([np.zeros(len(path)), path])
    return PivotMotion(t, pos, np.asarray(axis, dtype=float))


@dataclass
class BandState:
    """Every band member's stepper, advanced along the swing-up to a common time (copied for each candidate)."""

    members: tuple[BandMember, ...]
    steppers: list[StringStepper]
    t: float


def prepare_band(
    base: StringModel, members: tuple[BandMember, ...], pivot: PivotMotion, t: float, substeps: int = 1
) -> BandState:
    """Step each distinct (length, mass) of the band along ``pivot`` up to t [s] (the timing error acts only later)."""
    cache: dict[tuple[float, float], StringStepper] = {}
    steppers = []
    for m in members:
        key = (m.length, m.mass)
        if key not in cache:
            cache[key] = step_path(m.model(base), pivot, t, substeps)[0]
        steppers.append(cache[key])
    return BandState(members, steppers, t)


def judge_band(
    base: StringModel, band: BandState, pivot: PivotMotion, t_end: float, substeps: int = 1, until_missed: bool = False
) -> list[CatchOutcome]:
    """Continue every member from the band state along ``pivot`` to t_end [s] and summarise each run
    (``until_missed``: a member whose ball passes outside the rim is stopped there, ``string_stepper.step_path``)."""
    out = []
    for member, st0 in zip(band.members, band.steppers):
        st = copy.deepcopy(st0)
        st.m = member.model(base)  # the same string; the mass only changes the drag
        st.k = st.m.drag
        step_path(st.m, pivot, t_end, substeps, state=st, shift=member.shift, until_missed=until_missed)
        out.append(outcome(st.events, st.resting, st.inside))
    return out


def band_score(outcomes: list[CatchOutcome], radius_clearance: float) -> float:
    """What the search maximises: the share caught, then the entry margins (clipped to ±clearance, averaged, in
    clearances) and small relative entry speeds as tie-breakers."""
    caught = np.mean([o.caught for o in outcomes])
    margins = [
        max(-1.0, min(1.0, (o.margin if o.margin is not None else -radius_clearance) / radius_clearance))
        for o in outcomes
    ]
    speeds = [o.relative_speed for o in outcomes if o.relative_speed is not None]
    return float(caught + 0.2 * np.mean(margins) - 0.02 * (np.mean(speeds) if speeds else 3.0))


__all__ = [
    "CatchMove",
    "BandMember",
    "band_members",
    "cup_path",
    "pivot_motion",
    "prepare_band",
    "judge_band",
    "band_score",
]
