"""A real headless browser for the view's tests and benchmark: Debian's Chromium driven over CDP by playwright (a
test dependency; no browser is downloaded). ``.ci/run`` installs Chromium; tests skip without it
(``tests/helpers/browser.py``)."""

from __future__ import annotations

import contextlib
import shutil
import tempfile
import time

import numpy as np

CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)

# The position of a scene node in the scene's own frame (the robot's base frame), whatever viser's root does.
NODE_POSITION_JS = """name => {
  const m = window.__viserMutable, o = m && m.nodeRefFromName[name], root = m && m.nodeRefFromName[''];
  if (!o || !root) return null;
  o.updateWorldMatrix(true, false);
  const v = o.position.clone();
  o.getWorldPosition(v);
  root.worldToLocal(v);
  return [v.x, v.y, v.z, o.visible];
}"""
STATUS_JS = (
    "() => { const s = window.__viserSceneTree && window.__viserSceneTree.getState()['/status']; "
    "return s ? s.message.props.text : null; }"
)


def chromium_path() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


@contextlib.contextmanager
def page(viewport=(480, 320)):
    """A fresh page in headless Chromium; yields (page, console) where console collects (type, text) of every
    console message and page error."""
    from playwright.sync_api import sync_playwright

    executable = chromium_path()
    if executable is None:
        raise FileNotFoundError("no Chromium (apt-get install chromium)")
    console: list[tuple[str, str]] = []
    with tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            profile,
            executable_path=executable,
            headless=True,
            args=list(CHROMIUM_FLAGS),
            viewport={"width": viewport[0], "height": viewport[1]},
        )
        try:
            pg = context.pages[0] if context.pages else context.new_page()
            pg.set_default_timeout(120_000)  # [ms]: a software-rendered page on a loaded machine answers late
            pg.on("console", lambda m: console.append((m.type, m.text)))
            pg.on("pageerror", lambda e: console.append(("pageerror", str(e))))
            yield pg, console
        finally:
            context.close()


def errors(console: list[tuple[str, str]]) -> list[tuple[str, str]]:
    return [(kind, text) for kind, text in console if kind in ("error", "pageerror")]


def node_position(pg, name: str) -> np.ndarray | None:
    value = pg.evaluate(NODE_POSITION_JS, name)
    return None if value is None else np.array(value[:3])


def wait_for_scene(pg, node: str, timeout: float = 120.0) -> None:
    """Wait until the page's scene has ``node`` (polled: a software-rendered page starves animation frames)."""
    deadline = time.monotonic() + timeout
    while pg.evaluate(NODE_POSITION_JS, node) is None:
        assert time.monotonic() < deadline, f"{node} never appeared in the page's scene"
        time.sleep(0.1)


def status(pg) -> str | None:
    return pg.evaluate(STATUS_JS)


def status_time(text: str) -> float:
    """The time line's time [s] from the status label 't = 1.234 s · …'."""
    return float(text.split("=")[1].split("s")[0])
