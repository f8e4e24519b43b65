"""Automatic start: find the face, eyes and mouth with OpenCV's bundled Haar cascades.

The result is the same five clicks a person would give (:class:`~tracker.clicks.Clicks`),
so calibration does not care where they came from. Steps:

1. faces from the frontal-face cascades (several variants, on the plain and on a
   contrast-equalised grey image); each candidate face is checked by the eye cascade in
   its upper half;
2. pupils: the darkest pupil-sized disc inside each eye box (or where the face box puts the
   eyes when the eye cascade misses one), snapped as in calibration;
3. brows: the darkest band above each pupil;
4. mouth: the smile cascade in the lower third of the face, then the reddest blob there
   (lips are redder than the skin around them, whatever the skin's colour).

The cascades ship inside the opencv-contrib-python-headless 4.x wheel
(``cv2.data.haarcascades``); nothing is downloaded.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import cv2
import numpy as np

from tracker.brows import brow_centre
from tracker.clicks import Clicks


class AutoInitError(RuntimeError):
    """The detectors found no usable face (one-line message)."""


@functools.lru_cache(maxsize=None)
def _cascade(name: str) -> cv2.CascadeClassifier:
    base = getattr(getattr(cv2, "data", None), "haarcascades", None)
    if not base:
        raise AutoInitError("this OpenCV build ships no Haar cascades (use --init CLICKS.json instead)")
    path = Path(base) / name
    c = cv2.CascadeClassifier(str(path))
    if c.empty():
        raise AutoInitError(f"cannot load the cascade {path} (use --init CLICKS.json instead)")
    return c


def _faces(grey: np.ndarray) -> list[tuple[int, int, int, int]]:
    h, w = grey.shape
    min_side = max(24, int(0.08 * min(w, h)))
    eq = cv2.equalizeHist(grey)
    out: list[tuple[int, int, int, int]] = []
    for name in ("haarcascade_frontalface_alt2.xml", "haarcascade_frontalface_default.xml", "haarcascade_frontalface_alt.xml"):
        for img in (grey, eq):
            for r in _cascade(name).detectMultiScale(img, 1.1, 3, minSize=(min_side, min_side)):
                out.append(tuple(int(v) for v in r))
    # merge near-duplicates
    merged: list[tuple[int, int, int, int]] = []
    for r in sorted(out, key=lambda r: -r[2] * r[3]):
        cx, cy = r[0] + r[2] / 2, r[1] + r[3] / 2
        if not any(abs(cx - (m[0] + m[2] / 2)) < 0.3 * m[2] and abs(cy - (m[1] + m[3] / 2)) < 0.3 * m[3] for m in merged):
            merged.append(r)
    return merged


def _dark_disc(grey: np.ndarray, box: tuple[int, int, int, int], radius: float) -> tuple[float, float, float]:
    """Centre of the pupil-like spot in ``box`` (frame px): a dark disc of ``radius`` px with a
    lighter ring around it (so an eyebrow, dark but long, loses to a pupil in its white)."""
    x, y, w, h = box
    H, W = grey.shape
    pad = int(math.ceil(2.5 * radius)) + 1
    x0, y0, x1, y1 = max(x - pad, 0), max(y - pad, 0), min(x + w + pad, W), min(y + h + pad, H)
    win = grey[y0:y1, x0:x1].astype(np.float32)
    k = max(int(round(2 * radius)) | 1, 3)
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)).astype(np.float32)
    kr = max(int(round(4.4 * radius)) | 1, k + 2)
    ring = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kr, kr)).astype(np.float32)
    o = (kr - k) // 2
    ring[o : o + k, o : o + k] -= disc
    ring = np.clip(ring, 0, None)
    dmean = cv2.filter2D(win, -1, disc / disc.sum(), borderType=cv2.BORDER_REPLICATE)
    rmean = cv2.filter2D(win, -1, ring / ring.sum(), borderType=cv2.BORDER_REPLICATE)
    score = rmean - dmean
    # only centres inside the box itself
    inner = np.full_like(score, -np.inf)
    bx0, by0 = max(x, 0) - x0, max(y, 0) - y0
    inner[by0 : by0 + h, bx0 : bx0 + w] = score[by0 : by0 + h, bx0 : bx0 + w]
    j, i = np.unravel_index(int(np.argmax(inner)), inner.shape)
    return float(x0 + i), float(y0 + j), float(dmean[j, i])


def _eyes(grey: np.ndarray, face: tuple[int, int, int, int]) -> tuple[list[tuple[float, float]], int]:
    """Two pupils (image-left first) for a face box and how many the eye cascade confirmed."""
    x, y, w, h = face
    upper = grey[y : y + int(0.6 * h), x : x + w]
    found = _cascade("haarcascade_eye.xml").detectMultiScale(upper, 1.1, 3, minSize=(max(8, w // 10), max(8, w // 10)))
    boxes = {"l": None, "r": None}
    for ex, ey, ew, eh in sorted(found, key=lambda r: -r[2] * r[3]):
        cx = ex + ew / 2
        side = "l" if cx < w / 2 else "r"
        if boxes[side] is None and 0.1 * h < ey + eh / 2 < 0.6 * h:
            boxes[side] = (x + ex, y + ey, ew, eh)
    confirmed = sum(b is not None for b in boxes.values())
    radius = max(0.02 * w, 1.5)
    pupils = []
    for side, fx in (("l", 0.3), ("r", 0.7)):
        b = boxes[side]
        if b is None:  # where a frontal face box usually has its eyes
            b = (int(x + (fx - 0.13) * w), int(y + 0.25 * h), int(0.26 * w), int(0.22 * h))
        else:  # the cascade's box includes the brow; the pupil sits in its lower two thirds
            b = (b[0] + b[2] // 6, b[1] + b[3] // 4, b[2] * 2 // 3, b[3] * 2 // 3)
        px, py, _ = _dark_disc(grey, b, radius)
        pupils.append((px, py))
    return pupils, confirmed


def _ring_contrast(grey: np.ndarray, p: tuple[float, float], r: float) -> float:
    """Median grey of the ring 2r..4r around ``p`` minus the mean inside radius r."""
    H, W = grey.shape
    R = int(math.ceil(4 * r)) + 1
    x0, x1 = max(int(p[0]) - R, 0), min(int(p[0]) + R + 1, W)
    y0, y1 = max(int(p[1]) - R, 0), min(int(p[1]) + R + 1, H)
    win = grey[y0:y1, x0:x1].astype(np.float32)
    yy, xx = np.mgrid[y0:y1, x0:x1]
    d = np.hypot(xx - p[0], yy - p[1])
    inner, ring = win[d <= r], win[(d >= 2 * r) & (d <= 4 * r)]
    if not len(inner) or not len(ring):
        return 0.0
    return float(np.median(ring) - inner.mean())


def _brow(grey: np.ndarray, pupil: tuple[float, float], ipd: float, up: np.ndarray) -> tuple[float, float]:
    """The darkest band's middle above a pupil (searching 0.2–0.75 ipd along ``up``)."""
    # sample the upright profile (rows above the pupil in an upright frame)
    n = int(round(0.8 * ipd))
    ts = np.arange(n, dtype=np.float32)
    xs = (pupil[0] + ts * up[0]).astype(np.float32).reshape(-1, 1)
    ys = (pupil[1] + ts * up[1]).astype(np.float32).reshape(-1, 1)
    offs = np.arange(-2, 3, dtype=np.float32).reshape(1, -1)
    side = np.array([-up[1], up[0]], dtype=np.float32)
    mx = xs + offs * side[0]
    my = ys + offs * side[1]
    prof = cv2.remap(grey.astype(np.float32), mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).mean(axis=1)
    lo, hi = int(0.2 * ipd), int(0.75 * ipd)
    seg = prof[lo:hi]
    if len(seg) < 3:
        raise AutoInitError("the face is too small to find its eyebrows")
    # the profile runs upwards from the pupil: index = distance above it
    d = brow_centre(prof, lo + int(np.argmin(seg)), max(int(0.08 * ipd), 2))
    return (float(pupil[0] + d * up[0]), float(pupil[1] + d * up[1]))


def _mouth(frame: np.ndarray, pupils: list[tuple[float, float]], face: tuple[int, int, int, int]) -> tuple[float, float]:
    """Mouth centre: smile cascade (if it fires) to narrow the area, then the reddest blob."""
    (lx, ly), (rx, ry) = pupils
    ipd = math.hypot(rx - lx, ry - ly)
    ux, uy = (rx - lx) / ipd, (ry - ly) / ipd
    dx, dy = -uy, ux  # face down
    mid = ((lx + rx) / 2, (ly + ry) / 2)
    guess = (mid[0] + 1.0 * ipd * dx, mid[1] + 1.0 * ipd * dy)
    H, W = frame.shape[:2]
    x, y, w, h = face
    lower = cv2.cvtColor(frame[y + h // 2 : y + h, x : x + w], cv2.COLOR_BGR2GRAY)
    smiles = _cascade("haarcascade_smile.xml").detectMultiScale(lower, 1.1, 8, minSize=(max(8, w // 6), max(6, h // 12)))
    if len(smiles):
        sx, sy, sw, sh = max(smiles, key=lambda r: r[2] * r[3])
        c = (x + sx + sw / 2, y + h // 2 + sy + sh / 2)
        if math.hypot(c[0] - guess[0], c[1] - guess[1]) < 0.5 * ipd:
            guess = c
    # redness (YCrCb Cr relative to the surroundings) in a box around the guess
    hw, hh = int(0.55 * ipd), int(0.35 * ipd)
    x0, x1 = max(int(guess[0]) - hw, 0), min(int(guess[0]) + hw + 1, W)
    y0, y1 = max(int(guess[1]) - hh, 0), min(int(guess[1]) + hh + 1, H)
    if x1 - x0 < 4 or y1 - y0 < 4:
        raise AutoInitError("the mouth lies outside the frame")
    cr = cv2.cvtColor(frame[y0:y1, x0:x1], cv2.COLOR_BGR2YCrCb)[..., 1].astype(np.float32)
    cr = cv2.GaussianBlur(cr, (3, 3), 0)
    base = float(np.median(cr))
    top = float(np.percentile(cr, 99))
    if top - base < 4:
        return guess
    mask = (cr > base + 0.5 * (top - base)).astype(np.uint8)
    n, lab, stats, cents = cv2.connectedComponentsWithStats(mask, connectivity=4)
    if n <= 1:
        return guess
    j = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    return (float(x0 + cents[j][0]), float(y0 + cents[j][1]))


def auto_clicks(frame_bgr: np.ndarray, frame_index: int = 0) -> Clicks:
    """The five clicks for the most plausible face in ``frame_bgr``; raises :class:`AutoInitError`."""
    if not (isinstance(frame_bgr, np.ndarray) and frame_bgr.ndim == 3 and frame_bgr.shape[2] == 3):
        raise AutoInitError("auto init needs a BGR (H, W, 3) frame")
    grey = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2GRAY)
    faces = _faces(grey)
    if not faces:
        raise AutoInitError("no face found by the bundled face detectors (use --init CLICKS.json instead)")
    best = None
    for face in faces[:6]:
        pupils, confirmed = _eyes(grey, face)
        (lx, ly), (rx, ry) = pupils
        ipd = math.hypot(rx - lx, ry - ly)
        if not (0.2 * face[2] < ipd < 0.7 * face[2]) or abs(ry - ly) > 0.5 * ipd:
            continue
        # a real pupil is a dark disc with lighter eye and skin around it
        contrast = min(_ring_contrast(grey, p, max(0.045 * ipd, 1.5)) for p in pupils)
        if contrast < 15:
            continue
        key = (confirmed + min(contrast / 40.0, 2.0), face[2] * face[3])
        if best is None or key > best[0]:
            best = (key, face, pupils)
    if best is None:
        raise AutoInitError("a face was detected but no pair of eyes in it (use --init CLICKS.json instead)")
    _, face, pupils = best
    (lx, ly), (rx, ry) = pupils
    ipd = math.hypot(rx - lx, ry - ly)
    up = np.array([(ry - ly) / ipd, -(rx - lx) / ipd])
    brows = [_brow(grey, p, ipd, up) for p in pupils]
    mouth = _mouth(frame_bgr, pupils, face)
    d = {
        "frame": int(frame_index),
        "left_pupil": list(pupils[0]),
        "right_pupil": list(pupils[1]),
        "left_brow": list(brows[0]),
        "right_brow": list(brows[1]),
        "mouth": list(mouth),
    }
    return Clicks.from_dict(d, where="auto init")
