"""``python -m app render``: drive a character from a video (or a recorded track) headless.

    python -m app render --video IN --art NAME --out OUT.mp4 [--init CLICKS.json]
        [--training SESSION] [--fps 10|15|30] [--side-by-side] [--params TRACK.csv|.ifs|.fap]
        [--force]

The output kind follows ``--out``: ``.mp4`` / ``.avi`` / ``.mkv`` (mp4v / MJPG / lossless FFV1,
character over a paper background), ``.gif`` (streamed palette GIF over paper) or a folder (no
suffix, or an existing directory) of numbered PNGs with alpha. An existing output is replaced
only with ``--force`` (a PNG folder must otherwise be new or empty; with ``--force`` the frames
of an earlier render in it are replaced and any it had beyond this one removed); an output that
is one of the inputs is always refused. Without ``--init`` the clicks file
``<video stem>.clicks.json`` beside the video is used if present, else the face is found
automatically. ``--params`` takes the ten values from a track file instead of tracking: CSV,
``.ifs`` packet stream or ``.fap`` (``tracker.stream_codec.read_track``; the video, if given,
still provides the calibration and the left half of ``--side-by-side``; without a video the
file's own ipd, neutral face and rate are used when it records them). Prints a progress line;
errors are one line, exit code 2.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

PAPER = (250, 248, 243)  # RGB behind the character where the output has no alpha


class RenderError(Exception):
    """An expected problem with the inputs or the output; the message is one line."""


def add_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    parser.add_argument("--video", metavar="IN", help="input video (the performer)")
    parser.add_argument("--art", metavar="NAME|DIR", required=True, help="character: a bundled name or an art-set folder")
    parser.add_argument("--out", metavar="OUT", required=True, help="output .mp4, .avi, .gif or a folder for PNGs")
    parser.add_argument("--init", metavar="CLICKS.json", help="calibration clicks (default: <video stem>.clicks.json, else automatic)")
    parser.add_argument("--training", metavar="SESSION", help="training session folder (default: automatic default training)")
    parser.add_argument("--fps", type=int, choices=(10, 15, 30), default=30, help="output rate; 10 / 15 average 3 / 2 frames (default 30)")
    parser.add_argument("--side-by-side", action="store_true", help="the performer's frame on the left, the character on the right")
    parser.add_argument("--params", metavar="TRACK", help="take the ten values from this track (CSV, .ifs packet stream or .fap) instead of tracking the video")
    parser.add_argument("--filter", default="gate+one_euro", help="temporal filter: none, one_euro, gate, gate+one_euro, chai (default gate+one_euro)")
    parser.add_argument("--strength", type=float, default=0.5, help="filter strength 0..1 (default 0.5)")
    parser.add_argument("--mapper", default="convex", help="expression mapper: convex (default), delaunay (the paper's), cardinal, ridge")
    parser.add_argument("--gain", type=float, default=1.0, help="head motion gain (0 = still head)")
    parser.add_argument("--overlay", action="store_true", help="draw the tracker's findings on the performer's frame")
    parser.add_argument("--max-frames", type=int, default=0, metavar="N", help="stop after N input frames")
    parser.add_argument("--force", action="store_true",
                        help="replace an existing output (or the frames in a PNG folder); inputs are never replaced")


# ---------------------------------------------------------------------------------- output
def _kind(out: Path) -> str:
    from app.record import RecordError, format_of

    try:
        return format_of(out)
    except RecordError as e:
        raise RenderError(str(e)) from None


# ----------------------------------------------------------------------------------- inputs
class _Video:
    """Frames of a video file, by index (sequential reads)."""

    def __init__(self, path: Path):
        import cv2

        if not path.is_file():
            raise RenderError(f"{path}: no such video")
        self.cap = cv2.VideoCapture(str(path))
        if not self.cap.isOpened():
            raise RenderError(f"{path}: cannot open video")
        fps = self.cap.get(cv2.CAP_PROP_FPS)
        self.fps = float(fps) if fps and np.isfinite(fps) and fps > 0 else 30.0
        self.count = int(self.cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        self.path = path
        self._next = 0

    def read(self) -> np.ndarray | None:
        ok, frame = self.cap.read()
        self._next += 1
        return frame if ok else None

    def frame(self, index: int) -> np.ndarray | None:
        """Frame ``index`` (only forward seeking by reading)."""
        import cv2

        if index < self._next:
            self.cap.set(cv2.CAP_PROP_POS_FRAMES, index)
            self._next = index
        frame = None
        while self._next <= index:
            frame = self.read()
            if frame is None:
                return None
        return frame

    def rewind(self) -> None:
        import cv2

        if self._next:
            self.cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
            self._next = 0

    def close(self) -> None:
        self.cap.release()


def _frames_after(video: _Video, index: int):
    """``(i, frame)`` for the frames after ``index``, read on from where the video stands."""
    i = index + 1
    while (frame := video.frame(i)) is not None:
        yield i, frame
        i += 1


def _calibration(video: _Video, init: str | None, need: bool):
    """Calibration from the clicks (given, beside the video, or automatic); None if not ``need``ed
    and none is available."""
    from tracker.calibration import CalibrationError, calibrate
    from tracker.clicks import Clicks

    clicks_path = Path(init) if init else video.path.with_name(video.path.stem + ".clicks.json")
    if init and not clicks_path.is_file():
        raise RenderError(f"{clicks_path}: no such clicks file")
    if clicks_path.is_file():
        clicks = Clicks.load(clicks_path)
        frame = video.frame(clicks.frame)
        if frame is None:
            raise RenderError(f"{clicks_path}: frame {clicks.frame} is not in {video.path}")
        h, w = frame.shape[:2]
        clicks.check_inside((w, h), where=str(clicks_path))
        from tracker.open_eyes import carried_note, carry_clicks

        given = clicks
        clicks, frame = carry_clicks(frame, given, _frames_after(video, given.frame))  # past a blink, as `track` does
        if note := carried_note(given, clicks, f"clicks {clicks_path}"):
            print(f"inkface: note: {note}", file=sys.stderr)
        try:
            return calibrate(frame, clicks)
        except CalibrationError as e:
            raise RenderError(f"{video.path}: {calibration_message(e)} (clicks {clicks_path}, frame {clicks.frame})") from None
    if video.frame(0) is None:
        raise RenderError(f"{video.path}: the video has no frames")
    try:
        from tracker.auto_init import auto_start
    except ImportError:
        if need:
            raise RenderError(f"{video.path}: no clicks file {clicks_path.name} beside it; pass --init CLICKS.json") from None
        return None
    try:
        video.rewind()
        clicks, frame = auto_start(_frames_after(video, -1), video.fps)  # the first frame with a face, however late
        return calibrate(frame, clicks)
    except Exception as e:
        if need:
            raise RenderError(f"{video.path}: could not find the face automatically ({_one_line(e)}); pass --init CLICKS.json") from None
        return None


def side_by_side(frame_bgr: np.ndarray | None, character_rgb: np.ndarray) -> np.ndarray:
    """The performer's frame (BGR, scaled to the character's height; grey when None), a dark
    gap, then the character (RGB): one RGB picture."""
    import cv2

    ch = character_rgb.shape[0]
    if frame_bgr is None:
        left = np.full((ch, ch * 4 // 3, 3), 40, np.uint8)
    else:
        h, w = frame_bgr.shape[:2]
        left = cv2.resize(frame_bgr, (max(1, round(w * ch / h)), ch), interpolation=cv2.INTER_AREA)[..., ::-1]
    gap = np.full((ch, 8, 3), 30, np.uint8)
    return np.ascontiguousarray(np.concatenate([left, gap, character_rgb], axis=1))


def calibration_message(e: BaseException) -> str:
    """A calibration error's one line without its generic ``calibration:`` lead."""
    msg = _one_line(e)
    return msg[len("calibration: "):] if msg.startswith("calibration: ") else msg


def _one_line(e: BaseException) -> str:
    lines = str(e).strip().splitlines()
    return lines[0] if lines else type(e).__name__


# ------------------------------------------------------------------------------------- run
def render(args, progress=True) -> int:
    """Do the render; returns the number of frames written. Raises RenderError and the core's
    one-line errors for bad input."""
    from app.record import FrameWriter, check_render_output, over_rgb
    from art_sets.io import load_artset
    from art_sets.library import find_artset
    from training.puppet import Puppet

    if not args.video and not args.params:
        raise RenderError("give --video IN (and/or --params TRACK.csv)")
    out = Path(args.out)
    kind = _kind(out)
    art_dir = find_artset(args.art)
    clicks = args.init or (str(Path(args.video).with_name(Path(args.video).stem + ".clicks.json")) if args.video else None)
    check_render_output(out, [args.video, args.params, clicks, args.training, art_dir], overwrite=args.force)
    artset = load_artset(art_dir)
    session = None
    if args.training:
        from training.session import TrainingSession

        session = TrainingSession.load(args.training, artset=artset, autosave=False)

    rows = track = None
    if args.params:
        from tracker.params import track_rate
        from tracker.stream_codec import read_track

        if not Path(args.params).is_file():
            raise RenderError(f"{args.params}: no such track file")
        track = read_track(args.params)
        rows = track.rows
        if not rows:
            raise RenderError(f"{args.params}: the track has no frames")
    video = _Video(Path(args.video)) if args.video else None
    try:
        cal = _calibration(video, args.init, need=rows is None) if video is not None else None
        in_fps = video.fps if video is not None else 30.0
        features = None
        if track is not None and video is None:
            in_fps = float(track.fps) if track.fps else track_rate(rows)
        if cal is None and track is not None and track.ipd and track.neutral is not None:
            from training.features import FeatureSpace

            features = FeatureSpace.from_values(track.ipd, track.neutral)  # the file's own performer
        puppet = Puppet(artset, calibration=cal, session=session, fps=args.fps, filter=args.filter,
                        strength=args.strength, mapper=args.mapper, gain=args.gain, input_fps=in_fps,
                        features=features)
        total = len(rows) if rows is not None else video.count
        if args.max_frames > 0:
            total = min(total, args.max_frames) if total > 0 else args.max_frames
        # no alpha in videos, and a GIF of the character reads best on paper
        writer = FrameWriter(out, args.fps, background=None if kind == "png" else PAPER)
        t0 = time.perf_counter()
        try:
            if video is not None:
                video.rewind()
            i = 0
            while True:
                if args.max_frames > 0 and i >= args.max_frames:
                    break
                frame = video.read() if video is not None else None
                if rows is not None:
                    if i >= len(rows):
                        break
                    pf = puppet.step_params(rows[i])
                else:
                    if frame is None:
                        break
                    pf = puppet.step(frame, i, i / in_fps)
                i += 1
                if pf.fresh and pf.rgba_pm is not None:
                    if args.side_by_side:
                        left = frame
                        if left is not None and args.overlay and pf.overlay is not None and hasattr(pf.overlay, "draw"):
                            left = pf.overlay.draw(left.copy())
                        writer.write_rgb(side_by_side(left, over_rgb(pf.rgba_pm, PAPER)))
                    else:
                        writer.write(pf.rgba_pm)
                if progress and (i % 10 == 0 or i == total):
                    dt = time.perf_counter() - t0
                    of = f"/{total}" if total > 0 else ""
                    print(f"\rrender: frame {i}{of}, {writer.frames} written, {i / max(dt, 1e-9):.0f} frames/s", end="", file=sys.stderr, flush=True)
            if writer.frames == 0:
                raise RenderError("no frames were rendered (is the input empty?)")
        except BaseException:
            writer.abort()
            raise
        writer.close()
        if progress:
            print(file=sys.stderr)
        print(f"wrote {out} ({writer.frames} frames at {args.fps} fps)")
        return writer.frames
    finally:
        if video is not None:
            video.close()


def run(args) -> int:
    from art_sets.io import ArtSetError
    from tracker.clicks import ClicksError
    from tracker.fap import FapError
    from tracker.params import TrackFormatError
    from tracker.stream_codec import StreamError
    from training.session import SessionError

    from app.record import RecordError
    from tracker.outputs import OutputError

    expected = [RenderError, ArtSetError, ClicksError, TrackFormatError, SessionError, StreamError, FapError,
                RecordError, OutputError]
    try:
        from tracker.calibration import CalibrationError

        expected.append(CalibrationError)
    except ImportError:
        pass
    try:
        render(args)
    except tuple(expected) as e:
        print(f"inkface: {_one_line(e)}", file=sys.stderr)
        return 2
    except OSError as e:  # e.g. a name the file system refuses; say which
        name = f"{str(e.filename)[:80]}: " if getattr(e, "filename", None) else ""
        print(f"inkface: {name}{e.strerror or _one_line(e)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ninkface: interrupted", file=sys.stderr)
        return 130
    return 0
