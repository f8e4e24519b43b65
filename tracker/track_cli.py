"""``python -m tracker track VIDEO (--init CLICKS.json | --auto) --csv OUT.csv``.

Calibrates on the clicked frame (or on the first frame where the face detectors find a
face), tracks every frame of the video from the start and writes the track CSV of
``shared/DESIGN.md`` (contract columns, then ``time``, ``status``, ``confidence``), one row per
frame, streamed to disk as it goes (the file appears when complete). Outputs are checked before
anything is read: one that is an input (the video, the clicks) is refused, an existing one is
replaced only with ``--force``, and the overlay folder must be new or empty. Expected problems —
a missing or unreadable video, a bad clicks file, a frame index past the end, a refused output —
print one line ``inkface: …`` to stderr and exit with code 2.
"""

from __future__ import annotations

import argparse
import sys
import time as _time
from pathlib import Path

import cv2
import numpy as np

from tracker.auto_init import AutoInitError, auto_start
from tracker.calibration import CalibrationError, calibrate, calibration_hints
from tracker.clicks import Clicks, ClicksError
from tracker.face_tracker import FaceTracker
from tracker.open_eyes import carried_note, carry_clicks
from tracker.outputs import OutputError, calibration_files, check_outputs
from tracker.params import TrackCsvWriter

class TrackCliError(RuntimeError):
    """An expected problem with the command's inputs (one line)."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``track`` command's arguments to ``parser``."""
    parser.add_argument("video", metavar="VIDEO", help="video file to track")
    start = parser.add_mutually_exclusive_group(required=True)
    start.add_argument("--init", metavar="CLICKS.json", help="the five calibration clicks: JSON {\"frame\": N, \"left_pupil\": [x, y], \"right_pupil\": [x, y], \"left_brow\": ..., \"right_brow\": ..., \"mouth\": ...} in pixels of that frame (left = image-left)")
    start.add_argument("--auto", action="store_true", help="find the face with the bundled face detectors")
    parser.add_argument("--csv", metavar="OUT.csv", required=True, help="where to write the track")
    parser.add_argument("--calibration", metavar="CAL.json", help="also save the calibration here (JSON + PNGs)")
    parser.add_argument("--overlay", metavar="DIR", help="write every Nth frame with the tracked features drawn as PNG")
    parser.add_argument("--overlay-every", type=int, default=30, metavar="N", help="overlay frame spacing (default 30)")
    parser.add_argument("--quiet", action="store_true", help="no progress line")
    parser.add_argument("--force", action="store_true",
                        help="replace existing outputs (the video and clicks are never replaced)")


class _Video:
    """Sequential frames of a video file, with one-line errors."""

    def __init__(self, path: Path, threads: int = 0):
        """``threads``: decoder threads (0: the library's choice). One keeps decoding inside
        :meth:`frames`' own calls: with more, the decoder goes on working on later frames in the
        background, on the same core when the process is pinned to one (timed runs)."""
        if not path.exists():
            raise TrackCliError(f"{path}: no such video file")
        if path.is_dir():
            raise TrackCliError(f"{path}: is a folder, not a video file")
        self.path = path
        self.cap = cv2.VideoCapture(str(path), cv2.CAP_ANY, [cv2.CAP_PROP_N_THREADS, threads]) if threads > 0 else None
        if self.cap is None or not self.cap.isOpened():
            self.cap = cv2.VideoCapture(str(path))
        if not self.cap.isOpened():
            raise TrackCliError(f"{path}: cannot open as a video")
        fps = self.cap.get(cv2.CAP_PROP_FPS)
        self.fps = float(fps) if fps and np.isfinite(fps) and fps > 0 else 30.0
        n = self.cap.get(cv2.CAP_PROP_FRAME_COUNT)
        self.count_hint = int(n) if n and np.isfinite(n) and n > 0 else 0

    def frames(self):
        i = 0
        while True:
            ok, img = self.cap.read()
            if not ok or img is None:
                break
            if img.ndim == 2:
                img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
            yield i, img
            i += 1

    def close(self) -> None:
        self.cap.release()


def _clicked(path: Path, clicks: Clicks, where: str) -> tuple[Clicks, np.ndarray]:
    """The clicks and the frame to calibrate on: the clicked frame, or where the clicks carried
    with the head find the eyes open when that frame caught a blink
    (:func:`~tracker.open_eyes.carry_clicks`). Raises :class:`TrackCliError` for a frame past the
    video's end, :class:`~tracker.clicks.ClicksError` for a click outside the frame."""
    v = _Video(path)
    try:
        frames = v.frames()
        n = 0
        for i, img in frames:
            n = i + 1
            if i == clicks.frame:
                h, w = img.shape[:2]
                clicks.check_inside((w, h), where=where)
                return carry_clicks(img, clicks, frames)
        if n == 0:
            raise TrackCliError(f"{path}: no frames could be read")
        raise TrackCliError(f"{path}: calibration frame {clicks.frame} is past the end of the video ({n} frames)")
    finally:
        v.close()


def _auto(path: Path, show: bool = False) -> tuple[Clicks, np.ndarray]:
    """:func:`~tracker.auto_init.auto_start` on the video at ``path``; with ``show``, a progress line
    on stderr once the search has taken a second."""
    v = _Video(path)
    t0 = last = _time.monotonic()

    def progress(i: int) -> None:
        nonlocal last
        now = _time.monotonic()
        if now - last > 1.0 and now - t0 > 1.0:
            total = f" of {v.count_hint}" if v.count_hint else ""
            print(f"\rlooking for a face in {path.name}: frame {i + 1}{total}", end="", file=sys.stderr, flush=True)
            last = now

    try:
        return auto_start(v.frames(), v.fps, progress if show else None)
    except AutoInitError as e:
        raise TrackCliError(f"{path}: {e}") from None
    finally:
        v.close()
        if show and last != t0:
            print(file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    """Run the command; 0 on success, 2 on an expected error (message on stderr)."""
    try:
        return _run(args)
    except (TrackCliError, ClicksError, CalibrationError, AutoInitError, OutputError) as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        name = f"{str(e.filename)[:80]}: " if getattr(e, "filename", None) else ""
        print(f"inkface: {name}{e.strerror or e}", file=sys.stderr)
        return 2


def _calibrate(video: Path, frame: np.ndarray, clicks: Clicks, where: str):
    try:
        return calibrate(frame, clicks)
    except CalibrationError as e:
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        msg = msg[len("calibration: "):] if msg.startswith("calibration: ") else msg
        raise TrackCliError(f"{video}: {msg} ({where}, frame {clicks.frame})") from None


_OVERLAY_NAME = "track_{:06d}.png"


def _run(args: argparse.Namespace) -> int:
    video = Path(args.video)
    csv_out = Path(args.csv)
    check_outputs(
        files=[csv_out] + (calibration_files(args.calibration) if args.calibration else []),
        folders=[args.overlay],
        inputs=[video, args.init],
        force=args.force,
    )
    _Video(video).close()  # a bad video is reported before anything else
    if args.auto:
        clicks, cal_frame = _auto(video, show=not args.quiet)
        where = "found automatically"
    else:
        given = Clicks.load(args.init)
        clicks, cal_frame = _clicked(video, given, str(args.init))
        where = f"clicks {args.init}"
        note = carried_note(given, clicks, where)
        if note and not args.quiet:
            print(f"inkface: note: {note}", file=sys.stderr)
    cal = _calibrate(video, cal_frame, clicks, where)
    if not args.quiet:
        for hint in calibration_hints(cal):
            print(f"inkface: note: {hint} ({where}, frame {clicks.frame})", file=sys.stderr)
    tracker = FaceTracker(cal)
    overlay_dir = Path(args.overlay) if args.overlay else None
    if overlay_dir is not None:
        overlay_dir.mkdir(parents=True, exist_ok=True)
    overlays: set[str] = set()
    v = _Video(video)
    t0 = _time.monotonic()
    last_print = t0
    show = not args.quiet
    n = lost = 0
    try:
        with TrackCsvWriter(csv_out) as out:
            for i, img in v.frames():
                res = tracker.track(img, index=i, time=i / v.fps)
                out.write(res.params)
                n += 1
                lost += res.params.status == "lost"
                if overlay_dir is not None and i % max(args.overlay_every, 1) == 0:
                    name = _OVERLAY_NAME.format(i)
                    cv2.imwrite(str(overlay_dir / name), res.overlay.draw(img))
                    overlays.add(name)
                now = _time.monotonic()
                if show and now - last_print > 1.0:
                    total = f"/{v.count_hint}" if v.count_hint else ""
                    print(f"\rtracking {video.name}: frame {i + 1}{total} ({(i + 1) / (now - t0):.0f} fps)", end="", file=sys.stderr, flush=True)
                    last_print = now
            if n == 0:
                raise TrackCliError(f"{video}: no frames could be read")
    finally:
        v.close()
    if show and last_print != t0:
        print(file=sys.stderr)
    if args.calibration:
        cal.save(args.calibration)
    if overlay_dir is not None:  # frames of an earlier run in the same folder would mislead
        for f in overlay_dir.glob("track_*.png"):
            if f.name not in overlays and f.stem[6:].isdigit() and len(f.stem) == 12:
                f.unlink(missing_ok=True)
    if show:
        print(f"{n} frames tracked ({lost} lost) → {args.csv}", file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> int:
    """Standalone entry: ``python -m tracker.track_cli VIDEO …``."""
    ap = argparse.ArgumentParser(prog="python -m tracker track", description=__doc__.split("\n\n")[0])
    add_arguments(ap)
    return run(ap.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
