"""Eyelid finder: from the pupil, walk along the face's up axis (and down) to the first lid pixel.

In the upright face crop the walk is a column through the pupil. The calibrated
eye-interior classifier (pupil, iris and white, learned along the pupil line) says where
the eye ends: the first run of pixels it does not claim is the lid (lashes or skin). The
crossing is then placed with sub-pixel precision where the luminance passes halfway
between the last interior sample and the first lid sample (a blurred step edge crosses
its midpoint exactly at the edge); when the two differ too little in luminance (a dark
iris against dark lashes) the classifier's own score is interpolated instead.
"""

from __future__ import annotations

import numpy as np

from tracker.colour_model import ColourClassifier


def _first_run(tags: np.ndarray, run: int) -> int:
    """Index of the first position starting ``run`` consecutive True values, or −1."""
    n = len(tags)
    if n < run:
        return -1
    t = tags.astype(np.int16)
    c = np.convolve(t, np.ones(run, dtype=np.int16), mode="valid")
    hit = np.nonzero(c == run)[0]
    return int(hit[0]) if len(hit) else -1


def _edge(lum: np.ndarray, prob: np.ndarray, k: int, min_contrast: float = 24.0) -> float:
    """Sub-sample edge between samples ``k-1`` (interior) and ``k`` (lid) of a walk."""
    if k == 0:
        return 0.0
    n = len(lum)
    inner = float(lum[max(k - 2, 0) : k].mean())
    outer = float(lum[k : min(k + 2, n)].mean())
    if abs(inner - outer) >= min_contrast:
        half = 0.5 * (inner + outer)
        for j in (k, k + 1, k - 1):  # the crossing may sit one sample either side of k
            if 1 <= j < n:
                a, b = float(lum[j - 1]), float(lum[j])
                if (a - half) * (b - half) <= 0 and a != b:
                    return (j - 1) + (half - a) / (b - a)
    a, b = float(prob[k - 1]), float(prob[k])
    if a > 127.5 >= b and a != b:
        return (k - 1) + (a - 127.5) / (a - b)
    return k - 0.5


class LidFinder:
    """``interior`` scores eye-interior pixels; walks go ``up_max`` crop px up and ``down_max`` down."""

    def __init__(self, interior: ColourClassifier, up_max: float, down_max: float, run: int = 2):
        self.interior = interior
        self.up_max = int(np.ceil(up_max))
        self.down_max = int(np.ceil(down_max))
        self.run = int(run)

    def _walk(self, bgr: np.ndarray, grey: np.ndarray, x: float, y: float, direction: int, length: int) -> float:
        h, w = grey.shape
        xi = int(np.clip(round(x), 0, w - 1))
        x0, x1 = max(xi - 1, 0), min(xi + 2, w)
        start = y
        steps = np.arange(length + 1)
        ys = start + direction * steps
        yi = np.clip(np.rint(ys).astype(np.int32), 0, h - 1)
        cols = bgr[yi, x0:x1]  # (n, k, 3)
        p = self.interior.prob_u8(cols).astype(np.float32).mean(axis=1)
        # luminance sampled at the sub-pixel positions (linear in y) through the same column
        fy = np.clip(ys, 0, h - 1)
        y_lo = np.floor(fy).astype(np.int32)
        y_hi = np.minimum(y_lo + 1, h - 1)
        t = fy - y_lo
        g = grey[:, x0:x1].mean(axis=1)
        lum = g[y_lo] * (1 - t) + g[y_hi] * t
        k = _first_run(p < 128, self.run)
        if k < 0:
            return float(length)
        return _edge(lum, p, k)

    def find(self, bgr: np.ndarray, grey: np.ndarray, pupil: tuple[float, float]) -> tuple[float, float]:
        """``(upper, lower)``: crop px from the pupil to the upper and to the lower lid."""
        up = self._walk(bgr, grey, pupil[0], pupil[1], -1, self.up_max)
        down = self._walk(bgr, grey, pupil[0], pupil[1], +1, self.down_max)
        return up, down
