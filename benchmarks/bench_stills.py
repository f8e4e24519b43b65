"""Still faces under a known camera motion: frames of the shared clips, and photos from
``$INKFACE_STILLS_DIR`` when it is set, each held still and moved as a hand-held camera moves it.

The measuring is :mod:`benchmarks.stills`; this registers it with the harness (``--auto`` and the
clicks on the shared clips' frames, ``--auto`` on photos). ``--quick`` holds one frame for a second.
"""

from __future__ import annotations

from benchmarks import realfaces as rf
from benchmarks import stills as S
from benchmarks.harness import Table, benchmark

QUICK_FRAMES = 25


@benchmark("stills")
def run(ctx):
    stills = []
    photos = S.stills_dir()
    if photos is not None:
        stills += S.photo_stills(photos)
    real = rf.real_dir()
    if real is not None:
        names = rf.clip_names(real)
        stills += S.clip_stills(real, names[:1] if ctx.quick else names, shares=(0.0,) if ctx.quick else S.CLIP_SHARES)
    if not stills:
        skip = Table("Still faces under a known camera motion", ["skipped"])
        skip.add(f"no stills: neither ../shared/real (or ${rf.REAL_DIR_ENV}) nor ${S.STILLS_DIR_ENV}")
        return [skip]
    frames = QUICK_FRAMES if ctx.quick else S.FRAMES
    results = S.measure_stills(stills, (True, False), frames, sheets=not ctx.quick, workers=1)
    note = f"contact sheets: {S.OUT_DIR}/" if not ctx.quick else f"{QUICK_FRAMES} frames only (quick run)"
    return [S.stills_table(results, note)]
