"""Training (the paper's Figure 2) and the expression space (its Figure 5).

Scrub a recorded clip of the performer; for each drawing of the character pick the frame
whose expression matches it. The session (``training.session.TrainingSession``) autosaves to
``<user data>/performers/<name>/sessions/<character folder>/`` on every change.

Below, the expression space of the part being trained: the drawings as points in the PCA
plane, their Delaunay triangles, the clip's frames as small dots, the live point (the
scrubbed frame, or the camera while live) moving inside, and shading where no drawing
covers — with the leave-one-out and coverage diagnostics of ``training.diagnostics`` and
its "add this expression" suggestion, one click away.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np
from PySide6.QtCore import QPointF, QRectF, QSize, Qt, QTimer, Signal
from PySide6.QtGui import QBrush, QColor, QFont, QImage, QKeySequence, QPainter, QPainterPath, QPen, QPolygonF
from PySide6.QtWidgets import (
    QFileDialog,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QMessageBox,
    QPushButton,
    QScrollArea,
    QSlider,
    QSpinBox,
    QSplitter,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app.settings import performer_dir
from app.views import VideoView, fit_rect, paint_placeholder
from app.workers import Hook, ProcessTask, SourceSpec, _one_line, array_to_qimage, bgr_to_qimage, bundled_performance, resolve_calibration

PARTS = ("eyes", "mouth")


def session_path(performer: str, art_path: str | Path) -> Path:
    """Folder of the training session of ``performer`` for the character at ``art_path``."""
    return performer_dir(performer) / "sessions" / Path(art_path).name


# ------------------------------------------------------------------------------------------
# clips


class PerformanceClip:
    """The bundled synthetic performance as a scrubbable clip."""

    def __init__(self, perf=None):
        self.perf = perf or bundled_performance()
        self.name = "bundled performance"
        self.fps = 30.0

    def __len__(self) -> int:
        return len(self.perf)

    def frame(self, i: int) -> np.ndarray:
        return self.perf.frame(int(i))


class VideoClip:
    """A video file as a scrubbable clip (seeks with a small cache of decoded frames)."""

    def __init__(self, path: str | Path, cache: int = 48):
        import cv2

        self.path = str(path)
        self.name = Path(path).name
        self._cap = cv2.VideoCapture(self.path)
        if not self._cap.isOpened():
            raise ValueError(f"{path}: cannot open this video")
        self.fps = float(self._cap.get(cv2.CAP_PROP_FPS) or 30.0)
        n = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        if n <= 0:  # some containers do not say: count by reading
            n = 0
            while self._cap.grab():
                n += 1
            self._cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
        self._n = n
        self._pos = 0
        self._cache: OrderedDict[int, np.ndarray] = OrderedDict()
        self._size = cache
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return self._n

    def frame(self, i: int) -> np.ndarray:
        import cv2

        i = int(np.clip(i, 0, max(0, self._n - 1)))
        with self._lock:
            if i in self._cache:
                self._cache.move_to_end(i)
                return self._cache[i]
            if i != self._pos:
                self._cap.set(cv2.CAP_PROP_POS_FRAMES, i)
            ok, img = self._cap.read()
            if not ok:
                raise ValueError(f"{self.path}: cannot read frame {i}")
            self._pos = i + 1
            self._cache[i] = img
            while len(self._cache) > self._size:
                self._cache.popitem(last=False)
            return img


def open_clip(source: SourceSpec | str | None):
    if isinstance(source, str):
        return VideoClip(source)
    if source is not None and source.kind == "video" and source.video:
        return VideoClip(source.video)
    from app.workers import bundled_performance_clip_path

    cached = bundled_performance_clip_path()
    if cached is not None:  # decoding is ~10x cheaper than drawing the synthetic frames again
        clip = VideoClip(cached)
        clip.name = "bundled performance"
        return clip
    return PerformanceClip()


def clip_descriptor(clip) -> tuple:
    """What a task process needs to reopen ``clip``: ("performance", perf) or ("video", path)."""
    if isinstance(clip, PerformanceClip):
        return ("performance", clip.perf)
    return ("video", clip.path)


def track_clip_task(report, cancelled, desc: tuple, calibration) -> tuple:
    """(Task process) track every frame of a clip: returns ``(track (m, 10) with NaN rows
    where the face was lost, the Calibration used)``; reports ``progress(i, n)``."""
    from tracker.face_tracker import FaceTracker

    clip = PerformanceClip(desc[1]) if desc[0] == "performance" else VideoClip(desc[1])
    cal = resolve_calibration(calibration)
    tr = FaceTracker(cal)
    n = len(clip)
    out = np.full((n, 10), np.nan)
    for i in range(n):
        if cancelled():
            break
        p = tr.track(clip.frame(i), index=i, time=i / clip.fps).params
        if getattr(p, "status", "ok") != "lost":
            out[i] = p.values()
        if i % 10 == 0 or i == n - 1:
            report("progress", i + 1, n)
    return out, cal


# ------------------------------------------------------------------------------------------
# pictures of drawings


def drawing_qimage(rgba: np.ndarray, paper=(250, 248, 243)) -> QImage:
    """A straight-alpha RGBA drawing on paper colour, as a QImage."""
    a = rgba[..., 3:4].astype(np.float32) / 255.0
    rgb = rgba[..., :3].astype(np.float32) * a + np.asarray(paper, np.float32) * (1 - a)
    return array_to_qimage(np.clip(rgb + 0.5, 0, 255).astype(np.uint8), QImage.Format.Format_RGB888)


def rgb_qimage(rgb: np.ndarray) -> QImage:
    return array_to_qimage(np.ascontiguousarray(rgb[..., :3].astype(np.uint8)), QImage.Format.Format_RGB888)


SYNTHETIC = "synthetic:"  # Pair.source of the automatic pairs: the synthetic performer's face


def source_label(source: str) -> str:
    """A card's short label for a pair whose frame is not from the clip ("synthetic · smile")."""
    if source.startswith(SYNTHETIC):
        return f"synthetic · {source[len(SYNTHETIC):].replace('_', ' ')}"
    return source


def source_text(source: str) -> str:
    """The same in words, for tooltips and the status line."""
    if source.startswith(SYNTHETIC):
        return f"the synthetic performer making the “{source[len(SYNTHETIC):].replace('_', ' ')}” face"
    return source


class DrawingCard(QWidget):
    """One drawing: its picture, name, the frame paired with it, and a button to pair."""

    pairRequested = Signal(str, str)  # part, drawing
    selected = Signal(str, str)

    def __init__(self, part: str, name: str, rgba: np.ndarray, parent=None):
        super().__init__(parent)
        self.part, self.name = part, name
        self.drawing = drawing_qimage(rgba)
        self.thumb: QImage | None = None
        self.frame_no: int | None = None
        self.source = ""  # set when the pair's frame is not from this clip ("synthetic:smile")
        self.active = False
        self.setFixedSize(QSize(268, 134))
        self.btn = QPushButton("Use this frame", self)
        self.btn.setGeometry(128, 98, 132, 28)
        self.btn.clicked.connect(lambda: self.pairRequested.emit(self.part, self.name))

    def set_pair(self, thumb: QImage | None, frame_no: int | None, source: str = "", clip: str = "") -> None:
        """Show the paired frame: ``frame_no`` of ``clip``, or the frame ``source`` names."""
        self.thumb, self.frame_no, self.source = thumb, frame_no, source
        if frame_no is None:
            self.setToolTip("")
        elif source:
            self.setToolTip(f"Paired automatically: {source_text(source)} (not a frame of this clip)")
        else:
            self.setToolTip(f"Paired with frame {frame_no} of {clip or 'the clip'}")
        self.update()

    def pair_label(self) -> str:
        """The short label under the frame: where the paired frame came from ("" if unpaired)."""
        if self.frame_no is None:
            return ""
        return source_label(self.source) if self.source else f"frame {self.frame_no}"

    @property
    def auto(self) -> bool:
        return bool(self.source)

    def mousePressEvent(self, _ev) -> None:
        self.selected.emit(self.part, self.name)

    def mouseDoubleClickEvent(self, _ev) -> None:
        self.pairRequested.emit(self.part, self.name)

    def paintEvent(self, _ev) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        r = QRectF(self.rect()).adjusted(1, 1, -1, -1)
        p.setPen(QPen(QColor("#7aa2f7") if self.active else QColor("#34363c"), 2 if self.active else 1))
        p.setBrush(QColor("#26282d"))
        p.drawRoundedRect(r, 10, 10)
        pic = QRectF(8, 8, 112, 88)
        path = QPainterPath()
        path.addRoundedRect(pic, 6, 6)
        p.save()
        p.setClipPath(path)
        p.fillRect(pic, QColor(250, 248, 243))
        p.drawImage(fit_rect(self.drawing.width(), self.drawing.height(), pic), self.drawing)
        p.restore()
        fr = QRectF(self.FRAME_RECT)
        if self.thumb is not None:
            path = QPainterPath()
            path.addRoundedRect(fr, 6, 6)
            p.save()
            p.setClipPath(path)
            p.fillRect(fr, QColor("#141518"))
            p.drawImage(fit_rect(self.thumb.width(), self.thumb.height(), fr), self.thumb)
            p.restore()
        else:
            p.setPen(QPen(QColor("#4a4d54"), 1, Qt.PenStyle.DashLine))
            p.setBrush(Qt.BrushStyle.NoBrush)
            p.drawRoundedRect(fr, 6, 6)
            p.setPen(QColor("#6b6f76"))
            p.drawText(fr, Qt.AlignmentFlag.AlignCenter, "no frame yet")
        p.setPen(QColor("#e6e6e6"))
        f = QFont(p.font())
        f.setBold(True)
        p.setFont(f)
        name = p.fontMetrics().elidedText(self.name, Qt.TextElideMode.ElideRight, int(self.NAME_RECT.width()))
        p.drawText(self.NAME_RECT, Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, name)
        if self.frame_no is not None:
            f.setBold(False)
            f.setPointSizeF(8)
            p.setFont(f)
            label, pill = self.label_layout(p.fontMetrics())
            p.setPen(Qt.PenStyle.NoPen)
            p.setBrush(QColor(20, 21, 24, 215))
            p.drawRoundedRect(pill, 5, 5)
            p.setPen(QColor("#e0af68") if self.source else QColor("#9ece6a"))
            p.drawText(pill, Qt.AlignmentFlag.AlignCenter, label)

    NAME_RECT = QRectF(10, 100, 112, 24)  # the drawing's name, under its picture
    FRAME_RECT = QRectF(128, 8, 132, 84)  # the paired frame's thumbnail

    def label_layout(self, fm) -> tuple[str, QRectF]:
        """Where the paired frame came from, fitted in a pill on the thumbnail's lower edge (so it
        never runs into the drawing's name)."""
        fr = self.FRAME_RECT
        label = fm.elidedText(self.pair_label(), Qt.TextElideMode.ElideRight, int(fr.width()) - 18)
        w = min(fm.horizontalAdvance(label) + 10, fr.width() - 8)
        return label, QRectF(fr.left() + 4, fr.bottom() - 19, w, 16)


# ------------------------------------------------------------------------------------------
# Figure 5


class ExpressionSpaceView(QWidget):
    """The expression space of one part: drawings as points in the map's PCA plane, the
    Delaunay triangles, the clip's frames, the live point and the uncovered regions."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.emap = None
        self.names: list[str] = []
        self.pictures: dict[int, QImage] = {}
        self.cloud = np.zeros((0, 2))
        self.cloud_out = np.zeros(0, bool)
        self.live: np.ndarray | None = None
        self.live_loc = None
        self.suggest: np.ndarray | None = None
        self.message = "Pair at least one drawing with a frame to see the expression space"
        self.setMinimumSize(360, 260)

    def set_map(self, emap, names: list[str], pictures: dict[int, QImage], cloud_feats: np.ndarray | None) -> None:
        self.emap, self.names, self.pictures = emap, names, pictures
        self.live = None
        self.live_loc = None
        self.suggest = None
        if emap is not None and cloud_feats is not None and len(cloud_feats):
            ok = np.all(np.isfinite(cloud_feats), axis=1)
            f = cloud_feats[ok]
            self.cloud = emap.project(f) if len(f) else np.zeros((0, 2))
            self.cloud_out = np.array([emap.locate(x).outside > 1e-9 for x in f], bool) if len(f) else np.zeros(0, bool)
        else:
            self.cloud = np.zeros((0, 2))
            self.cloud_out = np.zeros(0, bool)
        self.update()

    def set_live(self, feats: np.ndarray | None) -> None:
        if self.emap is None or feats is None or not np.all(np.isfinite(feats)):
            self.live, self.live_loc = None, None
        else:
            self.live = self.emap.project(feats)
            self.live_loc = self.emap.locate(feats)
        self.update()

    def set_suggestion(self, feats: np.ndarray | None) -> None:
        self.suggest = None if (self.emap is None or feats is None) else self.emap.project(feats)
        self.update()

    def _bounds(self) -> tuple[float, float, float, float]:
        pts = [self.emap.points2d] if self.emap is not None else []
        if len(self.cloud):
            pts.append(self.cloud)
        if self.live is not None:
            pts.append(self.live[None])
        a = np.concatenate(pts) if pts else np.zeros((1, 2))
        lo, hi = a.min(axis=0), a.max(axis=0)
        span = np.maximum(hi - lo, 1e-6)
        span = np.maximum(span, span.max() * 0.35)
        c = (lo + hi) / 2
        return c[0] - span[0] * 0.62, c[1] - span[1] * 0.62, span[0] * 1.24, span[1] * 1.24

    def paintEvent(self, _ev) -> None:  # noqa: C901 - one picture
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        p.fillRect(self.rect(), QColor("#141518"))
        area = QRectF(self.rect()).adjusted(10, 10, -10, -10)
        if self.emap is None:
            paint_placeholder(p, area, self.message)
            return
        x0, y0, w, h = self._bounds()
        s = min(area.width() / w, area.height() / h)
        ox = area.center().x() - (x0 + w / 2) * s
        oy = area.center().y() + (y0 + h / 2) * s

        def V(pt) -> QPointF:  # map plane (y up) -> widget
            return QPointF(ox + pt[0] * s, oy - pt[1] * s)

        P = self.emap.points2d
        plot = QRectF(area)
        # shade what no drawing covers: everything outside the hull of the drawings
        hull = _hull(P[self.emap._unique] if hasattr(self.emap, "_unique") else P)
        shade = QPainterPath()
        shade.addRoundedRect(plot, 8, 8)
        if hull is not None:
            hp = QPainterPath()
            hp.addPolygon(QPolygonF([V(q) for q in hull]))
            hp.closeSubpath()
            shade = shade.subtracted(hp)
            p.setPen(Qt.PenStyle.NoPen)
            p.setBrush(QColor(122, 162, 247, 22))
            p.drawPath(hp)
        p.setPen(Qt.PenStyle.NoPen)
        p.setBrush(QBrush(QColor(247, 118, 142, 40), Qt.BrushStyle.BDiagPattern))
        p.drawPath(shade)
        p.setBrush(QColor(247, 118, 142, 14))
        p.drawPath(shade)
        # triangles
        tris = getattr(self.emap, "triangles", np.zeros((0, 3)))
        live_tri = self.live_loc.triangle if self.live_loc is not None else -1
        for t, tri in enumerate(tris):
            poly = QPolygonF([V(P[i]) for i in tri])
            if t == live_tri:
                p.setBrush(QColor(158, 206, 106, 45))
                p.setPen(QPen(QColor("#9ece6a"), 2))
            else:
                p.setBrush(Qt.BrushStyle.NoBrush)
                p.setPen(QPen(QColor("#7aa2f7"), 1.4))
            p.drawPolygon(poly)
        if self.emap.mode == "line":
            idx = getattr(self.emap, "_line_idx", [])
            p.setPen(QPen(QColor("#7aa2f7"), 1.4))
            for a, b in zip(idx[:-1], idx[1:]):
                p.drawLine(V(P[a]), V(P[b]))
        # clip frames
        p.setPen(Qt.PenStyle.NoPen)
        for q, out in zip(self.cloud, self.cloud_out):
            p.setBrush(QColor(247, 118, 142, 150) if out else QColor(200, 205, 215, 90))
            p.drawEllipse(V(q), 2.2, 2.2)
        # drawings at their points
        f = QFont(p.font())
        f.setPointSizeF(8.5)
        p.setFont(f)
        box = 58.0
        for row, lab in enumerate(self.emap.labels):
            if hasattr(self.emap, "duplicate_of") and self.emap.duplicate_of[row] != row:
                continue
            c = V(P[row])
            pic = self.pictures.get(int(lab))
            r = QRectF(c.x() - box / 2, c.y() - box / 2, box, box * 0.78)
            p.setPen(QPen(QColor("#e6e6e6"), 1.2))
            p.setBrush(QColor(250, 248, 243))
            p.drawRoundedRect(r, 6, 6)
            if pic is not None:
                p.drawImage(fit_rect(pic.width(), pic.height(), r.adjusted(3, 3, -3, -3)), pic)
            name = self.names[int(lab)] if int(lab) < len(self.names) else str(lab)
            p.setPen(QColor("#cfd2d8"))
            p.drawText(QRectF(c.x() - 50, r.bottom() + 1, 100, 16), Qt.AlignmentFlag.AlignCenter, name)
        # suggestion
        if self.suggest is not None:
            c = V(self.suggest)
            p.setPen(QPen(QColor("#e0af68"), 2, Qt.PenStyle.DashLine))
            p.setBrush(Qt.BrushStyle.NoBrush)
            p.drawEllipse(c, 12, 12)
            p.setPen(QColor("#e0af68"))
            p.drawText(QRectF(c.x() + 14, c.y() - 9, 160, 18), Qt.AlignmentFlag.AlignVCenter, "add this expression")
        # live point
        if self.live is not None:
            c = V(self.live)
            p.setPen(Qt.PenStyle.NoPen)
            p.setBrush(QColor(255, 255, 255, 40))
            p.drawEllipse(c, 13, 13)
            outside = self.live_loc is not None and self.live_loc.outside > 1e-9
            p.setBrush(QColor("#f7768e") if outside else QColor("#9ece6a"))
            p.drawEllipse(c, 6.5, 6.5)
            if self.live_loc is not None:
                parts = [f"{self.names[i] if i < len(self.names) else i} {w:.2f}"
                         for i, w in zip(self.live_loc.indices, self.live_loc.weights) if w > 0.005]
                p.setPen(QColor("#e6e6e6"))
                p.drawText(QRectF(area.x() + 6, area.bottom() - 20, area.width() - 12, 18),
                           Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter,
                           "live: " + " + ".join(parts) + ("  (outside: snapped to the hull)" if outside else ""))
        # legend
        p.setPen(QColor("#9aa0aa"))
        p.drawText(QRectF(area.x() + 6, area.y() + 2, area.width() - 12, 18),
                   Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter,
                   "hatched: no drawing covers  ·  dots: clip frames (red = outside)")


def _hull(pts: np.ndarray) -> np.ndarray | None:
    """Convex hull polygon of 2-D points (None when degenerate)."""
    if len(pts) < 3:
        return None
    try:
        from scipy.spatial import ConvexHull, QhullError

        h = ConvexHull(pts)
        return pts[h.vertices]
    except (QhullError, ValueError, ImportError):
        return None


# ------------------------------------------------------------------------------------------
# the window


class TrainingWindow(QMainWindow):
    """Pair drawings with frames of a clip of the performer; see and check the expression space."""

    sessionSaved = Signal(object)
    clipTracked = Signal()

    def __init__(self, art_path: str, performer: str = "default", source: SourceSpec | None = None,
                 calibration: Any = None, parent=None, clip=None):
        super().__init__(parent)
        from art_sets.io import load_artset

        self.setWindowTitle("Train the character")
        self.art_path = str(art_path)
        self.artset = load_artset(self.art_path)
        self.performer = performer
        # "performance" / ("clicks", ...) are resolved by the tracking process, not here
        self.calibration_spec = calibration
        self.calibration = None if isinstance(calibration, (str, tuple)) else calibration
        self.clip = clip if clip is not None else open_clip(source)
        self.track: np.ndarray | None = None
        self.tracker_thread: ProcessTask | None = None
        self._recording: list[np.ndarray] | None = None
        self.recordingChanged = Hook()  # True while recording: the live input must be camera-size
        self._record_until = 0.0
        self._diag_worst: dict[str, int] = {}
        self._live_feats: np.ndarray | None = None
        self._undo: list[tuple[str, dict]] = []  # (what was done, the session's state before it)
        self._redo: list[tuple[str, dict]] = []
        # a hook the tests replace to answer without a modal dialog: ("replace" | "keep" | "cancel")
        self.ask_replace_pairs = self._ask_replace_pairs_dialog
        self.session = self._open_session()

        self._build_ui()
        self._update_undo_buttons()
        self.set_frame(0)
        self.refresh()
        self.resize(1320, 900)
        if self.calibration_spec is not None:
            self.track_clip()
        else:
            self.status.setText("No calibration for this performer: calibrate first (Tools → Calibrate) so frames can be tracked.")

    # ------------------------------------------------------------------------------ session
    def _open_session(self):
        from training.session import SessionError, TrainingSession

        folder = session_path(self.performer, self.art_path)
        s = None
        if (folder / "session.json").is_file():
            try:
                s = TrainingSession.load(folder, artset=self.artset)
            except SessionError:
                s = None
        if s is None:
            s = TrainingSession(self.artset.name, path=folder)
        if self.calibration is not None and hasattr(self.calibration, "ipd"):
            try:
                s.set_calibration(self.calibration, ref=str(performer_dir(self.performer) / "calibration.json"))
            except Exception:
                pass
        return s

    # ----------------------------------------------------------------------------------- ui
    def _build_ui(self) -> None:
        self.frame_view = VideoView()
        self.frame_view.placeholder = "No clip"
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, max(0, len(self.clip) - 1))
        self.slider.valueChanged.connect(self.set_frame)
        self.frame_spin = QSpinBox()
        self.frame_spin.setRange(0, max(0, len(self.clip) - 1))
        self.frame_spin.valueChanged.connect(self.slider.setValue)
        self.play_btn = QPushButton("▶")
        self.play_btn.setCheckable(True)
        self.play_btn.setFixedWidth(40)
        self.play_btn.toggled.connect(self._on_play)
        self._play_timer = QTimer(self, interval=33, timeout=lambda: self.slider.setValue((self.slider.value() + 1) % max(1, len(self.clip))))
        self.clip_label = QLabel("")
        self.clip_label.setObjectName("hint")
        open_btn = QPushButton("Open clip…")
        open_btn.clicked.connect(self._open_clip_dialog)
        self.record_btn = QPushButton("● Record 6 s from camera")
        self.record_btn.setToolTip("Record a new training clip from the main window's live input")
        self.record_btn.clicked.connect(lambda: self.start_recording(6.0))

        left = QWidget()
        lv = QVBoxLayout(left)
        lv.setContentsMargins(0, 0, 0, 0)
        t = QLabel("Performer clip")
        t.setObjectName("title")
        lv.addWidget(t)
        lv.addWidget(self.frame_view, 1)
        row = QHBoxLayout()
        row.addWidget(self.play_btn)
        row.addWidget(self.slider, 1)
        row.addWidget(self.frame_spin)
        lv.addLayout(row)
        row = QHBoxLayout()
        row.addWidget(self.clip_label, 1)
        row.addWidget(open_btn)
        row.addWidget(self.record_btn)
        lv.addLayout(row)

        self.tabs = QTabWidget()
        self.cards: dict[tuple[str, str], DrawingCard] = {}
        self.pictures: dict[str, dict[int, QImage]] = {}
        for part in PARTS:
            holder = QWidget()
            grid = QGridLayout(holder)
            grid.setSpacing(10)
            grid.setContentsMargins(8, 8, 8, 8)
            pics = {}
            for i, d in enumerate(self.artset.parts[part].drawings):
                card = DrawingCard(part, d.name, d.image)
                card.pairRequested.connect(self.pair_current)
                card.selected.connect(self._select_card)
                self.cards[(part, d.name)] = card
                grid.addWidget(card, i // 2, i % 2)
                pics[i] = card.drawing
            grid.setRowStretch(grid.rowCount(), 1)
            self.pictures[part] = pics
            sc = QScrollArea()
            sc.setWidgetResizable(True)
            sc.setWidget(holder)
            self.tabs.addTab(sc, part.capitalize())
        self.tabs.currentChanged.connect(lambda _i: self.refresh())
        right = QWidget()
        rv = QVBoxLayout(right)
        rv.setContentsMargins(0, 0, 0, 0)
        t = QLabel(f"Drawings of {self.artset.name} — pick the frame that matches each")
        t.setObjectName("title")
        rv.addWidget(t)
        rv.addWidget(self.tabs, 1)

        top = QSplitter(Qt.Orientation.Horizontal)
        top.addWidget(left)
        top.addWidget(right)
        top.setSizes([640, 560])

        self.space = ExpressionSpaceView()
        self.diag = QLabel("")
        self.diag.setWordWrap(True)
        self.diag.setTextFormat(Qt.TextFormat.RichText)
        self.diag.setAlignment(Qt.AlignmentFlag.AlignTop | Qt.AlignmentFlag.AlignLeft)
        self.suggest_btn = QPushButton("Show the expression to add")
        self.suggest_btn.clicked.connect(self.go_to_suggestion)
        self.suggest_btn.setEnabled(False)
        self.default_btn = QPushButton("Pair automatically")
        self.default_btn.setToolTip("Pair each drawing with the synthetic performer making the face of its name "
                                    "(asks before replacing pairs you picked; Undo takes it back)")
        self.default_btn.clicked.connect(self.pair_defaults)
        self.undo_btn = QPushButton("Undo")
        self.undo_btn.setShortcut(QKeySequence(QKeySequence.StandardKey.Undo))
        self.undo_btn.clicked.connect(self.undo)
        self.redo_btn = QPushButton("Redo")
        self.redo_btn.setShortcut(QKeySequence(QKeySequence.StandardKey.Redo))
        self.redo_btn.clicked.connect(self.redo)
        self.use_btn = QPushButton("Use this training")
        self.use_btn.setObjectName("primary")
        self.use_btn.clicked.connect(self.use_training)
        dv = QVBoxLayout()
        t = QLabel("Diagnostics")
        t.setObjectName("title")
        dv.addWidget(t)
        dsc = QScrollArea()
        dsc.setWidgetResizable(True)
        dsc.setWidget(self.diag)
        dv.addWidget(dsc, 1)
        dv.addWidget(self.suggest_btn)
        dv.addWidget(self.default_btn)
        ur = QHBoxLayout()
        ur.addWidget(self.undo_btn, 1)
        ur.addWidget(self.redo_btn, 1)
        dv.addLayout(ur)
        dv.addWidget(self.use_btn)
        dw = QWidget()
        dw.setLayout(dv)
        dw.setFixedWidth(380)
        bottom = QWidget()
        bh = QHBoxLayout(bottom)
        bh.setContentsMargins(0, 0, 0, 0)
        sv = QVBoxLayout()
        self.space_title = QLabel("Expression space")
        self.space_title.setObjectName("title")
        sv.addWidget(self.space_title)
        sv.addWidget(self.space, 1)
        bh.addLayout(sv, 1)
        bh.addWidget(dw)

        main = QSplitter(Qt.Orientation.Vertical)
        main.addWidget(top)
        main.addWidget(bottom)
        main.setSizes([470, 400])
        central = QWidget()
        cv = QVBoxLayout(central)
        cv.setContentsMargins(14, 12, 14, 8)
        cv.addWidget(main, 1)
        self.status = QLabel("")
        self.status.setObjectName("hint")
        cv.addWidget(self.status)
        self.setCentralWidget(central)

    def part(self) -> str:
        return PARTS[self.tabs.currentIndex()] if self.tabs.currentIndex() >= 0 else "mouth"

    def _select_card(self, part: str, name: str) -> None:
        for (pt, nm), c in self.cards.items():
            c.active = pt == part and nm == name
            c.update()

    # --------------------------------------------------------------------------------- clip
    def set_clip(self, clip) -> None:
        if self.tracker_thread is not None and self.tracker_thread.isRunning():
            self.tracker_thread.cancel()
            self.tracker_thread.wait(5000)
        self.clip = clip
        self.track = None
        n = max(0, len(clip) - 1)
        self.slider.setRange(0, n)
        self.frame_spin.setRange(0, n)
        self.set_frame(0)
        if self.calibration_spec is not None:
            self.track_clip()

    def _open_clip_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "A clip of the performer", str(performer_dir(self.performer)),
                                              "Videos (*.mp4 *.avi *.mkv *.mov);;All files (*)")
        if path:
            try:
                self.set_clip(VideoClip(path))
            except Exception as e:
                self.status.setText(_one_line(e))

    def track_clip(self) -> None:
        """Track every frame of the clip in the background (for pairing and the frame cloud)."""
        self.status.setText(f"Tracking the clip ({len(self.clip)} frames)…")
        self.tracker_thread = ProcessTask("app.training_window:track_clip_task", clip_descriptor(self.clip),
                                          self.calibration if self.calibration is not None else self.calibration_spec)
        self.tracker_thread.progress.connect(lambda i, n: self.status.setText(f"Tracking the clip… {i}/{n}"))
        self.tracker_thread.done.connect(self._on_tracked)
        self.tracker_thread.failed.connect(lambda m: self.status.setText(f"Tracking failed: {m}"))
        self.tracker_thread.start()

    def _on_tracked(self, result) -> None:
        track, cal = result
        if self.calibration is None and cal is not None:
            self.calibration = cal
            try:
                self.session.set_calibration(cal, ref=str(performer_dir(self.performer) / "calibration.json"))
            except Exception:
                pass
        self.track = track
        ok = np.all(np.isfinite(track), axis=1)
        ref = getattr(self.clip, "path", None) or self.clip.name
        try:
            self.session.set_reference(ref, np.where(ok[:, None], track, np.nanmean(track[ok], axis=0) if ok.any() else 0))
        except Exception as e:
            self.status.setText(_one_line(e))
        self.status.setText(f"Tracked {int(ok.sum())} of {len(track)} frames. Scrub to an expression, then press "
                            "“Use this frame” on the matching drawing.")
        self.refresh()
        self.set_frame(self.slider.value())
        self.clipTracked.emit()

    def set_frame(self, i: int) -> None:
        if len(self.clip) == 0:
            return
        i = int(np.clip(i, 0, len(self.clip) - 1))
        for w, v in ((self.slider, i), (self.frame_spin, i)):
            if w.value() != v:
                w.blockSignals(True)
                w.setValue(v)
                w.blockSignals(False)
        try:
            img = self.clip.frame(i)
        except Exception as e:
            self.status.setText(_one_line(e))
            return
        self.frame_view.set_frame(bgr_to_qimage(img))
        self.clip_label.setText(f"{self.clip.name} · frame {i} of {len(self.clip)}")
        vals = self.values_at(i)
        if self._recording is None and self._live_feats is None:
            self.space.set_live(self._feats(self.part(), vals) if vals is not None else None)

    def values_at(self, i: int) -> np.ndarray | None:
        if self.track is None or i >= len(self.track) or not np.all(np.isfinite(self.track[i])):
            return None
        return self.track[i]

    def _on_play(self, on: bool) -> None:
        self.play_btn.setText("❚❚" if on else "▶")
        (self._play_timer.start if on else self._play_timer.stop)()

    # ------------------------------------------------------------------------------ pairing
    def pair_current(self, part: str, drawing: str) -> bool:
        """Pair ``drawing`` of ``part`` with the frame under the scrubber (replacing its old pair)."""
        i = self.slider.value()
        vals = self.values_at(i)
        if vals is None:
            self.status.setText(f"Frame {i} has no tracked values yet (tracking still running, or the face was lost).")
            return False
        before = self._state()
        for k in reversed(range(len(self.session.pairs))):
            pr = self.session.pairs[k]
            if pr.part == part and pr.drawing == drawing and pr.blend is None:
                self.session.pairs.pop(k)
        try:
            self.session.add_pair(part, drawing, vals, frame=i, image=self.clip.frame(i), bgr=True)
        except Exception as e:
            self._restore(before)
            self.status.setText(f"Could not save the pair: {_one_line(e)}")
            return False
        self._did(f"pair {part}/{drawing} with frame {i}", before)
        self.status.setText(f"{part}/{drawing} ← frame {i}  (saved to {self.session.path})")
        self.refresh()
        return True

    def hand_picked(self) -> list:
        """The pairs the user made (frames of a clip), as opposed to automatic ones."""
        return [p for p in self.session.pairs if not p.source]

    def pair_defaults(self) -> bool:
        """Pair each drawing with the synthetic performer making the face of its name.

        Pairs the user picked are only replaced when they say so ("replace"); "keep" pairs only
        the drawings they left unpaired. Either way one Undo takes it back. True if it paired."""
        try:
            from training.defaults import default_session, expression_for
        except ImportError:
            self.status.setText("Automatic pairing is not available in this build.")
            return False
        mine = self.hand_picked()
        choice = "replace"
        if mine:
            choice = self.ask_replace_pairs(len(mine))
            if choice not in ("replace", "keep"):
                self.status.setText("Automatic pairing cancelled; your pairs are unchanged.")
                return False
        try:
            d = default_session(self.artset, thumbnails=True, reference=self.session.reference_track is None)
        except Exception as e:
            self.status.setText(f"Automatic pairing failed: {_one_line(e)}")
            return False
        for pr in d.pairs:
            expr = expression_for(pr.part, pr.drawing) if pr.drawing else None
            pr.source = f"{SYNTHETIC}{expr or pr.drawing}"
        before = self._state()
        if choice == "keep":
            taken = {(p.part, p.drawing) for p in mine}
            taken |= {(p.part, n) for p in mine if p.blend for n in p.blend}
            new = [p for p in d.pairs if (p.part, p.drawing) not in taken]
            self.session.pairs = mine + new
        else:
            new = list(d.pairs)
            self.session.pairs = new
        if self.session.features is None and d.features is not None:
            self.session.features = d.features
        if self.session.reference_track is None and d.reference_track is not None:
            self.session.reference_track = d.reference_track
            self.session.reference_clip = d.reference_clip
        try:
            self.session._changed()
        except Exception as e:
            self._restore(before)
            self.status.setText(f"Automatic pairing not saved: {_one_line(e)}")
            return False
        self._did("automatic pairing", before)
        kept = f", kept your {len(mine)}" if choice == "keep" and mine else (
            f", replacing your {len(mine)}" if mine else "")
        self.status.setText(f"Paired automatically: {len(new)} pairs{kept}. Undo (Ctrl+Z) takes it back.")
        self.refresh()
        return True

    def _ask_replace_pairs_dialog(self, n_mine: int) -> str:
        box = QMessageBox(self)
        box.setWindowTitle("Pair automatically")
        box.setIcon(QMessageBox.Icon.Question)
        box.setText(f"You picked {n_mine} pair{'s' if n_mine != 1 else ''} yourself.")
        box.setInformativeText("Automatic pairing uses the synthetic performer's faces, not your clip. "
                               "Replace your pairs too, or only pair the drawings you have not paired?\n"
                               "Either way, Undo takes it back.")
        keep = box.addButton("Keep mine, pair the rest", QMessageBox.ButtonRole.AcceptRole)
        replace = box.addButton("Replace mine", QMessageBox.ButtonRole.DestructiveRole)
        box.addButton(QMessageBox.StandardButton.Cancel)
        box.setDefaultButton(keep)
        box.exec()
        return "keep" if box.clickedButton() is keep else "replace" if box.clickedButton() is replace else "cancel"

    # --------------------------------------------------------------------------------- undo
    def _state(self) -> dict:
        """What an undo step restores: the pairs (the list; pairs themselves never change) and
        what automatic pairing may fill in."""
        s = self.session
        return {"pairs": list(s.pairs), "features": s.features, "reference_clip": s.reference_clip,
                "reference_track": s.reference_track}

    def _restore(self, state: dict) -> None:
        s = self.session
        s.pairs = list(state["pairs"])
        s.features = state["features"]
        s.reference_clip = state["reference_clip"]
        s.reference_track = state["reference_track"]
        for p in s.pairs:  # thumbnails a save removed are written again from memory
            if p.thumb_file and p.thumbnail is not None and (s.path is None or not (s.path / p.thumb_file).is_file()):
                p.thumb_file = ""

    def _did(self, what: str, before: dict) -> None:
        self._undo.append((what, before))
        del self._undo[:-50]
        self._redo.clear()
        self._update_undo_buttons()

    def _step(self, src: list, dst: list, verb: str) -> bool:
        if not src:
            return False
        what, state = src.pop()
        dst.append((what, self._state()))
        self._restore(state)
        try:
            self.session._changed()
        except Exception as e:
            self.status.setText(f"{verb} {what}, but could not save: {_one_line(e)}")
        else:
            self.status.setText(f"{verb} {what}.")
        self._update_undo_buttons()
        self.refresh()
        return True

    def undo(self) -> bool:
        """Take back the last pairing (automatic or by hand); True if there was one."""
        return self._step(self._undo, self._redo, "Undid")

    def redo(self) -> bool:
        return self._step(self._redo, self._undo, "Redid")

    def _update_undo_buttons(self) -> None:
        self.undo_btn.setEnabled(bool(self._undo))
        self.redo_btn.setEnabled(bool(self._redo))
        self.undo_btn.setToolTip(f"Undo {self._undo[-1][0]} (Ctrl+Z)" if self._undo else "Nothing to undo")
        self.redo_btn.setToolTip(f"Redo {self._redo[-1][0]} (Ctrl+Shift+Z)" if self._redo else "Nothing to redo")

    def use_training(self) -> None:
        try:
            self.session.check(self.artset)
            if self.session.path is not None:
                self.session.save()
        except Exception as e:
            self.status.setText(_one_line(e))
            return
        self.sessionSaved.emit(self.session)
        self.status.setText("Training handed to the performance window.")

    # ---------------------------------------------------------------------- space + diagnostics
    def _feats(self, part: str, values) -> np.ndarray | None:
        try:
            return self.session.feature_space().part(part, values)
        except Exception:
            return None

    def refresh(self) -> None:
        """Redraw cards, the expression space and the diagnostics after any change."""
        by = {(p.part, p.drawing): p for p in self.session.pairs if p.blend is None}
        for (part, name), card in self.cards.items():
            pr = by.get((part, name))
            card.set_pair(rgb_qimage(pr.thumbnail) if pr is not None and pr.thumbnail is not None else None,
                          pr.frame if pr is not None else None, pr.source if pr is not None else "",
                          getattr(self.clip, "name", ""))
        part = self.part()
        names = self.artset.parts[part].names()
        self.space_title.setText(f"Expression space — {part} (PCA plane of the training points, Delaunay triangles)")
        emap = None
        cloud = None
        try:
            pts, labels = self.session.training_points(part, names)
            if len(pts):
                from morph.expression_map import ExpressionMap

                emap = ExpressionMap(pts, labels=labels)
                if self.session.reference_track is not None:
                    cloud = self.session.feature_space().part(part, self.session.reference_track)
        except Exception as e:
            self.space.message = _one_line(e)
        self.space.set_map(emap, names, self.pictures.get(part, {}), cloud)
        vals = self.values_at(self.slider.value())
        self.space.set_live(self._feats(part, vals) if vals is not None else None)
        self._update_diagnostics(part)

    def _update_diagnostics(self, part: str) -> None:
        names = self.artset.parts[part].names()
        paired = {p.drawing for p in self.session.pairs_of(part) if p.blend is None}
        missing = [n for n in names if n not in paired]
        lines = [f"<b>{len(paired)}</b> of {len(names)} {part} drawings paired."]
        if missing:
            lines.append("Still to pair: " + ", ".join(f"<i>{n}</i>" for n in missing) + ".")
        self._diag_worst.pop(part, None)
        self.suggest_btn.setEnabled(False)
        self.space.set_suggestion(None)
        try:
            from training.diagnostics import report

            rep = report(self.session, self.artset)[part]
        except Exception as e:
            if self.session.pairs_of(part):
                lines.append(f"<span style='color:#9aa0aa'>({_one_line(e)})</span>")
            self.diag.setText("<br>".join(lines))
            return
        loo = rep.get("loo") or []
        if loo:
            lines.append("<br><b>Leave-one-out</b>: each pair predicted by the others (own weight, 1 = perfect; "
                         "a drawing with one pair shows what would stand in for it, and how far off that is):")
            for r in loo:
                pred = ", ".join(f"{n} {w:.2f}" for n, w in r.predicted[:3])
                if r.recon_error is None:  # the part's only pair: nothing else to predict it
                    lines.append(f"<span style='color:#6b6f76'>■</span> {r.name}: the only pair so far — "
                                 "pair another drawing to see how the others stand in for it")
                    continue
                if r.alone:  # its own weight is 0 by construction: show what stands in for it
                    lines.append(f"<span style='color:#6b6f76'>■</span> {r.name}: without it → {pred} "
                                 f"<span style='color:#9aa0aa'>(error {r.recon_error:.3f})</span>")
                    continue
                col = "#9ece6a" if r.weight_error < 0.34 else ("#e0af68" if r.weight_error < 0.67 else "#f7768e")
                lines.append(f"<span style='color:{col}'>■</span> {r.name}: {1 - r.weight_error:.2f} "
                             f"<span style='color:#9aa0aa'>(from {pred}; error {r.recon_error:.3f})</span>")
        cov = rep.get("coverage")
        if cov is not None and not cov.hull:
            lines.append(f"<br><b>Coverage</b>: {cov.suggestion[len(part) + 2:]}.")
        elif cov is not None:
            lines.append(f"<br><b>Coverage</b>: {cov.outside_share:.0%} of the clip's {cov.frames} frames fall "
                         f"outside the drawings (max {cov.max_outside:.3f}).")
            if cov.worst_frame >= 0:
                self._diag_worst[part] = int(cov.worst_frame)
                self.suggest_btn.setEnabled(True)
                vals = self.values_at(cov.worst_frame)
                if vals is not None:
                    self.space.set_suggestion(self._feats(part, vals))
                lines.append(f"<span style='color:#e0af68'>Suggestion: {cov.suggestion}</span>")
        self.diag.setText("<br>".join(lines))

    def go_to_suggestion(self) -> None:
        """Scrub to the frame that falls farthest outside: the expression to draw and add."""
        f = self._diag_worst.get(self.part())
        if f is not None:
            self.slider.setValue(f)
            self.status.setText(f"Frame {f} is the expression no drawing covers: draw it (or pair a drawing with it).")

    # -------------------------------------------------------------------------- live input
    def live_frame(self, fr) -> None:
        """A frame from the main window: records it when recording; moves the live point."""
        if fr is None:
            return
        if self._recording is not None and fr.frame_bgr is not None:
            self._recording.append(fr.frame_bgr.copy())
            if time.monotonic() >= self._record_until:
                self._finish_recording()
            return
        params = getattr(fr, "params", None)
        if params is not None and self.isVisible() and not self.play_btn.isChecked() and self.track is None:
            self.space.set_live(self._feats(self.part(), params.values()))

    def start_recording(self, seconds: float = 6.0) -> None:
        self._recording = []
        self.recordingChanged.emit(True)
        self._record_until = time.monotonic() + seconds
        self.record_btn.setEnabled(False)
        self.record_btn.setText("Recording…")
        self.status.setText(f"Recording {seconds:.0f} s from the live input: make every expression of the drawings.")

    def _finish_recording(self) -> Path | None:
        frames, self._recording = self._recording, None
        self.recordingChanged.emit(False)
        frames = [f for f in frames if f.shape == frames[-1].shape]  # the first may predate full size
        self.record_btn.setEnabled(True)
        self.record_btn.setText("● Record 6 s from camera")
        if not frames:
            self.status.setText("No frames arrived while recording.")
            return None
        import cv2

        folder = performer_dir(self.performer) / "clips"
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / time.strftime("clip-%Y%m%d-%H%M%S.avi")
        tmp = path.with_name("." + path.name)
        h, w = frames[0].shape[:2]
        vw = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (w, h))
        for f in frames:
            vw.write(f)
        vw.release()
        tmp.replace(path)
        self.status.setText(f"Recorded {len(frames)} frames to {path}")
        self.set_clip(VideoClip(path))
        return path

    def closeEvent(self, ev) -> None:
        self._play_timer.stop()
        if self.tracker_thread is not None and self.tracker_thread.isRunning():
            self.tracker_thread.cancel()
            self.tracker_thread.wait(5000)
        super().closeEvent(ev)
