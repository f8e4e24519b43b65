"""Mouth finder for real faces: lip colour → blob → radial polygon → snake → corners and lip edges.

Works in the upright mouth crop of :class:`~tracker.calibration.FaceFrame` (y down, the face's up
is −y), cut with :data:`~tracker.mouth_model.MOUTH_RECT` around the predicted mouth centre, with
a :class:`~tracker.mouth_model.MouthModel` learned at calibration. Per frame:

1. **classify**: one 64³ table lookup per pixel gives the evidence map — the lip score (cue
   ``"colour"``) or the not-skin distance (cue ``"contrast"``: lips, dark inside, teeth and
   shading all differ from the skin) — smoothed a little;
2. **blob**: tag the map, cut thin vertical bridges (philtrum, creases) with a horizontal
   opening, label the pieces; the core is the piece that best fits a mouth near the prediction,
   joined by the pieces straight above or below it (upper and lower lip apart around teeth, a
   tongue, a dark open mouth); every column between the top and bottom of the joined pieces is
   filled, so the dark inside and the teeth count as mouth;
3. **radial polygon**: the farthest blob pixel on each of :data:`N_RAYS` rays from its centre
   (Toyama's radial spanning);
4. **snake**: on each ray the sub-pixel position of the strongest fall of the edge value (the
   lip axis for colour, the not-skin distance for contrast) near the polygon, balanced against a
   second-difference smoothness term around the loop (a closed-form active contour);
5. **measure**: corners = the outline's extreme points along x, centre = their midpoint,
   ``lip_upper`` / ``lip_lower`` = from the centre up / down to the outline, refined to where the
   edge value crosses half-way between lip and skin on that column;
6. **score** in 0..1 — "this is this person's mouth": the outline's size against the calibrated
   mouth, its place against the prediction, how many rays found a lip edge, and how lip-like
   (or how unlike skin) its outer band is. :data:`SCORE_OK` is the threshold for "on the mouth".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np

from tracker.colour_model import lut_index
from tracker.mouth_model import N_RAYS, MouthModel, _smooth_loop, lip_weights

RADIAL = "blob"
SCORE_OK = 0.5
"""A result whose score is at least this is taken to be on this person's mouth."""
LIP_TAG = 0.6
"""Lip value (0 skin, 1 lip) at and above which a pixel is tagged as lip for the blob: above
half-way, so shaded or stubbly skin next to the lips does not join them (the snake then finds
the edge itself)."""


@dataclass
class MouthResult:
    """One frame's mouth, in crop px (y down; the face's up is −y).

    ``left``/``right`` are the corners, ``centre`` their midpoint, ``lip_upper``/``lip_lower``
    the distances from the centre to the outer lip edges along up/down. ``polygon`` (k, 2) is
    the snake outline, ``raw_polygon`` the radial polygon before it, ``blob`` the mouth blob
    (bool, crop size), ``cue`` the evidence used this frame (``"colour"`` or ``"contrast"``),
    ``score`` 0..1 (≥ :data:`SCORE_OK`: on this person's mouth).
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


def sample_rays(img: np.ndarray, centre: tuple[float, float], dirs: np.ndarray, radii: np.ndarray,
                interpolation: int = cv2.INTER_NEAREST) -> np.ndarray:
    """``img`` at ``centre + r·dir`` for every ray (rows) and radius (columns); 0 outside the image."""
    mx = (dirs[:, 0:1] * radii[None, :] + np.float32(centre[0])).astype(np.float32)
    my = (dirs[:, 1:2] * radii[None, :] + np.float32(centre[1])).astype(np.float32)
    return cv2.remap(img, mx, my, interpolation, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


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


def column_fill(mask: np.ndarray) -> np.ndarray:
    """``mask`` (uint8 0/1) with every column filled from its topmost to its bottommost set pixel."""
    h = mask.shape[0]
    has = mask.any(axis=0)
    top = np.argmax(mask, axis=0)
    bottom = h - 1 - np.argmax(mask[::-1], axis=0)
    ys = np.arange(h)[:, None]
    return ((ys >= top[None, :]) & (ys <= bottom[None, :]) & has[None, :]).astype(np.uint8)


def open_kernel(wi: float) -> np.ndarray:
    """A horizontal line 0.12 wi long: opening with it cuts the thin vertical bridges (philtrum,
    creases) that join the lips to the nose or the chin, and keeps the lips (horizontal bands)."""
    return np.ones((1, max(int(round(0.12 * wi)) | 1, 3)), np.uint8)


def find_blob(ev: np.ndarray, thr: float, pred: tuple[float, float], wi: float, width0: float, up0: float,
              min_area: int, inside_like: Callable[[], np.ndarray], kernel: np.ndarray | None = None,
              ) -> tuple[np.ndarray, tuple[int, int, int, int]] | None:
    """The mouth blob in the evidence map ``ev`` (uint8; tagged at ``ev ≥ thr``): uint8 0/1 with
    its columns filled, and its bounding box ``(x, y, w, h)``; None if nothing is tagged.

    The tags are opened with :func:`open_kernel` and labelled; the *core* is the piece most like a
    mouth of width ``width0`` near ``pred``. Pieces straight above or below it join it (the other
    lip, across teeth, a tongue or a dark open mouth) when the gap between them is under 0.06 wi or
    mostly ``inside_like()`` (a lazily computed bool map), and nothing joins from far above the
    upper lip's expected top (``pred`` − ``up0`` − 0.3 wi: the upper lip hangs from the head).
    """
    if ev.dtype == np.uint8:
        _, tags = cv2.threshold(ev, thr - 0.5, 1, cv2.THRESH_BINARY)
    else:
        tags = (ev >= thr).view(np.uint8)
    tags = cv2.morphologyEx(tags, cv2.MORPH_OPEN, kernel if kernel is not None else open_kernel(wi))
    n, lab, stats, cents = cv2.connectedComponentsWithStats(tags, connectivity=4)
    if n <= 1:
        return None
    areas = stats[1:, cv2.CC_STAT_AREA].astype(np.float64)
    xs, ys, ws, hs = (stats[1:, i].astype(np.float64) for i in range(4))
    good = areas >= min_area
    if not good.any():
        return None
    dx = (cents[1:, 0] - pred[0]) / (0.3 * wi)
    dy = (cents[1:, 1] - pred[1]) / (0.35 * wi)
    near = np.exp(-0.5 * (dx * dx + dy * dy))
    wide = np.minimum(ws / max(width0, 1.0), 1.0)
    core = int(np.argmax(np.where(good, near * wide * np.sqrt(areas), -1.0)))
    x0, x1 = xs[core], xs[core] + ws[core]
    ov = np.minimum(xs + ws, x1) - np.maximum(xs, x0)
    below = ys - (ys[core] + hs[core])
    gap = np.maximum(np.maximum(below, ys[core] - (ys + hs)), 0.0)
    cxs = cents[1:, 0]
    cand = (
        good
        & (ov >= 0.5 * np.minimum(ws, ws[core]))
        & (ws >= 0.4 * ws[core])
        & (cxs >= x0) & (cxs <= x1)
        & (gap <= 0.5 * wi)
        & (ys >= pred[1] - up0 - 0.3 * wi)
    )
    cand[core] = False
    keep = [core]
    inside = None
    for j in np.flatnonzero(cand):
        if gap[j] > 0.06 * wi:
            if inside is None:
                inside = inside_like()
            ga, gb = int(max(xs[j], x0)), int(min(xs[j] + ws[j], x1))
            gy0, gy1 = (int(ys[core] + hs[core]), int(ys[j])) if below[j] > 0 else (int(ys[j] + hs[j]), int(ys[core]))
            if gb <= ga or gy1 <= gy0 or float(inside[gy0:gy1, ga:gb].mean()) < 0.35:
                continue
        keep.append(int(j))
    kk = np.array(keep)
    m = (lab == core + 1).astype(np.uint8) if len(kk) == 1 else np.isin(lab, kk + 1).astype(np.uint8)
    bx0, by0 = int(xs[kk].min()), int(ys[kk].min())
    bx1, by1 = int((xs + ws)[kk].max()), int((ys + hs)[kk].max())
    m[by0:by1, bx0:bx1] = column_fill(m[by0:by1, bx0:bx1])
    return m, (bx0, by0, bx1 - bx0, by1 - by0)


def blob_centre(blob: np.ndarray, box: tuple[int, int, int, int]) -> tuple[float, float] | None:
    x, y, w, h = box
    m = cv2.moments(blob[y : y + h, x : x + w], binaryImage=True)
    if m["m00"] <= 0:
        return None
    return (m["m10"] / m["m00"] + x, m["m01"] / m["m00"] + y)


def farthest_radii(blob: np.ndarray, centre: tuple[float, float], dirs: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Radius of the farthest blob pixel on each ray (Toyama's radial spanning), to the pixel's outer
    edge; 0 on a ray that meets none."""
    inside = sample_rays(blob, centre, dirs, radii) > 0
    last = len(radii) - 1 - np.argmax(inside[:, ::-1], axis=1)
    r = radii[last].astype(np.float64) + 0.5
    r[~inside.any(axis=1)] = 0.0
    return r


def exit_radii(mask: np.ndarray, centre: tuple[float, float], dirs: np.ndarray, radii: np.ndarray, gap: int) -> np.ndarray:
    """Radius on each ray from ``centre`` where it leaves the region ``mask`` (uint8 0/1) for good:
    the first run of ``gap`` samples outside it after the first inside one (half-way between the
    last inside and first outside sample); the ray's end if it never leaves, 0 if it never enters."""
    inside = sample_rays(mask, centre, dirs, radii) > 0
    n, m = inside.shape
    entered = np.maximum.accumulate(inside, axis=1)
    out = np.concatenate([~inside & entered, np.ones((n, gap), bool)], axis=1)
    c = np.zeros((n, m + gap + 1), np.int32)
    np.cumsum(out, axis=1, out=c[:, 1:])
    run = (c[:, gap : gap + m] - c[:, :m]) == gap
    k = np.where(run.any(axis=1), np.argmax(run, axis=1), m - 1)
    step = float(radii[1] - radii[0]) if len(radii) > 1 else 0.5
    r = radii[np.clip(k, 0, m - 1)].astype(np.float64) - 0.5 * step
    r[~entered[:, -1]] = 0.0
    return np.maximum(r, 0.0)


def outline_from_blob(found: np.ndarray, wi: float, n_rays: int = N_RAYS) -> np.ndarray | None:
    """The radial polygon ``(n, 2)`` of a blob (uint8 0/1), spikes removed; None for an empty blob."""
    ys, xs = np.nonzero(found)
    if not len(xs):
        return None
    c = (float(xs.mean()), float(ys.mean()))
    dirs = ray_directions(n_rays)
    r = _smooth_loop(farthest_radii(found, c, dirs, np.arange(0.0, 0.85 * wi, 0.5, dtype=np.float32)))
    return dirs * r[:, None] + np.array(c)


class MouthFinder:
    """Find one performer's mouth in mouth crops (see the module docstring).

    ``model`` comes from :func:`~tracker.mouth_model.learn_mouth`; ``work_ipd`` is the crop
    frame's inter-eye distance (px). Ray directions, sample radii, kernels and the snake's
    matrix are precomputed here.
    """

    def __init__(self, model: MouthModel, work_ipd: float, n_rays: int = N_RAYS, alpha: float = 0.6):
        self.model = model
        self.wi = wi = float(work_ipd)
        k = wi / model.work_ipd  # the model's lengths → this crop's
        self.k = k
        self.width0 = model.width * k
        self.height0 = (model.lip_upper + model.lip_lower) * k
        self.up0 = model.lip_upper * k
        self.n = n_rays
        self.dirs = ray_directions(n_rays)
        self._dirs32 = self.dirs.astype(np.float32)
        self.step = 0.5
        self.max_r = 0.85 * wi
        self.radii = np.arange(0.0, self.max_r + 1e-9, self.step, dtype=np.float32)
        self.search = np.arange(-0.05 * wi, 0.05 * wi + 1e-9, self.step, dtype=np.float32)
        self.sigma = max(0.012 * wi, 0.6)
        self.sigma_blob = max(0.022 * wi, 0.8)
        self.exit_gap = max(int(round(0.035 * wi / self.step)), 2)
        self.edge_level = {"colour": 0.5, "contrast": 1.0}
        self._band = np.array([[1.5, 3.0]], np.float32)
        g = max(int(round(0.08 * wi)) | 1, 3)
        self.grow_kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (g, g))
        self.open_kernel = open_kernel(wi)
        self.min_area = max(int(0.02 * model.area * k * k), 6)
        self.axis_up = np.asarray(model.axis_up[:3], dtype=np.float32).reshape(1, 3)
        self.axis_dn = np.asarray(model.axis_down[:3], dtype=np.float32).reshape(1, 3)
        self.off_up, self.off_dn = float(model.axis_up[3]), float(model.axis_down[3])
        d2 = np.zeros((n_rays, n_rays))
        for i in range(n_rays):
            d2[i, (i - 1) % n_rays] += 1.0
            d2[i, i] -= 2.0
            d2[i, (i + 1) % n_rays] += 1.0
        self._dtd = alpha * d2.T @ d2
        self._rows = np.arange(n_rays)

    # ------------------------------------------------------------------ evidence
    def tags(self, idx: np.ndarray, cue: str) -> tuple[np.ndarray, float]:
        """The smoothed tag map (uint8) for ``cue`` from the crop's table indices, and its threshold:
        the lip classifier's score for colour, the not-skin distance for contrast."""
        if cue == "colour":
            return cv2.GaussianBlur(self.model.lip.table.take(idx), (0, 0), self.sigma_blob), 128.0
        return cv2.GaussianBlur(self.model.not_skin_table.take(idx), (0, 0), self.sigma), self.model.threshold

    def lip_value(self, crop: np.ndarray, y_line: float) -> np.ndarray:
        """The lip value (float32; 0 skin, 1 lip): the upper lip's axis above the mouth line ``y_line``,
        the lower lip's below, blended across it."""
        c32 = crop.astype(np.float32)
        vu = cv2.transform(c32, self.axis_up)
        vd = cv2.transform(c32, self.axis_dn)
        vu += np.float32(self.off_up)
        vd -= vu
        vd += np.float32(self.off_dn)
        vd *= lip_weights(crop.shape[0], y_line, self.wi)
        vd += vu
        return cv2.GaussianBlur(vd, (0, 0), 0.7)

    def edge_value(self, crop: np.ndarray, idx: np.ndarray, y_line: float, cue: str) -> np.ndarray:
        """The float32 value whose fall marks the outer lip edge: the lip value for colour, the
        not-skin distance over its threshold for contrast."""
        if cue == "colour":
            return self.lip_value(crop, y_line)
        d = cv2.GaussianBlur(self.model.not_skin_table.take(idx), (0, 0), self.sigma).astype(np.float32)
        return d * np.float32(1.0 / self.model.threshold)

    def blob(self, tags: np.ndarray, thr: float, pred: tuple[float, float], idx: np.ndarray
             ) -> tuple[np.ndarray, tuple[int, int, int, int]] | None:
        """The mouth blob and its box (:func:`find_blob` with this performer's sizes; teeth, the dark
        inside and bright pixels between two lips let them join)."""
        return find_blob(tags, thr, pred, self.wi, self.width0, self.up0, self.min_area,
                         lambda: self.model.inside_table.take(idx) > 0, self.open_kernel)

    # ------------------------------------------------------------------ polygon and snake
    def snake(self, value: np.ndarray, centre: tuple[float, float], r0: np.ndarray, iters: int = 2) -> tuple[np.ndarray, np.ndarray]:
        """Radii refined to the outer lip edge near ``r0`` on each ray, smoothed around the loop; also
        the fall found on each ray (edge strength).

        The edge on a ray is the *outermost* local maximum of the fall of ``value`` (inside → outside)
        that is at least half the ray's strongest: an open mouth's or the lips' inner edges (lip to
        teeth, to the dark gap) can be stronger than the outer one, and must not pull it in."""
        r = r0.astype(np.float64)
        cx, cy = np.float32(centre[0]), np.float32(centre[1])
        dx, dy = self._dirs32[:, 0:1], self._dirs32[:, 1:2]
        off = self.search[None, :]
        rows = self._rows
        strength = np.zeros(self.n)
        m = len(self.search) - 2
        pos = np.arange(m)[None, :]
        for _ in range(iters):
            rr = np.maximum(r.astype(np.float32)[:, None] + off, 0.0)
            prof = cv2.remap(value, cx + dx * rr, cy + dy * rr, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            fall = prof[:, :-2] - prof[:, 2:]
            peak = np.zeros_like(fall, dtype=bool)
            peak[:, 1:-1] = (fall[:, 1:-1] >= fall[:, :-2]) & (fall[:, 1:-1] >= fall[:, 2:])
            best = fall[:, 1:-1].max(axis=1)
            strong = peak & (fall >= 0.999 * best[:, None]) & (fall > 0)
            strong[:, 0] = strong[:, -1] = False
            j = np.where(strong.any(axis=1), np.max(np.where(strong, pos, -1), axis=1), np.argmax(fall[:, 1:-1], axis=1) + 1)
            j = np.clip(j, 1, m - 2)
            a, b, c = fall[rows, j - 1], fall[rows, j], fall[rows, j + 1]
            den = a - 2 * b + c
            den = np.where(np.abs(den) > 1e-9, den, -1e-9)
            frac = np.clip(0.5 * (a - c) / den, -0.5, 0.5)
            edge = rr[rows, j + 1] + frac * self.step
            strength = b
            wgt = np.clip(b / max(float(np.median(b)), 1e-6), 0.02, 1.0)
            A = self._dtd.copy()
            A[rows, rows] += wgt
            r = np.linalg.solve(A, wgt * edge)
        return np.maximum(r, 0.0), strength

    # ------------------------------------------------------------------ measurements
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

    def _score(self, res_w: float, res_h: float, centre, pred, fit: float) -> float:
        """Score 0..1: ``fit`` (how well the outline separates mouth inside from skin outside) times
        the plausibility of its width and height against the calibrated mouth and of its place
        against the prediction."""
        wi = self.wi
        rho = res_w / max(self.width0, 1e-6)
        s_w = float(np.clip((rho - 0.3) / 0.25, 0, 1) * np.clip((2.1 - rho) / 0.4, 0, 1))
        s_h = float(np.clip((1.15 * wi - res_h) / (0.2 * wi), 0, 1) * np.clip(res_h / max(0.25 * self.height0, 1.0), 0, 1))
        dx = (centre[0] - pred[0]) / (0.3 * wi)
        dy = (centre[1] - pred[1]) / (0.45 * wi)
        s_p = math.exp(-0.5 * (dx * dx + dy * dy))
        return float(s_w * s_h * (0.3 + 0.7 * s_p) * fit)

    def _fit(self, value: np.ndarray, level: float, centre, r: np.ndarray) -> float:
        """Share of rays whose outline has mouth just inside (``value ≥ level`` 1.5–3 px in) times the
        share with skin just outside (``value < level`` 1.5–3 px out)."""
        rr = np.concatenate([np.maximum(r[:, None] - self._band, 0.5), r[:, None] + self._band], axis=1).astype(np.float32)
        mx = self._dirs32[:, 0:1] * rr + np.float32(centre[0])
        my = self._dirs32[:, 1:2] * rr + np.float32(centre[1])
        v = cv2.remap(value, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        k = self._band.shape[1]
        inside = float(np.mean(v[:, :k].mean(axis=1) >= level))
        outside = float(np.mean(v[:, k:].mean(axis=1) < level))
        return inside * outside

    def find(self, crop_bgr: np.ndarray, predicted_centre_crop: tuple[float, float]) -> MouthResult | None:
        """The mouth in one crop (:data:`~tracker.mouth_model.MOUTH_RECT` around the predicted centre),
        or None when nothing there can be a mouth."""
        crop = crop_bgr
        pred = (float(predicted_centre_crop[0]), float(predicted_centre_crop[1]))
        cues = (self.model.cue,) if self.model.cue == "contrast" else ("colour", "contrast")
        best = None
        for cue in cues:
            res = self._find(crop, pred, cue)
            if res is not None and (best is None or res.score > best.score):
                best = res
        return best

    def _find(self, crop: np.ndarray, pred: tuple[float, float], cue: str) -> MouthResult | None:
        idx = lut_index(crop)
        tag_map, thr = self.tags(idx, cue)
        found = self.blob(tag_map, thr, pred, idx)
        if found is None:
            return None
        blob, box = found
        centre = blob_centre(blob, box)
        if centre is None:
            return None
        value = self.edge_value(crop, idx, centre[1], cue)
        # the mouth region seen from its centre: lip, or the inside (dark, teeth); each ray ends
        # where it first leaves it for skin — the nose or a chin's shadow further out do not count
        if RADIAL == "exit":
            region = (value >= self.edge_level[cue]).view(np.uint8) | self.model.inside_table.take(idx)
            r0 = exit_radii(region, centre, self.dirs, self.radii, self.exit_gap)
        elif RADIAL == "blobexit":
            region = blob | ((value >= self.edge_level[cue]).view(np.uint8) & cv2.dilate(blob, self.grow_kernel))
            r0 = exit_radii(region, centre, self.dirs, self.radii, self.exit_gap)
        else:
            r0 = farthest_radii(blob, centre, self.dirs, self.radii)
        raw = self.dirs * r0[:, None] + np.array(centre)
        r, strength = self.snake(value, centre, r0)
        poly = self.dirs * r[:, None] + np.array(centre)
        left, right, up, down = polygon_measures(poly)
        cx, cy = 0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1])
        reach = max(0.04 * self.wi, 2.0)
        top = self._refine_vertical(value, cx, cy - up, -1, reach)
        bottom = self._refine_vertical(value, cx, cy + down, +1, reach)
        width = math.hypot(right[0] - left[0], right[1] - left[1])
        fit = self._fit(value, self.edge_level[cue], centre, r)
        score = self._score(width, bottom - top, (cx, cy), pred, fit)
        return MouthResult(
            left=left, right=right, centre=(cx, cy), lip_upper=cy - top, lip_lower=bottom - cy,
            polygon=poly, raw_polygon=raw, blob=blob.astype(bool), cue=cue, score=score,
        )
