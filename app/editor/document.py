"""The editor's document: the art set being edited, its undo stack, selection, saving and autosave.

Every edit goes through :meth:`EditorDocument.edit` (or :meth:`push_state` for live drags and
brush strokes), which pushes a :class:`SnapshotCommand` onto a ``QUndoStack``. A snapshot is an
``art_sets.editing.clone`` — a copy of the structure that shares the image and line arrays,
which the editing functions never modify in place — so undo is exact and cheap.

Autosave writes the whole set with ``art_sets.io.save_artset`` into a hidden side folder
(``DIR/.artset.autosave/``, or the user data folder for an unsaved character) on a worker thread
a moment after the last edit; the validator then runs on that copy, so the problems panel always
describes what is on screen. Opening a folder whose side copy is newer offers to recover it.
"""

from __future__ import annotations

import re
import shutil
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Sequence

from PySide6.QtCore import QObject, QTimer, Signal
from PySide6.QtGui import QUndoCommand, QUndoStack

from art_sets import editing as ed
from art_sets.atomic_file import sweep_temp
from art_sets.model import ArtSet

AUTOSAVE_NAME = ".artset.autosave"


def _user_autosave_root() -> Path:
    try:
        from app.settings import user_data_dir

        base = Path(user_data_dir())
    except Exception:  # settings module missing or unusable: fall back to the home folder
        base = Path.home() / ".inkface"
    return base / "editor-autosave"


def is_bundled(path: Path) -> bool:
    """True for a folder inside the bundled characters (shipped files: never written to)."""
    try:
        from art_sets.library import bundled_dir

        Path(path).resolve().relative_to(Path(bundled_dir()).resolve())
        return True
    except Exception:
        return False


def autosave_dir_for(path: Path | None) -> Path:
    """Where the side copy of the set at ``path`` is kept: ``DIR/.artset.autosave``; for a new,
    unsaved set (None) or a bundled one, a folder in the user data folder."""
    if path is None:
        return _user_autosave_root() / "untitled"
    if is_bundled(path):
        return _user_autosave_root() / f"bundled-{Path(path).name}"
    return Path(path) / AUTOSAVE_NAME


def recoverable(path: Path | None) -> Path | None:
    """The side copy of ``path`` if it exists and is newer than the saved set, else None."""
    side = autosave_dir_for(path)
    mf = side / "artset.json"
    if not mf.is_file():
        return None
    if path is not None:
        saved = Path(path) / "artset.json"
        if saved.is_file() and saved.stat().st_mtime >= mf.stat().st_mtime:
            return None
    return side


def write_side_copy(art: ArtSet, folder: Path, written: dict) -> None:
    """Write ``art`` as a complete art-set folder, fast: light PNG compression, and images that
    are the very arrays written last time (the model never changes an array in place) are kept
    without encoding them again. One generation (``art_sets.io.save_artset``): a crash at any
    moment leaves the previous side copy or this one, never a mix.

    ``written`` is the cache ``save_artset`` keeps between saves into ``folder``; it is updated.
    ``art``'s image names become the side copy's (pass a snapshot).
    """
    from art_sets.io import save_artset

    save_artset(art, folder, fast=True, cache=written)


def _plain_names(art: ArtSet) -> None:
    """Drop the ``.v2`` a generation switch may have given image names (``mouth/ah.v2.png`` ->
    ``mouth/ah.png``), so a recovered side copy saves under the set's usual names."""
    from art_sets.atomic_file import base_name

    art.head_files = [base_name(f) for f in art.head_files]
    for p in art.parts.values():
        for d in p.drawings:
            d.file = base_name(d.file) if d.file else d.file
            for ly in d.layers:
                ly.file = base_name(ly.file) if ly.file else ly.file
    if art.body is not None and art.body.file:
        art.body.file = base_name(art.body.file)


_SIZE_PROBLEM = re.compile(r"is \d+x\d+, the .* is \d+x\d+$")


def load_tolerant(path: Path) -> ArtSet:
    """Load an art set for editing: half-finished control lines and drawings or heads of the wrong
    size are let through (the editor offers to fix them); anything else raises ``ArtSetError``."""
    from art_sets.io import ArtSetError, load_artset, scan

    try:
        return load_artset(path, strict=False)
    except ArtSetError as first:
        art, problems = scan(path, strict_geometry=False)
        if art is None or not problems or not all(_SIZE_PROBLEM.search(p.message) for p in problems):
            raise first from None
        if len(art.heads) == 0:
            raise first from None
        return art


@dataclass
class Advice:
    """A recommendation that is not an error (``art_sets.validate.recommendations``)."""

    message: str


def check_folder(folder: Path) -> list:
    """The validator's problems for ``folder``, then its advice (as :class:`Advice`)."""
    from art_sets.validate import validate

    found: list = list(validate(folder))
    try:
        from art_sets.validate import recommendations

        found += [Advice(str(t)) for t in recommendations(folder)]
    except Exception:  # advice is optional
        pass
    return found


@dataclass
class Issue:
    """A row of the problems panel: what is wrong and where to jump to fix it."""

    severity: str  # "error" (validator), "todo" (editor: lines to place, sizes) or "advice"
    file: str
    message: str
    part: str | None = None
    drawing: int | None = None
    line: int | None = None
    head: int | None = None

    def text(self) -> str:
        where = f"{self.file}: " if self.file else ""
        return f"{where}{self.message}"


class SnapshotCommand(QUndoCommand):
    """An undoable edit stored as the art set before and after it."""

    def __init__(self, doc: "EditorDocument", text: str, before: ArtSet, after: ArtSet, selection=None):
        super().__init__(text)
        self.doc, self.before, self.after = doc, before, after
        self.sel_before = doc.selection()
        self.sel_after = selection if selection is not None else self.sel_before

    def redo(self) -> None:
        self.doc._restore(self.after, self.sel_after)

    def undo(self) -> None:
        self.doc._restore(self.before, self.sel_before)


class EditorDocument(QObject):
    """Holds the art set being edited and performs every edit as an undoable command."""

    changed = Signal()  # the art set changed (edit, undo, redo, open, new)
    selectionChanged = Signal()
    problemsChanged = Signal()
    autosaved = Signal(str)
    message = Signal(str)  # a one-line note for the status bar

    def __init__(self, parent: QObject | None = None, autosave_delay_ms: int = 1500):
        super().__init__(parent)
        self.artset: ArtSet | None = None
        self.path: Path | None = None
        self.undo_stack = QUndoStack(self)
        self.undo_stack.setUndoLimit(300)
        self.part = "mouth"
        self.drawing = 0
        self.line = -1
        self.head = 0
        self.issues: list[Issue] = []
        self._base_heads: dict = {}  # head file -> the head as loaded/added, before holes were cut
        self._autosave_timer = QTimer(self)
        self._autosave_timer.setSingleShot(True)
        self._autosave_timer.setInterval(autosave_delay_ms)
        self._autosave_timer.timeout.connect(self.autosave_now)
        self._autosave_thread: threading.Thread | None = None
        self._autosave_result: tuple[str, list] | None = None
        self._autosave_poll = QTimer(self)
        self._autosave_poll.setInterval(50)
        self._autosave_poll.timeout.connect(self._collect_autosave)
        self._autosave_again = False
        self._autosave_target: Path | None = None
        self._autosave_written: dict = {}
        self.undo_stack.indexChanged.connect(self._on_stack_changed)
        sweep_temp(_user_autosave_root(), recursive=True)  # what a crash of an earlier session left

    # ------------------------------------------------------------------ documents
    def new_character(
        self,
        name: str,
        heads: Sequence[str | Path],
        eyes: Sequence[str | Path] = (),
        mouths: Sequence[str | Path] = (),
        author: str = "",
        fit: str = "resize",
    ) -> ArtSet:
        """Start a new character from image files (names of drawings come from the file names)."""
        art = ed.new_artset(
            name,
            [ed.load_image(p) for p in heads],
            [(ed.name_from_path(p, "eyes"), ed.load_image(p)) for p in eyes],
            [(ed.name_from_path(p, "mouth"), ed.load_image(p)) for p in mouths],
            author=author,
            fit=fit,
        )
        self._set_document(art, None)
        return art

    def open(self, path: str | Path, recover: bool = False) -> ArtSet:
        """Open the set at ``path`` (its side copy instead when ``recover``); ArtSetError if unreadable."""
        path = Path(path)
        if path.name == "artset.json":
            path = path.parent
        src = autosave_dir_for(path) if recover else path
        art = load_tolerant(src)
        if recover:
            _plain_names(art)
        for pname in art.parts:
            ed.make_consistent(art, pname)
        art.path = path
        self._set_document(art, path)
        if recover:
            self.undo_stack.resetClean()
            self._push_dirty_marker()
            self.message.emit(f"recovered unsaved changes of {path}")
        else:
            self.refresh_problems_from(path)
        return art

    def open_recovered_untitled(self) -> ArtSet:
        """Reopen the side copy of a character that was never saved."""
        art = load_tolerant(autosave_dir_for(None))
        _plain_names(art)
        art.path = None
        self._set_document(art, None)
        self._push_dirty_marker()
        return art

    def _push_dirty_marker(self) -> None:
        # a no-op command so the recovered state counts as unsaved
        cur = ed.clone(self.artset)
        self.undo_stack.push(SnapshotCommand(self, "recover autosave", cur, ed.clone(cur)))

    def _set_document(self, art: ArtSet, path: Path | None) -> None:
        self.artset = art
        self.path = path
        self._base_heads = dict(zip(art.head_files, art.heads))
        self.undo_stack.clear()
        self.part = "mouth" if art.mouth.drawings or not art.eyes.drawings else "eyes"
        self.drawing, self.line, self.head = 0, -1, 0
        self.issues = []
        self._compute_issues([])
        self.changed.emit()
        self.selectionChanged.emit()

    @property
    def dirty(self) -> bool:
        return self.artset is not None and not self.undo_stack.isClean()

    # ------------------------------------------------------------------ selection
    def selection(self) -> tuple[str, int, int, int]:
        return (self.part, self.drawing, self.line, self.head)

    def select(self, part: str | None = None, drawing: int | None = None, line: int | None = None,
               head: int | None = None) -> None:
        if part is not None and part != self.part:
            self.part = part
            if drawing is None:
                drawing = 0
            if line is None:
                line = -1
        if drawing is not None:
            self.drawing = drawing
        if line is not None:
            self.line = line
        if head is not None:
            self.head = head
        self._clamp_selection()
        self.selectionChanged.emit()

    def _clamp_selection(self) -> None:
        if self.artset is None:
            return
        p = self.artset.parts[self.part]
        self.drawing = min(max(self.drawing, 0), max(len(p.drawings) - 1, 0))
        n = ed.line_count(p)
        if self.line >= n:
            self.line = n - 1 if n else -1
        self.head = min(max(self.head, 0), max(len(self.artset.heads) - 1, 0))

    # ------------------------------------------------------------------ undoable edits
    def edit(self, text: str, fn: Callable[[ArtSet], object], select: dict | None = None):
        """Run ``fn(artset)`` as one undoable command; returns what ``fn`` returned.

        ``fn`` mutates the art set through ``art_sets.editing``; an ``EditError`` leaves the
        document unchanged and is re-raised. ``select`` (keys part/drawing/line/head, values may
        be callables of ``fn``'s result) is the selection after the edit.
        """
        if self.artset is None:
            raise ed.EditError("no character is open")
        before = ed.clone(self.artset)
        work = ed.clone(self.artset)
        result = fn(work)
        sel = list(self.selection())
        for k, v in (select or {}).items():
            v = v(result) if callable(v) else v
            sel[("part", "drawing", "line", "head").index(k)] = v
        self.undo_stack.push(SnapshotCommand(self, text, before, work, tuple(sel)))
        return result

    def push_state(self, text: str, before: ArtSet, after: ArtSet) -> None:
        """Record an edit that was already shown live (a drag, a brush stroke)."""
        self.undo_stack.push(SnapshotCommand(self, text, before, ed.clone(after)))

    def _restore(self, state: ArtSet, selection) -> None:
        path = self.artset.path if self.artset is not None else None
        self.artset = ed.clone(state)
        self.artset.path = path
        self.part, self.drawing, self.line, self.head = selection
        self._clamp_selection()
        self.changed.emit()
        self.selectionChanged.emit()

    # convenience wrappers: the actions the window's menus, canvases and tests use
    def add_drawings(self, part: str, paths: Iterable[str | Path], fit: str = "resize") -> list[int]:
        paths = list(paths)
        images = [(ed.name_from_path(p, part), ed.load_image(p)) for p in paths]

        def fn(art):
            return [ed.add_drawing(art, part, n, img, fit) for n, img in images]

        return self.edit(f"add {len(images)} {part} drawing(s)", fn,
                         select={"part": part, "drawing": lambda r: r[0] if r else self.drawing})

    def add_heads(self, paths: Iterable[str | Path], fit: str = "resize") -> list[int]:
        images = [ed.load_image(p) for p in paths]
        added = self.edit(f"add {len(images)} head(s)", lambda art: [ed.add_head(art, im, fit) for im in images],
                          select={"head": lambda r: r[0] if r else self.head})
        for i in added:
            self._base_heads[self.artset.head_files[i]] = self.artset.heads[i]
        return added

    def remove_head(self, index: int) -> None:
        self.edit("remove head", lambda art: ed.remove_head(art, index))

    def remove_drawing(self, part: str, index: int) -> None:
        self.edit(f"remove {part} drawing", lambda art: ed.remove_drawing(art, part, index))

    def rename_drawing(self, part: str, index: int, name: str) -> str:
        return self.edit("rename drawing", lambda art: ed.rename_drawing(art, part, index, name))

    def replace_image(self, part: str, index: int, path: str | Path, fit: str = "resize") -> None:
        img = ed.load_image(path)
        self.edit("replace drawing image", lambda art: ed.replace_drawing_image(art, part, index, img, fit))

    def fit_part(self, part: str, mode: str) -> None:
        self.edit(f"{mode} {part} drawings to the box", lambda art: ed.fit_part(art, part, mode))

    def fit_heads(self, mode: str) -> None:
        self.edit(f"{mode} heads to the canvas", lambda art: ed.fit_heads(art, mode))

    def add_line(self, part: str, drawing: int, line) -> int:
        return self.edit("add line", lambda art: ed.add_line(art, part, drawing, line),
                         select={"part": part, "drawing": drawing, "line": lambda r: r})

    def move_line(self, part: str, drawing: int, index: int, line) -> None:
        self.edit("move line", lambda art: ed.move_line(art, part, drawing, index, line),
                  select={"part": part, "drawing": drawing, "line": index})

    def delete_line(self, part: str, index: int) -> None:
        self.edit("delete line", lambda art: ed.delete_line(art, part, index),
                  select={"line": -1})

    def reverse_line(self, part: str, drawing: int, index: int) -> None:
        self.edit("reverse line", lambda art: ed.swap_direction(art, part, drawing, index))

    def copy_lines(self, part: str, src: int, dst: int) -> None:
        self.edit("copy lines", lambda art: ed.copy_lines(art, part, src, dst),
                  select={"part": part, "drawing": dst})

    def add_starter_lines(self, part: str) -> int:
        """Frame each drawing's ink with starter lines (four per feature) to refine by hand."""
        return self.edit("starter lines", lambda art: ed.add_starter_lines(art, part),
                         select={"part": part, "line": -1})

    def accept_lines(self, part: str, drawing: int, indices=None) -> None:
        self.edit("accept lines", lambda art: ed.mark_placed(art, part, drawing, indices))

    def set_box(self, part: str, box, mode: str = "resize") -> None:
        self.edit(f"set {part} box", lambda art: ed.set_box(art, part, box, mode))

    def set_pivot(self, pivot) -> None:
        def fn(art):
            art.pivot = (float(pivot[0]), float(pivot[1]))
        self.edit("move pivot", fn)

    def make_holes(self, radius: float, base_heads=None) -> None:
        """Cut feathered holes for the part boxes into every head.

        Holes are cut into the heads as they were loaded or added (so moving a box and cutting
        again moves the hole instead of adding a second one); brush strokes made since are redone
        by hand.
        """
        if base_heads is None and self.artset is not None:
            base_heads = [self._base_heads.get(f, h) for f, h in zip(self.artset.head_files, self.artset.heads)]
            base_heads = [b if b.shape == h.shape else h for b, h in zip(base_heads, self.artset.heads)]
        self.edit(f"cut holes (radius {radius:g})", lambda art: ed.make_holes(art, radius, base_heads))

    def paint(self, head: int | None, points, radius: float, erase: bool = True, hardness: float = 0.5) -> None:
        """Paint a brush stroke into one head's alpha (``head=None``: every head)."""
        def fn(art):
            idx = range(len(art.heads)) if head is None else [head]
            for i in idx:
                ed.set_head(art, i, ed.paint_alpha(art.heads[i], points, radius, erase=erase, hardness=hardness))
        self.edit("paint hole" if erase else "paint head", fn)

    def set_info(self, name: str | None = None, author: str | None = None) -> None:
        def fn(art):
            if name is not None:
                art.name = name.strip() or art.name
            if author is not None:
                art.author = author
        self.edit("rename character", fn)

    # ------------------------------------------------------------------ saving
    def save(self, path: str | Path | None = None, runner: Callable | None = None) -> Path:
        """Save atomically (a crash never spoils the previous save); raises ArtSetError/OSError.

        ``runner(fn)`` may run the slow part (writing PNGs, validating) elsewhere, e.g. on a
        thread while the window shows a busy dialog; it must return ``fn()``'s result or raise.
        """
        if self.artset is None:
            raise ed.EditError("no character is open")
        target = Path(path) if path is not None else self.path
        if target is None:
            raise ed.EditError("choose a folder to save the character in")
        if target.name == "artset.json":
            target = target.parent
        self.wait_autosave()
        snapshot = ed.clone(self.artset)

        def work():
            saved = ed.save_safely(snapshot, target)
            try:
                problems = check_folder(target)
            except Exception as e:  # the validator must never lose a save
                problems = [f"validator failed: {' '.join(str(e).split())}"]
            return saved, problems

        saved, problems = runner(work) if runner is not None else work()
        # keep the file names the save chose, without an undo step
        for pname, p in saved.parts.items():
            for d, s in zip(self.artset.parts[pname].drawings, p.drawings):
                d.file = s.file
        for old, new in zip(self.artset.head_files, saved.head_files):
            if old in self._base_heads:
                self._base_heads[new] = self._base_heads[old]
        self.artset.head_files = list(saved.head_files)
        old_side = autosave_dir_for(self.path)
        self.path = target
        self.artset.path = target
        self.undo_stack.setClean()
        self._autosave_timer.stop()
        for side in {old_side, autosave_dir_for(target)}:
            shutil.rmtree(side, ignore_errors=True)
        self._autosave_written = {}
        self._compute_issues(problems, root=target)
        self.message.emit(f"saved {target}")
        return target

    def discard_autosave(self) -> None:
        self.wait_autosave()
        shutil.rmtree(autosave_dir_for(self.path), ignore_errors=True)
        self._autosave_written = {}

    # ------------------------------------------------------------------ autosave
    def _on_stack_changed(self, *_):
        if self.artset is None:
            return
        self._compute_issues(None)
        self._autosave_timer.start()

    def autosave_now(self, wait: bool = False) -> None:
        """Write the side copy on a worker thread (``wait``: block until written)."""
        if self.artset is None:
            return
        if self.undo_stack.isClean() and self.path is not None:
            return
        if self._autosave_thread is not None and self._autosave_thread.is_alive():
            self._autosave_again = True
            if wait:
                self.wait_autosave()
                self.autosave_now(wait=True)
            return
        snapshot = ed.clone(self.artset)
        target = autosave_dir_for(self.path)

        if self._autosave_target != target:
            self._autosave_target, self._autosave_written = target, {}
        written = self._autosave_written

        def work():
            try:
                write_side_copy(snapshot, target, written)
                self._autosave_result = (str(target), check_folder(target))
            except Exception as e:  # reported in the status bar; the next edit retries
                self._autosave_result = ("", [f"autosave failed: {' '.join(str(e).split())}"])

        self._autosave_thread = threading.Thread(target=work, name="editor-autosave", daemon=True)
        self._autosave_thread.start()
        if wait:
            self.wait_autosave()
        else:
            self._autosave_poll.start()

    def wait_autosave(self, timeout: float = 30.0) -> None:
        t = self._autosave_thread
        if t is not None:
            t.join(timeout)
        self._collect_autosave()

    def _collect_autosave(self) -> None:
        t = self._autosave_thread
        if t is not None and t.is_alive():
            return
        self._autosave_poll.stop()
        res, self._autosave_result = self._autosave_result, None
        if res is None:
            return
        where, problems = res
        if not where:
            self.message.emit(problems[0])
            return
        self._compute_issues(problems, root=Path(where))
        self.autosaved.emit(where)
        if self._autosave_again:
            self._autosave_again = False
            self._autosave_timer.start()

    # ------------------------------------------------------------------ problems
    def refresh_problems_from(self, folder: Path) -> None:
        try:
            problems = check_folder(folder)
        except Exception as e:  # the validator must never take the editor down
            problems = []
            self.message.emit(f"validator failed: {e}")
        self._compute_issues(problems, root=Path(folder))

    def _compute_issues(self, problems, root: Path | None = None) -> None:
        """Rebuild the problems list: validator problems (``None``: keep the last ones) + editor to-dos."""
        art = self.artset
        if art is None:
            return
        if problems is not None:
            self._validator_issues = [self._issue_from_problem(p, root) for p in problems]
        todo: list[Issue] = []
        for hi in ed.head_mismatches(art):
            h = art.heads[hi]
            todo.append(Issue("todo", art.head_files[hi] if hi < len(art.head_files) else "",
                              f"head is {h.shape[1]}x{h.shape[0]} but the canvas is {art.canvas[0]}x{art.canvas[1]}: resize or crop it",
                              head=hi))
        for pname, p in art.parts.items():
            for di in ed.size_mismatches(p):
                d = p.drawings[di]
                todo.append(Issue("todo", d.file, f"{d.size[0]}x{d.size[1]} but the {pname} box is {p.size[0]}x{p.size[1]}: resize or crop it", pname, di))
            miss = ed.missing_lines(art, pname)
            for di, d in enumerate(p.drawings):
                idx = [i for i, names in miss.items() if d.name in names]
                if idx:
                    which = f"line {idx[0]}" if len(idx) == 1 else f"lines {', '.join(map(str, idx))}"
                    todo.append(Issue("todo", d.file, f"{pname} {which} not placed yet in {d.name!r} (dashed)", pname, di, idx[0]))
            if not p.drawings:
                todo.append(Issue("todo", "", f"{pname}: add drawings (drop image files on the {pname} list)", pname))
            elif ed.line_count(p) == 0:
                todo.append(Issue("todo", p.drawings[0].file, f"{pname}: draw control lines (drag on the drawing)", pname, 0))
        self.issues = list(getattr(self, "_validator_issues", [])) + todo
        self.problemsChanged.emit()

    def _issue_from_problem(self, prob, root: Path | None) -> Issue:
        if isinstance(prob, str):
            return Issue("error", "", prob)
        if isinstance(prob, Advice):
            m = re.match(r"(eyes|mouth)\b", prob.message)
            return Issue("advice", "", prob.message, part=m.group(1) if m else None)
        file, msg = str(getattr(prob, "file", "")), str(getattr(prob, "message", prob))
        rel = file
        if root is not None:
            try:
                rel = Path(file).resolve().relative_to(root.resolve()).as_posix()
            except (ValueError, OSError):
                rel = Path(file).name
        issue = Issue("error", rel, msg)
        art = self.artset
        if rel in art.head_files:
            issue.head = art.head_files.index(rel)
        m = re.search(r"parts\.(\w+)|\b(eyes|mouth)\b", msg)
        if m:
            issue.part = m.group(1) or m.group(2)
        for pname, p in art.parts.items():
            for di, d in enumerate(p.drawings):
                if d.file == rel or f"drawing {d.name!r}" in msg or f"({d.name})" in msg:
                    if issue.part in (None, pname):
                        issue.part, issue.drawing = pname, di
                        break
            if issue.drawing is not None:
                break
        m = re.search(r"line\(s\) (\d+)", msg)
        if m:
            issue.line = int(m.group(1))
        return issue

    def close(self) -> None:
        self._autosave_timer.stop()
        self.wait_autosave(5.0)
        if not self.dirty:
            self.discard_autosave()
