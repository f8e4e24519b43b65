"""Frame sources: one interface over a video file, a camera, the synthetic performer and a fake camera.

Every source iterates :class:`Frame` objects (index from 0, time in seconds from the start,
``image`` a BGR ``uint8 (H, W, 3)`` array), knows its ``fps`` and ``size`` ``(w, h)``, has
``close()`` and works as a context manager. Opening problems raise :class:`SourceError` with a
one-line message that names the file or the camera index.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import threading
import time as _time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Iterator, Protocol, Sequence, runtime_checkable

import cv2
import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from tracker.synthetic import Performance


class SourceError(RuntimeError):
    """A frame source could not be opened or read; the message is one line naming it."""


@dataclass(frozen=True, slots=True)
class Frame:
    """One frame: ``index`` from 0, ``time`` in seconds from the source's start, BGR ``image``."""

    index: int
    time: float
    image: np.ndarray


@runtime_checkable
class FrameSource(Protocol):
    """What every source offers."""

    fps: float
    size: tuple[int, int]

    def __iter__(self) -> Iterator[Frame]: ...

    def close(self) -> None: ...

    def __enter__(self) -> "FrameSource": ...

    def __exit__(self, *exc) -> None: ...


class _Source:
    """Shared plumbing: context manager, closed flag, ``name`` for messages."""

    name: str = "source"
    fps: float = 30.0
    size: tuple[int, int] = (0, 0)

    def __init__(self) -> None:
        self._closed = False
        self._lock = threading.Lock()  # a capture is read and released under it (close may come from another thread)

    def _read(self, cap) -> np.ndarray | None:
        """The next image of ``cap``, or None at the end or once closed."""
        with self._lock:
            if self._closed:
                return None
            ok, img = cap.read()
        return _as_bgr(img) if ok and img is not None else None

    def _release(self, cap) -> None:
        """Release ``cap`` once no read is in progress (give up waiting on a stuck device)."""
        if self._lock.acquire(timeout=2.0):
            try:
                cap.release()
            finally:
                self._lock.release()

    @property
    def closed(self) -> bool:
        return self._closed

    def close(self) -> None:
        self._closed = True

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        w, h = self.size
        return f"<{type(self).__name__} {self.name} {w}x{h} @ {self.fps:g} fps>"


@contextlib.contextmanager
def _quiet_opencv():
    """Silence OpenCV's own warnings (e.g. from a failed open); we raise a clear error instead."""
    log = getattr(getattr(cv2, "utils", None), "logging", None)
    if log is None:
        yield
        return
    old = log.getLogLevel()
    log.setLogLevel(log.LOG_LEVEL_ERROR)
    try:
        yield
    finally:
        log.setLogLevel(old)


def _valid_fps(v: float, default: float = 30.0) -> float:
    return float(v) if v and math.isfinite(v) and 0.5 <= v <= 1000.0 else default


class VideoFileSource(_Source):
    """Frames of a video file read with OpenCV. ``time`` is ``index / fps``.

    Opening reads the first frame, so a file that exists but cannot be decoded fails here
    rather than on the first iteration. Iterating again starts from the beginning.
    ``frame_count`` is the container's frame count (may be approximate; -1 if unknown).
    """

    def __init__(self, path: str | os.PathLike):
        super().__init__()
        self.path = Path(path)
        self.name = str(self.path)
        if not self.path.exists():
            raise SourceError(f"{self.path}: no such video file")
        if self.path.is_dir():
            raise SourceError(f"{self.path}: is a folder, not a video file")
        self._cap, self._first = self._open()
        h, w = self._first.shape[:2]
        self.size = (int(w), int(h))
        self.fps = _valid_fps(self._cap.get(cv2.CAP_PROP_FPS))
        n = self._cap.get(cv2.CAP_PROP_FRAME_COUNT)
        self.frame_count = int(n) if n and math.isfinite(n) and n > 0 else -1
        self._used = False

    def _open(self) -> tuple[cv2.VideoCapture, np.ndarray]:
        with _quiet_opencv():
            cap = cv2.VideoCapture(str(self.path))
            if not cap.isOpened():
                cap.release()
                raise SourceError(f"{self.path}: cannot open as a video (unknown format or codec)")
            ok, img = cap.read()
        if not ok or img is None:
            cap.release()
            raise SourceError(f"{self.path}: contains no readable frames")
        return cap, _as_bgr(img)

    def __iter__(self) -> Iterator[Frame]:
        if self._closed:
            raise SourceError(f"{self.path}: source is closed")
        if self._used:  # start again from the top
            self._release(self._cap)
            self._cap, self._first = self._open()
        self._used = True
        cap, first = self._cap, self._first
        yield Frame(0, 0.0, first)
        i = 1
        while (img := self._read(cap)) is not None:
            yield Frame(i, i / self.fps, img)
            i += 1

    def frame(self, index: int) -> np.ndarray:
        """The image of frame ``index``, decoded from the start (exact, unlike seeking)."""
        if index < 0:
            raise SourceError(f"{self.path}: frame {index} does not exist")
        if index == 0:
            return self._first
        cap, _ = self._open()
        try:
            for i in range(1, index + 1):
                ok, img = cap.read()
                if not ok or img is None:
                    raise SourceError(f"{self.path}: has no frame {index} (only {i} frames)")
        finally:
            cap.release()
        return _as_bgr(img)

    def close(self) -> None:
        super().close()
        self._release(self._cap)


def _as_bgr(img: np.ndarray) -> np.ndarray:
    if img.ndim == 2:
        return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    if img.shape[2] == 4:
        return cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
    return img


def _device_missing(index: int) -> bool:
    """True when a camera index surely does not exist (Linux: no V4L2 device node for it)."""
    return sys.platform.startswith("linux") and not Path(f"/dev/video{index}").exists()


def _run_with_timeout(fn, timeout: float, what: str):
    """Run ``fn()`` in a daemon thread; raise :class:`SourceError` if it takes over ``timeout`` s."""
    box: dict = {}

    def target():
        try:
            box["value"] = fn()
        except BaseException as e:  # handed to the caller
            box["error"] = e

    th = threading.Thread(target=target, name=f"open {what}", daemon=True)
    th.start()
    th.join(timeout)
    if th.is_alive():
        raise SourceError(f"{what}: did not respond within {timeout:g} s")
    if "error" in box:
        raise box["error"]
    return box.get("value")


class CameraSource(_Source):
    """Live frames from camera ``index`` (OpenCV capture). ``time`` is seconds since opening.

    A camera that does not exist fails at once (on Linux the device node is checked before
    OpenCV is asked); one that hangs fails after ``timeout`` seconds. ``size`` and ``fps`` are
    requests; the attributes hold what the camera actually delivers.
    """

    def __init__(self, index: int = 0, size: tuple[int, int] | None = None, fps: float | None = None,
                 timeout: float = 5.0):
        super().__init__()
        try:
            self.index = int(index)
        except (TypeError, ValueError):
            raise SourceError(f"camera {index!r}: a camera index must be a whole number") from None
        self.name = f"camera {self.index}"
        if self.index < 0:
            raise SourceError(f"{self.name}: camera indices start at 0")
        if _device_missing(self.index):
            raise SourceError(f"{self.name}: not found (no /dev/video{self.index})")

        def open_cam():
            with _quiet_opencv():
                cap = cv2.VideoCapture(self.index)
                if not cap.isOpened():
                    cap.release()
                    return None, None
                if size is not None:
                    cap.set(cv2.CAP_PROP_FRAME_WIDTH, int(size[0]))
                    cap.set(cv2.CAP_PROP_FRAME_HEIGHT, int(size[1]))
                if fps is not None:
                    cap.set(cv2.CAP_PROP_FPS, float(fps))
                ok, img = cap.read()
            if not ok or img is None:
                cap.release()
                return cap, False
            return cap, img

        cap, first = _run_with_timeout(open_cam, timeout, self.name)
        if cap is None:
            raise SourceError(f"{self.name}: cannot be opened (missing or in use)")
        if first is False:
            raise SourceError(f"{self.name}: opened but delivers no frames")
        self._cap, self._first = cap, _as_bgr(first)
        h, w = self._first.shape[:2]
        self.size = (int(w), int(h))
        self.fps = _valid_fps(cap.get(cv2.CAP_PROP_FPS), float(fps) if fps else 30.0)
        self._t0 = _time.monotonic()

    def __iter__(self) -> Iterator[Frame]:
        if self._closed:
            raise SourceError(f"{self.name}: source is closed")
        i = 0
        if self._first is not None:
            yield Frame(0, 0.0, self._first)
            self._first = None
            i = 1
        while (img := self._read(self._cap)) is not None:
            yield Frame(i, _time.monotonic() - self._t0, img)
            i += 1

    def close(self) -> None:
        super().close()
        self._release(self._cap)


class SyntheticSource(_Source):
    """The synthetic performer as a source; ``loop`` plays it again and again (indices keep
    counting, times keep growing), ``realtime`` paces it at its fps like a camera.
    ``truth(frame)`` gives the exact parameters of a frame."""

    def __init__(self, performance: "Performance", loop: bool = False, realtime: bool = False):
        super().__init__()
        self.performance = performance
        self.loop = bool(loop)
        self.realtime = bool(realtime)
        self.fps = float(performance.fps)
        self.size = tuple(performance.frame_size)
        self.name = f"synthetic performer (seed {performance.seed}, {len(performance)} frames)"

    def __len__(self) -> int:
        return len(self.performance)

    def truth(self, frame: Frame | int):
        i = frame.index if isinstance(frame, Frame) else int(frame)
        p = self.performance.truth(i % len(self.performance))
        return p.replace(frame=i, time=i / self.fps)

    def __iter__(self) -> Iterator[Frame]:
        n = len(self.performance)
        t0 = _time.monotonic()
        i = 0
        while not self._closed:
            if self.realtime:
                wait = t0 + i / self.fps - _time.monotonic()
                if wait > 0:
                    _time.sleep(wait)
            yield Frame(i, i / self.fps, self.performance.frame(i % n))
            i += 1
            if i >= n and not self.loop:
                return


class FakeCamera(_Source):
    """A stand-in camera for tests: plays a list of BGR frames at ``fps``.

    ``loop`` repeats them until closed; ``realtime`` paces delivery at ``fps`` like a real
    camera (otherwise frames come as fast as they are asked for). ``time`` is ``index / fps``.
    """

    def __init__(self, frames: Sequence[np.ndarray] | Iterable[np.ndarray], fps: float = 30.0, loop: bool = False,
                 realtime: bool = False):
        super().__init__()
        self.frames = list(frames)
        self.name = f"fake camera ({len(self.frames)} frames)"
        if not self.frames:
            raise SourceError("fake camera: no frames given")
        first = np.asarray(self.frames[0])
        for k, f in enumerate(self.frames):
            f = np.asarray(f)
            if f.dtype != np.uint8 or f.ndim != 3 or f.shape[2] != 3:
                raise SourceError(f"fake camera: frame {k} is {f.dtype} {f.shape}, expected uint8 (H, W, 3) BGR")
            if f.shape != first.shape:
                raise SourceError(f"fake camera: frame {k} is {f.shape[1]}x{f.shape[0]}, "
                                  f"frame 0 is {first.shape[1]}x{first.shape[0]}")
        if not (fps > 0 and math.isfinite(fps)):
            raise SourceError(f"fake camera: fps must be positive, got {fps}")
        self.fps = float(fps)
        self.size = (int(first.shape[1]), int(first.shape[0]))
        self.loop = bool(loop)
        self.realtime = bool(realtime)

    def __len__(self) -> int:
        return len(self.frames)

    def __iter__(self) -> Iterator[Frame]:
        n = len(self.frames)
        t0 = _time.monotonic()
        i = 0
        while not self._closed:
            if self.realtime:
                wait = t0 + i / self.fps - _time.monotonic()
                if wait > 0:
                    _time.sleep(wait)
            yield Frame(i, i / self.fps, self.frames[i % n])
            i += 1
            if i >= n and not self.loop:
                return


def open_source(spec: str | int) -> _Source:
    """A source from a command-line style spec: a camera index (``0``), ``synth[:SECONDS[:SEED]]``
    for the synthetic performer, or a video file path."""
    if isinstance(spec, int) or (isinstance(spec, str) and spec.strip().isdigit()):
        return CameraSource(int(spec))
    s = str(spec)
    if s == "synth" or s.startswith("synth:"):
        from tracker.synthetic import Performance

        parts = s.split(":")[1:]
        try:
            seconds = float(parts[0]) if parts and parts[0] else 10.0
            seed = int(parts[1]) if len(parts) > 1 and parts[1] else 0
        except ValueError:
            raise SourceError(f"{s}: expected synth[:SECONDS[:SEED]]") from None
        return SyntheticSource(Performance(seconds=seconds, seed=seed))
    return VideoFileSource(s)
