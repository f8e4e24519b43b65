"""Exports line up and stream: GIF timing and looks, flat memory, one track row per frame."""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np
import pytest
from PIL import Image, ImageSequence

from app.record import FrameWriter, GifStream, RecordError, Recorder, to_straight
from benchmarks.soak_window import count_video_frames
from tracker.params import FaceParams, read_csv


def _scene(i: int, size: int = 96) -> np.ndarray:
    """Premultiplied RGBA: a soft-edged disc with a colour ramp, moving, on a transparent field."""
    yy, xx = np.mgrid[:size, :size]
    cx, cy = size / 2 + size / 4 * math.sin(i / 7), size / 2 + size / 6 * math.cos(i / 5)
    a = np.clip((size / 3 - np.hypot(xx - cx, yy - cy)) * 6, 0, 255).astype(np.uint16)
    f = np.zeros((size, size, 4), np.uint8)
    f[..., 0] = a * (128 + (xx * 127) // size) // 255
    f[..., 1] = a * (60 + (yy * 120) // size) // 255
    f[..., 2] = a * 40 // 255
    f[..., 3] = a
    return f


def _gif_frames(path) -> tuple[list[np.ndarray], list[int]]:
    with Image.open(path) as im:
        frames = [np.asarray(f.convert("RGBA")) for f in ImageSequence.Iterator(im)]
    with Image.open(path) as im:
        durations = [f.info["duration"] for f in ImageSequence.Iterator(im)]
    return frames, durations


@pytest.mark.parametrize("fps", [30, 15, 10, 24, 25])
def test_gif_delays_alternate_to_average_the_rate(fps):
    g = GifStream(io.BytesIO(), fps)
    delays = [g.delay_cs(i) for i in range(600)]
    assert set(delays) <= {math.floor(100 / fps), math.ceil(100 / fps)}
    for n in (3, 10, 77, 600):  # the clock never drifts by more than half a centisecond
        assert abs(sum(delays[:n]) - n * 100 / fps) <= 0.5
    if fps == 30:
        assert delays[:6] == [3, 4, 3, 3, 4, 3]


def test_gif_file_plays_at_the_rate_and_shows_the_pictures(tmp_path):
    out = tmp_path / "a.gif"
    w = FrameWriter(out, fps=30, background=(250, 248, 243))
    want = []
    for i in range(45):
        pm = _scene(i)
        w.write(pm)
        a = pm[..., 3:4].astype(np.uint16)
        want.append(np.minimum(pm[..., :3] + (np.array([250, 248, 243], np.uint16) * (255 - a) + 127) // 255, 255))
    w.close()
    frames, durations = _gif_frames(out)
    assert len(frames) == 45
    assert sum(durations) == pytest.approx(45 * 1000 / 30, abs=10)  # 1.5 s, not 1.35 s
    for got, ref in zip(frames, want):
        err = np.abs(got[..., :3].astype(int) - ref.astype(int)).max(axis=2)
        assert err.mean() < 2.0 and np.percentile(err, 99.5) <= 16
    assert out.stat().st_size < 45 * 96 * 96  # the unchanged paper is not stored again and again


def test_transparent_gif_keeps_the_shape(tmp_path):
    out = tmp_path / "t.gif"
    w = FrameWriter(out, fps=15, background=None)
    scenes = [_scene(i) for i in range(12)]
    for pm in scenes:
        w.write(pm)
    w.close()
    frames, durations = _gif_frames(out)
    assert len(frames) == 12 and durations[:3] == [70, 60, 70]
    for got, pm in zip(frames, scenes):
        assert np.array_equal(got[..., 3] == 255, pm[..., 3] >= 128)  # cleared between frames
        inside = pm[..., 3] >= 128
        assert np.abs(got[inside, :3].astype(int) - to_straight(pm)[inside, :3]).max() <= 24


def _rss_kb() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError("no VmRSS")


@pytest.mark.parametrize("name", ["long.gif", "long_alpha.gif", "frames"])
def test_gif_and_png_writers_hold_no_frames(tmp_path, name):
    """RSS over a long stream of 256×256 frames stays put. Holding the frames, as the GIF export
    once did, would add at least 64 kB a frame (19 MB over these 300)."""
    size = 256
    base = [np.ascontiguousarray(np.kron(_scene(i, 64), np.ones((4, 4, 1), np.uint8))) for i in range(24)]
    w = FrameWriter(tmp_path / name, fps=30, background=None if "alpha" in name or name == "frames" else (255, 255, 255))
    marks = []
    for i in range(400):
        f = np.roll(base[i % len(base)], i % 17, axis=1)
        f[i % size, :, :] = (i * 7) % 255  # a line that moves: every frame differs
        w.write(f)
        if i in (99, 399):
            marks.append(_rss_kb())
    w.close()
    assert w.frames == 400
    assert marks[1] - marks[0] < 6 * 1024, f"RSS grew {marks[1] - marks[0]} kB over 300 frames"


@dataclass
class _Frame:  # what app.workers.DisplayFrame gives the recorder
    rgba: np.ndarray
    time: float
    params: FaceParams | None



@pytest.mark.parametrize("source_fps, out_fps", [(30, 30), (10, 30), (30, 10), (24, 15)])
def test_the_track_has_one_row_per_written_frame(tmp_path, source_fps, out_fps):
    out = tmp_path / "take.mp4"
    rec = Recorder(out, fps=out_fps)
    for i in range(2 * source_fps):  # two seconds
        params = None if i == 0 else FaceParams(frame=1000 + i, mid_x=float(i), time=i / source_fps)
        rec.add(_Frame(_scene(i, 32), i / source_fps, params))
    res = rec.finish()
    rows = read_csv(res.track)
    n = count_video_frames(out)
    last_t = (2 * source_fps - 1) / source_fps  # frames sit on the output clock by their times
    assert n == res.frames == len(rows) == math.floor(last_t * out_fps + 1e-6) + 1
    assert [r.frame for r in rows] == list(range(n))
    assert np.allclose([r.time for r in rows], np.arange(n) / out_fps, atol=1e-4)
    assert sum(r.status == "lost" for r in rows) == sum(1 for r in rows if math.isnan(r.mid_x)) >= 1
    mids = [r.mid_x for r in rows if not math.isnan(r.mid_x)]
    assert mids == sorted(mids)  # frames in order, repeated when the output rate is higher


def test_finish_reports_progress_and_a_failed_write_leaves_nothing(tmp_path):
    rec = Recorder(tmp_path / "a.gif", fps=30)
    for i in range(30):
        rec.add_rgba(_scene(i, 48), FaceParams())
    seen = []
    res = rec.finish(progress=lambda done, total: seen.append((done, total)))
    assert res.frames == 30 and rec.pending == 0
    assert all(d <= t for d, t in seen)
    rec = Recorder(tmp_path / "b.gif", fps=30)
    rec.add_rgba(_scene(0, 48), FaceParams())
    rec.add_rgba(_scene(1, 64), FaceParams())  # another size: the GIF cannot take it
    with pytest.raises(Exception, match="b.gif"):
        rec.finish()
    assert not (tmp_path / "b.gif").exists() and not (tmp_path / "b.csv").exists()
    assert not list(tmp_path.glob(".*"))


@pytest.mark.parametrize("name", ["a.gif", "a.mp4", "frames/a.png"])
def test_stop_before_the_first_frame_says_nothing_was_written(tmp_path, name):
    """A recording stopped before a frame arrived used to report "Saved 0 frames to a.gif" for a
    file that was never made."""
    rec = Recorder(tmp_path / name, fps=30)
    with pytest.raises(RecordError, match="nothing was written"):
        rec.finish()
    assert not (tmp_path / name).exists() and not list(tmp_path.glob("*.csv")) and not list(tmp_path.glob(".*"))
