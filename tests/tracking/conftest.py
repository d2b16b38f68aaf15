"""The tracking tests' shared fixture: the scenarios of tracking.scenarios rendered and tracked once per module."""

from __future__ import annotations

import pytest

from tracking import scenarios
from tracking.color import color_spec
from tracking.pipeline import track_video

SCENARIO_SIZE = (480, 270)  # [px] ball radius ≈ 4.6 px


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """run(name, duration_s=2.0) → (scenario, track, outcome), each scenario rendered and tracked once per module."""
    folder = tmp_path_factory.mktemp("scenarios")
    cache = {}

    def get(name, duration_s=2.0):
        if name not in cache:
            sc = scenarios.ALL[name](folder / f"{name}.mp4", SCENARIO_SIZE, duration_s)
            kw = dict(sc.track_kwargs)
            ball = kw.pop("ball", color_spec("red"))
            track = track_video(sc.path, ball, **kw)
            cache[name] = (sc, track, scenarios.score(sc, track))
        return cache[name]

    return get
