"""tracker.auto_init: the pair of eyes found from a face detector's box, on drawn faces whose
eyes are hard to tell apart from what is around them."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from tracker.auto_init import EYE_WI, IRIS_RADIUS, TEETH_LEAD, _lip_span, _mirror, _mouth, _upright, centre_votes, find_brows, find_pupils, iris_contrast, rim_bars
from tracker.brows import brow_centre, column_profile
from tracker.face_finder import DEFAULT_EYES


def narrow_face(ipd: float = 90.0, roll: float = 0.0, iris: float = 180.0, size=(480, 360)) -> tuple[np.ndarray, np.ndarray]:
    """A face (BGR) with narrow eyes whose light iris is barely darker than the white (only its
    dark pupil stands out, with a highlight beside it), dark lashes on the upper lid, a lid crease
    above each eye and a brow above that, rolled by ``roll`` degrees; and the pupils (2, 2) px."""
    w, h = size
    img = np.full((h, w), 165.0, np.float32)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    c, s = math.cos(math.radians(roll)), math.sin(math.radians(roll))
    mid = np.array([w / 2, h / 2 - 20.0])
    pts = []
    for side in (-1, 1):
        ex, ey = mid + side * 0.5 * ipd * np.array([c, -s])
        pts.append((ex, ey))
        u, v = (xx - ex) * c - (yy - ey) * s, (xx - ex) * s + (yy - ey) * c  # along the eye line, down
        almond = (u / (0.2 * ipd)) ** 2 + (v / (0.055 * ipd)) ** 2 <= 1.0
        img[almond] = 210.0
        img[almond & (np.hypot(u, v) <= 0.09 * ipd)] = iris
        img[np.hypot(u, v) <= 0.035 * ipd] = 25.0
        img[(np.abs(u - 0.05 * ipd) <= 0.02 * ipd) & (np.abs(v + 0.01 * ipd) <= 0.015 * ipd)] = 250.0
        top = -0.055 * ipd * np.sqrt(np.clip(1 - (u / (0.2 * ipd)) ** 2, 0, 1))
        img[(v < top) & (v >= top - 0.03 * ipd) & (np.abs(u) < 0.19 * ipd)] = 45.0
        crease = -0.15 * ipd * np.sqrt(np.clip(1 - (u / (0.24 * ipd)) ** 2, 0, 1))
        img[(np.abs(v - crease) <= 0.012 * ipd) & (np.abs(u) < 0.22 * ipd)] = 95.0
        img[(np.abs(v + 0.38 * ipd) <= 0.05 * ipd) & (np.abs(u) < 0.25 * ipd)] = 60.0
    img = cv2.GaussianBlur(img, (0, 0), 0.8)
    return cv2.cvtColor(np.clip(img, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR), np.array(pts)


def box_for(pts: np.ndarray, shift=(0.0, 0.0), grow: float = 1.0) -> tuple[float, float, float, float]:
    """The square face box whose eye guess (:data:`DEFAULT_EYES`) is the level pair about the
    pupils' middle, moved by ``shift`` inter-pupil distances and ``grow`` times as far apart."""
    ipd, mid = math.dist(*pts), pts.mean(axis=0)
    (a, b), (c, _) = DEFAULT_EYES
    side = grow * ipd / (c - a)
    return (mid[0] + shift[0] * ipd - 0.5 * (a + c) * side, mid[1] + shift[1] * ipd - b * side, side, side)


@pytest.mark.parametrize("roll", [0.0, 8.0, -8.0])
@pytest.mark.parametrize("shift,grow", [((0.0, 0.0), 1.0), ((0.1, 0.1), 0.9), ((-0.1, -0.1), 1.15), ((0.12, 0.0), 1.15)])
def test_narrow_light_eyes_are_found_from_a_box_that_is_off(roll, shift, grow):
    """The detector's box puts real eyes 5–12 % of their distance off, and a head may be rolled:
    the pupils are found all the same, not the lid crease above a light iris or the skin under
    it (the single-eye search put one eye 6–35 % off on these faces)."""
    img, pts = narrow_face(roll=roll)
    grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float32)
    found = find_pupils(grey, box_for(pts, shift, grow))
    for p, q in zip(found, pts):
        assert math.dist(p, q) < 0.03 * 90.0


def _with_rims(img: np.ndarray, pts: np.ndarray, ipd: float, roll: float, thick: int = 4) -> np.ndarray:
    """``img`` with near-black spectacle rims (0.76 × 0.47 eye distances, ``thick`` px) round both eyes."""
    c, s = math.cos(math.radians(roll)), math.sin(math.radians(roll))
    u, dn = np.array([c, -s]), np.array([s, c])
    out = img.copy()
    for p in pts:
        centre = p + 0.03 * ipd * dn
        box = [centre + ipd * (a * u + b * dn) for a, b in ((-0.38, -0.22), (0.38, -0.22), (0.38, 0.25), (-0.38, 0.25))]
        cv2.polylines(out, [np.round(np.array(box) * 8).astype(np.int32)], True, (25, 25, 25), thick, cv2.LINE_AA, shift=3)
    return out


@pytest.mark.parametrize("roll", [0.0, 8.0])
@pytest.mark.parametrize("thick", [4, 6])
def test_narrow_eyes_behind_thick_rims_are_found_not_the_rims_bars(roll, thick):
    """A thick rim's lower bar is a dark line with skin above and below, and its middle draws the
    votes of a dark round thing more than narrow light eyes do (a copy of a shared clip with thick
    rims: both pupils on the lower bars, 0.28 eye distances low). A line that runs on level past an
    eye's width is no eye (:data:`~tracker.auto_init.BAR_RUN`)."""
    ipd = 90.0
    img, pts = narrow_face(ipd=ipd, roll=roll)
    grey = cv2.cvtColor(_with_rims(img, pts, ipd, roll, thick), cv2.COLOR_BGR2GRAY).astype(np.float32)
    for p, q in zip(find_pupils(grey, box_for(pts)), pts):
        assert math.dist(p, q) < 0.03 * ipd


def test_rim_bars_mark_a_rims_bars_not_an_eye():
    img, pts = narrow_face()
    grey = cv2.cvtColor(_with_rims(img, pts, 90.0, 0.0), cv2.COLOR_BGR2GRAY).astype(np.float32)
    band, m = _upright(grey, pts[0], pts[1])
    bars = rim_bars(band)
    for x, y in (m @ np.c_[pts, np.ones(2)].T).T:
        x, y = int(round(x)), int(round(y))
        assert not bars[y - 6 : y + 7, x - 8 : x + 9].any()  # the eye, its lashes and its crease
        assert bars[y + int(0.28 * EYE_WI) - 2 : y + int(0.28 * EYE_WI) + 3, x].any()  # the lower bar under it
        assert bars[y + 2, x + int(0.41 * EYE_WI) - 2 : x + int(0.41 * EYE_WI) + 3].any()  # the lens's side
    bare, _ = _upright(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float32), pts[0], pts[1])
    assert not rim_bars(bare).any()  # the brows, the creases and the lashes are no bars


def test_votes_peak_on_a_dark_disc_not_on_a_dark_line():
    """Gradients pointing away from a centre: a disc's middle collects them all, a line of the
    same darkness (a lash line, a brow) only the half that faces each place."""
    img = np.full((120, 200), 200.0, np.float32)
    cv2.circle(img, (70, 60), 7, 60.0, -1, cv2.LINE_AA)
    cv2.line(img, (110, 58), (190, 58), 60.0, 5, cv2.LINE_AA)
    votes = centre_votes(cv2.GaussianBlur(img, (0, 0), 1.0), (100.0, 60.0), (60.0, 20.0))
    j, i = np.unravel_index(int(votes.argmax()), votes.shape)
    assert abs(i + 40 - 70) <= 1 and abs(j + 40 - 60) <= 1
    flat = centre_votes(np.full((120, 200), 128.0, np.float32), (100.0, 60.0), (60.0, 20.0))
    assert not np.any(flat)


def test_disc_contrast_needs_white_on_both_sides():
    """An iris has the white of the eye left and right of it; an eye's dark corner (or the lashes
    that end it) has white on one side only and skin on the other, here darker than the white as
    on a dark face. Averaging the two sides scored the corner above the iris; the darker side
    decides."""
    r = IRIS_RADIUS * EYE_WI
    img = np.full((80, 200), 70.0, np.float32)  # dark skin
    cv2.ellipse(img, (90, 40), (int(3.2 * r), int(1.3 * r)), 0, 0, 360, 200.0, -1, cv2.LINE_AA)  # the white
    cv2.circle(img, (90, 40), int(round(r)), 110.0, -1, cv2.LINE_AA)  # a mid-brown iris
    cv2.circle(img, (int(90 + 3.4 * r), 40), int(round(0.8 * r)), 40.0, -1, cv2.LINE_AA)  # the dark corner
    c = iris_contrast(cv2.GaussianBlur(img, (0, 0), 1.0))
    j, i = np.unravel_index(int(c[:, 40:160].argmax()), c[:, 40:160].shape)
    assert abs(i + 40 - 90) <= 2 and abs(j - 40) <= 2


def _lower_face(beard: bool, open_mouth: bool = False):
    """Grey and Lab a* images of a lower face (eyes at rows 40, 100 px apart): skin, red lips round
    a dark gap (or an open mouth's dark inside) about 1.15 eye distances below the eyes and, with
    ``beard``, a band of dark, colourless hair under the lower lip, darker than the gap."""
    h, w = 260, 200
    grey = np.full((h, w), 170.0, np.float32)
    red = np.full((h, w), 145.0, np.float32)
    gap0, gap1 = (148, 162) if open_mouth else (154, 156)
    for y0, y1 in ((gap0 - 10, gap0), (gap1, gap1 + 12)):  # upper lip, lower lip
        grey[y0:y1, 60:140] = 120.0
        red[y0:y1, 60:140] = 165.0
    grey[gap0:gap1, 60:140] = 40.0 if open_mouth else 70.0
    if beard:
        grey[gap1 + 14 : gap1 + 60, 40:160] = 35.0
        red[gap1 + 14 : gap1 + 60, 40:160] = 133.0
    return grey, red


@pytest.mark.parametrize("open_mouth", [False, True])
def test_the_mouth_point_is_between_the_lips_not_in_a_beard(open_mouth):
    """The darkest line below the eyes is the beard; the lips' colour says the mouth is higher. With
    no beard, or no colour, the darkest line as before."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    gap = 155.0
    grey, red = _lower_face(beard=True, open_mouth=open_mouth)
    assert _mouth(grey, left, right)[1] > gap + 14  # the darkest line alone: the beard
    x, y = _mouth(grey, left, right, red)
    assert abs(y - gap) <= (8 if open_mouth else 2) and abs(x - 100.0) < 1
    grey, red = _lower_face(beard=False, open_mouth=open_mouth)
    assert _mouth(grey, left, right, red) == pytest.approx(_mouth(grey, left, right))
    flat = np.full_like(red, 145.0)  # a colourless camera: the lips' colour cannot help
    grey, _ = _lower_face(beard=True, open_mouth=open_mouth)
    assert _mouth(grey, left, right, flat) == pytest.approx(_mouth(grey, left, right))


def test_the_mouth_point_stays_above_the_chin_the_face_detector_saw():
    """A warm picture where the lips are no redder than the skin, and the neck's shadow under the chin,
    inside the mouth's range, is far darker than the gap between the lips: the darkest line was the
    neck (a laughing face in a photo: about 1.5 eye distances below the eyes, the grin at 0.85). The face
    detector's box ends at the chin, and the range ends with it (:data:`~tracker.auto_init.BOX_MOUTH`):
    the point is on the gap. Where the box ends below the range, nothing changes."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey, red = _lower_face(beard=False)
    red[:] = 145.0  # no lip colour to go by
    grey[190:, :] = 25.0  # the neck in the chin's shadow, from 1.5 eye distances down
    grey[196:, :] = 60.0  # a collar below the shadow: the shadow is a valley too
    assert _mouth(grey, left, right, red)[1] > 185.0
    x, y = _mouth(grey, left, right, red, chin=185.0)
    assert abs(y - 155.0) <= 2 and abs(x - 100.0) < 1
    assert _mouth(grey, left, right, red, chin=260.0) == pytest.approx(_mouth(grey, left, right, red))


@pytest.mark.parametrize("beard", [False, True])
def test_the_mouth_point_is_on_the_line_when_only_the_lower_lip_is_red(beard):
    """An upper lip in shade, darker than it is red (expr_d10's copy darkened to a deep brown): the
    lip-red rows are the lower lip's alone, the line between the lips is just over them, and the
    mouth point is on it — before, with no dark row inside the lower lip's rows, it fell on the
    lower lip's middle, a fifth of the eye distance low, and that clip's tracked opening followed
    the peer at r 0.50 instead of 0.96."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey, red = _lower_face(beard=beard)
    red[144:154, 60:140] = 145.0  # the upper lip: as red as the skin
    x, y = _mouth(grey, left, right, red)
    assert abs(y - 155.0) <= 2 and abs(x - 100.0) < 1


def test_the_mouth_point_is_on_the_lips_not_on_a_pinker_chin():
    """A chin pinker than brownish lips (expr_d3, shaken copy): the reddest row below the eyes is the
    chin's, and the lips' own red is under half its lead. The lips' reddest row is looked for above
    where a chin begins — before, the run round the chin had no dark row inside it, and the point
    fell on the chin's middle; the `--auto` point there sat 17 % of the eye distance low, and the
    clip's opening followed the peer at r 0.75 (0.97 with this)."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey, red = _lower_face(beard=False)
    red[144:168, 60:140] = np.where(red[144:168, 60:140] > 150.0, 153.0, red[144:168, 60:140])  # brownish lips
    grey[190:205, 50:150] = 175.0
    red[190:205, 50:150] = 178.0  # the chin: pink and bright
    x, y = _mouth(grey, left, right, red)
    assert abs(y - 155.0) <= 2 and abs(x - 100.0) < 1


def test_the_mouth_point_is_on_the_lips_not_on_reddened_nostrils():
    """A cheap dim webcam (half size, noise, JPEG): the lips are only a little redder than the skin,
    and the skin under the nose, reddened round the nostrils at the very start of the range looked
    in, is over half as red as they are; the runs were joined into one span of lips, and the
    nostrils' shadow, a little darker than the gap between the lips, took the mouth point half an
    eye distance up (the ``cheap`` copy of expr_d0 with --auto: mouth opening r 0.50, 0.75 with
    this). A red run that starts at the range's start without the reddest row in it is no lip."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey, red = _lower_face(beard=False)
    red[red > 150.0] = 152.0  # weakly red lips (rows 144-167)
    top = 40 + int(round(0.8 * 100))
    red[top - 10 : top + 7, 72:128] = 150.0  # the skin under the nose, reddened, from above the range into it
    grey[top + 2 : top + 7, 81:98] = 10.0  # the nostrils: their rows darker on the whole than the gap's
    grey[top + 2 : top + 7, 102:119] = 10.0
    x, y = _mouth(grey, left, right, red)
    assert abs(y - 155.0) <= 2 and abs(x - 100.0) < 1


def _mouth_bands(bands) -> tuple[np.ndarray, np.ndarray]:
    """Grey and Lab a* images of a lower face (eyes at rows 40, 100 px apart) on skin of grey 170 and
    a* 145, with ``bands`` ((row0, row1), grey, a*) across the mouth, columns 60-140."""
    grey = np.full((260, 200), 170.0, np.float32)
    red = np.full((260, 200), 145.0, np.float32)
    for (y0, y1), g, r in bands:
        grey[y0:y1, 60:140] = g
        red[y0:y1, 60:140] = r
    return grey, red


def test_a_childs_smile_close_under_the_eyes_is_found_between_its_lips():
    """A young child's mouth sits about 0.95 eye distances below the eyes (an adult's 1.05-1.2). A
    wide smile: the upper lip, the upper teeth, the gap, the lower teeth, a redder lower lip. The
    search once began at 0.9: the upper lip fell outside it, the lower lip's red alone was the
    lips, and the point went to the lower lip (the ``child`` copy of talk_b: 0.34 eye distances low)."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey, red = _mouth_bands([((116, 127), 120.0, 165.0), ((127, 133), 225.0, 138.0), ((133, 136), 30.0, 150.0),
                              ((136, 141), 225.0, 138.0), ((141, 153), 125.0, 175.0)])
    x, y = _mouth(grey, left, right, red)
    assert abs(y - 134.5) <= 2 and abs(x - 100.0) < 1


def test_the_mouth_point_is_at_the_teeth_under_a_pale_upper_lip(monkeypatch):
    """Parted lips: an upper lip no redder than the skin, the upper teeth, the dark gap, a red lower
    lip and the shade under it, darker than the gap. The lip-red rows are the lower lip and its shade,
    so the darkest row among them was the shade — the ``late`` copy of expr_d6 with ``--auto``: the
    point a fifth of the eye distance low, calibration learned the lower lip alone, and the clip's
    opening followed the peer at r 0.06 (0.83 with this). Teeth over the lips' red say the mouth is
    open there: the point is on the gap under them."""
    import tracker.auto_init as ai

    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey, red = _mouth_bands([((135, 146), 150.0, 145.0), ((146, 153), 225.0, 140.0), ((153, 156), 60.0, 150.0),
                              ((156, 170), 125.0, 170.0), ((170, 174), 45.0, 160.0)])
    x, y = _mouth(grey, left, right, red)
    assert abs(y - 154.5) <= 2 and abs(x - 100.0) < 1
    no_teeth = grey.copy()
    no_teeth[146:153, 60:140] = 150.0  # the same rows as the pale lip: as before, the shade
    assert _mouth(no_teeth, left, right, red)[1] > 168.0
    monkeypatch.setattr(ai, "TEETH_OVER", 0.0)
    assert _mouth(grey, left, right, red)[1] > 168.0, "without the rule the shade is the line (else this shows nothing)"


def test_the_mouth_line_is_not_the_nostrils():
    """Without the lips' colour the mouth is the darkest line across the face: two nostrils darken
    most of a short row's mean but a quarter of it stays bright, while a closed mouth's paler gap
    darkens all of its row."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey = np.full((260, 200), 170.0, np.float32)
    grey[122:130, 80:94] = 40.0
    grey[122:130, 106:120] = 40.0
    grey[149:152, 60:140] = 110.0
    x, y = _mouth(grey, left, right, np.full_like(grey, 145.0))
    assert abs(y - 150.0) <= 2 and abs(x - 100.0) < 1


def test_lip_span_joins_an_open_mouths_two_lips_and_needs_a_lead_over_the_skin():
    red = np.full(80, 140.0)
    red[10:16] = 160.0  # upper lip
    red[40:48] = 158.0  # lower lip, 0.3 eye distances (of 100 px) below
    assert _lip_span(red, 140.0, 100.0) == (10, 47)
    assert _lip_span(red, 140.0, 40.0) == (10, 15)  # a small face: too far apart to be one mouth
    assert _lip_span(np.full(80, 141.0), 140.0, 100.0) is None


@pytest.mark.parametrize("glasses", [False, True])
@pytest.mark.parametrize("roll", [0.0, 8.0])
def test_the_brow_point_is_on_the_brow_not_on_a_spectacle_rim(glasses, roll):
    """Spectacle rims (near-black, under the brows, round each eye) are the darkest band above the
    eyes; the brow point stays on the brow (0.38 eye distances above the pupil), with or without them
    (the darkest band alone put it on the rim's upper bar, 0.2 above)."""
    ipd = 90.0
    img, pts = narrow_face(ipd=ipd, roll=roll)
    if glasses:
        c, s = math.cos(math.radians(roll)), math.sin(math.radians(roll))
        u, dn = np.array([c, -s]), np.array([s, c])
        for p in pts:
            centre = p + 0.03 * ipd * dn
            box = [centre + ipd * (a * u + b * dn) for a, b in ((-0.38, -0.22), (0.38, -0.22), (0.38, 0.25), (-0.38, 0.25))]
            cv2.polylines(img, [np.round(np.array(box) * 8).astype(np.int32)], True, (25, 25, 25), 4, cv2.LINE_AA, shift=3)
    grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float32)
    for b, p in zip(find_brows(grey, pts[0], pts[1]), pts):
        assert math.dist(b, p) == pytest.approx(0.38 * ipd, abs=0.04 * ipd)


def _bands_over_eyes(skin: float, bands, blur: float):
    """A grey face (eyes 100 px apart at row 220) with ``bands`` (from, to, grey) painted over each
    eye, from and to in eye distances above the pupil, 0.6 eye distances wide, then blurred by
    ``blur`` px: the picture, the pupils and the eye distance."""
    ipd = 100.0
    img = np.full((300, 400), skin, np.float32)
    pts = np.array([[150.0, 220.0], [250.0, 220.0]])
    for x, y in pts:
        cols = slice(int(x - 0.3 * ipd), int(x + 0.3 * ipd))
        for a, b, g in bands:
            img[int(round(y - b * ipd)) : int(round(y - a * ipd)), cols] = g
    return cv2.GaussianBlur(img, (0, 0), blur), pts, ipd


def test_the_brow_point_keeps_calibration_off_the_lids_shadow():
    """On a dark face the shadow of the upper lid is darker than the brow and runs up to it. The
    darkest band's middle sat on the brow's lower edge, within 0.08 eye distances (calibration's
    reach for the brow) of that shadow, and calibration took the shadow for the brow; the point
    is in the brow's upper half, and calibration finds the brow from it."""
    # the lid's shadow, darker than the brow; then the brow
    img, pts, ipd = _bands_over_eyes(70.0, [(0.05, 0.17, 20.0), (0.17, 0.20, 34.0), (0.20, 0.32, 30.0)], 1.0)
    for b, (x, y) in zip(find_brows(img, pts[0], pts[1]), pts):
        assert 0.26 * ipd < y - b[1] < 0.32 * ipd  # the brow: 0.2-0.32
        top = int(y - 1.1 * ipd)
        prof = column_profile(img, x, top, int(y), 2)
        found = y - (top + brow_centre(prof, int(round(b[1] - top)), int(round(0.08 * ipd))))
        assert 0.2 * ipd < found < 0.32 * ipd


@pytest.mark.parametrize("brow", [(0.36, 0.46), (0.12, 0.21)])
def test_the_brow_point_is_on_the_brow_not_on_a_childs_lid(brow):
    """A child's eye is larger against the eye distance: its lid and lashes reach past 0.2 eye
    distances over the pupil, where the brow's range starts, darkest there and darker still below.
    With a brow higher up, a band clearly darker than the skin round it, the point is on the brow;
    before, it was on the lid (the ``child`` copy of expr_d11: 0.25 eye distances low). A low brow
    that begins under the range (an adult's, expr_d18's at 0.15) still gives the range's start."""
    # the lid and lashes, then the brow; or the brow alone, over the lid's skin
    bands = [(0.08, 0.23, 40.0), (*brow, 90.0)] if brow[0] > 0.2 else [(*brow, 40.0)]
    img, pts, ipd = _bands_over_eyes(150.0, bands, 1.5)
    for b, (x, y) in zip(find_brows(img, pts[0], pts[1]), pts):
        if brow[0] > 0.2:
            assert brow[0] * ipd < y - b[1] < brow[1] * ipd + 2
        else:
            assert 0.19 * ipd < y - b[1] < 0.26 * ipd


def test_skin_a_little_brighter_than_under_the_nose_is_no_teeth():
    """A shut mouth with the skin over the upper lip a little better lit (6 % brighter) than the rows
    under the nose: no teeth show there, and the point is on the line between the lips. Before,
    any row brighter than those rows passed for teeth, and the point went up onto that skin (the
    child, pale, deep and glasses copies of expr_d0: 17 % of the eye distance high)."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    lit = 170.0 * (1.0 + 0.6 * TEETH_LEAD)
    grey, red = _mouth_bands([((138, 144), lit, 145.0), ((144, 154), 150.0, 145.0), ((154, 156), 70.0, 150.0),
                              ((156, 168), 125.0, 168.0)])
    x, y = _mouth(grey, left, right, red)
    assert abs(y - 155.0) <= 2 and abs(x - 100.0) < 1
    teeth = grey.copy()
    teeth[146:153, 60:140] = 225.0  # the same mouth with its upper teeth showing: the gap under them
    assert abs(_mouth(teeth, left, right, red)[1] - 154.5) <= 2


def test_bright_skin_over_a_red_upper_lip_is_no_teeth():
    """Red upper and lower lips round an open mouth's dark inside, under a brightly lit philtrum
    (25 % brighter than the skin under the nose): teeth cannot show above a red upper lip, so the
    point is in the mouth, not on the philtrum (the third-size copy of talk_a: a fifth of the eye
    distance high)."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    grey, red = _mouth_bands([((150, 162), 212.0, 141.0), ((162, 170), 110.0, 170.0), ((170, 178), 35.0, 146.0),
                              ((178, 190), 115.0, 172.0)])
    x, y = _mouth(grey, left, right, red)
    assert 169.0 <= y <= 179.0 and abs(x - 100.0) < 1


def test_the_mouth_point_is_on_a_thin_line_under_a_dark_moustache():
    """A dark moustache over the upper lip, a one-row line between the lips right under it, and only
    the lower lip red: smoothed, the grey only rises from the moustache down and shows no valley in
    the lips' rows; the rows' own means still have the line. Before, the point fell on the lower
    lip's middle (a painted beard round expr_d18: 7 % of the eye distance low)."""
    left, right = np.array([50.0, 40.0]), np.array([150.0, 40.0])
    moustache = [((r, r + 1), 40.0 + 2.0 * (r - 126), 138.0) for r in range(126, 152)]  # thinning downwards
    grey, red = _mouth_bands(moustache + [((152, 154), 94.0, 145.0), ((154, 155), 91.0, 146.0), ((155, 156), 100.0, 160.0),
                                          ((156, 170), 135.0, 168.0)])
    x, y = _mouth(grey, left, right, red)
    assert abs(y - 154.5) <= 1.5 and abs(x - 100.0) < 1


def _eye_band(shift: float, corners: bool = False) -> tuple[np.ndarray, list[tuple[float, float]]]:
    """An upright band at EYE_WI with two almond eyes, their irises ``shift`` (× the eye's half width)
    to the image's right in both (a glance aside), and with ``corners`` dark outer corners (shadow,
    make-up). Returns the band and the iris centres."""
    band = np.full((60, int(2 * EYE_WI)), 150, np.uint8)
    half, r = 0.22 * EYE_WI, IRIS_RADIUS * EYE_WI
    irises = []
    for cx in (0.5 * EYE_WI, 1.5 * EYE_WI):
        cv2.ellipse(band, (int(cx), 30), (int(half), int(0.4 * half)), 0, 0, 360, 235, -1, cv2.LINE_AA)
        ix = cx + shift * half
        cv2.circle(band, (int(round(ix)), 30), int(round(r)), 45, -1, cv2.LINE_AA)
        irises.append((ix, 30.0))
        if corners:
            side = -1 if cx < EYE_WI else 1
            tip = int(cx + side * half)
            cv2.fillPoly(band, [np.array([(tip, 30), (tip - side * 9, 25), (tip - side * 9, 35)], np.int32)], 40)
    return cv2.GaussianBlur(band, (0, 0), 1.0).astype(np.float32), irises


def test_eyes_glancing_aside_are_a_pair_and_two_dark_outer_corners_are_not_a_better_one():
    """Both irises to one side: the eyes are copies of each other, not mirror images; the pair's
    likeness takes either. Two dark outer corners are mirror images of each other, and mirroring
    alone scored them above the glancing irises (expr_d0's frame 19: a pupil on a corner)."""
    band, (a, b) = _eye_band(0.55, corners=True)
    glance = _mirror(band, a, b)
    outer = _mirror(band, (0.5 * EYE_WI - 0.22 * EYE_WI + 4, 30.0), (1.5 * EYE_WI + 0.22 * EYE_WI - 4, 30.0))
    assert glance > 0.9 and glance > outer
    straight, (a0, b0) = _eye_band(0.0)
    assert _mirror(straight, a0, b0) > 0.9


@pytest.mark.parametrize("hat", [0.55, 0.62, 0.68])
def test_a_hat_or_fringe_reaching_into_the_brow_search_is_not_taken_for_the_brows(hat):
    """Hair, a fringe or a hat's band from the top of the picture down to ``hat`` eye distances above the
    pupils, as dark as the brows: it is dark from its lower edge up past the search's top, with no
    forehead above it as a brow has, and the brows are found under the forehead below it (an old
    naval portrait's cap band was taken for the brows, 0.73 eye distances up, held there)."""
    from tracker.synthetic import FaceState, face_landmarks, render_face

    state = FaceState(cx=320.0, cy=240.0, ipd=80.0)
    img, _ = render_face(state)
    lm = face_landmarks(state)
    left, right = lm["left_pupil"], lm["right_pupil"]
    img[: int(round(left[1] - hat * 80.0)), :] = (40, 40, 60)
    grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float32)
    for found, true in zip(find_brows(grey, left, right), (lm["left_brow"], lm["right_brow"])):
        assert abs(found[1] - true[1]) < 0.05 * 80.0, (hat, found, true)


def test_a_brow_raised_high_is_still_the_brow():
    """A dark band at 0.6-0.7 eye distances over the pupils, darker than the brow below it, with the
    forehead above it (a brow raised high, the performer's hairline 0.76 up): the forehead over it says
    it is a brow, not hair."""
    from tracker.synthetic import FaceState, face_landmarks, render_face

    state = FaceState(cx=320.0, cy=240.0, ipd=80.0)
    img, _ = render_face(state)
    lm = face_landmarks(state)
    left, right = lm["left_pupil"], lm["right_pupil"]
    y0, y1 = int(round(left[1] - 0.7 * 80.0)), int(round(left[1] - 0.6 * 80.0))
    img[y0:y1, int(left[0]) - 20 : int(right[0]) + 21] = (20, 20, 30)
    grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float32)
    for found in find_brows(grey, left, right):
        assert y0 - 2 <= found[1] <= y1 + 2, (found, y0, y1)
