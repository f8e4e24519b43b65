"""Art sets: a character's heads and its eye and mouth drawings with control lines.

Public API: :mod:`art_sets.model` (ArtSet, Part, Drawing), :func:`art_sets.io.load_artset`,
:func:`art_sets.io.save_artset`, :class:`art_sets.io.ArtSetError`,
:func:`art_sets.validate.validate`, and :mod:`art_sets.library` (bundled / user sets, thumbnails).
Imports only numpy and Pillow.
"""

from art_sets.io import ArtSetError, Problem, load_artset, save_artset
from art_sets.model import FORMAT_VERSION, ArtSet, Drawing, Part

__all__ = ["ArtSet", "ArtSetError", "Drawing", "FORMAT_VERSION", "Part", "Problem", "load_artset", "save_artset"]
