"""numpy ⇄ Qt image helpers and small painting helpers shared by the editor's widgets."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QBrush, QColor, QImage, QPainter, QPen, QPixmap, QPolygonF

from art_sets.editing import line_color


def rgba_to_qimage(rgba: np.ndarray, premultiplied: bool = False) -> QImage:
    """An owned QImage of an RGBA uint8 ``(h, w, 4)`` array (straight alpha unless ``premultiplied``)."""
    a = np.ascontiguousarray(rgba, dtype=np.uint8)
    h, w = a.shape[:2]
    fmt = QImage.Format.Format_RGBA8888_Premultiplied if premultiplied else QImage.Format.Format_RGBA8888
    return QImage(a.data, w, h, int(a.strides[0]), fmt).copy()


class ImageCache:
    """QImages (or icons) made from numpy arrays, found again by the array's identity.

    The model never changes an array in place, so an array seen before gives the same picture.
    The arrays are kept referenced, so an id is never reused while its entry lives.
    """

    def __init__(self, make, limit: int = 96):
        self.make, self.limit = make, limit
        self._items: dict[int, tuple[np.ndarray, object]] = {}

    def get(self, arr: np.ndarray):
        hit = self._items.get(id(arr))
        if hit is None or hit[0] is not arr:
            if len(self._items) >= self.limit:
                self._items.pop(next(iter(self._items)))
            hit = self._items[id(arr)] = (arr, self.make(arr))
        return hit[1]


def bgr_to_qimage(bgr: np.ndarray) -> QImage:
    a = np.ascontiguousarray(bgr, dtype=np.uint8)
    h, w = a.shape[:2]
    return QImage(a.data, w, h, int(a.strides[0]), QImage.Format.Format_BGR888).copy()


def checker_brush(size: int = 8) -> QBrush:
    """A light grey checkerboard that shows where an image is transparent."""
    pm = QPixmap(size * 2, size * 2)
    pm.fill(QColor(236, 236, 236))
    p = QPainter(pm)
    p.fillRect(0, 0, size, size, QColor(214, 214, 214))
    p.fillRect(size, size, size, size, QColor(214, 214, 214))
    p.end()
    return QBrush(pm)


def qcolor_for_line(i: int, alpha: int = 255) -> QColor:
    r, g, b = line_color(i)
    return QColor(r, g, b, alpha)


def draw_control_line(
    p: QPainter,
    a: QPointF,
    b: QPointF,
    index: int,
    *,
    selected: bool = False,
    unplaced: bool = False,
    width: float = 2.0,
    label: bool = True,
    handles: bool = True,
) -> None:
    """Paint one control line: coloured by index, arrow head at its end, number at its middle.

    Unplaced lines (copied in, not yet moved onto their feature) are dashed; the selected line has
    a white halo so it stands out on dark ink.
    """
    col = qcolor_for_line(index)
    w = width * (1.8 if selected else 1.0)
    if selected:
        p.setPen(QPen(QColor(255, 255, 255, 230), w + 4, Qt.SolidLine, Qt.RoundCap))
        p.drawLine(a, b)
    pen = QPen(col, w, Qt.DashLine if unplaced else Qt.SolidLine, Qt.RoundCap)
    p.setPen(pen)
    p.drawLine(a, b)
    d = b - a
    n = (d.x() ** 2 + d.y() ** 2) ** 0.5
    if n > 1e-6:
        ux, uy = d.x() / n, d.y() / n
        s = 5.0 + w * 1.5
        tip = b
        left = QPointF(tip.x() - ux * s - uy * s * 0.55, tip.y() - uy * s + ux * s * 0.55)
        right = QPointF(tip.x() - ux * s + uy * s * 0.55, tip.y() - uy * s - ux * s * 0.55)
        p.setPen(Qt.NoPen)
        p.setBrush(col)
        p.drawPolygon(QPolygonF([tip, left, right]))
    if handles:
        r = 3.5 if not selected else 5.0
        p.setPen(QPen(QColor(255, 255, 255), 1.2))
        p.setBrush(col)
        p.drawEllipse(a, r, r)
        p.setBrush(QColor(255, 255, 255))
        p.setPen(QPen(col, 2.0))
        p.drawEllipse(b, r * 0.8, r * 0.8)
    if label:
        mid = (a + b) / 2
        txt = str(index)
        fm = p.fontMetrics()
        tw, th = fm.horizontalAdvance(txt) + 6, fm.height()
        rect = QRectF(mid.x() - tw / 2 + 8, mid.y() - th / 2 - 8, tw, th)
        p.setPen(Qt.NoPen)
        p.setBrush(QColor(255, 255, 255, 220))
        p.drawRoundedRect(rect, 3, 3)
        p.setPen(col.darker(140))
        p.drawText(rect, Qt.AlignCenter, txt)
