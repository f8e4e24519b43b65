"""Automatic start: the five clicks a careful person would make, found by machine.

The result is a :class:`~tracker.clicks.Clicks`, so calibration does not care where it came
from. Steps, each using only what every face has:

1. the face: OpenCV's bundled frontal-face cascade (:func:`tracker.face_finder.detect_faces`);
   the largest face wins;
2. pupils: the detector's box says roughly where the eyes are (about 5 % of the inter-pupil
   distance off on real faces); near there, each iris is the dark disc with the brighter
   white of the eye on both sides (:func:`iris_centre`);
3. brows: the darkest band on the column above each pupil;
4. mouth: the darkest line across the lower face, a little more than one inter-pupil
   distance below the eyes — the gap between closed lips or the inside of an open mouth
   (the nostrils sit higher, the chin's shadow lower).

The cascades ship inside the opencv-contrib-python-headless 4.x wheel
(``cv2.data.haarcascades``); nothing is downloaded.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from tracker.brows import brow_centre
from tracker.clicks import Clicks
from tracker.face_finder import detect_faces, eyes_in_box, face_cascade

IRIS_RADIUS = 0.09
"""Iris radius as a fraction of the inter-pupil distance (about 5.8 mm of 63 mm)."""
BROW_RANGE = (0.2, 0.75)
"""Where brows are looked for above the pupils, in inter-pupil distances."""
MOUTH_RANGE = (0.9, 1.6)
"""Where the mouth's dark line is looked for below the eye line, in inter-pupil distances."""


class AutoInitError(RuntimeError):
    """The detectors found no usable face (one-line message)."""


def iris_centre(grey: np.ndarray, prior: tuple[float, float], ipd: float, reach: tuple[float, float] = (0.15, 0.1)) -> tuple[tuple[float, float], float]:
    """The iris nearest ``prior`` (frame px) and its contrast (grey levels).

    Score of a place: the mean of two small boxes left and right of an iris-sized disc there
    (the white of the eye) minus the mean of the disc — high on an iris, low on brows, lashes
    and shadows, which are dark but have no white beside them. ``reach`` is the search
    half-width across and along the face, in inter-pupil distances.
    """
    r = max(IRIS_RADIUS * ipd, 2.0)
    rx, ry = max(reach[0] * ipd, 1.0), max(reach[1] * ipd, 1.0)
    pad = int(math.ceil(max(rx, ry) + 2.2 * r)) + 2
    h, w = grey.shape
    xi, yi = int(round(prior[0])), int(round(prior[1]))
    x0, x1 = max(xi - pad, 0), min(xi + pad + 1, w)
    y0, y1 = max(yi - pad, 0), min(yi + pad + 1, h)
    if x1 - x0 < 3 or y1 - y0 < 3:
        return (float(prior[0]), float(prior[1])), 0.0
    win = grey[y0:y1, x0:x1].astype(np.float32)
    kd = int(round(1.6 * r)) | 1
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kd, kd)).astype(np.float32)
    disc /= disc.sum()
    bw = max(int(round(0.5 * r)), 1)
    bh = max(int(round(0.8 * r)), 1) | 1
    off = int(round(1.35 * r))
    side = np.zeros((bh, 2 * off + bw), np.float32)
    side[:, :bw] = 1.0
    side[:, -bw:] = 1.0
    side /= side.sum()
    score = cv2.filter2D(win, -1, side, borderType=cv2.BORDER_REPLICATE) - cv2.filter2D(win, -1, disc, borderType=cv2.BORDER_REPLICATE)
    yy, xx = np.mgrid[y0:y1, x0:x1]
    inside = ((xx - prior[0]) / rx) ** 2 + ((yy - prior[1]) / ry) ** 2 <= 1.0
    masked = np.where(inside, score, -np.inf)
    j, i = np.unravel_index(int(np.argmax(masked)), masked.shape)
    return (float(x0 + i), float(y0 + j)), float(score[j, i])


def _strip(img: np.ndarray, origin: np.ndarray, along: np.ndarray, across: np.ndarray, n: int, half: int) -> np.ndarray:
    """Mean grey of ``n`` samples (1 px apart) from ``origin`` along ``along``, each averaged over
    ``±half`` px along ``across``."""
    ts = np.arange(n, dtype=np.float32).reshape(-1, 1)
    offs = np.arange(-half, half + 1, dtype=np.float32).reshape(1, -1)
    mx = (origin[0] + ts * along[0] + offs * across[0]).astype(np.float32)
    my = (origin[1] + ts * along[1] + offs * across[1]).astype(np.float32)
    return cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).mean(axis=1)


def _brow(grey: np.ndarray, pupil: tuple[float, float], ipd: float, up: np.ndarray) -> tuple[float, float]:
    """The middle of the darkest band above a pupil, along ``up``."""
    n = int(round(BROW_RANGE[1] * ipd)) + 2
    side = np.array([-up[1], up[0]])
    prof = _strip(grey, np.asarray(pupil, dtype=np.float64), up, side, n, max(int(0.12 * ipd), 1))
    lo, hi = int(BROW_RANGE[0] * ipd), int(BROW_RANGE[1] * ipd)
    seg = prof[lo:hi]
    if len(seg) < 3:
        raise AutoInitError("the face is too small to find its eyebrows")
    # the upper lid and its lashes are dark too, but lie below the range; keep the centre in it
    d = min(max(brow_centre(prof, lo + int(np.argmin(seg)), max(int(0.05 * ipd), 2)), lo), hi)
    return (float(pupil[0] + d * up[0]), float(pupil[1] + d * up[1]))


def _mouth(grey: np.ndarray, left: np.ndarray, right: np.ndarray) -> tuple[float, float]:
    """The mouth's centre: the darkest line across the face in :data:`MOUTH_RANGE` below the eyes."""
    ipd = math.dist(left, right)
    u = (right - left) / ipd
    down = np.array([-u[1], u[0]])
    mid = 0.5 * (left + right)
    start = mid + MOUTH_RANGE[0] * ipd * down
    n = int(round((MOUTH_RANGE[1] - MOUTH_RANGE[0]) * ipd))
    if n < 3:
        raise AutoInitError("the face is too small to find its mouth")
    prof = _strip(grey, start, down, u, n, max(int(0.2 * ipd), 1))
    prof = cv2.GaussianBlur(prof.reshape(-1, 1), (1, 0), max(0.02 * ipd, 0.5)).ravel()
    k = int(np.argmin(prof))
    return (float(start[0] + k * down[0]), float(start[1] + k * down[1]))


def _face_cascade_check() -> None:
    if face_cascade() is None:
        raise AutoInitError("this OpenCV build ships no Haar cascades (use --init CLICKS.json instead)")


def auto_clicks(frame_bgr: np.ndarray, frame_index: int = 0) -> Clicks:
    """The five clicks for the largest face in ``frame_bgr``; raises :class:`AutoInitError`."""
    if not (isinstance(frame_bgr, np.ndarray) and frame_bgr.ndim == 3 and frame_bgr.shape[2] == 3):
        raise AutoInitError("auto init needs a BGR (H, W, 3) frame")
    _face_cascade_check()
    faces = detect_faces(frame_bgr, None)
    if not faces:
        raise AutoInitError("no face found by the bundled face detector (use --init CLICKS.json instead)")
    grey = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2GRAY).astype(np.float32)
    face = faces[0]
    prior = eyes_in_box(face)
    ipd0 = math.dist(prior[0], prior[1])
    (lp, cl), (rp, cr) = iris_centre(grey, tuple(prior[0]), ipd0), iris_centre(grey, tuple(prior[1]), ipd0)
    left, right = np.array(lp), np.array(rp)
    ipd = math.dist(lp, rp)
    if min(cl, cr) <= 0 or not (0.75 * ipd0 < ipd < 1.3 * ipd0) or abs(right[1] - left[1]) > 0.25 * ipd:
        left, right = prior[0], prior[1]  # no clear irises (shut, dark or glinting eyes): the box's guess
        ipd = ipd0
    up = np.array([(right[1] - left[1]) / ipd, -(right[0] - left[0]) / ipd])
    brows = [_brow(grey, tuple(p), ipd, up) for p in (left, right)]
    mouth = _mouth(grey, left, right)
    d = {
        "frame": int(frame_index),
        "left_pupil": [float(left[0]), float(left[1])],
        "right_pupil": [float(right[0]), float(right[1])],
        "left_brow": list(brows[0]),
        "right_brow": list(brows[1]),
        "mouth": list(mouth),
    }
    return Clicks.from_dict(d, where="auto init")
