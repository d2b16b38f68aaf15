"""The preview caption is legible: the white text lies inside its dark outline (OpenCV 5.0 draws the two at
different widths, the caption then smears; pyproject bounds OpenCV below 5)."""

import numpy as np
import pytest


def caption_masks():
    from tracking.overlay import draw_overlay

    frame = np.full((60, 640, 3), 128, np.uint8)
    draw_overlay(frame, 12.345, (600.0, 50.0), 4.0, (620.0, 50.0), 0.5)
    band = frame[:45, :560].astype(int)  # the caption area, clear of the ball and pivot drawings
    text = (band > 200).all(axis=2)
    outline = (band < 60).all(axis=2)
    return text, outline


def _columns(mask):
    cols = np.flatnonzero(mask.any(axis=0))
    return cols.min(), cols.max()


def test_caption_text_sits_inside_its_outline():
    import cv2

    major = int(cv2.__version__.split(".")[0])
    if major >= 5:
        pytest.skip(f"OpenCV {cv2.__version__} is outside the project's bound (<5); `pip install -e .` installs 4.x")
    text, outline = caption_masks()
    assert text.sum() > 200 and outline.sum() > text.sum()
    t0, t1 = _columns(text)
    o0, o1 = _columns(outline)
    assert o0 <= t0 and t1 <= o1 and (t0 - o0) <= 4 and (o1 - t1) <= 4  # same width, outline 1-2 px around
    # text pixels have outline within 3 px to their left or right on their row (the halo that makes it legible)
    rows, cols = np.nonzero(text)
    near = np.zeros(len(rows), bool)
    for d in range(1, 4):
        near |= outline[rows, np.clip(cols - d, 0, text.shape[1] - 1)]
        near |= outline[rows, np.clip(cols + d, 0, text.shape[1] - 1)]
    assert near.mean() > 0.75  # 0.88 with OpenCV 4.14; 0.51 with 5.0
