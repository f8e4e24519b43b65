"""Mouth finder: lip blob → radial polygon → snake → corners and lip heights.

Everything here works in a small upright crop (the face's up axis is −y) holding the lip
score of each pixel (0..255 from the lip :class:`~tracker.colour_model.ColourClassifier`).
The caller maps the results back to frame pixels.

Steps (Buck et al. §2, with a snake as the issue asks):
1. tag pixels with lip score ≥ 128, open and close them with a 3×3 cross to drop specks
   and bridge the dark gap between the lips, keep the largest 4-connected component
   (``cv2.connectedComponentsWithStats``) and fill its holes (an open mouth is a ring);
2. span rays from the blob's centre and take the farthest blob pixel on each: a many-sided
   polygon of the outer lip outline (Toyama's radial spanning);
3. snake: on each ray find the strongest falling edge of the smoothed lip score near the
   polygon (sub-pixel), then solve for radii that balance those edges against a
   second-difference smoothness term — a closed-form active contour, iterated twice;
4. corners = the extreme points along the face's x axis (refined on the rows near them),
   centre = their midpoint, upper/lower lip = distance from the centre to the contour
   straight up/down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))


@dataclass
class MouthResult:
    """Mouth measurements in crop pixels (y down; the face's up is −y).

    ``polygon`` (k, 2) is the snake-refined outline, ``raw_polygon`` the radial spanning
    before the snake, ``blob`` the cleaned lip mask (bool, crop size).
    """

    left: tuple[float, float]
    right: tuple[float, float]
    centre: tuple[float, float]
    lip_upper: float
    lip_lower: float
    polygon: np.ndarray
    raw_polygon: np.ndarray
    blob: np.ndarray
    area: int

    @property
    def width(self) -> float:
        return math.hypot(self.right[0] - self.left[0], self.right[1] - self.left[1])


class MouthFinder:
    """Precomputed ray directions, sample offsets and snake matrix for ``n_rays`` rays."""

    def __init__(self, n_rays: int = 48, alpha: float = 0.5, search: float = 2.5, step: float = 0.5):
        self.n = int(n_rays)
        ang = np.arange(self.n) * (2 * math.pi / self.n)
        self.dirs = np.stack([np.cos(ang), np.sin(ang)], axis=1)
        self.alpha = float(alpha)
        self.offsets = np.arange(-search, search + 1e-9, step)
        self.step = float(step)
        n = self.n
        d2 = np.zeros((n, n))
        for i in range(n):
            d2[i, (i - 1) % n] += 1.0
            d2[i, i] -= 2.0
            d2[i, (i + 1) % n] += 1.0
        self._dtd = self.alpha * d2.T @ d2
        self._smooth_all = np.linalg.inv(np.eye(n) + self._dtd)
        self._rows = np.arange(n)
        self._ray_cache: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._dx32 = self.dirs[:, 0:1].astype(np.float32)
        self._dy32 = self.dirs[:, 1:2].astype(np.float32)
        self._off32 = self.offsets.astype(np.float32)[None, :]
        self._border_cache: dict[tuple[int, int], np.ndarray] = {}

    # ------------------------------------------------------------------ blob
    @staticmethod
    def blob(
        score_u8: np.ndarray, seed: tuple[float, float] | None = None, min_area: int = 6
    ) -> tuple[np.ndarray, np.ndarray, int] | None:
        """The cleaned lip blob: ``(mask bool, stats row, area)`` or None.

        Tags (score ≥ 128) are opened and closed with a 3×3 cross; of the 4-connected
        components the largest wins, discounted by its distance from ``seed`` if given;
        pieces directly above or below it (a lip cut off by the teeth) join it.
        Holes are not filled: the radial spanning takes each ray's farthest blob pixel, so
        an open mouth's ring of lip gives its outer outline all the same.
        """
        _, tags = cv2.threshold(score_u8, 127, 1, cv2.THRESH_BINARY)
        tags = cv2.morphologyEx(tags, cv2.MORPH_OPEN, _CROSS)
        tags = cv2.morphologyEx(tags, cv2.MORPH_CLOSE, _CROSS)
        # labels alone are several times cheaper than labels with statistics, and a single
        # component (the usual case) is the tag image itself
        n, _ = cv2.connectedComponents(tags, connectivity=4)
        if n <= 1:
            return None
        if n == 2:  # a single component: nothing to choose or merge
            area = cv2.countNonZero(tags)
            if area < min_area:
                return None
            return tags.view(bool), np.array([*cv2.boundingRect(tags), area], dtype=np.int32), int(area)
        n, lab, stats, cents = cv2.connectedComponentsWithStats(tags, connectivity=4)
        areas = stats[1:, cv2.CC_STAT_AREA].astype(np.float64)
        score = areas
        if seed is not None:
            d = np.hypot(cents[1:, 0] - seed[0], cents[1:, 1] - seed[1])
            diag = math.hypot(*score_u8.shape[:2])
            score = areas * (1.0 - 0.5 * np.minimum(d / (0.5 * diag), 1.0))
        best = int(np.argmax(score))
        if areas[best] < min_area:
            return None
        # teeth or a tongue can cut an open mouth's lips apart: pieces of lip right above
        # or below the main blob, overlapping it sideways, belong to the same mouth
        x, y, w, h = (int(v) for v in stats[best + 1, :4])
        sx, sy, sw, sh = (stats[1:, i] for i in range(4))
        overlap = np.minimum(x + w, sx + sw) - np.maximum(x, sx)
        gap = np.maximum(np.maximum(sy - (y + h), y - (sy + sh)), 0)
        near = (areas >= max(min_area, 0.04 * areas[best])) & (overlap >= 0.5 * np.minimum(w, sw)) & (gap <= 0.25 * w)
        near[best] = False
        keep = [best + 1] + [int(j) + 1 for j in np.flatnonzero(near)]
        if len(keep) == 1:
            return lab == best + 1, stats[best + 1], int(areas[best])
        mask = np.isin(lab, keep)
        x0 = min(int(stats[j, 0]) for j in keep)
        y0 = min(int(stats[j, 1]) for j in keep)
        x1 = max(int(stats[j, 0] + stats[j, 2]) for j in keep)
        y1 = max(int(stats[j, 1] + stats[j, 3]) for j in keep)
        st = np.array([x0, y0, x1 - x0, y1 - y0, int(sum(stats[j, 4] for j in keep))])
        return mask, st, int(st[4])

    # ------------------------------------------------------------------ polygon
    def _rays(self, max_r: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        key = int(math.ceil(max_r))
        if key not in self._ray_cache:
            rs = np.arange(0.0, key + 1e-9, 0.5)
            ox = (self.dirs[:, 0:1] * rs[None, :]).astype(np.float32)
            oy = (self.dirs[:, 1:2] * rs[None, :]).astype(np.float32)
            self._ray_cache[key] = (rs, ox, oy)
        return self._ray_cache[key]

    def radial(self, mask: np.ndarray, centre: tuple[float, float], max_r: float) -> np.ndarray:
        """Radius (crop px) of the farthest mask pixel on each ray from ``centre`` (0.5 px steps)."""
        rs, ox, oy = self._rays(max_r)
        inside = cv2.remap(
            mask.view(np.uint8), ox + np.float32(centre[0]), oy + np.float32(centre[1]), cv2.INTER_NEAREST,
            borderMode=cv2.BORDER_CONSTANT, borderValue=0,
        ).astype(bool)
        last = len(rs) - 1 - np.argmax(inside[:, ::-1], axis=1)
        r = rs[last] + 0.5  # to the pixel's outer edge
        r[~inside.any(axis=1)] = 0.5
        return r

    def snake(self, score: np.ndarray, centre: tuple[float, float], r0: np.ndarray, iters: int = 1) -> np.ndarray:
        """Refine radii ``r0`` to the lip boundary of the float image ``score`` (lip high).

        External term: on each ray the sub-pixel position of the steepest fall of the score
        within ``search`` px of the current radius (rays whose fall is under 15 % of the
        steepest barely count). Internal term: ``alpha`` × squared second differences of
        the radii around the loop. Each iteration solves the resulting linear system
        exactly (a precomputed inverse when every ray found an edge).
        """
        r = r0.astype(np.float64)
        cx, cy = np.float32(centre[0]), np.float32(centre[1])
        dx, dy, off = self._dx32, self._dy32, self._off32
        rows = self._rows
        for _ in range(iters):
            rr = np.maximum(r.astype(np.float32)[:, None] + off, 0.0)
            prof = cv2.remap(score, cx + dx * rr, cy + dy * rr, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            fall = prof[:, :-2] - prof[:, 2:]  # ∝ −d/dr, positive where the lip ends
            j = np.argmax(fall[:, 1:-1], axis=1) + 1
            a, b, c = fall[rows, j - 1], fall[rows, j], fall[rows, j + 1]
            den = a - 2 * b + c
            den = np.where(np.abs(den) > 1e-9, den, -1e-9)
            frac = np.minimum(np.maximum(0.5 * (a - c) / den, -0.5), 0.5)
            edge = rr[rows, j + 1] + frac * self.step
            good = b > 0.15 * float(b.max())
            if good.all():  # the usual case: every ray found the lip's edge
                r = self._smooth_all @ edge
            else:
                wgt = np.where(good, 1.0, 1e-3)
                A = self._dtd.copy()
                A[rows, rows] += wgt
                r = np.linalg.solve(A, wgt * edge)
        return np.maximum(r, 0.0)

    def polygon(self, centre: tuple[float, float], r: np.ndarray) -> np.ndarray:
        """Vertices ``(n, 2)`` at radii ``r`` along the rays from ``centre``."""
        return self.dirs * r[:, None] + np.array(centre, dtype=np.float64)

    def _border_median(self, value: np.ndarray) -> float:
        """Median of a 2-D array's border pixels (top and bottom rows, then the side columns)."""
        h, w = value.shape
        idx = self._border_cache.get((h, w))
        if idx is None:
            flat = np.arange(h * w).reshape(h, w)
            idx = np.concatenate([flat[0], flat[-1], flat[1:-1, 0], flat[1:-1, -1]])
            self._border_cache[(h, w)] = idx
        v = value.take(idx)
        n = len(v)
        k = n // 2
        if n % 2:
            return float(np.partition(v, k)[k])
        p = np.partition(v, (k - 1, k))
        return float((p[k - 1] + p[k]) / v.dtype.type(2))

    # ------------------------------------------------------------------ measurements
    @staticmethod
    def _crossing_y(poly: np.ndarray, x: float, centre_y: float) -> tuple[float, float]:
        """Smallest and largest y where the closed polygon crosses the vertical line ``x``."""
        p1 = np.concatenate([poly[1:], poly[:1]])
        x0, x1 = poly[:, 0], p1[:, 0]
        hit = (x0 <= x) != (x1 <= x)
        if not hit.any():
            return centre_y, centre_y
        t = (x - x0[hit]) / (x1[hit] - x0[hit])
        ys = poly[hit, 1] + t * (p1[hit, 1] - poly[hit, 1])
        return float(ys.min()), float(ys.max())

    @staticmethod
    def _corner(norm: np.ndarray, start: tuple[float, float], side: int) -> tuple[float, float]:
        """Sub-pixel mouth corner on ``side`` (−1 left, +1 right).

        Starts at the blob's extreme point ``start`` and scans the rows within two pixels
        of it for the farthest point where the normalised lip value falls through 0.5
        going outwards.
        """
        vx, vy = float(start[0]), float(start[1])
        h, w = norm.shape
        a = min(max(int(round(vx - side * 6)), 0), w - 1)
        b = min(max(int(round(vx + side * 5)), 0), w - 1)
        lo, hi = min(a, b), max(a, b)
        y0 = int(round(vy))
        ya, yb = max(y0 - 2, 0), min(y0 + 3, h)
        if hi - lo < 2 or ya >= yb:
            return vx, vy
        block = norm[ya:yb, lo : hi + 1]
        if side < 0:
            block = block[:, ::-1]
        # a handful of rows and columns: plain Python beats a dozen numpy calls here
        m = block.shape[1]
        rows, pos = [], []
        for row, vals in enumerate(block.tolist()):
            k = m - 1
            while k >= 0 and not vals[k] >= 0.5:  # last lip sample going outwards
                k -= 1
            if k < 0 or k == m - 1:
                continue
            va, vb = block[row, k], block[row, k + 1]  # float32: the crossing in float32 as before
            t = float((va - 0.5) / (va - vb)) if va != vb else 0.0
            rows.append(row)
            pos.append(k + t)
        if not rows:
            return vx, vy
        best = pos.index(max(pos))
        yb, xb = float(rows[best]), pos[best]
        flat = [r for r, p in zip(rows, pos) if p >= pos[best] - 0.15]
        if len(flat) > 1:  # a blunt corner: the middle of the rows that reach furthest
            yb = 0.5 * float(flat[0] + flat[-1])
        # a sharp tip lies between rows: fit a parabola through the best row and its neighbours
        elif 0 < best < len(rows) - 1 and rows[best - 1] == rows[best] - 1 and rows[best + 1] == rows[best] + 1:
            a_, b_, c_ = float(pos[best - 1]), float(pos[best]), float(pos[best + 1])
            den = a_ - 2 * b_ + c_
            if den < -1e-6:
                d = min(max(0.5 * (a_ - c_) / den, -0.5), 0.5)
                yb += d
                xb = b_ - 0.25 * (a_ - c_) * d
        xx = lo + xb if side > 0 else hi - xb
        return float(xx), float(ya + yb)

    @staticmethod
    def _refine_vertical(norm: np.ndarray, x: float, y_est: float, direction: int, reach: float = 3.0) -> float:
        """Sub-pixel y where the normalised lip value crosses 0.5 on the column through ``x``.

        Searches ``y_est ± reach`` walking outwards (``direction`` −1 up, +1 down) and returns
        the outermost crossing from lip (≥ 0.5) to skin; ``y_est`` if there is none.
        """
        h, w = norm.shape
        ys = np.minimum(np.maximum(y_est + _VSTEPS_BY_DIR[direction], 0.0), h - 1).astype(np.float32).reshape(1, -1)
        xs = np.full(ys.shape, min(max(x, 0.0), w - 1.0), dtype=np.float32)
        vals = cv2.remap(norm, xs, ys, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).ravel()
        ys = ys.ravel()
        # half-way between the lip just inside and the skin just outside this very edge
        inner, outer = float(np.add.reduce(vals[:8])) * 0.125, float(np.add.reduce(vals[-4:])) * 0.25
        half = 0.5 * (inner + outer) if inner - outer > 0.3 else 0.5
        inside = vals >= half
        idx = np.nonzero(inside[:-1] & ~inside[1:])[0]
        if len(idx) == 0:
            return y_est
        i = int(idx[-1])
        a, b = float(vals[i]), float(vals[i + 1])
        t = (a - half) / (a - b) if a != b else 0.5
        return float(ys[i] + t * (ys[i + 1] - ys[i]))

    def find(
        self,
        score_u8: np.ndarray,
        value: np.ndarray | None = None,
        seed: tuple[float, float] | None = None,
        min_area: int = 6,
        lip_level: float | None = None,
    ) -> MouthResult | None:
        """Run all steps on a crop of lip scores; None when no lip blob is found.

        ``value`` (float32, crop size) is an optional lip value that is linear in colour
        mixtures (high on lip, low on skin, e.g. a projection of BGR); edges are then placed
        where it crosses half-way between the lip's level and the level along the crop's
        border (skin), which is exact for anti-aliased or blurred edges; ``lip_level`` is
        the lip's nominal value if known: the lip level is then the mean over blob pixels
        within ±50 % of it (the dark inside of an open mouth would bias a plain mean). Without ``value`` the smoothed score is used.
        """
        found = self.blob(score_u8, seed, min_area)
        if found is None:
            return None
        blob, st, area = found
        x0, y0, bw, bh = (int(v) for v in st[:4])
        sub = blob[y0 : y0 + bh, x0 : x0 + bw]
        m = cv2.moments(sub.view(np.uint8), binaryImage=True)
        centre = (m["m10"] / m["m00"] + x0, m["m01"] / m["m00"] + y0)
        max_r = 0.5 * math.hypot(bw, bh) + 3.0
        r0 = self.radial(blob, centre, max_r)
        raw = self.polygon(centre, r0)
        if value is not None:
            lo_level = self._border_median(value)
            lip_vals = value[y0 : y0 + bh, x0 : x0 + bw][sub & (score_u8[y0 : y0 + bh, x0 : x0 + bw] >= 128)]
            if lip_level is not None and len(lip_vals):
                # only values near the lip's own (not the dark inside of an open mouth)
                near = lip_vals[(lip_vals > 0.5 * lip_level) & (lip_vals < 1.5 * lip_level)]
                lip_vals = near if len(near) >= 8 else lip_vals
            hi_level = float(np.add.reduce(lip_vals)) / len(lip_vals) if len(lip_vals) else lo_level + 1.0
            span = hi_level - lo_level
            if abs(span) < 1e-6:
                span = 1.0
            norm = cv2.GaussianBlur(value, (3, 3), 0.6)
            norm = (norm - np.float32(lo_level)) * np.float32(1.0 / span)
        else:
            norm = cv2.GaussianBlur(score_u8.astype(np.float32) * np.float32(1.0 / 255.0), (5, 5), 0.8)
        r = self.snake(norm, centre, r0)
        poly = self.polygon(centre, r)
        ends = []
        for c in (0, bw - 1):  # the blob's leftmost and rightmost columns
            rows = np.flatnonzero(sub[:, c])
            ends.append((c + x0, 0.5 * float(rows[0] + rows[-1]) + y0))
        left = self._corner(norm, ends[0], -1)
        right = self._corner(norm, ends[1], +1)
        cx = 0.5 * (left[0] + right[0])
        cy = 0.5 * (left[1] + right[1])
        top, bottom = self._crossing_y(poly, cx, cy)
        top = self._refine_vertical(norm, cx, top, -1)
        bottom = self._refine_vertical(norm, cx, bottom, +1)
        return MouthResult(
            left=left,
            right=right,
            centre=(cx, cy),
            lip_upper=cy - top,
            lip_lower=bottom - cy,
            polygon=poly,
            raw_polygon=raw,
            blob=blob,
            area=area,
        )


_VSTEPS = np.arange(-3.0, 3.0 + 1e-9, 0.25)
_VSTEPS_BY_DIR = {-1: _VSTEPS * -1, 1: _VSTEPS * 1}
