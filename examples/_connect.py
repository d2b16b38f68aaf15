"""Shared by the examples: run a client against a named robot, or against the built-in simulator on loopback."""

from __future__ import annotations

import argparse

from lbrcli.fri import ClientApplication, SessionResult, interrupts_brake


def arguments(description: str, duration_s: float = 5.0) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--robot", help="controller address; without it the built-in simulator is used")
    p.add_argument("--port", type=int, default=30200, help="local FRI port (robot only)")
    p.add_argument("--duration", type=float, default=duration_s, help="session length [s]")
    p.add_argument("--period", type=int, default=5, help="simulator send period [ms]")
    p.add_argument("--fri-version", default="1.15", choices=("1.15", "2.7"), help="simulator wire format")
    p.add_argument(
        "--sim-lenient",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="simulator tolerant of a loaded PC (1 s quality window; --no-sim-lenient: as strict as a robot)",
    )
    p.add_argument(
        "--sim-lockstep",
        action="store_true",
        help="simulator that waits for each reply on its period's grid: a loaded PC does not drop the session",
    )
    p.add_argument(
        "--sim-fast",
        action="store_true",
        help="simulator in lock-step as fast as the client answers: it waits for each reply, so a loaded PC behaves as "
        "an idle one; simulated time runs faster than --duration's wall-clock seconds",
    )
    return p


def run(client, args, observers=(), **sim_options) -> SessionResult:
    """Run ``client`` for ``args.duration`` seconds; ``sim_options`` configure the simulated controller."""
    if args.robot is not None:
        with ClientApplication(client, args.robot, args.port, observers=observers) as app, interrupts_brake(app):
            return app.run(args.duration)
    from lbrcli.fri.sim import SimConfig, SimulatorProcess, lenient_quality

    if args.sim_lenient:
        sim_options = {**lenient_quality(args.period), **sim_options}
    if args.sim_fast or args.sim_lockstep:
        sim_options = {"lockstep_timeout_s": 0.5, "lockstep_free": args.sim_fast, **sim_options}

    with ClientApplication(client, "127.0.0.1", 0, bind_host="127.0.0.1", version=args.fri_version, observers=observers,
                           first_message_timeout_s=20, reply_gap_s=0.5 if args.sim_lenient else None,
                           paced_by_replies=args.sim_fast or args.sim_lockstep, catch_up=not args.sim_lenient) as app:  # fmt: skip
        config = SimConfig(client_port=app.port, version=args.fri_version, period_ms=args.period, **sim_options)
        with SimulatorProcess(config), interrupts_brake(app):
            return app.run(args.duration)
