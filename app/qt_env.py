"""Prepare the process for Qt: choose a platform plugin and guard against a PySide6 bug.

Without a display, Qt's default xcb plugin aborts the whole process, so when neither
``DISPLAY`` nor ``WAYLAND_DISPLAY`` is set and the user has not chosen a platform we fall
back to ``offscreen``. Import this module before any PySide6 import (``app.views`` and
``app.workers`` do).

The guard: with PySide6 6.12 on CPython 3.11, many calls return ``None`` or ``True`` without
taking a reference (every ``QPainter.fillRect`` / ``drawImage`` / ``processEvents`` lowers
``None``'s reference count by one, every ``Signal.emit`` lowers ``True``'s). After some tens of
thousands of calls the count reaches zero and the interpreter aborts ("deallocating None").
CPython 3.12 makes these singletons immortal; :func:`immortalize_singletons` does the same
here by giving them a reference count no program can use up.
"""

from __future__ import annotations

import os
import sys

_GUI_PLATFORMS_NEEDING_DISPLAY = {"xcb": "DISPLAY", "wayland": "WAYLAND_DISPLAY", "wayland-egl": "WAYLAND_DISPLAY"}


def has_display() -> bool:
    """True when a window could actually be shown on a screen."""
    plat = os.environ.get("QT_QPA_PLATFORM", "").split(":")[0].strip().lower()
    if plat in ("offscreen", "minimal", "vnc"):
        return False
    if plat in _GUI_PLATFORMS_NEEDING_DISPLAY:
        return bool(os.environ.get(_GUI_PLATFORMS_NEEDING_DISPLAY[plat]))
    if plat:  # cocoa, windows, eglfs, linuxfb ...: the user knows their machine
        return True
    if os.name == "nt" or os.uname().sysname == "Darwin":
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def prepare() -> str:
    """Set ``QT_QPA_PLATFORM`` sensibly if needed; return the platform Qt will use ('' = Qt's default)."""
    plat = os.environ.get("QT_QPA_PLATFORM", "")
    name = plat.split(":")[0].strip().lower()
    if name in _GUI_PLATFORMS_NEEDING_DISPLAY and not os.environ.get(_GUI_PLATFORMS_NEEDING_DISPLAY[name]):
        os.environ["QT_QPA_PLATFORM"] = "offscreen"
    elif not name and not has_display():
        os.environ["QT_QPA_PLATFORM"] = "offscreen"
    return os.environ.get("QT_QPA_PLATFORM", "")


def immortalize_singletons() -> bool:
    """Give None, True, False, Ellipsis and NotImplemented a huge reference count (CPython < 3.12).

    These objects are never freed by a correct program, so this changes nothing except that
    a library which forgets to take references to them can no longer bring the process down.
    Returns True when it did something.
    """
    if sys.implementation.name != "cpython" or sys.version_info >= (3, 12):
        return False
    import ctypes

    for obj in (None, True, False, Ellipsis, NotImplemented):
        ref = ctypes.c_ssize_t.from_address(id(obj))  # ob_refcnt is the first field of every object
        if ref.value < (1 << 40):
            ref.value += 1 << 40
    return True


prepare()
SINGLETONS_GUARDED: bool = immortalize_singletons()
