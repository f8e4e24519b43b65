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
    n = 60 if ctx.quick else 300
    perf = Performance(seconds=n / 30.0, fps=30, seed=3)
    frames = [perf.frame(i) for i in range(len(perf))]
    cal = calibrate(frames[0], Clicks.from_dict(perf.clicks()))
    t = Table(
        "Whole loop per 640×480 frame, decode excluded (track + filter + map + render 512×512, one core)",
        ["character", "stage"] + TIMING_COLUMNS + ["fps at median", "budget"],
    )
    for name in names:
        puppet = Puppet(name, calibration=cal)
        for i in range(5):
            puppet.step(frames[i], i, i / 30.0)
        puppet.reset()
        total, stages = [], {}
        for i, img in enumerate(frames):
            t0 = time.perf_counter()
            out = puppet.step(img, i, i / 30.0)
            total.append((time.perf_counter() - t0) * 1000.0)
            for k, v in out.timings_ms.items():
                stages.setdefault(k, []).append(v)
        whole = Timing(total)
        t.add(name, "whole loop", *whole.cells(), f"{1000.0 / whole.median:.0f}", "≥ 150 fps")
        for k, v in stages.items():
            st = Timing(v)
            t.add("", k, *st.cells(), "", "")
    t.note = f"{len(frames)} frames of the bundled synthetic performance (seed 3) per character; paper: 25 fps on a 450 MHz PIII"
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
