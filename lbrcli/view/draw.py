"""The scene as viser nodes: the arms from the model's primitives, balls and strings, paths, turning points,
obstacles, the cup and the state label; :meth:`Drawing.show` puts every moving node at frame k.

Node names (what a test or a script finds in the page's scene tree): ``/arms/<file>/<role>/body1..body8``
(bodies A1..A7 and the flange), ``/balls/<file>/ball_<kind>`` and ``…_string``, ``/status`` (the label with
"t = … s · state · phase"), ``/paths/…``, ``/turning_points/k``, ``/obstacles/<name>``, ``/base``.
"""

from __future__ import annotations

import numpy as np

from trajectories.description import BASE_BODY, FLANGE_BODY, Shape, link_shapes

from .scene import Scene

ARM_COLOURS = {"planned": (70, 170, 90), "commanded": (50, 120, 235), "measured": (255, 120, 20)}  # RGB
ARM_OPACITY = {"planned": 0.5, "commanded": 0.35, "measured": 0.85}  # ghosts; an arm drawn alone is opaque
BALL_COLOURS = {"predicted": (40, 170, 60), "simulated": (225, 45, 45), "tracked": (40, 90, 235)}
PATH_COLOURS = {
    "planned": (70, 170, 90),
    "commanded": (50, 120, 235),
    "measured": (255, 120, 20),
    "task": (120, 120, 120),
}
_UNCHANGED = 1e-7  # [m] and quaternion units: a node that moved less is not sent again


def _add_shape(api, name: str, shape: Shape, colour, opacity) -> None:
    """A primitive (viser's cylinder, its height along z, or icosphere) at its placement in its body's frame."""
    from scipy.spatial.transform import Rotation

    m = shape.matrix
    wxyz = Rotation.from_matrix(m[:3, :3]).as_quat(scalar_first=True)
    if shape.kind == "cylinder":
        api.add_cylinder(
            name, radius=shape.radius, height=shape.length, color=colour, opacity=opacity, wxyz=wxyz, position=m[:3, 3]
        )
    else:
        api.add_icosphere(name, radius=shape.radius, color=colour, opacity=opacity, wxyz=wxyz, position=m[:3, 3])


class Drawing:
    """The viser nodes of a :class:`Scene` (``api``: a viser SceneApi, e.g. ``server.scene``)."""

    def __init__(self, api, scene: Scene, robot) -> None:
        self.scene = scene
        self.api = api
        self._sent: dict[str, np.ndarray] = {}
        shapes = link_shapes(robot)
        api.add_grid("/ground", width=2.0, height=2.0, cell_size=0.1, section_size=0.5)
        for k, shape in enumerate(s for s in shapes if s.body == BASE_BODY):
            _add_shape(api, f"/base/{k}", shape, (170, 170, 175), None)
        alone = len(scene.arms) == 1
        self.bodies: dict[str, list] = {}  # per arm: the frame nodes of bodies A1..A7 and the flange
        for arm in scene.arms:
            opacity = None if alone else ARM_OPACITY.get(arm.role, 0.5)
            colour = ARM_COLOURS.get(arm.role, (200, 200, 200))
            frames = []
            for b in range(1, FLANGE_BODY + 1):
                name = f"/arms/{arm.key}/body{b}"
                frames.append(api.add_frame(name, show_axes=False))
                for k, shape in enumerate(s for s in shapes if s.body == b):
                    _add_shape(api, f"{name}/{k}", shape, colour, opacity)
            self.bodies[arm.key] = frames
        if scene.cup_arm is not None and scene.settings.cup is not None:
            radius, depth = scene.settings.cup  # a translucent cylinder on the TCP along the flange's z axis
            tool = np.asarray(robot.config.tool, dtype=float)
            api.add_cylinder(
                f"/arms/{scene.cup_arm}/body{FLANGE_BODY}/cup",
                radius=radius,
                height=depth,
                color=(90, 90, 200),
                opacity=0.45,
                position=tool + (0.0, 0.0, depth / 2),
            )
        self.balls: dict[str, tuple] = {}
        for ball in scene.balls:
            colour = BALL_COLOURS.get(ball.kind, (200, 0, 200))
            handle = api.add_icosphere(f"/balls/{ball.key}", radius=scene.settings.ball_radius, color=colour)
            string = api.add_line_segments(
                f"/balls/{ball.key}_string", np.zeros((1, 2, 3), np.float32), colour, thickness=0.003
            )
            self.balls[ball.key] = (handle, string)
        for path in scene.paths:
            pts = path.points.astype(np.float32)
            if len(pts) > 1:
                api.add_line_segments(
                    f"/paths/{path.key}",
                    np.stack([pts[:-1], pts[1:]], axis=1),
                    PATH_COLOURS.get(path.role, (120, 120, 120)),
                    thickness=0.004,
                )
        for k, p in enumerate(scene.turning_points[:200]):
            api.add_icosphere(f"/turning_points/{k}", radius=0.012, color=(230, 30, 160), position=tuple(p))
        for obstacle in scene.obstacles:
            lo, hi = np.asarray(obstacle.lower, float), np.asarray(obstacle.upper, float)
            api.add_box(
                f"/obstacles/{obstacle.name}",
                dimensions=tuple(hi - lo),
                position=tuple((lo + hi) / 2),
                color=(150, 150, 150),
                opacity=0.6,
            )
        self.status = api.add_label(
            "/status", scene.status[0] if scene.status else "", position=(0.0, 0.0, 1.55), anchor="bottom-center"
        )

    def _set(self, name: str, handle, position: np.ndarray, wxyz: np.ndarray | None = None) -> None:
        """Move a node unless it stands where it was last sent (keeps the message stream small)."""
        value = np.concatenate([position, wxyz]) if wxyz is not None else position
        last = self._sent.get(name)
        if last is not None and np.all(np.abs(last - value) <= _UNCHANGED):
            return
        self._sent[name] = value
        handle.position = position
        if wxyz is not None:
            handle.wxyz = wxyz

    def show(self, k: int) -> None:
        """Every moving node at frame ``k``."""
        scene = self.scene
        k = int(np.clip(k, 0, len(scene.t) - 1))
        for arm in scene.arms:
            poses = arm.poses[k]
            for b, handle in enumerate(self.bodies[arm.key]):
                self._set(f"{arm.key}/{b}", handle, poses[b, :3], poses[b, 3:])
        for ball in scene.balls:
            handle, string = self.balls[ball.key]
            p = ball.ball[k]
            visible = bool(np.all(np.isfinite(p)))
            if handle.visible != visible:
                handle.visible = string.visible = visible
            if visible:
                name = f"{ball.key}/ball"
                before = self._sent.get(name)
                self._set(name, handle, p)
                if self._sent.get(name) is not before:  # the ball moved: so did its string
                    string.points = np.array([[ball.pivot[k], p]], dtype=np.float32)
        if scene.status:
            self.status.text = scene.status[k]
