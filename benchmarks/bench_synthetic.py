"""The synthetic performer: time to draw one 640×480 frame (and its truth) per style."""

from __future__ import annotations

import statistics
import time

from benchmarks.harness import TIMING_COLUMNS, Table, benchmark, time_call, time_each
from tracker.synthetic import STYLES, Performance


def _cpu_ms(fn, items) -> float:
    """Median CPU time (this process) per call, in ms: less sensitive to a busy machine than wall time."""
    out = []
    for it in items:
        t0 = time.process_time()
        fn(it)
        out.append((time.process_time() - t0) * 1000.0)
    return statistics.median(out)


@benchmark("synthetic")
def run(ctx):
    n = ctx.runs(120, 10)
    t = Table("Synthetic performer, one 640×480 frame (Performance.frame)",
              ["style"] + TIMING_COLUMNS + ["fps (median)", "cpu ms (median)"])
    for name in ("default", "small_far", "strong_roll", "noisy", "lighting", "webcam"):
        perf = Performance(seconds=max(n / 30.0, 1.0), seed=1, style=STYLES[name])
        idx = list(range(len(perf)))[:n]
        tm = time_each(perf.frame, idx)
        cpu = _cpu_ms(perf.frame, idx)
        t.add(name, *tm.cells(), f"{1000.0 / tm.median:.0f}", f"{cpu:.2f}")
    perf = Performance(seconds=10, seed=1)
    tt = time_call(lambda: perf.truth(123), ctx.runs(2000, 50))
    t.note = (f"frames of a scripted performance (talking, blinks, roll, drift, leaning; noisy = noise + blur + "
              f"JPEG); truth alone: median {tt.median:.3f} ms over {tt.runs} runs")
    return t
