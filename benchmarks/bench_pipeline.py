"""The whole loop (track → filter → map → render, decode excluded) and resident memory.

Frames of the synthetic performer are decoded into memory first, so the timed loop is exactly
what a live session spends per camera frame after the camera has delivered it.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.harness import TIMING_COLUMNS, Table, Timing, benchmark
from tracker.calibration import calibrate
from tracker.clicks import Clicks
from tracker.synthetic import Performance
from training.puppet import Puppet


def _whole_loop(ctx, names: list[str]) -> Table:
    from art_sets.io import load_artset
    from art_sets.library import find_artset

    n = 60 if ctx.quick else 300
    perf = Performance(seconds=n / 30.0, fps=30, seed=3)
    frames = [perf.frame(i) for i in range(len(perf))]
    cal = calibrate(frames[0], Clicks.from_dict(perf.clicks()))
    t = Table(
        "Whole loop per 640×480 frame, decode excluded (track + filter + map + render 512×512, one core)",
        ["character", "drawings", "stage"] + TIMING_COLUMNS + ["fps at median", "budget"],
    )
    for name in names:
        art = load_artset(find_artset(name))
        variants = [("as bundled" + (" (layers, body)" if art.layered or art.body is not None else ""), art)]
        if art.layered or art.body is not None:
            variants.append(("one picture per drawing, no body", art.single_pictures()))
        puppets = [Puppet(a, calibration=cal) for _, a in variants]
        total = [[] for _ in variants]
        stages = [{} for _ in variants]
        for p in puppets:
            for i in range(5):
                p.step(frames[i], i, i / 30.0)
        for _ in range(1 if ctx.quick else 2):  # alternating rounds: both variants see the same host load
            for k, p in enumerate(puppets):
                p.reset()
                for i, img in enumerate(frames):
                    t0 = time.perf_counter()
                    out = p.step(img, i, i / 30.0)
                    total[k].append((time.perf_counter() - t0) * 1000.0)
                    for key, v in out.timings_ms.items():
                        stages[k].setdefault(key, []).append(v)
        for k, (label, _) in enumerate(variants):
            whole = Timing(total[k])
            t.add(name, label, "whole loop", *whole.cells(), f"{1000.0 / whole.median:.0f}", "≥ 150 fps")
            for key, v in stages[k].items():
                t.add("", "", key, *Timing(v).cells(), "", "")
    t.note = (f"{len(frames)} frames of the bundled synthetic performance (seed 3) per character and round; "
              "'one picture per drawing' renders the same drawings flattened, without the body (the format-1 path), "
              "in alternating rounds with the bundled set; paper: 25 fps on a 450 MHz PIII")
    return t


# Runs `python -m app ARGS...` in this child and prints its own peak resident set (kB) last.
# VmHWM belongs to the child's own address space; ru_maxrss would not do: Linux keeps it across
# exec, so it can report the benchmark parent's size at the moment of the fork.
_MEASURE_CHILD = """
import resource, sys
from app.cli import run
code = run(sys.argv[1:])
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
try:
    with open("/proc/self/status") as fh:
        peak = next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))
except (OSError, StopIteration):
    pass
print(peak)
sys.exit(code)
"""


def _peak_rss_of_render(ctx) -> Table:
    seconds = 2 if ctx.quick else 10
    t = Table("Resident memory, headless render (`python -m app render`, peak RSS of the process)",
              ["clip", "peak RSS MB", "budget"])
    with tempfile.TemporaryDirectory() as d:
        clip = Path(d) / "perf.avi"
        perf = Performance(seconds=seconds, fps=30, seed=4)
        perf.write(clip, Path(d) / "truth.csv")
        argv = ["render", "--video", str(clip), "--art", "ivy", "--out", str(Path(d) / "out.mp4")]
        r = subprocess.run([sys.executable, "-c", _MEASURE_CHILD, *argv], capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"render failed: {r.stderr.strip()[-300:]}")
        peak = int(r.stdout.strip().splitlines()[-1])
    t.add(f"{seconds} s synthetic, 640×480 → 512×512 MP4", f"{peak / 1024:.0f}", "≤ 300 MB")
    t.note = "peak resident set (VmHWM) of the render process itself, read by that process when the render has finished"
    return t


@benchmark("pipeline")
def run(ctx):
    names = ["ivy"] if ctx.quick else ["ivy", "noodle", "bleu", "gnash"]
    return [_whole_loop(ctx, names), _peak_rss_of_render(ctx)]
