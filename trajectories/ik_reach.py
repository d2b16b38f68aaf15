"""What a TCP path asks that no choice of the redundancy can give: facts of the poses and of the path, exact at
every sample.

For the iiwa's S-R-S chain (:mod:`.arm_angle`) a flange pose fixes the wrist, the elbow angle A4 (up to its sign)
and a circle of elbow positions (the arm angle ψ). The shoulder rotation R03 and the wrist rotation R47 are
linear in (sin ψ, cos ψ, 1) (Shimizu et al., 2008), so every joint limit is a condition on such linear forms:
``cos A2 ≥ cos L2`` (and A6), and for a turning joint (A1, A3, A5, A7) "not within π − L of ±π" is
``f₁ ≥ 0 or f₂ ≥ 0`` for two forms built from the atan2 arguments. The 8 branches (signs of A2, A4, A6) map the
turning joints by + π and the pivot joints by a sign, so one set of forms serves all of them. Between two
consecutive zeros of the forms nothing changes sign: testing one arm angle in each such arc decides exactly
whether any arm angle of any branch keeps every joint inside its position limits.

Facts found here, first sample first:

- **out of reach**: the wrist is farther from the shoulder than the two arm segments reach;
- **position limit**: the pose needs a joint beyond its limit at every arm angle of every branch (A4 alone: the
  wrist is so close to the shoulder that the elbow must fold past its limit);
- **velocity limit** / **acceleration limit**: A4's angle is set by the pose alone up to its sign, so the speed
  and (asked for when the file must pass `lbr check`) the acceleration it needs are facts of the path, whatever
  the redundancy does. Where the elbow passes near straight (|A4| within one step's travel of 0) A4 may change
  sign or turn back: the least of those is found by a 4-state search over the signs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .arm_angle import BRANCHES, ArmGeometry, _rz_rx, inverse
from .limits import JointLimits

CHUNK = 8192  # samples per vectorised block (bounds the memory; the scan stops at the first block with a fact)
PSI0 = 0.3  # [rad] arm angle at which the shoulder and wrist rotations are computed (the forms are in ψ − PSI0)
QUICK_PHI = np.linspace(0.0, 2 * math.pi, 6, endpoint=False)  # [rad] arm angles tried before the arcs
EXPLAIN_PSI = 3600  # arm-angle grid (0.1°) of the closest configuration named in a position-limit fact
TURNING = (0, 2, 4, 6)  # A1, A3, A5, A7: limits below π, the branches turn them by π
# parity of the π turn of A1, A3, A5, A7 in each branch (shoulder s, elbow e, wrist w flips): s, s⊕e, e⊕w, w
_FLIPS = (BRANCHES < 0).astype(int)  # (8, 3): s, e, w
PARITY = np.stack([_FLIPS[:, 0], _FLIPS[:, 0] ^ _FLIPS[:, 1], _FLIPS[:, 1] ^ _FLIPS[:, 2], _FLIPS[:, 2]], axis=1)
# bit b of a mask: branch b; per turning joint (A1, A3, A5, A7), the branches turning it by π (odd) and not
BRANCH_BITS = 1 << np.arange(len(PARITY), dtype=np.uint8)
_ODD = np.array([int(BRANCH_BITS[PARITY[:, i] == 1].sum()) for i in range(4)], dtype=np.uint8)
_EVEN = ~_ODD


@dataclass(frozen=True)
class PathFact:
    """The first sample that no joint path reaches inside the limits, and why.

    ``reason``: "out of reach", "position limit" or "velocity limit"; ``joint`` 0-based (None when out of reach);
    ``needed``: how far beyond reach [m], the angle the closest configuration needs [rad], or the speed [rad/s];
    ``limit``: the reach [m], position limit [rad] or speed limit [rad/s]; ``psi`` [rad] and ``branch`` (signs of
    A2, A4, A6) of the closest configuration for a position limit."""

    index: int
    reason: str
    joint: int | None
    needed: float
    limit: float
    psi: float | None = None
    branch: tuple[float, float, float] | None = None

    @property
    def of_pose(self) -> bool:
        """A fact of the pose alone (out of reach, position limit), not of its neighbours (speed, acceleration)."""
        return self.reason not in ("velocity limit", "acceleration limit")

    def describe(self) -> str:
        """What makes the sample unreachable, as a sentence fragment."""
        if self.reason == "out of reach":
            return (
                f"out of reach by {self.needed * 1e3:.1f} mm (the wrist would be {self.limit + self.needed:.3f} m "
                f"from the shoulder; the arm reaches {self.limit:.3f} m)"
            )
        j = self.joint + 1  # type: ignore[operator]
        if self.reason in ("velocity limit", "acceleration limit"):
            unit = "rad/s" if self.reason == "velocity limit" else "rad/s²"
            return (
                f"needs A{j} at {self.needed:.4g} {unit}, above its limit {self.limit:.4g} {unit} (×"
                f"{self.needed / self.limit:.3f}); A4's angle is set by the pose alone (the wrist's distance from "
                f"the shoulder), whatever the arm angle"
            )
        if self.joint == 3:
            return (
                f"needs A4 at ±{math.degrees(abs(self.needed)):.2f}° (limit ±{math.degrees(self.limit):.2f}°) at "
                f"every arm angle: the wrist is too close to the shoulder"
            )
        signs = "".join("+" if b > 0 else "−" for b in self.branch) if self.branch else "?"
        return (
            f"needs a joint beyond its position limit at every arm angle of every branch (the closest: A{j} at "
            f"{math.degrees(self.needed):.2f}°, limit ±{math.degrees(self.limit):.2f}°, at arm angle "
            f"{math.degrees(self.psi or 0.0):.1f}° in branch {signs} of A2/A4/A6)"
        )


def _frames(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shoulder rotation R03 and wrist rotation R47 (..., 3, 3) of configurations q (..., 7) [rad]."""
    r03 = _rz_rx(q[..., 0], -1.0) @ _rz_rx(q[..., 1], 1.0) @ _rz_rx(q[..., 2], 1.0)
    c, s = np.cos(q[..., 6]), np.sin(q[..., 6])
    z, o = np.zeros_like(c), np.ones_like(c)
    rz7 = np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)
    return r03, _rz_rx(q[..., 4], -1.0) @ _rz_rx(q[..., 5], 1.0) @ rz7


def _fit(geometry: ArmGeometry, rotations: np.ndarray, positions: np.ndarray, psi0: float):
    """Coefficients (m, 3, 3, 3) of R03 and R47 of branch +++ on (sin φ, cos φ, 1), φ = ψ − ψ0: the arm turns
    rigidly about the shoulder–wrist axis u, so R03(ψ) = Rot(u, φ)·R03(ψ0) and R47(ψ) = R04(ψ0)ᵀ·Rot(u, φ)ᵀ·R07,
    with Rot(u, φ) = I + sin φ·K + (1 − cos φ)·K², K = [u]×."""
    q, _ = inverse(geometry, rotations, positions, np.full(len(positions), psi0), BRANCHES[0])
    r03, _ = _frames(q)
    r04t = (r03 @ _rz_rx(q[:, 3], -1.0)).transpose(0, 2, 1)
    wrist = positions - np.einsum("nij,j->ni", rotations, geometry.tool) - geometry.wrist_flange * rotations[:, :, 2]
    u = wrist - np.array([0.0, 0.0, geometry.base_shoulder])
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    k = np.zeros((len(u), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -u[:, 2], u[:, 1], -u[:, 0]
    k -= k.transpose(0, 2, 1)
    k2 = k @ k
    ik2 = np.eye(3) + k2
    c03 = np.stack([k @ r03, -k2 @ r03, ik2 @ r03], axis=1)
    c47 = np.stack([-r04t @ k @ rotations, -r04t @ k2 @ rotations, r04t @ ik2 @ rotations], axis=1)
    return c03, c47


def _forms(c03: np.ndarray, c47: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """The 10 linear forms (m, 10, 3) whose signs decide the position limits ``bound`` (7,) [rad] for branch +++:
    cos A2 − cos L2, cos A6 − cos L6, then (f₁, f₂) of A1, A3, A5, A7 (atan2 arguments (u, v) turned by ±δ,
    δ = π − L: the joint is outside its limit iff both are negative)."""
    uv = (
        (c03[..., 0, 1], c03[..., 1, 1]),  # A1 = atan2(R03[1,1], R03[0,1])
        (-c03[..., 2, 0], -c03[..., 2, 2]),  # A3 = atan2(−R03[2,2], −R03[2,0])
        (c47[..., 0, 2], c47[..., 1, 2]),  # A5 = atan2(R47[1,2], R47[0,2])
        (-c47[..., 2, 0], c47[..., 2, 1]),  # A7 = atan2(R47[2,1], −R47[2,0])
    )
    one = np.array([0.0, 0.0, 1.0])
    forms = [c03[..., 2, 1] - math.cos(bound[1]) * one, c47[..., 2, 2] - math.cos(bound[5]) * one]
    for j, (u, v) in zip(TURNING, uv):
        delta = math.pi - bound[j]
        forms += [u * math.sin(delta) + v * math.cos(delta), u * math.sin(delta) - v * math.cos(delta)]
    return np.stack(forms, axis=1)


def _test_angles(forms: np.ndarray) -> np.ndarray:
    """Angles φ (m, T) [rad], one inside every arc between consecutive zeros of the forms (m, F, 3) in φ."""
    a, b, c = forms[..., 0], forms[..., 1], forms[..., 2]
    r = np.hypot(a, b)
    ratio = np.where(r > 1e-300, -c / np.where(r > 1e-300, r, 1.0), 2.0)
    has = np.abs(ratio) < 1.0
    phi = np.arctan2(b, a)
    s = np.arcsin(np.clip(ratio, -1.0, 1.0))
    roots = np.concatenate([np.where(has, s - phi, 0.0), np.where(has, math.pi - s - phi, 0.0)], axis=1)
    roots = np.sort(np.mod(roots, 2 * math.pi), axis=1)  # absent zeros sit at 0: extra arcs, still exact
    nxt = np.concatenate([roots[:, 1:], roots[:, :1] + 2 * math.pi], axis=1)
    return 0.5 * (roots + nxt)


def _feasible(forms: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Whether some branch keeps every joint but A4 inside its limit at some of the angles φ (m, T) [rad] → (m,)."""
    basis = np.stack([np.sin(phi), np.cos(phi), np.ones_like(phi)], axis=-1)  # (m, T, 3)
    val = np.einsum("mfi,mti->mft", forms, basis)  # (m, F, T)
    nonneg, nonpos = val >= 0.0, val <= 0.0
    mask = np.where(nonneg[:, 0] & nonneg[:, 1], np.uint8(255), np.uint8(0))  # the pivots A2, A6: every branch
    for i in range(4):  # A1, A3, A5, A7: inside unless both forms are negative (turned by π: positive)
        even = nonneg[:, 2 + 2 * i] | nonneg[:, 3 + 2 * i]
        odd = nonpos[:, 2 + 2 * i] | nonpos[:, 3 + 2 * i]
        mask &= np.where(even, _EVEN[i], np.uint8(0)) | np.where(odd, _ODD[i], np.uint8(0))
    return (mask != 0).any(axis=1)


def wrist_geometry(
    geometry: ArmGeometry, positions: np.ndarray, rotations: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The wrist's distance from the shoulder (n,) [m] and |A4| (n,) [rad] of each pose (clipped where out of reach)."""
    d1, d3, d5 = geometry.base_shoulder, geometry.shoulder_elbow, geometry.elbow_wrist
    flange = positions - np.einsum("nij,j->ni", rotations, geometry.tool)
    wrist = flange - geometry.wrist_flange * rotations[:, :, 2]
    length = np.linalg.norm(wrist - np.array([0.0, 0.0, d1]), axis=1)
    cos4 = np.clip((length**2 - d3 * d3 - d5 * d5) / (2.0 * d3 * d5), -1.0, 1.0)
    return length, np.arccos(cos4)


def _within(geometry: ArmGeometry, length: np.ndarray, a4: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """Within reach and A4 inside ``bound[3]``."""
    d3, d5 = geometry.shoulder_elbow, geometry.elbow_wrist
    return (length <= d3 + d5) & (length >= abs(d3 - d5)) & (length > 1e-9) & (a4 <= bound[3])


def arm_angle_feasible(
    geometry: ArmGeometry, positions: np.ndarray, rotations: np.ndarray, bound: np.ndarray
) -> np.ndarray:
    """Per pose (m,) within reach: whether some arm angle of some branch keeps A1–A3, A5–A7 inside ``bound``."""
    forms = _forms(*_fit(geometry, rotations, positions, PSI0), bound)
    # most poses are inside the limits at one of a few arm angles; the others are decided arc by arc
    ok = _feasible(forms, np.broadcast_to(QUICK_PHI, (len(forms), len(QUICK_PHI))))
    rest = np.flatnonzero(~ok)
    if len(rest):
        ok[rest] = _feasible(forms[rest], _test_angles(forms[rest]))
    return ok


def pose_feasibility(
    geometry: ArmGeometry, positions: np.ndarray, rotations: np.ndarray, bound: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pose (n,): within reach, A4 inside ``bound[3]``, and some arm angle of some branch keeping the other
    joints inside ``bound`` (7,) [rad]; also the wrist's distance from the shoulder [m] and |A4| [rad]."""
    positions = np.asarray(positions, dtype=float)
    rotations = np.asarray(rotations, dtype=float)
    length, a4 = wrist_geometry(geometry, positions, rotations)
    ok = _within(geometry, length, a4, bound)
    todo = np.flatnonzero(ok)
    if len(todo):
        ok[todo] = arm_angle_feasible(geometry, positions[todo], rotations[todo], bound)
    return ok, length, a4


def closest_configuration(
    geometry: ArmGeometry, position: np.ndarray, rotation: np.ndarray, bound: np.ndarray
) -> tuple[int, float, float, np.ndarray]:
    """The configuration of one pose, over a 0.1° arm-angle grid and every branch, whose worst joint is least
    beyond ``bound`` → (that joint, its angle [rad], the arm angle [rad], the branch signs)."""
    psi = np.linspace(-math.pi, math.pi, EXPLAIN_PSI, endpoint=False)
    q, _ = inverse(geometry, rotation, position, psi[None, :], BRANCHES[:, None, :])  # (8, P, 7)
    excess = np.abs(q) - bound
    worst = excess.max(axis=-1)
    b, p = np.unravel_index(int(np.argmin(worst)), worst.shape)
    j = int(np.argmax(excess[b, p]))
    return j, float(q[b, p, j]), float(psi[p]), BRANCHES[b]


def _a4_motion(a4: np.ndarray, times: np.ndarray, limits: JointLimits, acceleration: bool):
    """The first sample (and why: reason, needed value) where no sign sequence of A4 = ±|A4| (n,) [rad] keeps A4's
    speed — and with ``acceleration`` its second difference — within the limits, or None. Away from a straight
    elbow the sign cannot change (it would need |A4| twice within one step's travel), so the differences of |A4|
    decide; near it, a search over (previous sign, sign) pairs."""
    n = len(a4)
    if n < 2:
        return None
    dt = np.diff(times)
    vmax, amax = float(limits.velocity[3]), float(limits.acceleration[3])
    tol = 1.0 + 1e-9
    speed = np.abs(np.diff(a4)) / dt  # [rad/s] into sample k + 1
    acc = np.abs(np.diff(a4, 2)) / dt[1:] ** 2 if n > 2 else np.empty(0)  # into sample k + 2
    near = a4 <= vmax * float(dt.max()) * tol  # a sign change is possible only between two such samples
    zone = near.copy()
    for shift in (1, 2):  # the differences touching a near sample are decided by the search
        zone[shift:] |= near[:-shift]
        zone[:-shift] |= near[shift:]
    firsts = []
    over_v = np.flatnonzero((speed > vmax * tol) & ~zone[1:])
    if len(over_v):
        k = int(over_v[0]) + 1
        firsts.append((k, "velocity limit", float(speed[k - 1]), vmax))
    if acceleration and len(acc):
        over_a = np.flatnonzero((acc > amax * tol) & ~zone[2:])
        if len(over_a):
            k = int(over_a[0]) + 2
            firsts.append((k, "acceleration limit", float(acc[k - 2]), amax))
    for run in np.split(np.flatnonzero(zone), np.flatnonzero(np.diff(np.flatnonzero(zone)) > 1) + 1):
        if len(run):
            found = _a4_signs(a4, times, int(run[0]), int(run[-1]), vmax, amax, acceleration)
            if found is not None:
                firsts.append(found)
    return min(firsts) if firsts else None


def _a4_signs(a4, times, first: int, last: int, vmax: float, amax: float, acceleration: bool):
    """The search of :func:`_a4_motion` over samples first..last (the sign before them taken as +)."""
    tol = 1.0 + 1e-9
    states = {(1.0, 1.0): True}  # (sign of sample k − 1, sign of sample k) reachable so far
    start = max(first, 1)
    for k in range(start, last + 1):
        nxt: dict = {}
        blocked = None
        h = float(times[k] - times[k - 1])
        for sp, sc in states:
            for sn in (1.0, -1.0):
                v = abs(sn * a4[k] - sc * a4[k - 1]) / h
                if v > vmax * tol:
                    blocked = blocked or ("velocity limit", v, vmax)
                    continue
                if acceleration and k >= 2:
                    a = abs(sn * a4[k] - 2.0 * sc * a4[k - 1] + sp * a4[k - 2]) / (h * h)
                    if a > amax * tol:
                        blocked = ("acceleration limit", a, amax)
                        continue
                nxt[(sc, sn)] = True
        if not nxt:
            reason, need, lim = blocked
            return (k, reason, float(need), lim)
        states = nxt
    return None


def first_unreachable(
    geometry: ArmGeometry,
    positions: np.ndarray,
    rotations: np.ndarray,
    times: np.ndarray | None,
    limits: JointLimits,
    margin: float = 1e-4,
    speed: bool = True,
    acceleration: bool = False,
    stride: int = 1,
) -> PathFact | None:
    """The first sample of a TCP path (positions (n, 3) [m], rotations (n, 3, 3) at ``times`` (n,) [s]) that no joint
    path reaches with every joint ``margin`` [rad] inside its position limits — or, with ``speed``, with A4 within
    its speed limit (and with ``acceleration`` its acceleration limit, second differences) — and why; None when
    there is none. Reach and A4 are checked at every sample; the arm angles at every ``stride``-th sample, and at
    every sample from the last one checked before the first found without (so a pose excursion shorter than the
    stride can be missed; ``stride`` 1 misses none)."""
    positions = np.asarray(positions, dtype=float)
    rotations = np.asarray(rotations, dtype=float)
    n = len(positions)
    bound = limits.position - margin
    length, a4 = wrist_geometry(geometry, positions, rotations)
    within = _within(geometry, length, a4, bound)
    end = n if within.all() else int(np.argmin(within)) + 1  # up to the first pose beyond reach or A4's limit
    pose_k = None if within.all() else end - 1
    # the arm angles before it: on the grid first (block by block, so the scan ends early), then every sample
    # between the last grid sample that has one and the first that has none
    grid = np.unique(np.r_[np.arange(0, end, max(1, stride)), end - 1]) if end else np.empty(0, dtype=int)
    grid = grid[within[grid]]
    for start in range(0, len(grid), CHUNK):
        idx = grid[start : start + CHUNK]
        ok = arm_angle_feasible(geometry, positions[idx], rotations[idx], bound)
        if not ok.all():
            bad = int(idx[np.argmin(ok)])
            lo = int(grid[start + int(np.argmin(ok)) - 1]) + 1 if start + int(np.argmin(ok)) > 0 else 0
            fine = np.arange(lo, bad + 1)
            fine_ok = arm_angle_feasible(geometry, positions[fine], rotations[fine], bound)
            pose_k = int(fine[np.argmin(fine_ok)])
            break
    pose_fact = None
    if pose_k is not None:
        pose_fact = _pose_fact(geometry, positions, rotations, limits, bound, pose_k, length[pose_k], a4[pose_k])
    stop = n if pose_k is None else pose_k + 1
    motion = _a4_motion(a4[:stop], times[:stop], limits, acceleration) if speed and times is not None else None
    if motion is not None and (pose_fact is None or motion[0] < pose_fact.index):
        k, reason, need, lim = motion
        return PathFact(int(k), reason, 3, need, lim)
    return pose_fact


def _pose_fact(geometry, positions, rotations, limits, bound, k: int, length: float, a4: float) -> PathFact:
    """Why pose k has no configuration inside ``bound``: beyond the reach, A4, or the closest configuration's
    worst joint."""
    reach_limit = geometry.shoulder_elbow + geometry.elbow_wrist
    if length > reach_limit or length <= 1e-9:
        return PathFact(k, "out of reach", None, float(length - reach_limit), reach_limit)
    if a4 > bound[3]:
        return PathFact(k, "position limit", 3, float(a4), float(limits.position[3]))
    j, value, psi, branch = closest_configuration(geometry, positions[k], rotations[k], bound)
    return PathFact(k, "position limit", j, value, float(limits.position[j]), psi, tuple(float(b) for b in branch))  # type: ignore[arg-type]
