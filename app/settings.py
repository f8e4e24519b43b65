"""Typed access to the window's remembered settings (a thin QSettings wrapper).

Values live under organisation "Inkface", application "Inkface" in the platform's usual
place. ``INKFACE_SETTINGS`` (a path to an .ini file) overrides that, which tests use to
keep their settings out of the user's. ``user_data_dir()`` is where performers'
calibrations, training sessions, recorded clips and user characters are kept: the one data
folder of :mod:`app.data_dir` (``INKFACE_DATA`` overrides it).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from PySide6.QtCore import QByteArray, QSettings

ORG = "Inkface"
APP = "Inkface"

DEFAULTS: dict[str, object] = {
    "source/kind": "performance",  # camera | video | performance
    "source/camera": 0,
    "source/video": "",
    "art/current": "",
    "art/user_dirs": [],
    "output/fps": 30,
    "filter/name": "one_euro",
    "filter/strength": 0.5,
    "render/gain": 1.0,
    "render/detail": False,
    "render/background": "colour",  # colour | transparent | green
    "render/background_colour": "#2b2d31",
    "view/overlay": True,
    "view/video": True,
    "performer/name": "default",
    "record/dir": "",
    "record/format": "mp4",
}


def _as_bool(v) -> bool:
    if isinstance(v, str):
        return v.strip().lower() in ("1", "true", "yes", "on")
    return bool(v)


class Settings:
    """Remembered choices of the performance window with typed getters and setters."""

    def __init__(self, path: str | os.PathLike | None = None) -> None:
        path = path or os.environ.get("INKFACE_SETTINGS")
        if path:
            self._q = QSettings(str(path), QSettings.Format.IniFormat)
        else:
            self._q = QSettings(ORG, APP)

    # generic -----------------------------------------------------------------------------
    def get(self, key: str, default=None):
        d = DEFAULTS.get(key, default) if default is None else default
        v = self._q.value(key, d)
        if isinstance(d, bool):
            return _as_bool(v)
        if isinstance(d, int):
            try:
                return int(v)
            except (TypeError, ValueError):
                return d
        if isinstance(d, float):
            try:
                return float(v)
            except (TypeError, ValueError):
                return d
        if isinstance(d, list):
            if v is None or v == "":
                return []
            return [str(x) for x in (v if isinstance(v, (list, tuple)) else [v])]
        return v if v is not None else d

    def set(self, key: str, value) -> None:
        self._q.setValue(key, value)

    def sync(self) -> None:
        self._q.sync()

    def clear(self) -> None:
        self._q.clear()

    # window geometry -------------------------------------------------------------------
    def geometry(self, name: str) -> QByteArray | None:
        v = self._q.value(f"window/{name}")
        return v if isinstance(v, QByteArray) else None

    def set_geometry(self, name: str, data: QByteArray) -> None:
        self._q.setValue(f"window/{name}", data)

    # user characters ---------------------------------------------------------------------
    def user_art_dirs(self) -> list[str]:
        return [p for p in self.get("art/user_dirs") if p]

    def add_user_art_dir(self, path: str | os.PathLike) -> None:
        p = str(Path(path).resolve())
        dirs = [d for d in self.user_art_dirs() if d != p]
        self.set("art/user_dirs", dirs + [p])


def user_data_dir() -> Path:
    """Folder for calibrations, sessions, clips and user characters (created on demand)."""
    from app.data_dir import data_dir

    base = data_dir()
    base.mkdir(parents=True, exist_ok=True)
    return base


def performer_slug(name: str) -> str:
    """A folder-safe name for a performer ("Ann Lee" -> "ann-lee")."""
    s = re.sub(r"[^a-z0-9]+", "-", name.strip().lower()).strip("-")
    return s or "default"


def performer_dir(name: str) -> Path:
    """Where one performer's calibration, sessions and clips are kept."""
    d = user_data_dir() / "performers" / performer_slug(name)
    d.mkdir(parents=True, exist_ok=True)
    return d
