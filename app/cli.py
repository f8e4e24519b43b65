"""Command-line dispatch for ``python -m app``.

Each sub-command lives in its own module exposing ``add_arguments(parser, command)``
and ``run(args) -> int`` (``args.command`` names the sub-command); this file only wires them up, so modules load lazily.
With no sub-command the performance window opens.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# sub-command -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "window": ("app.window_cmd", "open the performance window (the default)"),
    "demo": ("app.demo_cmd", "play the bundled performance through the default character"),
    "render": ("app.render_cmd", "render a video or track headless to MP4 / GIF / PNGs"),
    "edit": ("app.editor_cmd", "open the art-set editor"),
    "sheet": ("app.sheet_cmd", "draw an art set's contact sheet with its rendered blends"),
    "send": ("app.net_cmd", "track a camera or video and send 10-byte packets over UDP"),
    "receive": ("app.net_cmd", "receive packets over UDP and draw the character"),
}


def run(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="python -m app", description="Inkface: a face on video drives a hand-drawn cartoon.")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    available = {}
    for name, (modname, helptext) in COMMANDS.items():
        try:
            mod = importlib.import_module(modname)
        except ModuleNotFoundError as e:
            if e.name != modname:
                raise
            continue
        p = sub.add_parser(name, help=helptext, description=helptext)
        mod.add_arguments(p, name)
        available[name] = mod
    if not argv or argv[0].startswith("-") and argv[0] not in ("-h", "--help"):
        argv = ["window"] + argv
    args = ap.parse_args(argv)
    mod = available.get(args.command)
    if mod is None:
        print(f"inkface: '{args.command}' is not available in this build", file=sys.stderr)
        return 2
    from app.data_dir import setup

    setup()  # one data folder, decided before anything asks for a path (and old folders moved in)
    return int(mod.run(args) or 0)
