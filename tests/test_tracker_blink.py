"""A blink the eye finder half misses: an eye doubted while the face is plainly there (its iris
blurred by the closing lids, the pair disagreeing with the head's pose) has its lids read where the
pose puts it, so both eyes close together — held at its last gap, the cartoon winked."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import tracker.face_tracker as face_tracker
from tracker.calibration import calibrate
from tracker.clicks import Clicks
from tracker.eyes import EyeFinder
from tracker.face_tracker import FaceTracker
from tracker.synthetic import FaceState, clicks_for, render_face

BLINK = (1.0, 0.7, 0.4, 0.15, 0.15, 0.4, 0.7, 1.0, 1.0)
"""Both eyes' opening (× open) over the clip: open, a blink, open."""


@pytest.fixture(scope="module")
def open_cal():
    start = FaceState(cx=320.0, cy=210.0, ipd=80.0)
    return start, calibrate(render_face(start)[0], Clicks.from_dict(clicks_for(start)))


def _blink_with_right_eye_doubted(start: FaceState, cal, monkeypatch, measure: bool = True):
    """Track :data:`BLINK` with the right eye doubted on every frame past the first (as a real blink's
    blurred iris gets it doubted); per frame, the two reported eye openings (px)."""
    tr = FaceTracker(cal)
    judge = tr._judge_eyes
    calls = []

    def right_doubted(*args, **kwargs):
        doubt, strong, far = judge(*args, **kwargs)
        calls.append(1)
        return ([doubt[0], True], False, far) if len(calls) > 1 else (doubt, strong, far)

    monkeypatch.setattr(tr, "_judge_eyes", right_doubted)
    if not measure:  # the control: no way to read a doubted eye's lids, so it is held
        monkeypatch.delattr(EyeFinder, "lids_at")
    out = []
    for i, k in enumerate(BLINK):
        r = tr.track(render_face(start.replace(eye_open=k))[0], i)
        assert r.params.status in ("ok", "eyes_closed")
        out.append((r.params.eye_open_l, r.params.eye_open_r))
    return np.array(out)


def test_a_doubted_eye_closes_with_the_seen_one_in_a_blink(open_cal, monkeypatch):
    start, cal = open_cal
    eyes = _blink_with_right_eye_doubted(start, cal, monkeypatch)
    left, right = eyes[:, 0], eyes[:, 1]
    shut = int(np.argmin(left))
    assert left[shut] < 0.5 * left[0]  # the seen eye shows the blink
    assert right[shut] < 0.5 * right[0]  # and so does the doubted one, read where the pose puts it
    assert abs(right[-1] - left[-1]) < 0.25 * left[-1]  # open again together


def test_without_reading_it_the_doubted_eye_stays_open_through_the_blink(open_cal, monkeypatch):
    """The control: a doubted eye whose lids are not read holds its last gap, and the blink shows on
    one eye only (a wink)."""
    start, cal = open_cal
    eyes = _blink_with_right_eye_doubted(start, cal, monkeypatch, measure=False)
    shut = int(np.argmin(eyes[:, 0]))
    assert eyes[shut, 1] > 0.8 * eyes[0, 1]


def test_lids_at_the_found_iris_agree_with_the_finder(open_cal):
    """:meth:`EyeFinder.lids_at` through the iris the finder found measures an open eye's gap as the
    finder does (to within a pixel and a half), and a shut eye's as a slit."""
    start, cal = open_cal
    tr = FaceTracker(cal)
    for k in (1.0, 0.15):
        tr.track(render_face(start.replace(eye_open=k))[0], 0)
        crop = tr._last_eye_crop
        res = tr.eye_finder.find(crop, cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY), tr._pupils_eye_crop)
        for i, o in enumerate(res.eyes):
            up, down = tr.eye_finder.lids_at(crop, i, (o.x, o.y))
            if k == 1.0:
                assert abs((up + down) - (o.upper + o.lower)) < 1.5
            else:
                assert up + down < 0.5 * cal.eye_model.lid_open[i]


def _covered_right_eye(start: FaceState, cal, monkeypatch) -> tuple[float, float]:
    """The right eye's reported opening (px) on an open frame, then on the same frame with that
    eye painted over in the cheek's colour and doubted."""
    tr = FaceTracker(cal)
    judge = tr._judge_eyes

    def right_doubted(*args, **kwargs):
        doubt, _, far = judge(*args, **kwargs)
        return [doubt[0], True], False, far

    monkeypatch.setattr(tr, "_judge_eyes", right_doubted)
    img = render_face(start)[0]
    rx, ry = (int(round(v)) for v in clicks_for(start)["right_pupil"])
    covered = img.copy()
    covered[ry - 14 : ry + 15, rx - 22 : rx + 23] = img[ry + 40, rx]  # the cheek under the eye
    return tr.track(img, 0).params.eye_open_r, tr.track(covered, 1).params.eye_open_r


def test_a_doubted_eye_that_reads_as_skin_beside_an_open_one_is_held(open_cal, monkeypatch):
    """A fingertip over one eye (or a pupil calibrated on the lid) reads as skin where the pose puts
    that eye: a gap under :data:`~tracker.face_tracker.PAIR_GAP` of the other, seen eye's is no
    measurement of it, and the last gap is held — and without that rule it would read shut."""
    start, cal = open_cal
    before, after = _covered_right_eye(start, cal, monkeypatch)
    assert after == pytest.approx(before, abs=0.01)
    monkeypatch.setattr(face_tracker, "PAIR_GAP", 0.0)
    before, after = _covered_right_eye(start, cal, monkeypatch)
    assert after < 0.3 * before
