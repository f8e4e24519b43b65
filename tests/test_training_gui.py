"""The training window respects hand-picked pairs: automatic pairing asks first and can be
undone, pairs say which frame they came from, and the diagnostics never show NaN.

The window runs offscreen with pytest-qt. The clip is the synthetic performer; its "tracked"
values are the performer's truth (the window's logic, not the tracker, is under test here, so
no tracking process is started).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

pytest.importorskip("pytestqt")

from app.settings import Settings  # noqa: E402,F401  (imports Qt after conftest set the platform)


pytestmark = pytest.mark.usefixtures("isolated_user_dirs")


@pytest.fixture(scope="module")
def performer():
    """One second of the synthetic performer, its true ten values per frame, its calibration."""
    from tracker.synthetic import Performance

    from app.workers import performance_calibration

    perf = Performance(seconds=1.0, seed=5)
    return {"perf": perf, "calibration": performance_calibration(perf),
            "truth": np.array([p.values() for p in perf.truths()])}


def _art() -> str:
    from art_sets.library import list_bundled

    items = [str(p) for _, p in list_bundled()]
    if not items:
        pytest.skip("no bundled characters installed")
    return items[0]


def _window(qtbot, performer, name="ann"):
    from app.training_window import PerformanceClip, TrainingWindow

    w = TrainingWindow(_art(), performer=name, clip=PerformanceClip(performer["perf"]))
    qtbot.addWidget(w)
    w.session.set_calibration(performer["calibration"])
    w.track = performer["truth"]
    w.session.set_reference("synthetic clip", performer["truth"])
    w.refresh()
    return w


def _hand_pairs(w, frames=(3, 9, 15)):
    names = w.artset.mouth.names()
    for f, n in zip(frames, names):
        w.slider.setValue(f)
        assert w.pair_current("mouth", n)
    return {(p.part, p.drawing, p.frame) for p in w.session.pairs}


def _on_disk(w):
    from training.session import TrainingSession

    return {(p.part, p.drawing, p.frame, p.source) for p in TrainingSession.load(w.session.path).pairs}


def test_pair_automatically_asks_before_replacing_hand_picked_pairs(qtbot, performer):
    w = _window(qtbot, performer)
    mine = _hand_pairs(w)
    asked = []
    w.ask_replace_pairs = lambda n: asked.append(n) or "cancel"
    assert not w.pair_defaults()
    assert asked == [3]
    assert {(p.part, p.drawing, p.frame) for p in w.session.pairs} == mine
    assert "unchanged" in w.status.text()

    # keep mine: only the drawings without a hand-picked pair get automatic ones
    w.ask_replace_pairs = lambda n: "keep"
    assert w.pair_defaults()
    hand = {(p.part, p.drawing, p.frame) for p in w.hand_picked()}
    assert hand == mine
    auto = [p for p in w.session.pairs if p.source]
    assert auto and not {(p.part, p.drawing) for p in auto} & {(pt, d) for pt, d, _ in mine}
    assert all(p.source.startswith("synthetic:") for p in auto)

    # replace: asked again (the hand-picked pairs are still there), then only automatic pairs
    w.ask_replace_pairs = lambda n: asked.append(n) or "replace"
    assert w.pair_defaults()
    assert asked[-1] == 3
    assert not w.hand_picked()


def test_automatic_pairing_can_be_undone_and_redone(qtbot, performer):
    w = _window(qtbot, performer, "undo")
    mine = _hand_pairs(w)
    before = _on_disk(w)
    w.ask_replace_pairs = lambda n: "replace"
    assert w.undo_btn.isEnabled() and not w.redo_btn.isEnabled()  # the hand pairs can be undone
    assert w.pair_defaults()
    after = _on_disk(w)
    assert after != before and all(src for *_, src in after)
    assert "Undo" in w.status.text()

    w.undo_btn.click()  # the button the user presses
    assert {(p.part, p.drawing, p.frame) for p in w.session.pairs} == mine
    assert _on_disk(w) == before  # the autosaved session is back too
    assert w.cards[("mouth", w.artset.mouth.names()[0])].pair_label() == "frame 3"
    # the restored pairs' thumbnails were written again
    for p in w.session.pairs:
        assert p.thumb_file and (w.session.path / p.thumb_file).is_file()

    assert w.redo()
    assert _on_disk(w) == after
    # undo walks back through the hand-picked pairs as well
    assert w.undo() and w.undo()
    assert len(w.session.pairs) == 2


def test_the_real_question_dialog_keeps_hand_picked_pairs(qtbot, performer):
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication, QMessageBox

    w = _window(qtbot, performer, "dialog")
    mine = _hand_pairs(w, frames=(4,))
    seen = []

    def answer():
        box = QApplication.activeModalWidget()
        if not isinstance(box, QMessageBox):
            QTimer.singleShot(20, answer)
            return
        seen.append(box.text() + " " + box.informativeText())
        keep = next(b for b in box.buttons() if b.text().startswith("Keep mine"))
        keep.click()

    QTimer.singleShot(0, answer)
    assert w.pair_defaults()
    assert seen and "1 pair yourself" in seen[0] and "Undo" in seen[0]
    assert {(p.part, p.drawing, p.frame) for p in w.hand_picked()} == mine


def test_pairs_say_which_frame_they_came_from_also_after_reopening(qtbot, performer):
    from app.training_window import PerformanceClip, TrainingWindow

    w = _window(qtbot, performer, "labels")
    names = w.artset.mouth.names()
    w.slider.setValue(7)
    assert w.pair_current("mouth", names[0])
    w.ask_replace_pairs = lambda n: "keep"
    assert w.pair_defaults()
    labels = {(pt, n): c.pair_label() for (pt, n), c in w.cards.items()}
    assert labels[("mouth", names[0])] == "frame 7"
    autos = [lab for key, lab in labels.items() if key != ("mouth", names[0]) and lab]
    assert autos and all(lab.startswith("synthetic · ") for lab in autos)
    assert not any(re.fullmatch(r"frame \d+", lab) for lab in autos)
    smile = w.cards.get(("mouth", "smile"))
    if smile is not None and smile.frame_no is not None:
        assert smile.pair_label() == "synthetic · smile"
        assert "synthetic performer" in smile.toolTip()

    for card in w.cards.values():  # the label sits on the thumbnail, clear of the drawing's name
        if card.frame_no is not None:
            text, pill = card.label_layout(card.fontMetrics())
            assert not pill.intersects(card.NAME_RECT) and card.FRAME_RECT.contains(pill)
            assert card.fontMetrics().horizontalAdvance(text) <= pill.width()
    again = TrainingWindow(w.art_path, performer="labels", clip=PerformanceClip(performer["perf"]))
    qtbot.addWidget(again)
    assert {(pt, n): c.pair_label() for (pt, n), c in again.cards.items()} == labels


@pytest.mark.parametrize("n_pairs", [1, 2, 3])
def test_diagnostics_show_no_nan_with_few_pairs(qtbot, performer, n_pairs):
    w = _window(qtbot, performer, f"few{n_pairs}")
    w.tabs.setCurrentIndex(1)  # mouth
    _hand_pairs(w, frames=(3, 9, 15)[:n_pairs])
    text = w.diag.text()
    assert "Leave-one-out" in text
    assert not re.search(r"\bnan\b|\binf\b", text, flags=re.I), text
    if n_pairs == 1:
        assert "the only pair so far" in text
    if n_pairs < 3:  # no hull yet: the window says so instead of "0 % outside"
        assert "pair at least three different drawings" in text and "fall outside" not in text


def test_leave_one_out_numbers_are_finite_for_any_pairing():
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from training.diagnostics import leave_one_out

    names = ["neutral", "smile", "ah", "oo"]

    @settings(max_examples=60, deadline=None)
    @given(st.lists(st.tuples(st.integers(0, 3), st.lists(st.floats(-2, 2), min_size=3, max_size=3)),
                    min_size=1, max_size=7))
    def check(rows):
        X = np.array([r[1] for r in rows], float)
        y = np.array([r[0] for r in rows])
        out = leave_one_out(X, y, names)
        assert len(out) == len(rows)
        for r in out:
            assert math.isfinite(r.weight_error)
            assert r.recon_error is None or math.isfinite(r.recon_error)
            assert all(math.isfinite(a) for _, a in r.predicted)
        if len(rows) == 1:
            assert out[0].recon_error is None and out[0].alone

    check()
