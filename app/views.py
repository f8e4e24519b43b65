"""The window's picture widgets: the video with the tracker's overlay, the character, the
strip of character thumbnails, and the shared dark palette.

All painting is QPainter over QImages made by the worker threads; nothing here touches
tracking or rendering.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import app.qt_env  # noqa: F401  (before Qt: platform plugin, PySide6 refcount guard)
from PySide6.QtCore import QPointF, QRectF, QSize, Qt, QVariantAnimation, Signal
from PySide6.QtGui import QBrush, QColor, QFont, QIcon, QImage, QPainter, QPainterPath, QPalette, QPen, QPixmap, QPolygonF
from PySide6.QtWidgets import QApplication, QListWidget, QListWidgetItem, QWidget

from app.workers import Hook

# ------------------------------------------------------------------------------------------
# look

ACCENT = QColor("#7aa2f7")
OK_GREEN = QColor("#9ece6a")
WARN = QColor("#e0af68")
BAD = QColor("#f7768e")
STATUS_COLOURS = {"ok": OK_GREEN, "eyes_closed": WARN, "mouth_lost": WARN, "lost": BAD, "starting": ACCENT}
STATUS_TIP = ("The badge says what the tracker sees in this frame:\n"
              "ok — both eyes and the mouth are tracked\n"
              "eyes closed — the eyes are shut (the character blinks)\n"
              "mouth lost — the mouth could not be found; the last mouth is held\n"
              "lost — no face; the character holds its pose, then relaxes\n"
              "starting — not tracking yet: the character is loading, there is no calibration yet, or the face "
              "has not been found since the source or the character changed")

STYLE_SHEET = """
QWidget { font-size: 10pt; }
QMainWindow, QDialog { background: #1e1f22; }
QGroupBox { border: 1px solid #34363c; border-radius: 8px; margin-top: 14px; padding: 10px 8px 8px 8px; }
QGroupBox::title { subcontrol-origin: margin; left: 10px; padding: 0 4px; color: #9aa0aa; }
QPushButton, QToolButton { background: #2f3136; border: 1px solid #3c3f45; border-radius: 6px; padding: 5px 12px; color: #e6e6e6; }
QPushButton:hover, QToolButton:hover { background: #383b41; }
QPushButton:pressed, QToolButton:pressed { background: #44474e; }
QPushButton:checked { background: #3d4a66; border-color: #7aa2f7; }
QPushButton#primary { background: #3b5bdb; border-color: #4c6ef5; color: white; }
QPushButton#primary:hover { background: #4c6ef5; }
QPushButton:disabled { color: #6b6f76; }
QComboBox, QSpinBox, QDoubleSpinBox, QLineEdit { background: #2a2c31; border: 1px solid #3c3f45; border-radius: 6px; padding: 4px 8px; color: #e6e6e6; }
QComboBox::drop-down { border: none; width: 18px; }
QSpinBox::up-button, QSpinBox::down-button { width: 16px; border: none; background: transparent; }
QSpinBox::up-arrow { image: none; border-left: 4px solid transparent; border-right: 4px solid transparent; border-bottom: 5px solid #aab0ba; width: 0; height: 0; }
QSpinBox::down-arrow { image: none; border-left: 4px solid transparent; border-right: 4px solid transparent; border-top: 5px solid #aab0ba; width: 0; height: 0; }
QComboBox QAbstractItemView { background: #2a2c31; selection-background-color: #3d4a66; }
QSlider::groove:horizontal { height: 4px; background: #3a3d43; border-radius: 2px; }
QSlider::sub-page:horizontal { background: #7aa2f7; border-radius: 2px; }
QSlider::handle:horizontal { background: #e6e6e6; width: 14px; margin: -6px 0; border-radius: 7px; }
QListWidget { background: #232428; border: 1px solid #303237; border-radius: 8px; padding: 4px; }
QListWidget::item { border-radius: 8px; padding: 4px; color: #cfd2d8; }
QListWidget::item:selected { background: #3d4a66; color: white; }
QListWidget::item:hover { background: #2c2f35; }
QStatusBar { background: #191a1d; color: #9aa0aa; }
QStatusBar QLabel { color: #9aa0aa; padding: 0 6px; }
QMenuBar { background: #1e1f22; color: #d8dadf; }
QMenuBar::item:selected { background: #2f3136; }
QMenu { background: #26272b; color: #e6e6e6; border: 1px solid #3a3c42; }
QMenu::item:selected { background: #3d4a66; }
QLabel#hint { color: #9aa0aa; }
QLabel#title { font-size: 13pt; font-weight: 600; color: #f0f0f0; }
QLabel#prompt { font-size: 12pt; color: #f0f0f0; background: #2b3550; border-radius: 8px; padding: 8px 12px; }
QCheckBox { color: #d8dadf; spacing: 6px; }
QTabWidget::pane { border: 1px solid #303237; border-radius: 8px; }
QTabBar::tab { background: #26272b; color: #aab0ba; padding: 6px 14px; border-top-left-radius: 6px; border-top-right-radius: 6px; }
QTabBar::tab:selected { background: #33363c; color: #ffffff; }
QProgressBar { background: #2a2c31; border: 1px solid #3c3f45; border-radius: 6px; text-align: center; color: #e6e6e6; }
QProgressBar::chunk { background: #7aa2f7; border-radius: 5px; }
QScrollArea { border: none; }
"""


def apply_theme(app: QApplication) -> None:
    """Dark neutral Fusion palette plus the small style sheet above."""
    app.setStyle("Fusion")
    pal = QPalette()
    c = {
        QPalette.ColorRole.Window: "#1e1f22",
        QPalette.ColorRole.WindowText: "#e6e6e6",
        QPalette.ColorRole.Base: "#2a2c31",
        QPalette.ColorRole.AlternateBase: "#26272b",
        QPalette.ColorRole.ToolTipBase: "#2f3136",
        QPalette.ColorRole.ToolTipText: "#e6e6e6",
        QPalette.ColorRole.Text: "#e6e6e6",
        QPalette.ColorRole.Button: "#2f3136",
        QPalette.ColorRole.ButtonText: "#e6e6e6",
        QPalette.ColorRole.BrightText: "#ffffff",
        QPalette.ColorRole.Highlight: "#3d4a66",
        QPalette.ColorRole.HighlightedText: "#ffffff",
        QPalette.ColorRole.Link: "#7aa2f7",
        QPalette.ColorRole.PlaceholderText: "#6b6f76",
    }
    for role, col in c.items():
        pal.setColor(role, QColor(col))
    pal.setColor(QPalette.ColorGroup.Disabled, QPalette.ColorRole.Text, QColor("#6b6f76"))
    pal.setColor(QPalette.ColorGroup.Disabled, QPalette.ColorRole.ButtonText, QColor("#6b6f76"))
    app.setPalette(pal)
    app.setStyleSheet(STYLE_SHEET)


def fit_rect(img_w: int, img_h: int, area: QRectF) -> QRectF:
    """The largest rectangle of the image's aspect ratio centred in ``area``."""
    if img_w <= 0 or img_h <= 0:
        return QRectF(area)
    s = min(area.width() / img_w, area.height() / img_h)
    w, h = img_w * s, img_h * s
    return QRectF(area.x() + (area.width() - w) / 2, area.y() + (area.height() - h) / 2, w, h)


def view_box(w: QWidget, margin: int = 6) -> tuple[int, int]:
    """The picture area of a view in device pixels (what the engine scales pictures to)."""
    dpr = w.devicePixelRatioF()
    return (max(1, int((w.width() - 2 * margin) * dpr)), max(1, int((w.height() - 2 * margin) * dpr)))


def snap_rect(r: QRectF, img: QImage, dpr: float = 1.0) -> QRectF:
    """``r`` made exactly the image's size when it nearly is, so it is drawn 1:1 (no rescale)."""
    iw, ih = img.width() / dpr, img.height() / dpr
    if abs(r.width() - iw) <= 2 and abs(r.height() - ih) <= 2:
        c = r.center()
        return QRectF(round(c.x() - iw / 2), round(c.y() - ih / 2), iw, ih)
    return r


def draw_image(p: QPainter, r: QRectF, img: QImage) -> None:
    """Draw ``img`` into ``r``: a plain copy when sizes match, else a smooth scale."""
    if p.device().devicePixelRatioF() == 1.0 and abs(r.width() - img.width()) < 0.5 and abs(r.height() - img.height()) < 0.5:
        p.drawImage(r.topLeft(), img)
    else:
        p.drawImage(r, img)


def checker_brush(cell: int = 12) -> QBrush:
    """The transparent-background checkerboard."""
    pm = QPixmap(cell * 2, cell * 2)
    pm.fill(QColor("#cfd0d4"))
    p = QPainter(pm)
    p.fillRect(0, 0, cell, cell, QColor("#9fa1a7"))
    p.fillRect(cell, cell, cell, cell, QColor("#9fa1a7"))
    p.end()
    return QBrush(pm)


def paint_placeholder(p: QPainter, rect: QRectF, text: str) -> None:
    p.setPen(QColor("#6b6f76"))
    f = QFont(p.font())
    f.setPointSizeF(11)
    p.setFont(f)
    p.drawText(rect, Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap, text)


# ------------------------------------------------------------------------------------------
# overlay geometry (tolerant of how the tracker names things)


def _pts(v) -> np.ndarray | None:
    if v is None:
        return None
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return None
    if a.size == 0:
        return None
    if a.ndim == 1 and a.size >= 2 and a.size % 2 == 0:
        a = a.reshape(-1, 2)
    if a.ndim != 2 or a.shape[1] < 2:
        return None
    a = a[np.all(np.isfinite(a[:, :2]), axis=1), :2]
    return a if len(a) else None


def _get(obj, *names):
    for n in names:
        if isinstance(obj, dict) and n in obj:
            return obj[n]
        v = getattr(obj, n, None)
        if v is not None:
            return v
    return None


def overlay_shapes(ov: Any) -> dict[str, list[np.ndarray]]:
    """The overlay's geometry as lists of (k,2) point arrays by kind: pupils, brows, lids,
    lips, corners, rois. Unknown or missing fields are left out."""
    out: dict[str, list[np.ndarray]] = {k: [] for k in ("pupils", "brows", "lids", "lips", "corners", "rois")}
    if ov is None:
        return out
    for kind, names in (
        ("pupils", ("pupils", "pupil_points")),
        ("brows", ("brows", "brow_points")),
        ("lids", ("lids", "lid_points")),
        ("corners", ("mouth_corners", "corners")),
    ):
        v = _get(ov, *names)
        if isinstance(v, dict):
            v = list(v.values())
        a = _pts(v) if v is not None and not isinstance(v, (list, tuple)) else None
        if a is not None:
            out[kind].append(a)
        elif isinstance(v, (list, tuple)):
            arrs = [_pts(x) for x in v]
            if all(x is not None for x in arrs) and arrs:
                out[kind].extend(arrs)
            else:
                a = _pts(v)
                if a is not None:
                    out[kind].append(a)
    for names in (("left_pupil",), ("right_pupil",)):
        a = _pts(_get(ov, *names))
        if a is not None:
            out["pupils"].append(a)
    lips = _pts(_get(ov, "lip_polygon", "lips", "mouth_polygon"))
    if lips is not None:
        out["lips"].append(lips)
    rois = _get(ov, "rois", "regions", "regions_of_interest")
    if isinstance(rois, dict):
        rois = list(rois.values())
    if rois is not None:
        try:
            for r in rois:
                a = _pts(r)
                if a is not None and len(a) >= 3:
                    out["rois"].append(a)
        except TypeError:
            pass
    return out


def overlay_status(ov: Any, params: Any = None) -> str:
    s = _get(ov, "status") if ov is not None else None
    if s is None and params is not None:
        s = getattr(params, "status", None)
    return str(s) if s is not None else ""


def paint_overlay(p: QPainter, ov: Any, to_view, scale: float) -> None:
    """Draw the tracker's findings; ``to_view`` maps frame (x, y) to a QPointF in the widget."""
    shapes = overlay_shapes(ov)
    lw = max(1.0, 1.6 * scale ** 0.5)

    def poly(a: np.ndarray) -> QPolygonF:
        return QPolygonF([to_view(x, y) for x, y in a])

    p.setBrush(Qt.BrushStyle.NoBrush)
    p.setPen(QPen(QColor(255, 255, 255, 80), 1.0))  # solid: dashed antialiased lines cost ~3 ms each
    for r in shapes["rois"]:
        p.drawPolygon(poly(r))
    lip_col = QColor("#ff7eb6")
    for a in shapes["lips"]:
        p.setPen(QPen(lip_col, lw))
        fill = QColor(lip_col)
        fill.setAlpha(45)
        p.setBrush(fill)
        p.drawPolygon(poly(a))
    p.setBrush(Qt.BrushStyle.NoBrush)
    p.setPen(QPen(QColor("#ffd166"), lw * 1.5))
    for a in shapes["brows"]:
        for x, y in a:
            c = to_view(x, y)
            p.drawLine(QPointF(c.x() - 8, c.y()), QPointF(c.x() + 8, c.y()))
    p.setPen(QPen(QColor("#7ee0d2"), lw))
    for a in shapes["lids"]:
        for x, y in a:
            c = to_view(x, y)
            p.drawLine(QPointF(c.x() - 5, c.y()), QPointF(c.x() + 5, c.y()))
    p.setPen(QPen(lip_col, lw))
    for a in shapes["corners"]:
        for x, y in a:
            p.drawEllipse(to_view(x, y), 3.5, 3.5)
    p.setPen(QPen(QColor("#7aa2f7"), lw * 1.3))
    for a in shapes["pupils"]:
        for x, y in a:
            c = to_view(x, y)
            p.drawEllipse(c, 6, 6)
            p.drawLine(QPointF(c.x() - 9, c.y()), QPointF(c.x() - 3, c.y()))
            p.drawLine(QPointF(c.x() + 3, c.y()), QPointF(c.x() + 9, c.y()))
    if shapes["pupils"]:
        allp = np.concatenate(shapes["pupils"])
        if len(allp) == 2:
            p.setPen(QPen(QColor(122, 162, 247, 120), lw, Qt.PenStyle.DotLine))
            p.drawLine(to_view(*allp[0]), to_view(*allp[1]))


def paint_pill(p: QPainter, anchor: QPointF, text: str, colour: QColor, right: bool = False) -> None:
    """A small rounded label (status, fps) over a picture."""
    f = QFont(p.font())
    f.setPointSizeF(9)
    f.setBold(True)
    p.setFont(f)
    fm = p.fontMetrics()
    w, h = fm.horizontalAdvance(text) + 22, fm.height() + 8
    x = anchor.x() - w if right else anchor.x()
    r = QRectF(x, anchor.y(), w, h)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(QColor(20, 21, 24, 200))
    p.drawRoundedRect(r, h / 2, h / 2)
    p.setBrush(colour)
    p.drawEllipse(QPointF(r.x() + 10, r.center().y()), 3.5, 3.5)
    p.setPen(QColor("#e6e6e6"))
    p.drawText(r.adjusted(16, 0, 0, 0), Qt.AlignmentFlag.AlignVCenter | Qt.AlignmentFlag.AlignLeft, text)


# ------------------------------------------------------------------------------------------
# widgets


class VideoView(QWidget):
    """The camera/video frame, fitted to the widget, with the tracker's overlay on top."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.image: QImage | None = None
        self.overlay: Any = None
        self.params: Any = None
        self.show_overlay = True
        self.placeholder = "No video yet"
        self.frame_size: tuple[int, int] | None = None
        self.status = ""
        self.sizeChanged = Hook()  # (w, h) in device pixels of the picture area
        self.setMinimumSize(320, 240)
        self.setToolTip(STATUS_TIP)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)

    def set_frame(self, image: QImage | None, overlay: Any = None, params: Any = None,
                  frame_size: tuple[int, int] | None = None, status: str | None = None) -> None:
        """Show ``image``; overlay coordinates are pixels of a ``frame_size`` frame (default:
        the image's own size; the engine may send the picture pre-scaled for display).
        ``status`` is the badge (default: the tracker's status in ``overlay`` / ``params``)."""
        self.image, self.overlay, self.params = image, overlay, params
        self.status = status if status is not None else overlay_status(overlay, params)
        self.frame_size = frame_size if frame_size and frame_size[0] > 0 else None
        self.update()

    def resizeEvent(self, ev) -> None:
        super().resizeEvent(ev)
        self.sizeChanged.emit(view_box(self))

    def image_rect(self) -> QRectF:
        r = QRectF(self.rect()).adjusted(6, 6, -6, -6)
        if self.image is None:
            return r
        return snap_rect(fit_rect(self.image.width(), self.image.height(), r), self.image, self.devicePixelRatioF())

    def paintEvent(self, _ev) -> None:
        p = QPainter(self)
        p.fillRect(self.rect(), QColor("#141518"))
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        if self.image is None or self.image.isNull():
            paint_placeholder(p, QRectF(self.rect()), self.placeholder)
            return
        r = self.image_rect()
        path = QPainterPath()
        path.addRoundedRect(r, 8, 8)
        p.setClipPath(path)
        draw_image(p, r, self.image)
        p.setClipping(False)
        fw, fh = self.frame_size or (self.image.width(), self.image.height())
        sx = r.width() / fw
        sy = r.height() / fh
        if self.show_overlay and self.overlay is not None:
            paint_overlay(p, self.overlay, lambda x, y: QPointF(r.x() + (x + 0.5) * sx, r.y() + (y + 0.5) * sy), sx)
        status = self.status
        if status and not status.startswith("error"):
            paint_pill(p, QPointF(r.x() + 10, r.y() + 10), status.replace("_", " "), STATUS_COLOURS.get(status, WARN))


class CharacterView(QWidget):
    """The drawn character, large and smooth, over a colour, checkerboard or green screen.

    Switching characters cross-fades: the last frame of the old character fades out over
    the new one for ``fade_ms``.
    """

    BACKGROUNDS = ("colour", "transparent", "green")

    def __init__(self, parent=None):
        super().__init__(parent)
        self.image: QImage | None = None
        self._old: QImage | None = None
        self._fade = 0.0
        self.background = "colour"
        self.colour = QColor("#2b2d31")
        self.green = QColor(0, 177, 64)
        self.placeholder = "Loading the character…"
        self.fade_ms = 450
        self.fades = 0  # cross-fades started (for tests and curiosity)
        self.sizeChanged = Hook()  # (w, h) in device pixels of the picture area
        self._key = ""
        self._checker = checker_brush()
        self._anim = QVariantAnimation(self)
        self._anim.setStartValue(1.0)
        self._anim.setEndValue(0.0)
        self._anim.valueChanged.connect(self._on_fade)
        self.setMinimumSize(320, 320)

    def set_background(self, kind: str, colour: QColor | str | None = None) -> None:
        self.background = kind if kind in self.BACKGROUNDS else "colour"
        if colour is not None:
            self.colour = QColor(colour)
        self.update()

    def resizeEvent(self, ev) -> None:
        super().resizeEvent(ev)
        self.sizeChanged.emit(view_box(self))

    def background_colour(self) -> QColor | None:
        """The flat colour behind the character, or None for transparent."""
        if self.background == "transparent":
            return None
        return self.green if self.background == "green" else self.colour

    def set_image(self, image: QImage | None, key: str = "") -> None:
        """Show ``image``; when ``key`` (the character) changes, cross-fade from the last picture."""
        if key and self._key and key != self._key and self.image is not None and image is not None:
            self._old = self.image
            self.fades += 1
            self._anim.stop()
            self._anim.setDuration(self.fade_ms)
            self._anim.start()
        if key:
            self._key = key
        self.image = image
        self.update()

    @property
    def fading(self) -> bool:
        return self._old is not None

    def _on_fade(self, v) -> None:
        self._fade = float(v)
        if self._fade <= 0.0:
            self._old = None
        self.update()

    def paintEvent(self, _ev) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        p.fillRect(self.rect(), QColor("#141518"))
        area = QRectF(self.rect()).adjusted(6, 6, -6, -6)
        img = self.image if self.image is not None else self._old
        r = snap_rect(fit_rect(img.width(), img.height(), area), img, self.devicePixelRatioF()) if img is not None else area
        path = QPainterPath()
        path.addRoundedRect(r, 10, 10)
        p.setClipPath(path)
        if self.background == "transparent":
            p.fillRect(r, self._checker)
        else:
            p.fillRect(r, self.background_colour())
        if img is None:
            p.setClipping(False)
            paint_placeholder(p, QRectF(self.rect()), self.placeholder)
            return
        if self._old is not None and self.image is not None and self._old is not self.image:
            p.setOpacity(1.0)
            draw_image(p, r, self.image)
            p.setOpacity(self._fade)
            draw_image(p, r, self._old)
            p.setOpacity(1.0)
        else:
            draw_image(p, r, img)


class ThumbnailStrip(QListWidget):
    """A horizontal row of character thumbnails; one click picks a character."""

    artChosen = Signal(str)

    def __init__(self, parent=None, icon: int = 84):
        super().__init__(parent)
        self.setViewMode(QListWidget.ViewMode.IconMode)
        self.setFlow(QListWidget.Flow.LeftToRight)
        self.setWrapping(False)
        self.setMovement(QListWidget.Movement.Static)
        self.setIconSize(QSize(icon, icon))
        self.setSpacing(4)
        self.setFixedHeight(icon + 46)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAsNeeded)
        self.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.setUniformItemSizes(True)
        self.setGridSize(QSize(icon + 26, icon + 36))
        self.itemClicked.connect(self._clicked)
        self._icon = icon

    def add_character(self, name: str, path: str, thumb_rgba: np.ndarray | None, user: bool = False) -> QListWidgetItem:
        for i in range(self.count()):
            if self.item(i).data(Qt.ItemDataRole.UserRole) == path:
                return self.item(i)
        item = QListWidgetItem(name)
        item.setData(Qt.ItemDataRole.UserRole, path)
        item.setToolTip(f"{name}{' (yours)' if user else ''}\n{path}")
        item.setIcon(QIcon(self._thumb_pixmap(thumb_rgba)))
        item.setTextAlignment(Qt.AlignmentFlag.AlignHCenter)
        self.addItem(item)
        return item

    def _thumb_pixmap(self, rgba: np.ndarray | None) -> QPixmap:
        s = self._icon
        pm = QPixmap(s, s)
        pm.fill(QColor("#e9e6df"))
        if rgba is not None:
            from app.workers import array_to_qimage

            img = array_to_qimage(np.ascontiguousarray(rgba[..., :4].astype(np.uint8)), QImage.Format.Format_RGBA8888)
            p = QPainter(pm)
            p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
            p.drawImage(fit_rect(img.width(), img.height(), QRectF(2, 2, s - 4, s - 4)), img)
            p.end()
        rounded = QPixmap(s, s)
        rounded.fill(Qt.GlobalColor.transparent)
        p = QPainter(rounded)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        path = QPainterPath()
        path.addRoundedRect(QRectF(0, 0, s, s), 10, 10)
        p.setClipPath(path)
        p.drawPixmap(0, 0, pm)
        p.end()
        return rounded

    def select_path(self, path: str) -> None:
        for i in range(self.count()):
            if self.item(i).data(Qt.ItemDataRole.UserRole) == path:
                self.setCurrentRow(i)
                return

    def entries(self) -> list[tuple[str, str]]:
        """(name, folder) of every character in the strip, in order."""
        return [(self.item(i).text(), self.item(i).data(Qt.ItemDataRole.UserRole)) for i in range(self.count())]

    def paths(self) -> list[str]:
        return [self.item(i).data(Qt.ItemDataRole.UserRole) for i in range(self.count())]

    def _clicked(self, item: QListWidgetItem) -> None:
        self.artChosen.emit(item.data(Qt.ItemDataRole.UserRole))
