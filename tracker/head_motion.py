"""The head as a rigid thing: its frame-to-frame similarity motion from sparse optical flow.

Colour finders look in small regions; when the head moves fast or the face pulls a big
expression, a region placed from the last frame's features slides off. Corners on the face
(eye corners, nostrils, brow ends, hairline, glasses frames, skin texture) move together with
the skull, so tracking a few dozen of them with pyramidal Lucas–Kanade
(``cv2.calcOpticalFlowPyrLK``) and fitting one rotation + uniform scale + translation to their
motion with RANSAC (``cv2.estimateAffinePartial2D``) predicts where the eyes and the mouth
are before any finder looks. Points on the moving mouth or on the eyes' pupils are outvoted.
When under :data:`SCALE_TRUST` of the corners agree (a quick turn, motion blur), the motion's
rotation and shift are kept but not its scale.

Everything runs on a grey copy of the frame scaled so the inter-pupil distance is about
:data:`FLOW_IPD` pixels (cheap and, for the flow, precise enough); positions going in and
coming out are frame pixels.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

FLOW_IPD = 56.0
"""Inter-pupil distance (px) of the scaled grey image the flow runs on."""
MAX_POINTS = 48
RESEED_EVERY = 12
"""Frames between topping up the tracked corners (they drift off features and die)."""
SCALE_TRUST = 0.6
"""Least share of the tracked corners that must agree with a frame's motion for its change of scale
to count (under it, the rotation and the shift about the agreeing corners' middle only): in a quick
turn or a blur most corners are lost or torn, and 12 of 30 once read a head 6 % larger in one
frame, which nothing took back."""
LK_REACH = 40
"""Working px round a tracked corner whose grey values can change where the flow puts it: its
9 × 9 window at the pyramid's third level (four px a step there), that level's smoothing and a
move of twice the window."""
LK_PART = 0.2
"""Share of the image under which the flow's search runs on the tracked corners' part of it alone
(their box and :data:`LK_REACH` round it): the same corners found to within float rounding, for a
fraction of the pyramids' cost; over it, on the whole image."""
_LK = dict(winSize=(9, 9), maxLevel=2, criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.03))


@dataclass
class Motion:
    """One frame's rigid motion: ``matrix`` (2×3, previous frame px → this frame px), the
    number of corners that agree with it (``inliers``) out of ``tracked``."""

    matrix: np.ndarray
    inliers: int
    tracked: int

    @property
    def scale(self) -> float:
        return math.hypot(self.matrix[0, 0], self.matrix[1, 0])

    @property
    def angle(self) -> float:
        """Rotation in radians, positive counter-clockwise on screen (y down)."""
        return math.atan2(-self.matrix[1, 0], self.matrix[0, 0])


def apply(matrix: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Points ``(n, 2)`` moved by a 2×3 affine matrix."""
    p = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    return p @ matrix[:, :2].T + matrix[:, 2]


def similarity_from_pairs(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """The 2×3 similarity taking two points ``src`` exactly onto two points ``dst``."""
    s = np.asarray(src, dtype=np.float64).reshape(2, 2)
    d = np.asarray(dst, dtype=np.float64).reshape(2, 2)
    (sx0, sy0), (sx1, sy1) = s.tolist()
    (dx0, dy0), (dx1, dy1) = d.tolist()
    zs = complex(sx1 - sx0, sy1 - sy0)
    zd = complex(dx1 - dx0, dy1 - dy0)
    if abs(zs) < 1e-9:
        return np.array([[1.0, 0.0, dx0 - sx0], [0.0, 1.0, dy0 - sy0]])
    a = zd / zs
    m = np.array([[a.real, -a.imag, 0.0], [a.imag, a.real, 0.0]])
    m[:, 2] = d[0] - m[:, :2] @ s[0]
    return m


@functools.lru_cache(maxsize=None)
def _disc_offsets(radius: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column offsets ``(1, k)`` of the pixels ``cv2.circle`` fills for a disc of this
    radius round an integer centre."""
    c = np.zeros((2 * radius + 3, 2 * radius + 3), np.uint8)
    cv2.circle(c, (radius + 1, radius + 1), radius, 1, -1)
    ys, xs = np.nonzero(c)
    return (ys - radius - 1)[None, :], (xs - radius - 1)[None, :]


def _polygon(p: np.ndarray | Callable[[], np.ndarray]) -> np.ndarray:
    return p() if callable(p) else p


def compose(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """The 2×3 affine ``outer ∘ inner`` (apply ``inner`` first)."""
    r = outer[:, :2]
    m = np.empty((2, 3))
    m[:, :2] = r @ inner[:, :2]
    m[:, 2] = r @ inner[:, 2] + outer[:, 2]
    return m


class HeadMotion:
    """Sparse optical flow on the face, one rigid motion per frame.

    ``face_polygon(pts)``-style masks are built by the caller: :meth:`seed` takes the face
    region as a polygon in frame px (where corners may be picked) and the inter-pupil
    distance in frame px (to choose the working scale). :meth:`step` returns the motion from
    the previous frame or None when too few corners agree (the head is covered, gone, or
    moved beyond what the pyramid can follow).
    """

    def __init__(self, min_inliers: int = 6):
        self.min_inliers = int(min_inliers)
        self.scale = 1.0
        self._prev: np.ndarray | None = None
        self._pts: np.ndarray | None = None  # (n, 1, 2) float32, scaled px
        self._age = 0
        self._buf: dict[tuple, np.ndarray] = {}
        self._greys: list[np.ndarray | None] = []  # the working-scale grey images :meth:`grey` keeps

    # ------------------------------------------------------------------ images
    def grey(self, frame_bgr: np.ndarray, box: tuple[float, float, float, float] | None = None) -> np.ndarray:
        """The frame in grey at the working scale :attr:`scale` (a power of two: area
        averaging by a whole factor is several times cheaper than by a fraction).

        With ``box`` (x0, y0, x1, y1, frame px) only that part is made anew, in a kept image of the
        frame's size at the working scale whose other pixels hold earlier frames: while the face is
        followed nothing outside it is looked at, and a face at arm's length from a webcam needs a
        fifth to a half of its frame. The part made anew is the pixels the whole frame's copy has
        there, to the bit: the box is widened to whole working pixels and each halving is an
        average of 2 × 2 pixels."""
        h, w = frame_bgr.shape[:2]
        f = 1
        while f * self.scale < 0.999:
            f *= 2
        size = (h // f, w // f)
        # two kept images in turn, never the one the flow holds as the previous frame
        keep = self._greys
        if len(keep) != 2 or keep[0] is None or keep[0].shape != size:
            keep[:] = [None, None]
            box = None
        slot = 1 if keep[0] is self._prev and keep[0] is not None else 0
        if box is None or keep[slot] is None:
            g = _grey_scaled(frame_bgr, f)
            keep[slot] = g
            return g
        out = keep[slot]
        x0, y0, x1, y1 = box
        a, b = max(int(math.floor(x0 / f)), 0), min(int(math.ceil(x1 / f)), size[1])
        c, d = max(int(math.floor(y0 / f)), 0), min(int(math.ceil(y1 / f)), size[0])
        if b > a and d > c:
            out[c:d, a:b] = _grey_scaled(frame_bgr[c * f : d * f, a * f : b * f], f)
        return out

    def points_box(self) -> tuple[float, float, float, float] | None:
        """The part of the frame (x0, y0, x1, y1, frame px) the next :meth:`step` reads round the
        tracked corners: their box and :data:`LK_REACH` working px round it (None: no corners)."""
        if self._pts is None or not len(self._pts):
            return None
        x0, y0, x1, y1 = _bounds(self._pts)
        k = 1.0 / self.scale
        return (x0 - LK_REACH) * k, (y0 - LK_REACH) * k, (x1 + LK_REACH) * k, (y1 + LK_REACH) * k

    def set_scale(self, ipd_px: float, flow_ipd: float = FLOW_IPD) -> None:
        """Choose the working scale for a face with this inter-pupil distance (frame px):
        1, 1/2, 1/4 … so the face's pupils end up between 0.7 and 1.4 × ``flow_ipd`` apart
        (:data:`FLOW_IPD` per frame; more for a motion followed over many frames in one go)."""
        s = 1.0
        while ipd_px * s > 1.4 * flow_ipd and s > 1 / 16:
            s *= 0.5
        if abs(s - self.scale) > 1e-6:
            self.scale = s
            self._prev = None
            self._pts = None

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget the previous frame and every corner."""
        self._prev = None
        self._pts = None
        self._age = 0

    @property
    def active(self) -> bool:
        return self._prev is not None and self._pts is not None and len(self._pts) >= self.min_inliers

    def seed(self, frame_bgr: np.ndarray, face_polygon: np.ndarray, grey: np.ndarray | None = None) -> int:
        """Pick corners inside ``face_polygon`` (frame px) on this frame; returns how many."""
        g = self.grey(frame_bgr) if grey is None else grey
        self._prev = g
        self._pts = self._pick(g, face_polygon, None)
        self._age = 0
        return 0 if self._pts is None else len(self._pts)

    def _pick(self, g: np.ndarray, face_polygon: np.ndarray, keep: np.ndarray | None) -> np.ndarray | None:
        h, w = g.shape
        poly = np.round(np.asarray(face_polygon, dtype=np.float64) * self.scale).astype(np.int32)
        x0, y0 = max(int(poly[:, 0].min()), 0), max(int(poly[:, 1].min()), 0)
        x1, y1 = min(int(poly[:, 0].max()) + 1, w), min(int(poly[:, 1].max()) + 1, h)
        if x1 - x0 < 8 or y1 - y0 < 8:
            return keep
        key = ("mask", y1 - y0, x1 - x0)
        mask = self._buf.get(key)
        if mask is None:
            mask = self._buf[key] = np.empty((y1 - y0, x1 - x0), np.uint8)
        mask[:] = 0
        cv2.fillPoly(mask, [poly - (x0, y0)], 255)
        min_d = max(3.0, 0.09 * FLOW_IPD)
        want = MAX_POINTS
        if keep is not None and len(keep):
            # no new corner next to one still tracked: the pixels cv2.circle fills round each
            # (truncated) corner, all at once
            dy, dx = _disc_offsets(int(min_d))
            ip = keep.reshape(-1, 2).astype(np.int64)
            ys = (ip[:, 1:2] - y0 + dy).ravel()
            xs = (ip[:, 0:1] - x0 + dx).ravel()
            inside = (ys >= 0) & (ys < mask.shape[0]) & (xs >= 0) & (xs < mask.shape[1])
            mask[ys[inside], xs[inside]] = 0
            want = MAX_POINTS - len(keep)
        if want <= 0:
            return keep
        found = cv2.goodFeaturesToTrack(g[y0:y1, x0:x1], want, 0.01, min_d, mask=mask, blockSize=5)
        if found is None:
            return keep
        found = found.astype(np.float32) + np.float32([x0, y0])
        if keep is None or not len(keep):
            return found
        return np.concatenate([keep, found])

    def _limits(self, w: int, h: int) -> np.ndarray:
        """``(w, h)`` as float32 (1, 2), made once per image size: a corner's x and y stay under them."""
        key = ("limits", w, h)
        lim = self._buf.get(key)
        if lim is None:
            lim = self._buf[key] = np.array([[w, h]], np.float32)
        return lim

    def step(self, frame_bgr: np.ndarray, face_polygon: np.ndarray | Callable[[], np.ndarray] | None = None,
             grey: np.ndarray | None = None) -> Motion | None:
        """The rigid motion from the previous frame to this one (frame px), or None.

        ``face_polygon`` (frame px, where the face is now as far as the caller knows; or a
        function that returns it, called only when corners are picked) lets corners be topped
        up every :data:`RESEED_EVERY` frames or when many died. ``grey`` is this frame from
        :meth:`grey` when the caller already made it.
        """
        g = self.grey(frame_bgr) if grey is None else grey
        prev, pts = self._prev, self._pts
        self._prev = g
        if prev is None or pts is None or len(pts) < self.min_inliers or prev.shape != g.shape:
            self._pts = self._pick(g, _polygon(face_polygon), None) if face_polygon is not None else None
            self._age = 0
            return None
        h, w = g.shape
        nxt, st = _search(prev, g, pts)
        if nxt is not None:
            q = nxt.reshape(-1, 2)
            inside = (q >= 0.0) & (q < self._limits(w, h))
            ok = inside[:, 0] & inside[:, 1]
            ok &= st.reshape(-1) != 0
        else:
            ok = st.reshape(-1) != 0
        n_ok = int(np.count_nonzero(ok))
        motion = None
        if n_ok >= self.min_inliers:
            a, b = (pts, nxt) if n_ok == len(ok) else (pts[ok], nxt[ok])
            m, inl = cv2.estimateAffinePartial2D(
                a, b, method=cv2.RANSAC, ransacReprojThreshold=max(0.6, 0.025 * FLOW_IPD), maxIters=200,
                confidence=0.99, refineIters=5,
            )
            if m is not None and inl is not None:
                inl = inl.reshape(-1).astype(bool)
                n_in = int(np.count_nonzero(inl))
                if n_in >= self.min_inliers and n_in >= 0.4 * n_ok:
                    s = self.scale
                    fm = m.astype(np.float64)  # a copy
                    if n_in < SCALE_TRUST * n_ok:
                        _without_scale(fm, a.reshape(-1, 2)[inl])
                    fm[:, 2] /= s  # scaled px → frame px (rotation/scale part is unchanged)
                    motion = Motion(fm, n_in, n_ok)
                    pts = b if n_in == len(inl) else b[inl]
                    pts = pts.reshape(-1, 1, 2)
                else:
                    pts = b.reshape(-1, 1, 2)
            else:
                pts = b.reshape(-1, 1, 2)
        else:
            pts = None
        self._age += 1
        if face_polygon is not None and (pts is None or len(pts) < 0.6 * MAX_POINTS or self._age >= RESEED_EVERY):
            if motion is not None or pts is None:
                pts = self._pick(g, _polygon(face_polygon), pts if motion is not None else None)
                self._age = 0
        self._pts = pts
        return motion


def _bounds(pts: np.ndarray) -> tuple[float, float, float, float]:
    """The box (x0, y0, x1, y1) of corners ``pts`` (n, 1, 2)."""
    q = pts.reshape(-1, 2)
    (x0, y0), (x1, y1) = q.min(axis=0).tolist(), q.max(axis=0).tolist()
    return x0, y0, x1, y1


def _search(prev: np.ndarray, g: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
    """Pyramidal Lucas–Kanade from ``prev`` to ``g`` for corners ``pts`` (working px): where they
    are, and whether each was found. On the corners' part of the two images alone (their box and
    :data:`LK_REACH` round it) where that is under :data:`LK_PART` of them — a face at arm's length
    from a webcam: the pyramids cost by area. The part starts on a multiple of 2^levels, so its
    pyramids sample the whole images' pixels."""
    h, w = g.shape
    x0, y0, x1, y1 = _bounds(pts)
    k = 1 << _LK["maxLevel"]
    a, c = max(int(x0) - LK_REACH, 0) // k * k, max(int(y0) - LK_REACH, 0) // k * k
    b, d = min(int(x1) + LK_REACH + 1, w), min(int(y1) + LK_REACH + 1, h)
    if (b - a) * (d - c) >= LK_PART * w * h:
        nxt, st, _ = cv2.calcOpticalFlowPyrLK(prev, g, pts, None, **_LK)
        return nxt, st
    at = np.array([a, c], np.float32)
    nxt, st, _ = cv2.calcOpticalFlowPyrLK(prev[c:d, a:b], g[c:d, a:b], pts - at, None, **_LK)
    if nxt is not None:
        nxt += at
    return nxt, st


def _grey_scaled(frame_bgr: np.ndarray, f: int) -> np.ndarray:
    """``frame_bgr`` in grey, averaged over ``f`` × ``f`` pixels (``f`` a power of two; a last
    row or column short of a whole block is dropped)."""
    g = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2GRAY)
    while f > 1:
        # one halving at a time: OpenCV's area averaging by exactly 2 is ten times quicker than
        # by 4 in one go (a 1080p frame: 0.05 against 0.5 ms), and two of them average the same
        # 4 × 4 pixels (to within a grey level of rounding)
        h, w = g.shape
        g = cv2.resize(g[: h & ~1, : w & ~1], (w // 2, h // 2), interpolation=cv2.INTER_AREA)
        f //= 2
    return g


def _without_scale(m: np.ndarray, pts: np.ndarray) -> None:
    """Take the scale out of the similarity ``m`` (2×3, in place), keeping its rotation and where
    it takes the middle of ``pts`` (n, 2)."""
    k = math.hypot(m[0, 0], m[1, 0])
    if k <= 1e-9:
        return
    c = pts.mean(axis=0).astype(np.float64)
    to = m[:, :2] @ c + m[:, 2]
    m[:, :2] /= k
    m[:, 2] = to - m[:, :2] @ c
