"""Running an FRI client from the command line: the embedded simulator (no robot named), the log, the lab
attachments, signals and the summary. The FRI commands build their settings (:mod:`lbrcli.session_settings`) and
hand them to :func:`run_client`."""

from __future__ import annotations

import contextlib
import dataclasses
from pathlib import Path
from typing import Any, Callable

import typer

from .option_groups import name_text
from .session_settings import LogColumns, SessionSettings, SimulatorSettings


class _TapObserver:
    """Adapts the lab's telemetry tap to an application observer."""

    name = "the MQTT telemetry"

    def __init__(self, tap: Callable[[float, Any], None]) -> None:
        self.tap = tap

    def on_cycle(self, app) -> None:
        self.tap(app.cycle.t, app.state.message)


def realtime_context(realtime: bool):
    """The real-time settings for the session (a null context without ``realtime``); RealtimeRefused (exit 2)
    already here when the system does not permit them, before anything starts."""
    if not realtime:
        return contextlib.nullcontext()
    from lbrcli.fri.realtime import RealtimeRefused
    from lbrcli.fri.realtime import realtime as realtime_settings
    from trajectories.errors import SettingError

    try:
        with realtime_settings():
            pass
    except RealtimeRefused as exc:
        raise SettingError(SessionSettings, "realtime", exc.message) from None
    return realtime_settings()


LATE_REPLIES_HINT = (
    ": the simulator's connection-quality rule dropped it for late replies, as a controller does (this computer was "
    "too busy to answer every period in time; lock-step (SimulatorSettings.lockstep) waits for each reply, see "
    "docs/explanations/fri-timing.md)"
)


class _SessionParts:
    """What a session started besides the application — log writer, simulator, lab attachments — and their stop."""

    def __init__(self, rep, app, session: SessionSettings, simulator: SimulatorSettings | None, lab) -> None:
        self.rep, self.app, self.session, self.simulator, self.lab = rep, app, session, simulator, lab
        self.log = self.sim = self.attached = self.sim_stats = None
        self.lab_figures: dict[str, Any] = {}

    def start(self, client, columns: LogColumns) -> None:
        """Log, simulator (or the wait for the robot), lab; then the observers in their order."""
        from lbrcli.fri.logwriter import LogProcess

        if self.session.log is not None:
            self.log = LogProcess(self.session.log)  # rows formatted in a child process, off the FRI loop
        if self.simulator is not None:
            self._start_simulator()
        else:
            self.rep.print(f"waiting for FRI messages from {self.app.transport.robot_ip} on UDP port {self.app.port} …")
        columns = self._attach_lab(client, columns)
        if self.log is not None:
            self.log.extra_names, self.log.extra = columns.names, columns.values
            self.app.observers.insert(0, self.log)
        if hasattr(client, "figures"):
            self.app.observers.append(client)
        if self.sim is not None:
            sim = self.sim
            self.app.watchdog = lambda: None if sim.running else "the simulator process ended"

    def _start_simulator(self) -> None:
        from lbrcli.fri.sim import SimulatorProcess

        config = self.simulator.config(self.app.port, self.session.version, self.session.realtime)  # type: ignore[union-attr]
        self.sim = SimulatorProcess(config)
        self.sim.start()
        self.rep.print(
            f"simulator on {self.sim.address[0]}:{self.sim.address[1]} → client on 127.0.0.1:{self.app.port}"
        )

    def _attach_lab(self, client, columns: LogColumns) -> LogColumns:
        """The pendulum module (read by the client where it wants it, logged) and the telemetry tap."""
        lab = self.lab
        if lab is None or not (lab.pendulum or lab.mqtt):
            return columns
        from lbrcli.lab.attach import LabAttachments

        emulated = lab.pendulum == "sim"
        path = self.sim.pendulum_path if emulated else lab.pendulum  # type: ignore[union-attr]
        # in lock-step the module's lines are read in the cycle: they are on the pty before the message
        polled = emulated and self.simulator is not None and self.simulator.paced_by_replies
        attached = self.attached = LabAttachments(lab, path, polled=polled).start()
        if attached.pendulum is not None:
            self.rep.print(f"pendulum module on {path}")
            if getattr(client, "sway", None) is not None:  # the module's angle is the sway to wait for
                client.sway.source = attached.pendulum_sway
            if hasattr(client, "reader"):  # a feedback client reads the module itself
                client.reader = attached.pendulum
            columns = columns + LogColumns(attached.extra_names, attached.extra)
        if attached.publisher is not None:
            self.rep.print(f"telemetry to {lab.mqtt} at {lab.mqtt_rate_hz:g} Hz")
            self.app.observers.append(_TapObserver(attached.tap))
        return columns

    def stop(self) -> None:
        """Everything stopped, the log closed; the lab's and the simulator's figures kept."""
        if self.attached is not None:
            self.attached.stop()
            self.lab_figures = self.attached.summary()
            self.rep.print("lab: " + ", ".join(f"{k} {v}" for k, v in self.lab_figures.items()))
        if self.sim is not None:
            try:
                self.sim_stats = self.sim.stop()
            except Exception as exc:  # the session's own outcome matters more
                self.rep.warn(f"simulator: {exc}")
        if self.log is not None:
            self.log.close()

    def judged(self, result):
        """The session's result, failed when the log could not write its last rows (not what was asked); when the
        embedded simulator dropped the session for late replies, the detail says why and how to avoid it."""
        import dataclasses

        from lbrcli.fri import EndReason, Outcome

        if not result.ok and self._dropped_for_late_replies():
            return dataclasses.replace(result, detail=result.detail + LATE_REPLIES_HINT)
        if self.log is None or not self.log.error or not result.ok:
            return result
        return dataclasses.replace(
            result, outcome=Outcome.FAILED, reason=EndReason.OBSERVER_FAILED, detail=self.log.error
        )

    def _dropped_for_late_replies(self) -> bool:
        """The embedded simulator, on the period's grid, ended the session for its connection quality."""
        stats, sim = self.sim_stats, self.simulator
        if stats is None or sim is None or sim.paced_by_replies or sim.loss > 0 or sim.malformed > 0:
            return False  # (injected faults are their own explanation)
        return stats.end_reason == "quality"


def run_client(rep, client, session: SessionSettings, simulator: SimulatorSettings | None = None, *, lab=None,
               observers=(), extra: LogColumns = LogColumns()):  # fmt: skip
    """Bind, start the simulator if no robot was named (``simulator``: its settings, default ones if None), attach
    the log (with the ``extra`` columns), the pendulum module and telemetry (``lab``: LabOptions), run the session with
    Ctrl-C/SIGTERM braking, stop everything; (result, simulator stats or None, lab figures). A client with a
    ``reader`` attribute gets the pendulum module's reader, one with a ``sway`` watch the module's angle."""
    from lbrcli.fri import SessionFigures, interrupts_brake

    if not session.embedded:
        simulator = None
    elif simulator is None:
        simulator = SimulatorSettings()
    realtime = realtime_context(session.realtime)  # refused before anything starts (exit 2)
    if lab is not None:
        lab.validate(session.embedded)
    app = session.application(client, [SessionFigures(), *observers], lenient=simulator is not None and simulator.lenient,
                              paced_by_replies=simulator is not None and simulator.paced_by_replies)  # fmt: skip
    app.connect()
    parts = _SessionParts(rep, app, session, simulator, lab)
    try:
        parts.start(client, extra)
        with interrupts_brake(app), realtime:
            result = app.run(session.duration_s)
    finally:
        app.disconnect()
        parts.stop()
    result = parts.judged(result)
    if name_text(result.detail) != result.detail:  # a hint naming settings: the command's flags
        result = dataclasses.replace(result, detail=name_text(result.detail))
    return result, parts.sim_stats, parts.lab_figures


def print_summary(rep, result, sim_stats, log_path: Path | None) -> dict[str, Any]:
    """Human summary and the figures for --json."""
    from lbrcli.fri.constants import SessionState

    r = result
    f = r.figures
    states = " → ".join(SessionState(s).name for s in r.states_seen)
    period = f"{r.period_s * 1e3:g} ms" if r.period_s else "?"
    rep.print(f"session: {states} (FRI {r.version})")
    rep.print(f"ended: {r.detail} ({r.outcome.value})")
    rep.print(
        f"cycles {r.cycles} (period {period}), answered {r.answered}, missed {r.missed}, "
        f"stale {r.stale}, foreign {r.foreign}, malformed {r.malformed}"
    )
    if f.get("move_rows") or f.get("trajectory_rows") or f.get("settle_rows"):
        rep.print(
            f"commanded: {f.get('move_rows', 0)} move-to-start rows, {f.get('trajectory_rows', 0)} trajectory rows, "
            f"{f.get('settle_rows', 0)} settle rows"
        )
    if f.get("start_sway_deg") is not None:
        waited = f.get("sway_wait_s") or 0.0
        if f.get("start_sway_above_threshold"):
            rep.warn(
                name_text(
                    f"the rows started with {f['start_sway_deg']:.3f}° of sway, above SwayWatch.threshold "
                    f"{f['sway_threshold_deg']:g}° after waiting {waited:.2f} s (SwayWatch.max_wait_s; a damped ball decays, "
                    "an undamped simulated one does not)"
                )
            )
        else:
            rep.print(
                f"start sway {f['start_sway_deg']:.3f}° (below {f['sway_threshold_deg']:g}° after waiting {waited:.2f} s)"
            )
    if r.braking_cycles:
        rep.print(
            f"braking stop: {r.braking_cycles} cycles ({r.braking_cycles * (r.period_s or 0):.3f} s) within the limits"
        )
    if f.get("min_tracking") is not None:
        rep.print(f"min tracking performance {f['min_tracking']:.4f} over {r.active_cycles} COMMANDING_ACTIVE cycles")
    if f.get("max_tracking_error") is not None:
        prev = f.get("max_tracking_error_prev")
        lag = f", {prev:.3e} rad against the previous cycle's command" if prev is not None else ""
        rep.print(f"max |measured − commanded| {f['max_tracking_error']:.3e} rad (same cycle){lag}")
    if f.get("max_ball_theta") is not None:
        resid = f", residual {f['residual_ball_theta_deg']:.3f}°" if f.get("residual_ball_theta") is not None else ""
        rep.print(f"ball sway: max {f['max_ball_theta_deg']:.3f}°{resid}")
    if r.latency_p50_ms is not None:
        rep.print(
            f"reply latency p50 {r.latency_p50_ms:.3f} ms, p99 {r.latency_p99_ms:.3f} ms, max {r.latency_max_ms:.3f} ms"
            + (f"; CPU {r.cpu_us_per_cycle:.1f} µs per cycle" if r.cpu_us_per_cycle is not None else "")
        )
    if log_path is not None:
        rep.print(f"log: {log_path} ({f.get('log_rows', 0)} rows)")
    figures = r.to_dict()
    figures["log"] = str(log_path) if log_path is not None else None
    if sim_stats is not None:
        figures["simulator"] = sim_stats.to_dict()
    return figures


def exit_for(
    result, lab_figures: dict[str, Any] | None = None, mqtt: str | None = None, failed: str | None = None
) -> None:
    """Exit 2 for bad input found in the session, 1 for any other end that is not what was asked (the session's,
    lab telemetry that never reached its broker, or ``failed``: an output the command could not write, e.g. the
    plot), 130 for Ctrl-C."""
    import sys

    from lbrcli.fri import EndReason, Outcome

    if result.ok:
        lab = lab_figures or {}
        if mqtt and not lab.get("mqtt_published"):
            sys.stderr.write(f"lbr: failed: telemetry: nothing was published to {mqtt} (is the broker running?)\n")
            raise typer.Exit(1)
        if failed:
            sys.stderr.write(f"lbr: failed: the session completed, but {failed}\n")
            raise typer.Exit(1)
        return
    if result.reason is EndReason.BAD_INPUT:
        sys.stderr.write(f"lbr: error: {result.detail}\n")
        raise typer.Exit(2)
    sys.stderr.write(f"lbr: {result.outcome.value}: {result.detail}\n")
    raise typer.Exit(130 if result.outcome is Outcome.INTERRUPTED else 1)


def plot_log(
    path: Path | None,
    log_path: Path | None,
    rep,
    title: str,
    figures: dict[str, Any] | None = None,
    draw: Callable | None = None,
) -> str | None:
    """Draw the plot of a session's log (``draw(log, path)``; default: the execution plot). A plot that fails is
    reported (and in ``figures['plot_error']``), never an exception after the session: what failed, or None."""
    if path is None:
        return None
    if log_path is None:
        rep.warn(
            name_text(
                "Plot.path needs the session's log (ExecutionLog.path): the plot is drawn from the log; no plot written"
            )
        )
        return None
    if draw is None:
        from .plots.execute import plot_execution

        def draw(log: Path, out: Path) -> None:
            plot_execution(log, out, title=title)

    try:
        draw(Path(log_path), Path(path))
    except Exception as exc:  # noqa: BLE001 - the run is done and logged; the plot is extra
        text = f"no plot written to {path}: {str(exc) or type(exc).__name__}"
        rep.warn(text)
        if figures is not None:
            figures["plot_error"] = text
        return text
    rep.print(f"plot: {path}")
    return None
