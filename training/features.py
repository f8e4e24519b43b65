"""Scale-free feature vectors from the ten tracked values.

The expression map works on lengths divided by the performer's calibrated inter-pupil distance
(ipd, pixels) and taken relative to that performer's neutral face, so two performers, or one
performer at two distances from the camera at calibration time, give comparable numbers.

* eyes, k = 4: ``eye_open_l, eye_open_r, brow_l, brow_r``
* mouth, k = 3: ``mouth_width, lip_upper, lip_lower``
* pose, 3: ``mid_x, mid_y`` (in ipd) and ``roll`` (radians), relative to neutral

:meth:`FeatureSpace.normalise` turns the ten values into one 10-vector in these units
``[pose 3 | eyes 4 | mouth 3]``; the filters run on that vector so their settings do not depend
on the camera resolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from tracker.params import PARAM_NAMES, FaceParams

__all__ = [
    "EYE_NAMES",
    "MOUTH_NAMES",
    "EYES",
    "MOUTH",
    "POSE",
    "FeatureSpace",
    "PART_SLICES",
]

EYE_NAMES: tuple[str, ...] = ("eye_open_l", "eye_open_r", "brow_l", "brow_r")
MOUTH_NAMES: tuple[str, ...] = ("mouth_width", "lip_upper", "lip_lower")

POSE = slice(0, 3)
EYES = slice(3, 7)
MOUTH = slice(7, 10)
PART_SLICES: dict[str, slice] = {"eyes": EYES, "mouth": MOUTH}
"""Where each part's features sit in the normalised 10-vector (same positions as PARAM_NAMES)."""

assert PARAM_NAMES[3:7] == EYE_NAMES and PARAM_NAMES[7:10] == MOUTH_NAMES

# Rough human proportion used only when no calibration is known: the mouth of a neutral adult
# face is about 0.8 of the inter-pupil distance wide.
_MOUTH_PER_IPD = 0.8


@dataclass(frozen=True)
class FeatureSpace:
    """The performer's calibration as the features need it: ``ipd`` (pixels) and the neutral
    face's ten values (pixels / degrees)."""

    ipd: float
    neutral: tuple[float, ...]

    def __post_init__(self):
        if not (self.ipd > 0 and math.isfinite(self.ipd)):
            raise ValueError(f"inter-pupil distance must be a positive number, got {self.ipd}")
        if len(self.neutral) != len(PARAM_NAMES):
            raise ValueError(f"neutral face needs {len(PARAM_NAMES)} values, got {len(self.neutral)}")
        n = np.asarray(self.neutral, dtype=np.float64)
        object.__setattr__(self, "_n", n)
        scale = np.full(10, 1.0 / self.ipd)
        scale[2] = math.pi / 180.0  # roll: degrees -> radians
        object.__setattr__(self, "_s", scale)

    # ------------------------------------------------------------------------- constructors
    @classmethod
    def from_calibration(cls, calibration) -> "FeatureSpace":
        """From a ``tracker.calibration.Calibration`` (uses ``.ipd`` and ``.neutral``)."""
        neutral = calibration.neutral
        vals = neutral.values() if isinstance(neutral, FaceParams) else np.asarray(neutral, dtype=np.float64)
        return cls(float(calibration.ipd), tuple(float(v) for v in vals))

    @classmethod
    def from_values(cls, ipd: float, neutral: Sequence[float] | FaceParams) -> "FeatureSpace":
        vals = neutral.values() if isinstance(neutral, FaceParams) else neutral
        return cls(float(ipd), tuple(float(v) for v in vals))

    @classmethod
    def estimate(cls, rows: Sequence[FaceParams] | np.ndarray, first: int = 15) -> "FeatureSpace":
        """Without a calibration: the neutral face is the median of the first ``first`` usable
        frames (a take starts neutral) and the ipd is guessed from the neutral mouth width
        (typical human proportion). Prefer a real calibration."""
        if isinstance(rows, np.ndarray):
            vals = np.asarray(rows, dtype=np.float64).reshape(-1, 10)
        else:
            ok = [r for r in rows if r.status != "lost"] or list(rows)
            vals = np.array([r.values() for r in ok], dtype=np.float64).reshape(-1, 10)
        vals = vals[np.all(np.isfinite(vals), axis=1)]
        if len(vals) == 0:
            raise ValueError("no usable frames to estimate a neutral face from")
        neutral = np.median(vals[:first], axis=0)
        ipd = neutral[7] / _MOUTH_PER_IPD if neutral[7] > 0 else 1.0
        return cls(float(ipd), tuple(float(v) for v in neutral))

    # ---------------------------------------------------------------------------- features
    def normalise(self, values) -> np.ndarray:
        """Ten values (pixels / degrees) -> the scale-free 10-vector ``[pose | eyes | mouth]``
        (lengths in ipd, roll in radians, all relative to neutral). Accepts ``(10,)`` or ``(m, 10)``
        arrays or a :class:`FaceParams`."""
        v = values.values() if isinstance(values, FaceParams) else np.asarray(values, dtype=np.float64)
        return (v - self._n) * self._s

    def denormalise(self, z) -> np.ndarray:
        """Inverse of :meth:`normalise`."""
        return np.asarray(z, dtype=np.float64) / self._s + self._n

    def eyes(self, values) -> np.ndarray:
        """Eye features (k = 4) of one or more frames."""
        return self.normalise(values)[..., EYES]

    def mouth(self, values) -> np.ndarray:
        """Mouth features (k = 3) of one or more frames."""
        return self.normalise(values)[..., MOUTH]

    def part(self, name: str, values) -> np.ndarray:
        """Features of part ``name`` (``"eyes"`` or ``"mouth"``)."""
        return self.normalise(values)[..., PART_SLICES[name]]

    def pose(self, values) -> tuple[float, float, float]:
        """(dx, dy) in ipd and roll in degrees, relative to neutral."""
        z = self.normalise(values)
        return float(z[0]), float(z[1]), float(z[2] * 180.0 / math.pi)

    def to_dict(self) -> dict:
        return {"ipd": self.ipd, "neutral": dict(zip(PARAM_NAMES, self.neutral))}

    @classmethod
    def from_dict(cls, d: dict) -> "FeatureSpace":
        neutral = d["neutral"]
        if isinstance(neutral, dict):
            neutral = [float(neutral[n]) for n in PARAM_NAMES]
        return cls(float(d["ipd"]), tuple(float(v) for v in neutral))
