"""Frame prefetching: order kept, the producer's errors raised in the consumer, an early stop closes the source."""

import threading

import pytest

from tracking.video import prefetched
from trajectories.errors import InputError


def test_items_arrive_in_order_from_another_thread():
    seen_threads = set()

    def source():
        for k in range(200):
            seen_threads.add(threading.current_thread().name)
            yield k

    assert list(prefetched(source(), depth=3)) == list(range(200))
    assert seen_threads == {"frame-prefetch"}


def test_an_error_of_the_source_is_raised_in_the_consumer_after_the_items_before_it():
    def source():
        yield 1
        yield 2
        raise InputError("video has no decodable frames", file="x.mp4")

    got = []
    with pytest.raises(InputError, match="no decodable frames"):
        for item in prefetched(source()):
            got.append(item)
    assert got == [1, 2]


def test_a_consumer_that_stops_early_closes_the_source():
    closed = threading.Event()

    def source():
        try:
            k = 0
            while True:
                yield k
                k += 1
        finally:
            closed.set()

    for item in prefetched(source(), depth=2):
        if item == 5:
            break
    assert closed.wait(5.0)
