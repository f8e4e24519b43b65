"""``python -m app demo`` (what ``make demo`` runs): the bundled synthetic performance played
through the default character.

With a display it opens the performance window on that performance. Without one it renders
the same thing headless — the performer on the left, the character on the right — to
``out/demo.mp4`` and prints where it went.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

DEFAULT_OUT = "out/demo.mp4"
"""The demo's own file: ``make demo`` replaces it each time (an ``--out`` the user names is not)."""


def add_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    parser.add_argument("--art", metavar="NAME|DIR", help="the character (default: the first bundled one)")
    parser.add_argument("--out", metavar="FILE",
                        help="where the headless render goes (default: out/demo.mp4, replaced each time)")
    parser.add_argument("--force", action="store_true", help="replace --out if it exists")
    parser.add_argument("--seconds", type=float, default=10.0, help="length of the headless render (default 10)")
    parser.add_argument("--fps", type=int, choices=(10, 15, 30), default=30, help="output rate")
    parser.add_argument("--headless", action="store_true", help="render to --out even when a display is present")


def render_headless(out: str, art: str | None, seconds: float, fps: int, force: bool = True) -> Path:
    """Render the bundled performance through the character to ``out`` (side by side, any format
    :class:`app.record.FrameWriter` writes); an existing ``out`` is replaced only with ``force``."""
    from app.record import PAPER_WHITE, FrameWriter, check_render_output, over_rgb
    from app.render_cmd import side_by_side
    from app.workers import (
        PuppetSpec,
        SourceSpec,
        bundled_performance,
        default_art_path,
        load_artset,
        make_puppet,
        open_source,
        performance_calibration,
    )

    art = art or default_art_path()
    if not art:
        raise RuntimeError("no bundled character is installed")
    out_p = Path(out)
    check_render_output(out_p, [art], overwrite=force)
    seconds = max(1.0, seconds)
    perf = bundled_performance(seconds=seconds, seed=0)
    cal = performance_calibration(perf)
    puppet = make_puppet(load_artset(art), PuppetSpec(art=art, fps=fps, calibration=cal))
    writer = FrameWriter(out_p, fps)
    n = len(perf)
    t0 = time.perf_counter()
    last = None
    step = max(1, round(30 / fps))
    src = open_source(SourceSpec("performance", seconds=seconds))  # played once, then cached as video
    try:
        for fr in src:
            i, frame = fr.index, fr.image
            pf = puppet.step(frame, i, i / 30.0)
            if pf is not None and getattr(pf, "rgba_pm", None) is not None:
                last = pf.rgba_pm
            if last is None or i % step:
                continue
            writer.write_rgb(side_by_side(frame, over_rgb(last, PAPER_WHITE)))
            if sys.stderr.isatty():
                print(f"\rrendering {i + 1}/{n} frames", end="", file=sys.stderr)
        if writer.frames == 0:
            raise RuntimeError("the puppet produced no frames")
    except BaseException:
        writer.abort()
        raise
    finally:
        src.close()
    writer.close()
    if sys.stderr.isatty():
        print(file=sys.stderr)
    dt = time.perf_counter() - t0
    print(f"wrote {out_p} ({writer.frames} frames at {fps} fps, {n / dt:.0f} frames/s rendered)")
    return out_p


def run(args) -> int:
    from app.qt_env import display_problem, prepare

    prepare()
    art = None
    try:
        if args.art:
            from app.window_cmd import resolve_art

            art = resolve_art(args.art)
    except Exception as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    problem = "" if args.headless else display_problem()
    if args.headless or problem:
        if problem:
            print(f"inkface: {problem} — rendering the demo to a file instead", file=sys.stderr)
        try:
            render_headless(args.out or DEFAULT_OUT, art, args.seconds, args.fps, force=args.force or not args.out)
        except Exception as e:
            msg = str(e).strip().splitlines()
            print(f"inkface: {msg[0] if msg else type(e).__name__}", file=sys.stderr)
            return 2
        return 0
    from app.window_cmd import make_app, open_window, quit_on_ctrl_c
    from app.workers import SourceSpec

    qapp = make_app()
    quit_on_ctrl_c(qapp)
    win = open_window(SourceSpec("performance"), art, args.fps)
    rc = qapp.exec()
    del win
    return int(rc)
