"""Choose a Qt platform plugin before PySide6 loads.

Without a display, Qt's default xcb plugin aborts the whole process, so when neither
``DISPLAY`` nor ``WAYLAND_DISPLAY`` is set and the user has not chosen a platform we fall
back to ``offscreen``. Import this module (and call :func:`prepare`) before any PySide6 import.
"""

from __future__ import annotations

import os

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


prepare()
