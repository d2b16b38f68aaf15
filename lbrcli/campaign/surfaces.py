"""Every surface that moves the robot, as a client the scripted controller can run, with the world it needs: the
point-to-point move (``lbr ptp``), the bridge's follower fed by a UDP source (``lbr serve``), the damper fed by a
simulated ball (``lbr control damp``), the upright controller fed by a simulated pendulum module (``lbr control
upright``), TORQUE and WRENCH overlays (KUKA's sine overlays), and a user's own naive clients. The CSV player
(``lbr execute``) has its own cases (:mod:`lbrcli.campaign.execute`).

Each surface gives its client, its session length, the COMMANDING_ACTIVE cycle where faults strike (mid-motion),
its own ends, and hooks; :func:`surface_cases` crosses it with the controller's faults and adds its own (faulty
sources and sensors)."""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Callable

import numpy as np

from lbrcli.fri import ClientCommandMode, EndReason, LBRClient, StopSession
from lbrcli.fri.testing import CA, Cycle, active, preamble
from lbrcli.fri.testing.campaign import Case, Run
from trajectories.limits import default_limits
from trajectories.start_poses import THESIS_START

from .faults import NORMAL, PREAMBLE, Fault, controller_faults

LIM = default_limits()
Q0 = THESIS_START  # [rad]
DIRECTION = np.array([1, 0.5, -0.5, 1, 0.3, -1, 1])
REFUSED = (EndReason.CLIENT_REFUSED, EndReason.GUARD)


@dataclass
class Surface:
    name: str
    client: Callable[[], LBRClient]
    n: int  # COMMANDING_ACTIVE cycles in the script
    at: int  # where faults strike
    ends: tuple[EndReason, ...]  # its own ends
    mode: int = 1  # clientCommandMode of the script (1 POSITION, 2 WRENCH, 3 TORQUE)
    inputs: Callable[[int, Run], dict[str, float]] | None = None
    on_cycle: Callable[[int, Run], None] | None = None
    around: Callable[[Run], Any] | None = None
    log_extra: Callable[[LBRClient], tuple[tuple[str, ...], Callable | None]] | None = None
    own: list[Case] = field(default_factory=list)  # surface-specific cases
    jerk_judged: bool = True  # (Case.jerk_judged)


def _case(s: Surface, name: str, category: str, script: list[Cycle], ends: tuple, **kw: Any) -> Case:
    expect = tuple(e for e in ends if e != NORMAL) + (s.ends if NORMAL in ends else ())
    base = dict(client=s.client, expect=expect, surface=s.name, inputs=s.inputs, on_cycle=s.on_cycle,
                around=s.around, log_extra=s.log_extra, q_start=Q0, jerk_judged=s.jerk_judged)  # fmt: skip
    base.update(kw)
    return Case(f"{s.name}: {name}", category, script, **base)


def _with_mode(script: list[Cycle], mode: int) -> list[Cycle]:
    if mode == 1:
        return script
    return [Cycle(**{**c.__dict__, "mode": mode}) if c.raw is None else c for c in script]


def _interrupt_at(i_at: int, reason: EndReason, then: Callable[[int, Run], None] | None):
    def hook(i: int, run: Run) -> None:
        if then is not None:
            then(i, run)
        if i == i_at:
            run.app.interrupt(reason)

    return hook


def surface_cases(s: Surface, faults: list[Fault] | None = None) -> list[Case]:
    """The surface crossed with the controller's faults, then its own cases."""
    out = []
    for f in faults if faults is not None else controller_faults():
        script = _with_mode(f.script(s.n, s.at), s.mode)
        kw: dict[str, Any] = {}
        if f.signal is not None:
            kw["on_cycle"] = _interrupt_at(PREAMBLE + s.at, f.signal, s.on_cycle)
        if f.full_disk:
            kw["full_disk_at"] = PREAMBLE + s.at
        # (TORQUE and WRENCH overlays run in the controller's impedance control: a push is theirs to take)
        ends = (NORMAL,) if f.category == "pushed" and s.mode != 1 else f.ends
        out.append(_case(s, f.name, f.category, script, ends, **kw))
    return out + s.own


# -- lbr ptp -----------------------------------------------------------------------------------------------------
def ptp_surface() -> Surface:
    """A 1 s jerk-limited move to a goal 0.4 rad away (per joint, scaled), held 0.2 s (``lbr ptp`` at its defaults)."""
    from lbrcli.fri import TrajectoryPlayer

    goal = np.array(Q0) + 0.4 * DIRECTION / np.abs(DIRECTION).max()

    def make(target=goal, time_s: float = 1.0) -> Callable[[], LBRClient]:
        return lambda: TrajectoryPlayer(np.asarray(target)[None, :], LIM, start_tolerance=math.inf, move_to_start=True,
                                        move_scale=0.2, move_minimum_duration=time_s, settle_s=0.2,
                                        finish_text="reached Q and settled")  # fmt: skip

    s = Surface("ptp", make(), 1700, 400, (EndReason.FINISHED,))
    lossy = {k: Cycle(state=CA, seq_jump=1) for k in range(0, 1700, 20)}  # 5 % of the messages lost
    s.own = [
        _case(s, "5 % of messages lost", "loss", preamble() + active(1800, lossy), (EndReason.FINISHED,)),
        _case(
            s,
            "2 s move with 5 % lost",
            "loss",
            preamble() + active(3000, lossy),
            (EndReason.FINISHED,),
            client=make(goal, 2.0),
        ),  # fmt: skip
        _case(
            s,
            "goal 1e-6 rad inside A4's limit",
            "limits",
            preamble() + active(2500),
            (EndReason.FINISHED,),
            client=make(tuple(Q0[:3]) + (-LIM.position[3] + 1e-6,) + tuple(Q0[4:]), 1.0),
        ),  # fmt: skip
    ]
    return s


# -- lbr serve ----------------------------------------------------------------------------------------------------
def _wave(t: float) -> np.ndarray:
    """The source's joint target at ``t`` [s]: A1 and A4 swinging (≈ 0.6 of their velocity limits)."""
    q = np.array(Q0)
    q[0] += 0.3 * math.sin(2 * math.pi * 0.5 * t)
    q[3] += 0.3 * math.sin(2 * math.pi * 0.5 * t)
    return q


@dataclass
class Source:
    """How the campaign's UDP source behaves: every ``every`` cycles a target, a fault from ``at`` on."""

    every: int = 1
    fault: str | None = None  # nan, beyond, stale, spoof, garbage, dead, flood, foreign-garbage, near-limit
    at: int = 600  # COMMANDING_ACTIVE cycle of the fault
    end_at: int = 1500  # the end message


def _serve_client() -> LBRClient:
    """The bridge's follower (speed scale 0.5, dead-man 0.5 s) reading targets from a UDP port of its own."""
    from lbrcli.bridge.follower import TargetFollower
    from lbrcli.bridge.udp import UdpTargets

    # the dead-man at 0.5 s: in lock-step a loaded machine runs the controller's cycles slower than real time
    return TargetFollower(UdpTargets(0, "127.0.0.1", limits=LIM), LIM, timeout_s=0.5, first_target_s=5.0,
                          speed_scale=0.5)  # fmt: skip


def _serve_around(src: Source) -> Callable[[Run], Any]:
    """The session's world: the source (and another sender) on the follower's port, behaving as ``src`` says."""
    from lbrcli.bridge.client import BridgeClient

    @contextlib.contextmanager
    def around(run: Run):
        client: Any = run.client
        port = client.source.port
        run.state["src"] = BridgeClient("127.0.0.1", port)
        run.state["other"] = BridgeClient("127.0.0.1", port)
        run.state["cfg"] = src
        try:
            yield
        finally:
            run.state["closed"] = True  # the controller's thread may run a few cycles more
            run.state["src"].close()
            run.state["other"].close()
            client.source.close()

    return around


def _serve_source_cycle(i: int, run: Run) -> None:
    """Before script cycle ``i``: what the source (and the other sender) sends, its fault included."""
    if run.state.get("closed"):
        return
    cfg: Source = run.state["cfg"]
    k = i - PREAMBLE + 5  # the source starts a little before commanding
    if k < 0:
        return
    src, other = run.state["src"], run.state["other"]
    t = k * 1e-3
    if k == cfg.end_at:
        src.sock.sendto(b'{"end": true}', src.address)
        return
    if k > cfg.end_at or k % cfg.every:
        return
    f = cfg.fault if k >= cfg.at else None
    if f == "dead":
        return
    q = _wave(t)
    if f == "nan":
        q[2] = math.nan
    elif f == "beyond":
        q[3] = -LIM.position[3] - 0.05
    elif f == "near-limit":
        q[3] = -LIM.position[3] + 1e-6
    if f == "stale":  # a replay of old targets (their counters are behind)
        seq = src.seq
        src.seq = max(0, seq - 50)
        src.send_joint(q, t=t)
        src.seq = seq
    if f == "garbage":
        src.sock.sendto(b"hello", src.address)
        return
    if f == "foreign-garbage":
        other.sock.sendto(b"hello", other.address)
    if f == "spoof":
        other.send_joint(_wave(t + 0.5), t=t)
    src.send_joint(q, t=t)
    if f == "flood":
        for _ in range(50):
            src.send_joint(q, t=t)


def serve_surface() -> Surface:
    """The bridge's follower (speed scale 0.5, dead-man 0.5 s) fed by a UDP source in lock-step with the controller."""
    base = Source()
    s = Surface(
        "serve",
        _serve_client,
        2000,
        600,
        (EndReason.FINISHED,),
        on_cycle=_serve_source_cycle,
        around=_serve_around(base),
    )
    s.own = []
    for name, cfg, ends in [
        ("1 kHz source", Source(), (EndReason.FINISHED,)),
        ("30 Hz source", Source(every=33), (EndReason.FINISHED,)),
        ("NaN target", Source(fault="nan"), REFUSED),
        ("target beyond A4's limit", Source(fault="beyond"), REFUSED),
        ("target 1e-6 rad inside A4's limit", Source(fault="near-limit"), (EndReason.FINISHED,)),
        ("replayed old targets", Source(fault="stale"), (EndReason.FINISHED,)),
        ("another source spoofs targets", Source(fault="spoof"), (EndReason.FINISHED,)),
        ("another source sends garbage", Source(fault="foreign-garbage"), (EndReason.FINISHED,)),
        ("the owner sends garbage", Source(fault="garbage"), REFUSED),
        ("the source dies mid-motion", Source(fault="dead"), (EndReason.CLIENT_REFUSED,)),
        ("the source floods 50 per cycle", Source(fault="flood"), (EndReason.FINISHED,)),
        ("dead source at 30 Hz", Source(every=33, fault="dead"), (EndReason.CLIENT_REFUSED,)),
    ]:  # fmt: skip
        s.own.append(_case(s, name, "sources", preamble() + active(2000), ends, around=_serve_around(cfg)))
    bursts = {k: Cycle(state=CA, seq_jump=5 + k % 5) for k in range(700, 760, 6)}
    s.own.append(_case(s, "bursts of 5–9 lost while following", "bursts", preamble() + active(2000, bursts),
                       (EndReason.FINISHED, EndReason.SUPERVISION)))  # fmt: skip
    return s


# -- lbr control damp ---------------------------------------------------------------------------------------------
@lru_cache(maxsize=1)
def _damp_plan():
    """A crane-like rest-to-rest move of the thesis start pose (2 s), its correction tables and the TCP model."""
    from planners.feedback.correction import correction_plan
    from trajectories.robot import Robot

    robot = Robot()
    s = np.linspace(0.0, 1.0, 2000)
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    rows = np.array(Q0) + p[:, None] * np.array([0.5, 0.15, 0, -0.2, 0, 0.05, 0])
    return rows, correction_plan(robot, rows, LIM, 1e-3), robot


@dataclass
class Sensor:
    """The ball's angles as the damper reads them: ``fault`` from COMMANDING_ACTIVE cycle ``at`` on."""

    fault: str | None = None  # still (reads 0), noise, frozen, jump, nan, reversed, late
    at: int = 900
    length: float = 0.3  # [m] the real string (the damper assumes 0.3 m)


def _ball_inputs(sensor: Sensor):
    """Analog inputs ball_theta_x/y from a simulated ball hanging from the TCP the scripted robot executes."""
    from lbrcli.fri.sim.plant import PlantContext
    from lbrcli.plants.ball import BallSpec

    def inputs(i: int, run: Run) -> dict[str, float]:
        st = run.state
        if "ball" not in st:
            _, _, robot = _damp_plan()
            st["ball"] = BallSpec(sensor.length).build(PlantContext(1e-3, robot, Q0))
            st["robot"] = robot
            st["late"] = []
        q = run.controller.q
        ang = st["ball"].step(0.0, st["robot"].fk(np.asarray(q)).translation.tolist())
        x, y = ang[2], ang[3]
        k = i - PREAMBLE
        f = sensor.fault if k >= sensor.at else None
        rng = st.setdefault("rng", np.random.default_rng(i))
        if sensor.fault == "still":
            x = y = 0.0
        elif f == "noise":
            x, y = x + rng.normal(0, 0.01), y + rng.normal(0, 0.01)
        elif f == "frozen":
            x, y = st.setdefault("frozen", (x, y))
        elif f == "jump":
            x, y = x + 0.35, y - 0.35
        elif f == "nan":
            x = math.nan
        elif sensor.fault == "reversed":
            x, y = -x, -y
        elif sensor.fault == "late":
            st["late"].append((x, y))
            x, y = st["late"][max(0, len(st["late"]) - 30)]
        return {"ball_theta_x": x, "ball_theta_y": y, "ball_theta": math.hypot(x, y) if x == x else math.nan}

    return inputs


def damp_surface() -> Surface:
    """``lbr control damp`` with the analog-input sensor: the rows, 1 s of damping after them, the return."""
    from lbrcli.control.damping import LOG_COLUMNS, DampingClient

    def make() -> LBRClient:
        rows, plan, _ = _damp_plan()
        return DampingClient(rows, LIM, 1e-3, 0.3, plan, damp_s=3.3, sensor_delay_s=0.002, start_tolerance=1e-3)

    def extra(client: Any):
        return LOG_COLUMNS, lambda state: client.log_values()

    s = Surface("damp", make, 9000, 900, (EndReason.FINISHED,), inputs=_ball_inputs(Sensor()), log_extra=extra)
    s.own = [
        _case(s, f"sensor {name}", "sensors", preamble() + active(9000), ends, inputs=_ball_inputs(sensor))
        for name, sensor, ends in [
            ("reads 0 (the ball hangs still for it)", Sensor("still"), (EndReason.CLIENT_REFUSED,)),
            ("noise 0.6°", Sensor("noise"), (EndReason.FINISHED,)),
            ("freezes mid-move", Sensor("frozen"), (EndReason.CLIENT_REFUSED,)),
            ("jumps 20°", Sensor("jump"), (EndReason.CLIENT_REFUSED,)),
            ("NaN", Sensor("nan"), REFUSED),
            ("reversed sign", Sensor("reversed"), (EndReason.CLIENT_REFUSED,)),
            ("30 ms late", Sensor("late"), (EndReason.FINISHED,)),
            ("string 20 % shorter", Sensor(length=0.24), (EndReason.FINISHED,)),
        ]
    ]  # fmt: skip
    return s


# -- lbr control upright ------------------------------------------------------------------------------------------
@lru_cache(maxsize=1)
def _rail():
    from planners.rail import build_rail
    from trajectories.robot import Robot

    return build_rail(Robot(), Q0, LIM, 0.3), Robot()


@dataclass
class Encoder:
    """The module's encoder as the controller reads it: 12 bits at 200 Hz, 6 ms late; ``fault`` from ``at`` on."""

    fault: str | None = None  # noise, frozen, reversed, jump, dropout, offset
    at: int = 6500
    rod: float = 0.4  # [m] the real rod (the controller assumes 0.4 m)


class _Reader:
    latest: Any = None


def _module(encoder: Encoder):
    """The simulator's pendulum module (a rigid rod on the flange driven by the TCP the scripted robot executes) and
    the reader the controller polls: 12-bit counts every 5 ms, 6 ms late, with ``encoder``'s fault."""
    import time

    from lbrcli.fri.sim.plant import PlantContext
    from lbrcli.lab.pendulum_serial import PendulumReading
    from lbrcli.plants.rigid_module import RigidModuleSpec
    from planners.rigid_pendulum import RigidPendulum, wrap_angle

    counts = 4096

    def hook(i: int, run: Run) -> None:
        st = run.state
        rail, robot = _rail()
        if "rod" not in st:
            spec = RigidModuleSpec(RigidPendulum(rod_length=encoder.rod), rate_hz=200.0, delay_ms=6.0, jitter_ms=0.0)
            st["rod"] = spec.build(PlantContext(1e-3, robot, Q0))
            st["queue"] = []
            st["rng"] = np.random.default_rng(7)
            run.client.reader = st["reader"] = _Reader()  # type: ignore[attr-defined]
        pose = robot.fk(np.asarray(run.controller.q))
        phi, omega = st["rod"].step(i * 1e-3, pose.translation.tolist(), pose.rotation)
        k = i - PREAMBLE
        if i % 5 == 0:  # a reading every 5 ms, delivered 6 ms later
            f = encoder.fault if k >= encoder.at else None
            count = round(phi / (2 * math.pi) * counts)
            if encoder.fault == "noise2":
                count += int(st["rng"].integers(-2, 3))
            if f == "offset":
                count += 40
            if encoder.fault == "reversed":
                count, omega = -count, -omega
            if f == "jump":
                count += 600
            theta = wrap_angle(count * 2 * math.pi / counts)
            if f == "frozen":
                theta, omega = st.setdefault("frozen", (theta, 0.0))
            if f != "dropout" or k > encoder.at + 500:
                st["queue"].append((i + 6, theta, omega))
        while st["queue"] and st["queue"][0][0] <= i:
            _, theta, omega = st["queue"].pop(0)
            st["reader"].latest = PendulumReading(time.monotonic(), theta, omega)

    return hook


_FITTER: Any = None


def _fitter():
    """One identification worker for the whole campaign (spawned once, stopped at exit: a pool left to the
    interpreter's teardown printed an ignored AttributeError traceback)."""
    global _FITTER
    if _FITTER is None:
        import atexit

        from lbrcli.control.fitter import ProcessFitter

        _FITTER = ProcessFitter()
        atexit.register(_FITTER.close)
    return _FITTER


def upright_surface() -> Surface:
    """``lbr control upright`` (rod 0.4 m: identified, swung up within 4 s, balanced 2 s, lowered) on a simulated
    module."""
    from lbrcli.control.upright import LOG_COLUMNS, UprightClient
    from planners.feedback.session import SessionOptions
    from planners.rigid_pendulum import RigidPendulum

    def make() -> LBRClient:
        rail, _ = _rail()
        opts = SessionOptions(hold_s=2.0, swing_timeout_s=6.0, recatch_s=4.0, wait_s=2.0, lower_ramp_s=3.0,
                              lower_timeout_s=8.0)  # fmt: skip
        return UprightClient(rail, RigidPendulum(rod_length=0.4).equivalent_length, LIM, session=opts,
                             fitter=_fitter())  # fmt: skip

    def extra(client: Any):
        return LOG_COLUMNS, lambda state: client.log_values()

    ends = (EndReason.FINISHED, EndReason.CLIENT_REFUSED)
    n = 26000  # the move, the wait, the identification (≈ 5 s), the swing-up, the hold, the lowering and the park
    s = Surface("upright", make, n, 6500, ends, on_cycle=_module(Encoder()), log_extra=extra)
    s.own = [
        _case(s, f"encoder {name}", "sensors", preamble() + active(n), ends, on_cycle=_module(enc))
        for name, enc in [
            ("noise ±2 counts", Encoder("noise2")),
            ("freezes while swinging", Encoder("frozen")),
            ("reversed sign", Encoder("reversed")),
            ("jumps 53°", Encoder("jump")),
            ("drops out for 0.5 s", Encoder("dropout")),
            ("zero 3.5° off", Encoder("offset", at=0)),
            ("rod 20 % shorter", Encoder(rod=0.32)),
        ]
    ]  # fmt: skip
    return s


# -- TORQUE and WRENCH overlays -----------------------------------------------------------------------------------
class _EffortOverlay(LBRClient):
    """KUKA's sine overlays: the ipo position plus a torque on every joint, or a wrench; ends after ``n`` cycles."""

    def __init__(self, mode: int, n: int, amplitude: float) -> None:
        self.mode, self.n, self.amplitude, self.k = mode, n, amplitude, 0

    def _effort(self) -> tuple[float, ...]:
        s = math.sin(2 * math.pi * self.k * 1e-3)
        if self.mode == ClientCommandMode.TORQUE:
            return tuple(self.amplitude * s * min(1.0, t / 40.0) for t in LIM.torque)
        a = self.amplitude  # [N] the force's amplitude; moments a tenth of it [Nm]
        return (a * s, -a * s, 0.5 * a * s, 0.1 * a * s, -0.1 * a * s, 0.05 * a * s)

    def command(self, state):
        self.hold_ipo(state)
        self.k += 1
        if self.k > self.n:
            raise StopSession("overlay done", completed=True)
        if self.mode == ClientCommandMode.TORQUE:
            self.robot_command.set_torque(self._effort())
        else:
            self.robot_command.set_wrench(self._effort())


def effort_surface(mode: int) -> Surface:
    name = "torque" if mode == ClientCommandMode.TORQUE else "wrench"
    nominal = 39.6 if mode == ClientCommandMode.TORQUE else 19.8  # [Nm] KUKA's torque example; [N] within 20 N
    s = Surface(name, lambda: _EffortOverlay(mode, 1000, nominal), 1700, 300, (EndReason.FINISHED,), mode=int(mode))
    beyond = 45.0 if mode == ClientCommandMode.TORQUE else 25.0
    s.own = [_case(s, f"{name} beyond its bound", "limits", _with_mode(preamble() + active(1700), int(mode)),
                   (EndReason.GUARD,), client=lambda: _EffortOverlay(mode, 1000, beyond))]  # fmt: skip
    return s


# -- a user's own client ------------------------------------------------------------------------------------------
class _Naive(LBRClient):
    """What a user might write first: a sine on every joint from the first ipo position, ``amplitude`` [rad] at
    ``freq`` [Hz], maybe broken at cycle ``broken_at`` (NaN, an exception, a jump); ends after ``n`` cycles."""

    def __init__(self, amplitude: float, freq: float, n: int, broken: str | None = None, broken_at: int = 400) -> None:
        self.amplitude, self.freq, self.n, self.broken, self.broken_at = amplitude, freq, n, broken, broken_at
        self.k = 0
        self.q0: tuple[float, ...] | None = None

    def command(self, state):
        if self.q0 is None:
            self.q0 = state.ipo_joint_position
        self.k += 1
        if self.k > self.n:
            raise StopSession("done", completed=True)
        t = self.k * 1e-3
        q = [a + self.amplitude * math.sin(2 * math.pi * self.freq * t) for a in self.q0]
        if self.broken and self.k >= self.broken_at:
            if self.broken == "nan":
                q[2] = math.nan
            elif self.broken == "raise":
                raise RuntimeError("bug in the user's client")
            elif self.broken == "jump":
                q[3] += 0.2
            elif self.broken == "limit":
                q[0] = LIM.position[0] + 0.5
        return q


def user_surface() -> Surface:
    ends = (EndReason.FINISHED,)
    s = Surface("user", lambda: _Naive(0.2, 1.0, 1500), 2500, 600, ends, jerk_judged=False)
    s.own = [
        _case(s, name, "user clients", preamble() + active(2500), e, client=make)
        for name, make, e in [
            ("sine 0.5 rad at 3 Hz (5× the velocity limit)", lambda: _Naive(0.5, 3.0, 1500), ends),
            ("returns NaN", lambda: _Naive(0.2, 1.0, 1500, "nan"), (EndReason.GUARD,)),
            ("raises", lambda: _Naive(0.2, 1.0, 1500, "raise"), (EndReason.CLIENT_ERROR,)),
            ("jumps 0.2 rad", lambda: _Naive(0.2, 1.0, 1500, "jump"), ends),
            ("asks for A1 beyond its limit", lambda: _Naive(0.0, 1.0, 1500, "limit"), ends),
        ]
    ]  # fmt: skip
    return s


def all_surfaces() -> list[Surface]:
    return [ptp_surface(), serve_surface(), damp_surface(), upright_surface(),
            effort_surface(ClientCommandMode.TORQUE), effort_surface(ClientCommandMode.WRENCH), user_surface()]  # fmt: skip
