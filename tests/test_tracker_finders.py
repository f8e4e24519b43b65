"""Each finder on synthetic frames with known truth."""

import math

import cv2
import numpy as np
import pytest

from tracker.calibration import calibrate
from tracker.clicks import Clicks
from tracker.face_tracker import FaceTracker
from tracker.mouth import MouthFinder
from tracker.params import EYES_CLOSED
from tracker.synthetic import STYLES, FaceState, clicks_for, face_landmarks, render_face

MOUTH_PRECISION = ("issue 13 (i13-mouth): the real-face mouth finder misses the synthetic performer's lip_upper / "
                   "lip_lower (1.5-3 px) and pale-lip width precision; everything else is asserted first")

BASE = FaceState(cx=320.0, cy=210.0, ipd=80.0)


@pytest.fixture(scope="module")
def cal():
    frame, _ = render_face(BASE)
    return calibrate(frame, Clicks.from_dict(clicks_for(BASE)))


def _track(cal, state, style=None, warm=None):
    tr = FaceTracker(cal)
    if warm is not None:
        tr.track(render_face(warm, style)[0])
    img, truth = render_face(state, style)
    return tr, tr.track(img), truth


@pytest.mark.parametrize("expr", ["neutral", "smile", "ah", "oo", "brows_up", "brows_angry", "wide"])
def test_expressions_match_truth(cal, expr):
    st = BASE.with_expression(expr)
    _, r, t = _track(cal, st)
    e = np.abs(r.params.values() - t.values())
    tol = np.array([1, 1, 1, 1.5, 1.5, 1.5, 1.5, 2, 1.5, 1.5])
    named = dict(zip(["x", "y", "roll", "el", "er", "bl", "br", "w", "lu", "ll"], e.round(2)))
    assert np.all(e[:7] <= tol[:7]), named
    if not np.all(e[7:] <= tol[7:]):
        pytest.xfail(MOUTH_PRECISION + f" ({named})")


def test_roll_and_shift_are_followed(cal):
    """The regions of interest rotate with the pupil line and move with the face."""
    tr = FaceTracker(cal)
    for i, roll in enumerate(np.linspace(0, 24, 9)):
        st = BASE.replace(roll_deg=float(roll), cx=320 + 3 * i, cy=210 - 2 * i)
        img, t = render_face(st)
        r = tr.track(img, i)
    assert abs(r.params.roll_deg - 24) < 0.5
    assert abs(r.params.mid_x - t.mid_x) < 1 and abs(r.params.mid_y - t.mid_y) < 1
    assert abs(r.params.mouth_width - t.mouth_width) < 2
    assert abs(r.params.brow_l - t.brow_l) < 1.5


def test_closed_eyes_keep_the_pupils(cal):
    """A shut eye's point is the middle of the slit between its lids (as a landmark tracker
    puts it): near where the pupil was, and the midpoint between the eyes does not move."""
    tr = FaceTracker(cal)
    r0 = tr.track(render_face(BASE)[0])
    r1 = tr.track(render_face(BASE.with_expression("eyes_closed"))[0], 1)
    assert r1.params.status == EYES_CLOSED
    assert all(r1.debug["closed"])
    assert np.allclose(r1.overlay.pupils, r0.overlay.pupils, atol=1.5)
    assert abs(r1.params.mid_x - r0.params.mid_x) < 0.5 and abs(r1.params.mid_y - r0.params.mid_y) < 0.5
    assert r1.params.eye_open_l < 3 and r1.params.eye_open_r < 3
    # and they are found again when the eyes open
    r2 = tr.track(render_face(BASE)[0], 2)
    assert r2.params.status == "ok" and abs(r2.params.eye_open_l - 16) < 1.5


def test_eyes_are_reported_shut_only_where_their_lids_are_too(cal):
    """A blink's half-open frames blur the iris, so its picture can match less than an iris that
    shows while the lids already stand well apart (a real clip: the peer at 73 % of the eye's usual
    opening, both irises matching 0.46-0.55, the frame reported shut and so counted lost). Both eyes
    judged shut by the finder make the frame ``eyes_closed`` only where their measured lid gaps
    are shut as well; shut lids still do."""
    import dataclasses

    from tracker.eyes import EyeResult

    def judged_shut(tr):
        find = tr.eye_finder.find

        def shut(*args, **kwargs):
            res = find(*args, **kwargs)
            return EyeResult(tuple(dataclasses.replace(e, open=False, iris_match=0.5) for e in res.eyes))
        tr.eye_finder.find = shut

    for expr, want in (("neutral", "ok"), ("smile", "ok"), ("eyes_closed", EYES_CLOSED)):
        tr = FaceTracker(cal)
        tr.track(render_face(BASE)[0])
        judged_shut(tr)
        r = tr.track(render_face(BASE.with_expression(expr))[0], 1)
        assert all(r.debug["closed"]), expr
        assert r.params.status == want, expr


def test_a_wink_keeps_the_closed_pupil_beside_the_open_one(cal):
    tr = FaceTracker(cal)
    tr.track(render_face(BASE)[0])
    st = BASE.with_expression("wink_l").replace(cx=324.0, cy=212.0)
    img, t = render_face(st)
    r = tr.track(img, 1)
    assert r.debug["closed"] == [True, False]
    lm = face_landmarks(st)
    assert np.allclose(r.overlay.pupils, [lm["left_pupil"], lm["right_pupil"]], atol=1.0)
    assert r.params.eye_open_l < 3 and abs(r.params.eye_open_r - t.eye_open_r) < 1.5


def test_a_red_object_outside_the_mouth_region_is_ignored(cal):
    img, t = render_face(BASE.with_expression("smile"))
    lip = tuple(int(c) for c in STYLES["default"].lip)
    cv2.circle(img, (520, 300), 30, lip, -1)  # a lip-coloured ball beside the face
    cv2.rectangle(img, (300, 420), (360, 470), lip, -1)  # and one on the shirt
    tr = FaceTracker(cal)
    r = tr.track(img)
    assert abs(r.params.mouth_width - t.mouth_width) < 2
    lm = face_landmarks(BASE.with_expression("smile"))
    assert np.allclose(r.overlay.mouth_corners, [lm["mouth_left"], lm["mouth_right"]], atol=2)


def test_mouth_polygon_and_snake_hug_a_known_lip_shape():
    """A lens-shaped lip (two parabolas) drawn at 8× and area-averaged: known outline."""
    ss = 8
    h, w, cx, cy, hw, up, lo = 90, 140, 70.0, 45.0, 45.0, 12.0, 16.0
    yy, xx = (np.mgrid[0 : h * ss, 0 : w * ss] + 0.5) / ss - 0.5  # pixel-centre coordinates
    u = (xx - cx) / hw
    inside = (np.abs(u) < 1) & (yy >= cy - up * (1 - u**2)) & (yy <= cy + lo * (1 - u**2))
    cover = cv2.resize(inside.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)
    score = np.round(cover * 255).astype(np.uint8)
    res = MouthFinder().find(score, value=cover, seed=(cx, cy))
    assert res is not None
    assert abs(res.width - 2 * hw) < 1.5
    assert abs(res.lip_upper - up) < 0.6 and abs(res.lip_lower - lo) < 0.6
    # every snake vertex lies on the true outline (within a pixel), the raw polygon near it
    for poly, tol in ((res.polygon, 1.0), (res.raw_polygon, 1.6)):
        px, py = poly[:, 0], poly[:, 1]
        uu = np.clip((px - cx) / hw, -1, 1)
        top, bot = cy - up * (1 - uu**2), cy + lo * (1 - uu**2)
        d = np.minimum(np.abs(py - top), np.abs(py - bot))
        assert np.median(d) < 0.5 and np.percentile(d, 90) < tol


def test_mouth_ring_blob_gives_outer_outline():
    """An open mouth is a ring of lip around a dark hole: the polygon is the outer edge."""
    img = np.zeros((80, 120), np.float32)
    cv2.ellipse(img, (60, 40), (40, 25), 0, 0, 360, 1.0, -1)
    cv2.ellipse(img, (60, 40), (30, 14), 0, 0, 360, 0.0, -1)
    res = MouthFinder().find((img * 255).astype(np.uint8), value=img)
    assert res is not None
    assert abs(res.width - 81) < 2
    assert abs(res.lip_upper - 25.5) < 1.0 and abs(res.lip_lower - 25.5) < 1.0


@pytest.mark.parametrize("style", ["dark_skin", "pale_lips"])
def test_other_performers_calibrate_and_track(style):
    s = STYLES[style]
    frame, _ = render_face(BASE, s)
    c = calibrate(frame, Clicks.from_dict(clicks_for(BASE)))
    mouth_misses = []
    for expr in ("neutral", "ah", "smile"):
        img, t = render_face(BASE.with_expression(expr), s)
        r = FaceTracker(c).track(img)
        e = np.abs(r.params.values() - t.values())
        assert e[:3].max() < 1 and e[3:7].max() < 1.5, (expr, e.round(2))
        if not (e[7] < 2 and e[8:].max() < 1.5):
            mouth_misses.append((expr, e[7:].round(2)))
    if mouth_misses:
        pytest.xfail(MOUTH_PRECISION + f" ({mouth_misses})")


def test_clicks_a_few_pixels_off_still_calibrate():
    c = clicks_for(BASE)
    rng = np.random.default_rng(4)
    for k in ("left_pupil", "right_pupil", "left_brow", "right_brow", "mouth"):
        c[k] = [v + float(rng.uniform(-2.5, 2.5)) for v in c[k]]
    frame, t = render_face(BASE)
    cal = calibrate(frame, Clicks.from_dict(c))
    e = np.abs(cal.neutral.values() - t.values())
    assert e[:3].max() < 1 and e[3:7].max() < 1.5 and e[7] < 2
    assert math.isclose(cal.ipd, 80, abs_tol=1)


def test_brow_clicks_next_to_the_lashes_still_calibrate():
    """Low, sparse brows or a hurried click just above the lashes: the darkest band near the click
    is the lash line, which is no brow — calibration looks above it and, failing that, takes the
    click, and never refuses the face."""
    c = clicks_for(BASE)
    lm = face_landmarks(BASE)
    for side in ("left", "right"):
        px, py = lm[f"{side}_pupil"]
        c[f"{side}_brow"] = [float(px), float(py - 0.1 * BASE.ipd)]
    frame, _ = render_face(BASE)
    cal = calibrate(frame, Clicks.from_dict(c))
    assert all(0.08 * BASE.ipd < h < BASE.ipd for h in cal.brow_heights)


def test_a_face_in_a_dark_room_is_found_without_equalising_the_frame():
    """A small face in a frame that is otherwise nearly black: equalising the whole frame's histogram
    spends its grey levels on the room and flattens the face, and the cascade misses it on the 320-px
    copy; the unequalised copy, tried next, shows it. The frame is equalised first because a dim
    face needs it."""
    from tracker.face_finder import detect_faces

    img, _ = render_face(BASE, STYLES["default"])
    small = cv2.resize(img, None, fx=0.3, fy=0.3, interpolation=cv2.INTER_AREA)
    frame = np.full((720, 960, 3), 10, np.uint8)
    frame[60 : 60 + small.shape[0], 200 : 200 + small.shape[1]] = small
    boxes = detect_faces(frame, None)
    assert boxes
    x, y, w, h = boxes[0]
    cx, cy = 200 + 0.3 * BASE.cx, 60 + 0.3 * BASE.cy  # the performer's face centre, shrunk and placed
    assert x < cx < x + w and y < cy + 0.1 * h and cy - 0.1 * h < y + h


def test_a_mouth_out_of_place_is_traced_again_from_the_last_line(cal, monkeypatch):
    """With hair round the mouth at calibration, a mouth the finder puts too high (the line ran along
    a moustache's lower edge) is not taken; the finder traces the line again from the last sure frame's
    row, and the frame keeps its mouth — before, it was ``mouth_lost`` (the painted-beard copies of the
    shared clips, 2-4 % of their frames). Where the second look is out of place too, the frame is lost
    as before. Without hair the second look is from the valleys under the line instead (see
    :func:`test_a_mouth_too_high_is_traced_again_from_the_valleys_under_it`)."""
    from tracker import mouth_finder as mf
    from tracker.params import MOUTH_LOST, OK

    tr, tr2 = FaceTracker(cal), FaceTracker(cal)
    assert not tr._hair
    tr._hair = tr2._hair = True  # (the synthetic performer has none)
    img, truth = render_face(BASE)
    assert all(t.track(img, 0).params.status == OK for t in (tr, tr2))
    real = type(tr.mouth_finder).find
    calls = []

    def high(self, crop, at, previous=None, steps=1.0, held=False, below=None):
        """The mouth found a third of the eye distance up, unless traced from the held line."""
        calls.append(held)
        r = real(self, crop, at, previous, steps, held, below)
        if r is None or held:
            return r
        up = 0.35 * cal.work_ipd
        return mf.MouthFinder.shifted(r, 0.0, -up)

    monkeypatch.setattr(type(tr.mouth_finder), "find", high)
    r = tr.track(img, 1)
    assert calls == [False, True]
    assert r.params.status == OK and abs(r.params.mouth_width - truth.mouth_width) < 2.0
    calls.clear()
    monkeypatch.setattr(type(tr.mouth_finder), "find", lambda self, crop, at, previous=None, steps=1.0, held=False, below=None: (
        calls.append(held), mf.MouthFinder.shifted(real(self, crop, at, previous, steps, False), 0.0, -0.35 * cal.work_ipd))[1])
    assert tr2.track(img, 1).params.status == MOUTH_LOST and calls == [False, True]


def test_a_mouth_too_high_is_traced_again_from_the_valleys_under_it(cal, monkeypatch):
    """Without hair round the mouth, a mouth the finder puts too high (the line ran along the shadow
    under the nose, darker than a grin's gap over its teeth and with the thin upper lip under it) is
    traced again from the valleys under the refused line's start (the finder's ``below``), and the
    frame keeps its mouth when that one is in place: a photo of a broad grin was ``mouth_lost`` on 73 %
    of its frames. When the second look is too high as well, or finds nothing, the frame is
    ``mouth_lost`` as before."""
    from tracker import mouth_finder as mf
    from tracker.params import MOUTH_LOST, OK

    img, truth = render_face(BASE)
    up = 0.35 * cal.work_ipd
    real = mf.MouthFinder.find
    for retry_too, want in ((None, OK), ("high", MOUTH_LOST), ("none", MOUTH_LOST)):
        tr = FaceTracker(cal)
        assert not tr._hair and tr.track(img, 0).params.status == OK
        calls = []

        def find(self, crop, at, previous=None, steps=1.0, held=False, below=None):
            calls.append(below)
            r = real(self, crop, at, previous, steps, held, below)
            if below is None:
                return mf.MouthFinder.shifted(r, 0.0, -up)
            if retry_too == "none":
                return None
            return mf.MouthFinder.shifted(r, 0.0, -up) if retry_too == "high" else r

        monkeypatch.setattr(mf.MouthFinder, "find", find)
        r = tr.track(img, 1)
        monkeypatch.undo()
        assert len(calls) == 2 and calls[0] is None and calls[1] is not None
        assert r.params.status == want
        if want == OK:
            assert abs(r.params.mouth_width - truth.mouth_width) < 2.0
