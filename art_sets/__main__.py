"""``python -m art_sets check DIR`` validates an art set; ``sheet DIR --out PNG`` draws its contact sheet.

``check`` prints one line per problem (``FILE: message``) and exits 1, or ``OK: ...`` and exits 0.
``sheet`` shows the drawings, their control lines and layers, the heads and the body; the
rendered blends are added by ``python -m app sheet`` (this package knows no renderer).
``list`` prints the bundled and user art sets. Expected errors print ``inkface: <message>``
on stderr and exit 2. The format is described in ``art_sets/FORMAT.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _resolve(target: str) -> Path:
    from art_sets.library import find_artset

    p = Path(target)
    return p if p.exists() else find_artset(target)


def cmd_check(args) -> int:
    from art_sets.io import scan
    from art_sets.validate import recommendations, validate

    folder = _resolve(args.dir)
    problems = validate(folder)
    art = scan(folder)[0] if not problems else None
    for p in problems:
        print(p)
    if problems:
        return 1
    assert art is not None
    print(f"OK: {art.name} ({folder}): {len(art.eyes.drawings)} eyes, {len(art.mouth.drawings)} mouths, "
          f"{len(art.heads)} heads, {len(art.eyes.drawings[0].lines)}+{len(art.mouth.drawings[0].lines)} control lines")
    if _layers_note(art):
        print(f"note: {_layers_note(art)}")
    for r in recommendations(folder):
        print(f"note: {r}")
    return 0


def _layers_note(art) -> str:
    """``layers of eyes: a, b; of mouth: c, d; a body`` for a format-2 set, else ``""``."""
    from art_sets.model import layer_names

    bits = [f"layers of {p.name}: {', '.join(layer_names(p))}" for p in (art.eyes, art.mouth) if layer_names(p)]
    if art.body is not None:
        bits.append(f"a body (follows the head by {art.body.follow:g}, rolls by {art.body.roll:g})")
    return "; ".join(bits)


def cmd_sheet(args) -> int:
    from art_sets.io import load_artset
    from art_sets.sheet import render_sheet

    art = load_artset(_resolve(args.dir), strict=False)  # a sheet helps most while lines are still wrong
    img = render_sheet(art)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    img.convert("RGB").save(out)
    print(f"wrote {out} ({img.width}x{img.height})")
    return 0


def cmd_list(args) -> int:
    from art_sets.library import list_bundled, list_user, user_dir

    for name, path in list_bundled():
        print(f"{name}\t{path}\tbundled")
    for name, path in list_user():
        print(f"{name}\t{path}\tuser ({user_dir()})")
    return 0


def main(argv: list[str] | None = None) -> int:
    from art_sets.io import ArtSetError

    ap = argparse.ArgumentParser(prog="python -m art_sets", description="Inkface art sets")
    sub = ap.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="validate an art-set folder")
    c.add_argument("dir", help="art-set folder, its artset.json, or a bundled name")
    c.set_defaults(fn=cmd_check)
    s = sub.add_parser("sheet", help="render a contact sheet PNG (with the rendered blends: python -m app sheet)")
    s.add_argument("dir")
    s.add_argument("--out", required=True, help="output PNG")
    s.add_argument("--no-morph", action="store_true", help=argparse.SUPPRESS)  # blends moved to `python -m app sheet`
    s.set_defaults(fn=cmd_sheet)
    ls = sub.add_parser("list", help="list bundled and user art sets")
    ls.set_defaults(fn=cmd_list)
    args = ap.parse_args(argv)
    try:
        return args.fn(args)
    except ArtSetError as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"inkface: {' '.join(str(e).split())}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
