"""The view in the browser: a viser server on loopback with play/pause, a time slider, speed and layers, or the
whole replay recorded into one self-contained HTML file (viser's embedded player: play/pause, slider, speed).
"""

from __future__ import annotations

import contextlib
import io
import threading
import time
from pathlib import Path

import numpy as np

from .draw import Drawing
from .scene import Scene

SPEEDS = ("0.1x", "0.25x", "0.5x", "1x", "2x", "4x")
CAMERA_POSITION = (1.7, 1.1, 1.2)  # [m], looking at the arm from the front right
CAMERA_LOOK_AT = (0.3, 0.0, 0.55)


def start_server(host: str = "127.0.0.1", port: int = 8080):
    """A viser server bound to ``host`` (loopback by default; port 0: any free port), its banner kept off stdout
    (``--json`` prints one object there), its share button hidden (sharing would open a tunnel to the internet) and
    its control panel docked to the right edge (collapsible, off the scene).
    """
    import viser

    with contextlib.redirect_stdout(io.StringIO()):  # viser's banner: `lbr view` prints the URL itself
        server = viser.ViserServer(host=host, port=port, verbose=False)
    server.gui.configure_theme(show_share_button=False)
    server.gui.main_panel.dock_right()  # viser ≥ 1.1: replaces configure_theme(control_layout="collapsible")
    server.initial_camera.position = CAMERA_POSITION
    server.initial_camera.look_at = CAMERA_LOOK_AT
    return server


def stop_server(server) -> None:
    with contextlib.redirect_stdout(io.StringIO()):  # "(viser) Server stopped"
        server.stop()


def offline_html(scene: Scene, robot) -> str:
    """The replay as one HTML page that needs nothing but a browser: viser's client with the recording embedded,
    every frame at its time (viser's player shows play/pause, a time slider and the speed)."""
    server = start_server(port=0)
    try:
        drawing = Drawing(server.scene, scene, robot)
        drawing.show(0)
        recorder = server.get_scene_serializer()
        period = 1.0 / scene.settings.fps
        for k in range(1, len(scene.t)):
            recorder.insert_sleep(period)
            drawing.show(k)
        recorder.insert_sleep(period)
        return recorder.as_html()
    finally:
        stop_server(server)


def write_offline(scene: Scene, robot, out: Path) -> int:
    """Write :func:`offline_html` to ``out`` (temporary name, renamed when complete); its size [bytes]."""
    from ..outputs import atomic_path

    html = offline_html(scene, robot).encode()
    with atomic_path(out) as tmp:
        Path(tmp).write_bytes(html)
    return len(html)


class Player:
    """Plays a :class:`Scene` on a live server: a loop thread advances the time line at the chosen speed, the GUI
    (play/pause, time slider, speed, loop, layers, the state) steers it; every client sees the same time."""

    def __init__(self, server, scene: Scene, robot) -> None:
        self.server, self.scene = server, scene
        self.drawing = Drawing(server.scene, scene, robot)
        self.t = 0.0  # [s] on the time line
        self.speed = 1.0
        self.playing = True
        self.frames_shown = 0
        self._shown = -1
        self._gui_updated = 0.0  # [s] monotonic time the slider and the state were last sent
        self._lock = threading.Lock()
        self._stop = threading.Event()
        gui = server.gui
        with gui.add_folder("Replay"):
            self.button = gui.add_button("Pause")
            self.slider = gui.add_slider(
                "time [s]", min=0.0, max=max(scene.duration, 1e-3), step=1.0 / scene.settings.fps, initial_value=0.0
            )
            self.speed_menu = gui.add_dropdown("speed", SPEEDS, initial_value="1x")
            self.loop = gui.add_checkbox("loop", initial_value=True)
            self.state = gui.add_markdown(scene.status[0] if scene.status else "")
        with gui.add_folder("Layers"):
            for key, handles in self._layers():
                box = gui.add_checkbox(key, initial_value=True)
                box.on_update(lambda _, hs=handles, b=box: [setattr(h, "visible", b.value) for h in hs])
        self.button.on_click(lambda _: self.toggle())
        self.slider.on_update(self._on_slider)
        self.speed_menu.on_update(lambda _: setattr(self, "speed", float(self.speed_menu.value.rstrip("x"))))
        self.show_time(0.0)
        self._thread = threading.Thread(target=self._run, name="lbr-view-player", daemon=True)
        self._thread.start()

    def _layers(self) -> list[tuple[str, list]]:
        out = [(f"arm {arm.key}", self.drawing.bodies[arm.key]) for arm in self.scene.arms]
        out += [(f"ball {key}", list(handles)) for key, handles in self.drawing.balls.items()]
        return out

    def toggle(self) -> None:
        self.playing = not self.playing
        self.button.label = "Pause" if self.playing else "Play"

    def _on_slider(self, event) -> None:
        if event.client is None:  # our own update of the slider as the replay runs
            return
        with self._lock:
            self.playing = False
            self.button.label = "Play"
            self.show_time(float(self.slider.value), move_slider=False)

    def show_time(self, t: float, move_slider: bool = True) -> None:
        """Show the frame at time ``t`` [s] (clamped to the time line); the slider and the state panel follow at
        ≤ 10 Hz while playing (the scene's own label every frame), so the GUI does not crowd the scene's updates."""
        scene = self.scene
        self.t = float(np.clip(t, 0.0, scene.duration))
        k = int(round(self.t * scene.settings.fps))
        if k != self._shown:
            with self.server.atomic():
                self.drawing.show(k)
            self._shown = k
            self.frames_shown += 1
        now = time.monotonic()
        if move_slider and self.playing and now - self._gui_updated < 0.1:
            return
        self._gui_updated = now
        if scene.status:
            self.state.content = scene.status[min(k, len(scene.status) - 1)]
        if move_slider:
            self.slider.value = round(self.t, 6)

    def _run(self) -> None:
        period = 1.0 / self.scene.settings.fps
        last = time.monotonic()
        while not self._stop.wait(period / 2):
            now = time.monotonic()
            with self._lock:
                if self.playing:
                    t = self.t + (now - last) * self.speed
                    if t > self.scene.duration:
                        if self.loop.value:
                            t = 0.0
                        else:
                            t = self.scene.duration
                            self.toggle()
                    self.show_time(t)
            last = now

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
