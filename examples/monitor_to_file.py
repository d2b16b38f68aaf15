"""Watch a session and log everything the controller reports (KUKA's default client never moves the robot).

    python examples/monitor_to_file.py --log mon.csv --duration 10 [--robot IP]

Unlike KUKA's client, which answers until IDLE, the run ends when the session leaves COMMANDING_ACTIVE (if the
application has an overlay: lbrcli.fri's robot-side end) or after --duration.
"""

from __future__ import annotations

from _connect import arguments, run

from lbrcli.fri import LBRClient, LogProcess


def main(argv=None):
    p = arguments(__doc__.splitlines()[0])
    p.add_argument("--log", required=True)
    args = p.parse_args(argv)
    with LogProcess(args.log) as log:  # rows formatted by a child process, off the FRI loop
        result = run(LBRClient(), args, observers=[log])
    rows = log.written
    print(f"{result.outcome.value}: {result.detail}; {rows} rows in {args.log}")
    return result, rows


if __name__ == "__main__":
    main()
