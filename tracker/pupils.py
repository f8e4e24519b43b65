"""Pupil finder: colour tags, then correlation with the stored eye picture at the tagged pixels.

Works in an upright crop of the face (see :class:`tracker.calibration.FaceFrame`): the stored
template was cut from the calibration frame in the same upright, scale-normalised frame, so
a plain normalised cross-correlation (``cv2.TM_CCOEFF_NORMED``) compares like with like even
when the head rolls or leans in.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from tracker.colour_model import ColourClassifier


def parabola_offset(a: float, b: float, c: float) -> float:
    """Sub-sample offset (−0.5..0.5) of the extremum of a parabola through (−1,a), (0,b), (1,c)."""
    a, b, c = float(a), float(b), float(c)
    den = a - 2.0 * b + c
    if abs(den) < 1e-12:
        return 0.0
    return min(max(0.5 * (a - c) / den, -0.5), 0.5)


def subpixel_peak(score: np.ndarray, x: int, y: int) -> tuple[float, float]:
    """Refine an integer maximum of a 2-D score map with a separable parabola fit."""
    h, w = score.shape
    dx = parabola_offset(score[y, x - 1], score[y, x], score[y, x + 1]) if 0 < x < w - 1 else 0.0
    dy = parabola_offset(score[y - 1, x], score[y, x], score[y + 1, x]) if 0 < y < h - 1 else 0.0
    return x + dx, y + dy


@dataclass
class PupilResult:
    """One pupil in crop pixels; ``closed`` means the eye picture did not match well enough."""

    x: float
    y: float
    score: float
    closed: bool
    tagged: int
    used_tags: bool


class PupilFinder:
    """Find one pupil near a predicted position.

    ``template`` is the stored grey eye picture (float32, odd sides, pupil at its centre),
    ``classifier`` the pupil colour classifier, ``threshold`` the lowest correlation still
    counted as an open eye, ``near`` the half-size (crop px) of the neighbourhood searched
    when no pixel is tagged.
    """

    def __init__(self, template: np.ndarray, classifier: ColourClassifier, threshold: float = 0.5, near: int = 3):
        t = np.asarray(template, dtype=np.float32)
        if t.ndim != 2 or t.shape[0] % 2 == 0 or t.shape[1] % 2 == 0:
            raise ValueError("eye template must be a 2-D array with odd sides")
        self.template = t
        self.hy, self.hx = t.shape[0] // 2, t.shape[1] // 2
        self.classifier = classifier
        self.threshold = float(threshold)
        self.near = int(near)

    def find(
        self,
        bgr: np.ndarray,
        grey: np.ndarray,
        predicted: tuple[float, float],
        search: tuple[int, int],
        previous: tuple[float, float] | None = None,
    ) -> PupilResult | None:
        """Search ``predicted ± search`` (crop px) in a crop (``bgr`` uint8 and ``grey`` float32).

        Returns None if the search window falls outside the crop. ``previous`` (crop px) is
        where the pupil was last seen: the fallback neighbourhood and the position kept
        when the eye is closed (defaults to ``predicted``).
        """
        h, w = grey.shape
        px, py = int(round(predicted[0])), int(round(predicted[1]))
        sx, sy = search
        x0, x1 = max(px - sx, self.hx), min(px + sx, w - 1 - self.hx)
        y0, y1 = max(py - sy, self.hy), min(py + sy, h - 1 - self.hy)
        if x1 < x0 or y1 < y0:
            return None
        roi = grey[y0 - self.hy : y1 + self.hy + 1, x0 - self.hx : x1 + self.hx + 1]
        score = cv2.matchTemplate(roi, self.template, cv2.TM_CCOEFF_NORMED)  # (y1-y0+1, x1-x0+1)
        tags = self.classifier.prob_u8(bgr[y0 : y1 + 1, x0 : x1 + 1]) >= 128
        n_tagged = int(np.count_nonzero(tags))
        used = n_tagged > 0
        # the neighbourhood of the previous pupil is always a candidate as well: a pupil
        # whose colour the classifier gave up on (claimed by two classes) is still found
        prev = previous if previous is not None else predicted
        qx, qy = int(round(prev[0])) - x0, int(round(prev[1])) - y0
        nb = self.near
        tags[max(qy - nb, 0) : max(qy + nb + 1, 0), max(qx - nb, 0) : max(qx + nb + 1, 0)] = True
        if not tags.any():
            tags[:] = True
        masked = np.where(tags, score, -2.0)
        j, i = divmod(int(masked.argmax()), masked.shape[1])
        best = float(score[j, i])
        fx, fy = subpixel_peak(score, int(i), int(j))
        x, y = fx + x0, fy + y0
        closed = best < self.threshold
        if closed:
            keep = previous if previous is not None else predicted
            x, y = float(keep[0]), float(keep[1])
        return PupilResult(x=float(x), y=float(y), score=best, closed=closed, tagged=n_tagged, used_tags=used)
