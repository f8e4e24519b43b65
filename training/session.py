"""A training session: one performer with one art set (Buck et al.'s training step).

It holds the performer's calibration (inter-pupil distance and neutral face, plus a reference to
the calibration file), the reference clip (path and, once tracked, its ten values per frame) and
the *pairs*: a drawing of a part matched with a video frame that shows the same expression, its
ten tracked values and a small thumbnail of the frame. A pair may also match a frame with a
*blend* of drawings (``{"smile": 0.6, "ah": 0.4}``), which the ridge mapper can learn from.

On disk a session is a folder: ``session.json`` (``"format": 1``) and ``thumbs/*.png``. Every
write is atomic (temporary file in the same folder, then ``os.replace``). With a ``path`` the
session saves itself after every change (autosave).
"""

from __future__ import annotations

import io
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable

import numpy as np

from tracker import atomic_file, safe_json
from tracker.params import PARAM_NAMES, FaceParams
from training.features import PART_SLICES, FeatureSpace

__all__ = ["FORMAT_VERSION", "SESSION_FILE", "Pair", "SessionError", "TrainingSession"]

FORMAT_VERSION = 1
SESSION_FILE = "session.json"
THUMB_DIR = "thumbs"
THUMB_WIDTH = 160
PARTS = ("eyes", "mouth")


class SessionError(ValueError):
    """A session could not be loaded, saved or used; the message is one line naming the file."""


@dataclass
class Pair:
    """One training pair: part, a drawing name (or a blend of drawing names), the frame index in
    the reference clip, its ten values (pixels / degrees) and a thumbnail (RGB uint8 or None)."""

    part: str
    drawing: str | None
    frame: int
    values: tuple[float, ...]
    blend: dict[str, float] | None = None
    thumbnail: np.ndarray | None = field(default=None, repr=False)
    thumb_file: str = ""
    source: str = ""  # where the frame came from when not the reference clip, e.g. "synthetic:smile"

    @property
    def is_blend(self) -> bool:
        return self.blend is not None

    def label(self) -> str:
        if self.blend is None:
            return f"{self.part}/{self.drawing}"
        return f"{self.part}/" + "+".join(f"{w:.2f} {n}" for n, w in self.blend.items())

    def to_dict(self) -> dict:
        d = {"part": self.part, "frame": int(self.frame), "values": dict(zip(PARAM_NAMES, map(float, self.values)))}
        if self.blend is None:
            d["drawing"] = self.drawing
        else:
            d["blend"] = {k: float(v) for k, v in self.blend.items()}
        if self.thumb_file:
            d["thumbnail"] = self.thumb_file
        if self.source:
            d["source"] = self.source
        return d


def _thumb(image: np.ndarray, bgr: bool) -> np.ndarray:
    """A small RGB copy of a frame (THUMB_WIDTH wide)."""
    from PIL import Image

    img = np.asarray(image)
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=2)
    img = img[..., :3]
    if bgr:
        img = img[..., ::-1]
    img = np.ascontiguousarray(img, dtype=np.uint8)
    h, w = img.shape[:2]
    if w > THUMB_WIDTH:
        im = Image.fromarray(img, "RGB").resize((THUMB_WIDTH, max(1, round(h * THUMB_WIDTH / w))), Image.BILINEAR)
        img = np.asarray(im)
    return img


def _png(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img, "RGB").save(buf, format="PNG")
    return buf.getvalue()


def _values10(values) -> tuple[float, ...]:
    v = values.values() if isinstance(values, FaceParams) else np.asarray(values, dtype=np.float64).ravel()
    if len(v) != len(PARAM_NAMES):
        raise SessionError(f"a pair needs {len(PARAM_NAMES)} tracked values, got {len(v)}")
    if not all(math.isfinite(float(x)) for x in v):
        raise SessionError("a pair's tracked values must be finite (was the face lost on that frame?)")
    return tuple(float(x) for x in v)


class TrainingSession:
    """Training pairs of one performer for one art set (see the module docstring).

    ``artset`` is the art set's name; ``features`` the performer's calibration as a
    :class:`~training.features.FeatureSpace` (or None until calibrated); ``calibration_ref`` a
    path to the calibration file; ``reference_clip`` the video the pairs' frames come from.
    With ``path`` set, every change is saved at once.
    """

    def __init__(
        self,
        artset: str,
        features: FeatureSpace | None = None,
        calibration_ref: str = "",
        reference_clip: str = "",
        path: str | os.PathLike | None = None,
        autosave: bool = True,
    ):
        self.artset = str(artset)
        self.features = features
        self.calibration_ref = str(calibration_ref or "")
        self.reference_clip = str(reference_clip or "")
        self.reference_track: np.ndarray | None = None
        self.pairs: list[Pair] = []
        self.notes: list[str] = []
        self.path: Path | None = None if path is None else self._folder(path)
        self.autosave = autosave
        self._thumb_seq = 0

    # ------------------------------------------------------------------------------- edits
    def _changed(self) -> None:
        if self.autosave and self.path is not None:
            self.save()

    def add_pair(self, part: str, drawing: str, values, frame: int = 0, image=None, bgr: bool = True) -> Pair:
        """Match drawing ``drawing`` of ``part`` with frame ``frame`` and its ten ``values``
        (FaceParams or 10 numbers). ``image`` is the frame (BGR when ``bgr``) for the thumbnail."""
        self._check_part(part)
        p = Pair(part, str(drawing), int(frame), _values10(values))
        return self._add(p, image, bgr)

    def add_blend_pair(self, part: str, blend: dict[str, float], values, frame: int = 0, image=None, bgr: bool = True) -> Pair:
        """Match a frame with a blend of drawings, ``{name: weight}`` (weights ≥ 0, normalised)."""
        self._check_part(part)
        if not blend:
            raise SessionError("a blend pair needs at least one drawing")
        w = {str(k): float(v) for k, v in blend.items()}
        if any(v < 0 or not math.isfinite(v) for v in w.values()) or sum(w.values()) <= 0:
            raise SessionError(f"blend weights must be non-negative and not all zero, got {blend}")
        s = sum(w.values())
        p = Pair(part, None, int(frame), _values10(values), blend={k: v / s for k, v in w.items()})
        return self._add(p, image, bgr)

    def _add(self, p: Pair, image, bgr: bool) -> Pair:
        if image is not None:
            p.thumbnail = _thumb(image, bgr)
        self.pairs.append(p)
        self._changed()
        return p

    def remove_pair(self, index: int) -> Pair:
        p = self.pairs.pop(index)
        self._changed()
        return p

    def clear_pairs(self, part: str | None = None) -> None:
        self.pairs = [p for p in self.pairs if part is not None and p.part != part]
        self._changed()

    def set_calibration(self, calibration, ref: str | os.PathLike = "") -> None:
        """Use a ``Calibration`` (or a :class:`FeatureSpace`) and remember where it is stored."""
        self.features = calibration if isinstance(calibration, FeatureSpace) else FeatureSpace.from_calibration(calibration)
        self.calibration_ref = str(ref or "")
        self._changed()

    def set_reference(self, clip: str | os.PathLike, track: Iterable[FaceParams] | np.ndarray | None = None) -> None:
        """The reference clip and (optionally) its tracked values, ``(m, 10)`` or FaceParams rows."""
        self.reference_clip = str(clip)
        if track is None:
            self.reference_track = None
        else:
            arr = track if isinstance(track, np.ndarray) else np.array([r.values() for r in track])
            self.reference_track = np.asarray(arr, dtype=np.float64).reshape(-1, len(PARAM_NAMES))
        self._changed()

    @staticmethod
    def _check_part(part: str) -> None:
        if part not in PARTS:
            raise SessionError(f"unknown part {part!r} (expected eyes or mouth)")

    # ------------------------------------------------------------------------ fitting data
    def feature_space(self) -> FeatureSpace:
        """The calibration, or an estimate (reference track, else the pairs) when there is none."""
        if self.features is not None:
            return self.features
        if self.reference_track is not None and len(self.reference_track):
            return FeatureSpace.estimate(self.reference_track)
        if self.pairs:
            return FeatureSpace.estimate(np.array([p.values for p in self.pairs]))
        raise SessionError("session has no calibration, reference track or pairs to scale features by")

    def pairs_of(self, part: str) -> list[Pair]:
        return [p for p in self.pairs if p.part == part]

    def training_points(self, part: str, drawing_names: list[str]) -> tuple[np.ndarray, np.ndarray]:
        """One training point per paired drawing of ``part`` (mean features of its frames) and the
        drawing's index in ``drawing_names``. Blend pairs are left out (see :meth:`training_data`)."""
        fs = self.feature_space()
        by_name: dict[str, list[np.ndarray]] = {}
        for p in self.pairs_of(part):
            if p.blend is None:
                by_name.setdefault(p.drawing, []).append(fs.part(part, p.values))
        pts, labels = [], []
        for name, feats in by_name.items():
            if name in drawing_names:
                pts.append(np.mean(feats, axis=0))
                labels.append(drawing_names.index(name))
        k = PART_SLICES[part].stop - PART_SLICES[part].start
        return np.array(pts, dtype=np.float64).reshape(-1, k), np.array(labels, dtype=np.intp)

    def training_data(self, part: str, drawing_names: list[str]) -> tuple[np.ndarray, np.ndarray]:
        """Every pair of ``part`` as a feature row and a target weight row over ``drawing_names``
        (one-hot for drawing pairs, the blend for blend pairs)."""
        fs = self.feature_space()
        X, Y = [], []
        for p in self.pairs_of(part):
            y = np.zeros(len(drawing_names))
            items = {p.drawing: 1.0} if p.blend is None else p.blend
            ok = True
            for n, w in items.items():
                if n not in drawing_names:
                    ok = False
                    break
                y[drawing_names.index(n)] += w
            if ok:
                X.append(fs.part(part, p.values))
                Y.append(y)
        k = PART_SLICES[part].stop - PART_SLICES[part].start
        return np.array(X, dtype=np.float64).reshape(-1, k), np.array(Y).reshape(-1, len(drawing_names))

    def fit(self, artset, mapper: str = "delaunay") -> dict:
        """Fit one mapper per part (``{part: mapper or None}``; None when a part has no pairs).
        Raises :class:`SessionError` if the session does not belong to ``artset``."""
        from morph.mappers import make_mapper

        self.check(artset)
        out = {}
        for part in PARTS:
            names = artset.parts[part].names()
            if mapper == "ridge":
                X, Y = self.training_data(part, names)
                if len(X) == 0:
                    out[part] = None
                    continue
                used = np.flatnonzero(Y.sum(axis=0) > 0)
                m = make_mapper("ridge", X, targets=Y[:, used])
                m.labels = used.astype(np.intp)
                out[part] = m
            else:
                pts, labels = self.training_points(part, names)
                out[part] = make_mapper(mapper, pts, labels=labels) if len(pts) else None
        return out

    # -------------------------------------------------------------------------- checking
    def check(self, artset) -> None:
        """Raise :class:`SessionError` (one line) if this session was made for another art set or
        pairs a drawing the art set does not have."""
        where = str(self.path) if self.path else "training session"
        if artset.name != self.artset:
            raise SessionError(f"{where}: made for art set {self.artset!r}, not {artset.name!r}")
        for p in self.pairs:
            names = artset.parts[p.part].names()
            wanted = [p.drawing] if p.blend is None else list(p.blend)
            for n in wanted:
                if n not in names:
                    raise SessionError(f"{where}: pairs drawing {p.part}/{n!r}, which art set {artset.name!r} does not have")

    # ------------------------------------------------------------------------ persistence
    @staticmethod
    def _folder(path: str | os.PathLike) -> Path:
        p = Path(path).expanduser()
        return p.parent if p.suffix.lower() == ".json" else p

    def to_dict(self) -> dict:
        d = {
            "format": FORMAT_VERSION,
            "artset": self.artset,
            "calibration": {"ref": self.calibration_ref, **(self.features.to_dict() if self.features else {})},
            "reference_clip": self.reference_clip,
            "pairs": [p.to_dict() for p in self.pairs],
        }
        if self.reference_track is not None:  # null where the face was lost
            d["reference_track"] = [[round(float(x), 4) if math.isfinite(x) else None for x in row]
                                    for row in self.reference_track]
        if self.notes:
            d["notes"] = list(self.notes)
        return d

    def save(self, path: str | os.PathLike | None = None) -> Path:
        """Write ``session.json`` and the thumbnails into the session folder as one
        :class:`~tracker.atomic_file.Generation` (a crash leaves the previous save or this one);
        thumbnails no pair uses any more are removed. Returns the JSON path."""
        if path is not None:
            new = self._folder(path)
            if new != self.path:
                for p in self.pairs:  # thumbnails are rewritten in the new folder
                    p.thumb_file = ""
            self.path = new
        if self.path is None:
            raise SessionError("training session has no path to save to")
        folder = self.path
        target = folder / SESSION_FILE
        try:
            gen = atomic_file.Generation(folder, SESSION_FILE, _thumbs_named_by(target))
            for p in self.pairs:
                if p.thumb_file:
                    try:
                        gen.keep(p.thumb_file)
                        continue
                    except KeyError:
                        p.thumb_file = ""
                if p.thumbnail is not None:
                    stem = re.sub(r"[^A-Za-z0-9_-]+", "_", p.drawing or "blend")[:64]
                    p.thumb_file = gen.put(f"{THUMB_DIR}/{p.part}-{stem}-{p.frame:06d}.png", _png(p.thumbnail))
            gen.commit((json.dumps(self.to_dict(), indent=1) + "\n").encode("utf-8"))
            tdir = folder / THUMB_DIR
            if tdir.is_dir():  # the session's own folder: thumbnails of interrupted saves go too
                for f in tdir.glob("*.png"):
                    if f"{THUMB_DIR}/{f.name}" not in gen.names:
                        f.unlink(missing_ok=True)
        except OSError as e:
            raise SessionError(f"{folder}: cannot save training session ({e.strerror or e})") from None
        return target

    @classmethod
    def load(cls, path: str | os.PathLike, artset=None, autosave: bool = True) -> "TrainingSession":
        """Read a session folder (or its ``session.json``). With ``artset``, also :meth:`check` it."""
        folder = cls._folder(path)
        f = folder / SESSION_FILE
        if not f.exists():
            raise SessionError(f"{f}: no training session here")
        atomic_file.sweep_temp(folder)
        atomic_file.sweep_temp(folder / THUMB_DIR)
        # NaN: a frame where the face was lost, as sessions before format checks wrote it
        raw = safe_json.read(f, "training session", max_bytes=MAX_FILE_BYTES, allow_nan=True, error=SessionError)
        s = cls._from_dict(raw, folder, autosave)
        if artset is not None:
            s.check(artset)
        return s

    @classmethod
    def _from_dict(cls, raw, folder: Path, autosave: bool) -> "TrainingSession":
        f = folder / SESSION_FILE
        if not isinstance(raw, dict):
            raise SessionError(f"{f}: expected a JSON object")
        fmt = raw.get("format")
        if isinstance(fmt, bool) or fmt != FORMAT_VERSION:
            raise SessionError(f"{f}: unsupported session format {safe_json.show(fmt)} (this build reads {FORMAT_VERSION})")
        r = _Reader(f)
        if "artset" not in raw:
            raise SessionError(f"{f}: malformed training session (missing key 'artset')")
        cal = raw.get("calibration") or {}
        r.mapping(cal, "calibration")
        features = _feature_space(r, cal) if "ipd" in cal else None
        s = cls(r.string(raw["artset"], "artset"), features, r.string(cal.get("ref", ""), "calibration.ref"),
                r.string(raw.get("reference_clip", ""), "reference_clip"), path=None, autosave=autosave)
        if raw.get("reference_track") is not None:
            rows = safe_json.sequence(raw["reference_track"], f"{f}: reference_track", SessionError, MAX_TRACK_ROWS)
            s.reference_track = np.array([r.values(row, f"reference_track[{i}]", nan_ok=True) for i, row in enumerate(rows)],
                                         dtype=np.float64).reshape(-1, len(PARAM_NAMES))
        s.notes = [r.string(n, "notes") for n in safe_json.sequence(raw.get("notes", []), f"{f}: notes", SessionError, 10_000)]
        for i, d in enumerate(safe_json.sequence(raw.get("pairs", []), f"{f}: pairs", SessionError, MAX_PAIRS)):
            s.pairs.append(cls._pair_from_dict(r, d, f"pairs[{i}]", folder))
        s.path = folder
        return s

    @classmethod
    def _pair_from_dict(cls, r: "_Reader", d, where: str, folder: Path) -> Pair:
        d = r.mapping(d, where)
        for key in ("part", "values"):
            if key not in d:
                raise SessionError(f"{r.file}: malformed training session ({where}: missing key '{key}')")
        part = r.string(d["part"], f"{where}.part")
        if part not in PARTS:
            raise SessionError(f"{r.file}: {where}: unknown part {safe_json.show(part)} (expected eyes or mouth)")
        drawing = None if d.get("drawing") is None else r.string(d["drawing"], f"{where}.drawing")
        blend = None
        if d.get("blend") is not None:
            raw_blend = r.mapping(d["blend"], f"{where}.blend")
            blend = {r.string(k, f"{where}.blend"): safe_json.number(v, f"{r.file}: {where}.blend.{k}", SessionError, 0.0)
                     for k, v in raw_blend.items()}
            if not blend or sum(blend.values()) <= 0:
                raise SessionError(f"{r.file}: {where}.blend: weights must not all be zero")
        if blend is None and not drawing:
            raise SessionError(f"{r.file}: a pair has neither 'drawing' nor 'blend'")
        frame = safe_json.integer(d.get("frame", 0), f"{r.file}: {where}.frame", SessionError, 0, int(safe_json.MAGNITUDE))
        source = r.string(d["source"], f"{where}.source") if d.get("source") is not None else ""
        p = Pair(part, drawing, frame, r.values(d["values"], f"{where}.values"), blend=blend, source=source)
        tf = d.get("thumbnail", "")
        if tf:
            full = atomic_file.inside(folder, r.string(tf, f"{where}.thumbnail"))
            if full is not None and full.is_file():
                try:
                    from PIL import Image

                    with Image.open(full) as im:
                        if im.width * im.height <= MAX_THUMB_PIXELS:
                            p.thumbnail = np.asarray(im.convert("RGB"))
                            p.thumb_file = tf
                except (OSError, ValueError, Image.DecompressionBombError):
                    p.thumbnail = None
        return p


# ----------------------------------------------------------------------------- reading files
MAX_FILE_BYTES = 64 * 1024 * 1024
MAX_TRACK_ROWS = 2_000_000
MAX_PAIRS = 100_000
MAX_THUMB_PIXELS = 1024 * 1024


def _thumbs_named_by(f: Path) -> list[str]:
    """The thumbnails the session file ``f`` names now (none if it is missing or unreadable)."""
    try:
        raw = safe_json.read(f, "training session", max_bytes=MAX_FILE_BYTES, allow_nan=True, error=SessionError)
    except SessionError:
        return []
    pairs = raw.get("pairs") if isinstance(raw, dict) else None
    if not isinstance(pairs, list):
        return []
    return [d["thumbnail"] for d in pairs if isinstance(d, dict) and isinstance(d.get("thumbnail"), str)]


class _Reader:
    """Checks values of one session file; every error names the file."""

    def __init__(self, file: Path):
        self.file = file

    def string(self, v, where: str) -> str:
        return safe_json.string(v, f"{self.file}: {where}", SessionError)

    def mapping(self, v, where: str) -> dict:
        return safe_json.mapping(v, f"{self.file}: {where}", SessionError)

    def values(self, v, where: str, nan_ok: bool = False) -> tuple[float, ...]:
        """Ten values, as ``{name: number}`` or a list in PARAM_NAMES order (null: not measured)."""
        if isinstance(v, dict):
            missing = [n for n in PARAM_NAMES if n not in v]
            if missing:
                raise SessionError(f"{self.file}: malformed training session ({where}: missing {', '.join(missing)})")
            v = [v[n] for n in PARAM_NAMES]
        if not isinstance(v, list) or len(v) != len(PARAM_NAMES):
            raise SessionError(f"{self.file}: {where} must be {len(PARAM_NAMES)} numbers, got {safe_json.show(v)}")
        if nan_ok:
            v = [math.nan if x is None else x for x in v]
        return tuple(safe_json.number(x, f"{self.file}: {where}", SessionError, nan_ok=nan_ok) for x in v)


def _feature_space(r: _Reader, cal: dict) -> FeatureSpace:
    ipd = safe_json.number(cal["ipd"], f"{r.file}: calibration.ipd", SessionError, 1e-3, 1e6)
    neutral = r.values(cal.get("neutral"), "calibration.neutral")
    return FeatureSpace.from_dict({"ipd": ipd, "neutral": list(neutral)})
