"""Regenerate the bundled characters: ``python -m art_sets.authoring [SLUG ...] [--out DIR]``."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from art_sets.authoring import characters
from art_sets.io import save_artset
from art_sets.library import bundled_dir
from art_sets.validate import validate


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m art_sets.authoring", description=__doc__)
    ap.add_argument("slugs", nargs="*", help="characters to build (default: all)")
    ap.add_argument("--out", type=Path, default=None, help="parent folder (default: the bundled folder)")
    args = ap.parse_args(argv)
    out = args.out or bundled_dir()
    chars = [c for c in characters() if not args.slugs or c.slug in args.slugs]
    if not chars:
        print(f"inkface: no character matches {' '.join(args.slugs)}", file=sys.stderr)
        return 2
    status = 0
    for c in chars:
        t0 = time.perf_counter()
        folder = save_artset(c.build(), out / c.slug)
        problems = validate(folder)
        for p in problems:
            print(p)
        status |= bool(problems)
        size = sum(f.stat().st_size for f in folder.rglob("*") if f.is_file())
        print(f"{c.slug}: {folder} ({size / 1e6:.2f} MB, {time.perf_counter() - t0:.1f} s)")
    return 1 if status else 0


if __name__ == "__main__":
    sys.exit(main())
