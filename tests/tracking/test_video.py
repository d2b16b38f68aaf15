"""Frame prefetching: order kept, the producer's errors raised in the consumer, an early stop closes the source; frames
fetched again for the looks after a first pass; OpenCV's pool set for a block; a video tracked with one OpenCV thread
and read ahead by the prefetch thread."""

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


def test_opencv_threads_sets_the_pool_for_the_block_and_restores_it_after_an_error_too():
    import cv2

    from tracking.video import opencv_threads

    before = cv2.getNumThreads()
    with opencv_threads(1):
        assert cv2.getNumThreads() == 1
    assert cv2.getNumThreads() == before
    with pytest.raises(RuntimeError), opencv_threads(1):
        raise RuntimeError
    assert cv2.getNumThreads() == before


def test_a_video_is_tracked_with_one_opencv_thread_and_read_ahead_by_another_thread(tmp_path, monkeypatch):
    """The tracker's calls run without OpenCV's pool (see opencv_threads) and the frames come from the prefetch
    thread, so that FFmpeg's threads decode ahead while the tracker works; the pool is as before afterwards."""
    import cv2
    import numpy as np

    from tracking import pipeline
    from tracking.color import color_spec
    from tracking.pipeline import track_video

    producers: list[str] = []

    def spy(items):  # noqa: ANN001, ANN202
        def named():
            for item in items:
                producers.append(threading.current_thread().name)
                yield item

        return real(named())

    real = pipeline.prefetched
    monkeypatch.setattr(pipeline, "prefetched", spy)
    path = tmp_path / "ball.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (160, 120))
    for k in range(12):
        frame = np.full((120, 160, 3), 30, np.uint8)
        cv2.circle(frame, (60 + 3 * k, 70), 6, (0, 0, 220), -1)
        writer.write(frame)
    writer.release()
    seen: list[tuple[int, str]] = []
    before = cv2.getNumThreads()
    track = track_video(
        path, color_spec("red"), pivot_uv=(80.0, 10.0),
        on_frame=lambda bgr, res: seen.append((cv2.getNumThreads(), threading.current_thread().name)),
    )  # fmt: skip
    assert cv2.getNumThreads() == before
    assert len(seen) == 12 and {n for n, _ in seen} == {1}
    assert track.found_fraction > 0.9
    # the frames were decoded by the prefetch thread, the tracker ran in the caller's
    assert producers and set(producers) == {"frame-prefetch"}
    assert {name for _, name in seen} == {threading.current_thread().name}
