"""Reading and writing art-set folders (``artset.json`` + PNGs).

The manifest format is described for artists in ``art_sets/FORMAT.md``. Images are RGBA with
straight alpha, loaded with Pillow. Format 1 is read exactly as it always was (a ``body`` key
there is just an extra key); format 2 adds layered drawings and the body. Every image's header is checked (size, pixel count) before any
pixels are decoded, so a decompression bomb is refused without being loaded. Image paths are
relative to the folder and may never leave it (no absolute paths, no ``..``, no symlink out).

:func:`load_artset` raises :class:`ArtSetError` with a one-line message naming the file;
:func:`scan` (used by ``art_sets.validate``) collects every problem instead of stopping.
"""

from __future__ import annotations

import io as _io
import json
import math
import os
import reprlib
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from PIL import Image

from art_sets import atomic_file, safe_json
from art_sets.model import (FORMAT_VERSION, MAX_BODY_ROLL, PART_NAMES, READ_FORMATS, ArtSet, Body, Drawing, Layer,
                            Part, flatten)

MANIFEST = "artset.json"
MIN_DRAWINGS = 3  # a part needs a triangle of drawings for the barycentric morph
MIN_LINE_LENGTH = 1.0  # px; shorter control lines make the Beier-Neely field singular
MAX_MANIFEST_BYTES = 8 * 1024 * 1024

# Limits that keep loading a character a matter of seconds and a few hundred MB. Building a
# part's morph tables costs time and memory in proportion to drawings² × lines (16 drawings of
# 12 lines: about 2–3 s for both parts on one core); images cost their pixels several times over.
MAX_SIDE = 1024
"""Largest canvas (and head image) side, px."""
MAX_PIXELS = MAX_SIDE * MAX_SIDE
"""Largest head image, px; images are refused from their header, before decoding."""
MAX_DRAWING_PIXELS = 512 * 512
"""Largest part box, and so the largest eye or mouth drawing, px."""
MAX_HEADS = 8
MAX_DRAWINGS = 16
"""Drawings per part."""
MAX_LINES = 12
"""Control lines per drawing."""
MAX_LAYERS = 8
"""Layers per drawing (format 2)."""
MAX_LAYER_LINES = 48
"""Control lines of one layered drawing, or of one layer's own (format 2)."""
MAX_LINE_WORK = MAX_DRAWINGS * (MAX_DRAWINGS - 1) * MAX_LINES
"""Of a layered part: drawings × (drawings − 1) × lines, summed over its distinct sets of control
lines — what building its morph tables costs, held to what the single-picture limits allow."""
MAX_PATH_CHARS = 1024
"""Longest image path in a manifest (and 255 characters for one name in it)."""
MAX_TEXT = 4096
"""Longest name, author or drawing name."""
_KNOWN_KEYS = {"format", "name", "author", "canvas", "pivot", "heads", "parts"}
_KNOWN_KEYS_2 = _KNOWN_KEYS | {"body"}


class ArtSetError(Exception):
    """An art set that cannot be loaded; the message is one line and names the file."""


@dataclass(frozen=True)
class Problem:
    """One problem found in an art set: the file it concerns and what is wrong."""

    file: str
    message: str

    def __str__(self) -> str:
        return f"{self.file}: {self.message}"


def _folder_of(path: str | os.PathLike) -> Path:
    p = Path(path)
    return p.parent if p.name == MANIFEST or p.suffix.lower() == ".json" else p


class _Scan:
    """Reads a folder, collecting problems; keeps whatever loaded cleanly."""

    def __init__(self, folder: Path, strict_geometry: bool = True):
        self.folder = folder
        self.strict = strict_geometry
        self.problems: list[Problem] = []
        self.manifest_file = str(folder / MANIFEST)
        self.alpha_seen: dict[str, bool] = {}
        self.format = 1
        self.swept: set[Path] = set()

    def add(self, file: str, message: str) -> None:
        self.problems.append(Problem(file, message))

    # --- images ------------------------------------------------------------------------
    def safe_path(self, rel, where: str) -> Path | None:
        """Resolve a manifest image path inside the folder, or record why it is refused."""
        if not isinstance(rel, str) or not rel.strip():
            self.add(self.manifest_file, f"{where}: image path must be a non-empty string")
            return None
        shown = safe_json.show(rel)
        if len(rel) > MAX_PATH_CHARS or any(len(part) > 255 for part in rel.split("/")):
            self.add(self.manifest_file, f"{where}: image path {shown} is too long (at most {MAX_PATH_CHARS} characters, 255 per name)")
            return None
        if "\x00" in rel:
            self.add(self.manifest_file, f"{where}: image path {shown} contains a NUL character")
            return None
        if "\\" in rel or os.path.isabs(rel) or rel.startswith(("/", "~")) or ":" in rel.split("/")[0]:
            self.add(self.manifest_file, f"{where}: image path {shown} is absolute; it must be relative to the art-set folder")
            return None
        if ".." in Path(rel).parts:
            self.add(self.manifest_file, f"{where}: image path {shown} leaves the art-set folder")
            return None
        full = self.folder / rel
        try:
            full.resolve().relative_to(self.folder.resolve())
        except ValueError:
            self.add(self.manifest_file, f"{where}: image path {shown} leaves the art-set folder (symlink)")
            return None
        except (OSError, RuntimeError) as e:  # a symlink loop, a name the file system refuses
            self.add(self.manifest_file, f"{where}: image path {shown} cannot be followed ({_reason(e)})")
            return None
        return full

    def image(self, rel, where: str, max_pixels: int = MAX_PIXELS) -> np.ndarray | None:
        full = self.safe_path(rel, where)
        if full is None:
            return None
        name = str(full)
        try:
            is_file = full.is_file()
        except OSError as e:
            self.add(name, f"image cannot be opened ({_reason(e)}; named by {where})")
            return None
        if not is_file:
            self.add(name, f"missing image (named by {where})")
            return None
        if full.parent not in self.swept:
            self.swept.add(full.parent)
            atomic_file.sweep_temp(full.parent)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", Image.DecompressionBombWarning)
                with Image.open(full) as im:  # reads the header only
                    w, h = im.size
                    if im.format != "PNG":
                        self.add(name, f"not a PNG image ({im.format or 'unknown format'})")
                        return None
                    if w > MAX_SIDE or h > MAX_SIDE or w * h > max_pixels:
                        limit = f"{MAX_SIDE}x{MAX_SIDE}" if max_pixels >= MAX_PIXELS else f"{max_pixels:,}-pixel"
                        self.add(name, f"image is {w}x{h}, larger than the {limit} limit; refused without decoding")
                        return None
                    if w < 1 or h < 1:
                        self.add(name, f"image has no pixels ({w}x{h})")
                        return None
                    has_alpha = im.mode in ("RGBA", "LA", "PA") or "transparency" in im.info
                    arr = np.asarray(im.convert("RGBA"), dtype=np.uint8).copy()
        except (Image.DecompressionBombError, Image.DecompressionBombWarning):
            self.add(name, "image looks like a decompression bomb; refused")
            return None
        except (OSError, ValueError, SyntaxError) as e:
            self.add(name, f"unreadable PNG ({_one_line(e)})")
            return None
        self.alpha_seen[name] = has_alpha
        return arr

    # --- manifest ----------------------------------------------------------------------
    def run(self) -> ArtSet | None:
        mf = self.folder / MANIFEST
        if not self.folder.is_dir():
            self.add(str(self.folder), "not a folder")
            return None
        if not mf.is_file():
            self.add(self.manifest_file, "missing manifest (artset.json)")
            return None
        self.swept.add(self.folder)
        atomic_file.sweep_temp(self.folder)
        try:
            data = safe_json.read(mf, "manifest", max_bytes=MAX_MANIFEST_BYTES, error=ArtSetError)
        except ArtSetError as e:
            self.add(self.manifest_file, str(e).removeprefix(f"{mf}: "))
            return None
        if not isinstance(data, dict):
            self.add(self.manifest_file, "manifest must be a JSON object")
            return None
        missing = [k for k in ("format", "name", "canvas", "heads", "parts") if k not in data]
        if missing:
            self.add(self.manifest_file, f"missing key(s): {', '.join(missing)}")
            return None
        if data["format"] not in READ_FORMATS or isinstance(data["format"], bool) or not isinstance(data["format"], int):
            self.add(self.manifest_file, f"format {reprlib.repr(data['format'])} is not supported (this version reads formats "
                                         f"{', '.join(map(str, READ_FORMATS))})")
            return None
        self.format = int(data["format"])
        name = data["name"]
        if not isinstance(name, str) or not name.strip() or len(name) > MAX_TEXT:
            self.add(self.manifest_file, f"name must be a non-empty string of at most {MAX_TEXT} characters")
            name = safe_json.show(name)
        author = data.get("author", "")
        if not isinstance(author, str) or len(author) > MAX_TEXT:
            self.add(self.manifest_file, f"author must be a string of at most {MAX_TEXT} characters")
            author = safe_json.show(author)
        canvas = _int_pair(data["canvas"])
        if canvas is None or min(canvas) < 1 or max(canvas) > MAX_SIDE:
            self.add(self.manifest_file, f"canvas must be [width, height] in 1..{MAX_SIDE} (the canvas size limit), got {safe_json.show(data['canvas'])}")
            return None
        pivot_raw = data.get("pivot", [canvas[0] / 2, canvas[1] / 2])
        pivot = _num_pair(pivot_raw)
        if pivot is None or not all(-c <= v <= 2 * c for v, c in zip(pivot, canvas)):
            self.add(self.manifest_file, f"pivot must be [x, y] numbers at most one canvas width or height outside the canvas, got {safe_json.show(pivot_raw)}")
            pivot = (canvas[0] / 2, canvas[1] / 2)

        heads, head_files = self.read_heads(data["heads"], canvas)
        parts = self.read_parts(data["parts"], canvas)
        if parts is None:
            return None
        known = _KNOWN_KEYS_2 if self.format >= 2 else _KNOWN_KEYS
        body = self.read_body(data["body"], canvas) if self.format >= 2 and "body" in data else None
        extra = {k: v for k, v in data.items() if k not in known}
        return ArtSet(name=name, canvas=canvas, pivot=pivot, heads=heads, parts=parts, author=author,
                      head_files=head_files, path=self.folder, extra=extra, body=body)

    def read_body(self, raw, canvas) -> Body | None:
        """The optional ``body``: ``{"image": PATH, "follow": 0..1, "roll": 0..1, "pivot": [x, y]}``."""
        if not isinstance(raw, dict) or "image" not in raw:
            self.add(self.manifest_file, "body must be an object with 'image' (and optionally 'follow', 'roll', 'pivot')")
            return None
        bad = False
        vals = {}
        for key, default, hi in (("follow", Body.follow, 1.0), ("roll", Body.roll, MAX_BODY_ROLL)):
            v = raw.get(key, default)
            if not _is_num(v) or not 0 <= v <= hi:
                self.add(self.manifest_file, f"body.{key} must be a number from 0 to {hi:g}, got {safe_json.show(v)}")
                bad = True
            vals[key] = float(v) if _is_num(v) else default
        pivot = None
        if raw.get("pivot") is not None:
            pivot = _num_pair(raw["pivot"])
            if pivot is None:
                self.add(self.manifest_file, f"body.pivot must be [x, y] numbers, got {safe_json.show(raw['pivot'])}")
                bad = True
        img = self.image(raw["image"], "body")
        if img is None or bad:
            return None
        if (img.shape[1], img.shape[0]) != canvas:
            self.add(str(self.folder / raw["image"]), f"body is {img.shape[1]}x{img.shape[0]}, the canvas is {canvas[0]}x{canvas[1]}")
            return None
        return Body(image=img, file=raw["image"], follow=vals["follow"], roll=vals["roll"], pivot=pivot)

    def read_heads(self, raw, canvas) -> tuple[list[np.ndarray], list[str]]:
        heads, files = [], []
        if not isinstance(raw, list) or not raw:
            self.add(self.manifest_file, "heads must be a non-empty list of image paths")
            return heads, files
        if len(raw) > MAX_HEADS:
            self.add(self.manifest_file, f"{len(raw)} heads; at most {MAX_HEADS} are allowed (the heads limit)")
            return heads, files
        for i, rel in enumerate(raw):
            img = self.image(rel, f"heads[{i}]")
            if img is None:
                continue
            file = str(self.folder / rel)
            if (img.shape[1], img.shape[0]) != canvas:
                self.add(file, f"head is {img.shape[1]}x{img.shape[0]}, the canvas is {canvas[0]}x{canvas[1]}")
            elif not self.alpha_seen.get(file, True) or img[..., 3].min() == 255:
                self.add(file, "head has no transparency; it needs soft alpha holes where the eyes and mouth show through")
            heads.append(img)
            files.append(rel)
        return heads, files

    def read_parts(self, raw, canvas) -> dict[str, Part] | None:
        if not isinstance(raw, dict):
            self.add(self.manifest_file, "parts must be an object with 'eyes' and 'mouth'")
            return None
        parts: dict[str, Part] = {}
        for pname in PART_NAMES:
            if pname not in raw:
                self.add(self.manifest_file, f"parts: missing part {pname!r}")
                continue
            p = self.read_part(pname, raw[pname], canvas)
            if p is not None:
                parts[pname] = p
        for pname in raw:
            if pname not in PART_NAMES:
                self.add(self.manifest_file, f"parts: unknown part {pname!r} (expected {', '.join(PART_NAMES)})")
        return parts if len(parts) == len(PART_NAMES) else None

    def read_part(self, pname: str, raw, canvas) -> Part | None:
        where = f"parts.{pname}"
        if not isinstance(raw, dict) or "box" not in raw or "drawings" not in raw:
            self.add(self.manifest_file, f"{where}: needs 'box' and 'drawings'")
            return None
        box = _int_quad(raw["box"])
        if box is None or box[2] < 1 or box[3] < 1:
            self.add(self.manifest_file, f"{where}.box must be [x, y, w, h] integers with w, h > 0, got {raw['box']!r}")
            return None
        if box[0] < 0 or box[1] < 0 or box[0] + box[2] > canvas[0] or box[1] + box[3] > canvas[1]:
            self.add(self.manifest_file, f"{where}.box {list(box)} does not fit inside the {canvas[0]}x{canvas[1]} canvas")
        if box[2] * box[3] > MAX_DRAWING_PIXELS:
            self.add(self.manifest_file, f"{where}.box is {box[2]}x{box[3]}, more than the {MAX_DRAWING_PIXELS:,}-pixel limit for a part")
            return None
        raw_d = raw["drawings"]
        if not isinstance(raw_d, list):
            self.add(self.manifest_file, f"{where}.drawings must be a list")
            return None
        if len(raw_d) > MAX_DRAWINGS:
            self.add(self.manifest_file, f"{where}: {len(raw_d)} drawings; at most {MAX_DRAWINGS} are allowed (the drawings-per-part limit)")
            return None
        if len(raw_d) < MIN_DRAWINGS:
            self.add(self.manifest_file, f"{where}: {len(raw_d)} drawing(s); at least {MIN_DRAWINGS} are needed to make a triangle")
        drawings: list[Drawing] = []
        seen: set[str] = set()
        count_ref: tuple[int, str] | None = None
        for i, d in enumerate(raw_d):
            dw = f"{where}.drawings[{i}]"
            if self.format >= 2 and isinstance(d, dict) and "layers" in d:
                if "image" in d:
                    self.add(self.manifest_file, f"{dw}: has both 'image' and 'layers'; a drawing is one or the other")
                    continue
                drawing = self.read_layered(pname, dw, d, box, seen)
                if drawing is not None:
                    drawings.append(drawing)
                continue
            if not isinstance(d, dict) or not {"name", "image", "lines"} <= set(d):
                need = "'name', 'lines' and 'image' (or 'layers')" if self.format >= 2 else "'name', 'image' and 'lines'"
                self.add(self.manifest_file, f"{dw}: needs {need}")
                continue
            named = self.named_lines(where, dw, d, seen, MAX_LINES, "the lines-per-drawing limit")
            if named is None:
                continue
            dname, lines = named
            img = self.image(d["image"], f"{dw} ({dname})", MAX_DRAWING_PIXELS)
            if img is None:
                continue
            file = str(self.folder / d["image"])
            h, w = img.shape[:2]
            if (w, h) != (box[2], box[3]):
                self.add(file, f"{pname} drawing {dname!r} is {w}x{h}, the {pname} box is {box[2]}x{box[3]}")
            if self.strict:
                if count_ref is None:
                    count_ref = (len(lines), dname)
                elif len(lines) != count_ref[0]:
                    self.add(self.manifest_file, f"{where}: drawing {dname!r} has {len(lines)} control lines, {count_ref[1]!r} has {count_ref[0]}")
                self.check_lines(where, f"drawing {dname!r}", lines, w, h)
            drawings.append(Drawing(name=dname, image=img, lines=lines, file=d["image"]))
        if any(d.layers for d in drawings):
            self.check_layer_structure(where, drawings)
        elif self.strict and count_ref is not None and count_ref[0] == 0:
            self.add(self.manifest_file, f"{where}: drawings have no control lines; a morph needs at least one")
        return Part(name=pname, box=box, drawings=drawings)

    def check_lines(self, where: str, what: str, lines: np.ndarray, w: int, h: int) -> None:
        """Lines inside the ``w``×``h`` image and at least ``MIN_LINE_LENGTH`` long."""
        if not len(lines):
            return
        xs, ys = lines[:, [0, 2]], lines[:, [1, 3]]
        bad = np.nonzero((xs < 0).any(1) | (xs > w).any(1) | (ys < 0).any(1) | (ys > h).any(1))[0]
        if len(bad):
            self.add(self.manifest_file, f"{where}: {what} line(s) {', '.join(map(str, bad))} lie outside its {w}x{h} image")
        short = np.nonzero(np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1]) < MIN_LINE_LENGTH)[0]
        if len(short):
            self.add(self.manifest_file, f"{where}: {what} line(s) {', '.join(map(str, short))} are shorter than {MIN_LINE_LENGTH:g} px")

    def named_lines(self, where: str, dw: str, d: dict, seen: set[str], max_lines: int, limit: str
                    ) -> tuple[str, np.ndarray] | None:
        """A drawing's name (unique in its part) and control lines, or None with the problem recorded."""
        dname = d["name"]
        if not isinstance(dname, str) or not dname or len(dname) > MAX_TEXT:
            self.add(self.manifest_file, f"{dw}: name must be a non-empty string of at most {MAX_TEXT} characters")
            return None
        if dname in seen:
            self.add(self.manifest_file, f"{where}: two drawings are called {dname!r}")
        seen.add(dname)
        if isinstance(d["lines"], list) and len(d["lines"]) > max_lines:
            self.add(self.manifest_file, f"{dw} ({dname}): {len(d['lines'])} control lines; at most {max_lines} are allowed ({limit})")
            return None
        lines = _lines(d["lines"])
        if lines is None:
            self.add(self.manifest_file, f"{dw} ({dname}): lines must be a list of [x0, y0, x1, y1] numbers of at most {MAX_COORD:g}")
            return None
        return dname, lines

    def read_layered(self, pname: str, dw: str, d: dict, box, seen: set[str]) -> Drawing | None:
        """A format-2 drawing made of layers (bottom first), each ``{"name", "image"[, "lines"]}``."""
        where = f"parts.{pname}"
        if not {"name", "lines"} <= set(d):
            self.add(self.manifest_file, f"{dw}: needs 'name', 'lines' and 'layers'")
            return None
        named = self.named_lines(where, dw, d, seen, MAX_LAYER_LINES, "the lines-per-layered-drawing limit")
        if named is None:
            return None
        dname, lines = named
        raw_l = d["layers"]
        if not isinstance(raw_l, list) or not raw_l:
            self.add(self.manifest_file, f"{dw} ({dname}): layers must be a non-empty list")
            return None
        if len(raw_l) > MAX_LAYERS:
            self.add(self.manifest_file, f"{dw} ({dname}): {len(raw_l)} layers; at most {MAX_LAYERS} are allowed (the layers limit)")
            return None
        layers: list[Layer] = []
        names: set[str] = set()
        ok = True
        for k, ly in enumerate(raw_l):
            lw = f"{dw} ({dname}).layers[{k}]"
            if not isinstance(ly, dict) or not {"name", "image"} <= set(ly):
                self.add(self.manifest_file, f"{lw}: needs 'name' and 'image' (and optionally 'lines')")
                ok = False
                continue
            lname = ly["name"]
            if not isinstance(lname, str) or not lname.strip() or len(lname) > MAX_TEXT:
                self.add(self.manifest_file, f"{lw}: name must be a non-empty string of at most {MAX_TEXT} characters")
                ok = False
                continue
            if lname in names:
                self.add(self.manifest_file, f"{dw} ({dname}): two layers are called {lname!r}")
            names.add(lname)
            own = None
            if ly.get("lines") is not None:
                own = _lines(ly["lines"]) if not (isinstance(ly["lines"], list) and len(ly["lines"]) > MAX_LAYER_LINES) else None
                if own is None:
                    self.add(self.manifest_file, f"{lw} ({lname}): lines must be a list of at most {MAX_LAYER_LINES} "
                                                 f"[x0, y0, x1, y1] numbers of at most {MAX_COORD:g}")
                    ok = False
                    continue
            img = self.image(ly["image"], f"{lw} ({lname})", MAX_DRAWING_PIXELS)
            if img is None:
                ok = False
                continue
            h, w = img.shape[:2]
            if (w, h) != (box[2], box[3]):
                self.add(str(self.folder / ly["image"]),
                         f"{pname} drawing {dname!r} layer {lname!r} is {w}x{h}, the {pname} box is {box[2]}x{box[3]}")
                ok = False
                continue
            if self.strict and own is not None:
                self.check_lines(where, f"drawing {dname!r} layer {lname!r}", own, w, h)
            layers.append(Layer(name=lname, image=img, lines=own, file=ly["image"]))
        if not ok:
            return None
        if self.strict:
            self.check_lines(where, f"drawing {dname!r}", lines, box[2], box[3])
        return Drawing.from_layers(dname, layers, lines)

    def check_layer_structure(self, where: str, drawings: list[Drawing]) -> None:
        """Every drawing of a layered part has the same layers, in the same order, each with its
        own lines everywhere (the same number) or nowhere; every layer has lines to move with."""
        ref = next(d for d in drawings if d.layers)
        names = [ly.name for ly in ref.layers]
        for d in drawings:
            if not d.layers:
                self.add(self.manifest_file, f"{where}: drawing {d.name!r} is a single picture but {ref.name!r} has layers "
                                             f"({', '.join(names)}); give every drawing of a part the same layers")
                return
            if [ly.name for ly in d.layers] != names:
                self.add(self.manifest_file, f"{where}: drawing {d.name!r} has layers {[ly.name for ly in d.layers]}, "
                                             f"{ref.name!r} has {names}; every drawing needs the same layers in the same order")
                return
        line_sets = {tuple(len(d.layer_lines(k)) for d in drawings) + ((k if drawings[0].layers[k].lines is not None else -1),)
                     for k in range(len(names))}
        work = sum(len(drawings) * (len(drawings) - 1) * max(key[:-1]) for key in line_sets)
        if work > MAX_LINE_WORK:
            self.add(self.manifest_file, f"{where}: {len(drawings)} drawings × their control lines ({work} line pairs) is more than "
                                         f"the {MAX_LINE_WORK} the morph tables may take (the line-work limit); fewer drawings, "
                                         f"lines or layers with their own lines")
        if not self.strict:
            return
        for k, lname in enumerate(names):
            counts = {d.name: len(d.layer_lines(k)) for d in drawings}
            owns = {d.name: d.layers[k].lines is not None for d in drawings}
            if len(set(owns.values())) > 1:
                have = [n for n, o in owns.items() if o]
                self.add(self.manifest_file, f"{where}: layer {lname!r} has its own control lines in {', '.join(map(repr, have))} "
                                             f"but not in every drawing; give it lines everywhere or nowhere")
                continue
            if len(set(counts.values())) > 1:
                n0, c0 = next(iter(counts.items()))
                odd = next(n for n, c in counts.items() if c != c0)
                whose = f"layer {lname!r}" if owns[n0] else "the drawing"
                self.add(self.manifest_file, f"{where}: {whose} control lines: {odd!r} has {counts[odd]}, {n0!r} has {c0}")
                continue
            if next(iter(counts.values())) == 0:
                self.add(self.manifest_file, f"{where}: layer {lname!r} has no control lines to move with; a morph needs at least one")


def scan(path: str | os.PathLike, strict_geometry: bool = True) -> tuple[ArtSet | None, list[Problem]]:
    """Read the art set at ``path`` (folder or its artset.json); return it and every problem found."""
    s = _Scan(_folder_of(path), strict_geometry)
    art = s.run()
    return art, s.problems


def load_artset(path: str | os.PathLike, strict: bool = True) -> ArtSet:
    """Load an art-set folder (or its ``artset.json``) into an :class:`ArtSet`.

    Raises :class:`ArtSetError` naming the file of the first problem. With ``strict=False``
    control-line problems (counts, bounds, lengths) are tolerated, e.g. for an editor opening
    a half-finished set; unsafe paths, bad images and sizes are always refused.
    """
    art, problems = scan(path, strict_geometry=strict)
    if problems:
        more = f" (and {len(problems) - 1} more problem(s); run `python -m art_sets check`)" if len(problems) > 1 else ""
        raise ArtSetError(f"{problems[0]}{more}")
    assert art is not None
    return art


# --- writing -----------------------------------------------------------------------------
def _png_bytes(img: np.ndarray, fast: bool = False) -> bytes:
    arr = np.asarray(img)
    if arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[2] != 4:
        raise ArtSetError(f"image must be uint8 (h, w, 4) RGBA, got {arr.dtype} {arr.shape}")
    buf = _io.BytesIO()
    opts = {"compress_level": 1} if fast else {"optimize": True}
    Image.fromarray(arr, "RGBA").save(buf, format="PNG", **opts)
    return buf.getvalue()


def write_png(path: str | os.PathLike, img: np.ndarray) -> None:
    """Write an RGBA uint8 image as PNG atomically."""
    atomic_file.write_bytes(Path(path), _png_bytes(img))


def _lines_json(lines) -> list:
    return [[float(v) for v in row] for row in np.asarray(lines, dtype=np.float64).reshape(-1, 4)]


def _drawing_json(pname: str, d: Drawing) -> dict:
    if not d.layers:
        return {"name": d.name, "image": _drawing_file(pname, d), "lines": _lines_json(d.lines)}
    layers = []
    for ly in d.layers:
        entry = {"name": ly.name, "image": _layer_file(pname, d, ly)}
        if ly.lines is not None:
            entry["lines"] = _lines_json(ly.lines)
        layers.append(entry)
    return {"name": d.name, "lines": _lines_json(d.lines), "layers": layers}


def manifest_dict(art: ArtSet) -> dict:
    """The JSON manifest for ``art`` (image paths as in ``head_files`` / ``Drawing.file`` /
    ``Layer.file`` / ``Body.file``). Format 1 unless the set has layers or a body."""
    head_files = _head_files(art)
    v2 = art.layered or art.body is not None
    parts = {}
    for pname in PART_NAMES:
        p = art.parts[pname]
        parts[pname] = {"box": [int(v) for v in p.box], "drawings": [_drawing_json(pname, d) for d in p.drawings]}
    out = {"format": FORMAT_VERSION if v2 else 1, "name": art.name, "author": art.author,
           "canvas": [int(art.canvas[0]), int(art.canvas[1])],
           "pivot": [float(art.pivot[0]), float(art.pivot[1])],
           "heads": head_files}
    if art.body is not None:
        b = art.body
        out["body"] = {"image": b.file or "body.png", "follow": float(b.follow), "roll": float(b.roll)}
        if b.pivot is not None:
            out["body"]["pivot"] = [float(b.pivot[0]), float(b.pivot[1])]
    out["parts"] = parts
    known = _KNOWN_KEYS_2 if v2 else _KNOWN_KEYS
    for k, v in art.extra.items():
        if k not in known:
            out[k] = v
    return out


def _head_files(art: ArtSet) -> list[str]:
    files = list(art.head_files[: len(art.heads)])
    files += [f"head-{i + 1}.png" for i in range(len(files), len(art.heads))]
    return files


def _drawing_file(pname: str, d: Drawing) -> str:
    return d.file or f"{pname}/{d.name}.png"


def _layer_file(pname: str, d: Drawing, ly: Layer) -> str:
    return ly.file or f"{pname}/{d.name}/{ly.name}.png"


def _image_slots(art: ArtSet) -> list[tuple[str, np.ndarray, Callable[[str], None]]]:
    """Every image ``art`` saves: its path in the manifest, its pixels, and how to rename it."""
    files = _head_files(art)
    art.head_files = files

    def head(i: int) -> Callable[[str], None]:
        return lambda name: art.head_files.__setitem__(i, name)

    def drawing(d: Drawing) -> Callable[[str], None]:
        return lambda name: setattr(d, "file", name)

    def layer(ly: Layer) -> Callable[[str], None]:
        return lambda name: setattr(ly, "file", name)

    slots = [(files[i], img, head(i)) for i, img in enumerate(art.heads)]
    for pname in PART_NAMES:
        for d in art.parts[pname].drawings:
            if not d.layers:
                slots.append((_drawing_file(pname, d), d.image, drawing(d)))
                continue
            for ly in d.layers:
                ly.file = _layer_file(pname, d, ly)
                slots.append((ly.file, ly.image, layer(ly)))
    if art.body is not None:
        art.body.file = art.body.file or "body.png"
        slots.append((art.body.file, art.body.image, lambda name: setattr(art.body, "file", name)))
    # a layer that is the same in several drawings names one file: one slot, renaming them all
    merged: dict[str, tuple[np.ndarray, list]] = {}
    for rel, img, rename in slots:
        if rel in merged:
            if not (merged[rel][0] is img or np.array_equal(merged[rel][0], img)):
                raise ArtSetError(f"{rel}: two different images would be written to this file")
            merged[rel][1].append(rename)
        else:
            merged[rel] = (img, [rename])
    return [(rel, img, (lambda name, fs=fs: [f(name) for f in fs])) for rel, (img, fs) in merged.items()]


def _files_named_by(folder: Path) -> list[str]:
    """Every image path the manifest in ``folder`` names now (none without a readable manifest)."""
    try:
        data = safe_json.read(folder / MANIFEST, "manifest", max_bytes=MAX_MANIFEST_BYTES, error=ArtSetError)
    except ArtSetError:
        return []
    return _png_paths(data, folder)


def _png_paths(manifest, folder: Path) -> list[str]:
    """Each string in ``manifest`` that is a safe relative ``.png`` path, whatever key holds it
    (so files named by keys this version does not know are never taken for garbage)."""
    found, stack = [], [manifest]
    while stack:
        v = stack.pop()
        if isinstance(v, dict):
            stack.extend(v.values())
        elif isinstance(v, list):
            stack.extend(v)
        elif isinstance(v, str) and v.lower().endswith(".png") and atomic_file.inside(folder, v) is not None:
            found.append(v)
    return found


def save_artset(art: ArtSet, path: str | os.PathLike, *, fast: bool = False, cache: dict | None = None) -> Path:
    """Write ``art`` to the folder ``path`` (PNGs and ``artset.json``) so that a crash at any
    moment leaves the folder's previous set or this one complete, never a mix.

    Image paths come from ``head_files`` / ``Drawing.file`` (defaults ``head-N.png`` and
    ``<part>/<name>.png``) and must stay inside the folder. Unchanged PNGs are kept; a PNG whose
    pixels changed is written under a name the folder's current manifest does not use
    (``mouth/ah.png`` <-> ``mouth/ah.v2.png``), the manifest last, and then the files only the
    old manifest named are removed (an :class:`~art_sets.atomic_file.Generation`). ``art``'s
    ``head_files`` and ``Drawing.file`` are set to the names written.

    ``fast`` uses light PNG compression (autosave). ``cache`` (a dict the caller keeps between
    saves into one folder) skips encoding images that are the very array last saved there: it
    maps manifest path -> (file name, array). Returns the folder.
    """
    folder = _folder_of(path)
    slots = _image_slots(art)
    checker = _Scan(folder)
    for rel, _, _ in slots:
        if checker.safe_path(rel, rel) is None:
            raise ArtSetError(str(checker.problems[-1]))
    gen = atomic_file.Generation(folder, MANIFEST, _files_named_by(folder))
    for rel, img, rename in slots:
        hit = cache.get(rel) if cache is not None else None
        name = None
        if hit is not None and hit[1] is img:
            try:
                name = gen.keep(hit[0])
            except KeyError:
                name = None
        if name is None:
            name = gen.put(rel, _png_bytes(img, fast))
        if cache is not None:
            cache[rel] = (name, img)
        rename(name)
    manifest = manifest_dict(art)
    for rel in _png_paths(manifest, folder):  # e.g. a picture an unknown key names: still in use
        if rel in gen.current and rel not in gen.names:
            try:
                gen.keep(rel)
            except KeyError:
                pass
    gen.commit((json.dumps(manifest, indent=1, ensure_ascii=False) + "\n").encode("utf-8"))
    if cache is not None:
        for rel in [r for r, (name, _) in cache.items() if name not in gen.names]:
            del cache[rel]
    return folder


# --- small parsers -------------------------------------------------------------------------
def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


MAX_COORD = 1e6
"""Largest coordinate (px) a manifest may hold anywhere."""


def _reason(e: BaseException) -> str:
    return (e.strerror if isinstance(e, OSError) and e.strerror else _one_line(e)) or type(e).__name__


def _is_num(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and abs(v) <= MAX_COORD


def _int_pair(v) -> tuple[int, int] | None:
    if isinstance(v, list) and len(v) == 2 and all(_is_num(x) and float(x).is_integer() for x in v):
        return int(v[0]), int(v[1])
    return None


def _num_pair(v) -> tuple[float, float] | None:
    if isinstance(v, list) and len(v) == 2 and all(_is_num(x) for x in v):
        return float(v[0]), float(v[1])
    return None


def _int_quad(v) -> tuple[int, int, int, int] | None:
    if isinstance(v, list) and len(v) == 4 and all(_is_num(x) and float(x).is_integer() for x in v):
        return tuple(int(x) for x in v)  # type: ignore[return-value]
    return None


def _lines(v) -> np.ndarray | None:
    if not isinstance(v, list) or not all(isinstance(r, list) and len(r) == 4 and all(_is_num(x) for x in r) for r in v):
        return None
    return np.asarray(v, dtype=np.float64).reshape(-1, 4)
