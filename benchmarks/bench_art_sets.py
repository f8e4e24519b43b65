"""Bundled characters: ghosting of halfway morphs vs cross-dissolves, and loading time.

Ghosting measure ("stray half-strength ink"): a cross-dissolve of two drawings whose features
sit in different places shows each line twice at about half strength; a feature-aligned morph
moves the lines to one place, where they stay at full strength. For each pair of drawings of a
part we take the background colour (the median pixel of the first drawing), measure every
pixel's colour distance from it relative to full-strength ink (the 98th percentile over both
drawings), and count pixels at 20–70 % strength that are more than 2 px from any full-strength
(≥ 70 %) pixel: the anti-aliased rims of real strokes, and the slight softening a warp's
resampling gives them, sit right next to full-strength ink and are not counted; a faint
doubled line is. We report the EXCESS over the mean count of the two source drawings (pencil
drawings have faint strokes of their own). Lower is cleaner; 0 means no more stray grey than
the drawings themselves.
"""

from __future__ import annotations

import statistics
from itertools import combinations

import numpy as np

from art_sets.io import load_artset
from art_sets.library import list_bundled
from art_sets.sheet import cross_dissolve, to_straight
from benchmarks.harness import TIMING_COLUMNS, Table, benchmark, machine, time_call

LOW, HIGH, RIM = 0.20, 0.70, 2


def _dilate(m: np.ndarray, r: int) -> np.ndarray:
    h, w = m.shape
    p = np.pad(m, r)
    out = np.zeros_like(m)
    for dy in range(2 * r + 1):
        for dx in range(2 * r + 1):
            out |= p[dy:dy + h, dx:dx + w]
    return out


def stray_half_strength(rgb: np.ndarray, bg: np.ndarray, full: float) -> int:
    """Pixels at 20–70 % of full ink strength that are not on the rim of a full-strength stroke."""
    s = np.linalg.norm(rgb.astype(np.float32) - bg, axis=2) / max(full, 1e-6)
    mid = (s > LOW) & (s < HIGH)
    return int(np.count_nonzero(mid & ~_dilate(s >= HIGH, RIM)))


def ghosting(a: np.ndarray, b: np.ndarray, halfway: np.ndarray) -> int:
    """Excess stray half-strength pixels of ``halfway`` (straight RGBA) over drawings ``a`` and ``b``."""
    bg = np.median(a[..., :3].reshape(-1, 3), axis=0).astype(np.float32)
    dist = [np.linalg.norm(x[..., :3].astype(np.float32) - bg, axis=2) for x in (a, b)]
    full = float(np.percentile(np.concatenate([d.ravel() for d in dist]), 98))
    base = (stray_half_strength(a[..., :3], bg, full) + stray_half_strength(b[..., :3], bg, full)) / 2
    return int(round(stray_half_strength(halfway[..., :3], bg, full) - base))


@benchmark("art_sets")
def run(ctx):
    sets = list_bundled()
    tables = []
    load = Table("Bundled characters: loading time", ["character", "files MB", "what"] + TIMING_COLUMNS)
    try:
        from morph.renderer import CharacterRenderer
    except Exception:  # morph not available: loading only
        CharacterRenderer = None
    for name, path in sets:
        mb = sum(f.stat().st_size for f in path.rglob("*") if f.is_file()) / 1e6
        load.add(name, f"{mb:.2f}", "load_artset (JSON + PNG decode)", *time_call(lambda: load_artset(path), ctx.runs(7, 2), warmup=1).cells())
        if CharacterRenderer is not None:
            load.add(name, f"{mb:.2f}", "+ CharacterRenderer (all α tables)",
                     *time_call(lambda: CharacterRenderer(load_artset(path)), ctx.runs(3, 1), warmup=0).cells())
    load.note = f"{machine()}. Wall-clock; α tables = 11 steps per ordered pair of drawings, 30×30 mesh."
    tables.append(load)

    try:
        from morph.beier_neely import polymorph_exact
    except Exception:
        polymorph_exact = None
    if polymorph_exact is None:
        t = Table("Ghosting: halfway morph vs cross-dissolve", ["note"])
        t.add("morph.beier_neely.polymorph_exact not available")
        return tables + [t]
    g = Table("Ghosting: excess stray half-strength pixels, halfway morph vs halfway cross-dissolve",
              ["character", "part", "pairs", "morph median px", "dissolve median px", "morph / dissolve",
               "pairs morph cleaner", "worst pair (morph px)"])
    chosen = sets[:1] if ctx.quick else sets
    for name, path in chosen:
        art = load_artset(path)
        for part in (art.eyes, art.mouth):
            idx = range(min(3, len(part.drawings))) if ctx.quick else range(len(part.drawings))
            m_scores, d_scores, worst = [], [], ("", -10**9)
            for i, j in combinations(idx, 2):
                a, b = part.drawings[i], part.drawings[j]
                mh = to_straight(polymorph_exact([a.image, b.image], [a.lines, b.lines], [0.5, 0.5]))
                dh = cross_dissolve(a.image, b.image)
                ms, ds = ghosting(a.image, b.image, mh), ghosting(a.image, b.image, dh)
                m_scores.append(ms)
                d_scores.append(ds)
                if ms > worst[1]:
                    worst = (f"{a.name}–{b.name}", ms)
            mm, dm = statistics.median(m_scores), statistics.median(d_scores)
            cleaner = sum(m < d for m, d in zip(m_scores, d_scores))
            ratio = f"{mm / dm:.2f}" if dm > 0 else "–"
            g.add(name, part.name, str(len(m_scores)), f"{mm:.0f}", f"{dm:.0f}", ratio, f"{cleaner}/{len(m_scores)}",
                  f"{worst[0]} ({worst[1]})")
    g.note = (__doc__.split("\n\n", 1)[1].replace("\n", " ").strip()
              + (" Quick mode: first character, first 3 drawings per part." if ctx.quick else ""))
    tables.append(g)
    return tables
