"""Bundled characters: ghosting of the renderer's blends against cross-dissolves, and loading time.

Ghosting measure ("stray half-strength ink"): a cross-dissolve of drawings whose features sit in
different places shows each line several times at partial strength; a feature-aligned morph
moves the lines to one place, where they stay at full strength. For each blend of a part's
drawings we take the background colour (the median pixel of the first drawing), measure every
pixel's colour distance from it relative to full-strength ink (the 98th percentile over the
blended drawings), and count pixels at 20–70 % strength that are more than 2 px from any
full-strength (≥ 70 %) pixel: the anti-aliased rims of real strokes, and the slight softening a
warp's resampling gives them, sit right next to full-strength ink and are not counted; a faint
doubled line, a half-transparent lid over an eyeball, is. We report the EXCESS over the mean
count of the blended drawings themselves (pencil drawings have faint strokes of their own).
Lower is cleaner; 0 means no more stray grey than the drawings themselves.

Blends: every pair of drawings at the halfway point, and random three-way blends (weights inside
the triangle, each ≥ 0.1). "layered" is what the renderer draws (``CharacterRenderer``, layers
morphed and stacked); "one picture" morphs the same drawings flattened to single pictures with
the drawing's control lines, as format 1 would; "dissolve" is the plain cross-dissolve.
"""

from __future__ import annotations

import statistics
from itertools import combinations

import numpy as np

from art_sets.io import load_artset
from art_sets.library import list_bundled
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


def ghosting(sources, blend: np.ndarray) -> int:
    """Excess stray half-strength pixels of ``blend`` (straight RGBA) over the ``sources`` it blends."""
    bg = np.median(sources[0][..., :3].reshape(-1, 3), axis=0).astype(np.float32)
    dist = [np.linalg.norm(x[..., :3].astype(np.float32) - bg, axis=2) for x in sources]
    full = float(np.percentile(np.concatenate([d.ravel() for d in dist]), 98))
    base = np.mean([stray_half_strength(x[..., :3], bg, full) for x in sources])
    return int(round(stray_half_strength(blend[..., :3], bg, full) - base))


def _triples(n: int, count: int, rng: np.random.Generator) -> list[tuple[tuple[int, ...], tuple[float, ...]]]:
    out = []
    for _ in range(count):
        idx = tuple(int(i) for i in rng.choice(n, size=3, replace=False))
        w = 0.1 + 0.7 * rng.dirichlet(np.ones(3))
        out.append((idx, tuple(float(x) for x in w / w.sum())))
    return out


def ghosting_rows(art, renderer, quick: bool = False, seed: int = 0) -> list[dict]:
    """Per part and kind of blend: the ghosting of the renderer, of one-picture morphs, of dissolves."""
    from morph.compositor import to_straight
    from morph.contact import dissolve
    from morph.polymorph import PartMorpher

    rng = np.random.default_rng(seed)
    rows = []
    for part in (art.eyes, art.mouth):
        n = min(3, len(part.drawings)) if quick else len(part.drawings)
        images = [d.image for d in part.drawings]
        layered = any(d.layers for d in part.drawings)
        flat = PartMorpher(images, [d.lines for d in part.drawings]) if layered else None
        blends = [("halfway pairs", ((i, j), (0.5, 0.5))) for i, j in combinations(range(n), 2)]
        blends += [("random three-way", t) for t in _triples(n, 4 if quick else 12, rng)]
        for kind in ("halfway pairs", "random three-way"):
            got = {"layered": [], "one picture": [], "dissolve": []}
            worst = ("", -10**9)
            for k, (idx, w) in [b for b in blends if b[0] == kind]:
                src = [images[i] for i in idx]
                lay = ghosting(src, to_straight(renderer.render_part(part.name, (idx, w))))
                got["layered"].append(lay)
                got["dissolve"].append(ghosting(src, dissolve(src, w)))
                if flat is not None:
                    got["one picture"].append(ghosting(src, to_straight(flat.render(idx, w))))
                if lay > worst[1]:
                    worst = ("–".join(part.drawings[i].name for i in idx), lay)
            rows.append(dict(part=part.name, kind=kind, blends=len(got["layered"]), worst=worst, **got))
    return rows


def _ratio(a: list, b: list) -> str:
    sb = sum(b)
    return f"{sum(a) / sb:.2f}" if sb > 0 else "–"


@benchmark("art_sets")
def run(ctx):
    sets = list_bundled()
    tables = []
    load = Table("Bundled characters: loading time", ["character", "files MB", "what"] + TIMING_COLUMNS)
    from morph.renderer import CharacterRenderer

    for name, path in sets:
        mb = sum(f.stat().st_size for f in path.rglob("*") if f.is_file()) / 1e6
        load.add(name, f"{mb:.2f}", "load_artset (JSON + PNG decode)", *time_call(lambda: load_artset(path), ctx.runs(7, 2), warmup=1).cells())
        load.add(name, f"{mb:.2f}", "+ CharacterRenderer (all α tables)",
                 *time_call(lambda: CharacterRenderer(load_artset(path)), ctx.runs(3, 1), warmup=0).cells())
    load.note = f"{machine()}. Wall-clock; α tables = 11 steps per ordered pair of drawings and per set of control lines, 30×30 mesh."
    tables.append(load)

    g = Table("Ghosting: excess stray half-strength pixels of the renderer's blends (median per blend; ratios of the totals)",
              ["character", "part", "blends", "n", "layered px", "one picture px", "dissolve px",
               "layered / dissolve", "one picture / dissolve", "worst (layered px)"])
    chosen = sets[:1] if ctx.quick else sets
    for name, path in chosen:
        art = load_artset(path)
        r = CharacterRenderer(art)
        for row in ghosting_rows(art, r, ctx.quick):
            one = row["one picture"]
            g.add(name, row["part"], row["kind"], str(row["blends"]), f"{statistics.median(row['layered']):.0f}",
                  f"{statistics.median(one):.0f}" if one else "–", f"{statistics.median(row['dissolve']):.0f}",
                  _ratio(row["layered"], row["dissolve"]), _ratio(one, row["dissolve"]) if one else "–",
                  f"{row['worst'][0]} ({row['worst'][1]})")
    g.note = (__doc__.split("\n\n", 1)[1].replace("\n", " ").strip()
              + " Goal with layers: layered / dissolve ≤ 0.1."
              + (" Quick mode: first character, first 3 drawings per part, 4 three-way blends." if ctx.quick else ""))
    tables.append(g)
    return tables
