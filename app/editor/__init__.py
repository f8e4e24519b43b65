"""The art-set editor (``python -m app edit [DIR]``): bring your own drawings.

Make a character from images, place its part boxes and feathered holes on the head, draw the
control lines that make the drawings morph, preview the morphs, and save (atomically, with
autosave and recovery). The pure logic lives in ``art_sets.editing``; this package is the Qt UI.
"""

from __future__ import annotations

from pathlib import Path


import app.qt_env  # chooses a Qt platform before PySide6 loads; guards the singletons


NONE_WORKAROUND: bool = app.qt_env.SINGLETONS_GUARDED
"""True when app.qt_env guarded None/True/False against PySide6 builds that drop references."""


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
