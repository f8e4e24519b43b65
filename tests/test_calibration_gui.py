"""The calibration window, offscreen with pytest-qt: Auto never places points that are not
shaped like a face, the masks show as soon as five points exist (or say why they cannot), the
frame never moves under the cursor while the prompt changes, and Start over forgets what was
said."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pytestqt")

from PySide6.QtCore import QPoint, Qt  # noqa: E402

from app.calibration_window import MASK_PLACEHOLDER, POINTS, CalibrationWindow  # noqa: E402

from tests.test_constellation import CLUSTER  # noqa: E402


pytestmark = pytest.mark.usefixtures("isolated_user_dirs")


@pytest.fixture
def themed(qapp):
    """The performance window's theme (its style sheet sets the prompt's 12 pt font), undone after."""
    from app.views import apply_theme

    style, sheet, palette = qapp.style().name(), qapp.styleSheet(), qapp.palette()
    apply_theme(qapp)
    yield qapp
    qapp.setStyleSheet(sheet)
    qapp.setPalette(palette)
    qapp.setStyle(style)


def _settle(qapp) -> None:
    """Run the layout passes a change of text has posted (as the event loop would before painting)."""
    for _ in range(3):
        qapp.sendPostedEvents()
        qapp.processEvents()


def _natural_height(label, text: str) -> int:
    """How tall a free word-wrapped label of ``label``'s font and width would be for ``text``."""
    from PySide6.QtCore import QRect

    fm = label.fontMetrics()
    return fm.boundingRect(QRect(0, 0, label.contentsRect().width(), 10_000), Qt.TextFlag.TextWordWrap, text).height()


@pytest.fixture(scope="module")
def performance():
    from tracker.synthetic import Performance

    return Performance(seconds=20.0, seed=0)


def _truth(performance, i):
    from tracker.synthetic import clicks_for

    return clicks_for(performance.state(i), i)


def _fake_auto(monkeypatch, points):
    from tracker import auto_init
    from tracker.clicks import Clicks

    monkeypatch.setattr(auto_init, "auto_clicks",
                        lambda frame, frame_index=0: Clicks.from_dict({"frame": frame_index, **points}, where="test"))


def _dialog(qtbot, frame, **kw):
    dlg = CalibrationWindow(frame, **kw)
    qtbot.addWidget(dlg)
    dlg.show()
    qtbot.waitExposed(dlg)
    return dlg


def test_auto_places_nothing_when_what_it_found_is_not_a_face(qtbot, performance, monkeypatch):
    """The report's frame: tilted, mouth open; the detector put all five round one eye."""
    _fake_auto(monkeypatch, CLUSTER)
    dlg = _dialog(qtbot, performance.frame(320), frame_index=320)
    qtbot.mouseClick(dlg.auto_btn, Qt.MouseButton.LeftButton)
    assert dlg.view.points == {}
    assert dlg.calibration is None and not dlg.accept_btn.isEnabled()
    info = dlg.info.text()
    assert "does not look like a face" in info and "lips" in info and "click the five yourself" in info
    assert "drag any point" not in info
    assert dlg.prompt.text().startswith("1 of 5")
    # the user's own points survive a failed Auto, and the note stays while they place the rest
    truth = _truth(performance, 320)
    dlg.click(*truth["left_pupil"])
    assert "does not look like a face" in dlg.info.text()
    assert dlg.auto() is False
    assert list(dlg.view.points) == ["left_pupil"]


def test_masks_appear_as_soon_as_auto_places_the_points(qtbot, performance, monkeypatch):
    truth = _truth(performance, 320)
    _fake_auto(monkeypatch, {k: truth[k] for k in POINTS})
    dlg = _dialog(qtbot, performance.frame(320), frame_index=320)
    assert dlg.auto()
    assert set(dlg.view.points) == set(POINTS)
    assert dlg.calibration is not None, dlg.error
    assert dlg.accept_btn.isEnabled()
    assert all(mv.image is not None for mv in dlg.mask_views)
    assert "Found automatically" in dlg.info.text()
    assert "look shut" not in dlg.info.text()


def test_auto_on_a_frame_with_shut_eyes_says_so_and_still_places_the_points(qtbot, performance, monkeypatch):
    """Where the eyes look shut at Auto's pupils (tracker.auto_init.eyes_shown), the points are placed
    and calibrated as usual, and the window asks for a frame with the eyes open: the eyes' pictures
    and lid gap are learned from this frame."""
    from tracker import auto_init

    truth = _truth(performance, 320)
    _fake_auto(monkeypatch, {k: truth[k] for k in POINTS})
    monkeypatch.setattr(auto_init, "eyes_shown", lambda frame, clicks: 0.5)
    dlg = _dialog(qtbot, performance.frame(320), frame_index=320)
    assert dlg.auto() and dlg.calibration is not None and dlg.accept_btn.isEnabled()
    assert "look shut" in dlg.info.text() and "Found automatically" in dlg.info.text()


@pytest.mark.parametrize("shown, warned", [(0.5, True), (6.0, False)])
def test_points_placed_by_hand_on_shut_eyes_ask_for_a_frame_with_the_eyes_open(qtbot, performance, monkeypatch,
                                                                                shown, warned):
    """A blink caught on the frozen frame: the points are calibrated as usual, and the window asks for a
    frame with the eyes open (the tracker learns the eyes from this one), as it does for Auto's points."""
    from tracker import auto_init

    monkeypatch.setattr(auto_init, "eyes_shown", lambda frame, clicks: shown)
    truth = _truth(performance, 0)
    dlg = _dialog(qtbot, performance.frame(0))
    dlg.set_points({k: truth[k] for k in POINTS})
    assert dlg.calibration is not None and dlg.accept_btn.isEnabled()
    assert ("look shut" in dlg.info.text()) == warned
    assert ("place the points there" in dlg.info.text()) == warned and "Auto again" not in dlg.info.text()


def test_masks_say_why_when_the_tracker_learns_nothing_from_five_points(qtbot, performance):
    frame = performance.frame(320)
    dlg = _dialog(qtbot, frame, frame_index=320)
    # placed by hand, upside down (mouth above the eyes): judged and warned about, and the
    # tracker refuses to learn from it
    upside_down = dict(CLUSTER, mouth=(255.0, 110.0))
    dlg.set_points(upside_down)
    assert dlg.calibration is None
    assert dlg.error
    assert all(mv.image is None and mv.note != MASK_PLACEHOLDER for mv in dlg.mask_views)
    info = dlg.info.text()
    assert "do not look like a face" in info and "could not learn" in info
    assert dlg.prompt.text().startswith("All five points placed")


def test_the_frame_does_not_move_while_the_prompt_changes(qtbot, performance, themed):
    """Click all five points with the mouse at two window widths: the frame's rectangle stays
    put whatever the prompt says (one line or two), and every click lands where it was aimed."""
    frame = performance.frame(0)
    truth = _truth(performance, 0)
    wrapped = set()
    for width in (1180, 900):
        dlg = _dialog(qtbot, frame)
        dlg.resize(width, 640)
        qtbot.waitUntil(lambda: dlg.width() == width)
        _settle(themed)
        geometry = dlg.view.geometry()
        rect = dlg.view._rect()
        heights, natural = set(), set()
        for k in POINTS:
            heights.add(dlg.prompt.height())
            natural.add(_natural_height(dlg.prompt, dlg.prompt.text()))
            at = dlg.view.to_view(*truth[k])
            qtbot.mouseClick(dlg.view, Qt.MouseButton.LeftButton, pos=QPoint(round(at.x()), round(at.y())))
            _settle(themed)
            assert dlg.view.geometry() == geometry and dlg.view._rect() == rect, (width, k, dlg.prompt.text())
            assert np.hypot(*np.subtract(dlg.view.points[k], truth[k])) < 1.5
        assert dlg.calibration is not None, dlg.error
        qtbot.mouseClick(dlg.undo_btn, Qt.MouseButton.LeftButton)
        qtbot.mouseClick(dlg.reset_btn, Qt.MouseButton.LeftButton)
        _settle(themed)
        assert dlg.view.geometry() == geometry and dlg.view._rect() == rect
        assert len(heights) == 1
        wrapped.add(len(natural) > 1)
        dlg.close()
    assert True in wrapped  # at some width the prompt wraps to one line for some points, two for others


def test_start_over_forgets_what_was_said(qtbot, performance, monkeypatch):
    _fake_auto(monkeypatch, CLUSTER)
    dlg = _dialog(qtbot, performance.frame(320))
    dlg.auto()
    stale = dlg.info.text()
    assert "does not look like a face" in stale
    qtbot.mouseClick(dlg.reset_btn, Qt.MouseButton.LeftButton)
    assert dlg.info.text() != stale and "face" not in dlg.info.text()
    # after a calibration, too: no inter-pupil distance or mask notes stay behind
    truth = _truth(performance, 0)
    dlg2 = _dialog(qtbot, performance.frame(0))
    dlg2.set_points({k: truth[k] for k in POINTS})
    assert dlg2.calibration is not None and "Inter-pupil" in dlg2.info.text()
    qtbot.mouseClick(dlg2.reset_btn, Qt.MouseButton.LeftButton)
    assert dlg2.view.points == {} and dlg2.calibration is None and not dlg2.accept_btn.isEnabled()
    assert "Inter-pupil" not in dlg2.info.text()
    assert all(mv.image is None and mv.note == MASK_PLACEHOLDER for mv in dlg2.mask_views)
    assert dlg2.prompt.text().startswith("1 of 5")
