"""Layered parts: morph each layer across the drawings, then stack the layers (format 2).

A layered drawing is a stack of pictures, bottom first (an eyeball under the lids, the inside of
a mouth under the lips). Blending whole drawings mixes an opaque lid with the eyeball it covers;
here every layer is warped and blended on its own, with the weights of the frame, and the blended
layers are then laid over each other with "over", so an opaque lid hides what lies under it.

Loading precomputes, per distinct set of control lines, one :class:`PartMorpher` (its α tables):
layers that share the drawing's lines share one set of tables and, per frame, one set of meshes
and dense maps. A layer that is the same picture with the same lines in every drawing (an eyeball
that never changes) is kept as it is and never warped. Each moving layer is only warped inside
the rectangle its content can reach (its content's bounding box widened by the largest
displacement the tables can give there), so a small layer costs little.

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
    rect: tuple[int, int, int, int]  # (x0, y0, x1, y1) the layer's content can reach, in part pixels
    window: object | None = None  # MeshWindow for ``rect`` when it is smaller than the part, else None
    scratch: list | None = None  # per-frame buffers of the rectangle's size: 3 warped images + 1 pair sum


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
                self.layers.append(_Layer(name, -1, [pm] * self.n, (0, 0, w, h), None))
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
            self.layers.append(_Layer(name, g, pms, (0, 0, shape[1], shape[0]), None))
        h, w = self.layers[0].pm[0].shape[:2]
        self.size = (int(w), int(h))
        self.exact_three_way = bool(exact_three_way)
        self.detail_sigma = float(detail_sigma)
        self.grid = self.groups[0].grid if self.groups else MeshGrid(self.size, cells)
        if not self.exact_three_way:
            self._limit_windows()
        for ly in self.layers:
            x0, y0, x1, y1 = ly.rect
            ly.scratch = [np.empty((y1 - y0, x1 - x0, 4), np.uint8) for _ in range(4)]
        # each drawing stacked: what a frame showing one drawing alone returns (``pm`` as in PartMorpher)
        self.pm = [self._stack([ly.pm[i] for ly in self.layers]) for i in range(self.n)]
        for s in self.pm:
            s.flags.writeable = False
        self._layer_out = [np.zeros((h, w, 4), np.uint8) for _ in self.layers]
        self._inv = np.empty((h, w, 4), np.uint8)

    # --- load time -------------------------------------------------------------------------
    def _limit_windows(self) -> None:
        """Shrink each moving layer's rectangle to where its content can land.

        A frame's mesh of drawing A is ``V + Σ_B D_AB(w_B)`` over at most two other drawings, and
        the dense map interpolates mesh vertices, so an output pixel moves at most twice the largest
        table displacement of the vertices around it (``reach``). An output pixel can only be
        non-transparent if its source, that far away, touches content of some drawing.
        """
        w, h = self.size
        for ly in self.layers:
            if ly.group < 0:
                continue
            m = self.groups[ly.group]
            tab = m.tables  # (n, n, steps, v, v, 2)
            vmax = np.sqrt((tab.astype(np.float64) ** 2).sum(-1)).max(axis=(0, 1, 2))  # per vertex (v, v)
            reach = 2.0 * _dense_max(vmax, m.grid) + _REACH_MARGIN
            content = np.zeros((h, w), np.uint8)
            for pm in ly.pm:
                content |= (pm[:, :, 3] > 0).astype(np.uint8)
            if not content.any():
                ly.rect = (0, 0, 1, 1)
            else:
                dist = cv2.distanceTransform(1 - content, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
                ys, xs = np.nonzero(dist <= reach)
                ly.rect = (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
            if ly.rect != (0, 0, w, h):
                ly.window = m.grid.window(*ly.rect)

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
        maps: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        planes_of: dict[int, np.ndarray] = {}
        results = []
        for k, ly in enumerate(self.layers):
            if ly.group < 0:
                results.append(ly.pm[0])
                continue
            m = self.groups[ly.group]
            if ly.group not in planes_of:
                planes = m._mesh_planes(act)
                if jitter is not None:
                    planes += np.moveaxis(np.asarray(jitter, dtype=np.float32), -1, 0)
                planes_of[ly.group] = planes
            key = (ly.group, id(ly.window))
            if key not in maps:
                up = ly.window if ly.window is not None else m.grid
                maps[key] = up.upsample_planes(planes_of[ly.group], reuse=True)
            mx, my = maps[key]
            x0, y0, x1, y1 = ly.rect
            dst = self._layer_out[k]
            region = dst[y0:y1, x0:x1]
            warped = [
                cv2.remap(ly.pm[ia], mx[j], my[j], dst=ly.scratch[j],
                          interpolation=cv2.INTER_LINEAR, borderMode=m.border, borderValue=(0, 0, 0, 0))
                for j, (ia, _) in enumerate(act)
            ]
            wts = [wa for _, wa in act]
            if detail and len(act) > 1:
                region[...] = detail_blend(warped, wts, sigma=self.detail_sigma, plain=blend_u8(warped, wts))
            elif len(act) == 3:
                _blend3_u8(warped, wts, out=region, scratch=ly.scratch[3])
            else:
                blend_u8(warped, wts, out=region)
            results.append(dst)
        if out is None:
            out = np.empty_like(self.pm[0])
        np.copyto(out, results[0])
        for img in results[1:]:
            over_u8(img, out, out, self._inv)
        return out


class _Plain:
    """``PartMorpher.active`` for a part whose layers are all static (no morpher to borrow)."""

    def __init__(self, n: int):
        self.n = n

    active = PartMorpher.active


def _dense_max(vertex_values: np.ndarray, grid) -> np.ndarray:
    """Per pixel ``(h, w)``: the largest of the (up to four) vertex values around it."""
    v = vertex_values.astype(np.float32)
    cells = grid.cells
    xs = np.minimum(np.floor(np.arange(grid.w) * cells / (grid.w - 1)).astype(int), cells - 1)
    ys = np.minimum(np.floor(np.arange(grid.h) * cells / (grid.h - 1)).astype(int), cells - 1)
    q = np.maximum(np.maximum(v[:-1, :-1], v[1:, :-1]), np.maximum(v[:-1, 1:], v[1:, 1:]))  # per cell
    return q[ys][:, xs]
