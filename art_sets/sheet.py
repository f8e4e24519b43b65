"""Contact sheets: every drawing with its numbered control lines, the heads, and halfway morphs.

The morph is passed in (``morph_fn(images, lines_list, weights) -> premultiplied RGBA``,
e.g. ``morph.beier_neely.polymorph_exact``) so this package stays free of ``morph``;
without it the sheet shows drawings and heads only.
"""

from __future__ import annotations

from itertools import combinations
from typing import Callable

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from art_sets.library import compose_still
from art_sets.model import ArtSet, Part

MorphFn = Callable[[list, list, list], np.ndarray]

BG = (236, 234, 228, 255)
LINE = (214, 30, 160, 255)
TEXT = (40, 40, 48, 255)


def _font(size: int):
    for name in ("DejaVuSans.ttf", "LiberationSans-Regular.ttf", "Arial.ttf"):
        try:
            return ImageFont.truetype(name, size)
        except OSError:
            continue
    try:
        return ImageFont.load_default(size)
    except TypeError:  # Pillow < 10.1
        return ImageFont.load_default()


def to_straight(pm: np.ndarray) -> np.ndarray:
    """Premultiplied RGBA uint8 -> straight RGBA uint8."""
    a = pm[..., 3:4].astype(np.float32)
    rgb = np.where(a > 0, pm[..., :3].astype(np.float32) * 255.0 / np.maximum(a, 1), 0)
    return np.concatenate([np.clip(rgb + 0.5, 0, 255).astype(np.uint8), pm[..., 3:4]], -1)


def cross_dissolve(a: np.ndarray, b: np.ndarray, t: float = 0.5) -> np.ndarray:
    """Straight RGBA blend ``(1-t)·a + t·b`` computed on premultiplied colour."""
    fa, fb = a.astype(np.float32) / 255, b.astype(np.float32) / 255
    pa = np.concatenate([fa[..., :3] * fa[..., 3:], fa[..., 3:]], -1)
    pb = np.concatenate([fb[..., :3] * fb[..., 3:], fb[..., 3:]], -1)
    m = (1 - t) * pa + t * pb
    al = m[..., 3:]
    rgb = np.where(al > 1e-6, m[..., :3] / np.maximum(al, 1e-6), 0)
    return (np.clip(np.concatenate([rgb, al], -1), 0, 1) * 255 + 0.5).astype(np.uint8)


def halfway(part: Part, i: int, j: int, morph_fn: MorphFn) -> np.ndarray:
    """The halfway morph of drawings i and j of ``part`` as straight RGBA."""
    d0, d1 = part.drawings[i], part.drawings[j]
    pm = morph_fn([d0.image, d1.image], [d0.lines, d1.lines], [0.5, 0.5])
    return to_straight(np.asarray(pm, np.uint8))


def annotate(img: np.ndarray, lines: np.ndarray, scale: float = 1.0) -> Image.Image:
    """The drawing (straight RGBA) on a checker-free background with numbered control lines."""
    im = Image.fromarray(img, "RGBA")
    if scale != 1.0:
        im = im.resize((round(im.width * scale), round(im.height * scale)), Image.LANCZOS)
    bg = Image.new("RGBA", im.size, (255, 255, 255, 255))
    bg.alpha_composite(im)
    d = ImageDraw.Draw(bg)
    font = _font(max(10, int(11 * scale)))
    for n, (x0, y0, x1, y1) in enumerate(np.asarray(lines).reshape(-1, 4) * scale):
        d.line([(x0, y0), (x1, y1)], fill=LINE, width=2)
        d.ellipse([x0 - 3, y0 - 3, x0 + 3, y0 + 3], fill=LINE)
        ang = np.arctan2(y1 - y0, x1 - x0)
        for da in (2.6, -2.6):
            d.line([(x1, y1), (x1 + 7 * np.cos(ang + da), y1 + 7 * np.sin(ang + da))], fill=LINE, width=2)
        mx, my = (x0 + x1) / 2, (y0 + y1) / 2
        d.text((mx + 3, my - 14), str(n), fill=(120, 0, 90, 255), font=font)
    return bg


def _over_grey(img: np.ndarray) -> Image.Image:
    im = Image.fromarray(img, "RGBA")
    bg = Image.new("RGBA", im.size, (120, 128, 140, 255))
    bg.alpha_composite(im)
    return bg


def render_sheet(art: ArtSet, morph_fn: MorphFn | None = None, max_width: int = 1800) -> Image.Image:
    """The contact sheet of ``art`` as a Pillow RGBA image."""
    title_font, font = _font(26), _font(14)
    blocks: list[tuple[str, list[tuple[str, Image.Image]]]] = []
    faces = [("head %d" % (k + 1), _over_grey(h)) for k, h in enumerate(art.heads)]
    names = art.mouth.names()
    faces.append(("face (open, %s)" % names[0], _over_grey(compose_still(art, 0, 0))))
    faces = [(t, im.resize((256, 256), Image.LANCZOS)) for t, im in faces]
    blocks.append(("heads (grey shows the feathered holes)", faces))
    for part in (art.eyes, art.mouth):
        counts = sorted({len(d.lines) for d in part.drawings})
        what = f"{counts[0]} control lines each" if len(counts) == 1 else f"UNEQUAL control-line counts {counts}"
        blocks.append((f"{part.name}: {len(part.drawings)} drawings, {what}",
                       [(f"{d.name} ({len(d.lines)})", annotate(d.image, d.lines)) for d in part.drawings]))
    if morph_fn is not None:
        for part in (art.eyes, art.mouth):
            if len({len(d.lines) for d in part.drawings}) != 1 or len(part.drawings[0].lines) == 0:
                blocks.append((f"{part.name}: no morphs (the drawings' control lines do not correspond)", []))
                continue
            cells = []
            for i, j in combinations(range(len(part.drawings)), 2):
                a, b = part.drawings[i], part.drawings[j]
                mimg = Image.fromarray(halfway(part, i, j, morph_fn), "RGBA")
                dimg = Image.fromarray(cross_dissolve(a.image, b.image), "RGBA")
                pair = Image.new("RGBA", (mimg.width, mimg.height * 2 + 4), BG)
                pair.paste(mimg, (0, 0))
                pair.paste(dimg, (0, mimg.height + 4))
                cells.append((f"{a.name} ↔ {b.name}", pair))
            blocks.append((f"{part.name}: halfway morph (top) vs cross-dissolve (bottom)", cells))
    # layout
    pad, label_h = 14, 20
    rows: list[tuple[str, list[list[tuple[str, Image.Image]]]]] = []
    for title, cells in blocks:
        lines, cur, x = [], [], pad
        for c in cells:
            if cur and x + c[1].width + pad > max_width:
                lines.append(cur)
                cur, x = [], pad
            cur.append(c)
            x += c[1].width + pad
        if cur:
            lines.append(cur)
        rows.append((title, lines))
    width = max_width
    height = 60 + sum(34 + sum(max(c[1].height for c in ln) + label_h + pad for ln in lines) for _, lines in rows)
    sheet = Image.new("RGBA", (width, height), BG)
    d = ImageDraw.Draw(sheet)
    d.text((pad, 14), f"{art.name} — {art.extra.get('style', '')}   {art.canvas[0]}×{art.canvas[1]}, "
                      f"{len(art.heads)} heads   ({art.path or ''})", fill=TEXT, font=title_font)
    y = 60
    for title, lines in rows:
        d.text((pad, y), title, fill=TEXT, font=_font(18))
        y += 34
        for ln in lines:
            x = pad
            for label, im in ln:
                d.text((x, y), label, fill=TEXT, font=font)
                sheet.paste(im, (x, y + label_h))
                x += im.width + pad
            y += max(c[1].height for c in ln) + label_h + pad
    return sheet
