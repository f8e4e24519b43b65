"""Layered parts: morph each layer across the drawings, then stack the layers (format 2).

A layered drawing is a stack of pictures, bottom first (an eyeball under the lids, the inside of
a mouth under the lips). Blending whole drawings mixes an opaque lid with the eyeball it covers;
here every layer is warped and blended on its own, with the weights of the frame, and the blended
layers are then laid over each other with "over", so an opaque lid hides what lies under it.

Loading precomputes, per distinct set of control lines, one :class:`PartMorpher` (its α tables):
layers that share the drawing's lines share one set of tables and, per frame, one set of meshes
and meshes. A layer that is the same picture with the same lines in every drawing (an eyeball
that never changes) is kept as it is and never warped. Each frame, a moving layer is only warped
inside the rectangle its content can reach under that frame's meshes (the mesh cells whose corners
sample its content), so a small layer, such as a lower lid, costs little.

Everything is premultiplied RGBA uint8 (see ``morph``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np

from morph.beier_neely import DEFAULT_A, DEFAULT_B, DEFAULT_BORDER, DEFAULT_P, premultiply
from morph.compositor import over_u8
from morph.detail import detail_blend
from morph.mesh import DEFAULT_CELLS, MeshGrid
from morph.polymorph import PartMorpher, _blend3_u8, blend_u8

# Pixels added to each layer's reach: the bilinear footprint, the style jitter (morph.style,
# 1.5 px at full level) and rounding.
_REACH_MARGIN = 4.0


@dataclass
class _Layer:
    name: str
    group: int  # index into LayeredMorpher.groups, or -1 for a static layer
    pm: list[np.ndarray]  # premultiplied image per drawing (one shared array when static)
    boxes: np.ndarray | None = None  # (n, 4) float x0, y0, x1, y1 of each drawing's content, widened for bilinear reads
    full: bool = True  # every drawing's content spans the part: no rectangle to find per frame


class LayeredMorpher:
    """Morphs the layered drawings of one part (``art_sets.model.Drawing`` with ``layers``).

    Same interface as :class:`PartMorpher` (``render``, ``active``, ``size``, ``n``, ``grid``),
    which it uses for each distinct set of control lines.
    """

    def __init__(
        self,
        drawings: Sequence,
        alpha_steps: int = 11,
        cells: int = DEFAULT_CELLS,
        a: float = DEFAULT_A,
        b: float = DEFAULT_B,
        p: float = DEFAULT_P,
        detail_sigma: float = 2.0,
        border: str = DEFAULT_BORDER,
        exact_three_way: bool = False,
    ):
        if not drawings:
            raise ValueError("LayeredMorpher needs at least one drawing")
        names = [ly.name for ly in drawings[0].layers]
        if not names:
            raise ValueError(f"drawing {drawings[0].name!r} has no layers")
        for d in drawings:
            if [ly.name for ly in d.layers] != names:
                raise ValueError(f"every drawing needs the layers {names}; {d.name!r} has {[ly.name for ly in d.layers]}")
        self.n = len(drawings)
        self.layer_names = names
        kw = dict(alpha_steps=alpha_steps, cells=cells, a=a, b=b, p=p, detail_sigma=detail_sigma, border=border,
                  exact_three_way=exact_three_way)
        self.groups: list[PartMorpher] = []
        keys: dict[bytes, int] = {}
        self.layers: list[_Layer] = []
        for k, name in enumerate(names):
            images = [np.asarray(d.layers[k].image) for d in drawings]
            lines = [np.asarray(d.layer_lines(k), np.float64).reshape(-1, 4) for d in drawings]
            shape = images[0].shape
            for d, im in zip(drawings, images):
                if im.shape != shape or im.dtype != np.uint8 or im.ndim != 3 or im.shape[2] != 4:
                    raise ValueError(f"layer {name!r} of drawing {d.name!r} is {im.dtype} {im.shape}; expected uint8 {shape}")
            static = all(np.array_equal(im, images[0]) for im in images[1:]) and \
                all(l.shape == lines[0].shape and np.array_equal(l, lines[0]) for l in lines[1:])
            if static:
                pm = premultiply(images[0])
                pm.flags.writeable = False
                h, w = shape[:2]
                self.layers.append(_Layer(name, -1, [pm] * self.n))
                continue
            key = b"".join(l.tobytes() + bytes(str(l.shape), "ascii") for l in lines)
            if key not in keys:
                try:
                    self.groups.append(PartMorpher(images, lines, **kw))
                except ValueError as e:
                    raise ValueError(f"layer {name!r}: {e}") from None
                keys[key] = len(self.groups) - 1
                pms = self.groups[-1].pm
            else:
                pms = []
                for im in images:
                    pm = np.ascontiguousarray(premultiply(im))
                    pm.flags.writeable = False
                    pms.append(pm)
            g = keys[key]
            self.layers.append(_Layer(name, g, pms))
        h, w = self.layers[0].pm[0].shape[:2]
        self.size = (int(w), int(h))
        self.exact_three_way = bool(exact_three_way)
        self.detail_sigma = float(detail_sigma)
        self.grid = self.groups[0].grid if self.groups else MeshGrid(self.size, cells)
        self._spans = self.grid.cell_spans()
        for ly in self.layers:
            if ly.group >= 0:
                self._content_boxes(ly)
        # each drawing stacked: what a frame showing one drawing alone returns (``pm`` as in PartMorpher)
        self.pm = [self._stack([ly.pm[i] for ly in self.layers]) for i in range(self.n)]
        for s in self.pm:
            s.flags.writeable = False
        self._scratch = np.empty(5 * h * w * 4, np.uint8)  # 3 warped images, a pair sum, the blend: of the rectangle's size
        self._inv = np.empty((h, w, 4), np.uint8)  # scratch for over_u8 (its prefix, reshaped, for a rectangle)

    # --- load time -------------------------------------------------------------------------
    def _content_boxes(self, ly: _Layer) -> None:
        """Each drawing's bounding box of non-transparent pixels, one pixel wider (bilinear reads)."""
        w, h = self.size
        boxes = np.full((self.n, 4), (np.inf, np.inf, -np.inf, -np.inf))
        for i, pm in enumerate(ly.pm):
            ys, xs = np.nonzero(pm[:, :, 3])
            if len(xs):
                boxes[i] = (xs.min() - 1.0, ys.min() - 1.0, xs.max() + 1.0, ys.max() + 1.0)
        ly.boxes = boxes
        ly.full = bool(np.all(boxes[:, :2] <= -1.0) and np.all(boxes[:, 2] >= w) and np.all(boxes[:, 3] >= h))

    def _frame_rect(self, ly: _Layer, planes: np.ndarray, act) -> tuple[int, int, int, int] | None:
        """The pixels ``(x0, y0, x1, y1)`` of the part where ``ly`` can be non-transparent this
        frame, or None: the mesh cells some of whose corners, for some active drawing, sample
        inside that drawing's content box (a pixel's source is a convex mix of its cell's corners)."""
        w, h = self.size
        if ly.full:
            return 0, 0, w, h
        k = len(act)
        b = ly.boxes[[ia for ia, _ in act]]
        # a cell can sample a box if one of its corners lies beyond each of the box's sides
        inside = np.empty((4, k) + planes.shape[2:], bool)
        np.greater_equal(planes[:k, 0], b[:, 0, None, None], out=inside[0])
        np.less_equal(planes[:k, 0], b[:, 2, None, None], out=inside[1])
        np.greater_equal(planes[:k, 1], b[:, 1, None, None], out=inside[2])
        np.less_equal(planes[:k, 1], b[:, 3, None, None], out=inside[3])
        corner = inside[..., :-1, :-1] | inside[..., 1:, :-1] | inside[..., :-1, 1:] | inside[..., 1:, 1:]  # (4, k, c, c)
        hit = corner.all(axis=0).any(axis=0)
        rows = np.nonzero(hit.any(axis=1))[0]
        if not len(rows):
            return None
        cols = np.nonzero(hit.any(axis=0))[0]
        xs, ys = self._spans
        return int(xs[cols[0], 0]), int(ys[rows[0], 0]), int(xs[cols[-1], 1]), int(ys[rows[-1], 1])

    @staticmethod
    def _stack(images: Sequence[np.ndarray]) -> np.ndarray:
        """Premultiplied layers bottom first, each laid over the ones below (a new array)."""
        acc = np.array(images[0])
        inv = np.empty_like(acc)
        for img in images[1:]:
            over_u8(img, acc, acc, inv)
        return acc

    # --- per frame -------------------------------------------------------------------------
    def active(self, indices: Sequence[int], weights: Sequence[float]) -> list[tuple[int, float]]:
        """See :meth:`PartMorpher.active`."""
        return (self.groups[0] if self.groups else _Plain(self.n)).active(indices, weights)

    def render(
        self,
        indices: Sequence[int],
        weights: Sequence[float],
        detail: bool = False,
        jitter: np.ndarray | None = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """The morphed, stacked part: premultiplied RGBA uint8 of the part size (a new array, or
        ``out``). Arguments as in :meth:`PartMorpher.render`; one frame at a time per instance."""
        act = self.active(indices, weights)
        if len(act) == 1 and jitter is None:
            if out is None:
                return self.pm[act[0][0]].copy()
            np.copyto(out, self.pm[act[0][0]])
            return out
        if out is None:
            out = np.empty_like(self.pm[0])
        planes_of: dict[int, np.ndarray] = {}
        wts = [wa for _, wa in act]
        w, h = self.size
        for k, ly in enumerate(self.layers):
            if ly.group < 0:
                if k == 0:
                    np.copyto(out, ly.pm[0])
                else:
                    over_u8(ly.pm[0], out, out, self._inv)
                continue
            m = self.groups[ly.group]
            if ly.group not in planes_of:
                planes = m._mesh_planes(act)
                if jitter is not None:
                    planes += np.moveaxis(np.asarray(jitter, dtype=np.float32), -1, 0)
                planes_of[ly.group] = planes
            rect = self._frame_rect(ly, planes_of[ly.group], act)
            if k == 0 and rect != (0, 0, w, h):
                out[...] = 0
            if rect is None:
                continue
            x0, y0, x1, y1 = rect
            if rect == (0, 0, w, h):
                mx, my = m.grid.upsample_planes(planes_of[ly.group], reuse=True)
            else:
                mx, my = m.grid.upsample_rect(planes_of[ly.group], rect)
            n_px = (y1 - y0) * (x1 - x0) * 4
            bufs = [self._scratch[j * n_px:(j + 1) * n_px].reshape(y1 - y0, x1 - x0, 4) for j in range(5)]
            warped = [
                cv2.remap(ly.pm[ia], mx[j], my[j], dst=bufs[j], interpolation=cv2.INTER_LINEAR,
                          borderMode=m.border, borderValue=(0, 0, 0, 0))
                for j, (ia, _) in enumerate(act)
            ]
            if detail and len(act) > 1:
                blended = detail_blend(warped, wts, sigma=self.detail_sigma, plain=blend_u8(warped, wts))
            elif len(act) == 3:
                blended = _blend3_u8(warped, wts, out=bufs[4], scratch=bufs[3])
            else:
                blended = blend_u8(warped, wts, out=bufs[4])
            region = out[y0:y1, x0:x1]
            if k == 0:
                region[...] = blended
            else:
                over_u8(blended, region, region, self._inv.reshape(-1)[:n_px].reshape(y1 - y0, x1 - x0, 4))
        return out


class _Plain:
    """``PartMorpher.active`` for a part whose layers are all static (no morpher to borrow)."""

    def __init__(self, n: int):
        self.n = n

    active = PartMorpher.active
