"""The synthetic performer: what is drawn agrees with its truth; performances are reproducible."""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hs

from tracker.clicks import PIXEL_CENTRE
from tracker.params import PARAM_NAMES, read_csv
from tracker.synthetic import (
    EXPRESSIONS,
    STYLES,
    FaceState,
    Performance,
    Style,
    SynthError,
    face_landmarks,
    face_truth,
    render_face,
)

CLEAN = Style(catchlight=False, limbus=1.0)
# eyes drawn as plain white almonds on skin: isolates the lid outline for measuring
WHITE_EYES = Style(catchlight=False, limbus=1.0, iris=CLEAN.sclera, pupil=CLEAN.sclera, lash_width=0.0)


def sample(img: np.ndarray, p0, d, ts: np.ndarray) -> np.ndarray:
    """Bilinear samples of ``img`` (float) at ``p0 + t·d`` for each t."""
    pts = np.asarray(p0, np.float64)[None, :] + ts[:, None] * np.asarray(d, np.float64)[None, :]
    mx = pts[:, 0].astype(np.float32).reshape(1, -1)
    my = pts[:, 1].astype(np.float32).reshape(1, -1)
    out = cv2.remap(img.astype(np.float32), mx, my, cv2.INTER_LINEAR)
    return out.reshape(len(ts), -1)


def edge_from(img, p0, d, start: float, stop: float, ref_out, ref_in) -> float:
    """Where the shape of colour ``ref_in`` ends, walking from ``p0 + start·d`` (outside, colour
    about ``ref_out``) towards ``p0 + stop·d``; returned as t along ``d``.

    First the half-way crossing, then, for sub-pixel accuracy, the integral of the shape's
    coverage between a point 1.2 px inside and 2.5 px outside that crossing (skin is shaded, so
    the outside colour is re-sampled there).
    """
    sgn = 1.0 if stop > start else -1.0
    ts = np.arange(start, stop, 0.05 * sgn)

    def frac(ts, ref):
        axis = np.asarray(ref_in, np.float64) - np.asarray(ref, np.float64)
        return (sample(img, p0, d, ts) - np.asarray(ref)) @ axis / float(axis @ axis)

    f = frac(ts, ref_out)
    hit = np.nonzero(f >= 0.5)[0]
    assert hit.size, "edge not found"
    k = int(hit[0])
    assert k > 0, "started inside the shape"
    e0 = float(ts[k])
    t_out, t_in = e0 - 2.5 * sgn, e0 + 1.2 * sgn
    ref = sample(img, p0, d, np.array([t_out]))[0]
    fine = np.linspace(t_out, t_in, 371)
    cov = np.clip(frac(fine, ref), 0.0, 1.0)
    inside_len = float(np.sum((cov[1:] + cov[:-1]) / 2.0) * abs(fine[1] - fine[0]))
    return t_in - sgn * inside_len


def unit(roll_deg: float):
    th = math.radians(roll_deg)
    right = np.array([math.cos(th), -math.sin(th)])
    up = np.array([-math.sin(th), -math.cos(th)])
    return right, up


def measure_eye_open(state: FaceState, side: str) -> float:
    img, _ = render_face(state, WHITE_EYES)
    lm = face_landmarks(state)
    _, up = unit(state.roll_deg)
    p = lm[f"{side}_pupil"]
    skin = sample(img, p, up, np.array([0.21 * state.ipd]))[0]
    white = np.asarray(WHITE_EYES.sclera, np.float64)
    top = edge_from(img, p, up, 0.21 * state.ipd, 0.0, skin, white)
    bottom = edge_from(img, p, -up, 0.27 * state.ipd, 0.0, skin, white)
    return top + bottom


def measure_brow(state: FaceState, side: str) -> float:
    img, _ = render_face(state, CLEAN)
    lm = face_landmarks(state)
    _, up = unit(state.roll_deg)
    p = lm[f"{side}_pupil"]
    u = state.ipd
    skin_lo = sample(img, p, up, np.array([0.2 * u]))[0]
    brow = np.asarray(CLEAN.brow, np.float64)
    lower = edge_from(img, p, up, 0.2 * u, 0.7 * u, skin_lo, brow)
    skin_hi = sample(img, p, up, np.array([lower + 0.13 * u]))[0]
    upper = edge_from(img, p, up, lower + 0.13 * u, lower, skin_hi, brow)
    return 0.5 * (lower + upper)


def lip_mask(img: np.ndarray, style: Style, state: FaceState) -> np.ndarray:
    """Pixels at least half-way from skin to lip colour, near the mouth."""
    lm = face_landmarks(state)
    f = img.astype(np.float64)
    skin = np.asarray(style.skin, np.float64)
    lip = np.asarray(style.lip, np.float64) * 0.93
    axis = lip - skin
    frac = (f - skin) @ axis / float(axis @ axis)
    near_skin = np.linalg.norm(f - skin, axis=2) < 0.5 * np.linalg.norm(axis)
    ys, xs = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    near = np.hypot(xs - lm["mouth"][0], ys - lm["mouth"][1]) < 0.7 * state.ipd
    return (frac >= 0.5) & near & ~near_skin


def blob_corners(mask: np.ndarray, roll_deg: float) -> tuple[float, float]:
    """Extreme extents of the mask's pixels along the pupil-line direction."""
    ys, xs = np.nonzero(mask)
    right, _ = unit(roll_deg)
    proj = xs * right[0] + ys * right[1]
    return float(proj.min()), float(proj.max())


POSES = [
    dict(),
    dict(roll_deg=25.0, cx=300.3, cy=220.7),
    dict(roll_deg=-17.5, ipd=64.4, cx=350.6, cy=190.2),
    dict(roll_deg=9.0, ipd=96.0),
    dict(roll_deg=-30.0, ipd=50.0, cx=280.0),
]


def measure_corners(img: np.ndarray, state: FaceState) -> tuple[float, float]:
    """Signed distances (outward, px) from each true corner to the lip blob's end, measured on
    the corner line by the half-way crossing from skin to lip colour."""
    lm = face_landmarks(state)
    right, _ = unit(state.roll_deg)
    lip = np.asarray(CLEAN.lip, np.float64) * 0.93
    out = []
    for side, d in (("mouth_left", -right), ("mouth_right", right)):
        skin = sample(img, lm[side], d, np.array([4.0]))[0]
        out.append(edge_from(img, lm[side], d, 4.0, -6.0, skin, lip))
    return out[0], out[1]


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("expr", ["neutral", "smile", "ah", "oo", "grin", "frown", "squint", "brows_up", "brows_angry"])
def test_mouth_corners_match_mouth_width(pose, expr):
    st = FaceState(**pose).with_expression(expr)
    img, truth = render_face(st, CLEAN)
    el, er = measure_corners(img, st)
    assert abs(el) < 0.5 and abs(er) < 0.5
    assert truth.mouth_width + el + er == pytest.approx(truth.mouth_width, abs=1.0)
    # the thresholded lip blob spans the same width (whole pixels, so a coarser bound)
    lo, hi = blob_corners(lip_mask(img, CLEAN, st), st.roll_deg)
    assert hi - lo + 1.0 == pytest.approx(truth.mouth_width, abs=1.5)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("expr", ["neutral", "smile", "ah", "oo", "frown"])
def test_lip_edges_match_truth(pose, expr):
    st = FaceState(**pose).with_expression(expr)
    img, truth = render_face(st, CLEAN)
    lm = face_landmarks(st)
    _, up = unit(st.roll_deg)
    u = st.ipd
    c = lm["mouth"]
    skin_up = sample(img, c, up, np.array([0.45 * u]))[0]
    skin_dn = sample(img, c, -up, np.array([0.62 * u]))[0]
    lip_u = np.asarray(CLEAN.lip, np.float64) * 0.86
    lip_l = np.asarray(CLEAN.lip, np.float64)
    upper = edge_from(img, c, up, 0.45 * u, -0.2 * u, skin_up, lip_u)
    lower = edge_from(img, c, -up, 0.62 * u, -0.2 * u, skin_dn, lip_l)
    assert upper == pytest.approx(truth.lip_upper, abs=0.25)
    assert lower == pytest.approx(truth.lip_lower, abs=0.25)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("eye", [1.0, 0.5, 1.3, 0.2])
def test_lid_gap_matches_eye_open(pose, eye):
    st = FaceState(**pose).replace(eye_open_l=eye, eye_open_r=1.0)
    truth = face_truth(st)
    assert measure_eye_open(st, "left") == pytest.approx(truth.eye_open_l, abs=0.3)
    assert measure_eye_open(st, "right") == pytest.approx(truth.eye_open_r, abs=0.3)


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("brow", [0.0, 1.0, -1.0, 0.5])
def test_brow_middle_line_matches_truth(pose, brow):
    st = FaceState(**pose).replace(brow_l=brow, brow_r=-0.3 * brow)
    truth = face_truth(st)
    assert measure_brow(st, "left") == pytest.approx(truth.brow_l, abs=0.25)
    assert measure_brow(st, "right") == pytest.approx(truth.brow_r, abs=0.25)


def pupil_centroid(img: np.ndarray, centre, radius: float) -> np.ndarray:
    """Centroid of the darkness (coverage-weighted) of the pupil disc against the iris."""
    x0, y0 = int(centre[0] - 2 * radius), int(centre[1] - 2 * radius)
    x1, y1 = int(centre[0] + 2 * radius) + 2, int(centre[1] + 2 * radius) + 2
    g = img[y0:y1, x0:x1].astype(np.float64).mean(axis=2)
    iris = np.asarray(CLEAN.iris, np.float64).mean()
    pupil = np.asarray(CLEAN.pupil, np.float64).mean()
    a = np.clip((iris - g) / (iris - pupil), 0.0, 1.0)
    ys, xs = np.mgrid[y0:y1, x0:x1]
    return np.array([(a * xs).sum() / a.sum(), (a * ys).sum() / a.sum()])


@pytest.mark.parametrize("pose", POSES)
def test_pupil_centres_and_roll(pose):
    st = FaceState(**pose)
    img, truth = render_face(st, CLEAN)
    lm = face_landmarks(st)
    left = pupil_centroid(img, lm["left_pupil"], 0.042 * st.ipd)
    right = pupil_centroid(img, lm["right_pupil"], 0.042 * st.ipd)
    assert np.allclose(left, lm["left_pupil"], atol=0.15)
    assert np.allclose(right, lm["right_pupil"], atol=0.15)
    mid = (left + right) / 2 + PIXEL_CENTRE  # the params count from the frame's corner
    assert mid == pytest.approx([truth.mid_x, truth.mid_y], abs=0.15)
    roll = math.degrees(math.atan2(-(right[1] - left[1]), right[0] - left[0]))
    assert roll == pytest.approx(truth.roll_deg, abs=0.3)
    assert np.hypot(*(right - left)) == pytest.approx(st.ipd, abs=0.3)


def test_roll_sign_image_right_pupil_higher():
    st = FaceState(roll_deg=20.0)
    lm = face_landmarks(st)
    assert lm["right_pupil"][1] < lm["left_pupil"][1]
    assert lm["right_pupil"][0] > lm["left_pupil"][0]
    assert face_truth(st).roll_deg == 20.0


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    roll=hs.floats(-30, 30), ipd=hs.floats(45, 110), cx=hs.floats(250, 390), cy=hs.floats(170, 230),
    smile=hs.floats(-1, 1), mouth_open=hs.floats(0, 1), pucker=hs.floats(0, 1),
    eye=hs.floats(0.3, 1.3), brow=hs.floats(-1, 1), gx=hs.floats(-0.04, 0.04), gy=hs.floats(-0.015, 0.015),
)
def test_truth_agrees_with_drawing_everywhere(roll, ipd, cx, cy, smile, mouth_open, pucker, eye, brow, gx, gy):
    st = FaceState(cx=cx, cy=cy, roll_deg=roll, ipd=ipd, smile=smile, mouth_open=mouth_open, pucker=pucker,
                   eye_open_l=eye, eye_open_r=1.0, brow_l=brow, brow_r=0.0, gaze_x=gx, gaze_y=gy)
    img, truth = render_face(st, CLEAN)
    el, er = measure_corners(img, st)
    assert abs(el) < 0.6 and abs(er) < 0.6
    assert measure_eye_open(st, "left") == pytest.approx(truth.eye_open_l, abs=0.3)
    assert measure_brow(st, "left") == pytest.approx(truth.brow_l, abs=0.3)


def test_frame_zero_is_neutral_frontal_and_clicks_match():
    for seed in (0, 1, 2):
        perf = Performance(seconds=2, seed=seed)
        st = perf.state(0)
        assert st.roll_deg == 0.0 and st.gaze_x == 0.0 and st.visible
        for k, v in EXPRESSIONS["neutral"].items():
            assert getattr(st, k) == v
        c = perf.clicks()
        t = perf.truth(0)
        assert set(c) == {"frame", "left_pupil", "right_pupil", "left_brow", "right_brow", "mouth"}
        assert c["frame"] == 0
        lp, rp = np.array(c["left_pupil"]), np.array(c["right_pupil"])
        assert (lp + rp) / 2 == pytest.approx([t.mid_x, t.mid_y], abs=0.01)
        assert lp[0] < rp[0]
        assert c["left_pupil"][1] - c["left_brow"][1] == pytest.approx(t.brow_l, abs=0.01)
        assert c["mouth"][1] - c["left_pupil"][1] > 0


def test_performance_is_deterministic_by_seed():
    a, b, c = Performance(seconds=3, seed=5, style=STYLES["noisy"]), Performance(seconds=3, seed=5, style=STYLES["noisy"]), Performance(seconds=3, seed=6)
    for i in (0, 17, 60, 89):
        assert np.array_equal(a.frame(i), b.frame(i))
        assert a.truth(i) == b.truth(i)
    assert any(a.truth(i).values().tolist() != c.truth(i).values().tolist() for i in (30, 60, 89))


def test_performance_covers_the_script():
    perf = Performance(seconds=20, seed=3)
    v = np.array([perf.truth(i).values() for i in range(len(perf))])
    sts = [perf.state(i) for i in range(len(perf))]
    assert len(perf) == 600
    roll = v[:, PARAM_NAMES.index("roll_deg")]
    assert 10 < np.abs(roll).max() <= 25.0
    assert min(s.eye_open_l for s in sts) < 0.05  # blinks
    assert max(s.mouth_open for s in sts) > 0.6  # talking
    assert max(s.smile for s in sts) > 0.5
    assert max(max(s.brow_l, s.brow_r) for s in sts) > 0.5
    ipd = np.array([s.ipd for s in sts])
    assert ipd.max() / ipd.min() > 1.15  # leaning in and out
    assert np.ptp(v[:, 0]) > 30  # drift
    step = np.abs(np.diff(v[:, :3], axis=0)).max(axis=0)
    assert step[0] < 8 and step[2] < 3  # smooth motion


def test_performance_options_switch_parts_off():
    perf = Performance(seconds=6, seed=1, roll_amplitude=0, drift=0, scale_amplitude=0, talk=False, blink=False,
                       brows=False, smiles=False, gaze=False)
    t0 = perf.truth(0).values()
    for i in range(0, len(perf), 7):
        assert np.allclose(perf.truth(i).values(), t0, atol=1e-6)


def test_face_can_leave_the_frame():
    perf = Performance(seconds=2, seed=0, away=[(0.5, 1.0)])
    assert perf.truth(20).status == "lost" and not perf.state(20).visible
    assert perf.truth(10).status == "ok"
    empty = perf.frame(20)
    assert np.array_equal(empty, render_face(FaceState(visible=False))[0])
    far, _ = render_face(FaceState(cx=-2000.0, cy=-900.0))
    assert np.array_equal(far, empty)


def test_face_can_slide_out_of_the_frame_and_back():
    perf = Performance(seconds=4, seed=0, away=[(1.0, 3.0)], away_mode="slide")
    st = [perf.truth(i) for i in range(len(perf))]
    assert st[25].status == "ok" and st[60].status == "lost" and st[110].status == "ok"
    assert abs(st[60].mid_x - 320) > 320 + perf.ipd
    assert np.array_equal(perf.frame(60), render_face(FaceState(visible=False))[0])
    steps = np.abs(np.diff([t.mid_x for t in st]))
    assert steps.max() < 50  # it slides, it does not jump
    with pytest.raises(ValueError, match="away_mode"):
        Performance(seconds=1, away_mode="teleport")


def test_status_follows_what_is_in_the_frame():
    size = (640, 480)
    assert face_truth(FaceState(), frame_size=size).status == "ok"
    low = FaceState(cy=430.0)  # pupils in, mouth below the bottom edge
    assert face_truth(low, frame_size=size).status == "mouth_lost"
    assert face_truth(FaceState(cx=-10.0), frame_size=size).status == "lost"
    assert render_face(low)[1].status == "mouth_lost"


def test_eyes_closed_status_and_closed_lids_show_no_white():
    st = FaceState().with_expression("eyes_closed")
    assert face_truth(st).status == "eyes_closed"
    assert face_truth(st).eye_open_l == 0.0
    img, _ = render_face(st, WHITE_EYES)
    lm = face_landmarks(st)
    x, y = lm["left_pupil"]
    patch = img[int(y) - 5:int(y) + 6, int(x) - 5:int(x) + 6].astype(int)
    assert np.abs(patch - np.asarray(WHITE_EYES.sclera)).sum(axis=2).min() > 60


@pytest.mark.parametrize("name", sorted(STYLES))
def test_every_style_renders(name):
    perf = Performance(seconds=1, seed=2, style=STYLES[name])
    img = perf.frame(15)
    assert img.shape == (480, 640, 3) and img.dtype == np.uint8
    assert img.std() > 10


def test_styles_change_the_picture_not_the_truth():
    st = FaceState().with_expression("smile")
    clean, t0 = render_face(st, CLEAN)
    noisy, t1 = render_face(st, STYLES["noisy"])
    assert t0 == t1
    assert 2 < np.abs(clean.astype(int) - noisy.astype(int)).mean() < 20
    dark, _ = render_face(st, STYLES["dark_skin"])
    lm = face_landmarks(st)
    x, y = (lm["left_pupil"] + lm["mouth"]) / 2
    assert dark[int(y), int(x)].mean() < clean[int(y), int(x)].mean() - 60


def test_other_frame_sizes_scale_the_face():
    perf = Performance(seconds=1, seed=0, frame_size=(1280, 720))
    assert perf.frame(0).shape == (720, 1280, 3)
    assert perf.state(0).ipd == pytest.approx(80.0 * 1.5)
    c = perf.clicks()
    assert 400 < c["left_pupil"][0] < 880


def test_write_clip_truth_and_clicks(tmp_path):
    perf = Performance(seconds=1, seed=4, frame_size=(320, 240))
    video = tmp_path / "clip.mp4"
    clicks = perf.write(video, tmp_path / "truth.csv")
    assert clicks == tmp_path / "clip.clicks.json"
    assert json.loads(clicks.read_text()) == perf.clicks()
    rows = read_csv(tmp_path / "truth.csv")
    assert len(rows) == 30 and rows[5].frame == 5
    assert np.allclose(rows[7].values(), perf.truth(7).values(), atol=1e-3)
    cap = cv2.VideoCapture(str(video))
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    assert n == 30
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_write_errors_name_the_file(tmp_path):
    perf = Performance(seconds=0.2)
    with pytest.raises(SynthError, match="clip.xyz"):
        perf.write(tmp_path / "clip.xyz", None)
    with pytest.raises(SynthError, match="nowhere"):
        perf.write(tmp_path / "nowhere" / "clip.mp4", None)


def test_expressions_are_complete_and_named():
    need = {"neutral", "smile", "frown", "ah", "oo", "ee", "grin", "blink", "eyes_closed", "brows_up",
            "brows_angry", "squint"}
    assert need <= set(EXPRESSIONS)
    base = FaceState(cx=111.0, roll_deg=7.0)
    for name in EXPRESSIONS:
        st = base.with_expression(name)
        assert st.cx == 111.0 and st.roll_deg == 7.0
    t = {n: face_truth(base.with_expression(n)) for n in EXPRESSIONS}
    assert t["ah"].lip_lower > t["neutral"].lip_lower + 15
    assert t["oo"].mouth_width < t["neutral"].mouth_width - 15
    assert t["smile"].mouth_width > t["neutral"].mouth_width
    assert t["brows_up"].brow_l > t["neutral"].brow_l + 8 > t["brows_angry"].brow_l + 8
    with pytest.raises(KeyError, match="nope"):
        base.with_expression("nope")


# ---------------------------------------------------------------------------------------------
# python -m tracker synth


def test_synth_cli_writes_clip_truth_and_clicks(tmp_path, capsys):
    from tracker.__main__ import main

    out = tmp_path / "clip.avi"
    rc = main(["synth", "--out", str(out), "--truth", str(tmp_path / "t.csv"), "--seconds", "0.5", "--seed", "3",
               "--style", "dark_skin", "--size", "320x240", "--quiet"])
    assert rc == 0
    assert "clip.avi" in capsys.readouterr().out
    rows = read_csv(tmp_path / "t.csv")
    perf = Performance(seconds=0.5, seed=3, style=STYLES["dark_skin"], frame_size=(320, 240))
    assert len(rows) == 15
    assert np.allclose([r.values() for r in rows], [perf.truth(i).values() for i in range(15)], atol=1e-3)
    assert json.loads((tmp_path / "clip.clicks.json").read_text()) == perf.clicks()
    cap = cv2.VideoCapture(str(out))
    ok, first = cap.read()
    cap.release()
    assert ok and first.shape == (240, 320, 3)
    assert np.abs(first.astype(int) - perf.frame(0)).mean() < 4


def test_synth_cli_default_truth_path_and_still_head(tmp_path):
    from tracker.__main__ import main

    assert main(["synth", "--out", str(tmp_path / "c.mp4"), "--seconds", "0.4", "--still", "--quiet",
                 "--away", "0.2:0.3"]) == 0
    rows = read_csv(tmp_path / "c.truth.csv")
    assert len(rows) == 12
    assert all(r.roll_deg == 0.0 and r.mid_x == rows[0].mid_x for r in rows)
    assert [r.status for r in rows].count("lost") == 3


@pytest.mark.parametrize("argv,message", [
    (["--out", "{tmp}/missing/c.mp4"], "missing"),
    (["--out", "{tmp}/c.webm"], "c.webm"),
    (["--out", "{tmp}/c.mp4", "--seconds", "99999"], "--seconds"),
])
def test_synth_cli_errors_are_one_line(tmp_path, capsys, argv, message):
    from tracker.__main__ import main

    rc = main(["synth", "--quiet"] + [a.replace("{tmp}", str(tmp_path)) for a in argv])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("inkface: ") and message in err and err.count("\n") == 1


@pytest.mark.parametrize("argv", [["--size", "640"], ["--style", "nope"], ["--seconds", "-1"], ["--away", "3"],
                                  ["--away", "4:2"]])
def test_synth_cli_rejects_bad_options(tmp_path, capsys, argv):
    from tracker.__main__ import main

    with pytest.raises(SystemExit) as e:
        main(["synth", "--out", str(tmp_path / "c.mp4")] + argv)
    assert e.value.code == 2
    assert "Traceback" not in capsys.readouterr().err


@pytest.mark.slow
def test_python_m_tracker_synth_runs(tmp_path):
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "tracker", "synth", "--out", str(tmp_path / "c.mp4"), "--truth",
                        str(tmp_path / "t.csv"), "--seconds", "0.3", "--size", "160x120"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "c.mp4").stat().st_size > 0 and (tmp_path / "c.clicks.json").exists()
    bad = subprocess.run([sys.executable, "-m", "tracker", "track", str(tmp_path / "nope.mp4"), "--init",
                          str(tmp_path / "c.clicks.json"), "--csv", str(tmp_path / "o.csv")],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and bad.stderr.startswith("inkface: ") and "nope.mp4" in bad.stderr


def test_bad_state_and_size_are_refused():
    with pytest.raises(ValueError, match="inter-pupil"):
        render_face(FaceState(ipd=0.0))
    with pytest.raises(ValueError, match="frame size"):
        render_face(FaceState(), frame_size=(0, 480))


@settings(max_examples=40, deadline=None)
@given(cx=hs.floats(-400, 1000), cy=hs.floats(-300, 800), roll=hs.floats(-40, 40), ipd=hs.floats(4, 300),
       w=hs.integers(16, 400), h=hs.integers(16, 300), expr=hs.sampled_from(sorted(EXPRESSIONS)))
def test_any_pose_and_frame_size_renders(cx, cy, roll, ipd, w, h, expr):
    st = FaceState(cx=cx, cy=cy, roll_deg=roll, ipd=ipd).with_expression(expr)
    img, truth = render_face(st, STYLES["webcam"], frame_size=(w, h))
    assert img.shape == (h, w, 3) and img.dtype == np.uint8
    assert truth.mid_x == cx + PIXEL_CENTRE and np.isfinite(truth.values()).all()


def test_textured_blushing_skin_keeps_the_features_exact():
    style = STYLES["realistic"].replace(noise=0.0, blur=0.0, jpeg_quality=0, lighting_drift=0.0, catchlight=False)
    st = FaceState(roll_deg=12.0).with_expression("smile")
    img, truth = render_face(st, style)
    el, er = measure_corners(img, st)
    assert abs(el) < 0.6 and abs(er) < 0.6
    plain, _ = render_face(st, style.replace(texture=0.0, blush=0.0))
    lm = face_landmarks(st)
    cheek = (lm["left_pupil"] * 0.3 + lm["mouth_left"] * 0.7).astype(int)
    x, y = cheek
    assert img[y, x, 2] - img[y, x, 1] > plain[y, x, 2] - plain[y, x, 1]  # redder cheek


def test_track_without_the_tracker_says_not_available(monkeypatch, capsys):
    import sys

    from tracker.__main__ import main

    monkeypatch.setitem(sys.modules, "tracker.track_cli", None)  # import fails as if the module were absent
    assert main(["track", "clip.mp4", "--init", "c.json", "--csv", "o.csv"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("inkface: track: not available") and err.count("\n") == 1


@pytest.mark.parametrize("style", ["default", "strong_roll", "small_far"])
def test_scripted_faces_stay_in_view(style):
    for seed in range(4):
        perf = Performance(seconds=30, seed=seed, style=STYLES[style])
        w, h = perf.frame_size
        for i in range(0, len(perf), 3):
            lm = face_landmarks(perf.state(i))
            pts = np.array([lm[k] for k in ("left_brow", "right_brow", "mouth_left", "mouth_right", "lip_lower")])
            assert (pts > 10).all() and (pts[:, 0] < w - 10).all() and (pts[:, 1] < h - 10).all(), (seed, i)
            assert perf.truth(i).status in ("ok", "eyes_closed")
