"""Mouth finder for real faces: the gap, the lips' thickness and the corners, on 1-D profiles.

Works in the upright mouth crop of :class:`~tracker.calibration.FaceFrame` (y down, the face's up
is −y), cut with :data:`~tracker.mouth_model.MOUTH_RECT` around the predicted mouth centre, with
a :class:`~tracker.mouth_model.MouthModel` learned at calibration. Per frame:

1. **light**: the crop's median colour (mostly skin) is matched to the calibration's
   (:meth:`MouthFinder.gains`), folded into every profile below;
2. **the lips on the vertical profile through the centre** (:meth:`MouthFinder.vertical`): the
   calibrated templates of the upper and the lower lip — from each lip's inner edge out over the
   skin beyond it — are matched to the profile, each lip stretched by 0.5–1.7× and placed
   anywhere near the prediction, with the rows between the two lips (the gap) costing nothing
   where they look like the inside of a mouth (dark and colourless, teeth) and a fixed price
   where they do not (a tongue, skin). The best pair gives the inner lip edges (the gap) and the
   outer ones (inner edge ± stretched thickness): the outer edge cannot drift into the philtrum,
   a chin's shadow or stubble, since the whole lip — its colour, its shading, the skin past it —
   must fit, and what is inside the mouth does not matter;
3. **the corners** (:meth:`MouthFinder.corners`): the mouth line is traced from the gap's
   middle outwards along the darkest valley, and on each side the corner is where the columns
   along it (the bands above, on and below the line) start to look like the calibrated cheek;
4. the centre moves to the corners' midpoint and step 2 runs again there;
5. **score** in 0..1 — "this is this person's mouth": how well the lip templates fit, how
   clearly the columns between the corners differ from the cheek against the calibration, the
   plausibility of the size, the place against the prediction and, with the previous frame's
   result, of the change since then. :data:`SCORE_OK` is the threshold.

Everything runs on a few profiles (one column band, a strip around the line), never on every
pixel of the crop; the outline (``polygon``) is drawn through the corners and the outer lip
edges, ``raw_polygon`` through the corners and the inner ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from tracker.colour_model import lut_index
from tracker.mouth_model import (
    BAND, N_RAYS, MouthModel, band_columns, cheek_run, corner_distance, lens_outline, line_columns, line_geometry, mouth_body,
    profile_features, trace_line, unlike_cheek,
)

SCORE_OK = 0.5
"""A result whose score is at least this is taken to be on this person's mouth."""
STRETCH = np.round(np.arange(0.5, 1.71, 0.1), 2)
"""Lip thickness scales (× the calibration's) the vertical match tries."""
ROBUST = 9.0
"""Largest squared feature distance one template row can cost (an outlier row: a highlight, teeth)."""
GAP_PRICE = 3.0
"""Cost of one row between the lips that does not look like the inside of a mouth (a tongue)."""
STRETCH_PRICE = 12.0
"""Cost of stretching a lip by ``k``: ``STRETCH_PRICE · ln(k)²`` (k = 1.5 ≈ two bad rows)."""
RELATIVE = 0.12
"""A template row's tolerance per feature: a just visible difference, or this share of the feature's
range over the templates (strong lipstick varies more in absolute terms than pale lips)."""
ALIGN = 0.75
"""Pixels a template row may be off on an edge and still count as matching."""
REACH = (-0.35, 0.55)
"""Where (× wi, relative to the predicted gap) the gap's edges are looked for: a yawn drops the jaw."""


@dataclass
class MouthResult:
    """One frame's mouth, in crop px (y down; the face's up is −y).

    ``left``/``right`` are the corners, ``centre`` their midpoint, ``lip_upper``/``lip_lower``
    the distances from the centre to the outer lip edges along up/down. ``polygon`` (k, 2) is
    the outline through the corners and the outer lip edges, ``raw_polygon`` (k, 2) the one
    through the corners and the inner lip edges (the gap), ``blob`` the outline filled (bool,
    crop size), ``cue`` the model's cue (``"colour"`` or ``"contrast"``), ``score`` 0..1 (≥
    :data:`SCORE_OK`: on this person's mouth). ``gap_top`` / ``gap_bottom`` are the inner lip
    edges' rows on the centre column, ``stretch`` the upper and lower lip's thickness against the
    calibration's.
    """

    left: tuple[float, float]
    right: tuple[float, float]
    centre: tuple[float, float]
    lip_upper: float
    lip_lower: float
    polygon: np.ndarray
    raw_polygon: np.ndarray
    cue: str
    score: float
    gap_top: float = 0.0
    gap_bottom: float = 0.0
    stretch: tuple[float, float] = (1.0, 1.0)
    shape: tuple[int, int] = (0, 0)
    _blob: np.ndarray | None = field(default=None, repr=False)

    @property
    def width(self) -> float:
        return math.hypot(self.right[0] - self.left[0], self.right[1] - self.left[1])

    @property
    def blob(self) -> np.ndarray:
        """The outline filled (bool, crop size), made on first use."""
        if self._blob is None:
            m = np.zeros(self.shape, np.uint8)
            cv2.fillPoly(m, [np.round(self.polygon * 16).astype(np.int32)], 1, cv2.LINE_8, 4)
            self._blob = m.astype(bool)
        return self._blob


def polygon_measures(poly: np.ndarray) -> tuple[tuple[float, float], tuple[float, float], float, float]:
    """Corners (the extreme points along x) of a closed polygon, and its upper and lower extent on
    the vertical through their midpoint, as distances from it (``lip_upper``, ``lip_lower``)."""
    i0, i1 = int(np.argmin(poly[:, 0])), int(np.argmax(poly[:, 0]))
    left, right = (float(poly[i0, 0]), float(poly[i0, 1])), (float(poly[i1, 0]), float(poly[i1, 1]))
    cx, cy = 0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1])
    p1 = np.roll(poly, -1, axis=0)
    x0, x1 = poly[:, 0], p1[:, 0]
    hit = (x0 <= cx) != (x1 <= cx)
    if not hit.any():
        return left, right, 0.0, 0.0
    t = (cx - x0[hit]) / (x1[hit] - x0[hit])
    ys = poly[hit, 1] + t * (p1[hit, 1] - poly[hit, 1])
    return left, right, float(cy - ys.min()), float(ys.max() - cy)


def _parabola(a: float, b: float, c: float) -> float:
    """Offset (−0.5…0.5) of the minimum of a parabola through three equally spaced values."""
    den = a - 2.0 * b + c
    return min(max(0.5 * (a - c) / den, -0.5), 0.5) if den > 1e-9 else 0.0


class _Side:
    """One lip's template, prepared for matching: for every stretch and template row, the frame row
    offset from the inner edge (outwards) split into integer part and fraction."""

    def __init__(self, tmpl: np.ndarray, thick: float, scale: float, unit: np.ndarray):
        j = np.arange(len(tmpl), dtype=np.float64)
        k = STRETCH[:, None]
        off = scale * np.where(j[None, :] < thick, j[None, :] * k, thick * k + (j[None, :] - thick))  # (K, J)
        self.tmpl = tmpl.astype(np.float32)
        # each row's tolerance: ``unit`` (per feature), or what the template changes over ALIGN px
        # on an edge (a fraction of a pixel off there is not a different mouth)
        grad = np.gradient(tmpl.astype(np.float64), axis=0) / max(scale, 1e-6)
        self.inv_var = (1.0 / (unit**2 + (ALIGN * grad) ** 2)).astype(np.float32)
        self.thick = thick * scale
        self.off = off
        self.i = np.floor(off).astype(np.int32)
        self.t = (off - self.i).astype(np.float32)[..., None]
        self.prior = (STRETCH_PRICE * np.log(STRETCH) ** 2).astype(np.float32)
        self.rows = len(tmpl)


class MouthFinder:
    """Find one performer's mouth in mouth crops (see the module docstring).

    ``model`` comes from :func:`~tracker.mouth_model.learn_mouth`; ``work_ipd`` is the crop
    frame's inter-eye distance (px). Template offsets, bands and search ranges are precomputed here.
    """

    def __init__(self, model: MouthModel, work_ipd: float):
        self.model = model
        self.wi = wi = float(work_ipd)
        self.k = k = wi / model.work_ipd  # the model's lengths → this crop's
        self.width0 = model.width * k
        self.height0 = (model.lip_upper + model.lip_lower) * k
        self.line0 = model.line * k
        self.half = max(BAND * wi, 1.5)
        both = np.concatenate([model.tmpl_up, model.tmpl_down])
        unit = np.maximum(RELATIVE * (both.max(axis=0) - both.min(axis=0)), 1.0)
        self.up = _Side(model.tmpl_up, model.thick_up, k, unit)
        self.down = _Side(model.tmpl_down, model.thick_down, k, unit)
        self.a1, self.a2 = line_geometry(wi)
        self.strip_half = int(math.ceil(0.32 * wi)) + self.a2 + 2
        self.sigma_line = max(0.015 * wi, 1.0)
        self.n_side = int(math.ceil(0.95 * wi))
        self.cheeks = (model.cheek_left, model.cheek_right)
        self.run = cheek_run(wi)
        self.body = mouth_body(wi)
        self.reach = (int(math.floor(REACH[0] * wi)), int(math.ceil(REACH[1] * wi)))
        # the calibration mouth's own columns: how unlike the cheek a mouth is (for the score)
        self.lip_l = float(np.minimum(model.tmpl_up[: max(int(model.thick_up), 1), 0].min(),
                                      model.tmpl_down[: max(int(model.thick_down), 1), 0].min()))
        self.gain0 = max(0.25 * (model.half_left + model.half_right) * k, 1.0)

    # ------------------------------------------------------------------ light
    def gains(self, crop: np.ndarray) -> np.ndarray | None:
        """Per-channel gains (3,) that bring the crop's median colour — mostly skin — to the calibration
        crop's, or None when they are within 4 % of 1: light that dims, brightens or changes colour
        after calibration (auto exposure, a lamp, the sun) moves every colour, and the templates and
        the inside table were learned under the calibration's light. Clamped to 0.33–3×."""
        ref = self.model.crop_median
        if ref is None:
            return None
        sub = crop[::4, ::4].reshape(-1, 3)
        med = np.partition(sub, len(sub) // 2, axis=0)[len(sub) // 2].astype(np.float64)
        g = np.clip(np.asarray(ref, dtype=np.float64) / np.maximum(med, 1.0), 0.33, 3.0)
        return None if np.all(np.abs(g - 1.0) < 0.04) else g

    # ------------------------------------------------------------------ the vertical profile
    def profile(self, crop: np.ndarray, x: float, gains: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The vertical profile through column ``x``: features (H, 3) of each row's mean over the
        band, and how much each row looks like the inside of a mouth (H,) 0..1 (the table's share of
        the band's pixels, or darker than both lips by a third)."""
        x0, x1 = band_columns(x, self.half, crop.shape[1])
        band = crop[:, x0:x1]
        if gains is not None:
            band = cv2.transform(band, np.diag(gains).astype(np.float32))
        mean = band.mean(axis=1, dtype=np.float32)
        f = profile_features(mean, self.model.skin_level)
        inside = self.model.inside_table.take(lut_index(band)).mean(axis=1, dtype=np.float32)
        dark = np.clip((np.float32(0.85 * self.lip_l) - f[:, 0]) / np.float32(max(0.2 * self.lip_l, 1e-3)), 0.0, 1.0)
        return f, np.maximum(inside, dark)

    def _side_costs(self, f: np.ndarray, ys: np.ndarray, side: _Side, sign: int) -> tuple[np.ndarray, np.ndarray]:
        """For each candidate inner-edge row ``ys``: the template's best cost over the stretches, and
        that stretch's index. ``sign`` −1: the template runs up from the row; +1: down."""
        n = len(f)
        if sign < 0:
            i0 = ys[:, None, None] - side.i[None] - 1
            t = 1.0 - side.t
        else:
            i0 = ys[:, None, None] + side.i[None]
            t = side.t
        i0 = np.clip(i0, 0, n - 2)
        p = f[i0] * (1.0 - t) + f[i0 + 1] * t  # (Y, K, J, 3)
        p -= side.tmpl
        d = np.einsum("ykjc,ykjc,jc->ykj", p, p, side.inv_var)
        np.minimum(d, np.float32(ROBUST), out=d)
        c = d.sum(axis=2) + side.prior
        best = np.argmin(c, axis=1)
        return c[np.arange(len(ys)), best], best

    def vertical(self, f: np.ndarray, inside: np.ndarray, y_line: float, span: tuple[int, int] | None = None,
                 previous=None):
        """Match the lip templates to a profile (:meth:`profile`) with the gap expected around row
        ``y_line``, its edges within ``span`` (rows relative to it; default :data:`REACH`):
        ``(gap_top, gap_bottom, top, bottom, (k_up, k_down), (fit_up, fit_down))`` — the inner and the
        outer lip edges (rows, sub-pixel), the stretches and each lip's mean cost per template row."""
        n = len(f)
        lo, hi = span if span is not None else self.reach
        ys = np.arange(max(int(y_line) + lo, 1), min(int(y_line) + hi + 1, n - 1))
        if len(ys) < 3:
            return None
        cu, ku = self._side_costs(f, ys, self.up, -1)
        cl, kl = self._side_costs(f, ys, self.down, +1)
        gap = np.float32(GAP_PRICE) * (1.0 - inside[ys])
        cum = np.concatenate([[0.0], np.cumsum(gap, dtype=np.float64)])
        # rows strictly between the two inner edges are the gap
        m = len(ys)
        between = cum[None, :m] - cum[1 : m + 1, None]
        mid = 0.5 * (ys[:, None] + ys[None, :]) - y_line
        tot = cu[:, None] + cl[None, :] + np.maximum(between, 0.0) + 3.0 * (mid / (0.25 * self.wi)) ** 2
        if previous is not None:
            g0 = previous.gap_bottom - previous.gap_top
            tot += 2.0 * ((ys[None, :] - ys[:, None] - g0) / (0.15 * self.wi)) ** 2
        tot[np.tril_indices(m, -1)] = np.inf
        a, b = np.unravel_index(int(np.argmin(tot)), tot.shape)
        ya = float(ys[a]) + (_parabola(tot[a - 1, b], tot[a, b], tot[a + 1, b]) if 0 < a < m - 1 and a + 1 <= b else 0.0)
        yb = float(ys[b]) + (_parabola(tot[a, b - 1], tot[a, b], tot[a, b + 1]) if 0 < b < m - 1 and b - 1 >= a else 0.0)
        k_up, k_dn = float(STRETCH[ku[a]]), float(STRETCH[kl[b]])
        top = ya - k_up * self.up.thick
        bottom = yb + k_dn * self.down.thick
        return ya, yb, top, bottom, (k_up, k_dn), (float(cu[a]) / self.up.rows, float(cl[b]) / self.down.rows)

    # ------------------------------------------------------------------ the corners
    def corners(self, crop: np.ndarray, x: float, y_line: float, gains: np.ndarray | None = None):
        """The corners from the line through ``(x, y_line)``: ``(left, right, gains)`` — each corner
        (x, y) and how clearly the mouth's columns differed from the cheek on that side
        (:func:`~tracker.mouth_model.corner_distance`'s sum)."""
        H, W = crop.shape[:2]
        y0 = max(int(round(y_line)) - self.strip_half, 0)
        y1 = min(int(round(y_line)) + self.strip_half + 1, H)
        strip = crop[y0:y1]
        lum = cv2.GaussianBlur(cv2.cvtColor(strip, cv2.COLOR_BGR2GRAY), (0, 0), self.sigma_line)
        x0 = min(max(int(round(x)), 0), W - 1)
        out, strength = [], []
        for step, cheek in ((-1, self.cheeks[0]), (+1, self.cheeks[1])):
            n = min(self.n_side, x0 if step < 0 else W - 1 - x0)
            if n < 4:
                out.append((float(x0), float(y_line)))
                strength.append(0.0)
                continue
            ys = trace_line(lum, x0, y_line - y0, step, n)
            cols = line_columns(strip, x0, ys, step, self.a1, self.a2, self.model.skin_level, gains)
            d = unlike_cheek(cols, (cheek[0], cheek[1]))
            half, g = corner_distance(d, 0.15 * self.wi, 0.9 * self.wi, self.run, self.body)
            k = min(int(half), len(ys) - 2)
            t = half - k
            out.append((x0 + step * half, y0 + float(ys[k] * (1 - t) + ys[k + 1] * t)))
            strength.append(g)
        return out[0], out[1], strength

    # ------------------------------------------------------------------ the whole
    def find(self, crop_bgr: np.ndarray, predicted_centre_crop: tuple[float, float],
             previous: MouthResult | None = None) -> MouthResult | None:
        """The mouth in one crop (:data:`~tracker.mouth_model.MOUTH_RECT` around the predicted centre,
        the calibrated mouth centre under the head's motion), or None when nothing there can be a
        mouth. ``previous`` (optional) is the last frame's result in this crop's pixels (the crop
        moves with the head): a mouth's gap cannot jump from one frame to the next, so a result
        far from it scores lower."""
        crop = crop_bgr
        H, W = crop.shape[:2]
        px, py = float(predicted_centre_crop[0]), float(predicted_centre_crop[1])
        gains = self.gains(crop)
        y_line = py + self.line0
        if previous is not None and previous.score >= SCORE_OK:
            px = 0.5 * (px + previous.centre[0])
        f, inside = self.profile(crop, px, gains)
        v = self.vertical(f, inside, y_line, previous=previous)
        if v is None:
            return None
        mid = 0.5 * (v[0] + v[1])
        left, right, strength = self.corners(crop, px, mid, gains)
        cx = 0.5 * (left[0] + right[0])
        if abs(cx - px) > 0.03 * self.wi:
            f, inside = self.profile(crop, cx, gains)
            s = int(math.ceil(0.12 * self.wi))
            v2 = self.vertical(f, inside, mid, span=(int(v[0] - mid) - s, int(v[1] - mid) + s + 1), previous=previous)
            if v2 is not None:
                v = v2
        gap_top, gap_bottom, top, bottom, stretch, fit = v
        cy = 0.5 * (left[1] + right[1])
        width = math.hypot(right[0] - left[0], right[1] - left[1])
        score = self._score(width, bottom - top, (cx, cy), (px, py), fit, strength, gap_top, gap_bottom, previous)
        poly = lens_outline(left, right, top, bottom, cx, N_RAYS)
        raw = lens_outline(left, right, gap_top, gap_bottom, cx, N_RAYS)
        return MouthResult(
            left=left, right=right, centre=(cx, cy), lip_upper=cy - top, lip_lower=bottom - cy, polygon=poly,
            raw_polygon=raw, cue=self.model.cue, score=score, gap_top=gap_top, gap_bottom=gap_bottom,
            stretch=stretch, shape=(H, W),
        )

    def _score(self, width, height, centre, pred, fit, strength, gap_top, gap_bottom, previous) -> float:
        """Fit of the lip templates (mean cost per row: full under 2, none at 5), clarity of the
        corners against the calibration (full at 40 % of its columns' difference from the cheek),
        plausibility of the width (0.5–1.8× the calibrated mouth's) and height (under 1.1 wi), the
        place against the prediction (full within ~0.3 wi) and, with a previous result, the change
        of the gap and the centre (full within 0.15 wi)."""
        wi = self.wi
        ramp = lambda v, a, b: min(max((v - a) / (b - a), 0.0), 1.0)
        s_fit = ramp(-max(fit), -5.0, -2.0)
        s_corner = ramp(min(strength) / self.gain0, 0.0, 0.4)
        rho = width / max(self.width0, 1e-6)
        s_size = ramp(rho, 0.4, 0.5) * ramp(-rho, -1.9, -1.8) * ramp(-height, -1.2 * wi, -1.1 * wi)
        dx = (centre[0] - pred[0]) / (0.3 * wi)
        dy = (centre[1] - pred[1]) / (0.4 * wi)
        d = math.sqrt(dx * dx + dy * dy)
        s_place = 1.0 if d <= 1.0 else max(math.exp(-(d - 1.0)), 0.3)
        s_prev = 1.0
        if previous is not None and previous.score >= SCORE_OK:
            jump = max(abs((gap_bottom - gap_top) - (previous.gap_bottom - previous.gap_top)),
                       math.hypot(centre[0] - previous.centre[0], centre[1] - previous.centre[1]))
            s_prev = ramp(-jump, -0.3 * wi, -0.15 * wi)
        return float(s_fit * s_corner * s_size * s_place * s_prev)
