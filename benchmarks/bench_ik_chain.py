"""`lbr ik` as the rest of the chain sees it (issue 41), on ≥ 100 task paths: the 76 of ``ik_paths.build_suite``,
the user-like paths of ``ik_paths.build_rest_suite`` (handwriting and drawings with pens and other flanges,
near-singular passes, orientation-heavy moves, FK-built paths at rest at both ends, paths leaving the workspace, a
60 s path at 1 ms and one that leaves the reach at 50 s) and anti-sway pivot paths at five heights — solved as
`lbr ik` solves them (start chosen automatically, speed limits).

Judges, none of them the solver's own code:

- an output: pinocchio FK against every pose (≤ 1e-6 m, 1e-5 rad) and `lbr check` (default options); a task path
  counts as at rest at an end when its first / last step moves the TCP by < 1e-3 m/s and 1e-3 rad/s;
- a refusal of a pose (no configuration inside the limits): the closed-form IK on a 0.05° grid of arm angles × 8
  branches, refined to 0.0005° around its 5 best configurations, then bounded least squares on pinocchio's
  kinematics (scipy) from those — the pose must be unreachable by all, the pose before it reachable by one, and
  the poses before it reachable (every sample of the last 0.2 s, every 20th before); of A4's speed: A4 of
  pinocchio-solved configurations of the two poses; and, as a witness, `lbr ik` on the poses before it;
- wall time of every refusal (goal ≤ 2 s).

With ``IK_BASELINE=/path/to/an/older/checkout`` the same paths are also solved by that checkout's IK in a
subprocess and judged the same way (before/after). Figures are written to ``benchmarks/results/ik_chain.json``
and the table of every path to ``docs/guides/ik-suite.md``.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results" / "ik_chain.json"
TABLE = HERE.parent / "docs" / "guides" / "ik-suite.md"
REST_SPEED = 1e-3  # [m/s], [rad/s] the judge's "at rest" for the first and last task step
REFUSAL_GOAL = 2.0  # [s]
HEIGHTS = (0.25, 0.35, 0.45, 0.55, 0.65)  # [m] anti-sway layouts


def _antisway_paths(quick: bool):
    """Pivot paths of anti-sway plans (flange down, default layout and a long diagonal) at five heights."""
    from lbrcli.antisway import flange_down_rotation
    from planners.antisway import DEFAULT_LAYOUT, AntiSwayOptions, plan_layout
    from trajectories.ik_paths import TaskPath

    out = []
    layouts = (("default", DEFAULT_LAYOUT, 0.005), ("diagonal", ((0.35, -0.45), (0.7, 0.3)), 0.001))
    for name, points, dt in layouts:
        for z in HEIGHTS[::2] if quick else HEIGHTS:
            plan = plan_layout(np.array(points), 0.25, 2.0, z, dt, AntiSwayOptions(shaper="zv", length_tolerance=0.0))
            rot = np.broadcast_to(flange_down_rotation(), (len(plan.t), 3, 3)).copy()
            out.append(TaskPath(f"antisway-{name}-z{z:g}-{dt * 1e3:g}ms", "antisway", plan.t, plan.position, rot))
    return out


def suite(quick: bool = False):
    from trajectories.ik_paths import build_rest_suite, build_suite
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    limits = default_limits()
    return build_suite(Robot(), limits, quick=quick) + build_rest_suite(limits, quick) + _antisway_paths(quick)


# ---- the solver, here or in another checkout --------------------------------------------------------------------

SOLVE = r"""
import sys, time, pickle, numpy as np
from trajectories.errors import IkError
from trajectories.ik import IkOptions, solve_ik_path
from trajectories.limits import default_limits
from trajectories.robot import Flange, Robot, RobotConfig
paths = pickle.load(open(sys.argv[1], "rb"))
limits, options, robots, out = default_limits(), IkOptions(nullspace_gain=None, speed_limits=True), {}, []
for p in paths:
    key = (p["flange"], tuple(p["tool"]))
    robot = robots.setdefault(key, Robot(RobotConfig(flange=Flange(p["flange"]), tool=key[1])))
    t0 = time.perf_counter()
    try:
        res = solve_ik_path(robot, p["position"], p["rotation"], None, limits, options, times=p["t"])
        out.append({"q": res.q, "time": time.perf_counter() - t0, "start": res.start})
    except IkError as exc:
        out.append({"refused": exc.index, "reason": exc.reason, "kind": getattr(exc, "kind", ""),
                    "message": str(exc), "time": time.perf_counter() - t0})
pickle.dump(out, open(sys.argv[2], "wb"))
"""


def solve_all(paths, root: str | None = None) -> list[dict]:
    """Solve every path with the IK of this checkout or of ``root`` (in a subprocess with that code first on the
    path) → per path {q, time, start} or {refused, reason, kind, message, time}."""
    import pickle

    with tempfile.TemporaryDirectory() as tmp:
        src, dst = Path(tmp) / "paths.pkl", Path(tmp) / "out.pkl"
        plain = [{"t": p.t, "position": p.position, "rotation": p.rotation, "flange": p.config.flange.value,
                  "tool": list(p.config.tool)} for p in paths]  # fmt: skip
        src.write_bytes(pickle.dumps(plain))
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
        if root is not None:
            env["PYTHONPATH"] = root
        subprocess.run([sys.executable, "-c", SOLVE, str(src), str(dst)], check=True, env=env,
                       cwd=root or str(HERE.parent))  # fmt: skip
        return pickle.loads(dst.read_bytes())


# ---- judges ----------------------------------------------------------------------------------------------------


def task_rest(path) -> tuple[bool, bool]:
    """The judge's "at rest": the TCP's first and last step slower than REST_SPEED (translation and rotation)."""
    from trajectories.chain import rotation_log

    out = []
    for a, b in ((0, 1), (-2, -1)):
        v = np.linalg.norm(path.position[b] - path.position[a]) / path.dt
        w = np.linalg.norm(rotation_log((path.rotation[b] @ path.rotation[a].T)[None])[0]) / path.dt
        out.append(bool(v < REST_SPEED and w < REST_SPEED))
    return out[0], out[1]


def _grid(geometry, pos, rot, bound, psi):
    from trajectories.arm_angle import BRANCHES, inverse

    q, reach = inverse(geometry, rot, pos, psi[None, :], BRANCHES[:, None, :])
    excess = np.where(reach[..., None], np.abs(q) - bound, np.inf).max(axis=-1)  # (8, P)
    return q, excess


def _least_squares(robot, pos, rot, bound, seed) -> float:
    """Pose error [m + rad] that scipy's bounded least squares on pinocchio's kinematics ends at from ``seed``."""
    import pinocchio as pin
    from scipy.optimize import least_squares

    target = pin.SE3(rot, pos)
    model, data, fid = robot.model, robot.data, robot.tcp_id

    def err(q):
        pin.framesForwardKinematics(model, data, q)
        return pin.log6(target.actInv(data.oMf[fid])).vector

    def jac(q):
        pin.computeJointJacobians(model, data, q)
        dm = target.actInv(pin.updateFramePlacement(model, data, fid))
        return pin.Jlog6(dm) @ pin.getFrameJacobian(model, data, fid, pin.LOCAL)

    res = least_squares(err, np.clip(seed, -bound, bound), jac=jac, bounds=(-bound, bound), xtol=1e-15,
                        ftol=1e-15, gtol=1e-15, max_nfev=200)  # fmt: skip
    return float(np.linalg.norm(res.fun))


def pose_reachable(robot, geometry, pos, rot, bound, step_deg: float = 0.05) -> bool:
    """The judge of one pose: some configuration inside ``bound`` (grid, refined grid, bounded least squares)."""
    q, excess = _grid(geometry, pos, rot, bound, np.radians(np.arange(-180.0, 180.0, step_deg)))
    if (excess <= 0).any():
        return True
    best = np.argsort(excess, axis=None)[:5]
    for flat in best:
        b, p = np.unravel_index(flat, excess.shape)
        psi0 = math.radians(-180.0 + p * step_deg)
        fine = psi0 + np.radians(np.arange(-2 * step_deg, 2 * step_deg, 0.0005))
        qf, ef = _grid(geometry, pos, rot, bound, fine)
        if (ef <= 0).any():
            return True
        if _least_squares(robot, pos, rot, bound, q[b, p]) < 1e-9:
            return True
    return False


def _a4(robot, geometry, pos, rot) -> float:
    """|A4| [rad] of a configuration pinocchio's least squares finds for the pose (any branch and arm angle)."""
    from trajectories.arm_angle import BRANCHES, inverse

    seed, _ = inverse(geometry, rot, pos, 0.7, BRANCHES[0])
    import pinocchio as pin
    from scipy.optimize import least_squares

    target = pin.SE3(rot, pos)
    model, data, fid = robot.model, robot.data, robot.tcp_id

    def err(q):
        pin.framesForwardKinematics(model, data, q)
        return pin.log6(target.actInv(data.oMf[fid])).vector

    res = least_squares(err, seed + 0.01, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return abs(float(res.x[3]))


def judge_refusal(path, robot, limits, result: dict, prefix_witness: bool) -> dict:
    """Whether a refusal's index is exact (see the module) and the witness of the poses before it."""
    from trajectories.arm_angle import ArmGeometry
    from trajectories.ik_paths import verify_joint_path

    geometry = ArmGeometry.of(robot)
    bound = limits.position - 1e-4
    k = int(result["refused"])
    out: dict = {"index": k}
    if result.get("kind") == "path":  # A4's speed or acceleration: A4 of pinocchio-solved configurations
        order = 1 if result.get("reason") == "velocity limit" else 2
        lim = (limits.velocity if order == 1 else limits.acceleration)[3] * (1 + 1e-9)
        rows = [i for i in range(k - order - 1, k + 1) if i >= 0]
        a4 = np.array([_a4(robot, geometry, path.position[i], path.rotation[i]) for i in rows])
        if k - order < 0:  # at the start: the robot at rest before it (as lbr check counts)
            a4 = np.r_[np.repeat(a4[:1], order + 1 - len(rows) + 1, axis=0), a4]
        needed = np.abs(np.diff(a4, order)) / float(path.dt) ** order
        out["needed_a4"] = float(needed[-1])
        fact = needed[-1] > lim
        before_ok = len(needed) < 2 or needed[-2] <= lim
    else:
        fact = not pose_reachable(robot, geometry, path.position[k], path.rotation[k], bound)
        before = list(range(max(0, k - 200), k)) + list(range(0, max(0, k - 200), 20))
        before_ok = all(pose_reachable(robot, geometry, path.position[i], path.rotation[i], bound, 1.0)
                        for i in before)  # fmt: skip
    out["confirmed"] = bool(fact and before_ok)
    if prefix_witness and k >= 3:
        from trajectories.errors import IkError
        from trajectories.ik import IkOptions, solve_ik_path

        try:
            res = solve_ik_path(robot, path.position[:k], path.rotation[:k], None, limits,
                                IkOptions(nullspace_gain=None, speed_limits=True), times=path.t[:k])  # fmt: skip
            sub = type(path)(path.name, path.kind, path.t[:k], path.position[:k], path.rotation[:k])
            out["prefix_solved"] = verify_joint_path(robot, sub, res.q, limits).ok(1e-6, 1e-5)
        except IkError:
            out["prefix_solved"] = False
    return out


def judge_output(path, robot, limits, q: np.ndarray) -> dict:
    from trajectories.check import check_trajectory
    from trajectories.ik_paths import verify_joint_path
    from trajectories.trajectory import JointTrajectory

    check = verify_joint_path(robot, path, q, limits)
    report = check_trajectory(JointTrajectory(t=path.t, q=q), limits)
    ratios = report.ratios()
    return {
        "accurate": bool(check.position_error <= 1e-6 and check.rotation_error <= 1e-5),
        "speeds_ok": bool(check.ok(1e-6, 1e-5)),
        "check_ok": bool(report.ok),
        "failing": sorted({f"{v.quantity}{' ' + v.note if v.note else ''}" for v in report.failing}),
        "acceleration_ratio": float(max(ratios["acceleration"].max(), ratios["step acceleration"].max())),
        "jerk_ratio": float(ratios["jerk"].max()),
    }


def evaluate(paths, results, prefix_witness: bool = True) -> list[dict]:
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    limits = default_limits()
    robots: dict = {}
    rows = []
    for path, res in zip(paths, results):
        robot = robots.setdefault(path.config, Robot(path.config))
        row = {"name": path.name, "kind": path.kind, "samples": len(path.t), "duration_s": float(path.t[-1]),
               "rest": task_rest(path), "witness": path.witness is not None, "time_s": res["time"]}  # fmt: skip
        if "q" in res:
            row.update(judge_output(path, robot, limits, res["q"]))
        else:
            row.update({"refused": res["refused"], "reason": res.get("reason"), "refusal_kind": res.get("kind"),
                        "message": res.get("message", "")})  # fmt: skip
            row.update(judge_refusal(path, robot, limits, res, prefix_witness))
        rows.append(row)
    return rows


def figures(rows: list[dict], prefix: str = "") -> list[tuple[str, float, str]]:
    solved = [r for r in rows if "refused" not in r]
    refused = [r for r in rows if "refused" in r]
    rest = [r for r in solved if all(r["rest"])]
    facts = [r for r in refused if r.get("refusal_kind") in ("pose", "path")]
    times = [r["time_s"] for r in refused]
    poses = sum(r["samples"] for r in rows)
    elapsed = sum(r["time_s"] for r in rows)
    p = prefix
    return [
        (f"{p}paths", len(rows), "paths"),
        (f"{p}paths at rest at both ends (judge)", sum(all(r["rest"]) for r in rows), "paths"),
        (f"{p}solved accurately with speeds inside the limits", sum(r["speeds_ok"] for r in solved), "paths"),
        (f"{p}outputs of paths at rest at both ends", len(rest), "paths"),
        (f"{p}  of those passing lbr check", sum(r["check_ok"] for r in rest), "paths"),
        (
            f"{p}  of those failing on rest at an end",
            sum(any(f.startswith("rest") for f in r["failing"]) for r in rest),
            "paths",
        ),
        (
            f"{p}  of those failing on acceleration",
            sum(any("acceleration" in f for f in r["failing"]) for r in rest),
            "paths",
        ),
        (f"{p}refused", len(refused), "paths"),
        (f"{p}  refused as facts of the pose or path", len(facts), "paths"),
        (f"{p}  with the index confirmed by the judges", sum(bool(r.get("confirmed")) for r in refused), "paths"),
        (f"{p}  with lbr ik solving the poses before it", sum(bool(r.get("prefix_solved")) for r in refused), "paths"),
        (f"{p}  refusals of FK-built (reachable) paths", sum(r["witness"] for r in refused), "paths"),
        (f"{p}refusal time, worst", max(times) if times else 0.0, "s"),
        (f"{p}refusal time, median", float(np.median(times)) if times else 0.0, "s"),
        (f"{p}refusals within {REFUSAL_GOAL:g} s", sum(t <= REFUSAL_GOAL for t in times), "paths"),
        (f"{p}throughput over the suite (refusals included)", poses / elapsed if elapsed else 0.0, "poses/s"),
    ]


def _fmt(value, unit: str) -> str:
    return f"{value:.3g} {unit}" if isinstance(value, float) else f"{value} {unit}"


def _table(rows: list[dict], before: list[dict] | None, summary: list[tuple[str, float, str]]) -> str:
    def cell(r: dict) -> str:
        if "refused" in r:
            ok = "confirmed" if r.get("confirmed") else "not confirmed"
            return f"refused at {r['refused']} ({r.get('reason')}, {r.get('refusal_kind') or '?'}; {ok}) in {r['time_s']:.2f} s"
        verdict = "passes" if r["check_ok"] else "fails (" + ", ".join(r["failing"]) + ")"
        return f"{'accurate' if r['accurate'] else 'INACCURATE'}; lbr check {verdict}; {r['time_s']:.2f} s"

    head = "| path | samples | at rest (start, end) | lbr ik now |" + (" before |" if before else "")
    lines = [
        "# `lbr ik` on the path suite of the IK guide (generated)",
        "",
        "Written by `python benchmarks/run_all.py ik_chain` (`benchmarks/bench_ik_chain.py`); do not edit by hand. "
        "See [the IK guide](ik.md) for what the figures mean.",
        "",
        "| figure | now |" + (" before |" if before else ""),
        "|---|---|" + ("---|" if before else ""),
    ]
    now = [(k, v, u) for k, v, u in summary if not k.startswith("before: ")]
    then = {k.removeprefix("before: "): v for k, v, u in summary if k.startswith("before: ")}
    for k, v, u in now:
        lines.append(f"| {k.strip()} | {_fmt(v, u)} |" + (f" {_fmt(then[k], u)} |" if k in then else ""))
    lines += [
        "",
        head,
        "|---|---|---|---|" + ("---|" if before else ""),
    ]
    for i, r in enumerate(rows):
        rest = "/".join("yes" if x else "no" for x in r["rest"])
        line = f"| {r['name']} | {r['samples']} | {rest} | {cell(r)} |"
        if before:
            line += f" {cell(before[i])} |"
        lines.append(line)
    return "\n".join(lines) + "\n"


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    paths = suite(quick)
    t0 = time.perf_counter()
    rows = evaluate(paths, solve_all(paths))
    out = figures(rows)
    baseline = os.environ.get("IK_BASELINE")
    before = None
    if baseline:
        before = evaluate(paths, solve_all(paths, baseline), prefix_witness=False)
        out += figures(before, "before: ")
    for r in rows:
        if "refused" in r or not r["check_ok"]:
            print("  ", r["name"], "→", r.get("message") or r["failing"])
    if not quick:
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(json.dumps({"figures": {k: v for k, v, _ in out}, "paths": rows,
                                       "before": before, "measured_s": time.perf_counter() - t0}, indent=1))  # fmt: skip
        TABLE.parent.mkdir(parents=True, exist_ok=True)
        TABLE.write_text(_table(rows, before, out))
    return out
