"""Prepare the process for Qt: choose a platform plugin and guard against a PySide6 bug.

Without a usable display, Qt's xcb plugin aborts the whole process (SIGABRT, no Python error
to catch). So before Qt loads, :func:`has_display` asks the display itself: it connects to the
X server named by ``DISPLAY`` (with libxcb, as Qt would, so a server that refuses us counts as
absent; a bare socket connect when libxcb is missing) or to the Wayland socket, and checks that
Qt's xcb plugin can load its libraries. A ``DISPLAY`` pointing at nothing costs a few
milliseconds to find out. When there is no usable display and the user has not chosen a
platform, :func:`prepare` falls back to ``offscreen``; :func:`display_problem` says in one line
why no window can open. Import this module before any PySide6 import (``app.views`` and
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
import re
import socket
import sys

_GUI_PLATFORMS_NEEDING_DISPLAY = {"xcb": "DISPLAY", "wayland": "WAYLAND_DISPLAY", "wayland-egl": "WAYLAND_DISPLAY"}
_TCP_TIMEOUT_S = 0.5  # a remote X display that does not answer within this is taken as absent
_X_DISPLAY = re.compile(r"(?P<host>.*?)(?P<sep>::?)(?P<num>\d+)(?:\.\d+)?")

_probed: dict[tuple, str] = {}  # (platform, DISPLAY, WAYLAND_DISPLAY) -> problem ("" = fine)


def _unix_connects(path: str) -> bool:
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(_TCP_TIMEOUT_S)
            s.connect(path)
        return True
    except OSError:
        return False


def _tcp_answers(host: str, port: int) -> bool:
    try:
        with socket.create_connection((host, port), timeout=_TCP_TIMEOUT_S):
            return True
    except (OSError, ValueError, OverflowError):
        return False


_x_connections: list = []  # probe connections kept open until exit (see _x_problem)


def _x_problem(display: str) -> str:
    """Why Qt could not open the X ``display`` ("" when it can): a real connection (libxcb, as Qt
    connects: it also checks this user may use the server), then the xcb plugin's libraries.

    A good connection is left open: closing the only client of a bare X server (Xvfb, as
    ``xvfb-run`` starts it) makes the server reset, and Qt connecting a moment later would fail.
    """
    import ctypes

    try:
        xcb = ctypes.CDLL("libxcb.so.1")  # the soname: no search (ctypes.util runs ldconfig)
    except OSError:
        return "Qt's xcb platform plugin cannot load (libxcb.so.1 is missing)"
    m = _X_DISPLAY.fullmatch(display)
    if m is None:
        return f"DISPLAY={display!r} is not an X display name (like :0 or host:0)"
    host = m["host"]
    if host not in ("", "unix") and not host.startswith("/") and not _tcp_answers(host, 6000 + int(m["num"])):
        return f"the X display {display!r} does not answer"  # before libxcb, which could wait minutes
    xcb.xcb_connect.restype = ctypes.c_void_p
    xcb.xcb_connect.argtypes = [ctypes.c_char_p, ctypes.c_void_p]
    xcb.xcb_connection_has_error.argtypes = [ctypes.c_void_p]
    xcb.xcb_disconnect.argtypes = [ctypes.c_void_p]
    conn = xcb.xcb_connect(os.fsencode(display), None)
    if not conn or xcb.xcb_connection_has_error(conn):
        if conn:
            xcb.xcb_disconnect(conn)
        return f"cannot connect to the X display {display!r} (no X server there, or it refuses this user)"
    _x_connections.append(conn)
    return _plugin_problem("xcb")


def _plugin_problem(name: str) -> str:
    """Why Qt's platform plugin ``name`` would not load ("" when it would, or cannot tell).

    Loads the system libraries the plugin and its Qt helper library need (a few ms), not the
    plugin itself (which would load most of Qt: ~80 ms); a missing one is what makes Qt abort."""
    import ctypes

    qt = _pyside_qt()
    if qt is None:
        return ""
    plugin = qt / "plugins" / "platforms" / f"libq{name}.so"
    if not plugin.is_file():
        return f"Qt has no {name} platform plugin"
    needed = _elf_needed(plugin)
    helper = qt / "lib" / f"libQt6{name.capitalize()}Qpa.so.6"
    if needed is not None and helper.is_file():
        more = _elf_needed(helper)
        needed = None if more is None else needed + more
    try:
        if needed is None:  # not an ELF file we can read: load the plugin itself
            ctypes.CDLL(str(plugin), mode=getattr(os, "RTLD_LAZY", 1))
        else:
            for lib in dict.fromkeys(n for n in needed if not n.startswith("libQt6")):
                ctypes.CDLL(lib)
    except OSError as e:
        missing = str(e).split(":")[0].strip()
        return f"Qt's {name} platform plugin cannot load ({missing} is missing)"
    return ""


def _pyside_qt():
    """PySide6's ``Qt`` folder, found without importing PySide6 (None if not found)."""
    import importlib.util
    from pathlib import Path

    try:
        spec = importlib.util.find_spec("PySide6")
    except (ImportError, ValueError):
        return None
    for base in (spec.submodule_search_locations or []) if spec else []:
        if (Path(base) / "Qt").is_dir():
            return Path(base) / "Qt"
    return None


def _elf_needed(path) -> list[str] | None:
    """The libraries a 64-bit little-endian ELF file names as needed (DT_NEEDED), or None."""
    import struct

    try:
        data = path.read_bytes()
        if data[:6] != b"\x7fELF\x02\x01":
            return None
        phoff, phentsize, phnum = struct.unpack_from("<Q", data, 32)[0], *struct.unpack_from("<HH", data, 54)
        loads, dynamic = [], None
        for i in range(phnum):
            p_type, _, off, vaddr, _, filesz, _, _ = struct.unpack_from("<IIQQQQQQ", data, phoff + i * phentsize)
            if p_type == 1:
                loads.append((vaddr, off, filesz))
            elif p_type == 2:
                dynamic = (off, filesz)
        if dynamic is None:
            return []
        names, strtab = [], None
        for k in range(dynamic[0], dynamic[0] + dynamic[1], 16):
            tag, val = struct.unpack_from("<qQ", data, k)
            if tag == 0:
                break
            if tag == 1:
                names.append(val)
            elif tag == 5:
                strtab = val
        base = next(off + strtab - va for va, off, size in loads if va <= strtab < va + size)
        return [data[base + n : data.index(b"\0", base + n)].decode() for n in names]
    except (OSError, struct.error, StopIteration, ValueError, TypeError, UnicodeDecodeError):
        return None


def _wayland_problem(name: str) -> str:
    path = name if name.startswith("/") else os.path.join(os.environ.get("XDG_RUNTIME_DIR", ""), name)
    if not _unix_connects(path):
        return f"the Wayland display {name!r} does not answer"
    return _plugin_problem("wayland")


def display_problem() -> str:
    """Why no window can be shown, in one line ("" when one can). Asks the display once per
    setting (a few milliseconds; up to half a second for a remote X display that is silent)."""
    plat = os.environ.get("QT_QPA_PLATFORM", "").split(":")[0].strip().lower()
    x, wl = os.environ.get("DISPLAY", ""), os.environ.get("WAYLAND_DISPLAY", "")
    key = (plat, x, wl)
    if key not in _probed:
        _probed[key] = _ask_display(plat, x, wl)
    return _probed[key]


def _ask_display(plat: str, x: str, wl: str) -> str:
    if plat in ("offscreen", "minimal", "vnc"):
        return f"Qt is set to draw off screen (QT_QPA_PLATFORM={plat})"
    if plat == "xcb":
        return _x_problem(x) if x else "no display (DISPLAY is not set)"
    if plat in ("wayland", "wayland-egl"):
        return _wayland_problem(wl) if wl else "no display (WAYLAND_DISPLAY is not set)"
    if plat:  # cocoa, windows, eglfs, linuxfb ...: the user knows their machine
        return ""
    if os.name == "nt" or sys.platform == "darwin":
        return ""
    if not x and not wl:
        return "no display (neither DISPLAY nor WAYLAND_DISPLAY is set)"
    problems = []
    if wl:
        problems.append(_wayland_problem(wl))
        if not problems[-1]:
            return ""
    if x:
        problems.append(_x_problem(x))
        if not problems[-1]:
            return ""
    return "; ".join(problems)


def has_display() -> bool:
    """True when a window could actually be shown on a screen (see :func:`display_problem`)."""
    return not display_problem()


def prepare() -> str:
    """Set ``QT_QPA_PLATFORM`` to ``offscreen`` when the display it would use is missing or does
    not answer; return the platform Qt will use ('' = Qt's default)."""
    plat = os.environ.get("QT_QPA_PLATFORM", "")
    name = plat.split(":")[0].strip().lower()
    if (not name or name in _GUI_PLATFORMS_NEEDING_DISPLAY) and display_problem():
        problem = display_problem()
        os.environ["QT_QPA_PLATFORM"] = "offscreen"
        _probed[("offscreen", os.environ.get("DISPLAY", ""), os.environ.get("WAYLAND_DISPLAY", ""))] = problem
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
