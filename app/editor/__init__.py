"""The art-set editor (``python -m app edit [DIR]``): bring your own drawings.

Make a character from images, place its part boxes and feathered holes on the head, draw the
control lines that make the drawings morph, preview the morphs, and save (atomically, with
autosave and recovery). The pure logic lives in ``art_sets.editing``; this package is the Qt UI.
"""

from __future__ import annotations

from pathlib import Path

import sys

import app.qt_env  # noqa: F401  (choose a Qt platform before PySide6 loads)


def keep_none_alive() -> bool:
    """Work around PySide6 builds that return ``None``/``True``/``False`` without a new reference.

    PySide6 6.12 assumes these singletons are immortal (true from CPython 3.12 on). On 3.11 every
    call of a void Qt method (``QPainter.drawLine``, ``QWidget.update`` …) takes one reference from
    ``None`` for good, and ``Signal.emit`` one from ``True``/``False``; after a few thousand calls
    the interpreter aborts ("Fatal Python error: none_dealloc" / "bool_dealloc"), in any thread.
    If a probe shows the leak, the three singletons get a reserve of 2**40 references each (they
    are never freed anyway). Returns True when the reserve was added.
    """
    if sys.version_info >= (3, 12):
        return False
    import ctypes

    from PySide6.QtGui import QColor

    probe = QColor()
    before = sys.getrefcount(None)
    for _ in range(64):
        probe.setRed(0)
    if before - sys.getrefcount(None) < 32:
        return False
    for singleton in (None, True, False):
        ctypes.c_ssize_t.from_address(id(singleton)).value += 1 << 40
    return True


NONE_WORKAROUND = keep_none_alive()


def open_editor(path: str | Path | None = None, parent=None):
    """Open the editor window (on the art set at ``path`` if given) and return it (a QWidget).

    With a ``parent`` the editor is still its own top-level window. A QApplication must exist.
    """
    from PySide6.QtCore import Qt

    from .window import EditorWindow

    win = EditorWindow(parent)
    if parent is not None:
        win.setWindowFlag(Qt.Window, True)
    win.setAttribute(Qt.WA_DeleteOnClose, True)
    win.show()
    if path is not None:
        win.open_path(path)
    else:
        win.offer_untitled_recovery()
    return win


__all__ = ["open_editor"]
