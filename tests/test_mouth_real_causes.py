"""The mouth's real-face fixes, each on a synthetic case built to show its cause.

* the lower lip's outer edge is placed by the lip's colour, not at the shadow under the lip;
* lip-coloured rows under the skin below a thin "lower lip" make the split go on (teeth as light
  as skin between the lips);
* the mouth crop follows a dropped jaw down by at most :data:`~tracker.face_tracker.CROP_DROP`, and
  the jaw's offset is bounded asymmetrically (far down, little up: the nostrils sit above the mouth);
* a mouth is "too wide" only against max(calibrated width, :data:`~tracker.mouth_finder.WIDE_REF` wi);
* at calibration a moustache over thin closed lips, darker than the line between them, is not the gap;
* a lower lip redder than at calibration is still lip (a tongue paler than it is not);
* an open mouth's corners that stopped inside it (a grin's dark corners above the line) go out to the
  ends of its inside;
* on a dark face a grin's shaded corners, brown and parted from the teeth by a sliver of lip, are
  part of that inside (unless hair round the mouth at calibration was as dark);
* at calibration on a grin the lower lip is measured from where its red begins, past the teeth's
  soft edge.
"""

import dataclasses
import types
import warnings

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tracker import face_tracker as ft
from tracker.mouth_finder import WIDE_REF, MouthFinder, MouthResult
from tracker.colour_model import lut_index
from tracker.mouth_model import DARK_ROUND, _colour_edge, _gap, _outer_edge, profile_features

SKIN = np.array([120.0, 150.0, 200.0])  # BGR: a warm skin
LIP = np.array([125.0, 125.0, 215.0])  # redder, about as bright (a lit lower lip)
WI = 80.0


def _profile(rows: list[tuple[np.ndarray, int]]) -> np.ndarray:
    """Stack (colour, count) runs into a (n, 3) float profile of mean BGR rows."""
    return np.concatenate([np.repeat(c[None, :], k, axis=0) for c, k in rows]).astype(np.float64)


def test_lower_edge_by_colour_skips_the_shadow_under_the_lip():
    """Gap, 8 rows of a lit lower lip shading off to 80 %, 5 rows of its shadow on the skin (the skin
    at 45 %), then lit skin, blurred a little: the mean-contrast split takes the shadow into the lip;
    the colour edge stops where the lip ends."""
    gap = np.array([40.0, 40.0, 50.0])
    lip_rows = [(LIP * k, 1) for k in np.linspace(1.0, 0.8, 8)]
    rows = _profile([(SKIN, 20), (LIP, 6), (gap, 2)] + lip_rows + [(0.45 * SKIN, 5), (SKIN, 30)])
    rows = cv2.GaussianBlur(rows.reshape(-1, 1, 3), (1, 0), 0.8).reshape(-1, 3)
    start = 27  # the gap's last row
    f = profile_features(rows, float(SKIN @ [0.114, 0.587, 0.299]))
    first = _outer_edge(f, start, +1, 0.05, 0.3, WI)
    rng = np.random.default_rng(0)
    skin_px = SKIN + rng.normal(0.0, 4.0, (400, 3))
    edge = _colour_edge(rows, start, +1, first, skin_px, (0.05, 0.3), WI)
    assert first > start + 10.5, "the contrast split should be fooled by the shadow (else this case shows nothing)"
    assert abs(edge - (start + 8.5)) <= 1.0


def test_colour_edge_keeps_the_first_edge_when_lips_are_skin_coloured():
    rows = _profile([(SKIN, 20), (0.8 * SKIN, 16), (SKIN, 30)])
    rng = np.random.default_rng(1)
    skin_px = SKIN + rng.normal(0.0, 4.0, (400, 3))
    assert _colour_edge(rows, 24, +1, 31.0, skin_px, (0.05, 0.3), WI) == 31.0


def test_jaw_bounds_are_asymmetric():
    """The mouth may drop far below its rigid place (a yawn) but rise little (the nose is there)."""
    assert ft.JAW_MAX[1] >= 0.6 and -0.35 <= ft.JAW_MIN[1] <= -0.2
    assert 0 < ft.CROP_DROP < ft.JAW_MAX[1]


def test_wide_reference_lets_a_pout_at_calibration_grin_later():
    assert 0.5 < WIDE_REF < 0.8


@pytest.mark.parametrize("dropped", [0.0, 0.6])
def test_mouth_crop_keeps_the_upper_lip_of_a_yawn(dropped):
    """The crop's top edge stays above the rigid mouth place's upper lip whatever the jaw does."""
    from tracker.calibration import mouth_rect
    from tracker.mouth_model import MOUTH_RECT

    wi = 40.0
    rigid = np.array([0.0, 50.0])
    centre = rigid + (0.0, dropped * wi)
    cy = min(float(centre[1]), float(rigid[1]) + ft.CROP_DROP * wi)
    rect = mouth_rect((float(centre[0]), cy), wi)
    upper_lip_top = rigid[1] - 0.25 * wi
    assert rect[1] <= upper_lip_top
    assert rect[1] + rect[3] >= centre[1] + 0.3 * wi  # and the lower lip of the dropped jaw
    assert MOUTH_RECT[1] < 0


def test_teeth_as_light_as_skin_do_not_end_the_lower_lip(monkeypatch):
    """A profile of the calibrated classes: skin, upper lip, the dark line under it, four rows that
    look like skin (teeth in warm light), the lower lip, skin. The split must put the lower lip's
    outer edge under the real lower lip; without the price on lip-coloured rows past the skin below
    it took the dark line for a thin lower lip and the teeth for the skin below it."""
    from tests.test_mouth_finder import _calibrate
    import tracker.mouth_finder as mfm

    model, _ = _calibrate()
    mf = MouthFinder(model, model.work_ipd)
    mu = mf._mu
    t_up, t_dn = int(round(mf.t_up)), int(round(mf.t_dn))
    dark = mu[2].copy()
    dark[0] *= 0.8
    teeth = mu[4] + (1.5, 0.5, 0.0)
    runs = [(mu[0], 14), (mu[1], t_up), (dark, 3), (teeth, 4), (mu[2], t_dn), (mu[3], 14)]
    f = np.concatenate([np.repeat(c[None, :], k, axis=0) for c, k in runs]).astype(np.float32)
    inside = np.zeros(len(f), np.float32)
    gap_top = 14 + t_up
    true_bottom = gap_top + 7 + t_dn

    def bottom() -> float:
        return mf.vertical(f, inside, gap_top + 1.0, spread=0.12)[3]

    assert abs(bottom() - true_bottom) <= 1.5
    monkeypatch.setattr(mfm, "OUTSIDE_PRICE", 0.0)
    assert abs(bottom() - true_bottom) > 1.5, "without the price the teeth end the lip (else this case shows nothing)"


def test_corner_found_when_the_cheek_is_lit_unlike_the_calibration(monkeypatch):
    """Unlikeness to the calibrated cheek along one side: the mouth's body (20), its dark corner (90),
    then the cheek — shaded by a turned head, it stays at 8, above the calibration's level of 6. The
    corner is where that plateau starts, not at the far end of the search."""
    import tracker.mouth_model as mm

    d = np.array([20.0] * 10 + [60.0, 90.0, 60.0, 30.0] + [8.0, 9.0, 8.5, 8.0] * 5)
    x, _ = mm.corner_distance(d, 4, 30, 3, (2, 9))
    assert 12.5 <= x <= 14.5
    monkeypatch.setattr(mm, "CHEEK_FAR", 0.0)
    x_old, _ = mm.corner_distance(d, 4, 30, 3, (2, 9))
    assert x_old > 20, "with the calibration's level alone the corner runs out (else this case shows nothing)"


def test_corner_of_a_low_contrast_mouth_is_where_its_columns_meet_the_cheek(monkeypatch):
    """Pale lips, or a camera with little colour: the mouth's body is only 8 unlike the cheek and its
    tapering ends (teeth and lower lip in a grin) 5, the cheek 0.5-1. The corner is where the columns
    meet the cheek (after column 21), not where the body gives way to the ends (10): no absolute floor
    above the mouth's own contrast ends it early."""
    import tracker.mouth_model as mm

    d = np.array([8.0] * 10 + [5.0] * 12 + [0.5, 1.0, 0.8] * 6)
    x, _ = mm.corner_distance(d, 4, 30, 3, (2, 9))
    assert 21.0 <= x <= 22.0
    monkeypatch.setattr(mm, "CHEEK_LEVEL", 6.0)
    x_old, _ = mm.corner_distance(d, 4, 30, 3, (2, 9))
    assert x_old < 12, "with a floor of 6 the corner ends where the body does (else this case shows nothing)"


def test_a_corner_holds_its_place_along_a_crease_as_unlike_the_cheek_as_its_level():
    """Past the lips (body 40, level 0.3 × 40 = 12) a crease runs on for six columns at 11.5-12.5,
    then the cheek. Noise puts the crease's columns either side of the level from frame to frame, so
    the corner would jump between the lips' end (column 12-13) and the crease's (18); with the last
    frame's corner it stays where it was, at either end. A mouth that really widens (lip columns
    well above the level) still moves it, and without a last corner the rule is the plain one."""
    import tracker.mouth_model as mm

    lips, cheek = [40.0] * 13, [1.0] * 12
    above = np.array(lips + [12.5, 12.2, 12.4, 12.3, 12.6, 12.1] + cheek)
    below = np.array(lips + [11.5, 11.8, 11.6, 11.7, 11.4, 11.9] + cheek)
    assert mm.corner_distance(above, 4, 30, 3, (2, 9))[0] > 18
    assert mm.corner_distance(below, 4, 30, 3, (2, 9))[0] < 13  # what noise alone does without a hold
    for d in (above, below):
        assert mm.corner_distance(d, 4, 30, 3, (2, 9), previous=13.2)[0] == pytest.approx(13.2)
        assert mm.corner_distance(d, 4, 30, 3, (2, 9), previous=17.6)[0] == pytest.approx(17.6)
        assert mm.corner_distance(d, 4, 30, 3, (2, 9), previous=25.0)[0] < 19.5  # not past the crease
        assert mm.corner_distance(d, 4, 30, 3, (2, 9), previous=5.0)[0] > 11.9  # nor inside the lips
    wider = np.array(lips + [40.0] * 5 + cheek + cheek)
    assert mm.corner_distance(wider, 4, 30, 3, (2, 9), previous=12.4)[0] > 17  # a smile widens it


def _mouth_at(line_centre, width, rise):
    """A stand-in for a mouth result: the traced line's ends about ``line_centre`` (face px)."""
    from types import SimpleNamespace

    cx, cy = line_centre
    return SimpleNamespace(width=width, level_rise=rise, line_centre=(cx, cy))


def test_mouth_place_and_tilt_checks():
    """A lopsided mouth tilted by 0.4 of its width is a mouth; a mouth coming back up to its rigid place
    after a yawn is one too; above the rigid place by more than the jaw allows it is not (a nostril)."""
    from tests.test_tracker_track import BASE, clicks_for
    from tracker.calibration import calibrate
    from tracker.clicks import Clicks
    from tracker.synthetic import render_face

    frame, _ = render_face(BASE)
    tr = ft.FaceTracker(calibrate(frame, Clicks.from_dict(clicks_for(BASE))))
    wi, w = tr.wi, tr.cal.mouth_width
    rigid = (0.0, 100.0)
    here = lambda dy, rise=0.0, pred_dy=0.0: tr._plausible_mouth(
        _mouth_at((0.0, rigid[1] + dy * wi), w, rise * w), (0.0, rigid[1] + pred_dy * wi), (0.0, 0.0), rigid)
    assert here(0.0) and here(0.0, rise=0.4) and not here(0.0, rise=0.5)
    assert here(0.0, pred_dy=0.6)  # the jaw closed in one frame: back at its rigid place
    assert not here(-0.4, pred_dy=0.0) and not here(-0.4, pred_dy=0.6)  # above the rigid place: the nose


HAIR = np.array([40.0, 48.0, 60.0])  # BGR: dark brown hair, no redder than the skin


def _rows_for_gap(runs: list[tuple[np.ndarray, int]]):
    """Luminance and r − g chroma (minus the skin's) per row of a profile built from colour runs."""
    prof = _profile(runs)
    f = profile_features(prof.astype(np.float32), 150.0)
    skin_red = float(profile_features(SKIN[None, :].astype(np.float32), 150.0)[0, 1])
    lum = prof @ np.array([0.114, 0.587, 0.299])
    return lum, f[:, 1] - skin_red


@pytest.mark.parametrize("lips", ["closed", "open"])
def test_calibration_gap_is_between_the_lips_not_in_a_moustache(lips):
    """Skin, a moustache (darker than anything else), the upper lip, the line between the lips (a
    little darker than them) or an open mouth's dark inside, the lower lip, skin; the click in the
    middle of the lips. The darkest row alone is the moustache; with the lips' colour the gap is the
    line between them, and an open mouth's inside stays the gap."""
    line = LIP * 0.8
    inside = np.array([30.0, 30.0, 35.0])
    middle = [(line, 1)] if lips == "closed" else [(inside, 10)]
    runs = [(SKIN, 30), (HAIR, 8), (LIP * 0.9, 7)] + middle + [(LIP, 9), (SKIN, 30)]
    lum, red = _rows_for_gap(runs)
    line_row = 45 if lips == "closed" else 49
    click = 46.0 if lips == "closed" else 50.0
    teeth = np.zeros(len(lum))
    if lips == "closed":
        assert 30 <= _gap(lum, teeth, click, WI)[2] < 38  # colour-blind: the moustache
        assert _gap(lum, teeth, click, WI, red)[2] == line_row
    else:
        assert 45 <= _gap(lum, teeth, click, WI, red)[2] <= 54  # the inside, as without colour
        assert _gap(lum, teeth, click, WI, red)[2] == _gap(lum, teeth, click, WI)[2]
    flat = np.zeros(len(lum))  # no colour to go by (a colourless camera): the darkest row, as before
    assert _gap(lum, teeth, click, WI, flat) == _gap(lum, teeth, click, WI)


def test_a_lower_lip_redder_than_calibrated_is_still_the_lower_lip(monkeypatch):
    """Pale lips as a real face shows them (their lead over the skin a few spreads, not ten), then a
    frame of an open mouth: the dark inside, a pinkish tongue a little paler than the lower lip, and
    the lower lip itself redder than at calibration (a pout turns its moist inside out). The gap must
    take the tongue and the lower lip keep its outer edge; costing a redder lip like skin made the
    tongue the lower lip (expr_d6's pouts). An open mouth's lower lip may roll out (``OPEN_GROW``), so
    it may take a row or two of a tongue nearly as pink as itself, but not the tongue."""
    import dataclasses

    from tests.test_mouth_finder import _calibrate
    import tracker.mouth_finder as mfm

    model, _ = _calibrate()
    classes = np.array([[[21.2, 9.9, 6.9], [1.0, 1.0, 1.0]], [[14.1, 16.8, 10.8], [1.7, 3.5, 1.0]],
                        [[15.4, 16.3, 9.8], [2.2, 2.0, 1.0]], [[19.6, 11.7, 8.0], [1.2, 1.3, 1.0]],
                        [[20.0, 9.6, 7.5], [1.5, 1.0, 1.0]]], np.float32)
    pale = dataclasses.replace(model, classes=classes)

    def split() -> tuple[float, float]:
        mf = MouthFinder(pale, pale.work_ipd)
        mu = mf._mu.astype(np.float64)
        t_up, t_dn = int(round(mf.t_up)), int(round(mf.t_dn))
        redder = mu[2] + np.r_[0.0, mu[2, 1:] - mu[4, 1:]]  # twice the lower lip's chroma lead, as bright
        tongue = mu[4] + 0.8 * (mu[2] - mu[4])
        dark = np.array([0.25, 0.3, 0.3]) * mu[4]
        runs = [(mu[0], 14), (mu[1], t_up), (dark, 3), (tongue, 4), (redder, t_dn), (mu[3], 14)]
        f = _profile(runs).astype(np.float32)
        gap_top = 14 + t_up
        inside = np.zeros(len(f), np.float32)
        inside[gap_top : gap_top + 3] = 1.0
        v = mf.vertical(f, inside, gap_top + 1.0, spread=0.12)
        lip_top = gap_top + 7.0  # the lower lip's first row
        return v[1] - lip_top, v[3] - (lip_top + t_dn)  # the gap's and the lip's outer edge's errors

    gap_err, bottom_err = split()
    assert gap_err >= -2.0 and abs(bottom_err) <= 1.5
    monkeypatch.setattr(mfm, "LIP_BEYOND", 0.0)
    gap_err, _ = split()
    assert gap_err < -3.0, "without the allowance the tongue is the lower lip (else this case shows nothing)"


def _grin_crop(wedges: bool = True, line: bool = False, edge: bool = False) -> np.ndarray:
    """A grin at the working scale (40 px between the eyes): skin, an upper lip, teeth from column 26
    to 50, a lower lip, and (``wedges``) a near-black triangle beside each end of the teeth rising to
    a tip at (17, 17) and (59, 17) — the dark corners of a grin, which the lips hide from the line's
    rows on a dark face — or (``line``) a one-row dark line running on from the teeth's right end
    (a crease), or (``edge``) a dark edge running down from it (dark lipstick's lower edge)."""
    from tracker.synthetic import STYLES

    st = STYLES["default"]
    img = np.empty((64, 76, 3), np.uint8)
    img[:] = st.skin
    img[14:20, 20:57] = st.lip
    img[26:32, 22:55] = st.lip
    img[20:26, 26:51] = st.teeth
    dark = (30, 25, 35)
    if wedges:
        for tri in ([(27, 19), (27, 26), (17, 17)], [(49, 19), (49, 26), (59, 17)]):
            cv2.fillPoly(img, [np.array(tri, np.int32)], dark)
    if line:
        img[22, 51:62] = dark
    if edge:  # the lower lip's dark outer edge, running down and out from the teeth's right end
        cv2.line(img, (51, 24), (53, 33), dark, 2)
    return img


def test_an_open_mouths_corners_reach_the_ends_of_its_inside(monkeypatch):
    """A grin whose corners the line search left inside the mouth (on the teeth's ends, the dark
    corners above the line's rows): the corners move out to the ends of the mouth's inside, at its
    rows there. A closed mouth, a corner outside the inside's thick part (a crease running on from
    it), a lip's dark edge running down from it and an inside running on past OPEN_REACH are left
    alone."""
    from tests.test_mouth_finder import _calibrate
    import tracker.mouth_finder as mfm

    model, _ = _calibrate()
    mf = MouthFinder(model, model.work_ipd)
    assert mf.wi == pytest.approx(40.0) and mf.r == pytest.approx(1.0)
    bias = mfm.CORNER_BIAS
    maps = mf.prepare(_grin_crop())
    left, right = mf.inside_ends(maps, (28.0, 24.0), (48.0, 24.0), (19.0, 26.0), (14.0, 31.0))
    assert abs(left[0] - (17 - bias)) <= 1.0 and abs(right[0] - (59 + bias)) <= 1.0, (left, right)
    assert 16.0 <= left[1] <= 19.0 and 16.0 <= right[1] <= 19.0, (left, right)
    # the lips shut: no inside to go by
    assert mf.inside_ends(maps, (28.0, 24.0), (48.0, 24.0), (22.5, 23.0), (14.0, 31.0)) == ((28.0, 24.0), (48.0, 24.0))
    # a corner already past the teeth, on a one-row crease running on from them, stays
    creased = mf.prepare(_grin_crop(wedges=False, line=True))
    assert mf.inside_ends(creased, (25.0, 23.0), (53.0, 22.0), (19.0, 26.0), (14.0, 31.0))[1] == (53.0, 22.0)
    # an inside that goes down more steeply than OPEN_SLOPE from the corner is a lip's edge: it stays
    edged = mf.prepare(_grin_crop(wedges=False, edge=True))
    assert mf.inside_ends(edged, (28.0, 24.0), (49.0, 23.0), (19.0, 26.0), (14.0, 34.0))[1] == (49.0, 23.0)
    with monkeypatch.context() as steep:
        steep.setattr(mfm, "OPEN_SLOPE", 10.0)
        assert mf.inside_ends(edged, (28.0, 24.0), (49.0, 23.0), (19.0, 26.0), (14.0, 34.0))[1][0] > 51.5
    # an inside running on past OPEN_REACH is not the mouth's own (hair round it): the corners stay
    # (the finder's maps are one buffer: the grin again)
    maps = mf.prepare(_grin_crop())
    monkeypatch.setattr(mfm, "OPEN_REACH", 0.25)
    assert mf.inside_ends(maps, (28.0, 24.0), (48.0, 24.0), (19.0, 26.0), (14.0, 31.0)) == ((28.0, 24.0), (48.0, 24.0))
    # ... unless the last sure frame had its corners where the inside ends (an inside ending where the
    # mouth ended a frame ago is that mouth's); a last frame with its corners elsewhere, or an unsure
    # one, does not count
    def last(left_x: float, right_x: float, score: float = 1.0) -> MouthResult:
        return MouthResult(left=(left_x, 18.0), right=(right_x, 18.0), centre=(38.0, 18.0), lip_upper=6.0,
                           lip_lower=8.0, polygon=np.zeros((4, 2)), raw_polygon=np.zeros((4, 2)), cue="colour", score=score)

    left, right = mf.inside_ends(maps, (28.0, 24.0), (48.0, 24.0), (19.0, 26.0), (14.0, 31.0), last(16.5, 59.5))
    assert abs(left[0] - (17 - bias)) <= 1.0 and abs(right[0] - (59 + bias)) <= 1.0, (left, right)
    for other in (last(27.0, 49.0), last(16.5, 59.5, score=0.3)):
        assert mf.inside_ends(maps, (28.0, 24.0), (48.0, 24.0), (19.0, 26.0), (14.0, 31.0), other) == ((28.0, 24.0), (48.0, 24.0))
    # an inside running on to the crop's side (the dark beside a turned face) is not the mouth's own,
    # however far it may reach
    monkeypatch.setattr(mfm, "OPEN_REACH", 2.0)
    sided = _grin_crop()
    sided[19:26, 51:] = (30, 25, 35)
    left, right = mf.inside_ends(mf.prepare(sided), (28.0, 24.0), (48.0, 24.0), (19.0, 26.0), (14.0, 31.0))
    assert abs(left[0] - (17 - bias)) <= 1.0 and right == (48.0, 24.0), (left, right)


def test_the_corners_move_out_to_the_inside_more_the_more_the_lips_part():
    """Lips parted about OPEN_ENDS: the corners move part of the way towards the inside's ends, more
    the wider the gap, so the width follows the gap without a step (a still face whose gap read 3.9
    and 4.1 rows about a threshold of 4 had its corner jump 2.3 px and back frame after frame)."""
    from tests.test_mouth_finder import _calibrate
    import tracker.mouth_finder as mfm

    model, _ = _calibrate()
    mf = MouthFinder(model, model.work_ipd)
    maps = mf.prepare(_grin_crop())
    unit = mfm.OPEN_ENDS * mf.wi
    lo, hi = mfm.OPEN_ENDS_RAMP
    xs = []
    for k in (lo - 0.05, lo + 0.25 * (hi - lo), lo + 0.5 * (hi - lo), lo + 0.75 * (hi - lo), hi, hi + 0.5):
        gap = (23.0 - 0.5 * k * unit, 23.0 + 0.5 * k * unit)
        left, right = mf.inside_ends(maps, (28.0, 24.0), (48.0, 24.0), gap, (14.0, 31.0))
        xs.append((left[0], right[0]))
    assert xs[0] == (28.0, 48.0)  # under the ramp: not at all
    full = xs[-1]
    assert xs[-2] == pytest.approx(full)  # past it: all of the way
    for (l0, r0), (l1, r1) in zip(xs, xs[1:]):
        assert l1 <= l0 and r1 >= r0  # out, step by step
    assert xs[2][0] == pytest.approx(28.0 + 0.5 * (full[0] - 28.0)) and xs[2][1] == pytest.approx(48.0 + 0.5 * (full[1] - 48.0))


def _dark_grin_crop(style) -> np.ndarray:
    """A grin on a dark face at the working scale (40 px between the eyes): ``style``'s skin and
    lips, teeth from column 26 to 50, and beside each end of the teeth, past a 3-column sliver of
    lip, a triangle of the skin at half its light rising to a tip at (17, 17) and (59, 17) — the
    shaded corners of a grin, as brown as the skin round them."""
    img = np.empty((64, 76, 3), np.uint8)
    img[:] = style.skin
    img[14:20, 20:57] = style.lip
    img[26:32, 22:55] = style.lip
    img[20:26, 26:51] = style.teeth
    shade = tuple(int(0.5 * c) for c in style.skin)
    for tri in ([(22, 19), (22, 26), (17, 17)], [(54, 19), (54, 26), (59, 17)]):
        cv2.fillPoly(img, [np.array(tri, np.int32)], shade)
    return img


def test_a_grins_shaded_corners_on_a_dark_face_are_inside_the_mouth(monkeypatch):
    """The shaded corners of a grin on a dark face are not the inside's colours (dark and colourless,
    or teeth), and a sliver of lip parts them from the teeth: the corners stopped at the teeth's ends
    (the ``darkeyes`` copy of expr_d19: width r 0.58 / 0.49). Pixels far darker than the lips
    (OPEN_DARK) and gaps up to OPEN_JOIN across closed take them to the shading's tips; without either
    the corners stay at the teeth, and so they do where the skin round the mouth was that dark at
    calibration (hair: DARK_ROUND)."""
    from tests.test_mouth_finder import _calibrate
    from tracker.synthetic import STYLES
    import tracker.mouth_finder as mfm

    style = STYLES["dark_skin"]
    model, _ = _calibrate(style)
    assert model.dark_round is not None and model.dark_round <= DARK_ROUND
    crop = _dark_grin_crop(style)
    assert not model.inside_table.take(lut_index(crop[20:23, 20:22])).any(), "the shading is no inside colour"
    bias = mfm.CORNER_BIAS
    corners = ((28.0, 24.0), (48.0, 24.0), (19.0, 26.0), (14.0, 31.0))  # the corners on the teeth, the gap, the lips

    def ends(m):
        f = MouthFinder(m, m.work_ipd)
        return f.inside_ends(f.prepare(crop), *corners)

    left, right = ends(model)
    assert abs(left[0] - (17 - bias)) <= 1.0 and abs(right[0] - (59 + bias)) <= 1.0, (left, right)
    assert 16.0 <= left[1] <= 19.5 and 16.0 <= right[1] <= 19.5, (left, right)
    for name, value in (("OPEN_DARK", 0.0), ("OPEN_JOIN", 0.05)):
        with monkeypatch.context() as m:
            m.setattr(mfm, name, value)
            left, right = ends(model)
            assert left[0] >= 24.0 and right[0] <= 52.0, (name, left, right)
    left, right = ends(dataclasses.replace(model, dark_round=2 * DARK_ROUND, dark_chin=1.0))
    assert left[0] >= 24.0 and right[0] <= 52.0, ("hair round the mouth", left, right)


TONGUE_PINK = np.array([122.0, 124.0, 208.0])  # BGR: a tongue as red as the lips, a shade paler
DARK_INSIDE = np.array([30.0, 32.0, 45.0])


def _yawn_runs(lower_lip: np.ndarray = LIP) -> list[tuple[np.ndarray, int]]:
    """A yawn through the click (80 px between the eyes): skin, upper lip, the dark inside above the
    tongue, the tongue, the dark inside in front of the lower teeth, the lower lip, skin."""
    return [(SKIN, 20), (LIP * 0.9, 6), (DARK_INSIDE, 4), (TONGUE_PINK, 22), (DARK_INSIDE * 0.7, 8),
            (lower_lip, 10), (SKIN, 30)]


def test_a_yawns_gap_runs_on_past_the_tongue_to_the_lower_lip():
    """The click on the tongue of a yawn: the darkest row near it is the band above the tongue, and the
    gap stopped there (the tongue then was the lower lip, 0.3 wi thick: the ``late`` copy of expr_d18
    calibrated on such a frame, and its opening followed the peer at r 0.28). Past the tongue the gap
    reaches the second dark band, with the lower lip after it."""
    lum, red = _rows_for_gap(_yawn_runs())
    teeth = np.zeros(len(lum))
    click = 36.0  # on the tongue, the band above it within the darkest row's reach and the one below not
    top, bottom, _ = _gap(lum, teeth, click, WI, red)
    assert (top, bottom) == (26, 29), "without the rule the gap is the band above the tongue (else this shows nothing)"
    top, bottom, _ = _gap(lum, teeth, click, WI, red, past_tongue=True)
    assert (top, bottom) == (26, 59)
    # a dark band that runs on past the tallest opening (OPEN_SPAN) is no inside in front of teeth
    runs = _yawn_runs()
    runs[4] = (DARK_INSIDE * 0.7, 40)
    lum, red = _rows_for_gap(runs)
    assert _gap(lum, np.zeros(len(lum)), click, WI, red, past_tongue=True)[:2] == (26, 29)


@pytest.mark.parametrize("case", ["shade under a thick lip", "beard", "shade across a full lip"])
def test_past_the_tongue_the_gap_does_not_take_a_thick_lower_lip(case):
    """Closed lips and a thick, very red lower lip (a child's pout) with the dark shade under it and a
    paler chin after that; the lower lip with a dark beard under it; parted lips and a full lower lip
    with a crease of shade across it, dark, but lighter than the gap (the ``late`` copy of expr_d6).
    None is a tongue: the gap stays the line between the lips."""
    line = LIP * 0.6
    if case == "shade across a full lip":
        runs = [(SKIN, 20), (LIP * 0.9, 8), (DARK_INSIDE * 1.7, 3), (LIP, 14), (LIP * 0.41, 3), (LIP, 6), (SKIN, 30)]
    elif case == "beard":
        runs = [(SKIN, 20), (LIP * 0.9, 8), (line, 2), (LIP, 12), (HAIR * 0.6, 12), (HAIR, 30)]
    else:
        red_lip = np.array([110.0, 100.0, 220.0])
        chin = SKIN + (LIP - SKIN) * 0.5  # pinkish, but paler than the lip
        runs = [(SKIN, 20), (LIP * 0.9, 8), (line, 2), (red_lip, 22), (0.35 * SKIN, 4), (chin, 30)]
    lum, red = _rows_for_gap(runs)
    teeth = np.zeros(len(lum))
    assert _gap(lum, teeth, 29.0, WI, red, past_tongue=True) == _gap(lum, teeth, 29.0, WI, red)


def _yawn_crop() -> np.ndarray:
    """A yawn's mouth crop at 80 px between the eyes, drawn from ellipses: the lips' ring, the dark
    inside, a tongue filling its lower half (dark bands left above and below it)."""
    crop = np.empty((160, 160, 3), np.uint8)
    crop[:] = SKIN.astype(np.uint8)
    cv2.ellipse(crop, (80, 64), (30, 28), 0, 0, 360, LIP.tolist(), -1, cv2.LINE_AA)
    cv2.ellipse(crop, (80, 64), (25, 22), 0, 0, 360, DARK_INSIDE.tolist(), -1, cv2.LINE_AA)
    cv2.ellipse(crop, (80, 67), (21, 11), 0, 0, 360, TONGUE_PINK.tolist(), -1, cv2.LINE_AA)
    return cv2.GaussianBlur(crop, (0, 0), 0.8)


def test_a_yawn_at_calibration_is_learned_as_an_open_mouth(monkeypatch):
    """:func:`~tracker.mouth_model.learn_mouth` on a yawn, the click on the tongue: the gap spans the
    inside (from the upper lip's inner edge to the lower lip's, 44 rows) and the lower lip is a lip's
    thickness; looking no further than the band above the tongue, the tongue was learned as a lower
    lip as thick as lips get (:data:`~tracker.mouth_model.LIP_MAX`)."""
    import tracker.mouth_model as mm

    crop = _yawn_crop()
    model = mm.learn_mouth(crop, (80.0, 62.0), WI)
    assert 38.0 <= model.gap <= 46.0, model.gap
    assert model.thick_down <= 0.12 * WI, model.thick_down
    monkeypatch.setattr(mm, "TONGUE", False)
    before = mm.learn_mouth(crop, (80.0, 62.0), WI)
    assert before.gap < 20.0 and before.thick_down >= mm.LIP_MAX[1] * WI - 0.5, (before.gap, before.thick_down)


def test_the_rest_line_of_an_open_calibration_mouth_is_at_its_upper_lip():
    """The mouth's rigid place: a closed or talking mouth's own line; a yawn's line (half an eye
    distance below its upper lip's inner edge) moves up to :data:`~tracker.calibration.RIGID_OPEN`
    wi below that edge. On the synthetic performer, whose widest mouth opens only 0.3 wi, calibrating
    with it open still puts the rigid place within 0.03 wi of where calibrating with it closed does
    (no harm there; the yawn it is for is the ``expr_d18-late`` case in ``test_realfaces``)."""
    from tracker.calibration import RIGID_OPEN, calibrate, rest_height
    from tracker.clicks import Clicks
    from tracker.synthetic import FaceState, clicks_for, render_face

    assert rest_height(100.0, 99.0, WI) == 100.0
    assert rest_height(100.0, 100.0 - RIGID_OPEN * WI, WI) == 100.0
    assert rest_height(100.0, 60.0, WI) == pytest.approx(60.0 + RIGID_OPEN * WI)
    base = FaceState(cx=320.0, cy=210.0, ipd=80.0)
    heights = []
    for opening in (0.0, 1.0):
        face = base.replace(mouth_open=opening, teeth=True)
        cal = calibrate(render_face(face)[0], Clicks.from_dict(clicks_for(face)))
        heights.append(cal.mouth_offset[1] / cal.work_ipd)
    assert abs(heights[1] - heights[0]) <= 0.03, heights


def test_a_look_whose_corners_lie_over_its_lips_does_not_move_the_rigid_place(monkeypatch):
    """Calibration looks for the mouth where its last look put the line, as the tracker will. A look
    that traced the shadow under the nose on a grin puts its corners above the lips it split below
    them (its upper lip's height from the corners' line -0.16 wi): not a look that found the mouth,
    so the rigid place stays where the last whole look had it. Without the check it followed the
    looks up, 0.15 eye distances on this face."""
    import tracker.calibration as cal_mod
    from tracker.clicks import Clicks
    from tracker.mouth_finder import MouthFinder as MF, _moved
    from tracker.synthetic import FaceState, clicks_for, render_face

    face = FaceState(cx=320.0, cy=210.0, ipd=80.0)
    frame = render_face(face)[0]
    clicks = Clicks.from_dict(clicks_for(face))
    calm = cal_mod.calibrate(frame, clicks)
    real_find = MF.find
    looks = []

    def find(self, crop, at, *args, **kwargs):
        r = real_find(self, crop, at, *args, **kwargs)
        looks.append(r)
        if r is not None and len(looks) <= 3:
            # the first look a little low (the loop looks again from its line), the next ones on the
            # nostrils' shadow 0.3 wi up
            wi = calm.work_ipd  # the crop's px between the eyes (the finder's own wi is its working scale)
            up = -0.05 * wi if len(looks) == 1 else 0.3 * wi
            over = -0.16 * wi if len(looks) > 1 else r.lip_upper - up  # the nose's shadow: 0.16 wi over the lips
            r = _moved(r, centre=(r.centre[0], r.centre[1] - up), left=(r.left[0], r.left[1] - up),
                       right=(r.right[0], r.right[1] - up), lip_upper=over, lip_lower=r.lip_lower + up,
                       line_ends=tuple((p[0], p[1] - up) for p in r.line_ends))
        return r

    monkeypatch.setattr(MF, "find", find)
    moved = cal_mod.calibrate(frame, clicks)
    assert len(looks) >= 2
    assert abs(moved.mouth_offset[1] - calm.mouth_offset[1]) <= 0.02 * calm.work_ipd, (moved.mouth_offset, calm.mouth_offset)
    assert not cal_mod.found_mouth(None, 80.0)
    look = types.SimpleNamespace(score=1.0, lip_upper=-0.07 * 80.0, lip_lower=10.0)
    assert cal_mod.found_mouth(look, 80.0)  # along a moustache's lower edge, just over the lips' top
    assert not cal_mod.found_mouth(types.SimpleNamespace(score=1.0, lip_upper=-0.16 * 80.0, lip_lower=30.0), 80.0)
    assert not cal_mod.found_mouth(types.SimpleNamespace(score=1.0, lip_upper=10.0, lip_lower=-0.15 * 80.0), 80.0)


def test_the_rigid_place_does_not_climb_off_the_lips_calibration_measured(monkeypatch):
    """Each calibration look starts where the last one put its line. On a grin each look can be sure
    and whole by its own split and still lie higher than the last: the upper lip's top edge, then
    the shadow under the nose (a grinning man's photo: three looks 0.46 eye distances up, and the
    rigid place, after the rest-height rule, 0.32 up on the nostrils). A look whose line leaves the
    lips the model measured — past their outer edges by more than WHOLE_MOUTH — is no look at the
    mouth, and the place goes back to where the last whole look was made from, as for a look that is
    not sure or not whole; without the bound these looks carry it 0.45 wi up."""
    import tracker.calibration as cal_mod
    from tracker.clicks import Clicks
    from tracker.mouth_finder import MouthFinder as MF, _moved
    from tracker.synthetic import FaceState, clicks_for, render_face

    face = FaceState(cx=320.0, cy=210.0, ipd=80.0)
    frame = render_face(face)[0]
    clicks = Clicks.from_dict(clicks_for(face))
    calm = cal_mod.calibrate(frame, clicks)
    wi = calm.work_ipd
    real_find = MF.find
    looks = []

    def find(self, crop, at, *args, **kwargs):
        r = real_find(self, crop, at, *args, **kwargs)
        looks.append(r)
        if r is not None and len(looks) <= cal_mod.RIGID_STEPS:
            up = 0.15 * wi + r.line_centre[1] - at[1]  # the line 0.15 wi over where this look started
            r = _moved(r, centre=(r.centre[0], r.centre[1] - up), left=(r.left[0], r.left[1] - up),
                       right=(r.right[0], r.right[1] - up), line_ends=tuple((p[0], p[1] - up) for p in r.line_ends))
        return r

    monkeypatch.setattr(MF, "find", find)
    moved = cal_mod.calibrate(frame, clicks)
    model = calm.mouth_model
    rise = calm.mouth_offset[1] - moved.mouth_offset[1]
    assert len(looks) >= 3
    assert 0.15 * wi < model.lip_upper + cal_mod.WHOLE_MOUTH * wi < 0.3 * wi  # one look's climb stays on the lips, two do not
    assert abs(rise) <= 0.02 * wi, rise / wi
    monkeypatch.setattr(cal_mod, "WHOLE_MOUTH", 10.0)  # the control: no bound, the looks carry it up
    looks.clear()
    free = cal_mod.calibrate(frame, clicks)
    assert calm.mouth_offset[1] - free.mouth_offset[1] > 0.4 * wi


def test_between_lips_bounds_a_line_by_the_lips_outer_edges():
    """A look's line (face px) lies on the measured mouth from its upper lip's outer edge less
    WHOLE_MOUTH × wi down to its lower lip's outer edge plus as much."""
    import types

    import tracker.calibration as cal_mod

    wi, top = 80.0, 100.0
    model = types.SimpleNamespace(centre=(60.0, 50.0), lip_upper=10.0, lip_lower=12.0)
    centre = top + 50.0
    slack = cal_mod.WHOLE_MOUTH * wi
    assert cal_mod.between_lips(centre, top, model, wi)
    assert cal_mod.between_lips(centre - 10.0 - slack, top, model, wi)
    assert not cal_mod.between_lips(centre - 10.0 - slack - 0.5, top, model, wi)
    assert cal_mod.between_lips(centre + 12.0 + slack, top, model, wi)
    assert not cal_mod.between_lips(centre + 12.0 + slack + 0.5, top, model, wi)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), st.integers(1, 30)),
                min_size=2, max_size=12),
       st.floats(5.0, 155.0), st.floats(5.0, 155.0))
def test_calibration_of_any_banded_mouth_crop_gives_a_finite_mouth(runs, click_x, click_y):
    """Crops of horizontal bands of any colours and heights (lips, teeth, tongues, shadows, beards in
    any order, as the tongue and gap rules see them) with the click anywhere in the crop: a model
    every time, its sizes, colours and lip axes finite. A lip or skin band past the crop's edge once
    gave an empty sample, and a lip axis of NaNs."""
    import tracker.mouth_model as mm

    rows = np.concatenate([np.repeat(np.array([[b, g, r]], np.uint8), k, axis=0) for b, g, r, k in runs])
    rows = np.resize(rows, (160, 3))
    crop = np.ascontiguousarray(np.repeat(rows[:, None, :], 160, axis=1))
    crop = cv2.GaussianBlur(crop, (0, 0), 0.8)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no mean of an empty sample on the way
        model = mm.learn_mouth(crop, (float(click_x), float(click_y)), WI)
    for v in (model.gap, model.thick_up, model.thick_down, model.width, model.lip_upper, model.lip_lower):
        assert np.isfinite(v)
    assert np.isfinite(model.axis_up).all() and np.isfinite(model.axis_down).all()
    assert np.isfinite(model.classes).all() and np.isfinite(model.separation)
    assert model.gap >= 0.0 and model.thick_up > 0.0 and model.thick_down > 0.0 and model.width > 0.0


def _grin_bands(lower: int, blur: float) -> tuple[np.ndarray, tuple[float, float]]:
    """A grin's mouth crop at 80 px between the eyes, in bands: skin, a thin upper lip, the dark line
    under it, yellowish teeth, a pale lower lip ``lower`` rows thick, skin — blurred up and down by
    ``blur`` px as a camera does (the colours of expr_d0's grin). Returns the crop and the click, on
    the teeth."""
    H, W = 96, 152
    skin, lip = np.array([104.0, 118.0, 152.0]), np.array([100.0, 108.0, 158.0])
    runs = [(skin, 34), (lip, 6), (np.array([60.0, 60.0, 85.0]), 2), (np.array([145.0, 160.0, 182.0]), 12), (lip, lower)]
    runs.append((skin, H - sum(k for _, k in runs)))
    col = cv2.GaussianBlur(_profile(runs).reshape(-1, 1, 3), (1, 0), blur).reshape(-1, 3)
    crop = np.repeat(col[:, None, :], W, axis=1)
    crop[:, np.abs(np.arange(W) - W / 2) > 44] = skin  # the cheeks past the corners
    crop = cv2.GaussianBlur(crop, (0, 0), 0.7)
    return np.clip(crop, 0, 255).astype(np.uint8), (W / 2, 45.0)


@pytest.mark.parametrize("blur", [1.6, 2.0])
def test_a_grins_lower_lip_is_measured_past_the_teeths_soft_edge(monkeypatch, blur):
    """Calibration on a grin: the teeth end on a soft edge a few rows tall, greyer than the skin; the
    lower lip's thickness is measured from where its red begins, not from the teeth's last clear row
    (from there, the soft edge against the lip next to it was the strongest split, and real grins and
    dark-skinned copies of a talking clip calibrated a lower lip 0.04 wi thick)."""
    import tracker.mouth_model as mm

    crop, click = _grin_bands(16, blur)
    assert abs(mm.learn_mouth(crop, click, WI).thick_down - 16) <= 2.0
    monkeypatch.setattr(mm, "TEETH_BLUR", 0.0)
    assert mm.learn_mouth(crop, click, WI).thick_down < 6, "without the step the lip reads thin (else this case shows nothing)"


def test_past_teeth_stops_at_the_first_red_row_and_within_reach():
    import tracker.mouth_model as mm

    red = np.array([-5.0] * 10 + [-2.0, -1.0, 3.0, 4.0])
    assert mm._past_teeth(red, 9, +1, WI) == 11
    assert mm._past_teeth(np.full(20, -3.0), 9, +1, WI) == 9, "no lip within reach: the gap stays"
    assert mm._past_teeth(red[::-1].copy(), 4, -1, WI) == 2


def test_a_smiles_dark_folds_and_nostrils_are_not_hair_but_a_dark_chin_is():
    """Hair round the mouth switches the tracker's dark rules (:func:`~tracker.mouth_finder.hair_round`).
    A smile calibrated on has dark skin round the mouth of its own: the folds beside it and the
    nostrils' shadow over it (0.05-0.21 of the round on seven of the fourteen still photos, none of
    them bearded). Painted on the synthetic face's calibration crop they make ``dark_round`` pass
    :data:`DARK_ROUND`, but the chin under the lower lip stays light, so it is no hair; a beard
    painted on that chin too makes it hair. Older calibrations without ``dark_chin`` go by the round
    alone; a share outside 0..1 is refused naming it."""
    from tests.test_mouth_finder import BASE, WI as FWI, _crop, _frame_of
    from tracker.mouth_finder import dark_rule, hair_round
    from tracker.mouth_model import DARK_CHIN, MouthModel, chin_band, learn_mouth
    from tracker.synthetic import face_landmarks, render_face

    img, _ = render_face(BASE)
    ff = _frame_of(BASE)
    click = ff.to_face(face_landmarks(BASE)["mouth"][None])[0]
    crop, origin = _crop(img, ff, click)
    at = tuple(click - origin)
    clean = learn_mouth(crop, at, FWI)
    assert clean.dark_round <= DARK_ROUND and clean.dark_chin == 0.0 and not hair_round(clean)

    outline = clean.outline + np.array(clean.centre)
    y0, y1, x0, x1 = chin_band(crop.shape, outline, FWI)
    assert y1 - y0 >= 0.2 * FWI and x1 - x0 >= 0.2 * FWI and y0 > outline[:, 1].max()
    shadow = np.array([20, 20, 25], np.uint8)
    smiling = crop.copy()
    cx, cy = (int(round(v)) for v in clean.centre)
    hw = int(round(0.5 * (outline[:, 0].max() - outline[:, 0].min())))
    for side in (-1, 1):  # a fold down each side, past the corners, and a nostril over the lip
        x = cx + side * (hw + int(0.12 * FWI))
        smiling[cy - int(0.25 * FWI) : cy + int(0.3 * FWI), x - 2 : x + 3] = shadow
        smiling[cy - int(0.4 * FWI) : cy - int(0.32 * FWI), cx + side * int(0.12 * FWI) - 3 : cx + side * int(0.12 * FWI) + 4] = shadow
    smile = learn_mouth(smiling, at, FWI)
    assert smile.dark_round > DARK_ROUND and smile.dark_chin < DARK_CHIN
    assert not hair_round(smile) and dark_rule(smile)
    assert hair_round(dataclasses.replace(smile, dark_chin=None)), "an older calibration: the round alone"

    bearded = smiling.copy()
    bearded[y0:y1, x0:x1] = shadow
    beard = learn_mouth(bearded, at, FWI)
    assert beard.dark_chin >= DARK_CHIN and hair_round(beard) and not dark_rule(beard)

    assert MouthModel.from_dict(beard.to_dict()).dark_chin == pytest.approx(beard.dark_chin)
    old = beard.to_dict()
    del old["dark_chin"]
    assert MouthModel.from_dict(old).dark_chin is None
    with pytest.raises(ValueError, match="dark_chin"):
        MouthModel.from_dict({**beard.to_dict(), "dark_chin": -0.2})


def test_the_upper_lips_thickness_keeps_most_of_the_centres_when_the_sides_lose_its_edge():
    """Calibration measures the upper lip on three columns and takes the median, so that one column's
    crease or highlight does not decide. On a noisy or low-contrast picture the side columns lose the
    lip's soft top edge first (expr_d19: 12.2 / 10.6 / 11.8 px on the clip, 12.5 / 7.4 / 5.7 on its
    noisy copy), and a lip expected 40 % too thin was laid onto the skin above it all clip long. The
    centre's own reading now floors it (:data:`UPPER_FLOOR`); a column that saw no edge is no vote,
    and with none seen the thickness is :data:`UPPER_UNSEEN`."""
    from tracker.mouth_model import UPPER_FLOOR, UPPER_UNSEEN, upper_thickness

    nan = float("nan")
    assert upper_thickness([12.2, 10.6, 11.8], 80.0) == pytest.approx(11.8), "the clip: the median, untouched"
    assert upper_thickness([12.5, 7.4, 5.7], 80.0) == pytest.approx(UPPER_FLOOR * 12.5), "its noisy copy"
    assert 7.4 < UPPER_FLOOR * 12.5
    assert upper_thickness([nan, 5.4, nan], 80.0) == pytest.approx(5.4), "no centre reading: the sides decide"
    assert upper_thickness([12.0, nan, 7.0], 80.0) == pytest.approx(UPPER_FLOOR * 12.0)
    assert upper_thickness([nan, nan, nan], 80.0) == pytest.approx(UPPER_UNSEEN * 80.0)
    assert upper_thickness([9.0], 80.0) == pytest.approx(9.0)
