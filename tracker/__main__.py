"""``python -m tracker``: the tracker's command line.

* ``synth --out CLIP.mp4 --truth TRUTH.csv [--seconds S --seed N --style NAME --size WxH]`` writes a
  synthetic performer clip, its exact ten parameters per frame and ``CLIP.clicks.json``.
* ``track VIDEO (--init CLICKS.json | --auto) --csv OUT.csv`` tracks a video (``tracker.track_cli``).

Neither replaces an existing file unless given ``--force``, nor ever writes over its inputs.

Expected problems print one line ``inkface: <message>`` to stderr and exit with code 2.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not WIDTHxHEIGHT, e.g. 640x480") from None
    if not (64 <= w <= 4096 and 64 <= h <= 4096) or w % 2 or h % 2:
        raise argparse.ArgumentTypeError(f"{text}: width and height must be even, 64..4096")
    return w, h


def _interval(text: str) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not START:END in seconds, e.g. 3:4.5") from None
    if not 0 <= a < b:
        raise argparse.ArgumentTypeError(f"{text}: need 0 <= START < END")
    return a, b


def _positive(kind):
    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not v > 0:
            raise argparse.ArgumentTypeError(f"{text} must be positive")
        return v

    return parse


def _add_synth(sub) -> None:
    from tracker.synthetic import STYLES

    p = sub.add_parser("synth", help="write a synthetic performer clip with ground truth",
                       description="Write a clip of the synthetic performer, its exact parameters per frame "
                                   "(track CSV) and CLIP.clicks.json (the five calibration clicks of frame 0).")
    p.add_argument("--out", required=True, metavar="CLIP.mp4", help="video to write (.mp4 mp4v, .avi MJPG, .mkv FFV1)")
    p.add_argument("--truth", metavar="TRUTH.csv", help="truth track to write (default: CLIP.truth.csv beside the clip)")
    p.add_argument("--seconds", type=_positive(float), default=10.0, help="length in seconds (default 10)")
    p.add_argument("--seed", type=int, default=0, help="seed of the scripted performance (default 0)")
    p.add_argument("--style", default="default", choices=sorted(STYLES), help="look and camera effects (default: default)")
    p.add_argument("--size", type=_size, default=(640, 480), metavar="WxH", help="frame size (default 640x480)")
    p.add_argument("--fps", type=_positive(float), default=30.0, help="frames per second (default 30)")
    p.add_argument("--ipd", type=_positive(float), help="inter-pupil distance in pixels (default from the style)")
    p.add_argument("--roll", type=float, metavar="DEG", help="roll amplitude in degrees (default from the style)")
    p.add_argument("--still", action="store_true", help="keep the head still (no roll, drift or leaning)")
    p.add_argument("--away", type=_interval, action="append", default=[], metavar="START:END",
                   help="the face is gone between these seconds (repeatable)")
    p.add_argument("--away-mode", choices=("vanish", "slide"), default="vanish",
                   help="how the face goes: vanish, or slide out of the frame and back (default vanish)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.add_argument("--force", action="store_true", help="replace the clip, truth or clicks file if they exist")
    p.set_defaults(run=_run_synth)


def _run_synth(args) -> int:
    from tracker.outputs import check_outputs
    from tracker.synthetic import STYLES, Performance

    out = Path(args.out)
    truth = Path(args.truth) if args.truth else out.with_name(out.stem + ".truth.csv")
    if args.seconds > 3600:
        raise _Fail(f"--seconds {args.seconds:g}: at most 3600")
    check_outputs(files=[out, truth, out.with_name(out.stem + ".clicks.json")], force=args.force)
    still = dict(roll_amplitude=0.0, drift=0.0, scale_amplitude=0.0) if args.still else {}
    if args.roll is not None and not args.still:
        still["roll_amplitude"] = args.roll
    perf = Performance(seconds=args.seconds, fps=args.fps, seed=args.seed, frame_size=args.size,
                       style=STYLES[args.style], ipd=args.ipd, away=args.away, away_mode=args.away_mode, **still)
    progress = None if args.quiet else _Progress(f"synth {out.name}")
    clicks = perf.write(out, truth, progress=progress)
    if progress is not None:
        progress.done()
    w, h = perf.frame_size
    print(f"wrote {out} ({len(perf)} frames, {w}x{h} @ {perf.fps:g} fps), {truth}, {clicks}")
    return 0


class _Progress:
    """A progress line on stderr, redrawn in place on a terminal, a few times a second at most."""

    def __init__(self, what: str):
        self.what = what
        self.tty = sys.stderr.isatty()
        self.t0 = time.monotonic()
        self.last = 0.0
        self.shown = False

    def __call__(self, done: int, total: int) -> None:
        now = time.monotonic()
        if now - self.last < (0.25 if self.tty else 5.0) and done < total:
            return
        self.last = now
        rate = done / max(now - self.t0, 1e-6)
        line = f"{self.what}: {done}/{total} frames ({100 * done / total:.0f} %, {rate:.0f} fps)"
        if self.tty:
            sys.stderr.write("\r" + line)
        elif now - self.t0 >= 5.0:
            sys.stderr.write(line + "\n")
        else:
            return
        sys.stderr.flush()
        self.shown = True

    def done(self) -> None:
        if self.tty and self.shown:
            sys.stderr.write("\n")
            sys.stderr.flush()


def _add_track(sub) -> None:
    try:
        from tracker.track_cli import add_arguments, run
    except ImportError as e:
        reason = str(e)
        p = sub.add_parser("track", help="track a video (not available in this build)", add_help=False)
        p.add_argument("rest", nargs=argparse.REMAINDER)

        def unavailable(args) -> int:
            raise _Fail(f"track: not available in this build ({reason})")

        p.set_defaults(run=unavailable)
        return
    p = sub.add_parser("track", help="track a video into a CSV of the ten parameters",
                       description="Track every frame of VIDEO and write the track CSV of DESIGN.md.")
    add_arguments(p)
    p.set_defaults(run=run)


class _Fail(Exception):
    """An expected problem: reported as one line, exit code 2."""


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m tracker",
                                 description="Inkface tracker: synthetic test clips and video tracking.")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    _add_synth(sub)
    _add_track(sub)
    return ap


def main(argv: list[str] | None = None) -> int:
    from tracker.outputs import OutputError
    from tracker.params import TrackFormatError
    from tracker.sources import SourceError
    from tracker.synthetic import SynthError

    args = build_parser().parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except (_Fail, SourceError, SynthError, TrackFormatError, OutputError) as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        name = f"{str(e.filename)[:80]}: " if getattr(e, "filename", None) else ""
        print(f"inkface: {name}{e.strerror or e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("inkface: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
