"""The in-memory art set: a character's heads and its two parts (eyes, mouth) with drawings.

Conventions (used by ``morph`` and ``app`` too):

* images are ``uint8`` arrays of shape ``(h, w, 4)``, **RGBA, straight (not premultiplied)
  alpha**, exactly as stored in the PNGs;
* boxes are ``(x, y, w, h)`` integers in pixels of the head canvas;
* control lines are ``float64`` arrays of shape ``(n, 4)``, rows ``(x0, y0, x1, y1)`` in pixels
  of the drawing they belong to. Line *i* means the same feature in every drawing of a part.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

FORMAT_VERSION = 1
PART_NAMES: tuple[str, ...] = ("eyes", "mouth")


@dataclass
class Drawing:
    """One drawing of a part: its expression name, RGBA image and control lines."""

    name: str
    image: np.ndarray
    lines: np.ndarray
    file: str = ""  # path relative to the art-set folder, as in the manifest

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return int(self.image.shape[1]), int(self.image.shape[0])


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
class ArtSet:
    """A character: manifest fields, head images and the parts.

    ``heads`` are RGBA canvases of size ``canvas`` whose alpha is soft (feathered) where the
    eyes and mouth show through; ``head_files`` are their manifest paths. ``extra`` keeps
    manifest keys this version does not interpret, so a load/save round trip loses nothing.
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

    @property
    def eyes(self) -> Part:
        return self.parts["eyes"]

    @property
    def mouth(self) -> Part:
        return self.parts["mouth"]
