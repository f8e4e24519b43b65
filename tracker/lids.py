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

from tracker.colour_model import ColourClassifier, lut_index


def _first_run(tags: np.ndarray, run: int) -> int:
    """Index of the first position starting ``run`` (1 or 2) consecutive True values, or −1."""
    if run >= 2:
        tags = tags[:-1] & tags[1:]
    if not len(tags):
        return -1
    k = int(tags.argmax())
    return k if tags[k] else -1


def _edge(lum: np.ndarray, prob: np.ndarray, k: int, min_contrast: float = 24.0) -> float:
    """Sub-sample edge between samples ``k-1`` (interior) and ``k`` (lid) of a walk."""
    if k == 0:
        return 0.0
    n = len(lum)
    inner = 0.5 * (float(lum[max(k - 2, 0)]) + float(lum[k - 1]))
    outer = float(lum[k])
    if abs(inner - outer) >= min_contrast:
        half = 0.5 * (inner + outer)
        for j in (k, k - 1, k + 1):  # blur may put the crossing one sample either side of k
            if 1 <= j < n:
                a, b = float(lum[j - 1]), float(lum[j])
                if (a - half) * (b - half) <= 0 and a != b:
                    return (j - 1) + (half - a) / (b - a)
    a, b = float(prob[k - 1]), float(prob[k])
    if a > 127.5 >= b and a != b:
        return (k - 1) + (a - 127.5) / (a - b)
    return k - 0.5


class LidFinder:
    """Walks up and down from the pupil to the lids.

    ``interior`` scores the eye's inside (iris and white), ``pupil`` the pupil; a walk first
    leaves the pupil (``pupil_radius`` crop px, give or take), then stops at the first run of
    pixels that are not inside. If nothing next to the pupil is inside, the lid cuts the
    pupil and the walk ends where the pupil's colour does. ``white`` is the luminance
    threshold between the eye's white and everything darker (learned at calibration).
    Walks go ``up_max`` crop px up and ``down_max`` down.
    """

    def __init__(
        self, interior: ColourClassifier, pupil: ColourClassifier, up_max: float, down_max: float,
        pupil_radius: float = 3.0, run: int = 1, white: float | None = None, half_width: int = 1,
        iris: float | None = None,
    ):
        self.iris = iris
        self.half_width = int(half_width)
        self.white = white
        self.interior = interior
        self.skip = int(np.ceil(1.7 * pupil_radius)) + 1
        self.pupil = pupil
        self.up_max = int(np.ceil(up_max))
        self.down_max = int(np.ceil(down_max))
        self.run = int(run)

    def find(self, bgr: np.ndarray, grey: np.ndarray, pupil: tuple[float, float]) -> tuple[float, float]:
        """``(upper, lower)``: crop px from the pupil to the upper and to the lower lid.

        One strip of ``2·half_width+1`` columns through the pupil is classified at once; each walk starts
        at the pupil's row. A walk that finds no lid returns its full length.
        """
        h, w = grey.shape
        hw = self.half_width
        xi = min(max(int(round(pupil[0])), hw), w - 1 - hw)
        yi = min(max(int(round(pupil[1])), 0), h - 1)
        y0, y1 = max(yi - self.up_max, 0), min(yi + self.down_max + 1, h)
        strip = bgr[y0:y1, xi - hw : xi + hw + 1]
        inv = np.float32(1.0 / (2 * hw + 1))
        idx = lut_index(strip)
        p = np.add.reduce(self.interior.prob_at(idx), axis=1, dtype=np.float32) * inv
        q = self.pupil.prob_at(idx[:, hw])
        lum = np.add.reduce(grey[y0:y1, xi - hw : xi + hw + 1], axis=1) * inv
        c = yi - y0
        dy = yi - pupil[1]  # sample j of a walk sits j ∓ dy from the pupil
        up = self._walk(p[c::-1], q[c::-1], lum[c::-1]) - dy
        down = self._walk(p[c:], q[c:], lum[c:]) + dy
        return max(up, 0.0), max(down, 0.0)

    def _walk(self, p: np.ndarray, q: np.ndarray, lum: np.ndarray) -> float:
        n = len(p)
        inside = p >= 128
        lim = min(self.skip, n)
        pr = 0  # the pupil's own samples (its colour, within about its radius)
        while pr < lim and q[pr] >= 64:
            pr += 1
        after = inside[pr:lim]
        j = int(after.argmax()) if len(after) else 0
        if not len(after) or not after[j]:
            # no iris or white between the pupil and its rim: the lid crosses the pupil
            # (or the eye is shut) and the walk ends where the pupil's colour does
            return max(pr - 0.5, 0.0)
        s = pr + j  # the walk leaves the pupil into iris or white
        inside[:s] = True
        stop = ~inside
        if self.white is not None and n > 1:
            # a lone doubtful sample right before clear white (the blend of iris and white)
            # is not a lid
            stop[:-1] &= ~(inside[1:] & (lum[1:] >= self.white))
        k = _first_run(stop, self.run)
        if k < 0:
            k = n
        if self.white is not None and k < n:
            # the white next to the lid: the edge is where the luminance drops out of it
            # (dark lashes and a dark iris may share colours, so the colour test alone can
            # run past the edge). Only a white run ending within three samples of the lid
            # counts, so a highlight on the pupil does not.
            white = lum[s:k] >= self.white
            if white.any():
                w_last = s + len(white) - 1 - int(white[::-1].argmax())
                if k - w_last <= 3 and float(lum[w_last + 1]) < self.white:
                    a, b = float(lum[w_last]), float(lum[w_last + 1])
                    return w_last + (a - self.white) / (a - b)
        if k >= n:
            return float(max(n - 1, 0))
        if self.iris is not None:
            # blur makes the classifier notice the lid late: walk back to where the
            # luminance is half-way between the iris's (calibrated) and the lid's
            outer = float(lum[k])
            if abs(outer - self.iris) >= 24.0:
                half = 0.5 * (outer + self.iris)
                sgn = 1.0 if outer > self.iris else -1.0
                for j in range(k, max(s, k - 4), -1):
                    a, b = float(lum[j - 1]), float(lum[j])
                    if sgn * (a - half) < 0 <= sgn * (b - half):
                        return (j - 1) + (half - a) / (b - a)
        pp = np.where(inside, np.maximum(p, 128.0), p)
        return _edge(lum, pp, k)
