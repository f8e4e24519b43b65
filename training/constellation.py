"""Is a set of five calibration points shaped like a face?

The five points are the CLICKS.json points (both pupils, both eyebrows, the mouth centre;
``left_*`` = image-left). A face puts them in a fixed constellation: measured in the face's own
frame (``u`` from the left to the right pupil, ``up`` perpendicular to it, towards the brows)
and in units of the inter-pupil distance (ipd), each brow sits 0.2–0.8 ipd above its pupil and
the mouth centre 0.9–1.8 ipd below the pupils' midpoint on the nine real clips of
``../shared/real`` (every frame, a landmark tracker's points). The limits below are about
twice as wide, so a real face — tilted, grinning, brows up — passes, while a detector's
mistake (five points bunched round one eye, pupils swapped, a brow on the hairline, the mouth
on the chin) does not.

:func:`constellation_problems` returns plain sentences for the user, empty when plausible.
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

__all__ = ["LIMITS", "constellation_problems", "face_frame", "lip_contrast"]

LIMITS = {
    "min_ipd_px": 8.0,  # pupils closer than this cannot be tracked at all
    "min_ipd_frac": 0.04,  # ... nor closer than this share of the frame's shorter side
    "max_ipd_frac": 0.75,  # ... nor farther apart than this share of its longer side
    "max_roll_deg": 50.0,  # head tilt
    "brow_up": (0.05, 1.1),  # brow above its pupil, ipd
    "brow_side": 0.75,  # brow beside its pupil (either way), ipd
    "brow_asym": 0.5,  # difference of the two brows' heights, ipd
    "mouth_down": (0.55, 2.4),  # mouth below the pupils' midpoint, ipd
    "mouth_side": 0.6,  # mouth beside that midpoint, ipd
    "lip_contrast": 4.0,  # lips at the mouth point at least this much redder than the face (Cr levels)
}
"""Bounds of a plausible face; lengths are in units of the inter-pupil distance unless named ``_px``."""

Point = Sequence[float]


def face_frame(points: Mapping[str, Point]) -> tuple[float, float, tuple[float, float], tuple[float, float]]:
    """``(ipd px, roll degrees, u, up)`` of the pupils: ``u`` the unit vector from the left
    to the right pupil, ``up`` perpendicular to it pointing up in the image when the head is
    upright; roll is positive when the image-right pupil is higher (DESIGN.md's ``roll_deg``)."""
    lx, ly = map(float, points["left_pupil"])
    rx, ry = map(float, points["right_pupil"])
    dx, dy = rx - lx, ry - ly
    ipd = math.hypot(dx, dy)
    if ipd == 0.0:
        return 0.0, 0.0, (1.0, 0.0), (0.0, -1.0)
    u = (dx / ipd, dy / ipd)
    return ipd, math.degrees(math.atan2(-dy, dx)), u, (u[1], -u[0])


def _cr(bgr: np.ndarray) -> np.ndarray:
    """The Cr (red-difference) channel of BGR pixels, 0..255 (ITU-R BT.601, as OpenCV's YCrCb)."""
    b, g, r = (bgr[..., i].astype(np.float32) for i in range(3))
    return 128.0 + 0.5 * r - 0.4187 * g - 0.0813 * b


def _box(img: np.ndarray, cx: float, cy: float, hw: float, hh: float) -> np.ndarray:
    h, w = img.shape[:2]
    x0, x1 = int(max(0, math.floor(cx - hw))), int(min(w, math.ceil(cx + hw) + 1))
    y0, y1 = int(max(0, math.floor(cy - hh))), int(min(h, math.ceil(cy + hh) + 1))
    return img[y0:y1, x0:x1]


def lip_contrast(frame_bgr: np.ndarray, mouth: Point, ipd: float, centre: Point) -> float:
    """How much redder the reddest pixels round ``mouth`` are than the face round ``centre``.

    The 95th percentile of Cr in a box of 1 × 0.9 ipd on the mouth point, minus the median Cr
    of a box of 2.4 × 2.4 ipd on the face's centre. Lips are redder than the skin round them
    whatever the skin's colour, so a real mouth scores well above zero; a "mouth" on an eye, a
    cheek or the hair scores about zero. NaN when a box falls outside the frame.
    """
    if ipd <= 0:
        return float("nan")
    lips = _box(frame_bgr, float(mouth[0]), float(mouth[1]), 0.5 * ipd, 0.45 * ipd)
    face = _box(frame_bgr, float(centre[0]), float(centre[1]), 1.2 * ipd, 1.2 * ipd)
    if lips.size == 0 or face.size == 0:
        return float("nan")
    return float(np.percentile(_cr(lips), 95) - np.median(_cr(face)))


def _side(side: str) -> str:
    return "image-left" if side == "left" else "image-right"


def constellation_problems(points: Mapping[str, Point], frame_bgr: np.ndarray | None = None,
                           frame_size: tuple[int, int] | None = None) -> list[str]:
    """Why the five ``points`` do not look like a face, as short sentences (empty: plausible).

    With the frame they are on (``frame_bgr``, H×W×3 uint8) or just its ``frame_size``
    ``(width, height)`` in pixels, points outside the frame and a face too small or too large
    for it are reported too; with the frame, also a "mouth" with no lips round it
    (:func:`lip_contrast`). Missing points are not judged (place all five first).
    """
    need = ("left_pupil", "right_pupil", "left_brow", "right_brow", "mouth")
    if any(k not in points for k in need):
        return []
    pts = {k: (float(points[k][0]), float(points[k][1])) for k in need}
    if not all(math.isfinite(v) for p in pts.values() for v in p):
        return ["some points are not numbers"]
    out: list[str] = []
    if frame_bgr is not None:
        frame_size = (frame_bgr.shape[1], frame_bgr.shape[0])
    if frame_size is not None:
        w, h = float(frame_size[0]), float(frame_size[1])
        outside = [k.replace("_", " ") for k, (x, y) in pts.items() if not (0 <= x <= w - 1 and 0 <= y <= h - 1)]
        if outside:
            out.append(f"{', '.join(outside)} outside the frame")
    ipd, roll, u, up = face_frame(pts)
    small = LIMITS["min_ipd_px"]
    if frame_size is not None:
        small = max(small, LIMITS["min_ipd_frac"] * min(frame_size))
    if ipd < small:
        spread = max(math.dist(a, b) for a in pts.values() for b in pts.values())
        out.append(f"the pupils are only {ipd:.0f} px apart and all five points lie within {spread:.0f} px: "
                   "too small for a face — they look bunched round one feature")
        return out
    if frame_size is not None and ipd > LIMITS["max_ipd_frac"] * max(frame_size):
        out.append(f"the pupils are {ipd:.0f} px apart, most of the frame's width")
    if abs(roll) > 180.0 - LIMITS["max_roll_deg"]:
        out.append("the image-left pupil is to the right of the other: left and right look swapped")
        return out
    if abs(roll) > LIMITS["max_roll_deg"]:
        out.append(f"the pupils would put the head at a {abs(roll):.0f}° tilt")
        return out

    def along(p: tuple[float, float], origin: tuple[float, float]) -> tuple[float, float]:
        dx, dy = p[0] - origin[0], p[1] - origin[1]
        return (dx * u[0] + dy * u[1]) / ipd, (dx * up[0] + dy * up[1]) / ipd

    lo, hi = LIMITS["brow_up"]
    heights = []
    for side in ("left", "right"):
        lat, height = along(pts[f"{side}_brow"], pts[f"{side}_pupil"])
        heights.append(height)
        if height < lo:
            out.append(f"the {_side(side)} eyebrow is not above its pupil")
        elif height > hi:
            out.append(f"the {_side(side)} eyebrow is {height:.1f}× the eye distance above its pupil (a brow sits about 0.4×)")
        if abs(lat) > LIMITS["brow_side"]:
            out.append(f"the {_side(side)} eyebrow is far to the side of its pupil")
    if all(lo <= v <= hi for v in heights) and abs(heights[0] - heights[1]) > LIMITS["brow_asym"]:
        out.append("one eyebrow is much higher than the other")
    mid = ((pts["left_pupil"][0] + pts["right_pupil"][0]) / 2, (pts["left_pupil"][1] + pts["right_pupil"][1]) / 2)
    lat, height = along(pts["mouth"], mid)
    lo, hi = LIMITS["mouth_down"]
    if -height < lo:
        out.append("the mouth is not below the eyes" if -height <= 0 else "the mouth is too close under the eyes")
    elif -height > hi:
        out.append(f"the mouth is {-height:.1f}× the eye distance below the eyes (a mouth sits about 1.2×)")
    if abs(lat) > LIMITS["mouth_side"]:
        out.append("the mouth is far to the side of the face's middle")
    if frame_bgr is not None and not out:
        centre = ((mid[0] + pts["mouth"][0]) / 2, (mid[1] + pts["mouth"][1]) / 2)
        red = lip_contrast(frame_bgr, pts["mouth"], ipd, centre)
        if math.isfinite(red) and red < LIMITS["lip_contrast"]:
            out.append("there are no lips round the mouth point (nothing there is redder than the face)")
    return out
