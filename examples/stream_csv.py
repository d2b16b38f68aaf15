"""Stream a joint CSV (t,q1..q7 at the FRI period) with the TrajectoryPlayer client, logging every cycle.

The player knows its next command, so each reply is prepared a cycle ahead (LBRClient.prepare_command) and goes
out as soon as the controller's message is decoded and checked.

    python examples/stream_csv.py move.csv --log run.csv [--robot IP]
"""

from __future__ import annotations

from _connect import arguments, run

from lbrcli.fri import LogProcess, TrajectoryPlayer
from trajectories.csvio import read_joint_csv
from trajectories.limits import default_limits


def main(argv=None):
    p = arguments(__doc__.splitlines()[0], duration_s=600.0)
    p.add_argument("csv")
    p.add_argument("--log", required=True)
    args = p.parse_args(argv)
    traj = read_joint_csv(args.csv)
    args.period = round(traj.dt * 1e3)
    player = TrajectoryPlayer(traj.q, default_limits(), period_s=traj.dt, settle_s=0.2)
    with LogProcess(args.log) as log:  # rows formatted by a child process, off the FRI loop
        result = run(player, args, observers=[log], q0=tuple(traj.q[0]))
    print(
        f"{result.outcome.value}: {result.detail}; {player.trajectory_rows} rows streamed, "
        f"{result.prepared_replies} of {result.answered} replies prepared a cycle ahead"
    )
    return result, player


if __name__ == "__main__":
    main()
