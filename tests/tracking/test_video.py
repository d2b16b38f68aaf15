"""Frame prefetching: order kept, the producer's errors raised in the consumer, an early stop closes the source; frames
fetched again for the looks after a first pass."""

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


def test_frames_at_takes_the_kept_frames_and_decodes_only_the_others(tmp_path):
    import cv2
    import numpy as np

    from tracking.video import frames_at

    path = tmp_path / "count.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (64, 48))
    for k in range(10):
        writer.write(np.full((48, 64, 3), 20 * k, np.uint8))
    writer.release()
    marker = np.zeros((48, 64, 3), np.uint8)
    got = frames_at(path, None, [2, 5, 7], kept={5: marker, 9: marker})
    assert sorted(got) == [2, 5, 7]
    assert got[5] is marker  # kept: not decoded again
    assert abs(float(got[7].mean()) - 140.0) < 3.0 and abs(float(got[2].mean()) - 40.0) < 3.0
    assert frames_at(path, None, [5], kept={5: marker}) == {5: marker}  # nothing to decode


def test_frames_decoded_into_buffers_are_those_decoded_afresh_and_the_buffers_are_reused(tmp_path):
    import cv2
    import numpy as np

    from tracking.video import FrameBuffers, iter_frames

    path = tmp_path / "noise.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (64, 48))
    rng = np.random.default_rng(1)
    for _ in range(30):
        writer.write(rng.integers(0, 255, (48, 64, 3), np.uint8))
    writer.release()
    fresh = [f for _, _, f in iter_frames(path)]
    buffers, kept, seen = FrameBuffers(), {}, set()
    for k, _, frame in iter_frames(path, buffers=buffers):
        assert np.array_equal(frame, fresh[k])
        seen.add(frame.__array_interface__["data"][0])
        if k in (3, 17):
            kept[k] = frame  # not handed back: never decoded into again
        else:
            buffers.give_back(frame)
    assert len(seen) <= 3  # two kept, the others decoded into one buffer again and again
    assert all(np.array_equal(f, fresh[k]) for k, f in kept.items())
