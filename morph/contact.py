"""Rendered blends for a contact sheet: what the renderer makes between an art set's drawings.

``blend_blocks`` returns blocks of ``(title, [(label, straight RGBA uint8 image), ...])`` for
``art_sets.sheet.render_sheet``: every pair of drawings of each part at the halfway point (the
renderer's blend above a plain cross-dissolve of the same two drawings, for comparison) and
three-way blends with even weights. The blends go through :class:`CharacterRenderer`, so a layered
set shows its layers morphed and stacked, exactly as in a performance.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from morph.compositor import to_straight

BG = (236, 234, 228, 255)


def dissolve(images, weights) -> np.ndarray:
    """Straight RGBA ``Σ w_i · image_i`` of straight RGBA images, computed on premultiplied colour."""
    acc = None
    for img, w in zip(images, weights):
        f = np.asarray(img, np.float32) / 255
        pm = np.concatenate([f[..., :3] * f[..., 3:], f[..., 3:]], -1) * float(w)
        acc = pm if acc is None else acc + pm
    al = acc[..., 3:]
    rgb = np.where(al > 1e-6, acc[..., :3] / np.maximum(al, 1e-6), 0)
    return (np.clip(np.concatenate([rgb, al], -1), 0, 1) * 255 + 0.5).astype(np.uint8)


def cross_dissolve(a: np.ndarray, b: np.ndarray, t: float = 0.5) -> np.ndarray:
    """Straight RGBA blend ``(1-t)·a + t·b`` of two straight RGBA images (see :func:`dissolve`)."""
    return dissolve((a, b), (1 - t, t))


def _stack(top: np.ndarray, bottom: np.ndarray, gap: int = 4) -> np.ndarray:
    h, w = top.shape[:2]
    out = np.empty((2 * h + gap, w, 4), np.uint8)
    out[:] = BG
    out[:h], out[h + gap:] = top, bottom
    return out


def blend_blocks(art, renderer=None, triples: int = 6) -> list[tuple[str, list[tuple[str, np.ndarray]]]]:
    """Halfway blends of every pair and ``triples`` even three-way blends of each part of ``art``.

    ``renderer`` is a :class:`CharacterRenderer` of ``art`` (built here when None). A part whose
    drawings cannot be morphed (control lines that do not correspond) gets a block saying why.
    """
    from morph.renderer import CharacterRenderer

    blocks: list[tuple[str, list[tuple[str, np.ndarray]]]] = []
    try:
        r = renderer if renderer is not None else CharacterRenderer(art)
    except ValueError as e:
        return [(f"no blends: {' '.join(str(e).split())}", [])]
    layered = getattr(art, "layered", False)
    how = "layers morphed and stacked" if layered else "morph"
    for part in (art.eyes, art.mouth):
        names = part.names()
        n = len(names)
        cells = []
        for i, j in combinations(range(n), 2):
            mid = to_straight(r.render_part(part.name, ((i, j), (0.5, 0.5))))
            dis = cross_dissolve(part.drawings[i].image, part.drawings[j].image)
            cells.append((f"{names[i]} ↔ {names[j]}", _stack(mid, dis)))
        blocks.append((f"{part.name}: halfway blends ({how}, top) vs cross-dissolve (bottom)", cells))
        trip = list(combinations(range(n), 3))
        if trip:
            step = max(1, len(trip) // max(1, triples))
            cells = [(" + ".join(names[k] for k in t), to_straight(r.render_part(part.name, (t, (1 / 3, 1 / 3, 1 / 3)))))
                     for t in trip[::step][:triples]]
            blocks.append((f"{part.name}: three-way blends, even weights", cells))
    return blocks
