"""The harder copies of the real clips: points move with the pixels, parameters follow the points."""

import csv
import json

import cv2
import numpy as np
import pytest

from benchmarks import realfaces as rf
from benchmarks import stress_clips as sc
from tracker.params import PARAM_NAMES


def _write_clip(folder, n=4, w=64, h=48):
    """A tiny clip with a peer: pupils, lids, brows, corners and lip points at fixed places."""
    vw = cv2.VideoWriter(str(folder / "c.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 25.0, (w, h))
    rng = np.random.default_rng(0)
    for _ in range(n):
        vw.write(rng.integers(0, 255, (h, w, 3), dtype=np.uint8))
    vw.release()
    pts = {"left_pupil": (20, 15), "right_pupil": (44, 13), "left_upper_lid": (20, 12), "left_lower_lid": (20, 18),
           "right_upper_lid": (44, 10), "right_lower_lid": (44, 16), "left_brow": (19, 7), "right_brow": (45, 5),
           "left_mouth_corner": (22, 36), "right_mouth_corner": (42, 35), "upper_lip_top": (32, 32), "lower_lip_bottom": (32, 41)}
    with open(folder / "c.points.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["frame"] + [f"{p}_{c}" for p in sc.POINTS for c in "xy"])
        for i in range(n):
            wr.writerow([i] + [v for p in sc.POINTS for v in pts[p]])
    vals = sc.peer_params({p: np.array([pts[p]] * n, float) for p in sc.POINTS})
    with open(folder / "c.mp.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["frame", *PARAM_NAMES, "ipd"])
        for i in range(n):
            wr.writerow([i, *vals[i]])
    (folder / "c.clicks.json").write_text(json.dumps({"frame": 0, "left_pupil": [20, 15], "right_pupil": [44, 13],
                                                     "left_brow": [19, 7], "right_brow": [45, 5], "mouth": [32, 36]}))
    return pts


def _made(tmp_path, kind, n):
    """Variant ``kind`` of an ``n``-frame 160×120 clip from :func:`_write_clip`: (its points, the
    variant's folder, the source's folder)."""
    src, out = tmp_path / "src", tmp_path / kind
    src.mkdir()
    pts = _write_clip(src, n=n, w=160, h=120)
    sc.make_variant(src, "c", kind, out)
    return pts, out, src


def test_peer_params_follow_the_readme_definitions():
    p = {k: np.array([[0.0, 0.0]]) for k in sc.POINTS}
    p["left_pupil"], p["right_pupil"] = np.array([[10.0, 20.0]]), np.array([[50.0, 20.0]])
    p["left_upper_lid"], p["left_lower_lid"] = np.array([[10.0, 17.0]]), np.array([[10.0, 23.0]])
    p["left_brow"] = np.array([[10.0, 8.0]])
    p["left_mouth_corner"], p["right_mouth_corner"] = np.array([[20.0, 60.0]]), np.array([[40.0, 60.0]])
    p["upper_lip_top"], p["lower_lip_bottom"] = np.array([[30.0, 55.0]]), np.array([[30.0, 70.0]])
    v = dict(zip([*PARAM_NAMES, "ipd"], sc.peer_params(p)[0]))
    assert (v["mid_x"], v["mid_y"], v["roll_deg"], v["ipd"]) == (30.0, 20.0, 0.0, 40.0)
    assert v["eye_open_l"] == pytest.approx(6.0) and v["brow_l"] == pytest.approx(12.0)
    assert v["mouth_width"] == 20.0 and v["lip_upper"] == pytest.approx(5.0) and v["lip_lower"] == pytest.approx(10.0)


@pytest.mark.parametrize("kind", ["half", "mirror", "shake", "jolt"])
def test_variant_moves_points_with_pixels(tmp_path, kind):
    src, out = tmp_path / "src", tmp_path / kind
    src.mkdir()
    pts = _write_clip(src)
    sc.make_variant(src, "c", kind, out)
    cap = cv2.VideoCapture(str(out / "c.mp4"))
    ok, img = cap.read()
    cap.release()
    assert ok
    peer = rf.load_peer(out, "c")
    clicks = json.loads((out / "c.clicks.json").read_text())
    lp, rp = peer.points["left_pupil"][0], peer.points["right_pupil"][0]
    if kind == "half":
        assert img.shape[:2] == (24, 32)
        # the files measure from the frame's corner (PIXEL_CENTRE): a point halves with the picture
        assert lp == pytest.approx([20 * 0.5, 15 * 0.5], abs=0.01)
    elif kind == "mirror":
        assert lp == pytest.approx([64 - 44, 13], abs=0.01) and rp == pytest.approx([64 - 20, 15], abs=0.01)
        assert lp[0] < rp[0] and clicks["left_pupil"][0] < clicks["right_pupil"][0]
    assert peer.ipd[0] == pytest.approx(float(np.hypot(*(rp - lp))), abs=0.01)
    assert clicks["left_pupil"] == pytest.approx(list(lp), abs=0.06)


def test_jolt_smears_each_frame_along_its_motion_and_puts_the_points_mid_exposure(tmp_path):
    """``jolt``: the shake's kind of wander, each frame the average of the picture over the last
    EXPOSURE of the motion since the frame before — a white square on grey gets soft edges across
    the way it moved, as many more mid-grey pixels as it moved far — and the peer's points where
    the middle of that exposure put them."""
    src, out = tmp_path / "src", tmp_path / "jolt"
    src.mkdir()
    pts = _write_clip(src, n=24, w=160, h=120)
    img = np.full((120, 160, 3), 40, np.uint8)
    img[50:70, 70:90] = 230
    vw = cv2.VideoWriter(str(src / "c.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 25.0, (160, 120))
    for _ in range(24):
        vw.write(img)
    vw.release()
    sc.make_variant(src, "c", "jolt", out)
    maps, _ = sc._affine_frames(24, "jolt", (160, 120), sum(map(ord, "c")) + sum(map(ord, "jolt")))
    centre = np.array([79.5, 59.5])
    moves = [float(np.hypot(*(sc._move(centre, maps[i]) - sc._move(centre, maps[i - 1])))) for i in range(1, 24)]
    i = 1 + int(np.argmax(moves))
    assert moves[i - 1] > 3.0
    cap = cv2.VideoCapture(str(out / "c.mp4"))
    frames = [cap.read()[1] for _ in range(24)]
    cap.release()
    share = sc.EXPOSURE[0]
    mid = maps[i - 1] + (maps[i] - maps[i - 1]) * (1.0 - 0.5 * share)
    peer = rf.load_peer(out, "c")
    assert peer.points["left_pupil"][i] == pytest.approx(sc._move(np.array(pts["left_pupil"], float), mid), abs=0.01)
    sharp = cv2.warpAffine(img, mid, (160, 120), flags=cv2.INTER_LINEAR, borderValue=(40, 40, 40))

    def soft(a: np.ndarray) -> int:
        g = a.mean(axis=2)
        return int(((g > 80) & (g < 190)).sum())

    assert soft(frames[i]) > soft(sharp) + 2.0 * moves[i - 1]


def test_stress_summary_counts_targets():
    ok = rf.Metrics(frames=10, visible=10, lost_pct=0.0, pupil_med=1.0, pupil_p95=2.0, roll_med=0.1, r_open=0.9,
                    r_width=0.9, r_eye=0.9, r_brow=0.9)
    bad = rf.Metrics(**{**ok.__dict__, "r_open": 0.5, "lost_pct": 5.0})
    res = [rf.ClipResult("a", "clicks", ok, np.zeros(0), 1.0), rf.ClipResult("a", "auto", bad, np.zeros(0), 1.0)]
    row, passes = rf.stress_summary("v", res)
    assert row[:3] == ["v", "1/1", "0/1"] and "a/a: L+O" in row[3]
    assert passes["r_open"] == 1 and passes["r_eye"] == 2


@pytest.mark.parametrize("kind", ["tilt", "lean"])
def test_tilt_turns_and_lean_scales_the_face_from_none_at_the_start(tmp_path, kind):
    """``tilt`` turns the picture up to 25° and ``lean`` scales it up to 1.2× (both slowly, 7 s and 9 s
    waves); on frame 0, where calibration looks, the face is as it was; the peer's roll and eye
    distance follow the picture."""
    pts, out, _ = _made(tmp_path, kind, 60)
    peer = rf.load_peer(out, "c")
    roll, ipd = peer.values[:, PARAM_NAMES.index("roll_deg")], peer.ipd
    assert json.loads((out / "c.clicks.json").read_text())["left_pupil"] == pytest.approx(list(pts["left_pupil"]), abs=0.06)
    assert ipd[0] == pytest.approx(float(np.hypot(24, 2)), abs=0.01)
    peak = 44  # 1.76 s at 25 frames a second: a quarter of the tilt's wave, the lean's largest
    if kind == "tilt":
        assert abs(roll[peak] - roll[0]) == pytest.approx(25.0, abs=0.2)
        assert ipd[peak] == pytest.approx(ipd[0], abs=0.01)
    else:
        assert roll[peak] == pytest.approx(roll[0], abs=0.01)
        assert ipd[peak] / ipd[0] == pytest.approx(1.2, abs=0.002)


@pytest.mark.parametrize("kind", ["leave", "covered"])
def test_away_variants_hide_the_face_and_blank_the_peer_there(tmp_path, kind):
    """While the face is out of the frame or under the hand the peer's points are blank (and the row
    of parameters with them); before and after the event the clip and its peer are the original's."""
    n = 120
    pts, out, src = _made(tmp_path, kind, n)
    peer = rf.load_peer(out, "c")
    start, ramp, hold = int(sc.AWAY[0] * n), sc.AWAY[1], sc.AWAY[2]
    gone = start + ramp + hold // 2  # the middle of the stay away
    assert not peer.visible[gone]
    assert np.isnan(peer.points["left_pupil"][gone]).all() and np.isnan(peer.points["right_pupil"][gone]).all()
    assert peer.visible[0] and peer.visible[n - 1]
    assert peer.points["left_pupil"][0] == pytest.approx(pts["left_pupil"])
    assert peer.points["right_pupil"][n - 1] == pytest.approx(pts["right_pupil"])
    assert json.loads((out / "c.clicks.json").read_text())["left_pupil"] == pytest.approx(list(pts["left_pupil"]))
    frames, src_frames = sc.read_frames(out / "c.mp4")[0], sc.read_frames(src / "c.mp4")[0]
    assert len(frames) == len(src_frames) == n
    x, y = (int(v) for v in pts["left_pupil"])
    assert np.abs(frames[0].astype(int) - src_frames[0].astype(int)).mean() < 8  # untouched (but for the codec)
    assert np.abs(frames[gone][y, x].astype(int) - src_frames[gone][y, x].astype(int)).max() > 0  # something else is there


def test_the_hand_is_skin_coloured_and_covers_the_face(tmp_path):
    n = 120
    pts, out, _ = _made(tmp_path, "covered", n)
    frames = sc.read_frames(out / "c.mp4")[0]
    gone = int(sc.AWAY[0] * n) + sc.AWAY[1] + sc.AWAY[2] // 2
    x, y = (int(v) for v in pts["left_pupil"])
    patch = frames[gone][y - 3 : y + 4, x - 3 : x + 4].reshape(-1, 3).astype(float)
    assert patch.std(axis=0).max() < 25  # smooth skin, not the random clip under it


def test_the_light_steps_by_quarters_and_falls_across_the_side_lit_frame():
    """``step``: every other quarter of the clip at STEP_LIGHT; ``side``: the left edge untouched,
    the right edge at SIDE_LIGHT, darker from left to right; ``shade``: from none of it to all."""
    n = 8
    img = np.full((10, 50, 3), 200, np.uint8)
    step = sc._photometric("step", n, 0)
    levels = [float(step(img, i).mean()) for i in range(n)]
    assert levels[:2] == levels[4:6] == [200.0, 200.0]
    assert levels[2:4] == levels[6:8] == [pytest.approx(200 * sc.STEP_LIGHT, abs=1)] * 2
    lit = sc._photometric("side", n, 0)(img, 0)[5, :, 1].astype(float)
    assert lit[0] == 200 and lit[-1] == pytest.approx(200 * sc.SIDE_LIGHT, abs=1)
    assert np.all(np.diff(lit) <= 0) and lit[25] < 150
    shade = sc._photometric("shade", n, 0)
    assert np.array_equal(shade(img, 0), img)  # even light at the start, the side light at the end
    assert np.array_equal(shade(img, n - 1), sc._photometric("side", n, 0)(img, 0))



def test_low_light_is_noisy_coarse_and_greyer_and_warm_light_is_orange():
    """``lowlight``: the level kept on average, but noisy and with less colour; ``warm``: every
    channel by WARM_BGR."""
    img = np.zeros((40, 60, 3), np.uint8)
    img[:, :30] = (90, 120, 200)  # a skin-like colour
    img[:, 30:] = np.linspace(40, 220, 30, dtype=np.uint8)[None, :, None]  # a grey ramp
    out = sc._photometric("lowlight", 4, 0)(img, 0).astype(np.float32)
    skin = out[5:35, 5:25].reshape(-1, 3)
    assert np.abs(skin.mean(axis=0) - (90, 120, 200)).max() < 0.5 * 110  # the colour partly gone ...
    assert skin[:, 2].mean() - skin[:, 0].mean() > 30  # ... not all of it
    assert skin[:, 2].mean() - skin[:, 0].mean() < 0.8 * (200 - 90)
    assert 1.5 < skin.std(axis=0).max() < 25.0  # noisy, less than a broken camera
    assert abs(float(out[:, 30:].mean()) - float(img[:, 30:].mean())) < 6.0  # the level brought back
    warm = sc._photometric("warm", 4, 0)(img, 0)
    assert warm[0, 0].tolist() == [int(90 * 0.72), int(120 * 0.95), 230]

def test_the_beard_darkens_round_the_mouth_and_leaves_the_lips_and_eyes_bare():
    """``beard``: hair (dark) under the lower lip, beside the corners and over the upper lip; the lips
    between the corners and the outer lip edges, the eyes and the cheeks far out keep their pixels."""
    h, w = 160, 200
    img = np.full((h, w, 3), 180, np.uint8)
    pts = {"left_pupil": (70.0, 50.0), "right_pupil": (130.0, 50.0), "left_mouth_corner": (80.0, 110.0),
           "right_mouth_corner": (120.0, 110.0), "upper_lip_top": (100.0, 104.0), "lower_lip_bottom": (100.0, 118.0)}
    points = {k: np.array([v], float) for k, v in pts.items()}
    out = sc._beard(points, (h, w), 0)(img, 0).astype(float)
    lum = out.mean(axis=2)
    assert lum[127, 100] < 90  # under the lower lip: the beard
    assert lum[111, 75] < 90 and lum[111, 125] < 90  # beside the corners
    assert lum[98, 100] < 120  # the moustache over the upper lip
    assert abs(lum[111, 100] - 180) < 10  # the lips stay bare
    assert np.array_equal(out[50, 70], img[50, 70]) and np.array_equal(out[110, 5], img[110, 5])  # eyes, far cheek
    # the face turned: the beard turns with it (under the lower lip along the face's down)
    a = np.radians(20.0)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    turned = {k: (v - [100.0, 80.0]) @ rot.T + [100.0, 80.0] for k, v in points.items()}
    below = (np.array([100.0, 127.0]) - [100.0, 80.0]) @ rot.T + [100.0, 80.0]
    out2 = sc._beard(turned, (h, w), 0)(img, 0).mean(axis=2)
    assert out2[int(round(below[1])), int(round(below[0]))] < 90


def test_glasses_put_dark_rims_round_the_eyes_and_leave_the_eyes_and_mouth_bare():
    """``glasses``: a dark rim between each eye and its brow and under each eye, a bridge between the
    eyes; the pupils and the mouth keep their pixels; the frames turn with the face."""
    h, w = 160, 200
    img = np.full((h, w, 3), 180, np.uint8)
    pts = {"left_pupil": (70.0, 50.0), "right_pupil": (130.0, 50.0)}
    points = {k: np.array([v], float) for k, v in pts.items()}
    out = sc._glasses(points, (h, w))(img, 0).astype(float)
    lum = out.mean(axis=2)
    a, b, t = sc.LENS
    top, bottom = int(round(50 + 0.03 * 60 - b * 60)), int(round(50 + 0.03 * 60 + b * 60))
    assert lum[top, 70] < 80 and lum[bottom, 70] < 80 and lum[bottom, 130] < 80  # the rims
    assert lum[int(round(50 - 0.45 * b * 60 + 0.03 * 60)), 100] < 120  # the bridge
    assert np.array_equal(out[50, 70], img[50, 70]) or lum[50, 70] > 180  # the pupil: bare or under glare
    assert np.array_equal(out[130, 100], img[130, 100])  # the mouth
    a_ = np.radians(20.0)
    rot = np.array([[np.cos(a_), -np.sin(a_)], [np.sin(a_), np.cos(a_)]])
    turned = {k: (v - [100.0, 80.0]) @ rot.T + [100.0, 80.0] for k, v in points.items()}
    under = (np.array([70.0, bottom]) - [100.0, 80.0]) @ rot.T + [100.0, 80.0]
    out2 = sc._glasses(turned, (h, w))(img, 0).mean(axis=2)
    assert out2[int(round(under[1])), int(round(under[0]))] < 80


def test_deep_darkens_skin_and_lips_and_leaves_whites_and_hair():
    """``deep``: skin-coloured and lip-coloured pixels are taken by DEEP_SKIN (a cheek 150, 170, 210 →
    about 51, 70, 109); a grey white of the eye, a dark brow and a green background keep their colours."""
    img = np.zeros((40, 50, 3), np.uint8)
    img[:, :10] = (150, 170, 210)  # a light cheek
    img[:, 10:20] = (90, 80, 170)  # lips
    img[:, 20:30] = (200, 205, 205)  # the white of an eye
    img[:, 30:40] = (30, 32, 35)  # a brow
    img[:, 40:] = (60, 160, 70)  # a green screen
    out = sc._photometric("deep", 1, 0)(img, 0).astype(float)
    assert np.allclose(out[20, 5], np.array([150, 170, 210]) * sc.DEEP_SKIN, atol=2)
    assert out[20, 15].sum() < 0.6 * img[20, 15].astype(float).sum()
    for x in (25, 35, 45):
        assert np.allclose(out[20, x], img[20, x], atol=2)


def _one_face(upper_lid: float) -> dict[str, np.ndarray]:
    """The peer's points of one frame of a 200 × 200 face: eyes at rows 70 (60 px apart), the upper
    lids at row ``upper_lid``, the mouth from row 124 to 158."""
    pts = {"left_pupil": (70.0, 70.0), "right_pupil": (130.0, 70.0),
           "left_upper_lid": (70.0, upper_lid), "left_lower_lid": (70.0, 76.0),
           "right_upper_lid": (130.0, upper_lid), "right_lower_lid": (130.0, 76.0),
           "left_mouth_corner": (72.0, 140.0), "right_mouth_corner": (128.0, 140.0),
           "upper_lip_top": (100.0, 124.0), "lower_lip_bottom": (100.0, 158.0)}
    return {k: np.array([v], float) for k, v in pts.items()}


def test_deep_darkens_the_whole_face_but_the_whites_of_the_eyes_and_the_teeth():
    """``deep`` with the peer's points: a washed-out, nearly grey forehead inside the face is
    darkened like the skin (it is skin that lost its chroma to the light), while the pinkish
    whites between each eye's lids (as red as skin on a webcam) and bright teeth between the
    lips keep their colours; outside the face only skin colours change."""
    h, w = 200, 200
    img = np.zeros((h, w, 3), np.uint8)
    img[:] = (150, 170, 210)  # skin
    img[30:45, :] = (225, 228, 230)  # a washed-out forehead
    img[:, 185:] = (200, 205, 205)  # a grey wall beside the face
    img[68:73, 55:86] = (185, 190, 225)  # the left eye's pinkish white
    img[138:143, 85:116] = (235, 240, 240)  # teeth
    points = _one_face(upper_lid=64.0)
    out = sc._photometric("deep", 1, 0, points)(img, 0).astype(float)
    assert np.allclose(out[100, 40], np.array([150, 170, 210]) * sc.DEEP_SKIN, atol=3)  # a cheek
    assert out[37, 100].sum() < 0.6 * img[37, 100].astype(float).sum()  # the forehead
    assert np.allclose(out[70, 62], img[70, 62], atol=3)  # the white of the eye
    assert np.allclose(out[140, 100], img[140, 100], atol=3)  # the teeth
    assert np.allclose(out[100, 195], img[100, 195], atol=3)  # the wall


def test_darkeyes_darkens_the_irises_where_they_show_and_keeps_the_whites():
    """``darkeyes``: ``deep``, and each iris between the lids darker still (DARK_IRIS of its light),
    darker than the deep skin round it; the white beside it is kept, and the skin over the iris's
    top (under the upper lid) is darkened as skin, not as iris."""
    h, w = 200, 200
    img = np.zeros((h, w, 3), np.uint8)
    img[:] = (150, 170, 210)  # skin
    img[64:77, 50:91] = (185, 190, 225)  # the left eye's pinkish white
    cv2.circle(img, (70, 70), 6, (90, 110, 130), -1)  # a light brown iris, its top under the lid
    points = _one_face(upper_lid=66.0)
    deep = sc._photometric("deep", 1, 0, points)(img, 0).astype(float)
    dark = sc._photometric("darkeyes", 1, 0, points)(img, 0).astype(float)
    assert np.allclose(dark[71, 70], img[71, 70] * sc.DARK_IRIS, atol=3)  # the iris, between the lids
    assert np.allclose(deep[71, 70], img[71, 70], atol=3)  # deep keeps it
    assert dark[71, 70].sum() < dark[100, 40].sum()  # darker than the deep skin
    assert np.allclose(dark[70, 60], deep[70, 60], atol=1) and dark[70, 60].sum() > 0.9 * img[70, 60].sum()  # the white
    assert np.allclose(dark[100, 40], deep[100, 40], atol=1)  # a cheek, as deep has it
    assert np.allclose(dark[62, 70], deep[62, 70], atol=1)  # the lid over the iris's top: skin


def test_child_squeeze_keeps_the_eyes_and_draws_the_mouth_up():
    """``child``: nothing moves above the lower lids, distances under them shrink, an adult's mouth
    1.15 eye distances below the eyes lands near 0.98, the squeeze fades out far below, and the map
    only increases (each output row has one source)."""
    k, reach, v0 = sc.CHILD
    v = np.linspace(-1.0, 6.0, 2001)
    f = sc.child_squeeze(v)
    assert np.array_equal(f[v <= v0], v[v <= v0])
    assert np.all(np.diff(f) > 0)
    assert 0.95 < float(sc.child_squeeze(1.15)) < 1.0
    assert abs(float(sc.child_squeeze(6.0)) - 6.0) < 0.01


@pytest.mark.parametrize("roll", [0.0, 20.0])
def test_child_moves_the_points_with_the_pixels(roll):
    """Bright dots where the mouth and an upper lid are land where their points are moved to (the
    face level or rolled): the mouth up the face, the lid away from its pupil; the pupil stays."""
    h, w = 200, 200
    a = np.radians(roll)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    centre = np.array([100.0, 70.0])
    place = lambda p: (np.asarray(p, float) - centre) @ rot.T + centre  # noqa: E731
    pupil = place((70.0, 60.0))
    points = {"left_pupil": np.array([pupil + 0.5]), "right_pupil": np.array([place((130.0, 60.0)) + 0.5])}  # as the files count
    image, point = sc._child(points, (h, w))
    ys, xs = np.mgrid[0:h, 0:w]
    for spot, radius in ((place((100.0, 129.0)), 3), (place((70.0, 52.0)), 2)):
        img = np.full((h, w, 3), 60, np.uint8)
        cv2.circle(img, (int(round(spot[0] * 8)), int(round(spot[1] * 8))), radius * 8, (250, 250, 250), -1, cv2.LINE_AA, shift=3)
        g = image(img, 0)[..., 0].astype(float) - 60.0
        moved = point(spot + 0.5, 0) - 0.5  # the files' points count pixel centres at 0.5
        near = np.hypot(xs - moved[0], ys - moved[1]) < 4 * radius
        c = np.array([(g * xs)[near].sum(), (g * ys)[near].sum()]) / g[near].sum()
        assert np.hypot(*(c - moved)) < 0.5
        assert np.hypot(*(moved - spot)) > 1.0  # it did move
    mouth, lid = place((100.0, 129.0)), place((70.0, 52.0))
    assert np.dot(point(mouth + 0.5, 0) - 0.5 - mouth, pupil - mouth) > 0  # towards the eyes
    assert np.hypot(*(point(lid + 0.5, 0) - 0.5 - pupil)) > np.hypot(*(lid - pupil)) + 1.0  # away from the pupil
    assert np.allclose(point(pupil + 0.5, 0) - 0.5, pupil)


def _moving_variant(tmp_path, kind):
    """Variant ``kind`` of a 10-frame 160×120 clip whose peer's face moves (frame i's points i px right
    of frame 0's): the source's frames and frame rate, and the variant's folder."""
    src, out = tmp_path / "src", tmp_path / kind
    src.mkdir()
    _write_clip(src, n=10, w=160, h=120)
    with open(src / "c.points.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for i, r in enumerate(rows):
        for k in r:
            if k.endswith("_x"):
                r[k] = str(float(r[k]) + i)
    with open(src / "c.points.csv", "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)
    frames, fps = sc.read_frames(src / "c.mp4")
    sc.make_variant(src, "c", kind, out)
    return frames, fps, out


def test_late_starts_mid_clip_with_clicks_on_the_peers_points_there(tmp_path):
    """``late``: the clip from :data:`~benchmarks.stress_clips.LATE` of its frames on, the peer's rows
    renumbered from 0, and the clicks put where the shared clips' clicks are put on their frame 0
    (pupils and brows on the peer's, the mouth at the midpoint of its corners) — on the new frame 0,
    whatever the face is doing there."""
    frames, _, out = _moving_variant(tmp_path, "late")
    start = int(sc.LATE * 10)
    got, _ = sc.read_frames(out / "c.mp4")
    assert len(got) == 10 - start
    assert np.abs(got[0].astype(int) - frames[start].astype(int)).mean() < 12  # the codec's loss only
    peer = rf.load_peer(out, "c")
    assert peer.points["left_pupil"][0] == pytest.approx([20 + start, 15], abs=0.01)
    clicks = json.loads((out / "c.clicks.json").read_text())
    assert clicks["frame"] == 0
    assert clicks["left_pupil"] == pytest.approx([20 + start, 15], abs=0.06)
    assert clicks["right_brow"] == pytest.approx([45 + start, 5], abs=0.06)
    assert clicks["mouth"] == pytest.approx([32 + start, 35.5], abs=0.06)
    with open(out / "c.mp.csv", newline="") as f:
        assert [r["frame"] for r in csv.DictReader(f)] == [str(i) for i in range(10 - start)]


def test_choppy_keeps_every_other_frame_at_half_the_rate_with_the_peers_rows_alike(tmp_path):
    """``choppy``: frames 0, 2, 4 … of the clip at half its frame rate, the peer's rows the same ones
    renumbered from 0, and the clicks (made on frame 0) where they were."""
    frames, fps, out = _moving_variant(tmp_path, "choppy")
    got, got_fps = sc.read_frames(out / "c.mp4")
    assert len(got) == 5 and got_fps == pytest.approx(0.5 * fps)
    assert np.abs(got[1].astype(int) - frames[2].astype(int)).mean() < 12  # the codec's loss only
    peer = rf.load_peer(out, "c")
    assert peer.points["left_pupil"][:, 0] == pytest.approx([20, 22, 24, 26, 28], abs=0.01)
    clicks = json.loads((out / "c.clicks.json").read_text())
    assert clicks["frame"] == 0 and clicks["left_pupil"] == pytest.approx([20, 15], abs=0.06)


def test_cheap_halves_the_picture_dims_it_and_adds_noise():
    """``cheap``: the picture at half size (points halved, as ``half``), its light at 60 % and grainy —
    a flat grey frame comes back darker, with a spread of grey levels it did not have."""
    maps, size = sc._affine_frames(3, "cheap", (160, 120), 0)
    assert size == (80, 60) and maps[0] == pytest.approx(np.array([[0.5, 0.0, -0.25], [0.0, 0.5, -0.25]]))
    f = sc._photometric("cheap", 3, 0)
    flat = np.full((60, 80, 3), 200, np.uint8)
    out = f(flat, 0).astype(np.float64)
    assert out.mean() == pytest.approx(200 * sc.CHEAP[1], abs=3)
    assert 0.5 < out.std() < sc.CHEAP[2]  # the grain, partly smoothed away by the JPEG step
