"""Still faces under a known camera motion (benchmarks.stills): the motion, the figures, a whole run."""

import json
import math

import cv2
import numpy as np
import pytest

from benchmarks import realfaces as rf
from benchmarks import stills as S
from tracker.params import PARAM_NAMES
from tracker.synthetic import FaceState, clicks_for, face_landmarks, render_face


def test_the_motion_starts_still_and_is_undone_by_its_inverse():
    assert np.allclose(S.motion(0), [[1, 0, 0], [0, 1, 0]])
    for i in (7, 31, 80):
        m = S.motion(i)
        pts = np.array([[10.0, 20.0], [300.0, 400.0]])
        assert np.allclose(S.apply(S.inverse(m), S.apply(m, pts)), pts)
        assert abs(S.scale_of(m) - 1.0) <= S.MOTION[2] + 1e-9
    scales = [S.scale_of(S.motion(i)) for i in range(S.FRAMES)]
    assert max(scales) > 1.03 and min(scales) < 0.97  # it leans in and out


def _run_following(mats, pupils0, mouth0, values0):
    """A perfect tracker on a still: points moved by the motion, lengths scaled with it."""
    n = len(mats)
    run = S.StillRun("x", "clicks", statuses=["ok"] * n)
    run.pupils = np.array([S.apply(m, pupils0) for m in mats])
    run.mouths = np.array([S.apply(m, mouth0[None])[0] for m in mats])
    run.values = np.array([values0 * np.r_[np.ones(3), np.full(7, S.scale_of(m))] for m in mats])
    return run


def _values():
    v = np.zeros(len(PARAM_NAMES))
    ix = {k: i for i, k in enumerate(PARAM_NAMES)}
    for k, x in (("eye_open_l", 20), ("eye_open_r", 21), ("brow_l", 40), ("brow_r", 41), ("mouth_width", 90),
                 ("lip_upper", 10), ("lip_lower", 15)):
        v[ix[k]] = x
    return v


def test_a_tracker_that_follows_the_motion_has_no_drift_flicker_or_jumps():
    mats = np.array([S.motion(i) for i in range(60)])
    pupils0 = np.array([[200.0, 220.0], [300.0, 221.0]])
    run = _run_following(mats, pupils0, np.array([250.0, 340.0]), _values())
    m = S.still_metrics(run, mats, {"left_pupil": pupils0[0], "right_pupil": pupils0[1],
                                    "left_mouth_corner": np.array([210.0, 340.0]), "right_mouth_corner": np.array([290.0, 340.0])})
    assert m["ok_pct"] == 100.0 and m["pupil_drift_max"] < 1e-6 and m["mouth_drift_p95"] < 1e-6
    assert all(m[f"sd_{k}"] < 1e-6 for k in S.SHAPES) and m["jumps"] == 0
    assert m["pupil_err"] < 1e-6 and m["mouth_err"] < 1e-6
    assert not any(S.still_misses(m).values())


def test_a_flip_of_one_pupil_and_of_the_width_is_drift_flicker_and_jumps():
    mats = np.array([S.motion(i) for i in range(60)])
    pupils0 = np.array([[200.0, 220.0], [300.0, 220.0]])
    run = _run_following(mats, pupils0, np.array([250.0, 340.0]), _values())
    run.pupils[2::3, 1, 1] -= 4.0  # every third frame, 4 % of the eye distance up
    run.values[10, PARAM_NAMES.index("mouth_width")] += 15.0  # one frame 15 % wider
    run.statuses[30] = "lost"
    m = S.still_metrics(run, mats)
    assert 3.0 < m["pupil_drift_max"] <= 4.0 / (1.0 - S.MOTION[2]) + 1e-6 and m["pupil_drift_p95"] > 3.0  # (4 frame px, back in the still)
    assert m["jumps"] == 2  # into the wide frame and out of it
    assert m["sd_width"] > 1.0 and m["sd_open"] < 1e-6
    assert m["ok_pct"] == pytest.approx(100.0 * 59 / 60)
    x = S.still_misses(m)
    assert x["pupil_drift_p95"] and x["jumps"] and x["ok_pct"] and not x["sd_eye"]
    assert math.isnan(m["pupil_err"])  # no peer on a photo


def test_nothing_ok_gives_no_figures_but_ok_pct():
    mats = np.array([S.motion(i) for i in range(5)])
    run = S.StillRun("x", "auto", statuses=["lost"] * 5, pupils=np.zeros((5, 2, 2)), mouths=np.zeros((5, 2)),
                     values=np.zeros((5, len(PARAM_NAMES))))
    m = S.still_metrics(run, mats)
    assert m["ok_pct"] == 0.0 and math.isnan(m["pupil_drift_p95"])
    assert all(S.still_misses(m).values())


@pytest.fixture(scope="module")
def performer_still():
    state = FaceState(cx=256.0, cy=230.0, ipd=90.0)
    img, _ = render_face(state, frame_size=(512, 512))
    lm = face_landmarks(state)
    truth = {k: np.asarray(lm[k], float) for k in ("left_pupil", "right_pupil")}
    return S.Still("performer", "synthetic", img, face_px=90.0, truth=truth, clicks=clicks_for(state))


def test_the_synthetic_performer_holds_still_on_a_still(tmp_path, performer_still):
    r = S.measure_still(performer_still, auto=False, frames=24, sheets=True, out_dir=tmp_path)
    assert r.error is None, r.error
    m = r.metrics
    assert m["ok_pct"] == 100.0 and m["pupil_drift_p95"] < 1.0 and m["pupil_err"] < 2.0
    assert m["jumps"] == 0 and all(m[f"sd_{k}"] < 1.0 for k in S.SHAPES)
    sheet = cv2.imread(r.sheet)
    assert sheet is not None and sheet.shape[1] == 4 * 256
    table = S.stills_table([r]).render()
    assert "performer" in table and "clicks: 1/1 stills meet every target" in table


def test_photos_are_cropped_round_each_face_and_unreadable_ones_skipped(tmp_path, capsys):
    state = FaceState(cx=400.0, cy=300.0, ipd=70.0)
    img, _ = render_face(state, frame_size=(800, 600))
    cv2.imwrite(str(tmp_path / "face.png"), img)
    (tmp_path / "broken.jpg").write_bytes(b"not a picture")
    cv2.imwrite(str(tmp_path / "wall.png"), np.full((300, 300, 3), 128, np.uint8))
    stills = S.photo_stills(tmp_path)
    assert [s.name for s in stills] == ["face"]
    s = stills[0]
    assert s.image.shape == (S.SIZE, S.SIZE, 3) and s.clicks is None and s.truth is None
    err = capsys.readouterr().err
    assert "broken.jpg: not a picture" in err and "wall.png: no face found" in err


def test_a_photo_has_no_clicks_and_a_failed_start_is_a_row(tmp_path):
    blank = S.Still("blank", "photo", np.full((128, 128, 3), 90, np.uint8))
    r = S.measure_still(blank, auto=False, frames=3)
    assert r.error == "no clicks for a photo"
    r = S.measure_still(blank, auto=True, frames=3)
    assert r.error and "\n" not in r.error
    assert "start failed" in S.stills_table([r]).render()


def test_main_needs_a_source(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv(S.STILLS_DIR_ENV, raising=False)
    assert S.main(["--photos", str(tmp_path / "nowhere")]) == 2
    assert "no such folder" in capsys.readouterr().err
    assert S.main(["--no-clips"]) == 2


