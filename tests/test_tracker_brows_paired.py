"""A brow under hair follows the other brow; brows both seen move on their own."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tracker.eyes as eyes
import tracker.face_tracker as ft
from tracker.calibration import calibrate
from tracker.clicks import Clicks
from tracker.face_tracker import FaceTracker, paired_brows
from tracker.synthetic import FaceState, clicks_for, render_face

BASE = FaceState(cx=320.0, cy=210.0, ipd=80.0)


def test_a_brow_found_poorly_for_good_takes_the_other_brows_rise():
    # the right brow's running mean match lags the left's: hair over it
    means = [0.95, 0.8]
    # the left brow rose 20 % of its calibrated height; the right one read 20 px (the lid's crease)
    out = paired_brows([48.0, 20.0], [0.95, ft.BROW_WEAK], [True, True], means, [40.0, 30.0])
    assert out[0] == 48.0
    assert out[1] == pytest.approx(36.0)  # 30 × 1.2
    half = paired_brows([48.0, 20.0], [0.95, 0.5 * (ft.BROW_WEAK + ft.BROW_SURE)], [True, True], means, [40.0, 30.0])
    assert half[1] == pytest.approx(0.5 * (20.0 + 36.0))


@pytest.mark.parametrize("matches,means,seen", [
    ([0.95, 0.75], [0.95, 0.93], [True, True]),  # as often well found as the other: a bad frame, not hair
    ([0.85, 0.75], [0.95, 0.8], [True, True]),  # the other brow is not sure this frame
    ([0.95, 0.92], [0.95, 0.8], [True, True]),  # this frame it is found surely
    ([0.95, 0.75], [0.95, 0.8], [True, False]),  # held, not measured
    ([0.95, 0.75], [0.95, None], [True, True]),  # no history yet
])
def test_a_brow_keeps_its_own_height_unless_it_is_the_hard_one_and_the_other_is_sure(matches, means, seen):
    assert paired_brows([48.0, 20.0], matches, seen, means, [40.0, 30.0]) == [48.0, 20.0]


@given(h=st.tuples(st.floats(5, 80), st.floats(5, 80)), m=st.tuples(st.floats(0, 1), st.floats(0, 1)),
       avg=st.tuples(st.floats(0, 1), st.floats(0, 1)), cal=st.tuples(st.floats(10, 60), st.floats(10, 60)))
@settings(max_examples=300, deadline=None)
def test_a_paired_brow_lies_between_its_own_height_and_the_other_brows_rise(h, m, avg, cal):
    out = paired_brows(list(h), list(m), [True, True], list(avg), list(cal))
    for i in range(2):
        j = 1 - i
        mirrored = cal[i] * h[j] / cal[j]
        lo, hi = min(h[i], mirrored), max(h[i], mirrored)
        assert lo - 1e-9 <= out[i] <= hi + 1e-9
    assert out[0] == h[0] or out[1] == h[1]  # never both moved: only the weaker one follows


@pytest.fixture(scope="module")
def cal():
    frame, _ = render_face(BASE)
    return calibrate(frame, Clicks.from_dict(clicks_for(BASE)))


def _hair_over_the_right_brow(monkeypatch):
    """The eye finder as if hair lay over the image-right brow: its cross-section matches at 0.75 and
    lands on the lid's crease, 40 % under its calibrated height, whatever the brow does."""
    real = eyes.EyeFinder.find

    def find(self, crop_bgr, crop_grey, centres, brows=True):
        res = real(self, crop_bgr, crop_grey, centres, brows)
        if brows:
            e = res.eyes[1]
            e.brow, e.brow_match = 0.6 * self.model.brow_heights[1], 0.75
        return res

    monkeypatch.setattr(eyes.EyeFinder, "find", find)


def _brows(cal, states):
    tr = FaceTracker(cal)
    out = []
    for i, s in enumerate(states):
        r = tr.track(render_face(s)[0], i)
        assert r.params.status == "ok", r.debug
        out.append((r.params.brow_l, r.params.brow_r))
    return out


def test_a_brow_under_hair_rises_with_the_other(cal, monkeypatch):
    _hair_over_the_right_brow(monkeypatch)
    rest, up = BASE, BASE.replace(brow=1.0)
    got = _brows(cal, [rest] * 30 + [up] * 3)
    (l0, r0), (l1, r1) = got[29], got[-1]
    assert l1 > 1.1 * l0
    assert r1 / r0 == pytest.approx(l1 / l0, rel=0.05)
    monkeypatch.setattr(ft, "BROW_SIDE_GAP", 1.0)  # the rule off: the hidden brow stays on the crease
    (l0, r0), (l1, r1) = _brows(cal, [rest] * 30 + [up] * 3)[29::3]
    assert r1 == pytest.approx(r0, rel=0.02)


def test_one_brow_raised_alone_still_shows_when_both_are_seen(cal):
    got = _brows(cal, [BASE] * 5 + [BASE.replace(brow_l=1.0)] * 3)
    (l0, r0), (l1, r1) = got[4], got[-1]
    assert l1 > 1.1 * l0
    assert r1 == pytest.approx(r0, rel=0.05)


@pytest.fixture(scope="module")
def finder():
    cal = calibrate(render_face(BASE)[0], Clicks.from_dict(clicks_for(BASE)))
    return FaceTracker(cal).eye_finder


def _two_peaks(f, i: int, py: float, top: int, above: float, lead: float):
    """A brow strip's correlations with a peak at the calibrated height and another ``above`` wi higher,
    ``lead`` better (a forehead's crease or a fringe of hair as like the brow's cross-section)."""
    base = py - top - f.model.brow_centres[i]
    k_cal = int(round(base - f.model.brow_heights[i]))
    k_up = int(round(k_cal - above * f.wi))
    score = np.zeros(k_cal + 8, np.float32)
    score[k_cal], score[k_up] = 0.8, 0.8 + lead
    return score, base


@pytest.mark.parametrize("lead, want_calibrated", [(0.1, True), (0.3, False)])
def test_the_first_brow_after_a_fresh_start_is_looked_for_near_calibration(finder, lead, want_calibrated):
    """With no last frame's brow (the first frame, or after the face was lost) a brow is looked for near
    its calibrated height: a crease above it that matches a little better does not take it, and the
    brow's steadiness then holds it there (the ``late`` copy of expr_d19, calibrated a blink later
    than its first frame: the right brow read on the forehead, three times its height, for the 15
    frames before). One that matches clearly better still wins."""
    i, py, top = 1, 120.0, 60
    finder.forget()
    score, base = _two_peaks(finder, i, py, top, 0.2, lead)
    h, match = finder._brow_peak(score, top, py, i)
    assert (abs(h - finder.model.brow_heights[i]) < 1.0) == want_calibrated, (h, finder.model.brow_heights[i])
    finder.forget()
