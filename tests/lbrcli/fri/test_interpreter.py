"""Python's settings around an FRI loop: no automatic collection, a short switch interval, both restored; with
``LBR_FRI_PROFILE`` the loop's profile written where it names."""

from __future__ import annotations

import gc
import pstats
import sys

from lbrcli.fri.interpreter import PROFILE_ENV, SWITCH_INTERVAL_S, loop_settings


def _cycle_work() -> int:
    return sum(range(100))


def test_the_loop_runs_without_collection_and_restores_the_settings(monkeypatch):
    monkeypatch.delenv(PROFILE_ENV, raising=False)
    switch, enabled = sys.getswitchinterval(), gc.isenabled()
    with loop_settings():
        assert not gc.isenabled() and sys.getswitchinterval() <= SWITCH_INTERVAL_S
    assert sys.getswitchinterval() == switch and gc.isenabled() == enabled


def test_the_profile_of_the_loop_is_written_when_asked(monkeypatch, tmp_path):
    out = tmp_path / "loop.prof"
    monkeypatch.setenv(PROFILE_ENV, str(out))
    with loop_settings():
        for _ in range(3):
            _cycle_work()
    calls = {fn: v[1] for (_, _, fn), v in pstats.Stats(str(out)).stats.items()}
    assert calls.get("_cycle_work") == 3  # what ran inside the loop, counted
    assert sys.getprofile() is None  # and the profiler is off again
