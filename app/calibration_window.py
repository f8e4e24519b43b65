"""Calibration: freeze a frame, click the five points (or press Auto and adjust), look at the
colour masks the tracker learned, accept.

The five points are the CLICKS.json points of DESIGN.md: both pupils, both eyebrows, the
mouth centre (``left_*`` = image-left). Accepting saves, per performer, ``calibration.json``
(via ``Calibration.save``), ``clicks.json`` and the frozen frame as PNG into
``<user data>/performers/<name>/``, where the main window looks next time.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QFont, QImage, QPainter, QPainterPath, QPen
from PySide6.QtWidgets import (
    QDialog,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QSizePolicy,
    QVBoxLayout,
    QWidget,
)

from app.settings import performer_dir
from app.views import fit_rect, paint_placeholder
from app.workers import _one_line, bgr_to_qimage

POINTS = ("left_pupil", "right_pupil", "left_brow", "right_brow", "mouth")
PROMPTS = {
    "left_pupil": "Click the centre of the pupil on the image's LEFT",
    "right_pupil": "Click the centre of the pupil on the image's RIGHT",
    "left_brow": "Click the middle of the eyebrow on the image's LEFT",
    "right_brow": "Click the middle of the eyebrow on the image's RIGHT",
    "mouth": "Click the centre of the mouth",
}
SHORT = {"left_pupil": "L pupil", "right_pupil": "R pupil", "left_brow": "L brow", "right_brow": "R brow", "mouth": "mouth"}
COLOURS = {
    "left_pupil": QColor("#7aa2f7"),
    "right_pupil": QColor("#7aa2f7"),
    "left_brow": QColor("#ffd166"),
    "right_brow": QColor("#ffd166"),
    "mouth": QColor("#ff7eb6"),
}


class ClickView(QWidget):
    """The frozen frame; click to place the next point, drag a placed point to move it."""

    changed = Signal()

    def __init__(self, frame_bgr: np.ndarray, parent=None):
        super().__init__(parent)
        self.frame = frame_bgr
        self.image = bgr_to_qimage(frame_bgr)
        self.points: dict[str, tuple[float, float]] = {}
        self._drag: str | None = None
        self._zoom = 1.0
        self._centre = (frame_bgr.shape[1] / 2.0, frame_bgr.shape[0] / 2.0)
        self.setMouseTracking(True)
        self.setMinimumSize(480, 360)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setCursor(Qt.CursorShape.CrossCursor)

    def next_point(self) -> str | None:
        return next((k for k in POINTS if k not in self.points), None)

    def _rect(self) -> QRectF:
        """Where the whole frame is drawn: fitted to the widget, then zoomed about ``_centre``."""
        base = fit_rect(self.image.width(), self.image.height(), QRectF(self.rect()).adjusted(4, 4, -4, -4))
        if self._zoom <= 1.0:
            return base
        s = base.width() / self.image.width() * self._zoom
        cx, cy = self._centre
        w, h = self.image.width() * s, self.image.height() * s
        return QRectF(base.center().x() - (cx + 0.5) * s, base.center().y() - (cy + 0.5) * s, w, h)

    def wheelEvent(self, ev) -> None:
        """Zoom in and out about the cursor (for precise clicks on small faces)."""
        before = self.to_frame(ev.position())
        step = 1.25 if ev.angleDelta().y() > 0 else 1 / 1.25
        self._zoom = float(np.clip(self._zoom * step, 1.0, 8.0))
        if self._zoom > 1.0:
            # keep the frame point under the cursor where it was
            base = fit_rect(self.image.width(), self.image.height(), QRectF(self.rect()).adjusted(4, 4, -4, -4))
            s = base.width() / self.image.width() * self._zoom
            self._centre = (before[0] + 0.5 - (ev.position().x() - base.center().x()) / s - 0.5,
                            before[1] + 0.5 - (ev.position().y() - base.center().y()) / s - 0.5)
        self.update()

    def to_view(self, x: float, y: float) -> QPointF:
        r = self._rect()
        s = r.width() / self.image.width()
        return QPointF(r.x() + (x + 0.5) * s, r.y() + (y + 0.5) * s)

    def to_frame(self, p: QPointF) -> tuple[float, float]:
        r = self._rect()
        s = r.width() / self.image.width()
        x = (p.x() - r.x()) / s - 0.5
        y = (p.y() - r.y()) / s - 0.5
        return (float(np.clip(x, 0, self.image.width() - 1)), float(np.clip(y, 0, self.image.height() - 1)))

    def _hit(self, pos: QPointF) -> str | None:
        best, bd = None, 14.0
        for k, (x, y) in self.points.items():
            d = (self.to_view(x, y) - pos).manhattanLength()
            if d < bd:
                best, bd = k, d
        return best

    def set_point(self, key: str, xy: tuple[float, float]) -> None:
        self.points[key] = (float(xy[0]), float(xy[1]))
        self.changed.emit()
        self.update()

    def mousePressEvent(self, ev) -> None:
        if ev.button() != Qt.MouseButton.LeftButton:
            return
        pos = ev.position()
        hit = self._hit(pos)
        if hit is not None:
            self._drag = hit
            return
        nxt = self.next_point()
        if nxt is not None and self._rect().contains(pos):
            self.set_point(nxt, self.to_frame(pos))

    def mouseMoveEvent(self, ev) -> None:
        if self._drag is not None:
            self.points[self._drag] = self.to_frame(ev.position())
            self.update()
        else:
            self.setCursor(Qt.CursorShape.OpenHandCursor if self._hit(ev.position()) else Qt.CursorShape.CrossCursor)

    def mouseReleaseEvent(self, ev) -> None:
        if self._drag is not None:
            self._drag = None
            self.changed.emit()

    def paintEvent(self, _ev) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        p.fillRect(self.rect(), QColor("#141518"))
        r = self._rect()
        path = QPainterPath()
        path.addRoundedRect(r.intersected(QRectF(self.rect()).adjusted(4, 4, -4, -4)), 8, 8)
        p.setClipPath(path)
        p.drawImage(r, self.image)
        p.setClipping(False)
        p.setClipRect(self.rect())
        f = QFont(p.font())
        f.setPointSizeF(9)
        f.setBold(True)
        p.setFont(f)
        if "left_pupil" in self.points and "right_pupil" in self.points:
            p.setPen(QPen(QColor(122, 162, 247, 150), 1.2, Qt.PenStyle.DotLine))
            p.drawLine(self.to_view(*self.points["left_pupil"]), self.to_view(*self.points["right_pupil"]))
        for k, (x, y) in self.points.items():
            c = self.to_view(x, y)
            col = COLOURS[k]
            p.setPen(QPen(QColor(0, 0, 0, 160), 4))
            p.drawEllipse(c, 7, 7)
            p.setPen(QPen(col, 2))
            p.drawEllipse(c, 7, 7)
            p.drawLine(QPointF(c.x() - 12, c.y()), QPointF(c.x() - 4, c.y()))
            p.drawLine(QPointF(c.x() + 4, c.y()), QPointF(c.x() + 12, c.y()))
            p.drawLine(QPointF(c.x(), c.y() - 12), QPointF(c.x(), c.y() - 4))
            p.drawLine(QPointF(c.x(), c.y() + 4), QPointF(c.x(), c.y() + 12))
            label = SHORT[k]
            tw = p.fontMetrics().horizontalAdvance(label) + 10
            lr = QRectF(c.x() + 10, c.y() - 24, tw, 18)
            p.setPen(Qt.PenStyle.NoPen)
            p.setBrush(QColor(20, 21, 24, 210))
            p.drawRoundedRect(lr, 5, 5)
            p.setBrush(Qt.BrushStyle.NoBrush)
            p.setPen(col)
            p.drawText(lr, Qt.AlignmentFlag.AlignCenter, label)


MASK_PLACEHOLDER = "Place all five points to see what the tracker learned"


class MaskView(QWidget):
    """One learned colour mask over the dimmed frame, with a caption; without a mask, a note
    saying why (points still to place, or what the tracker could not learn)."""

    def __init__(self, caption: str, parent=None):
        super().__init__(parent)
        self.caption = caption
        self.image: QImage | None = None
        self.note = MASK_PLACEHOLDER
        self.setMinimumSize(200, 150)

    def set_image(self, img: QImage | None, note: str = MASK_PLACEHOLDER) -> None:
        self.image = img
        self.note = note
        self.update()

    def paintEvent(self, _ev) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        p.fillRect(self.rect(), QColor("#141518"))
        area = QRectF(self.rect()).adjusted(4, 22, -4, -4)
        p.setPen(QColor("#9aa0aa"))
        p.drawText(QRectF(6, 2, self.width() - 12, 18), Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, self.caption)
        if self.image is None:
            paint_placeholder(p, area, self.note)
            return
        p.drawImage(fit_rect(self.image.width(), self.image.height(), area), self.image)


def classifier_regions(name: str, pts: dict[str, tuple[float, float]], ipd: float) -> list[tuple[int, int, int, int]]:
    """Rectangles (x0, y0, x1, y1) where the tracker applies the classifier called ``name``:
    around the pupils for pupil/eye colours, around the mouth for lip colours."""
    if "lip" in name or "mouth" in name:
        x, y = pts["mouth"]
        boxes = [(x - 0.75 * ipd, y - 0.4 * ipd, x + 0.75 * ipd, y + 0.55 * ipd)]
    elif "pupil" in name or "eye" in name:
        boxes = [(x - 0.33 * ipd, y - 0.22 * ipd, x + 0.33 * ipd, y + 0.22 * ipd)
                 for x, y in (pts["left_pupil"], pts["right_pupil"])]
    else:
        boxes = [face_box(pts, ipd)]
    return [tuple(int(round(v)) for v in b) for b in boxes]


def face_box(pts: dict[str, tuple[float, float]], ipd: float) -> tuple[float, float, float, float]:
    xs = [p[0] for p in pts.values()]
    ys = [p[1] for p in pts.values()]
    return (min(xs) - 0.8 * ipd, min(ys) - 0.6 * ipd, max(xs) + 0.8 * ipd, max(ys) + 0.7 * ipd)


def mask_picture(frame_bgr: np.ndarray, mask: np.ndarray, colour: QColor,
                 regions: list[tuple[int, int, int, int]] | None = None,
                 crop: tuple[float, float, float, float] | None = None) -> QImage:
    """The frame dimmed to grey with the mask's pixels painted in ``colour``, only inside
    ``regions`` (outlined), cropped to ``crop``."""
    import cv2

    h, w = frame_bgr.shape[:2]
    grey = frame_bgr.mean(axis=2, keepdims=True) * 0.45
    out = np.repeat(grey, 3, axis=2)
    m = np.asarray(mask, dtype=np.float32)
    if m.max() > 1.0:
        m = m / 255.0
    if regions:
        keep = np.zeros((h, w), np.float32)
        for x0, y0, x1, y1 in regions:
            keep[max(0, y0):max(0, y1), max(0, x0):max(0, x1)] = 1.0
        m = m * keep
    col = np.array([colour.blue(), colour.green(), colour.red()], np.float32)
    out = out * (1 - m[..., None]) + col * m[..., None]
    out = np.clip(out, 0, 255).astype(np.uint8)
    for x0, y0, x1, y1 in regions or []:
        cv2.rectangle(out, (x0, y0), (x1, y1), (200, 200, 200), 1, cv2.LINE_AA)
    if crop is not None:
        x0, y0, x1, y1 = (int(round(v)) for v in crop)
        x0, y0 = max(0, x0), max(0, y0)
        x1, y1 = min(w, max(x0 + 2, x1)), min(h, max(y0 + 2, y1))
        out = out[y0:y1, x0:x1]
    return bgr_to_qimage(np.ascontiguousarray(out))


def learned_masks(cal, frame_bgr: np.ndarray) -> dict[str, np.ndarray]:
    """Masks of every colour classifier the calibration carries, applied to the whole frame.

    Found by duck typing (any attribute with a ``mask(bgr)`` method, or a ``classifiers`` dict),
    so a tracker that adds a classifier shows up here without changes."""
    found: dict[str, object] = {}
    cls = getattr(cal, "classifiers", None)
    if isinstance(cls, dict):
        found.update(cls)  # the tracker says which classes it uses: only those
    for name in ([] if found else dir(cal)):
        if name.startswith("_") or name in found:
            continue
        try:
            v = getattr(cal, name)
        except Exception:
            continue
        if callable(getattr(v, "mask", None)) and not isinstance(v, type):
            found[name] = v
    order = {"pupil": 0, "lip": 1, "eye": 2, "skin": 3}
    out = {}
    for name, c in sorted(found.items(), key=lambda kv: (order.get(kv[0], 9), kv[0])):
        try:
            m = np.asarray(c.mask(frame_bgr))
        except Exception:
            continue
        if m.shape[:2] == frame_bgr.shape[:2]:
            out[name.replace("_classifier", "").replace("_model", "").replace("_", " ")] = m.astype(bool)
    return out


class CalibrationWindow(QDialog):
    """Five clicks (or Auto) on a frozen frame → ``tracker.calibration.calibrate`` → saved."""

    calibrated = Signal(object)

    def __init__(self, frame_bgr: np.ndarray, performer: str = "default", parent=None, frame_index: int = 0):
        super().__init__(parent)
        self.setWindowTitle("Calibrate the tracker")
        self.frame = np.ascontiguousarray(frame_bgr)
        self.frame_index = int(frame_index)
        self.calibration = None
        self.error = ""
        self.saved_to: Path | None = None

        self._auto_note = ""  # why Auto placed nothing, kept while the user places the points
        self._auto_found = False  # the points on screen are Auto's (its caution is shown with the masks)
        self.view = ClickView(self.frame)
        self.view.changed.connect(self._on_changed)
        self.prompt = QLabel("")
        self.prompt.setObjectName("prompt")
        self.prompt.setWordWrap(True)
        self.prompt.setAlignment(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter)
        self.prompt.setToolTip("The mouse wheel zooms the frame about the cursor; drag a placed point to move it")

        self.auto_btn = QPushButton("Auto")
        self.auto_btn.setToolTip("Find the face, eyes and mouth automatically; then drag any point to adjust")
        self.auto_btn.clicked.connect(self.auto)
        self.undo_btn = QPushButton("Undo point")
        self.undo_btn.clicked.connect(self.undo)
        self.reset_btn = QPushButton("Start over")
        self.reset_btn.clicked.connect(self.reset)
        self.name_edit = QLineEdit(performer)
        self.name_edit.setPlaceholderText("performer's name")
        self.name_edit.setMaximumWidth(200)
        self.accept_btn = QPushButton("Accept and save")
        self.accept_btn.setObjectName("primary")
        # the shared style sheet colours the primary button the same when it is disabled
        self.accept_btn.setStyleSheet("QPushButton:disabled { background: #2f3136; border-color: #3c3f45; color: #6b6f76; }")
        self.accept_btn.clicked.connect(self.accept_calibration)
        cancel = QPushButton("Cancel")
        cancel.clicked.connect(self.reject)

        self.masks_box = QWidget()
        self.mask_grid = QGridLayout(self.masks_box)
        self.mask_grid.setContentsMargins(0, 0, 0, 0)
        self.mask_grid.setSpacing(8)
        self.mask_views: list[MaskView] = []
        self._set_mask_views(["pupil", "lip"])
        self.info = QLabel("")
        self.info.setObjectName("hint")
        self.info.setWordWrap(True)

        left = QVBoxLayout()
        left.setSpacing(10)
        left.addWidget(self.prompt)
        left.addWidget(self.view, 1)
        row = QHBoxLayout()
        for b in (self.auto_btn, self.undo_btn, self.reset_btn):
            row.addWidget(b)
        row.addStretch(1)
        left.addLayout(row)

        right = QVBoxLayout()
        right.setSpacing(10)
        t = QLabel("What the tracker learned")
        t.setObjectName("title")
        right.addWidget(t)
        right.addWidget(self.masks_box, 1)
        right.addWidget(self.info)
        nr = QHBoxLayout()
        nr.addWidget(QLabel("Performer"))
        nr.addWidget(self.name_edit, 1)
        right.addLayout(nr)
        br = QHBoxLayout()
        br.addStretch(1)
        br.addWidget(cancel)
        br.addWidget(self.accept_btn)
        right.addLayout(br)

        h = QHBoxLayout(self)
        h.setContentsMargins(16, 16, 16, 16)
        h.setSpacing(16)
        h.addLayout(left, 3)
        rw = QWidget()
        rw.setLayout(right)
        rw.setMinimumWidth(340)
        h.addWidget(rw, 2)
        self.resize(1180, 640)
        self._fix_prompt_height()
        self._on_changed()

    def _fix_prompt_height(self) -> None:
        """Give the prompt room for two lines whatever it says, so the frame under it never
        moves while clicking (a prompt that wrapped to one line or two shifted it by a line)."""
        self.prompt.ensurePolished()
        text = self.prompt.text()
        self.prompt.setText("Ag\nAg")
        h = self.prompt.sizeHint().height()
        self.prompt.setText(text)
        self.prompt.setFixedHeight(h)

    # ---------------------------------------------------------------------------- points
    def set_points(self, points: dict[str, tuple[float, float]]) -> None:
        """Place points programmatically (tests, Auto)."""
        self.view.points = {k: (float(v[0]), float(v[1])) for k, v in points.items() if k in POINTS}
        self.view.update()
        self._on_changed()

    def click(self, x: float, y: float) -> None:
        """Place the next point at frame pixel (x, y), as a mouse click would."""
        nxt = self.view.next_point()
        if nxt is not None:
            self.view.set_point(nxt, (x, y))

    def undo(self) -> None:
        placed = [k for k in POINTS if k in self.view.points]
        if placed:
            del self.view.points[placed[-1]]
            self.view.update()
            self._on_changed()

    def reset(self) -> None:
        """Remove every point and everything said about them."""
        self._auto_note = ""
        self._auto_found = False
        self.error = ""
        self.set_points({})

    def auto(self) -> bool:
        """Find the five points with ``tracker.auto_init.auto_clicks``; True when it placed them.

        What it finds is checked against a face's constellation
        (``training.constellation``): when the points are not shaped like a face, none are
        placed (points the user already placed stay) and the window says why."""
        try:
            from tracker.auto_init import auto_clicks
        except ImportError:
            self._auto_note = "Automatic start is not available in this build: please click the points."
            self._on_changed()
            return False
        try:
            c = auto_clicks(self.frame, self.frame_index)
        except Exception as e:
            self._auto_note = f"Auto found no face: {_one_line(e)}. Please click the five points yourself."
            self._on_changed()
            return False
        from training.constellation import constellation_problems

        problems = constellation_problems(c.points(), self.frame)
        if problems:
            self._auto_note = ("Auto's guess does not look like a face: " + "; ".join(problems)
                               + ". It placed no points — please click the five yourself, in the order "
                               "the prompt above asks.")
            self._on_changed()
            return False
        self._auto_note, self._auto_found = "", True
        from tracker.clicks import PIXEL_CENTRE

        self.set_points(c.moved(-PIXEL_CENTRE, -PIXEL_CENTRE).points())  # the view's points: pixel centres at whole numbers
        return True

    def clicks(self):
        """The placed points as CLICKS.json has them (measured from the frame's top-left corner)."""
        from tracker.clicks import PIXEL_CENTRE, Clicks

        d = {"frame": self.frame_index, **{k: list(v) for k, v in self.view.points.items()}}
        return Clicks.from_dict(d, where="calibration clicks").moved(PIXEL_CENTRE, PIXEL_CENTRE)

    # ------------------------------------------------------------------------ calibrating
    def _on_changed(self) -> None:
        nxt = self.view.next_point()
        n = len(self.view.points)
        if nxt is not None:
            self.prompt.setText(f"{n + 1} of 5 — {PROMPTS[nxt]}")
            self.calibration = None
            self.error = ""
            self.accept_btn.setEnabled(False)
            for mv in self.mask_views:
                mv.set_image(None)
            self._auto_found = False
            self.info.setText(self._auto_note or "Click the points in the order the prompt asks, or press Auto.")
            return
        self.prompt.setText("All five points placed — drag any that is off, check the masks, then accept")
        self._auto_note = ""  # the points are there now: why Auto placed none no longer matters
        self._calibrate()

    def _shape_warning(self) -> str:
        """A warning when the placed points are not shaped like a face ("" when they are)."""
        from training.constellation import constellation_problems

        problems = constellation_problems(self.view.points, self.frame)
        return ("These points do not look like a face: " + "; ".join(problems) + ". ") if problems else ""

    def _calibrate(self) -> None:
        warn = self._shape_warning()
        try:
            from tracker.calibration import calibrate, calibration_hints

            self.calibration = calibrate(self.frame, self.clicks())
            self.error = ""
            hints = calibration_hints(self.calibration)
        except Exception as e:
            self.calibration = None
            self.error = _one_line(e)
            self.info.setText(f"{warn}The tracker could not learn from these points: {self.error}. "
                              "Drag the points that are off.")
            self.accept_btn.setEnabled(False)
            for mv in self.mask_views:
                mv.set_image(None, "Nothing learned from these points — see the note below")
            return
        self.accept_btn.setEnabled(True)
        masks = learned_masks(self.calibration, self.frame)
        names = list(masks) or ["pupil", "lip"]
        self._set_mask_views(names)
        palette = [QColor("#7aa2f7"), QColor("#ff7eb6"), QColor("#9ece6a"), QColor("#ffd166")]
        pts = self.view.points
        ipd = float(getattr(self.calibration, "ipd", 0.0) or self.clicks().ipd())
        crop = face_box(pts, ipd)
        for i, (name, mv) in enumerate(zip(names, self.mask_views)):
            if name in masks:
                regions = classifier_regions(name, pts, ipd)
                mv.set_image(mask_picture(self.frame, masks[name], palette[i % len(palette)], regions, crop))
            else:
                mv.set_image(None, "this tracker exposes no colour classifiers")
        ipd = getattr(self.calibration, "ipd", None)
        note = ("Found automatically — Auto can be wrong, so check each point (pupil centres, brow middles, "
                "mouth centre) and drag any that is off, then accept. ") if self._auto_found else ""
        if self._eyes_look_shut():
            note += ("The eyes look shut on this frame: the tracker learns the eyes from it, so freeze a frame "
                     "with the eyes open and " + ("press Auto again. " if self._auto_found else "place the points there. "))
        advice = "".join(h[0].upper() + h[1:] + ". " for h in hints)
        self.info.setText(
            warn + note + advice
            + (f"Inter-pupil distance {ipd:.1f} px. " if isinstance(ipd, (int, float)) else "")
            + "Inside the boxes the tracker searches, coloured pixels are what each colour class "
            "takes in: the lips, the inside of the eyes (white, iris, lashes) and the mouth's dark gap "
            "should light up, little else. The tracker also uses shape and motion, so a loose mask is "
            "not fatal — but a mask that misses the lips or the eyes means: click again."
        )

    def _eyes_look_shut(self) -> bool:
        """Whether the eyes look shut at the placed pupils (``tracker.auto_init.eyes_shown``): a blink
        caught on the frozen frame, whose eyes the tracker would learn as shut. A caution only: never
        a reason to refuse the points."""
        try:
            from tracker.auto_init import EYES_SHOWN, eyes_shown

            return eyes_shown(self.frame, self.clicks()) < EYES_SHOWN
        except Exception:
            return False

    def _set_mask_views(self, names: list[str]) -> None:
        if [m.caption for m in self.mask_views] == [f"{n} colour" for n in names]:
            return
        for mv in self.mask_views:
            mv.setParent(None)
        self.mask_views = [MaskView(f"{n} colour") for n in names]
        for i, mv in enumerate(self.mask_views):
            self.mask_grid.addWidget(mv, i // 2, i % 2)

    def accept_calibration(self) -> Path | None:
        """Save the calibration for the performer and hand it to the main window."""
        if self.calibration is None:
            return None
        name = self.name_edit.text().strip() or "default"
        folder = performer_dir(name)
        try:
            self.calibration.save(folder / "calibration.json")
            self.clicks().save(folder / "clicks.json")
            bgr_to_qimage(self.frame).save(str(folder / "calibration-frame.png"), "PNG")
        except Exception as e:
            self.info.setText(f"Could not save: {_one_line(e)}")
            return None
        self.saved_to = folder / "calibration.json"
        parent = self.parent()
        if parent is not None and hasattr(parent, "settings"):
            parent.settings.set("performer/name", name)
        self.calibrated.emit(self.calibration)
        self.accept()
        return self.saved_to
