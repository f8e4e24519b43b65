"""The mouth model (calibration) and finder on synthetic frames with exact truth.

Crops are cut the way the tracker cuts them: an upright face frame from the true pupils
(``work_ipd`` between the eyes), :data:`~tracker.mouth_model.MOUTH_RECT` around the mouth centre
predicted from the calibration.
"""

import json
import math

import cv2
import numpy as np
import pytest

from tracker.calibration import FaceFrame
from tracker.colour_model import CHROMA_GAIN_MAX, SKIN_CHROMA, TILE_SHAPE, chroma_gain
from tracker import mouth_finder
from tracker.mouth_finder import OPEN_THICK, SCORE_OK, THICKNESS, WORK_IPD, MouthFinder, polygon_measures
from tracker.mouth_model import MOUTH_RECT, MouthModel, fisher_axis, learn_mouth, lens_outline, lip_columns, lip_end, lip_gap
from tracker.synthetic import STYLES, FaceState, face_landmarks, render_face

GRIN_CORNERS = pytest.mark.xfail(
    strict=True,
    reason="issue 13: in the synthetic grin the traced mouth line runs along the lower teeth and the corners' "
           "heights from the lips next to them still sit ~2 px (face px, IPD 80) above or below the true ones, "
           "which moves the lip_upper / lip_lower split by 2-2.5 px (their sum is within 1 px)",
)
PALE_CORNERS = pytest.mark.xfail(
    strict=True,
    reason="issue 13: with pale lips barely apart from the skin, the corners are found 8-15 px inside the true "
           "ones (the columns near the corners look like the calibrated cheek)",
)
BASE = FaceState(cx=320.0, cy=210.0, ipd=80.0)
WI = 80.0


def _frame_of(state: FaceState) -> FaceFrame:
    lm = face_landmarks(state)
    return FaceFrame.from_pupils(tuple(lm["left_pupil"]), tuple(lm["right_pupil"]), WI)


def _crop(img: np.ndarray, ff: FaceFrame, centre_face) -> tuple[np.ndarray, np.ndarray]:
    """The mouth crop around ``centre_face`` (face px) and its origin (face px)."""
    x0 = int(math.floor(centre_face[0] + MOUTH_RECT[0] * WI))
    y0 = int(math.floor(centre_face[1] + MOUTH_RECT[1] * WI))
    w, h = int(math.ceil(MOUTH_RECT[2] * WI)), int(math.ceil(MOUTH_RECT[3] * WI))
    return ff.crop(img, (x0, y0, w, h)), np.array([x0, y0], dtype=np.float64)


def _truth_in_crop(state: FaceState, ff: FaceFrame, origin: np.ndarray) -> dict[str, np.ndarray]:
    lm = face_landmarks(state)
    return {k: ff.to_face(lm[k][None])[0] - origin for k in ("mouth_left", "mouth_right", "lip_upper", "lip_lower", "mouth")}


def _calibrate(style=None):
    """Learn from the neutral frame with the mouth click on the true centre; return (model, centre in face px)."""
    img, _ = render_face(BASE, style)
    ff = _frame_of(BASE)
    click = ff.to_face(face_landmarks(BASE)["mouth"][None])[0]
    crop, origin = _crop(img, ff, click)
    model = learn_mouth(crop, tuple(click - origin), WI)
    return model, np.array(model.centre) + origin


@pytest.fixture(scope="module")
def calibrated():
    return _calibrate()


def _find(model, centre_face, state, style=None, shift=(0.0, 0.0)):
    img, _ = render_face(state, style)
    ff = _frame_of(state)
    pred_face = centre_face + np.array(shift)
    crop, origin = _crop(img, ff, pred_face)
    res = MouthFinder(model, WI).find(crop, tuple(pred_face - origin))
    return res, _truth_in_crop(state, ff, origin)


def _errors(res, t):
    """|width error|, |lip_upper error|, |lip_lower error| in face px."""
    tw = float(np.hypot(*(t["mouth_right"] - t["mouth_left"])))
    tc = 0.5 * (t["mouth_left"] + t["mouth_right"])
    tu = float(tc[1] - t["lip_upper"][1])
    tl = float(t["lip_lower"][1] - tc[1])
    return abs(res.width - tw), abs(res.lip_upper - tu), abs(res.lip_lower - tl)


def test_calibration_finds_the_neutral_mouth(calibrated):
    model, centre = calibrated
    t = face_landmarks(BASE)
    ff = _frame_of(BASE)
    true_centre = ff.to_face(0.5 * (t["mouth_left"] + t["mouth_right"])[None])[0]
    assert model.cue == "colour" and model.separation >= 2.0
    assert np.hypot(*(centre - true_centre)) < 1.5
    true_width = float(np.hypot(*(t["mouth_right"] - t["mouth_left"]))) * ff.scale
    assert abs(model.width - true_width) < 2.0


@pytest.mark.parametrize("expr", ["neutral", "smile", "ah", "oo", pytest.param("grin", marks=GRIN_CORNERS), "surprise"])
def test_expressions_match_truth(calibrated, expr):
    model, centre = calibrated
    res, t = _find(model, centre, BASE.with_expression(expr))
    assert res is not None and res.score >= SCORE_OK
    ew, eu, el = _errors(res, t)
    assert ew < 2.5 and eu < 1.5 and el < 1.5, (expr, round(ew, 2), round(eu, 2), round(el, 2))


def test_grin_corners_found_along_the_line_bent_to_their_height(calibrated):
    """In a grin the traced line runs along the lower teeth and the corners rise in dark triangles
    above it: the columns along the straight line turn to cheek inside the corners (width 3.1 px
    short at 80 px between the eyes). Looked for again along the line bent to the corners' height,
    they end at the triangles' tips."""
    model, centre = calibrated
    res, t = _find(model, centre, BASE.with_expression("grin"))
    assert res is not None and res.score >= SCORE_OK
    ew, _, _ = _errors(res, t)
    assert ew < 2.0, round(ew, 2)


def test_bent_line_reaches_the_corner_height_only_near_the_corner(calibrated):
    """:meth:`MouthFinder.bent` leaves the traced rows alone up to CORNER_BEND wi before the corner,
    ramps them to the corner's height over that stretch and keeps that height past the corner."""
    model, _ = calibrated
    finder = MouthFinder(model, WI)
    ys = np.full(31, 20.0)
    (left, right) = finder.bent(15, [ys, None], [20.0, None], (14.0, 0.0))
    assert right is None
    start = 20.0 - finder.bend
    k = np.arange(31)
    assert np.all(left[k <= start] == 20.0)
    assert np.all(left[k >= 20] == 14.0)
    assert np.all(np.diff(left) <= 0.0)


def test_open_mouth_counts_teeth_and_inside_as_mouth(calibrated):
    """A wide-open mouth with teeth: the outer lip edges, not the teeth or the dark inside."""
    model, centre = calibrated
    state = BASE.replace(mouth_open=1.0, teeth=True)
    res, t = _find(model, centre, state)
    _, eu, el = _errors(res, t)
    assert eu < 1.5 and el < 1.5


def test_roll_and_lean_are_handled_by_the_crop(calibrated):
    model, centre = calibrated
    for roll, ipd in ((12.0, 80.0), (-20.0, 70.0), (5.0, 95.0)):
        state = BASE.replace(roll_deg=roll, ipd=ipd).with_expression("smile")
        res, t = _find(model, centre, state)
        ew, eu, el = _errors(res, t)
        assert ew < 2.5 and eu < 1.5 and el < 1.5


def test_prediction_error_is_absorbed(calibrated):
    """The head-motion prediction is a few px off: the mouth is still found where it is."""
    model, centre = calibrated
    for shift in ((4.0, -3.0), (-5.0, 6.0), (0.0, 10.0)):
        res, t = _find(model, centre, BASE.with_expression("ah"), shift=shift)
        ew, eu, el = _errors(res, t)
        assert ew < 2.5 and eu < 1.5 and el < 1.5


@pytest.mark.parametrize("style", ["dark_skin", pytest.param("pale_lips", marks=PALE_CORNERS)])
def test_other_performers(style):
    model, centre = _calibrate(STYLES[style])
    for expr in ("neutral", "ah", "smile"):
        res, t = _find(model, centre, BASE.with_expression(expr), STYLES[style])
        assert res is not None and res.score >= SCORE_OK, (style, expr)
        ew, eu, el = _errors(res, t)
        assert ew < 3.0 and eu < 2.0 and el < 2.0, (style, expr, round(ew, 2), round(eu, 2), round(el, 2))


def test_a_noisy_blurred_jpeg_camera():
    """Noise, blur and JPEG: corners within 3 px, and the opening follows the jaw (the lip edges are
    softer here: within 7 px of the truth)."""
    style = STYLES["noisy"]
    model, centre = _calibrate(style)
    opens = []
    for o in (0.0, 0.4, 0.8):
        res, t = _find(model, centre, BASE.replace(mouth_open=o), style)
        assert res is not None and res.score >= SCORE_OK
        ew, eu, el = _errors(res, t)
        assert ew < 3.0 and eu + el < 7.0, (o, round(ew, 2), round(eu, 2), round(el, 2))
        opens.append(res.lip_upper + res.lip_lower)
    assert opens[0] < opens[1] < opens[2]


def test_a_lip_coloured_object_away_from_the_mouth_is_ignored(calibrated):
    model, centre = calibrated
    state = BASE.with_expression("smile")
    img, _ = render_face(state)
    lip = tuple(int(c) for c in STYLES["default"].lip)
    lm = face_landmarks(state)
    mouth = lm["mouth"]
    cv2.circle(img, (int(mouth[0]) + 62, int(mouth[1]) + 40), 14, lip, -1)  # beside the chin, inside the crop
    ff = _frame_of(state)
    crop, origin = _crop(img, ff, centre)
    res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    ew, eu, el = _errors(res, _truth_in_crop(state, ff, origin))
    assert ew < 2.5 and eu < 1.5 and el < 1.5


def test_no_mouth_in_the_crop_is_not_a_confident_mouth(calibrated):
    """Predicted on the forehead (or the face gone): no result, or one that says it is not the mouth."""
    model, centre = calibrated
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    crop, origin = _crop(img, ff, centre + np.array([0.0, -1.6 * WI]))
    res = MouthFinder(model, WI).find(crop, tuple(centre + np.array([0.0, -1.6 * WI]) - origin))
    assert res is None or res.score < SCORE_OK
    blank = np.full_like(crop, (140, 172, 218))
    res = MouthFinder(model, WI).find(blank, tuple(centre - origin))
    assert res is None or res.score < SCORE_OK


def test_dimmer_light_after_calibration(calibrated):
    """The light falls to 60 % and turns warmer: the crop's light is matched to the calibration's."""
    model, centre = calibrated
    state = BASE.with_expression("ah")
    img, _ = render_face(state)
    dim = np.clip(img.astype(np.float32) * np.array([0.5, 0.6, 0.7], np.float32), 0, 255).astype(np.uint8)
    ff = _frame_of(state)
    crop, origin = _crop(dim, ff, centre)
    res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    assert res is not None and res.score >= SCORE_OK
    ew, eu, el = _errors(res, _truth_in_crop(state, ff, origin))
    assert ew < 2.5 and eu < 1.5 and el < 1.5


def test_calibration_never_refuses():
    """Lips the colour of the skin, or no mouth at all: a model all the same, and it says which cue."""
    img, _ = render_face(BASE, STYLES["default"].replace(lip=STYLES["default"].skin))
    ff = _frame_of(BASE)
    click = ff.to_face(face_landmarks(BASE)["mouth"][None])[0]
    crop, origin = _crop(img, ff, click)
    model = learn_mouth(crop, tuple(click - origin), WI)
    assert model.cue in ("colour", "contrast")
    blank = np.full_like(crop, (140, 172, 218))
    model = learn_mouth(blank, tuple(click - origin), WI)
    assert model.cue == "contrast" and model.width > 0


def test_low_contrast_lips_use_the_contrast_cue_and_still_move():
    """Lips barely redder than the skin: the contrast cue, and the opening still follows the jaw."""
    style = STYLES["default"].replace(lip=(128, 156, 214))
    model, centre = _calibrate(style)
    opens = []
    for o in (0.0, 0.5, 1.0):
        res, t = _find(model, centre, BASE.replace(mouth_open=o), style)
        assert res is not None
        opens.append(res.lip_upper + res.lip_lower)
    assert opens[0] < opens[1] < opens[2]


def test_model_round_trips_through_json(calibrated):
    model, centre = calibrated
    d = json.loads(json.dumps(model.to_dict()))
    images = model.images()
    assert set(images) == {"inside"} and all(v.shape == TILE_SHAPE and v.dtype == np.uint8 for v in images.values())
    again = MouthModel.from_dict(d, images)
    assert np.array_equal(again.inside_table, model.inside_table)
    img, _ = render_face(BASE.with_expression("smile"))
    ff = _frame_of(BASE)
    crop, origin = _crop(img, ff, centre)
    a = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    b = MouthFinder(again, WI).find(crop, tuple(centre - origin))
    assert np.allclose(a.polygon, b.polygon, atol=1e-3) and abs(a.score - b.score) < 1e-6


def test_from_dict_names_the_problem():
    with pytest.raises(ValueError, match="mouth model"):
        MouthModel.from_dict({"format": 99})
    model, _ = _calibrate()
    d = model.to_dict()
    del d["axis_up"]
    with pytest.raises(ValueError, match="malformed"):
        MouthModel.from_dict(d)


def test_polygon_measures_of_a_known_lens():
    t = np.linspace(-1, 1, 41)
    top = np.stack([50 + 30 * t, 40 - 10 * (1 - t * t)], axis=1)
    bottom = np.stack([50 - 30 * t, 40 + 14 * (1 - t * t)], axis=1)
    left, right, up, down = polygon_measures(np.concatenate([top, bottom[1:-1]]))
    assert left == pytest.approx((20.0, 40.0)) and right == pytest.approx((80.0, 40.0))
    assert up == pytest.approx(10.0, abs=0.05) and down == pytest.approx(14.0, abs=0.05)


def test_fisher_axis_maps_skin_to_zero_and_lip_to_one_whatever_the_shading():
    rng = np.random.default_rng(1)
    skin = np.array([140.0, 172.0, 218.0])
    lip = np.array([92.0, 78.0, 188.0])
    shade = rng.uniform(0.6, 1.1, (400, 1))
    skin_px = skin * shade + rng.normal(0, 2, (400, 3))
    lip_px = lip + rng.normal(0, 3, (300, 3))
    axis, sep = fisher_axis(lip_px, skin_px)
    v = lambda c: np.asarray(c) @ axis[:3] + axis[3]
    assert v(lip) == pytest.approx(1.0, abs=0.05) and abs(v(skin)) < 0.05
    assert abs(v(0.6 * skin)) < 0.05 and abs(v(1.1 * skin)) < 0.05  # shading leaves skin at 0
    assert sep > 5


# ---------------------------------------------------------------------------------------------
# adaptation: the lips learned again from well-fitted frames


def _crops_of(states, centre_face):
    """(crop, predicted centre in crop px, truth) for each state."""
    out = []
    for state in states:
        img, _ = render_face(state)
        ff = _frame_of(state)
        crop, origin = _crop(img, ff, centre_face)
        out.append((crop, tuple(centre_face - origin), _truth_in_crop(state, ff, origin)))
    return out


TALK = [BASE.replace(cx=320.0 + 0.37 * i, cy=210.0 - 0.23 * i, mouth_open=0.15 * (i % 3)) for i in range(24)]


def test_adaptation_mends_a_lip_thickness_calibration_got_wrong(calibrated):
    """A calibration frame can measure a lip too thick (the edge search ran into the shadow under
    it): the well-fitted frames that follow take the expected thickness most of the way back, and
    the lips are still measured right."""
    model, centre = calibrated
    wrong = MouthModel.from_dict({**model.to_dict(), "thick_down": 1.3 * model.thick_down})
    frames = _crops_of(TALK, centre)
    finder = MouthFinder(wrong, WI)
    used = sum(finder.adapt(finder.find(c, p)) for _ in range(2) for c, p, _ in frames)
    assert used == 2 * len(frames)  # these frames all fit well
    true_t = model.thick_down * finder.k
    assert abs(finder.t_dn - true_t) < 0.5 * 0.3 * true_t, (finder.t_dn, true_t)
    for c, p, t in frames:
        res = finder.find(c, p)
        assert res.score >= SCORE_OK
        ew, eu, el = _errors(res, t)
        assert ew < 2.5 and eu < 1.5 and el < 1.5, (round(ew, 2), round(eu, 2), round(el, 2))


def test_only_an_open_mouths_lower_lip_may_roll_out(calibrated):
    """A jaw dropped wide rolls the lower lip out and its wet inner side shows above its outer edge:
    in an open mouth the lower lip may reach OPEN_THICK of its expected thickness, and growing costs
    less there; in a closed mouth it stays within THICKNESS (a longer one cannot be chosen). A thinner
    lower lip costs the same either way, and the upper lip's range is as before."""
    model, _ = calibrated
    f = MouthFinder(model, WI)
    lengths, closed, k = f._len[1]
    opened = f._pd_open[0]
    beyond = lengths > math.ceil(THICKNESS[1] * f.t_dn)
    assert beyond.any() and lengths.max() >= math.floor(OPEN_THICK * f.t_dn)
    assert np.isinf(closed[beyond]).all() and np.isfinite(opened).all()
    grows = (k > 0) & ~beyond
    assert grows.any() and (opened[grows] < closed[grows]).all()
    assert np.array_equal(opened[k <= 0], closed[k <= 0])
    assert f._len[0][0].max() <= math.ceil(THICKNESS[1] * f.t_up)


def test_adaptation_stays_near_the_calibration(calibrated):
    """Frames of another face (paler lips, another skin) can move the colours used only part of the
    way and only so far, and the thicknesses only within their reach of the calibration's."""
    import tracker.mouth_finder as mf

    model, centre = calibrated
    finder = MouthFinder(model, WI)
    mu0 = finder._mu.copy()
    pale = STYLES["default"].replace(lip=STYLES["pale_lips"].lip, skin=STYLES["dark_skin"].skin)
    img, _ = render_face(BASE, pale)
    crop, origin = _crop(img, _frame_of(BASE), centre)
    for _ in range(200):
        res = finder.find(crop, tuple(centre - origin))
        if res is not None:
            res.score = 1.0  # count every frame, whatever its fit
            res._split = (res._split[0], res._split[1][:5] + ((0.0, 0.0),))
            finder.adapt(res)
    limit = (1.0 - mf.ADAPT_FLOOR) * mf.ADAPT_REACH * np.asarray(model.classes)[:4, 1] + 1e-4
    assert np.all(np.abs(finder._mu[:4] - mu0[:4]) <= limit)
    assert np.array_equal(finder._mu[4], mu0[4])  # the skin round the mouth is the calibration's
    t0 = np.array([model.thick_up, model.thick_down]) * finder.k
    t = np.array([finder.t_up, finder.t_dn])
    assert np.all(t <= t0 * mf.THICK_REACH + 1e-9) and np.all(t >= t0 / mf.THICK_REACH - 1e-9)


def test_frames_that_fit_badly_do_not_adapt(calibrated):
    """No mouth where it was predicted (the forehead), or a poor fit: nothing is learned."""
    model, centre = calibrated
    finder = MouthFinder(model, WI)
    mu0, t0 = finder._mu.copy(), (finder.t_up, finder.t_dn)
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    up = centre + np.array([0.0, -1.6 * WI])
    crop, origin = _crop(img, ff, up)
    res = finder.find(crop, tuple(up - origin))
    assert res is None or not finder.adapt(res)
    c, p, _ = _crops_of([BASE], centre)[0]
    res = finder.find(c, p)
    res._split = (res._split[0], res._split[1][:5] + ((9.0, 9.0),))  # as if the rows fitted badly
    assert not finder.adapt(res)
    assert np.array_equal(finder._mu, mu0) and (finder.t_up, finder.t_dn) == t0


def test_reset_adaptation_is_the_calibration_again(calibrated):
    model, centre = calibrated
    wrong = MouthModel.from_dict({**model.to_dict(), "thick_down": 2.0 * model.thick_down})
    frames = _crops_of(TALK[:12], centre)
    finder, fresh = MouthFinder(wrong, WI), MouthFinder(wrong, WI)
    for c, p, _ in frames:
        finder.adapt(finder.find(c, p))
    assert finder.t_dn != fresh.t_dn and not np.array_equal(finder._mu, fresh._mu)
    finder.reset_adaptation()
    c, p, _ = frames[0]
    a, b = finder.find(c, p), fresh.find(c, p)
    assert (a.lip_upper, a.lip_lower, a.left, a.right) == (b.lip_upper, b.lip_lower, b.left, b.right)


@pytest.mark.parametrize("gap", [1, 6])
def test_a_corner_with_no_cheek_past_it_is_placed_from_the_other_one(calibrated, gap):
    """Dark hair on the cheek ``gap`` px past the right corner, out to the crop's edge and as high
    as the lips (a beard, a collar). With skin between the corner and the hair the cheek is seen
    and the corner found there. Right beside the corner the line runs on into the hair and no
    column past it looks like the cheek: that corner is placed from the left one — at the last
    frame's width when there is a sure last frame, else mirrored about the line's start (the
    prediction) — and the mouth stays sure, where it used to run on to the crop's edge and be
    refused."""
    model, centre = calibrated
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    crop, origin = _crop(img, ff, centre)
    t = _truth_in_crop(BASE, ff, origin)
    clean = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    y = int(round(t["mouth"][1]))
    crop = crop.copy()
    crop[y - 10 : y + 11, int(t["mouth_right"][0]) + gap :] = (38, 48, 62)
    res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    assert res is not None and res.score >= SCORE_OK
    assert _errors(res, t)[0] < (2.5 if gap > 1 else 1.5)
    assert abs(res.right[1] - t["mouth_right"][1]) < 2.0
    if gap == 1:
        off = tuple(centre - origin + np.array([6.0, 0.0]))  # the prediction 6 px to the right
        mirrored = MouthFinder(model, WI).find(crop, off)
        held = MouthFinder(model, WI).find(crop, off, previous=clean)
        assert _errors(mirrored, t)[0] > 10.0  # twice the prediction's error
        assert _errors(held, t)[0] < 0.5 and held.score >= SCORE_OK


@pytest.mark.parametrize("hair", ["beard", "moustache"])
def test_the_mouth_line_starts_between_the_lips_not_in_hair_beside_them(calibrated, hair):
    """Dark, colourless hair right under the lower lip (a beard) or over the upper lip (a moustache),
    darker than the line between the lips and inside the seed's reach: the line still starts between
    the lips (hair has lip colour on one side only), and the mouth is found where it is."""
    model, centre = calibrated
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    crop, origin = _crop(img, ff, centre)
    t = _truth_in_crop(BASE, ff, origin)
    x0, x1 = int(t["mouth_left"][0]) - 12, int(t["mouth_right"][0]) + 12
    crop = crop.copy()
    if hair == "beard":
        y0 = int(math.ceil(t["lip_lower"][1])) + 1
        crop[y0 : y0 + 16, x0:x1] = (28, 32, 38)
    else:
        y1 = int(math.floor(t["lip_upper"][1])) - 1
        crop[y1 - 8 : y1, x0:x1] = (28, 32, 38)
    res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    assert res is not None and res.score >= SCORE_OK
    assert abs(res.line_centre[1] - t["mouth"][1]) < 3.0
    w, _, _ = _errors(res, t)
    assert w < 6.0


def _bearded(img: np.ndarray, state: FaceState, seed: int = 3, reach: float = 0.75) -> np.ndarray:
    """``img`` with a grey-brown textured beard and moustache round the lips (frame px), the lips
    left bare: hair in an oval ``2 · reach`` mouth-widths wide from under the nose to the chin, minus
    the lips' lens, with streaks brighter and darker than the hair's mean (as a real beard's hairs are)."""
    lm = face_landmarks(state)
    (lx, ly), (rx, ry) = lm["mouth_left"], lm["mouth_right"]
    cx, cy = 0.5 * (lx + rx), 0.5 * (ly + ry)
    w = rx - lx
    h, wd = img.shape[:2]
    rng = np.random.default_rng(seed)
    streaks = cv2.resize(rng.normal(0.0, 1.0, (h // 6, wd)).astype(np.float32), (wd, h))
    hair = np.clip(np.array([70.0, 84.0, 96.0])[None, None] + 30.0 * streaks[..., None], 0, 255)
    mask = np.zeros((h, wd), np.uint8)
    cv2.ellipse(mask, (int(cx), int(cy + 0.05 * state.ipd)), (int(reach * w), int(0.42 * state.ipd)), 0, 0, 360, 255, -1)
    lens = lens_outline((lx, ly), (rx, ry), float(lm["lip_upper"][1]), float(lm["lip_lower"][1]), float(cx))
    cv2.fillPoly(mask, [np.round(lens).astype(np.int32)], 0)
    out = img.copy()
    out[mask > 0] = hair[mask > 0].astype(np.uint8)
    return out


@pytest.mark.parametrize("expr", ["neutral", "smile", "ah", "oo", "grin"])
def test_a_beard_round_the_lips_does_not_widen_the_mouth(expr):
    """A performer with a beard and moustache right round the lips: the hair is as unlike the cheek
    past it as the lips are, so the corners were placed at the beard's edge — the calibrated mouth
    29 px too wide (IPD 80), 20-38 px while tracking, and the lips' split up to 20 px off in the
    grin (on bearded copies of the shared clips the calibrated mouths were 1.2-1.6 times too wide).
    Now the corners lie a few px past the lips' colour, at calibration and while tracking."""
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    click = ff.to_face(face_landmarks(BASE)["mouth"][None])[0]
    crop, origin = _crop(_bearded(img, BASE), ff, click)
    model = learn_mouth(crop, tuple(click - origin), WI)
    t = face_landmarks(BASE)
    true_width = float(np.hypot(*(t["mouth_right"] - t["mouth_left"]))) * ff.scale
    assert abs(model.width - true_width) < 5.0
    centre = np.array(model.centre) + origin
    state = BASE.with_expression(expr)
    img, _ = render_face(state)
    ff = _frame_of(state)
    crop, origin = _crop(_bearded(img, state), ff, centre)
    res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    assert res is not None and res.score >= SCORE_OK
    ew, eu, el = _errors(res, _truth_in_crop(state, ff, origin))
    assert ew < 8.0 and eu < 2.5 and el < 2.5



@pytest.mark.parametrize("expr", ["neutral", "ah"])
def test_a_full_beard_leaves_no_cheek_and_the_lips_end_the_corners(expr):
    """Calibrated with skin between the beard and the cheek beside it, tracked where hair reaches past
    where the corners are looked for on both sides (the bearded copy of expr_d18 laughing: the
    lips stretch into the beard, and the skin calibration saw past the corners is out of reach).
    Along the mouth line there was no cheek on either side, the corners ran to the search's ends and
    the mouth was refused ("ah"). The lips' own red ends at the corners, and the mouth is found there.
    (Calibrated with one beard and tracked with a wider one, the other expressions still go wrong,
    with the change or without it: not claimed here.)"""
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    click = ff.to_face(face_landmarks(BASE)["mouth"][None])[0]
    crop, origin = _crop(_bearded(img, BASE), ff, click)
    model = learn_mouth(crop, tuple(click - origin), WI)
    centre = np.array(model.centre) + origin
    state = BASE.with_expression(expr)
    img, _ = render_face(state)
    ff = _frame_of(state)
    crop, origin = _crop(_bearded(img, state, reach=2.4), ff, centre)
    res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    assert res is not None and res.score >= SCORE_OK, expr
    ew, eu, el = _errors(res, _truth_in_crop(state, ff, origin))
    assert ew < 8.0 and eu < 3.0 and el < 3.0, (expr, round(ew, 2), round(eu, 2), round(el, 2))


def _red_strands(img: np.ndarray, state: FaceState, bgr, first: float = 9.0, every: float = 8.0, width: int = 4) -> np.ndarray:
    """``img`` bearded (:func:`_bearded`) with strands of lip red in the hair across the mouth line on
    both sides, from ``first`` px past each corner, every ``every`` px, ``width`` px wide."""
    out = _bearded(img, state)
    lm = face_landmarks(state)
    (lx, ly), (rx, ry) = lm["mouth_left"], lm["mouth_right"]
    y = int(round(0.5 * (ly + ry)))
    for side, x0 in ((-1, lx), (1, rx)):
        for k in range(6):
            x = int(round(x0 + side * (first + k * every)))
            a, b = (x - width + 1, x + 1) if side < 0 else (x, x + width)
            out[y - 6 : y + 7, a:b] = bgr
    return out


@pytest.mark.parametrize("expr", ["neutral", "smile", "ah", "oo", "grin"])
def test_red_strands_in_a_beard_do_not_carry_the_corners_out(expr):
    """Strongly red lips in a beard whose hair has strands as red as the lips past the corners (lit
    hairs, a red beard): each corner was bounded by the last column along the line that showed the
    lips' red, which was the farthest strand — 26-46 px too wide (IPD 80; the bearded copy of talk_b:
    width r 0.52 with the peer). Where the lips are at least twice :data:`LIP_LEAD` redder than the
    skin, the lips end at the first columns in a row without their red (:func:`lip_gap`), as they do
    where no cheek is seen past the hair."""
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    lm = face_landmarks(BASE)
    click = ff.to_face(lm["mouth"][None])[0]
    crop, origin = _crop(_bearded(img, BASE), ff, click)
    model = learn_mouth(crop, tuple(click - origin), WI)
    centre = np.array(model.centre) + origin
    lip = img[int(round(0.5 * (lm["mouth"][1] + lm["lip_lower"][1]))), int(round(lm["mouth"][0]))]
    state = BASE.with_expression(expr)
    img, _ = render_face(state)
    ff = _frame_of(state)
    crop, origin = _crop(_red_strands(img, state, lip), ff, centre)
    t = _truth_in_crop(state, ff, origin)
    finder = MouthFinder(model, WI)
    assert finder._strong_red
    res = finder.find(crop, tuple(centre - origin))
    assert res is not None and res.score >= SCORE_OK
    assert _errors(res, t)[0] < 9.0
    finder._strong_red = False  # the lips' last red column bounds the corner, as before
    assert _errors(finder.find(crop, tuple(centre - origin)), t)[0] > 20.0


def test_lip_gap_ends_the_lips_at_their_first_gap():
    """Pure cases of :func:`lip_gap`: the lips end ``reach`` past the last lip column before the first
    ``run`` columns without them, whatever lies further out (bright skin past a beard passing for
    teeth); a stray non-lip column inside the lips is no gap; no gap before the corner, or too few
    lip columns in the body (a hand over the mouth), gives None."""
    lips = [True] * 12 + [False] * 8 + [True] * 12
    assert lip_gap(lips, 30.0, 1.0, (2, 9), 3) == 12.0
    holed = [True] * 10 + [False] + [True] * 5 + [False] * 16
    assert lip_gap(holed, 30.0, 1.0, (2, 9), 3) == 16.0
    assert lip_gap([True] * 32, 30.0, 1.0, (2, 9), 3) is None
    speck = [False] * 6 + [True] + [False] * 25
    assert lip_gap(speck, 30.0, 1.0, (2, 9), 3) is None

def test_lip_end_bounds_a_corner_by_the_lips_last_column():
    """Pure cases of :func:`lip_end`: the corner comes to ``reach`` past the last lip column; a corner
    already near it, or a line with too few lip columns in the lips' body (a hand over the mouth with
    a speck of red), is left alone."""
    lips = [True] * 12 + [False] * 20
    assert lip_end(lips, 25.0, 2.0, (2, 9)) == 13.0
    assert lip_end(lips, 12.5, 2.0, (2, 9)) == 12.5
    speck = [False] * 6 + [True] + [False] * 25
    assert lip_end(speck, 25.0, 2.0, (2, 9)) == 25.0
    assert lip_end([False] * 32, 25.0, 2.0, (2, 9)) == 25.0


def test_lip_columns_see_red_bands_and_teeth_but_not_a_beards_odd_red_hair():
    """Per column of :func:`~tracker.mouth_model.line_columns` features: lip-red in any band, or
    teeth (light, colourless) in any band, shows the mouth; one red column among hair does not
    when the redness is averaged over a run of columns."""
    skin = np.array([20.0, 8.0, 10.0], np.float32)
    cols = np.tile(np.array([14.0, 2.0, 3.0] * 3, np.float32), (20, 1))  # grey-brown hair
    cols[:5, 1] = 16.0  # lip-red in the band above
    cols[5:8, 6:9] = (26.0, 1.0, 1.0)  # teeth in the band below
    cols[14, 4] = 16.0  # one red hair on the line
    got = lip_columns(cols, 12.0, skin)
    assert got[:8] == [True] * 8 and got[14] and not any(got[8:14])
    smooth = lip_columns(cols, 12.0, skin, run=3)
    assert not smooth[14] and all(smooth[:4])


def _washed(img: np.ndarray, keep: float) -> np.ndarray:
    """``img`` with only ``keep`` of its colour (the rest grey): a camera or a dim light that washes
    the colours out."""
    grey = cv2.cvtColor(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
    return cv2.addWeighted(img, keep, grey, 1.0 - keep, 0.0)


def test_a_camera_that_washes_the_colours_out():
    """The pale-lipped performer through a camera that keeps a third of the colours (skin chroma
    0.044 against 0.13): every chroma rule of the mouth saw lips barely apart from the skin, and the
    closed and smiling mouths were refused. With the chroma scaled back up by the skin's own, they
    are found as in the full-colour picture, the lips' edges within 2.5 px (IPD 80; the corners of
    these pale lips are not asserted, see PALE_CORNERS)."""
    style, keep = STYLES["pale_lips"], 0.35
    img, _ = render_face(BASE, style)
    ff = _frame_of(BASE)
    click = ff.to_face(face_landmarks(BASE)["mouth"][None])[0]
    crop, origin = _crop(_washed(img, keep), ff, click)
    model = learn_mouth(crop, tuple(click - origin), WI)
    assert model.skin_sat < SKIN_CHROMA
    centre = np.array(model.centre) + origin
    for expr in ("neutral", "smile", "ah", "surprise"):
        state = BASE.with_expression(expr)
        frame, _ = render_face(state, style)
        ff = _frame_of(state)
        crop, origin = _crop(_washed(frame, keep), ff, centre)
        res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
        assert res is not None and res.score >= SCORE_OK, expr
        _, eu, el = _errors(res, _truth_in_crop(state, ff, origin))
        assert eu < 2.5 and el < 2.5, (expr, round(eu, 2), round(el, 2))


def test_chroma_gain_lifts_only_washed_out_skin():
    assert chroma_gain(0.25) == chroma_gain(SKIN_CHROMA) == 1.0
    assert chroma_gain(0.5 * SKIN_CHROMA) == pytest.approx(2.0)
    assert chroma_gain(0.0) == chroma_gain(0.001) == CHROMA_GAIN_MAX


@pytest.mark.parametrize("expr", ["neutral", "smile"])
def test_a_seed_in_the_hair_under_the_lip_is_checked_against_the_last_line(calibrated, expr, monkeypatch):
    """Teeth filling the gap leave the shadow or hair under the lower lip the darkest row near the
    prediction, and the line seeded there runs along the hair: a whole mouth found 20-30 px low that
    scores as well as the real one (the bearded copy of expr_d10, frames 16-41: ``ok`` on the chin).
    With a sure mouth the frame before, the line is also traced from that frame's row, and the
    better-scoring mouth kept: the jump away from the last mouth costs the one in the hair."""
    model, centre = calibrated
    state = BASE.with_expression(expr)
    img, _ = render_face(state)
    ff = _frame_of(state)
    crop, origin = _crop(img, ff, centre)
    t = _truth_in_crop(state, ff, origin)
    x0, x1 = int(t["mouth_left"][0]) - 12, int(t["mouth_right"][0]) + 12
    y0 = int(math.ceil(t["lip_lower"][1])) + 1
    crop = crop.copy()
    crop[y0 : y0 + 16, x0:x1] = (28, 32, 38)
    finder = MouthFinder(model, WI)
    before = finder.find(crop, tuple(centre - origin))
    assert before.score >= SCORE_OK and abs(before.line_centre[1] - t["mouth"][1]) < 3.0
    s = WORK_IPD / WI
    monkeypatch.setattr(finder, "line_seeds", lambda *a: [(y0 + 8 + 0.5) * s - 0.5])  # the hair's middle row
    lost = finder.find(crop, tuple(centre - origin))
    assert lost.line_centre[1] - t["mouth"][1] > 12.0  # (the case: seeded in the hair, nothing else tells)
    res = finder.find(crop, tuple(centre - origin), before)
    assert res.score >= SCORE_OK and abs(res.line_centre[1] - t["mouth"][1]) < 3.0
    assert _errors(res, t)[0] < 3.0
    monkeypatch.setattr(mouth_finder, "HOLD_LINE", 0.0)
    assert finder.find(crop, tuple(centre - origin), before).line_centre[1] - t["mouth"][1] > 12.0


def _neutral(calibrated):
    """A fresh finder on the neutral frame's crop round the calibrated centre: the finder, the crop,
    the predicted centre and the truth (crop px)."""
    model, centre = calibrated
    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    crop, origin = _crop(img, ff, centre)
    return MouthFinder(model, WI), crop, tuple(centre - origin), _truth_in_crop(BASE, ff, origin)


def _two_lines(calibrated, monkeypatch, side: float):
    """A sure mouth on the neutral frame, then the next frame's line seeded twice
    :data:`~tracker.mouth_finder.HOLD_LINE` away from its row (``side`` +1 below, −1 above), so the
    line is also traced from the held row: the finder, the crop, the predicted centre (crop px), the
    sure mouth, the held row and the seeded row (working px)."""
    finder, crop, at, _ = _neutral(calibrated)
    before = finder.find(crop, at)
    assert before.score >= SCORE_OK
    s = WORK_IPD / WI
    held_row = (before.line_centre[1] + 0.5) * s - 0.5
    far = held_row + side * 2.0 * mouth_finder.HOLD_LINE * WORK_IPD
    monkeypatch.setattr(finder, "line_seeds", lambda *a: [far])
    return finder, crop, at, before, held_row, far


@pytest.mark.parametrize("held_wider", [True, False])
def test_of_two_sure_mouths_from_this_frames_line_and_the_last_ones_the_wider_is_kept(calibrated, monkeypatch, held_wider):
    """The line seeded far from the last sure frame's line is also traced from that line; when both
    mouths score the same (full marks, as most real mouths do), the wider one is kept: a line traced
    off the mouth's middle (the teeth's lower edge, a dark lower lip) ends where that edge ends, short
    of the corners (a grin in a dark face read as its teeth, 0.6-0.8 of its width)."""
    finder, crop, at, before, held_row, far = _two_lines(calibrated, monkeypatch, +1.0)
    s = WORK_IPD / WI
    real = finder._from_seed
    widths = {}

    def traced(maps, px, py, seed, previous):
        """The mouth traced from the true line, full marks, 4 px narrower for one of the two rows."""
        r = real(maps, px, py, held_row, previous)
        if (seed == far) == held_wider:
            r = mouth_finder._moved(r, left=(r.left[0] + 2.0, r.left[1]), right=(r.right[0] - 2.0, r.right[1]))
        widths["held" if seed == held_row else "seeded"] = r.right[0] - r.left[0]
        return mouth_finder._moved(r, score=1.0, line_ends=((0.0, seed), (1.0, seed)))

    monkeypatch.setattr(finder, "_from_seed", traced)
    res = finder.find(crop, at, before)
    assert set(widths) == {"held", "seeded"} and widths["held"] != widths["seeded"]
    kept = "held" if held_wider else "seeded"
    assert (res.right[0] - res.left[0]) * s == pytest.approx(widths[kept], abs=0.01)
    assert res.line_centre[1] == pytest.approx(((held_row if held_wider else far) + 0.5) / s - 0.5, abs=0.01)


@pytest.mark.parametrize("rise", [0.4, 0.1])
def test_a_wider_mouth_whose_upper_lip_jumped_up_loses_to_the_held_line(calibrated, monkeypatch, rise):
    """Of two sure mouths the wider is kept — unless its upper lip's outer edge rose further from the
    last sure frame's than an upper lip moves in a frame (:data:`~tracker.mouth_finder.UPPER_RISE`)
    while the other's did not: a line traced along a moustache's lower edge runs on past the corners
    too, and the mouth it makes has the nostrils' shadow for its upper lip (a painted beard round
    expr_d6: the mouth on the nostrils, ``ok``, for twenty frames). A small rise keeps the rule as it was."""
    finder, crop, at, before, held_row, far = _two_lines(calibrated, monkeypatch, -1.0)  # seeded above: the moustache's edge
    s = WORK_IPD / WI
    real = finder._from_seed

    def traced(maps, px, py, seed, previous):
        """Full marks both; the seeded one 4 px wider, its upper lip ``rise`` wi higher."""
        r = real(maps, px, py, held_row, previous)
        if seed == far:
            r = mouth_finder._moved(r, left=(r.left[0] - 2.0, r.left[1]), right=(r.right[0] + 2.0, r.right[1]),
                                    lip_upper=r.lip_upper + rise * WORK_IPD)
        return mouth_finder._moved(r, score=1.0, line_ends=((0.0, seed), (1.0, seed)))

    monkeypatch.setattr(finder, "_from_seed", traced)
    row = lambda r: (r + 0.5) / s - 0.5
    res = finder.find(crop, at, before)
    assert res.line_centre[1] == pytest.approx(row(held_row if rise > 0.3 else far), abs=0.01)
    monkeypatch.setattr(mouth_finder, "UPPER_RISE", 1.0)  # the control: no bound on the rise, the wider wins
    assert finder.find(crop, at, before).line_centre[1] == pytest.approx(row(far), abs=0.01)


def test_a_held_search_traces_the_last_line_alone(calibrated, monkeypatch):
    """``held``: the line is traced from the last sure frame's row, whatever valley lies near the
    prediction (the caller found the valley's mouth out of place: a moustache's lower edge a little
    above the lips, nearer the last line than :data:`~tracker.mouth_finder.HOLD_LINE`, so not checked
    against it). Nothing to hold without a sure last frame."""
    finder, crop, at, t = _neutral(calibrated)
    before = finder.find(crop, at)
    assert before.score >= SCORE_OK and abs(before.line_centre[1] - t["mouth"][1]) < 3.0
    s = WORK_IPD / WI
    held_row = (before.line_centre[1] + 0.5) * s - 0.5
    seen = []
    real = finder._from_seed

    def traced(maps, px, py, seed, previous):
        seen.append(seed)
        return real(maps, px, py, seed, previous)

    monkeypatch.setattr(finder, "_from_seed", traced)
    monkeypatch.setattr(finder, "line_seeds", lambda *a: [held_row - 0.5 * mouth_finder.HOLD_LINE * WORK_IPD])
    finder.find(crop, at, before)
    assert seen == [held_row - 0.5 * mouth_finder.HOLD_LINE * WORK_IPD]  # the valley alone
    seen.clear()
    res = finder.find(crop, at, before, held=True)
    assert seen == [pytest.approx(held_row)]
    assert res.score >= SCORE_OK and abs(res.line_centre[1] - t["mouth"][1]) < 3.0
    assert finder.find(crop, at, None, held=True) is None
    assert finder.find(crop, at, mouth_finder._moved(before, score=0.2), held=True) is None


def _lens_result(gap_top: float, gap_bottom: float, t_up: float, t_dn: float, column: float = 40.0) -> mouth_finder.MouthResult:
    """A mouth result with its corners at (20, 30) and (60, 30), split on ``column``: the gap's rows and
    each lip's thickness as given."""
    from tracker.mouth_model import N_RAYS, lens_outlines

    left, right = (20.0, 30.0), (60.0, 30.0)
    top, bottom = gap_top - t_up, gap_bottom + t_dn
    poly, raw = lens_outlines(left, right, (top, gap_top), (bottom, gap_bottom), column, N_RAYS)
    return mouth_finder.MouthResult(left=left, right=right, centre=(40.0, 30.0), lip_upper=30.0 - top, lip_lower=bottom - 30.0,
                                    polygon=poly, raw_polygon=raw, cue="colour", score=1.0, gap_top=gap_top,
                                    gap_bottom=gap_bottom, column=column)


def test_steady_lips_keep_the_gap_and_steady_the_thickness():
    """The reported lips keep this frame's gap exactly and move each lip's thickness part of the way
    (LIP_STEADY per frame's worth of time) from the last report; the outline passes through the new
    outer edges on the split's column. The first frame (or the first after a lost one) is reported as
    found."""
    from tracker.mouth_finder import LIP_STEADY, steady_lips

    first = _lens_result(28.0, 32.0, 6.0, 8.0)
    same, held = steady_lips(first, None)
    assert same is first and held == pytest.approx((6.0, 8.0))
    closed = _lens_result(30.0, 30.0, 10.0, 4.0, column=44.0)  # lips shut, the upper lip read thicker, the lower thinner
    out, held = steady_lips(closed, held)
    want = (6.0 + LIP_STEADY * 4.0, 8.0 - LIP_STEADY * 4.0)
    assert held == pytest.approx(want)
    assert (out.gap_top, out.gap_bottom, out.left, out.right, out.centre) == (30.0, 30.0, closed.left, closed.right, closed.centre)
    assert out.lip_upper == pytest.approx(want[0]) and out.lip_lower == pytest.approx(want[1])
    top_x = out.polygon[np.argmin(out.polygon[:, 1])]
    assert top_x[1] == pytest.approx(30.0 - want[0], abs=0.05) and abs(top_x[0] - 44.0) <= 1.0
    assert out.polygon[:, 1].max() == pytest.approx(30.0 + want[1], abs=0.05)
    # two frames' worth of time: the new reading weighs as two frames would have
    _, held2 = steady_lips(closed, (6.0, 8.0), steps=2.0)
    w2 = 1.0 - (1.0 - LIP_STEADY) ** 2
    assert held2 == pytest.approx((6.0 + w2 * 4.0, 8.0 - w2 * 4.0))


def test_steady_lips_quiet_the_edges_not_the_gap():
    """Lips whose outer edges jitter by a pixel while the gap opens and shuts: the reported opening
    follows the gap frame by frame (no lag) and jitters less than the readings."""
    from tracker.mouth_finder import steady_lips

    rng = np.random.default_rng(3)
    gaps = np.concatenate([np.zeros(10), np.linspace(0, 12, 4), np.full(10, 12.0), np.linspace(12, 0, 4), np.zeros(10)])
    held, found, told = None, [], []
    for g in gaps:
        t_up, t_dn = 6.0 + rng.normal(0, 1.0), 8.0 + rng.normal(0, 1.0)
        res = _lens_result(30.0 - 0.5 * g, 30.0 + 0.5 * g, t_up, t_dn)
        out, held = steady_lips(res, held)
        found.append(res.lip_upper + res.lip_lower)
        told.append(out.lip_upper + out.lip_lower)
        assert out.gap_bottom - out.gap_top == pytest.approx(g)
    found, told = np.array(found), np.array(told)
    assert np.std(np.diff(told - gaps)) < 0.7 * np.std(np.diff(found - gaps))
    assert np.corrcoef(told, gaps)[0, 1] > np.corrcoef(found, gaps)[0, 1]


def _seeded(calibrated, monkeypatch, rows_from_mouth: list[float]):
    """The neutral frame's finder with its valleys replaced by rows ``rows_from_mouth`` (× wi from the
    true mouth line, in that order), each traced one recorded: the finder, the crop, the predicted
    centre (crop px), the truth (crop px), the rows (working px) and the list the traced rows go to."""
    finder, crop, at, t = _neutral(calibrated)
    s = WORK_IPD / WI
    line = (t["mouth"][1] + 0.5) * s - 0.5
    rows = [line + k * WORK_IPD for k in rows_from_mouth]
    monkeypatch.setattr(finder, "line_seeds", lambda *a: list(rows))
    traced, real = [], finder._from_seed

    def spy(maps, px, py, seed, previous):
        traced.append(seed)
        return real(maps, px, py, seed, previous)

    monkeypatch.setattr(finder, "_from_seed", spy)
    return finder, crop, at, t, rows, traced


def test_a_valley_that_gives_no_mouth_hands_on_to_the_next(calibrated, monkeypatch):
    """When the likeliest valley's line makes no mouth (the shadow under the nose of a broad grin, darker
    than the gap over its teeth), the next valleys are traced (:data:`~tracker.mouth_finder.SEED_TRIES`)
    and the best mouth kept; a sure mouth from the first valley is kept without tracing more."""
    finder, crop, at, t, rows, traced = _seeded(calibrated, monkeypatch, [-0.4, 0.0, 0.1])
    monkeypatch.setattr(mouth_finder, "SEED_TRIES", 0)
    alone = finder.find(crop, at)
    assert traced == [rows[0]] and alone.score < SCORE_OK
    traced.clear()
    monkeypatch.setattr(mouth_finder, "SEED_TRIES", 2)
    res = finder.find(crop, at)
    assert traced == [rows[0], rows[1]]  # the second is sure: the third is not traced
    assert res.score >= SCORE_OK and abs(res.line_centre[1] - t["mouth"][1]) < 3.0
    assert _errors(res, t)[0] < 3.0
    traced.clear()
    rows[:] = [rows[1], rows[0]]
    assert finder.find(crop, at).score >= SCORE_OK and traced == [rows[0]]


def test_below_traces_only_the_valleys_under_a_refused_line(calibrated, monkeypatch):
    """``below`` (the row a refused line started from, crop px): only valleys at least
    :data:`~tracker.mouth_finder.BELOW_GAP` wi under it are traced, in their order — the one the line
    started from and any just under it are not; None when no valley is left."""
    finder, crop, at, t, rows, traced = _seeded(calibrated, monkeypatch, [-0.3, -0.25, 0.0])
    s = WORK_IPD / WI
    refused = (rows[0] + 0.5) / s - 0.5
    res = finder.find(crop, at, below=refused)
    assert traced == [rows[2]]
    assert res.score >= SCORE_OK and abs(res.line_centre[1] - t["mouth"][1]) < 3.0
    assert res.seed == pytest.approx(t["mouth"][1], abs=0.01)  # (the row it started from, in crop px)
    traced.clear()
    assert finder.find(crop, at, below=(rows[2] + 0.5) / s - 0.5) is None and traced == []


def test_an_unsure_mouth_near_the_last_line_is_traced_again_from_it(calibrated, monkeypatch):
    """After a sure frame, a valley whose mouth is unsure is checked against the last sure frame's line
    even when it lies nearer than :data:`~tracker.mouth_finder.HOLD_LINE` (a grin's nose shadow, 0.15-0.2
    wi over its teeth): the line traced from the last row is kept when it scores better. The other
    valleys are not tried after a sure frame (in a beard they make sure mouths along the hair)."""
    finder, crop, at, t, rows, traced = _seeded(calibrated, monkeypatch, [0.0])
    before = finder.find(crop, at)
    assert before.score >= SCORE_OK
    s = WORK_IPD / WI
    held_row = (before.line_centre[1] + 0.5) * s - 0.5
    near = held_row - 0.5 * mouth_finder.HOLD_LINE * WORK_IPD
    rows[:] = [near, near + 0.3 * WORK_IPD]
    spy = finder._from_seed

    def unsure_near(maps, px, py, seed, previous):
        r = spy(maps, px, py, seed, previous)
        return mouth_finder._moved(r, score=0.2) if seed == near else r

    monkeypatch.setattr(finder, "_from_seed", unsure_near)
    traced.clear()
    res = finder.find(crop, at, before)
    assert traced == [near, pytest.approx(held_row)]
    assert res.score >= SCORE_OK and abs(res.line_centre[1] - t["mouth"][1]) < 3.0
    traced.clear()
    assert finder.find(crop, at).score >= SCORE_OK and traced == [near, rows[1]]  # no sure frame: the next valley
