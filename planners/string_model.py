"""The ball on a real string, with the cup on the flange: the one model of the cup-and-ball game.

Every integrator and judge of the project uses these laws (``string_sim`` event-driven with scipy, ``string_stepper``
cycle by cycle in the FRI simulator); ``string_penalty`` is the deliberately different judge that does not.

- String: massless, inextensible, one-sided, from the anchor p (the TCP, at the bottom of the cup) to the ball centre
  b. Taut (|b − p| = l, tension T > 0): the driven spherical pendulum of ``planners.pendulum`` (s = (b − p)/l,
  l·s̈ = (I − s sᵀ)(g − p̈) − l|ṡ|²s) plus the tangential part of the air drag. Slack (|b − p| < l or T ≤ 0): free
  flight, b̈ = g − k·|ḃ|·ḃ. Re-tension (|b − p| reaches l while the ball moves away): an impulse along the string,
  the radial velocity relative to the anchor v_r > 0 becomes −e_s·v_r (``retension`` e_s = 0: fully inelastic).
  An optional viscous damping of the taut swing (−c·ṡ) stands for losses the model does not resolve.
- Ball: a sphere of radius r and mass m. Air drag k = ½·ρ·C_d·π·r²/m [1/m]; the mass enters the motion only here (the
  robot is position controlled and the string massless).
- Cup: an open cylinder fixed to the flange, a solid of revolution about its axis a through the anchor: a bottom
  slab (0 ≤ z ≤ rim − depth, ρ ≤ R + w) and a wall (R ≤ ρ ≤ R + w, 0 ≤ z ≤ rim) with z along a from the anchor,
  ρ the distance from the axis, R the inner radius, w the wall thickness. The ball touches it where the distance from
  its centre to that solid is r (rim edges are the solid's corners: rounded contact).
- Contact: an impulse at the first touch: the normal relative velocity v_n < 0 becomes −e·v_n (restitution e), the
  tangential one loses at most μ·(1 + e)·|v_n| (Coulomb). A ball that meets the bottom slower than ``rest_speed``
  rests in the cup and moves with it until the cup accelerates away from it along the axis faster than gravity
  ((p̈ − g)·a ≤ 0). The cup's rotation rate and the ball's spin are neglected.

Base frame z up. Vectors here are 3-tuples of floats: the laws run inside the simulator's 1 kHz loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .pendulum import G, _rhs_floats

Vec3 = tuple[float, float, float]
G_TUPLE: Vec3 = (0.0, 0.0, -G)

TAUT, SLACK, IN_CUP = 0, 1, 2  # phases reported per sample (prediction files, the simulator's ball_phase)
RESTING = 3  # internal: the ball rests on the cup (on its bottom: IN_CUP; on its rim: reported SLACK)
PHASE_NAMES = {TAUT: "taut", SLACK: "slack", IN_CUP: "in the cup"}


@dataclass(frozen=True)
class Ball:
    """A sphere: radius [m], mass [kg], drag coefficient C_d [-] and air density [kg/m³]."""

    radius: float = (
        0.01  # [m] (assumed: the thesis gives the mass, not the size; see docs/explanations/string-physics.md)
    )
    mass: float = 0.0139  # [kg] thesis §5.2
    drag_coefficient: float = 0.47  # smooth sphere
    air_density: float = 1.2  # [kg/m³]

    @property
    def drag_per_mass(self) -> float:
        """k [1/m]: the drag acceleration is −k·|v|·v."""
        return 0.5 * self.air_density * self.drag_coefficient * math.pi * self.radius**2 / self.mass


@dataclass(frozen=True)
class Cup:
    """An open cylinder on the flange; lengths in metres, ``axis`` the opening direction in the flange frame.

    The string anchor (the TCP) is on the axis at the outside of the bottom; ``rim_height`` is the rim's height above
    it, ``depth`` the inside depth (bottom thickness rim_height − depth), ``wall`` the wall thickness.
    """

    inner_radius: float = 0.03  # [m]
    depth: float = 0.045  # [m]
    rim_height: float = 0.05  # [m]
    wall: float = 0.003  # [m]
    axis: tuple[float, float, float] = (-1.0, 0.0, 0.0)  # flange frame; base +z at the thesis start pose

    @property
    def outer_radius(self) -> float:
        return self.inner_radius + self.wall

    @property
    def bottom_height(self) -> float:
        """Height of the inside bottom above the anchor [m]."""
        return self.rim_height - self.depth

    @property
    def extent(self) -> float:
        """Largest distance of a point of the cup from the anchor [m]."""
        return math.hypot(self.outer_radius, self.rim_height)

    def profile(self) -> tuple[tuple[float, float, float, float], ...]:
        """The cup's boundary in the (ρ, z) half-plane as segments (ρ0, z0, ρ1, z1), solid on their left side."""
        ri, ro, rim, zb = self.inner_radius, self.outer_radius, self.rim_height, self.bottom_height
        return ((0.0, 0.0, ro, 0.0), (ro, 0.0, ro, rim), (ro, rim, ri, rim), (ri, rim, ri, zb), (ri, zb, 0.0, zb))


@dataclass(frozen=True)
class StringModel:
    """String, ball, cup and the contact coefficients: everything the ball's motion depends on."""

    length: float  # [m] anchor to ball centre
    ball: Ball = field(default_factory=Ball)
    cup: Cup | None = field(default_factory=Cup)
    retension: float = 0.0  # restitution of the jerk when the string tightens (0: inelastic)
    restitution: float = 0.5  # ball–cup normal restitution
    friction: float = 0.3  # ball–cup Coulomb friction
    rest_speed: float = 0.05  # [m/s] a ball meeting the bottom slower than this rests in the cup
    damping: float = 0.0  # [1/s] viscous damping of the taut swing (−damping·ṡ, as ``pendulum.rhs``)

    def validate(self) -> None:
        """ValueError naming the first value out of range."""
        checks = [
            (
                all(
                    math.isfinite(v)
                    for v in (
                        self.length,
                        self.ball.radius,
                        self.ball.mass,
                        self.retension,
                        self.restitution,
                        self.friction,
                        self.rest_speed,
                        self.damping,
                    )
                ),
                "values must be finite",
            ),
            (self.length > 0, f"string length must be > 0 m, got {self.length:g}"),
            (self.ball.radius > 0, f"ball radius must be > 0 m, got {self.ball.radius:g}"),
            (self.ball.mass > 0, f"ball mass must be > 0 kg, got {self.ball.mass:g}"),
            (
                self.ball.drag_coefficient >= 0 and self.ball.air_density >= 0,
                "drag coefficient and air density must be >= 0",
            ),
            (0.0 <= self.retension <= 1.0, f"re-tension coefficient must be in [0, 1], got {self.retension:g}"),
            (0.0 <= self.restitution <= 1.0, f"restitution must be in [0, 1], got {self.restitution:g}"),
            (self.friction >= 0.0, f"friction must be >= 0, got {self.friction:g}"),
            (self.rest_speed >= 0.0, f"rest speed must be >= 0 m/s, got {self.rest_speed:g}"),
            (self.damping >= 0.0, f"damping must be >= 0 1/s, got {self.damping:g}"),
        ]
        c = self.cup
        if c is not None:
            n = math.sqrt(sum(x * x for x in c.axis))
            checks += [
                (
                    c.inner_radius > self.ball.radius,
                    f"the cup's inner radius {c.inner_radius:g} m must exceed the ball radius {self.ball.radius:g} m",
                ),
                (c.wall > 0, f"cup wall must be > 0 m, got {c.wall:g}"),
                (
                    0 < c.depth <= c.rim_height,
                    f"cup depth must be in (0, rim height {c.rim_height:g}] m, got {c.depth:g}",
                ),
                (n > 0.5, "cup axis must be a non-zero direction"),
                (
                    self.length > c.extent + self.ball.radius,
                    f"string length {self.length:g} m must exceed the cup's extent + ball radius "
                    f"({c.extent + self.ball.radius:.3f} m)",
                ),
            ]
        for ok, message in checks:
            if not ok:
                raise ValueError(message)

    @property
    def drag(self) -> float:
        """k [1/m] of the ball."""
        return self.ball.drag_per_mass

    @property
    def axis_flange(self) -> Vec3:
        """The cup axis in the flange frame, unit length."""
        a = self.cup.axis if self.cup is not None else (-1.0, 0.0, 0.0)
        n = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
        return (a[0] / n, a[1] / n, a[2] / n)


# -- small vector helpers on 3-tuples ------------------------------------------------------------------------------


def dot(a: Vec3, b: Vec3) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def norm(a: Vec3) -> float:
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def sub(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def axpy(k: float, x: Vec3, y: Vec3) -> Vec3:
    """k·x + y."""
    return (k * x[0] + y[0], k * x[1] + y[1], k * x[2] + y[2])


# -- the laws ------------------------------------------------------------------------------------------------------


def drag_accel(v: Vec3, drag: float) -> Vec3:
    """Air drag acceleration −k·|v|·v [m/s²] of a ball moving at v [m/s] in still air."""
    if drag == 0.0:
        return (0.0, 0.0, 0.0)
    k = -drag * norm(v)
    return (k * v[0], k * v[1], k * v[2])


def taut_accel(
    s: Vec3, sdot: Vec3, pivot_vel: Vec3, pivot_acc: Vec3, length: float, drag: float, damping: float = 0.0
) -> Vec3:
    """s̈ [1/s²] of the taut string: the spherical pendulum (``pendulum.rhs``, viscous ``damping`` [1/s]) plus the
    tangential drag / l."""
    sdd = _rhs_floats(s, sdot, pivot_acc, length, damping)
    if drag == 0.0:
        return sdd
    f = drag_accel(axpy(length, sdot, pivot_vel), drag)
    fr = dot(f, s)
    il = 1.0 / length
    return (sdd[0] + (f[0] - fr * s[0]) * il, sdd[1] + (f[1] - fr * s[1]) * il, sdd[2] + (f[2] - fr * s[2]) * il)


def tension_per_mass(s: Vec3, sdot: Vec3, pivot_vel: Vec3, pivot_acc: Vec3, length: float, drag: float) -> float:
    """String tension / ball mass [m/s²] the taut constraint needs (≤ 0: the string goes slack)."""
    f = drag_accel(axpy(length, sdot, pivot_vel), drag)
    return length * dot(sdot, sdot) + dot(s, (f[0] - pivot_acc[0], f[1] - pivot_acc[1], -G + f[2] - pivot_acc[2]))


def flight_accel(v: Vec3, drag: float) -> Vec3:
    """b̈ [m/s²] of the free ball: gravity and drag."""
    f = drag_accel(v, drag)
    return (f[0], f[1], f[2] - G)


def retension_velocity(s: Vec3, v_rel: Vec3, coefficient: float) -> Vec3:
    """The ball's velocity relative to the anchor after the string tightens along s: v_r > 0 → −e_s·v_r."""
    vr = dot(v_rel, s)
    if vr <= 0.0:
        return v_rel
    return axpy(-(1.0 + coefficient) * vr, s, v_rel)


def cup_gap(rel: Vec3, axis: Vec3, cup: Cup) -> tuple[float, Vec3, int]:
    """Distance [m] from the ball centre at ``rel`` = b − p to the cup's solid (negative inside it), the unit
    normal pointing from the solid to the ball (base frame) and the index of the nearest profile segment
    (0 outer bottom, 1 outer wall, 2 rim top, 3 inner wall, 4 inner bottom)."""
    z = dot(rel, axis)
    radial = axpy(-z, axis, rel)
    rho = norm(radial)
    er = (radial[0] / rho, radial[1] / rho, radial[2] / rho) if rho > 1e-12 else (0.0, 0.0, 0.0)
    best, bn, seg = math.inf, (0.0, 1.0), 0
    for k, (r0, z0, r1, z1) in enumerate(cup.profile()):
        dr, dz = r1 - r0, z1 - z0
        ll = dr * dr + dz * dz
        u = ((rho - r0) * dr + (z - z0) * dz) / ll
        u = 0.0 if u < 0.0 else 1.0 if u > 1.0 else u
        cr, cz = rho - (r0 + u * dr), z - (z0 + u * dz)
        d = math.hypot(cr, cz)
        if d < best:
            best, seg = d, k
            bn = (cr / d, cz / d) if d > 1e-15 else (dz / math.sqrt(ll), -dr / math.sqrt(ll))
    # the solid is the union of two rectangles: inside means inside either
    ri, ro, zb, rim = cup.inner_radius, cup.outer_radius, cup.bottom_height, cup.rim_height
    inside = (0.0 <= z <= zb and rho <= ro) or (ri <= rho <= ro and 0.0 <= z <= rim)
    if inside:
        best = -best
        bn = (-bn[0], -bn[1])
    n = axpy(bn[1], axis, (bn[0] * er[0], bn[0] * er[1], bn[0] * er[2]))
    return best, n, seg


def contact_velocity(v_rel: Vec3, n: Vec3, restitution: float, friction: float) -> Vec3:
    """The ball's velocity relative to the cup after an impact on the normal n (v_rel·n < 0)."""
    vn = dot(v_rel, n)
    if vn >= 0.0:
        return v_rel
    vt = axpy(-vn, n, v_rel)
    st = norm(vt)
    dvt = min(st, friction * (1.0 + restitution) * -vn)
    scale = (st - dvt) / st if st > 0.0 else 0.0
    return axpy(-restitution * vn, n, (vt[0] * scale, vt[1] * scale, vt[2] * scale))


def rest_load(pivot_acc: Vec3, axis: Vec3) -> float:
    """(p̈ − g)·a [m/s²]: the bottom's push on a resting ball per unit mass; ≤ 0: the ball lifts off."""
    return dot(pivot_acc, axis) + G * axis[2]


def in_cup(rel: Vec3, axis: Vec3, cup: Cup) -> bool:
    """The ball centre at ``rel`` = b − p is inside the cup: below the rim plane, within the inner radius."""
    z = dot(rel, axis)
    rho = norm(axpy(-z, axis, rel))
    return cup.bottom_height < z < cup.rim_height and rho < cup.inner_radius


def entry_margin(rel: Vec3, axis: Vec3, cup: Cup, ball_radius: float) -> float:
    """(R − r) − ρ [m] of a ball centre at ``rel``: > 0 it fits through the opening there, < 0 it hits the rim or
    passes outside by that much."""
    z = dot(rel, axis)
    return cup.inner_radius - ball_radius - norm(axpy(-z, axis, rel))


def contact_outcome(
    rel: Vec3, v_rel: Vec3, pivot_acc: Vec3, axis: Vec3, model: StringModel
) -> tuple[bool, Vec3, int, float]:
    """What a touch of the cup does to the ball at ``rel`` = b − p with relative velocity ``v_rel``:
    (rests, new relative velocity, profile segment, normal approach speed [m/s]).

    A ball that meets an upward face (the bottom, the rim top) slower than ``rest_speed`` while the cup pushes it up
    rests there; a faster one bounces (restitution, friction); a slow touch elsewhere (a wall, an edge) leaves with
    ``rest_speed`` along the normal, so that it slides off instead of chattering.
    """
    cup = model.cup
    _, n, seg = cup_gap(rel, axis, cup)
    vn = dot(v_rel, n)
    slow = -vn < model.rest_speed
    if slow and seg in (2, 4) and dot(n, axis) > 0.9 and rest_load(pivot_acc, axis) > 0.0:
        return True, (0.0, 0.0, 0.0), seg, -vn
    v_new = contact_velocity(v_rel, n, 0.0 if slow else model.restitution, model.friction)
    if slow:
        v_new = axpy(model.rest_speed - dot(v_new, n), n, v_new)
    return False, v_new, seg, -vn


def retension_outcome(s: Vec3, v_rel: Vec3, pivot_vel: Vec3, pivot_acc: Vec3, model: StringModel) -> tuple[bool, Vec3]:
    """The string tightens along s with the ball's relative velocity ``v_rel``: (taut afterwards, new relative
    velocity). Taut when the jerk is inelastic and the string then pulls (tension > 0); otherwise the ball stays
    slack (bouncing back along the string with ``retension`` > 0)."""
    v_new = retension_velocity(s, v_rel, model.retension)
    l = model.length
    sd = (v_new[0] / l, v_new[1] / l, v_new[2] / l)
    taut = model.retension == 0.0 and tension_per_mass(s, sd, pivot_vel, pivot_acc, l, model.drag) > 0.0
    return taut, v_new
