"""Calibration files, tracking a performance (loss and recovery) and the track CLI."""

import csv
import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

from tracker.auto_init import AutoInitError, auto_clicks
from tracker.calibration import Calibration, CalibrationError, calibrate
from tracker.clicks import Clicks
from tracker.face_tracker import FaceTracker
from tracker.params import CSV_COLUMNS, LOST, read_csv
from tracker.synthetic import STYLES, FaceState, Performance, clicks_for, render_face
from tracker.track_cli import add_arguments, run

from late_face import write_late_face_clip

MOUTH_PRECISION = ("issue 13 (i13-mouth): the real-face mouth finder misses the synthetic performer's lip_upper / "
                   "lip_lower (1.5-3 px) and pale-lip width precision; everything else is asserted first")

BASE = FaceState(cx=320.0, cy=210.0, ipd=80.0)


@pytest.fixture(scope="module")
def cal():
    frame, _ = render_face(BASE)
    return calibrate(frame, Clicks.from_dict(clicks_for(BASE)))


def test_calibration_save_load_round_trip(cal, tmp_path):
    p = tmp_path / "perf" / "me.json"
    cal.save(p)
    assert (p.parent / "me.eye_l.png").exists() and (p.parent / "me.eye_r.png").exists()
    assert (p.parent / "me.colour_tables.png").exists()
    assert json.loads(p.read_text())["format"] == 2
    back = Calibration.load(p)
    for name in ("pupil", "lip", "eye"):
        assert np.array_equal(getattr(back, name).table, getattr(cal, name).table)
    assert np.allclose(back.eye_templates[0], cal.eye_templates[0])
    assert back.neutral.values() == pytest.approx(cal.neutral.values())
    img, _ = render_face(BASE.with_expression("ah").replace(roll_deg=10.0))
    a = FaceTracker(cal).track(img).params.values()
    b = FaceTracker(back).track(img).params.values()
    assert np.allclose(a, b, atol=1e-6)
    assert not list(p.parent.glob(".*.tmp"))  # atomic writes leave no temporaries


def test_format_1_calibration_rebuilds_its_colour_tables(cal, tmp_path):
    p = tmp_path / "old.json"
    cal.save(p)
    d = json.loads(p.read_text())
    d["format"] = 1
    del d["colour_tables"]
    p.write_text(json.dumps(d))
    (tmp_path / "old.colour_tables.png").unlink()
    back = Calibration.load(p)
    for name in ("pupil", "lip", "eye"):
        assert np.array_equal(getattr(back, name).table, getattr(cal, name).table)


def test_calibration_with_a_broken_colour_table_image_names_it(cal, tmp_path):
    p = tmp_path / "me.json"
    cal.save(p)
    cv2.imwrite(str(tmp_path / "me.colour_tables.png"), np.zeros((40, 30), np.uint8))
    with pytest.raises(CalibrationError, match="me.colour_tables.png"):
        Calibration.load(p)
    (tmp_path / "me.colour_tables.png").unlink()
    with pytest.raises(CalibrationError, match="me.colour_tables.png"):
        Calibration.load(p)


def test_calibration_load_errors(tmp_path):
    with pytest.raises(CalibrationError, match="cannot read"):
        Calibration.load(tmp_path / "none.json")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": 99}))
    with pytest.raises(CalibrationError, match="format"):
        Calibration.load(bad)


def test_calibrate_rejects_clicks_off_the_face():
    frame, _ = render_face(BASE)
    c = clicks_for(BASE)
    c["mouth"] = [320.0, 150.0]  # above the eyes
    with pytest.raises(CalibrationError, match="mouth"):
        calibrate(frame, Clicks.from_dict(c))
    c = clicks_for(BASE)
    c["mouth"] = [320.0, 700.0]
    with pytest.raises(CalibrationError, match="outside"):
        calibrate(frame, Clicks.from_dict(c))


@pytest.mark.slow
def test_performance_with_roll_blinks_and_an_absence():
    """A 3 s performance; the face is gone for 0.4 s and must be back within 5 frames."""
    perf = Performance(seconds=3.0, seed=11, style=STYLES["strong_roll"], away=[(1.6, 2.0)])
    cal = calibrate(perf.frame(0), Clicks.from_dict(perf.clicks()))
    tr = FaceTracker(cal)
    errs, status, vis = [], [], []
    for i in range(len(perf)):
        img, t = perf.render(i)
        r = tr.track(img, i, i / 30)
        status.append(r.params.status)
        vis.append(t.status != LOST)
        if t.status != LOST and r.params.status != LOST:
            errs.append(np.abs(r.params.values() - t.values()))
    e = np.median(np.array(errs), axis=0)
    assert e[:2].max() < 1 and e[2] < 1 and e[3:7].max() < 1.5, e.round(2)
    away = [i for i, v in enumerate(vis) if not v]
    assert all(status[i] == LOST for i in away[1:])  # lost (values held) while gone
    back = away[-1] + 1
    lost_after = 0
    while status[back + lost_after] == LOST:
        lost_after += 1
    assert lost_after <= 5
    assert sum(s == LOST and v for s, v in zip(status, vis)) == lost_after
    if not (e[7] < 2 and e[8:].max() < 1.5):
        pytest.xfail(MOUTH_PRECISION + f" (width, lips: {e[7:].round(2)})")


def test_a_face_sliding_out_of_the_picture_is_not_ok_once_an_eye_is_out():
    """The performer slides out to the left fast (seed 4 of the slide-away benchmark): on the frame
    the face leaves the picture its left eye is already outside it and cannot have been measured,
    so the frame is lost, not ok (the pupils were allowed 0.1 of the eye distance past the edge)."""
    perf = Performance(seconds=3.0, seed=4, away=[(2.0, 3.0)], away_mode="slide")
    tr = FaceTracker(calibrate(perf.frame(0), Clicks.from_dict(perf.clicks())))
    for i in range(len(perf)):
        img, t = perf.render(i)
        r = tr.track(img, i, i / 30)
        if t.status == LOST:
            assert r.params.status != "ok", f"frame {i}: ok while the face is out of the picture"


def _hand_over(img: np.ndarray, state: FaceState, share: float) -> np.ndarray:
    """``img`` with a flat, shaded, skin-coloured hand (the stress clips' ``covered`` hand, without its
    texture) that has come ``share`` (0..1) of the way in from the right to cover the face (an ellipse
    2.5 × 3.2 eye distances)."""
    from benchmarks.stress_clips import paint_hand
    from tracker.synthetic import face_landmarks

    lm = face_landmarks(state)
    c = 0.5 * (lm["left_pupil"] + lm["right_pupil"]) + (0.0, 0.45 * state.ipd)
    w = img.shape[1]
    cheek = img[int(c[1]) - 10 : int(c[1]) + 10, int(c[0] + 0.5 * state.ipd) : int(c[0] + 0.5 * state.ipd) + 10]
    skin = 0.92 * np.median(cheek.reshape(-1, 3), axis=0)
    x = w + 1.3 * state.ipd + (c[0] - w - 1.3 * state.ipd) * share
    return paint_hand(img, (x, c[1]), (1.25 * state.ipd, 1.6 * state.ipd), skin)


def test_a_hand_over_the_face_is_not_the_face(cal):
    """A hand (skin-coloured, lit like a face) passes over the face: once it covers both eyes the
    frames are lost within two frames — neither ok nor "mouth lost" with the eyes held as if seen —
    and the face is ok again as soon as the hand has left the eyes."""
    tr = FaceTracker(cal)
    shares = [0.0] * 5 + [0.25, 0.5, 0.75] + [1.0] * 10 + [0.75, 0.5, 0.25] + [0.0] * 5
    status = []
    for i, share in enumerate(shares):
        state = BASE.replace(cx=320.0 + 0.3 * i)
        img = render_face(state)[0]
        status.append(tr.track(_hand_over(img, state, share) if share else img, i, i / 30).params.status)
    covered = [s for s, share in zip(status, shares) if share == 1.0]
    assert "ok" not in covered and all(s == LOST for s in covered[2:]), covered
    assert all(s == "ok" for s, share in zip(status, shares) if share <= 0.5), status


def test_a_second_look_finds_the_face_where_the_tracker_is_not(cal):
    """The face finder's second look (detector, eye pictures, face picture) gives the face's pupils
    when the tracker's are an eye-distance off, and nothing when they are right; the tracker takes
    it after RECHECK_EVERY unsure frames, then no sooner than RECHECK_GAP frames apart."""
    from tracker.face_tracker import RECHECK_EVERY, RECHECK_GAP

    img, t = render_face(BASE)
    tr = FaceTracker(cal)
    tr.track(img, 0)
    right = tr.pupils.copy()
    assert tr._second_look(img) is None
    tr.pupils = right - (BASE.ipd, 0.0)
    tr.anchors = tr.anchors - (BASE.ipd, 0.0)  # the pose followed them there
    found = tr._second_look(img)
    assert found is not None and np.abs(found - right).max() < 2.0
    # "eyes" a fifth too far apart in the box (a turned head's outer eye corners) while the pose is
    # on the face and only the reported eyes are off: the face picture says stay
    tr.anchors = tr.anchors + (BASE.ipd, 0.0)
    mid = right.mean(axis=0)
    tr._face_in_box = lambda frame, box: mid + 1.2 * (right - mid)
    assert tr._second_look(img) is None
    tr = FaceTracker(cal)
    looks = []
    tr._second_look = lambda frame: looks.append(len(looks)) or None
    for i in range(RECHECK_EVERY + 2 * RECHECK_GAP + 1):
        state = BASE.replace(mouth_open=0.0)
        frame = render_face(state)[0]
        frame[int(t.mid_y + 0.7 * BASE.ipd) : int(t.mid_y + 1.4 * BASE.ipd), int(t.mid_x - BASE.ipd) : int(t.mid_x + BASE.ipd)] = (40, 40, 40)
        assert tr.track(frame, i).params.status != "ok"  # the mouth is hidden: unsure frames
    assert len(looks) == 3


def test_a_face_found_again_may_have_glancing_eyes_when_its_picture_vouches_for_it(cal, monkeypatch):
    """Found again in a detector's box, eyes that a glance or a stare make only half like the
    calibrated ones (scores 0.45-0.6) are taken when the face picture there is plainly this face's,
    and refused when it is not (the same eyes on a blank wall)."""
    from tracker.face_finder import detect_faces
    from tracker.face_tracker import EYE_LOOSE, EYE_STRONG

    img, _ = render_face(BASE)
    tr = FaceTracker(cal)
    tr.track(img, 0)
    box = detect_faces(img, BASE.ipd)[0]
    true_pair = tr._eye_pair
    # eyes that score 0.5 (under EYE_STRONG, over EYE_LOOSE) where the box puts them, in this picture
    glance = lambda frame, guess, sure: None if (p := true_pair(img, guess, sure)) is None else (p[0], 0.5)
    monkeypatch.setattr(tr, "_eye_pair", glance)
    assert EYE_LOOSE <= 0.5 < EYE_STRONG
    found = tr._face_in_box(img, box)
    assert found is not None and np.abs(found - tr.pupils).max() < 2.0
    wall = render_face(BASE.replace(visible=False))[0]
    tr._grey = tr.motion.grey(wall)  # the face picture is looked for in this frame
    assert tr._face_in_box(wall, box) is None


def test_two_clear_eyes_outvote_a_face_picture_a_side_light_has_spoiled(cal, monkeypatch):
    """A strong side light lays a ramp over the face picture (real clips: 0.9 in even light, 0.3
    with one side in deep shade) while both eyes still match their pictures at 0.8-0.9 where the
    pose puts them: the face is there. Shut eyes cannot vouch for it: then the picture decides."""
    import tracker.face_tracker as ft

    tr = FaceTracker(cal)
    tr.track(render_face(BASE)[0], 0)
    monkeypatch.setattr(ft, "locate_face", lambda *a, **k: (np.zeros(2), 0.25))
    status = [tr.track(render_face(BASE.replace(cx=320.0 + 0.3 * i))[0], i, i / 30).params.status for i in range(1, 6)]
    assert status == ["ok"] * 5, status
    shut = tr.track(render_face(BASE.replace(cx=321.8).with_expression("eyes_closed"))[0], 6, 0.2)
    assert shut.params.status == LOST and shut.debug.get("lost") == "not this face"


def test_without_the_flow_weak_eyes_move_the_head_but_do_not_grow_it_unless_the_face_picture_agrees(cal):
    """With the flow lost for a frame (a quick turn), two weak eyes found on their outer corners
    12 % too far apart move the head's midpoint and roll but not its scale: on a darkened copy of a
    real clip such a frame grew the head 4 % at a time and every pupil after it stayed on the eye
    corners, 10 % of the eye distance off and reported ok. Two clear eyes still grow it, as far as
    a frame allows."""
    import math

    from tracker.face_tracker import MAX_GROW

    img, _ = render_face(BASE)
    tr = FaceTracker(cal)
    tr.track(img, 0)
    a = tr.anchors.copy()
    mid = 0.5 * (a[0] + a[1]) + (3.0, -2.0)
    wide = mid + 1.12 * (a - 0.5 * (a[0] + a[1]))
    found = tr._pupils_face.copy()
    length = lambda p: math.hypot(*(p[1] - p[0]))
    tr._follow(a, wide, [True, True], found, flow_ok=False, pinned=False, strong=False)
    assert length(tr.anchors) == pytest.approx(length(a), rel=1e-6)  # the picture is at the old scale
    assert np.allclose(0.5 * (tr.anchors[0] + tr.anchors[1]), mid)
    tr.anchors = a.copy()
    tr._follow(a, wide, [True, True], found, flow_ok=False, pinned=False, strong=True)
    assert length(tr.anchors) == pytest.approx((1 + MAX_GROW) * length(a), rel=1e-6)


def test_consensus_keeps_the_middle_reading_never_an_outlier_or_a_blend():
    """Calibration learns each model on a few crops a fraction of a pixel apart and keeps the one
    whose readings sit in the middle: one crop's odd reading (a lower lip read at a third of its
    thickness) is never the one kept, and what is kept is a reading one crop really gave."""
    from tracker.calibration import CONSENSUS_SHIFTS, consensus

    readings = [[0.35, 2.0], [1.10, 2.1], [1.00, 2.0], [0.90, 1.95], [1.05, 2.05]]
    assert consensus(readings) == 2
    assert consensus([[0.0]]) == 0 and consensus([[1.0], [3.0], [2.0]]) == 2
    assert CONSENSUS_SHIFTS[0] == (0.0, 0.0) and len(CONSENSUS_SHIFTS) % 2 == 1
    assert all(abs(dx) < 1.0 and abs(dy) < 1.0 for dx, dy in CONSENSUS_SHIFTS)


def test_the_kept_models_are_ones_a_shifted_crop_gave(cal):
    """The eye and mouth models kept are learned on one of the shifted crops (their readings are
    one crop's, not an average)."""
    from tracker.calibration import CONSENSUS_SHIFTS, FaceFrame, eye_calibration_crop
    from tracker.eyes import learn_eyes
    from tracker.mouth_model import learn_mouth

    frame, _ = render_face(BASE)
    c = cal.clicks
    ff = FaceFrame.from_pupils(c.left_pupil, c.right_pupil, cal.work_ipd)
    wi = cal.work_ipd
    got = []
    for dx, dy in CONSENSUS_SHIFTS:
        r0 = eye_calibration_crop(wi)
        r = (r0[0] + dx, r0[1] + dy, r0[2], r0[3])
        crop = ff.crop(frame, r)
        brows = ff.to_face(np.array([c.left_brow, c.right_brow])) - r[:2]
        m = learn_eyes(crop, cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY).astype(np.float32),
                       np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]]) - r[:2], brows, wi)
        got.append(tuple(m.lid_open))
    assert any(np.allclose(cal.eye_model.lid_open, g, rtol=1e-6) for g in got)


def test_lost_holds_the_last_values(cal):
    tr = FaceTracker(cal)
    r0 = tr.track(render_face(BASE)[0])
    empty = render_face(BASE.replace(visible=False))[0]
    r1 = tr.track(empty, 1)
    r2 = tr.track(empty, 2)
    assert r1.params.status == LOST and r2.params.status == LOST
    assert np.allclose(r2.params.values(), r0.params.values())
    moved = BASE.replace(cx=200.0, cy=260.0, roll_deg=8.0)
    img, t = render_face(moved)
    r3 = tr.track(img, 3)
    r4 = tr.track(img, 4)
    assert r4.params.status != LOST
    assert abs(r4.params.mid_x - t.mid_x) < 1 and abs(r4.params.mid_y - t.mid_y) < 1


def test_the_mouth_adapts_on_ok_frames_and_forgets_after_a_long_loss(cal):
    """The tracker lets the mouth finder learn the lips from the frames it reports ok, and sends it
    back to the calibration with the eyes once the face has been lost for RESET_ADAPTATION frames."""
    from tracker.face_tracker import RESET_ADAPTATION

    tr = FaceTracker(cal)
    mf = tr.mouth_finder
    for i in range(6):
        state = BASE.replace(cx=320.0 + i, mouth_open=0.1 * (i % 2))
        assert tr.track(render_face(state)[0], i).params.status == "ok"
    assert mf._adapted == 6 and not np.array_equal(mf._mu, mf._mu0)
    empty = render_face(BASE.replace(visible=False))[0]
    for i in range(RESET_ADAPTATION + 1):
        assert tr.track(empty, 6 + i).params.status == LOST
    assert mf._adapted == 0 and np.array_equal(mf._mu, mf._mu0)
    assert (mf.t_up, mf.t_dn) == mf._thick0


def test_the_reported_lips_start_afresh_after_a_lost_frame(cal, monkeypatch):
    """The lips' thicknesses the tracker reports are steadied over the frames (steady_lips), but
    never across a lost frame: the first ok frame after one reports what the finder found."""
    import tracker.face_tracker as ftm

    seen = []
    real = ftm.steady_lips

    def spy(res, held, steps=1.0):
        seen.append(held)
        return real(res, held, steps)

    monkeypatch.setattr(ftm, "steady_lips", spy)
    tr = FaceTracker(cal)
    for i in range(3):
        assert tr.track(render_face(BASE.replace(mouth_open=0.2 * i))[0], i).params.status == "ok"
    assert seen[0] is None and all(h is not None for h in seen[1:])
    assert tr.track(render_face(BASE.replace(visible=False))[0], 3).params.status == LOST
    assert tr._lips_held is None
    n = len(seen)
    for i in range(4, 7):
        tr.track(render_face(BASE)[0], i)
    assert len(seen) > n and seen[n] is None
    # a frame judged lost after its mouth was found (a hand over the eyes) forgets them too
    assert tr._lips_held is not None
    tr._lost_result(7, 7 / 30, "not this face")
    assert tr._lips_held is None


def test_overlay_draws(cal, tmp_path):
    img, _ = render_face(BASE.with_expression("grin").replace(roll_deg=-12))
    tr = FaceTracker(cal)
    tr.track(img)
    r = tr.track(img, 1)
    out = r.overlay.draw(img)
    assert out.shape == img.shape and not np.array_equal(out, img)
    assert r.overlay.lip_polygon.shape[1] == 2 and len(r.overlay.rois) == 2
    assert len(r.overlay.blob_contour()) > 10
    # the blob is filled from the mouth result when first asked for, and can be replaced
    blob = r.overlay.blob
    assert blob is not None and blob.dtype == bool and blob.any() and r.overlay.blob is blob
    r.overlay.blob = None
    assert r.overlay.blob is None and len(r.overlay.blob_contour()) == 0


@pytest.mark.parametrize("style", ["default", "small_far"])
def test_auto_init_finds_the_clicks(style):
    st = BASE.replace(ipd=STYLES[style].ipd)
    img, _ = render_face(st, STYLES[style])
    got = auto_clicks(img)
    want = Clicks.from_dict(clicks_for(st))
    for k, v in got.points().items():
        assert np.hypot(*np.subtract(v, want.points()[k])) < 0.08 * st.ipd, k
    c = calibrate(img, got)
    assert abs(c.ipd - st.ipd) < 1.5


@pytest.mark.parametrize("roll", [20.0, -25.0, 30.0])
def test_auto_init_finds_a_rolled_head(roll):
    """The face detector finds faces within about 15° of upright; a head rolled further at the start is
    found on the frame turned by 20° either way, and the points come back to the frame as it is."""
    st = BASE.replace(roll_deg=roll)
    img, _ = render_face(st, STYLES["default"])
    got = auto_clicks(img)
    want = Clicks.from_dict(clicks_for(st))
    for k in ("left_pupil", "right_pupil", "mouth"):
        assert np.hypot(*np.subtract(got.points()[k], want.points()[k])) < 0.05 * st.ipd, k


def test_auto_init_finds_a_small_face_far_from_the_camera():
    """A face about 30 px between the eyes in a 640×480 frame, the rest of it a dark room: too small for
    the detector on the 160-px copy an any-size search starts with; found on the larger one."""
    img, _ = render_face(BASE, STYLES["default"])
    small = cv2.resize(img, None, fx=0.35, fy=0.35, interpolation=cv2.INTER_AREA)
    frame = np.full_like(img, 30)
    frame[100 : 100 + small.shape[0], 300 : 300 + small.shape[1]] = small
    got = auto_clicks(frame)
    want = Clicks.from_dict(clicks_for(BASE))
    lp = np.multiply(want.left_pupil, 0.35) + (300.0, 100.0)  # where the shrunk face put it (pixel centres at .5)
    assert np.hypot(*np.subtract(got.left_pupil, lp)) < 0.08 * 0.35 * BASE.ipd


def test_auto_init_says_when_nothing_is_found():
    blank = np.full((240, 320, 3), 128, np.uint8)
    with pytest.raises(AutoInitError, match="no face"):
        auto_clicks(blank)


# --------------------------------------------------------------------------- CLI


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    d = tmp_path_factory.mktemp("clip")
    perf = Performance(seconds=1.0, seed=4)
    video = d / "clip.avi"
    w = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"FFV1"), 30, perf.frame_size)
    assert w.isOpened()
    for i in range(len(perf)):
        w.write(perf.frame(i))
    w.release()
    clicks = d / "clip.clicks.json"
    clicks.write_text(json.dumps(perf.clicks()))
    return video, clicks, perf


@pytest.mark.parametrize("shown, want", [
    ({0: 5.0}, 0),  # the first frame's eyes show: taken at once
    ({0: 1.0, 2: 1.5, 4: 6.0, 6: 3.0}, 4),  # shut at first: the first frame within the look whose eyes show
    ({0: 1.0, 2: 2.5, 4: 9.0}, 2),  # ... the first that shows them, not the one that shows them most
    ({0: 1.5, 2: 1.0, 4: 1.8, 6: 1.2}, 4),  # none shows them: the one that comes nearest
    ({0: 1.0}, 0),  # nothing better within the look: the first after all
])
def test_auto_start_looks_past_a_first_frame_with_shut_eyes(clip, monkeypatch, shown, want):
    """``--auto`` takes the first frame with a face, unless its eyes look shut (a clip that starts in a
    blink or a squeeze: an eye model learned there misreads the whole clip); then the first frame within
    :data:`~tracker.track_cli.AUTO_LOOK` whose eyes show — or, where none does, the one whose eyes show
    most. (The measure itself is judged on real clips: the synthetic performer's shut lids are crisp
    lines that look like an eye's ring to it.)"""
    import tracker.auto_init as ai
    import tracker.track_cli as tc

    video, _, _ = clip
    seen = []

    def fake(img, found):
        seen.append(found.frame)
        return shown.get(found.frame, 0.5)

    monkeypatch.setattr(ai, "eyes_shown", fake)
    found, img = tc._auto(video)
    assert found.frame == want and img.shape[2] == 3
    looked = list(range(0, ai.AUTO_LOOK[0], ai.AUTO_LOOK[1]))
    opened = [f for f in looked if shown.get(f, 0.5) >= ai.EYES_SHOWN]
    assert seen == (looked[: looked.index(opened[0]) + 1] if opened else looked)


@pytest.mark.parametrize("empty", [3, 47])
def test_auto_start_waits_for_a_face_that_comes_late(tmp_path, empty):
    """A recording that opens on an empty room (or a camera started before the performer sits down)
    starts where the face first shows — one frame at a time at first, then one every
    :data:`~tracker.auto_init.AUTO_EVERY` s — and tracking from frame 0 reports ``lost`` until then."""
    import tracker.auto_init as ai

    video = tmp_path / "late.avi"
    perf = write_late_face_clip(video, empty, Performance(seconds=1.0, seed=4), faces=12, fps=25)
    from tracker.track_cli import _Video

    v = _Video(video)
    try:
        found, img = ai.auto_start(v.frames(), 25.0)
    finally:
        v.close()
    stride = max(int(round(ai.AUTO_EVERY * 25.0)), 1)
    assert empty <= found.frame < empty + stride
    assert np.array_equal(img, perf.frame(found.frame - empty))
    want = Clicks.from_dict(clicks_for(perf.state(found.frame - empty)))
    assert np.hypot(*np.subtract(found.left_pupil, want.left_pupil)) < 0.1 * perf.state(0).ipd
    out = tmp_path / "late.csv"
    assert _cli(video, "--auto", "--csv", out, "--quiet") == 0
    rows = read_csv(out)
    assert len(rows) == empty + 12
    assert [r.status for r in rows[:empty]] == [LOST] * empty
    assert all(r.status == "ok" for r in rows[found.frame + 1 :])


def test_auto_start_reports_each_frame_it_tries_until_the_face(tmp_path):
    """While no face is found, each frame tried is reported (the command line shows a progress line
    during a long empty opening): one by one at first, then one every AUTO_EVERY s."""
    import tracker.auto_init as ai
    from tracker.track_cli import _Video

    video = tmp_path / "late.avi"
    write_late_face_clip(video, 30, Performance(seconds=1.0, seed=4), faces=6, fps=25)
    seen = []
    v = _Video(video)
    try:
        found, _ = ai.auto_start(v.frames(), 25.0, seen.append)
    finally:
        v.close()
    stride = max(int(round(ai.AUTO_EVERY * 25.0)), 1)
    assert seen[: ai.AUTO_TRIES] == list(range(ai.AUTO_TRIES))
    later = seen[ai.AUTO_TRIES :]
    assert later[0] == ai.AUTO_TRIES and all(b - a == stride for a, b in zip(later, later[1:]))
    assert seen[-1] == found.frame >= 30


def test_auto_start_says_when_no_frame_holds_a_face(tmp_path, capsys):
    video = tmp_path / "wall.avi"
    w = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"FFV1"), 25, (320, 240))
    for _ in range(40):
        w.write(np.full((240, 320, 3), 128, np.uint8))
    w.release()
    assert _cli(video, "--auto", "--csv", tmp_path / "o.csv", "--quiet") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "wall.avi: no face found in any frame" in err[0]


def test_clicks_on_a_blink_calibrate_on_the_frame_the_head_carries_them_to(clip, monkeypatch):
    """``--init`` clicks on a frame whose eyes look shut are carried with the head's motion to the first
    frame within :data:`~tracker.open_eyes.LOOK` whose eyes show (tracker.open_eyes; its own tests
    cover the carrying), and calibration reads that frame."""
    import tracker.open_eyes as oe
    import tracker.track_cli as tc

    video, clicks_path, perf = clip
    monkeypatch.setattr(oe, "eyes_shown", lambda img, c: 5.0 if c.frame == 6 else 0.5)
    got, img = tc._clicked(video, Clicks.load(clicks_path), "clicks")
    assert got.frame == 6
    assert np.array_equal(img, perf.frame(6))  # a lossless clip: the very frame
    mid = 0.5 * (np.asarray(got.left_pupil) + got.right_pupil)
    truth = perf.truth(6)
    assert np.hypot(mid[0] - truth.mid_x, mid[1] - truth.mid_y) < 0.5


def test_the_command_says_where_it_calibrated_when_the_clicked_frame_caught_a_blink(clip, tmp_path, monkeypatch, capsys):
    import tracker.open_eyes as oe

    video, clicks_path, perf = clip
    monkeypatch.setattr(oe, "eyes_shown", lambda img, c: 5.0 if c.frame == 4 else 0.5)
    assert _cli(video, "--init", clicks_path, "--csv", tmp_path / "out.csv") == 0
    err = capsys.readouterr().err
    assert "eyes look shut on frame 0" in err and "calibrated on frame 4" in err
    assert len(read_csv(tmp_path / "out.csv")) == len(perf)  # every frame tracked, from the first


def _cli(*argv):
    import argparse

    ap = argparse.ArgumentParser()
    add_arguments(ap)
    return run(ap.parse_args([str(a) for a in argv]))


def test_cli_tracks_a_clip(clip, tmp_path, capsys):
    video, clicks, perf = clip
    out = tmp_path / "out.csv"
    assert _cli(video, "--init", clicks, "--csv", out, "--quiet") == 0
    with open(out) as f:
        header = next(csv.reader(f))
    assert tuple(header[:11]) == CSV_COLUMNS
    rows = read_csv(out)
    assert len(rows) == len(perf)
    err = np.array([np.abs(r.values() - perf.truth(i).values()) for i, r in enumerate(rows)])
    med = np.median(err, axis=0)
    assert med[:3].max() < 1 and med[3:7].max() < 1.5 and med[7] < 2 and med[8:].max() < 1.5, med.round(2)
    assert all(r.status != LOST for r in rows)


@pytest.mark.parametrize(
    "case, message",
    [
        ("missing_video", "no such video"),
        ("not_video", "cannot open"),
        ("missing_key", "missing key"),
        ("outside", "outside"),
        ("past_end", "past the end"),
        ("bad_json", "not valid JSON"),
    ],
)
def test_cli_bad_inputs_give_one_line(clip, tmp_path, capsys, case, message):
    video, clicks, perf = clip
    d = json.loads(clicks.read_text())
    cl = tmp_path / "c.json"
    v = video
    if case == "missing_video":
        v = tmp_path / "none.avi"
    elif case == "not_video":
        v = tmp_path / "text.avi"
        v.write_text("hello")
    elif case == "missing_key":
        d.pop("left_brow")
    elif case == "outside":
        d["mouth"] = [700, 20]
    elif case == "past_end":
        d["frame"] = 500
    cl.write_text("{oops" if case == "bad_json" else json.dumps(d))
    rc = _cli(v, "--init", cl, "--csv", tmp_path / "o.csv", "--quiet")
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert err.startswith("inkface: ") and message in err and "\n" not in err and "Traceback" not in err


def test_cli_notes_a_calibration_frame_with_the_eyes_aside(clip, tmp_path, capsys, monkeypatch):
    """The performer looking ahead: no note. A calibration whose iris pictures keep a glance: one
    note on stderr, naming where the points came from; nothing with --quiet."""
    import tracker.track_cli as tc

    video, clicks, perf = clip
    assert _cli(video, "--init", clicks, "--csv", tmp_path / "a.csv") == 0
    assert "note:" not in capsys.readouterr().err
    monkeypatch.setattr(tc, "calibration_hints", lambda cal: ["the eyes look to one side"])
    assert _cli(video, "--init", clicks, "--csv", tmp_path / "b.csv", "--force") == 0
    notes = [ln for ln in capsys.readouterr().err.splitlines() if "note:" in ln]
    assert notes == [f"inkface: note: the eyes look to one side (clicks {clicks}, frame {perf.clicks()['frame']})"]
    assert _cli(video, "--init", clicks, "--csv", tmp_path / "c.csv", "--quiet") == 0
    assert "note:" not in capsys.readouterr().err


def test_calibration_hints_name_a_glance_aside(cal):
    """The synthetic performer's calibration looks ahead; the same with iris pictures whose white
    lies on one side only (the iris against the eye's shaded corner) asks for a frame looking into
    the camera."""
    from dataclasses import replace

    from tracker.calibration import calibration_hints

    assert calibration_hints(cal) == []
    pics = []
    for pic in cal.eye_model.iris_pictures:
        p = np.array(pic, dtype=np.float32)
        p[:, : p.shape[1] // 2 - int(round(cal.eye_model.radius[0]))] = 90.0  # the shaded corner over the left flank
        pics.append(p)
    # (glance None: read from these pictures, as for a model saved before the glance was kept)
    glancing = replace(cal, eye_model=replace(cal.eye_model, iris_pictures=pics, glance=None))
    hints = calibration_hints(glancing)
    assert len(hints) == 1 and "look into the camera" in hints[0]


def test_calibration_hints_ask_a_small_face_to_come_closer(cal):
    """A face 36 px between the eyes (a far face, a low-resolution camera) is calibrated as any
    other, with advice to come closer; at 80 px there is none."""
    from tracker.calibration import calibration_hints

    far = FaceState(cx=160.0, cy=110.0, ipd=36.0)
    frame, _ = render_face(far)
    small = calibrate(frame, Clicks.from_dict(clicks_for(far)))
    hints = calibration_hints(small)
    assert len(hints) == 1 and "(36 px between the eyes)" in hints[0] and "come closer" in hints[0]
    assert calibration_hints(cal) == []


def test_cli_module_entry_point_exit_code(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "tracker.track_cli", str(tmp_path / "x.mp4"), "--init", "c.json", "--csv", "o.csv"],
        capture_output=True, text=True, timeout=60,
    )
    assert r.returncode == 2
    assert r.stderr.strip().count("\n") == 0 and "no such video" in r.stderr
