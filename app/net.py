"""The teleconference split over UDP: a sender of parameter packets and a receiver (no Qt).

The paper's application: the tracker runs on the sender's machine and only ten bytes a frame
cross the network; the receiver draws the character. Both halves are plain classes so the
command line (``python -m app send`` / ``receive``) and the performance window share them.

On the wire (all datagrams little-endian, each self-describing by its two magic bytes):

* ``IH`` hello, sent first and again every ``hello_every`` frames (UDP may lose it): session id,
  frame size, ipd, fps, whether frames are compressed, key interval and the performer's neutral
  face as ten codes — what the receiver needs to turn codes back into pixels (see :data:`_HELLO`).
* ``IF`` a plain frame packet of :mod:`tracker.params` (12-byte header + ten codes), or
* ``IZ`` a compressed frame packet of :mod:`tracker.stream_codec` (12-byte header + 0..10 bytes).

The receiver binds 127.0.0.1 unless told otherwise, follows one sender at a time (the source
address of the hello it accepted; others are *foreign* until that sender has been silent for
``switch_after_s``), counts and drops malformed and foreign datagrams (it never raises on
input), detects loss, duplicates and reordering from sequence numbers (a late frame is counted
and dropped: a newer pose is already shown), holds the last pose for ``hold_s`` when packets
stop and then eases to the neutral face over ``ease_s``, and measures bandwidth.

Sequence numbers are taken only in a window around the expected one (:data:`SEQ_AHEAD` ahead,
:data:`SEQ_BEHIND` behind): a packet outside it is counted as an *anomaly* and ignored, so one
stray datagram cannot move the stream's position. A sender that really jumped (it restarted
and its hello was lost, or the link was down for a while) is followed again after
:data:`RESYNC_AFTER` packets that agree with each other; a new hello re-synchronises at once.
Bandwidth figures count UDP payload bytes; IPv4 + UDP headers add 28 bytes per datagram.

Use from a window or a loop (no threads needed; ``poll`` never blocks longer than asked)::

    rx = UdpReceiver(9000)                  # 127.0.0.1:9000
    rx.poll(0.01)                           # handle what arrived -> list of new FaceParams
    pose = rx.pose()                        # newest, held, or easing to neutral (None before any)
    rx.frames(0.01)                         # or: every received frame, plus held / easing poses
                                            #     at the sender's rate while none arrive
    rx.stats.summary()                      # loss, reordering, drops, bits/frame, bit/s

    tx = Sender("127.0.0.1:9000", frame_size=(640, 480), ipd=cal.ipd, neutral=cal.neutral, compress=True)
    tx.send(face_params)                    # per tracked frame
"""

from __future__ import annotations

import math
import os
import socket
import struct
import time
from collections import deque
from dataclasses import dataclass
from typing import Callable

import numpy as np

from tracker.params import (
    LOST,
    PACKET_MAGIC,
    PARAM_NAMES,
    FaceParams,
    PacketError,
    ParamCodec,
    decode_packet,
    encode_packet,
)
from tracker.stream_codec import (
    STREAM_MAGIC,
    StreamDecoder,
    StreamEncoder,
    StreamError,
    decode_stream_packet,
    encode_stream_packet,
)

N = len(PARAM_NAMES)
HELLO_MAGIC = b"IH"
HELLO_VERSION = 1
# magic, version, flags (bit 0 compressed, bit 1 neutral present), session id, width, height,
# ipd (px, float32), fps x 100, key interval, neutral codes
_HELLO = struct.Struct("<2sBBIHHfHH10s")
HELLO_SIZE = _HELLO.size
UDP_IP_OVERHEAD = 28
"""Bytes of IPv4 + UDP header around every datagram (not counted in the bandwidth figures)."""
SEQ_AHEAD = 10
"""A frame up to this many sequence numbers ahead of the last one is taken at once (the ones
skipped count as lost); farther ahead needs :data:`RESYNC_AFTER` agreeing packets."""
SEQ_BEHIND = 256
"""A frame up to this far behind is a late (reordered) or duplicate frame; farther is an anomaly."""
RESYNC_AFTER = 3
"""Consecutive packets outside the window, each following the one before (within
:data:`SEQ_AHEAD`), that move the stream to them: a stray packet costs nothing, a real jump
costs ``RESYNC_AFTER - 1`` frames."""
_RATE_TICKS = 10  # rate window resolution: sums per 1/10 s
_RUNS_KEPT = 64  # runs of agreeing anomalies followed at once (stray packets between do not break one)


class NetError(ValueError):
    """A network setting or socket operation failed; the message is one line."""


def parse_address(text: str, default_host: str | None = None) -> tuple[str, int]:
    """``HOST:PORT`` (or ``[v6]:PORT``; ``:PORT`` with ``default_host``) -> ``(host, port)``."""
    s = text.strip()
    if s.startswith("["):
        host, sep, port = s[1:].partition("]:")
    else:
        host, sep, port = s.rpartition(":")
    if not sep:
        raise NetError(f"address {text!r} must be HOST:PORT, e.g. 127.0.0.1:9000")
    if not host:
        if default_host is None:
            raise NetError(f"address {text!r} has no host (use HOST:PORT, e.g. 127.0.0.1:9000)")
        host = default_host
    return host, check_port(port, allow_zero=False)


def check_port(value: str | int, allow_zero: bool = True) -> int:
    """A UDP port number, or :class:`NetError` naming the bad value."""
    try:
        port = int(str(value).strip())
    except ValueError:
        raise NetError(f"port {value!r} is not a number") from None
    lo = 0 if allow_zero else 1
    if not lo <= port <= 65535:
        raise NetError(f"port {port} is out of range ({lo}..65535)")
    return port


def _resolve(host: str, port: int) -> tuple[int, tuple]:
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)
    except (socket.gaierror, UnicodeError) as e:
        raise NetError(f"cannot resolve host {host!r} ({getattr(e, 'strerror', None) or e})") from None
    if not infos:
        raise NetError(f"cannot resolve host {host!r}")
    # prefer IPv4: "localhost" may resolve to ::1 first while the receiver listens on 127.0.0.1
    infos.sort(key=lambda i: i[0] != socket.AF_INET)
    family, _, _, _, addr = infos[0]
    return family, addr


# ---------------------------------------------------------------------------------------------
# hello


@dataclass(frozen=True)
class Hello:
    """The stream's configuration as the receiver learns it."""

    session: int
    frame_size: tuple[int, int]
    ipd: float
    fps: float = 30.0
    compressed: bool = False
    key_interval: int = 30
    neutral_codes: bytes | None = None

    def encode(self) -> bytes:
        flags = (1 if self.compressed else 0) | (2 if self.neutral_codes is not None else 0)
        return _HELLO.pack(
            HELLO_MAGIC, HELLO_VERSION, flags, self.session & 0xFFFFFFFF, self.frame_size[0], self.frame_size[1],
            self.ipd, int(round(self.fps * 100)) & 0xFFFF, self.key_interval & 0xFFFF, self.neutral_codes or bytes(N),
        )  # fmt: skip

    @classmethod
    def decode(cls, data: bytes) -> "Hello":
        if len(data) != HELLO_SIZE:
            raise PacketError(f"hello must be {HELLO_SIZE} bytes, got {len(data)}")
        magic, version, flags, session, w, h, ipd, fps100, key_interval, neutral = _HELLO.unpack(data)
        if magic != HELLO_MAGIC:
            raise PacketError(f"not an Inkface hello (magic {magic!r})")
        if version != HELLO_VERSION:
            raise PacketError(f"unsupported hello version {version}")
        if flags & ~3:
            raise PacketError(f"unknown hello flags 0x{flags:02x}")
        if w == 0 or h == 0 or not (math.isfinite(ipd) and ipd > 0) or fps100 == 0 or key_interval == 0:
            raise PacketError("hello with a zero frame size, ipd, fps or key interval")
        return cls(session, (w, h), float(ipd), fps100 / 100.0, bool(flags & 1), key_interval, neutral if flags & 2 else None)


def _f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


# ---------------------------------------------------------------------------------------------
# sender


@dataclass
class SendStats:
    frames: int = 0
    hellos: int = 0
    bytes: int = 0  # every datagram, UDP payload
    payload_bytes: int = 0  # frame payloads only (the ten codes, or their compressed code)
    dropped: int = 0  # frame packets deliberately not sent (simulated loss)

    @property
    def payload_bits_per_frame(self) -> float:
        return 8.0 * self.payload_bytes / self.frames if self.frames else 0.0


class Sender:
    """Turn :class:`FaceParams` into UDP datagrams to ``address`` (``(host, port)`` or ``"HOST:PORT"``).

    ``frame_size`` and ``ipd`` fix the 8-bit quantisation (see :class:`tracker.params.ParamCodec`);
    ``neutral`` (the calibrated neutral face) lets the receiver ease to it when packets stop.
    Values the tracker could not measure (NaN) are sent as the last value sent (or neutral), and
    the frame's status says what happened. ``simulate_loss`` drops that fraction of frame packets
    (not hellos) at random, to try a receiver on a lossy link.
    """

    def __init__(
        self,
        address: tuple[str, int] | str,
        frame_size: tuple[int, int],
        ipd: float,
        fps: float = 30.0,
        compress: bool = False,
        key_interval: int = 30,
        neutral: FaceParams | None = None,
        hello_every: int = 30,
        simulate_loss: float = 0.0,
        seed: int | None = None,
    ) -> None:
        host, port = parse_address(address) if isinstance(address, str) else address
        family, self.address = _resolve(host, check_port(port, allow_zero=False))
        w, h = int(frame_size[0]), int(frame_size[1])
        if not (0 < w <= 65535 and 0 < h <= 65535):
            raise NetError(f"frame size {w}x{h} must be between 1 and 65535 pixels")
        if not (math.isfinite(ipd) and ipd > 0):
            raise NetError(f"inter-pupil distance must be positive, got {ipd}")
        ipd = _f32(float(ipd))  # the hello carries float32; both sides must quantise alike
        self.codec = ParamCodec((w, h), ipd)
        self.encoder = StreamEncoder(key_interval) if compress else None
        self.hello = Hello(
            session=int.from_bytes(os.urandom(4), "little"), frame_size=(w, h), ipd=ipd, fps=fps,
            compressed=compress, key_interval=key_interval,
            neutral_codes=self.codec.encode(neutral) if neutral is not None else None,
        )  # fmt: skip
        self.hello_every = max(1, int(hello_every))
        if not 0.0 <= simulate_loss < 1.0:
            raise NetError(f"simulated loss must be in [0, 1), got {simulate_loss}")
        self.simulate_loss = float(simulate_loss)
        self._rng = np.random.default_rng(seed)
        self.stats = SendStats()
        self._seq = 0
        self._last_values: np.ndarray | None = None
        self._neutral_values = neutral.values() if neutral is not None else None
        self._sock = socket.socket(family, socket.SOCK_DGRAM)

    def _send(self, data: bytes) -> None:
        try:
            self._sock.sendto(data, self.address)
        except OSError as e:
            raise NetError(f"cannot send to {self.address[0]}:{self.address[1]} ({e.strerror or e})") from None
        self.stats.bytes += len(data)

    def send_hello(self) -> None:
        self._send(self.hello.encode())
        self.stats.hellos += 1

    def send(self, params: FaceParams) -> int:
        """Send one frame (preceded by a hello when one is due); returns the datagram bytes sent."""
        before = self.stats.bytes
        if self._seq % self.hello_every == 0:
            self.send_hello()
        vals = params.values()
        bad = ~np.isfinite(vals)
        if bad.any():  # a value the tracker could not measure: hold the last one sent (or neutral)
            fill = self._last_values if self._last_values is not None else self._neutral_values
            vals = np.where(bad, fill, vals) if fill is not None else vals
        self._last_values = np.where(np.isfinite(vals), vals, self._last_values if self._last_values is not None else 0.0)
        codes = self.codec.quantise(vals).tobytes()
        ts = int(round(params.time * 1000.0)) if math.isfinite(params.time) else 0
        if self.encoder is None:
            payload, data = codes, encode_packet(codes, self._seq, ts, params.status)
        else:
            key, payload = self.encoder.encode(codes)
            data = encode_stream_packet(key, payload, self._seq, ts, params.status)
        if self.simulate_loss and self._rng.random() < self.simulate_loss:
            self.stats.dropped += 1
        else:
            self._send(data)
        self._seq += 1
        self.stats.frames += 1
        self.stats.payload_bytes += len(payload)
        return self.stats.bytes - before

    def close(self) -> None:
        self._sock.close()

    def __enter__(self) -> "Sender":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# ---------------------------------------------------------------------------------------------
# receiver


@dataclass
class ReceiveStats:
    """Counters of everything the receiver saw (all datagrams are counted exactly once in
    ``frames``, ``hellos``, ``malformed``, ``foreign``, ``duplicates``, ``late``, ``waiting``
    or ``anomalies``)."""

    datagrams: int = 0
    frames: int = 0  # frames decoded and delivered
    hellos: int = 0
    malformed: int = 0  # ours by the magic, but broken
    foreign: int = 0  # not ours, or from another sender
    duplicates: int = 0
    late: int = 0  # arrived after a newer frame (reordered), dropped
    waiting: int = 0  # valid but not decodable yet: no hello, or waiting for a key frame
    lost: int = 0  # sequence numbers never seen (a late arrival takes one back)
    anomalies: int = 0  # sequence number far outside the expected window: ignored
    resyncs: int = 0  # times the stream was followed to a new position after agreeing anomalies
    sessions: int = 0
    bytes: int = 0
    payload_bytes: int = 0  # frame payloads of delivered frames
    bits_per_second: float = 0.0  # all datagrams over the last window
    payload_bits_per_second: float = 0.0
    first_arrival: float = math.nan  # clock seconds of the first and the latest datagram
    last_arrival: float = math.nan

    @property
    def mean_bits_per_second(self) -> float:
        """All datagram bits over the time from the first to the latest datagram."""
        span = self.last_arrival - self.first_arrival
        return 8.0 * self.bytes / span if span > 0 else 0.0

    @property
    def bits_per_frame(self) -> float:
        """Mean frame payload bits per delivered frame (80 for the plain stream)."""
        return 8.0 * self.payload_bytes / self.frames if self.frames else 0.0

    @property
    def loss_rate(self) -> float:
        total = self.frames + self.lost + self.waiting
        return self.lost / total if total else 0.0

    def summary(self) -> str:
        return (
            f"{self.frames} frames, {self.lost} lost, {self.late} late, {self.duplicates} duplicate, "
            f"{self.waiting} waiting, {self.malformed} malformed, {self.foreign} foreign, "
            f"{self.anomalies} out of sequence ({self.resyncs} resyncs); "
            f"{self.bits_per_frame:.1f} payload bits/frame, {self.bits_per_second:.0f} bit/s now, "
            f"{self.mean_bits_per_second:.0f} bit/s mean (UDP payloads)"
        )


def _smoothstep(t: float) -> float:
    t = 0.0 if t < 0 else (1.0 if t > 1 else t)
    return t * t * (3.0 - 2.0 * t)


class Receiver:
    """The socket-free receiving core: feed it datagrams with :meth:`handle`, ask :meth:`pose`.

    ``clock`` gives seconds (monotonic); tests pass their own.
    """

    def __init__(
        self,
        hold_s: float = 0.5,
        ease_s: float = 1.0,
        window_s: float = 2.0,
        switch_after_s: float = 2.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.hold_s, self.ease_s, self.window_s, self.switch_after_s = hold_s, ease_s, window_s, switch_after_s
        self.clock = clock
        self.stats = ReceiveStats()
        self.hello: Hello | None = None
        self.codec: ParamCodec | None = None
        self.neutral: FaceParams | None = None
        self.sender: object = None
        self._decoder = StreamDecoder()
        self._last_seq: int | None = None
        self._missing: deque[int] = deque(maxlen=SEQ_BEHIND)
        self._runs: dict[int, int] = {}  # last seq of a run of agreeing anomalies -> its length
        self._last_from_sender = -math.inf
        self._window: deque[list] = deque()  # [tick start s, datagram bytes, payload bytes]
        self.last_frame: FaceParams | None = None
        self.last_arrival = -math.inf
        self._gap_anchor = -math.inf
        self._gap_frames = 0
        self._resting = False
        self._alive = -math.inf

    # --- input ---------------------------------------------------------------------------------

    def handle(self, data: bytes, addr: object = None, now: float | None = None) -> FaceParams | None:
        """Take one datagram from ``addr``; return the frame it completes, if any. Never raises."""
        now = self.clock() if now is None else now
        st = self.stats
        st.datagrams += 1
        st.bytes += len(data)
        if st.datagrams == 1:
            st.first_arrival = now
        st.last_arrival = now
        try:
            magic = bytes(data[:2])
            if magic == HELLO_MAGIC:
                self._on_hello(Hello.decode(bytes(data)), addr, now)
                self._account(now, len(data), 0)
                return None
            if magic not in (PACKET_MAGIC, STREAM_MAGIC):
                st.foreign += 1
                return None
            if self.sender is not None and addr != self.sender:
                st.foreign += 1
                return None
            if magic == PACKET_MAGIC:
                p = decode_packet(bytes(data))
                key = True
            else:
                p = decode_stream_packet(bytes(data))
                key = p.key
        except (PacketError, StreamError, struct.error, ValueError):
            st.malformed += 1
            return None
        self._account(now, len(data), 0)
        if self.codec is None:
            st.waiting += 1
            return None
        if not self._sequence(p.seq):
            return None
        self._last_from_sender = now
        if magic == PACKET_MAGIC:
            codes = p.payload
        else:
            try:
                codes = self._decoder.decode(key, p.payload, p.seq)
            except StreamError:
                st.malformed += 1
                return None
            if codes is None:
                st.waiting += 1
                self._alive = now  # the sender is there: hold, do not ease, until the key frame
                return None
        frame = self.codec.decode(codes, frame=p.seq, time=p.timestamp_ms / 1000.0, status=p.status)
        st.frames += 1
        st.payload_bytes += len(p.payload)
        self._window[-1][2] += len(p.payload)
        self.last_frame = frame
        self.last_arrival = now
        return frame

    def _on_hello(self, hello: Hello, addr: object, now: float) -> None:
        st = self.stats
        if self.sender is not None and addr != self.sender and now - self._last_from_sender < self.switch_after_s:
            st.foreign += 1
            return
        st.hellos += 1
        self._last_from_sender = now
        if self.hello is not None and hello == self.hello and addr == self.sender:
            return
        if self.hello is None or hello.session != self.hello.session or addr != self.sender:
            st.sessions += 1
            self._decoder.reset()
            self._last_seq = None
            self._missing.clear()
            self._runs.clear()
        self.sender = addr
        self.hello = hello
        try:
            self.codec = ParamCodec(hello.frame_size, hello.ipd)
        except ValueError:  # pragma: no cover - Hello.decode already rejects these
            self.codec = None
            return
        self.neutral = (
            self.codec.decode(hello.neutral_codes, frame=-1) if hello.neutral_codes is not None else None
        )

    def _sequence(self, seq: int) -> bool:
        """Book-keep ``seq``; False when the frame is a duplicate, late or out of sequence (and is
        dropped)."""
        st = self.stats
        last = self._last_seq
        if last is None:
            self._last_seq = seq
            return True
        d = ((seq - last + 0x80000000) & 0xFFFFFFFF) - 0x80000000  # signed distance, wrapping
        if 0 < d <= SEQ_AHEAD:
            st.lost += d - 1
            for s in range(1, d):
                self._missing.append((last + s) & 0xFFFFFFFF)
            self._last_seq = seq
            self._runs.clear()
            return True
        if d == 0:
            st.duplicates += 1
            return False
        if -SEQ_BEHIND <= d < 0:
            if seq in self._missing:
                self._missing.remove(seq)
                st.lost -= 1
                st.late += 1
            else:
                st.duplicates += 1
            return False
        runs = self._runs
        n = 1
        for k in range(1, SEQ_AHEAD + 1):  # does it follow one of the recent anomalies?
            prev = (seq - k) & 0xFFFFFFFF
            if prev in runs:
                n = runs.pop(prev) + 1
                break
        if n < RESYNC_AFTER:
            runs[seq] = n
            if len(runs) > _RUNS_KEPT:
                del runs[next(iter(runs))]
            st.anomalies += 1
            return False
        # the sender really is there now: follow it (frames between were lost if it went ahead)
        st.resyncs += 1
        if 0 < d <= 0xFFFF:
            st.lost += max(0, d - n)
        self._missing.clear()
        runs.clear()
        self._last_seq = seq
        return True

    def _account(self, now: float, nbytes: int, payload: int) -> None:
        """Add a datagram to the rate window: per-tenth-of-a-second sums, so a flood of datagrams
        costs no more memory than a trickle."""
        w = self._window
        tick = math.floor(now * _RATE_TICKS) / _RATE_TICKS
        if w and w[-1][0] == tick:
            w[-1][1] += nbytes
            w[-1][2] += payload
        else:
            w.append([tick, nbytes, payload])
        while w and w[0][0] < now - self.window_s:
            w.popleft()

    # --- output --------------------------------------------------------------------------------

    def update_rates(self, now: float | None = None) -> None:
        """Refresh ``stats.bits_per_second`` over the last ``window_s`` seconds."""
        now = self.clock() if now is None else now
        w = self._window
        while w and w[0][0] < now - self.window_s:
            w.popleft()
        if not w:
            self.stats.bits_per_second = self.stats.payload_bits_per_second = 0.0
            return
        span = self.window_s
        self.stats.bits_per_second = 8.0 * sum(b for _, b, _ in w) / span
        self.stats.payload_bits_per_second = 8.0 * sum(p for _, _, p in w) / span

    def pose(self, now: float | None = None) -> FaceParams | None:
        """The pose to draw now: the newest frame (its time advanced to now while it is held); after
        ``hold_s`` without packets, eased towards the neutral face over ``ease_s`` (status ``lost``,
        confidence falling to 0). Packets that arrive but wait for a key frame count as signs of
        life: the pose is held, not eased, until the stream decodes again."""
        last = self.last_frame
        if last is None:
            return None
        now = self.clock() if now is None else now
        age = now - self.last_arrival
        silent = now - max(self.last_arrival, self._alive)
        if silent <= self.hold_s:
            return last if age <= 0 else last.replace(time=last.time + age)
        s = _smoothstep((silent - self.hold_s) / self.ease_s if self.ease_s > 0 else 1.0)
        target = self.neutral.values() if self.neutral is not None else last.values()
        vals = last.values()
        vals = np.where(np.isfinite(vals), vals, target)
        return FaceParams.from_values(
            vals + (target - vals) * s, frame=last.frame, time=last.time + age, status=LOST,
            confidence=last.confidence * (1 - s),
        )

    @property
    def last_seq(self) -> int | None:
        """The newest sequence number seen in this session (None before any frame packet)."""
        return self._last_seq

    @property
    def stale(self) -> bool:
        return self.clock() - self.last_arrival > self.hold_s

    def gap_poses(self, now: float | None = None) -> list[FaceParams]:
        """Poses due while no frame arrives, at the sender's frame rate: the held pose, then the
        ease to neutral, then nothing once at rest. Call it when no datagram is waiting; each
        pose is returned once (the count restarts when a frame arrives)."""
        last = self.last_frame
        if last is None or self.hello is None:
            return []
        if self._gap_anchor != self.last_arrival:
            self._gap_anchor, self._gap_frames, self._resting = self.last_arrival, 0, False
        if self._resting:
            return []
        now = self.clock() if now is None else now
        period = 1.0 / max(self.hello.fps, 1.0)
        out = []
        while self.last_arrival + (self._gap_frames + 1.5) * period <= now:
            self._gap_frames += 1
            pose = self.pose(self.last_arrival + self._gap_frames * period)
            out.append(pose)
            if pose.status == LOST and pose.confidence == 0.0:
                self._resting = True
                break
        return out


class UdpReceiver(Receiver):
    """A :class:`Receiver` on a UDP socket bound to ``bind:port`` (port 0 picks a free one)."""

    def __init__(self, port: int, bind: str = "127.0.0.1", **kw) -> None:
        super().__init__(**kw)
        port = check_port(port)
        family, addr = _resolve(bind, port)
        self._sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            self._sock.bind(addr)
        except OSError as e:
            self._sock.close()
            raise NetError(f"cannot listen on {bind}:{port} ({e.strerror or e})") from None
        self._sock.setblocking(False)

    @property
    def address(self) -> tuple[str, int]:
        return self._sock.getsockname()[:2]

    def poll(self, timeout: float = 0.0, max_datagrams: int = 1000) -> list[FaceParams]:
        """Handle every datagram waiting (waiting up to ``timeout`` s for the first); returns new frames."""
        import select

        out = []
        if timeout > 0:
            ready, _, _ = select.select([self._sock], [], [], timeout)
            if not ready:
                self.update_rates()
                return out
        for _ in range(max_datagrams):
            try:
                data, addr = self._sock.recvfrom(2048)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:  # e.g. ICMP port unreachable reported on some systems
                continue
            f = self.handle(data, addr)
            if f is not None:
                out.append(f)
        self.update_rates()
        return out

    def frames(self, timeout: float = 0.0) -> list[FaceParams]:
        """The frames to draw now, at the sender's rate: every newly received frame, or — when
        nothing arrived within ``timeout`` — the held / easing poses that are due (see :meth:`gap_poses`)."""
        new = self.poll(timeout)
        return new if new else self.gap_poses()

    def close(self) -> None:
        self._sock.close()

    def __enter__(self) -> "UdpReceiver":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
