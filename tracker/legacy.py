"""The first tracker's finders behind today's interfaces, for calibrations saved before the
eye and mouth models existed.

Such a calibration holds eye pictures, brow cross-sections, lid colours and a lip colour
classifier, but no :class:`~tracker.eyes.EyeModel` or :class:`~tracker.mouth_model.MouthModel`.
Rather than making the user calibrate again, these adapters run the old finders
(:mod:`tracker.pupils`, :mod:`tracker.lids`, :mod:`tracker.brows`, :mod:`tracker.mouth`) and
answer like :class:`tracker.eyes.EyeFinder` and :class:`tracker.mouth_finder.MouthFinder`, so
the tracker has one frame loop.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from tracker.brows import BrowFinder
from tracker.eyes import EyeObservation, EyeResult
from tracker.lids import LidFinder
from tracker.mouth import MouthFinder as LipBlobFinder
from tracker.mouth_finder import MouthResult
from tracker.pupils import PupilFinder

SEARCH_X, SEARCH_Y = 0.22, 0.12  # pupil search half-window (× work ipd), as the eye finder's
LID_UP, LID_DOWN = 0.26, 0.22
BROW_LO, BROW_HI = 0.55, 1.6


class LegacyEyes:
    """Eye pictures, lid walks and brow profiles of an old calibration, as an eye finder."""

    def __init__(self, cal, work_ipd: float):
        wi = self.wi = float(work_ipd)
        near = max(int(round(0.08 * wi)), 2)
        self.pupils = [PupilFinder(t, cal.pupil, cal.pupil_threshold, near=near) for t in cal.eye_templates]
        self.search = (max(int(round(SEARCH_X * wi)), 3), max(int(round(SEARCH_Y * wi)), 2))
        self.brows = [BrowFinder(p, c, BROW_LO * h, BROW_HI * h)
                      for p, c, h in zip(cal.brow_profiles, cal.brow_centres, cal.brow_heights)]
        self.lids = LidFinder(cal.eye, cal.pupil, LID_UP * wi, LID_DOWN * wi, cal.pupil_radius,
                              white=cal.white_threshold, half_width=max(1, int(round(0.025 * wi))), iris=cal.iris_level)
        self.radius = float(cal.pupil_radius)
        th, tw = cal.eye_templates[0].shape
        sx, sy = self.search
        brow_top = max(BROW_HI * h + (len(p) - c) + 2 for p, c, h in zip(cal.brow_profiles, cal.brow_centres, cal.brow_heights))
        mx = sx + tw // 2 + 2
        top = max(brow_top, sy + th // 2 + 2, LID_UP * wi + 2)
        bottom = max(sy + th // 2 + 2, LID_DOWN * wi + 2)
        self.rect = (int(math.floor(-0.5 * wi - mx)), int(math.floor(-top)), int(math.ceil(wi + 2 * mx)), int(math.ceil(top + bottom)))

    def find(self, crop_bgr: np.ndarray, crop_grey: np.ndarray, eye_centres_crop) -> EyeResult:
        grey = np.asarray(crop_grey, dtype=np.float32)
        eyes = []
        for i, c in enumerate(np.asarray(eye_centres_crop, dtype=np.float64).reshape(2, 2)):
            p = (float(c[0]), float(c[1]))
            r = self.pupils[i].find(crop_bgr, grey, p, self.search, previous=p)
            if r is None:
                eyes.append(EyeObservation(p[0], p[1], 0.0, False, 0.0, 0.0, float("nan"), p, self.radius))
                continue
            at = (r.x, r.y)
            up, down = self.lids.find(crop_bgr, grey, at)
            if r.closed:
                up, down = min(up, 0.04 * self.wi), min(down, 0.04 * self.wi)
            brow, corr = self.brows[i].find(grey, at)
            eyes.append(EyeObservation(r.x, r.y, max(float(r.score), 0.0), not r.closed, up, down, brow, at, self.radius,
                                       iris_match=float(r.score), brow_match=float(corr)))
        return EyeResult((eyes[0], eyes[1]))

    def adapt(self, *args, **kwargs) -> bool:
        return False

    def reset_adaptation(self) -> None:
        pass


class LegacyMouth:
    """The lip-colour blob, radial polygon and snake of an old calibration, as a mouth finder."""

    def __init__(self, cal, work_ipd: float):
        self.cal = cal
        self.finder = LipBlobFinder()
        self.axis = np.asarray(cal.lip_axis, dtype=np.float32).reshape(1, 3)
        self.min_area = max(int(0.12 * cal.mouth_area), 6)

    def find(self, crop_bgr: np.ndarray, predicted_centre_crop) -> MouthResult | None:
        score = self.cal.lip.prob_u8(crop_bgr)
        value = cv2.transform(crop_bgr.astype(np.float32), self.axis)
        seed = (float(predicted_centre_crop[0]), float(predicted_centre_crop[1]))
        r = self.finder.find(score, value=value, seed=seed, min_area=self.min_area, lip_level=1.0)
        w = self.cal.mouth_width
        if r is None or not (0.2 * w <= r.width <= 2.2 * w):
            return None
        return MouthResult(r.left, r.right, r.centre, r.lip_upper, r.lip_lower, r.polygon, r.raw_polygon,
                           cue="lip colour", score=1.0, shape=tuple(r.blob.shape), _blob=r.blob)
