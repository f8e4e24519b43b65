"""``CharacterRenderer``: one art set, morph weights in, a premultiplied RGBA frame out.

Loading builds a ``PartMorpher`` per part (the α tables: the slow part, done once), or a
``LayeredMorpher`` for a part drawn in layers, and a ``Compositor`` (with the body, when the set
has one). ``render`` then costs two mesh polymorphs (one per moving layer of a layered part), the
head composite and one affine warp (two with a body). A part asked for with the same drawings
and weights as in the last frame is not rendered again.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from morph.compositor import Compositor
from morph.layers import LayeredMorpher
from morph.polymorph import PartMorpher
from morph.style import ExpressionStyle

# The drawing shown for a part when the caller passes no weights (first match, else drawing 0).
_REST_NAMES = {"mouth": ("neutral", "rest"), "eyes": ("open", "neutral")}

Weights = tuple[Sequence[int], Sequence[float]]


class CharacterRenderer:
    """Renders an ``art_sets.model.ArtSet``.

    ``gain`` scales the pose (head translation and roll); ``detail`` switches on the
    detail-keeping blend; ``style`` sets the expression-driven style used when ``render`` gets a
    positive ``style_level``; ``exact_three_way`` trades 1–2 ms a part for the exact
    three-way field instead of the paper's sum of two-way warps (``PartMorpher``);
    ``keep_in_frame`` softly limits head translation so the head stays on the canvas (see
    ``Compositor``; rotation is never limited).
    """

    def __init__(
        self,
        artset,
        gain: float = 1.0,
        detail: bool = False,
        alpha_steps: int = 11,
        style: ExpressionStyle | None = None,
        shimmer_every: int = 2,
        exact_three_way: bool = False,
        keep_in_frame: bool = True,
    ):
        self.artset = artset
        self.detail = bool(detail)
        self.style = style or ExpressionStyle()
        self.morphers: dict[str, PartMorpher | LayeredMorpher] = {}
        self.rest: dict[str, int] = {}
        for name, part in artset.parts.items():
            if not part.drawings:
                raise ValueError(f"art set {artset.name!r}: part {name!r} has no drawings")
            try:
                if any(d.layers for d in part.drawings):
                    self.morphers[name] = LayeredMorpher(part.drawings, alpha_steps=alpha_steps,
                                                         exact_three_way=exact_three_way)
                else:
                    self.morphers[name] = PartMorpher(
                        [d.image for d in part.drawings], [d.lines for d in part.drawings], alpha_steps=alpha_steps,
                        exact_three_way=exact_three_way,
                    )
            except ValueError as e:
                raise ValueError(f"art set {artset.name!r}, part {name!r}: {e}") from None
            if self.morphers[name].size != part.size:
                raise ValueError(
                    f"art set {artset.name!r}: drawings of part {name!r} are {self.morphers[name].size}, box is {part.size}"
                )
            names = part.names()
            self.rest[name] = next((names.index(n) for n in _REST_NAMES.get(name, ()) if n in names), 0)
        self._part_buffers = {n: np.empty_like(m.pm[0]) for n, m in self.morphers.items()}
        self._parts: dict[str, np.ndarray] = dict(self._part_buffers)  # each part's last picture
        self._part_keys: dict[str, tuple | None] = {n: None for n in self.morphers}  # ... and what it shows
        body = getattr(artset, "body", None)
        self.compositor = Compositor(
            artset.canvas, artset.pivot, artset.heads, {n: p.box for n, p in artset.parts.items()},
            gain=gain, shimmer_every=shimmer_every, keep_in_frame=keep_in_frame,
            body=None if body is None else body.image,
            body_follow=0.0 if body is None else body.follow,
            body_roll=0.0 if body is None else body.roll,
            body_pivot=None if body is None else body.pivot,
        )

    @property
    def canvas(self) -> tuple[int, int]:
        """Output size ``(w, h)``."""
        return self.compositor.canvas

    @property
    def gain(self) -> float:
        return self.compositor.gain

    @gain.setter
    def gain(self, value: float) -> None:
        self.compositor.gain = float(value)

    def render_part(
        self, name: str, weights: Weights | None, frame_no: int = 0, style_level: float = 0.0,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """One part, premultiplied RGBA of its box size (a new array unless ``out`` is given)."""
        m = self.morphers[name]
        if weights is None:
            idx, wts = (self.rest[name],), (1.0,)
        else:
            idx, wts = weights
        jitter = None
        if style_level > 0:
            part_no = list(self.morphers).index(name)
            jitter = self.style.jitter(style_level, frame_no, part_no, m.grid.cells)
        return m.render(idx, wts, detail=self.detail, jitter=jitter, out=out)

    def render(
        self,
        eyes: Weights | None = None,
        mouth: Weights | None = None,
        pose: Sequence[float] = (0.0, 0.0, 0.0),
        frame_no: int = 0,
        style_level: float = 0.0,
    ) -> np.ndarray:
        """A frame: premultiplied RGBA uint8 ``(h, w, 4)`` of ``canvas`` size (a new array).

        ``eyes`` / ``mouth`` are ``(indices, weights)`` of three drawings each (None: the rest
        drawing); ``pose`` is ``(dx, dy, roll_deg)`` in canvas pixels and degrees, scaled by
        ``gain``; ``frame_no`` drives the head shimmer; ``style_level`` 0..1 the expression style.
        """
        given = {"eyes": eyes, "mouth": mouth}
        parts = {}  # rendered into per-part buffers: the compositor copies them into the frame
        for name in self.morphers:
            key = None if style_level > 0 else _part_key(given.get(name) or ((self.rest[name],), (1.0,)), self.detail)
            if key is None or not _same_key(key, self._part_keys[name]):
                self._part_keys[name] = None
                # (the detail blend returns a new array rather than filling the buffer)
                self._parts[name] = self.render_part(name, given.get(name), frame_no, style_level,
                                                     out=self._part_buffers[name])
                self._part_keys[name] = key
            parts[name] = self._parts[name]
        if style_level <= 0:
            return self.compositor.compose(parts, pose, frame_no)
        flat = self.style.apply_tint(self.compositor.flat(parts, frame_no), style_level)
        return self.compositor.transform(flat, pose)


# A part whose drawings and weights are within this of the last frame's is not rendered again
# (a performer holding still, a face held while lost): its vertices would move by well under
# 1/1000 px and its pixels by under 1/1000 of a level.
REUSE_EPS = 1e-6


def _part_key(weights: Weights, detail: bool) -> tuple:
    """What a part's buffer shows: ``(detail, indices, weights)``."""
    idx, wts = weights
    return (detail, tuple(int(i) for i in idx), tuple(float(w) for w in wts))


def _same_key(a: tuple, b: tuple | None) -> bool:
    """Same detail flag and drawings in the same order, weights within ``REUSE_EPS``."""
    if b is None or a[:2] != b[:2] or len(a[2]) != len(b[2]):
        return False
    return all(abs(x - y) <= REUSE_EPS for x, y in zip(a[2], b[2]))
