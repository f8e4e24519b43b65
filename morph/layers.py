"""Layered parts: morph each layer across the drawings, then stack the layers (format 2).

A layered drawing is a stack of pictures, bottom first (an eyeball under the lids, the inside of
a mouth under the lips). Blending whole drawings mixes an opaque lid with the eyeball it covers;
here every layer is warped and blended on its own, with the weights of the frame, and the blended
layers are then laid over each other with "over", so an opaque lid hides what lies under it.

Loading precomputes, per distinct set of control lines, one :class:`PartMorpher` (its α tables):
layers that share the drawing's lines share one set of tables and, per frame, one set of meshes
and dense maps. A layer that is the same picture with the same lines in every drawing (an eyeball
that never changes) is kept as it is and never warped. Each frame, a moving layer is only warped
inside the rectangle its content can reach under that frame's meshes (the mesh cells whose corners
sample its content), so a small layer, such as a lower lid, costs little.

The per-frame work is batched over the part's line sets: their α tables live in one array, so
every set's meshes come from one gather and one product (the mixing weights depend only on the
frame's weights); the rectangles of all small layers are found in one pass over the meshes; and
the dense maps of the layers that span the part, or most of it, come from one upsampling call.
Layers are warped top first. A layer that spans the part (upper lids and lips) then finds the box
where it lets light through (its eye openings, the gap of the lips): the layers below it are
warped only inside that box, a small layer there without a rectangle of its own, and around it
the layer is copied rather than laid over (under an opaque pixel, "over" gives the top pixel
whatever lies below). All of this is exact: the frames equal a layer-by-layer, full-box render.

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
    which it uses for each distinct set of control lines, with ``cross_terms`` on by default: three-way
    frames of layered parts add the tabled second-order term of the field (``morph.polymorph``), so
    lips and lids that move far land within a fraction of a pixel of the exact three-way field.
    (One-picture parts keep the paper's plain sum, so format-1 sets render as they always have.)
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
        cross_terms: bool = True,
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
                  exact_three_way=exact_three_way, cross_terms=cross_terms)
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
        self._batch_tables()
        self._rect_layers = [k for k, ly in enumerate(self.layers) if ly.group >= 0 and not ly.full]
        # line sets whose dense maps are upsampled over the whole part in one call: those of layers
        # that span it, and of layers whose content covers most of it anyway (one call for all of
        # them costs less than a call per rectangle)
        big = {ly.group for ly in self.layers if ly.group >= 0 and (ly.full or self._content_share(ly) >= _FULL_MAP_SHARE)}
        self._full_groups = sorted(big)
        self._full_slot = {k: self._full_groups.index(ly.group) for k, ly in enumerate(self.layers) if ly.group in big}
        self._moving_top_down = [k for k in reversed(range(len(self.layers))) if self.layers[k].group >= 0]
        self._layer_bufs = {k: np.empty(h * w * 4, np.uint8) for k in self._moving_top_down}
        # moving layers spanning the part over something: each frame finds where they let light through
        self._sees = {k for k in self._moving_top_down if k > 0 and self.layers[k].full}
        # The small layers whose rectangles a frame needs: under a layer that finds where it lets
        # light through, a layer is warped inside that box, where its own rectangle adds little
        # (the detail blend, which finds no such box, needs them all).
        under = [k for k in self._rect_layers if not any(j > k for j in self._sees)]
        self._rect_sets = {detail: self._rect_set(self._rect_layers if detail else under) for detail in (False, True)}
        # each drawing stacked: what a frame showing one drawing alone returns (``pm`` as in PartMorpher)
        self.pm = [self._stack([ly.pm[i] for ly in self.layers]) for i in range(self.n)]
        for s in self.pm:
            s.flags.writeable = False
        self._scratch = np.empty(4 * h * w * 4, np.uint8)  # 3 warped images and a pair sum, of the rectangle's size
        self._inv = np.empty((h, w, 4), np.uint8)  # scratch for over_u8 (its prefix, reshaped, for a rectangle)

    # --- load time -------------------------------------------------------------------------
    def _content_boxes(self, ly: _Layer) -> None:
        """Each drawing's bounding box of non-transparent pixels, one pixel wider (bilinear reads).
        With the edge border, a box that touches the part's edge runs on past it: the warp reads
        outside the drawing there and repeats the edge pixels."""
        w, h = self.size
        edge = self.groups[ly.group].border == cv2.BORDER_REPLICATE
        boxes = np.full((self.n, 4), (np.inf, np.inf, -np.inf, -np.inf))
        for i, pm in enumerate(ly.pm):
            ys, xs = np.nonzero(pm[:, :, 3])
            if len(xs):
                boxes[i] = (xs.min() - 1.0, ys.min() - 1.0, xs.max() + 1.0, ys.max() + 1.0)
                if edge:
                    boxes[i, :2][boxes[i, :2] < 0] = -np.inf
                    boxes[i, 2:][boxes[i, 2:] >= (w, h)] = np.inf
        ly.boxes = boxes
        ly.full = bool(np.all(boxes[:, :2] <= -1.0) and np.all(boxes[:, 2] >= w) and np.all(boxes[:, 3] >= h))

    def _batch_tables(self) -> None:
        """Put every line set's α tables into one array (each ``PartMorpher`` keeps a view of its
        rows), so one gather reads the rows a frame needs from all of them."""
        if not self.groups:
            self._table = None
            return
        self._group_rows = self.groups[0]._planes.shape[0]
        table = np.concatenate([g._planes for g in self.groups])
        table.flags.writeable = False
        for g, m in enumerate(self.groups):
            m._planes = table[g * self._group_rows:(g + 1) * self._group_rows]
        self._table = table
        self._row_offsets = np.arange(len(self.groups))[:, None] * self._group_rows

    def _content_share(self, ly: _Layer) -> float:
        """The mean share of the part that ``ly``'s content boxes cover in its drawings."""
        w, h = self.size
        b = ly.boxes
        sides = np.clip(b[:, 2:], 0, (w, h)) - np.clip(b[:, :2], 0, (w, h))
        return float(np.mean(np.prod(np.maximum(sides, 0), axis=1))) / (w * h)

    def _rect_set(self, layers: list[int]) -> tuple | None:
        """``(layers, bounds, groups)`` for ``_frame_rects``: the layers, their content boxes as
        ``(L, n, 4)`` float32 ``x0, y0, −x1, −y1`` and their line sets (None for no layers)."""
        if not layers:
            return None
        boxes = np.stack([self.layers[k].boxes for k in layers])
        bounds = np.concatenate((boxes[..., :2], -boxes[..., 2:]), axis=-1).astype(np.float32)
        return layers, bounds, np.array([self.layers[k].group for k in layers])

    def _frame_rects(self, planes: np.ndarray, act, rect_set: tuple) -> dict[int, tuple[int, int, int, int] | None]:
        """For each layer of ``rect_set`` (see ``_rect_set``), the pixels ``(x0, y0, x1, y1)`` of the
        part where it can be non-transparent this frame, or None: the mesh cells some of whose
        corners, for some active drawing, sample inside that drawing's content box (a pixel's source
        is a convex mix of its cell's corners). ``planes``: ``(groups, len(act), 2, m, m)``, all
        line sets' meshes."""
        layers, bounds, groups = rect_set
        p = planes[groups]  # (L, k, 2, m, m)
        signed = np.concatenate((p, -p), axis=2)  # x, y, −x, −y: one comparison for all four sides
        inside = signed >= bounds[:, [ia for ia, _ in act], :, None, None]
        # a cell can sample a box if one of its corners lies beyond each of the box's sides
        pair = inside[..., :-1, :] | inside[..., 1:, :]
        corner = pair[..., :-1] | pair[..., 1:]  # (L, k, 4, c, c)
        hit = corner.all(axis=2).any(axis=1)  # (L, c, c)
        xs, ys = self._spans
        out = {}
        for k, rows, cols in zip(layers, hit.any(axis=2), hit.any(axis=1)):
            r = np.flatnonzero(rows)
            if not len(r):
                out[k] = None
                continue
            c = np.flatnonzero(cols)
            out[k] = (int(xs[c[0], 0]), int(ys[r[0], 0]), int(xs[c[-1], 1]), int(ys[r[-1], 1]))
        return out

    def _all_mesh_planes(self, act: list[tuple[int, float]]) -> np.ndarray:
        """``(groups, len(act), 2, m, m)`` float32: every line set's meshes for this frame (what
        each ``PartMorpher._mesh_planes`` gives, from one gather and one batched product)."""
        g0 = self.groups[0]
        m = self.grid.cells + 1
        k = len(act)
        if k == 1 or (self.exact_three_way and k > 2):
            return np.stack([g._mesh_planes(act) for g in self.groups])
        rows, coef = g0._mesh_terms(act)
        gathered = self._table[(self._row_offsets + np.array(rows)).ravel()].reshape(len(self.groups), len(rows), -1)
        return np.matmul(coef, gathered).reshape(len(self.groups), k, 2, m, m)

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
        self._compose(act, detail, jitter, out)
        return out

    def _compose(self, act: list[tuple[int, float]], detail: bool, jitter: np.ndarray | None, out: np.ndarray) -> None:
        """Warp, blend and stack every layer for the active drawings ``act`` into ``out``.

        Moving layers are warped top first, each only where every layer above it lets some
        light through: once a layer is computed over the whole visible box, the box shrinks to
        its pixels with α < 255 (under an opaque pixel, ``over`` gives the top pixel exactly,
        whatever lies below). The warped layers are then stacked bottom first, as drawn."""
        w, h = self.size
        k_act = len(act)
        wts = [wa for _, wa in act]
        shown: dict[int, tuple] = {}  # layer -> its rectangle x0, y0, x1, y1, blended, see-through box or None
        if self.groups:
            planes = self._all_mesh_planes(act)
            if jitter is not None:
                planes += np.moveaxis(np.asarray(jitter, dtype=np.float32), -1, 0)
            m = planes.shape[-1]
            if self._full_groups:
                sel = planes if len(self._full_groups) == len(self.groups) else planes[self._full_groups]
                full_x, full_y = self.grid.upsample_planes(sel.reshape(-1, 2, m, m), reuse=True)
            rect_set = self._rect_sets[bool(detail)]
            rects = self._frame_rects(planes, act, rect_set) if rect_set else {}
            vis = (0, 0, w, h)
            for k in self._moving_top_down:
                r = rects.get(k, (0, 0, w, h))
                if r is None:
                    continue
                x0, y0, x1, y1 = max(r[0], vis[0]), max(r[1], vis[1]), min(r[2], vis[2]), min(r[3], vis[3])
                if x1 <= x0 or y1 <= y0:
                    continue
                slot = self._full_slot.get(k)
                if slot is not None:
                    cut = (slice(slot * k_act, (slot + 1) * k_act), slice(y0, y1), slice(x0, x1))
                    mx, my = full_x[cut], full_y[cut]
                else:
                    mx, my = self.grid.upsample_rect(planes[self.layers[k].group], (x0, y0, x1, y1))
                blended = self._warp_blend(k, act, wts, mx, my, detail)
                light = None  # where it lets light through, when looked for (an empty box: nowhere)
                if k in self._sees and not detail and (x0, y0, x1, y1) == vis:  # (the detail blend's blur would see a cut)
                    vis = _see_through(blended, x0, y0)
                    light = vis or (x0, y0, x0, y0)
                shown[k] = (x0, y0, x1, y1, blended, light)
                if vis is None:
                    break
        for k, ly in enumerate(self.layers):
            if ly.group < 0:
                if k == 0:
                    np.copyto(out, ly.pm[0])
                else:
                    over_u8(ly.pm[0], out, out, self._inv)
                continue
            x0, y0, x1, y1, blended, light = shown.get(k, (0, 0, 0, 0, None, None))
            if k == 0 and (x0, y0, x1, y1) != (0, 0, w, h):
                out[...] = 0
            if blended is None:
                continue
            if k == 0:
                out[y0:y1, x0:x1] = blended
                continue
            if light is not None:  # opaque around its see-through box: a copy there, "over" inside
                lx0, ly0, lx1, ly1 = light
                out[y0:ly0, x0:x1] = blended[:ly0 - y0]
                out[ly1:y1, x0:x1] = blended[ly1 - y0:]
                out[ly0:ly1, x0:lx0] = blended[ly0 - y0:ly1 - y0, :lx0 - x0]
                out[ly0:ly1, lx1:x1] = blended[ly0 - y0:ly1 - y0, lx1 - x0:]
                blended, (x0, y0, x1, y1) = blended[ly0 - y0:ly1 - y0, lx0 - x0:lx1 - x0], light
                if x1 == x0:
                    continue
            region = out[y0:y1, x0:x1]
            n_px = (y1 - y0) * (x1 - x0) * 4
            over_u8(blended, region, region, self._inv.reshape(-1)[:n_px].reshape(y1 - y0, x1 - x0, 4))

    def _warp_blend(self, k: int, act, wts, mx: np.ndarray, my: np.ndarray, detail: bool) -> np.ndarray:
        """Layer ``k`` of the active drawings resampled along the maps ``mx, my`` (one per drawing,
        of a rectangle's size) and blended with the weights, into that layer's own buffer."""
        ly = self.layers[k]
        rh, rw = mx.shape[1:]
        n_px = rh * rw * 4
        bufs = [self._scratch[j * n_px:(j + 1) * n_px].reshape(rh, rw, 4) for j in range(4)]
        border = self.groups[ly.group].border
        warped = [
            cv2.remap(ly.pm[ia], mx[j], my[j], dst=bufs[j], interpolation=cv2.INTER_LINEAR,
                      borderMode=border, borderValue=(0, 0, 0, 0))
            for j, (ia, _) in enumerate(act)
        ]
        dst = self._layer_bufs[k][:n_px].reshape(rh, rw, 4)
        if detail and len(act) > 1:
            return detail_blend(warped, wts, sigma=self.detail_sigma, plain=blend_u8(warped, wts))
        if len(act) == 3:
            return _blend3_u8(warped, wts, out=dst, scratch=bufs[3])
        return blend_u8(warped, wts, out=dst)


def _see_through(blended: np.ndarray, x0: int, y0: int) -> tuple[int, int, int, int] | None:
    """The bounding box ``(x0, y0, x1, y1)`` of the pixels of ``blended`` (placed at ``x0, y0``)
    with α < 255, or None when it is opaque everywhere."""
    bx, by, bw, bh = cv2.boundingRect(cv2.compare(cv2.extractChannel(blended, 3), 255, cv2.CMP_LT))
    if bw == 0:
        return None
    return x0 + bx, y0 + by, x0 + bx + bw, y0 + by + bh


# A layer whose content boxes cover at least this share of the part gets its dense maps from the
# one upsampling call for the whole part (see ``__init__``).
_FULL_MAP_SHARE = 0.5


class _Plain:
    """``PartMorpher.active`` for a part whose layers are all static (no morpher to borrow)."""

    def __init__(self, n: int):
        self.n = n

    active = PartMorpher.active
