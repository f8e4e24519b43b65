"""Capture, tracking and rendering off the GUI thread — in a separate engine process.

* The **engine process** (:class:`EngineLoop`) runs a :class:`Capture` thread that reads the
  frame source (camera, video file, the synthetic performance) into a one-item
  :class:`LatestSlot`, paced to the source's rate for files; when the engine has not taken the
  previous frame it is overwritten and counted as dropped — frames are never queued. The
  :class:`Engine` steps ``training.puppet.Puppet`` on the newest frame (track → filter → map →
  render) and keeps only its newest result for the window; it is published when the window has
  taken the previous one, so a slow window drops frames too. Characters are built on a loader
  thread so video keeps flowing meanwhile. Recording happens there as well; a stopped
  recording is closed on its own thread while frames go on.
* The **window side** (:class:`Pipeline`) posts requests and reads what came back from the
  event loop (a socket notifier), turning the newest frame into QImages on the GUI thread.

Neither side ever waits for the other (:mod:`app.channel`): requests and events are small
non-blocking messages, pictures travel through shared memory, calibrations, sessions and test
frames by file. Why a process and not QThreads: see the note above :class:`Hook`.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

import app.qt_env  # noqa: F401  (before Qt: platform plugin, PySide6 refcount guard)
from PySide6.QtCore import QTimer
from PySide6.QtGui import QImage

# ------------------------------------------------------------------------------------------
# one-item mailbox


class LatestSlot:
    """A single-item, thread-safe mailbox: ``put`` overwrites, ``take`` empties.

    ``dropped`` counts items that were overwritten before anyone took them.
    """

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._item: Any = None
        self._full = False
        self.dropped = 0
        self.delivered = 0

    def put(self, item: Any) -> bool:
        """Store ``item``; return True when an untaken item was dropped to make room."""
        with self._cond:
            overwrote = self._full
            if overwrote:
                self.dropped += 1
            self._item, self._full = item, True
            self._cond.notify_all()
            return overwrote

    def take(self, timeout: float | None = 0.0) -> Any:
        """The newest item (and empty the slot), waiting up to ``timeout`` s; None if none came."""
        with self._cond:
            if not self._full and timeout:
                self._cond.wait_for(lambda: self._full, timeout)
            if not self._full:
                return None
            item, self._item, self._full = self._item, None, False
            self.delivered += 1
            self._cond.notify_all()
            return item

    def wait_empty(self, timeout: float) -> bool:
        """Block until the slot has been taken (used by unpaced runs that must not drop)."""
        with self._cond:
            return self._cond.wait_for(lambda: not self._full, timeout)

    def notify_taken(self) -> None:
        with self._cond:
            self._cond.notify_all()

    @property
    def full(self) -> bool:
        return self._full

    def clear(self) -> None:
        with self._cond:
            self._item, self._full = None, False
            self._cond.notify_all()


# ------------------------------------------------------------------------------------------
# what the window asks for


@dataclass(frozen=True)
class SourceSpec:
    """Where frames come from: ``kind`` is "camera", "video" or "performance"."""

    kind: str = "performance"
    camera: int = 0
    video: str = ""
    seconds: float = 20.0
    seed: int = 0
    loop: bool = True

    def describe(self) -> str:
        if self.kind == "camera":
            return f"camera {self.camera}"
        if self.kind == "video":
            return Path(self.video).name
        return "bundled performance"


@dataclass(frozen=True)
class PuppetSpec:
    """Everything that decides how the puppet is built and driven."""

    art: str = ""  # art-set folder
    fps: int = 30  # output rate: 10, 15 or 30
    filter: str = "one_euro"
    strength: float = 0.5
    gain: float = 1.0
    detail: bool = False
    calibration: Any = None  # tracker.calibration.Calibration or None
    session: Any = None  # training.session.TrainingSession or None


@dataclass
class DisplayFrame:
    """One frame for the window. The worker fills the arrays; the GUI thread makes the
    QImages (``video``, ``character``) with :meth:`to_images`, so no Qt object is touched
    off the GUI thread."""

    index: int
    time: float
    frame_bgr: np.ndarray | None
    rgba: np.ndarray | None = None  # premultiplied RGBA, a private copy (None: no character yet)
    params: Any = None
    overlay: Any = None
    weights: Any = None
    timings_ms: dict = field(default_factory=dict)
    fps: float = 0.0  # frames tracked per second
    fps_in: float = 0.0  # frames read from the source per second
    fps_out: float = 0.0  # new character pictures per second (the output rate)
    dropped_capture: int = 0
    dropped_display: int = 0
    art: str = ""
    status: str = ""
    fresh: bool = True  # False: the output rate held the previous picture
    frames_read: int = 0  # by the capture so far
    frames_done: int = 0  # by the engine so far
    frame_size: tuple = (0, 0)  # (w, h) of the camera frame; ``frame_bgr`` may be scaled for display
    source_id: int = 0  # the window's number for the source this frame came from
    requests_seen: int = 0  # the newest request the engine had read before making this frame
    video: QImage | None = None
    character: QImage | None = None

    def to_images(self, previous: "DisplayFrame | None" = None, video: bool = True) -> None:
        """Make the QImages (GUI thread only); a held picture reuses the previous QImage."""
        if video and self.frame_bgr is not None and self.video is None:
            self.video = bgr_to_qimage(self.frame_bgr)
        if self.rgba is not None and self.character is None:
            if previous is not None and previous.rgba is self.rgba and previous.character is not None:
                self.character = previous.character
            else:
                self.character = rgba_pm_to_qimage(self.rgba)


# ------------------------------------------------------------------------------------------
# conversions (no copies beyond the one QImage needs to own its pixels)


def array_to_qimage(arr: np.ndarray, fmt: QImage.Format) -> QImage:
    """Copy a uint8 (h, w, c) array into a new QImage that owns its pixels.

    The pixels are copied into Qt's own buffer (``QImage(w, h, fmt)`` then ``bits()``) rather
    than wrapping the numpy buffer: a QImage wrapping Python memory releases it from whichever
    thread drops the image, which corrupts reference counts when that is a worker thread.
    """
    h, w = arr.shape[:2]
    c = 1 if arr.ndim == 2 else arr.shape[2]
    img = QImage(w, h, fmt)
    dst = np.frombuffer(img.bits(), np.uint8, count=img.bytesPerLine() * h).reshape(h, img.bytesPerLine())
    dst[:, : w * c] = arr.reshape(h, w * c)
    return img


def bgr_to_qimage(frame: np.ndarray) -> QImage:
    """A BGR uint8 (H,W,3) frame as an owned QImage."""
    return array_to_qimage(frame, QImage.Format.Format_BGR888)


def rgba_pm_to_qimage(rgba: np.ndarray) -> QImage:
    """A premultiplied RGBA uint8 (h,w,4) image as an owned QImage."""
    return array_to_qimage(rgba, QImage.Format.Format_RGBA8888_Premultiplied)


def qimage_to_rgba(img: QImage) -> np.ndarray:
    """A QImage as a straight-alpha RGBA uint8 array (owned)."""
    img = img.convertToFormat(QImage.Format.Format_RGBA8888)
    w, h = img.width(), img.height()
    arr = np.frombuffer(img.constBits(), np.uint8, count=img.bytesPerLine() * h)
    return arr.reshape(h, img.bytesPerLine())[:, : w * 4].reshape(h, w, 4).copy()


# ------------------------------------------------------------------------------------------
# building the core objects (imports are lazy: the core modules load only when needed)


class CoreMissing(RuntimeError):
    """A part of the core this feature needs is not installed in this build."""


def open_source(spec: SourceSpec):
    """Open the frame source a :class:`SourceSpec` names (raises ``SourceError`` one-liners)."""
    from tracker import sources

    if spec.kind == "camera":
        return sources.CameraSource(spec.camera)
    if spec.kind == "video":
        return sources.VideoFileSource(spec.video)
    cached = performance_cache_path(spec.seconds, spec.seed)
    if cached.is_file():
        return sources.VideoFileSource(str(cached))
    return CachingPerformanceSource(bundled_performance(spec.seconds, spec.seed), cached)


def cache_dir() -> Path:
    """Where re-creatable files go (``INKFACE_CACHE``, else ``$XDG_CACHE_HOME/inkface``)."""
    import os

    env = os.environ.get("INKFACE_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "inkface"


def performance_cache_path(seconds: float = 20.0, seed: int = 0) -> Path:
    """The bundled performance pre-rendered to MJPG, keyed by the synthetic performer's code.

    Drawing a synthetic frame costs ~25 ms; decoding the cached one ~2 ms, which leaves the
    CPU to the tracker and the renderer when the performance loops.
    """
    import hashlib

    import tracker.synthetic as syn

    h = hashlib.sha1(Path(syn.__file__).read_bytes()).hexdigest()[:10]
    return cache_dir() / f"performance-{seconds:g}s-seed{seed}-{h}.avi"


class CachingPerformanceSource:
    """Plays a synthetic :class:`Performance` and writes it to the cache file as it goes;
    the file is kept only when the whole performance was played."""

    def __init__(self, perf, path: Path):
        self.perf = perf
        self.path = Path(path)
        self.fps = float(perf.fps)
        self.size = tuple(perf.frame_size)

    def __iter__(self):
        import cv2

        from tracker.sources import Frame

        writer = None
        tmp = self.path.with_name(f".{self.path.stem}.{threading.get_ident()}.part.avi")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"MJPG"), self.fps, self.size)
            if writer.isOpened():
                writer.set(cv2.VIDEOWRITER_PROP_QUALITY, 95)
            else:
                writer = None
        except OSError:
            writer = None
        complete = False
        try:
            for i in range(len(self.perf)):
                img = self.perf.frame(i)
                if writer is not None:
                    writer.write(img)
                yield Frame(i, i / self.fps, img)
            complete = True
        finally:
            if writer is not None:
                writer.release()
                if complete and not self.path.exists():
                    try:
                        tmp.replace(self.path)
                    except OSError:
                        pass
                tmp.unlink(missing_ok=True)

    def close(self) -> None:
        pass


_PERF_CACHE: dict[tuple, Any] = {}


def bundled_performance(seconds: float = 20.0, seed: int = 0):
    """The scripted synthetic performer used by the demo and when no camera is present."""
    key = (float(seconds), int(seed))
    if key not in _PERF_CACHE:
        from tracker.synthetic import Performance

        _PERF_CACHE[key] = Performance(seconds=seconds, fps=30, seed=seed)
    return _PERF_CACHE[key]


def performance_calibration(perf):
    """Calibrate the tracker for the synthetic performer from its own five clicks."""
    from tracker.calibration import calibrate
    from tracker.clicks import Clicks

    clicks = Clicks.from_dict(perf.clicks())
    return calibrate(perf.frame(clicks.frame), clicks)


def bundled_performance_clip_path(seconds: float = 20.0, seed: int = 0) -> Path | None:
    """The cached video of the bundled performance, if it has been played through once."""
    p = performance_cache_path(seconds, seed)
    return p if p.is_file() else None


PERFORMANCE_CALIBRATION = "performance"


def resolve_calibration(cal):
    """Turn a calibration request into a ``Calibration``: the bundled performer's own
    (``"performance"``), clicks beside a video (``("clicks", clicks_json, video)``), a saved
    calibration (``("file", calibration_json, n)``), or an object as is."""
    if isinstance(cal, tuple) and cal and cal[0] == "file":
        from tracker.calibration import Calibration

        return Calibration.load(cal[1])
    if cal == PERFORMANCE_CALIBRATION:
        return performance_calibration(bundled_performance())
    if isinstance(cal, tuple) and cal and cal[0] == "clicks":
        from tracker.calibration import calibrate
        from tracker.clicks import Clicks
        from tracker.sources import VideoFileSource

        clicks = Clicks.load(cal[1])
        with VideoFileSource(cal[2]) as src:
            for fr in src:
                if fr.index >= clicks.frame:
                    return calibrate(fr.image, clicks)
        raise ValueError(f"{cal[2]}: has no frame {clicks.frame} for {Path(cal[1]).name}")
    return cal


def resolve_session(session):
    """A training session from a request: ``("file", folder, n)`` is read (without autosave:
    the engine never writes it), None stays None (the default training), an object as is."""
    if isinstance(session, tuple) and session and session[0] == "file":
        from training.session import TrainingSession

        return TrainingSession.load(session[1], autosave=False)
    return session


def load_artset(path: str | Path):
    from art_sets.io import load_artset as _load

    return _load(Path(path))


def default_art_path() -> str:
    """The first bundled character's folder ('' when none are installed)."""
    try:
        from art_sets.library import list_bundled
    except ImportError:
        return ""
    items = list_bundled()
    return str(items[0][1]) if items else ""


def make_puppet(artset, spec: PuppetSpec):
    """Build a ``training.puppet.Puppet`` for ``artset`` as ``spec`` asks."""
    try:
        from training.puppet import Puppet
    except ImportError as e:  # the mapping room has not landed the puppet yet
        raise CoreMissing(f"the live puppet (training.puppet) is not available: {e}") from e
    session = spec.session
    if session is None:
        try:
            from training.defaults import default_session

            session = default_session(artset)
        except ImportError:
            session = None
    return _call_flexibly(
        Puppet,
        artset,
        calibration=spec.calibration,
        session=session,
        fps=spec.fps,
        filter=spec.filter,
        strength=spec.strength,
        gain=spec.gain,
        detail=spec.detail,
    )


def _call_flexibly(fn: Callable, *args, **kwargs):
    """Call ``fn`` with only the keyword arguments its signature accepts."""
    import inspect

    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return fn(*args, **kwargs)
    if any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values()):
        return fn(*args, **kwargs)
    return fn(*args, **{k: v for k, v in kwargs.items() if k in sig.parameters})


# ------------------------------------------------------------------------------------------
# the engine process
#
# Why a process and not QThreads: on this 2-core machine the tracker, the renderer and the
# window's painting are all Python + numpy, and in threads they take turns on one GIL; in two
# processes they really run side by side. The window process then runs no Python threads at
# all, which also keeps it clear of PySide6's thread-affinity pitfalls (see app/qt_env.py for
# the reference-count bug of PySide6 6.12 on CPython 3.11, which first showed up here).


class Hook:
    """A plain-Python signal: ``connect(fn)``, ``emit(*args)`` calls every fn in order."""

    def __init__(self) -> None:
        self._fns: list[Callable] = []

    def connect(self, fn: Callable) -> None:
        self._fns.append(fn)

    def disconnect(self, fn: Callable) -> None:
        if fn in self._fns:
            self._fns.remove(fn)

    def emit(self, *args) -> None:
        for fn in list(self._fns):
            fn(*args)


class RateMeter:
    """Events per second over the last ``window_s`` seconds (0 when none came lately)."""

    def __init__(self, window_s: float = 2.0):
        self.window_s = window_s
        self._times: deque[float] = deque()

    def tick(self, t: float | None = None) -> None:
        t = time.perf_counter() if t is None else t
        self._times.append(t)
        self._trim(t)

    def _trim(self, now: float) -> None:
        while self._times and now - self._times[0] > self.window_s:
            self._times.popleft()

    def rate(self, now: float | None = None) -> float:
        now = time.perf_counter() if now is None else now
        self._trim(now)
        if len(self._times) < 2:
            return 0.0
        span = max(now - self._times[0], self._times[-1] - self._times[0], 1e-6)
        return (len(self._times) - 1) / span if now - self._times[-1] < 0.5 else len(self._times) / self.window_s


class Worker(threading.Thread):
    """(Engine process) one long-lived thread for slow jobs (building a puppet, closing a
    recording), so the engine loop never runs them and a burst of requests does not become a
    crowd of threads. A job submitted with a ``key`` replaces a waiting job of that key (latest
    wins); others wait their turn. After each job freed memory is handed back to the system."""

    def __init__(self, name: str):
        super().__init__(name=name, daemon=True)
        self._cond = threading.Condition()
        self._jobs: deque = deque()
        self._halt = False
        self.start()

    def submit(self, fn: Callable[[], None], key: Any = None) -> None:
        with self._cond:
            if key is not None:
                self._jobs = deque(j for j in self._jobs if j[0] != key)
            self._jobs.append((key, fn))
            self._cond.notify()

    def run(self) -> None:
        while True:
            with self._cond:
                self._cond.wait_for(lambda: self._jobs or self._halt)
                if not self._jobs:
                    return
                _, fn = self._jobs.popleft()
            try:
                fn()
            finally:
                trim_memory()

    def stop(self, wait_s: float = 0.0) -> None:
        """No new jobs; those queued still run (``wait_s``: how long to wait for them)."""
        with self._cond:
            self._halt = True
            self._cond.notify()
        if wait_s:
            self.join(wait_s)


_LIBC: Any = None


def trim_memory() -> None:
    """Return freed heap memory to the system (glibc's ``malloc_trim``; a no-op elsewhere).

    Building a puppet or closing a recording frees hundreds of MB in blocks that glibc would
    otherwise keep, so a long session's footprint would creep up after every rebuild."""
    global _LIBC
    if _LIBC is None:
        try:
            import ctypes

            _LIBC = ctypes.CDLL("libc.so.6")
            _LIBC.malloc_trim.argtypes = [ctypes.c_size_t]
        except (OSError, AttributeError):
            _LIBC = False
    if _LIBC:
        _LIBC.malloc_trim(0)


class Capture(threading.Thread):
    """(Engine process) reads a frame source into its own :class:`LatestSlot`.

    ``realtime`` paces file and synthetic sources to their fps (cameras pace themselves);
    with ``realtime=False`` it waits for the engine to take each frame (no drops: used to
    measure the loop's top speed). ``events`` receives ``(name, args)`` notifications, each
    tagged with ``source_id`` (the window's number for this source) so late news from a source
    the window has left is recognisable. ``previous`` (the capture this one replaces) is
    joined on this thread before the source opens, so a camera is released before it is
    opened again and the engine loop never waits for either.
    """

    def __init__(self, spec: SourceSpec, realtime: bool, source, events: Callable, source_id: int = 0,
                 previous: "Capture | None" = None):
        super().__init__(name="inkface-capture", daemon=True)
        self.slot = LatestSlot()
        self.spec = spec
        self.realtime = realtime
        self.source_id = source_id
        self._given_source = source
        self._events = events
        self._previous = previous
        self._halt = threading.Event()
        self._paused = threading.Event()
        self.frames_read = 0
        self.rate = RateMeter()

    def post(self, name: str, *args) -> None:
        if not self._halt.is_set():
            self._events(name, (self.source_id, *args))

    def stop(self) -> None:
        self._halt.set()
        self.slot.notify_taken()

    def set_paused(self, paused: bool) -> None:
        (self._paused.set if paused else self._paused.clear)()

    def run(self) -> None:  # noqa: C901 - one loop, kept together on purpose
        if self._previous is not None:
            self._previous.join(5.0)
            self._previous = None
        if self._halt.is_set():
            return
        try:
            self._given_source = _rebuild(self._given_source)  # a test's fake camera, read from its file
            src = self._given_source if self._given_source is not None else open_source(self.spec)
        except Exception as e:  # SourceError, missing core, bad file: one line for the user
            self.post("sourceFailed", _one_line(e))
            return
        try:
            fps = float(getattr(src, "fps", 30.0) or 30.0)
            w, h = getattr(src, "size", (0, 0))
            self.post("sourceOpened", self.spec.describe(), fps, int(w), int(h))
            # a real camera paces itself; files, the synthetic performer and fakes are paced here
            pace = self.realtime and (self._given_source is not None or self.spec.kind != "camera")
            t0 = time.perf_counter()
            shown = 0
            offset = 0  # index offset across loops
            while not self._halt.is_set():
                got_any = False
                for fr in src:
                    got_any = True
                    if self._halt.is_set():
                        break
                    while self._paused.is_set() and not self._halt.is_set():
                        time.sleep(0.03)
                        t0 = time.perf_counter() - shown / fps
                    if pace:
                        due = t0 + shown / fps
                        delay = due - time.perf_counter()
                        if delay > 0:
                            self._halt.wait(delay)
                        elif delay < -0.5:  # hopelessly behind (debugger, suspend): resync
                            t0 = time.perf_counter() - shown / fps
                    elif not self.realtime:
                        while not self.slot.wait_empty(0.1):
                            if self._halt.is_set():
                                break
                    if self._halt.is_set():
                        break
                    shown += 1
                    self.frames_read += 1
                    self.rate.tick()
                    self.slot.put((fr.index + offset, fr.time + offset / fps, fr.image))
                if self._halt.is_set():
                    break
                if not (self.spec.loop and got_any and self.spec.kind != "camera"):
                    break
                offset += max(1, shown - offset)
                src = _reopen(src, self.spec, self._given_source)
                if src is None:
                    break
            self.post("finishedSource")
        except Exception as e:
            self.post("sourceFailed", _one_line(e))
        finally:
            try:
                src.close()
            except Exception:
                pass


class Engine:
    """(Engine process) steps the puppet on the newest captured frame and keeps the latest
    result for the window; builds puppets on a :class:`Worker` so frames keep flowing.

    The spec's ``calibration`` and ``session`` are references (see :func:`resolve_calibration`
    and :func:`resolve_session`): what they name is loaded off the engine loop."""

    def __init__(self, inbox: LatestSlot, spec: PuppetSpec, events: Callable):
        self.inbox = inbox
        self._events = events
        self._lock = threading.Lock()
        self._pending: PuppetSpec | None = spec
        self.spec = PuppetSpec()
        self.puppet = None
        self._cache: dict[str, Any] = {}  # art path -> loaded ArtSet
        self._cal_cache: dict[Any, Any] = {}
        self.calibration = None  # the resolved Calibration the puppet uses
        self.live_art = ""  # art set of the puppet in use ("" while none is ready)
        self.building = False
        self._gen = 0
        self._built = None
        self._loader = Worker("inkface-puppet-loader")
        self._last_rgba: np.ndarray | None = None
        self.rate = RateMeter()  # frames tracked per second
        self.out_rate = RateMeter()  # new character pictures per second
        self.frames_done = 0
        self.last_error = ""
        self.acquired = False  # the tracker has found the face since this puppet / source started

    def post(self, name: str, *args) -> None:
        self._events(name, args)

    def request(self, spec: PuppetSpec) -> None:
        with self._lock:
            self._pending = spec

    def _apply_pending(self) -> None:
        """Apply the window's latest request; swap in a puppet a loader thread has finished."""
        with self._lock:
            spec, self._pending = self._pending, None
            built, self._built = self._built, None
        if built is not None:
            gen, puppet, bspec, cal, err = built
            if gen == self._gen:  # not superseded by a newer request
                if err:
                    self.puppet, self.live_art = None, ""
                    self.last_error = err
                    self.post("puppetFailed", err)
                else:
                    self.puppet, self.live_art, self.calibration = puppet, bspec.art, cal
                    self._last_rgba = None
                    self.acquired = False
                    try:
                        _tune(puppet, self.spec)
                    except Exception:
                        pass
                    self.post("puppetReady", bspec.art)
            del built, puppet
            trim_memory()  # the puppet replaced (or the build not used) is freed now
        if spec is None:
            return
        old = self.spec
        target_puppet = self.puppet if self.live_art == old.art else None
        session_changed = not _same(spec.session, old.session)
        rebuild = (
            target_puppet is None
            or spec.art != old.art
            or spec.detail != old.detail
            or not _same(spec.calibration, old.calibration)
            or (session_changed and not callable(getattr(self.puppet, "set_session", None)))
            or (
                any(getattr(spec, k) != getattr(old, k) for k in ("fps", "filter", "strength", "gain"))
                and not _can_tune(self.puppet)
            )
        )
        self.spec = spec
        if not spec.art:
            self._gen += 1
            self.puppet, self.live_art = None, ""
            return
        if rebuild:
            self._gen += 1
            self.building = True
            self._loader.submit(lambda g=self._gen, sp=spec: self._build(g, sp), key="build")
            return
        if session_changed:
            try:
                session = resolve_session(spec.session)
                if session is None:
                    from training.defaults import default_session

                    session = default_session(self.puppet.artset)
                self.puppet.set_session(session)
            except Exception as e:
                self.post("puppetFailed", _one_line(e))
        _tune(self.puppet, spec)

    def _build(self, gen: int, spec: PuppetSpec) -> None:
        """Load the art set, resolve the calibration and session, build the puppet (loader thread)."""
        puppet = cal = None
        err = ""
        if gen != self._gen:  # superseded while it waited
            return
        try:
            art = self._cache.get(spec.art)
            if art is None:
                art = load_artset(spec.art)
                self._cache[spec.art] = art
            cal = self._resolve_calibration(spec.calibration)
            session = resolve_session(spec.session)
            if gen != self._gen:
                return
            puppet = make_puppet(art, replace(spec, calibration=cal, session=session))
        except Exception as e:
            err = _one_line(e) or type(e).__name__
        finally:
            if gen == self._gen:
                self.building = False
        with self._lock:
            self._built = (gen, puppet, spec, cal, err)
        self.inbox.notify_taken()

    def _resolve_calibration(self, cal):
        """The Calibration a reference names; the bundled performer's and clicks files are
        kept (they are the same every time), calibration files are read each time."""
        if isinstance(cal, str) or (isinstance(cal, tuple) and cal and cal[0] == "clicks"):
            if cal not in self._cal_cache:
                self._cal_cache[cal] = resolve_calibration(cal)
            return self._cal_cache[cal]
        return resolve_calibration(cal)

    def tracking(self) -> bool:
        """True once the puppet's tracker runs (it waits for a calibration or a found face)."""
        p = self.puppet
        return p is not None and getattr(p, "tracker", True) is not None

    def step(self, timeout: float) -> DisplayFrame | None:
        """Apply requests, then process the newest frame (waiting up to ``timeout`` s)."""
        self._apply_pending()
        item = self.inbox.take(timeout=timeout)
        if item is None:
            return None
        index, t, image = item
        try:
            out = self._process(index, t, image)
        except Exception as e:  # keep going; say what went wrong once
            msg = _one_line(e)
            if msg != self.last_error:
                self.last_error = msg
                self.post("error", msg)
            out = DisplayFrame(index, t, image, status=f"error: {msg}")
        now = time.perf_counter()
        self.rate.tick(now)
        if out.rgba is not None and out.fresh:
            self.out_rate.tick(now)
        out.fps = self.rate.rate(now)
        out.fps_out = self.out_rate.rate(now)
        self.frames_done += 1
        return out

    def _process(self, index: int, t: float, image: np.ndarray) -> DisplayFrame:
        p = self.puppet
        if p is None:
            return DisplayFrame(index, t, image, status=STARTING)
        pf = p.step(image, index, t)
        if pf is None:
            return DisplayFrame(index, t, image, art=self.live_art, status=STARTING)
        rgba = getattr(pf, "rgba_pm", None)
        fresh = bool(getattr(pf, "fresh", True))
        if rgba is not None:
            if not fresh and self._last_rgba is not None:  # held picture (lower output rate)
                rgba = self._last_rgba
            else:  # a private copy: the renderer may reuse its buffer for the next frame
                rgba = self._last_rgba = rgba.copy()
        params = getattr(pf, "params", None)
        status = str(getattr(params, "status", "")) if params is not None else ""
        if not self.tracking() or (status == "lost" and not self.acquired):
            status = STARTING  # no calibration yet, or the face not found yet: nothing was lost
        elif status and status != "lost":
            self.acquired = True
        return DisplayFrame(
            index, t, image, rgba,
            params=params,
            overlay=getattr(pf, "overlay", None),
            weights=getattr(pf, "weights", None),
            timings_ms=dict(getattr(pf, "timings_ms", {}) or {}),
            art=self.live_art,
            status=status,
            fresh=fresh,
        )


STARTING = "starting"
"""The badge before the tracker has found the face: the character is loading, there is no
calibration yet, or the face has not been found since the source or the puppet changed."""

_META = ("index", "time", "params", "overlay", "weights", "timings_ms", "fps", "fps_in", "fps_out",
         "dropped_capture", "dropped_display", "art", "status", "fresh", "frames_read", "frames_done", "frame_size",
         "source_id", "requests_seen")


def fit_size(w: int, h: int, box: tuple[int, int] | None) -> tuple[int, int]:
    """(w, h) scaled to fit ``box`` keeping the aspect ratio (unchanged without a box)."""
    if not box or box[0] <= 0 or box[1] <= 0:
        return w, h
    s = min(box[0] / w, box[1] / h)
    return max(1, int(round(w * s))), max(1, int(round(h * s)))


def scale_for_view(img: np.ndarray, box: tuple[int, int] | None) -> np.ndarray:
    """Resize for display (area-averaged when shrinking, bilinear when enlarging).

    Done in the engine so the window only copies pixels: Qt's smooth scaling of a 512² picture
    to ~700² costs the GUI thread ~9 ms a frame, ``cv2.resize`` a fraction of that."""
    import cv2

    h, w = img.shape[:2]
    tw, th = fit_size(w, h, box)
    if abs(tw - w) <= 1 and abs(th - h) <= 1:
        return img
    interp = cv2.INTER_AREA if tw < w else cv2.INTER_LINEAR
    return cv2.resize(img, (tw, th), interpolation=interp)


# ------------------------------------------------------------------------------------------
# the engine loop


class EngineLoop:
    """(Engine process) the loop: requests in, one frame through the puppet, pictures out.

    Per pass it reads every request that has arrived (so a request waits at most one frame),
    steps the puppet on the newest captured frame, and publishes the newest result if the
    window has taken the previous one — otherwise that result waits and is replaced by the
    next (counted as dropped). Nothing here waits on the window: sends are non-blocking and
    pictures go into shared memory. A stopped recording is closed on the saver thread.
    """

    def __init__(self, chan, source: SourceSpec, spec: PuppetSpec, realtime: bool, fake=None):
        from app.channel import SharedPictures

        self.chan = chan
        self.realtime = realtime
        self._events: deque = deque()  # (name, args) posted by any thread, sent by the loop
        self.capture = self._start_capture(source, fake, 0)
        self.engine = Engine(self.capture.slot, spec, self._post)
        self.pictures = SharedPictures()
        self.gui_free = True
        self.paused = False
        self.send_video = True
        self.targets: dict = {}  # view sizes for display scaling; "full": send camera-size frames
        self._char_box = None
        self.latest: DisplayFrame | None = None
        self.last_shown: DisplayFrame | None = None  # newest processed frame (for snapshots, recalibration)
        self.last_ok: DisplayFrame | None = None  # newest frame with face, eyes and mouth tracked
        self.dropped_display = 0
        self._last_sent_rgba = None
        self.snapshot_wanted = False
        self.requests_seen = 0
        self.recorders: dict[int, Any] = {}  # id -> Recorder, while recording
        self.finishing: dict[int, Any] = {}  # id -> Recorder, until its files are closed
        self._saved: deque = deque()  # ids whose files are closed (appended by the saver)
        self.saver = Worker("inkface-record-saver")  # closes stopped recordings in turn
        self.jobs = Worker("inkface-engine-jobs")  # recalibrations
        self._progress_at = 0.0
        self.quit = False

    def _post(self, name: str, args: tuple, key: Any = None) -> None:
        """An event for the window (any thread); with a ``key``, a newer one replaces it unsent."""
        self._events.append((name, args, key))

    def _start_capture(self, spec: SourceSpec, fake, source_id: int, previous: Capture | None = None) -> Capture:
        c = Capture(spec, self.realtime, fake, self._post, source_id, previous)
        c.start()
        return c

    # requests ---------------------------------------------------------------------------
    def handle(self, msg: tuple) -> None:  # noqa: C901 - one dispatch table
        seq, cmd, arg = msg
        self.requests_seen = max(self.requests_seen, seq)
        if cmd == "quit":
            self.quit = True
        elif cmd == "ack":
            self.gui_free = True
        elif cmd == "video":
            self.send_video = bool(arg)
        elif cmd == "targets":
            self.targets = dict(arg)
        elif cmd == "snapshot":
            self.snapshot_wanted = True
        elif cmd == "pause":
            self.paused = bool(arg)
            self.capture.set_paused(self.paused)
        elif cmd == "source":
            spec, fake, source_id = arg
            old = self.capture
            old.stop()
            self.capture = self._start_capture(spec, fake, source_id, previous=old)
            self.capture.set_paused(self.paused)
            self.engine.inbox = self.capture.slot
            self.engine.acquired = False
            self.dropped_display = 0
            self.latest = self.last_ok = None
        elif cmd == "puppet":
            self.engine.request(arg)
        elif cmd == "record":
            self._start_recording(*arg)
        elif cmd == "stop_record":
            self._stop_recording(arg)
        elif cmd == "recalibrate":
            self._recalibrate(arg)

    def _start_recording(self, rid: int, path: str, fps: float, background, overwrite: bool = False) -> None:
        from app.record import RecordError, Recorder

        try:
            self.recorders[rid] = Recorder(path, fps=fps, background=background, calibration=self.engine.calibration,
                                           overwrite=overwrite)
            self._post("recordStarted", (rid, path))
        except (RecordError, OSError) as e:
            self._post("recordFailed", (rid, _one_line(e)))

    def _stop_recording(self, rid: int) -> None:
        rec = self.recorders.pop(rid, None)
        if rec is None:
            self._post("recorded", (rid, None))
            return

        def progress(done: int, total: int) -> None:
            self._post("recordProgress", (rid, done, total), key=("progress", rid))

        def finish():
            try:
                res = rec.finish(progress=progress)
                n = frames_in_file(res.output)
                if n is not None:
                    res.frames = n  # what a player finds in the file (a GIF merges repeated frames)
                self._post("recorded", (rid, res))
            except Exception as e:
                self._post("recordFailed", (rid, _one_line(e)))
            finally:
                self._saved.append(rid)

        self.finishing[rid] = rec
        self.saver.submit(finish)

    def _recalibrate(self, save_to: str) -> None:
        """Calibrate again on the newest frame (for when the light changed), on a thread."""
        fr = self.last_shown
        ok = self.last_ok  # a blink at the key press: the newest fully tracked frame, if recent
        if fr is not None and ok is not None and ok is not fr and fr.status != "ok" and fr.time - ok.time < 1.0:
            fr = ok
        if fr is None or fr.frame_bgr is None:
            self._post("recalibrateFailed", ("no frame to calibrate on yet",))
            return
        image, overlay, index = fr.frame_bgr, fr.overlay, fr.index
        old = self.engine.calibration

        def work():
            try:
                cal, how = recalibrate(image, overlay, old, index)
                cal.save(save_to)
                self._post("recalibrated", (save_to, how))
            except Exception as e:
                self._post("recalibrateFailed", (_one_line(e),))

        self.jobs.submit(work, key="recalibrate")

    # frames -------------------------------------------------------------------------------
    def publish(self, fr: DisplayFrame, kind: str = "frame") -> None:
        """Pictures into shared memory, the rest as a small notice (only when the window is free)."""
        img = None
        if fr.frame_bgr is not None and (self.send_video or kind == "snapshot"):
            full = kind == "snapshot" or self.targets.get("full")
            img = fr.frame_bgr if full else scale_for_view(fr.frame_bgr, self.targets.get("video"))
        rgba = fr.rgba if kind == "frame" else None
        same = rgba is not None and rgba is self._last_sent_rgba and self._char_box == self.targets.get("char")
        if rgba is not None and not same:
            self._last_sent_rgba = rgba
            self._char_box = self.targets.get("char")
            rgba = scale_for_view(rgba, self._char_box)
        if fr.frame_bgr is not None:
            fr.frame_size = (int(fr.frame_bgr.shape[1]), int(fr.frame_bgr.shape[0]))
        name, layout = self.pictures.write([img, None if same else rgba])
        meta = {k: getattr(fr, k) for k in _META}
        meta["rgba_same"] = same
        self.chan.send(("frame", kind, meta, name, layout), key="frame")
        self.gui_free = False

    def _stamp(self, fr: DisplayFrame) -> None:
        cap = self.capture
        fr.dropped_capture = cap.slot.dropped
        fr.dropped_display = self.dropped_display
        fr.frames_read = cap.frames_read
        fr.frames_done = self.engine.frames_done
        fr.fps_in = cap.rate.rate()
        fr.source_id = cap.source_id
        fr.requests_seen = self.requests_seen

    def _report_progress(self) -> None:
        """Frames written so far by each recording in progress (the saver reports its own)."""
        now = time.monotonic()
        while self._saved:
            self.finishing.pop(self._saved.popleft(), None)
        if now - self._progress_at < 0.1:
            return
        self._progress_at = now
        for rid, rec in self.recorders.items():
            self.chan.send(("event", "recording", (rid, rec.frames, rec.dropped)), key=("recording", rid))

    # the loop ---------------------------------------------------------------------------
    def run(self) -> None:
        from app.channel import ChannelClosed

        try:
            while not self.quit:
                for msg in self.chan.receive():
                    self.handle(msg)
                if self.chan.closed:
                    return
                if self.quit:
                    break
                fr = self.engine.step(timeout=0.005)
                if fr is not None:
                    self.last_shown = fr
                    if fr.status == "ok":
                        self.last_ok = fr
                    for rec in self.recorders.values():
                        rec.add(fr)
                    if self.latest is not None:
                        self.dropped_display += 1  # the window never saw it: dropped, not queued
                    self._stamp(fr)
                    self.latest = fr
                while self._events:
                    name, args, key = self._events.popleft()
                    self.chan.send(("event", name, args), key=key)
                if self.recorders or self.finishing:
                    self._report_progress()
                if self.gui_free and self.snapshot_wanted:
                    self.snapshot_wanted = False
                    if self.last_shown is None:
                        self.chan.send(("event", "snapshot", (None,)))
                    else:
                        self.publish(self.last_shown, "snapshot")
                if self.gui_free and self.latest is not None:
                    self.publish(self.latest)
                    self.latest = None
                self.chan.flush()
        except ChannelClosed:
            return
        finally:
            self.close()

    def close(self) -> None:
        self.pictures.close()  # first: the window has stopped reading, and a slow exit may be cut short
        self.capture.stop()
        for rec in self.recorders.values():
            try:
                rec.finish()  # the window is gone or quitting: keep what was recorded
            except Exception:
                pass
        self.recorders.clear()
        self.saver.stop(wait_s=60.0)  # the recordings already stopped are closed too
        self.jobs.stop()
        self.engine._loader.stop()
        self.capture.join(3.0)  # let it leave OpenCV before the process exits


def frames_in_file(path: str | Path) -> int | None:
    """How many frames a recording holds as a reader sees it (MP4/AVI from the container, GIF
    frames, PNGs in a folder); None when it cannot be told."""
    p = Path(path)
    try:
        if p.is_dir():
            return len(list(p.glob("*.png")))
        if p.suffix.lower() == ".gif":
            from PIL import Image

            with Image.open(p) as im:
                return int(getattr(im, "n_frames", 1))
        import cv2

        cap = cv2.VideoCapture(str(p))
        try:
            n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) if cap.isOpened() else 0
        finally:
            cap.release()
        return n if n > 0 else None
    except (OSError, ValueError):
        return None


def recalibrate(image: np.ndarray, overlay, old, index: int = 0):
    """A new calibration on ``image``: at the points the tracker found in it, else where the
    face detector finds the face, else at the old calibration's clicks. Returns (Calibration, how)."""
    from tracker.calibration import calibrate
    from tracker.clicks import PIXEL_CENTRE, Clicks

    tries = []
    if overlay is not None and str(getattr(overlay, "status", "")) != "lost":
        try:
            pupils = np.asarray(overlay.pupils, float)
            brows = np.asarray(overlay.brows, float)
            mouth = np.asarray(overlay.mouth_centre, float)
            if np.all(np.isfinite(pupils)) and np.all(np.isfinite(brows)) and np.all(np.isfinite(mouth)):
                tries.append(("at the tracked points", lambda: Clicks.from_dict({
                    "frame": int(index), "left_pupil": list(pupils[0]), "right_pupil": list(pupils[1]),
                    "left_brow": list(brows[0]), "right_brow": list(brows[1]), "mouth": list(mouth)}
                ).moved(PIXEL_CENTRE, PIXEL_CENTRE)))  # the overlay's convention to the clicks
        except (AttributeError, TypeError, ValueError):
            pass

    def found():
        from tracker.auto_init import auto_clicks

        return auto_clicks(image, int(index))

    tries.append(("where the face was found", found))
    if old is not None and getattr(old, "clicks", None) is not None:
        tries.append(("at the previous clicks", lambda: old.clicks.moved(PIXEL_CENTRE, PIXEL_CENTRE)))
    last: Exception | None = None
    for how, clicks in tries:
        try:
            return calibrate(image, clicks()), how
        except Exception as e:  # the next way may still work; say why this one did not
            last = e
            print(f"inkface: recalibration {how} did not work: {_one_line(e)}", file=sys.stderr)
    raise ValueError(f"could not calibrate on this frame ({_one_line(last) if last else 'no face'})")


ENGINE_ENV = {"MALLOC_ARENA_MAX": "2"}
"""Environment the engine process starts with (a user's own setting wins). glibc gives every
thread that allocates its own heap arena; the engine's capture, loader and saver threads come and
go with each source, character and recording, and their arenas fragment: in the 10-minute soak
the engine grew from 297 to 412 MB with the default, and stayed within 261–304 MB with two arenas (window + engine −1.8 % after warm-up)."""


@contextlib.contextmanager
def _engine_environment():
    """Set :data:`ENGINE_ENV` while the engine process is spawned (it inherits the environment)."""
    added = {k: v for k, v in ENGINE_ENV.items() if k not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for k in added:
            os.environ.pop(k, None)


def engine_main(sock, source: SourceSpec, spec: PuppetSpec, realtime: bool, fake_source=None) -> None:
    """The engine process: capture thread + puppet + recorder; talks to the window over ``sock``."""
    import faulthandler
    import os
    import signal

    from app.channel import Channel

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl+C is the window's to handle; it stops us
    if hasattr(signal, "SIGUSR1"):
        faulthandler.register(signal.SIGUSR1, all_threads=True)  # `kill -USR1 <pid>`: print every stack
    for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(v, "1")
    chan = Channel(sock)
    try:
        EngineLoop(chan, source, spec, realtime, fake_source).run()
    except KeyboardInterrupt:
        pass
    finally:
        chan.close()


def _rebuild(source):
    """(Engine process) the fake camera a window-side reference describes (or None)."""
    if isinstance(source, tuple) and source and source[0] == "fake":
        from app.channel import read_frames
        from tracker.sources import FakeCamera

        return FakeCamera(read_frames(source[1]), fps=source[2], loop=source[3])
    return source


# ------------------------------------------------------------------------------------------
# the window side


class Pipeline:
    """(Window side) the engine process, the channel to it, and the newest frame it sent.

    ``request(**changes)`` changes the puppet (character, rate, filter, gain, calibration,
    training session ...), ``set_source`` plays from elsewhere, ``take()`` returns the newest
    :class:`DisplayFrame` (its QImages made here, on the GUI thread). Every call returns at
    once: requests are posted on the :class:`app.channel.Channel` (latest wins per kind) and
    answers come back as hooks, dispatched from the GUI event loop: ``frameReady``,
    ``puppetReady``, ``puppetFailed``, ``error``, ``sourceOpened``, ``sourceFailed``,
    ``finishedSource``, ``snapshot``, ``recordStarted``, ``recording``, ``recordProgress``,
    ``recorded``, ``recordFailed``, ``recalibrated``, ``recalibrateFailed``.
    """

    HOOKS = ("frameReady", "puppetReady", "puppetFailed", "error", "sourceOpened", "sourceFailed", "finishedSource",
             "snapshot", "recordStarted", "recording", "recordProgress", "recorded", "recordFailed", "recalibrated",
             "recalibrateFailed")

    def __init__(self, source: SourceSpec, puppet: PuppetSpec, realtime: bool = True, fake_source=None,
                 poll_ms: int = 20):
        self.source_spec = source
        self.spec = puppet
        self.realtime = realtime
        self._fake = fake_source
        self.live_art = ""
        self.frames_done = self.frames_read = 0
        self.dropped_capture = self.dropped_display = 0
        self.frames_received = 0
        self.send_video = True
        self.requests_sent = 0  # sequence number of the newest request
        self.source_id = 0
        for name in self.HOOKS:
            setattr(self, name, Hook())
        self._latest: DisplayFrame | None = None
        self._prev: DisplayFrame | None = None
        self._last_rgba: np.ndarray | None = None
        self._proc = None
        self._chan = None
        self._notifier = None
        self._reader = None
        self._spool = None
        # "calibration" / "session": {id: (object, reference)}; "fake": (camera, reference)
        self._refs: dict[str, Any] = {}
        self._files: dict[int, tuple[Any, str]] = {}  # id(object) -> (object, file it is saved in)
        self._targets: dict = {}
        self._inbox: deque = deque()
        self._dispatching = False
        self._dead = False
        self._stopped = False
        self._timer = QTimer()
        self._timer.setInterval(poll_ms)
        self._timer.timeout.connect(self._poll)

    # lifecycle --------------------------------------------------------------------------
    def start(self) -> None:
        import multiprocessing as mp
        import socket

        from PySide6.QtCore import QSocketNotifier

        from app.channel import Channel, PictureReader, Spool

        self._spool = self._spool or Spool()
        self._reader = PictureReader()
        mine, theirs = socket.socketpair()
        ctx = mp.get_context("spawn")
        proc = ctx.Process(target=engine_main, args=(theirs, self.source_spec, self._wire(self.spec),
                                                     self.realtime, self._fake_ref(self._fake)),
                           name="inkface-engine", daemon=True)
        try:
            with _engine_environment():
                proc.start()
        except BaseException:  # no engine: nothing for stop() to join, no socket left open
            mine.close()
            theirs.close()
            raise
        self._proc = proc  # only a started process: stop() joins it
        theirs.close()
        self._chan = Channel(mine)
        self._notifier = QSocketNotifier(mine.fileno(), QSocketNotifier.Type.Read)
        self._notifier.activated.connect(lambda *_: self._poll())
        self._timer.start()

    def stop(self, wait_s: float = 3.0) -> None:
        """Ask the engine to quit (it closes an open recording) and let it go (once; later calls do nothing)."""
        if self._stopped:
            return
        self._stopped = True
        try:
            self._timer.stop()
            if self._notifier is not None:
                self._notifier.setEnabled(False)
        except RuntimeError:  # Qt already deleted them (the window went away at exit)
            pass
        self._notifier = None
        if self._chan is not None:
            try:
                self._send("quit", None)
                self._chan.flush()
            except OSError:
                pass
        if self._proc is not None:
            self._proc.join(wait_s)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join(2.0)
                if self._reader is not None:
                    self._reader.unlink()  # the engine had no time to remove its segment
            self._proc = None
        if self._chan is not None:
            self._chan.close()
            self._chan = None
        if self._reader is not None:
            self._reader.close()
        if self._spool is not None:
            self._spool.close()
            self._spool = None

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.is_alive()

    @property
    def engine_pid(self) -> int | None:
        return None if self._proc is None else self._proc.pid

    def _send(self, cmd: str, arg: Any = None, key: Any = None) -> int:
        """Post a request (never waits); returns its sequence number."""
        from app.channel import ChannelClosed

        self.requests_sent += 1
        if self._chan is not None and not self._dead:
            try:
                self._chan.send((self.requests_sent, cmd, arg), key=key)
            except ChannelClosed:
                self._engine_gone()
        return self.requests_sent

    # large payloads by file ---------------------------------------------------------------
    def note_file(self, obj: Any, path: str | Path) -> None:
        """``obj`` (a calibration) is saved in ``path``: send the path instead of writing a copy."""
        self._files[id(obj)] = (obj, str(path))

    def _ref(self, kind: str, obj: Any, fresh: bool = False) -> Any:
        """What crosses to the engine for a calibration or session: small values as they are,
        objects as a file reference ``("file", path, n)``. A session saved in its folder is read
        from there; anything else is written to the spool. Calibrations do not change once made,
        so each is written once; a session handed over again (``fresh``) is read again."""
        if obj is None or isinstance(obj, (str, tuple)):
            return obj
        cache = self._refs.setdefault(kind, {})
        held = cache.get(id(obj))
        if held is not None and held[0] is obj and not (fresh and kind == "session"):
            return held[1]
        noted = self._files.pop(id(obj), None)
        folder = getattr(obj, "path", None) if kind == "session" else None
        if self._spool is None:
            from app.channel import Spool

            self._spool = Spool()
        try:
            if noted is not None and noted[0] is obj:
                path = noted[1]
            elif folder is not None and (Path(folder) / "session.json").is_file():
                path = str(folder)  # the training window saved it there before handing it over
            elif kind == "calibration":
                path = str(self._spool.path("calibration", ".json"))
                obj.save(path)
            else:
                spooled = self._spool.path("session")
                spooled.mkdir(parents=True, exist_ok=True)
                (spooled / "session.json").write_text(json.dumps(obj.to_dict()) + "\n")
                path = str(spooled)
        except Exception as e:  # a full disk, an odd object: say so, keep what the engine has
            self.error.emit(f"could not hand the {kind} to the engine: {_one_line(e)}")
            return held[1] if held is not None else None
        ref = ("file", path, self.requests_sent + 1)
        cache[id(obj)] = (obj, ref)
        while len(cache) > 4:
            cache.pop(next(iter(cache)))
        return ref

    def _wire(self, spec: PuppetSpec, changed: tuple = ()) -> PuppetSpec:
        return replace(spec, calibration=self._ref("calibration", spec.calibration),
                       session=self._ref("session", spec.session, fresh="session" in changed))

    def _fake_ref(self, fake) -> tuple | None:
        """A fake camera as ``("fake", frames.npy, fps, loop)`` (its frames go by file)."""
        if fake is None:
            return None
        frames = getattr(fake, "frames", None)
        if frames is None:
            raise TypeError(f"cannot send a {type(fake).__name__} to the engine (only a FakeCamera)")
        held = self._refs.get("fake")
        if held is not None and (held[0] is fake or _same_frames(held[0].frames, frames)):
            return held[1][:2] + (float(getattr(fake, "fps", 30.0)), bool(getattr(fake, "loop", False)))
        from app.channel import Spool, write_frames

        if self._spool is None:
            self._spool = Spool()
        path = write_frames(self._spool.path("fake", ".npy"), frames)
        ref = ("fake", str(path), float(getattr(fake, "fps", 30.0)), bool(getattr(fake, "loop", False)))
        self._refs["fake"] = (fake, ref)
        return ref

    # requests ---------------------------------------------------------------------------
    def request(self, **changes) -> int:
        """Change the puppet; the engine applies it before its next frame."""
        self.spec = replace(self.spec, **changes)
        return self._send("puppet", self._wire(self.spec, tuple(changes)), key="puppet")

    def set_source(self, spec: SourceSpec, fake_source=None) -> int:
        self.source_spec = spec
        self._fake = fake_source
        self.source_id = self.requests_sent + 1
        self.dropped_capture = self.dropped_display = 0
        return self._send("source", (spec, self._fake_ref(fake_source), self.source_id), key="source")

    def set_paused(self, paused: bool) -> int:
        return self._send("pause", bool(paused), key="pause")

    def set_video(self, on: bool) -> int:
        self.send_video = bool(on)
        return self._send("video", bool(on), key="video")

    def set_targets(self, video: tuple[int, int] | None = None, char: tuple[int, int] | None = None,
                    full: bool | None = None) -> int:
        """Sizes (device pixels) the pictures are shown at; ``full`` asks for camera-size frames."""
        if video is not None:
            self._targets["video"] = tuple(int(v) for v in video)
        if char is not None:
            self._targets["char"] = tuple(int(v) for v in char)
        if full is not None:
            self._targets["full"] = bool(full)
        return self._send("targets", dict(self._targets), key="targets")

    def request_snapshot(self) -> int:
        """Ask for the newest camera frame at full size; it arrives through ``snapshot(array)``."""
        return self._send("snapshot", None, key="snapshot")

    def start_recording(self, rid: int, path: str, fps: float, background, overwrite: bool = False) -> int:
        """Record to ``path``; ``overwrite`` replaces what is there (else ``recordFailed`` says it exists)."""
        return self._send("record", (int(rid), str(path), float(fps), background, bool(overwrite)))

    def stop_recording(self, rid: int) -> int:
        return self._send("stop_record", int(rid))

    def recalibrate(self) -> int:
        """Calibrate again on the newest frame; the result arrives through ``recalibrated(path, how)``."""
        if self._spool is None:
            return self.requests_sent
        return self._send("recalibrate", str(self._spool.path("recalibration", ".json")), key="recalibrate")

    # polling ----------------------------------------------------------------------------
    def _poll(self) -> None:
        """Read what has arrived and dispatch it (from the event loop; never waits)."""
        chan = self._chan
        if chan is None or self._dead:
            return
        try:
            chan.flush()
        except OSError:
            pass
        self._inbox.extend(chan.receive())
        if chan.closed and not self._inbox:
            self._engine_gone()
            return
        if self._dispatching:  # a hook opened a nested event loop: the outer call goes on
            return
        self._dispatching = True
        try:
            got_frame = False
            while self._inbox and self._chan is not None:
                msg = self._inbox.popleft()
                if msg[0] == "event":
                    self._event(msg[1], msg[2])
                elif msg[0] == "frame":
                    got_frame = self._frame(*msg[1:]) or got_frame
            if got_frame:
                self.frameReady.emit()
        finally:
            self._dispatching = False
        if self._chan is not None and self._chan.closed:
            self._engine_gone()

    def _event(self, name: str, args: tuple) -> None:
        if name in ("sourceOpened", "sourceFailed", "finishedSource"):
            if args[0] != self.source_id:
                return  # news from a source the window has already left
            args = args[1:]
        elif name == "puppetReady":
            self.live_art = args[0]
        getattr(self, name).emit(*args)

    def _frame(self, kind: str, meta: dict, name: str, layout: list) -> bool:
        try:
            video, rgba = self._reader.read(name, layout)
        except (OSError, ValueError) as e:  # the segment vanished: the engine is going away
            self._send("ack", None, key="ack")
            self.error.emit(f"lost a frame from the engine ({_one_line(e)})")
            return False
        self._send("ack", None, key="ack")
        if kind == "snapshot":
            self.snapshot.emit(video)
            return False
        if rgba is None and meta.get("rgba_same"):
            rgba = self._last_rgba  # the output rate held the picture: it was not sent again
        self._last_rgba = rgba
        fr = DisplayFrame(meta["index"], meta["time"], video, rgba)
        for k in _META[2:]:
            setattr(fr, k, meta[k])
        if fr.source_id != self.source_id:
            fr.dropped_capture = fr.dropped_display = 0  # counted for the source the window left
        self.frames_received += 1
        self.dropped_capture, self.dropped_display = fr.dropped_capture, fr.dropped_display
        self.frames_read, self.frames_done = fr.frames_read, fr.frames_done
        self._latest = fr
        return True

    def _engine_gone(self) -> None:
        if self._dead:
            return
        self._dead = True
        self._timer.stop()
        if self._notifier is not None:
            self._notifier.setEnabled(False)
        self.error.emit("the engine process has stopped")

    def take(self) -> DisplayFrame | None:
        """The newest frame (once), with its QImages made on this (the GUI) thread."""
        fr, self._latest = self._latest, None
        if fr is not None:
            fr.to_images(self._prev, video=self.send_video)
            self._prev = fr
        return fr


def _task_main(conn, target: str, args: tuple) -> None:
    """(Task process) run ``module:function(report, cancelled, *args)`` and report back."""
    import importlib
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)

    mod, fn = target.split(":")
    func = getattr(importlib.import_module(mod), fn)
    state = {"cancel": False}

    def cancelled() -> bool:
        while conn.poll():
            if conn.recv() == "cancel":
                state["cancel"] = True
        return state["cancel"]

    def report(name: str, *a) -> None:
        conn.send((name, a))

    try:
        res = func(report, cancelled, *args)
        conn.send(("done", (res,)))
    except Exception as e:
        conn.send(("failed", (_one_line(e),)))


class ProcessTask:
    """A long job (re-render a track, track a clip) in its own process, polled by a timer.

    Same face as a worker thread: ``start()``, ``isRunning()``, ``cancel()``, ``wait(ms)``
    and hooks ``progress(i, n)``, ``done(result)``, ``failed(message)``.
    """

    def __init__(self, target: str, *args):
        self.target, self.args = target, args
        self.progress, self.done, self.failed = Hook(), Hook(), Hook()
        self._proc = self._conn = None
        self._finished = False
        self._timer = QTimer()
        self._timer.setInterval(20)
        self._timer.timeout.connect(self._poll)

    def start(self) -> None:
        import multiprocessing as mp

        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_task_main, args=(child, self.target, self.args), daemon=True)
        self._proc.start()
        child.close()
        self._timer.start()

    def isRunning(self) -> bool:  # noqa: N802 - same name as QThread's
        return self._proc is not None and not self._finished

    def cancel(self) -> None:
        if self._conn is not None and not self._finished:
            try:
                self._conn.send("cancel")
            except (OSError, BrokenPipeError):
                pass

    def wait(self, ms: int = 5000) -> bool:
        if self._proc is None:
            return True
        self._proc.join(ms / 1000.0)
        if self._proc.is_alive():
            return False
        self._poll()
        return True

    def _poll(self) -> None:
        if self._conn is None:
            return
        try:
            while self._conn.poll():
                name, args = self._conn.recv()
                if name in ("done", "failed"):
                    self._finish()
                getattr(self, name).emit(*args)
        except (EOFError, OSError):
            if not self._finished:
                self._finish()
                self.failed.emit("the task process stopped unexpectedly")

    def _finish(self) -> None:
        self._finished = True
        self._timer.stop()


def _same(a, b) -> bool:
    if isinstance(a, (str, tuple)) or isinstance(b, (str, tuple)):
        return a == b
    return a is b


def _same_frames(a, b) -> bool:
    """The same frame arrays in the same order (a new fake camera over the same frames)."""
    return len(a) == len(b) and all(x is y for x, y in zip(a, b))


def _can_tune(puppet) -> bool:
    return puppet is not None and callable(getattr(puppet, "configure", None))


def _tune(puppet, spec: PuppetSpec) -> None:
    """Change rate/filter/gain on a live puppet without rebuilding it."""
    _call_flexibly(puppet.configure, fps=spec.fps, filter=spec.filter, strength=spec.strength, gain=spec.gain)


def _reopen(src, spec: SourceSpec, given):
    """A fresh pass over the same source for looping playback."""
    try:
        src.close()
    except Exception:
        pass
    if given is not None:
        frames = getattr(given, "frames", None)
        if frames is None:
            return None
        try:
            return type(given)(frames, fps=given.fps)
        except Exception:
            return None
    return open_source(spec)


def _one_line(e: BaseException) -> str:
    msg = str(e).strip().splitlines()
    return msg[0] if msg else type(e).__name__


