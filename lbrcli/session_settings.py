"""The settings of an FRI session the commands run, one frozen object per concern.

:class:`SessionSettings` — the controller, the local socket, the log, the waits, real-time; :class:`SimulatorSettings`
— the embedded simulator (period, start pose, flange and tool, the ball and other plants, quality and lock-step); the
lab's attachments are :class:`lbrcli.lab.attach.LabOptions`; :class:`LogColumns` — the log columns a command adds.
The CLI edge builds them once from the options (:mod:`lbrcli.fri_options`) and hands them to
:func:`lbrcli.fri_runner.run_client`. Each checks itself when it is made and raises
:class:`~trajectories.errors.SettingError` naming the field (``SessionSettings.port``); they never name a flag.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

from trajectories.errors import SettingError
from trajectories.start_poses import THESIS_START

if TYPE_CHECKING:
    from lbrcli.fri import ClientApplication, LBRClient
    from lbrcli.fri.sim import SimConfig
    from lbrcli.plants import BallSpec
    from trajectories.limits import JointLimits

FRI_VERSIONS = ("1.15", "2.7")
SIMULATED_VERSION = "1.15"  # the embedded simulator's wire format unless told otherwise
LOOPBACK = "127.0.0.1"
ROBOT_FIRST_MESSAGE_S = 60.0  # [s] the wait for a robot's first message
SIMULATED_WAIT_S = 20.0  # [s] the waits for the embedded simulator's first message and for its commanding
LENIENT_TRACKING_LAG_S = 0.1  # [s] the lag at full speed the embedded simulator's robot may show on a loaded PC
LENIENT_REPLY_GAP_S = 0.5  # [s] replies the embedded simulator may miss in a row on a loaded PC (strict, robot: 50 ms)
LOCKSTEP_WAIT_S = 0.5  # [s] in lock-step: the longest the simulator waits for a reply (below the client's 1 s silence)


def _check_positive(owner: type, values: dict[str, float | None], unit: str) -> None:
    """SettingError for the first value that is given (not None) and not a finite number > 0."""
    for name, value in values.items():
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise SettingError(owner, name, f"must be > 0 {unit}, got {value!r}")


@dataclass(frozen=True)
class SessionSettings:
    """How the FRI session runs: against a named robot or the embedded simulator, where it listens, what it logs."""

    robot: str | None = None  # the controller's FRI address; None: the embedded simulator on loopback
    port: int = 30200  # local UDP port of the robot's FRI configuration (0: any free port)
    bind: str | None = None  # local IP address to bind (None: loopback with the simulator, all interfaces otherwise)
    version: str | None = None  # FRI wire format "1.15" or "2.7" (None: detected with a robot, 1.15 simulated)
    limits: JointLimits | None = None  # the limits every command is guarded with (None: the default tables)
    log: Path | None = None  # execution log CSV, one row per monitoring message
    wait_s: float | None = None  # [s] for the first FRI message (None: 60 with a robot, 20 simulated)
    duration_s: float | None = None  # [s] from the first message to the end (None: until the client ends it)
    commanding_timeout_s: float | None = None  # [s] for COMMANDING_ACTIVE (None: 20 simulated, unbounded otherwise)
    realtime: bool = False  # the FRI loop as a real-time task (SCHED_FIFO, pinned to a CPU, memory locked)
    busy_wait_s: float = 0.0  # [s] poll the socket this long before each message is due (0: block in the kernel)
    max_tracking_error: float | None = None  # [rad] (None: velocity limit × max(20 ms, 8 command periods))
    send_period_ms: int | None = None  # [ms] the send period a robot must have (None: whatever it sends; simulated:
    # the simulator's, SimulatorSettings.period_ms)

    def __post_init__(self) -> None:
        if not (isinstance(self.port, int) and 0 <= self.port <= 65535):
            raise SettingError(SessionSettings, "port", f"must be a UDP port 0..65535, got {self.port!r}")
        if self.version not in (None, *FRI_VERSIONS):
            raise SettingError(
                SessionSettings, "version", f"must be one of {', '.join(FRI_VERSIONS)}, got {self.version!r}"
            )
        _check_positive(SessionSettings, {"wait_s": self.wait_s, "duration_s": self.duration_s,
                                          "commanding_timeout_s": self.commanding_timeout_s}, "s")  # fmt: skip
        _check_positive(SessionSettings, {"max_tracking_error": self.max_tracking_error}, "rad")
        _check_positive(SessionSettings, {"send_period_ms": self.send_period_ms}, "ms")
        if not (math.isfinite(self.busy_wait_s) and self.busy_wait_s >= 0):
            raise SettingError(SessionSettings, "busy_wait_s", f"must be >= 0 s, got {self.busy_wait_s!r}")

    @property
    def embedded(self) -> bool:
        """No robot named: the session runs against the simulator this process starts on loopback."""
        return self.robot is None

    def application(self, client: LBRClient, observers: Sequence[Any] = (), lenient: bool = False,
                    paced_by_replies: bool = False) -> ClientApplication:  # fmt: skip
        """The :class:`~lbrcli.fri.ClientApplication` of these settings (not bound yet); ``lenient``: the embedded
        simulator judges its quality leniently, so the supervision tolerates the same loaded PC and the client
        answers every message in turn after a stall (the lenient simulator uses late replies) instead of
        catching up with the newest (``catch_up``: against a robot, whose controller bridged the periods missed);
        ``paced_by_replies``: it runs in lock-step (its messages' arrival times are not judged)."""
        from lbrcli.fri import ClientApplication

        sim = self.embedded
        lenient = lenient and sim
        return ClientApplication(
            client, LOOPBACK if sim else self.robot, self.port,  # type: ignore[arg-type]
            bind_host=self.bind if self.bind is not None else (LOOPBACK if sim else ""),
            version=self.version or (SIMULATED_VERSION if sim else None), limits=self.limits, observers=observers,
            first_message_timeout_s=self.wait_s if self.wait_s is not None else (SIMULATED_WAIT_S if sim else ROBOT_FIRST_MESSAGE_S),
            commanding_timeout_s=self.commanding_timeout_s if self.commanding_timeout_s is not None else (SIMULATED_WAIT_S if sim else None),
            max_tracking_error=self.max_tracking_error, busy_wait_s=self.busy_wait_s,
            send_period_s=None if sim or self.send_period_ms is None else self.send_period_ms * 1e-3,
            reply_gap_s=LENIENT_REPLY_GAP_S if lenient else None, tracking_lag_s=LENIENT_TRACKING_LAG_S if lenient else None,
            paced_by_replies=paced_by_replies and sim, catch_up=not lenient,
        )  # fmt: skip


@dataclass(frozen=True)
class SimulatorSettings:
    """The embedded simulator: what it simulates and how it paces the session. Checked as the simulator's own
    configuration (:meth:`config`), so a value is judged by the one rule the simulator applies."""

    period_ms: int = 1  # [ms] send period
    receive_multiplier: int = 1  # the client answers every k-th message
    start: tuple[float, ...] = THESIS_START  # [rad] where the simulated robot stands at start (7 joints)
    flange: str = "touch-electric"  # media flange (trajectories.robot.Flange value)
    tool: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m] TCP offset in the flange frame (the ball hangs there)
    ball: BallSpec | None = None  # the ball on its string hanging from the TCP (None: no ball)
    plants: tuple = ()  # further plant specs after the ball (the pendulum module, the rigid module, a camera)
    limits_path: Path | None = None  # TOML overriding the simulated robot's joint limits
    max_runtime_s: float | None = None  # [s] the simulator stops after this long whatever happens (None: never)
    lenient: bool = True  # quality over 1 s, GOOD at 50 % timely replies (False: as strict as the real controller)
    lockstep: bool = False  # wait for each reply before the next cycle (simulated time advances a period per cycle)
    fast: bool = False  # lock-step as fast as the client answers, not on the period's grid
    loss: float = 0.0  # fault injection: probability of dropping a monitoring message
    malformed: float = 0.0  # fault injection: probability of sending a corrupted datagram instead
    seed: int = 0  # of the fault injection

    def __post_init__(self) -> None:
        from lbrcli.plants import PendulumModuleSpec

        object.__setattr__(self, "start", tuple(float(v) for v in self.start))
        object.__setattr__(self, "tool", tuple(float(v) for v in self.tool))
        if self.ball is None and any(isinstance(p, PendulumModuleSpec) for p in self.plants):
            raise SettingError(SimulatorSettings, "ball", "the pendulum module emulation needs a simulated ball")
        self.config(client_port=30200).validate()

    @property
    def paced_by_replies(self) -> bool:
        """Lock-step (plain or fast): each cycle waits for the client's reply."""
        return self.lockstep or self.fast

    def plant_specs(self) -> tuple:
        """The ball (if any), then the other plants, in the order the simulator builds them."""
        return ((self.ball,) if self.ball is not None else ()) + tuple(self.plants)

    def config(self, client_port: int, version: str | None = None, realtime: bool = False) -> SimConfig:
        """The :class:`~lbrcli.fri.sim.SimConfig` of these settings for a client on loopback ``client_port``."""
        from lbrcli.fri.sim import SimConfig, lenient_quality

        paced = (
            isinstance(self.period_ms, int)
            and isinstance(self.receive_multiplier, int)
            and self.period_ms * self.receive_multiplier > 0
        )
        quality = lenient_quality(self.period_ms, self.receive_multiplier) if self.lenient and paced else {}
        return SimConfig(
            client_port=client_port, version=version or SIMULATED_VERSION, period_ms=self.period_ms,
            receive_multiplier=self.receive_multiplier, q0=self.start, flange=self.flange, tool=self.tool,
            plants=self.plant_specs(), limits_path=str(self.limits_path) if self.limits_path is not None else None,
            max_runtime_s=self.max_runtime_s, realtime=realtime, loss=self.loss, malformed=self.malformed, seed=self.seed,
            lockstep_timeout_s=LOCKSTEP_WAIT_S if self.paced_by_replies else None, lockstep_free=self.fast, **quality,
        )  # fmt: skip


@dataclass(frozen=True)
class LogColumns:
    """Columns a command adds to the execution log: their names and the function giving a row's values from the
    state (:class:`~lbrcli.fri.LBRState`); ``a + b`` puts b's after a's."""

    names: tuple[str, ...] = ()
    values: Callable[[Any], Sequence[float]] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(self.names))
        if self.names and self.values is None:
            raise SettingError(LogColumns, "values", f"columns {', '.join(self.names)} need a function giving them")

    def __add__(self, other: "LogColumns") -> "LogColumns":
        if not other.names:
            return self
        if not self.names:
            return other
        first, second = self.values, other.values
        return LogColumns(self.names + other.names, lambda state: (*first(state), *second(state)))  # type: ignore[misc]
