"""The in-memory art set: a character's heads, its two parts (eyes, mouth) with drawings, and
an optional body.

Conventions (used by ``morph`` and ``app`` too):

* images are ``uint8`` arrays of shape ``(h, w, 4)``, **RGBA, straight (not premultiplied)
  alpha**, exactly as stored in the PNGs;
* boxes are ``(x, y, w, h)`` integers in pixels of the head canvas;
* control lines are ``float64`` arrays of shape ``(n, 4)``, rows ``(x0, y0, x1, y1)`` in pixels
  of the drawing they belong to. Line *i* means the same feature in every drawing of a part.

A drawing is either one picture (format 1) or a stack of :class:`Layer` pictures, bottom first
(format 2): every drawing of a layered part has the same layers in the same order, each with
its own control lines or sharing the drawing's. ``Drawing.image`` of a layered drawing is the
layers flattened (``flatten``), for previews, thumbnails and checks; the renderer morphs each
layer on its own and stacks the results.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

FORMAT_VERSION = 2  # written when a set has layers or a body; plainer sets are still written as 1
READ_FORMATS = (1, 2)
PART_NAMES: tuple[str, ...] = ("eyes", "mouth")


@dataclass
class Layer:
    """One picture of a layered drawing: RGBA image of the part's box size and, optionally, its
    own control lines (``None``: the layer moves with the drawing's lines)."""

    name: str
    image: np.ndarray
    lines: np.ndarray | None = None
    file: str = ""  # path relative to the art-set folder, as in the manifest


@dataclass
class Drawing:
    """One drawing of a part: its expression name, RGBA image and control lines.

    ``layers`` (bottom first) make it a layered drawing; ``image`` is then their flattening.
    """

    name: str
    image: np.ndarray
    lines: np.ndarray
    file: str = ""  # path relative to the art-set folder, as in the manifest (unused when layered)
    layers: list[Layer] = field(default_factory=list)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return int(self.image.shape[1]), int(self.image.shape[0])

    @property
    def layered(self) -> bool:
        return bool(self.layers)

    def layer_lines(self, k: int) -> np.ndarray:
        """Control lines layer ``k`` moves with: its own, else the drawing's."""
        own = self.layers[k].lines
        return self.lines if own is None else own

    @staticmethod
    def from_layers(name: str, layers: list[Layer], lines) -> "Drawing":
        """A layered drawing whose ``image`` is the flattening of ``layers``."""
        return Drawing(name, flatten([ly.image for ly in layers]), np.asarray(lines, np.float64).reshape(-1, 4),
                       "", list(layers))


@dataclass
class Part:
    """A rectangle of the head canvas and the drawings that can fill it."""

    name: str
    box: tuple[int, int, int, int]
    drawings: list[Drawing] = field(default_factory=list)

    @property
    def size(self) -> tuple[int, int]:
        return int(self.box[2]), int(self.box[3])

    def names(self) -> list[str]:
        return [d.name for d in self.drawings]

    def index(self, name: str) -> int:
        """Index of the drawing called ``name`` (ValueError when absent)."""
        for i, d in enumerate(self.drawings):
            if d.name == name:
                return i
        raise ValueError(f"part {self.name!r} has no drawing {name!r}")


@dataclass
class Body:
    """What stays under the head: a canvas-sized RGBA image (neck, shoulders, collar).

    When the head moves by ``(dx, dy)`` and rolls by ``r`` degrees, the body moves by
    ``follow · (dx, dy)`` and rolls by ``roll · r`` about ``pivot`` (canvas pixels; ``None``:
    the art set's pivot). Where it meets the canvas edge it is continued by its mirror image, so
    a moving body never shows a gap at the edge.
    """

    image: np.ndarray
    file: str = "body.png"
    follow: float = 0.3
    roll: float = 0.0
    pivot: tuple[float, float] | None = None


DEFAULT_BODY_FOLLOW = Body.follow
MAX_BODY_ROLL = 1.0


@dataclass
class ArtSet:
    """A character: manifest fields, head images and the parts.

    ``heads`` are RGBA canvases of size ``canvas`` whose alpha is soft (feathered) where the
    eyes and mouth show through; ``head_files`` are their manifest paths. ``body`` is drawn
    under the head and moves less (``Body``). ``extra`` keeps manifest keys this version does
    not interpret, so a load/save round trip loses nothing.
    """

    name: str
    canvas: tuple[int, int]
    pivot: tuple[float, float]
    heads: list[np.ndarray]
    parts: dict[str, Part]
    author: str = ""
    head_files: list[str] = field(default_factory=list)
    path: Path | None = None
    extra: dict = field(default_factory=dict)
    body: Body | None = None

    @property
    def layered(self) -> bool:
        """True when some drawing has layers."""
        return any(d.layers for p in self.parts.values() for d in p.drawings)

    def single_pictures(self) -> "ArtSet":
        """A format-1 copy: every drawing its flattened picture with the drawing's lines, no body
        (what a renderer without layers would see; the images are shared, not copied)."""
        parts = {name: Part(name, p.box, [Drawing(d.name, d.image, d.lines, d.file if not d.layers else f"{name}/{d.name}.png")
                                          for d in p.drawings]) for name, p in self.parts.items()}
        return ArtSet(self.name, self.canvas, self.pivot, list(self.heads), parts, self.author, list(self.head_files),
                      None, dict(self.extra), None)

    @property
    def eyes(self) -> Part:
        return self.parts["eyes"]

    @property
    def mouth(self) -> Part:
        return self.parts["mouth"]


def layer_names(part: Part) -> list[str]:
    """The layer names of a layered part, bottom first (``[]`` when its drawings are single pictures)."""
    for d in part.drawings:
        if d.layers:
            return [ly.name for ly in d.layers]
    return []


def flatten(images) -> np.ndarray:
    """Straight RGBA uint8 images of one size stacked bottom first with "over": one straight RGBA image."""
    images = [np.asarray(im) for im in images]
    if not images:
        raise ValueError("flatten needs at least one image")
    if len(images) == 1:
        return images[0].copy()
    acc = np.zeros(images[0].shape, np.float32)  # premultiplied, 0..1
    for im in images:
        f = im.astype(np.float32) / 255.0
        a = f[..., 3:4]
        acc[..., :3] = f[..., :3] * a + acc[..., :3] * (1 - a)
        acc[..., 3:4] = a + acc[..., 3:4] * (1 - a)
    a = acc[..., 3:4]
    rgb = np.where(a > 1e-6, acc[..., :3] / np.maximum(a, 1e-6), 0)
    return np.clip(np.concatenate([rgb, a], -1) * 255 + 0.5, 0, 255).astype(np.uint8)
