"""Start-up of the largest character the validator accepts: load time and peak resident memory.

The art-set limits (``art_sets.io``: canvas, heads, part-box pixels, drawings per part, lines
per drawing) exist so that any set that passes ``python -m art_sets check`` starts in seconds
and a few hundred MB; the morph tables grow with drawings² × lines. A set built exactly at every
limit is loaded and its renderer built (``CharacterRenderer``: both parts' α tables and the
compositor) in a fresh, one-core child that reports its own time and peak resident set.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from art_sets import io as aio
from art_sets.library import list_bundled
from art_sets.model import ArtSet, Drawing, Part
from benchmarks.harness import Table, benchmark

_CHILD = """
import json, os, resource, sys, time
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
import cv2
cv2.setNumThreads(1)
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
t0, c0 = time.perf_counter(), cpu()
from art_sets.io import load_artset
from morph.renderer import CharacterRenderer
t1, c1 = time.perf_counter(), cpu()
art = load_artset(sys.argv[1])
t2, c2 = time.perf_counter(), cpu()
CharacterRenderer(art)
t3, c3 = time.perf_counter(), cpu()
with open("/proc/self/status") as fh:
    peak = next(int(line.split()[1]) for line in fh if line.startswith("VmHWM:"))
print(json.dumps({"imports": t1 - t0, "load": t2 - t1, "renderer": t3 - t2, "cpu": c3 - c1, "peak_mb": peak / 1024}))
"""


def at_the_limits(seed: int = 0) -> ArtSet:
    """A valid art set with every limit reached: canvas, heads, box pixels, drawings, lines."""
    rng = np.random.default_rng(seed)
    side = aio.MAX_SIDE
    bw = bh = int(aio.MAX_DRAWING_PIXELS ** 0.5)
    parts = {}
    for pname, (x, y) in (("eyes", (16, 16)), ("mouth", (side - bw - 16, side - bh - 16))):
        base = np.column_stack([rng.uniform(40, bw - 40, aio.MAX_LINES), rng.uniform(40, bh - 40, aio.MAX_LINES)])
        drawings = []
        for i in range(aio.MAX_DRAWINGS):
            p0 = base + rng.normal(0, 8, base.shape)
            ang = rng.uniform(0, np.pi, aio.MAX_LINES)
            p1 = np.clip(p0 + 30 * np.column_stack([np.cos(ang), np.sin(ang)]), 1, bw - 1)
            img = np.zeros((bh, bw, 4), np.uint8)
            img[..., :3] = rng.integers(0, 256, 3, dtype=np.uint8)
            img[..., 3] = 255
            img[i::9, :, :3] = 20  # some ink
            drawings.append(Drawing(f"d{i}", img, np.column_stack([p0, p1]), f"{pname}/d{i}.png"))
        parts[pname] = Part(pname, (x, y, bw, bh), drawings)
    heads = []
    for k in range(aio.MAX_HEADS):
        h = np.zeros((side, side, 4), np.uint8)
        h[..., :3] = (200 - 3 * k, 170, 150)
        h[..., 3] = 255
        for p in parts.values():
            x, y, w, hh = p.box
            h[y + 24:y + hh - 24, x + 24:x + w - 24, 3] = 0
        heads.append(h)
    return ArtSet("At the limits", (side, side), (side / 2, side * 0.6), heads, parts,
                  head_files=[f"head-{k + 1}.png" for k in range(aio.MAX_HEADS)])


def _measure(folder: Path) -> dict:
    r = subprocess.run([sys.executable, "-c", _CHILD, str(folder)], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "child failed")
    return json.loads(r.stdout.strip().splitlines()[-1])


@benchmark("art_set_limits")
def run(ctx):
    runs = ctx.runs(3, 1)
    t = Table("Start-up of a character: load + renderer (α tables, compositor), fresh one-core process",
              ["character", "drawings", "lines", "runs", "load s", "renderer s", "CPU s (median)", "peak RSS MB (max)",
               "budget"])
    with tempfile.TemporaryDirectory() as tmp:
        limits = aio.save_artset(at_the_limits(), Path(tmp) / "limits", fast=True)
        problems = aio.scan(limits)[1]
        if problems:
            raise RuntimeError(f"the set at the limits does not validate: {problems[0]}")
        cases = [] if ctx.quick else [(name, path) for name, path in list_bundled()[:1]]
        cases.append(("at every limit", limits))
        for name, path in cases:
            art = aio.load_artset(path)
            res = [_measure(path) for _ in range(runs)]
            med = lambda k: float(np.median([r[k] for r in res]))
            t.add(name, f"{len(art.eyes.drawings)} + {len(art.mouth.drawings)}",
                  str(art.eyes.drawings[0].lines.shape[0]), str(runs), f"{med('load'):.2f}", f"{med('renderer'):.2f}",
                  f"{med('cpu'):.2f}", f"{max(r['peak_mb'] for r in res):.0f}", "a few s, ≤ 300 MB")
    t.note = (f"limits: canvas {aio.MAX_SIDE}², {aio.MAX_HEADS} heads, part boxes {aio.MAX_DRAWING_PIXELS:,} px, "
              f"{aio.MAX_DRAWINGS} drawings a part, {aio.MAX_LINES} lines a drawing; imports not counted; "
              "wall-clock times depend on what else the machine runs, CPU s less so")
    return t
