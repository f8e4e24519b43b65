"""Recording the character: MP4, GIF or a PNG sequence with alpha, plus the parameter track.

* :class:`FrameWriter` writes frames to one of the formats (chosen by the file name: ``.mp4`` /
  ``.avi`` / ``.mkv``, ``.gif``, ``.png`` or a folder → numbered PNGs). Every format streams to
  disk as it goes, so memory stays the same however long the recording runs; a video or GIF
  appears under its name only when finished.
* :class:`GifStream` is the GIF encoder behind it: palette frames (a palette is kept while it
  fits the picture), only the changed rectangle of each frame, and centisecond delays that
  alternate so that they average the output rate (30 fps → 3, 4, 3, 3, 4, 3 … cs).
* :class:`Recorder` (used inside the engine process) takes the window's frames and hands them to
  a writer thread through a bounded queue, so encoding never stalls the pipeline. Beside the
  video it writes the parameter track — one CSV row per written frame, numbered and timed on
  the output clock — and the calibration used (so the track can be re-rendered later). It
  never replaces an existing file unless told to; :func:`free_recording_path` proposes a name
  whose files are all free.
* :func:`render_track` re-renders a recorded track with any character (``Puppet.step_params``);
  :func:`render_task` runs it in its own process with progress, and
  :class:`app.rerender_dialog.RerenderDialog` is the window for it.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import queue
import re
import struct
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO, Callable

import numpy as np

from morph.compositor import to_straight
from tracker import atomic_file
from tracker.outputs import OutputError, PendingFile, calibration_files, check_outputs, free_name

RECORD_FILTERS = [
    "MP4 video (*.mp4)",
    "Animated GIF (*.gif)",
    "PNG sequence with alpha (*.png)",
    "AVI video, MJPG (*.avi)",
]

PAPER_WHITE = (250, 248, 243)  # RGB behind transparent characters in formats without alpha

__all__ = [
    "RECORD_FILTERS", "RecordError", "FrameWriter", "GifStream", "Recorder", "RecordResult", "format_of",
    "track_path_for", "recording_files", "recording_conflicts", "free_recording_path", "check_render_output",
    "over_rgb", "to_straight", "render_track", "render_task",
]  # fmt: skip


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


_VIDEO_CODECS = {"mp4": "mp4v", "avi": "MJPG", "mkv": "FFV1"}


def format_of(path: str | os.PathLike) -> str:
    """"mp4", "avi", "mkv" (lossless FFV1), "gif" or "png" from a path (a folder or no suffix
    means a PNG sequence)."""
    p = Path(path)
    ext = p.suffix.lower().lstrip(".")
    if ext in ("mp4", "m4v", "mov"):
        return "mp4"
    if ext in ("avi", "mkv", "gif", "png"):
        return ext
    if not ext or p.is_dir():
        return "png"
    raise RecordError(f"{p}: unknown output format '.{ext}' (use .mp4, .avi, .mkv, .gif or .png)")


def _png_target(path: Path) -> tuple[Path, str]:
    """The folder a PNG sequence goes into and the frames' name stem: ``DIR/frame_00000.png`` for
    a folder, ``NAME/NAME_00000.png`` for ``NAME.png``."""
    if path.suffix.lower() == ".png":
        return path.with_suffix(""), path.stem
    return path, "frame"


def track_path_for(path: str | os.PathLike) -> Path:
    """Where the parameter track goes: ``NAME.csv`` beside ``NAME.mp4`` (inside a PNG folder)."""
    p = Path(path)
    if format_of(p) == "png" and not p.suffix:
        return p / "track.csv"
    return p.with_suffix(".csv")


def recording_files(path: str | os.PathLike, track: bool = True, calibration: bool = True
                    ) -> tuple[list[Path], list[Path]]:
    """What a recording to ``path`` writes: ``(files, folders)`` — the video or GIF (or the PNG
    folder), the track CSV and the calibration (JSON and pictures) beside it."""
    p = Path(path)
    files, folders = [], []
    if format_of(p) == "png":
        folders.append(_png_target(p)[0])
    else:
        files.append(p)
    if track:
        tp = track_path_for(p)
        files.append(tp)
        if calibration:
            files.extend(calibration_files(tp.with_suffix(".calibration.json")))
    return files, folders


def recording_conflicts(path: str | os.PathLike, track: bool = True, calibration: bool = True) -> list[Path]:
    """The existing files (or non-empty PNG folder) a recording to ``path`` would replace."""
    files, folders = recording_files(path, track, calibration)
    out = [f for f in files if f.exists() or f.is_symlink()]
    for d in folders:
        if d.exists() and (not d.is_dir() or next(d.iterdir(), None) is not None):
            out.append(d)
    return out


def free_recording_path(path: str | os.PathLike, track: bool = True, calibration: bool = True) -> Path:
    """``path`` if a recording to it would replace nothing, else the first ``NAME-2.ext``,
    ``NAME-3.ext``, … whose video, track and calibration are all free (``ivy.gif`` after
    ``ivy.mp4``, whose track is ``ivy.csv``, becomes ``ivy-2.gif``)."""
    return free_name(path, lambda c: bool(recording_conflicts(c, track, calibration)))


def check_render_output(out: str | os.PathLike, inputs=(), overwrite: bool = False) -> None:
    """:class:`tracker.outputs.OutputError` when rendering to ``out`` would write over one of the
    ``inputs`` or, unless ``overwrite``, over an existing file (a PNG folder must be new or empty)."""
    p = Path(out)
    kind = format_of(p)
    if kind == "png":
        check_outputs(folders=[_png_target(p)[0]], inputs=inputs, force=overwrite)
    else:
        check_outputs(files=[p], inputs=inputs, force=overwrite)


# ------------------------------------------------------------------------------------------
# GIF


def _gif_blocks(data: bytes, pos: int) -> int:
    """Position after the data sub-blocks starting at ``pos`` (through the 0 terminator)."""
    while True:
        n = data[pos]
        pos += 1 + n
        if n == 0:
            return pos


def _palette_frame(idx: np.ndarray, palette: bytes, transparency: int | None) -> tuple[bytes, bytes]:
    """``(colour_table, image_data)`` of an index image, encoded by Pillow's LZW coder.

    ``image_data`` is the LZW minimum code size and the data sub-blocks of a GIF image, as
    they follow its image descriptor."""
    from PIL import Image

    im = Image.fromarray(np.ascontiguousarray(idx), "P")
    im.putpalette(palette)
    buf = io.BytesIO()
    kw = {"transparency": transparency} if transparency is not None else {}
    im.save(buf, format="GIF", optimize=False, interlace=False, **kw)
    d = buf.getvalue()
    flags = d[10]
    pos = 13
    table = b""
    if flags & 0x80:
        n = 3 << ((flags & 7) + 1)
        table, pos = d[pos : pos + n], pos + n
    while d[pos] == 0x21:  # extensions (Pillow's own graphic control): skip
        pos = _gif_blocks(d, pos + 2)
    if d[pos] != 0x2C:
        raise RecordError("the GIF encoder wrote an unexpected block")
    img_flags = d[pos + 9]
    pos += 10
    if img_flags & 0x80:
        n = 3 << ((img_flags & 7) + 1)
        table, pos = d[pos : pos + n], pos + n
    end = _gif_blocks(d, pos + 1)
    return table, d[pos:end]


class GifStream:
    """An animated GIF written to ``f`` one frame at a time (memory: one frame's worth).

    Frames are RGB (opaque) or straight RGBA (``transparent=True``: alpha < 128 becomes the
    transparent colour). Each frame is mapped to a palette of 255 colours; the palette is kept
    while it still fits the picture (fewer colour jumps, no table per frame) and rebuilt from
    the frame when it does not. Opaque frames store only the rectangle that changed, with the
    unchanged pixels in it transparent; transparent GIFs store whole frames, each cleared
    before the next. Delays are whole centiseconds alternating so they average ``fps``
    (at least 2 cs each: players show faster GIFs slower, so above 50 fps they play slow).
    """

    KEY = 255  # palette index for "transparent" (transparent GIFs) or "unchanged" (opaque ones)
    MISFIT = 12  # a pixel more than this far (per channel) from its palette colour does not fit
    REFIT = 0.002  # rebuild the palette when this fraction of pixels more than at its making misfits

    def __init__(self, f: BinaryIO, fps: float = 30.0, transparent: bool = False):
        if not (math.isfinite(fps) and fps > 0):
            raise RecordError(f"frame rate must be positive, got {fps}")
        self._f = f
        self.fps = float(fps)
        self.transparent = bool(transparent)
        self.frames = 0
        self.palettes = 0  # palettes built so far (1 = one palette for the whole GIF)
        self._size: tuple[int, int] | None = None
        self._palette: bytes = b""  # the current 256-entry table (entry KEY unused by colours)
        self._lut: object = None  # Pillow P image carrying the current palette, for mapping
        self._misfit0 = 0.0
        self._global: bytes = b""
        self._shown: tuple | None = None  # (indices, palette) a player shows after the last frame (opaque)

    def delay_cs(self, i: int) -> int:
        """Delay of frame ``i`` in centiseconds: the rounded output clock's step."""
        a = math.floor(i * 100.0 / self.fps + 0.5)
        b = math.floor((i + 1) * 100.0 / self.fps + 0.5)
        return max(2, b - a)

    def _build_palette(self, rgb: np.ndarray, mask: np.ndarray | None) -> None:
        from PIL import Image

        sample = rgb if mask is None else rgb[mask].reshape(-1, 1, 3)
        if sample.size == 0:
            sample = np.zeros((1, 1, 3), np.uint8)
        q = Image.fromarray(np.ascontiguousarray(sample), "RGB").quantize(
            colors=255, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
        pal = np.zeros((256, 3), np.uint8)
        got = np.asarray(q.getpalette()[: 255 * 3], np.uint8).reshape(-1, 3)
        pal[: len(got)] = got
        pal[len(got) :] = got[-1] if len(got) else 0  # unused entries repeat a real colour
        self._snap_flat_colours(pal, sample)
        self._palette = pal.tobytes()
        lut = Image.new("P", (1, 1))
        lut.putpalette(self._palette)
        self._lut = lut
        self._pal = pal
        self.palettes += 1

    FLAT = 16  # the commonest colours of a frame (paper, fills, ink) get exact palette entries

    def _snap_flat_colours(self, pal: np.ndarray, sample: np.ndarray) -> None:
        """Make the commonest colours exact: the octree averages each into its neighbours, which
        tints large flat areas by a level or two."""
        px = sample.reshape(-1, 3)[:: max(1, sample.size // 3 // 65536)].astype(np.int32)
        packed = (px[:, 0] << 16) | (px[:, 1] << 8) | px[:, 2]
        colours, counts = np.unique(packed, return_counts=True)
        taken = set()
        for c in colours[np.argsort(counts)[::-1][: self.FLAT]]:
            rgb = np.array([(c >> 16) & 255, (c >> 8) & 255, c & 255], np.int32)
            d = np.abs(pal[: self.KEY].astype(np.int32) - rgb).max(axis=1)
            k = int(np.argmin(d))
            if d[k] <= self.MISFIT and k not in taken:
                pal[k] = rgb
                taken.add(k)

    def _map(self, rgb: np.ndarray) -> np.ndarray:
        from PIL import Image

        q = Image.fromarray(rgb, "RGB").quantize(palette=self._lut, dither=Image.Dither.NONE)
        idx = np.asarray(q, np.uint8).copy()
        idx[idx == self.KEY] = self.KEY - 1  # entry KEY repeats entry KEY-1's colour
        return idx

    def _misfit(self, rgb: np.ndarray, idx: np.ndarray, mask: np.ndarray | None) -> float:
        """Fraction of (a grid of every other row and column of) the pixels the palette misses."""
        import cv2

        sub = np.ascontiguousarray(rgb[::2, ::2])
        d = cv2.absdiff(self._pal[idx[::2, ::2]], sub)
        err = np.maximum(np.maximum(d[..., 0], d[..., 1]), d[..., 2]) > self.MISFIT
        if mask is not None:
            m = mask[::2, ::2]
            return float(np.count_nonzero(err & m)) / max(1, int(np.count_nonzero(m)))
        return float(np.count_nonzero(err)) / err.size

    def add(self, image: np.ndarray) -> None:
        """Append one frame: RGB uint8, or straight RGBA uint8 for a transparent GIF."""
        image = np.asarray(image)
        h, w = image.shape[:2]
        if self._size is None:
            if not (0 < w <= 65535 and 0 < h <= 65535):
                raise RecordError(f"a GIF frame must be 1 to 65535 pixels a side, got {w}x{h}")
            self._size = (w, h)
        elif self._size != (w, h):
            raise RecordError(f"GIF frames must all be {self._size[0]}x{self._size[1]}, got {w}x{h}")
        rgb = np.ascontiguousarray(image[..., :3])
        mask = image[..., 3] >= 128 if self.transparent and image.shape[2] == 4 else None
        new_palette = self._lut is None
        if new_palette:
            self._build_palette(rgb, mask)
        idx = self._map(rgb)
        misfit = self._misfit(rgb, idx, mask)
        if not new_palette and misfit > self._misfit0 + self.REFIT:
            self._build_palette(rgb, mask)
            idx = self._map(rgb)
            new_palette = True
            misfit = self._misfit(rgb, idx, mask)
        if new_palette:
            self._misfit0 = misfit
        if self.frames == 0:
            self._header()
        if self.transparent:
            if mask is not None:
                idx[~mask] = self.KEY
            self._frame(idx, 0, 0, disposal=2, transparency=self.KEY)
        else:
            if self._shown is None:
                self._frame(idx, 0, 0, disposal=1, transparency=None)
            else:
                prev_idx, prev_pal = self._shown
                if prev_pal is self._pal:
                    changed = idx != prev_idx
                else:  # a new palette: compare the colours a player shows
                    changed = np.any(self._pal[idx] != prev_pal[prev_idx], axis=2)
                rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
                if len(rows) == 0:  # nothing changed: one see-through pixel keeps the timing
                    self._frame(np.full((1, 1), self.KEY, np.uint8), 0, 0, disposal=1, transparency=self.KEY)
                else:
                    y0, y1, x0, x1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
                    sub = idx[y0:y1, x0:x1].copy()
                    sub[~changed[y0:y1, x0:x1]] = self.KEY
                    self._frame(sub, int(x0), int(y0), disposal=1, transparency=self.KEY)
            self._shown = (idx, self._pal)
        self.frames += 1

    def _header(self) -> None:
        w, h = self._size
        self._global = self._palette
        self._f.write(b"GIF89a" + struct.pack("<HHBBB", w, h, 0xF7, 0, 0) + self._global)
        self._f.write(b"\x21\xff\x0bNETSCAPE2.0\x03\x01\x00\x00\x00")  # loop forever

    def _frame(self, idx: np.ndarray, x: int, y: int, disposal: int, transparency: int | None) -> None:
        table, data = _palette_frame(idx, self._palette, transparency)
        packed = (disposal << 2) | (1 if transparency is not None else 0)
        gce = b"\x21\xf9\x04" + struct.pack("<BHB", packed, self.delay_cs(self.frames), transparency or 0) + b"\x00"
        h, w = idx.shape
        if table == self._global:
            desc = b"\x2c" + struct.pack("<HHHHB", x, y, w, h, 0)
        else:
            size = max(0, (len(table) // 3).bit_length() - 2)
            desc = b"\x2c" + struct.pack("<HHHHB", x, y, w, h, 0x80 | size) + table
        self._f.write(gce + desc + data)

    def close(self) -> None:
        """Write the trailer (the file object stays open)."""
        if self.frames:
            self._f.write(b"\x3b")


# ------------------------------------------------------------------------------------------
# the writer


class FrameWriter:
    """Writes frames to MP4/AVI/MKV, GIF or numbered PNGs with alpha, streaming to disk.

    :meth:`write` takes premultiplied RGBA uint8, :meth:`write_rgb` an opaque RGB picture.
    ``background`` is the RGB colour under the character (None = transparent: PNGs keep
    alpha, GIFs get a transparent colour, videos get paper white). A video or GIF is written
    to a temporary file and moved under its name by :meth:`close`; :meth:`abort` discards it.
    PNG frames go into the folder as they come; :meth:`close` then removes frames of an
    earlier, longer sequence of the same name, so the folder holds exactly this recording.
    """

    def __init__(self, path: str | os.PathLike, fps: float = 30.0, background=None):
        self.path = Path(path)
        self.fps = float(fps)
        self.format = format_of(self.path)
        self.background = _rgb_tuple(background)
        self.frames = 0
        self._pending = None  # tracker.outputs.PendingFile of a video or GIF
        self._video = None
        self._gif: GifStream | None = None
        self._file: BinaryIO | None = None
        self._png_dir: Path | None = None
        self._png_stem = ""
        if not (math.isfinite(self.fps) and self.fps > 0):
            raise RecordError(f"{self.path}: frame rate must be positive, got {fps}")
        if self.format == "png":
            self._png_dir, self._png_stem = _png_target(self.path)
            folder = self._png_dir
        else:
            folder = self.path.parent
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise RecordError(f"{folder}: cannot create the folder ({e.strerror or e})") from None

    def _temp(self) -> Path:
        self._pending = PendingFile(self.path, suffix=self.path.suffix)
        return self._pending.tmp

    def write(self, rgba_pm: np.ndarray) -> None:
        """Append a premultiplied RGBA frame."""
        if self.format == "png":
            self._write(to_straight(rgba_pm) if self.background is None else over_rgb(rgba_pm, self.background))
        elif self.format == "gif" and self.background is None:
            self._write(to_straight(rgba_pm))
        else:
            self._write(over_rgb(rgba_pm, self.background or PAPER_WHITE))

    def write_rgb(self, rgb: np.ndarray) -> None:
        """Append an opaque RGB frame (e.g. a side-by-side picture)."""
        self._write(np.asarray(rgb)[..., :3])

    def _write(self, image: np.ndarray) -> None:
        try:
            if self.format == "png":
                self._write_png(image)
            elif self.format == "gif":
                if self._gif is None:
                    self._file = open(self._temp(), "wb")
                    self._gif = GifStream(self._file, self.fps, transparent=image.shape[2] == 4)
                self._gif.add(image if self._gif.transparent else image[..., :3])
            else:
                self._write_video(image)
        except OSError as e:
            raise RecordError(f"{self.path}: cannot write ({e.strerror or e})") from None
        self.frames += 1

    def _write_png(self, image: np.ndarray) -> None:
        from PIL import Image

        target = self._png_dir / f"{self._png_stem}_{self.frames:05d}.png"
        with atomic_file.replacing(target) as tmp:
            Image.fromarray(np.ascontiguousarray(image)).save(tmp, format="PNG")

    def _write_video(self, rgb: np.ndarray) -> None:
        import cv2

        h, w = rgb.shape[:2]
        if self._video is None:
            fourcc = _VIDEO_CODECS[self.format]
            self._video = cv2.VideoWriter(str(self._temp()), cv2.VideoWriter_fourcc(*fourcc), self.fps, (w, h))
            if not self._video.isOpened():
                self._video = None
                self.abort()
                raise RecordError(f"{self.path}: the {fourcc} video encoder could not be opened")
            self._size = (w, h)
        elif (w, h) != self._size:
            raise RecordError(f"{self.path}: frames must all be {self._size[0]}x{self._size[1]}, got {w}x{h}")
        self._video.write(np.ascontiguousarray(rgb[..., 2::-1]))

    def _release(self) -> None:
        if self._video is not None:
            self._video.release()
            self._video = None
        if self._file is not None:
            if self._gif is not None:
                self._gif.close()
            self._file.close()
            self._file = None

    def close(self) -> Path:
        """Finish the file(s) and move them into place; returns the main output path (the folder
        for a PNG sequence)."""
        try:
            self._release()
            if self._pending is not None:
                self._pending.commit()
        except OSError as e:
            raise RecordError(f"{self.path}: cannot finish writing ({e.strerror or e})") from None
        if self._png_dir is not None:
            self._remove_stale_pngs()
            return self._png_dir
        return self.path

    def abort(self) -> None:
        """Stop and discard an unfinished video or GIF (PNG frames already written stay)."""
        try:
            self._release()
        finally:
            if self._pending is not None:
                self._pending.discard()

    def _remove_stale_pngs(self) -> None:
        pat = re.compile(rf"{re.escape(self._png_stem)}_(\d{{5,}})\.png")
        for f in self._png_dir.glob(f"{self._png_stem}_*.png"):
            m = pat.fullmatch(f.name)
            if m and int(m[1]) >= self.frames:
                f.unlink(missing_ok=True)


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


def _lost_row(index: int, time: float):
    from tracker.params import LOST, PARAM_NAMES, FaceParams

    return FaceParams.from_values([math.nan] * len(PARAM_NAMES), frame=index, time=time, status=LOST, confidence=0.0)


class Recorder:
    """Records the window's frames at ``fps`` on a writer thread, with the parameter track.

    Frames are placed on the output clock by their time stamps, so a 10 fps recording of a
    30 fps source lasts as long as the performance did. The track CSV gets one row per frame
    written (``frame`` = its index in the output, ``time`` = index / fps), so it lines up with
    the video frame for frame. Nothing existing is replaced unless ``overwrite``: otherwise a
    :class:`RecordError` names the file and proposes a free name (:func:`free_recording_path`).

    Progress for a window: :attr:`frames` (written so far), :attr:`accepted` (queued in all),
    :attr:`pending` (queued, not yet written); :meth:`finish` takes ``progress(written, total)``
    while it drains the queue.
    """

    def __init__(self, path: str | os.PathLike, fps: float = 30.0, background=None, track: bool = True,
                 calibration=None, max_queue: int = 240, overwrite: bool = False):
        path = Path(path)
        files, folders = recording_files(path, track, calibration is not None)
        try:
            check_outputs(files=files, folders=folders, force=overwrite, hint="choose another name")
        except OutputError as e:
            hint = ""
            with contextlib.suppress(OutputError, OSError):
                hint = f" (e.g. {free_recording_path(path, track, calibration is not None).name})"
            raise RecordError(f"{e}{hint}") from None
        self.writer = FrameWriter(path, fps, background)  # raises RecordError early
        self.fps = float(fps)
        self.track_path = track_path_for(path) if track else None
        self.calibration = calibration
        self._csv = None  # tracker.params.TrackCsvWriter, opened with the first frame
        self._tracked = False  # a written frame had parameters
        self._q: queue.Queue = queue.Queue(maxsize=max_queue)
        self._lock = threading.Lock()
        self._pending = 0
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
        self._put((img, copies, params), block=False)

    def add_rgba(self, rgba_pm: np.ndarray, params=None) -> None:
        """Queue a premultiplied RGBA frame directly (headless use; waits when the queue is full)."""
        self._put((rgba_pm, 1, params), block=True)

    def _put(self, item, block: bool) -> None:
        with self._lock:
            self._pending += item[1]
        try:
            self._q.put(item, block=block)
            self.accepted += item[1]
        except queue.Full:
            with self._lock:
                self._pending -= item[1]
            self.dropped += item[1]

    def _run(self) -> None:
        while True:
            item = self._q.get()
            if item is None:
                return
            img, copies, params = item
            try:
                for _ in range(copies):
                    if not self.error:
                        self._write(img, params)
            except Exception as e:
                self.error = str(e).splitlines()[0] if str(e) else type(e).__name__
            finally:
                with self._lock:
                    self._pending -= copies

    def _write(self, img: np.ndarray, params) -> None:
        i = self.writer.frames
        self.writer.write(img)
        if self.track_path is None:
            return
        if self._csv is None:
            from tracker.params import TrackCsvWriter

            self._csv = TrackCsvWriter(self.track_path)
        t = i / self.fps
        if params is None:
            row = _lost_row(i, t)
        else:
            row = params.replace(frame=i, time=t)
            self._tracked = True
        self._csv.write(row)

    @property
    def frames(self) -> int:
        """Frames written so far."""
        return self.writer.frames

    @property
    def pending(self) -> int:
        """Frames queued and not written yet (what :meth:`finish` still has to do)."""
        return max(0, self._pending)

    def describe(self) -> str:
        return f"Recording… {self.writer.frames} frames" + (f", {self.dropped} dropped" if self.dropped else "")

    def finish(self, progress: Callable[[int, int], None] | None = None) -> RecordResult:
        """Write what is queued, close the files, and the calibration beside the track.

        ``progress(written, total)`` is called about 20 times a second meanwhile (from the
        calling thread)."""
        self._q.put(None)
        while self._thread.is_alive():
            self._thread.join(0.05)
            if progress is not None:
                progress(self.frames, self.frames + self.pending)
        if self.error:
            self.writer.abort()
            if self._csv is not None:
                self._csv.abort()
            raise RecordError(f"{self.writer.path}: {self.error}")
        if self.writer.frames == 0:  # Stop before the first frame: say so rather than name a file that is not there
            self.writer.abort()
            if self._csv is not None:
                self._csv.abort()
            raise RecordError(f"{self.writer.path}: no frames arrived before Stop, so nothing was written")
        out = self.writer.close()
        track = None
        extra: list[Path] = []
        if self._csv is not None:
            if self._tracked:
                track = self._csv.close()
            else:
                self._csv.abort()
        if track is not None and self.calibration is not None and hasattr(self.calibration, "save"):
            cp = track.with_suffix(".calibration.json")
            try:
                self.calibration.save(cp)
                extra.append(cp)
            except Exception:  # the track is still usable without it (re-render calibrates itself)
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
    overwrite: bool = False,
) -> RecordResult:
    """Render a parameter track CSV with the character at ``art`` into ``out`` (any format).

    Uses ``NAME.calibration.json`` beside the track when present (a recording writes it), so
    the values are read relative to the same performer's neutral face. ``out`` may not be one
    of the inputs; an existing ``out`` is replaced only with ``overwrite``.
    """
    from tracker.params import read_csv, track_rate
    from training.puppet import Puppet

    from app.workers import load_artset

    cp = Path(track_csv).with_suffix(".calibration.json")
    try:
        check_render_output(out, [track_csv, art, *calibration_files(cp)], overwrite)
    except OutputError as e:
        raise RecordError(str(e)) from None
    rows = read_csv(track_csv)
    if not rows:
        raise RecordError(f"{track_csv}: the track has no frames")
    if calibration is None and cp.is_file():
        from tracker.calibration import Calibration

        calibration = Calibration.load(cp)
    artset = load_artset(art)
    # the track's own rate (a recording's is its output rate), so the render lasts as long
    puppet = Puppet(artset, calibration=calibration, fps=int(fps), filter="one_euro", input_fps=track_rate(rows))
    writer = FrameWriter(out, fps, background)
    n = len(rows)
    try:
        for i, fp in enumerate(rows):
            if cancelled is not None and cancelled():
                break
            pf = puppet.step_params(fp)
            if pf.fresh and pf.rgba_pm is not None:
                writer.write(pf.rgba_pm)
            if progress is not None:
                progress(i + 1, n)
    except BaseException:
        writer.abort()
        raise
    path = writer.close()
    return RecordResult(path, None, writer.frames)


def render_track_task(report, cancelled, track_csv, art, out, fps=30.0, background=None,
                      overwrite=False) -> RecordResult:
    """(Task process) :func:`render_track` reporting ``progress(i, n)``."""
    return render_track(track_csv, art, out, fps, background, progress=lambda i, n: report("progress", i, n),
                        cancelled=cancelled, overwrite=overwrite)


def render_task(track_csv, art, out, fps: float = 30.0, background=None, overwrite: bool = False):
    """A started-on-demand :class:`app.workers.ProcessTask` re-rendering a track (see
    :func:`render_track`): hooks ``progress(i, n)``, ``done(RecordResult)``, ``failed(msg)``."""
    from app.workers import ProcessTask

    return ProcessTask("app.record:render_track_task", str(track_csv), str(art), str(out), float(fps),
                       _rgb_tuple(background), bool(overwrite))


def __getattr__(name: str):
    if name == "RerenderDialog":  # the Qt window, loaded only when asked for
        from app.rerender_dialog import RerenderDialog

        return RerenderDialog
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
