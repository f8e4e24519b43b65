"""Capture, tracking and rendering off the GUI thread — in a separate engine process.

* The **engine process** (:func:`engine_main`) runs a :class:`Capture` thread that reads the
  frame source (camera, video file, the synthetic performance) into a one-item
  :class:`LatestSlot`, paced to the source's rate for files; when the engine has not taken the
  previous frame it is overwritten and counted as dropped — frames are never queued. The
  :class:`Engine` steps ``training.puppet.Puppet`` on the newest frame (track → filter → map →
  render) and keeps only its newest result for the window; it is sent when the window has
  acknowledged the previous one, so a slow window drops frames too. Characters are built on a
  loader thread so video keeps flowing meanwhile. Recording happens there as well.
* The **window side** (:class:`Pipeline`) polls the pipe from a timer and turns the newest
  frame into QImages on the GUI thread. Requests (another source, character, rate, filter,
  gain …) are messages; nothing heavy ever runs on the GUI thread.

Why a process and not QThreads: see the note above :class:`Hook`.
"""

from __future__ import annotations

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
    fps: float = 0.0
    dropped_capture: int = 0
    dropped_display: int = 0
    art: str = ""
    status: str = ""
    fresh: bool = True  # False: the output rate held the previous picture
    frames_read: int = 0  # by the capture so far
    frames_done: int = 0  # by the engine so far
    frame_size: tuple = (0, 0)  # (w, h) of the camera frame; ``frame_bgr`` may be scaled for display
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
    (``"performance"``), clicks beside a video (``("clicks", clicks_json, video)``), or an object as is."""
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


class Capture(threading.Thread):
    """(Engine process) reads a frame source into a :class:`LatestSlot`.

    ``realtime`` paces file and synthetic sources to their fps (cameras pace themselves);
    with ``realtime=False`` it waits for the engine to take each frame (no drops: used to
    measure the loop's top speed). ``events`` receives ``(name, args)`` notifications.
    """

    def __init__(self, slot: LatestSlot, spec: SourceSpec, realtime: bool, source, events: Callable):
        super().__init__(name="inkface-capture", daemon=True)
        self.slot = slot
        self.spec = spec
        self.realtime = realtime
        self._given_source = source
        self._events = events
        self._halt = threading.Event()
        self._paused = threading.Event()
        self.frames_read = 0

    def post(self, name: str, *args) -> None:
        self._events(name, args)

    def stop(self) -> None:
        self._halt.set()
        self.slot.notify_taken()

    def set_paused(self, paused: bool) -> None:
        (self._paused.set if paused else self._paused.clear)()

    def run(self) -> None:  # noqa: C901 - one loop, kept together on purpose
        try:
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
                    shown += 1
                    self.frames_read += 1
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
    result for the window; builds puppets on a loader thread so frames keep flowing."""

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
        self._build_lock = threading.Lock()
        self._last_rgba: np.ndarray | None = None
        self._times: deque[float] = deque(maxlen=60)
        self.frames_done = 0
        self.last_error = ""

    def post(self, name: str, *args) -> None:
        self._events(name, args)

    def request(self, spec: PuppetSpec) -> None:
        with self._lock:
            self._pending = spec

    def _apply_pending(self) -> None:
        """Apply the GUI's latest request; swap in a puppet a loader thread has finished."""
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
                    try:
                        _tune(puppet, self.spec)
                    except Exception:
                        pass
                    self.post("puppetReady", bspec.art)
        if spec is None:
            return
        old = self.spec
        target_puppet = self.puppet if self.live_art == old.art else None
        rebuild = (
            target_puppet is None
            or spec.art != old.art
            or spec.detail != old.detail
            or not _same(spec.calibration, old.calibration)
            or (spec.session is not old.session and not callable(getattr(self.puppet, "set_session", None)))
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
            threading.Thread(target=self._build, args=(self._gen, spec), name="inkface-puppet-loader", daemon=True).start()
            return
        if spec.session is not old.session and spec.session is not None:
            try:
                self.puppet.set_session(spec.session)
            except Exception as e:
                self.post("puppetFailed", _one_line(e))
        _tune(self.puppet, spec)

    def _build(self, gen: int, spec: PuppetSpec) -> None:
        """Load the art set, resolve the calibration and build the puppet (loader thread)."""
        puppet = cal = None
        err = ""
        try:
            with self._build_lock:  # one build at a time; a superseded one is skipped
                if gen != self._gen:
                    return
                art = self._cache.get(spec.art)
                if art is None:
                    art = load_artset(spec.art)
                    self._cache[spec.art] = art
                cal = self._resolve_calibration(spec.calibration)
                if gen != self._gen:
                    return
                puppet = make_puppet(art, replace(spec, calibration=cal))
        except Exception as e:
            err = _one_line(e) or type(e).__name__
        finally:
            if gen == self._gen:
                self.building = False
        with self._lock:
            self._built = (gen, puppet, spec, cal, err)
        self.inbox.notify_taken()

    def _resolve_calibration(self, cal):
        key = cal if isinstance(cal, (str, tuple)) else None
        if key is None:
            return cal
        if key not in self._cal_cache:
            self._cal_cache[key] = resolve_calibration(cal)
        return self._cal_cache[key]

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
        self._times.append(time.perf_counter())
        if len(self._times) > 1:
            out.fps = (len(self._times) - 1) / max(1e-9, self._times[-1] - self._times[0])
        self.frames_done += 1
        return out

    def _process(self, index: int, t: float, image: np.ndarray) -> DisplayFrame:
        p = self.puppet
        if p is None:
            return DisplayFrame(index, t, image, status="loading the character" if self.building else "no character")
        pf = p.step(image, index, t)
        if pf is None:
            return DisplayFrame(index, t, image, art=self.live_art)
        rgba = getattr(pf, "rgba_pm", None)
        fresh = bool(getattr(pf, "fresh", True))
        if rgba is not None:
            if not fresh and self._last_rgba is not None:  # held picture (lower output rate)
                rgba = self._last_rgba
            else:  # a private copy: the renderer may reuse its buffer for the next frame
                rgba = self._last_rgba = rgba.copy()
        params = getattr(pf, "params", None)
        return DisplayFrame(
            index, t, image, rgba,
            params=params,
            overlay=getattr(pf, "overlay", None),
            weights=getattr(pf, "weights", None),
            timings_ms=dict(getattr(pf, "timings_ms", {}) or {}),
            art=self.live_art,
            status=str(getattr(params, "status", "")) if params is not None else "",
            fresh=fresh,
        )


_META = ("index", "time", "params", "overlay", "weights", "timings_ms", "fps", "dropped_capture", "dropped_display",
         "art", "status", "fresh", "frames_read", "frames_done", "frame_size")


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


def _send_frame(conn, fr: DisplayFrame, send_video: bool, last_sent_rgba, targets: dict, cache: dict) -> None:
    """A frame over the pipe: the small fields as ordinary pipe messages, the two pictures as raw bytes, scaled
    to the views' sizes (``targets``) unless the window asked for full frames."""
    img = None
    if send_video and fr.frame_bgr is not None:
        img = fr.frame_bgr if targets.get("full") else scale_for_view(fr.frame_bgr, targets.get("video"))
    rgba = fr.rgba
    same = rgba is not None and rgba is last_sent_rgba and cache.get("box") == targets.get("char")
    if rgba is not None and not same:
        rgba = scale_for_view(rgba, targets.get("char"))
        cache["box"] = targets.get("char")
    if fr.frame_bgr is not None:
        fr.frame_size = (int(fr.frame_bgr.shape[1]), int(fr.frame_bgr.shape[0]))
    meta = {k: getattr(fr, k) for k in _META}
    meta["video_shape"] = None if img is None else img.shape
    meta["rgba_shape"] = None if rgba is None or same else rgba.shape
    meta["rgba_same"] = same
    conn.send(("frame", meta))
    if img is not None:
        conn.send_bytes(np.ascontiguousarray(img).reshape(-1).data)
    if rgba is not None and not same:
        conn.send_bytes(np.ascontiguousarray(rgba).reshape(-1).data)


def engine_main(conn, source: SourceSpec, spec: PuppetSpec, realtime: bool, fake_source=None) -> None:
    """The engine process: capture thread + puppet + recorder; talks to the window over ``conn``."""
    import os
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl+C is the window's to handle; it stops us

    for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(v, "1")
    events: deque = deque()
    post = lambda name, args: events.append((name, args))  # noqa: E731 - threads append, main loop sends
    inbox = LatestSlot()
    engine = Engine(inbox, spec, post)
    objects: dict[str, Any] = {}  # "calibration" / "session" as last sent by the window

    def start_capture(src_spec, fake):
        c = Capture(inbox, src_spec, realtime, _rebuild(fake), post)
        c.start()
        return c

    capture = start_capture(source, fake_source)
    gui_free = True
    send_video = True
    targets: dict = {}  # view sizes for display scaling; "full": send camera-size frames
    scale_cache: dict = {}
    last_frame: np.ndarray | None = None
    latest: DisplayFrame | None = None
    dropped_display = 0
    last_sent_rgba = None
    recorder = None
    try:
        while True:
            while conn.poll():
                msg = conn.recv()
                cmd = msg.get("cmd")
                if cmd == "quit":
                    return
                if cmd == "ack":
                    gui_free = True
                elif cmd == "video":
                    send_video = bool(msg["on"])
                elif cmd == "targets":
                    targets.update(msg["targets"])
                elif cmd == "snapshot":
                    post("snapshot", (last_frame,))
                elif cmd == "pause":
                    capture.set_paused(bool(msg["on"]))
                elif cmd == "source":
                    capture.stop()
                    capture.join(3.0)
                    inbox.clear()
                    capture = start_capture(msg["spec"], msg.get("fake"))
                elif cmd == "puppet":
                    for key in ("calibration", "session"):
                        if key in msg:
                            objects[key] = msg[key]
                    engine.request(replace(msg["spec"], calibration=objects.get("calibration"),
                                           session=objects.get("session")))
                elif cmd == "record":
                    from app.record import RecordError, Recorder

                    try:
                        recorder = Recorder(msg["path"], fps=msg["fps"], background=msg.get("background"),
                                            calibration=engine.calibration)
                        post("recordStarted", (msg["path"],))
                    except RecordError as e:
                        recorder = None
                        post("recordFailed", (str(e),))
                elif cmd == "stop_record":
                    if recorder is not None:
                        rec, recorder = recorder, None
                        try:
                            post("recorded", (rec.finish(),))
                        except Exception as e:
                            post("recordFailed", (_one_line(e),))
                    else:
                        post("recorded", (None,))
            fr = engine.step(timeout=0.005)
            if fr is not None:
                last_frame = fr.frame_bgr
                if recorder is not None:
                    recorder.add(fr)
                if latest is not None:
                    dropped_display += 1  # the window never saw it: dropped, not queued
                latest = fr
            while events:
                name, args = events.popleft()
                conn.send(("event", name, args))
            if latest is not None and gui_free:
                latest.dropped_capture = inbox.dropped
                latest.dropped_display = dropped_display
                latest.frames_read = capture.frames_read
                latest.frames_done = engine.frames_done
                _send_frame(conn, latest, send_video, last_sent_rgba, targets, scale_cache)
                last_sent_rgba = latest.rgba
                latest = None
                gui_free = False
    except (EOFError, BrokenPipeError, ConnectionResetError, KeyboardInterrupt):
        return
    finally:
        capture.stop()
        capture.join(3.0)  # let it leave OpenCV before the process exits
        if recorder is not None:
            try:
                recorder.finish()
            except Exception:
                pass


def _portable(source):
    """A fake camera as ``("fake", frames, fps, loop)`` so it can cross to the engine process
    (sources hold locks, which cannot cross a process pipe); anything else as is."""
    if source is None or isinstance(source, tuple):
        return source
    frames = getattr(source, "frames", None)
    if frames is not None:
        return ("fake", list(frames), float(getattr(source, "fps", 30.0)), bool(getattr(source, "loop", False)))
    return source


def _rebuild(source):
    """(Engine process) the source :func:`_portable` described."""
    if isinstance(source, tuple) and source and source[0] == "fake":
        from tracker.sources import FakeCamera

        return FakeCamera(source[1], fps=source[2], loop=source[3])
    return source


class Pipeline:
    """(Window side) the engine process and the timer that polls it.

    ``request(**changes)`` changes the puppet (character, rate, filter, gain ...),
    ``set_source`` plays from elsewhere, ``take()`` returns the newest :class:`DisplayFrame`
    (with its QImages made here, on the GUI thread). Hooks: ``frameReady``, ``puppetReady``,
    ``puppetFailed``, ``error``, ``sourceOpened``, ``sourceFailed``, ``recorded``,
    ``recordFailed``.
    """

    def __init__(self, source: SourceSpec, puppet: PuppetSpec, realtime: bool = True, fake_source=None,
                 poll_ms: int = 4):
        self.source_spec = source
        self.spec = puppet
        self.realtime = realtime
        self._fake = fake_source
        self.live_art = ""
        self.frames_done = self.frames_read = 0
        self.dropped_capture = self.dropped_display = 0
        self.frames_received = 0
        self.send_video = True
        self._sent_cal = self._sent_session = _UNSENT
        for name in ("frameReady", "puppetReady", "puppetFailed", "error", "sourceOpened", "sourceFailed",
                     "finishedSource", "recorded", "recordFailed", "recordStarted", "snapshot"):
            setattr(self, name, Hook())
        self._latest: DisplayFrame | None = None
        self._prev: DisplayFrame | None = None
        self._proc = None
        self._conn = None
        self._timer = QTimer()
        self._timer.setInterval(poll_ms)
        self._timer.timeout.connect(self._poll)

    # lifecycle --------------------------------------------------------------------------
    def start(self) -> None:
        import multiprocessing as mp

        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        spec, extra = self._spec_message(self.spec)
        spec = replace(spec, calibration=extra.get("calibration"), session=extra.get("session"))
        self._proc = ctx.Process(target=engine_main, args=(child, self.source_spec, spec, self.realtime,
                                                           _portable(self._fake)),
                                 name="inkface-engine", daemon=True)
        self._proc.start()
        child.close()
        self._timer.start()

    def stop(self, wait_s: float = 5.0) -> None:
        self._timer.stop()
        if self._conn is not None:
            try:
                self._conn.send({"cmd": "quit"})
            except (OSError, BrokenPipeError):
                pass
        if self._proc is not None:
            # keep draining: the engine may be blocked sending a frame into a full pipe
            end = time.monotonic() + wait_s
            while self._proc.is_alive() and time.monotonic() < end:
                try:
                    if self._conn is not None and self._conn.poll(0.01):
                        self._conn.recv_bytes()
                except (EOFError, OSError):
                    self._proc.join(0.05)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join(2.0)
            self._proc = None
        if self._conn is not None:
            self._conn.close()
            self._conn = None

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.is_alive()

    def _send(self, msg: dict) -> None:
        if self._conn is not None:
            try:
                self._conn.send(msg)
            except (OSError, BrokenPipeError):
                self.error.emit("the engine process has stopped")

    # requests ---------------------------------------------------------------------------
    def _spec_message(self, spec: PuppetSpec) -> tuple[PuppetSpec, dict]:
        """The spec without its big objects, plus those objects that changed since last sent."""
        extra = {}
        if not _same(spec.calibration, self._sent_cal):
            extra["calibration"] = spec.calibration
            self._sent_cal = spec.calibration
        if spec.session is not self._sent_session:
            extra["session"] = spec.session
            self._sent_session = spec.session
        return replace(spec, calibration=None, session=None), extra

    def request(self, **changes) -> None:
        """Change the puppet; the engine applies it before its next frame."""
        self.spec = replace(self.spec, **changes)
        if self._conn is not None:
            spec, extra = self._spec_message(self.spec)
            self._send({"cmd": "puppet", "spec": spec, **extra})

    def set_source(self, spec: SourceSpec, fake_source=None) -> None:
        self.source_spec = spec
        self._fake = fake_source
        self._send({"cmd": "source", "spec": spec, "fake": _portable(fake_source)})

    def set_paused(self, paused: bool) -> None:
        self._send({"cmd": "pause", "on": bool(paused)})

    def set_video(self, on: bool) -> None:
        self.send_video = bool(on)
        self._send({"cmd": "video", "on": bool(on)})

    def set_targets(self, video: tuple[int, int] | None = None, char: tuple[int, int] | None = None,
                    full: bool | None = None) -> None:
        """Sizes (device pixels) the pictures are shown at; ``full`` asks for camera-size frames."""
        t = {}
        if video is not None:
            t["video"] = tuple(int(v) for v in video)
        if char is not None:
            t["char"] = tuple(int(v) for v in char)
        if full is not None:
            t["full"] = bool(full)
        self._send({"cmd": "targets", "targets": t})

    def full_frame(self, timeout_s: float = 5.0) -> np.ndarray | None:
        """The newest camera frame at full size (waits for the engine, pumping its messages)."""
        got: list = []
        fn = got.append
        self.snapshot.connect(fn)
        try:
            self._send({"cmd": "snapshot"})
            end = time.monotonic() + timeout_s
            while not got and time.monotonic() < end and self.running:
                self._poll()
                time.sleep(0.005)
        finally:
            self.snapshot.disconnect(fn)
        return got[0] if got else None

    def start_recording(self, path: str, fps: float, background) -> None:
        self._send({"cmd": "record", "path": str(path), "fps": float(fps), "background": background})

    def stop_recording(self) -> None:
        self._send({"cmd": "stop_record"})

    # polling ----------------------------------------------------------------------------
    def _poll(self) -> None:
        conn = self._conn
        if conn is None:
            return
        got_frame = False
        try:
            while conn.poll():
                msg = conn.recv()
                if msg[0] == "event":
                    _, name, args = msg
                    if name == "puppetReady":
                        self.live_art = args[0]
                    getattr(self, name).emit(*args)
                    if self._conn is None:
                        return
                elif msg[0] == "frame":
                    self._latest = self._receive_frame(conn, msg[1])
                    got_frame = True
                    conn.send({"cmd": "ack"})
        except (EOFError, OSError):
            self._timer.stop()
            self.error.emit("the engine process has stopped")
            return
        if got_frame:
            self.frameReady.emit()

    def _receive_frame(self, conn, meta: dict) -> DisplayFrame:
        video = rgba = None
        if meta["video_shape"] is not None:
            video = np.frombuffer(conn.recv_bytes(), np.uint8).reshape(meta["video_shape"])
        if meta["rgba_shape"] is not None:
            rgba = np.frombuffer(conn.recv_bytes(), np.uint8).reshape(meta["rgba_shape"])
        elif meta["rgba_same"] and self._prev is not None:
            rgba = self._prev.rgba
        fr = DisplayFrame(meta["index"], meta["time"], video, rgba)
        for k in _META[2:]:
            setattr(fr, k, meta[k])
        self.frames_received += 1
        self.dropped_capture, self.dropped_display = fr.dropped_capture, fr.dropped_display
        self.frames_read, self.frames_done = fr.frames_read, fr.frames_done
        return fr

    def take(self) -> DisplayFrame | None:
        """The newest frame (once), with its QImages made on this (the GUI) thread."""
        fr, self._latest = self._latest, None
        if fr is not None:
            fr.to_images(self._prev, video=self.send_video)
            self._prev = fr
        return fr


_UNSENT = object()


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


