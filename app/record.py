"""Recording the character: MP4, GIF or a PNG sequence with alpha, plus the parameter track.

* :class:`FrameWriter` writes premultiplied RGBA frames to one of the three formats (chosen
  by the file name: ``.mp4``/``.avi``, ``.gif``, ``.png`` or a folder → numbered PNGs).
* :class:`Recorder` (used inside the engine process) takes the frames and hands them to a
  writer thread through a bounded queue, so encoding never stalls the pipeline. It also keeps every
  frame's :class:`FaceParams` and writes them as a track CSV beside the video, with the
  calibration used (so the track can be re-rendered later).
* :func:`render_track` re-renders a recorded track with any character (``Puppet.step_params``);
  :func:`render_task` runs it in its own process with progress, and :class:`RerenderDialog`
  is the window for it.
"""

from __future__ import annotations

import os
import queue
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from tracker import atomic_file

RECORD_FILTERS = [
    "MP4 video (*.mp4)",
    "Animated GIF (*.gif)",
    "PNG sequence with alpha (*.png)",
    "AVI video, MJPG (*.avi)",
]

PAPER_WHITE = (250, 248, 243)  # RGB behind transparent characters in formats without alpha


class RecordError(ValueError):
    """A recording could not be started or written; the message names the file."""


def _rgb_tuple(bg) -> tuple[int, int, int] | None:
    """A QColor, '#rrggbb' or (r, g, b) as an RGB tuple; None stays None (transparent)."""
    if bg is None:
        return None
    if hasattr(bg, "red"):
        return (bg.red(), bg.green(), bg.blue())
    if isinstance(bg, str):
        s = bg.lstrip("#")
        return (int(s[0:2], 16), int(s[2:4], 16), int(s[4:6], 16))
    r, g, b = bg[:3]
    return (int(r), int(g), int(b))


def over_rgb(rgba_pm: np.ndarray, rgb: tuple[int, int, int]) -> np.ndarray:
    """Premultiplied RGBA over a flat colour → RGB uint8."""
    a = rgba_pm[..., 3:4].astype(np.uint16)
    bg = np.asarray(rgb, np.uint16)
    out = rgba_pm[..., :3].astype(np.uint16) + (bg * (255 - a) + 127) // 255
    return np.minimum(out, 255).astype(np.uint8)


def to_straight(rgba_pm: np.ndarray) -> np.ndarray:
    """Premultiplied → straight RGBA uint8 (as PNG stores it)."""
    a = rgba_pm[..., 3:4].astype(np.float32)
    rgb = np.where(a > 0, rgba_pm[..., :3].astype(np.float32) * 255.0 / np.maximum(a, 1), 0)
    return np.concatenate([np.clip(rgb + 0.5, 0, 255).astype(np.uint8), rgba_pm[..., 3:4]], axis=2)


def format_of(path: str | os.PathLike) -> str:
    """"mp4", "avi", "gif" or "png" from a path (a folder or no suffix means a PNG sequence)."""
    p = Path(path)
    ext = p.suffix.lower().lstrip(".")
    if ext in ("mp4", "m4v", "mov"):
        return "mp4"
    if ext in ("avi", "gif", "png"):
        return ext
    if not ext or p.is_dir():
        return "png"
    raise RecordError(f"{p}: unknown output format '.{ext}' (use .mp4, .avi, .gif or .png)")


def track_path_for(path: str | os.PathLike) -> Path:
    """Where the parameter track goes: ``NAME.csv`` beside ``NAME.mp4`` (inside a PNG folder)."""
    p = Path(path)
    if format_of(p) == "png" and not p.suffix:
        return p / "track.csv"
    return p.with_suffix(".csv")


class FrameWriter:
    """Writes premultiplied RGBA uint8 frames to MP4/AVI, GIF or numbered PNGs with alpha.

    ``background`` is the RGB colour under the character for formats without alpha (None =
    transparent: PNGs keep alpha, GIFs get a transparent colour key, videos get paper white).
    """

    def __init__(self, path: str | os.PathLike, fps: float = 30.0, background=None):
        self.path = Path(path)
        self.fps = float(fps)
        self.format = format_of(self.path)
        self.background = _rgb_tuple(background)
        self.frames = 0
        self._video = None
        self._gif: list = []
        self._png_dir: Path | None = None
        parent = self.path if (self.format == "png" and not self.path.suffix) else self.path.parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise RecordError(f"{parent}: cannot create the folder ({e.strerror or e})") from e
        if self.format == "png":
            self._png_dir = self.path if not self.path.suffix else self.path.with_suffix("")
            self._png_dir.mkdir(parents=True, exist_ok=True)
            self._png_stem = "frame" if not self.path.suffix else self.path.stem

    def write(self, rgba_pm: np.ndarray) -> None:
        if self.format in ("mp4", "avi"):
            import cv2

            rgb = over_rgb(rgba_pm, self.background or PAPER_WHITE)
            if self._video is None:
                h, w = rgb.shape[:2]
                fourcc = cv2.VideoWriter_fourcc(*("mp4v" if self.format == "mp4" else "MJPG"))
                self._tmp = self.path.with_name(f".{self.path.stem}.part{self.path.suffix}")
                self._video = cv2.VideoWriter(str(self._tmp), fourcc, self.fps, (w, h))
                if not self._video.isOpened():
                    raise RecordError(f"{self.path}: the video encoder could not be opened")
                self._size = (w, h)
            self._video.write(np.ascontiguousarray(rgb[..., ::-1]))
        elif self.format == "gif":
            from PIL import Image

            if self.background is None:
                st = to_straight(rgba_pm)
                im = Image.fromarray(st, "RGBA")
            else:
                im = Image.fromarray(over_rgb(rgba_pm, self.background), "RGB")
            self._gif.append(im)
        else:
            from PIL import Image

            assert self._png_dir is not None
            target = self._png_dir / f"{self._png_stem}-{self.frames:05d}.png"
            im = Image.fromarray(to_straight(rgba_pm) if self.background is None else over_rgb(rgba_pm, self.background))
            _atomic_save(im, target)
        self.frames += 1

    def close(self) -> Path:
        """Finish the file(s); returns the main output path."""
        if self._video is not None:
            self._video.release()
            self._video = None
            os.replace(self._tmp, self.path)
        elif self.format == "gif" and self._gif:
            first, rest = self._gif[0], self._gif[1:]
            kwargs = dict(save_all=True, append_images=rest, duration=max(20, int(round(1000 / self.fps))), loop=0,
                          disposal=2)
            if self.background is None:
                kwargs["transparency"] = 0
            ims = [_gif_frame(im) for im in [first] + rest] if self.background is None else [first] + rest
            kwargs["append_images"] = ims[1:]
            with atomic_file.replacing(self.path) as tmp:
                ims[0].save(tmp, format="GIF", **kwargs)
            self._gif = []
        return self._png_dir if self._png_dir is not None else self.path


def _gif_frame(im):
    """An RGBA image as a palette image whose index 0 is transparent (alpha < 128)."""
    from PIL import Image

    alpha = np.asarray(im.getchannel("A"))
    rgb = im.convert("RGB").quantize(colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    idx = np.asarray(rgb, dtype=np.uint8) + 1
    idx[alpha < 128] = 0
    pal = rgb.getpalette()[: 255 * 3]
    out = Image.fromarray(idx.astype(np.uint8), "P")
    out.putpalette([0, 0, 0] + pal + [0] * (768 - 3 - len(pal)))
    out.info["transparency"] = 0
    return out


def _atomic_save(im, target: Path) -> None:
    with atomic_file.replacing(target) as tmp:
        im.save(tmp, format="PNG")


@dataclass
class RecordResult:
    """What a recording produced."""

    output: Path
    track: Path | None
    frames: int
    dropped: int = 0
    extra: list[Path] = field(default_factory=list)

    def describe(self) -> str:
        s = f"Saved {self.frames} frames to {self.output}"
        if self.track is not None:
            s += f" and the track to {self.track.name}"
        if self.dropped:
            s += f" ({self.dropped} dropped: the disk could not keep up)"
        return s


class Recorder:
    """Records the window's frames at ``fps`` on a writer thread; keeps the parameter track.

    Frames are placed on the output clock by their time stamps, so a 10 fps recording of a
    30 fps source lasts as long as the performance did.
    """

    def __init__(self, path: str | os.PathLike, fps: float = 30.0, background=None, track: bool = True,
                 calibration=None, max_queue: int = 240):
        self.writer = FrameWriter(path, fps, background)  # raises RecordError early
        self.fps = float(fps)
        self.track_path = track_path_for(path) if track else None
        self.params: list = []
        self.calibration = calibration
        self._q: queue.Queue = queue.Queue(maxsize=max_queue)
        self._next_t: float | None = None
        self._last_t: float | None = None
        self.dropped = 0
        self.accepted = 0  # frames queued for the writer (``frames`` of them are written so far)
        self.error: str = ""
        self._thread = threading.Thread(target=self._run, name="inkface-recorder", daemon=True)
        self._thread.start()

    def add(self, frame, background=None) -> None:
        """Queue one window frame (a :class:`app.workers.DisplayFrame`)."""
        img = getattr(frame, "rgba", None)  # premultiplied RGBA array (no Qt object crosses threads)
        if img is None:
            return
        params = getattr(frame, "params", None)
        if params is not None and (not self.params or self.params[-1] is not params):
            self.params.append(params)
        t = float(getattr(frame, "time", 0.0))
        if self._last_t is not None and t < self._last_t:  # source looped: keep the clock running
            self._next_t = None
        self._last_t = t
        if self._next_t is None:
            self._next_t = t
        if t - self._next_t > 1.0:  # a jump in the source's clock: resynchronise, do not fill the gap
            self._next_t = t
        copies = 0
        while self._next_t <= t + 1e-6:
            copies += 1
            self._next_t += 1.0 / self.fps
        if copies == 0:
            return
        try:
            self._q.put_nowait((img, copies))
            self.accepted += copies
        except queue.Full:
            self.dropped += copies

    def add_rgba(self, rgba_pm: np.ndarray, params=None) -> None:
        """Queue a premultiplied RGBA frame directly (headless use)."""
        if params is not None:
            self.params.append(params)
        self._q.put((rgba_pm, 1))
        self.accepted += 1

    def _run(self) -> None:
        while True:
            item = self._q.get()
            if item is None:
                return
            img, copies = item
            try:
                for _ in range(copies):
                    self.writer.write(img)
            except Exception as e:
                self.error = str(e).splitlines()[0] if str(e) else type(e).__name__

    @property
    def frames(self) -> int:
        return self.writer.frames

    def describe(self) -> str:
        return f"Recording… {self.writer.frames} frames" + (f", {self.dropped} dropped" if self.dropped else "")

    def finish(self) -> RecordResult:
        """Flush the queue, close the files, write the track CSV (and calibration) beside them."""
        self._q.put(None)
        self._thread.join()
        if self.error:
            raise RecordError(f"{self.writer.path}: {self.error}")
        out = self.writer.close()
        track = None
        extra: list[Path] = []
        if self.track_path is not None and self.params:
            from tracker.params import write_csv

            write_csv(self.track_path, self.params)
            track = self.track_path
            if self.calibration is not None and hasattr(self.calibration, "save"):
                cp = self.track_path.with_suffix(".calibration.json")
                try:
                    self.calibration.save(cp)
                    extra.append(cp)
                except Exception:
                    pass
        return RecordResult(out, track, self.writer.frames, self.dropped, extra)


# ------------------------------------------------------------------------------------------
# re-rendering a recorded track


def render_track(
    track_csv: str | os.PathLike,
    art: str | os.PathLike,
    out: str | os.PathLike,
    fps: float = 30.0,
    background=None,
    calibration=None,
    progress: Callable[[int, int], None] | None = None,
    cancelled: Callable[[], bool] | None = None,
) -> RecordResult:
    """Render a parameter track CSV with the character at ``art`` into ``out`` (any format).

    Uses ``NAME.calibration.json`` beside the track when present (a recording writes it), so
    the values are read relative to the same performer's neutral face.
    """
    from tracker.params import read_csv

    from app.workers import PuppetSpec, load_artset, make_puppet

    rows = read_csv(track_csv)
    if not rows:
        raise RecordError(f"{track_csv}: the track has no frames")
    if calibration is None:
        cp = Path(track_csv).with_suffix(".calibration.json")
        if cp.is_file():
            from tracker.calibration import Calibration

            calibration = Calibration.load(cp)
    artset = load_artset(art)
    puppet = make_puppet(artset, PuppetSpec(art=str(art), fps=int(fps), calibration=calibration))
    writer = FrameWriter(out, fps, background)
    n = len(rows)
    for i, fp in enumerate(rows):
        if cancelled is not None and cancelled():
            break
        pf = puppet.step_params(fp)
        if pf is not None and getattr(pf, "rgba_pm", None) is not None:
            writer.write(pf.rgba_pm)
        if progress is not None:
            progress(i + 1, n)
    path = writer.close()
    return RecordResult(path, None, writer.frames)


# Qt parts are defined lazily so that FrameWriter / render_track import without a display.
try:
    from PySide6.QtWidgets import (
        QComboBox,
        QDialog,
        QDialogButtonBox,
        QFileDialog,
        QFormLayout,
        QHBoxLayout,
        QLabel,
        QLineEdit,
        QProgressBar,
        QPushButton,
        QVBoxLayout,
    )
except ImportError:  # pragma: no cover - PySide6 is a dependency of app/
    QDialog = object  # type: ignore


def render_track_task(report, cancelled, track_csv, art, out, fps=30.0, background=None) -> RecordResult:
    """(Task process) :func:`render_track` reporting ``progress(i, n)``."""
    return render_track(track_csv, art, out, fps, background, progress=lambda i, n: report("progress", i, n),
                        cancelled=cancelled)


def render_task(track_csv, art, out, fps: float = 30.0, background=None):
    """A started-on-demand :class:`app.workers.ProcessTask` re-rendering a track (see
    :func:`render_track`): hooks ``progress(i, n)``, ``done(RecordResult)``, ``failed(msg)``."""
    from app.workers import ProcessTask

    return ProcessTask("app.record:render_track_task", str(track_csv), str(art), str(out), float(fps),
                       _rgb_tuple(background))


class RerenderDialog(QDialog):
    """Pick a recorded track, a character (``characters``: (name, folder) pairs) and an output;
    render with a progress bar."""

    def __init__(self, characters: list[tuple[str, str]], background=None, fps: int = 30, parent=None, track: str = ""):
        super().__init__(parent)
        self.setWindowTitle("Re-render a track with another character")
        self.setMinimumWidth(520)
        self.background = background
        self.thread = None  # app.workers.ProcessTask while rendering
        self.result_: RecordResult | None = None
        v = QVBoxLayout(self)
        v.setContentsMargins(18, 18, 18, 18)
        v.setSpacing(12)
        f = QFormLayout()
        self.track_edit = QLineEdit(track)
        b = QPushButton("…")
        b.clicked.connect(self._pick_track)
        row = QHBoxLayout()
        row.addWidget(self.track_edit, 1)
        row.addWidget(b)
        f.addRow("Track (CSV)", row)
        self.art_combo = QComboBox()
        for name, p in characters:
            self.art_combo.addItem(name, p)
        f.addRow("Character", self.art_combo)
        self.out_edit = QLineEdit("")
        b = QPushButton("…")
        b.clicked.connect(self._pick_out)
        row = QHBoxLayout()
        row.addWidget(self.out_edit, 1)
        row.addWidget(b)
        f.addRow("Output", row)
        self.fps_combo = QComboBox()
        for r in (10, 15, 30):
            self.fps_combo.addItem(f"{r} fps", r)
        self.fps_combo.setCurrentIndex(max(0, self.fps_combo.findData(fps)))
        f.addRow("Rate", self.fps_combo)
        v.addLayout(f)
        self.bar = QProgressBar()
        self.bar.setRange(0, 100)
        self.bar.setValue(0)
        v.addWidget(self.bar)
        self.msg = QLabel("")
        self.msg.setObjectName("hint")
        self.msg.setWordWrap(True)
        v.addWidget(self.msg)
        self.buttons = QDialogButtonBox()
        self.start_btn = self.buttons.addButton("Render", QDialogButtonBox.ButtonRole.AcceptRole)
        self.start_btn.setObjectName("primary")
        self.close_btn = self.buttons.addButton("Close", QDialogButtonBox.ButtonRole.RejectRole)
        self.start_btn.clicked.connect(self.start)
        self.close_btn.clicked.connect(self._close_or_cancel)
        v.addWidget(self.buttons)

    def _pick_track(self) -> None:
        p, _ = QFileDialog.getOpenFileName(self, "A recorded parameter track", "", "Tracks (*.csv)")
        if p:
            self.track_edit.setText(p)
            if not self.out_edit.text():
                self.out_edit.setText(str(Path(p).with_name(Path(p).stem + "-rerender.mp4")))

    def _pick_out(self) -> None:
        p, _ = QFileDialog.getSaveFileName(self, "Render to…", self.out_edit.text(), ";;".join(RECORD_FILTERS))
        if p:
            self.out_edit.setText(p)

    def start(self) -> None:
        track, out = self.track_edit.text().strip(), self.out_edit.text().strip()
        if not track or not out:
            self.msg.setText("Choose a track and an output file first.")
            return
        self.start_btn.setEnabled(False)
        self.close_btn.setText("Cancel")
        self.msg.setText("Rendering…")
        self.thread = render_task(track, self.art_combo.currentData(), out, self.fps_combo.currentData(),
                                  self.background)
        self.thread.progress.connect(self._on_progress)
        self.thread.done.connect(self._on_done)
        self.thread.failed.connect(self._on_failed)
        self.thread.start()

    def _on_progress(self, i: int, n: int) -> None:
        self.bar.setRange(0, n)
        self.bar.setValue(i)

    def _on_done(self, res: RecordResult) -> None:
        self.result_ = res
        self.msg.setText(res.describe())
        self._finish()

    def _on_failed(self, msg: str) -> None:
        self.msg.setText(f"Could not render: {msg}")
        self._finish()

    def _finish(self) -> None:
        self.start_btn.setEnabled(True)
        self.close_btn.setText("Close")

    def _close_or_cancel(self) -> None:
        if self.thread is not None and self.thread.isRunning():
            self.thread.cancel()
            return
        self.close()

    def closeEvent(self, ev) -> None:
        if self.thread is not None and self.thread.isRunning():
            self.thread.cancel()
            self.thread.wait(5000)
        super().closeEvent(ev)
