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
import warnings

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tracker import face_tracker as ft
from tracker.mouth_finder import WIDE_REF, MouthFinder
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


def _grin_crop(lower: int, blur: float) -> tuple[np.ndarray, tuple[float, float]]:
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

    crop, click = _grin_crop(16, blur)
    assert abs(mm.learn_mouth(crop, click, WI).thick_down - 16) <= 2.0
    monkeypatch.setattr(mm, "TEETH_BLUR", 0.0)
    assert mm.learn_mouth(crop, click, WI).thick_down < 6, "without the step the lip reads thin (else this case shows nothing)"


def test_past_teeth_stops_at_the_first_red_row_and_within_reach():
    import tracker.mouth_model as mm

    red = np.array([-5.0] * 10 + [-2.0, -1.0, 3.0, 4.0])
    assert mm._past_teeth(red, 9, +1, WI) == 11
    assert mm._past_teeth(np.full(20, -3.0), 9, +1, WI) == 9, "no lip within reach: the gap stays"
    assert mm._past_teeth(red[::-1].copy(), 4, -1, WI) == 2
