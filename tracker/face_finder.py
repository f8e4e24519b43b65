"""Finding a known face again after it was lost: a face detector, then where this person's eyes sit.

OpenCV's bundled frontal-face cascade (``cv2.data.haarcascades``) proposes face boxes on a
small grey copy of the frame, scaled so a face of the calibrated size is a few dozen pixels
wide (the detector's cost falls with the image). Each box becomes a guess of both eye
centres from where this performer's eyes sat inside the detector's box on the calibration
frame (:func:`eyes_in_box`); the tracker then checks the guess with the calibrated eye
pictures before it believes it.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import cv2
import numpy as np

DETECT_FACE_PX = 56.0
"""Width (px) a face of the calibrated size has in the image the detector runs on."""
DEFAULT_EYES = ((0.32, 0.395), (0.685, 0.395))
"""Eye centres as fractions of a frontal-face box, for when the calibration frame gave none."""
DETECT_STEP = 1.12
"""Scale step between the sizes the face detector tries."""
FACE_PER_IPD = 2.8
"""A frontal-face box's side, in inter-pupil distances (2.5–3.1 on real faces for the bundled cascade)."""
ANY_SIZE_HEIGHTS = (160, 320)
"""Heights (px) of the copies a search for a face of any size runs on, the next one only when the one
before found none; on each, the copy with its histogram equalised (a dark or dim face) and then, if
that found none, as it is (equalising a frame that is mostly a dark room stretches the room's
greys and flattens the face's). The ``small`` copy of expr_d19 (a man in glasses, 50 px between
the eyes in a 640×480 frame, the rest of it dark): found on 7 of 20 frames with the equalised
160-px copy alone, on all 20 now; no frame of 19 other copies lost (the dark-skinned copy needs the
equalised one: without it, 5 of 20 on one clip)."""


@functools.lru_cache(maxsize=None)
def face_cascade() -> cv2.CascadeClassifier | None:
    """The bundled frontal-face cascade, or None when this OpenCV build has none."""
    base = getattr(getattr(cv2, "data", None), "haarcascades", None)
    if not base:
        return None
    c = cv2.CascadeClassifier(str(Path(base) / "haarcascade_frontalface_alt2.xml"))
    return None if c.empty() else c


def detect_faces(frame_bgr: np.ndarray, ipd_px: float | None, spread: float = 1.8,
                 band: tuple[int, int] | None = None,
                 grey: tuple[np.ndarray, float] | None = None, neighbours: int = 3) -> list[tuple[float, float, float, float]]:
    """Frontal face boxes ``(x, y, w, h)`` in frame px, largest first.

    With ``ipd_px`` (the face's expected inter-pupil distance) the search is limited to faces
    within ``spread``× of that size and runs on a copy scaled to make such a face about
    :data:`DETECT_FACE_PX` wide; without it every size is searched on a 160-px-high copy, then
    on larger ones and unequalised while none is found (:data:`ANY_SIZE_HEIGHTS`); ``neighbours``
    is how many overlapping detections a face needs there (the cascade's ``minNeighbors``).
    ``band`` ``(k, n)`` (with ``ipd_px``) searches only the k-th of n equal parts (in scale) of
    that range of sizes, a little overlapping: n frames in turn cover it all at a third of
    the cost each for n = 3 (a lost face is looked for every frame). ``grey`` ``(image, scale)``
    is the frame in grey already scaled by ``scale`` (the tracker keeps one): the detector's
    copy is made from it when it is at least as large.
    """
    casc = face_cascade()
    if casc is None:
        return []
    h, w = frame_bgr.shape[:2]
    if not ipd_px:
        boxes = []
        for height in ANY_SIZE_HEIGHTS:
            s = min(1.0, height / h)
            for equalize in (True, False):
                boxes = _detect(casc, frame_bgr, s, None, spread, band, grey, equalize, neighbours)
                if boxes:
                    return boxes
            if s >= 1.0:
                break
        return []
    s = min(1.0, DETECT_FACE_PX / max(FACE_PER_IPD * ipd_px, 1.0))
    return _detect(casc, frame_bgr, s, ipd_px, spread, band, grey)


def _detect(casc, frame_bgr: np.ndarray, s: float, ipd_px: float | None, spread: float,
            band: tuple[int, int] | None, grey: tuple[np.ndarray, float] | None,
            equalize: bool = True, neighbours: int = 3) -> list[tuple[float, float, float, float]]:
    """:func:`detect_faces` on a copy of the frame scaled by ``s``, its histogram equalised or not."""
    h, w = frame_bgr.shape[:2]
    size = (max(int(round(w * s)), 24), max(int(round(h * s)), 24))
    if grey is not None and grey[1] >= s:
        g = grey[0] if grey[0].shape[1] == size[0] else cv2.resize(grey[0], size, interpolation=cv2.INTER_AREA)
    else:
        small = cv2.resize(frame_bgr, size, interpolation=cv2.INTER_AREA) if s < 1.0 else frame_bgr
        g = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)
    grey = cv2.equalizeHist(g) if equalize else g
    if ipd_px:
        f = FACE_PER_IPD * ipd_px * s
        a, b = f / spread, f * spread
        if band is not None and band[1] > 1:
            k, n = band[0] % band[1], band[1]
            r = b / a
            a, b = a * r ** (k / n), a * r ** ((k + 1) / n) * DETECT_STEP
        lo, hi = max(int(a), 20), max(int(b), 21)
        boxes = casc.detectMultiScale(grey, DETECT_STEP, 2, minSize=(lo, lo), maxSize=(hi, hi))
    else:
        boxes = casc.detectMultiScale(grey, 1.1, neighbours, minSize=(20, 20))
    out = [(x / s, y / s, bw / s, bh / s) for x, y, bw, bh in (tuple(float(v) for v in b) for b in boxes)]
    return sorted(out, key=lambda b: _rank(b, w, h))


def _rank(box: tuple[float, float, float, float], w: int, h: int) -> tuple[float, float, float, float]:
    """Largest first; between boxes of one size (the cascade's sizes are steps, so ties are common)
    the one nearest the frame's middle, then the upper, then the left one. The cascade's own order
    depends on how its threads happened to finish, so without a full order the same frame could give
    a different face on each run."""
    x, y, bw, bh = box
    return (-bw * bh, math.hypot(x + 0.5 * bw - 0.5 * w, y + 0.5 * bh - 0.5 * h), y, x)


def eyes_in_box(box: tuple[float, float, float, float], rel: tuple[tuple[float, float], tuple[float, float]] = DEFAULT_EYES) -> np.ndarray:
    """Both eye centres ``(2, 2)`` (frame px, image-left first) for a face box."""
    x, y, w, h = box
    return np.array([[x + rel[0][0] * w, y + rel[0][1] * h], [x + rel[1][0] * w, y + rel[1][1] * h]])


def learn_eyes_in_box(frame_bgr: np.ndarray, pupils: np.ndarray) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """Where these pupils sit, as fractions, inside the face box the detector puts round them
    on this frame (None when it finds no box holding both)."""
    p = np.asarray(pupils, dtype=np.float64).reshape(2, 2)
    ipd = float(np.hypot(*(p[1] - p[0])))
    for box in detect_faces(frame_bgr, ipd):
        x, y, w, h = box
        if all(x < px < x + w and y < py < y + h for px, py in p):
            rel = tuple((float((px - x) / w), float((py - y) / h)) for px, py in p)
            if abs(rel[1][0] - rel[0][0] - 1.0 / FACE_PER_IPD) < 0.2:
                return rel  # type: ignore[return-value]
    return None


def box_ipd(box: tuple[float, float, float, float], rel=DEFAULT_EYES) -> float:
    e = eyes_in_box(box, rel)
    return float(math.hypot(*(e[1] - e[0])))


# ---------------------------------------------------------------------------------------------
# is the face still there?

PATCH_IPD = 28.0
"""Inter-pupil distance (px) of the stored face picture used to tell the face from anything else."""
PATCH_RECT = (-1.0, -0.6, 2.0, 1.35)
"""The face picture's extent in inter-pupil distances (x0, y0, w, h): brows, eyes and nose, no mouth."""
_PATCH_PX = tuple(v * PATCH_IPD for v in PATCH_RECT)


def _pupil_floats(pupils) -> list[float]:
    """Both pupils (frame px) as plain floats ``[lx, ly, rx, ry]``; ``pupils`` is a (2, 2) array or
    two (x, y) pairs."""
    return np.asarray(pupils, dtype=np.float64).ravel().tolist()


def _patch_warp(scale: float, pupils: np.ndarray, margin: float) -> tuple[np.ndarray, tuple[int, int], tuple[float, float], tuple[float, float]]:
    """The affine from the scaled grey image to the face picture (grown by ``margin`` px on
    every side), the picture's size, and the picture's x and down axes in frame px per picture px."""
    lx, ly, rx, ry = (v * scale for v in _pupil_floats(pupils))
    ipd = max(math.hypot(rx - lx, ry - ly), 1e-6)
    k = PATCH_IPD / ipd
    c, s = (rx - lx) / ipd, (ry - ly) / ipd  # unit eye line (x right, y down)
    mx, my = 0.5 * (lx + rx), 0.5 * (ly + ry)
    x0, y0, w, h = _PATCH_PX
    # picture px = R·k·(grey px − mid) − origin, R turning the eye line onto +x
    a, b = k * c, k * s
    m = np.array([[a, b, -(a * mx + b * my) - (x0 - margin)], [-b, a, -(a * my - b * mx) - (y0 - margin)]])
    size = (int(round(w)) + 2 * int(margin), int(round(h)) + 2 * int(margin))
    per = 1.0 / (k * scale)
    return m, size, (c * per, s * per), (-s * per, c * per)


LIGHT_SIGMA = 0.35
"""Width (inter-pupil distances) of the local mean a face picture is divided by in :func:`light_free`."""
LIGHT_CHECK = 0.6
"""Correlation of the face pictures as they are under which their light-free versions are
compared too (at or above it, the pictures as they are decide alone)."""
LIGHT_SURE = 0.75
"""Correlation of the light-free pictures at or above which it stands for the face's. Side light
coming up after calibration dropped a real face's correlation from 0.9 to 0.26 while its
light-free one stayed at 0.87-0.95; a hand coming over the face took both down together (its
light-free one 0.4-0.7): a partly covered face must not pass for one under new light."""


def light_free(picture: np.ndarray) -> np.ndarray:
    """A face picture (float32) over its own local mean (a Gaussian :data:`LIGHT_SIGMA` inter-pupil
    distances wide): light that changes smoothly across the face — a lamp or a window to one side,
    coming up or going down after calibration — multiplies the picture by a smooth field, which the
    ratio cancels; the eyes, brows and nose keep their contrast against the skin round them."""
    mean = cv2.GaussianBlur(picture, (0, 0), LIGHT_SIGMA * PATCH_IPD, borderType=cv2.BORDER_REFLECT)
    np.maximum(mean, 1.0, out=mean)
    return cv2.divide(picture, mean)


FACE_CONTRAST = 0.5
"""A picture with less than this share of the face picture's contrast (the spread of its
:func:`light_free` values) matches it the less the flatter it is: light-free, a flat hand or wall
keeps only faint shading, which normalised correlation would blow up to a face's contrast."""


def _flatness(window: np.ndarray, reference_spread: float) -> float:
    """The factor (0..1] a match of ``window`` (light-free) with a light-free reference whose
    values spread ``reference_spread`` (their standard deviation) is scaled by."""
    return min(float(window.std()) / max(FACE_CONTRAST * reference_spread, 1e-6), 1.0)


_FREE_REFERENCE: tuple[np.ndarray, np.ndarray, float] | None = None
"""The last reference given to :func:`_match`, its :func:`light_free` version and that one's spread."""


def _free_reference(reference: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`light_free` of a reference picture and its spread, made once for the reference in use
    (the tracker compares every frame with the same calibrated picture)."""
    global _FREE_REFERENCE
    kept = _FREE_REFERENCE
    if kept is None or kept[0] is not reference:
        free = light_free(reference)
        kept = _FREE_REFERENCE = (reference, free, float(free.std()))
    return kept[1], kept[2]


def _match(window: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, float, tuple[int, int]]:
    """The face picture slid over ``window`` (at least its size): the map of normalised
    correlations, its best value and where (x, y) — of the pictures as they are, or of their
    :func:`light_free` versions when the first is under :data:`LIGHT_CHECK` and the second reaches
    :data:`LIGHT_SURE` and is better (scaled by :func:`_flatness` where it matched)."""
    r = cv2.matchTemplate(window, reference, cv2.TM_CCOEFF_NORMED)
    _, best, _, at = cv2.minMaxLoc(r)
    if best < LIGHT_CHECK:
        free = light_free(window)
        ref, spread = _free_reference(reference)
        r2 = cv2.matchTemplate(free, ref, cv2.TM_CCOEFF_NORMED)
        _, best2, _, (i, j) = cv2.minMaxLoc(r2)
        rh, rw = ref.shape
        best2 *= _flatness(free[j : j + rh, i : i + rw], spread)
        if best2 >= LIGHT_SURE and best2 > best:
            return r2, float(best2), (i, j)
    return r, float(best), at


def face_patch(grey: np.ndarray, scale: float, pupils: np.ndarray) -> np.ndarray:
    """The upright face picture (float32, blurred) for eyes at ``pupils`` (frame px).

    ``grey`` is the frame in grey scaled by ``scale`` (as :class:`tracker.head_motion.HeadMotion`
    keeps it); the picture is cut so the pupils are :data:`PATCH_IPD` px apart.
    """
    m, size, _, _ = _patch_warp(scale, pupils, 0)
    out = cv2.warpAffine(grey, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return cv2.GaussianBlur(out.astype(np.float32), (0, 0), 1.0)


def locate_face(grey: np.ndarray, scale: float, pupils: np.ndarray, reference: np.ndarray, reach: float = 0.15) -> tuple[np.ndarray, float]:
    """Where the face picture best matches near eyes at ``pupils``: the shift (frame px) that
    moves the pupils onto the match, and the match's normalised correlation — of the pictures as
    they are or, when that is under :data:`LIGHT_CHECK` and their :func:`light_free` versions
    match at least :data:`LIGHT_SURE` and better, of those (the light has changed across the face
    since calibration).

    ``reach`` is the search half-width in inter-pupil distances.
    """
    margin = max(int(math.ceil(reach * PATCH_IPD)), 1)
    m, size, ax, ay = _patch_warp(scale, pupils, margin)
    win = cv2.warpAffine(grey, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    if win.shape[0] < reference.shape[0] or win.shape[1] < reference.shape[1]:
        return np.zeros(2), 0.0
    x, y, best = _peak(win, reference)
    du, dv = x - margin, y - margin
    return np.array([du * ax[0] + dv * ay[0], du * ax[1] + dv * ay[1]]), best


def _peak(window: np.ndarray, reference: np.ndarray) -> tuple[float, float, float]:
    """The face picture's best match in ``window`` (grey, at the picture's scale; blurred here as the
    picture was): its top-left corner (x, y, sub-pixel) and the correlation there (:func:`_match`)."""
    win = cv2.GaussianBlur(window.astype(np.float32), (0, 0), 1.0)
    r, best, (i, j) = _match(win, reference)
    h, w = r.shape
    dx = _vertex(r[j, i - 1], r[j, i], r[j, i + 1]) if 0 < i < w - 1 else 0.0
    dy = _vertex(r[j - 1, i], r[j, i], r[j + 1, i]) if 0 < j < h - 1 else 0.0
    return i + dx, j + dy, float(best)


def search_face(grey: np.ndarray, scale: float, ipd_px: float, roll_deg: float,
                reference: np.ndarray) -> tuple[np.ndarray, float] | None:
    """The face picture looked for over the whole frame at one size and roll: the pupils (frame
    px, (2, 2), image-left first) of its best match and the match's correlation (as
    :func:`locate_face` measures it), or None when the frame is smaller than the picture.

    ``grey`` is the frame in grey scaled by ``scale``; ``ipd_px`` (frame px) and ``roll_deg``
    (degrees, positive with the image-right eye higher) are the size and roll the face had when
    last seen. Past the frame's edge the picture meets a flat grey, which matches nothing: a face
    sliding back in is found by the part of its brows, eyes and nose that is in, before a face
    detector, which wants the whole face, sees it."""
    k = PATCH_IPD / max(ipd_px * scale, 1e-6)  # grey px → picture px
    a = math.radians(roll_deg)
    c, s = math.cos(a), -math.sin(a)  # the eye line's direction in the image (x right, y down)
    A = np.array([[k * c, k * s], [-k * s, k * c]])  # turns the eye line onto +x, at the picture's scale
    h, w = grey.shape[:2]
    corners = np.array([[0.0, 0.0], [w, 0.0], [0.0, h], [w, h]]) @ A.T
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    size = (int(math.ceil(hi[0] - lo[0])), int(math.ceil(hi[1] - lo[1])))
    rh, rw = reference.shape[:2]
    if size[0] < rw + 2 or size[1] < rh + 2:
        return None
    m = np.hstack([A, -lo.reshape(2, 1)])
    win = cv2.warpAffine(grey, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                         borderValue=float(np.mean(grey)))
    x, y, best = _peak(win, reference)
    mid = np.array([x - _PATCH_PX[0], y - _PATCH_PX[1]])  # the eyes' middle in the searched picture
    pts = np.array([mid - (0.5 * PATCH_IPD, 0.0), mid + (0.5 * PATCH_IPD, 0.0)])
    return ((pts + lo) @ np.linalg.inv(A).T) / scale, best


def _vertex(a: float, b: float, c: float) -> float:
    den = float(a) - 2.0 * float(b) + float(c)
    if den >= -1e-9:
        return 0.0
    return min(max(0.5 * (float(a) - float(c)) / den, -0.5), 0.5)


def patch_similarity(patch: np.ndarray, reference: np.ndarray) -> float:
    """Normalised correlation (−1..1) of two face pictures of the same size: as they are, or of
    their :func:`light_free` versions where those match well and the pictures themselves do not
    (:data:`LIGHT_CHECK`, :data:`LIGHT_SURE`)."""
    if patch.shape != reference.shape:
        return 0.0
    return _match(patch, reference)[1]


def reference_vector(reference: np.ndarray) -> np.ndarray:
    """The face picture as a flat zero-mean unit vector (for :func:`face_turn`'s correlations)."""
    z = np.asarray(reference, dtype=np.float32).ravel()
    z = z - float(z.mean())
    return z / max(float(np.linalg.norm(z)), 1e-6)


def face_similarity(grey: np.ndarray, scale: float, pupils: np.ndarray, ref: np.ndarray) -> float:
    """Normalised correlation (−1..1) of the face picture at eyes ``pupils`` (frame px) with ``ref``
    (:func:`reference_vector`); ``grey`` is the frame in grey scaled by ``scale``."""
    p = face_patch(grey, scale, pupils).ravel()
    s1, s2 = float(np.add.reduce(p)), float(p @ p)
    return float(ref @ p) / max(math.sqrt(max(s2 - s1 * s1 / p.size, 0.0)), 1e-6)


def face_turn(grey: np.ndarray, scale: float, pupils: np.ndarray, ref: np.ndarray, turn: float) -> float:
    """Which roll of the face picture matches best round eyes at ``pupils`` (frame px): the
    picture is also cut turned by ±``turn`` (radians) about the eyes' middle, and a parabola
    through the three correlations gives the turn (radians, positive turning the image-right eye
    down) that would match best, at most one step either way. The flow's rotation drifts with
    every frame and a face pulled or turned can fool it for good; the calibrated picture does
    not drift, and a face's expressions (brows up, eyes wide, a yawn) are mostly symmetric, so
    they leave its roll alone — not its size: raised brows look like a larger face. ``grey`` is
    the frame in grey scaled by ``scale``; ``ref`` is :func:`reference_vector`."""
    lx, ly, rx, ry = _pupil_floats(pupils)
    mx, my = 0.5 * (lx + rx), 0.5 * (ly + ry)
    z = complex(0.5 * (rx - lx), 0.5 * (ry - ly))
    c0 = face_similarity(grey, scale, ((lx, ly), (rx, ry)), ref)
    cs = []
    for a in (-turn, turn):
        v = z * complex(math.cos(a), math.sin(a))
        cs.append(face_similarity(grey, scale, ((mx - v.real, my - v.imag), (mx + v.real, my + v.imag)), ref))
    lo, hi = cs
    den = lo - 2.0 * c0 + hi
    if den < -1e-9:
        d = min(max(0.5 * (lo - hi) / den, -1.0), 1.0)
    else:  # no peak between the three: a full step towards the better side
        d = 0.0 if lo == hi else math.copysign(1.0, hi - lo)
    return d * turn
