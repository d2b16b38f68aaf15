"""How a cycle's reply is made, mixed into :class:`~lbrcli.fri.application.ClientApplication`: the guarded command
written into the message, replies prepared one cycle ahead, and the rest of the cycle after the reply (counters,
supervision, the hold after a braking stop, the observers).

A client that knows its next command before the next message (``LBRClient.prepare_command``: a stream of
precomputed positions) has it guarded and encoded right after the current cycle, with the next sequence counter.
When that message arrives it is decoded and checked as every message (self-consistent, the robot side has not ended
the session), and the prepared reply goes out at once; the client's ``command`` call, which must set the same
position, and the rest of the cycle follow. Any other message (lost ones before it, a state change, a stop) takes
the full cycle. Supervision judges each message after its reply: a problem it finds brakes from the next command.

FRI 2.7: in CARTESIAN_POSE mode the client's pose is turned into joints (:class:`~lbrcli.fri.cartesian.PoseSolver`,
the TCP of the application's ``tcp_robot``: a ``trajectories.robot.Robot``, default the Touch Electric flange without
a tool) which pass the same core and guard as joint commands — a pose that cannot be reached or jumps is refused like
a joint command — and the pose of the admitted joints goes out (a braking stop's too). The application's
``transformation_client`` provides the frames the robot application requests (:mod:`~lbrcli.fri.transformation`):
called for every message but IDLE after the robot client, as KUKA's ``ClientApplication::step``.
"""

from __future__ import annotations

import time
from typing import Any

from .command import LBRCommand
from .constants import ClientCommandMode
from .motion import ExecutedMotion, Refused
from .outcome import EndReason, Outcome
from .supervision import Supervisor, commanding_end, consistent

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE

CLIENT_CLAMP = 1e-4  # [rad] a clamp the client is told about (``LBRClient.clamped``)
_POSITION = int(ClientCommandMode.POSITION)
_TORQUE = int(ClientCommandMode.TORQUE)
_WRENCH = int(ClientCommandMode.WRENCH)
_CARTESIAN = int(ClientCommandMode.CARTESIAN_POSE)

Prepared = tuple[int, bytes, tuple[float, ...]]  # (sequence counter it answers, datagram, joint position [rad])
Supervised = tuple[bool, bool, Any, int]  # (commanding, moving, command in force [rad], our last sequence counter)


class Replying:
    """The reply of a cycle and what follows it (state it reads is set by the application)."""

    client: Any
    cycle: Any
    transport: Any
    prepares: bool
    prepared_replies: int
    answered: int
    cycles: int
    active_cycles: int
    position_commands: int
    _clock: Any
    _motion: ExecutedMotion | None
    _sup: Supervisor | None
    _reply: Any
    _cmd: Any
    _stop: Any
    _ended: bool
    _prepared: Prepared | None
    _poses: Any = None  # the PoseSolver, built at the first Cartesian command
    transformation_client: Any
    tcp_robot: Any
    limits: Any
    _client_seq: int
    _reply_seq_prev: int | None
    _last_seq: int
    _answered_any: bool
    _unanswered_at_start: int
    missed: int
    _latencies: list[int]
    state: Any
    _last_data: bytes | None
    _codec: Any
    _mon: Any
    _bound: Any

    def _send_prepared(self, prepared: Prepared, mon: Any, seq: int, now: float, t_rx: int) -> bool | None:
        """Send the prepared reply to this expected message unless the robot side ended the session; the step's
        result, or None for the full cycle."""
        if commanding_end(mon, CMD_ACTIVE, True, self._clock.period_key) is not None:
            return None  # the full cycle ends the session with it
        try:
            self.transport.send(prepared[1])
        except OSError as exc:
            self._finish(Outcome.STOPPED, EndReason.SILENT, f"cannot send to the controller: {exc.strerror}")  # type: ignore[attr-defined]
            return False
        self._latencies.append(time.perf_counter_ns() - t_rx)
        return self._after_prepared(now, mon, seq, prepared[2])

    def _after(self, now: float, mon: Any, seq: int, supervised: Supervised, answered: bool) -> bool:
        """The cycle after its reply went out (or was not due): counters, supervision, the hold, observers, and
        the next cycle's prepared reply."""
        sup = self._sup
        if answered:
            self._call_client("after_reply")
            if sup is not None:
                sup.sent(self._client_seq, seq)
            if self.cycle.sent_position and self.cycle.state == CMD_ACTIVE:
                self._reply_seq_prev = self._client_seq
            if not self._answered_any:
                self._answered_any = True
                self._unanswered_at_start = self.missed  # messages that went by before the first reply
            self._client_seq = (self._client_seq + 1) & 0xFFFFFFFF
            self.answered += 1
            self.cycle.answered = True
            if self.cycle.sent_position:
                self.position_commands += 1
        state = self.cycle.state
        if sup is not None and self._stop is None:
            commanding, moving, command, last_sent = supervised
            stamp = getattr(self.transport, "received_ns", None)
            problem = sup.check(mon, seq, commanding, moving, mon.ipoData.clientCommandMode in (_POSITION, _CARTESIAN), command,
                                last_sent, stamp() if stamp is not None else None)  # fmt: skip
            if problem is not None:
                if sup.measured_period_s is not None and self._motion is not None:
                    self._motion.retime(sup.measured_period_s)  # brake at the period the robot really runs at
                self._stop_braking(Outcome.STOPPED, EndReason.SUPERVISION, f"supervision: {problem}")
        if answered and self._motion is not None and self._motion.held_long_enough():
            self._finish(*self._stop, observe=True)  # type: ignore[misc]
            return False
        self._observe()  # type: ignore[attr-defined]
        if state == CMD_ACTIVE and self.prepares:
            self._prepare(seq, mon)
        return self._check_clocks(now)  # type: ignore[attr-defined]

    def _after_prepared(self, now: float, mon: Any, seq: int, q: tuple[float, ...]) -> bool:
        """The rest of a cycle answered with the prepared reply carrying ``q`` [rad]: what the full cycle records,
        and the client's ``command`` call, which must set that same position."""
        clock = self._clock
        clock.received(now, 1, mon.connectionInfo.sendPeriod)
        self._last_seq = seq
        self.cycles += 1
        self.active_cycles += 1
        motion = self._motion
        supervised = (True, motion.moving, motion.prev, self.client_sequence)  # type: ignore[union-attr]
        cyc = self.cycle
        cyc.begin(clock.t, CMD_ACTIVE)
        motion.sent(q, CMD_ACTIVE)  # type: ignore[union-attr]  # before the client's call: a stop brakes from q
        client = self.client
        client.reply_due = True
        client.skipped = 0
        client.braking = False
        cmd = self._cmd
        cmd.reset()  # type: ignore[union-attr]
        got = self._call_client("command", self.state)
        if got is None:
            got = cmd.joint_position  # type: ignore[union-attr]
        if self._stop is None and (got is None or tuple(got) != q or cmd.torque is not None or cmd.wrench is not None  # type: ignore[union-attr]
                                   or cmd.io_writes):  # type: ignore[union-attr]  # fmt: skip
            self._stop_braking(Outcome.FAILED, EndReason.CLIENT_ERROR, "the client's prepare_command() did not predict "
                               "its command(): prepared a joint position, command() set "
                               + ("another one" if got is None or tuple(got) != q else "torques, a wrench or IO writes")
                               + " (the prepared one was sent)")  # fmt: skip
        cyc.command = q
        cyc.sent_position = True
        cyc.phase = client.phase
        cyc.row = client.row
        self.prepared_replies += 1
        return self._after(now, mon, seq, supervised, answered=True)

    def _prepare(self, seq: int, mon: Any) -> None:
        """Prepare the reply to the next message (``seq`` + 1) from the client's ``prepare_command``, guarded now:
        only in COMMANDING_ACTIVE, POSITION mode, receive multiplier 1, and while nothing stops or brakes."""
        motion = self._motion
        if (self._stop is not None or self._ended or motion is None or motion.braking
                or self.transformation_client is not None  # (its provide() runs in the full cycle)
                or mon.ipoData.clientCommandMode != _POSITION or (mon.connectionInfo.receiveMultiplier or 1) != 1):  # fmt: skip
            return
        try:
            q = self.client.prepare_command()
        except Exception:  # noqa: BLE001 - no preparation; command() runs when the message is there and reports
            return
        if q is None:
            return
        q = tuple(q)
        adm = motion.envelope.admit(q, motion.prev, motion.prev2, motion.prev3, self.client.jerk_limited)
        if adm.reason is not None or adm.clamped > 0.0 or motion.guard.refuse_position(q, motion.prev, motion.prev2,
                                                                                       False) is not None:  # fmt: skip
            return  # the full cycle decides (clamps it, or refuses it with its reason and brakes)
        reply = self._reply
        reply.set_motion(_POSITION, q, None, None)  # type: ignore[union-attr]
        reply.set_io(())  # type: ignore[union-attr]
        nxt = (seq + 1) & 0xFFFFFFFF
        self._prepared = (nxt, reply.datagram(self._client_seq, nxt), q)  # type: ignore[union-attr]

    def _warm(self) -> None:
        """Between messages (the transport's busy-wait): decode the last good datagram again into the message it
        is already in (the same values) and run the checks a prepared reply waits for, so that their code and data
        are in the CPU's caches when the next message arrives."""
        data = self._last_data
        if data is not None:
            mon = self._codec.decode_monitoring(data, self._mon)  # type: ignore[union-attr]
            consistent(mon, self._bound)
            commanding_end(mon, CMD_ACTIVE, True, self._clock.period_key)

    def _provide_frames(self) -> None:
        """The transformation client's ``provide`` for this message (values kept for the reply)."""
        tc = self.transformation_client
        if tc is not None:
            tc.robot_state = self.state
            tc.values.clear()
            self._call_client("provide", on=tc)  # type: ignore[attr-defined]

    def _set_extras(self, cmd: LBRCommand) -> None:
        """The client's IO writes and the transformation client's values into this cycle's reply."""
        self._reply.set_io(cmd.io_writes)
        if self.transformation_client is not None:
            self._reply.set_transformations(self.transformation_client.values)

    def _pose_solver(self, motion: ExecutedMotion) -> Any:
        """The session's PoseSolver (built at the first Cartesian command: pinocchio only for clients that use it)."""
        if self._poses is None:
            from trajectories.robot import Robot

            from .cartesian import PoseSolver

            self._poses = PoseSolver(self.tcp_robot or Robot(), self.limits, motion.period_s)
        return self._poses

    def _pose_joints(self, mon: Any, state: int, cmd: LBRCommand, motion: ExecutedMotion) -> str | None:
        """CARTESIAN_POSE: the joints of the client's pose as its joint command (``cmd.joint_position``), or why
        there are none. IK warm-started from the joints last sent (COMMANDING_WAIT: the measured ones), A3 at the
        client's E1 or else the ipo E1."""
        if cmd.cartesian_pose is None:
            return "no Cartesian pose was set (CARTESIAN_POSE mode needs one in every commanding cycle)"
        seed = motion.prev if state == CMD_ACTIVE else mon.monitorData.measuredJointPosition.value
        e1 = cmd.redundancy
        if e1 is None:
            red = mon.ipoData.redundancyInformation if mon.ipoData.HasField("redundancyInformation") else None
            e1 = red.value if red is not None else seed[2]
        m = cmd.cartesian_pose
        sol = self._pose_solver(motion).solve(seed, m[:3, 3], m[:3, :3], e1)
        if sol.problem is not None:
            return sol.problem
        cmd.joint_position = tuple(sol.q.tolist())
        return None

    def _build_motion(self, mon: Any, state: int, cmd: LBRCommand) -> bool:
        """Guard the client's joint position (or take the braking stop's) and write it into the message; False if
        the session ended instead (a refusal, nothing sent)."""
        motion = self._motion
        if motion is None:
            self._finish(
                Outcome.REFUSED,
                EndReason.GUARD,
                "the controller did not send its send period; no command is safe",
                observe=True,
            )
            return False
        mode = mon.ipoData.clientCommandMode
        client = self.client
        clamps = motion.clamped_cycles
        if mode == _CARTESIAN and not motion.braking:
            problem = self._pose_joints(mon, state, cmd, motion)
            if problem is not None:
                text = f"guard refused the Cartesian command: {problem}"
                if state != CMD_ACTIVE or not motion.moving:
                    self._finish(Outcome.REFUSED, EndReason.GUARD, text, observe=True)
                    return False
                motion.begin_braking()  # from the joints last sent, within the joint limits, as any stop
                if self._stop is None:
                    self._stop = (Outcome.REFUSED, EndReason.GUARD, text)
        try:
            q, tau, wrench, refused = motion.next_command(mon.monitorData.measuredJointPosition.value, state, mode,
                                                          cmd.joint_position, cmd.torque, cmd.wrench,
                                                          client.exact_command, client.jerk_limited)  # fmt: skip
        except Refused as exc:
            self._finish(Outcome.REFUSED, EndReason.GUARD, str(exc), observe=True)
            return False
        # (a clamp of a few µrad — after a reply the controller may have bridged — is no reason to re-plan)
        client.clamped = motion.clamped_cycles != clamps and motion.last_clamp > CLIENT_CLAMP
        if refused is not None and self._stop is None:
            if motion.loss_refused:  # not the client's command: the link lost it
                self._stop = (Outcome.STOPPED, EndReason.SUPERVISION, f"supervision: {refused}")
            else:
                self._stop = (Outcome.REFUSED, EndReason.GUARD, refused)
        cyc = self.cycle
        cyc.braking = motion.braking
        pose = None
        if mode == _CARTESIAN:  # what goes out is the pose of the joints the guard admitted (a stop's too)
            from .cartesian import pose_to_wire

            pose = pose_to_wire(*self._pose_solver(motion).tcp(q))
        self._reply.set_motion(mode, q, tau, wrench, pose)  # type: ignore[union-attr]
        cyc.torque = tau if mode == _TORQUE else None
        cyc.wrench = wrench if mode == _WRENCH else None
        q = tuple(q)
        motion.sent(q, state)
        cyc.command = q
        cyc.sent_position = True
        return True
