"""Automatic start: the five clicks a careful person would make, found by machine.

The result is a :class:`~tracker.clicks.Clicks`, so calibration does not care where it came
from. Steps, each using only what every face has:

1. the face: OpenCV's bundled frontal-face cascade (:func:`tracker.face_finder.detect_faces`);
   the largest face wins;
2. pupils: the detector's box says roughly where the eyes are (5–10 %, at times 20 %, of the
   inter-pupil distance off on real faces); near there, candidates for each eye from three
   cues, and the best *pair* of them: both dark round centres with white beside them, mirror
   images of each other, level and about the box's distance apart (:func:`find_pupils`), then
   snapped to the limbus as calibration snaps clicked pupils (:func:`tracker.eyes.refine_pupils`);
3. brows: the darkest band on the column above each pupil (a spectacle rim's upper bar, which
   goes round the eye, filled in first: :func:`tracker.eyes.spectacle_rims`), the point in its
   upper half, where a person clicks a brow (:func:`_brow`);
4. mouth: the darkest line across the lower face, 0.8–1.6 inter-pupil distances below the
   eyes (an adult's mouth about 1.1, a young child's about 0.95) — the gap between closed lips
   or the inside of an open mouth
   (the nostrils sit higher, the chin's shadow lower); where the lips are redder than the
   cheeks, the darkest line between them (a beard or a moustache is darker than the gap, but
   not red; :func:`_lip_span`).

On a video (:func:`auto_start`) the first frame with a face is used, however late it comes,
unless its eyes look shut: then the first frame soon after whose eyes show.

The cascades ship inside the opencv-contrib-python-headless 4.x wheel
(``cv2.data.haarcascades``); nothing is downloaded.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

import cv2
import numpy as np

from tracker.brows import brow_centre
from tracker.clicks import PIXEL_CENTRE, Clicks
from tracker.eyes import REFINE_WI, fill_rows, limbus_gradients, limbus_grid, limbus_scores, refine_pupils, spectacle_rims, thin_dark
from tracker.face_finder import detect_faces, eyes_in_box, face_cascade
from tracker.pupils import parabola_offset

IRIS_RADIUS = 0.09
"""Iris radius as a fraction of the inter-pupil distance (about 5.8 mm of 63 mm)."""
BROW_RANGE = (0.2, 0.75)
"""Where brows are looked for above the pupils, in inter-pupil distances."""
HAIR_PAST = 0.1
"""How far (× the inter-pupil distance) past the brows' range the grey is read: a darkest row that
stays dark that far up is hair, a fringe or a hat's band, not a brow raised to the range's top (see
:func:`_brow`)."""
BROW_BAND = 0.25
"""How much darker than the skin on its darker side (× the range's spread of grey) a band above the
range's dark start must be to be taken for the brow (see :func:`_brow`)."""
MOUTH_RANGE = (0.8, 1.6)
"""Where the mouth's dark line is looked for below the eye line, in inter-pupil distances. Adults'
mouths lie 1.05-1.2 below their eyes (the shared clips: 1.03-1.21), a young child's about 0.95:
from 0.9 a child's upper lip was cut off, and a wide-open smile's red lower lip alone was taken
for the lips (the ``child`` copy of talk_b: the mouth click 0.34 eye distances low). Above 0.8 lie
the nostrils and, on a bearded face, the reddish skin under the nose beside the moustache."""

BOX_MOUTH = 0.3
"""The least range (× the inter-pupil distance) :func:`_mouth` keeps when the face detector's box
ends it early (:data:`MOUTH_RANGE`): the bundled detector's box ends at the chin, and below it lie
the shadow under the chin, the neck and a collar, as dark as any mouth and, in a warm picture, as red
as its lips (a laughing face with no lip colour to go by: the point went to the shadow on the neck,
about 1.5 eye distances below the eyes, the grin at 0.85). On the shared clips and their child-sized,
small and tilted copies the mouth's point lies at 0.72-0.86 of the box's height, whose bottom is
1.48-1.95 eye distances below the eyes."""
LIP_RED = 4.0
"""Lab a* (0–255 scale) by which the reddest row below the eyes must outdo the cheeks for the lips'
colour to say where the mouth is."""
LIP_GAP = 0.5
"""Farthest apart (× the inter-pupil distance) two runs of lip-red rows are one mouth (an open
mouth's lips)."""
LIPS_ABOVE = 1.45
"""Lowest (× the inter-pupil distance below the eyes) the lips' reddest row may be: below it a closed
mouth's lower lip has ended and the chin begins."""
LINE_OVER = 0.06
"""How far (× the inter-pupil distance) above the lip-red rows the mouth's line may lie: an upper
lip less red than half the lips' lead is not in them (see :func:`_mouth`)."""
TEETH_OVER = 0.2
"""How far (× the inter-pupil distance) above the lips' red rows the upper teeth of an open mouth may
show (under a pale upper lip that is not in those rows; see :func:`_teeth_rows`)."""
TEETH_LEAD = 0.1
"""How much brighter (× the skin's brightest row between the nose and the lips) a row's brightest
tenth must be to show teeth (:func:`_teeth_rows`). The ``late`` copy of expr_d6's teeth: 0.25 over
it; on shut mouths, a row of skin a little better lit than the rows under the nose was up to 0.06
over it (expr_d0's child, pale, deep and glasses copies, expr_d6's deep one), and the mouth point
went up onto the philtrum, 17-22 % of the eye distance high."""
LINE_SHARE = 75.0
"""Percentile of each row's grey across the band the mouth's dark line is looked for on where the
lips' colour does not say where they are: a row is dark only where three quarters of it are. The
gap between the lips or an open mouth darkens the whole row; the nostrils darken two patches of
theirs, with bright skin between and beside them, and a row's mean took them for a line (expr_d0's
``washed`` copy, its lips' colour gone, once the search began at 0.8: the mouth click on the
nostrils)."""
ROLL_TRIES = (0.0, 20.0, -20.0)
"""Turns (degrees, counter-clockwise) of the frame the face and its pupils are looked for on; the
points come from the turn whose pupil pair scores best (:func:`pupil_pair`), found on that turned
frame and turned back. The cascade finds faces within about 15° of upright, and the pair is looked
for level (the ``tilt`` copies, heads rolled up to 25°: 37 of 168 frames sampled had no face
upright, and 28 of the rest, rolled 10-27°, a pupil a tenth of the eye distance or more off)."""
TURNED_NEIGHBOURS = 5
"""Neighbouring detections the cascade needs for a face on a turned frame (3 on the frame as it is):
a turned frame gives the detector another chance at a false face (the performer rolled 33°: a box
on its neck, whose "pupils" scored 9.2), and a real face there is found by many neighbours (all the
``tilt`` copies' frames still are)."""
ROLL_MARGIN = 0.5
"""How much better a turned frame's pupil pair must score than the upright frame's to be taken."""
ROLL_SURE = 10.0
"""A pupil pair scoring this much is taken without trying the other turns (a level face's scores
10-11.6 on the shared clips and their copies; the wrong pairs on rolled heads at most 9.3): auto
start stays at about 55 ms for most faces, 150 ms when every turn is tried."""
LINE_HALF = 0.2
"""Half-width (× the inter-pupil distance) of the band across the face the mouth's line is read on."""


class AutoInitError(RuntimeError):
    """The detectors found no usable face (one-line message)."""


EYE_WI = REFINE_WI
"""Inter-pupil distance (px, the face box's estimate) of the upright picture the eyes are looked for
in (the limbus arcs of :func:`tracker.eyes.limbus_scores` are sized for it)."""
EYE_REACH = (0.35, 0.25)
"""How far (× the box's inter-pupil distance, across and along the face) each eye is looked for
around the box's guess: the box puts real eyes 5–10 %, at times 20 % (a rolled head), off."""
PEAKS = 4
"""Local maxima each cue map gives as candidates, per eye."""
BAR_RUN = 0.55
"""Length (× :data:`EYE_WI`) of a level thin dark line from which it is a spectacle rim's bar, not an
eye (:func:`rim_bars`): an eye with its lashes and eyeliner is under 0.45 across (the shared clips and
their copies: 0-0.44), a rim's upper or lower bar 0.65 or more."""
BAR_TALL = 0.35
"""Height (× :data:`EYE_WI`) of an upright thin dark line from which it is a rim's side, not an eye
(a narrowed eye with its lashes is under 0.2 tall; a lens 0.4-0.5)."""
PAIR_DISTANCE = 0.2
"""|log(pair distance / the box's estimate)| that costs nothing (real faces' boxes: 0.9–1.17)."""
PAIR_WEIGHTS = {"votes": 4.0, "iris": 0.5, "rim": 0.5, "mirror": 2.0, "tilt": 4.0, "distance": 10.0, "near": 2.0}
"""Weights of a candidate pair's score (see :func:`find_pupils`): ``votes``, ``iris`` and ``rim``
per eye (each against the best of its eye's candidates), ``mirror`` for the eyes' likeness,
``tilt`` per unit of the pair's slope, ``distance`` per unit of |log| distance past
:data:`PAIR_DISTANCE`, ``near`` at the edge of :data:`EYE_REACH` (0 at the box's guess)."""


def _upright(grey: np.ndarray, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The eye band, upright and scaled to :data:`EYE_WI` px between ``left`` and ``right``
    (frame px, the box's guess, level), and the affine (2×3) from frame px to its px; the
    guessed eyes sit at ``(w/2 ∓ EYE_WI/2, h/2)``."""
    ipd = max(math.dist(left, right), 1e-6)
    k = EYE_WI / ipd
    mid = 0.5 * (np.asarray(left, np.float64) + np.asarray(right, np.float64))
    w = int(round(2 * (0.5 + EYE_REACH[0] + 0.3) * EYE_WI))
    h = int(round(2 * (EYE_REACH[1] + 0.3) * EYE_WI))
    m = np.array([[k, 0.0, 0.5 * w - k * mid[0]], [0.0, k, 0.5 * h - k * mid[1]]])
    src = grey if k >= 0.7 else cv2.GaussianBlur(grey, (0, 0), 0.4 / k)  # no aliasing when shrinking
    return cv2.warpAffine(src, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE), m


def centre_votes(band: np.ndarray, centre: tuple[float, float], reach: tuple[float, float]) -> np.ndarray:
    """How well each place within ``reach`` (px, half-size) of ``centre`` (px) of ``band`` is the
    centre of a dark round thing: the mean squared share of the strong grey gradients around it
    that point straight away from it (Timm & Barth 2011, "Accurate eye centre localisation by
    means of gradients"), times how dark it is (0 at the window's 95th percentile of grey, 1 at
    its 5th). Every edge of an iris or a pupil points away from its centre, whatever the iris's
    colour and however much of it the lids hide; a lash line, a crease or a brow's edges point
    away from a line, not a point. Returns the map (rows: y from ``centre[1] - reach[1]``)."""
    cx, cy = int(round(centre[0])), int(round(centre[1]))
    rx, ry = int(round(reach[0])), int(round(reach[1]))
    gr = int(round(0.15 * EYE_WI))  # gradients come from a little further out than the centres
    h, w = band.shape
    x0, x1 = max(cx - rx - gr, 1), min(cx + rx + gr + 1, w - 1)
    y0, y1 = max(cy - ry - gr, 1), min(cy + ry + gr + 1, h - 1)
    sub = cv2.GaussianBlur(band, (0, 0), 1.0)[y0:y1, x0:x1]
    gx = cv2.Sobel(sub, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(sub, cv2.CV_32F, 0, 1, ksize=3)
    mag = cv2.magnitude(gx, gy)
    ys, xs = np.nonzero(mag > mag.mean() + 0.3 * mag.std())
    cxs = np.arange(cx - rx, cx + rx + 1, dtype=np.float32)
    cys = np.arange(cy - ry, cy + ry + 1, dtype=np.float32)
    if len(xs) == 0:
        return np.zeros((len(cys), len(cxs)), np.float32)
    m = mag[ys, xs]
    ux, uy = gx[ys, xs] / m, gy[ys, xs] / m
    px, py = (xs + x0).astype(np.float32), (ys + y0).astype(np.float32)
    out = np.empty((len(cys), len(cxs)), np.float32)
    for j, yc in enumerate(cys):  # a row of centres at a time: (centres × gradients)
        dx = px[None, :] - cxs[:, None]
        dy = (py - yc)[None, :]
        dot = (dx * ux + dy * uy) / (np.sqrt(dx * dx + dy * dy) + 1e-3)
        np.maximum(dot, 0.0, out=dot)
        out[j] = (dot * dot).mean(axis=1)
    smooth = cv2.GaussianBlur(band, (0, 0), 2.0)
    win = smooth[max(cy - ry, 0): cy + ry + 1, max(cx - rx, 0): cx + rx + 1]
    lo, hi = np.percentile(win, (5, 95))
    yy = np.clip(cys.astype(int), 0, h - 1)[:, None]
    xx = np.clip(cxs.astype(int), 0, w - 1)[None, :]
    dark = np.clip((hi - smooth[yy, xx]) / max(hi - lo, 1.0), 0.0, 1.0)
    return out * dark


def iris_contrast(band: np.ndarray) -> np.ndarray:
    """At every place of ``band``: the grey of the darker of two small boxes left and right of an
    iris-sized disc there (the white of the eye) minus the disc's mean — high on an iris, low
    on brows, lashes and shadows, which are dark but have no white beside them, and on an eye's
    dark corner, which has white on one side only (on a dark face their mean put it above the iris)."""
    r = IRIS_RADIUS * EYE_WI
    kd = int(round(1.6 * r)) | 1
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kd, kd)).astype(np.float32)
    disc /= disc.sum()
    bw = max(int(round(0.5 * r)), 1)
    bh = max(int(round(0.8 * r)), 1) | 1
    off = int(round(1.35 * r))
    left = np.zeros((bh, 2 * off + bw), np.float32)
    left[:, :bw] = 1.0 / (bw * bh)
    right = left[:, ::-1].copy()
    sides = np.minimum(cv2.filter2D(band, -1, left, borderType=cv2.BORDER_REPLICATE),
                       cv2.filter2D(band, -1, right, borderType=cv2.BORDER_REPLICATE))
    return sides - cv2.filter2D(band, -1, disc, borderType=cv2.BORDER_REPLICATE)


def _blobs(band: np.ndarray, sigma: float) -> np.ndarray:
    """Dark-blob strength (grey levels) at scale ``sigma`` px: σ²·√det(Hessian) where both
    curvatures are upward (a dark spot: a pupil, an iris), 0 on lines and bright things."""
    g = cv2.GaussianBlur(band, (0, 0), sigma)
    xx = cv2.Sobel(g, cv2.CV_32F, 2, 0, ksize=3)
    yy = cv2.Sobel(g, cv2.CV_32F, 0, 2, ksize=3)
    xy = cv2.Sobel(g, cv2.CV_32F, 1, 1, ksize=3)
    d = xx * yy - xy * xy
    d[(xx <= 0) | (yy <= 0)] = 0.0
    return sigma * sigma * np.sqrt(np.maximum(d, 0.0))


def _peaks(m: np.ndarray, k: int, apart: int = 4) -> list[tuple[int, int]]:
    """The ``k`` highest local maxima (x, y) of ``m``, at least ``apart`` px from a higher one."""
    dil = cv2.dilate(m, np.ones((2 * apart + 1, 2 * apart + 1), np.uint8))
    ys, xs = np.nonzero((m >= dil) & (m > 0))
    order = np.argsort(-m[ys, xs])[:k]
    return [(int(xs[j]), int(ys[j])) for j in order]


def rim_bars(band: np.ndarray) -> np.ndarray:
    """Where ``band`` (grey, at :data:`EYE_WI`) has a spectacle rim's bar (bool, its shape): thin dark
    pixels (:func:`tracker.eyes.thin_dark`) on a level run of at least :data:`BAR_RUN` or an upright
    run of at least :data:`BAR_TALL` (each allowing a pixel's slant), grown by a pixel."""
    bar = thin_dark(np.asarray(band, dtype=np.float32), EYE_WI).astype(np.uint8)
    out = np.zeros_like(bar)
    for level, n in ((True, BAR_RUN), (False, BAR_TALL)):
        k = max(int(round(n * EYE_WI)), 3)
        slack = cv2.dilate(bar, np.ones((3, 1) if level else (1, 3), np.uint8))
        line = np.ones((1, k) if level else (k, 1), np.uint8)
        out |= cv2.morphologyEx(slack, cv2.MORPH_OPEN, line) & bar
    return cv2.dilate(out, np.ones((3, 3), np.uint8)).astype(bool)


def _rim_circle(grad: tuple[np.ndarray, np.ndarray], p: tuple[float, float]) -> tuple[float, float, float, float]:
    """The limbus's strength at ``p`` (band px): the best mean outward grey step on the sides of an
    iris-sized circle centred within 2 px of it (see :func:`tracker.eyes.limbus_centre`), and that
    circle's centre and radius ``(strength, x, y, r)``."""
    s = limbus_scores(grad, p)
    grid, c = limbus_grid(), s.shape[1] // 2
    near = s[:, c - 2 : c + 3, c - 2 : c + 3]
    k, i, j = np.unravel_index(int(near.argmax()), near.shape)
    return (float(near[k, i, j]), float(p[0] + grid.offs[c - 2 + i]), float(p[1] + grid.offs[c - 2 + j]),
            float(grid.radii[k]))


def _mirror(band: np.ndarray, a: tuple[float, float], b: tuple[float, float]) -> float:
    """Normalised correlation of the eye round ``a`` with the eye round ``b`` (both cut upright along
    the line a→b), mirrored or as it is, whichever is higher: two real eyes are mirror images, and
    glancing aside, both irises to one side, copies of each other; an iris and a lid crease, or a
    brow, are neither. Mirroring alone took two dark outer corners for the pair of an eye glancing
    aside (expr_d0's frame 19: a pupil 40 % of the eye distance off, on the corner)."""
    ang = math.atan2(b[1] - a[1], b[0] - a[0])
    pw, ph = int(round(0.44 * EYE_WI)), int(round(0.24 * EYE_WI))
    c, s = math.cos(ang), math.sin(ang)
    cuts = []
    for p in (a, b):
        m = np.array([[c, s, 0.5 * pw - (c * p[0] + s * p[1])], [-s, c, 0.5 * ph - (-s * p[0] + c * p[1])]])
        cuts.append(cv2.warpAffine(band, m, (pw, ph), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE))
    return max(float(cv2.matchTemplate(cuts[0], other, cv2.TM_CCOEFF_NORMED)[0, 0]) for other in (cv2.flip(cuts[1], 1), cuts[1]))


def find_pupils(grey: np.ndarray, box: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Both pupils (frame px, image-left first) of the face in the detector's ``box``: see
    :func:`pupil_pair`."""
    left, right, _ = pupil_pair(grey, box)
    return left, right


def pupil_pair(grey: np.ndarray, box: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray, float]:
    """Both pupils (frame px, image-left first) of the face in the detector's ``box``.

    The box guesses the eyes (:func:`eyes_in_box`); around each guess, in an upright picture
    at :data:`EYE_WI`, the candidates are the best places of three cues — gradients pointing
    away from a dark centre (:func:`centre_votes`), an iris-sized disc with white beside it
    (:func:`iris_contrast`) and a dark blob (:func:`_blobs`). Every pair of a left and a right
    candidate is scored by each one's votes, disc contrast and limbus (each against the best
    of its eye), how alike the two eyes are mirrored (:func:`_mirror`), less its tilt, how far its
    length is from the box's estimate and how far each eye is from the box's guess; the best
    pair wins. One eye alone can be fooled
    (a lid crease, a made-up corner, a frame of glasses); both fooled alike, mirror images of
    each other, level and the right distance apart, rarely are. Returns the pair (frame px,
    image-left first) and its score (higher is better, about 12 at most; −inf: no pair)."""
    prior = eyes_in_box(box)
    band, m = _upright(grey, prior[0], prior[1])
    h, w = band.shape
    rx, ry = EYE_REACH[0] * EYE_WI, EYE_REACH[1] * EYE_WI
    contrast = iris_contrast(band)
    blobs = _blobs(band, 0.0625 * EYE_WI)
    # a spectacle rim's bars are dark lines with skin on both sides: their middles draw the votes of
    # a dark round thing and the contrast of a disc with white beside it, but they run on well past
    # an eye's size, and give no candidates (the cues are still weighed against their best anywhere:
    # a heavy lash line can pass for a bar, and leaving it out must not change the eyes' weights)
    bars = rim_bars(band)
    keep = ~bars if bars.any() else None
    grad = limbus_gradients(band)
    eyes = []
    for cx in (0.5 * w - 0.5 * EYE_WI, 0.5 * w + 0.5 * EYE_WI):
        cy = 0.5 * h
        votes = centre_votes(band, (cx, cy), (rx, ry))
        ox, oy = int(round(cx)) - int(round(rx)), int(round(cy)) - int(round(ry))
        vh, vw = votes.shape
        cands: list[tuple[int, int]] = []
        for mp in (votes, contrast[oy : oy + vh, ox : ox + vw], blobs[oy : oy + vh, ox : ox + vw]):
            mp = np.ascontiguousarray(mp, dtype=np.float32) if keep is None else np.where(keep[oy : oy + vh, ox : ox + vw], mp, 0.0).astype(np.float32)
            for x, y in _peaks(mp, PEAKS):
                if all(abs(x - u) > 2 or abs(y - v) > 2 for u, v in cands):
                    cands.append((x, y))
        if not cands:
            cands = [(vw // 2, vh // 2)]
        vmax = max(float(votes.max()), 1e-6)
        cmax = max(float(contrast[oy : oy + vh, ox : ox + vw].max()), 1e-6)
        rims = [_rim_circle(grad, (x + ox, y + oy))[0] for x, y in cands]
        rmax = max(max(rims), 1e-6)
        near = PAIR_WEIGHTS["near"]
        eyes.append([((x + ox, y + oy), float(votes[max(y - 1, 0) : y + 2, max(x - 1, 0) : x + 2].max()) / vmax,
                      float(contrast[y + oy, x + ox]) / cmax, r / rmax,
                      near * (((x + ox - cx) / rx) ** 2 + ((y + oy - cy) / ry) ** 2)) for (x, y), r in zip(cands, rims)])
    wt = PAIR_WEIGHTS
    best, pick = -math.inf, None
    for pa, va, ca, ra, na in eyes[0]:
        for pb, vb, cb, rb, nb in eyes[1]:
            dx, dy = pb[0] - pa[0], pb[1] - pa[1]
            d = math.hypot(dx, dy)
            if not 0.6 * EYE_WI < d < 1.6 * EYE_WI:
                continue
            score = (wt["votes"] * (va + vb) + wt["iris"] * (ca + cb) + wt["rim"] * (ra + rb) - na - nb
                     - wt["tilt"] * abs(dy) / d - wt["distance"] * max(abs(math.log(d / EYE_WI)) - PAIR_DISTANCE, 0.0))
            if score + wt["mirror"] <= best:
                continue  # the mirror cannot lift it past the best
            score += wt["mirror"] * _mirror(band, pa, pb)
            if score > best:
                best, pick = score, (pa, pb)
    if pick is None:
        return prior[0].copy(), prior[1].copy(), -math.inf
    inv = cv2.invertAffineTransform(m)
    pts = np.array(pick, dtype=np.float64) @ inv[:, :2].T + inv[:, 2]
    return pts[0], pts[1], best


def _band(img: np.ndarray, origin: np.ndarray, along: np.ndarray, across: np.ndarray, n: int, half: int) -> np.ndarray:
    """``img`` sampled (bilinear) on ``n`` rows 1 px apart from ``origin`` along ``along``, each row
    ``±half`` px along ``across``: an (n, 2·half + 1) float32 array."""
    ts = np.arange(n, dtype=np.float32).reshape(-1, 1)
    offs = np.arange(-half, half + 1, dtype=np.float32).reshape(1, -1)
    mx = (origin[0] + ts * along[0] + offs * across[0]).astype(np.float32)
    my = (origin[1] + ts * along[1] + offs * across[1]).astype(np.float32)
    return cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def _strip(img: np.ndarray, origin: np.ndarray, along: np.ndarray, across: np.ndarray, n: int, half: int) -> np.ndarray:
    """Mean grey of ``n`` samples (1 px apart) from ``origin`` along ``along``, each averaged over
    ``±half`` px along ``across`` (:func:`_band`'s rows' means)."""
    return _band(img, origin, along, across, n, half).mean(axis=1)


def _valleys(profile: np.ndarray, a: int, b: int) -> list[int]:
    """The rows ``a..b-1`` of ``profile`` no darker than the rows on either side of them (``1 <= a``,
    ``b < len(profile)``)."""
    return [i for i in range(a, b) if profile[i] <= profile[i - 1] and profile[i] <= profile[i + 1]]


def _brow(grey: np.ndarray, pupil: tuple[float, float], ipd: float, up: np.ndarray,
          rim: tuple[float, float] | None = None) -> tuple[float, float]:
    """A point in the upper half of the darkest band above a pupil, along ``up``: halfway from its
    middle to its upper edge (the grey halfway from the band's darkest to the forehead above). The
    lid's shadow often darkens a brow's lower edge (on a dark face it is darker than the brow), so
    the band's middle sits low in the brow, and calibration, which takes the darkest band within
    0.08 eye distances of the point, took the lid's crease; a person clicks higher, the brow's
    middle. ``rim``: the distances (px along ``up``) of a spectacle rim's upper bar, filled in
    first (it is darker than many brows)."""
    n = int(round((BROW_RANGE[1] + HAIR_PAST) * ipd)) + 2
    side = np.array([-up[1], up[0]])
    prof = _strip(grey, np.asarray(pupil, dtype=np.float64), up, side, n, max(int(0.12 * ipd), 1))
    if rim is not None:
        fill_rows(prof, rim[0], rim[1])
    lo, hi = int(BROW_RANGE[0] * ipd), int(BROW_RANGE[1] * ipd)
    seg = prof[lo:hi]
    if len(seg) < 3:
        raise AutoInitError("the face is too small to find its eyebrows")
    # the upper lid and its lashes are dark too, but lie below the range; keep the centre in it
    k = lo + int(np.argmin(seg))
    span = float(seg.max()) - float(prof[k])
    if k - lo >= 3 and float(prof[k:].max()) <= float(prof[k]) + BROW_BAND * span:
        # dark from the darkest row up past the range's top: hair, a fringe or a hat's band reaching
        # down into the range, not a brow (a brow has the forehead above it, a raised one just past the
        # range); the brow is the darkest row under the forehead between them (the top of the rise
        # going down from the darkness)
        j = k
        while j - 1 >= lo and prof[j - 1] >= prof[j]:
            j -= 1
        if j - lo >= 2:
            b = lo + int(np.argmin(prof[lo:j]))
            if float(prof[b]) < float(prof[j]) - BROW_BAND * (float(prof[j]) - float(prof[k])):
                k = b
    if prof[k - 1] < prof[k]:
        # darkest at the range's start and darker still below it: a low brow that begins under the
        # range (expr_d18's, 0.15 eye distances over the pupils), or a child's larger eye whose lid
        # and lashes reach into it with the brow higher up: then a band in the range, clearly darker
        # than the skin on both sides of it, is the brow
        contrast = float(seg.max() - seg.min())
        bands = [i for i in _valleys(prof, lo + 1, hi - 1)
                 if min(float(prof[lo:i].max()), float(prof[i:hi].max())) - float(prof[i]) >= BROW_BAND * contrast]
        if bands:
            k = min(bands, key=prof.__getitem__)
    d = min(max(brow_centre(prof, k, max(int(0.05 * ipd), 2)), lo), hi)
    above = prof[k:hi]
    top = k + int(np.argmax(above >= 0.5 * (prof[k] + float(above.max()))))
    d = 0.5 * (d + top)
    return (float(pupil[0] + d * up[0]), float(pupil[1] + d * up[1]))


def find_brows(grey: np.ndarray, left: np.ndarray, right: np.ndarray) -> list[tuple[float, float]]:
    """Both brow points (frame px) above the pupils ``left`` and ``right`` (:func:`_brow`), with
    any spectacle rim's upper bar (:func:`tracker.eyes.spectacle_rims`, found on the eye band at the
    eye finder's scale) filled in first."""
    ipd = math.dist(left, right)
    up = np.array([(right[1] - left[1]) / ipd, -(right[0] - left[0]) / ipd])
    band, m = _upright(grey, left, right)
    at = np.array([left, right], dtype=np.float64) @ m[:, :2].T + m[:, 2]
    f = ipd / EYE_WI
    rims = [None if r is None else (-r[1] * f, -r[0] * f) for r in spectacle_rims(band, at, EYE_WI)]
    return [_brow(grey, tuple(p), ipd, up, r) for p, r in zip((left, right), rims)]


def _lip_reds(red: np.ndarray, skin_red: float, reddest_in: int | None) -> tuple[int, float, np.ndarray]:
    """The reddest row of a Lab a* profile ``red`` among its first ``reddest_in`` rows, its lead over
    the skin (``skin_red``), and which rows are redder than the skin by half that lead."""
    j = int(np.argmax(red[:reddest_in]))
    lead = float(red[j]) - skin_red
    return j, lead, red >= skin_red + 0.5 * lead


def _lip_span(red: np.ndarray, skin_red: float, ipd: float, reddest_in: int | None = None) -> tuple[int, int] | None:
    """The rows of a profile of Lab a* (``red``, rows down the face) that hold the lips: the run of
    rows redder than the skin (``skin_red``) by half the reddest row's lead, round the reddest row,
    joined with other such runs within :data:`LIP_GAP` eye distances (an open mouth's two lips);
    None when no row is :data:`LIP_RED` redder than the skin (pale lips, a colourless camera).
    ``reddest_in``: the reddest row is looked for in the first rows only (a chin pinker than
    brownish lips is not where they are)."""
    j, lead, reds = _lip_reds(red, skin_red, reddest_in)
    if lead < LIP_RED:
        return None
    reds = np.flatnonzero(reds)  # holds j
    runs = np.split(reds, np.flatnonzero(np.diff(reds) > max(int(round(LIP_GAP * ipd)), 1)) + 1)
    run = next(r for r in runs if r[0] <= j <= r[-1])
    return int(run[0]), int(run[-1])


def _nose_red(red: np.ndarray, skin_red: float, reddest_in: int) -> int:
    """Where the lips' rows (:func:`_lip_span`) begin at the range's very start but the reddest row lies
    in a later run of red rows: the row after that first run, which is the skin under the nose,
    reddened round the nostrils (the nostrils' shadow is a dark valley at the top of it), and no lip:
    a lip lies below :data:`MOUTH_RANGE`'s start. 1 (the first row a valley can be on) where the
    first run holds the reddest row — then it is lips. ``reddest_in`` as for :func:`_lip_span`."""
    j, _, reds = _lip_reds(red, skin_red, reddest_in)
    end = 0
    while end < len(reds) and reds[end]:
        end += 1
    return 1 if j < end else end + 1


def _two_red_lips(red: np.ndarray, span: tuple[int, int], skin_red: float) -> bool:
    """Whether the lips' rows ``span`` (:func:`_lip_span` of the Lab a* profile ``red``) are two red
    runs with rows under half the span's lead over the skin between them: the upper lip is red itself,
    so no teeth show above the span (a lit philtrum over a red upper lip is as bright as teeth: the
    third-size copy of talk_a put the mouth point on it, a fifth of the eye distance high)."""
    a, b = span
    inner = red[a : b + 1]
    return bool(np.any(inner < skin_red + 0.5 * (float(inner.max()) - skin_red)))


def _teeth_rows(band: np.ndarray, a: int, ipd: float) -> tuple[int, int] | None:
    """The first and last of the rows of the mouth's ``band`` (rows down the face from
    :data:`MOUTH_RANGE`'s start) that show teeth just above the lips' red, which begins at row ``a``
    (within :data:`TEETH_OVER` eye distances above it, or a little into it): rows whose brightest
    tenth is brighter, by :data:`TEETH_LEAD`, than any row of the skin between the nose and there
    (teeth are whiter than the skin round them, in the same light; the cheeks beside the mouth are
    no yardstick, a lamp above the face leaves them darker than the philtrum); None when none are,
    or when the band shows less than 0.1 eye distances of that skin."""
    p90 = np.percentile(band, 90, axis=1)
    lo, hi = max(a - int(round(TEETH_OVER * ipd)), 0), min(a + max(int(round(LINE_OVER * ipd)), 1), len(band))
    if lo < max(int(round(0.1 * ipd)), 2):
        return None
    level = (1.0 + TEETH_LEAD) * float(p90[:lo].max())
    rows = [i for i in range(lo, hi) if p90[i] > level]
    return (rows[0], rows[-1]) if rows else None


def _darkest_valley(profile: np.ndarray) -> int:
    """The darkest row of ``profile`` that is a valley (no darker than the rows on either side of it),
    or its darkest row when it has none. A line across the face has lighter rows on both sides; the
    range's end does not: where the grey still falls there (the shadow under the chin, a dark collar
    or background below it), its darkest row is only where the range was cut (a laughing face with no
    lip colour in a warm photo: the point went to the neck, about 1.5 eye distances below the eyes,
    the grin at 0.85)."""
    inner = _valleys(profile, 1, len(profile) - 1)
    return min(inner, key=profile.__getitem__) if inner else int(np.argmin(profile))


def _mouth(grey: np.ndarray, left: np.ndarray, right: np.ndarray, lab_a: np.ndarray | None = None,
           chin: float | None = None) -> tuple[float, float]:
    """The mouth's centre: the darkest line across the face in :data:`MOUTH_RANGE` below the eyes —
    inside the lips where their colour shows them (``lab_a``, the frame's Lab a* as float32: rows
    redder than the cheeks; :func:`_lip_span`): a beard, a moustache or the shadow under the lower
    lip is darker than the gap between closed lips, but not redder than the skin. There the darkest
    valley between the lips' first and last rows or just above them (a closed mouth's gap, an open
    mouth's inside; :data:`LINE_OVER`), on the rows' mean grey; without the lips' colour the line
    must also be told from the nostrils, so on :data:`LINE_SHARE` of each row. ``chin`` (optional): the
    face detector's box's bottom row (frame px); the range ends there where that comes first (see
    :data:`BOX_MOUTH`)."""
    ipd = math.dist(left, right)
    u = (right - left) / ipd
    down = np.array([-u[1], u[0]])
    mid = 0.5 * (left + right)
    start = mid + MOUTH_RANGE[0] * ipd * down
    end = MOUTH_RANGE[1]
    if chin is not None and down[1] > 0.5:  # the box's bottom, along the face from the eyes (ipd)
        end = min(end, max((chin - mid[1]) / (down[1] * ipd), MOUTH_RANGE[0] + BOX_MOUTH))
    n = int(round((end - MOUTH_RANGE[0]) * ipd))
    if n < 3:
        raise AutoInitError("the face is too small to find its mouth")
    half, sigma = max(int(LINE_HALF * ipd), 1), max(0.02 * ipd, 0.5)

    def smooth(profile: np.ndarray) -> np.ndarray:  # along the face, σ 0.02 eye distances
        return cv2.GaussianBlur(np.asarray(profile, np.float32).reshape(-1, 1), (1, 0), sigma).ravel()

    band = _band(grey, start, down, u, n, half)
    valley = smooth(np.percentile(band, LINE_SHARE, axis=1))
    k = _darkest_valley(valley)
    if lab_a is not None:
        red = smooth(_strip(lab_a, start, down, u, n, half))
        cheeks = [_strip(lab_a, mid + 0.75 * ipd * down + s * 0.45 * ipd * u, down, u, max(int(0.15 * ipd), 2), max(int(0.08 * ipd), 1))
                  for s in (-1.0, 1.0)]
        skin_red = float(np.median(np.concatenate(cheeks)))
        reddest_in = max(int(round((LIPS_ABOVE - MOUTH_RANGE[0]) * ipd)), 1)
        span = _lip_span(red, skin_red, ipd, reddest_in)
        if span is not None:
            a, b = span
            # the line may also lie just over the span: an upper lip darker than it is red (in
            # shade, on a darker face) falls short of the span while the lower lip holds it. A thin
            # line between closed lips right under a dark moustache leaves no valley once smoothed
            # (the grey only rises from the moustache down): then the rows' own means say where it is
            # (a painted beard round expr_d18: the point on the lower lip's middle, 7 % of the eye
            # distance low, and calibration learned the moustache for the upper lip)
            top = max(a - max(int(round(LINE_OVER * ipd)), 1), 1)
            if a == 0:
                top = max(top, _nose_red(red, skin_red, reddest_in))
            k, valley = (a + b) // 2, None
            means = band.mean(axis=1)
            for prof in (smooth(means), means):
                inner = _valleys(prof, top, b)
                if inner:
                    k, valley = min(inner, key=prof.__getitem__), prof
                    break
            teeth = None if _two_red_lips(red, span, skin_red) else _teeth_rows(band, a, ipd)
            if teeth is not None:
                # upper teeth between a pale upper lip and the red lower lip: the mouth is open there,
                # its line at the teeth's top or bottom edge (the ``late`` copy of expr_d6 with --auto:
                # the shade under the lower lip, darker than either, was taken for the line, and
                # calibration learned the lower lip alone as the mouth)
                over = max(int(round(LINE_OVER * ipd)), 1)
                near = _valleys(prof, max(teeth[0] - over, 1), min(teeth[1] + over + 1, n - 1))
                k, valley = (min(near, key=prof.__getitem__), prof) if near else ((teeth[0] + teeth[1]) // 2, None)
    t = float(k)
    if valley is not None and 0 < k < n - 1:  # between rows: the valley's bottom
        t += parabola_offset(valley[k - 1], valley[k], valley[k + 1])
    return (float(start[0] + t * down[0]), float(start[1] + t * down[1]))


def _face_cascade_check() -> None:
    if face_cascade() is None:
        raise AutoInitError("this OpenCV build ships no Haar cascades (use --init CLICKS.json instead)")


EYES_SHOWN = 2.0
"""Least :func:`eyes_shown` for a frame to show both eyes open. On the shared clips, frames where
the peer has the eyes at under 0.3 of their usual opening: 81 % of them under this; open ones (over
0.8 of it): 2 % under (7.7 median). The first frame of every shared clip and of all their copies:
2.2 or more."""
SHUT_LINE = 1.0
"""What :func:`eyes_shown` takes off an eye whose best circle's edge runs along its arcs as much as
across them (:meth:`tracker.eyes._LimbusGrid.across` under 0): a shut lid's line, which eyeliner or
heavy lashes can make as strong as a limbus, cut at a slant by the circle's sides. With it, shut
frames of the shared clips under :data:`EYES_SHOWN`: two thirds → 81 %; open ones: 2 % either way;
the first frames of the dark-skinned copies, whose light irises' edges run the other way, stay over
3.9."""


def eyes_shown(frame_bgr: np.ndarray, clicks: Clicks) -> float:
    """How plainly the weaker of the two eyes shows an iris at the clicked pupils: the limbus's
    strength there (the best outward grey step round an iris-sized circle centred within 2 px of the
    pupil, :func:`tracker.eyes.limbus_scores`) over the median grey gradient of the eye band, in an
    upright picture at :data:`EYE_WI`, less :data:`SHUT_LINE` where that circle's edge is a line
    crossing it rather than a ring. A shut eye's lid and lashes have edges but mostly no ring of
    them; see :data:`EYES_SHOWN`."""
    grey = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2GRAY).astype(np.float32)
    left = np.asarray(clicks.left_pupil, np.float64) - PIXEL_CENTRE
    right = np.asarray(clicks.right_pupil, np.float64) - PIXEL_CENTRE
    band, m = _upright(grey, left, right)
    gx, gy = limbus_gradients(band)
    level = max(float(np.median(cv2.magnitude(gx, gy))), 1e-3)
    out = []
    for p in (left, right):
        q = m[:, :2] @ p + m[:, 2]
        strength, x, y, r = _rim_circle((gx, gy), (float(q[0]), float(q[1])))
        line = limbus_grid().across(gx, gy, x, y, r) < 0.0
        out.append(strength / level - (SHUT_LINE if line else 0.0))
    return min(out)


def auto_clicks(frame_bgr: np.ndarray, frame_index: int = 0) -> Clicks:
    """The five clicks for the largest face in ``frame_bgr``; raises :class:`AutoInitError`."""
    if not (isinstance(frame_bgr, np.ndarray) and frame_bgr.ndim == 3 and frame_bgr.shape[2] == 3):
        raise AutoInitError("auto init needs a BGR (H, W, 3) frame")
    _face_cascade_check()
    h, w = frame_bgr.shape[:2]
    best = None
    for angle in ROLL_TRIES:  # the cascade finds faces near upright only, and the pupils' pair is looked for level
        turn = cv2.getRotationMatrix2D((0.5 * (w - 1), 0.5 * (h - 1)), angle, 1.0)
        img = frame_bgr if angle == 0 else cv2.warpAffine(frame_bgr, turn, (w, h), flags=cv2.INTER_LINEAR,
                                                         borderMode=cv2.BORDER_REPLICATE)
        faces = detect_faces(img, None, neighbours=3 if angle == 0 else TURNED_NEIGHBOURS)
        if not faces:
            continue
        grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float32)
        left, right, score = pupil_pair(grey, faces[0])
        if best is None or score > best[0] + (ROLL_MARGIN if best[1] == 0 else 0.0):
            best = (score, angle, turn, img, grey, left, right, faces[0])
        if best[0] >= ROLL_SURE:
            break
    if best is None:
        raise AutoInitError("no face found by the bundled face detector (use --init CLICKS.json instead)")
    _, _, turn, img, grey, left, right, box = best
    found = _clicks_in(img, grey, left, right, box[1] + box[3])
    back = cv2.invertAffineTransform(turn)
    d = {"frame": int(frame_index)}
    for k, p in found.items():
        q = back[:, :2] @ np.asarray(p, dtype=np.float64) + back[:, 2]
        d[k] = [float(q[0]), float(q[1])]
    return Clicks.from_dict(d, where="auto init").moved(PIXEL_CENTRE, PIXEL_CENTRE)


def _clicks_in(frame_bgr: np.ndarray, grey: np.ndarray, left: np.ndarray, right: np.ndarray,
               chin: float | None = None) -> dict[str, tuple[float, float]]:
    """The five points (OpenCV px) of the face whose pupils :func:`pupil_pair` put at ``left`` and
    ``right`` in ``frame_bgr`` (``grey``: its grey, float32): pupils, brows, mouth. ``chin``: the face
    detector's box's bottom row (px), past which the mouth is not looked for (:func:`_mouth`)."""
    # snapped to the limbus as calibration snaps clicks, before the brows and the mouth are looked for
    # from them: the candidates' cues are sized for an adult's iris (IRIS_RADIUS), and a child's
    # larger one put them 4 % of the eye distance low, the mouth's search with them
    left, right = (np.asarray(p, dtype=np.float64) for p in refine_pupils(grey, left, right))
    brows = find_brows(grey, left, right)
    lab_a = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2LAB)[..., 1].astype(np.float32)
    mouth = _mouth(grey, left, right, lab_a, chin)
    return {"left_pupil": (float(left[0]), float(left[1])), "right_pupil": (float(right[0]), float(right[1])),
            "left_brow": tuple(brows[0]), "right_brow": tuple(brows[1]), "mouth": tuple(mouth)}


AUTO_TRIES = 10
"""How many of a video's first frames :func:`auto_start` tries one by one."""
AUTO_EVERY = 0.2
"""After :data:`AUTO_TRIES` frames without a face, :func:`auto_start` tries one frame in this many
seconds, to the end of the video: a recording that opens on an empty room or a title, or a camera
started before the performer sits down, still starts where the face comes."""
AUTO_LOOK = (30, 2)
"""Where the first face found has its eyes shut (:func:`eyes_shown`), :func:`auto_start` looks on
this many frames past it, every so many frames, and takes the first frame whose eyes show (or, when
none does, the one whose eyes show most): a blink lasts 3-5 frames, and an eye model learned from
shut eyes misreads the whole clip. The first open frame, not the most open one in the second: the
face a second on may be in another pose or expression, and the clicks made by hand are carried to
the first open frame too (:mod:`tracker.open_eyes`). The ``late`` copies of the shared clips with
``--auto``: talk_b, whose first frame catches a blink, calibrated 26 frames on, mid-word, and its
opening followed the peer at r 0.69; 0.91 from frame 4."""


def auto_start(frames: Iterable[tuple[int, np.ndarray]], fps: float = 30.0,
               progress: Callable[[int], None] | None = None) -> tuple[Clicks, np.ndarray]:
    """The clicks (:func:`auto_clicks`) and the frame to calibrate on, from ``frames`` (``(index, BGR
    image)`` in order: a video file or a camera): the first frame with a face whose eyes show
    (:data:`EYES_SHOWN`), or — where they look shut — the first within :data:`AUTO_LOOK` of it whose
    eyes show (none: the one whose eyes show most). Frames are tried one by one at first, then one
    every :data:`AUTO_EVERY` s; ``progress`` (optional) is called with each frame's index tried while
    no face has been found (a long empty opening takes a while). Raises :class:`AutoInitError` (one
    line) when no frame holds a face."""
    stride = max(int(round(AUTO_EVERY * fps)), 1)
    last: AutoInitError | None = None
    best: tuple[float, Clicks, np.ndarray] | None = None  # eyes shown, points, frame
    first = 0  # the first frame with a face
    tried = 0
    for i, img in frames:
        if best is not None:
            if i - first >= AUTO_LOOK[0]:
                break
            if (i - first) % AUTO_LOOK[1]:
                continue
        elif tried >= AUTO_TRIES and (i - AUTO_TRIES) % stride:
            continue
        tried += 1
        if progress is not None and best is None:
            progress(i)
        try:
            found = auto_clicks(img, frame_index=i)
        except AutoInitError as e:
            last = e
            continue
        shown = eyes_shown(img, found)
        if shown >= EYES_SHOWN:
            return found, img
        if best is None:
            first = i
        if best is None or shown > best[0]:
            best = (shown, found, img)
    if best is not None:
        return best[1], best[2]
    if last is None:
        raise AutoInitError("no frames to look for a face in")
    msg = str(last)
    raise AutoInitError(msg.replace("no face found", "no face found in any frame", 1) if tried > 1 else msg)
