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
    """Precomputed ray directions and snake matrices for ``n_rays`` rays."""

    def __init__(self, n_rays: int = 72, alpha: float = 0.6, search: float = 3.0, step: float = 0.5):
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

    # ------------------------------------------------------------------ blob
    @staticmethod
    def blob(score_u8: np.ndarray, seed: tuple[float, float] | None = None, min_area: int = 6) -> np.ndarray | None:
        """The cleaned largest 4-connected lip blob (bool mask), or None.

        With ``seed`` given, a component containing or near it wins ties of similar size.
        """
        tags = (score_u8 >= 128).astype(np.uint8)
        tags = cv2.morphologyEx(tags, cv2.MORPH_OPEN, _CROSS)
        tags = cv2.morphologyEx(tags, cv2.MORPH_CLOSE, _CROSS)
        n, lab, stats, cents = cv2.connectedComponentsWithStats(tags, connectivity=4)
        if n <= 1:
            return None
        areas = stats[1:, cv2.CC_STAT_AREA].astype(np.float64)
        score = areas.copy()
        if seed is not None:
            d = np.hypot(cents[1:, 0] - seed[0], cents[1:, 1] - seed[1])
            diag = math.hypot(*score_u8.shape[:2])
            score = areas * (1.0 - 0.5 * np.clip(d / (0.5 * diag), 0, 1))
        best = int(np.argmax(score))
        if areas[best] < min_area:
            return None
        m = (lab == best + 1).astype(np.uint8)
        # fill holes: flood the background from outside, whatever is not reached is inside
        cnts, _ = cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        cv2.drawContours(m, cnts, -1, 1, thickness=cv2.FILLED)
        return m.astype(bool)

    # ------------------------------------------------------------------ polygon
    def radial(self, mask: np.ndarray, centre: tuple[float, float], max_r: float) -> np.ndarray:
        """Radius (crop px) of the farthest mask pixel on each ray from ``centre``."""
        h, w = mask.shape
        rs = np.arange(0.0, max_r, 0.5)
        px = centre[0] + self.dirs[:, 0:1] * rs[None, :]
        py = centre[1] + self.dirs[:, 1:2] * rs[None, :]
        xi = np.clip(np.rint(px).astype(np.int32), 0, w - 1)
        yi = np.clip(np.rint(py).astype(np.int32), 0, h - 1)
        inside = mask[yi, xi]
        inside &= (px >= -0.5) & (px <= w - 0.5) & (py >= -0.5) & (py <= h - 0.5)
        last = len(rs) - 1 - np.argmax(inside[:, ::-1], axis=1)
        r = rs[last] + 0.5  # to the pixel's outer edge
        r[~inside.any(axis=1)] = 0.5
        return r

    def snake(self, score: np.ndarray, centre: tuple[float, float], r0: np.ndarray, iters: int = 2) -> np.ndarray:
        """Refine radii ``r0`` to the lip boundary of the float score image ``score``.

        External term: on each ray the sub-pixel position of the steepest fall of the score
        within ``search`` px of the current radius, weighted by its steepness. Internal
        term: ``alpha`` × squared second differences of the radii around the loop.
        """
        r = r0.astype(np.float64).copy()
        cx, cy = centre
        off = self.offsets
        for _ in range(iters):
            rr = np.maximum(r[:, None] + off[None, :], 0.0)
            mx = (cx + self.dirs[:, 0:1] * rr).astype(np.float32)
            my = (cy + self.dirs[:, 1:2] * rr).astype(np.float32)
            prof = cv2.remap(score, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            fall = -(prof[:, 2:] - prof[:, :-2]) / (2 * self.step)  # centred derivative, positive on falling edges
            j = np.argmax(fall, axis=1)
            jj = np.clip(j, 1, fall.shape[1] - 2)
            rows = np.arange(self.n)
            a, b, c = fall[rows, jj - 1], fall[rows, jj], fall[rows, jj + 1]
            den = a - 2 * b + c
            frac = np.where(np.abs(den) > 1e-9, 0.5 * (a - c) / np.where(np.abs(den) > 1e-9, den, 1.0), 0.0)
            frac = np.clip(frac, -0.5, 0.5)
            edge = rr[rows, jj + 1] + frac * self.step
            strength = np.clip(b, 0.0, None)
            wgt = strength / (strength.max() + 1e-9)
            wgt = np.where(wgt > 0.15, wgt, 0.0) + 1e-3
            r = np.linalg.solve(np.diag(wgt) + self._dtd, wgt * edge)
        return np.maximum(r, 0.0)

    def polygon(self, centre: tuple[float, float], r: np.ndarray) -> np.ndarray:
        return np.stack([centre[0] + self.dirs[:, 0] * r, centre[1] + self.dirs[:, 1] * r], axis=1)

    # ------------------------------------------------------------------ measurements
    @staticmethod
    def _crossing_y(poly: np.ndarray, x: float, centre_y: float) -> tuple[float, float]:
        """Smallest and largest y where the closed polygon crosses the vertical line ``x``."""
        p0 = poly
        p1 = np.roll(poly, -1, axis=0)
        x0, x1 = p0[:, 0], p1[:, 0]
        hit = ((x0 <= x) & (x1 > x)) | ((x1 <= x) & (x0 > x))
        if not hit.any():
            return centre_y, centre_y
        t = (x - x0[hit]) / (x1[hit] - x0[hit])
        ys = p0[hit, 1] + t * (p1[hit, 1] - p0[hit, 1])
        return float(ys.min()), float(ys.max())

    @staticmethod
    def _corner(score: np.ndarray, poly: np.ndarray, side: int) -> tuple[float, float]:
        """Sub-pixel mouth corner on ``side`` (−1 left, +1 right).

        Starts at the polygon's extreme vertex and scans the rows within two pixels of it for
        the farthest point where the lip score crosses 0.5 going outwards.
        """
        k = int(np.argmax(poly[:, 0] * side))
        vx, vy = poly[k]
        h, w = score.shape
        best_x, best_y = float(vx), float(vy)
        y0 = int(round(vy))
        xs = int(np.clip(round(vx - side * 6), 0, w - 1))
        xe = int(np.clip(round(vx + side * 5), 0, w - 1))
        lo, hi = min(xs, xe), max(xs, xe)
        if hi - lo < 2:
            return best_x, best_y
        found = None
        for y in range(max(0, y0 - 2), min(h, y0 + 3)):
            row = score[y, lo : hi + 1]
            if side < 0:
                row = row[::-1]
            above = row >= 0.5
            if not above.any():
                continue
            idx = np.nonzero(above)[0]
            i = int(idx[-1])  # last tagged sample going outwards
            if i + 1 >= len(row):
                continue
            a, b = float(row[i]), float(row[i + 1])
            t = (a - 0.5) / (a - b) if a != b else 0.0
            pos = i + t
            xx = (lo + pos) if side > 0 else (hi - pos)
            if found is None or xx * side > found[0] * side:
                found = (xx, float(y))
        if found is not None:
            best_x, best_y = found
        return best_x, best_y

    @staticmethod
    def _refine_vertical(norm: np.ndarray, x: float, y_est: float, direction: int, reach: float = 3.0) -> float:
        """Sub-pixel y where the normalised lip value crosses 0.5 on the column through ``x``.

        Searches ``y_est ± reach`` walking outwards (``direction`` −1 up, +1 down) and returns
        the outermost crossing from lip (≥ 0.5) to skin; ``y_est`` if there is none.
        """
        h, w = norm.shape
        ys = y_est + np.arange(-reach, reach + 1e-9, 0.25) * direction
        ys = np.clip(ys, 0, h - 1)
        xs = np.full_like(ys, np.clip(x, 0, w - 1))
        vals = cv2.remap(
            norm, xs.astype(np.float32).reshape(1, -1), ys.astype(np.float32).reshape(1, -1), cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        ).ravel()
        inside = vals >= 0.5
        idx = np.nonzero(inside[:-1] & ~inside[1:])[0]
        if len(idx) == 0:
            return y_est
        i = int(idx[-1])
        a, b = float(vals[i]), float(vals[i + 1])
        t = (a - 0.5) / (a - b) if a != b else 0.5
        return float(ys[i] + t * (ys[i + 1] - ys[i]))

    def find(
        self,
        score_u8: np.ndarray,
        value: np.ndarray | None = None,
        seed: tuple[float, float] | None = None,
        min_area: int = 6,
        max_r: float | None = None,
    ) -> MouthResult | None:
        """Run all steps on a crop of lip scores; None when no lip blob is found.

        ``value`` (float32, crop size) is an optional lip value that is linear in colour
        mixtures (high on lip, low on skin, e.g. a projection of BGR); edges are then placed
        where it crosses half-way between the lip's and the surrounding skin's levels, which
        is exact for anti-aliased or blurred edges. Without it the smoothed score is used.
        """
        blob = self.blob(score_u8, seed, min_area)
        if blob is None:
            return None
        area = int(blob.sum())
        m = cv2.moments(blob.view(np.uint8), binaryImage=True)
        centre = (m["m10"] / m["m00"], m["m01"] / m["m00"])
        ys, xs = np.nonzero(blob)
        if max_r is None:
            max_r = 0.5 * math.hypot(xs.max() - xs.min() + 1, ys.max() - ys.min() + 1) + 3.0
        r0 = self.radial(blob, centre, max_r)
        raw = self.polygon(centre, r0)
        if value is not None:
            lipish = blob & (score_u8 >= 128)
            lo_level = float(np.median(value[~blob])) if (~blob).any() else 0.0
            hi_level = float(np.median(value[lipish])) if lipish.any() else lo_level + 1.0
            span = hi_level - lo_level
            if abs(span) < 1e-6:
                span = 1.0
            norm = (value.astype(np.float32) - np.float32(lo_level)) * np.float32(1.0 / span)
            norm = cv2.GaussianBlur(norm, (3, 3), 0.6)
        else:
            norm = cv2.GaussianBlur(score_u8.astype(np.float32) * (1.0 / 255.0), (5, 5), 0.8)
        r = self.snake(norm, centre, r0)
        poly = self.polygon(centre, r)
        left = self._corner(norm, poly, -1)
        right = self._corner(norm, poly, +1)
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
