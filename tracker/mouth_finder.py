"""Mouth finder for real faces: colour classifier → blob → radial polygon → snake → corners and lip edges.

Works in the upright mouth crop of :class:`~tracker.calibration.FaceFrame` (y down, the face's up
is −y), cut with :data:`~tracker.mouth_model.MOUTH_RECT` around the predicted mouth centre, with
a :class:`~tracker.mouth_model.MouthModel` learned at calibration. Per frame:

1. **classify**: each lip's linear colour classifier (its Fisher axis: 0 on the skin next to it,
   1 on the lip) gives the lip value of every pixel — the upper lip's above the mouth line, the
   lower lip's below — and one 64³ table lookup says which pixels look like the inside of a mouth
   (dark and colourless, teeth);
2. **blob**: lip-valued pixels are tagged (at half size) and labelled; the blob is the piece
   with the most evidence near the predicted centre (a red collar or the nose lose by distance and
   size). The other lip, if the blob is one lip, joins it (:meth:`MouthFinder.with_inside`), and
   everything between the two — teeth, a tongue, the dark gap or inside — counts as mouth;
3. **radial polygon**: from the blob's centre, on each of :data:`~tracker.mouth_model.N_RAYS`
   rays, the radius up to which the summed evidence along the ray is largest (Toyama's radial
   spanning made robust: a stretch of skin before the nose or a chin's shadow stops a ray), then
   re-cast from the polygon's own centre;
4. **snake**: each ray's radius moves to the strongest fall of the lip value near it (the upper
   lip's axis above the mouth line, the lower lip's below), balanced against a second-difference
   smoothness term around the loop (a closed-form active contour); a ray far from its neighbours
   counts for little;
5. **measure**: corners = where the evidence ends on the rows near the outline's extreme points
   (sub-pixel; a grin's dark corners count), centre = their midpoint, ``lip_upper`` /
   ``lip_lower`` = from the centre up / down to the outline, refined to where the lip value crosses
   half-way between lip and skin on that column;
6. **score** in 0..1 — "this is this person's mouth": how clearly the outline is a lip edge (lip
   value just inside minus just outside, on the upper and the lower arc), times the plausibility
   of its size against the calibrated mouth and of its place against the prediction.
   :data:`SCORE_OK` is the threshold.

Each frame's light is first matched to the calibration's (:meth:`MouthFinder.gains`): a slow or
sudden change of brightness or colour cast moves every colour, and the lip axes were learned
under the calibration's light. The cue (``model.cue``) says what the lip axes rest on: clear lip
colour, or — ``"contrast"`` — weak lip colour helped by the mouth's dark gap, inside and teeth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from tracker.colour_model import lut_index
from tracker.mouth_model import N_RAYS, MouthModel, lip_evidence


SCORE_OK = 0.5
"""A result whose score is at least this is taken to be on this person's mouth."""
INSIDE_NEAR = 0.5
"""Evidence given to the mouth's inside (see :meth:`MouthFinder.with_inside`)."""
GAP = 0.2
"""Tallest gap (× wi) between lip above and lip below near the blob that counts as the inside
whatever is in it (teeth of any colour); wider gaps only across teeth or the dark inside."""
REACH = 0.45
"""How far (× wi) above or below the blob the other lip may be (a wide-open mouth)."""
LIP_SURE = 0.4
"""Evidence above which a pixel surely is lip (lip value 0.7), for :meth:`MouthFinder.with_inside`."""
BIAS = 0.2
"""Evidence (+1 lip, −1 skin) a sample along a ray must exceed to be worth including."""


@dataclass
class MouthResult:
    """One frame's mouth, in crop px (y down; the face's up is −y).

    ``left``/``right`` are the corners, ``centre`` their midpoint, ``lip_upper``/``lip_lower``
    the distances from the centre to the outer lip edges along up/down. ``polygon`` (k, 2) is
    the snake outline, ``raw_polygon`` the radial polygon before it, ``blob`` the blob the rays
    start in (bool, crop size), ``cue`` the evidence the edges were placed on (``"colour"`` or
    ``"contrast"``), ``score`` 0..1 (≥ :data:`SCORE_OK`: on this person's mouth).
    """

    left: tuple[float, float]
    right: tuple[float, float]
    centre: tuple[float, float]
    lip_upper: float
    lip_lower: float
    polygon: np.ndarray
    raw_polygon: np.ndarray
    blob: np.ndarray
    cue: str
    score: float

    @property
    def width(self) -> float:
        return math.hypot(self.right[0] - self.left[0], self.right[1] - self.left[1])


def ray_directions(n: int = N_RAYS) -> np.ndarray:
    """Unit vectors ``(n, 2)`` of the rays, ray 0 along +x, turning towards +y (down)."""
    a = np.arange(n) * (2.0 * math.pi / n)
    return np.stack([np.cos(a), np.sin(a)], axis=1)


def polygon_measures(poly: np.ndarray) -> tuple[tuple[float, float], tuple[float, float], float, float]:
    """Corners (the extreme points along x) of a closed polygon, and its upper and lower extent on
    the vertical through their midpoint, as distances from it (``lip_upper``, ``lip_lower``)."""
    i0, i1 = int(np.argmin(poly[:, 0])), int(np.argmax(poly[:, 0]))
    left, right = (float(poly[i0, 0]), float(poly[i0, 1])), (float(poly[i1, 0]), float(poly[i1, 1]))
    up, down = _extent_at(poly, 0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]))
    return left, right, up, down


def _median(v: np.ndarray) -> float:
    """Median of a small 1-D array (the upper middle element for an even length)."""
    k = len(v) // 2
    return float(np.partition(v, k)[k])


def _extent_at(poly: np.ndarray, cx: float, cy: float) -> tuple[float, float]:
    """Upper and lower extent of a closed polygon on the vertical through ``cx``, as distances up and
    down from ``cy``."""
    p1 = np.roll(poly, -1, axis=0)
    x0, x1 = poly[:, 0], p1[:, 0]
    hit = (x0 <= cx) != (x1 <= cx)
    if not hit.any():
        return 0.0, 0.0
    t = (cx - x0[hit]) / (x1[hit] - x0[hit])
    ys = poly[hit, 1] + t * (p1[hit, 1] - poly[hit, 1])
    return float(cy - ys.min()), float(ys.max() - cy)


def column_fill(mask: np.ndarray) -> np.ndarray:
    """``mask`` (uint8 0/1) with every column filled from its topmost to its bottommost set pixel."""
    h = mask.shape[0]
    has = mask.any(axis=0)
    top = np.argmax(mask, axis=0)
    bottom = h - 1 - np.argmax(mask[::-1], axis=0)
    ys = np.arange(h)[:, None]
    return ((ys >= top[None, :]) & (ys <= bottom[None, :]) & has[None, :]).view(np.uint8)


class MouthFinder:
    """Find one performer's mouth in mouth crops (see the module docstring).

    ``model`` comes from :func:`~tracker.mouth_model.learn_mouth`; ``work_ipd`` is the crop
    frame's inter-eye distance (px). Ray directions and radii, kernels and the snake's matrices
    are precomputed here.
    """

    def __init__(self, model: MouthModel, work_ipd: float, n_rays: int = N_RAYS, alpha: float = 0.6):
        self.model = model
        self.wi = wi = float(work_ipd)
        k = wi / model.work_ipd  # the model's lengths → this crop's
        self.width0 = model.width * k
        self.height0 = (model.lip_upper + model.lip_lower) * k
        self.area0 = model.area * k * k
        self.n = n_rays
        self.dirs = ray_directions(n_rays)
        self._dx = self.dirs[:, 0:1].astype(np.float32)
        self._dy = self.dirs[:, 1:2].astype(np.float32)
        self.step = 0.5
        self.radii = np.arange(0.0, 0.85 * wi + 1e-9, self.step, dtype=np.float32)
        self._ox = self._dx * self.radii[None, :]
        self._oy = self._dy * self.radii[None, :]
        self.search = np.arange(-0.04 * wi, 0.08 * wi + 1e-9, self.step, dtype=np.float32)[None, :]
        self.band = np.array([[-3.0, -1.5, 1.5, 3.0]], np.float32)
        self.sigma = max(0.01 * wi, 0.6)
        self.sigma_blob = max(0.02 * wi, 0.8)
        self.min_area = max(int(0.02 * self.area0), 6)
        self.near_px = max(int(round(0.15 * wi)), 2)
        self.reach_px = max(int(round(REACH * wi)), 3)
        self.gap_kernel = np.ones((max(int(round(GAP * wi)) | 1, 3), 1), np.uint8)
        self.corner_kernel = np.ones((3, max(int(round(0.1 * wi)) | 1, 3)), np.uint8)
        d2 = np.zeros((n_rays, n_rays))
        for i in range(n_rays):
            d2[i, (i - 1) % n_rays] += 1.0
            d2[i, i] -= 2.0
            d2[i, (i + 1) % n_rays] += 1.0
        self._dtd = alpha * d2.T @ d2
        self._rows = np.arange(n_rays)
        self._diag = np.arange(n_rays) * (n_rays + 1)
        self._five = (np.arange(n_rays)[:, None] + np.arange(-2, 3)[None, :]) % n_rays
        self._rows_y = np.arange(int(math.ceil(2.0 * wi)) + 8, dtype=np.float32)
        ang = np.degrees(np.arctan2(self.dirs[:, 1], self.dirs[:, 0])) % 360.0
        self._upper = (ang > 200.0) & (ang < 340.0)
        self._corner_dy = np.arange(-0.04 * wi, 0.04 * wi + 1e-9, 0.5, dtype=np.float32)
        self._corner_dx = np.arange(-0.06 * wi, 0.1 * wi + 1e-9, 0.25, dtype=np.float32)
        self._corner_grid = (np.ascontiguousarray(np.broadcast_to(self._corner_dx[None, :], (len(self._corner_dy), len(self._corner_dx)))),
                             np.ascontiguousarray(np.broadcast_to(self._corner_dy[:, None], (len(self._corner_dy), len(self._corner_dx)))))
        self._lower = (ang > 20.0) & (ang < 160.0)


    # ------------------------------------------------------------------ evidence
    def lip_maps(self, crop: np.ndarray, gains: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The upper and the lower lip's value maps (float32; 0 skin, 1 lip), smoothed a little;
        ``gains`` (3,) scale the crop's channels first (folded into the axes: no extra pass)."""
        c32 = crop.astype(np.float32)
        out = []
        for a in (self.model.axis_up, self.model.axis_down):
            w = a[:3] if gains is None else a[:3] * gains
            v = cv2.transform(c32, w.reshape(1, 3).astype(np.float32))
            v += np.float32(a[3])
            out.append(cv2.GaussianBlur(v, (0, 0), self.sigma))
        return out[0], out[1]

    def blend(self, maps: tuple[np.ndarray, np.ndarray], y_line: float) -> np.ndarray:
        """The lip value: the upper lip's above the mouth line ``y_line``, the lower lip's below,
        blended over about ±0.03 wi."""
        vu, vd = maps
        if vu.shape[0] > len(self._rows_y):
            self._rows_y = np.arange(vu.shape[0], dtype=np.float32)
        y = (self._rows_y - np.float32(y_line)) * np.float32(1.0 / max(0.03 * self.wi, 1.0))
        wgt = (1.0 / (1.0 + np.exp(-np.clip(y, -30, 30)))).astype(np.float32)[: vu.shape[0], None]
        return vu + wgt * (vd - vu)

    def lip_value(self, crop: np.ndarray, y_line: float, gains: np.ndarray | None = None) -> np.ndarray:
        """The lip value (float32; 0 skin, 1 lip) of ``crop``, split at the mouth line ``y_line``."""
        return self.blend(self.lip_maps(crop, gains), y_line)

    def inside(self, crop: np.ndarray, gains: np.ndarray | None = None) -> np.ndarray:
        """1 where a pixel looks like the inside of a mouth (uint8; one table lookup of the crop,
        its channels scaled by ``gains`` first)."""
        if gains is not None:
            crop = cv2.transform(crop, np.diag(gains).astype(np.float32))
        return self.model.inside_table.take(lut_index(crop))

    def with_inside(self, ev: np.ndarray, inside: np.ndarray, blob: np.ndarray, fill: bool = True) -> np.ndarray:
        """``ev`` raised to at least :data:`INSIDE_NEAR` on the mouth's inside.

        The other lip is a lip-coloured piece at least 60 % as wide as the blob and mostly over or
        under it, within 0.45 wi (a wide-open mouth): touching it (a grin's lips meet at the corners),
        above it across a gap under :data:`THIN` or across teeth / the dark inside, or below it across teeth / the
        dark inside; every pixel between the two in their common columns is the inside (teeth, a
        tongue, the dark gap, whatever their colour) — the nostrils and a chin's shading are narrower,
        or skin lies between. Inside-
        like pixels (``inside``, uint8: dark and colourless, or teeth) next to the blob or that inside
        count too (a grin's dark corners). Without ``fill`` (the calibration's first outlines, on
        noisier evidence) only inside-like pixels between lip above and below count."""
        bx, by, bw, bh = cv2.boundingRect(blob)
        if bw == 0:
            return ev
        H, W = ev.shape
        mx, my = self.near_px, self.reach_px
        x, y = max(bx - mx, 0), max(by - my, 0)
        w, h = min(bx + bw + mx, W) - x, min(by + bh + my, H) - y
        lipish = (ev[y : y + h, x : x + w] > LIP_SURE).view(np.uint8)
        if not fill:
            between = column_fill(lipish) & inside[y : y + h, x : x + w]
        else:
            # near the blob, any gap up to GAP between lip above and lip below; further out (a wide-open
            # mouth), only a wide lip piece across teeth or the dark inside
            between = self._joined(lipish, blob[y : y + h, x : x + w], inside[y : y + h, x : x + w], bx - x, by - y, bw, bh)
            c0, c1 = max(by - self.near_px, 0) - y, min(by + bh + self.near_px, H) - y
            between[c0:c1] |= cv2.morphologyEx(lipish[c0:c1], cv2.MORPH_CLOSE, self.gap_kernel)
            between |= blob[y : y + h, x : x + w]
            between |= inside[y : y + h, x : x + w] & cv2.dilate(between, self.corner_kernel)
        if not between.any():
            return ev
        out = ev.copy()
        sub = out[y : y + h, x : x + w]
        np.maximum(sub, np.where(between > 0, np.float32(INSIDE_NEAR), sub), out=sub)
        return out

    def _joined(self, lipish, sub_blob, sub_in, b0, top, bw, bh):
        union = sub_blob.copy()
        n, lab, st, _ = cv2.connectedComponentsWithStats(lipish, connectivity=8)
        b1, bottom = b0 + bw, top + bh
        for j in range(1, n):
            px, py, pw, ph, pa = (int(v) for v in st[j])
            ov = min(px + pw, b1) - max(px, b0)
            if pw < 0.6 * bw or ov < 0.5 * pw or pa < 4:
                continue
            a0, a1 = max(px, b0), min(px + pw, b1)
            if a1 <= a0:
                continue
            if py >= bottom:  # below the blob: only across what looks like a mouth's inside
                if py > bottom and sub_in[bottom:py, a0:a1].mean() < 0.4:
                    continue
            elif py + ph <= top:  # above: an upper lip spans the mouth, across teeth or the dark inside
                if py + ph < top and (pw < 0.8 * bw or sub_in[py + ph : top, a0:a1].mean() < 0.3):
                    continue
            union |= (lab == j).view(np.uint8)
        return column_fill(union)

    # ------------------------------------------------------------------ blob
    def blob(self, ev: np.ndarray, pred: tuple[float, float]) -> tuple[np.ndarray, tuple[float, float]] | None:
        """The blob (uint8 0/1) of positive evidence (smoothed) with the most evidence near ``pred``,
        and its centroid."""
        wi = self.wi
        h, w = ev.shape
        half = cv2.resize(ev, ((w + 1) // 2, (h + 1) // 2), interpolation=cv2.INTER_AREA)  # tags at half size
        tags = cv2.GaussianBlur(half, (0, 0), 0.5 * self.sigma_blob)
        mask = (tags > 0.25).view(np.uint8)
        n, lab, stats, cents = cv2.connectedComponentsWithStats(mask, connectivity=4)
        if n <= 1:
            return None
        ev = np.bincount(lab.ravel(), weights=tags.ravel(), minlength=n)[1:]
        area = stats[1:, cv2.CC_STAT_AREA] * 4
        cx = 2.0 * cents[1:, 0] + 0.5
        cy = 2.0 * cents[1:, 1] + 0.5
        dx = (cx - pred[0]) / (0.3 * wi)
        dy = (cy - pred[1]) / (0.4 * wi)
        near = np.exp(-0.5 * (dx * dx + dy * dy))
        # a mouth's centre stays within ~0.55 wi sideways and −0.35…+0.6 wi up/down of the prediction
        # (a yawn drops it): hair or a collar at the crop's edge is not considered
        inside = (np.abs(dx) < 0.55 / 0.3) & (dy > -0.35 / 0.4) & (dy < 0.6 / 0.4)
        s = np.where((area >= self.min_area) & inside, ev * near, -1.0)
        j = int(np.argmax(s))
        if s[j] <= 0:
            return None
        blob = cv2.resize((lab == j + 1).view(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST)
        return blob, (float(cx[j]), float(cy[j]))

    # ------------------------------------------------------------------ radial polygon and snake
    def spans(self, llr: np.ndarray, centre: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
        """On each ray from ``centre``: the radius up to which the summed evidence (minus
        :data:`BIAS` per sample) is largest, and that sum (the ray's confidence)."""
        prof = cv2.remap(llr, self._ox + np.float32(centre[0]), self._oy + np.float32(centre[1]), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=-1.0)
        prof -= np.float32(BIAS)
        cs = np.cumsum(prof, axis=1)
        k = np.argmax(cs, axis=1)
        gain = cs[self._rows, k] * self.step
        return self.radii[k].astype(np.float64) + 0.5 * self.step, np.maximum(gain, 0.0)

    def smooth(self, r: np.ndarray, weight: np.ndarray) -> np.ndarray:
        """Radii balancing ``weight`` × (r − given)² against the loop's second differences; a ray far
        from the median of its five neighbours (a spike up the philtrum, down a chin's crease) counts
        for little."""
        med = np.partition(r[self._five], 2, axis=1)[:, 2]
        z = (r - med) / (0.2 * med + 1.5)
        weight = weight * np.exp(-z * z)
        a = self._dtd.copy()
        a.flat[self._diag] += np.maximum(weight, 1e-3)
        return np.linalg.solve(a, weight * r + 1e-3 * med * (weight < 1e-3))

    def snake(self, value: np.ndarray, centre: tuple[float, float], r0: np.ndarray, w0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Radii moved to the strongest fall of ``value`` (inside → outside) within −0.04…+0.08 wi of ``r0``
        on each ray, smoothed around the loop; also the fall found on each ray (edge strength).
        Rays with a weak fall keep their radius from ``r0`` (weight ``w0``)."""
        rows = self._rows
        rr = np.maximum(r0.astype(np.float32)[:, None] + self.search, 0.0)
        prof = cv2.remap(value, self._dx * rr + np.float32(centre[0]), self._dy * rr + np.float32(centre[1]),
                         cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        fall = prof[:, :-2] - prof[:, 2:]
        j = np.argmax(fall[:, 1:-1], axis=1) + 1
        a, b, c = fall[rows, j - 1], fall[rows, j], fall[rows, j + 1]
        den = a - 2 * b + c
        den = np.where(np.abs(den) > 1e-9, den, -1e-9)
        frac = np.clip(0.5 * (a - c) / den, -0.5, 0.5)
        edge = rr[rows, j + 1] + frac * self.step
        strong = np.clip(b / max(_median(b), 1e-6), 0.0, 1.0)
        target = strong * edge + (1.0 - strong) * r0
        return self.smooth(target, np.maximum(w0, 0.05)), b

    def outline(self, crop: np.ndarray, pred: tuple[float, float], maps, gains: np.ndarray | None = None):
        """:meth:`outline_on` this performer's lip evidence (``maps`` of :meth:`lip_maps`, split at the
        predicted centre)."""
        return self.outline_on(lip_evidence(self.blend(maps, pred[1])), self.inside(crop, gains), pred)

    def outline_on(self, ev: np.ndarray, inside: np.ndarray, pred: tuple[float, float], fill: bool = True):
        """Blob, radial polygon and the smoothed outline (no edge refinement) on an evidence map
        (``ev`` float32, +1 lip, −1 skin; ``inside`` uint8 inside-like pixels), the mouth expected
        at ``pred``: ``(poly, centre, blob, raw, ev, radii, weights)`` or None when there is no blob."""
        found = self.blob(ev, pred)
        if found is None:
            return None
        blob, c0 = found
        ev = self.with_inside(ev, inside, blob, fill)
        r, gain = self.spans(ev, c0)
        raw = self.dirs * r[:, None] + np.array(c0)
        w = np.clip(gain / max(_median(gain), 1e-6), 0.05, 1.0)
        poly = self.dirs * self.smooth(r, w)[:, None] + np.array(c0)
        # again from the outline's own centre (a blob may be one lip, or off-centre)
        left, right, up, down = polygon_measures(poly)
        c1 = (0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]) + 0.5 * (down - up))
        r, gain = self.spans(ev, c1)
        w = np.clip(gain / max(_median(gain), 1e-6), 0.05, 1.0)
        r1 = self.smooth(r, w)
        return self.dirs * r1[:, None] + np.array(c1), c1, blob, raw, ev, r1, w

    # ------------------------------------------------------------------ measurements
    def _corner(self, value: np.ndarray, start: tuple[float, float], side: int) -> tuple[float, float]:
        """Sub-pixel mouth corner on ``side`` (−1 left, +1 right) near the outline's extreme point:
        on the rows within 0.04 wi of it, the farthest point outwards where ``value`` crosses 0.5; a
        sharp tip between rows by a parabola through the best row and its neighbours."""
        gx, gy = self._corner_grid
        vals = cv2.remap(value, gx * np.float32(side) + np.float32(start[0]), gy + np.float32(start[1]),
                         cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        ins = vals >= 0.5
        m = ins.shape[1]
        rev = ins[:, ::-1]
        last = m - 1 - np.argmax(rev, axis=1)
        ok = rev.any(axis=1) & (last < m - 1)
        if not ok.any():
            return start
        rows = np.flatnonzero(ok)
        lr = last[rows]
        a, b = vals[rows, lr], vals[rows, lr + 1]
        t = np.where(a != b, (a - 0.5) / np.where(a != b, a - b, 1.0), 0.5)
        dx = self._corner_dx
        pos = dx[lr] + t * (dx[1] - dx[0])
        k = int(np.argmax(pos))
        yb, xb = float(self._corner_dy[rows[k]]), float(pos[k])
        if 0 < k < len(rows) - 1 and rows[k - 1] == rows[k] - 1 and rows[k + 1] == rows[k] + 1:
            p0, p1, p2 = float(pos[k - 1]), float(pos[k]), float(pos[k + 1])
            den = p0 - 2 * p1 + p2
            if den < -1e-6:
                d = min(max(0.5 * (p0 - p2) / den, -0.5), 0.5)
                yb += d * float(self._corner_dy[1] - self._corner_dy[0])
                xb = p1 - 0.25 * (p0 - p2) * d
        return (float(start[0] + side * xb), float(start[1] + yb))

    @staticmethod
    def _refine_vertical(value: np.ndarray, x: float, y: float, direction: int, reach: float) -> float:
        """Sub-pixel y near ``y`` on the column through ``x`` where ``value`` crosses half-way between
        the lip just inside and the skin just outside, walking outwards (``direction`` −1 up, +1 down)."""
        h, w = value.shape
        steps = np.arange(-reach, reach + 1e-9, 0.25, dtype=np.float32)
        ys = np.clip(y + direction * steps, 0, h - 1).astype(np.float32).reshape(1, -1)
        xs = np.full(ys.shape, min(max(x, 0.0), w - 1.0), dtype=np.float32)
        vals = cv2.remap(value, xs, ys, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).ravel()
        q = len(vals) // 4
        inner, outer = float(vals[:q].mean()), float(vals[-q:].mean())
        if inner - outer <= 1e-6:
            return y
        half = 0.5 * (inner + outer)
        ins = vals >= half
        idx = np.flatnonzero(ins[:-1] & ~ins[1:])
        if not len(idx):
            return y
        i = int(idx[-1])
        a, b = float(vals[i]), float(vals[i + 1])
        t = (a - half) / (a - b) if a != b else 0.5
        return float(ys[0, i] + t * (ys[0, i + 1] - ys[0, i]))

    def _contrast(self, value: np.ndarray, centre, r: np.ndarray) -> float:
        """How clearly the outline is a lip edge: on the upper arc and on the lower arc, the median of
        (lip value 1.5–3 px inside − lip value 1.5–3 px outside), averaged (1 on calibrated lips
        against their skin, about 0 on an outline through skin or shading)."""
        rr = np.maximum(r[:, None] + self.band, 0.5).astype(np.float32)
        v = cv2.remap(value, self._dx * rr + np.float32(centre[0]), self._dy * rr + np.float32(centre[1]),
                      cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        d = v[:, :2].mean(axis=1) - v[:, 2:].mean(axis=1)
        return float(0.5 * (_median(d[self._upper]) + _median(d[self._lower])))

    def _score(self, width: float, height: float, centre, pred, contrast: float) -> float:
        """The lip edge's clarity (:meth:`_contrast`, full at 0.45) times the plausibility of the width
        (0.35–2.5× the calibrated mouth's and 0.3–1.4 wi), of the height (0.05–1.15 wi) and of the
        place against the prediction (full within ~0.3 wi)."""
        fit = float(np.clip((contrast - 0.1) / 0.35, 0.0, 1.0))
        wi = self.wi
        rho = width / max(self.width0, 1e-6)
        s_w = float(np.clip((rho - 0.3) / 0.15, 0, 1) * np.clip((3.0 - rho) / 0.5, 0, 1)
                    * np.clip((width - 0.2 * wi) / (0.1 * wi), 0, 1) * np.clip((1.6 * wi - width) / (0.2 * wi), 0, 1))
        s_h = float(np.clip((1.15 * wi - height) / (0.15 * wi), 0, 1) * np.clip((height - 0.03 * wi) / (0.03 * wi), 0, 1))
        dx = (centre[0] - pred[0]) / (0.3 * wi)
        dy = (centre[1] - pred[1]) / (0.4 * wi)
        d = math.sqrt(dx * dx + dy * dy)
        s_p = 1.0 if d <= 1.0 else max(math.exp(-(d - 1.0)), 0.3)
        return float(s_w * s_h * s_p * fit)

    def find(self, crop_bgr: np.ndarray, predicted_centre_crop: tuple[float, float]) -> MouthResult | None:
        """The mouth in one crop (:data:`~tracker.mouth_model.MOUTH_RECT` around the predicted centre,
        the calibrated mouth centre under the head's motion), or None when nothing there can be a
        mouth. The crop's light is first matched to the calibration's (:meth:`gains`)."""
        pred = (float(predicted_centre_crop[0]), float(predicted_centre_crop[1]))
        return self._find(crop_bgr, pred, self.gains(crop_bgr))

    def gains(self, crop: np.ndarray) -> np.ndarray | None:
        """Per-channel gains (3,) that bring the crop's median colour — mostly skin — to the calibration
        crop's, or None when they are within 4 % of 1: light that dims, brightens or changes colour
        after calibration (auto exposure, a lamp, the sun) moves every colour, and the lip axes and
        the inside table were learned under the calibration's light. Clamped to 0.33–3×."""
        ref = self.model.crop_median
        if ref is None:
            return None
        sub = crop[::4, ::4].reshape(-1, 3)
        med = np.partition(sub, len(sub) // 2, axis=0)[len(sub) // 2].astype(np.float64)
        g = np.clip(np.asarray(ref, dtype=np.float64) / np.maximum(med, 1.0), 0.33, 3.0)
        return None if np.all(np.abs(g - 1.0) < 0.04) else g

    def _find(self, crop: np.ndarray, pred: tuple[float, float], gains: np.ndarray | None = None) -> MouthResult | None:
        maps = self.lip_maps(crop, gains)
        found = self.outline(crop, pred, maps, gains)
        if found is None:
            return None
        _, c1, blob, raw, ev, r1, w = found
        value = self.blend(maps, c1[1])
        r, _ = self.snake(value, c1, r1, w)
        poly = self.dirs * r[:, None] + np.array(c1)
        left, right, up, down = polygon_measures(poly)
        corner_map = 0.5 * (ev + 1.0)  # the evidence with the inside: a grin's dark corners count
        left = self._corner(corner_map, left, -1)
        right = self._corner(corner_map, right, +1)
        cx, cy = 0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1])
        up, down = _extent_at(poly, cx, cy)
        reach = max(0.04 * self.wi, 2.0)
        top = self._refine_vertical(value, cx, cy - up, -1, reach)
        bottom = self._refine_vertical(value, cx, cy + down, +1, reach)
        width = math.hypot(right[0] - left[0], right[1] - left[1])
        score = self._score(width, bottom - top, (cx, cy), pred, self._contrast(value, c1, r))
        return MouthResult(
            left=left, right=right, centre=(cx, cy), lip_upper=cy - top, lip_lower=bottom - cy,
            polygon=poly, raw_polygon=raw, blob=blob.astype(bool), cue=self.model.cue, score=score,
        )
