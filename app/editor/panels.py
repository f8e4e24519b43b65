"""Side panels of the editor: the character's image lists, the part strip, lines and problems."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtCore import QPointF, QRectF, QSize, Qt, Signal
from PySide6.QtGui import QColor, QIcon, QPainter, QPen, QPixmap
from PySide6.QtWidgets import QListWidget, QListWidgetItem, QSizePolicy, QWidget

from art_sets import editing as ed

from app.views import ACCENT, BAD, OK_GREEN, WARN

from .document import EditorDocument
from .imaging import ImageCache, checker_brush, draw_control_line, qcolor_for_line, rgba_to_qimage

CAPTION_H = 16  # px above each drawing of the part strip for its caption


def _notes(missing: int, line: int | None) -> list[str]:
    """The "to place" note of a caption, longest first."""
    if line is not None:
        return [f" — line {line} to place", f" · line {line}", f" · {line}"]
    if missing:
        return [f" — {missing} to place", f" · {missing} to place", f" · {missing}"]
    return [""]


def strip_caption(fm, name: str, missing: int, width: float, line: int | None = None, level: int = 0) -> str:
    """A part-strip caption that fits ``width`` px in font metrics ``fm``: the drawing's name and,
    when lines are still to place, how many (or which one, ``line``), in the ``level``-th
    shortest form that fits; the name is shortened ("ne…") only when even the shortest note
    leaves it no room. So captions of neighbouring drawings never overlap."""
    notes = _notes(missing, line)
    width = int(width) - 1  # elidedText may come out a pixel wider than asked
    for note in notes[min(level, len(notes) - 1):]:
        rest = width - fm.horizontalAdvance(note)
        if fm.horizontalAdvance(name) <= rest:
            return name + note
    note = notes[-1]
    rest = width - fm.horizontalAdvance(note)
    if rest >= fm.horizontalAdvance(name[:2] + "…"):
        return fm.elidedText(name, Qt.ElideRight, rest) + note
    return fm.elidedText(name + note, Qt.ElideRight, width)


def _fits(fm, name: str, missing: int, width: float, line: int | None, level: int) -> bool:
    notes = _notes(missing, line)
    return fm.horizontalAdvance(name + notes[min(level, len(notes) - 1)]) <= int(width) - 1


def dropped_paths(mime) -> list[Path]:
    return [Path(u.toLocalFile()) for u in mime.urls() if u.isLocalFile()] if mime.hasUrls() else []


def image_paths(paths) -> list[Path]:
    """Image files among ``paths`` (folders are searched one level deep), sorted by name."""
    out = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            out += sorted(q for q in p.iterdir() if q.suffix.lower() in ed.IMAGE_SUFFIXES)
        elif p.suffix.lower() in ed.IMAGE_SUFFIXES:
            out.append(p)
    return out


_ICONS: dict[int, ImageCache] = {}


def cached_icon(rgba: np.ndarray, size: int = 56) -> QIcon:
    """:func:`thumb_icon`, made once per array."""
    cache = _ICONS.setdefault(size, ImageCache(lambda a: thumb_icon(a, size), limit=128))
    return cache.get(rgba)


def thumb_icon(rgba: np.ndarray, size: int = 56) -> QIcon:
    img = rgba_to_qimage(rgba).scaled(size, size, Qt.KeepAspectRatio, Qt.SmoothTransformation)
    pm = QPixmap(size, size)
    pm.fill(Qt.transparent)
    p = QPainter(pm)
    p.fillRect(pm.rect(), checker_brush(4))
    p.drawImage((size - img.width()) // 2, (size - img.height()) // 2, img)
    p.end()
    return QIcon(pm)


class DropList(QListWidget):
    """A list of thumbnails that accepts image files dropped on it."""

    filesDropped = Signal(list)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setAcceptDrops(True)
        self.setIconSize(QSize(48, 48))
        self.setDragDropMode(QListWidget.DropOnly)
        self.setSizePolicy(QSizePolicy.Preferred, QSizePolicy.Expanding)

    def dragEnterEvent(self, ev):
        if image_paths(dropped_paths(ev.mimeData())):
            ev.acceptProposedAction()
        else:
            ev.ignore()

    def dragMoveEvent(self, ev):
        self.dragEnterEvent(ev)

    def dropEvent(self, ev):
        paths = image_paths(dropped_paths(ev.mimeData()))
        if paths:
            ev.acceptProposedAction()
            self.filesDropped.emit(paths)


class PartStrip(QWidget):
    """Every drawing of the selected part side by side with its lines; the selected line is
    highlighted in all of them and drawings still missing it get a red mark. Click to pick one."""

    drawingClicked = Signal(int)

    def __init__(self, doc: EditorDocument, parent=None):
        super().__init__(parent)
        self.doc = doc
        self.setMinimumHeight(96)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Preferred)
        self._cache: dict[int, tuple] = {}
        self._checker = checker_brush(4)
        doc.changed.connect(self.update)
        doc.selectionChanged.connect(self.update)
        doc.viewChanged.connect(self.update)

    def sizeHint(self):
        return QSize(600, 120)

    def _cells(self):
        art = self.doc.artset
        if art is None:
            return []
        part = art.parts[self.doc.part]
        n = len(part.drawings)
        if n == 0:
            return []
        w, h = part.size
        cw = self.cell_width()
        s = min((cw - 8) / w, (self.height() - CAPTION_H - 8) / h)
        out = []
        for i in range(n):
            x = 4 + i * cw + (cw - w * s) / 2
            out.append((i, QRectF(x, CAPTION_H + 2, w * s, h * s), s))
        return out

    def cell_width(self) -> float:
        """Width of each drawing's cell (its caption never runs past it)."""
        art = self.doc.artset
        n = len(art.parts[self.doc.part].drawings) if art is not None else 0
        return min((self.width() - 8) / max(n, 1), 260)

    def captions(self) -> list[tuple[str, QRectF]]:
        """Each drawing's caption as painted, and the rectangle it is painted in."""
        art = self.doc.artset
        if art is None:
            return []
        part = art.parts[self.doc.part]
        miss = ed.missing_lines(art, self.doc.part, self.doc.line_layer)
        fm = self.fontMetrics()
        cw = self.cell_width()
        rows = []
        for i, _r, _s in self._cells():
            d = part.drawings[i]
            missing = [k for k, names in miss.items() if d.name in names]
            line = self.doc.line if self.doc.line >= 0 and d.name in miss.get(self.doc.line, []) else None
            rows.append((d.name, len(missing), line, QRectF(4 + i * cw + 2, 1, cw - 4, CAPTION_H)))
        # one form of the note for every drawing (the longest that fits them all), so they read alike
        level = next((lv for lv in range(3) if all(_fits(fm, n, m, b.width(), ln, lv) for n, m, ln, b in rows)), 2)
        return [(strip_caption(fm, n, m, b.width(), ln, level), b) for n, m, ln, b in rows]

    def _qimage(self, arr):
        hit = self._cache.get(id(arr))
        if hit is None or hit[0] is not arr:  # the array itself is kept, so an id is never reused
            if len(self._cache) > 64:
                self._cache.clear()
            hit = self._cache[id(arr)] = (arr, rgba_to_qimage(arr))
        return hit[1]

    def paintEvent(self, ev):
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        p.setRenderHint(QPainter.SmoothPixmapTransform)
        p.fillRect(self.rect(), QColor(48, 50, 55))
        art = self.doc.artset
        if art is None:
            return
        part = art.parts[self.doc.part]
        miss = ed.missing_lines(art, self.doc.part, self.doc.line_layer)
        captions = self.captions()
        for i, r, s in self._cells():
            d = part.drawings[i]
            p.fillRect(r, self._checker)
            p.drawImage(r, self._qimage(self.doc.shown_image(self.doc.part, i)))
            sel = i == self.doc.drawing
            p.setPen(QPen(QColor(255, 200, 40) if sel else QColor(20, 20, 20), 3 if sel else 1))
            p.setBrush(Qt.NoBrush)
            p.drawRect(r.adjusted(-1, -1, 1, 1))
            un = ed.unplaced(art, self.doc.part, i, self.doc.line_layer)
            for k, ln in enumerate(ed.lines_of(d, self.doc.line_layer)):
                a = QPointF(r.left() + ln[0] * s, r.top() + ln[1] * s)
                b = QPointF(r.left() + ln[2] * s, r.top() + ln[3] * s)
                if self.doc.line >= 0 and k != self.doc.line:
                    p.setOpacity(0.35)
                draw_control_line(p, a, b, k, selected=(k == self.doc.line), unplaced=(k in un), width=1.2,
                                  label=False, handles=False)
                p.setOpacity(1.0)
            missing_here = [k for k, names in miss.items() if d.name in names]
            cap, box = captions[i]
            p.setPen(BAD if missing_here else QColor(225, 225, 225))
            p.drawText(box, Qt.AlignCenter, cap)

    def mousePressEvent(self, ev):
        for i, r, _ in self._cells():
            if r.adjusted(-4, -CAPTION_H - 2, 4, 4).contains(ev.position()):
                self.drawingClicked.emit(i)
                return


class LinesList(QListWidget):
    """One row per control line of the part: its colour and number, and where it is missing."""

    def __init__(self, doc: EditorDocument, parent=None):
        super().__init__(parent)
        self.doc = doc
        self._filling = False
        doc.changed.connect(self.refill)
        doc.selectionChanged.connect(self.refill)
        self.currentRowChanged.connect(self._picked)

    def refill(self):
        self._filling = True
        try:
            self.clear()
            art = self.doc.artset
            if art is None:
                return
            miss = ed.missing_lines(art, self.doc.part, self.doc.line_layer)
            for i, names in miss.items():
                pm = QPixmap(14, 14)
                pm.fill(qcolor_for_line(i))
                txt = f"line {i}: " + (f"to place in {', '.join(names)}" if names else "placed in every drawing")
                it = QListWidgetItem(QIcon(pm), txt)
                if names:
                    it.setForeground(BAD)
                self.addItem(it)
            if 0 <= self.doc.line < self.count():
                self.setCurrentRow(self.doc.line)
        finally:
            self._filling = False

    def _picked(self, row):
        if not self._filling and row >= 0:
            self.doc.select(line=row)


class ProblemsList(QListWidget):
    """The validator's problems and the editor's to-dos; clicking one selects what it is about."""

    issueActivated = Signal(object)  # the Issue clicked, after the selection moved to it

    def __init__(self, doc: EditorDocument, parent=None):
        super().__init__(parent)
        self.doc = doc
        doc.problemsChanged.connect(self.refill)
        self.itemClicked.connect(self._clicked)
        self.itemActivated.connect(self._clicked)

    def refill(self):
        self.clear()
        if not any(i.severity != "advice" for i in self.doc.issues):
            it = QListWidgetItem("✓ no problems: the validator accepts this character")
            it.setForeground(OK_GREEN)
            self.addItem(it)
        marks = {"error": ("✗", BAD), "todo": ("•", WARN), "advice": ("ⓘ", ACCENT)}
        for k, issue in enumerate(self.doc.issues):
            mark, col = marks.get(issue.severity, marks["todo"])
            it = QListWidgetItem(f"{mark} {issue.text()}")
            it.setData(Qt.UserRole, k)
            it.setForeground(col)
            self.addItem(it)

    def _clicked(self, item):
        k = item.data(Qt.UserRole)
        if k is None or k >= len(self.doc.issues):
            return
        issue = self.doc.issues[k]
        if issue.part or issue.head is not None:
            self.doc.select(part=issue.part, drawing=issue.drawing, line=issue.line, head=issue.head, layer=issue.layer)
        self.issueActivated.emit(issue)
