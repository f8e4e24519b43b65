"""Eyebrow finder: a 1-D template match of the stored brow cross-section along the face's up axis.

In the upright face crop "up" is −y, so the cross-section through a pupil is a short strip
of columns above it, averaged across the strip to beat noise. The stored profile was cut
from the calibration frame centred on the brow's middle line; the best normalised
correlation along the search range, refined with a parabola, gives the brow height.
"""

from __future__ import annotations

import cv2
import numpy as np

from tracker.pupils import parabola_offset


def column_profile(grey: np.ndarray, x: float, y0: int, y1: int, half_width: int) -> np.ndarray:
    """Mean grey value of rows ``y0..y1-1`` over columns ``x ± half_width`` (float32, y order).

    The strip's two edge columns are weighted by the sub-pixel position of ``x`` so the
    profile moves smoothly with it. Rows and columns outside the image repeat the border.
    """
    h, w = grey.shape
    xi = int(np.floor(x))
    f = float(x - xi)
    c0, c1 = xi - half_width, xi + half_width + 2  # columns c0..c1-1 get weights
    wts = np.ones(c1 - c0, dtype=np.float32)
    wts[0] = 1.0 - f
    wts[-1] = f
    wts /= wts.sum()
    a, b = max(y0, 0), min(y1, h)
    ca, cb = max(c0, 0), min(c1, w)
    if a >= b or ca >= cb:
        return np.full(max(y1 - y0, 0), float(grey.mean()), dtype=np.float32)
    strip = grey[a:b, ca:cb]
    if ca != c0 or cb != c1:
        strip = np.pad(strip, ((0, 0), (ca - c0, c1 - cb)), mode="edge")
    prof = strip @ wts
    if a != y0 or b != y1:
        prof = np.pad(prof, (a - y0, y1 - b), mode="edge")
    return prof


def brow_centre(profile: np.ndarray, guess: int, radius: int) -> float:
    """Middle line of the dark band nearest ``guess`` in a cross-section (sub-sample index).

    Darkness below the lighter of the band's two surroundings, weighted centroid within
    ``radius`` of the darkest sample near ``guess``.
    """
    n = len(profile)
    a, b = max(guess - radius, 0), min(guess + radius + 1, n)
    seg = profile[a:b]
    k = int(np.argmin(seg)) + a
    lo, hi = max(k - radius, 0), min(k + radius + 1, n)
    win = profile[lo:hi].astype(np.float64)
    bright = min(win[: max(k - lo, 1)].max(), win[max(k - lo, 0) :].max())
    dark = profile[k]
    thr = dark + 0.5 * (bright - dark)
    wgt = np.clip(thr - win, 0.0, None)
    # keep only the connected run of dark samples around k
    run = wgt > 0
    left = k - lo
    while left > 0 and run[left - 1]:
        left -= 1
    right = k - lo
    while right < len(run) - 1 and run[right + 1]:
        right += 1
    wgt[:left] = 0
    wgt[right + 1 :] = 0
    if wgt.sum() <= 0:
        return float(k)
    return float(lo + (wgt * np.arange(len(win))).sum() / wgt.sum())


class BrowFinder:
    """Match ``template`` (float32 profile, brow middle at index ``centre``) above a pupil.

    The search covers heights ``lo..hi`` crop px above the pupil.
    """

    def __init__(self, template: np.ndarray, centre: float, lo: float, hi: float, half_width: int = 2):
        self.template = np.asarray(template, dtype=np.float32).reshape(-1, 1)
        self.centre = float(centre)
        self.lo, self.hi = float(lo), float(hi)
        self.half_width = int(half_width)

    def find(self, grey: np.ndarray, pupil: tuple[float, float]) -> tuple[float, float]:
        """``(height above the pupil in crop px, correlation)`` of the best match."""
        px, py = pupil
        n = len(self.template)
        # rows covering template placements with brow heights lo..hi
        top = int(np.floor(py - self.hi - self.centre)) - 1
        bot = int(np.ceil(py - self.lo - self.centre)) + n + 1
        prof = column_profile(grey, px, top, bot, self.half_width).reshape(-1, 1)
        if len(prof) < n + 2:
            return float("nan"), 0.0
        score = cv2.matchTemplate(prof, self.template, cv2.TM_CCOEFF_NORMED).ravel()
        k = int(np.argmax(score))
        d = parabola_offset(score[k - 1], score[k], score[k + 1]) if 0 < k < len(score) - 1 else 0.0
        brow_y = top + k + d + self.centre
        return float(py - brow_y), float(score[k])
