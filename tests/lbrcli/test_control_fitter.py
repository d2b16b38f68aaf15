"""The rod's fit in lock-step: taken at a fixed cycle however long the worker took."""

import threading
from concurrent.futures import Future

from lbrcli.control.fitter import _AfterCycles


def test_a_fit_is_taken_exactly_at_its_cycle_when_ready_before():
    f: Future = Future()
    f.set_result("rod")
    h = _AfterCycles(f, 3)
    assert [h.done() for _ in range(5)] == [False, False, False, True, True] and h.result() == "rod"


def test_a_late_fit_is_waited_for_at_its_cycle_not_skipped():
    f: Future = Future()
    h = _AfterCycles(f, 2)
    assert not h.done() and not h.done()
    threading.Timer(0.05, f.set_result, args=("late rod",)).start()  # finishes while the third poll waits
    assert h.done() and h.result() == "late rod"


def test_a_failed_fit_is_done_and_raises_at_its_cycle():
    f: Future = Future()
    f.set_exception(RuntimeError("worker died"))
    h = _AfterCycles(f, 1)
    assert not h.done() and h.done()
    try:
        h.result()
    except RuntimeError as exc:
        assert "worker died" in str(exc)
    else:
        raise AssertionError("the worker's error was lost")
