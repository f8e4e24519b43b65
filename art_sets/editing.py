"""Editing operations on an in-memory art set (pure numpy/Pillow; the editor window calls these).

Rules every function here keeps, so the editor's undo can share arrays between snapshots:

* image and line arrays are never modified in place: an edit puts a NEW array in the model;
* all drawings of a part keep the same number of control lines. Adding a line to one drawing
  adds a copy of it to every other drawing of the part and marks it *unplaced* there (the artist
  still has to move it onto the feature); moving it marks it placed. The unplaced marks live in
  ``artset.extra["editor"]["unplaced"][part][drawing name]`` so they survive a save and reload.

Coordinates: boxes are ``(x, y, w, h)`` ints in head-canvas pixels, points ``(x, y)`` floats,
lines ``(x0, y0, x1, y1)`` float64 rows in pixels of their drawing. Images are straight RGBA uint8.
"""

from __future__ import annotations

import colorsys
import copy
import json
import re
from dataclasses import replace
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
from PIL import Image

from art_sets.model import ArtSet, Drawing, Part

FIT_MODES = ("resize", "crop")
HOLE_MARGIN = 2.0  # px along a part box's edge that holes leave closed (the validator checks 2)
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".gif", ".tif", ".tiff", ".webp")


class EditError(ValueError):
    """An edit that cannot be done; the message is one line meant for the user."""


# ----------------------------------------------------------------------------- images


def load_image(path: str | Path) -> np.ndarray:
    """Read any Pillow-readable image as straight RGBA uint8 ``(h, w, 4)``."""
    path = Path(path)
    try:
        with Image.open(path) as im:
            im.load()
            return np.asarray(im.convert("RGBA"), dtype=np.uint8).copy()
    except (OSError, ValueError, Image.DecompressionBombError) as e:
        raise EditError(f"{path}: cannot read image ({e})") from None


def as_rgba(image: np.ndarray) -> np.ndarray:
    """Coerce a grey, RGB or RGBA uint8 array to RGBA (opaque where there was no alpha)."""
    a = np.asarray(image)
    if a.dtype != np.uint8:
        raise EditError(f"image must be uint8, got {a.dtype}")
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise EditError(f"image must be (h, w, 3|4), got shape {a.shape}")
    if a.shape[2] == 3:
        a = np.concatenate([a, np.full(a.shape[:2] + (1,), 255, np.uint8)], axis=2)
    return a


def resize_image(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Scale an RGBA image to ``size=(w, h)`` (Lanczos on premultiplied colour, so no dark fringes)."""
    w, h = int(size[0]), int(size[1])
    if w < 1 or h < 1:
        raise EditError(f"size must be positive, got {w}x{h}")
    img = as_rgba(image)
    if img.shape[1] == w and img.shape[0] == h:
        return img.copy()
    a = img[:, :, 3:4].astype(np.float32) / 255.0
    pm = np.concatenate([img[:, :, :3].astype(np.float32) * a, a * 255.0], axis=2)
    chans = [np.asarray(Image.fromarray(pm[:, :, c], mode="F").resize((w, h), Image.LANCZOS))
             for c in range(4)]
    out = np.stack(chans, axis=2)
    alpha = np.clip(out[:, :, 3], 0.0, 255.0)
    safe = np.where(alpha > 0.5, alpha / 255.0, 1.0)[:, :, None]
    rgb = np.where(alpha[:, :, None] > 0.5, out[:, :, :3] / safe, 0.0)
    return np.dstack([np.clip(rgb, 0, 255), alpha]).round().astype(np.uint8)


def crop_image(image: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, tuple[int, int]]:
    """Centre-crop (or pad with transparency) to ``size=(w, h)``.

    Returns the new image and the offset ``(dx, dy)`` to add to a point of the old image to
    get the same point in the new one.
    """
    w, h = int(size[0]), int(size[1])
    if w < 1 or h < 1:
        raise EditError(f"size must be positive, got {w}x{h}")
    img = as_rgba(image)
    ih, iw = img.shape[:2]
    dx, dy = (w - iw) // 2, (h - ih) // 2
    out = np.zeros((h, w, 4), np.uint8)
    sx0, sy0 = max(0, -dx), max(0, -dy)
    tx0, ty0 = max(0, dx), max(0, dy)
    cw, ch = min(iw - sx0, w - tx0), min(ih - sy0, h - ty0)
    out[ty0:ty0 + ch, tx0:tx0 + cw] = img[sy0:sy0 + ch, sx0:sx0 + cw]
    return out, (dx, dy)


def fit_drawing(drawing: Drawing, size: tuple[int, int], mode: str = "resize") -> Drawing:
    """A copy of ``drawing`` made exactly ``size=(w, h)``, its lines following the pixels.

    ``mode="resize"`` scales the image (lines scale with it); ``"crop"`` centre-crops or pads it
    (lines shift by the offset).
    """
    if mode not in FIT_MODES:
        raise EditError(f"fit mode must be one of {FIT_MODES}, got {mode!r}")
    w, h = int(size[0]), int(size[1])
    ow, oh = drawing.size

    def fit(image, lines):
        lines = np.asarray(lines, np.float64).reshape(-1, 4)
        if mode == "resize":
            return resize_image(image, (w, h)), lines * np.array([w / ow, h / oh, w / ow, h / oh])
        image, (dx, dy) = crop_image(image, (w, h))
        return image, lines + np.array([dx, dy, dx, dy], np.float64)

    if drawing.layers:  # every layer, and the lines of those that have their own
        layers = []
        for ly in drawing.layers:
            img, own = fit(ly.image, ly.lines if ly.lines is not None else np.zeros((0, 4)))
            layers.append(replace(ly, image=img, lines=own if ly.lines is not None else None))
        return replace(Drawing.from_layers(drawing.name, layers, fit(drawing.image, drawing.lines)[1]), file=drawing.file)
    image, lines = fit(drawing.image, drawing.lines)
    return replace(drawing, image=image, lines=lines)


def size_mismatches(part: Part) -> list[int]:
    """Indices of drawings whose size is not the part's box size."""
    return [i for i, d in enumerate(part.drawings) if d.size != part.size]


# ----------------------------------------------------------------------------- names


def slug(text: str) -> str:
    """A file-safe lowercase name: letters, digits, ``-`` and ``_`` (``"drawing"`` if empty)."""
    s = re.sub(r"[^a-z0-9_-]+", "-", text.strip().lower()).strip("-_")
    return s or "drawing"


_ROLE_WORDS = {
    "heads": ("heads", "head", "face", "faces"),
    "eyes": ("eyes", "eye", "brows", "brow"),
    "mouth": ("mouths", "mouth", "lips", "lip"),
}


def name_from_path(path: str | Path, part: str | None = None) -> str:
    """Expression name from an image file name, without a leading word naming the part:
    ``"Mouth_AH.png"`` -> ``"ah"`` (part "mouth"), ``"eyes-open.png"`` -> ``"open"``."""
    name = slug(Path(path).stem)
    for word in _ROLE_WORDS.get(part or "", ()):
        for sep in ("-", "_"):
            if name.startswith(word + sep) and len(name) > len(word) + 1:
                return name[len(word) + 1:].strip("-_") or name
    return name


def sort_images(paths: Iterable[str | Path]) -> dict[str, list[Path]]:
    """Sort image files into ``heads``, ``eyes`` and ``mouth`` by a word in the file's name or its
    folder's name (head/face, eye/brow, mouth/lip); the rest go to ``"unsorted"``. Sorted by name."""
    out: dict[str, list[Path]] = {"heads": [], "eyes": [], "mouth": [], "unsorted": []}
    for p in sorted(Path(x) for x in paths):
        words = re.split(r"[^a-z]+", f"{p.parent.name} {p.stem}".lower())
        role = next((r for r, ws in _ROLE_WORDS.items() if any(w in ws for w in words)), "unsorted")
        out[role].append(p)
    return out


def unique_name(name: str, taken: Iterable[str]) -> str:
    """``name``, or ``name-2``, ``name-3``… if it is taken."""
    taken = set(taken)
    if name not in taken:
        return name
    k = 2
    while f"{name}-{k}" in taken:
        k += 1
    return f"{name}-{k}"


def drawing_file(part: str, name: str) -> str:
    """Manifest path of a drawing's PNG inside the art-set folder."""
    return f"{part}/{slug(name)}.png"


# ----------------------------------------------------------------------------- snapshots


def clone(artset: ArtSet) -> ArtSet:
    """A structural copy sharing the (never mutated) image and line arrays: cheap undo snapshots."""
    parts = {
        k: Part(p.name, tuple(p.box), [replace(d) for d in p.drawings]) for k, p in artset.parts.items()
    }
    return replace(
        artset,
        heads=list(artset.heads),
        head_files=list(artset.head_files),
        parts=parts,
        extra=copy.deepcopy(artset.extra),
    )


def same_artset(a: ArtSet, b: ArtSet) -> bool:
    """True when two art sets hold exactly the same manifest fields, pixels and lines."""
    if (a.name, a.author, tuple(a.canvas), tuple(map(float, a.pivot)), list(a.head_files), a.extra) != (
        b.name, b.author, tuple(b.canvas), tuple(map(float, b.pivot)), list(b.head_files), b.extra
    ):
        return False
    if len(a.heads) != len(b.heads) or any(not np.array_equal(x, y) for x, y in zip(a.heads, b.heads)):
        return False
    if set(a.parts) != set(b.parts):
        return False
    for k in a.parts:
        p, q = a.parts[k], b.parts[k]
        if tuple(p.box) != tuple(q.box) or len(p.drawings) != len(q.drawings):
            return False
        for d, e in zip(p.drawings, q.drawings):
            if d.name != e.name or d.file != e.file:
                return False
            if not np.array_equal(d.image, e.image):
                return False
            if not np.array_equal(np.asarray(d.lines).reshape(-1, 4), np.asarray(e.lines).reshape(-1, 4)):
                return False
    return True


# ----------------------------------------------------------------------------- new character


def default_box(canvas: tuple[int, int], part: str, size: tuple[int, int]) -> tuple[int, int, int, int]:
    """Where a part goes on a blank head: eyes centred at 40 % height, mouth at 72 %.

    ``size`` is the drawings' size, shrunk (keeping aspect) to fit 80 % of the canvas width and
    35 % of its height.
    """
    cw, ch = int(canvas[0]), int(canvas[1])
    w, h = max(1, int(size[0])), max(1, int(size[1]))
    s = min(1.0, 0.8 * cw / w, 0.35 * ch / h)
    w, h = max(1, int(round(w * s))), max(1, int(round(h * s)))
    cy = 0.40 * ch if part == "eyes" else 0.72 * ch
    x = int(round(cw / 2 - w / 2))
    y = int(round(min(max(cy - h / 2, 0), ch - h)))
    return (x, y, w, h)


def new_artset(
    name: str,
    heads: Sequence[np.ndarray],
    eyes: Sequence[tuple[str, np.ndarray]] = (),
    mouths: Sequence[tuple[str, np.ndarray]] = (),
    *,
    author: str = "",
    boxes: dict[str, tuple[int, int, int, int]] | None = None,
    fit: str = "resize",
) -> ArtSet:
    """A new character from images: the first head sets the canvas (others are resized to it).

    Each part's box defaults to :func:`default_box` sized from its first drawing; drawings of
    another size are fitted with ``fit`` ("resize" or "crop"). Drawings start with no lines.
    """
    if not heads:
        raise EditError("a character needs at least one head image")
    first = as_rgba(heads[0])
    canvas = (int(first.shape[1]), int(first.shape[0]))
    art = ArtSet(
        name=name.strip() or "Untitled",
        canvas=canvas,
        pivot=(canvas[0] / 2.0, round(canvas[1] * 0.6, 1)),
        heads=[],
        parts={},
        author=author,
        head_files=[],
        extra={},
    )
    for h in heads:
        add_head(art, h)
    boxes = dict(boxes or {})
    for pname, items in (("eyes", eyes), ("mouth", mouths)):
        if pname in boxes:
            box = tuple(int(v) for v in boxes[pname])
        elif items:
            img = as_rgba(items[0][1])
            box = default_box(canvas, pname, (img.shape[1], img.shape[0]))
        else:
            box = default_box(canvas, pname, (canvas[0] // 3, canvas[1] // 6))
        art.parts[pname] = Part(pname, box, [])
        for dname, img in items:
            add_drawing(art, pname, dname, img, fit=fit)
    return art


def add_head(artset: ArtSet, image: np.ndarray, fit: str = "resize") -> int:
    """Append a head (fitted to the canvas); returns its index."""
    img = as_rgba(image)
    if (img.shape[1], img.shape[0]) != tuple(artset.canvas):
        if fit == "resize":
            img = resize_image(img, artset.canvas)
        else:
            img, _ = crop_image(img, artset.canvas)
    artset.heads.append(img)
    artset.head_files.append(_free_head_file(set(artset.head_files)))
    return len(artset.heads) - 1


def _free_head_file(taken: set[str]) -> str:
    k = 1
    while f"head-{k}.png" in taken:
        k += 1
    return f"head-{k}.png"


def remove_head(artset: ArtSet, index: int) -> None:
    """Remove head ``index`` (the last head cannot be removed)."""
    if len(artset.heads) <= 1:
        raise EditError("a character needs at least one head")
    del artset.heads[index]
    del artset.head_files[index]


def set_head(artset: ArtSet, index: int, image: np.ndarray) -> None:
    """Replace head ``index``'s pixels (e.g. after painting its mask)."""
    img = as_rgba(image)
    if (img.shape[1], img.shape[0]) != tuple(artset.canvas):
        raise EditError(f"head must be {artset.canvas[0]}x{artset.canvas[1]}, got {img.shape[1]}x{img.shape[0]}")
    artset.heads[index] = img


def add_drawing(artset: ArtSet, part: str, name: str, image: np.ndarray, fit: str = "resize") -> int:
    """Append a drawing to ``part``, fitted to the box; returns its index.

    It gets a copy of the part's lines (from the first drawing) marked unplaced, so line counts
    stay equal.
    """
    p = artset.parts[part]
    name = unique_name(slug(name), p.names())
    d = Drawing(name=name, image=as_rgba(image), lines=np.zeros((0, 4)), file="")
    if d.size != p.size:
        d = fit_drawing(d, p.size, fit)
    d.file = unique_name(drawing_file(part, name), [e.file for e in p.drawings])
    if p.drawings:
        d.lines = np.array(p.drawings[0].lines, np.float64).reshape(-1, 4)
        _set_unplaced(artset, part, name, range(len(d.lines)))
    else:
        d.lines = np.zeros((0, 4))
    p.drawings.append(d)
    return len(p.drawings) - 1


def remove_drawing(artset: ArtSet, part: str, index: int) -> None:
    p = artset.parts[part]
    name = p.drawings[index].name
    del p.drawings[index]
    _unplaced_map(artset, part).pop(name, None)
    _tidy_unplaced(artset)


def rename_drawing(artset: ArtSet, part: str, index: int, new_name: str) -> str:
    """Rename a drawing (and its PNG path); returns the name actually used (made unique)."""
    p = artset.parts[part]
    d = p.drawings[index]
    name = unique_name(slug(new_name), [e.name for i, e in enumerate(p.drawings) if i != index])
    marks = _unplaced_map(artset, part).pop(d.name, None)
    p.drawings[index] = replace(
        d, name=name,
        file=unique_name(drawing_file(part, name), [e.file for i, e in enumerate(p.drawings) if i != index]),
    )
    if marks:
        _unplaced_map(artset, part)[name] = marks
    return name


def replace_drawing_image(artset: ArtSet, part: str, index: int, image: np.ndarray, fit: str = "resize") -> None:
    """Swap a drawing's pixels (fitted to the box), keeping its lines."""
    p = artset.parts[part]
    d = p.drawings[index]
    if d.layers:
        raise EditError(f"{part} drawing {d.name!r} is drawn in layers ({', '.join(ly.name for ly in d.layers)}); "
                        f"replace its layer files instead (see art_sets/FORMAT.md)")
    nd = Drawing(d.name, as_rgba(image), np.zeros((0, 4)), d.file)
    if nd.size != p.size:
        nd = fit_drawing(nd, p.size, fit)
    p.drawings[index] = replace(d, image=nd.image)


def head_mismatches(artset: ArtSet) -> list[int]:
    """Indices of heads whose size is not the canvas size."""
    return [i for i, h in enumerate(artset.heads) if (h.shape[1], h.shape[0]) != tuple(artset.canvas)]


def fit_heads(artset: ArtSet, mode: str = "resize") -> None:
    """Make every head the canvas size (``mode`` "resize" or "crop")."""
    if mode not in FIT_MODES:
        raise EditError(f"fit mode must be one of {FIT_MODES}, got {mode!r}")
    for i in head_mismatches(artset):
        h = artset.heads[i]
        artset.heads[i] = resize_image(h, artset.canvas) if mode == "resize" else crop_image(h, artset.canvas)[0]


def fit_part(artset: ArtSet, part: str, mode: str = "resize", indices: Iterable[int] | None = None) -> None:
    """Make the given (default: all mismatching) drawings of ``part`` the box's size."""
    p = artset.parts[part]
    for i in list(size_mismatches(p) if indices is None else indices):
        p.drawings[i] = fit_drawing(p.drawings[i], p.size, mode)


def set_box(artset: ArtSet, part: str, box: Sequence[float], mode: str = "resize") -> None:
    """Move / resize a part's box on the canvas (clamped to it); drawings follow a size change."""
    cw, ch = artset.canvas
    x, y, w, h = (int(round(v)) for v in box)
    w, h = max(4, min(w, cw)), max(4, min(h, ch))
    x, y = min(max(x, 0), cw - w), min(max(y, 0), ch - h)
    p = artset.parts[part]
    resized = (w, h) != p.size
    p.box = (x, y, w, h)
    if resized:
        fit_part(artset, part, mode, indices=range(len(p.drawings)))


# ----------------------------------------------------------------------------- control lines


_LINE_COLOURS = (
    (230, 25, 75), (0, 130, 200), (60, 180, 75), (245, 130, 48), (145, 30, 180), (70, 200, 220),
    (240, 50, 230), (150, 190, 20), (170, 110, 40), (0, 0, 128), (0, 128, 128), (128, 0, 0),
)


def line_color(i: int) -> tuple[int, int, int]:
    """The RGB colour of line ``i`` (the same in every drawing): twelve well-separated colours,
    then golden-angle hues."""
    if 0 <= i < len(_LINE_COLOURS):
        return _LINE_COLOURS[i]
    h = (i * 0.618033988749895 + 0.05) % 1.0
    r, g, b = colorsys.hsv_to_rgb(h, 0.85, 0.95 if i % 2 == 0 else 0.8)
    return int(r * 255), int(g * 255), int(b * 255)


def _editor_extra(artset: ArtSet) -> dict:
    return artset.extra.setdefault("editor", {})


def _unplaced_map(artset: ArtSet, part: str) -> dict[str, list[int]]:
    return _editor_extra(artset).setdefault("unplaced", {}).setdefault(part, {})


def _tidy_unplaced(artset: ArtSet) -> None:
    ed = artset.extra.get("editor")
    if not ed:
        return
    un = ed.get("unplaced", {})
    for part in list(un):
        for name in list(un[part]):
            if not un[part][name]:
                del un[part][name]
        if not un[part]:
            del un[part]
    if not un:
        ed.pop("unplaced", None)
    if not ed:
        del artset.extra["editor"]


def _set_unplaced(artset: ArtSet, part: str, name: str, indices: Iterable[int], value: bool = True) -> None:
    m = _unplaced_map(artset, part)
    cur = set(m.get(name, []))
    cur = cur | set(int(i) for i in indices) if value else cur - set(int(i) for i in indices)
    m[name] = sorted(cur)
    _tidy_unplaced(artset)


def unplaced(artset: ArtSet, part: str, drawing: int) -> set[int]:
    """Line indices of a drawing that were copied in but not yet moved onto its feature."""
    name = artset.parts[part].drawings[drawing].name
    return set(artset.extra.get("editor", {}).get("unplaced", {}).get(part, {}).get(name, []))


def line_count(part: Part) -> int:
    """The largest number of lines any drawing of the part has."""
    return max((len(np.asarray(d.lines).reshape(-1, 4)) for d in part.drawings), default=0)


def missing_lines(artset: ArtSet, part: str) -> dict[int, list[str]]:
    """For each line index, the names of drawings that miss it (no such line, or still unplaced)."""
    p = artset.parts[part]
    n = line_count(p)
    out: dict[int, list[str]] = {i: [] for i in range(n)}
    for di, d in enumerate(p.drawings):
        have = len(np.asarray(d.lines).reshape(-1, 4))
        un = unplaced(artset, part, di)
        for i in range(n):
            if i >= have or i in un:
                out[i].append(d.name)
    return out


def make_consistent(artset: ArtSet, part: str) -> None:
    """Pad drawings that have fewer lines than the part with copies from the fullest drawing (unplaced)."""
    p = artset.parts[part]
    n = line_count(p)
    if n == 0:
        return
    ref = max(p.drawings, key=lambda d: len(np.asarray(d.lines).reshape(-1, 4)))
    ref_lines = np.asarray(ref.lines, np.float64).reshape(-1, 4)
    for d in p.drawings:
        lines = np.asarray(d.lines, np.float64).reshape(-1, 4)
        if len(lines) < n:
            extra = _scale_lines(ref_lines[len(lines):], ref.size, d.size)
            d.lines = np.vstack([lines, extra])
            _set_unplaced(artset, part, d.name, range(len(lines), n))


def _scale_lines(lines: np.ndarray, src: tuple[int, int], dst: tuple[int, int]) -> np.ndarray:
    sx, sy = dst[0] / max(src[0], 1), dst[1] / max(src[1], 1)
    return np.asarray(lines, np.float64).reshape(-1, 4) * np.array([sx, sy, sx, sy])


def clamp_line(line: Sequence[float], size: tuple[int, int]) -> np.ndarray:
    """A line with both endpoints kept inside a drawing of ``size=(w, h)``."""
    w, h = size
    ln = np.asarray(line, np.float64).reshape(4).copy()
    ln[0::2] = np.clip(ln[0::2], 0.0, w - 1.0)
    ln[1::2] = np.clip(ln[1::2], 0.0, h - 1.0)
    return ln


def add_line(artset: ArtSet, part: str, drawing: int, line: Sequence[float]) -> int:
    """Add a line to one drawing; every other drawing of the part gets a copy, marked unplaced.

    Returns the new line's index. Lines shorter than one pixel are refused.
    """
    p = artset.parts[part]
    d = p.drawings[drawing]
    ln = clamp_line(line, d.size)
    if np.hypot(ln[2] - ln[0], ln[3] - ln[1]) < 1.0:
        raise EditError("a control line must be at least one pixel long")
    make_consistent(artset, part)
    index = line_count(p)
    for j, e in enumerate(p.drawings):
        row = ln if j == drawing else _scale_lines(ln, d.size, e.size)[0]
        e.lines = np.vstack([np.asarray(e.lines, np.float64).reshape(-1, 4), row[None, :]])
        if j != drawing:
            _set_unplaced(artset, part, e.name, [index])
    return index


def move_line(artset: ArtSet, part: str, drawing: int, index: int, line: Sequence[float]) -> None:
    """Set line ``index`` of one drawing (clamped into the drawing); it counts as placed there."""
    d = artset.parts[part].drawings[drawing]
    lines = np.array(d.lines, np.float64).reshape(-1, 4)
    lines[index] = clamp_line(line, d.size)
    d.lines = lines
    _set_unplaced(artset, part, d.name, [index], value=False)


def mark_placed(artset: ArtSet, part: str, drawing: int, indices: Iterable[int] | None = None) -> None:
    """Accept copied lines as they are (default: all of the drawing's lines)."""
    d = artset.parts[part].drawings[drawing]
    if indices is None:
        indices = range(len(np.asarray(d.lines).reshape(-1, 4)))
    _set_unplaced(artset, part, d.name, indices, value=False)


def delete_line(artset: ArtSet, part: str, index: int) -> None:
    """Remove line ``index`` from every drawing of the part (later lines move down by one)."""
    p = artset.parts[part]
    for d in p.drawings:
        lines = np.asarray(d.lines, np.float64).reshape(-1, 4)
        if index < len(lines):
            d.lines = np.delete(lines, index, axis=0)
        m = _unplaced_map(artset, part)
        if d.name in m:
            m[d.name] = sorted(i if i < index else i - 1 for i in m[d.name] if i != index)
    _tidy_unplaced(artset)


def swap_direction(artset: ArtSet, part: str, drawing: int, index: int) -> None:
    """Reverse line ``index`` in one drawing (start and end swapped)."""
    d = artset.parts[part].drawings[drawing]
    ln = np.asarray(d.lines, np.float64).reshape(-1, 4)[index]
    move_line(artset, part, drawing, index, [ln[2], ln[3], ln[0], ln[1]])


def copy_lines(artset: ArtSet, part: str, src: int, dst: int) -> None:
    """Replace ``dst``'s lines with ``src``'s (scaled if sizes differ), all marked unplaced.

    If ``src`` has more lines than the part's other drawings, those get the extra lines too.
    """
    p = artset.parts[part]
    s, d = p.drawings[src], p.drawings[dst]
    d.lines = _scale_lines(s.lines, s.size, d.size)
    _unplaced_map(artset, part)[d.name] = []
    _set_unplaced(artset, part, d.name, range(len(d.lines)))
    make_consistent(artset, part)


def snap_point(
    point: Sequence[float],
    lines: np.ndarray,
    radius: float,
    exclude: tuple[int, int] | None = None,
) -> tuple[tuple[float, float], tuple[int, int] | None]:
    """Snap ``point`` to the nearest line endpoint within ``radius`` pixels.

    ``exclude=(line, end)`` skips the endpoint being dragged (``end`` 0 = start, 1 = end).
    Returns the (possibly unchanged) point and the ``(line, end)`` it snapped to, or None.
    """
    pts = np.asarray(lines, np.float64).reshape(-1, 4).reshape(-1, 2)
    x, y = float(point[0]), float(point[1])
    if len(pts) == 0:
        return (x, y), None
    d = np.hypot(pts[:, 0] - x, pts[:, 1] - y)
    if exclude is not None:
        d[exclude[0] * 2 + exclude[1]] = np.inf
    k = int(np.argmin(d))
    if d[k] <= radius:
        return (float(pts[k, 0]), float(pts[k, 1])), (k // 2, k % 2)
    return (x, y), None


def hit_line(point: Sequence[float], lines: np.ndarray, radius: float) -> tuple[int, int] | None:
    """What a click at ``point`` grabs: ``(line, end)`` for an endpoint (end 0/1) or ``(line, -1)``
    for the body of a line, within ``radius`` pixels; None if nothing is near. Endpoints win."""
    ln = np.asarray(lines, np.float64).reshape(-1, 4)
    if len(ln) == 0:
        return None
    p = np.asarray(point, np.float64)
    ends = ln.reshape(-1, 2)
    de = np.hypot(*(ends - p).T)
    k = int(np.argmin(de))
    if de[k] <= radius:
        return k // 2, k % 2
    a, b = ln[:, :2], ln[:, 2:]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12), 0, 1)
    dl = np.hypot(*(a + t[:, None] * ab - p).T)
    k = int(np.argmin(dl))
    if dl[k] <= radius:
        return k, -1
    return None


# ----------------------------------------------------------------------------- masks


def hole_mask(
    canvas: tuple[int, int], boxes: Iterable[Sequence[int]], radius: float, margin: float = HOLE_MARGIN
) -> np.ndarray:
    """How much of the head to cut away for the parts: float32 ``(h, w)``, 1 = fully open.

    Each box becomes a rounded rectangle: closed on the ``margin`` pixels along the box edge,
    then fading in smoothly over ``radius`` pixels to fully open, so the rectangle of a drawing
    never shows around the face.
    """
    w, h = int(canvas[0]), int(canvas[1])
    r = max(float(radius), 0.0)
    m = max(float(margin), 0.0)
    xs = np.arange(w, dtype=np.float32) + 0.5
    ys = np.arange(h, dtype=np.float32) + 0.5
    out = np.zeros((h, w), np.float32)
    for obx, oby, obw, obh in boxes:
        bx, by = obx + m, oby + m
        bw, bh = max(obw - 2 * m, 0.0), max(obh - 2 * m, 0.0)
        if bw <= 0 or bh <= 0:
            continue
        rr = min(r, bw / 2.0, bh / 2.0)
        x0, x1 = bx + rr, bx + bw - rr
        y0, y1 = by + rr, by + bh - rr
        dx = np.maximum(np.maximum(x0 - xs, xs - x1), 0.0)
        dy = np.maximum(np.maximum(y0 - ys, ys - y1), 0.0)
        d = np.sqrt(dx[None, :] ** 2 + dy[:, None] ** 2)
        if rr > 1e-3:
            t = np.clip(1.0 - d / rr, 0.0, 1.0)
            v = t * t * (3.0 - 2.0 * t)
        else:
            v = (d <= 0).astype(np.float32)
        inside = ((xs[None, :] >= bx) & (xs[None, :] <= bx + bw)) & ((ys[:, None] >= by) & (ys[:, None] <= by + bh))
        out = np.maximum(out, np.where(inside, v, 0.0).astype(np.float32))
    return out


def cut_holes(head: np.ndarray, hole: np.ndarray) -> np.ndarray:
    """A new head whose alpha is lowered by ``hole`` (1 = transparent); colour is kept."""
    out = as_rgba(head).copy()
    a = out[:, :, 3].astype(np.float32) * (1.0 - np.clip(hole, 0.0, 1.0))
    out[:, :, 3] = np.round(a).astype(np.uint8)
    return out


def part_holes(artset: ArtSet, radius: float) -> np.ndarray:
    """:func:`hole_mask` for all of the art set's part boxes."""
    return hole_mask(artset.canvas, [p.box for p in artset.parts.values()], radius)


def make_holes(artset: ArtSet, radius: float, base_heads: Sequence[np.ndarray] | None = None) -> None:
    """Cut feathered holes for every part box into every head.

    ``base_heads`` (default: the current heads) are the heads before cutting, so the editor can
    try other radii without the holes adding up.
    """
    hole = part_holes(artset, radius)
    bases = list(base_heads) if base_heads is not None else list(artset.heads)
    artset.heads = [cut_holes(h, hole) for h in bases]


def brush(shape: tuple[int, int], center: Sequence[float], radius: float, hardness: float = 0.5) -> np.ndarray:
    """A round soft brush stamp as float32 ``(h, w)`` weights in 0..1 over an image of ``shape``.

    Full strength inside ``hardness * radius``, smooth fall-off to 0 at ``radius``.
    """
    h, w = int(shape[0]), int(shape[1])
    cx, cy = float(center[0]), float(center[1])
    r = max(float(radius), 0.5)
    inner = min(max(hardness, 0.0), 1.0) * r
    ys = np.arange(h, dtype=np.float32)[:, None] + 0.5
    xs = np.arange(w, dtype=np.float32)[None, :] + 0.5
    d = np.sqrt((xs - cx) ** 2 + (ys - cy) ** 2)
    t = np.clip((r - d) / max(r - inner, 1e-6), 0.0, 1.0)
    return (t * t * (3.0 - 2.0 * t)).astype(np.float32)


def paint_alpha(
    head: np.ndarray,
    points: Sequence[Sequence[float]],
    radius: float,
    *,
    erase: bool = True,
    hardness: float = 0.5,
    strength: float = 1.0,
) -> np.ndarray:
    """A new head with a brush stroke through ``points`` painted into its alpha.

    ``erase=True`` opens the head (alpha toward 0, a hole), ``False`` closes it (toward 255).
    Stamps are spaced a quarter radius apart along the stroke; each pixel takes the strongest
    stamp, so a slow and a fast stroke give the same result.
    """
    img = as_rgba(head)
    h, w = img.shape[:2]
    pts = np.asarray(points, np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return img.copy()
    step = max(radius / 4.0, 0.5)
    dense = [pts[0]]
    for a, b in zip(pts[:-1], pts[1:]):
        n = max(1, int(np.ceil(np.hypot(*(b - a)) / step)))
        dense.extend(a + (b - a) * (k / n) for k in range(1, n + 1))
    x0 = int(max(np.floor(min(p[0] for p in dense) - radius - 1), 0))
    y0 = int(max(np.floor(min(p[1] for p in dense) - radius - 1), 0))
    x1 = int(min(np.ceil(max(p[0] for p in dense) + radius + 1), w))
    y1 = int(min(np.ceil(max(p[1] for p in dense) + radius + 1), h))
    out = img.copy()
    if x1 <= x0 or y1 <= y0:
        return out
    wgt = np.zeros((y1 - y0, x1 - x0), np.float32)
    rr = int(np.ceil(radius)) + 1
    for p in dense:  # each stamp only touches its own small window
        lx0 = max(int(np.floor(p[0])) - rr - x0, 0)
        ly0 = max(int(np.floor(p[1])) - rr - y0, 0)
        lx1 = min(int(np.ceil(p[0])) + rr + 1 - x0, wgt.shape[1])
        ly1 = min(int(np.ceil(p[1])) + rr + 1 - y0, wgt.shape[0])
        if lx1 <= lx0 or ly1 <= ly0:
            continue
        win = wgt[ly0:ly1, lx0:lx1]
        np.maximum(win, brush(win.shape, (p[0] - x0 - lx0, p[1] - y0 - ly0), radius, hardness), out=win)
    wgt *= float(np.clip(strength, 0.0, 1.0))
    a = out[y0:y1, x0:x1, 3].astype(np.float32)
    target = 0.0 if erase else 255.0
    out[y0:y1, x0:x1, 3] = np.round(a + (target - a) * wgt).astype(np.uint8)
    return out


# ----------------------------------------------------------------------------- starter lines


def ink_mask(image: np.ndarray) -> np.ndarray:
    """Pixels that are drawn on, as a bool ``(h, w)`` mask.

    The paper is estimated from the image border (its median colour, or transparency when the
    border is mostly transparent); ink is whatever is opaque and clearly differs from it, the
    threshold scaling with how noisy the paper is (texture, scanner grain).
    """
    img = as_rgba(image)
    h, w = img.shape[:2]
    b = max(1, min(h, w) // 20)
    ring = np.concatenate([img[:b].reshape(-1, 4), img[-b:].reshape(-1, 4),
                           img[:, :b].reshape(-1, 4), img[:, -b:].reshape(-1, 4)]).astype(np.float32)
    opaque = img[:, :, 3] > 32
    if np.mean(ring[:, 3] > 32) < 0.5:  # drawn on transparency: every opaque pixel is ink
        return opaque
    paper = np.median(ring[ring[:, 3] > 32, :3], axis=0)
    spread = np.percentile(np.linalg.norm(ring[ring[:, 3] > 32, :3] - paper, axis=1), 95)
    dist = np.linalg.norm(img[:, :, :3].astype(np.float32) - paper, axis=2)
    return opaque & (dist > max(40.0, 2.0 * float(spread)))


def ink_box(mask: np.ndarray, trim: float = 0.5) -> tuple[float, float, float, float] | None:
    """``(x0, y0, x1, y1)`` of the ink in ``mask``, ignoring ``trim`` percent of stray pixels on
    each side; None when there is (almost) no ink."""
    ys, xs = np.nonzero(mask)
    if len(xs) < 8:
        return None
    x0, x1 = np.percentile(xs, [trim, 100 - trim])
    y0, y1 = np.percentile(ys, [trim, 100 - trim])
    return float(x0), float(y0), float(x1) + 1.0, float(y1) + 1.0


def suggest_lines(image: np.ndarray, part: str) -> np.ndarray:
    """Starter control lines for a drawing: the edges of its ink's bounding box.

    For each feature (the mouth; each eye with its brow, left and right half of an eyes
    drawing) four lines: top and bottom (left to right), left and right (top to bottom). Every
    drawing of a part gets the same lines in the same order, so a morph already moves the
    features' extents instead of cross-fading them; the artist then refines them.
    """
    mask = ink_mask(image)
    h, w = mask.shape
    regions = [(0, w // 2), (w // 2, w)] if part == "eyes" else [(0, w)]
    out = []
    for a, b in regions:
        box = ink_box(mask[:, a:b])
        if box is None:  # blank half: lines around its middle so counts still match
            cx, cy = (a + b) / 2.0, h / 2.0
            x0, y0, x1, y1 = cx - (b - a) / 4.0, cy - h / 8.0, cx + (b - a) / 4.0, cy + h / 8.0
        else:
            x0, y0, x1, y1 = box[0] + a, box[1], box[2] + a, box[3]
        y1 = max(y1, y0 + 1.0)
        x1 = max(x1, x0 + 1.0)
        out += [[x0, y0, x1, y0], [x0, y1, x1, y1], [x0, y0, x0, y1], [x1, y0, x1, y1]]
    lines = np.array(out, np.float64)
    lines[:, 0::2] = np.clip(lines[:, 0::2], 0, w - 1)
    lines[:, 1::2] = np.clip(lines[:, 1::2], 0, h - 1)
    return lines


def add_starter_lines(artset: ArtSet, part: str) -> int:
    """Append :func:`suggest_lines` to every drawing of ``part`` (placed: each is its own);
    returns the number of lines added per drawing."""
    p = artset.parts[part]
    if not p.drawings:
        raise EditError(f"{part}: add drawings first")
    make_consistent(artset, part)
    n = 0
    for d in p.drawings:
        new = suggest_lines(d.image, part)
        n = len(new)
        d.lines = np.vstack([np.asarray(d.lines, np.float64).reshape(-1, 4), new])
    return n


# ----------------------------------------------------------------------------- previews


def over(dst: np.ndarray, src: np.ndarray, x: int = 0, y: int = 0) -> np.ndarray:
    """Straight-alpha ``src`` over straight-alpha ``dst`` at ``(x, y)``; returns a new array."""
    out = as_rgba(dst).astype(np.float32)
    s = as_rgba(src).astype(np.float32)
    H, W = out.shape[:2]
    h, w = s.shape[:2]
    sx0, sy0 = max(0, -x), max(0, -y)
    tx0, ty0 = max(0, x), max(0, y)
    cw, ch = min(w - sx0, W - tx0), min(h - sy0, H - ty0)
    if cw <= 0 or ch <= 0:
        return out.round().astype(np.uint8)
    S = s[sy0:sy0 + ch, sx0:sx0 + cw]
    D = out[ty0:ty0 + ch, tx0:tx0 + cw]
    sa, da = S[:, :, 3:4] / 255.0, D[:, :, 3:4] / 255.0
    oa = sa + da * (1.0 - sa)
    rgb = (S[:, :, :3] * sa + D[:, :, :3] * da * (1.0 - sa)) / np.maximum(oa, 1e-6)
    out[ty0:ty0 + ch, tx0:tx0 + cw] = np.concatenate([rgb, oa * 255.0], axis=2)
    return np.clip(out, 0, 255).round().astype(np.uint8)


def compose_preview(
    artset: ArtSet,
    parts: dict[str, np.ndarray] | None = None,
    head: int = 0,
    background: tuple[int, int, int] = (255, 255, 255),
) -> np.ndarray:
    """The character as straight RGBA: parts (default: each part's first drawing) under the head.

    ``parts`` maps part name to a straight RGBA image of that part's box size.
    """
    cw, ch = artset.canvas
    out = np.zeros((ch, cw, 4), np.uint8)
    out[:, :, :3] = background
    out[:, :, 3] = 255
    for name, p in artset.parts.items():
        img = (parts or {}).get(name)
        if img is None and p.drawings:
            img = p.drawings[0].image
        if img is not None:
            out = over(out, img, int(p.box[0]), int(p.box[1]))
    if artset.heads:
        out = over(out, artset.heads[head % len(artset.heads)])
    return out


def cross_dissolve(images: Sequence[np.ndarray], weights: Sequence[float]) -> np.ndarray:
    """Weighted average of straight RGBA images (what a morph should beat); images of another
    size than the first are resized to it."""
    h0, w0 = np.asarray(images[0]).shape[:2]
    acc = np.zeros((h0, w0, 4), np.float32)
    wsum = float(sum(weights)) or 1.0
    for img, w in zip(images, weights):
        img = as_rgba(img)
        if img.shape[:2] != (h0, w0):
            img = resize_image(img, (w0, h0))
        a = img.astype(np.float32)
        acc[:, :, :3] += a[:, :, :3] * (a[:, :, 3:4] / 255.0) * w
        acc[:, :, 3] += a[:, :, 3] * w
    acc /= wsum
    al = acc[:, :, 3:4]
    rgb = np.where(al > 0.5, acc[:, :, :3] / np.maximum(al / 255.0, 1e-6), 0.0)
    return np.dstack([np.clip(rgb, 0, 255), al]).round().astype(np.uint8)


def triangle_weights(point: Sequence[float], corners: Sequence[Sequence[float]]) -> np.ndarray:
    """Barycentric weights (3,) of ``point`` in the triangle ``corners``, clamped to the triangle."""
    (ax, ay), (bx, by), (cx, cy) = corners
    px, py = point
    det = (by - cy) * (ax - cx) + (cx - bx) * (ay - cy)
    if abs(det) < 1e-12:
        return np.array([1.0, 0.0, 0.0])
    w1 = ((by - cy) * (px - cx) + (cx - bx) * (py - cy)) / det
    w2 = ((cy - ay) * (px - cx) + (ax - cx) * (py - cy)) / det
    w = np.clip(np.array([w1, w2, 1.0 - w1 - w2]), 0.0, None)
    s = w.sum()
    return w / s if s > 0 else np.array([1.0, 0.0, 0.0])



# ----------------------------------------------------------------------------- saving


def _on_disk(folder: Path) -> tuple[set[str], dict[str, np.ndarray | None]]:
    """Files the folder's current manifest names, and a lazy cache for their pixels."""
    from art_sets.io import MANIFEST

    mf = folder / MANIFEST
    files: set[str] = set()
    if mf.is_file():
        try:
            data = json.loads(mf.read_text(encoding="utf-8"))
            files.update(str(f) for f in data.get("heads", []) if isinstance(f, str))
            for p in (data.get("parts") or {}).values():
                for d in (p or {}).get("drawings", []):
                    if isinstance(d, dict) and isinstance(d.get("image"), str):
                        files.add(d["image"])
        except (OSError, ValueError, AttributeError, TypeError):
            pass
    return files, {}


def _same_pixels(path: Path, image: np.ndarray, cache: dict) -> bool:
    key = str(path)
    if key not in cache:
        try:
            with Image.open(path) as im:
                cache[key] = np.asarray(im.convert("RGBA"), dtype=np.uint8)
        except (OSError, ValueError):
            cache[key] = None
    old = cache[key]
    return old is not None and old.shape == image.shape and np.array_equal(old, image)


def _alternate(rel: str) -> str:
    """``mouth/ah.png`` <-> ``mouth/ah.v2.png``: the other of two names a drawing's PNG can have."""
    p = Path(rel)
    stem = p.stem[:-3] if p.stem.endswith(".v2") else p.stem + ".v2"
    return str(p.with_name(stem + p.suffix)).replace("\\", "/")


def plan_save(artset: ArtSet, folder: str | Path) -> ArtSet:
    """A clone of ``artset`` whose image paths never overwrite a file the folder's current manifest
    uses with different pixels.

    An image whose pixels changed goes to a file the old manifest does not name, so a crash at
    any moment of ``save_artset`` leaves the old manifest with all of its old files intact.
    """
    folder = Path(folder)
    old_files, cache = _on_disk(folder)
    art = clone(artset)
    used: set[str] = set()

    def choose(rel: str, image: np.ndarray) -> str:
        cands = [rel, _alternate(rel)]
        for c in cands:  # unchanged file: keep it
            if c not in used and c in old_files and _same_pixels(folder / c, image, cache):
                return c
        for c in cands:
            if c not in used and c not in old_files:
                return c
        k = 3
        while True:
            p = Path(rel)
            c = str(p.with_name(f"{p.stem}.v{k}{p.suffix}"))
            if c not in used and c not in old_files:
                return c
            k += 1

    files = []
    for i, img in enumerate(art.heads):
        rel = art.head_files[i] if i < len(art.head_files) and art.head_files[i] else f"head-{i + 1}.png"
        rel = choose(rel, img)
        used.add(rel)
        files.append(rel)
    art.head_files = files
    for pname, p in art.parts.items():
        for d in p.drawings:
            d.file = choose(d.file or drawing_file(pname, d.name), d.image)
            used.add(d.file)
    return art


def save_safely(artset: ArtSet, folder: str | Path) -> ArtSet:
    """Save with ``art_sets.io.save_artset`` so that a crash mid-save never spoils the old set.

    Returns the saved clone (its image paths may differ from ``artset``'s); PNGs the old manifest
    named and the new one does not are removed afterwards.
    """
    from art_sets.io import save_artset

    folder = Path(folder)
    old_files, _ = _on_disk(folder)
    art = plan_save(artset, folder)
    save_artset(art, folder)
    keep = set(art.head_files) | {d.file for p in art.parts.values() for d in p.drawings}
    for rel in old_files - keep:
        target = folder / rel
        try:
            target.resolve().relative_to(folder.resolve())
        except (ValueError, OSError):
            continue
        if target.suffix.lower() == ".png" and target.is_file():
            try:
                target.unlink()
            except OSError:
                pass
    art.path = folder
    return art
