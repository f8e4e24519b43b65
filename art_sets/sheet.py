"""Contact sheets: every drawing with its numbered control lines, its layers, the heads and the body.

This package draws no morphs (it knows the format, not the renderer): blends are passed in as
ready images (``blends``: blocks of ``(title, [(label, straight RGBA array), ...])``), e.g. by
``python -m app sheet``, which renders them with ``morph``.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from art_sets.library import compose_still
from art_sets.model import ArtSet, Part, layer_names

Block = tuple[str, Sequence[tuple[str, "np.ndarray | Image.Image"]]]

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


def _layer_cells(part: Part) -> list[tuple[str, Image.Image]]:
    """Each drawing's layers side by side over grey (what is see-through shows), lines where a layer has its own."""
    cells = []
    for d in part.drawings:
        tiles = []
        for ly in d.layers:
            tile = _over_grey(ly.image)
            if ly.lines is not None:
                tile = annotate(np.asarray(tile), ly.lines)
            tiles.append(tile)
        strip = Image.new("RGBA", (sum(t.width for t in tiles) + 4 * (len(tiles) - 1), tiles[0].height), BG)
        x = 0
        for t in tiles:
            strip.paste(t, (x, 0))
            x += t.width + 4
        cells.append((f"{d.name}: " + " · ".join(ly.name for ly in d.layers), strip))
    return cells


def render_sheet(art: ArtSet, blends: Sequence[Block] | None = None, max_width: int = 1800) -> Image.Image:
    """The contact sheet of ``art`` as a Pillow RGBA image; ``blends`` adds blocks of rendered images."""
    title_font, font = _font(26), _font(14)
    blocks: list[tuple[str, list[tuple[str, Image.Image]]]] = []
    faces = [("head %d" % (k + 1), _over_grey(h)) for k, h in enumerate(art.heads)]
    names = art.mouth.names()
    faces.append(("face (%s, %s)" % (art.eyes.names()[0], names[0]), _over_grey(compose_still(art, 0, 0))))
    if art.body is not None:
        faces.append((f"body (follows {art.body.follow:g}, rolls {art.body.roll:g})", _over_grey(art.body.image)))
    faces = [(t, im.resize((256, 256), Image.LANCZOS)) for t, im in faces]
    blocks.append(("heads (grey shows the feathered holes)" + (" and body" if art.body is not None else ""), faces))
    for part in (art.eyes, art.mouth):
        counts = sorted({len(d.lines) for d in part.drawings})
        what = f"{counts[0]} control lines each" if len(counts) == 1 else f"UNEQUAL control-line counts {counts}"
        blocks.append((f"{part.name}: {len(part.drawings)} drawings, {what}",
                       [(f"{d.name} ({len(d.lines)})", annotate(d.image, d.lines)) for d in part.drawings]))
        if layer_names(part) and all(d.layers for d in part.drawings):
            blocks.append((f"{part.name}: layers, bottom first (grey is see-through; lines where a layer has its own)",
                           _layer_cells(part)))
    for title, cells in blends or ():
        blocks.append((title, [(label, im if isinstance(im, Image.Image) else Image.fromarray(np.asarray(im), "RGBA"))
                               for label, im in cells]))
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
