"""Running an FRI client from the command line: the embedded simulator (no --robot), the log, the lab
attachments, signals and the summary. The commands `execute`, `monitor` and `ptp` are thin layers over this."""

from __future__ import annotations

import contextlib
import math
from pathlib import Path
from typing import Any, Callable, Sequence

import typer


LENIENT_TRACKING_LAG_S = 0.1  # [s] the lag at full speed the embedded simulator's robot may show on a loaded PC
LENIENT_REPLY_GAP_S = 0.5  # [s] replies the embedded simulator may miss in a row on a loaded PC (default; --sim-strict and a robot: 50 ms)


LOCKSTEP_WAIT_S = 0.5  # [s] --sim-lockstep: the longest the simulator waits for a reply (below the client's 1 s silence)


def simulator_kwargs(*, length: float | None, default_length: float, period_ms: int, sim_start: str | None,
                     default_start: str | Sequence[float], flange: str, tool: str | None, max_runtime_s: float,
                     limits=None) -> dict[str, Any]:  # fmt: skip
    """The embedded simulator's settings from the commands' simulator options: --length [m] (``default_length`` if
    None), --sim-start (``default_start``: text, or joint positions [rad]); OptionError on a bad one."""
    from trajectories.errors import OptionError
    from trajectories.robot import parse_tool

    from .parsing import parse_joint_vector

    ball = default_length if length is None else length
    if not (math.isfinite(ball) and 0 <= ball <= 5):
        raise OptionError(f"--length must be 0..5 m, got {ball:g}")
    return dict(
        period_ms=period_ms,
        q0=tuple(float(v) for v in (parse_joint_vector(sim_start, "--sim-start") if sim_start is not None
                                    else parse_joint_vector(default_start, "--sim-start") if isinstance(default_start, str)
                                    else default_start)),  # fmt: skip
        flange=flange,
        tool=parse_tool(tool),
        ball_length=ball if ball > 0 else None,
        limits_path=str(limits) if limits is not None else None,
        max_runtime_s=max_runtime_s,
    )


class _TapObserver:
    """Adapts the lab's telemetry tap to an application observer."""

    name = "the MQTT telemetry"

    def __init__(self, tap: Callable[[float, Any], None]) -> None:
        self.tap = tap

    def on_cycle(self, app) -> None:
        self.tap(app.cycle.t, app.state.message)


def run_client(
    rep,
    client,
    *,
    robot: str | None,
    port: int,
    bind: str | None,
    version: str | None,
    limits,
    log_path: Path | None,
    wait: float | None,
    sim_kwargs: dict[str, Any],
    duration_s: float | None = None,
    extra_names: Sequence[str] = (),
    extra: Callable | None = None,
    commanding_timeout_s: float | None = None,
    realtime: bool = False,
    sim_lenient: bool = True,
    sim_lockstep: bool = False,
    sim_fast: bool = False,
    lab=None,
    observers: Sequence[Any] = (),
    max_tracking_error: float | None = None,
    busy_wait_s: float | None = None,
    plants: Sequence[Any] | None = None,
):
    """Bind, start the simulator if no robot was named, attach the log, the pendulum module and telemetry, run the
    session with Ctrl-C/SIGTERM braking, stop everything; (result, simulator stats or None, lab figures).
    ``plants``: the simulator's plant specs instead of the ball (and ball-driven module) of ``sim_kwargs``; a client
    with a ``reader`` attribute gets the pendulum module's reader."""
    from lbrcli.fri import ClientApplication, SessionFigures, interrupts_brake
    from lbrcli.fri.logwriter import LogProcess

    embedded = robot is None
    if realtime:  # refused before anything starts (exit 2), entered for the session below
        from lbrcli.fri.realtime import realtime as realtime_settings

        with realtime_settings():
            pass
    app = ClientApplication(
        client,
        "127.0.0.1" if embedded else robot,
        port,
        bind_host=bind if bind is not None else ("127.0.0.1" if embedded else ""),
        version=version or ("1.15" if embedded else None),
        limits=limits,
        observers=[SessionFigures(), *observers],
        first_message_timeout_s=wait if wait is not None else (20.0 if embedded else 60.0),
        commanding_timeout_s=commanding_timeout_s if commanding_timeout_s is not None else (20.0 if embedded else None),
        max_tracking_error=max_tracking_error,
        reply_gap_s=LENIENT_REPLY_GAP_S if embedded and sim_lenient else None,
        tracking_lag_s=LENIENT_TRACKING_LAG_S if embedded and sim_lenient else None,
        busy_wait_s=busy_wait_s or 0.0,
    )
    if lab is not None:
        lab.validate(embedded)
    app.connect()
    sim = sim_stats = log = attached = None
    lab_figures: dict[str, Any] = {}
    extra_names = tuple(extra_names)
    try:
        if log_path is not None:
            log = LogProcess(log_path)  # rows formatted in a child process, off the FRI loop
        if embedded:
            from lbrcli.fri.sim import SimConfig, SimulatorProcess
            from lbrcli.plants import default_plants

            kw = dict(sim_kwargs)
            if realtime:
                kw["realtime"] = True
            if sim_lockstep or sim_fast:
                kw["lockstep_timeout_s"] = LOCKSTEP_WAIT_S
                kw["lockstep_free"] = sim_fast
            if sim_lenient:
                from .fri.sim import lenient_quality

                kw.update(lenient_quality(kw.get("period_ms", 1), kw.get("receive_multiplier", 1)))
            ball_length, ball_damping = kw.pop("ball_length", None), kw.pop("ball_damping", 0.0)
            ball_model = kw.pop("ball_model", None)
            specs = tuple(plants) if plants is not None else default_plants(
                ball_length, ball_damping, pendulum_pty=lab is not None and lab.pendulum == "sim", model=ball_model)
            sim = SimulatorProcess(SimConfig(client_port=app.port, version=version or "1.15", plants=specs, **kw))
            sim.start()
            rep.print(f"simulator on {sim.address[0]}:{sim.address[1]} → client on 127.0.0.1:{app.port}")
        else:
            rep.print(f"waiting for FRI messages from {app.transport.robot_ip} on UDP port {app.port} …")
        if lab is not None and (lab.pendulum or lab.mqtt):
            from lbrcli.lab.attach import LabAttachments

            path = sim.pendulum_path if lab.pendulum == "sim" else lab.pendulum
            # in lock-step the module's lines are read in the cycle: they are on the pty before the message
            attached = LabAttachments(lab, path, polled=embedded and (sim_lockstep or sim_fast) and lab.pendulum == "sim").start()
            if attached.pendulum is not None:
                rep.print(f"pendulum module on {path}")
                if getattr(client, "sway", None) is not None:  # the module's angle is the sway to wait for
                    client.sway.source = attached.pendulum_sway
                if hasattr(client, "reader"):  # a feedback client reads the module itself
                    client.reader = attached.pendulum
                base_names, base_extra = extra_names, extra
                extra_names = base_names + attached.extra_names
                extra = (lambda s: (*base_extra(s), *attached.extra(s))) if base_extra else attached.extra
            if attached.publisher is not None:
                rep.print(f"telemetry to {lab.mqtt} at {lab.mqtt_rate_hz:g} Hz")
                app.observers.append(_TapObserver(attached.tap))
        if log is not None:
            log.extra_names, log.extra = extra_names, extra
            app.observers.insert(0, log)
        if hasattr(client, "figures"):
            app.observers.append(client)
        if sim is not None:
            app.watchdog = lambda: None if sim.running else "the simulator process ended"
        with interrupts_brake(app), (realtime_settings() if realtime else contextlib.nullcontext()):
            result = app.run(duration_s)
    finally:
        app.disconnect()
        if attached is not None:
            attached.stop()
            lab_figures = attached.summary()
            rep.print("lab: " + ", ".join(f"{k} {v}" for k, v in lab_figures.items()))
        if sim is not None:
            try:
                sim_stats = sim.stop()
            except Exception as exc:  # the session's own outcome matters more
                rep.warn(f"simulator: {exc}")
        if log is not None:
            log.close()
    if log is not None and log.error and result.ok:  # the last rows could not be written: not what was asked
        import dataclasses

        from lbrcli.fri import EndReason, Outcome

        result = dataclasses.replace(result, outcome=Outcome.FAILED, reason=EndReason.OBSERVER_FAILED, detail=log.error)
    return result, sim_stats, lab_figures


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
                f"the rows started with {f['start_sway_deg']:.3f}° of sway, above --start-sway "
                f"{f['sway_threshold_deg']:g}° after waiting {waited:.2f} s (--sway-wait; a damped ball decays, "
                "an undamped simulated one does not)"
            )
        else:
            rep.print(f"start sway {f['start_sway_deg']:.3f}° (below {f['sway_threshold_deg']:g}° after waiting {waited:.2f} s)")
    if r.braking_cycles:
        rep.print(f"braking stop: {r.braking_cycles} cycles ({r.braking_cycles * (r.period_s or 0):.3f} s) within the limits")
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


def exit_for(result, lab_figures: dict[str, Any] | None = None, mqtt: str | None = None,
             failed: str | None = None) -> None:
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


def plot_log(path: Path | None, log_path: Path | None, rep, title: str, figures: dict[str, Any] | None = None,
             draw: Callable | None = None) -> str | None:
    """Draw the plot of a session's log (``draw(log, path)``; default: the execution plot). A plot that fails is
    reported (and in ``figures['plot_error']``), never an exception after the session: what failed, or None."""
    if path is None:
        return None
    if log_path is None:
        rep.warn("--plot needs --log (the plot is drawn from the log); no plot written")
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
