"""The client base class (KUKA's ``LBRClient``): answer each cycle of an FRI session.

Subclass it and override what you need; the :class:`~lbrcli.fri.application.ClientApplication` calls, for every
monitoring message, ``on_state_change(old, new)`` when the session state changed, then by state ``monitor``
(MONITORING_WAIT/READY), ``wait_for_command`` (COMMANDING_WAIT) or ``command`` (COMMANDING_ACTIVE). In the
commanding states set the joint position (always, as KUKA requires) through ``self.robot_command``, plus torques in
TORQUE mode or a wrench in WRENCH mode (FRI 2.7 CARTESIAN_POSE mode: ``set_cartesian_pose`` instead of joints). ``command`` may instead return the joint position [rad] (7 values).
``after_reply`` runs once the reply is on its way, for work that should not delay it. A client whose next command does
not depend on the next message (a stream of precomputed positions, or a feedback computed in ``after_reply`` from this
message) may say so in ``prepare_command`` (in TORQUE/WRENCH mode with ``prepare_overlay``): its reply then goes out as soon as
the message is checked.
To end the session raise :class:`~lbrcli.fri.errors.StopSession`; the application then brakes within the limits.
Every joint position passes the motion-safety core (:mod:`~lbrcli.fri.motion`): it is clamped into the braking
envelope (``clamped``), or — with ``exact_command`` — a command that would need the clamp ends the session braking.
"""

from __future__ import annotations

from typing import Any, Sequence

from .command import LBRCommand
from .constants import ClientCommandMode, SessionState
from .state import LBRState

_ZERO_TORQUE = (0.0,) * 7
_ZERO_WRENCH = (0.0,) * 6


class LBRClient:
    """Default behaviour: watch in the monitoring states, hold the robot where its application holds it (the ipo
    position, zero torque or wrench) in the commanding states."""

    robot_state: LBRState  # set by the application before the first callback
    robot_command: LBRCommand
    reply_due: bool = True  # set by the application: this cycle's command is sent (every k-th message)
    command_period_s: float | None = None  # set by the application from the first message outside IDLE: [s] send
    # period × receive multiplier, the period of the commands (None while unknown, or if the controller sends none)
    skipped: int = 0  # set by the application: command periods the controller bridged since the last command
    # (its messages to us were lost; it extrapolated) — a client that follows time should advance by them
    replies_lost: int = 0  # set by the application: our last command had not reached the controller when it sent
    # this message (its reflected counter says so): it bridged that period, or executes the command late; the
    # motion-safety core admits the next commands only if they suit either
    braking: bool = False  # set by the application: it brakes to a stop this cycle (the callbacks are not called)
    phase: int = 0  # free for the client: logged per cycle (e.g. which part of a trajectory is playing)
    row: int = -1
    # the motion-safety core: every joint position is admitted only if a braking stop from the state it creates stays
    # inside the limits; a command outside is clamped to that envelope (``clamped`` is set for that cycle) …
    exact_command: bool = False  # … unless the client sets this: then the session ends with a braking stop instead
    jerk_limited: bool = False  # the clamp also keeps the command within the jerk limit of what was executed
    replans: bool = False  # after a command the controller bridged, re-plan from ``executed`` when its ``replan_due``
    # is set (rather than the core taking the motion back onto this client's path by an offset)
    clamped: bool = False  # set by the application: the last command sent was clamped into the envelope
    executed: Any = None  # set by the application (ExecutedMotion, once the period is known): the executed
    # position [rad], velocity [rad/s] and acceleration [rad/s²] — the controller's extrapolation included — to
    # re-plan from after lost messages (``skipped``) or a clamp

    def on_state_change(self, old: SessionState, new: SessionState) -> None:
        """The session state changed from ``old`` to ``new`` (first call: old = IDLE)."""

    def monitor(self, state: LBRState) -> None:
        """MONITORING_WAIT or MONITORING_READY: nothing to command (IO outputs may be written)."""

    def wait_for_command(self, state: LBRState) -> None:
        """COMMANDING_WAIT: the controller waits for commands consistent with its ipo position."""
        self.hold_ipo(state)

    def command(self, state: LBRState) -> Sequence[float] | None:
        """COMMANDING_ACTIVE: set this cycle's command (or return the joint position [rad])."""
        self.hold_ipo(state)
        return None

    def prepare_command(self) -> Sequence[float] | None:
        """Optional, for lower latency: the joint position [rad] the next ``command`` call will set if the next
        message is the expected one (no lost messages, still COMMANDING_ACTIVE, POSITION mode, receive multiplier 1)
        — whatever that message says — or None (the default: ``command`` decides when the message is there). Called
        after each reply; the application guards the prepared position then and sends it as soon as the message
        arrives, before calling ``command`` with it, which must set exactly that position and nothing else (else
        the session ends with a braking stop). A stream of precomputed positions prepares; so can a closed loop that
        computes its next command in ``after_reply`` from this message (one period more of delay). In TORQUE or
        WRENCH mode the reply is prepared only when ``prepare_overlay`` also gives the torque or wrench."""
        return None

    def prepare_overlay(self) -> Sequence[float] | None:
        """Optional, with ``prepare_command`` in TORQUE or WRENCH mode: the torque [Nm] (7 values) or wrench [N, Nm]
        (6 values) the next ``command`` call will set beside the prepared position, or None (the default: that
        cycle's reply is made when the message is there). Guarded with the prepared position; ``command`` must set
        exactly this torque or wrench (else the session ends with a braking stop)."""
        return None

    def after_reply(self) -> None:
        """This cycle's reply has gone out: work that must not delay the command (publishing the state, say).
        Called every answered cycle, also while the application brakes (``braking``). A :class:`StopSession` here
        ends the session from the next cycle."""

    def hold_ipo(self, state: LBRState) -> None:
        """Command the ipo position, and zero torque / wrench in TORQUE / WRENCH mode; the ipo pose (and E1) in
        CARTESIAN_POSE mode (KUKA's default)."""
        cmd = self.robot_command
        mode = state.message.ipoData.clientCommandMode
        if mode == ClientCommandMode.CARTESIAN_POSE:
            cmd.set_cartesian_pose(state.ipo_cartesian_pose)
            return
        cmd.set_joint_position(state.message.ipoData.jointPosition.value)
        if mode == ClientCommandMode.TORQUE:
            cmd.set_torque(_ZERO_TORQUE)
        elif mode == ClientCommandMode.WRENCH:
            cmd.set_wrench(_ZERO_WRENCH)
