"""The simulated camera filming the simulated ball: the simulator publishes its ball, a camera renders it.

Every cycle the camera plant (:class:`SimCamera`, in the simulator's process) writes the ball plant's state — the
ball's centre and the pivot [m] (base frame), stamped with ``time.monotonic()`` — into a :class:`SceneRing`, a small
file mapped into memory by both sides. The camera (:class:`lbrcli.lab.camera_stream.CameraProcess`, MJPEG over HTTP
on loopback, started by the client before the simulator) renders frame k from that ring at its own frame times,
interpolating between the simulator's cycles; a frame never shows a moment the simulator has not reached yet (the
camera waits for it, as a real shutter cannot open on the future). Before the simulator's first cycle the ring holds
the ball hanging at the start pose.

Time stamps: the ball plant reports after cycle k the ball at cycle k−1 (see :mod:`.ball`); the ring pairs it with
the TCP and the monotonic time of cycle k−1 — the pose the client read from that cycle's message at that time.
"""

from __future__ import annotations

import math
import mmap
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from trajectories.errors import OptionError, SettingError

RING_ROWS = 4096  # samples kept (≥ 4 s at 1 ms cycles); a frame looks back at most exposure + latency
_WAIT_S = 0.05  # [s] longest wait for the simulator to reach a frame's moment (then the newest sample is shown)
_LIVE_S = 0.05  # [s] a newest sample older than this before a frame's moment: no simulator writing, no wait


class SceneRing:
    """(t [s, monotonic], ball xyz [m], pivot xyz [m]) samples (a :class:`~lbrcli.lab.timed_ring.TimedRing`) in a
    file mapped into memory (``path``): one writer (the simulator's loop), readers in other processes. Callable as
    the camera's scene: ``scene(t)`` for scene time t [s] since ``started(t_start)``. :meth:`create` makes the file,
    :meth:`attach` maps an existing one."""

    def __init__(self, path: str, rows: int = RING_ROWS) -> None:
        from lbrcli.lab.timed_ring import TimedRing

        self.path = path
        with open(path, "r+b") as f:
            self._mm = mmap.mmap(f.fileno(), TimedRing.nbytes(rows, 6))
        self.ring = TimedRing(rows, 6, self._mm)
        self.t0 = math.nan  # [s, monotonic] scene time 0

    @classmethod
    def create(cls, rows: int = RING_ROWS) -> "SceneRing":
        """A new, empty ring in a temporary file (in /dev/shm where there is one); :meth:`remove` deletes it."""
        from lbrcli.lab.timed_ring import TimedRing

        folder = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None
        fd, path = tempfile.mkstemp(prefix="lbr-scene-", suffix=".bin", dir=folder)
        with os.fdopen(fd, "wb") as f:
            f.truncate(TimedRing.nbytes(rows, 6))
        return cls(path, rows)

    def remove(self) -> None:
        try:
            os.unlink(self.path)
        except OSError:
            pass

    def push(self, t: float, ball: Sequence[float], pivot: Sequence[float]) -> None:
        """Append a sample at monotonic time t [s]."""
        self.ring.push(t, (*ball, *pivot))

    def __len__(self) -> int:
        return len(self.ring)

    def started(self, t_start: float) -> None:
        self.t0 = t_start

    @property
    def live_since(self) -> float | None:
        """When the simulator wrote its first sample [s, monotonic] (the first is the hanging start), None before."""
        return self.ring.time_of(1) if len(self.ring) >= 2 else None

    def at(self, t: float, wait_s: float = _WAIT_S) -> tuple[np.ndarray, np.ndarray]:
        """(ball, pivot) [m] at monotonic time t [s], linear between samples; before the first sample the first,
        after the newest the newest (once the simulator has reached t, or ``wait_s`` [s] waited, or at once when the
        newest sample is ``_LIVE_S`` older than t: no simulator is writing)."""
        deadline = None
        while True:
            newest = self.ring.newest_t
            if newest >= t or newest < t - _LIVE_S:  # reached, or no simulator writing (not yet, or stalled)
                break
            now = time.monotonic()
            deadline = deadline if deadline is not None else now + wait_s
            if now >= deadline:
                break
            time.sleep(0.0005)
        row = self.ring.at(t)
        if row is None:
            raise ValueError("the scene has no sample yet")
        return row[:3], row[3:]

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        return self.at(self.t0 + t)


@dataclass(frozen=True)
class SimCameraSpec:
    """The camera plant: publishes the ball plant (which must come before it in ``SimConfig.plants``) into the
    :class:`SceneRing` at ``ring_path`` (made by :meth:`SceneRing.create`, read by the camera). Picklable."""

    ring_path: str

    def validate(self) -> None:
        if not Path(self.ring_path).is_file():
            raise OptionError(f"the simulated camera's scene file {self.ring_path} does not exist")

    def build(self, context) -> "SimCamera":
        from .ball import Ball

        self.validate()
        ball = next((p for p in context.plants if isinstance(p, Ball)), None)
        if ball is None:
            raise SettingError(SimCameraSpec, "ball", "the simulated camera needs a simulated ball before it")
        return SimCamera(SceneRing(self.ring_path), ball, context.robot.fk(context.q0).translation)


class SimCamera:
    """Writes the ball's state into the scene ring every cycle."""

    name = "camera"
    inputs: tuple[str, ...] = ()

    def __init__(self, ring: SceneRing, ball, tcp0: Sequence[float]) -> None:
        self._ball = ball
        self.ring = ring
        self._prev = (time.monotonic(), np.asarray(tcp0, float))

    def step(self, t: float, tcp: Sequence[float]) -> tuple[()]:
        now = time.monotonic()
        t_prev, p_prev = self._prev
        stepper = self._ball.stepper  # the ball and the pivot at the previous cycle (see the module) [m]
        self.ring.push(t_prev, tuple(stepper.b), np.asarray(stepper.p, float))
        self._prev = (now, tcp)
        return ()

    def info(self) -> dict:
        return {}

    def figures(self) -> dict:
        return {"camera_samples": len(self.ring)}

    def close(self) -> None:
        pass


def hanging_scene(ring: SceneRing, pivot_m: Sequence[float], string_m: float) -> None:
    """Start the ring with the ball hanging still below ``pivot_m`` [m] (before the simulator runs)."""
    p = np.asarray(pivot_m, float)
    ring.push(time.monotonic(), p - np.array([0.0, 0.0, string_m]), p)
