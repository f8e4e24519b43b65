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
sample its content), so a small layer, such as a lower lid, costs little. Layers are also only
warped where the layers above them are not all opaque this frame (found the same way from each
drawing's box of see-through pixels): under an upper lid that covers the box but for a slot, the
eyeball and lower lid are drawn in the slot's rectangle, and the lid is laid over them only there.

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


Rect = tuple[int, int, int, int]  # pixels [x0, x1) × [y0, y1) of the part


@dataclass
class _Layer:
    name: str
    group: int  # index into LayeredMorpher.groups, or -1 for a static layer
    pm: list[np.ndarray]  # premultiplied image per drawing (one shared array when static)
    boxes: np.ndarray | None = None  # (n, b, 4) float x0, y0, x1, y1 of each drawing's content, widened for bilinear reads
    full: bool = True  # every drawing's content spans the part: no rectangle to find per frame
    holes: np.ndarray | None = None  # (n, b, 4) the same for each drawing's see-through (α < 255) pixels
    covers: bool = False  # opaque somewhere in some drawing: what lies under it can be hidden
    static_rect: list = None  # a static layer's content rectangles ([]: transparent)
    static_hole: list = None  # a static layer's see-through rectangles ([]: opaque everywhere)


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
        self._edge_border = all(g.border == cv2.BORDER_REPLICATE for g in self.groups)
        self.cull = True  # skip what the layers above hide (tests switch it off to compare)
        for ly in self.layers:
            self._content_boxes(ly)
        # each drawing stacked: what a frame showing one drawing alone returns (``pm`` as in PartMorpher)
        self.pm = [self._stack([ly.pm[i] for ly in self.layers]) for i in range(self.n)]
        for s in self.pm:
            s.flags.writeable = False
        self._scratch = np.empty(5 * h * w * 4, np.uint8)  # 3 warped images, a pair sum, the blend: of the rectangle's size
        self._inv = np.empty((h, w, 4), np.uint8)  # scratch for over_u8 (its prefix, reshaped, for a rectangle)

    # --- load time -------------------------------------------------------------------------
    def _content_boxes(self, ly: _Layer) -> None:
        """Each drawing's bounding boxes of non-transparent and of see-through pixels, one per run of
        columns holding some (two eyes: two boxes), one pixel wider (bilinear reads). A box that
        touches the part's edge runs on past it: the warp reads outside the drawing along the
        edges, and repeats the edge pixels there."""
        w, h = self.size
        n = 1 if ly.group < 0 else self.n
        found: dict[str, list[list[tuple]]] = {"boxes": [], "holes": []}
        for pm in ly.pm[:n]:
            for key, mask in (("boxes", pm[:, :, 3] > 0), ("holes", pm[:, :, 3] < 255)):
                found[key].append(_column_boxes(mask))
        for key, per in found.items():
            if key == "holes" and not self._edge_border:  # outside is transparent: a hole near every edge
                per = [[(-np.inf, -np.inf, np.inf, np.inf)] if b else [] for b in per]
            most = max(1, max(len(b) for b in per))
            arr = np.empty((n, most, 4))
            arr[:] = (np.inf, np.inf, -np.inf, -np.inf)  # an empty box: nothing samples inside it
            for i, b in enumerate(per):
                if b:
                    arr[i, :len(b)] = b
            setattr(ly, key, arr)
        everything = (-np.inf, -np.inf, np.inf, np.inf)
        ly.full = all(len(b) == 1 and b[0] == everything for b in found["boxes"])
        ly.covers = not all(everything in b for b in found["holes"]) and self._edge_border
        if ly.group < 0:
            ly.static_rect = [r for b in found["boxes"][0] if (r := self._clip(b))]
            ly.static_hole = [r for b in found["holes"][0] if (r := self._clip(b))]

    def _clip(self, box) -> Rect | None:
        """A float box (bilinear margin included) as the pixel rectangle it covers in the part."""
        w, h = self.size
        if not box[0] <= box[2]:
            return None
        x0 = 0 if box[0] == -np.inf else max(0, int(box[0]) + 1)
        y0 = 0 if box[1] == -np.inf else max(0, int(box[1]) + 1)
        x1 = w if box[2] == np.inf else min(w, int(box[2]))
        y1 = h if box[3] == np.inf else min(h, int(box[3]))
        return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None

    @staticmethod
    def _cell_bounds(planes: np.ndarray, k: int) -> tuple[np.ndarray, ...]:
        """Per mesh cell and active drawing, the least and greatest x and y its four corners sample
        (each ``(k, cells, cells)``): a pixel's source is a convex mix of its cell's corners."""
        def pick(p, f):
            return f(f(p[:, :-1, :-1], p[:, 1:, :-1]), f(p[:, :-1, 1:], p[:, 1:, 1:]))

        px, py = planes[:k, 0], planes[:k, 1]
        return pick(px, np.minimum), pick(px, np.maximum), pick(py, np.minimum), pick(py, np.maximum)

    def _frame_rects(self, boxes: np.ndarray, bounds: tuple[np.ndarray, ...], act) -> list[Rect]:
        """The pixels of the part whose samples, this frame, can fall inside ``boxes`` (one per
        drawing) of some active drawing: the mesh cells whose corners' bounding box meets the box,
        as one rectangle per run of such cell columns (two eyes' slots are two rectangles)."""
        b = boxes[[ia for ia, _ in act]][:, :, :, None, None]  # (k, boxes, 4, 1, 1)
        x_lo, x_hi, y_lo, y_hi = (c[:, None] for c in bounds)  # (k, 1, cells, cells)
        hit = (x_lo <= b[:, :, 2]) & (x_hi >= b[:, :, 0]) & (y_lo <= b[:, :, 3]) & (y_hi >= b[:, :, 1])
        hit = hit.any(axis=(0, 1))
        xs, ys = self._spans
        out = []
        for c0, c1 in _runs(hit.any(axis=0)):
            rows = np.flatnonzero(hit[:, c0:c1 + 1].any(axis=1))
            out.append((int(xs[c0, 0]), int(ys[rows[0], 0]), int(xs[c1, 1]), int(ys[rows[-1], 1])))
        return out

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
        w, h = self.size
        full = (0, 0, w, h)
        planes_of: dict[int, np.ndarray] = {}
        bounds_of: dict[int, tuple[np.ndarray, ...]] = {}
        for ly in self.layers:
            if ly.group >= 0 and ly.group not in planes_of:
                planes = self.groups[ly.group]._mesh_planes(act)
                if jitter is not None:
                    planes += np.moveaxis(np.asarray(jitter, dtype=np.float32), -1, 0)
                planes_of[ly.group] = planes
        # top down: where each layer can show (its content, where the layers above let it through),
        # and where the layers under it can show (what it is laid over)
        cull = self.cull and not detail  # the detail blend may take an opaque pixel under 255
        n = len(self.layers)
        rects: list[list[Rect]] = [[] for _ in range(n)]
        under: list[list[Rect]] = [[] for _ in range(n)]
        vis: list[Rect] = [full]
        for k in range(n - 1, -1, -1):
            ly = self.layers[k]
            if not cull:
                rect, hole = [full], [full]
            elif ly.group < 0:
                rect, hole = ly.static_rect, ly.static_hole
            else:
                g = ly.group
                if (ly.covers or not ly.full) and g not in bounds_of:
                    bounds_of[g] = self._cell_bounds(planes_of[g], len(act))
                rect = [full] if ly.full else self._frame_rects(ly.boxes, bounds_of[g], act)
                hole = self._frame_rects(ly.holes, bounds_of[g], act) if ly.covers else [full]
            rects[k] = _meet_all(rect, vis)
            vis = _meet_all(vis, hole)
            under[k] = _meet_all(vis, rects[k])
            if not vis:
                break
        # bottom up: each layer's rectangles blended, laid over what lies under them, and copied out
        wts = [wa for _, wa in act]
        first = True
        for k, ly in enumerate(self.layers):
            if first and rects[k] and rects[k] != [full]:
                out[...] = 0  # what no layer covers stays transparent
            for rect in rects[k]:
                x0, y0, x1, y1 = rect
                if ly.group < 0:
                    n_px = (y1 - y0) * (x1 - x0) * 4
                    blended = self._scratch[4 * n_px:5 * n_px].reshape(y1 - y0, x1 - x0, 4)
                    np.copyto(blended, ly.pm[0][y0:y1, x0:x1])
                else:
                    blended = self._blend_layer(ly, planes_of[ly.group], act, wts, rect, detail)
                if not first:
                    for u in under[k]:
                        v = _meet(u, rect)
                        if v is None:
                            continue
                        vx0, vy0, vx1, vy1 = v
                        top = blended[vy0 - y0:vy1 - y0, vx0 - x0:vx1 - x0]
                        n_px = (vy1 - vy0) * (vx1 - vx0) * 4
                        over_u8(top, out[vy0:vy1, vx0:vx1], top, self._inv.reshape(-1)[:n_px].reshape(vy1 - vy0, vx1 - vx0, 4))
                out[y0:y1, x0:x1] = blended
            if rects[k]:
                first = False
        if first:
            out[...] = 0
        return out

    def _blend_layer(self, ly: _Layer, planes: np.ndarray, act, wts, rect: Rect, detail: bool) -> np.ndarray:
        """Layer ``ly`` of the active drawings warped with this frame's meshes and blended, in ``rect``
        (a scratch buffer of the rectangle's size)."""
        m = self.groups[ly.group]
        x0, y0, x1, y1 = rect
        if rect == (0, 0) + self.size:
            mx, my = m.grid.upsample_planes(planes, reuse=True)
        else:
            mx, my = m.grid.upsample_rect(planes, rect)
        n_px = (y1 - y0) * (x1 - x0) * 4
        bufs = [self._scratch[j * n_px:(j + 1) * n_px].reshape(y1 - y0, x1 - x0, 4) for j in range(5)]
        warped = [
            cv2.remap(ly.pm[ia], mx[j], my[j], dst=bufs[j], interpolation=cv2.INTER_LINEAR,
                      borderMode=m.border, borderValue=(0, 0, 0, 0))
            for j, (ia, _) in enumerate(act)
        ]
        if detail and len(act) > 1:
            return detail_blend(warped, wts, sigma=self.detail_sigma, plain=blend_u8(warped, wts))
        if len(act) == 3:
            return _blend3_u8(warped, wts, out=bufs[4], scratch=bufs[3])
        return blend_u8(warped, wts, out=bufs[4])


def _column_boxes(mask: np.ndarray) -> list[tuple[float, float, float, float]]:
    """Bounding boxes ``(x0, y0, x1, y1)`` of ``mask``, one per run of columns holding some of it,
    widened by a pixel; a side touching the image's edge is pushed to infinity."""
    h, w = mask.shape
    out = []
    for c0, c1 in _runs(mask.any(axis=0)):
        rows = np.flatnonzero(mask[:, c0:c1 + 1].any(axis=1))
        r0, r1 = int(rows[0]), int(rows[-1])
        out.append((-np.inf if c0 == 0 else c0 - 1.0, -np.inf if r0 == 0 else r0 - 1.0,
                    np.inf if c1 == w - 1 else c1 + 1.0, np.inf if r1 == h - 1 else r1 + 1.0))
    return out


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``(first, last)`` index of each run of True in a 1-D boolean array."""
    edges = np.flatnonzero(np.diff(flags.astype(np.int8), prepend=0, append=0)).tolist()
    return [(a, b - 1) for a, b in zip(edges[::2], edges[1::2])]


def _meet(a: Rect | None, b: Rect | None) -> Rect | None:
    """The intersection of two rectangles (None: empty)."""
    if a is None or b is None:
        return None
    x0, y0, x1, y1 = max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3])
    return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def _meet_all(a: list[Rect], b: list[Rect]) -> list[Rect]:
    """The intersections of each rectangle of ``a`` with each of ``b`` (disjoint when both lists are)."""
    return [r for p in a for q in b if (r := _meet(p, q)) is not None]


class _Plain:
    """``PartMorpher.active`` for a part whose layers are all static (no morpher to borrow)."""

    def __init__(self, n: int):
        self.n = n

    active = PartMorpher.active
