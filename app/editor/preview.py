"""Preview panel: see a part morph while you edit its lines.

Three modes, one per tab: a slider between any two drawings of the part (with the plain
cross-dissolve beside it, so ghosting — doubled strokes where lines are missing or wrong — is
visible at once), a triangle in which you drag a point to blend three drawings, and live mode in
which the tracker drives the whole character (when the tracker and training modules are present).

Morphs use ``morph.polymorph.PartMorpher`` built only on the drawings shown (cheap to rebuild
after every line edit); without it the exact ``morph.beier_neely.polymorph_exact``; without
either, a cross-dissolve with a visible note.
"""

from __future__ import annotations

import threading
import time

import numpy as np
from PySide6.QtCore import QPointF, QRectF, QSize, Qt, QTimer, Signal
from PySide6.QtGui import QColor, QPainter, QPen, QPolygonF
from PySide6.QtWidgets import (
    QComboBox, QGridLayout, QHBoxLayout, QLabel, QPushButton, QSizePolicy, QSlider, QTabWidget,
    QVBoxLayout, QWidget,
)

from art_sets import editing as ed

from .document import EditorDocument
from .imaging import checker_brush, rgba_to_qimage


class MorphEngine:
    """Renders blends of one part's drawings; picks the best morph code that is installed.

    ``PartMorpher`` tables are built for the drawings shown and kept while their image and
    line arrays stay the same objects (edits always replace arrays, never change them). With
    ``wait=False`` a needed rebuild runs on a worker thread and :meth:`render` returns None
    until it is ready, so the window never stalls after an edit.
    """

    def __init__(self):
        self.note = ""
        self._src: tuple[list, list] | None = None  # the arrays the current morpher was built from
        self._morpher = None
        self._lock = threading.Lock()
        self._building: threading.Thread | None = None
        self._built: tuple | None = None  # (src, morpher or exception) from the worker
        try:
            from morph.layers import LayeredMorpher
            from morph.polymorph import PartMorpher

            self._PartMorpher = PartMorpher
            self._LayeredMorpher = LayeredMorpher
        except Exception:
            self._PartMorpher = self._LayeredMorpher = None
        try:
            from morph.beier_neely import polymorph_exact

            self._exact = polymorph_exact
        except Exception:
            self._exact = None
        if self._PartMorpher is None and self._exact is None:
            self.note = "morph engine not available: showing a cross-dissolve"

    def wait(self, timeout: float = 10.0) -> None:
        """Let a table build in progress finish (before the window closes)."""
        t = self._building
        if t is not None:
            t.join(timeout)

    @property
    def busy(self) -> bool:
        return self._building is not None and self._building.is_alive()

    def _same(self, src) -> bool:
        return self._src is not None and self._src_matches(self._src, src)

    def _make(self, images, lines, drawings):
        """A morpher of the shown drawings: their layers morphed and stacked when they have layers."""
        if drawings is not None:
            return self._LayeredMorpher(drawings, alpha_steps=11)
        return self._PartMorpher(images, lines, alpha_steps=11)

    def _build_in_background(self, src, images, lines, drawings=None) -> None:
        if self.busy:
            return  # the caller polls; the newest request is started when this one ends

        def work():
            try:
                result = self._make(images, lines, drawings)
            except Exception as e:  # reported by render()
                result = e
            with self._lock:
                self._built = (src, result)

        self._building = threading.Thread(target=work, name="editor-morph", daemon=True)
        self._building.start()

    def render(self, part, indices, weights, wait: bool = True) -> tuple[np.ndarray, bool] | None:
        """Blend of ``part.drawings[indices]`` with ``weights``: (RGBA, premultiplied?).

        Returns None only with ``wait=False`` while the morph tables are being built.
        """
        idx = [int(i) for i in indices]
        uniq = sorted(set(idx))
        images = [part.drawings[i].image for i in uniq]
        raw_lines = [part.drawings[i].lines for i in uniq]
        lines = [np.asarray(l, np.float64).reshape(-1, 4) for l in raw_lines]
        wmap = {i: 0.0 for i in uniq}
        for i, w in zip(idx, weights):
            wmap[i] += float(w)
        w = [wmap[i] for i in uniq]
        if len({im.shape for im in images}) != 1:
            self.note = "drawings of different sizes: resize or crop them to the box (Edit menu)"
            size = part.size
            images = [im if (im.shape[1], im.shape[0]) == size else ed.resize_image(im, size) for im in images]
            return ed.cross_dissolve(images, w), False
        if len({len(l) for l in lines}) != 1:
            self.note = "line counts differ: showing a cross-dissolve"
            return ed.cross_dissolve(images, w), False
        if self._PartMorpher is not None:
            shown = [part.drawings[i] for i in uniq]
            names = {tuple(ly.name for ly in d.layers) for d in shown}
            drawings = shown if len(names) == 1 and next(iter(names)) else None
            src = (list(images), list(raw_lines))
            with self._lock:
                built, self._built = self._built, None
            if built is not None and not isinstance(built[1], Exception):
                self._src, self._morpher = built
            try:
                if built is not None and isinstance(built[1], Exception) and self._src_matches(built[0], src):
                    raise built[1]
                if not self._same(src):
                    if not wait:
                        self._build_in_background(src, images, lines, drawings)
                        return None
                    self._morpher, self._src = self._make(images, lines, drawings), src
                self.note = ""
                return self._morpher.render(list(range(len(uniq))), w), True
            except Exception as e:  # a bug in morph must not close the editor
                self.note = f"morph failed ({_one_line(e)}): showing a cross-dissolve"
                self._src = None
        elif self._exact is not None:
            try:
                self.note = "fast morph not available: exact Beier–Neely (slower)"
                return self._exact(images, lines, w), True
            except Exception as e:
                self.note = f"morph failed ({_one_line(e)}): showing a cross-dissolve"
        return ed.cross_dissolve(images, w), False

    @staticmethod
    def _src_matches(a, b) -> bool:
        return len(a[0]) == len(b[0]) and all(x is y for x, y in zip(a[0] + a[1], b[0] + b[1]))


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


class ImageLabel(QWidget):
    """Shows an RGBA image fitted and centred over a checkerboard, with a caption."""

    def __init__(self, caption: str = "", parent=None):
        super().__init__(parent)
        self.caption = caption
        self._img = None
        self._checker = checker_brush(6)
        self.setMinimumSize(120, 70)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)

    def set_image(self, rgba: np.ndarray | None, premultiplied: bool = False) -> None:
        self._img = None if rgba is None else rgba_to_qimage(rgba, premultiplied)
        self.update()

    def paintEvent(self, ev):
        p = QPainter(self)
        p.setRenderHint(QPainter.SmoothPixmapTransform)
        p.fillRect(self.rect(), QColor(58, 60, 66))
        top = 16 if self.caption else 0
        if self._img is not None:
            iw, ih = self._img.width(), self._img.height()
            s = min((self.width() - 8) / iw, (self.height() - top - 8) / ih)
            w, h = iw * s, ih * s
            r = QRectF((self.width() - w) / 2, top + (self.height() - top - h) / 2, w, h)
            p.fillRect(r, self._checker)
            p.drawImage(r, self._img)
        if self.caption:
            p.setPen(QColor(225, 225, 225))
            p.drawText(QRectF(4, 0, self.width() - 8, 16), Qt.AlignLeft | Qt.AlignVCenter, self.caption)


class TriangleWidget(QWidget):
    """An equilateral triangle with a point you drag; emits barycentric weights (corner A, B, C)."""

    weightsChanged = Signal(object)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setMinimumSize(150, 130)
        self.point = None  # widget coordinates; None = centroid
        self.labels = ["A", "B", "C"]

    def corners(self) -> list[QPointF]:
        m = 22
        w, h = self.width() - 2 * m, self.height() - 2 * m
        side = min(w, h * 2 / np.sqrt(3))
        th = side * np.sqrt(3) / 2
        cx, top = self.width() / 2, m + (h - th) / 2
        return [QPointF(cx, top), QPointF(cx - side / 2, top + th), QPointF(cx + side / 2, top + th)]

    def weights(self) -> np.ndarray:
        c = self.corners()
        if self.point is None:
            return np.array([1 / 3, 1 / 3, 1 / 3])
        return ed.triangle_weights((self.point.x(), self.point.y()), [(q.x(), q.y()) for q in c])

    def set_weights(self, w) -> None:
        c = self.corners()
        w = np.asarray(w, np.float64) / max(float(np.sum(w)), 1e-9)
        self.point = QPointF(sum(wi * q.x() for wi, q in zip(w, c)), sum(wi * q.y() for wi, q in zip(w, c)))
        self.update()
        self.weightsChanged.emit(self.weights())

    def paintEvent(self, ev):
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        c = self.corners()
        p.setPen(QPen(QColor(120, 120, 130), 1.5))
        p.setBrush(QColor(245, 243, 236))
        p.drawPolygon(QPolygonF(c))
        w = self.weights()
        pt = QPointF(sum(wi * q.x() for wi, q in zip(w, c)), sum(wi * q.y() for wi, q in zip(w, c)))
        cols = [QColor(220, 80, 60), QColor(60, 140, 220), QColor(60, 170, 90)]
        text = self.palette().color(self.foregroundRole())
        for q, col, lab, wi in zip(c, cols, self.labels, w):
            p.setPen(Qt.NoPen)
            p.setBrush(col)
            p.drawEllipse(q, 5, 5)
            p.setPen(text)
            off = QPointF(0, -16) if q.y() < pt.y() else QPointF(0, 16)
            p.drawText(QRectF(q.x() - 60 + off.x(), q.y() - 8 + off.y(), 120, 16), Qt.AlignCenter, f"{lab} {wi:.2f}")
        p.setPen(QPen(QColor(20, 20, 20), 2))
        p.setBrush(QColor(255, 210, 60))
        p.drawEllipse(pt, 7, 7)

    def mousePressEvent(self, ev):
        self._move(ev.position())

    def mouseMoveEvent(self, ev):
        if ev.buttons() & Qt.LeftButton:
            self._move(ev.position())

    def _move(self, pos):
        c = self.corners()
        w = ed.triangle_weights((pos.x(), pos.y()), [(q.x(), q.y()) for q in c])
        self.point = QPointF(sum(wi * q.x() for wi, q in zip(w, c)), sum(wi * q.y() for wi, q in zip(w, c)))
        self.update()
        self.weightsChanged.emit(w)

    def sizeHint(self):
        return QSize(220, 180)


class PreviewPanel(QWidget):
    """Two-drawing slider, three-drawing triangle and live mode for the selected part."""

    def __init__(self, doc: EditorDocument, parent=None):
        super().__init__(parent)
        self.doc = doc
        self.engine = MorphEngine()
        self.wait_for_morph = False  # tests set True to render synchronously
        self.live = None
        self._stopped: list = []  # live previews told to stop, joined when the window closes
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        self.morph_view = ImageLabel("morph")
        self.dissolve_view = ImageLabel("cross-dissolve (doubled strokes = ghosting)")
        lay.addWidget(self.morph_view, 3)
        lay.addWidget(self.dissolve_view, 2)
        self.note = QLabel("")
        self.note.setWordWrap(True)
        self.note.setStyleSheet("color: #b35c00;")
        lay.addWidget(self.note)

        self.tabs = QTabWidget()
        lay.addWidget(self.tabs, 2)
        # two-way
        two = QWidget()
        g = QGridLayout(two)
        self.combo_a, self.combo_b = QComboBox(), QComboBox()
        self.slider = QSlider(Qt.Horizontal)
        self.slider.setRange(0, 100)
        self.slider.setValue(50)
        self.slider_label = QLabel("50 %")
        g.addWidget(QLabel("from"), 0, 0)
        g.addWidget(self.combo_a, 0, 1)
        g.addWidget(QLabel("to"), 1, 0)
        g.addWidget(self.combo_b, 1, 1)
        g.addWidget(self.slider, 2, 0, 1, 2)
        g.addWidget(self.slider_label, 3, 0, 1, 2)
        g.setRowStretch(4, 1)
        self.tabs.addTab(two, "Two drawings")
        # three-way
        three = QWidget()
        v = QVBoxLayout(three)
        combos = QHBoxLayout()
        self.tri_combos = [QComboBox() for _ in range(3)]
        for cb in self.tri_combos:
            combos.addWidget(cb)
        v.addLayout(combos)
        self.triangle = TriangleWidget()
        v.addWidget(self.triangle, 1)
        self.tabs.addTab(three, "Three drawings")
        # live
        livew = QWidget()
        lv = QVBoxLayout(livew)
        self.live_source = QComboBox()
        self.live_source.addItems(["bundled performance", "camera 0"])
        lv.addWidget(self.live_source)
        self.live_button = QPushButton("Start live preview")
        self.live_button.setCheckable(True)
        self.live_status = QLabel("The tracker drives the whole character being edited, from the bundled performance or a camera.")
        self.live_status.setWordWrap(True)
        lv.addWidget(self.live_button)
        lv.addWidget(self.live_status)
        lv.addStretch(1)
        self.tabs.addTab(livew, "Live")

        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(40)
        self._timer.timeout.connect(self.refresh)
        self._filling = False
        for cb in [self.combo_a, self.combo_b] + self.tri_combos:
            cb.currentIndexChanged.connect(self._schedule)
        self.slider.valueChanged.connect(self._schedule)
        self.triangle.weightsChanged.connect(self._schedule)
        self.tabs.currentChanged.connect(self._on_tab)
        self.live_button.toggled.connect(self._toggle_live)
        doc.changed.connect(self._fill_combos)
        doc.selectionChanged.connect(self._fill_combos)
        self._fill_combos()

    def sizeHint(self):
        return QSize(300, 600)

    def _schedule(self, *_):
        if not self._filling:
            self._timer.start()

    def _fill_combos(self):
        art = self.doc.artset
        names = art.parts[self.doc.part].names() if art else []
        self._filling = True
        try:
            defaults = [0, 1, 2]
            for k, cb in enumerate([self.combo_a, self.combo_b] + self.tri_combos):
                cur = cb.currentText()
                cb.clear()
                cb.addItems(names)
                if cur in names:
                    cb.setCurrentIndex(names.index(cur))
                elif names:
                    d = [0, 1][k] if k < 2 else defaults[k - 2]
                    cb.setCurrentIndex(min(d, len(names) - 1))
            self.triangle.labels = [cb.currentText() or "?" for cb in self.tri_combos]
        finally:
            self._filling = False
        self._timer.start()

    def _on_tab(self, i):
        if self.tabs.widget(i) is not None and self.tabs.tabText(i) != "Live" and self.live_button.isChecked():
            self.live_button.setChecked(False)
        self._schedule()

    def current_blend(self) -> tuple[list[int], list[float]] | None:
        """The drawings and weights the visible tab asks for (None in live mode or without drawings)."""
        art = self.doc.artset
        if art is None or not art.parts[self.doc.part].drawings:
            return None
        tab = self.tabs.tabText(self.tabs.currentIndex())
        if tab.startswith("Two"):
            t = self.slider.value() / 100.0
            return [max(self.combo_a.currentIndex(), 0), max(self.combo_b.currentIndex(), 0)], [1 - t, t]
        if tab.startswith("Three"):
            self.triangle.labels = [cb.currentText() or "?" for cb in self.tri_combos]
            return [max(cb.currentIndex(), 0) for cb in self.tri_combos], list(self.triangle.weights())
        return None

    def refresh(self):
        blend = self.current_blend()
        self.slider_label.setText(f"{self.slider.value()} % of the way")
        if blend is None:
            if self.live is None:
                self.morph_view.set_image(None)
                self.dissolve_view.set_image(None)
            return
        part = self.doc.artset.parts[self.doc.part]
        idx, w = blend
        self.dissolve_view.set_image(ed.cross_dissolve([part.drawings[i].image for i in idx], w))
        out = self.engine.render(part, idx, w, wait=self.wait_for_morph)
        if out is None:  # tables are being built on a worker thread: keep the last morph, poll
            self.morph_view.caption = "morph (updating…)"
            self.morph_view.update()
            self._timer.start(60)
            return
        img, pm = out
        self.morph_view.caption = "morph"
        self.morph_view.set_image(img, pm)
        self.note.setText(self.engine.note)
        self.note.setVisible(bool(self.engine.note))

    # ---------------------------------------------------------------- live mode
    def _toggle_live(self, on: bool):
        if not on:
            if self.live is not None:
                self.live.stop(wait=0.0)  # it ends by itself after the current frame
                self._stopped.append(self.live)
                self.live = None
            self.live_button.setText("Start live preview")
            self.dissolve_view.show()
            return
        if self.doc.artset is None:
            self.live_button.setChecked(False)
            return
        src = "camera" if self.live_source.currentIndex() == 1 else "performance"
        self.live = LivePreview(self.doc, self._show_live, src, on_stop=self._live_stopped)
        self.live_button.setText("Stop live preview")
        self.live_status.setText(self.live.describe())
        self.dissolve_view.hide()

    def _show_live(self, rgba_pm: np.ndarray | None, note: str):
        if rgba_pm is not None:
            self.morph_view.caption = "live"
            self.morph_view.set_image(rgba_pm, True)
        self.live_status.setText(note)

    def _live_stopped(self):
        if self.live is not None:
            self._stopped.append(self.live)
        self.live = None
        self.live_button.blockSignals(True)
        self.live_button.setChecked(False)
        self.live_button.blockSignals(False)
        self.live_button.setText("Start live preview")
        self.dissolve_view.show()

    def stop(self):
        """Stop live mode and wait for background work (the window is closing)."""
        self._timer.stop()
        if self.live is not None:
            self._stopped.append(self.live)
            self.live = None
        for live in self._stopped:
            live.stop(wait=15.0)
        self._stopped.clear()
        self.engine.wait()


_CALIBRATION: list = []  # the bundled performer's calibration, made once per process


def _performance_calibration(workers):
    if not _CALIBRATION:
        try:
            _CALIBRATION.append(workers.performance_calibration(workers.bundled_performance()))
        except Exception:  # the puppet can still run uncalibrated
            return None
    return _CALIBRATION[0]


class LivePreview:
    """Feeds frames through a ``training.puppet.Puppet`` built on the art set being edited.

    Everything slow — opening the source, calibrating on the bundled performance, building the
    puppet's α tables, tracking and rendering — runs on a worker thread at about 15 fps; the GUI
    only shows the newest frame. The source is the bundled performance (the synthetic performer,
    calibrated from its own clicks) or camera 0. After an edit the puppet is rebuilt from a
    snapshot once the edits have paused for a moment.
    """

    REBUILD_PAUSE_S = 0.8
    FRAME_S = 1 / 15

    def __init__(self, doc: EditorDocument, show, source: str = "performance", on_stop=None):
        self.doc, self.show, self.kind, self.on_stop = doc, show, source, on_stop
        self.what = "camera 0" if source == "camera" else "the bundled performance"
        self._lock = threading.Lock()
        self._latest = None  # (rgba_pm, note) from the worker
        self._error: str | None = None
        self._stop = threading.Event()
        self._art = ed.clone(doc.artset)  # snapshot the worker renders (arrays are shared, never changed)
        self._art_version = 0
        self._changed_at = 0.0
        doc.changed.connect(self._on_changed)
        self._connected = True
        self.timer = QTimer()
        self.timer.setInterval(40)
        self.timer.timeout.connect(self._poll)
        self.timer.start()
        self.thread = threading.Thread(target=self._run, name="editor-live", daemon=True)
        self.thread.start()

    def describe(self) -> str:
        return f"starting live preview from {self.what} (building the puppet)…"

    def _on_changed(self):
        with self._lock:
            self._art = ed.clone(self.doc.artset)
            self._art_version += 1
            self._changed_at = time.monotonic()

    def _run(self):
        try:
            from app import workers  # the window's helpers: sources with fallbacks, puppet building

            calibration = None
            if self.kind == "camera":
                src = workers.open_source(workers.SourceSpec(kind="camera", camera=0))
            else:
                src = workers.open_source(workers.SourceSpec(kind="performance"))
                calibration = _performance_calibration(workers)
            self.source = src
            frames = iter(src)
            version, puppet = -1, None
            while not self._stop.is_set():
                t0 = time.monotonic()
                with self._lock:
                    art, v, changed = self._art, self._art_version, self._changed_at
                if puppet is None or (v != version and t0 - changed > self.REBUILD_PAUSE_S):
                    puppet = workers.make_puppet(art, workers.PuppetSpec(calibration=calibration, fps=15))
                    version = v
                try:
                    fr = next(frames)
                except StopIteration:
                    frames = iter(src)
                    continue
                out = puppet.step(fr.image, fr.index, fr.time)
                ms = sum(getattr(out, "timings_ms", {}).values())
                status = getattr(getattr(out, "params", None), "status", "")
                stale = "  (showing the set before your last edits)" if v != version else ""
                with self._lock:
                    self._latest = (out.rgba_pm, f"live from {self.what} — {status} — {ms:.1f} ms a frame{stale}")
                self._stop.wait(max(self.FRAME_S - (time.monotonic() - t0), 0.0))
        except Exception as e:  # anything from the core: stop and say why, in one line
            self._error = _one_line(e)
        finally:
            try:
                self.source.close()
            except Exception:
                pass

    def _poll(self):
        if self._error is not None:
            msg = self._error
            self.stop()
            self.show(None, f"live preview stopped: {msg}")
            if self.on_stop is not None:
                self.on_stop()
            return
        with self._lock:
            latest, self._latest = self._latest, None
        if latest is not None:
            self.show(*latest)

    def stop(self, wait: float = 2.0):
        self.timer.stop()
        self._stop.set()
        if self._connected:
            self._connected = False
            try:
                self.doc.changed.disconnect(self._on_changed)
            except (RuntimeError, TypeError):
                pass
        if self.thread.is_alive() and threading.current_thread() is not self.thread:
            self.thread.join(wait)
