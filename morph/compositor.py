"""Assemble a frame: parts in their boxes, the head over them, shimmer, head tilt (Buck et al. §3.2).

Everything is premultiplied RGBA uint8 (see ``morph``). Each head has a precomputed premultiplied
canvas; per frame only the part boxes are rewritten with ``head + parts·(1 − α_head)``, so the
soft alpha of the head's holes feathers the parts in. The whole character is
then rotated about the art set's pivot and translated with ``cv2.warpAffine`` (bilinear), computed
only where content can land: the output rows are cut into bands of ``band_rows``, and each band
warps just the columns between the leftmost and rightmost moved point of the content's outline
(precomputed once: heads' α > 0 ∪ part boxes) near its rows, plus the bilinear reach; the rest
stays zero. That is about the content's area instead of the moved bounding box. A sub-rectangle
equals the same pixels of a full-canvas warp except where OpenCV's fixed-point sampling grid,
anchored at the sub-rectangle's origin, rounds a sample to the neighbouring 1/32 px: at hard edges
a few levels, mostly none.

An optional *body* (neck, shoulders, collar: a canvas-sized image) is drawn under the moved
head. It follows the head's translation only by a fraction and rolls by a fraction of the head's
roll (about its own pivot), so a tilt turns the head on a body that stays; where the body meets
the canvas edge it is continued by its mirror image there, so moving it never opens a gap (and
stripes or paper texture do not smear into streaks, as repeating the edge pixels would).
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import cv2
import numpy as np

from morph.beier_neely import premultiply

Box = tuple[int, int, int, int]


def over_u8(top: np.ndarray, under: np.ndarray, out: np.ndarray, inv: np.ndarray | None = None) -> np.ndarray:
    """Premultiplied ``top`` over ``under`` (uint8, same shape) into ``out``: ``top + under·(1 − α_top)``.

    ``inv`` is an optional C-contiguous scratch of the same shape (OpenCV writes a strided view ten
    times slower). Colour stays <= alpha (both terms do)."""
    a = np.ascontiguousarray(top[:, :, 3])
    if inv is not None and not inv.flags.c_contiguous:
        inv = None
    inv = cv2.merge((a, a, a, a), dst=inv)
    cv2.bitwise_not(inv, dst=inv)  # 255 − α
    inv = cv2.multiply(under, inv, dst=inv, scale=1.0 / 255.0)
    return cv2.add(top, inv, dst=out)


def _rect_intersection(a: Box, b: Box) -> Box | None:
    x0, y0 = max(a[0], b[0]), max(a[1], b[1])
    x1, y1 = min(a[0] + a[2], b[0] + b[2]), min(a[1] + a[3], b[1] + b[3])
    if x1 <= x0 or y1 <= y0:
        return None
    return x0, y0, x1 - x0, y1 - y0


class Compositor:
    """Places parts on a head canvas and moves the character with the performer.

    ``canvas`` is ``(w, h)``; ``pivot`` ``(x, y)`` canvas pixels (the neck, say); ``heads`` are
    straight RGBA images of the canvas size (several = shimmer: the head changes every
    ``shimmer_every`` frames); ``boxes`` maps part names to ``(x, y, w, h)``. The pose
    ``(dx, dy, roll_deg)`` is multiplied by ``gain``: dx, dy in canvas pixels (x right, y down),
    roll in degrees, positive turning the character counter-clockwise on screen (its right side
    up), as the performer's ``roll_deg`` does in the camera image.

    ``keep_in_frame`` softly limits the translation so the head (the content above the pivot, the
    neck) never leaves the canvas by more than ``margin`` pixels (default 0: the bundled heads
    fill most of the canvas, and a cut-off head reads as a bug): small moves pass almost unchanged, large ones approach the limit along a tanh curve.
    Rotation about the pivot is never changed; when a strong roll alone pushes the head out, the
    translation pulls it back. Off by default here (the maths stays plain); the renderer turns it on.

    ``band_rows`` is the height of the output bands the warp is cut into (32 measured fastest
    on 512×512 canvases: fewer warp calls against fewer wasted pixels).

    ``body`` (straight RGBA of the canvas size, or None) is drawn under the head, moved by
    ``body_follow`` × the head's translation and rolled by ``body_roll`` × its roll about
    ``body_pivot`` (default ``pivot``); a body that does not roll moves by whole pixels. With a body the heads hold only the head, so
    ``keep_in_frame`` keeps all of it (not just what lies above the pivot) on the canvas.
    """

    def __init__(
        self,
        canvas: tuple[int, int],
        pivot: tuple[float, float],
        heads: Sequence[np.ndarray],
        boxes: Mapping[str, Sequence[int]],
        gain: float = 1.0,
        shimmer_every: int = 2,
        heads_premultiplied: bool = False,
        keep_in_frame: bool = False,
        margin: float | None = None,
        band_rows: int = 32,
        body: np.ndarray | None = None,
        body_follow: float = 0.0,
        body_roll: float = 0.0,
        body_pivot: tuple[float, float] | None = None,
    ):
        self.w, self.h = int(canvas[0]), int(canvas[1])
        self.pivot = (float(pivot[0]), float(pivot[1]))
        self.gain = float(gain)
        self.shimmer_every = max(1, int(shimmer_every))
        if len(heads) == 0:
            raise ValueError("Compositor needs at least one head image")
        self.heads: list[np.ndarray] = []
        for i, hd in enumerate(heads):
            hd = np.asarray(hd)
            if hd.shape != (self.h, self.w, 4) or hd.dtype != np.uint8:
                raise ValueError(f"head {i} is {hd.dtype} {hd.shape}; expected uint8 {(self.h, self.w, 4)}")
            self.heads.append(np.ascontiguousarray(hd if heads_premultiplied else premultiply(hd)))
        full = (0, 0, self.w, self.h)
        self.boxes: dict[str, Box] = {}
        self._clip: dict[str, tuple[Box, tuple[int, int]]] = {}
        for name, box in boxes.items():
            box = tuple(int(v) for v in box)
            if len(box) != 4 or box[2] <= 0 or box[3] <= 0:
                raise ValueError(f"box of part {name!r} must be (x, y, w, h) with positive size, got {box}")
            self.boxes[name] = box
            inside = _rect_intersection(box, full)
            if inside is not None:
                self._clip[name] = (inside, (inside[0] - box[0], inside[1] - box[1]))
        # 255 − α of each head inside each box, 4 channels, for one cv2.multiply per part.
        self._inv_alpha = [
            {name: np.ascontiguousarray(np.repeat(255 - hd[y:y + bh, x:x + bw, 3:4], 4, axis=2))
             for name, ((x, y, bw, bh), _) in self._clip.items()}
            for hd in self.heads
        ]
        self._set_bands(band_rows)
        self.keep_in_frame = bool(keep_in_frame)
        self.margin = 0.0 if margin is None else float(margin)
        self._set_body(body, body_follow, body_roll, body_pivot)
        self._head_hull = self._content_hull(above_pivot=self.body is None)
        self._head_hull_xy = (self._head_hull[:, 0].copy(), self._head_hull[:, 1].copy())
        # One flat canvas: outside the boxes it equals the current head, so a frame rewrites
        # only the boxes, and the whole canvas when the shimmer changes the head. (One buffer
        # per head, rewritten only in the boxes, measured 1–2 % slower a frame: more memory for
        # the warp to read from farther caches.)
        self._flat = self.heads[0].copy()
        self._flat_head = 0
        self._overlaps = self._any_overlap()

    def _set_body(self, body, follow: float, roll: float, pivot) -> None:
        """Premultiply the body; find its content box and which canvas edges it runs off."""
        self.body = None
        self.body_follow, self.body_roll = float(follow), float(roll)
        self.body_pivot = self.pivot if pivot is None else (float(pivot[0]), float(pivot[1]))
        if body is None:
            return
        body = np.asarray(body)
        if body.shape != (self.h, self.w, 4) or body.dtype != np.uint8:
            raise ValueError(f"body is {body.dtype} {body.shape}; expected uint8 {(self.h, self.w, 4)}")
        self.body = np.ascontiguousarray(premultiply(body))
        pts = cv2.findNonZero((self.body[:, :, 3] > 0).astype(np.uint8))
        if pts is None:
            self.body = None
            return
        x, y, bw, bh = cv2.boundingRect(pts)
        self._body_box = (x, y, x + bw, y + bh)
        self._body_edges = (x == 0, y == 0, x + bw == self.w, y + bh == self.h)  # left, top, right, bottom
        self._body_buf = np.empty((self.h, self.w, 4), np.uint8)
        self._body_inv = np.empty(self.h * self.w * 4, np.uint8)  # scratch for over_u8, reshaped to each rectangle
        # A body that does not roll moves by whole pixels: a slice of the body mirrored out to
        # _BODY_PAD on every side (what the bilinear warp's mirrored border would give), no warp.
        self._body_pad = None
        if self.body_roll == 0.0:
            self._body_pad = np.pad(self.body, ((_BODY_PAD, _BODY_PAD), (_BODY_PAD, _BODY_PAD), (0, 0)), mode="reflect")

    def _content_hull(self, above_pivot: bool = False) -> np.ndarray:
        """Convex hull ``(k, 2)`` of every pixel that can be non-transparent (heads ∪ boxes).

        Pixel corners are used (a pixel at x covers x−0.5..x+0.5) so the hull encloses the
        pixels' area (``keep_in_frame`` keeps it on the canvas). ``above_pivot``:
        only the rows down to the pivot (the head without neck and shoulders), or everything
        when nothing lies above it.
        """
        alpha = self._content_mask()
        if above_pivot:
            cut = int(math.floor(self.pivot[1])) + 1
            if 0 < cut < self.h and alpha[:cut].any():
                alpha[cut:] = 0
        pts = cv2.findNonZero(alpha)
        if pts is None:
            return np.zeros((0, 2))
        hull = cv2.convexHull(pts).reshape(-1, 2).astype(np.float64)
        corners = (hull[:, None, :] + np.array([[-0.5, -0.5], [0.5, -0.5], [-0.5, 0.5], [0.5, 0.5]])).reshape(-1, 2)
        return cv2.convexHull(corners.astype(np.float32)).reshape(-1, 2).astype(np.float64)

    def _content_mask(self) -> np.ndarray:
        """uint8 ``(h, w)``: 1 where some head has α > 0 or a part box lies, else 0."""
        alpha = np.zeros((self.h, self.w), np.uint8)
        for hd in self.heads:
            alpha |= (hd[:, :, 3] > 0).astype(np.uint8)
        for (x, y, bw, bh), _ in self._clip.values():
            alpha[y:y + bh, x:x + bw] = 1
        return alpha

    def _set_bands(self, band_rows: int) -> None:
        """Precompute the banded warp (see ``_bands``): outline points, their reach, bin arrays.

        ``_outline`` holds each point twice as ``(x, y, 1, 0)`` and ``(x, y, 0, 1)``, so one
        matrix product gives a point's first and, in its copy, last band."""
        pts, gap = self._content_outline(_OUTLINE_STEP)
        self._reach = _REACH + gap
        if not int(band_rows) > 2 * self._reach:  # a point then reaches at most two bands
            raise ValueError(f"band_rows must be more than {2 * self._reach:.1f}, got {band_rows}")
        self.band_rows = int(band_rows)
        self._n_bands = -(-self.h // self.band_rows)
        n = len(pts)
        self._outline = np.zeros((2 * n, 4))
        self._outline[:, :2] = np.vstack([pts, pts])
        self._outline[:n, 2] = 1
        self._outline[n:, 3] = 1
        # m only rotates and moves, so every moved point has |y − ty| ≤ _radius: bounds the
        # band indices of any frame in which something is visible
        self._radius = float(np.hypot(pts[:, 0], pts[:, 1]).max()) if n else 0.0
        self._pad = int(math.ceil((2 * (self._radius + self._reach) + 1) / self.band_rows)) + 1
        span = self._n_bands + 2 * self._pad + 2
        self._lo_init = np.full(span, np.inf)
        self._hi_init = np.full(span, -np.inf)

    def _content_outline(self, step: int) -> tuple[np.ndarray, float]:
        """Every ``step``-th pixel centre along the outer contour of the content, as rows
        ``(x, y)`` (float64 ``(k, 2)``), and the largest distance (px) from any pixel of the
        content's outer edge (a 4-neighbour outside it or the canvas; holes filled) to one of them."""
        mask = self._content_mask()
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        if not contours:
            return np.zeros((0, 2)), 0.0
        filled = np.zeros_like(mask)
        cv2.drawContours(filled, contours, -1, 1, cv2.FILLED)
        filled |= mask
        inner = cv2.erode(filled, cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3)),
                          borderType=cv2.BORDER_CONSTANT, borderValue=0)
        pts = np.concatenate([c.reshape(-1, 2)[::step] for c in contours])
        far = np.full_like(mask, 255)
        far[pts[:, 1], pts[:, 0]] = 0
        dist = cv2.distanceTransform(far, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        gap = float(dist[filled > inner].max())
        return pts.astype(np.float64), gap

    def _any_overlap(self) -> bool:
        rects = [r for r, _ in self._clip.values()]
        return any(_rect_intersection(a, b) for i, a in enumerate(rects) for b in rects[i + 1:])

    @property
    def canvas(self) -> tuple[int, int]:
        return self.w, self.h

    def head_index(self, frame_no: int) -> int:
        return (int(frame_no) // self.shimmer_every) % len(self.heads)

    def matrix(self, pose: Sequence[float]) -> np.ndarray:
        """The 2×3 affine map canvas → output for ``pose`` (after ``gain`` and, if on, the
        keep-in-frame limit)."""
        a, b, tx, ty, dx, dy, _ = self._pose_terms(pose)
        return np.array([[a, b, tx + dx], [-b, a, ty + dy]])

    def body_matrix(self, pose: Sequence[float]) -> np.ndarray:
        """The 2×3 affine map of the body for ``pose``: ``body_follow`` × the head's (limited)
        translation, ``body_roll`` × its roll about ``body_pivot``."""
        *_, dx, dy, roll = self._pose_terms(pose)
        rad = roll * self.body_roll * (math.pi / 180)
        a, b = math.cos(rad), math.sin(rad)
        cx, cy = self.body_pivot
        tx, ty = (1 - a) * cx - b * cy, b * cx + (1 - a) * cy
        return np.array([[a, b, tx + self.body_follow * dx], [-b, a, ty + self.body_follow * dy]])

    def _pose_terms(self, pose: Sequence[float]) -> tuple[float, float, float, float, float, float, float]:
        """``(cos, sin, tx, ty, dx, dy, roll)``: the rotation about the pivot and the translation
        after ``gain`` and the keep-in-frame limit."""
        dx, dy, roll = (float(v) * self.gain for v in pose)
        if not all(math.isfinite(v) for v in (dx, dy, roll)):
            raise ValueError(f"pose must be three finite numbers (dx, dy, roll_deg), got {tuple(pose)}")
        # cv2.getRotationMatrix2D(pivot, roll, 1), written out (same double arithmetic, no call).
        rad = roll * (math.pi / 180)
        a, b = math.cos(rad), math.sin(rad)
        cx, cy = self.pivot
        tx, ty = (1 - a) * cx - b * cy, b * cx + (1 - a) * cy
        if self.keep_in_frame and len(self._head_hull):
            hx, hy = self._head_hull_xy
            px = hx * a + hy * b
            py = hx * -b + hy * a
            dx = _soft_clamp(dx, -self.margin - (px.min() + tx), self.w + self.margin - (px.max() + tx))
            dy = _soft_clamp(dy, -self.margin - (py.min() + ty), self.h + self.margin - (py.max() + ty))
        return a, b, tx, ty, dx, dy, roll

    def flat(self, parts: Mapping[str, np.ndarray], frame_no: int = 0) -> np.ndarray:
        """The untransformed character: parts under the head (an internal buffer, reused)."""
        k = self.head_index(frame_no)
        head = self.heads[k]
        out = self._flat
        if k != self._flat_head:
            np.copyto(out, head)
            self._flat_head = k
        if self._overlaps:
            return self._flat_overlapping(parts, head, out)
        for name, ((x, y, bw, bh), _) in self._clip.items():
            if name not in parts:
                out[y:y + bh, x:x + bw] = head[y:y + bh, x:x + bw]
        for name, part in parts.items():
            if name not in self._clip:
                if name in self.boxes:
                    continue  # box entirely off the canvas
                raise KeyError(f"no box for part {name!r} (boxes: {sorted(self.boxes)})")
            (x, y, bw, bh), (ox, oy) = self._clip[name]
            src = self._part_view(name, part, ox, oy, bw, bh)
            under = cv2.multiply(src, self._inv_alpha[k][name], scale=1.0 / 255.0)
            cv2.add(head[y:y + bh, x:x + bw], under, dst=out[y:y + bh, x:x + bw])
        return out

    def _part_view(self, name: str, part: np.ndarray, ox: int, oy: int, bw: int, bh: int) -> np.ndarray:
        box = self.boxes[name]
        if part.shape[:2] != (box[3], box[2]) or part.ndim != 3 or part.shape[2] != 4:
            raise ValueError(f"part {name!r} is {part.shape}; its box needs {(box[3], box[2], 4)}")
        src = part[oy:oy + bh, ox:ox + bw]
        return src if src.flags.c_contiguous else np.ascontiguousarray(src)

    def _flat_overlapping(self, parts, head, out) -> np.ndarray:
        """General path when boxes overlap: parts layered in order, then the head over them."""
        layer = np.zeros((self.h, self.w, 4), np.uint8)
        for name, part in parts.items():
            if name not in self._clip:
                if name in self.boxes:
                    continue
                raise KeyError(f"no box for part {name!r} (boxes: {sorted(self.boxes)})")
            (x, y, bw, bh), (ox, oy) = self._clip[name]
            src = self._part_view(name, part, ox, oy, bw, bh)
            under = layer[y:y + bh, x:x + bw]
            inv = np.repeat(255 - src[:, :, 3:4], 4, axis=2)
            layer[y:y + bh, x:x + bw] = cv2.add(src, cv2.multiply(under, inv, scale=1.0 / 255.0))
        inv_head = np.repeat(255 - head[:, :, 3:4], 4, axis=2)
        cv2.add(head, cv2.multiply(layer, inv_head, scale=1.0 / 255.0), dst=out)
        return out

    def compose(
        self,
        parts: Mapping[str, np.ndarray],
        pose: Sequence[float] = (0.0, 0.0, 0.0),
        frame_no: int = 0,
    ) -> np.ndarray:
        """The frame: premultiplied RGBA uint8 ``(h, w, 4)`` of the canvas size (a new array).

        ``parts`` maps part names to premultiplied RGBA images of their box size.
        """
        return self.transform(self.flat(parts, frame_no), pose)

    def transform(self, flat: np.ndarray, pose: Sequence[float]) -> np.ndarray:
        """``flat`` (canvas-sized, premultiplied) moved by ``pose`` × gain, as a new array.

        Bilinear ``cv2.warpAffine``, computed only in bands around the moved content.
        """
        if len(pose) != 3:
            raise ValueError(f"pose must be (dx, dy, roll_deg), got {tuple(pose)}")
        m = self.matrix(pose)
        (a, b, tx), (c, d, ty) = m.tolist()
        self._head_bands = None  # where the head can be in this frame: the whole canvas unless warped in bands
        if a == 1.0 and b == 0.0 and c == 0.0 and d == 1.0 and tx.is_integer() and ty.is_integer():
            out = self._shift(flat, int(tx), int(ty))  # what bilinear sampling gives, as a copy
        else:
            out = self._warp_content(flat, m)
        if self.body is not None:
            self._under_body(out, self.body_matrix(pose))
        return out

    def _under_body(self, out: np.ndarray, m: np.ndarray) -> None:
        """Lay the body moved by ``m`` under the head frame ``out`` (in place), only in the
        rectangle the moved body covers (to the canvas edge on the sides where it runs off).

        A body that does not roll is moved by the nearest whole pixels (a slice, no resampling)."""
        if self._body_pad is not None:
            sx = min(max(int(round(m[0, 2])), -_BODY_PAD), _BODY_PAD)
            sy = min(max(int(round(m[1, 2])), -_BODY_PAD), _BODY_PAD)
            x0, y0, x1, y1 = self._body_box
            left, top, right, bottom = self._body_edges
            rx0, ry0 = (0 if left else max(0, x0 + sx)), (0 if top else max(0, y0 + sy))
            rx1, ry1 = (self.w if right else min(self.w, x1 + sx)), (self.h if bottom else min(self.h, y1 + sy))
            if rx1 <= rx0 or ry1 <= ry0:
                return
            p = _BODY_PAD
            self._lay_under(out, self._body_pad[ry0 - sy + p:ry1 - sy + p, rx0 - sx + p:rx1 - sx + p], (rx0, ry0, rx1, ry1))
            return
        x0, y0, x1, y1 = self._body_box
        corners = np.array([[x0 - 0.5, y0 - 0.5, 1], [x1 - 0.5, y0 - 0.5, 1], [x0 - 0.5, y1 - 0.5, 1], [x1 - 0.5, y1 - 0.5, 1]])
        moved = corners @ m.T
        left, top, right, bottom = self._body_edges
        rx0 = 0 if left else max(0, math.floor(moved[:, 0].min() - _REACH))
        ry0 = 0 if top else max(0, math.floor(moved[:, 1].min() - _REACH))
        rx1 = self.w if right else min(self.w, math.ceil(moved[:, 0].max() + _REACH) + 1)
        ry1 = self.h if bottom else min(self.h, math.ceil(moved[:, 1].max() + _REACH) + 1)
        if rx1 <= rx0 or ry1 <= ry0:
            return
        local = m.copy()
        local[0, 2] -= rx0
        local[1, 2] -= ry0
        region = self._body_buf[ry0:ry1, rx0:rx1]
        cv2.warpAffine(self.body, local, (rx1 - rx0, ry1 - ry0), region, cv2.INTER_LINEAR, cv2.BORDER_REFLECT_101)
        self._lay_under(out, region, (rx0, ry0, rx1, ry1))

    def _shift(self, flat: np.ndarray, dx: int, dy: int) -> np.ndarray:
        """``flat`` moved by whole pixels (transparent where nothing moves in), a new array."""
        if dx == 0 and dy == 0:
            return flat.copy()
        out = np.zeros_like(flat)
        w, h = self.w - abs(dx), self.h - abs(dy)
        if w > 0 and h > 0:
            out[max(dy, 0):max(dy, 0) + h, max(dx, 0):max(dx, 0) + w] = \
                flat[max(-dy, 0):max(-dy, 0) + h, max(-dx, 0):max(-dx, 0) + w]
        return out

    def _bands(self, m: np.ndarray) -> list[tuple[int, int, int, int]]:
        """Output rows split into bands of ``band_rows``; per band that can receive content
        under ``m``, ``(y0, y1, x0, x1)``: its rows and the columns to compute.

        An output pixel can be non-zero only if its bilinear source footprint (Chebyshev
        radius 1) touches a content pixel. Going left or right along an output row from such a
        pixel, one leaves that region at a point within √2 of a moved edge pixel centre (half a
        pixel to the content's outline, half to that pixel's centre), so within ``_reach`` of a
        moved outline point: the outline points within ``_reach`` of a band's rows, widened by
        ``_reach``, bound its columns.
        """
        (a, b, tx), (c, d, ty) = m.tolist()
        hb, r, nb, w, h = self.band_rows, self._reach, self._n_bands, self.w, self.h
        if ty - self._radius > h + r or ty + self._radius < -r:
            return []
        # Each outline point twice (``_outline`` column 2 or 3 is 1): once with the first band it
        # reaches, once with the last, as band index + ``_pad`` (so ≥ 0; the cast floors).
        s = 1.0 / hb
        ky = np.dot(self._outline, (c * s, d * s, (ty + 1 - r) * s + self._pad, (ty + r) * s + self._pad))
        k = ky.astype(np.intp)
        x = np.dot(self._outline, (a, b, tx, tx))
        lo = self._lo_init.copy()
        hi = self._hi_init.copy()
        np.minimum.at(lo, k, x)
        np.maximum.at(hi, k, x)
        out = []
        y0 = 0
        for left, right in zip(lo[self._pad:self._pad + nb].tolist(), hi[self._pad:self._pad + nb].tolist()):
            if left <= right:
                x0 = max(0, math.floor(left - r))
                x1 = min(w, math.floor(right + r) + 1)
                if x1 > x0:
                    out.append((y0, min(h, y0 + hb), x0, x1))
            y0 += hb
        return out

    def _warp_content(self, flat: np.ndarray, m: np.ndarray) -> np.ndarray:
        """``cv2.warpAffine`` of ``flat`` by ``m``, computed only on the bands' column ranges
        (each sub-rectangle with the translation moved to its origin); zero elsewhere."""
        out = np.zeros((self.h, self.w, 4), np.uint8)
        local = m.copy()
        tx, ty = m[0, 2], m[1, 2]
        warp, linear, zero_border = cv2.warpAffine, cv2.INTER_LINEAR, cv2.BORDER_CONSTANT
        self._head_bands = bands = self._bands(m)
        for y0, y1, x0, x1 in bands:
            local[0, 2] = tx - x0
            local[1, 2] = ty - y0
            warp(flat, local, (x1 - x0, y1 - y0), out[y0:y1, x0:x1], linear, zero_border)
        return out

    def _inv_scratch(self, shape) -> np.ndarray:
        return self._body_inv[: shape[0] * shape[1] * 4].reshape(shape[0], shape[1], 4)

    def _lay_under(self, out: np.ndarray, body: np.ndarray, rect: tuple[int, int, int, int]) -> None:
        """``out[rect]`` = the head frame over ``body`` (a view of ``rect``'s size): "over" in the one
        rectangle that holds every warp band of the head meeting ``rect``, a plain copy of the body
        around it (where the head's warp left zeros)."""
        rx0, ry0, rx1, ry1 = rect
        hit = [(y0, y1, x0, x1) for y0, y1, x0, x1 in (self._head_bands or [])
               if y1 > ry0 and y0 < ry1 and x1 > rx0 and x0 < rx1]
        if self._head_bands is None:
            hx0, hy0, hx1, hy1 = rect
        elif not hit:
            out[ry0:ry1, rx0:rx1] = body
            return
        else:
            hy0, hy1 = max(ry0, hit[0][0]), min(ry1, hit[-1][1])
            hx0, hx1 = max(rx0, min(h[2] for h in hit)), min(rx1, max(h[3] for h in hit))
        b = lambda y0, y1, x0, x1: body[y0 - ry0:y1 - ry0, x0 - rx0:x1 - rx0]
        out[ry0:hy0, rx0:rx1] = b(ry0, hy0, rx0, rx1)
        out[hy1:ry1, rx0:rx1] = b(hy1, ry1, rx0, rx1)
        out[hy0:hy1, rx0:hx0] = b(hy0, hy1, rx0, hx0)
        out[hy0:hy1, hx1:rx1] = b(hy0, hy1, hx1, rx1)
        head = out[hy0:hy1, hx0:hx1]
        over_u8(head, b(hy0, hy1, hx0, hx1), head, self._inv_scratch(head.shape))


# Output pixels farther than this (px) from every moved content pixel centre stay transparent:
# √2 for the bilinear footprint, plus OpenCV's 1/32-px sampling grid.
_REACH = 1.5
# Every 4th contour pixel: a quarter of the per-frame points for about 3 px more reach.
_OUTLINE_STEP = 4
# Pixels of mirrored body kept on every side for a body that moves by whole pixels: more than it
# follows a head kept in frame (0.3 × a canvas's width is 154 px on a 512 canvas).
_BODY_PAD = 192


def _soft_clamp(x: float, lo: float, hi: float) -> float:
    """``x`` softly limited to ``(lo, hi)``: slope 1 at the rest position ``p`` (0 pulled into the
    range), tanh towards each bound; continuous in ``lo`` and ``hi`` so a limit that moves with
    the roll never makes the head jump."""
    if hi < lo:
        return 0.5 * (lo + hi)
    p = min(max(0.0, lo), hi)
    if x >= p:
        r = hi - p
        return p + r * math.tanh((x - p) / r) if r > 0 else p
    r = p - lo
    return p - r * math.tanh((p - x) / r) if r > 0 else p


def to_straight(pm: np.ndarray) -> np.ndarray:
    """Premultiplied RGBA uint8 -> straight RGBA uint8 (for PNG); transparent pixels become 0."""
    pm = np.asarray(pm)
    a = pm[:, :, 3:4].astype(np.uint32)
    rgb = (pm[:, :, :3].astype(np.uint32) * 255 + a // 2) // np.maximum(a, 1)
    out = np.empty_like(pm)
    out[:, :, :3] = np.minimum(rgb, 255)
    out[:, :, 3:] = pm[:, :, 3:]
    out[pm[:, :, 3] == 0] = 0
    return out


def over_background(pm: np.ndarray, bgr) -> np.ndarray:
    """Premultiplied RGBA over an opaque background -> BGR uint8 (for video or the screen).

    ``bgr`` is a colour ``(b, g, r)`` or a BGR image of the same size.
    """
    pm = np.asarray(pm)
    h, w = pm.shape[:2]
    bg = np.asarray(bgr)
    if bg.ndim == 1:
        if bg.shape[0] != 3:
            raise ValueError(f"background colour must be (b, g, r), got {tuple(bg)}")
        bg = np.broadcast_to(bg.astype(np.uint8), (h, w, 3))
    elif bg.shape != (h, w, 3):
        raise ValueError(f"background image is {bg.shape}; expected {(h, w, 3)}")
    fg = np.ascontiguousarray(pm[:, :, 2::-1])
    inv = np.ascontiguousarray(np.repeat(255 - pm[:, :, 3:4], 3, axis=2))
    return cv2.add(fg, cv2.multiply(np.ascontiguousarray(bg, dtype=np.uint8), inv, scale=1.0 / 255.0))
