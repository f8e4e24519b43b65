"""The parameter record: ten numbers per frame, the only thing that crosses from tracking to rendering.

Units are pixels of the input frame and degrees (see ``shared/DESIGN.md``):

========== ==================================================================
mid_x/y    midpoint between the two pupil centres (x right, y down; measured from the
           frame's top-left corner, pixel centres at +0.5: see tracker.clicks.PIXEL_CENTRE)
roll_deg   angle of the pupil segment from horizontal, + when the image-right
           pupil is higher (i.e. counter-clockwise on screen)
eye_open_* lid-to-lid distance through the pupil, along the face's up axis
brow_*     pupil centre to the middle line of the eyebrow, along up
mouth_*    distance between the mouth corners
lip_*      mouth centre to the outer edge of the upper / lower lip, along up
========== ==================================================================

``_l`` is the eye on the image's left.

Also here: the CSV track format of the command-line contract and the 8-bit wire codec
(one byte per value, a 10-byte payload, a small packet header).
"""

from __future__ import annotations

import csv
import dataclasses
import math
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from tracker.outputs import StreamedFile


PARAM_NAMES: tuple[str, ...] = (
    "mid_x",
    "mid_y",
    "roll_deg",
    "eye_open_l",
    "eye_open_r",
    "brow_l",
    "brow_r",
    "mouth_width",
    "lip_upper",
    "lip_lower",
)
"""The ten values, in contract order."""

CSV_COLUMNS: tuple[str, ...] = ("frame",) + PARAM_NAMES
"""The fixed leading columns of a track CSV; extra columns may follow."""

EXTRA_COLUMNS: tuple[str, ...] = ("time", "status", "confidence")
"""The extra columns Inkface writes after the contract's columns."""

# Status values a tracker may report.
OK = "ok"
EYES_CLOSED = "eyes_closed"
MOUTH_LOST = "mouth_lost"
LOST = "lost"
STATUSES: tuple[str, ...] = (OK, EYES_CLOSED, MOUTH_LOST, LOST)


class TrackFormatError(ValueError):
    """A track CSV could not be read; the message names the file and the problem."""


class PacketError(ValueError):
    """A packet could not be decoded; the message says why (size, magic or version)."""


@dataclass(slots=True)
class FaceParams:
    """One frame's ten values plus bookkeeping.

    ``frame`` is the frame index in its source, ``time`` seconds from the source's start,
    ``status`` one of :data:`STATUSES` (other strings are allowed and passed through),
    ``confidence`` in [0, 1].
    """

    frame: int = 0
    mid_x: float = 0.0
    mid_y: float = 0.0
    roll_deg: float = 0.0
    eye_open_l: float = 0.0
    eye_open_r: float = 0.0
    brow_l: float = 0.0
    brow_r: float = 0.0
    mouth_width: float = 0.0
    lip_upper: float = 0.0
    lip_lower: float = 0.0
    time: float = 0.0
    status: str = OK
    confidence: float = 1.0

    def values(self) -> np.ndarray:
        """The ten values as a float64 array in :data:`PARAM_NAMES` order."""
        return np.array([getattr(self, n) for n in PARAM_NAMES], dtype=np.float64)

    @classmethod
    def from_values(
        cls,
        values: Sequence[float] | np.ndarray,
        frame: int = 0,
        time: float = 0.0,
        status: str = OK,
        confidence: float = 1.0,
    ) -> "FaceParams":
        """Build a record from ten values in :data:`PARAM_NAMES` order."""
        if len(values) != len(PARAM_NAMES):
            raise ValueError(f"expected {len(PARAM_NAMES)} values, got {len(values)}")
        kw = {n: float(v) for n, v in zip(PARAM_NAMES, values)}
        return cls(frame=int(frame), time=float(time), status=status, confidence=float(confidence), **kw)

    def replace(self, **changes) -> "FaceParams":
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def params_array(rows: Iterable[FaceParams]) -> np.ndarray:
    """Stack records into an ``(n, 10)`` float64 array."""
    return np.array([r.values() for r in rows], dtype=np.float64).reshape(-1, len(PARAM_NAMES))


def track_rate(rows: Sequence[FaceParams], default: float = 30.0) -> float:
    """Frames per second of a track from its times (the median step), ``default`` when they
    do not tell (fewer than two distinct finite times)."""
    t = np.array([r.time for r in rows], dtype=np.float64)
    dt = np.diff(t[np.isfinite(t)])
    dt = dt[dt > 0]
    return float(1.0 / np.median(dt)) if len(dt) else float(default)


# ---------------------------------------------------------------------------------------------
# CSV


def _fmt(v: float) -> str:
    return f"{v:.4f}" if math.isfinite(v) else "nan"


class TrackCsvWriter(StreamedFile):
    """Writes a track CSV one row at a time, so a stream of any length needs no memory for it.

    The rows go to a temporary file beside ``path``; :meth:`close` moves the finished file into
    place (an interrupted write leaves any previous file untouched), :meth:`abort` discards it.
    As a context manager it closes on success and aborts on an exception.
    """

    def __init__(self, path: str | os.PathLike, extra: Sequence[str] = EXTRA_COLUMNS):
        super().__init__(path, "w", newline="")
        self.extra = tuple(extra)
        self.rows = 0
        self._w = csv.writer(self._f)
        self._w.writerow(list(CSV_COLUMNS) + list(self.extra))

    def write(self, r: FaceParams) -> None:
        """Append one frame's row: the contract's columns, then the ``extra`` fields."""
        line = [str(r.frame)] + [_fmt(getattr(r, n)) for n in PARAM_NAMES]
        for e in self.extra:
            v = getattr(r, e)
            line.append(_fmt(v) if isinstance(v, float) else str(v))
        self._w.writerow(line)
        self.rows += 1


def write_csv(path: str | os.PathLike, rows: Iterable[FaceParams], extra: Sequence[str] = EXTRA_COLUMNS) -> None:
    """Write a track CSV atomically: the contract's columns, then ``extra`` fields of the record."""
    with TrackCsvWriter(path, extra) as w:
        for r in rows:
            w.write(r)


VALUE_LIMIT = 1e6
"""Largest magnitude a track value may have (pixels or degrees); NaN (not measured) is allowed."""
FRAME_LIMIT = 2**31
TIME_LIMIT = 1e8
"""Seconds; about three years."""
_TOKEN_MAX = 64
_STATUS_MAX = 32


def _short(tok: str) -> str:
    return repr(tok if len(tok) <= 24 else tok[:16] + "…")


def _number(tok: str, column: str, lo: float, hi: float, nan_ok: bool) -> float:
    tok = tok.strip()
    if len(tok) > _TOKEN_MAX:
        raise ValueError(f"{column} value {_short(tok)} is too long for a number")
    try:
        v = float(tok)
    except ValueError:
        raise ValueError(f"{column} value {_short(tok)} is not a number") from None
    if math.isnan(v):
        if nan_ok:
            return v
        raise ValueError(f"{column} must be a number, not NaN")
    if not lo <= v <= hi:
        raise ValueError(f"{column} value {_short(tok)} is out of range ({lo:g} to {hi:g})")
    return v


def _frame_index(tok: str) -> int:
    v = _number(tok, "frame", -FRAME_LIMIT, FRAME_LIMIT - 1, nan_ok=False)
    if not v.is_integer():
        raise ValueError(f"frame {_short(tok.strip())} is not a whole number")
    return int(v)


def read_csv(path: str | os.PathLike) -> list[FaceParams]:
    """Read a track CSV written by Inkface or any tool that follows the contract.

    The first eleven columns must be the contract's; ``time``, ``status`` and ``confidence``
    are read when present (time defaults to the frame index at 30 fps). Values must be numbers
    within ±:data:`VALUE_LIMIT` or NaN (not measured), frames whole numbers, times finite,
    confidences in [0, 1] (NaN reads as 0). Raises :class:`TrackFormatError` with a one-line message naming the
    file (and line).
    """
    path = Path(path)
    try:
        f = open(path, newline="", encoding="utf-8")
    except OSError as e:
        raise TrackFormatError(f"{path}: cannot open track ({e.strerror or e})") from None
    with f:
        reader = csv.reader(f)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise TrackFormatError(f"{path}: empty file, expected a header row") from None
        except (csv.Error, UnicodeDecodeError) as e:
            raise TrackFormatError(f"{path}: not a CSV file ({e})") from None
        except OSError as e:
            raise TrackFormatError(f"{path}: cannot read track ({e.strerror or e})") from None
        if tuple(header[: len(CSV_COLUMNS)]) != CSV_COLUMNS:
            raise TrackFormatError(f"{path}: header must start with {','.join(CSV_COLUMNS)}")
        idx = {name: i for i, name in enumerate(header)}

        def column(row: list[str], name: str) -> str | None:
            i = idx.get(name)
            return row[i] if i is not None and i < len(row) else None

        out: list[FaceParams] = []
        lineno = 1
        try:
            for lineno, row in enumerate(reader, start=2):
                if not row or all(not c.strip() for c in row):
                    continue
                if len(row) < len(CSV_COLUMNS):
                    raise TrackFormatError(f"{path}:{lineno}: expected {len(CSV_COLUMNS)} columns, got {len(row)}")
                try:
                    frame = _frame_index(row[0])
                    vals = [_number(c, n, -VALUE_LIMIT, VALUE_LIMIT, nan_ok=True)
                            for c, n in zip(row[1 : len(CSV_COLUMNS)], PARAM_NAMES)]
                    tok = column(row, "time")
                    t = _number(tok, "time", -TIME_LIMIT, TIME_LIMIT, nan_ok=False) if tok is not None else frame / 30.0
                    tok = column(row, "confidence")
                    conf = _number(tok, "confidence", 0.0, 1.0, nan_ok=True) if tok is not None else 1.0
                    conf = 0.0 if math.isnan(conf) else conf  # not known: no confidence
                    status = (column(row, "status") or "").strip() or OK
                    if len(status) > _STATUS_MAX or not status.isprintable():
                        raise ValueError(f"status {_short(status)} is not a status")
                except ValueError as e:
                    raise TrackFormatError(f"{path}:{lineno}: {e}") from None
                out.append(FaceParams.from_values(vals, frame=frame, time=t, status=status, confidence=conf))
        except (csv.Error, UnicodeDecodeError) as e:
            raise TrackFormatError(f"{path}:{lineno + 1}: not a CSV file ({_one_line(e)})") from None
        except OSError as e:
            raise TrackFormatError(f"{path}: cannot read track ({e.strerror or e})") from None
    return out


def _one_line(e: BaseException) -> str:
    lines = str(e).strip().splitlines()
    return lines[0][:120] if lines else type(e).__name__


# ---------------------------------------------------------------------------------------------
# The 8-bit codec

QUANT_RANGES: dict[str, tuple[float, float]] = {
    "mid_x": (0.0, 1.0),  # fraction of frame width
    "mid_y": (0.0, 1.0),  # fraction of frame height
    "roll_deg": (-45.0, 45.0),  # degrees
    "eye_open_l": (0.0, 0.5),  # fraction of the inter-pupil distance
    "eye_open_r": (0.0, 0.5),
    "brow_l": (0.0, 1.0),
    "brow_r": (0.0, 1.0),
    "mouth_width": (0.0, 1.6),
    "lip_upper": (-0.2, 0.8),
    "lip_lower": (-0.2, 1.2),
}
"""Quantisation range of each value, in the unit the codec uses for it (see comments).

Each range is split into 255 equal steps; values outside are clipped to it.
"""

_LO = np.array([QUANT_RANGES[n][0] for n in PARAM_NAMES])
_HI = np.array([QUANT_RANGES[n][1] for n in PARAM_NAMES])


class ParamCodec:
    """Quantise the ten values to one byte each.

    Positions are stored as a fraction of the frame size, roll in degrees, lengths as a
    fraction of the inter-pupil distance ``ipd`` (pixels), so the receiver needs the same
    ``frame_size`` and ``ipd`` to restore pixels. Round-trip error is at most half a step
    (:meth:`step`) for values inside :data:`QUANT_RANGES`.
    """

    def __init__(self, frame_size: tuple[int, int], ipd: float):
        w, h = frame_size
        if w <= 0 or h <= 0:
            raise ValueError(f"frame size must be positive, got {frame_size}")
        if not ipd > 0:
            raise ValueError(f"inter-pupil distance must be positive, got {ipd}")
        self.frame_size = (int(w), int(h))
        self.ipd = float(ipd)
        # scale converts codec units to pixels / degrees
        self._scale = np.array([w, h, 1.0] + [self.ipd] * 7, dtype=np.float64)
        self._lo = _LO * self._scale
        self._span = (_HI - _LO) * self._scale

    def step(self) -> np.ndarray:
        """The quantisation step of each value in pixels / degrees."""
        return self._span / 255.0

    def quantise(self, values: np.ndarray) -> np.ndarray:
        """Ten values (pixels / degrees) to ten ``uint8`` codes."""
        v = np.asarray(values, dtype=np.float64)
        v = np.where(np.isfinite(v), v, self._lo)
        q = np.rint((v - self._lo) / self._span * 255.0)
        return np.clip(q, 0, 255).astype(np.uint8)

    def dequantise(self, codes: np.ndarray) -> np.ndarray:
        """Ten ``uint8`` codes back to pixels / degrees."""
        return self._lo + np.asarray(codes, dtype=np.float64) / 255.0 * self._span

    def encode(self, params: FaceParams) -> bytes:
        """The 10-byte payload of one frame."""
        return self.quantise(params.values()).tobytes()

    def decode(self, payload: bytes, frame: int = 0, time: float = 0.0, status: str = OK) -> FaceParams:
        """A 10-byte payload back to a record."""
        if len(payload) != len(PARAM_NAMES):
            raise PacketError(f"payload must be {len(PARAM_NAMES)} bytes, got {len(payload)}")
        codes = np.frombuffer(payload, dtype=np.uint8)
        return FaceParams.from_values(self.dequantise(codes), frame=frame, time=time, status=status)


PACKET_MAGIC = b"IF"
PACKET_VERSION = 1
_HEADER = struct.Struct("<2sBBII")  # magic, version, status code, sequence, timestamp (ms)
PACKET_SIZE = _HEADER.size + len(PARAM_NAMES)
"""Bytes in one frame packet: a 12-byte header and the 10-byte payload."""

_STATUS_CODES = {s: i for i, s in enumerate(STATUSES)}


@dataclass(frozen=True, slots=True)
class Packet:
    """A decoded packet: sequence number (wraps at 2**32), timestamp in ms, status and payload."""

    seq: int
    timestamp_ms: int
    status: str
    payload: bytes = field(repr=False)


def encode_packet(payload: bytes, seq: int, timestamp_ms: int, status: str = OK) -> bytes:
    """Wrap a 10-byte payload in the header. Unknown statuses are sent as ``lost``."""
    if len(payload) != len(PARAM_NAMES):
        raise PacketError(f"payload must be {len(PARAM_NAMES)} bytes, got {len(payload)}")
    code = _STATUS_CODES.get(status, _STATUS_CODES[LOST])
    head = _HEADER.pack(PACKET_MAGIC, PACKET_VERSION, code, seq & 0xFFFFFFFF, int(timestamp_ms) & 0xFFFFFFFF)
    return head + bytes(payload)


def decode_packet(data: bytes) -> Packet:
    """Parse a packet, raising :class:`PacketError` on a wrong size, magic, version or status."""
    if len(data) != PACKET_SIZE:
        raise PacketError(f"packet must be {PACKET_SIZE} bytes, got {len(data)}")
    magic, version, code, seq, ts = _HEADER.unpack_from(data)
    if magic != PACKET_MAGIC:
        raise PacketError(f"not an Inkface packet (magic {magic!r}, expected {PACKET_MAGIC!r})")
    if version != PACKET_VERSION:
        raise PacketError(f"unsupported packet version {version} (this build reads {PACKET_VERSION})")
    if code >= len(STATUSES):
        raise PacketError(f"unknown status code {code}")
    return Packet(seq=seq, timestamp_ms=ts, status=STATUSES[code], payload=bytes(data[_HEADER.size :]))
