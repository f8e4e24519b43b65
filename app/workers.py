"""Capture and tracking off the GUI thread.

Two threads feed the window:

* :class:`CaptureThread` reads frames from a :class:`tracker.sources` source (camera, video
  file, the synthetic performance), paced to the source's frame rate for files, and puts each
  one into a one-item :class:`LatestSlot`. If the pipeline has not taken the previous frame,
  that frame is overwritten and counted as dropped — frames are never queued.
* :class:`PipelineThread` takes the newest frame, runs ``Puppet.step`` (track → filter → map
  → render), converts the video frame and the character to ``QImage`` (allowed off the GUI
  thread), and hands a :class:`DisplayFrame` to the GUI through a second slot. The GUI is
  signalled only when it has consumed the previous one, so a slow GUI drops frames too.

Everything the GUI asks for (another source, character, rate, filter, gain …) goes through
thread-safe request methods; the pipeline thread applies them between frames, so the heavy
work of loading a character and precomputing its α tables never blocks the window.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
from PySide6.QtCore import QThread, Signal
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
    """One frame ready for the window, built entirely off the GUI thread."""

    index: int
    time: float
    video: QImage | None
    character: QImage | None
    frame_bgr: np.ndarray | None
    params: Any = None
    overlay: Any = None
    weights: Any = None
    timings_ms: dict = field(default_factory=dict)
    fps: float = 0.0
    dropped_capture: int = 0
    dropped_display: int = 0
    art: str = ""
    status: str = ""


# ------------------------------------------------------------------------------------------
# conversions (no copies beyond the one QImage needs to own its pixels)


def bgr_to_qimage(frame: np.ndarray) -> QImage:
    """A BGR uint8 (H,W,3) frame as an owned QImage."""
    h, w = frame.shape[:2]
    buf = np.ascontiguousarray(frame)
    img = QImage(buf.data, w, h, int(buf.strides[0]), QImage.Format.Format_BGR888)
    return img.copy()


def rgba_pm_to_qimage(rgba: np.ndarray) -> QImage:
    """A premultiplied RGBA uint8 (h,w,4) image as an owned QImage."""
    h, w = rgba.shape[:2]
    buf = np.ascontiguousarray(rgba)
    img = QImage(buf.data, w, h, int(buf.strides[0]), QImage.Format.Format_RGBA8888_Premultiplied)
    return img.copy()


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
    try:
        from tracker import sources
    except ImportError:  # the foundation's sources are not in this build: read with OpenCV directly
        sources = None
    if spec.kind == "camera":
        return sources.CameraSource(spec.camera) if sources else _Cv2Source(spec.camera, f"camera {spec.camera}")
    if spec.kind == "video":
        return sources.VideoFileSource(spec.video) if sources else _Cv2Source(spec.video, spec.video)
    cached = performance_cache_path(spec.seconds, spec.seed)
    if cached.is_file():
        return sources.VideoFileSource(str(cached)) if sources else _Cv2Source(str(cached), str(cached))
    return CachingPerformanceSource(bundled_performance(spec.seconds, spec.seed), cached)


class _Cv2Source:
    """Minimal OpenCV reader used only when ``tracker.sources`` is unavailable."""

    def __init__(self, what, name: str):
        import cv2

        self._cap = cv2.VideoCapture(what)
        if not self._cap.isOpened():
            raise ValueError(f"{name}: cannot be opened")
        self.fps = float(self._cap.get(cv2.CAP_PROP_FPS) or 30.0) or 30.0
        self.size = (int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))

    def __iter__(self):
        i = 0
        while True:
            ok, img = self._cap.read()
            if not ok:
                return
            yield _Frame(i, i / self.fps, img)
            i += 1

    def close(self) -> None:
        self._cap.release()


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


@dataclass
class _Frame:
    index: int
    time: float
    image: np.ndarray


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
                yield _Frame(i, i / self.fps, img)
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
# threads


class CaptureThread(QThread):
    """Reads a frame source into a :class:`LatestSlot`.

    ``realtime`` paces file and synthetic sources to their fps (cameras pace themselves);
    with ``realtime=False`` it waits for the pipeline to take each frame (no drops: used to
    measure the loop's top speed).
    """

    sourceFailed = Signal(str)
    sourceOpened = Signal(str, float, int, int)  # description, fps, width, height
    finishedSource = Signal()

    def __init__(self, slot: LatestSlot, spec: SourceSpec, realtime: bool = True, source=None, parent=None):
        super().__init__(parent)
        self.slot = slot
        self.spec = spec
        self.realtime = realtime
        self._given_source = source
        self._stop = threading.Event()
        self._paused = threading.Event()
        self.frames_read = 0

    def stop(self) -> None:
        self._stop.set()
        self.slot.notify_taken()

    def set_paused(self, paused: bool) -> None:
        (self._paused.set if paused else self._paused.clear)()

    def run(self) -> None:  # noqa: C901 - one loop, kept together on purpose
        try:
            src = self._given_source if self._given_source is not None else open_source(self.spec)
        except Exception as e:  # SourceError, missing core, bad file: one line for the user
            self.sourceFailed.emit(_one_line(e))
            return
        try:
            fps = float(getattr(src, "fps", 30.0) or 30.0)
            w, h = getattr(src, "size", (0, 0))
            self.sourceOpened.emit(self.spec.describe(), fps, int(w), int(h))
            # a real camera paces itself; files, the synthetic performer and fakes are paced here
            pace = self.realtime and (self._given_source is not None or self.spec.kind != "camera")
            t0 = time.perf_counter()
            shown = 0
            offset = 0  # index offset across loops
            while not self._stop.is_set():
                got_any = False
                for fr in src:
                    got_any = True
                    if self._stop.is_set():
                        break
                    while self._paused.is_set() and not self._stop.is_set():
                        time.sleep(0.03)
                        t0 = time.perf_counter() - shown / fps
                    if pace:
                        due = t0 + shown / fps
                        delay = due - time.perf_counter()
                        if delay > 0:
                            self._stop.wait(delay)
                        elif delay < -0.5:  # hopelessly behind (debugger, suspend): resync
                            t0 = time.perf_counter() - shown / fps
                    elif not self.realtime:
                        while not self.slot.wait_empty(0.1):
                            if self._stop.is_set():
                                break
                    shown += 1
                    self.frames_read += 1
                    self.slot.put((fr.index + offset, fr.time + offset / fps, fr.image))
                if self._stop.is_set():
                    break
                if not (self.spec.loop and got_any and self.spec.kind != "camera"):
                    break
                offset += max(1, shown - offset)
                src = _reopen(src, self.spec, self._given_source)
                if src is None:
                    break
            self.finishedSource.emit()
        except Exception as e:
            self.sourceFailed.emit(_one_line(e))
        finally:
            try:
                src.close()
            except Exception:
                pass


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


class PipelineThread(QThread):
    """Takes the newest frame, steps the puppet and publishes a :class:`DisplayFrame`."""

    frameReady = Signal()
    puppetReady = Signal(str)  # art-set path now live
    puppetFailed = Signal(str)
    error = Signal(str)

    def __init__(self, inbox: LatestSlot, outbox: LatestSlot, spec: PuppetSpec, parent=None):
        super().__init__(parent)
        self.inbox = inbox
        self.outbox = outbox
        self._lock = threading.Lock()
        self._pending: PuppetSpec | None = spec
        self.spec = PuppetSpec()
        self.puppet = None
        self._cache: dict[str, Any] = {}  # art path -> loaded ArtSet
        self._cal_cache: dict[Any, Any] = {}
        self._stop = threading.Event()
        self._gui_busy = threading.Event()
        self._times: deque[float] = deque(maxlen=60)
        self.frames_done = 0
        self.last_error = ""
        self.render_video = True
        self.calibration = None  # the resolved Calibration the puppet uses
        self.live_art = ""  # art set of the puppet in use ("" while none is ready)
        self.building = False
        self._gen = 0
        self._built = None
        self._build_lock = threading.Lock()
        self._last_char: QImage | None = None

    # requests from the GUI thread ------------------------------------------------------
    def request(self, **changes) -> None:
        """Ask for a new puppet configuration; applied before the next frame."""
        with self._lock:
            base = self._pending or self.spec
            self._pending = replace(base, **changes)

    def stop(self) -> None:
        self._stop.set()
        self.inbox.notify_taken()

    def gui_consumed(self) -> None:
        """The GUI has taken the last frame; the next one may be signalled."""
        self._gui_busy.clear()

    # the loop --------------------------------------------------------------------------
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
                    self.puppetFailed.emit(err)
                else:
                    self.puppet, self.live_art, self.calibration = puppet, bspec.art, cal
                    self._last_char = None
                    try:
                        _tune(puppet, self.spec)
                    except Exception:
                        pass
                    self.puppetReady.emit(bspec.art)
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
                self.puppetFailed.emit(_one_line(e))
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

    def run(self) -> None:
        while not self._stop.is_set():
            self._apply_pending()
            item = self.inbox.take(timeout=0.1)
            if item is None:
                continue
            index, t, image = item
            try:
                out = self._process(index, t, image)
            except Exception as e:  # keep the window alive; say what went wrong once
                msg = _one_line(e)
                if msg != self.last_error:
                    self.last_error = msg
                    self.error.emit(msg)
                out = DisplayFrame(index, t, bgr_to_qimage(image), None, image, status=f"error: {msg}")
            now = time.perf_counter()
            self._times.append(now)
            if len(self._times) > 1:
                out.fps = (len(self._times) - 1) / max(1e-9, self._times[-1] - self._times[0])
            self.frames_done += 1
            out.dropped_capture = self.inbox.dropped
            out.dropped_display = self.outbox.dropped
            self.outbox.put(out)
            if not self._gui_busy.is_set():
                self._gui_busy.set()
                self.frameReady.emit()

    def _process(self, index: int, t: float, image: np.ndarray) -> DisplayFrame:
        video = bgr_to_qimage(image) if self.render_video else None
        p = self.puppet
        if p is None:
            return DisplayFrame(index, t, video, None, image, status="loading the character" if self.building else "no character")
        pf = p.step(image, index, t)
        if pf is None:  # a puppet running at a lower output rate may skip frames
            return DisplayFrame(index, t, video, None, image, art=self.live_art, status="")
        rgba = getattr(pf, "rgba_pm", None)
        if rgba is None:
            char = None
        elif not getattr(pf, "fresh", True) and self._last_char is not None:  # held picture (lower output rate)
            char = self._last_char
        else:
            char = rgba_pm_to_qimage(rgba)
            self._last_char = char
        params = getattr(pf, "params", None)
        return DisplayFrame(
            index,
            t,
            video,
            char,
            image,
            params=params,
            overlay=getattr(pf, "overlay", None),
            weights=getattr(pf, "weights", None),
            timings_ms=dict(getattr(pf, "timings_ms", {}) or {}),
            art=self.live_art,
            status=str(getattr(params, "status", "")) if params is not None else "",
        )


def _same(a, b) -> bool:
    if isinstance(a, (str, tuple)) or isinstance(b, (str, tuple)):
        return a == b
    return a is b


def _can_tune(puppet) -> bool:
    return puppet is not None and callable(getattr(puppet, "configure", None))


def _tune(puppet, spec: PuppetSpec) -> None:
    """Change rate/filter/gain on a live puppet without rebuilding it."""
    _call_flexibly(puppet.configure, fps=spec.fps, filter=spec.filter, strength=spec.strength, gain=spec.gain)


class Pipeline:
    """Owns the capture and pipeline threads and their two slots; restarts the source on demand."""

    def __init__(self, source: SourceSpec, puppet: PuppetSpec, realtime: bool = True, fake_source=None):
        self.inbox = LatestSlot()
        self.outbox = LatestSlot()
        self.source_spec = source
        self.realtime = realtime
        self._fake = fake_source
        self.capture: CaptureThread | None = None
        self.worker = PipelineThread(self.inbox, self.outbox, puppet)

    def start(self) -> None:
        self.worker.start()
        self._start_capture()

    def _start_capture(self) -> None:
        self.capture = CaptureThread(self.inbox, self.source_spec, self.realtime, source=self._fake)
        self._on_capture(self.capture)
        self.capture.start()

    def _on_capture(self, cap: CaptureThread) -> None:
        """Hook for the window to connect the new capture thread's signals."""

    def set_source(self, spec: SourceSpec, fake_source=None) -> None:
        self.stop_capture()
        self.source_spec = spec
        self._fake = fake_source
        self.inbox.clear()
        self._start_capture()

    def stop_capture(self, wait_ms: int = 3000) -> None:
        if self.capture is not None:
            self.capture.stop()
            self.capture.wait(wait_ms)
            self.capture = None

    def stop(self) -> None:
        self.stop_capture()
        self.worker.stop()
        self.worker.wait(5000)
