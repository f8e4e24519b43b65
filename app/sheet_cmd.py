"""``python -m app sheet DIR --out PNG``: an art set's contact sheet with the rendered blends.

The drawings, their control lines and layers, the heads and the body (``art_sets.sheet``), and
below them what the renderer makes between the drawings (``morph.contact``): every pair halfway,
next to a plain cross-dissolve, and even three-way blends.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    parser.add_argument("dir", metavar="DIR", help="art-set folder, its artset.json, or a bundled character's name")
    parser.add_argument("--out", required=True, metavar="PNG", help="output PNG")
    parser.add_argument("--no-blends", action="store_true", help="only the drawings, layers, heads and body")


def run(args: argparse.Namespace) -> int:
    from art_sets.io import ArtSetError, load_artset
    from art_sets.library import find_artset
    from art_sets.sheet import render_sheet

    try:
        p = Path(args.dir)
        art = load_artset(p if p.exists() else find_artset(args.dir), strict=False)
        blends = None
        if not args.no_blends:
            from morph.contact import blend_blocks

            blends = blend_blocks(art)
        img = render_sheet(art, blends)
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        img.convert("RGB").save(out)
    except (ArtSetError, OSError) as e:
        print(f"inkface: {' '.join(str(e).split())}", file=sys.stderr)
        return 2
    print(f"wrote {out} ({img.width}x{img.height})")
    return 0
