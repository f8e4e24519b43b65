"""The one folder where Inkface keeps what the user makes, and moving the old folders into it.

The folder is the platform's application-data folder for "Inkface" (Qt's
``QStandardPaths.AppDataLocation`` with no organisation): ``~/.local/share/Inkface`` on Linux
(``$XDG_DATA_HOME`` respected), ``~/Library/Application Support/Inkface`` on macOS,
``%APPDATA%\\Inkface`` on Windows. Inside it::

    performers/<name>/   calibration, training sessions, recorded clips
    characters/<name>/   the user's own art sets
    editor-autosave/     side copies of characters never saved (or bundled ones being changed)
    cache/               files that can be made again (the bundled performance as video)

:func:`setup` decides the folder once, at start-up, before anything asks for a path, and hands
it to every other part through environment variables — ``INKFACE_DATA``, ``INKFACE_ART_DIR``
(read by ``art_sets.library``, which cannot import Qt) and ``INKFACE_CACHE`` — so the core
packages, the engine process and the editor (a child process) all agree. Variables already set
win: tests point them at temporary folders.

Earlier versions scattered these over three places (``…/Inkface/Inkface`` for performers,
``…/inkface/art_sets`` for characters, ``…/__main__.py/inkface`` for the editor's autosave, and
``~/.cache/inkface``). :func:`migrate` moves what is there into the new folder once: it moves,
never overwrites (a name already taken gets ``-old`` added), copies across file systems into a
temporary name that is renamed into place only when complete, rewrites the remembered paths in
the settings, and records what it did in ``.migration.json``, whose presence means "done".
What cannot be moved (a permission, a full disk) stays where it was, is listed in
``.migration-incomplete.json`` and is tried again at the next start.
"""

from __future__ import annotations

import contextlib
import filecmp
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

APP_NAME = "Inkface"
ENV_DATA = "INKFACE_DATA"
ENV_ART = "INKFACE_ART_DIR"
ENV_CACHE = "INKFACE_CACHE"
PERFORMERS = "performers"
CHARACTERS = "characters"
AUTOSAVE = "editor-autosave"
CACHE = "cache"
MARKER = ".migration.json"
FAILED = ".migration-incomplete.json"
LOCK = ".migration.lock"
PARTIAL = ".partial-"
FORMAT = 1
# settings whose values are paths the migration may have moved
PATH_SETTINGS = ("art/user_dirs", "art/current", "source/video", "record/dir")

_decided: Path | None = None


def _location(org: str, app: str, kind: str = "AppDataLocation") -> Path | None:
    """Qt's writable location of ``kind`` as it would be for organisation ``org`` and
    application ``app`` (the names are put back afterwards)."""
    from PySide6.QtCore import QCoreApplication, QStandardPaths

    old = QCoreApplication.organizationName(), QCoreApplication.applicationName()
    try:
        QCoreApplication.setOrganizationName(org)
        QCoreApplication.setApplicationName(app)
        loc = QStandardPaths.writableLocation(getattr(QStandardPaths.StandardLocation, kind))
    finally:
        QCoreApplication.setOrganizationName(old[0])
        QCoreApplication.setApplicationName(old[1])
    return Path(loc) if loc else None


def platform_data_dir() -> Path:
    """The platform's application-data folder for Inkface (not created)."""
    loc = _location("", APP_NAME)
    if loc is None:  # Qt knows no place on this platform: the XDG default
        return Path.home() / ".local" / "share" / APP_NAME
    return loc


def data_dir() -> Path:
    """The data folder: ``$INKFACE_DATA`` when set (as :func:`setup` does), else the platform's."""
    env = os.environ.get(ENV_DATA)
    return Path(env).expanduser() if env else platform_data_dir()


def setup(migrate_old: bool = True) -> Path:
    """Decide the data folder for this process and its children, once; see the module docstring.

    With ``$INKFACE_DATA`` already set the user (or a test) chose the folder: nothing is
    migrated into it. Returns the folder. Never raises for a folder that cannot be made or a
    migration that fails half-way: the program still starts (a one-line warning is printed).
    """
    global _decided
    if _decided is not None and os.environ.get(ENV_DATA) == str(_decided):
        return _decided
    chosen = bool(os.environ.get(ENV_DATA))
    root = data_dir()
    os.environ[ENV_DATA] = str(root)
    os.environ.setdefault(ENV_ART, str(root / CHARACTERS))
    os.environ.setdefault(ENV_CACHE, str(root / CACHE))
    _decided = root
    if migrate_old and not chosen:
        try:
            report = migrate(legacy_sources(root), root)
        except OSError as e:
            print(f"inkface: could not move the old data folders into {root}: {e}", file=sys.stderr)
        else:
            if report and report.get("left"):
                print(f"inkface: {len(report['left'])} old file(s) could not be moved into {root}; they are still "
                      f"where they were (see {root / FAILED})", file=sys.stderr)
    if root.is_dir():
        from tracker.atomic_file import sweep_temp

        sweep_temp(root, recursive=True)  # what saves killed half-way left behind
    return root


def legacy_sources(root: Path) -> list[tuple[Path, Path]]:
    """``(old folder, where its contents go)`` for every folder earlier versions wrote to."""
    home = Path.home()
    xdg_data = Path(os.environ.get("XDG_DATA_HOME") or home / ".local" / "share")
    xdg_cache = Path(os.environ.get("XDG_CACHE_HOME") or home / ".cache")
    out: list[tuple[Path, Path]] = []
    for org, app in ((APP_NAME, APP_NAME), ("", "__main__.py"), ("", "python"), ("", "python3")):
        loc = _location(org, app)
        if loc is not None:
            # the old code added "inkface" unless the folder was already called that
            out.append((loc if loc.name.lower() == "inkface" else loc / "inkface", root))
    old_lower = xdg_data / "inkface"  # the old art_sets folder, and user data when Qt knew no place
    out.append((old_lower / "art_sets", root / CHARACTERS))
    out.append((old_lower, root))
    out.append((xdg_cache / "inkface", root / CACHE))
    seen, unique = set(), []
    for src, dst in out:
        if src not in seen:
            seen.add(src)
            unique.append((src, dst))
    return unique


# ----------------------------------------------------------------------------------- moving


@contextlib.contextmanager
def _locked(root: Path, stale_s: float = 600.0) -> Iterator[bool]:
    """Hold ``root/.migration.lock`` (True) or find another process holding it (False)."""
    lock = root / LOCK
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            try:
                if time.time() - lock.stat().st_mtime > stale_s:  # left by a crashed start
                    lock.unlink(missing_ok=True)
                    continue
            except OSError:
                pass
            yield False
            return
        os.write(fd, str(os.getpid()).encode())
        os.close(fd)
        try:
            yield True
        finally:
            lock.unlink(missing_ok=True)
        return
    yield False


def _free_name(target: Path, is_dir: bool) -> Path:
    """``target`` itself if free, else ``name-old``, ``name-old-2``… (a file keeps its suffix)."""
    if not target.exists() and not target.is_symlink():
        return target
    stem, suffix = (target.name, "") if is_dir else (target.stem, target.suffix)
    k = 1
    while True:
        cand = target.with_name(f"{stem}-old{'' if k == 1 else f'-{k}'}{suffix}")
        if not cand.exists() and not cand.is_symlink():
            return cand
        k += 1


def _same_tree(a: Path, b: Path) -> bool:
    """True when folders (or files) ``a`` and ``b`` hold the same names and bytes."""
    if a.is_file() and b.is_file():
        return filecmp.cmp(a, b, shallow=False)
    if not (a.is_dir() and b.is_dir()):
        return False
    cmp = filecmp.dircmp(a, b)
    # common_funny: a name that is a file on one side and a folder on the other
    if cmp.left_only or cmp.right_only or cmp.funny_files or cmp.common_funny:
        return False
    if filecmp.cmpfiles(a, b, cmp.common_files, shallow=False)[1:] != ([], []):
        return False
    return all(_same_tree(a / d, b / d) for d in cmp.common_dirs)


def _move(src: Path, dst: Path) -> None:
    """Move ``src`` to the free path ``dst``: a rename on one file system; else a copy under a
    temporary name in ``dst``'s folder, renamed into place when complete, then ``src`` removed."""
    dst.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.rename(src, dst)
        return
    except OSError as e:
        import errno

        if e.errno != errno.EXDEV:
            raise
    tmp = Path(tempfile.mkdtemp(prefix=PARTIAL, dir=dst.parent))
    try:
        part = tmp / "x"
        if src.is_dir():
            shutil.copytree(src, part, symlinks=True)
        else:
            shutil.copy2(src, part)
        os.rename(part, dst)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if src.is_dir():
        shutil.rmtree(src)
    else:
        src.unlink()


def _is_container(folder: Path) -> bool:
    """A folder that only groups others (``performers``, ``characters``…) and is merged entry
    by entry; a folder holding files (one performer, one character) moves as one piece."""
    return folder.is_dir() and not folder.is_symlink() and all(p.is_dir() and not p.is_symlink() for p in folder.iterdir())


def _merge(src: Path, dst: Path, moved: list, left: list, skip: set) -> None:
    """Move every entry of ``src`` into ``dst`` (see :func:`migrate`); entries in ``skip`` stay."""
    for entry in sorted(src.iterdir()):
        if entry in skip or any(entry in s.parents for s in skip) or entry.name in (MARKER, FAILED, LOCK) \
                or entry.name.startswith(PARTIAL):
            continue
        target = dst / entry.name
        was = str(entry.resolve())
        try:
            if target.exists() and _same_tree(entry, target):  # already there: drop the duplicate
                shutil.rmtree(entry) if entry.is_dir() and not entry.is_symlink() else entry.unlink()
                moved.append((was, str(target.resolve())))
                continue
            if target.is_dir() and _is_container(entry) and _is_container(target):
                _merge(entry, target, moved, left, skip)
                with contextlib.suppress(OSError):
                    entry.rmdir()
                continue
            free = _free_name(target, entry.is_dir())
            _move(entry, free)
            moved.append((was, str(free.resolve())))
        except OSError as e:
            left.append(f"{entry}: {e.strerror or e}")


def migrate(sources: list[tuple[Path, Path]], root: Path) -> dict | None:
    """Move the contents of each old folder of ``sources`` (``(old, new)`` pairs) into its new
    place under ``root``, once; returns what was done (None when it had been done already or
    another process is doing it). See the module docstring for the rules."""
    root.mkdir(parents=True, exist_ok=True)
    if (root / MARKER).is_file():
        return None
    with _locked(root) as mine:
        if not mine or (root / MARKER).is_file():
            return None
        for junk in root.rglob(f"{PARTIAL}*"):  # copies a crash left unfinished (their sources are intact)
            shutil.rmtree(junk, ignore_errors=True)
        moved: list[tuple[str, str]] = []
        left: list[str] = []
        root_r = root.resolve()
        # an old folder inside another old one comes first in ``sources`` and is skipped by the outer one
        srcs = [(s, d) for s, d in sources if s.is_dir() and not s.is_symlink()]
        for src, dst in srcs:
            src_r = src.resolve()
            if src_r == dst.resolve() or src_r == root_r:
                continue
            skip = {root} | {s for s, _ in srcs if s != src and src in s.parents}
            _merge(src, dst, moved, left, skip)
            _prune(src)
        main_py = _location("", "__main__.py")  # the folder Qt made for the nameless editor
        if main_py is not None:
            with contextlib.suppress(OSError):
                main_py.rmdir()
        report = {"format": FORMAT, "when": time.strftime("%Y-%m-%dT%H:%M:%S"), "moved": moved, "left": left}
        if moved:
            _rewrite_settings(moved)
        # done once it all moved; what could not be moved stays where it was and is tried again next time
        _write_json(root / (FAILED if left else MARKER), report)
        if not left:
            (root / FAILED).unlink(missing_ok=True)
        return report


def _prune(folder: Path) -> None:
    """Remove ``folder`` and its sub-folders where they are empty now."""
    if not folder.is_dir():
        return
    for sub in sorted((p for p in folder.rglob("*") if p.is_dir()), key=lambda p: len(p.parts), reverse=True):
        with contextlib.suppress(OSError):
            sub.rmdir()
    with contextlib.suppress(OSError):
        folder.rmdir()


def _write_json(path: Path, data: dict) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(data, f, indent=1)
            f.write("\n")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def moved_path(path: str, moved: list[tuple[str, str]]) -> str:
    """Where ``path`` is after the moves ``moved`` (``(old, new)`` pairs); itself if not moved."""
    best = None
    for old, new in moved:
        if path == old or path.startswith(old.rstrip(os.sep) + os.sep):
            if best is None or len(old) > len(best[0]):
                best = (old, new)
    return path if best is None else best[1] + path[len(best[0]):]


def _rewrite_settings(moved: list[tuple[str, str]]) -> None:
    """Point the remembered paths (user characters, current character, video, recordings) at
    where the migration moved them."""
    try:
        from app.settings import Settings

        st = Settings()
    except Exception:  # settings unavailable: nothing remembered to fix
        return
    for key in PATH_SETTINGS:
        value = st.get(key)
        if isinstance(value, list):
            new = [moved_path(v, moved) for v in value]
        elif isinstance(value, str) and value:
            new = moved_path(value, moved)
        else:
            continue
        if new != value:
            st.set(key, new)
    st.sync()
