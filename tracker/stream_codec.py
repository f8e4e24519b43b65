"""Lossless temporal compression of the 8-bit parameter stream, and a packet-stream file.

The paper sends ten bytes a frame (80 bits, 2400 baud at 30 fps) and remarks that the
coherence between frames should compress further. This coder does that without loss: the
receiver recovers exactly the ten bytes that :class:`tracker.params.ParamCodec` made.

How a frame is coded
    Every ``key_interval``-th frame is a *key frame*: its ten codes are sent raw (10 bytes) and
    both sides reset their state, so a receiver that lost a packet resynchronises there.
    Every other frame is a *delta frame*: each code is predicted from the frames before it
    (the previous value, a linear extrapolation from the last two, or the mean of the last
    four; each channel picks the one that has recently been best, by the same rule on both
    sides, so nothing is sent for the choice). A channel with a partner coded before it (the
    other eye, the other brow, the next lip value) may add the partner's residual to its
    prediction, chosen the same way (both eyes blink together). The residual (mod 256) is
    binarised — zero? sign, magnitude in unary up to 7, from 8 on an Elias-gamma escape — coded
    with an adaptive binary arithmetic coder. Contexts: the channel's group (position, roll,
    eyes, brows, mouth), how busy the channel was last frame and what its partner did this
    frame. The arithmetic code of one frame ends on the fewest whole bytes that identify it
    (a still frame often takes 0 bytes);
    a frame whose code would not be shorter than 10 bytes is sent raw instead (both sides still
    adapt on it), so no frame ever costs more than the uncompressed 80 bits.

A delta frame decodes only when the previous frame was decoded; after a gap the decoder
waits for the next key frame (:meth:`StreamDecoder.decode` returns ``None`` until then).

Packets (compressed), little-endian::

    0  2  magic b"IZ"
    2  1  version (1)
    3  1  flags: bits 0-1 status code (tracker.params.STATUSES), bit 2 key frame
    4  4  sequence number (wraps at 2**32)
    8  4  timestamp, ms
    12 .. payload: 10 raw codes (key frame); delta frame: the arithmetic code (0-9 bytes,
          may be empty) or exactly 10 raw codes

Packet-stream file (``.ifs``): one UTF-8 JSON header line, ``{"format": 1, "kind":
"inkface-packet-stream", "frame_size": [w, h], "ipd": px, "fps": f, "compressed": bool,
"key_interval": n, "neutral": [10 codes] | null}``, then records of a little-endian ``u16``
length followed by one packet (compressed packets above, or the plain 22-byte packets of
:mod:`tracker.params` when ``compressed`` is false).
"""

from __future__ import annotations

import json
import math
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from tracker.outputs import StreamedFile
from tracker.params import (
    LOST,
    OK,
    PARAM_NAMES,
    STATUSES,
    FaceParams,
    PacketError,
    ParamCodec,
    decode_packet,
    encode_packet,
)

N = len(PARAM_NAMES)


class StreamError(ValueError):
    """A compressed packet or packet-stream file is malformed; the message says why (one line)."""


# ---------------------------------------------------------------------------------------------
# Binary arithmetic coder (32-bit, carry-free with pending bits; 16-bit probabilities)

_TOP = 0xFFFFFFFF
_HALF = 1 << 31
_QUARTER = 1 << 30
_3QUARTER = 3 << 30


class _Encoder:
    __slots__ = ("low", "high", "pending", "bits")

    def __init__(self) -> None:
        self.low = 0
        self.high = _TOP
        self.pending = 0
        self.bits: list[int] = []

    def _emit(self, b: int) -> None:
        self.bits.append(b)
        if self.pending:
            self.bits.extend([1 - b] * self.pending)
            self.pending = 0

    def bit(self, b: int, p0: int) -> None:
        """Code bit ``b`` where ``p0`` is P(0) in units of 1/65536."""
        low, high = self.low, self.high
        split = low + (((high - low + 1) * p0) >> 16) - 1
        if b:
            low = split + 1
        else:
            high = split
        while True:
            if high < _HALF:
                self._emit(0)
            elif low >= _HALF:
                self._emit(1)
                low -= _HALF
                high -= _HALF
            elif low >= _QUARTER and high < _3QUARTER:
                self.pending += 1
                low -= _QUARTER
                high -= _QUARTER
            else:
                break
            low <<= 1
            high = (high << 1) | 1
        self.low, self.high = low, high

    def finish(self) -> bytes:
        """The shortest byte string whose zero-padded value lies in the final interval."""
        low, high = self.low, self.high
        for k in range(1 if self.pending else 0, 33):
            unit = 1 << (32 - k)
            v = -(-low // unit) * unit
            if v <= high:
                break
        if k:
            top = v >> 31
            self._emit(top)
            for i in range(30, 31 - k, -1):
                self.bits.append((v >> i) & 1)
        bits = self.bits
        while bits and bits[-1] == 0:
            bits.pop()
        if not bits:
            return b""
        bits = bits + [0] * (-len(bits) % 8)
        return np.packbits(np.array(bits, dtype=np.uint8)).tobytes()


class _Decoder:
    __slots__ = ("low", "high", "value", "data", "pos", "nbits")

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.nbits = len(data) * 8
        self.pos = 0
        self.low = 0
        self.high = _TOP
        v = 0
        for _ in range(32):
            v = (v << 1) | self._next()
        self.value = v

    def _next(self) -> int:
        p = self.pos
        self.pos = p + 1
        if p >= self.nbits:
            return 0
        return (self.data[p >> 3] >> (7 - (p & 7))) & 1

    def bit(self, p0: int) -> int:
        low, high, value = self.low, self.high, self.value
        split = low + (((high - low + 1) * p0) >> 16) - 1
        if value <= split:
            high = split
            b = 0
        else:
            low = split + 1
            b = 1
        while True:
            if high < _HALF:
                pass
            elif low >= _HALF:
                low -= _HALF
                high -= _HALF
                value -= _HALF
            elif low >= _QUARTER and high < _3QUARTER:
                low -= _QUARTER
                high -= _QUARTER
                value -= _QUARTER
            else:
                break
            low <<= 1
            high = (high << 1) | 1
            value = (value << 1) | self._next()
        self.low, self.high, self.value = low, high, value
        return b


_COUNT_LIMIT = 240  # counts are halved above this: adapts within a few dozen frames


def _p0(ctx: list[int]) -> int:
    """P(0) of a context [n0, n1] (Krichevsky–Trofimov: counts start at one half each)."""
    p = (ctx[0] << 16) // (ctx[0] + ctx[1])
    return 64 if p < 64 else (65472 if p > 65472 else p)


def _update(ctx: list[int], b: int) -> None:
    ctx[b] += 2
    if ctx[0] + ctx[1] > _COUNT_LIMIT:
        ctx[0] = (ctx[0] + 1) >> 1
        ctx[1] = (ctx[1] + 1) >> 1


# ---------------------------------------------------------------------------------------------
# The model shared by encoder and decoder

# channel -> context group; partner = a channel coded earlier in the same frame that tends to
# move with this one (-1: none)
_GROUP = (0, 0, 1, 2, 2, 3, 3, 4, 4, 4)
_PARTNER = (-1, 0, -1, -1, 3, -1, 5, -1, 7, 8)
_NGROUPS = 5
_UNARY = 8  # magnitudes 1.._UNARY-1 in unary, then an escape
_ACT = 3  # activity buckets: 0, 1, >=2


def _bucket(m: int) -> int:
    return 0 if m == 0 else (1 if m == 1 else 2)


def _clip8(v: int) -> int:
    return 0 if v < 0 else (255 if v > 255 else v)


def _predictions(h: list[int]) -> tuple[int, int, int]:
    """Candidate predictions from the last four codes ``h`` (newest first): hold, linear
    extrapolation, and the mean of four (best when the track jitters about a slow motion)."""
    a = h[0]
    return a, _clip8(2 * a - h[1]), (a + h[1] + h[2] + h[3] + 2) >> 2


_NPRED = 3


class _Model:
    """Predictors, residual history and adaptive contexts; reset at every key frame."""

    __slots__ = ("hist", "res", "cost", "zero", "sign", "mag", "follow", "alone")

    def __init__(self, codes: Sequence[int]) -> None:
        self.hist = [[int(c)] * 4 for c in codes]
        self.res = [0] * N
        # running |residual| of each predictor per channel (x8, decays by 1/8 a frame);
        # hold starts ahead so a fresh model prefers it
        self.cost = [[0] + [8] * (_NPRED - 1) for _ in range(N)]
        self.follow = [8] * N
        self.alone = [0] * N
        self.zero = [[[1, 1] for _ in range(_ACT * _ACT)] for _ in range(_NGROUPS)]
        self.sign = [[[1, 1] for _ in range(3)] for _ in range(_NGROUPS)]
        self.mag = [[[[1, 1] for _ in range(_UNARY - 1)] for _ in range(2)] for _ in range(_NGROUPS)]

    def predict(self, c: int, cur_res: list[int] | None = None) -> int:
        cost = self.cost[c]
        best = min(range(_NPRED), key=cost.__getitem__)
        p = _predictions(self.hist[c])[best]
        q = _PARTNER[c]
        if q >= 0 and cur_res is not None and self.follow[c] < self.alone[c]:
            p = _clip8(p + cur_res[q])
        return p

    def contexts(self, c: int, cur_res: list[int]) -> tuple[list[int], list[int], list[list[int]]]:
        g = _GROUP[c]
        own = self.res[c]
        q = _PARTNER[c]
        partner = cur_res[q] if q >= 0 else own
        a_own, a_par = _bucket(abs(own)), _bucket(abs(partner))
        s_ref = partner if partner else own
        s = 0 if s_ref == 0 else (1 if s_ref > 0 else 2)
        return self.zero[g][a_own * _ACT + a_par], self.sign[g][s], self.mag[g][1 if max(a_own, a_par) == 2 else 0]

    def advance(self, codes: Sequence[int], res: list[int]) -> None:
        for c in range(N):
            x = codes[c]
            h = self.hist[c]
            cost = self.cost[c]
            preds = _predictions(h)
            best = min(range(_NPRED), key=cost.__getitem__)
            q = _PARTNER[c]
            if q >= 0:
                base = preds[best]
                self.alone[c] += 8 * abs(x - base) - (self.alone[c] >> 3)
                self.follow[c] += 8 * abs(x - _clip8(base + res[q])) - (self.follow[c] >> 3)
            for k, p in enumerate(preds):
                cost[k] += 8 * abs(x - p) - (cost[k] >> 3)
            h.pop()
            h.insert(0, x)
        self.res = res


def _wrap(d: int) -> int:
    """A difference mod 256 as a signed residual in [-128, 127]."""
    return ((d + 128) & 0xFF) - 128


class StreamEncoder:
    """Code a stream of ten-byte frames; see the module docstring for the scheme.

    ``key_interval`` frames make one group: the first is a key frame. A longer interval
    compresses better, a shorter one recovers sooner after a lost packet.
    """

    def __init__(self, key_interval: int = 30) -> None:
        if key_interval < 1:
            raise ValueError(f"key interval must be at least 1, got {key_interval}")
        self.key_interval = int(key_interval)
        self._count = 0
        self._model: _Model | None = None

    def force_key(self) -> None:
        """Make the next frame a key frame."""
        self._count = 0

    def encode(self, codes: bytes) -> tuple[bool, bytes]:
        """One frame's ten codes -> ``(is_key, payload)``."""
        if len(codes) != N:
            raise StreamError(f"a frame must be {N} bytes, got {len(codes)}")
        codes = bytes(codes)
        key = self._count % self.key_interval == 0 or self._model is None
        self._count += 1
        if key:
            self._model = _Model(codes)
            self._count = 1
            return True, codes
        enc = _Encoder()
        _code_frame(enc, self._model, codes)
        payload = enc.finish()
        # a coded frame is always shorter than a raw one, so a 10-byte delta payload means raw
        return False, payload if len(payload) < N else codes


def _code_frame(enc: _Encoder, m: _Model, codes: Sequence[int]) -> None:
    """Code one delta frame into ``enc`` and advance the model (contexts adapt as they code)."""
    res = [0] * N
    for c in range(N):
        r = _wrap(codes[c] - m.predict(c, res))
        res[c] = r
        _code_residual(enc, m.contexts(c, res), r)
    m.advance(codes, res)


class StreamDecoder:
    """Undo :class:`StreamEncoder`, tracking sequence numbers so a gap waits for a key frame."""

    def __init__(self) -> None:
        self._model: _Model | None = None
        self._last_seq: int | None = None

    @property
    def synced(self) -> bool:
        return self._model is not None

    def reset(self) -> None:
        self._model = None
        self._last_seq = None

    def decode(self, key: bool, payload: bytes, seq: int | None = None) -> bytes | None:
        """The ten codes of a frame, or ``None`` when it cannot be decoded yet (lost reference).

        With ``seq`` given, a delta frame decodes only if it directly follows the last decoded
        frame. Raises :class:`StreamError` on a malformed payload (the decoder then waits for a
        key frame).
        """
        if key:
            if len(payload) != N:
                self.reset()
                raise StreamError(f"key frame payload must be {N} bytes, got {len(payload)}")
            self._model = _Model(payload)
            self._last_seq = seq
            return bytes(payload)
        m = self._model
        if m is None:
            return None
        if seq is not None and self._last_seq is not None and seq != (self._last_seq + 1) & 0xFFFFFFFF:
            self.reset()
            return None
        if len(payload) > N:
            self.reset()
            raise StreamError(f"delta frame payload too long ({len(payload)} bytes)")
        if len(payload) == N:  # sent raw because it did not compress: adapt as the encoder did
            _code_frame(_Encoder(), m, payload)
            self._last_seq = seq
            return bytes(payload)
        dec = _Decoder(payload)
        res = [0] * N
        codes = [0] * N
        try:
            for c in range(N):
                r = _decode_residual(dec, m.contexts(c, res))
                res[c] = r
                codes[c] = (m.predict(c, res) + r) & 0xFF
        except StreamError:
            self.reset()
            raise
        m.advance(codes, res)
        self._last_seq = seq
        return bytes(codes)


def _code_residual(enc: _Encoder, ctxs, r: int) -> None:
    zc, sc, mc = ctxs
    if r == 0:
        enc.bit(0, _p0(zc))
        _update(zc, 0)
        return
    enc.bit(1, _p0(zc))
    _update(zc, 1)
    s = 1 if r < 0 else 0
    enc.bit(s, _p0(sc))
    _update(sc, s)
    m = -r if r < 0 else r
    for i in range(_UNARY - 1):  # bin i: "magnitude > i + 1 ?"
        b = 1 if m > i + 1 else 0
        ctx = mc[i]
        enc.bit(b, _p0(ctx))
        _update(ctx, b)
        if not b:
            return
    # escape: m - _UNARY >= 0 in Elias-gamma of (m - _UNARY + 1), ones-terminated-by-zero prefix
    v = m - _UNARY + 1
    nb = v.bit_length() - 1
    for _ in range(nb):
        enc.bit(1, 32768)
    enc.bit(0, 32768)
    for i in range(nb - 1, -1, -1):
        enc.bit((v >> i) & 1, 32768)


def _decode_residual(dec: _Decoder, ctxs) -> int:
    zc, sc, mc = ctxs
    b = dec.bit(_p0(zc))
    _update(zc, b)
    if not b:
        return 0
    s = dec.bit(_p0(sc))
    _update(sc, s)
    m = _UNARY
    for i in range(_UNARY - 1):
        ctx = mc[i]
        b = dec.bit(_p0(ctx))
        _update(ctx, b)
        if not b:
            m = i + 1
            break
    else:
        nb = 0
        while dec.bit(32768):
            nb += 1
            if nb > 8:
                raise StreamError("corrupt delta frame (escape code too long)")
        v = 1
        for _ in range(nb):
            v = (v << 1) | dec.bit(32768)
        m = v + _UNARY - 1
        if m > 128:
            raise StreamError(f"corrupt delta frame (residual {m} out of range)")
    return -m if s else m


# ---------------------------------------------------------------------------------------------
# Compressed packets

STREAM_MAGIC = b"IZ"
STREAM_VERSION = 1
_HEADER = struct.Struct("<2sBBII")
STREAM_HEADER_SIZE = _HEADER.size
_KEY_FLAG = 0x04
_STATUS_CODES = {s: i for i, s in enumerate(STATUSES)}


@dataclass(frozen=True, slots=True)
class StreamPacket:
    """A parsed compressed packet."""

    seq: int
    timestamp_ms: int
    status: str
    key: bool
    payload: bytes = field(repr=False)


def encode_stream_packet(key: bool, payload: bytes, seq: int, timestamp_ms: int, status: str = OK) -> bytes:
    """Wrap a coded frame in the compressed-packet header (unknown statuses travel as ``lost``)."""
    if key and len(payload) != N:
        raise StreamError(f"key frame payload must be {N} bytes, got {len(payload)}")
    flags = _STATUS_CODES.get(status, _STATUS_CODES[LOST]) | (_KEY_FLAG if key else 0)
    return _HEADER.pack(STREAM_MAGIC, STREAM_VERSION, flags, seq & 0xFFFFFFFF, int(timestamp_ms) & 0xFFFFFFFF) + bytes(payload)


def decode_stream_packet(data: bytes) -> StreamPacket:
    """Parse a compressed packet; :class:`StreamError` on a wrong size, magic, version or flags."""
    if len(data) < _HEADER.size:
        raise StreamError(f"compressed packet too short ({len(data)} bytes)")
    magic, version, flags, seq, ts = _HEADER.unpack_from(data)
    if magic != STREAM_MAGIC:
        raise StreamError(f"not a compressed Inkface packet (magic {magic!r})")
    if version != STREAM_VERSION:
        raise StreamError(f"unsupported compressed packet version {version} (this build reads {STREAM_VERSION})")
    if flags & ~(_KEY_FLAG | 0x03):
        raise StreamError(f"unknown flags 0x{flags:02x} in compressed packet")
    key = bool(flags & _KEY_FLAG)
    payload = bytes(data[_HEADER.size :])
    if key and len(payload) != N:
        raise StreamError(f"key frame payload must be {N} bytes, got {len(payload)}")
    if len(payload) > N:
        raise StreamError(f"delta frame payload too long ({len(payload)} bytes)")
    return StreamPacket(seq=seq, timestamp_ms=ts, status=STATUSES[flags & 0x03], key=key, payload=payload)


def compress_frames(frames: Iterable[bytes], key_interval: int = 30) -> list[tuple[bool, bytes]]:
    """Code a whole sequence of ten-byte frames (for tests and measurements)."""
    enc = StreamEncoder(key_interval)
    return [enc.encode(f) for f in frames]


def decompress_frames(coded: Iterable[tuple[bool, bytes]]) -> list[bytes]:
    """Decode a sequence made by :func:`compress_frames` with no losses."""
    dec = StreamDecoder()
    out = []
    for key, payload in coded:
        f = dec.decode(key, payload)
        if f is None:
            raise StreamError("delta frame before the first key frame")
        out.append(f)
    return out


# ---------------------------------------------------------------------------------------------
# Packet-stream files

STREAM_FILE_FORMAT = 1
STREAM_FILE_KIND = "inkface-packet-stream"
_LEN = struct.Struct("<H")
_HEADER_MAX = 4096  # bytes of the JSON header line (ours is about 200)


@dataclass
class StreamHeader:
    """What a receiver needs to turn codes back into pixels: frame size, ipd; plus fps etc."""

    frame_size: tuple[int, int]
    ipd: float
    fps: float = 30.0
    compressed: bool = True
    key_interval: int = 30
    neutral: list[int] | None = None

    def to_dict(self) -> dict:
        return {
            "format": STREAM_FILE_FORMAT,
            "kind": STREAM_FILE_KIND,
            "frame_size": list(self.frame_size),
            "ipd": self.ipd,
            "fps": self.fps,
            "compressed": self.compressed,
            "key_interval": self.key_interval,
            "neutral": self.neutral,
        }


class StreamFileWriter(StreamedFile):
    """Writes a packet-stream file one packet at a time (memory does not grow with its length).

    Packets go to a temporary file beside ``path``; :meth:`close` moves the finished file into
    place, :meth:`abort` discards it (a previous file stays as it was). As a context manager it
    closes on success and aborts on an exception.
    """

    def __init__(self, path: str | os.PathLike, header: StreamHeader):
        super().__init__(path, "wb")
        self.header = header
        self.packets = 0
        self._f.write(json.dumps(header.to_dict()).encode() + b"\n")

    def write_packet(self, p: bytes) -> None:
        if len(p) > 0xFFFF:
            raise StreamError(f"packet of {len(p)} bytes is too long for a stream file")
        self._f.write(_LEN.pack(len(p)) + p)
        self.packets += 1


def write_stream(path: str | os.PathLike, header: StreamHeader, packets: Iterable[bytes]) -> None:
    """Write a packet-stream file atomically."""
    with StreamFileWriter(path, header) as w:
        for p in packets:
            w.write_packet(p)


def read_stream(path: str | os.PathLike) -> tuple[StreamHeader, list[bytes]]:
    """Read a packet-stream file; :class:`StreamError` names the file and the problem."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise StreamError(f"{path}: cannot read packet stream ({e.strerror or e})") from None
    nl = data.find(b"\n")
    if nl < 0:
        raise StreamError(f"{path}: not a packet-stream file (no header line)")
    if nl > _HEADER_MAX:
        raise StreamError(f"{path}: not a packet-stream file (header line longer than {_HEADER_MAX} bytes)")
    try:
        h = json.loads(data[:nl].decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):  # JSONDecodeError is a ValueError
        raise StreamError(f"{path}: not a packet-stream file (header is not JSON)") from None
    if not isinstance(h, dict) or h.get("kind") != STREAM_FILE_KIND:
        raise StreamError(f"{path}: not a packet-stream file (kind is not {STREAM_FILE_KIND!r})")
    if h.get("format") != STREAM_FILE_FORMAT:
        raise StreamError(f"{path}: unsupported packet-stream format {h.get('format')!r} (this build reads {STREAM_FILE_FORMAT})")
    try:
        w, hh = (int(v) for v in h["frame_size"])
        neutral = h.get("neutral")
        header = StreamHeader(
            frame_size=(w, hh),
            ipd=float(h["ipd"]),
            fps=float(h.get("fps", 30.0)),
            compressed=bool(h.get("compressed", True)),
            key_interval=int(h.get("key_interval", 30)),
            neutral=[int(v) & 0xFF for v in neutral] if neutral else None,
        )
        if not (0 < w <= 65535 and 0 < hh <= 65535):
            raise ValueError("frame size must be 1 to 65535 pixels a side")
        if not (math.isfinite(header.ipd) and header.ipd > 0 and math.isfinite(header.fps) and header.fps > 0):
            raise ValueError("ipd and fps must be positive numbers")
        if header.neutral is not None and len(header.neutral) != N:
            raise ValueError(f"neutral must have {N} codes")
    except (KeyError, TypeError, ValueError, OverflowError) as e:
        raise StreamError(f"{path}: bad packet-stream header ({e})") from None
    packets = []
    pos = nl + 1
    while pos < len(data):
        if pos + 2 > len(data):
            raise StreamError(f"{path}: truncated packet record at byte {pos}")
        (n,) = _LEN.unpack_from(data, pos)
        pos += 2
        if pos + n > len(data):
            raise StreamError(f"{path}: truncated packet record at byte {pos - 2}")
        packets.append(data[pos : pos + n])
        pos += n
    return header, packets


def packets_to_track(header: StreamHeader, packets: Iterable[bytes], skip_bad: bool = True) -> list[FaceParams]:
    """Decode packets back to a track. Undecodable frames are skipped (or raise with ``skip_bad=False``)."""
    codec = ParamCodec(header.frame_size, header.ipd)
    dec = StreamDecoder()
    out = []
    for data in packets:
        try:
            if header.compressed:
                p = decode_stream_packet(data)
                codes = dec.decode(p.key, p.payload, p.seq)
                if codes is None:
                    if skip_bad:
                        continue
                    raise StreamError(f"frame {p.seq} cannot be decoded (its reference frame is missing)")
            else:
                p = decode_packet(data)
                codes = p.payload
        except (StreamError, PacketError):
            if skip_bad:
                continue
            raise
        out.append(codec.decode(codes, frame=p.seq, time=p.timestamp_ms / 1000.0, status=p.status))
    return out


class TrackStreamWriter(StreamFileWriter):
    """Records a parameter track as a packet-stream file frame by frame: sequence numbers from 0,
    timestamps from each record's ``time``; ``frame_size`` and ``ipd`` fix the quantisation."""

    def __init__(
        self,
        path: str | os.PathLike,
        frame_size: tuple[int, int],
        ipd: float,
        fps: float = 30.0,
        compressed: bool = True,
        key_interval: int = 30,
        neutral: FaceParams | None = None,
    ):
        self.codec = ParamCodec(frame_size, ipd)
        header = StreamHeader(
            frame_size=(int(frame_size[0]), int(frame_size[1])),
            ipd=float(ipd),
            fps=float(fps),
            compressed=compressed,
            key_interval=key_interval,
            neutral=list(self.codec.encode(neutral)) if neutral is not None else None,
        )
        self._enc = StreamEncoder(key_interval) if compressed else None
        super().__init__(path, header)

    def write(self, r: FaceParams) -> None:
        """Append one frame."""
        codes = self.codec.encode(r)
        ts = int(round(r.time * 1000.0)) if math.isfinite(r.time) else 0
        seq = self.packets
        if self._enc is None:
            self.write_packet(encode_packet(codes, seq, ts, r.status))
        else:
            key, payload = self._enc.encode(codes)
            self.write_packet(encode_stream_packet(key, payload, seq, ts, r.status))


def write_track_stream(
    path: str | os.PathLike,
    rows: Sequence[FaceParams],
    frame_size: tuple[int, int],
    ipd: float,
    fps: float = 30.0,
    compressed: bool = True,
    key_interval: int = 30,
    neutral: FaceParams | None = None,
) -> None:
    """Record a parameter track as a packet-stream file."""
    with TrackStreamWriter(path, frame_size, ipd, fps, compressed, key_interval, neutral) as w:
        for r in rows:
            w.write(r)


def read_track_stream(path: str | os.PathLike) -> tuple[StreamHeader, list[FaceParams]]:
    """Read a packet-stream file back to ``(header, track)``; frames that cannot be decoded are skipped."""
    header, packets = read_stream(path)
    return header, packets_to_track(header, packets)


@dataclass
class TrackFile:
    """A parameter track read from any of the three files, with what the file knows about it
    (``None`` where it does not say)."""

    rows: list[FaceParams]
    frame_size: tuple[int, int] | None
    ipd: float | None
    fps: float | None
    neutral: FaceParams | None


def read_track(path: str | os.PathLike) -> TrackFile:
    """Read a track CSV, a packet-stream file (``.ifs``) or an MPEG-4 FAP file (``.fap``).

    Raises the reader's one-line error (:class:`tracker.params.TrackFormatError`,
    :class:`StreamError` or :class:`tracker.fap.FapError`), each naming the file.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".ifs":
        header, rows = read_track_stream(path)
        neutral = None
        if header.neutral is not None:
            neutral = ParamCodec(header.frame_size, header.ipd).decode(bytes(header.neutral))
        return TrackFile(rows, header.frame_size, header.ipd, header.fps, neutral)
    if suffix == ".fap":
        from tracker.fap import read_fap

        fap = read_fap(path)
        return TrackFile(fap.rows, None, fap.fapu.es0, fap.fps, fap.neutral)
    from tracker.params import read_csv

    return TrackFile(read_csv(path), None, None, None, None)
