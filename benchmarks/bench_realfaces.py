"""Real faces: every clip of ``../shared/real/`` with its clicks and with ``--auto``, against the peer.

The measuring is :mod:`benchmarks.realfaces`; this registers it with the harness. Clips run one
after another in this (pinned) process, so the ms figures are one-core figures. A full run also
writes the contact sheets to ``out/realfaces/`` and adds the synthetic slide-away clips (seeds
1–4); ``--quick`` tracks the first frames of one short clip and one short synthetic clip.
"""

from __future__ import annotations

from benchmarks import realfaces as rf
from benchmarks.harness import Table, benchmark

QUICK_CLIP = "expr_d0"
QUICK_FRAMES = 40


@benchmark("realfaces")
def run(ctx):
    tables = []
    folder = rf.real_dir()
    if folder is None:
        skip = Table("Real faces vs the peer", ["skipped"])
        skip.add(f"no folder of real clips (../shared/real or ${rf.REAL_DIR_ENV})")
        tables.append(skip)
    else:
        names = rf.clip_names(folder)
        if ctx.quick:
            names = [QUICK_CLIP] if QUICK_CLIP in names else names[:1]
        results = rf.measure_all(folder, names, (False, True), sheets=not ctx.quick, workers=1,
                                 max_frames=QUICK_FRAMES if ctx.quick else None)
        notes = [f"first {QUICK_FRAMES} frames only (quick run)" if ctx.quick else "",
                 f"contact sheets (white dots = the peer's points): {rf.OUT_DIR}/" if not ctx.quick else ""]
        tables += [rf.results_table(results, notes), rf.speed_table(results)]
    seconds = 4.0 if ctx.quick else 10.0
    seeds = (1,) if ctx.quick else (1, 2, 3, 4)
    tables.append(rf.synth_table(rf.measure_synthetic(seeds, workers=1, seconds=seconds), seconds))
    return tables
