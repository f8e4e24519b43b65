"""Finding art sets: the bundled characters and the user's own folders, plus thumbnails.

User art sets live in one sub-folder each (with its artset.json) of :func:`user_dir`:
``$INKFACE_ART_DIR`` when set — the program sets it at start-up, to ``characters`` in its data
folder, so every part of it agrees — else ``characters`` in ``$INKFACE_DATA``, else in the
platform's data folder for Inkface (``~/.local/share/Inkface`` or ``$XDG_DATA_HOME/Inkface`` on
Linux, ``~/Library/Application Support/Inkface`` on macOS, ``%APPDATA%\\Inkface`` on Windows:
where Qt's ``AppDataLocation`` puts it, worked out here without Qt).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from art_sets.io import MANIFEST, ArtSetError
from art_sets.model import ArtSet


def bundled_dir() -> Path:
    """The folder holding the bundled characters (one sub-folder each)."""
    return Path(__file__).resolve().parent / "bundled"


def default_data_dir() -> Path:
    """The platform's application-data folder for Inkface, as Qt's ``AppDataLocation`` names it."""
    home = Path(os.path.expanduser("~"))
    if sys.platform == "win32":
        return Path(os.environ.get("APPDATA") or home / "AppData" / "Roaming") / "Inkface"
    if sys.platform == "darwin":
        return home / "Library" / "Application Support" / "Inkface"
    return Path(os.environ.get("XDG_DATA_HOME") or home / ".local" / "share") / "Inkface"


def user_dir() -> Path:
    """The folder where the user's own art sets are looked for (may not exist)."""
    env = os.environ.get("INKFACE_ART_DIR")
    if env:
        return Path(env).expanduser()
    data = os.environ.get("INKFACE_DATA")
    return (Path(data).expanduser() if data else default_data_dir()) / "characters"


def _manifest_name(folder: Path) -> str | None:
    try:
        data = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
        name = data.get("name") if isinstance(data, dict) else None
        return name if isinstance(name, str) and name.strip() else folder.name
    except (OSError, ValueError):
        return None


def _style(folder: Path) -> str:
    try:
        style = json.loads((folder / MANIFEST).read_text(encoding="utf-8")).get("style", "")
    except (OSError, ValueError, AttributeError):
        return ""
    return style.lower() if isinstance(style, str) else ""


def _list(root: Path) -> list[tuple[str, Path]]:
    if not root.is_dir():
        return []
    out = []
    for sub in sorted(root.iterdir()):
        if sub.is_dir() and (sub / MANIFEST).is_file():
            name = _manifest_name(sub)
            if name is not None:
                out.append((name, sub))
    return out


_ORDER = ("straight", "wavy", "blue", "monster")


def list_bundled() -> list[tuple[str, Path]]:
    """``(name, folder)`` of every bundled character, in the paper's order of styles."""
    items = _list(bundled_dir())

    def key(item):
        style = _style(item[1])
        return (_ORDER.index(style) if style in _ORDER else len(_ORDER), item[0].lower())

    return sorted(items, key=key)


def list_user() -> list[tuple[str, Path]]:
    """``(name, folder)`` of the art sets in :func:`user_dir`."""
    return _list(user_dir())


def list_all() -> list[tuple[str, Path]]:
    """Bundled sets first, then the user's."""
    return list_bundled() + list_user()


def find_artset(name_or_path: str | os.PathLike) -> Path:
    """The folder of an art set given its folder, its artset.json, its name or its folder's name.

    Names match case-insensitively against the manifest name and the folder name, bundled
    sets first, then against the manifest's ``style`` (so ``"monster"`` finds the monster). Raises :class:`ArtSetError` listing the known names when nothing matches.
    """
    p = Path(name_or_path).expanduser()
    if p.is_dir() and (p / MANIFEST).is_file():
        return p
    if p.is_file() and p.name == MANIFEST:
        return p.parent
    key = str(name_or_path).strip().lower()
    known = list_all()
    for name, folder in known:
        if key in (name.lower(), folder.name.lower()):
            return folder
    for name, folder in known:  # a style name ("straight", "wavy", "blue", "monster") picks its character
        if key == _style(folder):
            return folder
    if p.is_dir():
        raise ArtSetError(f"{p}: no {MANIFEST} in this folder")
    names = ", ".join(n for n, _ in known) or "none"
    raise ArtSetError(f"no art set named or at {str(name_or_path)!r} (known: {names})")


def _over(dst: np.ndarray, src: np.ndarray, x: int, y: int) -> None:
    """Straight-alpha 'over' of ``src`` onto float ``dst`` (premultiplied, 0..1) at (x, y)."""
    h, w = src.shape[:2]
    s = src.astype(np.float32) / 255.0
    a = s[..., 3:4]
    region = dst[y:y + h, x:x + w]
    region[..., :3] = s[..., :3] * a + region[..., :3] * (1 - a)
    region[..., 3:4] = a + region[..., 3:4] * (1 - a)


def compose_still(art: ArtSet, eyes: str | int = 0, mouth: str | int = 0, head: int = 0,
                  eyes_image: np.ndarray | None = None, mouth_image: np.ndarray | None = None) -> np.ndarray:
    """The face with the given drawings (names or indices) under head ``head``: RGBA straight uint8.

    ``eyes_image`` / ``mouth_image`` (straight RGBA of the box size) replace the drawings,
    e.g. to show a morph result. No warping; this is for previews and thumbnails.
    """
    w, h = art.canvas
    acc = np.zeros((h, w, 4), np.float32)
    for pname, sel, img in (("eyes", eyes, eyes_image), ("mouth", mouth, mouth_image)):
        part = art.parts[pname]
        if img is None:
            idx = part.index(sel) if isinstance(sel, str) else int(sel)
            img = part.drawings[idx].image
        x, y = part.box[0], part.box[1]
        _over(acc, img, x, y)
    _over(acc, art.heads[head % len(art.heads)], 0, 0)
    a = acc[..., 3:4]
    rgb = np.where(a > 1e-6, acc[..., :3] / np.maximum(a, 1e-6), 0)
    out = np.concatenate([rgb, a], axis=2)
    return np.clip(out * 255 + 0.5, 0, 255).astype(np.uint8)


def _default_index(part, names) -> int:
    for n in names:
        if n in part.names():
            return part.index(n)
    return 0


def thumbnail(art: ArtSet, size: int | tuple[int, int] = 128) -> np.ndarray:
    """A preview of the character (neutral face, first head) fitted into ``size``: RGBA straight uint8."""
    still = compose_still(art, _default_index(art.eyes, ("open",)), _default_index(art.mouth, ("neutral", "smile")))
    tw, th = (size, size) if isinstance(size, int) else (int(size[0]), int(size[1]))
    im = Image.fromarray(still, "RGBA")
    # premultiply for resampling so transparent pixels do not bleed colour
    im = im.convert("RGBa").resize(_fit(im.size, (tw, th)), Image.LANCZOS).convert("RGBA")
    out = Image.new("RGBA", (tw, th), (0, 0, 0, 0))
    out.paste(im, ((tw - im.width) // 2, (th - im.height) // 2))
    return np.asarray(out, dtype=np.uint8).copy()


def _fit(src: tuple[int, int], box: tuple[int, int]) -> tuple[int, int]:
    s = min(box[0] / src[0], box[1] / src[1])
    return max(1, round(src[0] * s)), max(1, round(src[1] * s))
