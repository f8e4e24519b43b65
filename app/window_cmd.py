"""``python -m app`` / ``python -m app window``: open the performance window."""

from __future__ import annotations

import argparse
import sys


def add_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    src = parser.add_mutually_exclusive_group()
    src.add_argument("--camera", type=int, metavar="N", help="play camera N")
    src.add_argument("--video", metavar="FILE", help="play a video file of a face")
    src.add_argument("--performance", action="store_true", help="play the bundled synthetic performance")
    parser.add_argument("--art", metavar="NAME|DIR", help="the character to start with (name or folder)")
    parser.add_argument("--fps", type=int, choices=(10, 15, 30), help="output rate")
    parser.add_argument("--performer", metavar="NAME", help="whose calibration and training to use")
    parser.add_argument("--init", metavar="CLICKS.json", help="calibrate from these five clicks on the --video")


def source_from_args(args):
    from app.workers import SourceSpec

    if getattr(args, "camera", None) is not None:
        return SourceSpec("camera", camera=args.camera)
    if getattr(args, "video", None):
        return SourceSpec("video", video=args.video)
    if getattr(args, "performance", False):
        return SourceSpec("performance")
    return None


def resolve_art(name: str | None) -> str | None:
    """An art-set folder from a name or path (raises ArtSetError with a one-line message)."""
    if not name:
        return None
    from art_sets.library import find_artset

    return str(find_artset(name).resolve())


def make_app(argv: list[str] | None = None):
    """The QApplication with Inkface's name and look (created once)."""
    import app.qt_env  # noqa: F401  (sets QT_QPA_PLATFORM before Qt loads)
    from PySide6.QtWidgets import QApplication

    from app.views import apply_theme

    qapp = QApplication.instance()
    if qapp is None:
        qapp = QApplication(argv or [sys.argv[0]])
        qapp.setOrganizationName("Inkface")
        qapp.setApplicationName("Inkface")
        qapp.setApplicationDisplayName("Inkface")
        apply_theme(qapp)
    return qapp


def quit_on_ctrl_c(qapp) -> None:
    """Ctrl+C in the terminal closes the window cleanly (the engine process is stopped too)."""
    import signal

    from PySide6.QtCore import QTimer

    def on_sigint(*_):
        for w in qapp.topLevelWidgets():
            w.close()
        qapp.quit()

    signal.signal(signal.SIGINT, on_sigint)
    t = QTimer(qapp)  # lets the interpreter run now and then, so the handler gets its turn
    t.timeout.connect(lambda: None)
    t.start(250)


def open_window(source=None, art: str | None = None, fps: int | None = None, performer: str | None = None,
                calibration=None):
    from app.main_window import MainWindow
    from app.settings import Settings

    settings = Settings()
    if performer:
        settings.set("performer/name", performer)
    if fps:
        settings.set("output/fps", fps)
    win = MainWindow(settings=settings, source=source, art=art, calibration=calibration)
    win.show()
    return win


def run(args) -> int:
    import os

    try:
        art = resolve_art(getattr(args, "art", None))
    except Exception as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    if getattr(args, "video", None) and not os.path.isfile(args.video):
        print(f"inkface: {args.video}: no such video file", file=sys.stderr)
        return 2
    calibration = None
    if getattr(args, "init", None):
        if not getattr(args, "video", None):
            print("inkface: --init needs --video (the clicks are on a frame of that video)", file=sys.stderr)
            return 2
        try:
            from tracker.clicks import Clicks

            Clicks.load(args.init)
        except Exception as e:
            print(f"inkface: {e}", file=sys.stderr)
            return 2
        calibration = ("clicks", os.path.abspath(args.init), os.path.abspath(args.video))
    from app.qt_env import display_problem

    problem = display_problem()  # asked before Qt loads: a display that is not there aborts Qt
    if problem:
        print(f"inkface: cannot open a window: {problem} (try `python -m app demo`, which renders "
              f"to out/demo.mp4 without one)", file=sys.stderr)
        return 2
    qapp = make_app()
    quit_on_ctrl_c(qapp)
    try:
        win = open_window(source_from_args(args), art, getattr(args, "fps", None), getattr(args, "performer", None),
                          calibration)
    except OSError as e:  # the engine process could not be started (out of memory, processes refused)
        print(f"inkface: cannot start the tracking engine: {e}", file=sys.stderr)
        return 1
    rc = qapp.exec()
    del win
    return int(rc)
