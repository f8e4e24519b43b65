"""Where a command may write: never over its own inputs, never over an existing file the user
did not ask to replace, and a sequence of frames only into an empty or new folder.

Commands call :func:`check_outputs` with everything they will write (including files they
write beside the named output, such as a calibration's pictures) and everything they read,
before they read or compute anything, so a refused output costs nothing and leaves every file
as it was. ``force`` (the commands' ``--force``) allows replacing existing outputs and writing
frames into a folder that already holds some; it never allows writing over an input.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Callable, Iterable

NAME_MAX = 255
"""Longest file name most file systems take (bytes); asked of the file system when it can say."""

TEMP_MARGIN = 40
"""Characters a temporary file's name may add to the name it stands for (atomic writes)."""

PathLike = str | os.PathLike


class OutputError(ValueError):
    """An output the command may not write; the one-line message names the path."""


def _existing_ancestor(p: Path) -> Path:
    for a in [p, *p.parents]:
        try:
            if a.is_dir():
                return a
        except OSError:
            continue
    return Path(".")


def _limits(p: Path) -> tuple[int, int]:
    base = _existing_ancestor(p.parent)
    try:
        return int(os.pathconf(base, "PC_NAME_MAX")), int(os.pathconf(base, "PC_PATH_MAX"))
    except (OSError, ValueError, AttributeError):
        return NAME_MAX, 4096


def check_name(path: PathLike, folder: bool = False) -> Path:
    """``path`` as a Path, or :class:`OutputError` when its name is too long to write (counting
    the temporary name an atomic write uses beside it) or its folder cannot hold files."""
    p = Path(path)
    name_max, path_max = _limits(p)
    for k, part in enumerate(p.parts):
        n, limit = len(os.fsencode(part)), name_max
        if k == len(p.parts) - 1 and not folder:
            limit -= TEMP_MARGIN
        if n > limit:
            short = part if len(part) <= 40 else part[:20] + "…" + part[-12:]
            raise OutputError(f"{short}: file name too long ({n} bytes; at most {limit})")
    n = len(os.fsencode(os.path.abspath(p)))
    if n > path_max - TEMP_MARGIN:
        raise OutputError(f"{str(p)[:40]}…: path too long ({n} bytes; at most {path_max - TEMP_MARGIN})")
    for a in p.parents:
        try:
            if a.exists() and not a.is_dir():
                raise OutputError(f"{p}: {a} is a file, not a folder")
        except OSError as e:
            raise OutputError(f"{p}: cannot use the folder {a} ({e.strerror or e})") from None
    return p


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def _inside(p: Path, folder: Path) -> bool:
    try:
        return p.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError, ValueError):
        return False


def _stat_exists(p: Path) -> bool:
    try:
        return p.exists() or p.is_symlink()
    except OSError as e:
        raise OutputError(f"{p}: cannot check the output ({e.strerror or e})") from None


def check_outputs(
    files: Iterable[PathLike | None] = (),
    folders: Iterable[PathLike | None] = (),
    inputs: Iterable[PathLike | None] = (),
    force: bool = False,
    hint: str = "pass --force to replace it",
) -> None:
    """Refuse, with one :class:`OutputError`, outputs that would destroy something.

    ``files`` are files the command writes (None entries are skipped), ``folders`` folders it
    fills with numbered frames, ``inputs`` files or folders it reads. Refused always: an output
    that is an input (also through a link), an existing output inside an input folder, a folder
    output that holds an input, the same path named for two outputs, a file output that is a
    folder (and the other way round), names too long to write. Refused unless ``force``: an
    existing file output, a folder output that is not empty (those messages end with ``hint``).
    """
    ins = [Path(p) for p in inputs if p is not None and str(p) != ""]
    seen: list[Path] = []
    for p, is_folder in [(f, False) for f in files if f is not None] + [(d, True) for d in folders if d is not None]:
        p = check_name(p, folder=is_folder)
        for q in seen:
            if p == q or (_stat_exists(p) and _same(p, q)) or p.resolve() == q.resolve():
                raise OutputError(f"{p}: named for two outputs; give each its own name")
        seen.append(p)
        exists = _stat_exists(p)
        for i in ins:
            if exists and _same(p, i):
                raise OutputError(f"{p}: is an input of this command; write the output somewhere else")
            if exists and i.is_dir() and _inside(p, i):
                raise OutputError(f"{p}: is inside the input folder {i}; write the output somewhere else")
            if is_folder and _inside(i, p):
                raise OutputError(f"{p}: holds the input {i}; write the frames into another folder")
        if not exists:
            continue
        if is_folder:
            if not p.is_dir():
                raise OutputError(f"{p}: is a file, not a folder for the frames")
            try:
                empty = next(p.iterdir(), None) is None
            except OSError as e:
                raise OutputError(f"{p}: cannot read the folder ({e.strerror or e})") from None
            if not empty and not force:
                raise OutputError(f"{p}: the folder is not empty; choose a new or empty folder, or {hint}")
        else:
            if p.is_dir():
                raise OutputError(f"{p}: is a folder; give a file name")
            if not force:
                raise OutputError(f"{p}: exists; {hint}")


def free_name(path: PathLike, taken: Callable[[Path], bool] | None = None) -> Path:
    """``path`` if it is free, else the first free ``NAME-2.ext``, ``NAME-3.ext``, … beside it.

    ``taken(candidate)`` says whether a write to the candidate would replace something (default:
    the candidate exists); pass one that also looks at the files written beside it.
    """
    p = Path(path)
    taken = taken or _stat_exists
    stem, suffix = (p.name, "") if not p.suffix else (p.stem, p.suffix)
    base = stem
    head, sep, tail = stem.rpartition("-")
    if sep and head and tail.isdigit() and len(tail) <= 3 and not tail.startswith("0"):
        base = head
    for n in range(1, 10000):
        cand = p if n == 1 else p.with_name(f"{base}-{n}{suffix}")
        if not taken(cand):
            return cand
    raise OutputError(f"{p}: no free name like it in {p.parent}")


def calibration_files(path: PathLike) -> list[Path]:
    """The files a calibration saved at ``path`` consists of: the JSON, the pictures
    :meth:`tracker.calibration.Calibration.save` first writes beside it, and whatever other
    pictures (later generations) a calibration already there names."""
    from tracker.calibration import files_named_by

    p = Path(path)
    first = [p.parent / f"{p.stem}.{part}.png" for part in ("eye_l", "eye_r", "colour_tables", "face")]
    named = [p.parent / n for n in files_named_by(p)] if p.is_file() else []
    return [p] + list(dict.fromkeys(first + named))


class PendingFile:
    """A file written over time under a temporary name beside ``path``
    (:func:`tracker.atomic_file.replacing`): :meth:`commit` moves it into place, :meth:`discard`
    removes it, and until then an earlier file at ``path`` stays as it was. For writers that
    stream (tracks, packet files, videos) and so cannot use the ``with`` form."""

    def __init__(self, path: PathLike, suffix: str = ".tmp"):
        from tracker import atomic_file

        self.path = Path(path)
        self._stack = contextlib.ExitStack()
        self.tmp: Path = self._stack.enter_context(atomic_file.replacing(self.path, suffix=suffix))
        self.done = False

    def commit(self) -> Path:
        """Move the finished file into place (once); returns ``path``."""
        if not self.done:
            self.done = True
            self._stack.close()
        return self.path

    def discard(self) -> None:
        """Remove the temporary file (once); ``path`` is left as it was."""
        if not self.done:
            self.done = True
            err = OutputError(f"{self.path}: discarded")
            self._stack.__exit__(OutputError, err, None)


class ClosingWriter:
    """The ``with`` protocol of a streaming writer: :meth:`close` on success, :meth:`abort` on an
    error (subclasses define both)."""

    def close(self) -> Path:
        raise NotImplementedError

    def abort(self) -> None:
        raise NotImplementedError

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


class StreamedFile(ClosingWriter):
    """A file a writer fills over time and publishes whole: it is written under a temporary
    name (:class:`PendingFile`) and appears at ``path`` only on :meth:`close`; :meth:`abort`
    leaves ``path`` as it was. As a context manager it closes on success, aborts on an error.
    Subclasses write to ``self._f`` (opened with ``mode`` and ``newline``)."""

    def __init__(self, path: PathLike, mode: str = "wb", newline: str | None = None):
        self.path = Path(path)
        self._pending = PendingFile(self.path)
        self._f = open(self._pending.tmp, mode, newline=newline)

    def close(self) -> Path:
        """Finish the file and move it into place; returns its path."""
        self._f.close()
        return self._pending.commit()

    def abort(self) -> None:
        """Discard what was written."""
        self._f.close()
        self._pending.discard()
