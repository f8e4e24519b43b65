"""The mouth finder's pieces on synthetic frames and profiles: the per-frame sums against the
direct means they replace, the corner search, the vertical split on open and pressed mouths, the
working scale and the last frame's mouth moved into a new crop."""

import math

import numpy as np
import pytest

from tracker.colour_model import lut_index
from tracker.mouth_finder import WORK_IPD, MouthFinder, _edge_shift, body_middle
from tracker.mouth_model import MouthModel, _inside, band_columns, corner_distance, corner_search, line_columns, profile_features

from test_mouth_finder import BASE, WI, _calibrate, _crop, _frame_of, render_face


@pytest.fixture(scope="module")
def finder_and_crop():
    model, centre = _calibrate()
    img, _ = render_face(BASE.with_expression("ah"))
    crop, origin = _crop(img, _frame_of(BASE), centre)
    finder = MouthFinder(model, WI)
    small = np.ascontiguousarray(crop[::2, ::2])
    return finder, small, tuple(np.array(centre) - origin)


def test_profile_from_the_integral_image_is_the_band_mean(finder_and_crop):
    finder, small, _ = finder_and_crop
    maps = finder.prepare(small)
    for x in (10.0, 37.4, float(small.shape[1] - 3)):
        f, inside = finder.profile(maps, x)
        x0, x1 = band_columns(x, finder.half, small.shape[1])
        direct = profile_features(small[:, x0:x1].astype(np.float32).mean(axis=1), finder.model.skin_level)
        assert np.allclose(f, direct, atol=1e-3)
        assert inside.shape == (small.shape[0],) and 0.0 <= inside.min() and inside.max() <= 1.0


def test_line_columns_from_the_running_sums_match_the_direct_ones(finder_and_crop):
    finder, small, _ = finder_and_crop
    maps = finder.prepare(small)
    ys = np.full(20, 30.0) + np.arange(20) % 3  # a line a little wavy, well inside the crop
    for step in (-1, 1):
        fast = finder._line_columns(maps, 38 + step * np.arange(len(ys)), ys)
        slow = line_columns(small, 38, ys, step, finder.a1, finder.a2, finder.model.skin_level)
        assert np.allclose(fast, slow, atol=1e-3)


def _corner_reference(d, lo, hi, run, body):
    """The corner search written plainly with numpy (the finder's runs in plain Python)."""
    from tracker.mouth_model import BODY_SHARE, CHEEK_FAR, CHEEK_LEVEL

    n = len(d)
    level = max(CHEEK_LEVEL, BODY_SHARE * float(np.sort(d[body[0] : body[1]])[(body[1] - body[0]) // 2]))
    a, b = max(int(lo), 1), min(int(hi), n - 2)
    level = max(level, CHEEK_FAR * float(d[a : b + 1].min()))
    gain = np.cumsum(np.minimum(d, 5.0 * level) - level)
    cheek = d < level
    runs = np.zeros(n + 1, int)
    for i in range(n - 1, -1, -1):
        runs[i] = runs[i + 1] + 1 if cheek[i] else 0
    need = min(run, n - 1 - b + run)
    ends = [i for i in range(a, b + 1) if not cheek[i] and runs[i + 1] >= need]
    if not ends and cheek[a : a + need + 1].all():  # the lips ended before lo
        ends = [i for i in range(a - 1, 0, -1) if not cheek[i]][:1]
    k = ends[0] if ends else a + int(np.argmax(gain[a : b + 1]))
    x = float(k)
    if d[k] >= level > d[k + 1]:
        x += (d[k] - level) / (d[k] - d[k + 1])
    return x, float(gain[k])


def test_corner_distance_matches_the_plain_reference():
    rng = np.random.default_rng(7)
    for _ in range(200):
        n = int(rng.integers(20, 45))
        end = int(rng.integers(6, n - 4))
        d = np.concatenate([rng.uniform(10, 60, end), rng.uniform(0, 8, n - end)])
        d[rng.integers(0, n)] = rng.uniform(0, 80)  # a blotch anywhere
        got = corner_distance(d, 4, n - 3, 3, (2, 9))
        want = _corner_reference(d, 4, n - 3, 3, (2, 9))
        assert got == pytest.approx(want, abs=1e-9)



def test_corner_search_says_whether_the_cheek_was_seen_past_the_corner():
    """With a run of cheek-like columns in reach the corner is where it starts (seen); with none —
    the line ran on into hair or a collar as unlike the cheek as the lips — the corner is only where
    the sum of unlikeness stopped growing (not seen). ``corner_distance`` is the same without the flag."""
    rng = np.random.default_rng(3)
    lips = rng.uniform(20, 60, 14)
    seen = corner_search(np.concatenate([lips, rng.uniform(0, 3, 20)]), 4, 30, 3, (2, 9))
    assert seen[2] and 13.0 <= seen[0] <= 15.0
    hair = corner_search(np.concatenate([lips, rng.uniform(15, 40, 20)]), 4, 30, 3, (2, 9))
    assert not hair[2]
    short = corner_search(np.full(6, 30.0), 4, 30, 3, (2, 9))
    assert not short[2]
    for d in (np.concatenate([lips, rng.uniform(0, 3, 20)]), np.concatenate([lips, rng.uniform(15, 40, 20)])):
        assert corner_distance(d, 4, 30, 3, (2, 9)) == corner_search(d, 4, 30, 3, (2, 9))[:2]


def test_lips_that_end_before_the_nearest_corner_allowed_still_see_the_cheek():
    """The line can start well off the mouth's middle (the mouth moved sideways against the head's
    prediction, or pursed): on the short side the lips end before ``lo`` and every column from there on
    is cheek. That corner is where the lips end, with the cheek seen — not the far end of the search
    with the cheek "never seen", which made a mouth twice as wide and refused it (expr_d6, 7 frames of
    the shared clips, 29 of their bearded copies)."""
    lips = [117.0, 165.0, 160.0, 70.0, 22.0, 8.0]
    d = np.array(lips + [0.5] * 30)
    x, gain, seen = corner_search(d, 6, 36, 3, (2, 9))
    assert seen
    assert 5.0 < x < 6.0  # between the last lip column (8) and the first cheek one, where d crosses the level
    assert gain > 0.0
    # one cheek-like column at lo with lips again after it is not the cheek: the search runs on as before
    blotch = np.array(lips + [0.5] + [30.0] * 6 + [0.5] * 23)
    assert corner_search(blotch, 6, 36, 3, (2, 9))[0] > 10.0
    # nothing unlike the cheek before lo either: no mouth on this side to end, the old answer stands
    flat = np.full(36, 0.5)
    assert not corner_search(flat, 6, 30, 3, (2, 9))[2]


def _profile(rows, finder):
    """A profile (features, inside) from a list of (kind, count): kinds are the model's classes."""
    cls = np.asarray(finder.model.classes)
    feats, inside = [], []
    for kind, k in rows:
        if kind == "inside":
            f, i = np.array([2.0, 0.0, 0.0]), 1.0
        elif kind == "tongue":
            f, i = cls[2, 0] + np.array([6.0, 0.0, 0.0]), 0.0  # lower-lip coloured, brighter
        elif kind == "skin_tongue":
            f, i = cls[4, 0] + np.array([-1.0, 0.5, 0.0]), 0.0  # as pale as the skin round the mouth
        elif kind == "teeth":
            f, i = cls[0, 0], 1.0  # as pale and grey as the skin above the lips, but the inside's
        elif kind == "lipstick_dark":
            f, i = cls[1, 0] * np.array([0.6, 1.0, 1.0]), 1.0  # the dark inside: as red as the lips, darker
        elif kind == "shaded_chin":
            f, i = cls[3, 0] + np.array([-2.5, 1.0, 0.0]), 0.0  # the chin under a dropped jaw, in shadow
        else:
            f, i = cls[{"skin_up": 0, "lip_up": 1, "lip_down": 2, "skin_down": 3}[kind], 0], 0.0
        feats += [f] * k
        inside += [i] * k
    return np.array(feats, np.float32), np.array(inside, np.float32)


def test_vertical_split_counts_the_inside_and_a_tongue_in_an_open_mouth(finder_and_crop):
    finder = finder_and_crop[0]
    tu, td = int(round(finder.t_up)), int(round(finder.t_dn))
    rows = [("skin_up", 20), ("lip_up", tu), ("inside", 4), ("tongue", 6), ("inside", 2), ("lip_down", td), ("skin_down", 20)]
    f, inside = _profile(rows, finder)
    top_true, bottom_true = 20, 20 + tu + 12 + td
    line = 20 + tu + 6
    gap_top, gap_bottom, top, bottom, _, _ = finder.vertical(f, inside, line)
    assert abs(top - (top_true - 0.5)) <= 1.5 and abs(bottom - (bottom_true - 0.5)) <= 1.5
    assert gap_top < line < gap_bottom


def test_pressed_lips_are_not_an_open_mouth(finder_and_crop):
    """Lip rows and no inside: the lips are closed, the outer edges are those of the two lips."""
    finder = finder_and_crop[0]
    tu, td = int(round(finder.t_up)), int(round(finder.t_dn))
    rows = [("skin_up", 20), ("lip_up", tu), ("lip_down", td), ("skin_down", 25)]
    f, inside = _profile(rows, finder)
    _, _, top, bottom, _, _ = finder.vertical(f, inside, 20 + tu)
    assert abs((bottom - top) - (tu + td)) <= 2.0


def test_a_large_crop_is_shrunk_to_the_working_scale_and_the_result_scaled_back():
    model, centre = _calibrate()
    img, _ = render_face(BASE)
    crop, origin = _crop(img, _frame_of(BASE), centre)
    finder = MouthFinder(model, WI)
    assert finder.s == pytest.approx(WORK_IPD / WI) and finder.wi == pytest.approx(WORK_IPD)
    res = finder.find(crop, tuple(np.array(centre) - origin))
    assert res is not None and res.shape == crop.shape[:2] and res.blob.shape == crop.shape[:2]
    cx, cy = res.centre
    assert abs(cx - (centre[0] - origin[0])) < 3.0 and abs(cy - (centre[1] - origin[1])) < 3.0
    assert np.all(res.polygon[:, 0] >= res.left[0] - 1e-6) and np.all(res.polygon[:, 0] <= res.right[0] + 1e-6)


def test_shifted_moves_every_point_and_keeps_the_opening():
    model, centre = _calibrate()
    img, _ = render_face(BASE.with_expression("ah"))
    crop, origin = _crop(img, _frame_of(BASE), centre)
    res = MouthFinder(model, WI).find(crop, tuple(np.array(centre) - origin))
    moved = MouthFinder.shifted(res, 3.0, -2.0)
    assert moved.centre == pytest.approx((res.centre[0] + 3.0, res.centre[1] - 2.0))
    assert moved.left == pytest.approx((res.left[0] + 3.0, res.left[1] - 2.0))
    assert moved.gap_top == pytest.approx(res.gap_top - 2.0) and moved.gap_bottom == pytest.approx(res.gap_bottom - 2.0)
    assert np.allclose(moved.polygon, res.polygon + (3.0, -2.0))
    assert moved.lip_upper == res.lip_upper and moved.lip_lower == res.lip_lower and math.isclose(moved.width, res.width)


def test_outlines_through_the_same_corners_at_once_match_one_at_a_time():
    from tracker.mouth_model import lens_outline, lens_outlines

    both = lens_outlines((10.0, 30.0), (60.0, 33.0), (20.0, 27.0), (40.0, 35.0), 35.0)
    assert both.shape == (2, 48, 2)
    assert np.allclose(both[0], lens_outline((10.0, 30.0), (60.0, 33.0), 20.0, 40.0, 35.0))
    assert np.allclose(both[1], lens_outline((10.0, 30.0), (60.0, 33.0), 27.0, 35.0, 35.0))
    top = both[0][np.argmin(np.abs(both[0][:24, 0] - 35.0))]
    assert top[1] == pytest.approx(20.0, abs=0.5)  # the upper edge passes through the given row at x_mid


def test_a_skin_coloured_tongue_is_inside_an_open_mouth(finder_and_crop):
    """A tongue as pale as the skin between the teeth and the lower lip, over a chin in the dropped
    jaw's shadow: the lower lip still decides where the mouth ends, not the first skin-like row."""
    finder = finder_and_crop[0]
    tu, td = int(round(finder.t_up)), int(round(finder.t_dn))
    rows = [("skin_up", 20), ("lip_up", tu), ("inside", 3), ("skin_tongue", 9), ("lip_down", td), ("shaded_chin", 20)]
    f, inside = _profile(rows, finder)
    bottom_true = 20 + tu + 12 + td
    _, _, _, bottom, _, _ = finder.vertical(f, inside, 20 + tu + 1)
    assert abs(bottom - (bottom_true - 0.5)) <= 1.5


def test_the_dark_inside_of_a_grin_is_not_a_lipstick_upper_lip(finder_and_crop, monkeypatch):
    """A broad grin: the upper lip stretched to one row, upper teeth as pale as the skin, then the dark
    between the rows of teeth, as red as the lips but darker, then the lower teeth. Read by colour
    alone, the teeth are the skin above an upper lip made of the dark inside (it is nearer the
    calibrated thickness than the stretched lip); rows darker than both lips are not lip
    (:data:`~tracker.mouth_finder.DARK_IN_LIP`), so the upper lip stays the one above the teeth."""
    import tracker.mouth_finder as mf

    finder = finder_and_crop[0]
    tu, td = int(round(finder.t_up)), int(round(finder.t_dn))
    rows = [("skin_up", 20), ("lip_up", 1), ("teeth", 6), ("lipstick_dark", tu), ("teeth", 2),
            ("lip_down", td), ("skin_down", 20)]
    f, inside = _profile(rows, finder)
    line = 20 + 1 + 6
    top = finder.vertical(f, inside, line)[2]
    assert abs(top - 19.5) <= 1.5
    monkeypatch.setattr(mf, "DARK_IN_LIP", 0.0)  # the colours alone: the teeth above are skin
    assert finder.vertical(f, inside, line)[2] > 19.5 + 4


def test_edge_shift_reads_the_lip_share_of_the_rows_at_the_edge():
    lip, skin = np.array([10.0, 20.0, 10.0]), np.array([20.0, 8.0, 6.0])
    f = np.array([skin, skin, lip, lip, lip])
    assert _edge_shift(f, 2, -1, lip, skin) == pytest.approx(0.0)  # a sharp edge between rows 1 and 2
    f[1] = 0.3 * lip + 0.7 * skin  # 30 % of the skin row above is lip: the edge is 0.3 rows out
    assert _edge_shift(f, 2, -1, lip, skin) == pytest.approx(0.3)
    f[1], f[2] = skin, 0.6 * lip + 0.4 * skin  # the outermost lip row is 40 % skin: 0.4 rows in
    assert _edge_shift(f, 2, -1, lip, skin) == pytest.approx(-0.4)
    assert _edge_shift(f, 0, -1, lip, skin) == 0.0  # no row beyond the crop


def test_body_middle_is_the_middle_of_the_run_through_the_line():
    unlike = [0.0] * 30
    unlike[10:16] = [6.0] * 6  # the mouth's rows on this column
    inside = [False] * 30
    middle, height = body_middle(unlike, inside, 12, 8)
    assert middle == pytest.approx(12.5, abs=0.51) and height == pytest.approx(6.0, abs=1.01)
    unlike[16] = 4.5  # a row partly lip below: the lower edge moves down into it
    m2, h2 = body_middle(unlike, inside, 12, 8)
    assert m2 > middle and h2 > height
    assert body_middle([0.2] * 30, inside, 12, 8) is None  # all skin
    far = [0.0] * 30
    far[2:4] = [6.0, 6.0]  # something dark 9 rows from the line is no corner
    assert body_middle(far, inside, 12, 10) is None
    teeth = [False] * 30
    teeth[11:14] = [True] * 3  # teeth between two lip rows: inside-like rows are the mouth's body too
    lips = [0.0] * 30
    lips[10] = lips[14] = 6.0
    m4, h4 = body_middle(lips, teeth, 12, 8)
    assert m4 == pytest.approx(12.5, abs=0.6) and h4 >= 4.0
    assert body_middle([0.0] * 30, teeth, 12, 8) is None  # nothing unlike skin: no mouth to speak of


def test_skin_seen_at_calibration_is_never_teeth():
    """A lit philtrum as bright and colourless as teeth was on the skin round the calibration's mouth:
    its colours are not inside-like, while a bright grey never seen on the skin still is."""
    skin_level, skin_sat = 150.0, 0.12
    highlight = np.array([[[200, 205, 215]]], np.uint8)  # BGR: bright, little colour
    teeth = np.array([[[225, 228, 230]]], np.uint8)
    h, t = int(lut_index(highlight)[0, 0]), int(lut_index(teeth)[0, 0])
    plain = _inside(60.0, skin_level, skin_sat)
    assert plain[h] and plain[t]
    seen = _inside(60.0, skin_level, skin_sat, np.array([h], np.int32))
    assert not seen[h] and seen[t]


def test_skin_bins_survive_a_save_and_old_models_load_without_them(finder_and_crop):
    model = finder_and_crop[0].model
    assert model.skin_bins is not None and len(model.skin_bins) > 0
    again = MouthModel.from_dict(model.to_dict())
    assert np.array_equal(again.skin_bins, model.skin_bins)
    assert np.array_equal(again.inside_table, model.inside_table)
    old = model.to_dict()
    del old["skin_bins"]
    assert MouthModel.from_dict(old).skin_bins is None
    bad = model.to_dict()
    bad["skin_bins"] = [-1]
    with pytest.raises(ValueError, match="skin_bins"):
        MouthModel.from_dict(bad)


def test_the_dark_share_round_the_mouth_survives_a_save_and_old_models_load_without_it(finder_and_crop):
    """``dark_round`` (the share of the skin round the mouth far darker than the lips, 0 on the clean
    synthetic face) is saved; a calibration older than it loads with None, which leaves the open
    mouth's dark rule off; a share outside 0..1 is refused with a one-line error naming it."""
    model = finder_and_crop[0].model
    assert model.dark_round == 0.0
    assert MouthModel.from_dict(model.to_dict()).dark_round == 0.0
    old = model.to_dict()
    del old["dark_round"]
    older = MouthModel.from_dict(old)
    assert older.dark_round is None
    assert MouthFinder(older, WI)._open_table is older.inside_table
    assert MouthFinder(model, WI)._open_table is not model.inside_table
    with pytest.raises(ValueError, match="dark_round"):
        MouthModel.from_dict({**model.to_dict(), "dark_round": 1.5})


def test_one_side_like_its_cheek_does_not_lose_the_mouth(finder_and_crop):
    """A side whose calibrated cheek was in shadow or under hair may look like it later (its
    columns differ little from that cheek): the mouth stays sure while the other side is clear,
    and is not sure when neither is."""
    from tracker.mouth_finder import SCORE_OK
    finder = finder_and_crop[0]
    g = finder.gain0
    args = dict(width=finder.width0, height=0.4 * finder.wi, on_line=(30.0, 24.0), centre=(30.0, 24.0),
                pred=(30.0, 24.0), fit=(1.0, 1.0), previous=None)
    assert finder._score(strength=[-0.1 * g, 2.0 * g], **args) >= SCORE_OK
    assert finder._score(strength=[0.05 * g, 0.1 * g], **args) < SCORE_OK


def test_plain_skin_costs_more_as_lip_than_an_outlier(finder_and_crop):
    """A row that is plainly skin says the lip is not there; a row like nothing calibrated (a
    highlight, a crease) only says the lip looks odd there: as lip, the first costs more."""
    finder = finder_and_crop[0]
    cls = np.asarray(finder.model.classes)
    skin = cls[0, 0]
    odd = cls[1, 0] + np.array([25.0, -15.0, 10.0], np.float32)  # far from every class
    e = finder.row_costs(np.array([skin, odd], np.float32))
    assert e[0, 0] < 1.0 and e[0, 1] > 3.0  # one is skin, the other is not
    assert e[1, 0] > e[1, 1] and e[2, 0] > e[2, 1]


def test_corners_rise_together_and_tilt_only_a_little(finder_and_crop, monkeypatch):
    """One side's lips say its corner is far above the line, the other's say it is where the line
    is: both move by the shared shift, each within a small tilt of it."""
    import tracker.mouth_finder as mf
    finder, small, _ = finder_and_crop
    maps = finder.prepare(small)
    shifts = iter([-6.0] * 3 + [0.0] * 3)  # the left side's lips 6 rows up, the right side's on the line
    monkeypatch.setattr(mf, "body_middle", lambda unlike, inside, y, reach, near_rows=mf.CORNER_NEAR: (y + next(shifts), 4.0))
    left, right = (10.0, 20.0), (40.0, 20.0)  # the traced line at row 20
    yl, yr = finder.corner_heights(maps, left, right)
    assert 0.5 * ((yl - 20.0) + (yr - 20.0)) == pytest.approx(-3.0)  # the mean of the two
    assert yl < yr and yr - yl == pytest.approx(2 * mf.CORNER_TILT * 30.0)  # tilted, a little


def test_a_dark_shadow_above_the_mouth_is_not_its_line():
    """A nose's shadow darker than the closed mouth's gap, a quarter of the eye distance above it:
    the mouth line starts on the mouth, not on the shadow."""
    import cv2
    from test_mouth_finder import _errors, _truth_in_crop
    from tracker.synthetic import face_landmarks
    model, centre = _calibrate()
    img, _ = render_face(BASE)
    lm = face_landmarks(BASE)
    mx, my = lm["mouth"]
    cv2.rectangle(img, (int(mx - 0.25 * WI), int(my - 0.26 * WI)), (int(mx + 0.25 * WI), int(my - 0.23 * WI)), (40, 45, 60), -1)
    ff = _frame_of(BASE)
    crop, origin = _crop(img, ff, centre)
    res = MouthFinder(model, WI).find(crop, tuple(centre - origin))
    ew, eu, el = _errors(res, _truth_in_crop(BASE, ff, origin))
    assert ew < 3.0 and eu < 2.0 and el < 2.0


def test_a_cheek_that_is_not_skin_at_calibration_borrows_the_other_side():
    """Beside a small or turned face the columns where one cheek should be can be hair, a collar or
    the background: that side takes the other side's cheek, and the corners stay on the mouth."""
    import cv2
    from tracker.mouth_model import learn_mouth
    from tracker.synthetic import face_landmarks
    lm = face_landmarks(BASE)
    mx, my = lm["mouth"]
    img, _ = render_face(BASE)
    cv2.rectangle(img, (int(mx - 0.9 * WI), int(my - 0.2 * WI)), (int(mx - 0.58 * WI), int(my + 0.2 * WI)), (120, 140, 60), -1)
    ff = _frame_of(BASE)
    click = ff.to_face(lm["mouth"][None])[0]
    crop, origin = _crop(img, ff, click)
    trace = {}
    model = learn_mouth(crop, tuple(click - origin), WI, _trace=trace)
    assert trace["cheek_skin"]["left"] > 1.0 >= trace["cheek_skin"]["right"]
    assert np.allclose(model.cheek_left, model.cheek_right)
    true_width = float(np.hypot(*(lm["mouth_right"] - lm["mouth_left"]))) * ff.scale
    assert abs(model.width - true_width) < 3.0


@pytest.mark.parametrize("fit, other, borrows", [
    (1.16, 0.04, True),   # expr_d11's shadowed fold, the shared clip: plainly not skin
    (0.82, 0.02, True),   # ... the same with the colours halved: far worse than the other side
    (0.83, 0.15, False),  # ... with the other side in a side light's shade: not far enough apart
    (0.30, 0.02, False),  # a cheek a little off the skin (shading) keeps its own model
    (2.0, 1.5, False),    # neither side is skin: nothing better to borrow
    (math.inf, 0.1, True),  # no cheek columns at all
])
def test_a_cheek_borrows_the_other_sides_when_it_is_not_skin_or_far_worse(fit, other, borrows):
    from tracker.mouth_model import borrows_cheek
    assert borrows_cheek(fit, other) is borrows


@pytest.mark.parametrize("expr", ["ah", "neutral"])
@pytest.mark.parametrize("retrace", [True, False])
def test_a_shadow_under_the_lower_lip_is_not_the_mouth_line(retrace, expr, monkeypatch):
    """An open mouth over a dark shadow under the lower lip, the prediction down on the shadow (the
    jaw's last offset): the mouth is found on the mouth — the lips' opening is above the traced line,
    so the line is traced again from inside it. Without that, the line stays on the shadow."""
    import tracker.mouth_finder as mf

    if not retrace:  # (the corners brought out to the ends of the open mouth's inside find it too)
        monkeypatch.setattr(mf, "RETRACE", 1e9)
        monkeypatch.setattr(mf, "OPEN_ENDS", 1e9)
    dy = _found_on_a_shadowed_mouth(expr)
    assert (dy < 0.1 * WI) == retrace


def _found_on_a_shadowed_mouth(expr: str) -> float:
    """The synthetic face with ``expr`` and a dark shadow drawn under its lower lip, the mouth finder
    predicted down on the shadow: how far (crop px) the found mouth's centre is from the true one
    (inf: none found)."""
    import cv2
    from test_mouth_finder import _truth_in_crop
    from tracker.synthetic import face_landmarks

    model, centre = _calibrate()
    st = BASE.with_expression(expr)
    img, _ = render_face(st)
    lx, ly = face_landmarks(st)["lip_lower"]
    cv2.rectangle(img, (int(lx - 0.3 * WI), int(ly + 0.02 * WI)), (int(lx + 0.3 * WI), int(ly + 0.08 * WI)), (25, 25, 40), -1)
    ff = _frame_of(st)
    crop, origin = _crop(img, ff, centre)
    shadow = ff.to_face(np.array([[lx, ly + 0.08 * WI]]))[0] - origin
    res = MouthFinder(model, WI).find(crop, (float(centre[0] - origin[0]), float(shadow[1])))
    truth = _truth_in_crop(st, ff, origin)
    return abs(res.centre[1] - truth["mouth"][1]) if res is not None else math.inf


def test_a_closed_mouths_one_row_gap_is_an_opening_to_trace_again_from(monkeypatch):
    """The traced line on the shadow under closed lips whose gap the split reads exactly one row
    high: the line is still traced again from that row (the rule once asked for more than one row,
    and a sub-pixel change in the split decided whether the mouth stayed on the shadow)."""
    import tracker.mouth_finder as mf

    vertical = mf.MouthFinder.vertical

    def one_row_gap(self, *a, **k):
        gap_top, gap_bottom, *rest = vertical(self, *a, **k)
        mid = 0.5 * (gap_top + gap_bottom)
        return (mid - 0.5, mid + 0.5, *rest)

    monkeypatch.setattr(mf.MouthFinder, "vertical", one_row_gap)
    assert _found_on_a_shadowed_mouth("neutral") < 0.1 * WI


def _upper_profile(lip_rows: int, shade: list[float]) -> tuple[np.ndarray, int]:
    """Profile features (rows, 3) up from a gap row: skin above, an upper lip ``lip_rows`` thick
    (a little darker and redder), its rows next to the gap darkened by ``shade`` (the line's blur)."""
    skin, lip = np.array([19.0, 12.0, 10.0]), np.array([18.0, 14.0, 10.5])
    gap = 40
    f = np.tile(skin, (60, 1))
    f[gap - lip_rows : gap] = lip
    for k, s in enumerate(shade):
        f[gap - 1 - k, 0] -= s
    f[gap] = (10.0, 14.0, 10.0)
    f[gap + 1 :] = lip
    return f, gap


def test_the_lines_shade_is_not_a_thin_upper_lip():
    """Rows next to the gap darkened by the line's blur make the thinnest lip the search allows split
    best (the shade against the lip): the peak further out, where the lip meets the skin, is the
    edge (expr_d19's clicked calibration took 2.5 px for an upper lip of ~11; its clicked mouth
    opening followed the peer at r 0.80, at 0.91 with this). A lip that really is that thin keeps
    its edge."""
    from tracker.mouth_model import _outer_edge

    f, gap = _upper_profile(11, [4.0, 3.0, 2.0, 1.0])
    assert abs((gap - _outer_edge(f, gap, -1, 0.04, 0.22, WI)) - 11.0) < 1.5
    f, gap = _upper_profile(3, [1.0])
    assert abs((gap - _outer_edge(f, gap, -1, 0.04, 0.22, WI)) - 3.0) < 1.0


# a lower lip as a profile through expr_d6's first frame shows it (features L, c1, c2 per row from the
# gap's last row on, rounded): the line's blurred shade, dark and red, then the lip lit and shaded
# (rows 1-19), then the chin
_D6_LOWER = np.array([
    [8.4, 30.2, 17.7], [10.0, 25.9, 14.9], [11.9, 22.3, 12.4], [13.1, 20.4, 11.1], [14.1, 19.2, 10.4],
    [14.9, 18.2, 9.9], [15.8, 17.3, 9.4], [16.6, 16.5, 9.0], [17.3, 15.9, 8.6], [17.2, 16.0, 8.7],
    [16.5, 16.6, 9.0], [15.8, 17.3, 9.4], [15.3, 17.8, 9.7], [15.1, 17.5, 10.0], [15.0, 16.2, 10.4],
    [14.9, 15.4, 10.7], [15.0, 15.1, 10.7], [15.6, 14.6, 10.3], [16.5, 13.9, 9.8], [17.5, 13.2, 9.3],
    [18.3, 12.6, 8.9], [18.7, 12.3, 8.7], [18.9, 12.2, 8.6], [19.0, 12.1, 8.6], [19.1, 12.0, 8.5],
    [19.2, 11.7, 8.5], [19.4, 10.9, 8.3], [19.6, 10.4, 8.2], [19.8, 10.2, 8.1], [19.9, 10.1, 8.1]])


def test_the_lines_shade_is_not_a_thin_lower_lip():
    """The same near tie under the gap (expr_d6's first frame): the thinnest lip the search allows
    split a little better than the whole lip against the chin on some columns and a little worse on
    others, so which one calibration took turned on a pixel of the click — one copy of the clip
    calibrated a lower lip of 4 px at 80 px between the eyes where the others had 16, and the
    tracker looked for a 4 px lip all clip long (a hand-held camera's copy of expr_d6, ``--auto``:
    its opening followed the peer at r .45; .82 with this). The peak further out is the edge. A
    lower lip that really is that thin keeps its edge."""
    import tracker.mouth_model as mm

    above = np.vstack([np.tile([12.0, 20.0, 12.0], (40, 1)), [[7.8, 31.7, 18.7]]])  # the upper lip, the gap
    gap = len(above)  # _D6_LOWER's first row
    f = np.vstack([above, _D6_LOWER, np.tile(_D6_LOWER[-1], (30, 1))])
    assert 17.0 < mm._outer_edge(f, gap, +1, 0.05, 0.3, WI) - gap < 22.0
    # the rule is what moved it: without the far peak the split at the thinnest lip wins here
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(mm, "EDGE_INTERIOR", 99.0)
        assert mm._outer_edge(f, gap, +1, 0.05, 0.3, WI) - gap < 5.0
    thin = np.vstack([above, _D6_LOWER[:1], np.tile([16.0, 18.0, 10.0], (4, 1)), np.tile(_D6_LOWER[-1], (40, 1))])
    assert abs(mm._outer_edge(thin, gap, +1, 0.05, 0.3, WI) - gap - 4.5) < 1.0


def test_an_upper_lip_edge_not_seen_is_a_thin_lip_not_the_search_floor():
    """When only the line's blurred shade tells the rows apart (a soft or low-resolution picture, a
    lip as pale as the skin) the split improves all the way to the gap and no edge stands out
    further up: the lip is taken as a thin one (UPPER_UNSEEN), not as the thinnest the search
    allows (expr_d19 at half resolution: 0.03 wi, where the tracker then looked for a one-to-three
    px lip for the whole clip and its opening followed the peer at r 0.70; 0.78 with this)."""
    from tracker.mouth_model import UPPER_UNSEEN, _outer_edge

    skin = np.array([19.0, 12.0, 10.0])
    f = np.tile(skin, (60, 1))
    gap = 40
    for k, s in enumerate([5.0, 3.5, 2.4, 1.6, 1.0, 0.6, 0.3]):  # the shade fading into the skin above
        f[gap - 1 - k, 0] -= s
    f[gap] = (10.0, 14.0, 10.0)
    thick = gap - _outer_edge(f, gap, -1, 0.04, 0.22, WI)
    assert abs(thick - UPPER_UNSEEN * WI) < 1e-9
    # a caller with other columns to go by (calibration) hears that there was nothing to measure
    assert math.isnan(_outer_edge(f, gap, -1, 0.04, 0.22, WI, math.nan))
    # a lip with an edge of its own is still measured (the thin one: the test above)
    f, gap = _upper_profile(11, [4.0, 3.0, 2.0, 1.0])
    assert abs((gap - _outer_edge(f, gap, -1, 0.04, 0.22, WI)) - 11.0) < 1.5
    assert abs((gap - _outer_edge(f, gap, -1, 0.04, 0.22, WI, math.nan)) - 11.0) < 1.5


def test_an_upper_lip_edge_the_shade_hides_is_found_by_its_colour():
    """A small, soft or noisy picture spreads the line's shade over a pale upper lip: split on all the
    features the rows improve all the way to the gap, and the lip's edge does not stand out. Its
    colour still ends where the lip does, so the same peak looked for on the colour alone finds it
    (expr_d19 shrunk to 45 % of its size: no column showed the edge, the calibration took a lip of
    0.09 eye distances where the full picture reads 0.14, and the opening followed the peer at r
    0.77; 0.87 with this). Without a visible difference of colour the lip stays unseen."""
    import tracker.mouth_model as mm

    skin = np.array([19.0, 12.0, 10.0])
    f = np.tile(skin, (60, 1))
    gap = 40
    f[gap - 12 : gap, 1:] = (13.4, 10.4)  # the upper lip, 12 rows, a little redder than the skin
    for k, s in enumerate([8.0, 6.0, 4.5, 3.3, 2.4, 1.6, 1.0, 0.6, 0.3]):  # the line's shade
        f[gap - 1 - k, 0] -= s
    f[gap] = (10.0, 14.0, 10.0)
    assert abs((gap - mm._outer_edge(f, gap, -1, 0.04, 0.22, WI, math.nan)) - 12.0) < 1.0
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(mm, "EDGE_CHROMA", False)  # the colour is what found it
        assert math.isnan(mm._outer_edge(f, gap, -1, 0.04, 0.22, WI, math.nan))
    faint = f.copy()
    faint[gap - 12 : gap, 1:] = (12.5, 10.1)  # a lip no visibly redder than the skin
    assert math.isnan(mm._outer_edge(faint, gap, -1, 0.04, 0.22, WI, math.nan))


def test_calibration_takes_the_upper_lip_from_the_columns_that_show_its_edge(monkeypatch):
    """Calibration measures the lips on three columns and takes the median; a column whose upper
    edge it cannot see is no vote for a thin lip (the glasses, pale and half-size copies of
    expr_d19: with one or two of three columns unseen the median fell on UPPER_UNSEEN, about half
    what the full picture reads, and the glasses copy's opening followed the peer at r 0.76
    instead of 0.92)."""
    import tracker.mouth_model as mm
    from test_mouth_finder import _calibrate

    before = _calibrate()[0].thick_up
    monkeypatch.setattr(mm, "UPPER_UNSEEN", 0.2)  # far from the performer's lip, so a vote for it shows
    orig, calls = mm._outer_edge, []

    def two_columns_unseen(f, start, direction, lo, hi, wi, unseen=None):
        if direction < 0:
            calls.append(start)
            if len(calls) in (3, 4):  # the click's column, then the centre's, left and right
                return unseen if unseen is not None else float(start) - mm.UPPER_UNSEEN * wi
        return orig(f, start, direction, lo, hi, wi, unseen)

    monkeypatch.setattr(mm, "_outer_edge", two_columns_unseen)
    after = _calibrate()[0].thick_up
    assert len(calls) == 4
    assert abs(after - before) < 1.0 and abs(after - 0.2 * WI) > 5.0


@pytest.mark.parametrize("shade", [0.0, 0.85])
def test_closed_lips_over_a_lip_coloured_shadow_keep_their_line(shade):
    """Closed lips with the shadowed skin under a full lower lip as brown as the lip (expr_d3's
    calibration): the lower lip measures thicker than any lip. Between closed
    lips the line is sure, so the lip's outer edge comes in to the thickest a lip is and the gap
    stays the line — before, the gap's edge moved down into the lip instead, the lower lip's colour
    came from the shadow, and the tracked lower lip sat 14 % of the eye distance below the peer's
    on 99 % of expr_d3's frames (its opening followed the peer at r 0.86; 0.98 with this)."""
    import cv2

    from tracker.mouth_model import LIP_MAX, SHUT_GAP, learn_mouth
    from tracker.synthetic import face_landmarks

    lm = face_landmarks(BASE)
    img, _ = render_face(BASE)
    (xl, _), (xr, _) = lm["mouth_left"], lm["mouth_right"]
    y_line, y_low = float(lm["mouth"][1]), float(lm["lip_lower"][1])
    if shade:
        lip = img[int(round(0.5 * (y_line + y_low))), int(round(lm["mouth"][0]))].astype(float)
        band = (int(xl + 0.12 * WI), int(round(y_low)) - 1, int(xr - 0.12 * WI), int(round(y_low + 0.16 * WI)))
        cv2.rectangle(img, band[:2], band[2:], tuple(float(v) for v in shade * lip), -1)
    ff = _frame_of(BASE)
    click = ff.to_face(lm["mouth"][None])[0]
    crop, origin = _crop(img, ff, click)
    model = learn_mouth(crop, tuple(click - origin), WI)
    assert model.gap <= SHUT_GAP * WI
    assert abs(model.centre[1] + origin[1] + model.line - ff.to_face(lm["mouth"][None])[0][1]) < 1.5
    assert model.thick_down <= LIP_MAX[1] * WI + 1e-6
    if not shade:
        assert abs(model.thick_down - (y_low - y_line)) < 2.0  # an ordinary lip keeps its own edge


def test_the_gap_between_lips_in_a_beard_does_not_run_on_into_the_moustache():
    """A closed mouth in a full beard: the line between the lips is a faint dip, lighter than the hair
    round the lips, so the profile's median is darker than the gap. Rows "nearly as dark as the gap"
    were then rows darker than it, and the gap ran up through the upper lip's darker top into the
    moustache (the bearded copy of expr_d18 with --auto's mouth point: a 21 px gap at calibration,
    the moustache learned as an upper lip). The gap is the line's row."""
    from tracker.mouth_model import _gap

    lum = np.full(90, 50.0)  # moustache and beard
    lum[40:45] = [60.0, 70.0, 80.0, 88.0, 93.0]  # the upper lip, darker at its top
    lum[45] = 90.0  # the line between the lips
    lum[46:57] = np.linspace(95.0, 118.0, 11)  # the lower lip
    red = np.full(90, -1.0)
    red[40:57] = 8.0
    top, bottom, darkest = _gap(lum, np.zeros(90), 48.0, 80.0, red)
    assert darkest == 45 and top == 45 and bottom == 45
    # a lit face round an open mouth: the dark inside is the gap, as before
    lum = np.full(90, 150.0)
    lum[38:44] = 120.0  # upper lip
    lum[44:56] = 30.0   # the inside
    lum[56:64] = 125.0  # lower lip
    red = np.full(90, -1.0)
    red[38:44] = red[56:64] = 8.0
    top, bottom, _ = _gap(lum, np.zeros(90), 50.0, 80.0, red)
    assert (top, bottom) == (44, 55)


def test_lip_rows_need_two_neighbouring_red_rows():
    """Pure cases of :func:`~tracker.mouth_model.lip_rows`: a column shows the lips where two rows next
    to each other across the line are lip-red; one red row (a hair, a crease) or two apart do not."""
    from tracker.mouth_model import lip_rows

    red = np.zeros((5, 8))
    red[0, 3:5] = 12.0  # two neighbouring rows
    red[1, 3] = 12.0  # one row
    red[2, [1, 5]] = 12.0  # two rows apart
    red[3, 6:8] = 11.9  # just under the need
    red[4, :] = 15.0
    assert lip_rows(red, 12.0).tolist() == [True, False, False, False, True]
    assert lip_rows(np.array([[13.0], [5.0]]), 12.0).tolist() == [True, False]  # one row across the line


def test_the_lips_off_the_lines_bands_still_bound_a_corner_in_hair(finder_and_crop):
    """With hair round the mouth the line can run along a moustache's lower edge, the lips' lens below
    it and thinning towards the corners: its red rows lie past the line's bands, no column showed the
    lips, their end bound no corner and the corners ran on through the hair to the beard's edge (the
    bearded copy of expr_d18: mouth width r 0.43 with the peer). The rows across the line
    (:data:`~tracker.mouth_model.LIP_ROWS`) see them, two neighbouring rows at a time, and a column
    just past the lens, whose run of columns takes a third of its strong red, is not lip."""
    from tracker.mouth_model import lip_columns

    finder = finder_and_crop[0]
    need = finder.lips_red
    assert need is not None
    skin, hair, lip = (150, 170, 210), (60, 72, 84), (40, 20, 225)
    edge = np.mean([lip, skin, skin], axis=0)  # a run of three columns with one of the lens in it
    reds = profile_features(np.array([skin, hair, lip, edge], np.float32), finder.model.skin_level, finder._chroma)[:, 1]
    assert reds[2] >= reds[3] >= need > max(reds[0], reds[1])
    crop = np.empty((40, 64, 3), np.uint8)
    crop[:] = skin
    y = 15
    crop[y - 6 : y + 1] = hair  # a moustache down to the line
    crop[y + 5 : y + 7, 10:30] = lip  # the lens: two rows, past the band below the line
    crop[y + 5, 36:46] = lip  # one red row
    crop[y + 9 : y + 11, 50:60] = lip  # two rows out of reach
    maps = finder.prepare(crop)
    xs = np.arange(2, 62)
    ys = np.full(len(xs), float(y))
    got = finder._red_rows(maps, xs, ys)
    assert got.tolist() == ((xs >= 10) & (xs < 30)).tolist()
    bands = lip_columns(finder._line_columns(maps, xs, ys), need, finder._skin_f, finder._lip_run)
    assert not any(bands)  # the bands alone miss the lens


def test_a_moustache_under_the_nostrils_is_not_an_open_mouth(finder_and_crop):
    """Hair round the mouth (:func:`~tracker.mouth_finder.hair_round`): a moustache is darker than the
    lips, and rows darker than the lips were the mouth's inside wherever they were. With the nostrils'
    red shadow over the moustache, the split took that shadow for the upper lip and the moustache and
    the upper lip for an open mouth's gap (the bearded copy of expr_d3: opening r 0.99 → 0.83). Dark
    rows that look like the skin calibrated above the lips (the hair there) are no inside now."""
    from tracker.mouth_finder import hair_round

    finder = finder_and_crop[0]
    model = finder.model
    cls = np.asarray(model.classes, dtype=np.float64).copy()
    cls[0, 0] = [0.5 * min(cls[1, 0, 0], cls[2, 0, 0]), cls[4, 0, 1] - 2.0, cls[4, 0, 2]]  # hair above the lips
    bearded = MouthModel.from_dict({**model.to_dict(), "classes": cls.tolist(), "dark_round": 0.3, "dark_chin": 0.5})
    assert hair_round(bearded) and not hair_round(model)
    f2 = MouthFinder(bearded, WI)
    tu, td = int(round(f2.t_up)), int(round(f2.t_dn))
    hair = cls[0, 0] + np.array([-2.5, 0.0, 0.0])  # a moustache a little darker than calibrated
    rows = [model.classes[0][0]] * 8 + [cls[1, 0]] * tu + [hair] * 10 + [cls[1, 0]] * tu + [cls[2, 0]] * td + [cls[3, 0]] * 20
    f = np.array(rows, np.float32)
    line = 8 + tu + 10 + tu
    gap_top, gap_bottom, top, bottom, _, _ = f2.vertical(f, np.zeros(len(f), np.float32), line)
    assert gap_bottom - gap_top < 1.0 and abs(top - (line - tu - 0.5)) <= 1.0 and abs(bottom - (line + td - 0.5)) <= 1.0
    f2._hair = False  # the rule as it was: the moustache is an open mouth's inside
    gap_top, _, top, _, _, _ = f2.vertical(f, np.zeros(len(f), np.float32), line)
    assert gap_top < line - tu - 5 and top < 8 + tu
