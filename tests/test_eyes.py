"""The eye finder (tracker.eyes) on synthetic faces with exact truth."""

import dataclasses
import json
import math
from types import SimpleNamespace

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tracker.calibration import FaceFrame
from tracker.eyes import (
    EyeFinder,
    EyeModel,
    IRIS_FLOOR,
    LID_SHOW,
    LIMBUS_DARK,
    RIM_HALO,
    _colour_samples,
    ARC_DEGREES,
    LIMBUS_INNER,
    EyeModelError,
    GAP_BLIND,
    SkinModel,
    _run,
    calibration_crop,
    dark_power,
    eye_light,
    iris_darkness,
    mirrored_sides,
    iris_radius,
    learn_eyes,
    limbus_below,
    limbus_centre,
    limbus_sides,
    spectacle_rims,
    thin_dark,
    refine_pupils,
    side_glance,
    walk_length,
)
from tracker.synthetic import STYLES, FaceState, face_landmarks, render_face

BASE = FaceState(cx=320.0, cy=210.0, ipd=80.0)


def _learn(state=BASE, style=None, frame=None):
    if frame is None:
        frame, _ = render_face(state, style)
    lm = face_landmarks(state)
    wi = min(state.ipd, 80.0)
    ff = FaceFrame.from_pupils(tuple(lm["left_pupil"]), tuple(lm["right_pupil"]), wi)
    rect = calibration_crop(wi)
    crop = ff.crop(frame, rect)
    o = np.array(rect[:2], dtype=np.float64)
    pupils = np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]]) - o
    brows = ff.to_face(np.array([lm["left_brow"], lm["right_brow"]])) - o
    model = learn_eyes(crop, cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY), pupils, brows, wi)
    return model, wi


def _find(finder, state, style=None, offset=(0.0, 0.0), roll_error=0.0, frame=None):
    """Run the finder on a render of ``state`` with the crop frame put on the true eye centres
    moved by ``offset`` (× work ipd) and turned by ``roll_error`` degrees; truth in crop px."""
    if frame is None:
        frame, _ = render_face(state, style)
    lm = face_landmarks(state)
    wi = finder.wi
    # the eye centres (without gaze): where the head puts the eyes
    g = np.array([state.gaze_x, state.gaze_y]) * state.ipd
    th = math.radians(state.roll_deg)
    R = np.array([[math.cos(th), math.sin(th)], [-math.sin(th), math.cos(th)]])
    lc, rc = lm["left_pupil"] - R @ g, lm["right_pupil"] - R @ g
    ff = FaceFrame.from_pupils(tuple(lc), tuple(rc), wi)
    mid = ff.to_image(np.array([[offset[0] * wi, offset[1] * wi]]))[0]
    ff = FaceFrame((float(mid[0]), float(mid[1])), ff.angle + math.radians(roll_error), ff.scale)
    x0, y0, w, h = finder.rect
    crop = ff.crop(frame, finder.rect)
    grey = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY)
    centres = np.array([[-0.5 * wi - x0, -y0], [0.5 * wi - x0, -y0]])
    finder.forget()  # each render on its own: no brow height carried over from another test
    res = finder.find(crop, grey, centres)
    o = np.array([x0, y0], dtype=np.float64)
    keys = ("pupil", "lid_upper", "lid_lower", "brow")
    truth = {s: {k: ff.to_face(lm[f"{s}_{k}"][None])[0] - o for k in keys} for s in ("left", "right")}
    return res, truth, ff, (crop, grey, centres)


@pytest.fixture(scope="module")
def finder():
    model, wi = _learn()
    return EyeFinder(model, wi)


def _check(res, truth, pupil=0.6, lid=1.5, brow=1.5):
    for e, side in zip(res.eyes, ("left", "right")):
        t = truth[side]
        assert math.hypot(e.x - t["pupil"][0], e.y - t["pupil"][1]) <= pupil, (side, (e.x, e.y), t["pupil"])
        assert abs(e.upper - (t["pupil"][1] - t["lid_upper"][1])) <= lid, (side, e.upper, t)
        assert abs(e.lower - (t["lid_lower"][1] - t["pupil"][1])) <= lid, (side, e.lower, t)
        assert abs(e.brow - (t["pupil"][1] - t["brow"][1])) <= brow, (side, e.brow, t)


def test_a_shadow_under_the_eyes_cannot_take_the_lower_lid_past_what_an_eye_can_show(finder):
    """Dark make-up or an eye bag's shadow joined to the lower lid: the colour run goes on through
    it (three times the lid's distance), and the lid reported stops at the iris radius plus the
    most white an eye shows below it."""
    frame, _ = render_face(BASE)
    lm = face_landmarks(BASE)
    d = BASE.ipd
    for side in ("left", "right"):
        x, y = lm[f"{side}_lid_lower"]
        bag = [[x - 0.22 * d, y - 1], [x + 0.22 * d, y - 1], [x + 0.15 * d, y + 0.2 * d], [x - 0.15 * d, y + 0.2 * d]]
        cv2.fillConvexPoly(frame, np.array(bag, np.int32), (70, 60, 90))
    frame = cv2.GaussianBlur(frame, (0, 0), 1.0)
    res, truth, _, (crop, _, _) = _find(finder, BASE, frame=frame)
    for i, (e, side) in enumerate(zip(res.eyes, ("left", "right"))):
        t = truth[side]
        most = finder.radius[i] + LID_SHOW[1] * finder.wi
        assert finder.lids(crop, i, (e.x, e.y), dark=False)[1] > 1.5 * most  # the run went on into the shadow
        assert e.lower == pytest.approx(most)
        assert abs(e.upper - (t["pupil"][1] - t["lid_upper"][1])) <= 1.5  # the upper lid is as it was


@pytest.mark.parametrize("expr", ["neutral", "brows_up", "brows_angry", "wide", "smile", "sad"])
def test_expressions_are_measured(finder, expr):
    res, truth, _, _ = _find(finder, BASE.with_expression(expr))
    _check(res, truth)
    assert all(e.open for e in res.eyes)


def test_a_squint_moves_the_eye_point_towards_the_middle_of_the_slit(finder):
    """Half-closed (lid gap 45 % of calibration): the point is on its way from the iris to the
    middle of what shows between the lids; the lids themselves stay right."""
    res, truth, _, _ = _find(finder, BASE.with_expression("squint"))
    for e, side in zip(res.eyes, ("left", "right")):
        t = truth[side]
        assert t["lid_upper"][1] < e.y < t["lid_lower"][1]
        assert abs(e.x - t["pupil"][0]) < 0.5 and abs(e.y - t["pupil"][1]) < 2.0
        assert abs((e.y - e.upper) - t["lid_upper"][1]) < 1.5 and abs((e.y + e.lower) - t["lid_lower"][1]) < 1.5
    # a squint is an open eye: a landmark tracker calls an eye shut below about 40 % of its opening
    assert all(e.open for e in res.eyes)


@pytest.mark.parametrize("offset", [(0.12, 0.0), (-0.12, 0.04), (0.05, -0.08), (-0.18, -0.03)])
def test_a_badly_predicted_crop_still_finds_the_eyes(finder, offset):
    res, truth, _, _ = _find(finder, BASE, offset=offset, roll_error=2.0)
    _check(res, truth, pupil=0.8)


def test_gaze_moves_the_iris_inside_the_eye(finder):
    st_ = BASE.replace(gaze_x=0.08, gaze_y=0.02)
    res, truth, _, _ = _find(finder, st_)
    _check(res, truth, lid=2.5)


def test_an_iris_that_plainly_shows_keeps_the_eye_point_whatever_the_gap_reads(finder, monkeypatch):
    """A lid gap read short by one frame's noise (a glance aside under make-up) moved the eye point
    toward the slit's middle although the iris picture matched at 0.96: a clear iris keeps it."""
    import tracker.eyes as E

    state = dataclasses.replace(BASE, gaze_x=0.03)
    res, truth, *_ = _find(finder, state)
    assert all(e.iris_match >= E.CLEAR_IRIS[1] for e in res.eyes)
    short = E.EyeFinder._both_lids
    monkeypatch.setattr(E.EyeFinder, "_both_lids", lambda self, *a, **k: [(u, d, 0.45 * g) for u, d, g in short(self, *a, **k)])
    res2, *_ = _find(finder, state)
    for e, e0 in zip(res2.eyes, res.eyes):
        assert math.hypot(e.x - e0.x, e.y - e0.y) < 1e-6
    monkeypatch.setattr(E, "CLEAR_IRIS", (1.5, 2.0))  # no picture could clear it: the gap moves the point
    res3, *_ = _find(finder, state)
    assert max(math.hypot(e.x - e0.x, e.y - e0.y) for e, e0 in zip(res3.eyes, res.eyes)) > 0.5


def test_closed_eyes_put_the_eye_point_on_the_slit(finder):
    res, truth, _, _ = _find(finder, BASE.with_expression("eyes_closed"))
    for e, side in zip(res.eyes, ("left", "right")):
        assert not e.open
        t = truth[side]
        # the lids meet on the pupil's line in the synthetic performer
        assert abs(e.y - t["pupil"][1]) < 2.0 and abs(e.x - t["pupil"][0]) < 0.1 * finder.wi
        assert e.upper + e.lower < 3.0


def test_a_wink_closes_one_eye(finder):
    res, _, _, _ = _find(finder, BASE.with_expression("wink_l"))
    assert [e.open for e in res.eyes] == [False, True]


def test_the_score_prefers_the_eyes_to_other_places(finder):
    res, _, _, _ = _find(finder, BASE)
    on = res.score
    assert on > 0.8
    for off in ((0.0, 0.65), (0.0, -0.5), (1.0, 0.0), (0.0, 1.0)):
        r, _, _, _ = _find(finder, BASE, offset=off)
        assert r.score < on - 0.2, off


@pytest.mark.parametrize("style", ["dark_skin", "noisy", "blue_eyes", "pale_lips"])
def test_other_performers(style):
    model, wi = _learn(style=STYLES[style])
    f = EyeFinder(model, wi)
    for expr in ("neutral", "brows_up", "smile"):
        res, truth, _, _ = _find(f, BASE.with_expression(expr), STYLES[style])
        _check(res, truth, pupil=1.0, lid=2.0)


LIGHT_EYES_DARK_SKIN = STYLES["dark_skin"].replace(name="light_eyes_dark_skin", iris=(150, 165, 140))


def test_iris_darkness_counts_a_dark_iris_and_not_a_light_one_in_a_dark_face():
    """The disc-darkness cue is for irises darker than the eye round them: fully on the default
    performer and a dark-skinned one with dark eyes, off for grey-green eyes in a dark face."""
    for style, want in ((None, 1.0), (STYLES["dark_skin"], 1.0), (LIGHT_EYES_DARK_SKIN, 0.0)):
        model, _ = _learn(style=style)
        assert iris_darkness(model.eye_pictures, model.radius) == pytest.approx(want, abs=0.05), style


def test_the_darkness_term_is_off_for_an_iris_hardly_darker_than_the_skin_round_it():
    """The search measures a disc's darkness against its window, which is mostly skin. A brown iris
    in a brown face is darker than its own eye picture (the white raises that picture's median), so
    :func:`iris_darkness` keeps the term, yet hardly darker than the window: the search's own
    measure (:meth:`EyeFinder.search_darkness`, stored with the model) turns it off there, and
    leaves it on for dark irises in light and dark faces. The irises are still found."""
    near = STYLES["dark_skin"].replace(name="brown_near_skin", iris=STYLES["dark_skin"].skin, pupil=(36, 48, 76),
                                       catchlight=False)
    seen = {}
    for name, style in (("default", None), ("dark_skin", STYLES["dark_skin"]), ("near", near)):
        model, wi = _learn(style=style)
        seen[name] = (model.search_dark, iris_darkness(model.eye_pictures, model.radius), dark_power(model))
        f = EyeFinder(model, wi)
        assert f.dark_power == pytest.approx(seen[name][2])
        for gaze in (-0.06, 0.0, 0.06):
            res, truth, _, _ = _find(f, BASE.with_expression("smile").replace(gaze_x=gaze), style, offset=(0.04, -0.03))
            for e, side in zip(res.eyes, ("left", "right")):
                assert math.dist(e.iris, truth[side]["pupil"]) < 1.0, (name, gaze, side)
    assert seen["default"][0] > seen["dark_skin"][0] > seen["near"][0]
    assert seen["default"][2] == seen["dark_skin"][2] == 1.0
    assert seen["near"][1] > 0.3 and seen["near"][2] == 0.0  # the eye picture's rule alone kept it
    # a model saved before the measure existed keeps the eye picture's rule
    model, _ = _learn(style=near)
    d = model.to_dict()
    assert d["search_dark"] == pytest.approx(model.search_dark, abs=1e-4)
    d.pop("search_dark")
    old = EyeModel.from_dict(d, model.images())
    assert old.search_dark is None and dark_power(old) == pytest.approx(seen["near"][1], abs=0.02)


def test_light_irises_in_a_dark_face_are_found_not_the_lashes():
    """Grey-green irises as light as the dark skin round them: the darkest discs near them are
    the lash lines and brows, so the search leans on the iris picture and the rim instead (with
    the darkness cue on, both eyes went to the lashes)."""
    model, wi = _learn(style=LIGHT_EYES_DARK_SKIN)
    f = EyeFinder(model, wi)
    for expr in ("neutral", "brows_up", "smile"):
        for off in ((0.0, 0.0), (0.04, -0.05)):
            res, truth, _, _ = _find(f, BASE.with_expression(expr), LIGHT_EYES_DARK_SKIN, offset=off)
            _check(res, truth, pupil=1.0, lid=2.0)


def _light_eyes(f: EyeFinder, centres, opening: float, skin: float = 70.0) -> np.ndarray:
    """A grey eye crop (``f.rect``) of dark skin with two light irises (grey 150, ``f``'s radii) at
    ``centres`` in white almonds ``2 × opening`` px tall, lids over the irises' tops and bottoms when
    the opening is under the radius, and a lash line along each upper lid."""
    x0, y0, w, h = f.rect
    img = np.full((h, w), skin, np.float32)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    for (cx, cy), r in zip(centres, f.radius):
        a = 2.6 * r
        almond = ((xx - cx) / a) ** 2 + ((yy - cy) / opening) ** 2 <= 1.0
        img[almond] = 215.0
        img[almond & (np.hypot(xx - cx, yy - cy) <= r)] = 150.0
        top = cy - opening * np.sqrt(np.clip(1.0 - ((xx - cx) / a) ** 2, 0.0, 1.0))
        img[(yy < top) & (yy >= top - 0.35 * r) & (np.abs(xx - cx) < 0.95 * a)] = 25.0
    return cv2.GaussianBlur(img, (0, 0), 1.0)


@pytest.mark.parametrize("opening", [0.8, 1.0, 1.6])
@pytest.mark.parametrize("off", [(0.0, -4.0), (3.0, -3.0), (-4.0, 2.0)])
def test_a_light_iris_found_off_its_centre_is_moved_onto_its_limbus(opening, off):
    """An iris no darker than the face round it: the search has only its picture, which can match
    with its top on the lid (real light eyes in a dark face: 9 % of the eye distance high). Each
    find is moved to the circle of the calibrated radius on the iris's rim — whether the lids
    cover its top and bottom (0.8, 1.0 radii open: arcs reaching 40° below, as the calibration's
    snap uses, rose 0.7-0.9 px off the lower lid) or the eye is wide open."""
    model, wi = _learn(style=LIGHT_EYES_DARK_SKIN)
    f = EyeFinder(model, wi)
    assert f.dark_power < LIMBUS_DARK
    x0, y0, _, _ = f.rect
    centres = [(-0.5 * wi - x0 + 1.3, -y0 - 0.6), (0.5 * wi - x0 - 0.8, -y0 + 0.4)]
    grey = _light_eyes(f, centres, opening * f.radius[0])
    out = f._on_limbus(grey, [(cx + off[0], cy + off[1], 0.5) for cx, cy in centres])
    for (x, y, match), (cx, cy) in zip(out, centres):
        assert math.hypot(x - cx, y - cy) < 0.3 and match == 0.5
    flat = np.full_like(grey, 70.0)  # no rim anywhere: the finds stay
    found = [(cx + off[0], cy + off[1], 0.5) for cx, cy in centres]
    assert f._on_limbus(flat, found) == found


@pytest.mark.parametrize("gaze", [-2.0, 0.0, 2.0])
def test_a_light_iris_is_found_between_its_whites_when_the_prediction_sits_on_the_lashes(gaze, monkeypatch):
    """A light iris in a dark face, the head's pose a tenth of the eye distance high (brows raised,
    eyes widened: the flow drifts up): without a darkness term the search had the iris picture and the
    ring, and settled on the lash line, 10 px off; the white on both sides of the iris
    (:data:`~tracker.eyes.WHITE_SIDES`) keeps it on the iris."""
    import tracker.eyes as eyes

    model, wi = _learn(style=LIGHT_EYES_DARK_SKIN)
    f = EyeFinder(model, wi)
    assert f.dark_power == 0.0
    x0, y0, _, _ = f.rect
    centres = [(-0.5 * wi - x0 + 1.3 + gaze, -y0 - 0.6), (0.5 * wi - x0 - 0.8 + gaze, -y0 + 0.4)]
    grey = _light_eyes(f, centres, f.radius[0])
    high = np.array([[-0.5 * wi - x0, -y0 - 0.1 * wi], [0.5 * wi - x0, -y0 - 0.1 * wi]])

    def worst() -> float:
        return max(math.hypot(x - cx, y - cy) for (x, y, _), (cx, cy) in zip(f.locate_irises(grey, high), centres))

    assert worst() < 0.5
    monkeypatch.setattr(eyes, "WHITE_SIDES", 0.0)
    assert worst() > 5.0  # the lash line, as before


def test_a_dark_iris_keeps_the_searchs_place(finder):
    """Where the iris is darker than the eye round it, the darkness places it and no limbus fit
    is made (its side arcs pin the height more loosely than a dark disc)."""
    assert finder.dark_power >= LIMBUS_DARK and finder._limbus is None


def test_an_iris_the_gap_rule_cannot_see_is_judged_open_or_shut_by_its_picture():
    """A brown iris of the dark skin's own colour: the lid gap measured at calibration is under an
    iris radius on a wide-open eye (blind), and the same rule called shut eyes open. The iris
    picture's match decides instead: open on open eyes, shut on shut ones and on a wink's shut eye."""
    style = STYLES["dark_skin"].replace(name="brown_as_skin", iris=STYLES["dark_skin"].skin)
    model, wi = _learn(style=style)
    f = EyeFinder(model, wi)
    assert all(g < GAP_BLIND * r for g, r in zip(model.lid_open, model.radius))
    for expr, want in (("neutral", (True, True)), ("brows_up", (True, True)), ("smile", (True, True)),
                       ("eyes_closed", (False, False)), ("wink_l", (False, True)), ("wink_r", (True, False))):
        res, _, _, _ = _find(f, BASE.with_expression(expr), style)
        assert tuple(e.open for e in res.eyes) == want, expr


def test_an_iris_the_gap_rule_cannot_see_keeps_its_column_while_it_shows(monkeypatch):
    """The gap rule that cannot see an iris (:data:`~tracker.eyes.GAP_BLIND`) reads a narrow gap on
    an open eye too, and the slit it measures runs on sideways into whatever is as dark as the eye's
    inside: the eye point moving to the slit's middle (:data:`~tracker.eyes.CLOSING`) went 11 px to
    the lash shadow at a grey photo's eye corner, on the calibration frame itself. While the iris
    picture shows, the point and the pupil reported keep the iris's column; they still take the slit's
    height (a deep-set eye's iris search rides up into the socket's shadow)."""
    import tracker.eyes as E

    style = STYLES["dark_skin"].replace(name="brown_as_skin", iris=STYLES["dark_skin"].skin)
    model, wi = _learn(style=style)
    f = EyeFinder(model, wi)
    assert all(f._gap_blind)
    monkeypatch.setattr(E, "CLEAR_IRIS", (1.5, 2.0))  # the gap decides, whatever the picture says
    state = dataclasses.replace(BASE, gaze_x=0.06)
    full = E.EyeFinder._both_lids
    monkeypatch.setattr(E.EyeFinder, "_both_lids", lambda self, *a, **k: [
        (u, d, 0.2 * self.model.lid_open[i]) for i, (u, d, _) in enumerate(full(self, *a, **k))])
    slit = (lambda self, crop, iris, gain: (iris[0] - 6.0, iris[1] + 2.0))  # a slit off to one side, lower
    monkeypatch.setattr(E.EyeFinder, "_slit", slit)
    res, *_ = _find(f, state, style)
    for e in res.eyes:
        assert e.iris_match >= E.IRIS_SHOWS
        assert e.x == pytest.approx(e.iris[0]) and e.shown[0] == pytest.approx(e.iris[0])
        assert e.y > e.iris[1] + 1.0  # the slit's height is taken
    f._gap_blind = [False, False]  # a gap rule that sees the iris: the point goes to the slit's middle
    res2, *_ = _find(f, state, style)
    assert all(e.x < e.iris[0] - 4.0 for e in res2.eyes)


def test_a_small_face_and_strong_roll():
    small = BASE.replace(ipd=44.0, roll_deg=25.0)
    model, wi = _learn(small)
    assert wi == 44.0
    f = EyeFinder(model, wi)
    res, truth, _, _ = _find(f, small.with_expression("brows_up").replace(roll_deg=-20.0))
    _check(res, truth, pupil=0.6, lid=1.5, brow=1.5)


def test_the_light_is_followed_by_adaptation():
    model, wi = _learn()
    f = EyeFinder(model, wi)
    dim = BASE.replace(light=(0.7, 0.72, 0.75))
    frame, _ = render_face(dim)
    for _ in range(60):  # a couple of seconds of confident frames
        res, truth, _, (crop, grey, _) = _find(f, dim, frame=frame)
        f.adapt(crop, grey, res)
    res, truth, _, _ = _find(f, dim, frame=frame)
    _check(res, truth, lid=1.5)
    f.reset_adaptation()
    assert f._gain is None


def test_the_light_is_followed_within_half_a_second():
    """Auto exposure or a lamp switched off: within 15 confident frames (half a second at 30 fps)
    the light's gain is most of the way to the new light, not a fraction of it."""
    model, wi = _learn()
    f = EyeFinder(model, wi)
    dim = BASE.replace(light=(0.7, 0.7, 0.7))
    frame, _ = render_face(dim)
    for _ in range(15):
        res, _, _, (crop, grey, _) = _find(f, dim, frame=frame)
        f.adapt(crop, grey, res)
    assert f._gain is not None and np.all(f._gain > 1.0 + 0.8 * (1 / 0.7 - 1.0))


def test_adaptation_spreads_its_updates_over_frames():
    """Every confident frame follows the light; each updates at most one of the iris pictures
    and the eye pictures, and within ADAPT_EVERY confident frames both have been updated."""
    from tracker.eyes import ADAPT_EVERY
    model, wi = _learn()
    f = EyeFinder(model, wi)
    dim = BASE.replace(light=(0.8, 0.82, 0.85), gaze_x=0.03)
    frame, _ = render_face(dim)
    changed = []
    for _ in range(ADAPT_EVERY):
        res, _, _, (crop, grey, _) = _find(f, dim, frame=frame)
        before = ([p.copy() for p in f._adapted_iris], [p.copy() for p in f._adapted_eye], f._gain_slow.copy())
        assert f.adapt(crop, grey, res)
        now = (f._adapted_iris, f._adapted_eye, f._gain_slow)
        changed.append([not all(np.array_equal(a, b) for a, b in zip(x, y)) if isinstance(x, list) else not np.array_equal(x, y)
                        for x, y in zip(before, now)])
    assert all(c[2] for c in changed)  # the light, every frame
    assert all(c[0] + c[1] <= 1 for c in changed)
    assert any(c[0] for c in changed) and any(c[1] for c in changed)


def test_model_round_trips_through_json(finder):
    m = finder.model
    d = json.loads(json.dumps(m.to_dict()))
    imgs = m.images()
    assert set(imgs) == set(EyeModel.IMAGE_NAMES) and all(v.dtype == np.uint8 for v in imgs.values())
    # PNG round trip of the pictures
    imgs = {k: cv2.imdecode(cv2.imencode(".png", v)[1], cv2.IMREAD_GRAYSCALE) for k, v in imgs.items()}
    m2 = EyeModel.from_dict(d, imgs)
    f2 = EyeFinder(m2, m2.work_ipd)
    assert f2.rect == finder.rect
    assert m2.search_dark == pytest.approx(m.search_dark, abs=1e-4) and f2.dark_power == pytest.approx(finder.dark_power, abs=1e-3)
    assert m.limbus is not None and m2.limbus == pytest.approx(m.limbus, abs=1e-3)
    res1, _, _, _ = _find(finder, BASE.with_expression("smile"))
    res2, _, _, _ = _find(f2, BASE.with_expression("smile"))
    for a, b in zip(res1.eyes, res2.eyes):
        assert abs(a.x - b.x) < 0.1 and abs(a.y - b.y) < 0.1 and abs(a.upper - b.upper) < 0.3 and abs(a.brow - b.brow) < 0.3


@pytest.mark.parametrize(
    "change",
    [
        lambda d, i: d.update(format=99),
        lambda d, i: d.pop("lid_open"),
        lambda d, i: d.update(radius=[1.0]),
        lambda d, i: i.pop("eye_l"),
        lambda d, i: i.update(iris_l=np.zeros((4, 6), np.uint8)),
        lambda d, i: d["skin"].update(levels=[3.0, 2.0]),
        lambda d, i: d["skin"].update(cov=[[1, 2, 0], [2, 1, 0], [0, 0, 1]]),
        lambda d, i: d.update(light=[[1.0, 1.0, 1.0]]),
        lambda d, i: d.update(light=[[1.0, 1.0, 1.0], [1.0, -1.0, 1.0]]),
        lambda d, i: d.update(light=[[1.0, 1.0], [1.0, 1.0]]),
        lambda d, i: d.update(search_dark="dark"),
        lambda d, i: d.update(search_dark=float("nan")),
        lambda d, i: d.update(glance=2),
        lambda d, i: d.update(glance=True),
        lambda d, i: d.update(glance="left"),
        lambda d, i: d.update(limbus=[20.0]),
        lambda d, i: d.update(limbus=[20.0, float("nan")]),
        lambda d, i: d.update(limbus="strong"),
    ],
)
def test_malformed_models_give_one_line_errors(finder, change):
    d = json.loads(json.dumps(finder.model.to_dict()))
    imgs = dict(finder.model.images())
    change(d, imgs)
    with pytest.raises(EyeModelError) as e:
        EyeModel.from_dict(d, imgs)
    assert "\n" not in str(e.value)


def test_learning_refuses_only_garbage():
    with pytest.raises(EyeModelError):
        learn_eyes(np.zeros((50, 50), np.uint8), np.zeros((50, 50), np.uint8), [[10, 10], [40, 10]], [[10, 0], [40, 0]], 30)
    with pytest.raises(EyeModelError):  # an eye at the crop's edge
        crop = np.full((60, 120, 3), 128, np.uint8)
        learn_eyes(crop, crop[..., 0], [[2, 30], [60, 30]], [[2, 10], [60, 10]], 58)
    # a flat grey face is not refused: nothing is iris-like, but it is a usable (if useless) model
    crop = np.full((136, 168, 3), (120, 150, 190), np.uint8)
    crop += np.random.default_rng(0).integers(0, 6, crop.shape, dtype=np.uint8)
    m = learn_eyes(crop, cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY), [[44, 96], [124, 96]], [[44, 64], [124, 64]], 80.0)
    assert all(r > 0 for r in m.radius)


def test_refine_pupils_snaps_clicks_to_the_irises():
    frame, _ = render_face(BASE)
    lm = face_landmarks(BASE)
    l, r = refine_pupils(frame, tuple(lm["left_pupil"] + (3, -2)), tuple(lm["right_pupil"] + (-2, 3)))
    assert np.hypot(*(np.array(l) - lm["left_pupil"])) < 0.5
    assert np.hypot(*(np.array(r) - lm["right_pupil"])) < 0.5


@pytest.mark.parametrize("iris", [1.35, 1.45])
def test_refine_pupils_snaps_to_a_childs_larger_iris(iris, monkeypatch):
    """A young child's iris is nearly an adult's between eyes 45-50 mm apart: 0.12-0.14 of the eye
    distance in radius (the performer's is 0.095). Refinement once tried radii up to 0.13 only, a
    smaller circle's rim beside the iris won, and both clicks moved 4 % of the eye distance to one
    side."""
    import tracker.synthetic as synthetic

    monkeypatch.setattr(synthetic, "IRIS_R", synthetic.IRIS_R * iris)
    frame, _ = render_face(BASE)
    lm = face_landmarks(BASE)
    l, r = refine_pupils(frame, tuple(lm["left_pupil"] + (2, -1)), tuple(lm["right_pupil"] + (-1, 2)))
    assert np.hypot(*(np.array(l) - lm["left_pupil"])) < 0.02 * BASE.ipd
    assert np.hypot(*(np.array(r) - lm["right_pupil"])) < 0.02 * BASE.ipd


def test_refine_pupils_keeps_the_clicks_where_snapping_again_moves_on(monkeypatch):
    """A snap stands where snapping the snapped pair again keeps it within ``SNAP_HOLD`` of the eye
    distance: a sharp eye's rim holds it (the performer's clicks, moved 3 px, snap onto the irises
    and stay); one that moves on is followed until it holds, and one that swings back and forth — a
    dim, blurred eye where the best circle depends on where the search starts — leaves the clicks as
    they were."""
    import tracker.eyes as eyes

    frame, _ = render_face(BASE)
    lm = face_landmarks(BASE)
    clicks = (tuple(lm["left_pupil"] + (3, -2)), tuple(lm["right_pupil"] + (-2, 3)))
    real = eyes._snap_pupils
    calls = []

    def drifting(grey, lp, rp, ipd):
        calls.append((lp, rp))
        k = 0.03 * ipd  # every snap moves the pair on by 3 % of the eye distance: nothing holds it
        return (lp[0] + k, lp[1] + k), (rp[0] + k, rp[1] + k)

    monkeypatch.setattr(eyes, "_snap_pupils", drifting)
    assert eyes.refine_pupils(frame, *clicks) == tuple(tuple(map(float, c)) for c in clicks)
    assert len(calls) == 1 + eyes.SNAP_TRIES

    def settling(grey, lp, rp, ipd):  # a second step of 3 %, then it holds: the second place stands
        calls.append((lp, rp))
        k = 0.03 * ipd if len(calls) <= 2 else 0.0
        return (lp[0] + k, lp[1]), (rp[0] - k, rp[1])

    calls.clear()
    monkeypatch.setattr(eyes, "_snap_pupils", settling)
    l, r = eyes.refine_pupils(frame, *clicks)
    assert l[0] == pytest.approx(clicks[0][0] + 0.06 * BASE.ipd, rel=0.02) and len(calls) == 3
    monkeypatch.setattr(eyes, "_snap_pupils", real)
    l, r = eyes.refine_pupils(frame, *clicks)
    assert np.hypot(*(np.array(l) - lm["left_pupil"])) < 0.5 and np.hypot(*(np.array(r) - lm["right_pupil"])) < 0.5


def test_refine_pupils_keeps_clicks_on_a_face_without_eyes():
    flat = np.full((200, 300, 3), 140, np.uint8)
    assert refine_pupils(flat, (100.0, 100.0), (180.0, 100.0)) == ((100.0, 100.0), (180.0, 100.0))


def _lidded_eye(iris: float, opening: float, lashes: float, dy: float = 0.0, skin: float = 190.0) -> np.ndarray:
    """One eye on skin of grey ``skin`` (grey, 160 × 120 px, an eye distance of 160 px): a white
    almond ``2 × opening`` px tall, an iris of radius 13 and grey ``iris`` centred at (80, 60 + dy)
    whose top the upper lid covers, and a dark lash line of grey ``lashes`` along the upper
    lid's edge (as thick as a third of the iris)."""
    img = np.full((120, 160), skin, np.float32)
    yy, xx = np.mgrid[0:120, 0:160].astype(np.float32)
    cy = 60.0 + dy
    almond = ((xx - 80.0) / 34.0) ** 2 + ((yy - cy) / opening) ** 2 <= 1.0
    img[almond] = 225.0
    img[almond & (np.hypot(xx - 80.0, yy - cy) <= 13.0)] = iris
    top = cy - opening * np.sqrt(np.clip(1.0 - ((xx - 80.0) / 34.0) ** 2, 0.0, 1.0))
    img[(yy < top) & (yy >= top - 4.5) & (np.abs(xx - 80.0) < 32.0)] = lashes
    return cv2.GaussianBlur(img, (0, 0), 1.0)


def _two_eyes(img: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(np.clip(np.hstack([img, img]), 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)


def test_refine_pupils_finds_a_dark_iris_under_dark_lashes_and_a_lower_lid():
    """A dark iris whose top the lid and its dark lashes cover and whose bottom the lower lid
    covers: the centre is the circle through the sides of its rim, not the middle of what
    shows (the old drawn-disc search put it 1.7 px low here)."""
    frame = _two_eyes(_lidded_eye(iris=60.0, opening=8.0, lashes=30.0))
    l, r = refine_pupils(frame, (81.5, 58.0), (238.5, 61.5))
    assert np.hypot(l[0] - 80.0, l[1] - 60.0) < 1.0 and np.hypot(r[0] - 240.0, r[1] - 60.0) < 1.0


@pytest.mark.parametrize("dy", [-3.0, 0.0, 2.5])
def test_refine_pupils_keeps_a_narrow_eyes_light_iris_off_its_lash_line(dy):
    """A narrow eye whose light iris shows as a band between the lids: the lash line above is the
    darkest thing there, but the centre stays on the iris."""
    frame = _two_eyes(_lidded_eye(iris=140.0, opening=8.0, lashes=40.0, dy=dy))
    l, r = refine_pupils(frame, (80.0, 60.0), (240.0, 60.0))
    for p, x in ((l, 80.0), (r, 240.0)):
        assert abs(p[0] - x) < 1.0 and abs(p[1] - (60.0 + dy)) < 1.5


@pytest.mark.parametrize("dy", [-2.0, 0.0, 2.0])
def test_refine_pupils_keeps_a_light_iris_in_a_dark_face_off_its_lid(dy):
    """A light iris in a narrow eye of a dark face: the dark lid over the light eye is the
    steepest edge near the click, and a circle centred on it has its lower arcs on that edge —
    but the grey there changes along the arcs as much as across them, which a limbus never does,
    so the careful clicks stay (the circle's centre went 3 px up onto the lid)."""
    frame = _two_eyes(_lidded_eye(iris=150.0, opening=7.0, lashes=25.0, dy=dy, skin=70.0))
    l, r = refine_pupils(frame, (80.0, 60.0 + dy), (240.0, 60.0 + dy))
    for p, x in ((l, 80.0), (r, 240.0)):
        assert abs(p[0] - x) < 1.0 and abs(p[1] - (60.0 + dy)) < 1.0


def _iris_eye(iris: float, highlight: bool) -> np.ndarray:
    """One open eye (grey, 160 × 120 px, an eye distance of 160 px): a white almond, an iris of
    radius 18 and grey ``iris`` round a dark pupil, and (``highlight``) a bright reflection just
    right of the pupil."""
    img = np.full((120, 160), 170.0, np.float32)
    yy, xx = np.mgrid[0:120, 0:160].astype(np.float32)
    almond = ((xx - 80.0) / 34.0) ** 2 + ((yy - 60.0) / 14.0) ** 2 <= 1.0
    img[almond] = 215.0
    img[almond & (np.hypot(xx - 80.0, yy - 60.0) <= 18.0)] = iris
    img[np.hypot(xx - 80.0, yy - 60.0) <= 4.5] = 25.0
    if highlight:
        img[(np.abs(xx - 89.0) <= 3.0) & (np.abs(yy - 59.0) <= 2.5)] = 250.0
    return cv2.GaussianBlur(img, (0, 0), 1.0)


@pytest.mark.parametrize("light", [150.0, 170.0])
def test_refine_pupils_fits_both_irises_at_one_size(light):
    """A light iris whose dark pupil and highlight make a small circle's edges beside the centre
    (stronger there than its own faint rim), next to a plain dark iris: the two irises are one
    size, so the light one's rim is the one at the dark one's radius (fitted alone, it went
    6.5 px to the side)."""
    frame = cv2.cvtColor(np.hstack([_iris_eye(70.0, False), _iris_eye(light, True)]).astype(np.uint8), cv2.COLOR_GRAY2BGR)
    l, r = refine_pupils(frame, (81.0, 61.0), (241.0, 59.0))
    assert np.hypot(l[0] - 80.0, l[1] - 60.0) < 1.0 and np.hypot(r[0] - 240.0, r[1] - 60.0) < 1.5


@pytest.mark.parametrize("light", [150.0, 170.0])
@pytest.mark.parametrize("dx", [-1.0, 0.0, 1.0])
def test_refine_pupils_fits_the_irises_not_a_ring_smaller_than_any_iris(light, dx):
    """Two light irises, each with a dark pupil and a highlight beside it: the circle through those
    is strongest at the smallest radius tried and stronger still below it, a ring no iris is that
    small. The rim is the radius where the edge peaks inside the range (at the range's end the
    centres went 6.5 px to the side, whichever way the clicks moved)."""
    eye = _iris_eye(light, True)
    frame = cv2.cvtColor(np.hstack([eye, eye]).astype(np.uint8), cv2.COLOR_GRAY2BGR)
    l, r = refine_pupils(frame, (80.0 + dx, 60.0), (240.0 + dx, 60.0))
    for p, x in ((l, 80.0), (r, 240.0)):
        assert abs(p[0] - x) < 1.0 and abs(p[1] - 60.0) < 2.0


def test_common_radius_is_a_peak_inside_the_range():
    """Edges that only grow towards the smallest radius tried (a pupil's ring) lose to a rim that
    peaks inside the range, even a weaker one; with no such peak the strongest radius is kept."""
    from tracker import eyes

    flat = np.zeros((10, 10), np.float32)
    eyes.limbus_scores((flat, flat), (5.0, 5.0))  # makes the grid
    g = eyes._LIMBUS
    n = len(g.radii)
    prior = g.prior

    def scores(by_radius):
        return np.asarray(by_radius, np.float32)[:, None, None] / prior.max() * np.ones((1,) + prior.shape, np.float32)

    falling = np.linspace(6.0, 1.0, n)
    k = n // 2
    bump = falling + 2.5 * np.exp(-0.5 * ((np.arange(n) - k) / 1.5) ** 2)
    lo, hi = eyes.common_radius((scores(bump), scores(bump)))
    assert lo < k < hi and bump[k] < bump[0]
    lo, hi = eyes.common_radius((scores(falling), scores(falling)))
    assert lo < 0 < hi


def _glancing_iris(shift: float, iris: float = 60.0, white: float = 215.0, corner: float = 95.0) -> np.ndarray:
    """A calibrated iris picture (grey, 13 × 29 px, the iris of radius 7 at its centre) of an eye
    whose white ends ``shift`` px past the iris on the image-left side (negative: on the right) and
    reaches the picture's edge on the other; the eye's shaded corner beyond the white's end."""
    pic = np.full((13, 29), white, np.float32)
    xx = np.arange(29, dtype=np.float32)[None, :] - 14.0
    yy = np.arange(13, dtype=np.float32)[:, None] - 6.0
    if shift > 0:
        pic[:, (xx < -7.0 - shift)[0]] = corner
    elif shift < 0:
        pic[:, (xx > 7.0 - shift)[0]] = corner
    pic[np.hypot(xx, yy) <= 7.0] = iris
    return cv2.GaussianBlur(pic, (0, 0), 0.8)


@pytest.mark.parametrize("left, right, side", [
    (None, None, 0),   # white both sides: looking ahead
    (1.0, 1.0, -1),    # the iris against both eyes' image-left corners: turned to image-left
    (-1.0, -1.0, 1),
    (1.0, None, 0),    # one eye alone (its corner in shadow, a lid): not a glance
    (1.0, -1.0, 0),    # opposite ways (crossing eyes, or a squint): not a glance
])
def test_side_glance_needs_white_on_one_side_only_in_both_eyes(left, right, side):
    pics = [_glancing_iris(0.0 if v is None else v) for v in (left, right)]
    model = SimpleNamespace(iris_pictures=pics, radius=[7.0, 7.0])
    assert side_glance(model) == side


@pytest.mark.parametrize("gaze, side", [(0.0, 0), (-0.25, -1), (0.25, 1)])
def test_a_calibration_frame_with_the_eyes_aside_is_told_after_the_pictures_are_evened_out(gaze, side):
    """The model keeps the glance seen on the pictures as cut: their sides are evened out
    (:func:`mirrored_sides`) before they are kept, which halves the white's lean, so the pictures
    kept would not tell it; a saved model keeps it too."""
    model, _ = _learn(dataclasses.replace(BASE, gaze_x=gaze))
    assert model.glance == side and side_glance(model) == side
    back = EyeModel.from_dict(json.loads(json.dumps(model.to_dict())), model.images())
    assert back.glance == side
    if side:
        assert side_glance(SimpleNamespace(iris_pictures=model.iris_pictures, radius=model.radius)) == 0
    old = model.to_dict()
    old.pop("glance")  # a model saved before the glance was kept: read from its pictures
    assert EyeModel.from_dict(old, model.images()).glance is None


def test_side_glance_says_nothing_of_an_iris_as_light_as_its_white():
    pics = [_glancing_iris(1.0, iris=205.0, white=215.0, corner=205.0)] * 2
    assert side_glance(SimpleNamespace(iris_pictures=pics, radius=[7.0, 7.0])) == 0


def test_limbus_centre_prefers_the_rim_near_the_click():
    """Two equal irises in reach: the one nearer the click wins; a flat picture has no edge."""
    img = np.full((60, 100), 200.0, np.float32)
    for x in (40.0, 58.0):
        cv2.circle(img, (int(x), 30), 7, 60.0, -1, cv2.LINE_AA)
    g = cv2.GaussianBlur(img, (0, 0), 1.0)
    grad = (cv2.Scharr(g, cv2.CV_32F, 1, 0, scale=1 / 32), cv2.Scharr(g, cv2.CV_32F, 0, 1, scale=1 / 32))
    x, y, radius, edge = limbus_centre(grad, (43.0, 30.0))
    assert abs(x - 40.0) < 0.7 and abs(y - 30.0) < 0.7 and abs(radius - 7.0) < 1.0 and edge > 10.0
    flat = np.zeros((60, 100), np.float32)
    assert limbus_centre((flat, flat), (43.0, 30.0))[3] == 0.0


def test_iris_radius_of_a_drawn_disc():
    img = np.full((60, 100), 200, np.float32)
    cv2.circle(img, (50, 30), 8, 40, -1, cv2.LINE_AA)
    assert abs(iris_radius(img, (50.0, 30.0), 80.0) - 8.0) < 0.8


def test_ring_votes_peak_at_a_dark_discs_centre(finder):
    img = np.full((41, 61), 200, np.float32)
    cv2.circle(img, (30, 20), int(round(0.5 * np.mean(finder.radius))), 30, -1, cv2.LINE_AA)
    gx, gy = cv2.Sobel(img, cv2.CV_32F, 1, 0), cv2.Sobel(img, cv2.CV_32F, 0, 1)
    w = 1.0 / (cv2.magnitude(gx, gy) + 1e-3)
    v = finder._ring_votes(gx * w, gy * w, 8)
    assert np.unravel_index(np.argmax(v), v.shape) == (20 - 8, 30 - 8)


def test_skin_model_ramps_from_skin_to_interior():
    skin = np.random.default_rng(1).normal((140, 172, 218), 3, (400, 3))
    sm = SkinModel.fit({"skin": skin}, np.array([[20.0, 20, 20]]))
    e = sm.interior(np.array([[140, 172, 218], [230, 235, 240], [20, 20, 20]], np.float32))
    assert e[0] == 0.0 and e[1] == 1.0 and e[2] == 1.0
    col = np.array([[[140, 172, 218]], [[230, 235, 240]]], np.float32)
    assert sm.profile(col) == pytest.approx(list(e[:2]))


def _skin(mean=(60, 90, 140), n=400, seed=1):
    return np.random.default_rng(seed).normal(mean, 3, (n, 3))


@given(k=st.floats(1.0, 1.45), gain=st.floats(0.8, 1.2))
@settings(max_examples=40, deadline=None)
def test_brighter_skin_is_still_skin_and_the_white_is_not(k, gain):
    """More light on the skin (the same colour, brighter: a lit lid, a highlight) stays skin;
    a white as bright is interior, and so is the skin's colour made darker."""
    base = np.array([60, 90, 140], np.float32)
    sm = SkinModel.fit({"skin": _skin(base)}, np.array([[20.0, 20, 20]]))
    e = sm.interior(np.array([base * k, [170, 175, 180], base * 0.5], np.float32))
    assert e[0] < 0.05 and e[1] == 1.0 and e[2] == 1.0
    g = np.full(3, gain, np.float32)
    assert sm.interior((base * k / gain)[None].astype(np.float32), g)[0] < 0.05  # the gain takes the light off first


def test_levels_and_dark_rule_set_after_fitting_take_effect():
    """set_levels and set_dark change what the membership computes (it is precomputed)."""
    rng = np.random.default_rng(2)
    shaded = np.array([60.0, 90, 140]) * rng.uniform(0.6, 1.1, (400, 1)) + rng.normal(0, 2, (400, 3))
    sm = SkinModel.fit({"skin": shaded}, np.array([[10.0, 10, 10]]))
    mid = np.array([[18, 27, 42]], np.float32)  # the skin's colour in deep shadow, far darker than any sample
    before = float(sm.interior(mid)[0])
    sm.set_dark([shaded], np.full((20, 3), 10.0))
    assert sm.dark > 0 and float(sm.interior(mid)[0]) > before
    assert float(sm.interior(np.array([[12, 12, 12]], np.float32))[0]) == 1.0
    lo = sm.lo
    sm.set_levels([np.full((10, 3), (30.0, 30, 30))])
    assert sm.lo != lo and SkinModel.from_dict(sm.to_dict()).interior(mid)[0] == pytest.approx(sm.interior(mid)[0], abs=1e-5)


def test_dark_rule_survives_lashes_in_the_band_above_the_eye():
    """A band over the eye that holds lashes and the lid crease (a tenth of it as dark as the
    iris) does not switch off "much darker than any skin"; a band that is mostly that dark does."""
    iris = np.full((20, 3), 12.0)
    skin = [_skin((60, 90, 140))]
    band = np.concatenate([_skin((40, 60, 95), 90), np.full((10, 3), 12.0)])
    sm = SkinModel.fit({"skin": skin[0]}, iris)
    sm.set_dark(skin, iris, [band])
    assert sm.dark > 12.0
    dark_band = np.concatenate([_skin((40, 60, 95), 40), np.full((60, 3), 14.0)])
    sm2 = SkinModel.fit({"skin": skin[0]}, iris)
    sm2.set_dark(skin, iris, [dark_band])
    assert sm2.dark < 0


@given(st.lists(st.floats(0.0, 1.0), min_size=0, max_size=30))
def test_run_length_is_bounded_and_stops_at_a_gap(e):
    r = _run(np.array(e, np.float32))
    assert 0.0 <= r <= max(len(e) - 0.5, 0.0) + 1e-6
    if len(e) >= 3 and e[1] < 0.5 and e[2] < 0.5:
        assert r == pytest.approx(0.5 * e[0])


def test_a_lid_far_from_the_calibrated_skin_still_ends_the_run():
    # a walk up from the iris (distance 9 from the skin) through a shadowed lid (5.5: past the
    # calibrated ramp 2..5, like the iris by colour) to the brow (7), never reaching skin like the
    # calibrated one (deep-set eyes at low resolution): the lid's edge is after the 4 iris
    # samples, not at the walk's end
    walk = [9.0] * 4 + [5.5] * 6 + [7.0] * 3
    assert walk_length(walk, 2.0, 5.0, 3, None) > 12.0  # the calibrated ramp alone: on to the walk's end
    assert walk_length(walk, 2.0, 5.0, 3, 8.0) == pytest.approx(3.5, abs=0.3)
    # a walk that reaches the calibrated skin keeps the calibrated ramp
    plain = [9.0] * 4 + [0.5] * 6
    assert walk_length(plain, 2.0, 5.0, 3, 8.0) == pytest.approx(walk_length(plain, 2.0, 5.0, 3, None))


def test_the_white_beside_the_iris_stays_inside_the_run():
    # iris (9), then the white above it (4.5, as calibrated), then a lid lit off the skin (2.5):
    # the ramp moves half-way to the white, not to the iris, so the white stays interior
    walk = [9.0] * 3 + [4.5] * 3 + [2.5] * 4
    assert walk_length(walk, 2.0, 5.0, 3, 4.5) == pytest.approx(5.0, abs=0.3)
    assert walk_length(walk, 2.0, 5.0, 3, math.inf) < 3.0  # the iris's level alone cuts the white off



def test_pale_skin_under_the_eye_ends_the_lower_walk_when_no_white_is_below():
    # down from the iris (9) over the lower lid to skin lit paler and greyer than the calibrated
    # skin (4, where the calibrated white is 2.6 from the skin): the capped ramp (its interior at
    # the white's level) took that skin for the eye and ran on to the walk's end; with no sample as
    # skin-like as the white, the lower walk's ramp sits between its own interior and skin
    walk = [9.4, 9.3, 8.9, 8.4, 7.6, 6.7, 5.7, 5.2, 5.0, 4.3, 4.1] + [4.0] * 9
    assert walk_length(walk, 2.0, 5.0, 8, 2.6) > 15.0
    assert walk_length(walk, 2.0, 5.0, 8, 2.6, below=True) == pytest.approx(5.1, abs=0.5)
    # white below the iris (2.5) is as skin-like as the calibrated white: capped as before
    white = [9.4, 9.3, 8.9, 8.4, 7.6, 2.5, 2.4, 2.6, 2.5, 3.0, 4.0, 4.5] + [1.0] * 4
    assert walk_length(white, 2.0, 5.0, 8, 2.6, below=True) == walk_length(white, 2.0, 5.0, 8, 2.6)

def test_a_model_without_a_white_level_loads_and_keeps_the_calibrated_ramp(finder):
    d = json.loads(json.dumps(finder.model.to_dict()))
    assert d["white"] == pytest.approx(finder.model.white)
    d.pop("white")
    m = EyeModel.from_dict(d, finder.model.images())
    assert m.white is None


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(dx=st.floats(-0.16, 0.16), dy=st.floats(-0.08, 0.08), gaze=st.floats(-0.05, 0.05))
def test_pupils_found_wherever_the_prediction_lands(finder, dx, dy, gaze):
    res, truth, _, _ = _find(finder, BASE.replace(gaze_x=gaze), offset=(dx, dy))
    for e, side in zip(res.eyes, ("left", "right")):
        assert math.hypot(e.x - truth[side]["pupil"][0], e.y - truth[side]["pupil"][1]) < 1.0


def test_brow_stays_on_the_brow_when_a_crease_below_looks_as_much_like_it(finder):
    """Two equally good places for the brow's cross-section: the first frame takes the one near the
    calibrated brow, the next frames stay where the brow was unless the other is much better."""
    top, py = 0, 80.0
    base = py - top - finder.model.brow_centres[0]
    brow_k = int(round(base - finder.model.brow_heights[0]))  # at the calibrated height
    crease_k = brow_k + 15  # the crease lies 15 px lower (a smaller height)
    score = np.zeros(crease_k + 10, np.float32)
    score[brow_k - 1 : brow_k + 2] = (0.7, 0.9, 0.7)
    score[crease_k - 1 : crease_k + 2] = (0.72, 0.93, 0.72)
    finder.forget()
    h, m = finder._brow_peak(score, top, py, 0)
    assert h == pytest.approx(base - brow_k) and m == pytest.approx(0.9)  # no history: calibration's place
    finder._brow_last[0] = py - (base - crease_k)  # had the brow been on the crease, it would stay there
    h, _ = finder._brow_peak(score, top, py, 0)
    assert h == pytest.approx(base - crease_k)
    finder._brow_last[0] = py - (base - brow_k)  # the brow's row
    h, _ = finder._brow_peak(score, top, py, 0)
    assert h == pytest.approx(base - brow_k)  # the brow was here: it stays
    score[crease_k] = 1.0
    score[brow_k] = 0.3  # the brow's match collapsed: the other place wins after all
    h, _ = finder._brow_peak(score, top, py, 0)
    assert h == pytest.approx(base - crease_k, abs=0.5)
    finder.forget()
    assert all(math.isnan(v) for v in finder._brow_last)


def test_a_blink_moving_the_eye_point_down_does_not_pull_the_brow_onto_the_crease(finder):
    """In a blink the eye point goes down to the slit (here 12 px) while the brow stays where it was
    in the crop, which follows the head. The lid's crease 15 px under the brow matches its
    cross-section a little better. Held as a height above the eye point, the last brow sat 3 px from
    the crease and 12 from itself, and the brow went to the crease (talk_a with ``--auto``, after a
    blink: the left brow 20 px low for ten frames); held as a row of the crop it stays on the brow."""
    n, c = 50, finder.model.brow_centres[0]
    finder.forget()
    score = np.zeros(n, np.float32)
    score[19:22] = (0.7, 0.9, 0.7)  # frame 1: the brow at offset 20 (row c + 20), alone
    h1, _ = finder._brow_peak(score, 0, 50.0, 0)
    assert h1 == pytest.approx(50.0 - c - 20)
    top, py = 12, 62.0  # frame 2: the eye point and its window 12 px lower
    score = np.zeros(n, np.float32)
    score[7:10] = (0.7, 0.9, 0.7)  # the brow, same row: offset 8
    score[22:25] = (0.72, 0.93, 0.72)  # the crease, 15 px lower: offset 23
    h2, _ = finder._brow_peak(score, top, py, 0)
    assert py - h2 == pytest.approx(c + 20)  # the same row as before
    assert h2 == pytest.approx(h1 + 12)


def test_checking_a_guess_without_the_brows_finds_the_same_eyes_and_keeps_the_brow_memory(finder):
    res, _, _, (crop, grey, centres) = _find(finder, BASE.with_expression("smile"))
    remembered = list(finder._brow_last)
    quick = finder.find(crop, grey, centres, brows=False)
    assert finder._brow_last == remembered
    for a, b in zip(res.eyes, quick.eyes):
        assert (a.x, a.y, a.score, a.open, a.upper, a.lower, a.iris) == (b.x, b.y, b.score, b.open, b.upper, b.lower, b.iris)
        assert math.isnan(b.brow) and math.isfinite(a.brow)


def _side_lit(frame: np.ndarray, far: float) -> np.ndarray:
    """The frame lit from its left: full light left of the face, ``far`` of it right of the face."""
    x = np.clip((np.arange(frame.shape[1], dtype=np.float32) - (BASE.cx - 1.2 * BASE.ipd)) / (2.4 * BASE.ipd), 0.0, 1.0)
    ramp = 1.0 - (1.0 - far) * x * x * (3.0 - 2.0 * x)
    return np.clip(frame.astype(np.float32) * ramp[None, :, None], 0, 255).astype(np.uint8)


@pytest.mark.parametrize("far", [0.35, 0.5])
def test_a_face_lit_from_one_side_has_both_eyes_measured(far):
    """A window beside the desk: one eye's side of the face in full light, the other's in the
    shade. One skin model learned from both sides as they are took every row of either eye for
    skin (the lids were 0 px from the iris); each eye's colours are taken to the light both share
    first (:func:`eye_light`), at calibration and on every frame."""
    frame = _side_lit(render_face(BASE)[0], far)
    model, wi = _learn(frame=frame)
    assert model.light is not None and np.all(model.light[1] > 1.1) and np.all(model.light[0] < 0.95)
    back = EyeModel.from_dict(json.loads(json.dumps(model.to_dict())), model.images())
    assert np.allclose(back.light, model.light, atol=1e-4)
    f = EyeFinder(model, wi)
    res, truth, _, _ = _find(f, BASE, frame=frame)
    _check(res, truth, lid=1.5)
    for expr in ("wide", "brows_up"):
        state = BASE.with_expression(expr)
        res, truth, _, _ = _find(f, state, frame=_side_lit(render_face(state)[0], far))
        _check(res, truth, lid=1.5)


def test_eyes_lit_alike_have_no_light_factors(finder):
    assert finder.model.light is None
    assert eye_light([np.full((20, 3), 100.0), np.full((20, 3), 103.0)]) is None
    f = eye_light([np.full((20, 3), 100.0), np.full((20, 3), 400.0)])
    assert f[0] == pytest.approx([2.0] * 3) and f[1] == pytest.approx([0.5] * 3)


@pytest.mark.parametrize("light", [0.5, 1.35])
def test_a_sudden_change_of_the_light_is_taken_at_once(light):
    """A lamp switched off or on, an exposure step: from the first frame in the new light the lids
    are measured as before it. The skin round the eyes, picked out under the old light's gain, no
    longer looks like skin (at half the light none of it did, so the gain was never measured
    again and the lids stayed wrong for good)."""
    model, wi = _learn()
    f = EyeFinder(model, wi)
    for _ in range(3):  # a few confident frames in the calibration's light
        res, truth, _, (crop, grey, _) = _find(f, BASE)
        assert f.adapt(crop, grey, res)
    state = BASE.replace(light=(light, light, light))
    res, truth, _, (crop, grey, _) = _find(f, state)
    _check(res, truth, lid=1.5)
    # (the median channel: the brighter render clips the skin's red at 255)
    assert f._gain is not None and abs(np.median(np.log(f._gain)) + math.log(light)) < 0.1
    for _ in range(10):  # and it stays: the slow measurement agrees
        f.adapt(crop, grey, res)
        res, truth, _, (crop, grey, _) = _find(f, state)
    _check(res, truth, lid=1.5)


@pytest.mark.parametrize("expr", ["eyes_closed", "brows_up", "wide", "squint"])
def test_a_face_pulled_in_the_same_light_is_no_jump_of_the_light(expr):
    """The jump check looks at the whole grid round the eyes, so closing the eyes or raising the
    brows in an unchanged light measures nothing again: the gain stays as the slow measurement
    left it, in a light a little dimmer than the calibration's."""
    model, wi = _learn()
    f = EyeFinder(model, wi)
    dim = BASE.replace(light=(0.9, 0.9, 0.9))
    for _ in range(20):
        res, truth, _, (crop, grey, _) = _find(f, dim)
        f.adapt(crop, grey, res)
    before = f._gain.copy()
    _find(f, dim.with_expression(expr))
    assert np.array_equal(before, f._gain)


def test_the_light_is_followed_as_it_falls_far_and_turns_warm():
    """A room's light falling to 40-60 % per channel (warmer: blue falls most) over two seconds:
    the gain follows past 2× (its old limit, where the skin round the eye stopped being skin and
    the lid runs ran to their ends: 20 px for 9.6), so the lids are still measured."""
    model, wi = _learn()
    f = EyeFinder(model, wi)
    for k in range(60):
        t = (k + 1) / 60.0
        state = BASE.replace(light=(1.0 - 0.6 * t, 1.0 - 0.5 * t, 1.0 - 0.4 * t))
        res, truth, _, (crop, grey, _) = _find(f, state)
        f.adapt(crop, grey, res)
    res, truth, _, _ = _find(f, state)
    assert f._gain is not None and f._gain.max() > 2.2
    _check(res, truth, lid=1.5)


def test_light_that_keeps_falling_is_followed_without_lagging_behind():
    """The light falling to 40-60 % per channel over two seconds, then staying: at the end of the
    fall the gain is within 5 % of the light (a plain average of the frames was 12 % behind); once
    the light stays, the gain's overshoot stays under 8 % and is gone within two seconds."""
    model, wi = _learn()
    f = EyeFinder(model, wi)
    errs = []
    for k in range(120):
        t = min((k + 1) / 60.0, 1.0)
        light = np.array([1.0 - 0.6 * t, 1.0 - 0.5 * t, 1.0 - 0.4 * t])
        res, _, _, (crop, grey, _) = _find(f, BASE.replace(light=tuple(light)))
        f.adapt(crop, grey, res)
        errs.append(np.log(f._gain_slow * light))  # 0: the gain undoes the light exactly
    errs = np.abs(np.array(errs))
    assert errs[59].max() < math.log(1.05)
    assert errs[60:].max() < math.log(1.08) and errs[-1].max() < 0.01


def _with_glasses(frame: np.ndarray, state: FaceState, thick: float = 0.05) -> np.ndarray:
    """``frame`` with near-black spectacle rims (rounded rectangles 0.76 × 0.5 IPD, ``thick`` IPD
    wide) round both eyes and a bridge between them: the lower rim crosses the skin under the eyes,
    the upper one the skin between the eyes and the brows."""
    lm = face_landmarks(state)
    out = frame.copy()
    d = state.ipd
    t = max(int(round(thick * d)), 1)
    for p in (lm["left_pupil"], lm["right_pupil"]):
        x, y = float(p[0]), float(p[1]) + 0.03 * d
        box = np.array([[x - 0.38 * d, y - 0.25 * d], [x + 0.38 * d, y - 0.25 * d], [x + 0.38 * d, y + 0.25 * d],
                        [x - 0.38 * d, y + 0.25 * d]])
        cv2.polylines(out, [np.round(box).astype(np.int32)], True, (28, 26, 30), t, cv2.LINE_AA)
    a, b = lm["left_pupil"] + [0.38 * d, -0.05 * d], lm["right_pupil"] - [0.38 * d, 0.05 * d]
    cv2.line(out, tuple(np.round(a).astype(int)), tuple(np.round(b).astype(int)), (28, 26, 30), t, cv2.LINE_AA)
    return out


def test_thin_dark_marks_a_rim_and_lashes_but_not_an_iris_or_shading():
    wi = 80.0
    grey = np.tile(np.linspace(120.0, 200.0, 200, dtype=np.float32), (120, 1))  # smooth shading
    grey[30:34, 10:190] = 30.0  # a rim, 4 px (0.05 wi)
    cv2.circle(grey, (100, 80), 8, 40.0, -1)  # an iris, 16 px across
    lines = thin_dark(grey, wi)
    assert lines[31, 20:180].all()
    assert not lines[80, 100] and lines[70:90, 95:105].mean() < 0.1
    assert not lines[50:60].any() and not lines[100:].any()


def test_skin_samples_behind_glasses_hold_no_rim_and_no_rim_edge(monkeypatch):
    """A rim's upper bar over the whole band above each eye (low brows leave it two rows) and its lower
    bar across the band below, their edges blurred as a camera and compression blur them: the band
    above gives no skin at all (it used to give every one of its pixels, the rim's, whenever the rim
    covered most of it), and neither band keeps the rim's soft edge (:data:`RIM_HALO`)."""
    import tracker.eyes as eyes

    wi, skin = 80.0, (120, 140, 190)
    crop = np.empty((110, 200, 3), np.uint8)
    crop[:] = skin
    pupils = np.array([[60.0, 55.0], [140.0, 55.0]])
    for px, py in pupils:
        cv2.circle(crop, (int(px), int(py)), 8, (40, 40, 50), -1)
    crop[39:47] = (28, 26, 30)  # upper bars (0.1 wi) over the bands above
    crop[74:78] = (28, 26, 30)  # lower bars across the bands below (0.15-0.3 wi under the pupils)
    crop = cv2.GaussianBlur(crop, (0, 0), 1.0)
    lines = thin_dark(cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY).astype(np.float32), wi)
    grey = (0.114, 0.587, 0.299)
    skin_grey = float(np.dot(skin, grey))

    def darkest(halo: int) -> dict[str, float]:
        monkeypatch.setattr(eyes, "RIM_HALO", halo)
        groups = _colour_samples(crop, pupils, [8.0, 8.0], [0.2 * wi, 0.2 * wi], wi, lines, glasses=True)[0]
        assert len(groups["above the eyes"]) == 0
        assert len(groups["below the eyes"]) > 100 and len(groups["between the eyes"]) > 50
        return {k: float((g.astype(np.float64) @ grey).min()) for k, g in groups.items() if len(g)}

    assert darkest(0)["below the eyes"] < 0.85 * skin_grey  # the blurred edge passes the line test
    assert min(darkest(RIM_HALO).values()) > 0.93 * skin_grey
    # lines over every band leave no skin at all: then every pixel of the bands, as on a bare face
    every = _colour_samples(crop, pupils, [8.0, 8.0], [0.2 * wi, 0.2 * wi], wi, np.ones_like(lines), glasses=True)[0]
    bare = _colour_samples(crop, pupils, [8.0, 8.0], [0.2 * wi, 0.2 * wi], wi, None, glasses=False)[0]
    assert all(np.array_equal(every[k], bare[k]) and len(bare[k]) for k in bare)


@pytest.mark.parametrize("thick", [0.03, 0.05, 0.08])
def test_spectacle_rims_across_the_skin_bands_do_not_shut_the_eyes(thick):
    """Calibrated and tracked with glasses on: the rims crossing the skin samples under and over the
    eyes are left out of the skin's colour, so the eyes' interior still stands out from it and the
    lids are measured (a skin model that takes the rims for skin calls almost anything skin: the lid
    gap came out 0–1 px and every frame was ``eyes_closed``)."""
    frame, _ = render_face(BASE)
    frame = _with_glasses(frame, BASE, thick)
    model, wi = _learn(frame=frame)
    finder = EyeFinder(model, wi)
    for expr in ("neutral", "wide"):
        state = BASE.with_expression(expr)
        img, _ = render_face(state)
        res, truth, _, _ = _find(finder, state, frame=_with_glasses(img, state, thick))
        assert all(e.open for e in res.eyes)
        _check(res, truth, lid=2.0, brow=math.inf)


def test_the_upper_lid_is_not_looked_for_past_a_spectacle_rim():
    """Behind glasses the lid's skin between the eye and the rim's upper bar can be shadowed (the
    frame, the lens) and no more like the skin round the eyes than the eye is: the colour walk up
    from the iris then runs through it, over the dark bar, to the skin above. The calibrated rim
    stops the walk: the upper lid is read under the bar, not above it, both by colour and by the
    dark rule, and the rim's place comes from the eye's predicted centre (the rim moves with the
    head, not with the gaze)."""
    frame, _ = render_face(BASE)
    model, wi = _learn(frame=_with_glasses(frame, BASE))
    assert all(r is not None for r in model.rims)
    finder = EyeFinder(model, wi)
    x0, y0, w, h = finder.rect
    skin = np.asarray(model.skin_bgr, dtype=np.float64)
    crop = np.empty((h, w, 3), np.uint8)
    crop[:] = np.clip(np.round(skin), 0, 255).astype(np.uint8)
    centres = np.array([[-0.5 * wi - x0, -y0], [0.5 * wi - x0, -y0]])
    for i, (cx, cy) in enumerate(centres):
        top, bottom = cy + model.rims[i][0], cy + model.rims[i][1]  # the bar's rows
        hw = int(0.2 * wi)
        shadow = np.clip(np.round(0.2 * skin), 0, 255).astype(np.uint8)
        crop[int(bottom) : int(cy), int(cx) - hw : int(cx) + hw + 1] = shadow  # the lid's skin in shadow
        crop[int(math.floor(top)) : int(bottom), int(cx) - hw - 8 : int(cx) + hw + 9] = (28, 26, 30)  # the bar
        cv2.circle(crop, (int(cx), int(cy)), int(round(finder.radius[i])), (40, 30, 30), -1)  # the iris
    for i, (cx, cy) in enumerate(centres):
        at = (float(cx), float(cy))
        under = -model.rims[i][1]  # from the iris's centre to the first row under the bar
        for dark in (False, True):
            up, _ = finder.lids(crop, i, at, dark=dark, centre=(cx, cy))
            free, _ = finder.lids(crop, i, at, dark=dark)
            assert 0.5 * finder.radius[i] < up <= under + 0.5, (i, dark, up, under)
            assert free >= up
        # the dark rule takes the bar for the eye's inside: without the rim the run goes on over it
        assert finder.lids(crop, i, at, dark=True)[0] > under + 2.0
        # the rim stays with the head: an iris looking up does not carry it up with it
        up_gaze, _ = finder.lids(crop, i, (at[0], at[1] - 3.0), dark=True, centre=(cx, cy))
        assert up_gaze <= under - 3.0 + 0.5


def test_mirrored_sides_even_out_the_sides_but_keep_the_iris():
    """Beyond the radius a quarter of the mirror image comes in (a streak on one side is three
    quarters as strong there and a quarter as strong on the other); the iris's columns, its
    off-centre catch-light among them, are kept as they were."""
    pic = np.full((9, 31), 100.0, np.float32)
    pic[:, 8:23] = 30.0  # an iris of radius 7 in the middle (column 15)
    pic[4, 17] = 250.0  # its catch-light, right of the centre
    pic[:, 1:4] = 200.0  # a bright streak on the left side only
    out = mirrored_sides(pic, 7.0, 0.25)
    assert np.array_equal(out[:, 8:23], pic[:, 8:23])
    assert out[0, 2] == pytest.approx(0.75 * 200.0 + 0.25 * 100.0)
    assert out[0, 28] == pytest.approx(0.75 * 100.0 + 0.25 * 200.0)
    assert np.array_equal(mirrored_sides(pic, 7.0, 0.0), pic)


def _hair_over_temples(frame: np.ndarray, state: FaceState) -> np.ndarray:
    """``frame`` with dark hair (near-black, as dark as the rims) hanging down both sides of the face
    from the brows to below the eyes, over the rims' outer sides: a rim there is no thin line, and
    the ring :func:`spectacle_rims` looks for is broken."""
    lm = face_landmarks(state)
    out = frame.copy()
    d = state.ipd
    for p, side in ((lm["left_pupil"], -1.0), (lm["right_pupil"], 1.0)):
        x0, x1 = sorted((float(p[0]) + side * 0.34 * d, float(p[0]) + side * 0.8 * d))
        y0, y1 = float(p[1]) - 0.45 * d, float(p[1]) + 0.2 * d
        cv2.rectangle(out, (int(round(x0)), int(round(y0))), (int(round(x1)), int(round(y1))), (22, 24, 30), -1)
    return out


def test_rims_broken_by_dark_hair_are_still_left_out_of_the_skin():
    """Thick rims whose outer sides lie under dark hair: no rim goes round an eye, but the lower bars
    cross the skin band under each eye, and that band alone says glasses (:data:`RIM_BAR`). Without
    it the bars were taken for skin, calibration's lid gap came out at its floor and almost every frame
    of such a copy of a shared clip was ``eyes_closed`` (22 % lost)."""
    thick = 0.05
    wi = 80.0
    frame, _ = render_face(BASE)
    frame = _hair_over_temples(_with_glasses(frame, BASE, thick), BASE)
    lm = face_landmarks(BASE)
    ff = FaceFrame.from_pupils(tuple(lm["left_pupil"]), tuple(lm["right_pupil"]), wi)
    rect = calibration_crop(wi)
    crop = cv2.cvtColor(ff.crop(frame, rect), cv2.COLOR_BGR2GRAY).astype(np.float32)
    pupils = np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]]) - np.array(rect[:2], dtype=np.float64)
    assert spectacle_rims(crop, pupils, wi) == [None, None]
    model, wi = _learn(frame=frame)
    finder = EyeFinder(model, wi)
    for expr in ("neutral", "wide"):
        state = BASE.with_expression(expr)
        img, _ = render_face(state)
        res, truth, _, _ = _find(finder, state, frame=_hair_over_temples(_with_glasses(img, state, thick), state))
        assert all(e.open for e in res.eyes)
        _check(res, truth, lid=2.0, brow=math.inf)


@pytest.mark.parametrize("thick", [0.03, 0.05, 0.08])
def test_a_spectacle_rim_under_the_brows_is_found_and_left_out_of_them(thick):
    """The rims go round each eye, so their upper bar is found (and nothing on a bare face: the
    lashes, the brows and the lids go round no eye that far out); filled in, the brows are read and
    follow the face (a rim darker than the brow and moving with the head held the brow's
    cross-section on the rim: a raised brow read as unmoved)."""
    wi = 80.0
    plain, _ = render_face(BASE)
    frame = _with_glasses(plain, BASE, thick)
    for img, has in ((plain, False), (frame, True)):
        lm = face_landmarks(BASE)
        ff = FaceFrame.from_pupils(tuple(lm["left_pupil"]), tuple(lm["right_pupil"]), wi)
        rect = calibration_crop(wi)
        crop = cv2.cvtColor(ff.crop(img, rect), cv2.COLOR_BGR2GRAY).astype(np.float32)
        pupils = np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]]) - np.array(rect[:2], dtype=np.float64)
        rims = spectacle_rims(crop, pupils, wi)
        if not has:
            assert rims == [None, None]
            continue
        bar = -(0.25 - 0.03) * wi  # the upper bar's middle, from the pupil
        for r in rims:
            assert r is not None and r[0] < bar < r[1] and r[1] - r[0] <= thick * wi + 5
    model, wi = _learn(frame=frame)
    assert all(r is not None for r in model.rims)
    assert EyeModel.from_dict(model.to_dict(), model.images()).rims == model.rims
    finder = EyeFinder(model, wi)
    for expr in ("neutral", "brows_up", "brows_angry"):
        state = BASE.with_expression(expr)
        img, _ = render_face(state)
        res, truth, _, _ = _find(finder, state, frame=_with_glasses(img, state, thick))
        _check(res, truth, lid=2.0, brow=2.0)


def test_a_dark_iris_near_the_skins_colour_is_inside_the_walk():
    # an iris 3 from the skin by colour (under the ramp's middle 3.5) but dark: by colour alone the
    # walk ends at once; with the dark rule as its floor it crosses the iris and goes on by colour
    # through the white (6) to the lid's skin (0.5)
    walk = [3.0] * 4 + [6.0] * 2 + [0.5] * 6
    assert walk_length(walk, 2.0, 5.0, 3, 4.5) < 1.0
    assert walk_length(walk, 2.0, 5.0, 3, 4.5, floor=[1.0] * 4) == pytest.approx(5.5, abs=0.3)
    # the floor only lifts: a walk already interior by colour is unchanged, and a floor past the
    # skin does not carry the run on
    plain = [9.0] * 4 + [0.5] * 6
    assert walk_length(plain, 2.0, 5.0, 3, 4.5, floor=[0.0] * 4) == walk_length(plain, 2.0, 5.0, 3, 4.5)
    assert walk_length(walk, 2.0, 5.0, 3, 4.5, floor=[1.0, 1.0]) < 2.0


def test_the_lid_walks_take_the_dark_rule_only_within_the_iris_floor(finder):
    # a strip whose eye point is on a dark iris that the colour walk calls skin: the dark rule lifts
    # the samples within IRIS_FLOOR radii of it and no further (a lash line on the rim stays out)
    i, c = 0, 40
    r = finder.radius[i]
    nr = int(math.floor(IRIS_FLOOR * r)) + 1
    dist = [3.0] * 81
    dark = [1.0] * 81  # everything dark: only the floor's reach may count
    up0, down0 = finder._lid_walks(dist, c, i, (10.0, float(c)))
    up1, down1 = finder._lid_walks(dist, c, i, (10.0, float(c)), dark)
    assert up0 < 1.0 and down0 < 1.0
    assert down1 == pytest.approx(nr - 0.5, abs=0.01)
    assert up1 == pytest.approx(max(nr - 0.5 - finder.model.lash[i], 0.0), abs=0.01)


def _low_res(img: np.ndarray, factor: float) -> np.ndarray:
    """``img`` as a camera ``factor`` times coarser sees it, scaled back up: grey at that resolution,
    colour (Cr, Cb) at half of it, as video keeps it."""
    h, w = img.shape[:2]
    small = cv2.resize(img, (int(round(w / factor)), int(round(h / factor))), interpolation=cv2.INTER_AREA)
    ycc = cv2.cvtColor(small, cv2.COLOR_BGR2YCrCb)
    sh, sw = ycc.shape[:2]
    for ch in (1, 2):
        half = cv2.resize(ycc[..., ch], (sw // 2, sh // 2), interpolation=cv2.INTER_AREA)
        ycc[..., ch] = cv2.resize(half, (sw, sh), interpolation=cv2.INTER_LINEAR)
    return cv2.resize(cv2.cvtColor(ycc, cv2.COLOR_YCrCb2BGR), (w, h), interpolation=cv2.INTER_LINEAR)


_GREEN_IRIS = (110, 140, 130)
_GREEN_STYLE = STYLES["realistic"].replace(iris=_GREEN_IRIS, pupil=(80, 90, 90), limbus=1.0, catchlight=False)


def _green_eyes_small(state: FaceState, factor: float = 2.0) -> np.ndarray:
    """A face whose grey-green irises are not much darker than the skin (the dark rule is off for
    them) and whose lower halves, lit from above, are nearly the skin's colour, seen ``factor``
    times coarser (2: 40 px between the eyes)."""
    img, _ = render_face(state, _GREEN_STYLE)
    lm = face_landmarks(state)
    yy, xx = np.mgrid[0 : img.shape[0], 0 : img.shape[1]]
    for side in ("left", "right"):
        x, y = lm[f"{side}_pupil"]
        r = 0.09 * state.ipd
        lit = (np.hypot(xx - x, yy - y) <= r) & (yy > y + 0.25 * r) & (np.abs(img.astype(int) - _GREEN_IRIS).sum(-1) < 40)
        img[lit] = (125, 158, 200)
    return _low_res(img, factor)


def test_a_light_iris_at_low_resolution_keeps_the_lower_lid_walk_going_to_the_lid():
    """A light iris whose lower half is lit nearly to the skin's colour, at 38-44 px between the
    eyes: the skin's colour bleeding into that half put it under the walk's ramp and the lower walk
    ended inside the iris (3.8-6 px, on average 0.15 px lower when the lid went 1.9 px lower). The
    rows that still look more like the calibrated iris than the skin carry the walk on to the lid."""
    errors, moves = [], []
    for factor in (1.8, 1.9, 2.0, 2.1):
        model, wi = _learn(frame=_green_eyes_small(BASE, factor))
        assert model.skin.dark < 0 and model.iris_colour is not None  # a light iris: no dark rule
        finder = EyeFinder(model, wi)
        lower = {}
        for expr in ("neutral", "wide"):  # the lid over the iris's bottom (6.4 px, radius 7), 1.9 px lower
            state = BASE.with_expression(expr)
            res, truth, _, _ = _find(finder, state, frame=_green_eyes_small(state, factor))
            lower[expr] = [(e.lower, truth[s]["lid_lower"][1] - truth[s]["pupil"][1]) for e, s in zip(res.eyes, ("left", "right"))]
        errors += [ours - true for ours, true in lower["neutral"]]
        moves += [w - n for (n, _), (w, _) in zip(lower["neutral"], lower["wide"])]
    assert abs(np.mean(errors)) <= 1.1, errors  # -0.7; without the iris's likeness -1.9
    assert np.mean(moves) >= 0.9, moves  # the lid moved 1.9 px: 1.4; without 0.15


def test_the_iris_likeness_is_only_for_light_irises_and_only_within_the_radius(finder):
    # the default performer's dark iris has the dark rule: no likeness floor
    assert finder.skin.dark > 0 and finder._iris_likeness(np.zeros((3, 1, 3), np.float32), None, [0.0] * 3) is None
    model, wi = _learn(frame=_green_eyes_small(BASE))
    f = EyeFinder(model, wi)
    i, c = 0, 40
    nr = int(math.floor(f.radius[i])) + 1
    dist = [3.0] * 81  # under the ramp everywhere
    up0, down0 = f._lid_walks(dist, c, i, (10.0, float(c)))
    up1, down1 = f._lid_walks(dist, c, i, (10.0, float(c)), None, [1.0] * 81)
    assert down0 < 1.0 and down1 == pytest.approx(nr - 0.5, abs=0.01)
    assert up1 == pytest.approx(max(nr - 0.5 - model.lash[i], 0.0), abs=0.01)
    # a row of the iris's own colour is the iris; the skin's colour is not
    from tracker.eyes import _YCC

    col = np.array([[np.linalg.solve(_YCC, model.iris_colour[0])], [np.linalg.solve(_YCC, model.skin.mean)]], np.float32)
    dist = f.skin.distances(col)[0]
    like = f._iris_likeness(col, None, dist)
    assert like[0] == 1.0 and like[1] == 0.0


def test_the_iris_colour_round_trips_and_an_older_model_goes_without_it():
    model, wi = _learn(frame=_green_eyes_small(BASE))
    d = json.loads(json.dumps(model.to_dict()))
    m2 = EyeModel.from_dict(d, model.images())
    assert np.allclose(m2.iris_colour[0], model.iris_colour[0], atol=1e-3)
    assert np.allclose(m2.iris_colour[1], model.iris_colour[1], atol=1e-3)
    d.pop("iris_colour")
    old = EyeModel.from_dict(d, model.images())
    assert old.iris_colour is None and EyeFinder(old, wi)._iris_M is None
    for bad in ({"mean": [1, 2], "cov": np.eye(3).tolist()}, {"mean": [1, 2, 3], "cov": (-np.eye(3)).tolist()}, "green"):
        d["iris_colour"] = bad
        with pytest.raises(EyeModelError) as e:
            EyeModel.from_dict(d, model.images())
        assert "\n" not in str(e.value)


@pytest.mark.parametrize("key,value", [("brow_profiles", 1e39), ("brow_heights", float("inf")), ("lash", float("nan")),
                                       ("lid_open", 1e400)])
def test_an_eye_model_with_a_number_past_float_range_is_refused_in_one_line(key, value, recwarn):
    """A calibration file edited or damaged to hold a number no float32 (or no float) holds: one
    line naming what is wrong, not an infinite brow profile that turns every correlation into NaN
    (nor a cast's overflow warning)."""
    model, _ = _learn()
    d = json.loads(json.dumps(model.to_dict()))
    if key == "brow_profiles":
        d[key][0][0] = value
    else:
        d[key][1] = value
    with pytest.raises(EyeModelError) as e:
        EyeModel.from_dict(d, model.images())
    assert "\n" not in str(e.value) and "finite" in str(e.value)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_limbus_below_is_how_far_down_the_edge_shows_on_both_sides():
    """Pure cases of :func:`limbus_below`: on each side the last angle before the edge on the circle
    is under the level or under :data:`LIMBUS_INNER` of a step inside it; the two sides' mean."""
    n = len(ARC_DEGREES)
    at = {a: k for k, a in enumerate(ARC_DEGREES.tolist())}
    ring, inner = np.full((2, n), 10.0), np.zeros((2, n))
    assert limbus_below(ring, inner, 5.0) == 90.0  # seen all the way down
    ring[0, at[35.0]:] = 2.0  # right side hidden from 35° down
    assert limbus_below(ring, inner, 5.0) == pytest.approx(0.5 * (30.0 + 90.0))
    inner[1, at[60.0]:] = 10.0 / LIMBUS_INNER + 1.0  # left side: a stronger edge inside the circle from 60°
    assert limbus_below(ring, inner, 5.0) == pytest.approx(0.5 * (30.0 + 55.0))
    ring[:, at[0.0]] = 0.0  # nothing at the pupil's row: nothing seen below it
    assert limbus_below(ring, inner, 5.0) == 0.0
    ring[:] = 10.0
    ring[:, at[-10.0]] = 0.0  # above the pupil's row does not count
    assert limbus_below(ring, np.zeros((2, n)), 5.0) == 90.0
    assert limbus_sides(np.full((2, n), 7.0)) == 7.0


def _lower_lidded_eyes(f: EyeFinder, centres, lid: float, iris: float = 90.0, skin: float = 170.0) -> np.ndarray:
    """A grey eye crop (``f.rect``): skin, two white almonds with irises (``f``'s radii, grey ``iris``)
    at ``centres``, each almond's lower edge — the lower lid, skin lighter than the iris — ``lid`` px
    below its iris's centre; the upper lid high above the iris."""
    x0, y0, w, h = f.rect
    img = np.full((h, w), skin, np.float32)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    for (cx, cy), r in zip(centres, f.radius):
        eye = (np.abs(xx - cx) < 2.6 * r) & (yy > cy - 1.6 * r) & (yy < cy + lid)
        img[eye] = 215.0
        img[eye & (np.hypot(xx - cx, yy - cy) <= r)] = iris
    return cv2.GaussianBlur(img, (0, 0), 1.0)


def _edge_calibrated(f: EyeFinder, centres, **look) -> EyeFinder:
    """``f``'s model with its irises' edge strength measured on drawn wide-open eyes
    (:func:`_lower_lidded_eyes` with ``look``), as calibration measures it on the clicked frame."""
    grey = _lower_lidded_eyes(f, centres, 1.8 * f.radius[0], **look)
    limbus = [limbus_sides(f.limbus_steps(grey, c, r)[0]) for c, r in zip(centres, f.radius)]
    return EyeFinder(dataclasses.replace(f.model, limbus=limbus), f.wi)


@pytest.mark.parametrize("share", [0.3, 0.5, 0.7, 1.3, 1.8])
@pytest.mark.parametrize("light_lid", [False, True])
def test_the_lower_lid_lies_at_least_as_low_as_the_iris_edge_shows(finder, share, light_lid):
    """The lower lid hides the iris's edge from where it crosses the circle down: the floor is the
    radius times the sine of how far down the edge shows — under the lid, never more than a pixel past
    it, whether the lid crosses the iris or runs below it (then the floor is the radius). A lid lit
    brighter than the white, over a dark iris: its margin's step, blurred, reaches the circle from
    inside it, and only the stronger step inside (:data:`LIMBUS_INNER`) keeps the floor within a
    quarter of the radius past the lid (without it: the whole radius for a lid at 0.7 of it)."""
    x0, y0, _, _ = finder.rect
    wi = finder.wi
    centres = [(-0.5 * wi - x0 + 0.4, -y0 - 0.3), (0.5 * wi - x0 - 0.2, -y0 + 0.2)]
    look = dict(iris=60.0, skin=230.0) if light_lid else {}
    f = _edge_calibrated(finder, centres, **look)
    r = f.radius[0]
    grey = _lower_lidded_eyes(f, centres, share * r, **look)
    for i, c in enumerate(centres):
        floor = f._lower_floor(grey, i, c)
        if share < 1.0:
            past = 0.25 * r if light_lid else 1.0
            assert share * r - 0.3 * r <= floor <= share * r + past, (share, floor)
        else:
            assert floor == pytest.approx(r, abs=0.05), (share, floor)


def test_a_lit_iris_as_pale_as_the_lid_still_has_its_lower_lid_found(finder):
    """An iris as light as the lid's skin: no step where the lid covers it, so the edge shows only
    against the white — the floor still follows the lid; and a shut eye (skin with a lash line, no
    iris) and a face without a calibrated edge have none."""
    x0, y0, _, _ = finder.rect
    wi = finder.wi
    centres = [(-0.5 * wi - x0, -y0), (0.5 * wi - x0, -y0)]
    look = dict(iris=150.0, skin=150.0)
    f = _edge_calibrated(finder, centres, **look)
    r = f.radius[0]
    grey = _lower_lidded_eyes(f, centres, 0.6 * r, **look)
    assert 0.3 * r <= f._lower_floor(grey, 0, centres[0]) <= 0.6 * r + 1.0
    shut = np.full_like(grey, 150.0)
    for cx, cy in centres:
        shut[int(cy) - 1 : int(cy) + 2, int(cx - 2 * r) : int(cx + 2 * r)] = 40.0
    shut = cv2.GaussianBlur(shut, (0, 0), 1.0)
    assert f._lower_floor(shut, 0, centres[0]) == 0.0
    model = dataclasses.replace(f.model, limbus=None)
    assert EyeFinder(model, wi)._lower_floor(grey, 0, centres[0]) == 0.0


def test_a_narrowed_eye_is_reported_partly_at_the_middle_of_what_shows(finder, monkeypatch):
    """An open eye whose lids have narrowed (to 70 % of the calibrated gap: a frown, eyes lowered)
    is reported halfway between the iris found and the middle of what shows between the lids
    (``shown``, :data:`~tracker.eyes.SHOWN_CLOSING`): the lids cut the iris's disc and its search
    rides the lash line, the visible eye's middle does not (a shared clip's lowered eyes: pupil
    error 3.5 → 2 % of the eye distance). The eye point the tracker follows stays on the iris, and
    an eye open as calibrated is reported there."""
    import tracker.eyes as E

    monkeypatch.setattr(E, "CLEAR_IRIS", (1.5, 2.0))  # the gap decides, whatever the picture says
    state = dataclasses.replace(BASE, gaze_x=0.06)
    full = E.EyeFinder._both_lids
    res, *_ = _find(finder, state)
    assert all(e.shown == pytest.approx((e.x, e.y)) for e in res.eyes)
    monkeypatch.setattr(E.EyeFinder, "_both_lids", lambda self, *a, **k: [
        (u, d, 0.7 * self.model.lid_open[i]) for i, (u, d, _) in enumerate(full(self, *a, **k))])
    res2, _, _, (crop, _, _) = _find(finder, state)
    for i, (e, e0) in enumerate(zip(res2.eyes, res.eyes)):
        assert (e.x, e.y) == pytest.approx((e0.x, e0.y))  # the eye point: still the iris
        slit = finder._slit(crop, (e.x, e.y), finder._eye_gain(i, finder._gain))
        half = (0.5 * (e.x + slit[0]), 0.5 * (e.y + slit[1]))
        assert math.hypot(slit[0] - e.x, slit[1] - e.y) > 1.0  # (else this case shows nothing)
        assert math.hypot(e.shown[0] - half[0], e.shown[1] - half[1]) < 0.3
