"""``python -m app edit [DIR]``: open the art-set editor (on the art set in DIR, or a bundled
character's name)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    parser.add_argument("dir", nargs="?", metavar="DIR",
                        help="art-set folder (or a bundled character's name) to open; omit to start empty")
    parser.add_argument("--screenshot", metavar="PNG",
                        help="render the editor window to PNG and exit (works without a display)")


def _resolve(target: str) -> Path:
    p = Path(target)
    if p.exists():
        if p.is_file() and p.name != "artset.json":
            raise ValueError(f"{p}: not an art-set folder")
        return p
    try:
        from art_sets.library import find_artset

        return Path(find_artset(target))
    except ImportError:
        raise ValueError(f"{target}: no such folder") from None


def run(args: argparse.Namespace) -> int:
    from app import qt_env

    path = None
    if args.dir:
        try:
            path = _resolve(args.dir)
        except Exception as e:  # ArtSetError or ValueError: one line, no traceback
            print(f"inkface: {' '.join(str(e).split())}", file=sys.stderr)
            return 2
        if not (path / "artset.json").is_file() and path.name != "artset.json":
            print(f"inkface: {path}: no artset.json in this folder", file=sys.stderr)
            return 2
    problem = "" if args.screenshot else qt_env.display_problem()
    if problem:
        print(f"inkface: the editor needs a screen: {problem} "
              f"(use --screenshot PNG to render it without one)", file=sys.stderr)
        return 2
    from PySide6.QtWidgets import QApplication

    from app.editor.window import EditorWindow

    qapp = QApplication.instance() or QApplication(sys.argv[:1])
    win = EditorWindow()
    if path is not None:
        from art_sets.io import ArtSetError, load_artset

        try:
            load_artset(path, strict=False)
        except (ArtSetError, OSError) as e:
            print(f"inkface: {' '.join(str(e).split())}", file=sys.stderr)
            return 2
        win.open_path(path)
    win.show()
    if path is None and not args.screenshot:
        win.offer_untitled_recovery()
    if args.screenshot:
        qapp.processEvents()
        win.preview.refresh()
        qapp.processEvents()
        win.grab().save(args.screenshot)
        win.doc.undo_stack.setClean()
        win.close()
        print(f"wrote {args.screenshot}")
        return 0
    return int(qapp.exec())
