"""Frame sources: video files, cameras (faked), the synthetic performer, the fake camera."""

from __future__ import annotations

import threading
import time

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as hs

from tracker import sources
from tracker.sources import (
    CameraSource,
    FakeCamera,
    Frame,
    FrameSource,
    SourceError,
    SyntheticSource,
    VideoFileSource,
    open_source,
)
from tracker.synthetic import Performance


def frames_of(n: int, w: int = 64, h: int = 48) -> list[np.ndarray]:
    out = []
    for i in range(n):
        img = np.zeros((h, w, 3), np.uint8)
        img[:, :, 0] = (i * 37) % 256
        img[:, :, 1] = np.linspace(0, 255, w, dtype=np.uint8)[None, :]
        img[: h // 2, : w // 2, 2] = 200
        out.append(img)
    return out


def write_video(path, frames, fps=25.0, fourcc="mp4v"):
    h, w = frames[0].shape[:2]
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    assert wr.isOpened()
    for f in frames:
        wr.write(f)
    wr.release()


@pytest.mark.parametrize("suffix,fourcc", [(".mp4", "mp4v"), (".avi", "MJPG"), (".mkv", "FFV1")])
def test_written_video_reads_back(tmp_path, suffix, fourcc):
    frames = frames_of(23, 96, 64)
    path = tmp_path / f"clip{suffix}"
    write_video(path, frames, fps=25.0, fourcc=fourcc)
    with VideoFileSource(path) as src:
        assert isinstance(src, FrameSource)
        assert src.size == (96, 64)
        assert src.fps == pytest.approx(25.0)
        got = list(src)
        assert len(got) == 23
        assert [f.index for f in got] == list(range(23))
        assert got[10].time == pytest.approx(10 / 25.0)
        assert all(f.image.shape == (64, 96, 3) and f.image.dtype == np.uint8 for f in got)
        if fourcc == "FFV1":  # lossless: exact colours
            assert all(np.array_equal(a.image, b) for a, b in zip(got, frames))
        else:
            assert np.abs(got[5].image.astype(int) - frames[5]).mean() < 6
        again = list(src)  # a second pass starts from the beginning
        assert len(again) == 23 and np.array_equal(again[0].image, got[0].image)
    assert src.closed


def test_video_frame_by_index(tmp_path):
    frames = frames_of(6)
    path = tmp_path / "c.mkv"
    write_video(path, frames, fourcc="FFV1")
    with VideoFileSource(path) as src:
        assert np.array_equal(src.frame(0), frames[0])
        assert np.array_equal(src.frame(4), frames[4])
        with pytest.raises(SourceError, match="no frame 9"):
            src.frame(9)
        assert len(list(src)) == 6  # reading a frame by index leaves iteration alone


def test_missing_file_names_it(tmp_path):
    missing = tmp_path / "nowhere" / "clip.mp4"
    with pytest.raises(SourceError, match="clip.mp4") as e:
        VideoFileSource(missing)
    assert "\n" not in str(e.value) and "no such video file" in str(e.value)


def test_not_a_video_names_it(tmp_path):
    junk = tmp_path / "notes.mp4"
    junk.write_text("this is not a video\n" * 20)
    with pytest.raises(SourceError, match="notes.mp4"):
        VideoFileSource(junk)
    with pytest.raises(SourceError, match="folder"):
        VideoFileSource(tmp_path)
    empty = tmp_path / "empty.avi"
    empty.write_bytes(b"")
    with pytest.raises(SourceError, match="empty.avi"):
        VideoFileSource(empty)


def test_camera_that_does_not_exist_fails_cleanly():
    for bad in (97, -1, "front"):
        with pytest.raises(SourceError) as e:
            CameraSource(bad, timeout=2.0)
        msg = str(e.value)
        assert "camera" in msg and str(bad) in msg and "\n" not in msg


class _FakeCapture:
    """Stands in for cv2.VideoCapture: plays frames, or hangs, or refuses to open."""

    behaviour = "play"
    frames: list = []

    def __init__(self, index):
        if self.behaviour == "hang":
            time.sleep(3.0)
        self.i = 0
        self.released = False

    def isOpened(self):
        return self.behaviour != "closed"

    def set(self, prop, value):
        return True

    def get(self, prop):
        return 15.0 if prop == cv2.CAP_PROP_FPS else 0.0

    def read(self):
        if self.behaviour == "dead" or self.i >= len(self.frames):
            return False, None
        self.i += 1
        return True, self.frames[self.i - 1]

    def release(self):
        self.released = True


@pytest.fixture
def fake_cv_camera(monkeypatch):
    monkeypatch.setattr(sources, "_device_missing", lambda index: False)
    monkeypatch.setattr(sources.cv2, "VideoCapture", _FakeCapture)
    _FakeCapture.frames = frames_of(7, 80, 60)
    _FakeCapture.behaviour = "play"
    return _FakeCapture


def test_camera_source_plays_what_the_device_delivers(fake_cv_camera):
    with CameraSource(0, size=(80, 60), fps=15) as cam:
        assert cam.size == (80, 60) and cam.fps == 15.0
        got = list(cam)
    assert [f.index for f in got] == list(range(7))
    assert np.array_equal(got[3].image, fake_cv_camera.frames[3])
    assert all(b.time >= a.time for a, b in zip(got, got[1:]))


@pytest.mark.parametrize("behaviour,message", [("closed", "cannot be opened"), ("dead", "no frames"),
                                               ("hang", "did not respond")])
def test_camera_failures_are_one_line(fake_cv_camera, behaviour, message):
    fake_cv_camera.behaviour = behaviour
    with pytest.raises(SourceError, match=message) as e:
        CameraSource(2, timeout=0.3)
    assert str(e.value).startswith("camera 2:")


def test_fake_camera_plays_its_frames():
    frames = frames_of(5)
    cam = FakeCamera(frames, fps=10)
    assert cam.size == (64, 48) and cam.fps == 10.0 and len(cam) == 5
    got = list(cam)
    assert [f.index for f in got] == [0, 1, 2, 3, 4]
    assert [f.time for f in got] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    assert all(f.image is src for f, src in zip(got, frames))


def test_fake_camera_loops_until_closed():
    cam = FakeCamera(frames_of(3), loop=True)
    seen = []
    for f in cam:
        seen.append(f.index)
        if f.index == 7:
            cam.close()
    assert seen == list(range(8))


def test_fake_camera_closed_from_another_thread_stops_realtime_playback():
    cam = FakeCamera(frames_of(2), fps=200, loop=True, realtime=True)
    got = []
    t = threading.Timer(0.2, cam.close)
    t.start()
    for f in cam:
        got.append(f.index)
    t.join()
    assert got and got == list(range(len(got)))


def test_fake_camera_rejects_bad_frames():
    with pytest.raises(SourceError, match="no frames"):
        FakeCamera([])
    with pytest.raises(SourceError, match="frame 1"):
        FakeCamera([np.zeros((4, 4, 3), np.uint8), np.zeros((4, 4), np.uint8)])
    with pytest.raises(SourceError, match="frame 1 is 5x4"):
        FakeCamera([np.zeros((4, 4, 3), np.uint8), np.zeros((4, 5, 3), np.uint8)])
    with pytest.raises(SourceError, match="fps"):
        FakeCamera(frames_of(1), fps=0)


@settings(max_examples=30, deadline=None)
@given(n=hs.integers(1, 12), fps=hs.floats(1.0, 120.0), take=hs.integers(0, 30))
def test_fake_camera_indices_and_times(n, fps, take):
    cam = FakeCamera(frames_of(n, 8, 6), fps=fps, loop=True)
    got = []
    for f in cam:
        if len(got) == take:
            break
        got.append(f)
    assert [f.index for f in got] == list(range(take))
    assert [f.time for f in got] == pytest.approx([i / fps for i in range(take)])
    assert all(f.image is cam.frames[f.index % n] for f in got)


def test_synthetic_source_matches_the_performance():
    perf = Performance(seconds=0.4, fps=30, seed=3, frame_size=(320, 240))
    src = SyntheticSource(perf)
    assert src.size == (320, 240) and src.fps == 30.0 and len(src) == 12
    got = list(src)
    assert len(got) == 12
    assert np.array_equal(got[5].image, perf.frame(5))
    assert src.truth(got[5]) == perf.truth(5)
    paced = SyntheticSource(perf, realtime=True)
    assert [f.index for f in paced] == list(range(12))
    looped = SyntheticSource(perf, loop=True)
    for f in looped:
        if f.index == 14:
            assert np.array_equal(f.image, perf.frame(2))
            assert looped.truth(f).frame == 14
            looped.close()


def test_open_source_dispatches(tmp_path):
    path = tmp_path / "c.avi"
    write_video(path, frames_of(4), fourcc="MJPG")
    with open_source(str(path)) as s:
        assert isinstance(s, VideoFileSource) and len(list(s)) == 4
    with open_source("synth:0.2:5") as s:
        assert isinstance(s, SyntheticSource) and len(s) == 6 and s.performance.seed == 5
    with pytest.raises(SourceError, match="camera 98"):
        open_source("98")
    with pytest.raises(SourceError, match="synth:x"):
        open_source("synth:x")
    with pytest.raises(SourceError, match="nope.mp4"):
        open_source(str(tmp_path / "nope.mp4"))


def test_frame_is_a_small_record():
    f = Frame(3, 0.1, np.zeros((2, 2, 3), np.uint8))
    assert (f.index, f.time, f.image.shape) == (3, 0.1, (2, 2, 3))


def test_video_closed_from_another_thread_while_playing(tmp_path):
    path = tmp_path / "long.avi"
    write_video(path, frames_of(200), fourcc="MJPG")
    src = VideoFileSource(path)
    seen = []
    for f in src:
        seen.append(f.index)
        if f.index == 5:
            th = threading.Thread(target=src.close)
            th.start()
            th.join()
    assert seen[-1] < 10 and src.closed
    with pytest.raises(SourceError, match="closed"):
        iter(src).__next__()


def test_one_decoder_thread_reads_the_same_frames(tmp_path):
    """Timed runs decode on one thread (no decoding in the background of a timed call): the
    frames are the same as the library's threaded decoder gives."""
    from tracker.track_cli import _Video

    rng = np.random.default_rng(3)
    frames = [np.clip(rng.normal(128, 40, (48, 64, 3)), 0, 255).astype(np.uint8) for _ in range(12)]
    path = tmp_path / "v.mp4"
    write_video(path, frames)
    got = []
    for threads in (0, 1):
        v = _Video(path, threads=threads)
        try:
            got.append([img for _, img in v.frames()])
        finally:
            v.close()
    assert len(got[0]) == len(got[1]) == len(frames)
    assert all(np.array_equal(a, b) for a, b in zip(*got))
