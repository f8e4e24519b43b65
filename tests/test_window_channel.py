"""The window ↔ engine channel: requests never wait on frames, frames never wait on the window."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("pytestqt")

from app.settings import Settings  # noqa: E402
from app.workers import SourceSpec  # noqa: E402
from benchmarks.soak_window import count_video_frames, watched_window  # noqa: E402

WAIT = 60_000


pytestmark = pytest.mark.usefixtures("isolated_user_dirs")  # settings, data and cache in tmp_path


@pytest.fixture(scope="module")
def performer():
    """Frames of a short synthetic performance, its clicks and the calibration from them."""
    from benchmarks.soak_window import drive_performer

    return drive_performer()


def _art():
    from art_sets.library import list_bundled

    items = [str(p) for _, p in list_bundled()]
    if not items:
        pytest.skip("no bundled characters installed")
    return items[0]


def test_requests_while_frames_flow_never_block_the_window(qtbot, performer):
    """Calibrations, sessions and source switches sent while frames play (the deadlock of issue 14)."""
    from tracker.sources import FakeCamera
    from training.defaults import default_session

    from app.workers import load_artset

    w, beat, dog = watched_window(performer)
    qtbot.addWidget(w)
    try:
        qtbot.waitUntil(lambda: w.last is not None and w.last.character is not None, timeout=WAIT)
        session = default_session(load_artset(w.current_art()))
        for i in range(12):
            w._on_calibrated(performer["calibration"])
            w._on_session_saved(session)
            if i % 4 == 3:
                w.set_source(SourceSpec("camera"), FakeCamera(performer["frames"], fps=30, loop=True))
            start = w.frames_shown
            qtbot.waitUntil(lambda: w.frames_shown >= start + 2 or dog.hung, timeout=WAIT)
            assert not dog.hung, "the window hung (stacks above)"
    finally:
        dog.stop()
        beat.stop()
    assert not dog.hung, "the window hung (stacks above)"
    w.close()


# ------------------------------------------------------------------------------------------
# the channel itself (no Qt, no engine)


def test_channel_send_never_blocks_when_the_other_end_does_not_read():
    import socket

    from app.channel import Channel

    a, b = socket.socketpair()
    tx = Channel(a)
    big = b"x" * 100_000
    for i in range(200):  # 20 MB: far more than any socket buffer
        tx.send(("event", "blob", (i, big)))
    assert tx.backlog > 0  # kept in the outbox, not blocking the caller
    for i in range(50):
        tx.send(("frame", i), key="frame")  # latest wins while unsent
    assert sum(1 for _, m in tx._pending if m[0] == "frame") == 1
    rx = Channel(b)
    got = []
    while tx.backlog or len(got) < 201:
        tx.flush()
        got += rx.receive()
    assert [m[2][0] for m in got[:200]] == list(range(200)) and got[-1] == ("frame", 49)
    tx.close()
    assert rx.receive() == [] and rx.closed


@settings(max_examples=25, deadline=None)
@given(st.lists(st.binary(max_size=5000), min_size=1, max_size=30), st.integers(1, 4096))
def test_channel_delivers_messages_whole_and_in_order(payloads, chunk):
    """However the bytes are split on the way, each message arrives whole and in order."""
    import socket

    from app.channel import Channel

    a, b = socket.socketpair()
    a.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, chunk)
    tx, rx = Channel(a), Channel(b)
    got = []
    for p in payloads:
        tx.send(p)
        got += rx.receive()
    while tx.backlog:
        tx.flush()
        got += rx.receive()
    got += rx.receive()
    assert got == payloads
    tx.close()
    rx.close()


def test_shared_pictures_round_trip_and_grow():
    from app.channel import PictureReader, SharedPictures

    w, r = SharedPictures(), PictureReader()
    try:
        small = [np.full((4, 5, 3), 7, np.uint8), None, np.arange(24, dtype=np.uint8).reshape(2, 3, 4)]
        name, layout = w.write(small)
        out = r.read(name, layout)
        assert out[1] is None and np.array_equal(out[0], small[0]) and np.array_equal(out[2], small[2])
        big = [np.random.default_rng(0).integers(0, 255, (800, 900, 3), dtype=np.uint8)]
        name2, layout2 = w.write(big)  # does not fit: a new, larger segment
        assert name2 != name
        assert np.array_equal(r.read(name2, layout2)[0], big[0])
    finally:
        r.close()
        w.close()


# ------------------------------------------------------------------------------------------
# honest status


def _window(qtbot, frames, calibration=None, art=None, **kw):
    from tracker.sources import FakeCamera

    from app.main_window import MainWindow

    w = MainWindow(settings=Settings(), source=SourceSpec("camera"), art=art or _art(),
                   fake_source=FakeCamera(frames, fps=30, loop=True), calibration=calibration, **kw)
    qtbot.addWidget(w)
    w.show()
    return w


def test_badge_says_starting_until_the_tracker_runs(qtbot):
    """No calibration and no face to start from: the badge says `starting`, never `lost`."""
    from app.views import STATUS_COLOURS

    blank = [np.full((480, 640, 3), 128, np.uint8)] * 10
    w = _window(qtbot, blank)
    seen = set()
    w.frameShown.connect(lambda _i: seen.add(w.last.status))
    qtbot.waitUntil(lambda: w.last is not None and w.last.character is not None and w.frames_shown > 10, timeout=WAIT)
    assert seen == {"starting"}
    assert w.video_view.status == "starting" and "starting" in STATUS_COLOURS
    assert "starting" in w.video_view.toolTip()
    w.close()


def test_badge_follows_the_tracker_from_the_first_tracked_frame(qtbot, performer):
    w = _window(qtbot, performer["frames"], performer["calibration"])
    seen = []
    w.frameShown.connect(lambda _i: seen.append(w.last.status))
    qtbot.waitUntil(lambda: "ok" in seen and len(seen) > 5, timeout=WAIT)
    first = seen.index("ok")
    # loading, then looking for the face: nothing was lost yet. The camera loops, so the tracker
    # may start on a frame where the head has moved from the calibration's place; it then finds the
    # eyes and, for a frame, not the mouth (`mouth_lost`, the badge following the tracker)
    assert set(seen[:first]) <= {"starting", "mouth_lost", "eyes_closed"}
    assert "lost" not in seen[: first + 5]
    w.close()


def test_fps_label_shows_input_and_output_rates(qtbot, performer):
    import re

    w = _window(qtbot, performer["frames"], performer["calibration"])
    w.set_rate(10)
    qtbot.waitUntil(lambda: w.last is not None and w.last.fps_out > 0 and w.frames_shown > 40, timeout=WAIT)
    start = w.frames_shown
    qtbot.waitUntil(lambda: w.frames_shown > start + 30, timeout=WAIT)
    w._refresh_status()
    m = re.match(r"in\s+([\d.]+) · out\s+([\d.]+) fps", w.fps_label.text())
    assert m, w.fps_label.text()
    fps_in, fps_out = float(m.group(1)), float(m.group(2))
    assert fps_in > 0 and 0 < fps_out <= 0.5 * fps_in  # every third tracked frame makes a drawing
    assert "out" in w.fps_label.toolTip() and "new character drawings" in w.fps_label.toolTip()
    w.close()


def test_dropped_is_explained_and_counts_per_source(qtbot, performer):
    from tracker.sources import FakeCamera

    w = _window(qtbot, performer["frames"], performer["calibration"])
    qtbot.waitUntil(lambda: w.last is not None and w.last.frames_read > 20, timeout=WAIT)
    w._refresh_status()
    assert w.drop_label.text().startswith("dropped")
    tip = w.drop_label.toolTip()
    assert "not tracked" in tip and "not shown" in tip and "source changes" in tip
    before = w.last.frames_read
    w.set_source(SourceSpec("camera"), FakeCamera(performer["frames"], fps=30, loop=True))
    assert w.drop_label.text() == "dropped 0"
    qtbot.waitUntil(lambda: w.last.source_id == w.pipeline.source_id, timeout=WAIT)
    fr = w.last
    assert fr.frames_read < before and fr.dropped_capture + fr.dropped_display <= fr.frames_read
    w.close()


def test_news_from_a_source_already_left_is_ignored(qtbot, performer):
    """A camera that fails after the user has moved on does not switch the window away."""
    from tracker.sources import FakeCamera

    w = _window(qtbot, performer["frames"], performer["calibration"])
    qtbot.waitUntil(lambda: w.last is not None, timeout=WAIT)
    w.set_source(SourceSpec("camera", camera=9))  # does not exist
    w.set_source(SourceSpec("camera"), FakeCamera(performer["frames"], fps=30, loop=True))
    qtbot.waitUntil(lambda: w.last.source_id == w.pipeline.source_id, timeout=WAIT)
    n = w.frames_shown
    qtbot.waitUntil(lambda: w.frames_shown > n + 20, timeout=WAIT)
    assert w.source_spec.kind == "camera" and w.pipeline._fake is not None
    w.close()


# ------------------------------------------------------------------------------------------
# recording, recalibration


def _recording(qtbot, performer, out, frames: int):
    """A window that has been recording to ``out`` for ``frames`` shown frames."""
    w = _window(qtbot, performer["frames"], performer["calibration"])
    qtbot.waitUntil(lambda: w.last is not None and w.last.character is not None, timeout=WAIT)
    assert w.start_recording(str(out))
    n = w.frames_shown
    qtbot.waitUntil(lambda: w.frames_shown > n + frames, timeout=WAIT)
    return w


def test_stop_recording_returns_at_once_and_saves_in_the_background(qtbot, performer, tmp_path):
    out = tmp_path / "take.gif"
    w = _recording(qtbot, performer, out, 20)
    got = []
    w.recordingSaved.connect(got.append)
    qtbot.waitUntil(lambda: "frames" in w.record_label.text(), timeout=WAIT)  # the engine says how far it is
    w.stop_recording()
    # back at once: the button is ready again and a progress bar stands for the save
    assert got == [] and w.recording is None and w.record_btn.text() == "● Record"
    assert w.save_progress.isVisible() and "take.gif" in w.save_progress.format()
    qtbot.waitUntil(lambda: bool(got), timeout=WAIT)
    assert not w.save_progress.isVisible()
    res = got[0]
    assert res.frames == count_video_frames(out) > 0
    assert f"Saved {res.frames} frames" in w.record_label.text()
    w.close()


def test_closing_while_saving_waits_for_the_file(qtbot, performer, tmp_path):
    out = tmp_path / "closing.mp4"
    w = _recording(qtbot, performer, out, 10)
    w.close()  # stops the recording; the window stays until the file is closed
    qtbot.waitUntil(lambda: not w.isVisible(), timeout=WAIT)
    assert out.is_file() and w.record_result is not None and w.record_result.frames > 0


def test_k_recalibrates_on_the_current_frame_without_stopping(qtbot, performer):
    from PySide6.QtCore import Qt

    from tracker.calibration import Calibration

    w = _window(qtbot, performer["frames"], performer["calibration"])
    qtbot.waitUntil(lambda: w.last is not None and w.last.status == "ok", timeout=WAIT)
    old = w._calibration
    w.activateWindow()
    qtbot.keyClick(w, Qt.Key.Key_K)
    qtbot.waitUntil(lambda: "Recalibrated" in w.calib_label.text(), timeout=WAIT)
    assert isinstance(w._calibration, Calibration) and w._calibration is not old
    assert "tracked points" in w.calib_label.text() or "face was found" in w.calib_label.text()
    n = w.frames_shown
    qtbot.waitUntil(lambda: w.frames_shown > n + 10 and w.last.status == "ok", timeout=WAIT)
    w.close()


def test_recording_to_a_name_in_use_is_refused_with_a_free_one(qtbot, performer, tmp_path):
    out = tmp_path / "take.mp4"
    out.write_bytes(b"an earlier take")
    w = _window(qtbot, performer["frames"], performer["calibration"])
    qtbot.waitUntil(lambda: w.last is not None and w.last.character is not None, timeout=WAIT)
    assert w.start_recording(str(out))
    qtbot.waitUntil(lambda: "Recording failed" in w.record_label.text(), timeout=WAIT)
    assert out.read_bytes() == b"an earlier take" and "take-2.mp4" in w.record_label.text()
    assert w.recording is None and w.record_btn.text() == "● Record"
    w.close()


def test_the_engine_starts_with_two_heap_arenas_unless_the_user_says_otherwise(monkeypatch):
    import os

    from app import workers

    monkeypatch.delenv("MALLOC_ARENA_MAX", raising=False)
    with workers._engine_environment():
        assert os.environ["MALLOC_ARENA_MAX"] == "2"
    assert "MALLOC_ARENA_MAX" not in os.environ
    monkeypatch.setenv("MALLOC_ARENA_MAX", "8")
    with workers._engine_environment():
        assert os.environ["MALLOC_ARENA_MAX"] == "8"
    assert os.environ["MALLOC_ARENA_MAX"] == "8"


def test_messages_travel_as_json_and_come_back_whole():
    """The wire format is JSON (no pickle): tuples, dicts with tuple keys, arrays, bytes, paths and
    the project's dataclasses come back equal; a class from elsewhere is refused, both ways."""
    import json
    from pathlib import Path

    import numpy as np
    import pytest as _pytest

    from app.channel import decode_message, encode_message
    from app.workers import SourceSpec
    from tracker.params import FaceParams

    msg = ("frame", {("recording", 2): (1, None), "p": FaceParams(frame=3, mid_x=1.5)},
           np.arange(6, dtype=np.float32).reshape(2, 3), b"\x00\xff", Path("/a/b"), SourceSpec(kind="video", video="x.mp4"))
    data = encode_message(msg)
    json.loads(data)  # plain JSON
    back = decode_message(data)
    assert back[0] == "frame" and back[1] == msg[1] and back[3:] == msg[3:]
    assert back[2].dtype == np.float32 and np.array_equal(back[2], msg[2])
    with _pytest.raises(TypeError):
        encode_message(object())
    with _pytest.raises(ValueError):
        decode_message(b'{"c": "os:system", "f": {}}')


def test_an_engine_that_never_started_is_stopped_without_an_error(qtbot, monkeypatch):
    """The engine process failing to start (no memory, a spawn refused) raises from ``start``, and the
    window's later ``stop`` (on close) has no process to join: it used to join the unstarted one and
    raise an AssertionError on top. Nothing is left open either."""
    import multiprocessing.context
    import socket

    from app.workers import Pipeline, PuppetSpec

    closed = []
    real_close = socket.socket.close

    def refuse(self):
        raise OSError("cannot start the engine")

    def close(self):
        closed.append(self)
        real_close(self)

    monkeypatch.setattr(multiprocessing.context.SpawnProcess, "start", refuse)
    monkeypatch.setattr(socket.socket, "close", close)
    p = Pipeline(SourceSpec(kind="performance", seconds=1.0), PuppetSpec())
    with pytest.raises(OSError, match="cannot start the engine"):
        p.start()
    assert len(closed) == 2 and not p.running
    p.stop()  # nothing to join, nothing raised
    p.stop()


def test_the_window_command_says_in_one_line_when_the_engine_cannot_start(qtbot, monkeypatch, capsys):
    """``python -m app window`` with the engine process refused: one line on stderr, exit status 1,
    no traceback."""
    import argparse
    import multiprocessing.context

    from app import window_cmd

    def refuse(self):
        raise OSError("Cannot allocate memory")

    import app.qt_env

    monkeypatch.setattr(multiprocessing.context.SpawnProcess, "start", refuse)
    monkeypatch.setattr(app.qt_env, "display_problem", lambda: "")  # the offscreen platform stands in for a display
    parser = argparse.ArgumentParser()
    window_cmd.add_arguments(parser, "window")
    assert window_cmd.run(parser.parse_args(["--performance"])) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["inkface: cannot start the tracking engine: Cannot allocate memory"]
