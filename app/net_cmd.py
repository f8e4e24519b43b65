"""``python -m app send`` and ``python -m app receive``: the teleconference split on the command line.

send
    ``send --to HOST:PORT [--camera N | --video FILE | --params TRACK] [--init CLICKS.json | --auto]
    [--compress]`` tracks a camera or a video (calibrated from the clicks — for a video,
    ``<video>.clicks.json`` beside it is used when no ``--init`` is given — or found
    automatically) and sends each frame's ten bytes over UDP, paced in real time. ``--params``
    replays a recorded track instead: a CSV track (give ``--ipd``, ``--init`` or let the mouth
    width estimate it), a packet-stream file (``.ifs``) or an MPEG-4 FAP file (``.fap``).
    ``--record OUT.ifs`` also keeps what was sent.

receive
    ``receive --port PORT [--art NAME] [--training SESSION] [--bind ADDR] [--out OUT.mp4 | --frames N]``
    listens on 127.0.0.1 (``--bind`` to change). With ``--art``/``--out``/``--training`` it draws
    every received frame with the character (``training.puppet``) into ``--out`` (MP4 / GIF /
    PNGs); while packets are late or have stopped it keeps the sender's frame rate, drawing the
    held pose and then the ease to neutral. Without them it only counts. The received track can
    be kept (``--csv``, ``--record OUT.ifs``, ``--fap``); every output is written as the frames
    arrive, and nothing is kept in memory per frame, so a session can run for hours. It stops after ``--frames`` frames,
    after ``--timeout`` seconds without packets once the stream started, or on Ctrl-C, and
    prints the link statistics (loss, reordering, drops, bits per frame, bit rate).

Received frames are numbered by the packets' sequence numbers, timed by their timestamps.
Existing output files are replaced only with ``--force``; inputs never. Expected errors print
one line, ``inkface: <message>``, and exit with code 2.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from app.net import Sender, UdpReceiver, check_port, parse_address
from tracker.outputs import check_outputs
from tracker.params import LOST, OK, FaceParams, params_array, track_rate

_MOUTH_PER_IPD = 0.8  # typical adult proportion, used only when a CSV track comes without its ipd


class _Fail(Exception):
    """An expected failure with a one-line message."""


def add_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    if command == "send":
        parser.add_argument("--to", required=True, metavar="HOST:PORT", help="where to send (e.g. 127.0.0.1:9000)")
        src = parser.add_mutually_exclusive_group()
        src.add_argument("--camera", type=int, metavar="N", help="camera index (the default source: camera 0)")
        src.add_argument("--video", metavar="FILE", help="track a video file")
        src.add_argument("--params", metavar="TRACK", help="replay a track: CSV, packet stream (.ifs) or FAP (.fap)")
        init = parser.add_mutually_exclusive_group()
        init.add_argument("--init", metavar="CLICKS.json", help="calibration clicks: JSON {\"frame\": N, \"left_pupil\": [x, y], \"right_pupil\": [x, y], \"left_brow\": ..., \"right_brow\": ..., \"mouth\": ...} in pixels of that frame (left = image-left)")
        init.add_argument("--auto", action="store_true", help="find the face automatically")
        parser.add_argument("--compress", action="store_true", help="lossless temporal compression (about 30-40 instead of 80 bits a frame)")
        parser.add_argument("--key-interval", type=int, default=30, metavar="N",
                            help="with --compress: a key frame every N frames (default 30)")
        parser.add_argument("--fps", type=float, metavar="F", help="send rate (default: the source's)")
        parser.add_argument("--ipd", type=float, metavar="PX", help="inter-pupil distance of a CSV track (pixels)")
        parser.add_argument("--frame-size", metavar="WxH", help="frame size of a CSV track (default: the smallest common size holding its positions)")
        parser.add_argument("--frames", type=int, metavar="N", help="stop after N frames")
        parser.add_argument("--record", metavar="OUT.ifs", help="also write what was sent as a packet-stream file")
        parser.add_argument("--simulate-loss", type=float, default=0.0, metavar="P",
                            help="drop this fraction of frame packets at random (to try a lossy link)")
        parser.add_argument("--quiet", action="store_true", help="no progress line")
        parser.add_argument("--force", action="store_true", help="replace --record's file if it exists")
    else:
        parser.add_argument("--port", required=True, metavar="PORT", help="UDP port to listen on")
        parser.add_argument("--bind", default="127.0.0.1", metavar="ADDR",
                            help="address to listen on (default 127.0.0.1; 0.0.0.0 for all)")
        parser.add_argument("--art", metavar="NAME|DIR", help="the character (default: the first bundled one)")
        parser.add_argument("--training", metavar="SESSION", help="a saved training session for the character")
        parser.add_argument("--out", metavar="OUT.mp4", help="draw the character into a video / GIF / PNGs")
        parser.add_argument("--frames", type=int, metavar="N", help="stop after N received frames")
        parser.add_argument("--fps", type=int, choices=(10, 15, 30), default=30, help="drawing rate (default 30)")
        parser.add_argument("--timeout", type=float, default=5.0, metavar="S",
                            help="stop after S seconds without packets once the stream started (default 5; 0 = never)")
        parser.add_argument("--wait", type=float, default=0.0, metavar="S",
                            help="give up if nothing arrives within S seconds (default 0 = wait forever)")
        parser.add_argument("--csv", metavar="OUT.csv", help="write the received track as CSV")
        parser.add_argument("--record", metavar="OUT.ifs", help="write the received track as a packet-stream file")
        parser.add_argument("--fap", metavar="OUT.fap", help="write the received track as MPEG-4 FAPs")
        parser.add_argument("--quiet", action="store_true", help="no progress line")
        parser.add_argument("--force", action="store_true", help="replace existing output files")


def run(args) -> int:
    try:
        return _send(args) if args.command == "send" else _receive(args)
    except KeyboardInterrupt:
        return 130
    except _Fail as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    except Exception as e:  # the project's one-line errors (track, stream, FAP, clicks, art set, ...)
        if not _expected(e):
            raise
        msg = str(e).strip().splitlines()
        print(f"inkface: {msg[0] if msg else type(e).__name__}", file=sys.stderr)
        return 2


def _expected(e: Exception) -> bool:
    """Errors that carry a user-facing one-line message: the project's own error classes
    (TrackFormatError, StreamError, FapError, ClicksError, SourceError, ArtSetError, ...) and OS errors."""
    return isinstance(e, OSError) or type(e).__module__.split(".")[0] in ("tracker", "art_sets", "training", "morph", "app")


# ---------------------------------------------------------------------------------------------
# send


@dataclass
class _Track:
    rows: list[FaceParams]
    frame_size: tuple[int, int]
    ipd: float
    fps: float
    neutral: FaceParams | None


def _frame_size(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise _Fail(f"frame size {text!r} must be WxH, e.g. 640x480") from None
    if w <= 0 or h <= 0:
        raise _Fail(f"frame size {text!r} must be positive")
    return w, h


_COMMON_SIZES = ((640, 480), (1280, 720), (1920, 1080), (2560, 1440), (3840, 2160))


def _covering_size(rows: list[FaceParams]) -> tuple[int, int]:
    """The smallest common frame size that holds every face position of a track without a size."""
    xy = params_array(rows)[:, :2]
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    mx, my = (xy.max(axis=0) if len(xy) else (0.0, 0.0))
    for w, h in _COMMON_SIZES:
        if mx < w and my < h:
            return w, h
    return max(int(mx) + 1, 640), max(int(my) + 1, 480)


def _load_track(args) -> _Track:
    from tracker.stream_codec import read_track

    path = Path(args.params)
    tf = read_track(path)
    rows = tf.rows
    if not rows:
        raise _Fail(f"{path}: the track has no frames")
    size = tf.frame_size or _frame_size(args.frame_size) or _covering_size(rows)
    fps = tf.fps or track_rate(rows)
    neutral = tf.neutral
    if neutral is None:  # a CSV: the median of the tracked frames stands in for the neutral face
        vals = params_array(r for r in rows if r.status != LOST)
        if len(vals) == 0:
            vals = params_array(rows)
        neutral = FaceParams.from_values(np.nanmedian(vals, axis=0), status=OK)
    ipd = args.ipd or tf.ipd
    if ipd is None and args.init:
        from tracker.clicks import Clicks

        c = Clicks.load(args.init)
        ipd = float(math.dist(c.left_pupil, c.right_pupil))
    if ipd is None:
        ipd = neutral.mouth_width / _MOUTH_PER_IPD
        if not args.quiet:
            print(f"inkface: {path.name} has no ipd; assuming {ipd:.1f} px from the mouth width (use --ipd)", file=sys.stderr)
    if not (math.isfinite(ipd) and ipd > 0):
        raise _Fail(f"{path}: cannot tell the inter-pupil distance; pass --ipd PX")
    return _Track(rows, size, float(ipd), fps, neutral)


def _tracked_frames(args):
    """Yield ``(frame_size, ipd, neutral, fps)`` once, then FaceParams for every tracked frame."""
    try:
        from tracker.calibration import CalibrationError, calibrate
        from tracker.face_tracker import FaceTracker
    except ImportError as e:
        raise _Fail(f"the tracker is not available in this build ({e}); replay a track with --params") from None

    def open_source():
        from tracker.sources import CameraSource, VideoFileSource

        return VideoFileSource(args.video) if args.video else CameraSource(args.camera or 0)

    if args.init:
        from tracker.clicks import Clicks

        clicks = Clicks.load(args.init)
    elif args.auto or not args.video:
        clicks = None
    else:
        guess = Path(args.video).with_suffix(".clicks.json")
        if not guess.exists():
            raise _Fail(f"{args.video}: no --init CLICKS.json given and no {guess.name} beside it (or use --auto)")
        from tracker.clicks import Clicks

        clicks = Clicks.load(guess)
    src = open_source()
    try:
        it = iter(src)
        where = args.video or "camera"
        if clicks is None:  # the first frame with a face, however late it comes (a camera: when someone sits down)
            from tracker.auto_init import AutoInitError, auto_start

            try:
                clicks, image = auto_start(((fr.index, fr.image) for fr in it), src.fps or 30.0)
            except AutoInitError as e:
                raise _Fail(f"{where}: {e}") from None
        else:
            image = next((fr.image for fr in it if fr.index >= clicks.frame), None)
            if image is None:
                raise _Fail(f"{where}: no frame {clicks.frame} to calibrate on")
        try:
            cal = calibrate(image, clicks)
        except CalibrationError as e:
            from app.render_cmd import calibration_message

            raise _Fail(f"{where}: {calibration_message(e)} (frame {clicks.frame})") from None
        yield src.size, cal.ipd, cal.neutral, src.fps
        tracker = FaceTracker(cal)
        if args.video:  # track the whole video from its first frame
            src.close()
            src = open_source()
            it = iter(src)
        for fr in it:
            yield tracker.track(fr.image, fr.index, fr.time).params
    finally:
        src.close()


def _send(args) -> int:
    host, port = parse_address(args.to)
    if args.key_interval < 1:
        raise _Fail(f"--key-interval must be at least 1, got {args.key_interval}")
    if args.fps is not None and not args.fps > 0:
        raise _Fail(f"--fps must be positive, got {args.fps}")
    if args.ipd is not None and not (math.isfinite(args.ipd) and args.ipd > 0):
        raise _Fail(f"--ipd must be a positive number of pixels, got {args.ipd}")
    _frame_size(args.frame_size)  # check it before reading anything
    check_outputs(files=[args.record], inputs=[args.params, args.video, args.init], force=args.force)
    if args.params:
        tr = _load_track(args)
        frames = iter(tr.rows)
        size, ipd, neutral, fps = tr.frame_size, tr.ipd, tr.neutral, tr.fps
        paced = True
    else:
        frames = _tracked_frames(args)
        size, ipd, neutral, fps = next(frames)
        paced = bool(args.video)  # a camera paces itself
    fps = args.fps or fps or 30.0
    t0 = time.monotonic()
    last_note = t0
    with Sender((host, port), size, ipd, fps=fps, compress=args.compress, key_interval=args.key_interval,
                neutral=neutral, simulate_loss=args.simulate_loss) as tx:  # fmt: skip
        record = None
        if args.record:
            from tracker.stream_codec import TrackStreamWriter

            record = TrackStreamWriter(args.record, size, tx.hello.ipd, fps=fps, compressed=args.compress,
                                       key_interval=args.key_interval, neutral=neutral)  # fmt: skip
        try:
            for i, p in enumerate(frames):
                if args.frames is not None and i >= args.frames:
                    break
                if paced:
                    delay = t0 + i / fps - time.monotonic()
                    if delay > 0:
                        time.sleep(delay)
                tx.send(p)
                if record is not None:
                    record.write(p)
                now = time.monotonic()
                if not args.quiet and sys.stderr.isatty() and now - last_note > 0.5:
                    last_note = now
                    print(f"\rsent {tx.stats.frames} frames, {tx.stats.payload_bits_per_frame:.1f} bits/frame", end="",
                          file=sys.stderr)  # fmt: skip
        except KeyboardInterrupt:  # Ctrl-C ends a live send; what was sent is still recorded
            pass
        except BaseException:
            if record is not None:
                record.abort()
            raise
        finally:
            if hasattr(frames, "close"):
                frames.close()
        if record is not None:
            record.close()
        if not args.quiet and sys.stderr.isatty():
            print(file=sys.stderr)
        st = tx.stats
    dt = max(time.monotonic() - t0, 1e-9)
    print(
        f"sent {st.frames} frames to {host}:{port} in {dt:.1f} s: {st.payload_bits_per_frame:.1f} payload bits/frame "
        f"({'compressed' if args.compress else 'plain'}), {8 * st.bytes / dt:.0f} bit/s in UDP payloads"
        + (f"; {st.dropped} dropped on purpose" if st.dropped else "")
    )
    return 0


# ---------------------------------------------------------------------------------------------
# receive


class _Drawing:
    """The character and the output file. The puppet is built before the stream starts (loading a
    character takes a moment); the sender's hello tells it the performer's ipd and neutral face."""

    def __init__(self, args) -> None:
        try:
            from training.puppet import Puppet
        except ImportError as e:
            raise _Fail(f"drawing needs the live puppet (training.puppet), not available in this build ({e})") from None
        from art_sets.io import load_artset

        artset = load_artset(Path(_art_dir(args)))
        session = None
        if args.training:
            from training.session import TrainingSession

            session = TrainingSession.load(args.training, artset=artset, autosave=False)
        self._puppet_cls = Puppet
        self.puppet = Puppet(artset, session=session, fps=args.fps)
        self.out = args.out
        self.fps = args.fps
        self.writer = None
        self._hello = None

    def draw(self, rx: UdpReceiver, frame: FaceParams) -> None:
        if rx.hello is not self._hello:  # a new stream: its performer's scale and neutral face
            from training.features import FeatureSpace

            self._hello = rx.hello
            features = FeatureSpace.from_values(rx.hello.ipd, rx.neutral) if rx.neutral is not None else None
            p = self.puppet
            if abs(rx.hello.fps - p.input_fps) > 0.5:  # filters and hold times count frames: rebuild
                self.puppet = p = self._puppet_cls(p.artset, session=p.session, fps=self.fps, renderer=p.renderer,
                                                   input_fps=rx.hello.fps, features=features)  # fmt: skip
            elif features is not None:
                p.features = features
        pf = self.puppet.step_params(frame)
        if self.out and pf.rgba_pm is not None and pf.fresh:
            if self.writer is None:
                from app.record import FrameWriter

                self.writer = FrameWriter(self.out, fps=self.fps)
            self.writer.write(pf.rgba_pm)

    def close(self, ok: bool = True) -> str:
        if self.writer is None:
            return "no frames drawn" if self.out and ok else ""
        if not ok:
            self.writer.abort()
            return ""
        path = self.writer.close()
        return f"wrote {path} ({self.writer.frames} frames)"


def _art_dir(args) -> str:
    from art_sets.library import find_artset, list_bundled

    if args.art:
        return str(find_artset(args.art))
    bundled = list_bundled()
    if not bundled:
        raise _Fail("no bundled character is installed; pass --art DIR")
    return str(bundled[0][1])


class _TrackFiles:
    """The received track as files (``--csv``, ``--record``, ``--fap``), each written as the
    frames arrive, so nothing is kept per frame however long the stream runs. The packet and
    FAP files start with the first frame (they need the sender's hello); the FAP file is
    relative to the hello's neutral face, or a generic one when the sender sent none."""

    def __init__(self, args) -> None:
        from tracker.params import TrackCsvWriter

        self.record_path, self.fap_path = args.record, args.fap
        self.csv = TrackCsvWriter(args.csv) if args.csv else None
        self.record = self.fap = None
        self.frames = 0

    def add(self, rx: UdpReceiver, f: FaceParams) -> None:
        self.frames += 1
        h = rx.hello
        if self.csv is not None:
            self.csv.write(f)
        if self.record_path and self.record is None and h is not None:
            from tracker.stream_codec import TrackStreamWriter

            self.record = TrackStreamWriter(self.record_path, h.frame_size, h.ipd, fps=h.fps, compressed=h.compressed,
                                            key_interval=h.key_interval, neutral=rx.neutral)  # fmt: skip
        if self.record is not None:
            self.record.write(f)
        if self.fap_path and self.fap is None and h is not None:
            from tracker.fap import FapWriter, generic_neutral

            neutral = rx.neutral if rx.neutral is not None else generic_neutral(h.frame_size, h.ipd)
            self.fap = FapWriter(self.fap_path, neutral, h.ipd, fps=h.fps)
        if self.fap is not None:
            self.fap.write(f)

    def _writers(self):
        return [w for w in (self.csv, self.record, self.fap) if w is not None]

    def close(self) -> None:
        for w in self._writers():
            w.close()

    def abort(self) -> None:
        for w in self._writers():
            w.abort()


def _session(args, rx, drawing: _Drawing | None, files: _TrackFiles, where: str) -> str:
    """Receive until ``--frames``, ``--timeout`` or Ctrl-C, passing each frame to the files and
    the drawing; nothing is kept per frame. Returns the drawing's closing note."""
    received = 0
    start = time.monotonic()
    last_note = start
    ok = False
    try:
        try:
            while True:
                new = rx.poll(0.02 if drawing is not None else 0.1)
                for f in new:
                    received += 1
                    files.add(rx, f)
                    if drawing is not None:
                        drawing.draw(rx, f)
                    if args.frames and received >= args.frames:
                        break
                if drawing is not None and not new:  # late or stopped: hold, then ease to neutral
                    for pose in rx.gap_poses():
                        drawing.draw(rx, pose)
                now = time.monotonic()
                if args.frames and received >= args.frames:
                    break
                if received and args.timeout and now - rx.last_arrival > args.timeout:
                    break
                if not received and args.wait and now - start > args.wait:
                    raise _Fail(f"nothing received on {where} within {args.wait:g} s")
                if not args.quiet and sys.stderr.isatty() and now - last_note > 1.0:
                    last_note = now
                    print(f"\r{rx.stats.summary()}   ", end="", file=sys.stderr)
        except KeyboardInterrupt:  # Ctrl-C ends the session; what arrived is kept
            pass
        ok = True
    finally:
        note = drawing.close(ok) if drawing is not None else ""
        if ok:
            files.close()
        else:
            files.abort()
    return note


def _receive(args) -> int:
    port = check_port(args.port)
    if args.frames is not None and args.frames < 1:
        raise _Fail(f"--frames must be at least 1, got {args.frames}")
    if args.out and not args.frames and not args.timeout:
        raise _Fail("--out needs --frames N or a --timeout to know when the recording ends")
    art = _art_dir(args) if (args.art or args.out or args.training) else None  # a wrong name fails first
    out_files, out_folders = [], []
    if args.out:
        from app.record import RecordError, recording_files

        try:
            out_files, out_folders = recording_files(args.out, track=False)
        except RecordError as e:
            raise _Fail(str(e)) from None
    check_outputs(files=[args.csv, args.record, args.fap, *out_files], folders=out_folders,
                  inputs=[art, args.training], force=args.force)  # fmt: skip
    with UdpReceiver(port, bind=args.bind) as rx:
        bound = rx.address
        if not args.quiet:
            print(f"listening on {bound[0]}:{bound[1]}", file=sys.stderr, flush=True)
        # packets arriving while the character loads wait in the socket's buffer
        drawing = _Drawing(args) if art is not None else None
        note = _session(args, rx, drawing, _TrackFiles(args), f"{bound[0]}:{bound[1]}")
        stats = rx.stats
    if not args.quiet and sys.stderr.isatty():
        print(file=sys.stderr)
    if note:
        print(note)
    print(f"received {stats.summary()}")
    return 0
