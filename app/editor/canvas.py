"""The editor's two big canvases.

:class:`LineCanvas` shows one drawing of a part with its control lines: drag on empty paper to
draw a line, drag an end to move it (ends snap to other lines' ends; hold Alt not to snap), drag
the middle to move the whole line, right-click for more. :class:`HeadCanvas` shows the head
over the parts: drag a box to move it, its corners to resize it (the drawings are resampled
once, on release), the cross to move the tilt pivot; in paint mode the brush opens holes in the
head (left button) or closes them (right button).

Both map widget points to image pixels with the same fit-and-centre transform; edits are
committed through the :class:`~app.editor.document.EditorDocument` so each one is undoable.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, QSize, Qt, Signal
from PySide6.QtGui import QColor, QFont, QImage, QPainter, QPen, QTransform
from PySide6.QtWidgets import QMenu, QSizePolicy, QWidget

from art_sets import editing as ed

from .document import EditorDocument
from .imaging import ImageCache, checker_brush, draw_control_line, qcolor_for_line, rgba_to_qimage


class _ImageView(QWidget):
    """Fits an image of ``image_size`` into the widget, centred, and converts coordinates."""

    MARGIN = 18

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setMouseTracking(True)
        self.setFocusPolicy(Qt.StrongFocus)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        self.setMinimumSize(240, 180)
        self._checker = checker_brush()
        self.zoom = 1.0  # on top of the fit; the wheel zooms about the cursor, "0" resets
        self.pan = QPointF(0, 0)  # widget pixels; middle-button drag pans
        self._pan_from = None

    def image_size(self) -> tuple[int, int]:
        return (1, 1)

    def fit_scale(self) -> float:
        w, h = self.image_size()
        s = min((self.width() - 2 * self.MARGIN) / max(w, 1), (self.height() - 2 * self.MARGIN) / max(h, 1))
        return max(min(s, 12.0), 0.05)

    def scale(self) -> float:
        return self.fit_scale() * self.zoom

    def offset(self) -> QPointF:
        w, h = self.image_size()
        s = self.scale()
        return QPointF((self.width() - w * s) / 2, (self.height() - h * s) / 2) + self.pan

    def reset_view(self) -> None:
        self.zoom, self.pan = 1.0, QPointF(0, 0)
        self.update()

    def wheelEvent(self, ev):
        steps = ev.angleDelta().y() / 120.0
        if not steps:
            return
        pos = ev.position()
        before = self.to_image(pos)
        self.zoom = float(min(max(self.zoom * (1.25 ** steps), 1.0), 16.0))
        if self.zoom == 1.0:
            self.pan = QPointF(0, 0)
        else:  # keep the image point under the cursor where it was
            after = self.to_widget(*before)
            self.pan += pos - after
        self.update()

    def _start_pan(self, ev) -> bool:
        if ev.button() == Qt.MiddleButton:
            self._pan_from = (ev.position(), QPointF(self.pan))
            self.setCursor(Qt.ClosedHandCursor)
            return True
        return False

    def _do_pan(self, ev) -> bool:
        if self._pan_from is None:
            return False
        start, pan0 = self._pan_from
        self.pan = pan0 + (ev.position() - start)
        self.update()
        return True

    def _end_pan(self, ev) -> bool:
        if self._pan_from is None or ev.button() != Qt.MiddleButton:
            return False
        self._pan_from = None
        self.setCursor(Qt.ArrowCursor)
        return True

    def to_widget(self, x: float, y: float) -> QPointF:
        o, s = self.offset(), self.scale()
        return QPointF(o.x() + x * s, o.y() + y * s)

    def to_image(self, pt: QPointF) -> tuple[float, float]:
        o, s = self.offset(), self.scale()
        return ((pt.x() - o.x()) / s, (pt.y() - o.y()) / s)

    def image_rect(self) -> QRectF:
        w, h = self.image_size()
        o, s = self.offset(), self.scale()
        return QRectF(o.x(), o.y(), w * s, h * s)

    def sizeHint(self) -> QSize:
        return QSize(640, 480)


class LineCanvas(_ImageView):
    """One drawing of the selected part with its numbered, coloured control lines."""

    SNAP_PX = 9.0  # widget pixels
    HIT_PX = 7.0

    def __init__(self, doc: EditorDocument, parent=None):
        super().__init__(parent)
        self.doc = doc
        self.ghost = -1  # index of a drawing shown faintly underneath (-1: none)
        self.show_other_lines = True
        self._drag = None
        self._live: np.ndarray | None = None
        self._hover = None
        self._image_cache: tuple[int, QImage] | None = None
        self._ghost_cache: tuple[int, QImage] | None = None
        doc.changed.connect(self.update)
        doc.selectionChanged.connect(self.update)
        doc.viewChanged.connect(self.update)

    # ---------------------------------------------------------------- model access
    def _part(self):
        return self.doc.artset.parts[self.doc.part] if self.doc.artset else None

    def _drawing(self):
        p = self._part()
        if p is None or not p.drawings:
            return None
        return p.drawings[min(self.doc.drawing, len(p.drawings) - 1)]

    def image_size(self):
        d = self._drawing()
        return d.size if d is not None else (4, 3)

    def lines(self) -> np.ndarray:
        """The lines being edited: the selected layer's own, else the drawing's."""
        if self._live is not None:
            return self._live
        d = self._drawing()
        return ed.lines_of(d, self.doc.line_layer) if d is not None else np.zeros((0, 4))

    def _qimage(self, arr: np.ndarray, cache_name: str) -> QImage:
        cache = getattr(self, cache_name)
        if cache is None or cache[0] is not arr:
            cache = (arr, rgba_to_qimage(arr))
            setattr(self, cache_name, cache)
        return cache[1]

    def empty_text(self) -> str:
        """What the canvas says when there is no drawing to show."""
        if self.doc.artset is None:
            return ("No character open.\nDrop head images here to start a new one, "
                    "or use File ▸ New character from images or File ▸ Open.")
        noun = "eye" if self.doc.part == "eyes" else self.doc.part
        return (f"No {noun} drawings yet.\nDrop image files here or on the {self.doc.part.capitalize()} list, "
                f"or use Add ▸ {noun.capitalize()} drawings…")

    # ---------------------------------------------------------------- painting
    def paintEvent(self, ev):
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        p.setRenderHint(QPainter.SmoothPixmapTransform, self.scale() < 6.0)
        p.fillRect(self.rect(), QColor(58, 60, 66))
        d = self._drawing()
        if d is None:
            p.setPen(QColor(220, 220, 220))
            p.setFont(QFont(p.font().family(), 12))
            p.drawText(self.rect().adjusted(12, 12, -12, -12), Qt.AlignCenter | Qt.TextWordWrap, self.empty_text())
            return
        r = self.image_rect()
        p.fillRect(r, self._checker)
        part = self._part()
        if 0 <= self.ghost < len(part.drawings) and self.ghost != self.doc.drawing:
            p.setOpacity(0.30)
            p.drawImage(r, self._qimage(self.doc.shown_image(self.doc.part, self.ghost), "_ghost_cache"))
            p.setOpacity(1.0)
            gl = ed.lines_of(part.drawings[self.ghost], self.doc.line_layer)
            for i, ln in enumerate(gl):
                p.setPen(QPen(qcolor_for_line(i, 90), 1.2, Qt.DotLine))
                p.drawLine(self.to_widget(ln[0], ln[1]), self.to_widget(ln[2], ln[3]))
            p.setOpacity(0.75)
        p.drawImage(r, self._qimage(self.doc.shown_image(self.doc.part, min(self.doc.drawing, len(part.drawings) - 1)),
                                    "_image_cache"))
        p.setOpacity(1.0)
        p.setPen(QPen(QColor(30, 30, 30, 160), 1))
        p.setBrush(Qt.NoBrush)
        p.drawRect(r)
        un = ed.unplaced(self.doc.artset, self.doc.part, self.doc.drawing, self.doc.line_layer)
        lines = self.lines()
        order = [i for i in range(len(lines)) if i != self.doc.line] + ([self.doc.line] if 0 <= self.doc.line < len(lines) else [])
        for i in order:
            ln = lines[i]
            draw_control_line(p, self.to_widget(ln[0], ln[1]), self.to_widget(ln[2], ln[3]), i,
                              selected=(i == self.doc.line), unplaced=(i in un), width=2.2)
        if self._drag and self._drag[0] == "new" and self._drag[2] is not None:
            a, b = self._drag[1], self._drag[2]
            draw_control_line(p, self.to_widget(*a), self.to_widget(*b), len(lines), selected=True, width=2.2)
        if self._hover is not None and self._hover[1] >= 0 and self._drag is None and self._hover[0] < len(lines):
            ln = lines[self._hover[0]]
            e = self._hover[1]
            p.setPen(QPen(QColor(255, 255, 255), 2))
            p.setBrush(Qt.NoBrush)
            p.drawEllipse(self.to_widget(ln[2 * e], ln[2 * e + 1]), 8, 8)
        if len(lines) == 0 and self._drag is None:
            p.setPen(QColor(255, 255, 255))
            p.drawText(r.adjusted(0, 0, 0, -8), Qt.AlignHCenter | Qt.AlignBottom,
                       "Drag across a feature (a lip edge, a lid, a brow) to draw control line 0")
        p.setPen(QColor(170, 172, 178))
        p.drawText(QRectF(8, self.height() - 18, self.width() - 16, 16), Qt.AlignLeft | Qt.AlignVCenter,
                   "drag: new line · drag an end or the middle: move · Alt: no snap · right-click: more · "
                   "Del: delete · Tab: next line · [ ]: drawings · wheel: zoom · middle-drag: pan · 0: fit")
        p.setPen(QColor(230, 230, 230))
        nmiss = len(un)
        txt = f"{self.doc.part} ▸ {d.name}"
        if d.layers and 0 <= self.doc.layer < len(d.layers):
            ly = d.layers[self.doc.layer]
            txt += f" ▸ {ly.name}{' (solo)' if self.doc.solo else ''}"
            txt += "   its own lines" if ly.lines is not None else "   the drawing's lines"
        txt += f"   {d.size[0]}×{d.size[1]} px   {len(lines)} line(s)"
        if nmiss:
            txt += f"   —   {nmiss} dashed line(s) still to place"
        p.drawText(QRectF(8, 2, self.width() - 16, 16), Qt.AlignLeft | Qt.AlignVCenter, txt)

    # ---------------------------------------------------------------- mouse
    def _snap(self, pt, exclude=None, snap=True):
        w, h = self.image_size()
        x = min(max(pt[0], 0.0), w - 1.0)
        y = min(max(pt[1], 0.0), h - 1.0)
        if not snap:
            return (x, y)
        lines = self.lines()
        (sx, sy), hit = ed.snap_point((x, y), lines, self.SNAP_PX / self.scale(), exclude=exclude)
        return (sx, sy)

    def mousePressEvent(self, ev):
        if self._start_pan(ev):
            return
        d = self._drawing()
        if d is None or ev.button() not in (Qt.LeftButton, Qt.RightButton):
            return
        pt = self.to_image(ev.position())
        hit = ed.hit_line(pt, self.lines(), self.HIT_PX / self.scale())
        if ev.button() == Qt.RightButton:
            if hit is not None:
                self.doc.select(line=hit[0])
            self._context_menu(ev.globalPosition().toPoint(), hit)
            return
        snap = not (ev.modifiers() & Qt.AltModifier)
        if hit is None:
            self._drag = ["new", self._snap(pt, snap=snap), None]
            self.doc.select(line=-1)
        else:
            i, end = hit
            self.doc.select(line=i)
            self._live = self.lines().copy()
            self._drag = ["end" if end >= 0 else "body", i, end, pt, self._live[i].copy()]
        self.update()

    def mouseMoveEvent(self, ev):
        if self._do_pan(ev):
            return
        pt = self.to_image(ev.position())
        snap = not (ev.modifiers() & Qt.AltModifier)
        if self._drag is None:
            hit = ed.hit_line(pt, self.lines(), self.HIT_PX / self.scale()) if self._drawing() else None
            if hit != self._hover:
                self._hover = hit
                self.setCursor(Qt.PointingHandCursor if hit and hit[1] >= 0 else
                               Qt.SizeAllCursor if hit else Qt.CrossCursor)
                self.update()
            return
        kind = self._drag[0]
        if kind == "new":
            self._drag[2] = self._snap(pt, snap=snap)
        elif kind == "end":
            _, i, end, _, orig = self._drag
            x, y = self._snap(pt, exclude=(i, end), snap=snap)
            self._live[i, 2 * end:2 * end + 2] = (x, y)
        else:
            _, i, _, start, orig = self._drag
            w, h = self.image_size()
            dx, dy = pt[0] - start[0], pt[1] - start[1]
            dx = min(max(dx, -min(orig[0], orig[2])), (w - 1) - max(orig[0], orig[2]))
            dy = min(max(dy, -min(orig[1], orig[3])), (h - 1) - max(orig[1], orig[3]))
            self._live[i] = orig + np.array([dx, dy, dx, dy])
        self.update()

    def mouseReleaseEvent(self, ev):
        if self._end_pan(ev):
            return
        drag, self._drag = self._drag, None
        live, self._live = self._live, None
        if drag is None or ev.button() != Qt.LeftButton:
            self.update()
            return
        part, di = self.doc.part, self.doc.drawing
        try:
            if drag[0] == "new":
                a, b = drag[1], drag[2]
                if b is not None and np.hypot(b[0] - a[0], b[1] - a[1]) * self.scale() >= 4:
                    self.doc.add_line(part, di, [a[0], a[1], b[0], b[1]])
            else:
                i = drag[1]
                if not np.array_equal(live[i], drag[4]):
                    self.doc.move_line(part, di, i, live[i])
        except ed.EditError as e:
            self.doc.message.emit(str(e))
        self.update()

    def keyPressEvent(self, ev):
        k = ev.key()
        if k in (Qt.Key_Delete, Qt.Key_Backspace) and self.doc.line >= 0:
            self.doc.delete_line(self.doc.part, self.doc.line)
        elif k == Qt.Key_Escape:
            self._drag, self._live = None, None
            self.doc.select(line=-1)
        elif k == Qt.Key_0:
            self.reset_view()
        elif k == Qt.Key_Tab or k == Qt.Key_Backtab:
            n = ed.line_count(self._part(), self.doc.line_layer) if self._part() else 0
            if n:
                step = -1 if k == Qt.Key_Backtab else 1
                self.doc.select(line=(self.doc.line + step) % n)
        elif k == Qt.Key_BracketRight or k == Qt.Key_PageDown:
            self.doc.select(drawing=self.doc.drawing + 1)
        elif k == Qt.Key_BracketLeft or k == Qt.Key_PageUp:
            self.doc.select(drawing=max(self.doc.drawing - 1, 0))
        else:
            super().keyPressEvent(ev)

    def focusNextPrevChild(self, nxt):  # keep Tab for cycling lines
        return False

    def _context_menu(self, pos, hit):
        art = self.doc.artset
        part = self._part()
        m = QMenu(self)
        if hit is not None:
            i = hit[0]
            m.addAction(f"Delete line {i} (in every drawing)", lambda: self.doc.delete_line(self.doc.part, i))
            m.addAction(f"Reverse line {i} here", lambda: self.doc.reverse_line(self.doc.part, self.doc.drawing, i))
            if i in ed.unplaced(art, self.doc.part, self.doc.drawing, self.doc.line_layer):
                m.addAction(f"Line {i} is right here: accept it",
                            lambda: self.doc.accept_lines(self.doc.part, self.doc.drawing, [i]))
            m.addSeparator()
        if ed.unplaced(art, self.doc.part, self.doc.drawing, self.doc.line_layer):
            m.addAction("Accept all dashed lines as placed", lambda: self.doc.accept_lines(self.doc.part, self.doc.drawing))
        sub = m.addMenu("Copy all lines from")
        for j, d in enumerate(part.drawings):
            if j != self.doc.drawing:
                sub.addAction(d.name, lambda j=j: self.doc.copy_lines(self.doc.part, j, self.doc.drawing))
        sub.setEnabled(len(part.drawings) > 1)
        m.exec(pos)


class HeadCanvas(_ImageView):
    """The head over the parts: boxes to drag, the tilt pivot, and a brush for the holes."""

    HANDLE_PX = 9.0
    boxesChanged = Signal()

    def __init__(self, doc: EditorDocument, parent=None):
        super().__init__(parent)
        self.doc = doc
        self.mode = "arrange"  # or "paint"
        self.brush_radius = 10.0
        self.brush_hardness = 0.5
        self.paint_all_heads = True
        self.head_only = False
        self.fit_mode = "resize"
        self._drag = None
        self._live_boxes: dict[str, tuple] = {}
        self._live_pivot = None
        self._live_head: np.ndarray | None = None
        self._mouse = None
        self.pose = (0.0, 0.0)  # a test pose (shift right in canvas px, tilt in degrees) to see the body stay
        self._images = ImageCache(rgba_to_qimage, limit=48)
        doc.changed.connect(self._invalidate)
        doc.selectionChanged.connect(self._invalidate)

    def image_size(self):
        return tuple(self.doc.artset.canvas) if self.doc.artset else (4, 3)

    def _invalidate(self):
        self.update()

    def _boxes(self) -> dict[str, tuple]:
        art = self.doc.artset
        out = {k: tuple(p.box) for k, p in art.parts.items()}
        out.update(self._live_boxes)
        return out

    def set_pose(self, shift: float, tilt: float) -> None:
        """Show the character moved ``shift`` px right and tilted ``tilt`` degrees (counter-clockwise,
        as the renderer turns it): the head turns about the pivot, the body follows as set."""
        self.pose = (float(shift), float(tilt))
        self.update()

    def _pose_transforms(self, r: QRectF) -> tuple[QTransform, QTransform]:
        """Canvas-pixel → widget transforms of the head (with its parts) and of the body for ``pose``."""
        art = self.doc.artset
        s = self.scale()
        shift, tilt = self.pose

        def about(pivot, deg, dx):
            t = QTransform()
            t.translate(r.left(), r.top())
            t.scale(s, s)
            t.translate(pivot[0] + dx, pivot[1])
            t.rotate(-deg)  # QPainter turns clockwise on a y-down screen; a positive roll turns counter-clockwise
            t.translate(-pivot[0], -pivot[1])
            return t

        body = art.body
        head_t = about(art.pivot, tilt, shift)
        if body is None:
            return head_t, head_t
        bp = body.pivot if body.pivot is not None else art.pivot
        return head_t, about(bp, tilt * body.roll, shift * body.follow)

    def _draw_composite(self, p: QPainter, r: QRectF) -> None:
        """The body, the parts (the selected drawing for the selected part, the first for the
        other) at their boxes, then the head over them — or the head alone. With a test pose the
        head and parts turn about the pivot and the body moves as its follow and roll say."""
        art = self.doc.artset
        head = self._live_head if self._live_head is not None else art.heads[self.doc.head % len(art.heads)]
        s = self.scale()
        head_t, body_t = self._pose_transforms(r)
        if not self.head_only:
            p.fillRect(r, QColor(250, 248, 242))
            if art.body is not None:
                p.save()
                p.setClipRect(r)
                p.setTransform(body_t)
                w, h = art.canvas
                img = self._images.get(art.body.image)
                steps = (-1, 0, 1) if self.pose != (0.0, 0.0) else (0,)
                for ty in steps:  # mirrored out on every side, as the renderer continues a moved body
                    for tx in steps:
                        tile = img if (tx, ty) == (0, 0) else img.mirrored(tx != 0, ty != 0)
                        p.drawImage(QRectF(tx * w, ty * h, w, h), tile)
                p.restore()
            p.save()
            if self.pose != (0.0, 0.0):
                p.setClipRect(r)
                p.setTransform(head_t)
                r_parts, s_parts = QRectF(0, 0, *art.canvas), 1.0
            else:
                r_parts, s_parts = r, s
            for name, part in art.parts.items():
                if not part.drawings:
                    continue
                i = min(self.doc.drawing, len(part.drawings) - 1) if name == self.doc.part else 0
                img = part.drawings[i].image
                x, y = part.box[0], part.box[1]
                p.drawImage(QRectF(r_parts.left() + x * s_parts, r_parts.top() + y * s_parts,
                                   img.shape[1] * s_parts, img.shape[0] * s_parts), self._images.get(img))
            head_img = self._images.get(head) if head is not self._live_head else rgba_to_qimage(head)
            p.drawImage(r_parts, head_img)
            p.restore()
            return
        p.drawImage(r, self._images.get(head) if head is not self._live_head else rgba_to_qimage(head))

    def paintEvent(self, ev):
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        p.setRenderHint(QPainter.SmoothPixmapTransform)
        p.fillRect(self.rect(), QColor(58, 60, 66))
        art = self.doc.artset
        if art is None:
            p.setPen(QColor(220, 220, 220))
            p.drawText(self.rect(), Qt.AlignCenter, "Open a character or make a new one (File menu).")
            return
        r = self.image_rect()
        p.fillRect(r, self._checker)
        self._draw_composite(p, r)
        for name, box in self._boxes().items():
            x, y, w, h = box
            tl, br = self.to_widget(x, y), self.to_widget(x + w, y + h)
            rect = QRectF(tl, br)
            selected = name == self.doc.part
            col = QColor(40, 140, 255) if name == "eyes" else QColor(240, 90, 60)
            p.setBrush(Qt.NoBrush)
            p.setPen(QPen(col, 2.5 if selected else 1.5, Qt.SolidLine if selected else Qt.DashLine))
            p.drawRect(rect)
            if self.mode == "arrange":
                p.setPen(QPen(QColor(255, 255, 255), 1))
                p.setBrush(col)
                for c in (rect.topLeft(), rect.topRight(), rect.bottomLeft(), rect.bottomRight()):
                    p.drawRect(QRectF(c.x() - 4.5, c.y() - 4.5, 9, 9))
            label = f"{name}  {w}×{h}"
            fm = p.fontMetrics()
            lr = QRectF(rect.left(), rect.top() - fm.height() - 4, fm.horizontalAdvance(label) + 10, fm.height() + 2)
            p.setPen(Qt.NoPen)
            p.setBrush(col)
            p.drawRoundedRect(lr, 3, 3)
            p.setPen(QColor(255, 255, 255))
            p.drawText(lr, Qt.AlignCenter, label)
        px, py = self._live_pivot or art.pivot
        c = self.to_widget(px, py)
        p.setPen(QPen(QColor(30, 160, 90), 2))
        p.setBrush(Qt.NoBrush)
        p.drawEllipse(c, 7, 7)
        p.drawLine(QPointF(c.x() - 12, c.y()), QPointF(c.x() + 12, c.y()))
        p.drawLine(QPointF(c.x(), c.y() - 12), QPointF(c.x(), c.y() + 12))
        if self.mode == "paint" and self._mouse is not None:
            rad = self.brush_radius * self.scale()
            p.setPen(QPen(QColor(255, 255, 255), 1.5))
            p.drawEllipse(self._mouse, rad, rad)
            p.setPen(QPen(QColor(0, 0, 0), 1, Qt.DotLine))
            p.drawEllipse(self._mouse, rad, rad)
        p.setPen(QColor(230, 230, 230))
        hint = ("drag boxes to move, corners to resize, the green cross to set the tilt pivot"
                if self.mode == "arrange" else "left button opens a hole, right button closes it")
        p.drawText(QRectF(8, 2, self.width() - 16, 16), Qt.AlignLeft | Qt.AlignVCenter,
                   f"head {self.doc.head + 1}/{len(art.heads)}   {art.canvas[0]}×{art.canvas[1]}   —   {hint}")

    def _hit(self, wpt: QPointF):
        art = self.doc.artset
        c = self.to_widget(*art.pivot)
        if (c - wpt).manhattanLength() < 14:
            return ("pivot", None, None)
        order = [self.doc.part] + [k for k in art.parts if k != self.doc.part]
        for name in order:
            x, y, w, h = art.parts[name].box
            corners = {(0, 0): (x, y), (1, 0): (x + w, y), (0, 1): (x, y + h), (1, 1): (x + w, y + h)}
            for key, (cx, cy) in corners.items():
                if (self.to_widget(cx, cy) - wpt).manhattanLength() < self.HANDLE_PX * 1.5:
                    return ("corner", name, key)
        ix, iy = self.to_image(wpt)
        for name in order:
            x, y, w, h = art.parts[name].box
            if x <= ix <= x + w and y <= iy <= y + h:
                return ("move", name, None)
        return None

    def mousePressEvent(self, ev):
        art = self.doc.artset
        if art is None or self._start_pan(ev):
            return
        pt = self.to_image(ev.position())
        if self.mode == "paint":
            if ev.button() in (Qt.LeftButton, Qt.RightButton):
                erase = ev.button() == Qt.LeftButton
                base = art.heads[self.doc.head]
                self._drag = ["paint", erase, [pt], base]
                self._live_head = ed.paint_alpha(base, [pt], self.brush_radius, erase=erase, hardness=self.brush_hardness)
                self.update()
            return
        if ev.button() != Qt.LeftButton:
            return
        hit = self._hit(ev.position())
        if hit is None:
            return
        kind, name, key = hit
        if name is not None and name != self.doc.part:
            self.doc.select(part=name)
        box = art.parts[name].box if name else None
        self._drag = [kind, name, key, pt, box]

    def mouseMoveEvent(self, ev):
        self._mouse = ev.position()
        art = self.doc.artset
        if art is None or self._do_pan(ev):
            return
        pt = self.to_image(ev.position())
        if self._drag is None:
            if self.mode == "arrange":
                hit = self._hit(ev.position())
                cur = Qt.ArrowCursor
                if hit:
                    cur = {"pivot": Qt.CrossCursor, "move": Qt.SizeAllCursor}.get(hit[0], Qt.SizeFDiagCursor)
                    if hit[0] == "corner" and hit[2] in ((1, 0), (0, 1)):
                        cur = Qt.SizeBDiagCursor
                self.setCursor(cur)
            else:
                self.setCursor(Qt.BlankCursor)
            self.update()
            return
        kind = self._drag[0]
        if kind == "paint":
            _, erase, pts, base = self._drag
            pts.append(pt)
            self._live_head = ed.paint_alpha(base, pts, self.brush_radius, erase=erase, hardness=self.brush_hardness)
        elif kind == "pivot":
            w, h = art.canvas
            self._live_pivot = (min(max(pt[0], 0), w), min(max(pt[1], 0), h))
        else:
            _, name, key, start, (x, y, w, h) = self._drag
            dx, dy = pt[0] - start[0], pt[1] - start[1]
            if kind == "move":
                nb = (x + dx, y + dy, w, h)
            else:
                x0, y0, x1, y1 = x, y, x + w, y + h
                if key[0] == 0:
                    x0 = min(x0 + dx, x1 - 8)
                else:
                    x1 = max(x1 + dx, x0 + 8)
                if key[1] == 0:
                    y0 = min(y0 + dy, y1 - 8)
                else:
                    y1 = max(y1 + dy, y0 + 8)
                nb = (x0, y0, x1 - x0, y1 - y0)
            cw, ch = art.canvas
            bw, bh = int(round(min(nb[2], cw))), int(round(min(nb[3], ch)))
            bx = int(round(min(max(nb[0], 0), cw - bw)))
            by = int(round(min(max(nb[1], 0), ch - bh)))
            self._live_boxes = {name: (bx, by, bw, bh)}
        self.update()

    def mouseReleaseEvent(self, ev):
        if self._end_pan(ev):
            return
        drag, self._drag = self._drag, None
        live_boxes, self._live_boxes = self._live_boxes, {}
        live_pivot, self._live_pivot = self._live_pivot, None
        self._live_head = None
        if drag is None:
            return
        kind = drag[0]
        try:
            if kind == "paint":
                self.doc.paint(None if self.paint_all_heads else self.doc.head, drag[2], self.brush_radius,
                               erase=drag[1], hardness=self.brush_hardness)
            elif kind == "pivot" and live_pivot is not None:
                self.doc.set_pivot(live_pivot)
            elif kind in ("move", "corner") and live_boxes:
                name = drag[1]
                if tuple(live_boxes[name]) != tuple(self.doc.artset.parts[name].box):
                    self.doc.set_box(name, live_boxes[name], self.fit_mode)
                    self.boxesChanged.emit()
        except ed.EditError as e:
            self.doc.message.emit(str(e))
        self._invalidate()

    def leaveEvent(self, ev):
        self._mouse = None
        self.update()

    def keyPressEvent(self, ev):
        if ev.key() == Qt.Key_0:
            self.reset_view()
        else:
            super().keyPressEvent(ev)
