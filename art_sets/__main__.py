"""``python -m art_sets check DIR`` validates an art set; ``sheet DIR --out PNG`` draws its contact sheet.

``check`` prints one line per problem (``FILE: message``) and exits 1, or ``OK: ...`` and exits 0.
``list`` prints the bundled and user art sets. Expected errors print ``inkface: <message>``
on stderr and exit 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _morph_fn():
    """``morph.beier_neely.polymorph_exact`` when the morph package provides it, else None."""
    try:
        from morph.beier_neely import polymorph_exact
    except Exception:  # morph missing or broken: the sheet is still useful without morphs
        return None
    return polymorph_exact


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
    for r in recommendations(folder):
        print(f"note: {r}")
    return 0


def cmd_sheet(args) -> int:
    from art_sets.io import load_artset
    from art_sets.sheet import render_sheet

    art = load_artset(_resolve(args.dir), strict=False)  # a sheet helps most while lines are still wrong
    fn = None if args.no_morph else _morph_fn()
    if fn is None and not args.no_morph:
        print("note: morph.beier_neely.polymorph_exact not available; sheet without morphs", file=sys.stderr)
    img = render_sheet(art, fn)
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
    s = sub.add_parser("sheet", help="render a contact sheet PNG")
    s.add_argument("dir")
    s.add_argument("--out", required=True, help="output PNG")
    s.add_argument("--no-morph", action="store_true", help="skip the halfway morphs")
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
