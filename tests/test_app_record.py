"""Recording plumbing and the latest-frame slot (no windows)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from app.record import FrameWriter, RecordError, format_of, over_rgb, to_straight, track_path_for
from app.workers import LatestSlot


def _pm_frames(n: int, w: int = 64, h: int = 48) -> list[np.ndarray]:
    """Premultiplied RGBA frames: a moving opaque red square on a half-transparent blue field."""
    out = []
    for i in range(n):
        a = np.zeros((h, w, 4), np.uint8)
        a[..., 2] = 64  # blue at alpha 128, premultiplied: 128 * 0.5
        a[..., 3] = 128
        a[:, :4] = 0  # a fully transparent margin on the left
        x = 4 + 3 * i
        a[10:30, x:x + 16] = (255, 0, 0, 255)
        out.append(a)
    return out


def test_latest_slot_overwrites_and_counts_drops():
    s = LatestSlot()
    assert s.take() is None
    assert s.put(1) is False
    assert s.put(2) is True and s.put(3) is True
    assert s.dropped == 2
    assert s.take() == 3
    assert s.take() is None
    assert s.delivered == 1


def test_latest_slot_slow_consumer_sees_newest_not_a_queue():
    s = LatestSlot()
    produced = 200
    seen = []

    def producer():
        for i in range(produced):
            s.put(i)
            time.sleep(0.0005)

    t = threading.Thread(target=producer)
    t.start()
    while t.is_alive():
        v = s.take(timeout=0.05)
        if v is not None:
            seen.append(v)
            time.sleep(0.01)  # a slow renderer
    t.join()
    v = s.take()
    if v is not None:
        seen.append(v)
    assert seen == sorted(seen)
    assert seen[-1] == produced - 1
    assert s.dropped + len(seen) == produced
    assert s.dropped > 0


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), st.integers(0, 255))
def test_over_rgb_and_straight_agree(r, g, b, a):
    straight = np.array([[[r, g, b, a]]], np.uint8)
    pm = np.round(straight[..., :3].astype(float) * a / 255).astype(np.uint8)
    pm = np.concatenate([pm, straight[..., 3:]], axis=2)
    bg = (10, 200, 30)
    got = over_rgb(pm, bg).astype(int)[0, 0]
    want = np.array([r, g, b]) * a / 255 + np.array(bg) * (255 - a) / 255
    assert np.all(np.abs(got - want) <= 1.01)
    if a >= 16:
        back = to_straight(pm)[0, 0].astype(int)
        assert np.all(np.abs(back[:3] - [r, g, b]) <= 255 / a + 1)


def test_format_of_and_track_path(tmp_path):
    assert format_of(tmp_path / "a.mp4") == "mp4"
    assert format_of(tmp_path / "a.GIF") == "gif"
    assert format_of(tmp_path / "frames") == "png"
    assert track_path_for(tmp_path / "a.mp4") == tmp_path / "a.csv"
    assert track_path_for(tmp_path / "frames") == tmp_path / "frames" / "track.csv"
    with pytest.raises(RecordError, match="unknown output format"):
        format_of(tmp_path / "a.docx")


def test_mp4_writer(tmp_path):
    import cv2

    out = tmp_path / "clip.mp4"
    w = FrameWriter(out, fps=15, background=(255, 255, 255))
    for f in _pm_frames(12):
        w.write(f)
    assert w.close() == out
    cap = cv2.VideoCapture(str(out))
    n = 0
    while True:
        ok, img = cap.read()
        if not ok:
            break
        if n == 0:
            assert img.shape[:2] == (48, 64)
            # the red square is red, the half-transparent blue over white is light blue
            assert img[20, 10, 2] > 200 and img[20, 10, 0] < 60
            assert img[40, 50, 0] > 180 and 100 < img[40, 50, 2] < 160
        n += 1
    assert n == 12
    assert not list(tmp_path.glob(".*part*"))


def test_png_sequence_keeps_alpha(tmp_path):
    w = FrameWriter(tmp_path / "seq", fps=30, background=None)
    for f in _pm_frames(3):
        w.write(f)
    folder = w.close()
    files = sorted(folder.glob("*.png"))
    assert len(files) == 3
    im = np.asarray(Image.open(files[0]))
    assert im.shape == (48, 64, 4)
    assert im[40, 50, 3] == 128 and abs(int(im[40, 50, 2]) - 128) <= 1  # straight alpha
    assert tuple(im[20, 10]) == (255, 0, 0, 255)


def test_gif_transparent_and_opaque(tmp_path):
    w = FrameWriter(tmp_path / "t.gif", fps=10, background=None)
    for f in _pm_frames(4):
        w.write(f)
    w.close()
    with Image.open(tmp_path / "t.gif") as im:
        assert im.n_frames == 4
        rgba = np.asarray(im.convert("RGBA"))
        assert rgba[5, 1, 3] == 0 and rgba[20, 10, 3] == 255
    w = FrameWriter(tmp_path / "o.gif", fps=10, background="#00b140")
    for f in _pm_frames(2):
        w.write(f)
    w.close()
    with Image.open(tmp_path / "o.gif") as im:
        rgb = np.asarray(im.convert("RGB"))
        assert rgb[2, 2, 1] > 100  # green screen shows through the transparent parts


def test_unwritable_folder_is_one_line_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(RecordError) as e:
        FrameWriter(blocker / "sub" / "a.mp4")
    assert "\n" not in str(e.value) and "sub" in str(e.value)
