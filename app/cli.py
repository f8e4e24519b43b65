"""Command-line dispatch for ``python -m app``; each sub-command lives in its own module."""

from __future__ import annotations

import argparse


def run(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="python -m app", description="Inkface: a face on video drives a hand-drawn cartoon.")
    sub = ap.add_subparsers(dest="command")
    sub.add_parser("demo", help="play the bundled performance through the default character")
    args = ap.parse_args(argv)
    if args.command == "demo":
        print("Inkface demo: the renderer is not built yet (see the open issues).")
        return 0
    ap.print_help()
    return 0
