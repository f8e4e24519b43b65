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

import numpy as np


def add_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    parser.add_argument("--art", metavar="NAME|DIR", help="the character (default: the first bundled one)")
    parser.add_argument("--out", default="out/demo.mp4", metavar="FILE",
                        help="where the headless render goes (default: out/demo.mp4)")
    parser.add_argument("--seconds", type=float, default=10.0, help="length of the headless render (default 10)")
    parser.add_argument("--fps", type=int, choices=(10, 15, 30), default=30, help="output rate")
    parser.add_argument("--headless", action="store_true", help="render to --out even when a display is present")


def side_by_side(frame_bgr: np.ndarray, rgba_pm: np.ndarray, background=(250, 248, 243)) -> np.ndarray:
    """The performer's frame scaled to the character's height, then the character: one BGR image."""
    import cv2

    from app.record import over_rgb

    ch = rgba_pm.shape[0]
    h, w = frame_bgr.shape[:2]
    left = cv2.resize(frame_bgr, (max(1, round(w * ch / h)), ch), interpolation=cv2.INTER_AREA)
    right = over_rgb(rgba_pm, background)[..., ::-1]
    gap = np.full((ch, 8, 3), 30, np.uint8)
    return np.ascontiguousarray(np.concatenate([left, gap, right], axis=1))


def render_headless(out: str, art: str | None, seconds: float, fps: int) -> Path:
    """Render the bundled performance through the character to ``out`` (MP4 side by side)."""
    import cv2

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
    seconds = max(1.0, seconds)
    perf = bundled_performance(seconds=seconds, seed=0)
    cal = performance_calibration(perf)
    puppet = make_puppet(load_artset(art), PuppetSpec(art=art, fps=fps, calibration=cal))
    out_p = Path(out)
    out_p.parent.mkdir(parents=True, exist_ok=True)
    tmp = out_p.with_name(f".{out_p.stem}.part{out_p.suffix or '.mp4'}")
    writer = None
    n = len(perf)
    t0 = time.perf_counter()
    last = None
    written = 0
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
            img = side_by_side(frame, last)
            if writer is None:
                writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"mp4v"), fps, (img.shape[1], img.shape[0]))
                if not writer.isOpened():
                    raise RuntimeError(f"{out_p}: the video encoder could not be opened")
            writer.write(img)
            written += 1
            if sys.stderr.isatty():
                print(f"\rrendering {i + 1}/{n} frames", end="", file=sys.stderr)
    finally:
        src.close()
        if writer is not None:
            writer.release()
    if writer is None:
        raise RuntimeError("the puppet produced no frames")
    tmp.replace(out_p)
    if sys.stderr.isatty():
        print(file=sys.stderr)
    dt = time.perf_counter() - t0
    print(f"wrote {out_p} ({written} frames at {fps} fps, {n / dt:.0f} frames/s rendered)")
    return out_p


def run(args) -> int:
    from app.qt_env import has_display, prepare

    prepare()
    art = None
    try:
        if args.art:
            from app.window_cmd import resolve_art

            art = resolve_art(args.art)
    except Exception as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    if args.headless or not has_display():
        if not args.headless:
            print("inkface: no display found — rendering the demo to a file instead", file=sys.stderr)
        try:
            render_headless(args.out, art, args.seconds, args.fps)
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
