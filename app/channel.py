"""The window ↔ engine channel: nothing on it can make either side wait for the other.

Three parts, each with one job:

* :class:`Channel` — small messages (requests one way, events and frame notices the other)
  over one end of a socket pair in non-blocking mode. ``send`` never waits: what the socket
  cannot take now stays in a local outbox and goes out on a later ``flush``; a message sent
  with a ``key`` replaces its unsent predecessor of the same key (latest wins), so a stalled
  reader cannot make the outbox grow without bound.
* :class:`SharedPictures` / :class:`PictureReader` — a frame's pixels (the video and the
  character, megabytes) travel in one shared-memory segment, never through the socket. The
  engine writes a frame only after the window has taken the previous one (its ``ack``);
  meanwhile newer frames replace the waiting one, so a slow window drops frames and nobody blocks.
* :class:`Spool` — other large payloads (a calibration, a training session, a test's fake
  camera) are written to files in a private folder and only their paths are sent.

Same idea as Qt's queued signals and napari's thread workers: the GUI thread only ever posts and
polls; it never waits on an answer.
"""

from __future__ import annotations

import base64
import dataclasses
import importlib
import json
import os
import shutil
import socket
import struct
import tempfile
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np

_HEADER = struct.Struct("<I")  # message length in bytes


class ChannelClosed(OSError):
    """The other end has gone (the engine or the window exited)."""


_OURS = ("app.", "tracker.", "training.", "art_sets.", "morph.")
"""Packages whose dataclasses may cross the channel (a message names its class; nothing else is built)."""


def _enc(o: Any) -> Any:
    """A message as plain JSON values: tuples, dicts with any keys, numpy arrays and scalars,
    bytes, paths and this project's dataclasses are tagged so :func:`_dec` restores them."""
    if o is None or isinstance(o, (bool, int, float, str)):
        return o
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, list):
        return [_enc(v) for v in o]
    if isinstance(o, tuple):
        return {"t": [_enc(v) for v in o]}
    if isinstance(o, dict):
        return {"d": [[_enc(k), _enc(v)] for k, v in o.items()]}
    if isinstance(o, np.ndarray):
        a = np.ascontiguousarray(o)
        return {"a": [a.dtype.str, list(a.shape), base64.b64encode(a.tobytes()).decode("ascii")]}
    if isinstance(o, (bytes, bytearray)):
        return {"b": base64.b64encode(bytes(o)).decode("ascii")}
    if isinstance(o, os.PathLike):
        return {"p": os.fspath(o)}
    cls = type(o)
    if dataclasses.is_dataclass(o) and cls.__module__.startswith(_OURS):
        return {"c": f"{cls.__module__}:{cls.__qualname__}",
                "f": {f.name: _enc(getattr(o, f.name)) for f in dataclasses.fields(o) if f.init}}
    raise TypeError(f"a {cls.__module__}.{cls.__qualname__} cannot go over the window-engine channel")


def _dec(o: Any) -> Any:
    """Inverse of :func:`_enc`."""
    if isinstance(o, list):
        return [_dec(v) for v in o]
    if not isinstance(o, dict):
        return o
    if "c" in o:
        return _dataclass(o)
    (tag, v), = o.items()
    if tag == "t":
        return tuple(_dec(x) for x in v)
    if tag == "d":
        return {_dec(k): _dec(x) for k, x in v}
    if tag == "a":
        dtype, shape, data = v
        return np.frombuffer(base64.b64decode(data), dtype=np.dtype(dtype)).reshape(shape).copy()
    if tag == "b":
        return base64.b64decode(v)
    if tag == "p":
        return Path(v)
    raise ValueError(f"the channel carries no {tag!r}")


def _dataclass(o: dict) -> Any:
    """One of this project's dataclasses from its tagged fields (see :func:`_enc`)."""
    module, _, name = o["c"].partition(":")
    if not module.startswith(_OURS):
        raise ValueError(f"the channel carries no {o['c']}")
    cls = importlib.import_module(module)
    for part in name.split("."):
        cls = getattr(cls, part)
    if not dataclasses.is_dataclass(cls):
        raise ValueError(f"the channel carries no {o['c']}")
    return cls(**{k: _dec(x) for k, x in o["f"].items()})


def encode_message(msg: Any) -> bytes:
    """One message's bytes on the channel (JSON, see :func:`_enc`)."""
    return json.dumps(_enc(msg), separators=(",", ":")).encode("utf-8")


def decode_message(data: bytes) -> Any:
    """The message :func:`encode_message` wrote."""
    return _dec(json.loads(data))


class Channel:
    """Length-prefixed JSON messages over a non-blocking stream socket (see the module doc)."""

    def __init__(self, sock: socket.socket):
        sock.setblocking(False)
        self.sock = sock
        self._pending: deque[tuple[Any, Any]] = deque()  # (key, message), not yet serialised
        self._out = bytearray()  # serialised, partly written
        self._in = bytearray()
        self.closed = False

    def fileno(self) -> int:
        return self.sock.fileno()

    def send(self, msg: Any, key: Any = None) -> None:
        """Queue ``msg`` and push out what the socket takes now; never waits."""
        if self.closed:
            raise ChannelClosed("the channel is closed")
        if key is not None and self._pending:
            self._pending = deque(item for item in self._pending if item[0] != key)
        self._pending.append((key, msg))
        self.flush()

    @property
    def backlog(self) -> int:
        """Messages (plus a partly written one) still waiting to go out."""
        return len(self._pending) + (1 if self._out else 0)

    def flush(self) -> bool:
        """Write what the socket takes without waiting; True when nothing is left to send."""
        while not self.closed:
            if not self._out:
                if not self._pending:
                    return True
                _, msg = self._pending.popleft()
                data = encode_message(msg)
                self._out += _HEADER.pack(len(data))
                self._out += data
            try:
                n = self.sock.send(self._out)
            except (BlockingIOError, InterruptedError):
                return False
            except OSError as e:
                self.closed = True
                raise ChannelClosed(str(e)) from None
            del self._out[:n]
        return False

    def receive(self) -> list:
        """Every complete message that has arrived (possibly none); never waits."""
        while not self.closed:
            try:
                chunk = self.sock.recv(1 << 17)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                self.closed = True
                break
            if not chunk:
                self.closed = True
                break
            self._in += chunk
        out = []
        pos = 0
        buf = self._in
        while len(buf) - pos >= _HEADER.size:
            (n,) = _HEADER.unpack_from(buf, pos)
            if len(buf) - pos - _HEADER.size < n:
                break
            start = pos + _HEADER.size
            out.append(decode_message(bytes(buf[start:start + n])))
            pos = start + n
        if pos:
            del buf[:pos]
        return out

    def close(self) -> None:
        self.closed = True
        try:
            self.sock.close()
        except OSError:
            pass


# ------------------------------------------------------------------------------------------
# pictures in shared memory


def _segment(name: str | None = None, size: int = 0):
    from multiprocessing import shared_memory

    if name is None:
        return shared_memory.SharedMemory(create=True, size=size)
    return shared_memory.SharedMemory(name=name)


class SharedPictures:
    """(Engine side) the segment a frame's pictures are written to, grown when one does not fit.

    The engine only writes after the window acknowledged the previous frame, so one segment is
    enough and a reader never sees a half-written picture. A replaced segment is unlinked at once
    (the window has finished with it; it attaches to the new one by name)."""

    def __init__(self) -> None:
        self._shm = None

    @property
    def name(self) -> str | None:
        return None if self._shm is None else self._shm.name

    def write(self, arrays: list[np.ndarray | None]) -> tuple[str, list]:
        """Copy ``arrays`` (uint8, any shape; None skipped) in; returns (segment name, layout)
        where layout holds ``(offset, shape)`` or None per array."""
        need = sum(int(a.nbytes) for a in arrays if a is not None)
        if self._shm is None or self._shm.size < need:
            self._replace(max(need + need // 4, 1 << 20))
        buf = self._shm.buf
        layout: list = []
        off = 0
        for a in arrays:
            if a is None:
                layout.append(None)
                continue
            a = np.ascontiguousarray(a, dtype=np.uint8)
            dst = np.frombuffer(buf, np.uint8, a.size, off)
            dst[:] = a.reshape(-1)
            del dst
            layout.append((off, tuple(a.shape)))
            off += a.size
        return self._shm.name, layout

    def _replace(self, size: int) -> None:
        self.close()
        self._shm = _segment(size=size)

    def close(self) -> None:
        if self._shm is not None:
            shm, self._shm = self._shm, None
            try:
                shm.close()
                shm.unlink()
            except (OSError, BufferError):
                pass


class PictureReader:
    """(Window side) copies pictures out of the engine's current segment."""

    def __init__(self) -> None:
        self._shm = None

    def read(self, name: str, layout: list) -> list[np.ndarray | None]:
        """Own copies of the arrays the engine described (None where it sent none)."""
        if self._shm is None or self._shm.name != name:
            self.close()
            self._shm = _segment(name)
        out: list[np.ndarray | None] = []
        for item in layout:
            if item is None:
                out.append(None)
                continue
            off, shape = item
            n = int(np.prod(shape))
            out.append(np.frombuffer(self._shm.buf, np.uint8, n, off).reshape(shape).copy())
        return out

    def close(self) -> None:
        if self._shm is not None:
            shm, self._shm = self._shm, None
            try:
                shm.close()
            except (OSError, BufferError):
                pass

    def unlink(self) -> None:
        """Remove the engine's segment (when the engine was stopped before it could)."""
        if self._shm is not None:
            shm = self._shm
            self.close()
            try:
                shm.unlink()
            except OSError:
                pass


# ------------------------------------------------------------------------------------------
# large payloads as files


class Spool:
    """A private folder for payloads sent by path; keeps the newest ``keep`` files per kind.

    A payload older than that has been superseded by newer requests of its kind (requests are
    latest-wins), so the engine never needs it."""

    def __init__(self, keep: int = 8):
        self.root = Path(tempfile.mkdtemp(prefix="inkface-channel-"))
        self.keep = keep
        self._n = 0
        self._made: dict[str, deque[Path]] = {}

    def path(self, kind: str, suffix: str = "") -> Path:
        """A fresh path for a payload of ``kind`` (older ones beyond ``keep`` are removed)."""
        self._n += 1
        p = self.root / f"{kind}-{self._n:06d}{suffix}"
        made = self._made.setdefault(kind, deque())
        made.append(p)
        while len(made) > self.keep:
            old = made.popleft()
            if old.is_dir():
                shutil.rmtree(old, ignore_errors=True)
            else:
                for f in old.parent.glob(old.stem + ".*"):
                    f.unlink(missing_ok=True)
        return p

    def close(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)


def write_frames(path: Path, frames) -> Path:
    """A fake camera's frames as one ``.npy`` array (N, H, W, 3) uint8, frame by frame."""
    frames = list(frames)
    first = np.asarray(frames[0], dtype=np.uint8)
    tmp = path.with_name(path.name + ".part")
    out = np.lib.format.open_memmap(tmp, mode="w+", dtype=np.uint8, shape=(len(frames), *first.shape))
    for i, f in enumerate(frames):
        out[i] = f
    out.flush()
    del out
    os.replace(tmp, path)
    return path


def read_frames(path: str | os.PathLike) -> list[np.ndarray]:
    arr = np.load(path, allow_pickle=False)
    return [arr[i] for i in range(len(arr))]
