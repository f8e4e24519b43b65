"""Crash-safe saves: single files replaced atomically, multi-file saves switched in one rename.

*One file*: the new content goes into a temporary file in the same folder, which then replaces
the target with ``os.replace``. A crash or an error part-way leaves the previous file untouched.

*A manifest and the files it names* (an art set's ``artset.json`` and PNGs, a calibration's JSON
and pictures, a training session's ``session.json`` and thumbnails): a :class:`Generation`. The
files of the generation on disk are never written to: a file whose content changes goes under a
name the current manifest does not use (``eyes/open.png`` <-> ``eyes/open.v2.png``), unchanged
files are kept as they are, and the new manifest, written last, switches to the new generation
in one rename. Only then are the old generation's files that the new one does not use removed.
At every moment the manifest on disk names a complete set of files: the old one or the new one.

Temporary files are called ``.<name>.inkface-tmp-<pid>-<random><suffix>``. A crash can leave one
behind; :func:`sweep_temp` removes those whose writing process is gone (the savers and loaders
of each folder call it, and so does the program at start-up). Finished files get ordinary
permissions (``mkstemp`` alone would leave them 0600). Standard library only: ``art_sets`` keeps
an identical copy (it may not import ``tracker``; ``tests/test_file_safety.py`` keeps the two equal).
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
import time
from pathlib import Path, PurePosixPath
from typing import Iterable, Iterator

TEMP_MARK = ".inkface-tmp-"
"""Every temporary file of a save has this in its name (after a dot and the target's name)."""
_TEMP_RE = re.compile(r"^\..*" + re.escape(TEMP_MARK) + r"(\d+)-")
STALE_SECONDS = 24 * 3600.0
"""A temporary file untouched this long is swept even if a process with its pid is running."""
_NAME_KEEP = 80  # characters of the target's name kept in a temporary name (limits are 255 bytes)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def is_temp(name: str) -> bool:
    """True for the name of a temporary file made by this module."""
    return _TEMP_RE.match(name) is not None


def _alive(pid: int) -> bool:
    if pid == os.getpid() or os.name == "nt":  # Windows' os.kill(pid, 0) would send a Ctrl-C: age decides there
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError, OverflowError, ValueError):
        return True  # someone else's process, or a pid this system cannot check: leave it
    return True


def sweep_temp(folder: str | os.PathLike, recursive: bool = False) -> int:
    """Remove the temporary files in ``folder`` whose writer has died (or that are stale).

    Files of a writer that is still running are left alone, so sweeping is safe while another
    process (or another thread of this one) saves into the same folder. Never raises: a folder
    that is missing or read-only is simply not swept. Returns the number of files removed.
    """
    removed = 0
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return 0
    now = time.time()
    for e in entries:
        try:
            if recursive and e.is_dir(follow_symlinks=False):
                removed += sweep_temp(e.path, recursive=True)
                continue
            m = _TEMP_RE.match(e.name)
            if m is None or not e.is_file(follow_symlinks=False):
                continue
            if _alive(int(m.group(1))) and now - e.stat(follow_symlinks=False).st_mtime < STALE_SECONDS:
                continue
            os.unlink(e.path)
            removed += 1
        except OSError:
            continue
    return removed


def _fsync_path(path: str | os.PathLike, directory: bool = False) -> None:
    try:
        fd = os.open(path, os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0))
    except OSError:
        return  # e.g. folders cannot be opened on Windows
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def replacing(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path``, on error it goes.

    ``suffix`` matters for writers that choose a format by extension (e.g. video writers).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    prefix = f".{path.name[:_NAME_KEEP]}{TEMP_MARK}{os.getpid()}-"
    fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        _fsync_path(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with replacing(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | os.PathLike, text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    write_bytes(path, text.encode("utf-8"))


def inside(folder: str | os.PathLike, rel: str) -> Path | None:
    """``folder / rel`` if it is a plain relative path that stays inside ``folder`` (symlinks
    resolved), else None. Never raises: a symlink loop or an over-long name gives None."""
    if not isinstance(rel, str) or not rel or "\x00" in rel or "\\" in rel:
        return None
    p = PurePosixPath(rel)
    if p.is_absolute() or ".." in p.parts or ":" in p.parts[0]:
        return None
    if len(rel) > 1024 or any(len(part.encode("utf-8", "surrogateescape")) > 255 for part in p.parts):
        return None  # longer than a file system holds
    try:
        base = Path(folder).resolve()
        full = (Path(folder) / rel).resolve()
        full.relative_to(base)
    except (OSError, RuntimeError, ValueError):
        return None
    return Path(folder) / rel


def base_name(rel: str) -> str:
    """``rel`` without the version a :class:`Generation` may have added: ``a/b.v2.png`` -> ``a/b.png``."""
    p = PurePosixPath(rel)
    m = re.fullmatch(r"(.+)\.v(\d+)", p.stem)
    return str(p.with_name(m.group(1) + p.suffix)) if m else rel


def _versions(rel: str) -> Iterator[str]:
    """``rel`` and then its other names: ``a/b.png``, ``a/b.v2.png``, ``a/b.v3.png`` …"""
    base = PurePosixPath(base_name(rel))
    yield rel
    yield str(base)
    k = 2
    while True:
        yield str(base.with_name(f"{base.stem}.v{k}{base.suffix}"))
        k += 1


class Generation:
    """One save of ``manifest`` (a file name in ``folder``) and the files it names.

    ``current`` are the names (relative to ``folder``, ``/``-separated) that the manifest on
    disk uses now; none of them is written to. :meth:`put` stores a file and returns the name it
    got, :meth:`keep` keeps a current file as it is; :meth:`commit` writes the manifest (which
    must name exactly the names returned), switching to the new generation, and removes the
    current files the new one does not use. Without :meth:`commit` (an error, a crash) the old
    generation stays what the folder holds; files already put are left for the next save to
    reuse or replace. Temporary files of dead writers in the folders written to are swept.
    """

    def __init__(self, folder: str | os.PathLike, manifest: str, current: Iterable[str] = ()):
        self.folder = Path(folder)
        self.manifest = manifest
        self.current = {c for c in current if isinstance(c, str)}
        self.names: set[str] = set()
        self._swept: set[Path] = set()
        self.folder.mkdir(parents=True, exist_ok=True)
        self._sweep(self.folder)

    def _sweep(self, d: Path) -> None:
        if d not in self._swept:
            self._swept.add(d)
            sweep_temp(d)

    def put(self, rel: str, data: bytes) -> str:
        """Store ``data`` under ``rel`` or, if a current file of that name holds other bytes, under
        another name (see :func:`_versions`); returns the name used. ValueError if ``rel`` leaves
        the folder."""
        if inside(self.folder, rel) is None:
            raise ValueError(f"{rel!r} is not a path inside {self.folder}")
        for name in _versions(rel):
            if name in self.names:
                continue
            target = self.folder / name
            same = _holds(target, data)
            if name in self.current and not same:
                continue
            if target.is_dir():
                continue
            if not same:
                self._sweep(target.parent)
                write_bytes(target, data)
            self.names.add(name)
            return name
        raise AssertionError("unreachable")  # _versions never ends

    def keep(self, rel: str) -> str:
        """Keep the current file ``rel`` unchanged in the new generation (KeyError if it is not
        current or no longer there)."""
        if rel not in self.current or rel in self.names or not (self.folder / rel).is_file():
            raise KeyError(rel)
        self.names.add(rel)
        return rel

    def commit(self, manifest: bytes) -> None:
        """Write the manifest (the switch) and remove the old generation's files no longer named."""
        target = self.folder / self.manifest
        write_bytes(target, manifest)
        _fsync_path(self.folder, directory=True)
        for rel in self.current - self.names:
            full = inside(self.folder, rel)
            if full is not None and full.is_file() and not full.is_symlink():
                with contextlib.suppress(OSError):
                    full.unlink()


def _holds(path: Path, data: bytes) -> bool:
    """True if ``path`` is a file holding exactly ``data``."""
    try:
        if not path.is_file() or path.stat().st_size != len(data):
            return False
        return path.read_bytes() == data
    except OSError:
        return False
