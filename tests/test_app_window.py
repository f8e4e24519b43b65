"""The performance, calibration and training windows, driven headless with pytest-qt.

A fake camera plays frames of the synthetic performer; nothing here needs a camera, a display
or the network. Waits are ``qtbot.waitUntil`` with generous timeouts, never fixed sleeps.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pytestqt")

from app.settings import Settings  # noqa: E402
from app.workers import SourceSpec  # noqa: E402

WAIT = 60_000  # ms; generous for a loaded 2-core machine


pytestmark = pytest.mark.usefixtures("isolated_user_dirs")  # settings, data and cache in tmp_path


@pytest.fixture(scope="module")
def performer():
    """Frames of a short synthetic performance, its clicks and the calibration from them."""
    from benchmarks.soak_window import drive_performer

    return drive_performer()


def _fake_camera(frames, loop=True):
    from tracker.sources import FakeCamera

    return FakeCamera(frames, fps=30, loop=loop)


def _bundled(n=2):
    from art_sets.library import list_bundled

    items = [str(p) for _, p in list_bundled()]
    if not items:
        pytest.skip("no bundled characters installed")
    return items[:n]


@pytest.fixture
def window(qtbot, performer):
    from app.main_window import MainWindow

    arts = _bundled(2)
    w = MainWindow(settings=Settings(), source=SourceSpec("camera"), art=arts[0],
                   fake_source=_fake_camera(performer["frames"]), calibration=performer["calibration"])
    qtbot.addWidget(w)
    w.show()
    yield w
    w.close()


def _wait_frames(qtbot, w, n, extra=lambda: True):
    start = w.frames_shown
    qtbot.waitUntil(lambda: w.frames_shown >= start + n and w.last is not None and w.last.character is not None
                    and extra(), timeout=WAIT)


def test_window_opens_and_frames_flow(qtbot, window):
    from app.views import overlay_shapes

    def pupils(fr):
        return sum(len(a) for a in overlay_shapes(fr.overlay)["pupils"]) if fr is not None else 0

    # frames flow, and the overlay shows what the tracker found: two pupils on the face
    # (the fake camera loops, so a frame right after the jump back may be a re-acquisition)
    _wait_frames(qtbot, window, 5, lambda: pupils(window.last) == 2)
    fr = window.last
    assert fr.frame_size == (640, 480) and fr.video is not None
    # the picture arrives scaled to the view (the engine scales, the window only copies)
    box = window.video_view.image_rect()
    assert abs(fr.video.width() - box.width()) <= 2 or fr.video.width() == 640
    got = []
    window.pipeline.snapshot.connect(got.append)
    window.pipeline.request_snapshot()  # returns at once; the frame comes back through the hook
    qtbot.waitUntil(lambda: len(got) == 1, timeout=WAIT)
    assert got[0] is not None and got[0].shape == (480, 640, 3)
    assert fr.character.width() > 0 and fr.params is not None
    assert set(fr.timings_ms) and all(v >= 0 for v in fr.timings_ms.values())
    window._refresh_status()
    assert "fps" in window.fps_label.text()
    img = window.grab()
    assert img.width() > 800


def test_switching_characters_and_rates(qtbot, window):
    arts = _bundled(2)
    _wait_frames(qtbot, window, 3)
    if len(arts) > 1:
        window.set_art(arts[1])
        _wait_frames(qtbot, window, 3, lambda: window.last.art == arts[1])
        assert window.char_view.fades == 1
        assert Settings().get("art/current") == arts[1]
    for r in (10, 15, 30):
        window.set_rate(r)
        _wait_frames(qtbot, window, 3, lambda: window.pipeline.spec.fps == r)
        assert window.rate() == r and Settings().get("output/fps") == r
    window.gain_slider.setValue(150)
    assert window.pipeline.spec.gain == 1.5
    window._set_background_kind("green")
    assert window.char_view.background_colour().green() > 150 and Settings().get("render/background") == "green"


def test_missing_camera_falls_back_to_bundled_performance(qtbot, monkeypatch):
    from app.main_window import MainWindow

    arts = _bundled(1)
    w = MainWindow(settings=Settings(), source=SourceSpec("camera", camera=9), art=arts[0])
    qtbot.addWidget(w)
    qtbot.waitUntil(lambda: w.source_spec.kind == "performance", timeout=WAIT)
    assert "camera" in w.statusBar().currentMessage().lower()
    w.close()


def test_recording_writes_video_and_track(qtbot, window, tmp_path):
    _wait_frames(qtbot, window, 2)
    out = tmp_path / "rec" / "take.mp4"
    assert window.start_recording(str(out))
    _wait_frames(qtbot, window, 8)
    with qtbot.waitSignal(window.recordingSaved, timeout=WAIT) as saved:
        window.stop_recording()  # returns at once; the files are closed in the engine
    res = saved.args[0]
    assert res is not None and res.frames >= 4
    assert out.is_file() and out.stat().st_size > 1000
    from tracker.params import read_csv

    rows = read_csv(out.with_suffix(".csv"))
    assert len(rows) >= 4


def test_calibration_clicks_produce_a_saved_calibration(qtbot, performer, tmp_path):
    from app.calibration_window import CalibrationWindow

    c = performer["clicks"]
    dlg = CalibrationWindow(performer["frames"][c["frame"]], performer="Ann Lee", frame_index=c["frame"])
    qtbot.addWidget(dlg)
    assert not dlg.accept_btn.isEnabled()
    assert "LEFT" in dlg.prompt.text()
    for k in ("left_pupil", "right_pupil", "left_brow", "right_brow"):
        dlg.click(*c[k])
    assert dlg.calibration is None
    dlg.click(*c["mouth"])
    assert dlg.calibration is not None, dlg.error
    assert abs(dlg.calibration.ipd - performer["calibration"].ipd) < 2.0
    assert any(mv.image is not None for mv in dlg.mask_views)
    got = []
    dlg.calibrated.connect(got.append)
    path = dlg.accept_calibration()
    assert got and path is not None and path.is_file()
    assert path.parent.name == "ann-lee"
    assert json.loads((path.parent / "clicks.json").read_text())["frame"] == c["frame"]
    from tracker.calibration import Calibration

    assert abs(Calibration.load(path).ipd - dlg.calibration.ipd) < 1e-6


def test_calibration_window_passes_on_advice_about_the_frame(qtbot, performer, monkeypatch):
    """What calibration advises about the frame (the eyes turned aside) is shown with the masks, as
    a sentence; the performer looking ahead gets none."""
    import tracker.calibration as tc
    from app.calibration_window import CalibrationWindow

    c = performer["clicks"]
    dlg = CalibrationWindow(performer["frames"][c["frame"]], performer="Ann Lee", frame_index=c["frame"])
    qtbot.addWidget(dlg)
    for k in ("left_pupil", "right_pupil", "left_brow", "right_brow", "mouth"):
        dlg.click(*c[k])
    assert dlg.calibration is not None and "look into the camera" not in dlg.info.text()
    monkeypatch.setattr(tc, "calibration_hints", lambda cal: ["the eyes look to one side; look into the camera"])
    dlg.undo()  # the mouth point taken back and placed again: calibrated again
    dlg.click(*c["mouth"])
    assert dlg.calibration is not None and dlg.accept_btn.isEnabled()
    assert "The eyes look to one side; look into the camera. " in dlg.info.text()


def test_calibration_click_by_mouse_and_drag(qtbot, performer):
    from PySide6.QtCore import Qt

    from app.calibration_window import CalibrationWindow

    dlg = CalibrationWindow(performer["frames"][0])
    qtbot.addWidget(dlg)
    dlg.show()
    v = dlg.view
    p = v.to_view(300.0, 200.0).toPoint()
    qtbot.mouseClick(v, Qt.MouseButton.LeftButton, pos=p)
    assert "left_pupil" in v.points
    x, y = v.points["left_pupil"]
    assert abs(x - 300) < 2 and abs(y - 200) < 2
    # zoomed in, clicks still land on the frame pixel under the cursor
    v._zoom, v._centre = 4.0, (330.0, 220.0)
    p = v.to_view(340.0, 210.0)
    fx, fy = v.to_frame(p)
    assert abs(fx - 340) < 1e-6 and abs(fy - 210) < 1e-6
    qtbot.mouseClick(v, Qt.MouseButton.LeftButton, pos=p.toPoint())
    x, y = v.points["right_pupil"]
    assert abs(x - 340) < 0.5 and abs(y - 210) < 0.5


def test_training_window_assigns_a_frame_and_saves(qtbot, performer):
    from app.training_window import PerformanceClip, TrainingWindow, session_path
    from training.session import TrainingSession

    art = _bundled(1)[0]
    w = TrainingWindow(art, performer="trainer", calibration=performer["calibration"], clip=PerformanceClip(performer["perf"]))
    qtbot.addWidget(w)
    w.show()
    qtbot.waitUntil(lambda: w.track is not None, timeout=WAIT)  # tracked in its own process
    assert w.calibration is not None
    names = w.artset.mouth.names()
    w.tabs.setCurrentIndex(1)
    w.slider.setValue(12)
    assert w.pair_current("mouth", names[0])
    w.slider.setValue(20)
    assert w.pair_current("mouth", names[1])
    w.slider.setValue(25)
    assert w.pair_current("mouth", names[0])  # re-pairing replaces the old frame
    folder = session_path("trainer", art)
    s = TrainingSession.load(folder)
    mouth = [p for p in s.pairs if p.part == "mouth"]
    assert sorted((p.drawing, p.frame) for p in mouth) == sorted([(names[0], 25), (names[1], 20)])
    assert np.allclose(mouth[0].values, w.track[mouth[0].frame])
    assert w.cards[("mouth", names[0])].frame_no == 25
    got = []
    w.sessionSaved.connect(got.append)
    w.use_training()
    assert got and got[0] is w.session


def test_expression_space_shows_drawings_triangles_and_live_point(qtbot, performer):
    from app.training_window import PerformanceClip, TrainingWindow

    art = _bundled(1)[0]
    w = TrainingWindow(art, performer="space", calibration=performer["calibration"], clip=PerformanceClip(performer["perf"]))
    qtbot.addWidget(w)
    qtbot.waitUntil(lambda: w.track is not None or "failed" in w.status.text(), timeout=WAIT)
    assert w.track is not None, w.status.text()
    w.tabs.setCurrentIndex(1)
    w.pair_defaults()
    sp = w.space
    assert sp.emap is not None and len(sp.emap.triangles) >= 1
    assert len(sp.cloud) > 0
    w.slider.setValue(10)
    assert sp.live is not None and sp.live_loc is not None
    assert abs(sum(sp.live_loc.weights) - 1) < 1e-6
    assert "Leave-one-out" in w.diag.text()


def test_gui_stays_responsive_during_a_long_render(qtbot, tmp_path, performer):
    """Re-rendering a long track runs in its own process while the event loop keeps ticking."""
    from PySide6.QtCore import QTimer

    from app.record import render_task
    from tracker.params import FaceParams, write_csv

    art = _bundled(1)[0]
    base = performer["calibration"].neutral
    rows = [FaceParams.from_values(base.values() + np.sin(i / 7.0) * np.r_[0, 0, 0, 0, 0, 0, 0, 4, 3, 3], frame=i,
                                   time=i / 30) for i in range(3000)]
    track = tmp_path / "long.csv"
    write_csv(track, rows)
    performer["calibration"].save(track.with_suffix(".calibration.json"))
    th = render_task(str(track), art, str(tmp_path / "long.mp4"), 30)
    progress = []
    th.progress.connect(lambda i, n: progress.append(i))
    ticks = []
    timer = QTimer(interval=10, timeout=lambda: ticks.append(th.isRunning()))
    timer.start()
    th.start()
    try:
        qtbot.waitUntil(lambda: len(progress) > 0, timeout=WAIT)
        t0 = len(ticks)
        qtbot.waitUntil(lambda: len(ticks) >= t0 + 10 or not th.isRunning(), timeout=WAIT)
        assert th.isRunning(), "the render finished before the GUI could be observed"
        assert sum(ticks[t0:]) >= 10  # the event loop ran while the render was busy
    finally:
        th.cancel()
        th.wait(10_000)
        timer.stop()


def test_drop_video_and_art_folder(qtbot, window, tmp_path, performer):
    import shutil

    import cv2

    _wait_frames(qtbot, window, 1)
    vid = tmp_path / "face.avi"
    vw = cv2.VideoWriter(str(vid), cv2.VideoWriter_fourcc(*"MJPG"), 30, (640, 480))
    for f in performer["frames"][:10]:
        vw.write(f)
    vw.release()
    assert window.open_path(str(vid))
    assert window.source_spec.kind == "video" and window.source_spec.video == str(vid)
    src = Path(_bundled(1)[0])
    mine = tmp_path / "mine"
    shutil.copytree(src, mine)
    assert window.open_path(str(mine))
    assert str(mine.resolve()) in window.strip.paths()
    assert str(mine.resolve()) in Settings().user_art_dirs()
    assert not window.open_path(str(tmp_path / "nothing.txt"))


def test_calibration_auto_then_adjust(qtbot, performer):
    pytest.importorskip("tracker.auto_init")
    from app.calibration_window import POINTS, CalibrationWindow

    dlg = CalibrationWindow(performer["frames"][0])
    qtbot.addWidget(dlg)
    assert dlg.auto(), dlg.info.text()
    assert set(dlg.view.points) == set(POINTS)
    assert dlg.calibration is not None and dlg.accept_btn.isEnabled()
    truth = performer["clicks"]
    for k in ("left_pupil", "right_pupil"):
        assert np.hypot(*(np.subtract(dlg.view.points[k], truth[k]))) < 6.0
    # dragging a point (here: setting it) recalibrates
    pts = dict(dlg.view.points)
    pts["mouth"] = tuple(truth["mouth"])
    dlg.set_points(pts)
    assert dlg.calibration is not None


def test_training_window_records_a_clip_from_live_frames(qtbot, performer):
    from types import SimpleNamespace

    from app.training_window import PerformanceClip, TrainingWindow

    art = _bundled(1)[0]
    w = TrainingWindow(art, performer="rec", calibration=performer["calibration"], clip=PerformanceClip(performer["perf"]))
    qtbot.addWidget(w)
    wanted = []
    w.recordingChanged.connect(wanted.append)
    w.start_recording(60.0)
    assert wanted == [True]
    for f in performer["frames"][:12]:
        w.live_frame(SimpleNamespace(frame_bgr=f, params=None))
    path = w._finish_recording()
    assert wanted == [True, False]
    assert path is not None and path.is_file() and path.parent.name == "clips"
    assert len(w.clip) == 12
    qtbot.waitUntil(lambda: w.track is not None and len(w.track) == 12, timeout=WAIT)
