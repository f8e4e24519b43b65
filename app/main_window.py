"""The performance window: video + overlay on the left, the character large on the right,
a strip of characters below, controls at the side, fps and ms per stage in the status bar.

The window itself does no tracking or rendering: it owns a :class:`app.workers.Pipeline`
(an engine process with the capture thread, the puppet and the recorder) and shows the
:class:`DisplayFrame` s it publishes.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import shiboken6
from PySide6.QtCore import QSize, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QActionGroup, QKeySequence
from PySide6.QtWidgets import (
    QButtonGroup,
    QCheckBox,
    QColorDialog,
    QComboBox,
    QFileDialog,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QMessageBox,
    QProgressBar,
    QPushButton,
    QScrollArea,
    QSlider,
    QSpinBox,
    QSplitter,
    QStatusBar,
    QVBoxLayout,
    QWidget,
)

from app import workers
from app.settings import Settings, performer_dir
from app.views import CharacterView, ThumbnailStrip, VideoView
from app.workers import DisplayFrame, Pipeline, PuppetSpec, SourceSpec

VIDEO_EXTS = {".mp4", ".avi", ".mkv", ".mov", ".webm", ".m4v", ".mpg", ".mpeg", ".wmv"}
RATES = (10, 15, 30)
FILTER_LABELS = {
    "none": "None",
    "one_euro": "One-Euro (adaptive)",
    "gate": "Outlier gate",
    "gate+one_euro": "Outlier gate + One-Euro",
    "chai": "Data-driven (Chai et al.)",
}

from app.workers import PERFORMANCE_CALIBRATION

DROPPED_TIP = ("Frames of this source that were skipped to stay live instead of falling behind:\n"
               "• not tracked: the source delivered a new frame while the tracker was still busy with the last\n"
               "• not shown: a finished picture was replaced by a newer one before the window could paint it\n"
               "Counting starts again when the source changes.")


def available_filters() -> list[str]:
    """Filter names the training package offers (the paper's first), or the known defaults."""
    try:
        from training import filters

        names = getattr(filters, "FILTERS", None) or getattr(filters, "FILTER_NAMES", None)
        if names:
            return list(names.keys() if isinstance(names, dict) else names)
    except ImportError:
        pass
    return list(FILTER_LABELS)


def find_clicks_beside(video: str) -> Path | None:
    """``CLIP.clicks.json`` next to ``CLIP.mp4`` (what ``python -m tracker synth`` writes)."""
    p = Path(video)
    c = p.with_name(p.stem + ".clicks.json")
    return c if c.is_file() else None


class MainWindow(QMainWindow):
    """Inkface's performance window."""

    frameShown = Signal(int)  # frame index, after the views were updated
    calibrationOpened = Signal(object)  # the CalibrationWindow, once the frame for it arrived
    recordingSaved = Signal(object)  # app.record.RecordResult, when a stopped recording is closed

    def __init__(
        self,
        settings: Settings | None = None,
        source: SourceSpec | None = None,
        art: str | None = None,
        fake_source: Any = None,
        realtime: bool = True,
        start: bool = True,
        calibration: Any = None,
    ):
        super().__init__()
        self.settings = settings or Settings()
        self.setWindowTitle("Inkface")
        self.setAcceptDrops(True)
        self.last: DisplayFrame | None = None
        self.frames_shown = 0
        self.recording: str | None = None  # output path while recording
        self.record_result = None  # the newest finished recording (app.record.RecordResult)
        self._record_id = 0  # of the recording in progress (0: none)
        self._saving: dict[int, str] = {}  # recordings being closed in the engine: id -> path
        self._close_when_saved = False
        self._snapshot_wanted = False
        self._fake = fake_source
        self._calibration = calibration  # given or made in the calibration window: wins over saved ones
        self._calibration_note = ""
        self._session = None
        self._art_names: dict[str, str] = {}
        self._children: list[QWidget] = []
        self._camera_failed_once = False

        self._build_ui()
        self._build_menus()
        self._populate_characters()
        self._load_settings_into_controls()

        spec = source or self._source_from_settings()
        art = art or self.settings.get("art/current") or ""
        if not art or not Path(art).is_dir():
            art = self.strip.paths()[0] if self.strip.count() else workers.default_art_path()
        self.strip.select_path(art)
        self.source_spec = spec
        self.pipeline = Pipeline(spec, self._puppet_spec(art), realtime=realtime, fake_source=fake_source)
        pl = self.pipeline
        pl.frameReady.connect(self._on_frame_ready)
        pl.puppetReady.connect(self._on_puppet_ready)
        pl.puppetFailed.connect(self._on_puppet_failed)
        pl.error.connect(lambda m: self.statusBar().showMessage(f"Problem: {m}", 6000))
        pl.sourceFailed.connect(self._on_source_failed)
        pl.sourceOpened.connect(self._on_source_opened)
        pl.snapshot.connect(self._on_snapshot)
        pl.recording.connect(self._on_recording)
        pl.recordProgress.connect(self._on_record_progress)
        pl.recorded.connect(self._on_recorded)
        pl.recordFailed.connect(self._on_record_failed)
        pl.recalibrated.connect(self._on_recalibrated)
        pl.recalibrateFailed.connect(lambda m: self.statusBar().showMessage(f"Could not recalibrate: {m}", 8000))
        self.destroyed.connect(lambda *_a, p=pl: p.stop())  # deleted without a close (tests): the engine goes too
        self.video_view.sizeChanged.connect(lambda box: self.pipeline.set_targets(video=box))
        self.char_view.sizeChanged.connect(lambda box: self.pipeline.set_targets(char=box))
        self._sync_source_controls(spec)
        self._status_timer = QTimer(self, interval=500, timeout=self._refresh_status)
        self._status_timer.start()
        geo = self.settings.geometry("main")
        if geo is not None:
            self.restoreGeometry(geo)
        else:
            self.resize(1360, 820)
        if start:
            self.start()

    # ------------------------------------------------------------------------------ layout
    def _build_ui(self) -> None:
        self.video_view = VideoView()
        self.video_view.placeholder = "Waiting for video…"
        self.char_view = CharacterView()

        self.splitter = QSplitter(Qt.Orientation.Horizontal)
        self.splitter.addWidget(self._titled(self.video_view, "Performer"))
        self.splitter.addWidget(self._titled(self.char_view, "Character"))
        self.splitter.setStretchFactor(0, 2)
        self.splitter.setStretchFactor(1, 3)
        self.splitter.setSizes([520, 720])
        self.splitter.setHandleWidth(8)

        self.strip = ThumbnailStrip()
        self.strip.artChosen.connect(self.set_art)

        left = QWidget()
        lv = QVBoxLayout(left)
        lv.setContentsMargins(12, 12, 6, 12)
        lv.setSpacing(10)
        lv.addWidget(self.splitter, 1)
        strip_label = QLabel("Characters — click to switch, drop a folder to add")
        strip_label.setObjectName("hint")
        lv.addWidget(strip_label)
        lv.addWidget(self.strip)

        side = QScrollArea()
        side.setWidgetResizable(True)
        side.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        controls = self._build_controls()
        side.setWidget(controls)
        side.setFixedWidth(max(300, controls.sizeHint().width() + side.verticalScrollBar().sizeHint().width() + 4))

        central = QWidget()
        h = QHBoxLayout(central)
        h.setContentsMargins(0, 0, 0, 0)
        h.setSpacing(0)
        h.addWidget(left, 1)
        h.addWidget(side)
        self.setCentralWidget(central)

        sb = QStatusBar()
        self.setStatusBar(sb)
        self.fps_label = QLabel("— fps")
        self.fps_label.setToolTip("in: frames read from the source per second · out: new character drawings per "
                                  "second (the output rate: 10, 15 or 30)")
        self.stage_label = QLabel("")
        self.stage_label.setToolTip("Milliseconds per frame in each stage of the engine")
        self.drop_label = QLabel("")
        self.drop_label.setToolTip(DROPPED_TIP)
        self.source_label = QLabel("")
        for lab in (self.source_label, self.stage_label, self.drop_label, self.fps_label):
            sb.addPermanentWidget(lab)

    def _titled(self, w: QWidget, title: str) -> QWidget:
        box = QWidget()
        v = QVBoxLayout(box)
        v.setContentsMargins(0, 0, 0, 0)
        v.setSpacing(6)
        lab = QLabel(title)
        lab.setObjectName("title")
        v.addWidget(lab)
        v.addWidget(w, 1)
        return box

    def _build_controls(self) -> QWidget:
        panel = QWidget()
        v = QVBoxLayout(panel)
        v.setContentsMargins(10, 12, 14, 12)
        v.setSpacing(10)

        # source
        g = QGroupBox("Source")
        f = QFormLayout(g)
        self.source_combo = QComboBox()
        self.source_combo.addItem("Bundled performance", "performance")
        self.source_combo.addItem("Camera", "camera")
        self.source_combo.addItem("Video file", "video")
        self.source_combo.activated.connect(self._on_source_combo)
        f.addRow("Input", self.source_combo)
        self.camera_spin = QSpinBox()
        self.camera_spin.setRange(0, 9)
        self.camera_spin.setToolTip("Camera index (0 is usually the built-in one); scroll or type")
        self.camera_spin.valueChanged.connect(self._on_camera_index)
        f.addRow("Camera", self.camera_spin)
        row = QHBoxLayout()
        self.open_video_btn = QPushButton("Open video…")
        self.open_video_btn.clicked.connect(self.open_video_dialog)
        self.pause_btn = QPushButton("Pause")
        self.pause_btn.setCheckable(True)
        self.pause_btn.toggled.connect(self.set_paused)
        row.addWidget(self.open_video_btn)
        row.addWidget(self.pause_btn)
        f.addRow(row)
        v.addWidget(g)

        # output
        g = QGroupBox("Output")
        f = QFormLayout(g)
        rates = QHBoxLayout()
        rates.setSpacing(4)
        self.rate_group = QButtonGroup(self)
        self.rate_group.setExclusive(True)
        for r in RATES:
            b = QPushButton(f"{r}")
            b.setCheckable(True)
            b.setToolTip(f"{r} frames per second (averaging {30 // r} tracked frame{'s' if r < 30 else ''})")
            self.rate_group.addButton(b, r)
            rates.addWidget(b)
        self.rate_group.idClicked.connect(self.set_rate)
        f.addRow("Rate (fps)", rates)
        self.filter_combo = QComboBox()
        for name in available_filters():
            self.filter_combo.addItem(FILTER_LABELS.get(name, name.replace("_", " ").title()), name)
        self.filter_combo.activated.connect(lambda _i: self._on_filter())
        f.addRow("Filter", self.filter_combo)
        self.strength_slider = QSlider(Qt.Orientation.Horizontal)
        self.strength_slider.setRange(0, 100)
        self.strength_slider.valueChanged.connect(lambda _v: self._on_filter())
        f.addRow("Strength", self.strength_slider)
        v.addWidget(g)

        # character
        g = QGroupBox("Character")
        f = QFormLayout(g)
        self.gain_slider = QSlider(Qt.Orientation.Horizontal)
        self.gain_slider.setRange(0, 200)
        self.gain_slider.setToolTip("How much the character follows the head's position and tilt")
        self.gain_label = QLabel("1.00×")
        self.gain_slider.valueChanged.connect(self._on_gain)
        gr = QHBoxLayout()
        gr.addWidget(self.gain_slider, 1)
        gr.addWidget(self.gain_label)
        f.addRow("Head motion", gr)
        self.detail_check = QCheckBox("Keep line detail when blending")
        self.detail_check.setToolTip("Blend the soft layers of the drawings and keep the sharp lines of the strongest one")
        self.detail_check.toggled.connect(self._on_detail)
        f.addRow(self.detail_check)
        self.bg_combo = QComboBox()
        self.bg_combo.addItem("Colour", "colour")
        self.bg_combo.addItem("Transparent", "transparent")
        self.bg_combo.addItem("Green screen", "green")
        self.bg_combo.activated.connect(lambda _i: self._on_background())
        self.bg_colour_btn = QPushButton("")
        self.bg_colour_btn.setFixedWidth(36)
        self.bg_colour_btn.setToolTip("Background colour")
        self.bg_colour_btn.clicked.connect(self._pick_bg_colour)
        br = QHBoxLayout()
        br.addWidget(self.bg_combo, 1)
        br.addWidget(self.bg_colour_btn)
        f.addRow("Background", br)
        self.overlay_check = QCheckBox("Show tracking overlay")
        self.overlay_check.toggled.connect(self._on_overlay)
        f.addRow(self.overlay_check)
        v.addWidget(g)

        # performer
        g = QGroupBox("Performer")
        gv = QVBoxLayout(g)
        self.calib_label = QLabel("")
        self.calib_label.setObjectName("hint")
        self.calib_label.setWordWrap(True)
        gv.addWidget(self.calib_label)
        row = QHBoxLayout()
        b = QPushButton("Calibrate…")
        b.clicked.connect(self.open_calibration)
        row.addWidget(b)
        b = QPushButton("Train…")
        b.clicked.connect(self.open_training)
        row.addWidget(b)
        gv.addLayout(row)
        v.addWidget(g)

        # record
        g = QGroupBox("Record")
        gv = QVBoxLayout(g)
        self.record_btn = QPushButton("● Record")
        self.record_btn.setObjectName("primary")
        self.record_btn.setCheckable(True)
        self.record_btn.toggled.connect(self._on_record_toggled)
        gv.addWidget(self.record_btn)
        self.record_label = QLabel("MP4, GIF or PNG sequence, plus the parameter track (CSV)")
        self.record_label.setObjectName("hint")
        self.record_label.setWordWrap(True)
        gv.addWidget(self.record_label)
        self.save_progress = QProgressBar()
        self.save_progress.setToolTip("Writing the frames still queued and closing the files; the performance goes on")
        self.save_progress.setVisible(False)
        gv.addWidget(self.save_progress)
        v.addWidget(g)
        v.addStretch(1)
        return panel

    def _build_menus(self) -> None:
        mb = self.menuBar()

        def act(menu, text, slot, shortcut=None, checkable=False, tip=""):
            a = QAction(text, self)
            if shortcut:
                a.setShortcut(QKeySequence(shortcut))
            a.setCheckable(checkable)
            if tip:
                a.setStatusTip(tip)
            a.triggered.connect(slot)
            menu.addAction(a)
            return a

        m = mb.addMenu("&File")
        act(m, "Open &video…", self.open_video_dialog, QKeySequence.StandardKey.Open)
        act(m, "Use &camera", lambda: self.set_source(SourceSpec("camera", camera=self.camera_spin.value())), "Ctrl+Shift+C")
        act(m, "Use bundled &performance", lambda: self.set_source(SourceSpec("performance")), "Ctrl+Shift+P")
        m.addSeparator()
        act(m, "Open &art set…", self.open_artset_dialog, "Ctrl+Shift+O")
        m.addSeparator()
        self.record_action = act(m, "&Record…", lambda c: self.record_btn.setChecked(c), "Ctrl+R", checkable=True)
        act(m, "&Export snapshot…", self.export_snapshot, "Ctrl+E")
        act(m, "Re-render a &track…", self.rerender_track_dialog, "Ctrl+Shift+R",
            tip="Render a recorded parameter track (CSV) with any character")
        m.addSeparator()
        act(m, "&Quit", self.close, QKeySequence.StandardKey.Quit)

        m = mb.addMenu("&View")
        self.overlay_action = act(m, "Tracking &overlay", lambda c: self.overlay_check.setChecked(c), "O", checkable=True)
        self.video_action = act(m, "Performer &video", self._toggle_video_panel, "V", checkable=True)
        self.video_action.setChecked(True)
        act(m, "&Full screen", self._toggle_full_screen, "F11", checkable=True)
        m.addSeparator()
        bg = QActionGroup(self)
        self.bg_actions = {}
        for i, (label, kind) in enumerate((("Colour background", "colour"), ("Transparent background", "transparent"),
                                           ("Green screen", "green"))):
            a = act(m, label, lambda _c=False, k=kind: self._set_background_kind(k), f"Ctrl+{i + 4}", checkable=True)
            bg.addAction(a)
            self.bg_actions[kind] = a
        m.addSeparator()
        for i, r in enumerate(RATES):
            act(m, f"{r} fps output", lambda _c=False, rr=r: self.set_rate(rr), f"Ctrl+{i + 1}")
        act(m, "Pause", lambda: self.pause_btn.toggle(), "Space")
        act(m, "Next character", lambda: self._cycle_art(1), "Ctrl+Right")
        act(m, "Previous character", lambda: self._cycle_art(-1), "Ctrl+Left")

        m = mb.addMenu("&Tools")
        act(m, "&Calibrate…", self.open_calibration, "Ctrl+K")
        self.recalibrate_action = act(
            m, "&Recalibrate on this frame", self.recalibrate, "K",
            tip="For when the light changed: calibrate again on the current frame without stopping "
                "(face the camera with a neutral face)")
        act(m, "&Train…", self.open_training, "Ctrl+T")
        self.editor_action = act(m, "Art-set &editor…", self.open_editor, "Ctrl+Shift+E")

        m = mb.addMenu("&Help")
        act(m, "&About Inkface", self.about)

    # ------------------------------------------------------------------------- characters
    def _populate_characters(self) -> None:
        try:
            from art_sets.library import list_bundled, list_user
        except ImportError:
            return
        items = [(n, p, False) for n, p in list_bundled()]
        items += [(n, p, True) for n, p in list_user()]
        seen = {str(p) for _, p, _ in items}
        for d in self.settings.user_art_dirs():
            if d not in seen and (Path(d) / "artset.json").is_file():
                items.append((Path(d).name, Path(d), True))
        for name, path, user in items:
            self._add_character(name, str(path), user)

    def _add_character(self, name: str, path: str, user: bool) -> None:
        thumb = None
        try:
            from art_sets.library import thumbnail

            thumb = thumbnail(workers.load_artset(path), 84)
        except Exception as e:  # a broken user folder: list it without a picture, say why
            self.statusBar().showMessage(f"{name}: {workers._one_line(e)}", 8000)
            if not user:
                return
        self._art_names[path] = name
        self.strip.add_character(name, path, thumb, user)

    def add_art_folder(self, folder: str) -> bool:
        """Add a user's art-set folder to the strip (remembered) and switch to it."""
        from art_sets.io import ArtSetError, load_artset

        try:
            art = load_artset(folder)
        except ArtSetError as e:
            QMessageBox.warning(self, "Inkface", str(e))
            return False
        path = str(Path(folder).resolve())
        self.settings.add_user_art_dir(path)
        self._add_character(art.name, path, True)
        self.set_art(path)
        return True

    def set_art(self, path: str) -> None:
        """Switch the character (cross-fades once the new one is ready)."""
        if not path or path == self.pipeline.spec.art:
            return
        self.strip.select_path(path)
        self.settings.set("art/current", path)
        self._session = self._load_session(path)
        self.pipeline.request(art=path, session=self._session)

    def current_art(self) -> str:
        return self.pipeline.spec.art

    def _cycle_art(self, step: int) -> None:
        paths = self.strip.paths()
        if not paths:
            return
        cur = self.current_art()
        i = paths.index(cur) if cur in paths else -1
        self.set_art(paths[(i + step) % len(paths)])

    def _on_puppet_ready(self, path: str) -> None:
        name = self._art_names.get(path, Path(path).name)
        self.statusBar().showMessage(f"Now playing {name}", 3000)

    def _on_puppet_failed(self, msg: str) -> None:
        self.char_view.placeholder = f"The character could not be drawn:\n{msg}"
        self.char_view.set_image(None)
        self.statusBar().showMessage(msg, 10000)

    # ------------------------------------------------------------------------------ source
    def _source_from_settings(self) -> SourceSpec:
        kind = self.settings.get("source/kind")
        if kind == "camera":
            return SourceSpec("camera", camera=self.settings.get("source/camera"))
        if kind == "video" and Path(self.settings.get("source/video") or "").is_file():
            return SourceSpec("video", video=self.settings.get("source/video"))
        return SourceSpec("performance")

    def set_source(self, spec: SourceSpec, fake_source: Any = None) -> None:
        """Play from another source (camera, video file, the bundled performance)."""
        self.source_spec = spec
        self._fake = fake_source
        self.settings.set("source/kind", spec.kind)
        if spec.kind == "camera":
            self.settings.set("source/camera", spec.camera)
        if spec.kind == "video":
            self.settings.set("source/video", spec.video)
        self.pipeline.request(calibration=self._calibration_for(spec))
        self._sync_source_controls(spec)  # after _calibration_for: the label says which calibration
        self.pipeline.set_source(spec, fake_source)
        self.drop_label.setText("dropped 0")
        self.pause_btn.setChecked(False)

    def _sync_source_controls(self, spec: SourceSpec) -> None:
        i = self.source_combo.findData(spec.kind)
        self.source_combo.blockSignals(True)
        self.source_combo.setCurrentIndex(max(0, i))
        self.source_combo.blockSignals(False)
        self.camera_spin.blockSignals(True)
        self.camera_spin.setValue(spec.camera)
        self.camera_spin.blockSignals(False)
        self.camera_spin.setEnabled(spec.kind == "camera")
        self.source_label.setText(spec.describe())
        self._update_calibration_label()

    def _on_source_combo(self, _i: int) -> None:
        kind = self.source_combo.currentData()
        if kind == "video":
            if not self.open_video_dialog():
                self._sync_source_controls(self.source_spec)
        elif kind == "camera":
            self.set_source(SourceSpec("camera", camera=self.camera_spin.value()))
        else:
            self.set_source(SourceSpec("performance"))

    def _on_camera_index(self, v: int) -> None:
        if self.source_spec.kind == "camera" and v != self.source_spec.camera:
            self.set_source(SourceSpec("camera", camera=v))

    def open_video_dialog(self) -> bool:
        start = str(Path(self.settings.get("source/video") or Path.home()).parent)
        path, _ = QFileDialog.getOpenFileName(self, "Open a video of a face", start,
                                              "Videos (*.mp4 *.avi *.mkv *.mov *.webm *.m4v);;All files (*)")
        if not path:
            return False
        self.set_source(SourceSpec("video", video=path))
        return True

    def _on_source_opened(self, desc: str, fps: float, w: int, h: int) -> None:
        self.source_label.setText(f"{desc} · {w}×{h} @ {fps:.0f}")

    def _on_source_failed(self, msg: str) -> None:
        spec = self.source_spec
        if spec.kind == "camera":
            self.statusBar().showMessage(f"No camera: {msg}. Playing the bundled performance instead.", 10000)
            if not self._camera_failed_once and self.isVisible() and not _testing():
                box = QMessageBox(QMessageBox.Icon.Information, "No camera",
                                  f"{msg}\n\nInkface will play the bundled performance instead.",
                                  QMessageBox.StandardButton.Ok, self)
                box.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
                box.open()  # not exec(): the event loop, and the performance, go on
            self._camera_failed_once = True
            self.set_source(SourceSpec("performance"))
        elif spec.kind == "video":
            self.statusBar().showMessage(f"{msg}. Playing the bundled performance instead.", 10000)
            self.set_source(SourceSpec("performance"))
        else:
            self.video_view.placeholder = msg
            self.video_view.update()
            self.statusBar().showMessage(msg, 10000)

    def set_paused(self, paused: bool) -> None:
        self.pipeline.set_paused(paused)
        self.pause_btn.setText("Resume" if paused else "Pause")

    # -------------------------------------------------------------------------- calibration
    def _calibration_for(self, spec: SourceSpec):
        """The calibration for this source: the synthetic performer's own, the clicks beside a
        video file, or the performer's saved one."""
        self._calibration_note = ""
        if self._calibration is not None and spec.kind != "performance":
            self._calibration_note = "Calibrated in this session"
            return self._calibration
        if spec.kind == "performance":
            self._calibration_note = "Bundled performer (calibrated from its own clicks)"
            return PERFORMANCE_CALIBRATION
        if spec.kind == "video":
            clicks = find_clicks_beside(spec.video)
            if clicks is not None:
                self._calibration_note = f"From {clicks.name}"
                return ("clicks", str(clicks), spec.video)
        cal = self._performer_calibration()
        if cal is not None:
            self._calibration_note = f"Saved calibration of “{self.performer()}”"
            return cal
        self._calibration_note = "Not calibrated — press Calibrate… (or Auto in it)"
        return None

    def performer(self) -> str:
        return str(self.settings.get("performer/name") or "default")

    def _performer_calibration(self):
        path = performer_dir(self.performer()) / "calibration.json"
        if not path.is_file():
            return None
        try:
            from tracker.calibration import Calibration

            return Calibration.load(path)
        except Exception as e:
            self.statusBar().showMessage(f"{path}: {workers._one_line(e)}", 8000)
            return None

    def _update_calibration_label(self) -> None:
        self.calib_label.setText(f"{self.performer()}: {self._calibration_note}" if self._calibration_note else self.performer())

    def open_calibration(self) -> None:
        """Ask the engine for the current frame at full size; the calibration window opens on
        it when it arrives (:attr:`calibrationOpened`), the performance playing on meanwhile."""
        self._snapshot_wanted = True
        self.pipeline.request_snapshot()
        self.statusBar().showMessage("Taking the current frame for calibration…", 3000)

    def _on_snapshot(self, frame) -> None:
        if not self._snapshot_wanted:
            return
        self._snapshot_wanted = False
        if frame is None:
            self.statusBar().showMessage("No frame to calibrate on yet", 4000)
            return
        from app.calibration_window import CalibrationWindow

        dlg = CalibrationWindow(np.array(frame), performer=self.performer(), parent=self)
        dlg.calibrated.connect(lambda cal, d=dlg: self._on_calibrated(cal, getattr(d, "saved_to", None)))
        self._adopt(dlg)
        dlg.show()
        self.calibrationOpened.emit(dlg)

    def _on_calibrated(self, cal, path: str | Path | None = None) -> None:
        """Use a new calibration; ``path`` is the file it was saved to (sent instead of the object)."""
        self._calibration = cal
        self._calibration_note = f"Calibrated just now ({self.performer()})"
        self._update_calibration_label()
        if path is not None:
            self.pipeline.note_file(cal, path)
        self.pipeline.request(calibration=cal)

    def recalibrate(self) -> None:
        """Calibrate again on the current frame (K), for when the light changed; frames go on."""
        self.pipeline.recalibrate()
        self.statusBar().showMessage("Recalibrating on the current frame…", 3000)

    def _on_recalibrated(self, path: str, how: str) -> None:
        try:
            from tracker.calibration import Calibration

            cal = Calibration.load(path)
        except Exception as e:
            self.statusBar().showMessage(f"Could not recalibrate: {workers._one_line(e)}", 8000)
            return
        self._on_calibrated(cal, path)
        self._calibration_note = (f"Recalibrated on the current frame ({how}; this session only — "
                                  "Calibrate… saves one)")
        self._update_calibration_label()
        self.statusBar().showMessage("Recalibrated on the current frame", 4000)

    def _adopt(self, win: QWidget) -> None:
        """Keep a child window; closed ones are let go (deleted) so repeated use does not pile up."""
        keep = []
        for c in self._children:
            if shiboken6.isValid(c) and c.isVisible():
                keep.append(c)
            elif shiboken6.isValid(c):
                c.deleteLater()
        self._children = keep + [win]

    def _feed_children(self) -> None:
        """Live frames for open training windows (they record clips from them)."""
        for c in self._children:
            if hasattr(c, "live_frame") and shiboken6.isValid(c) and c.isVisible():
                c.live_frame(self.last)

    # ----------------------------------------------------------------------------- training
    def _load_session(self, art_path: str):
        """The performer's saved training session for this character, if any."""
        spec = getattr(self, "source_spec", None)
        if spec is None or spec.kind == "performance":
            return None
        try:
            from app.training_window import session_path
            from training.session import TrainingSession

            p = session_path(self.performer(), art_path)
            return TrainingSession.load(p) if p.is_file() else None
        except Exception:
            return None

    def open_training(self):
        from app.training_window import TrainingWindow

        art = self.current_art()
        if not art:
            self.statusBar().showMessage("Pick a character first", 4000)
            return None
        cal = self.pipeline.spec.calibration
        win = TrainingWindow(art_path=art, performer=self.performer(), source=self.source_spec,
                             calibration=cal, parent=self)
        win.sessionSaved.connect(self._on_session_saved)
        win.recordingChanged.connect(lambda on: self.pipeline.set_targets(full=on))
        self._adopt(win)
        win.show()
        return win

    def _on_session_saved(self, session) -> None:
        self._session = session
        self.pipeline.request(session=session)
        self.statusBar().showMessage("Training saved and in use", 4000)

    # ------------------------------------------------------------------------------ editor
    def open_editor(self) -> None:
        if importlib.util.find_spec("app.editor_cmd") is None and importlib.util.find_spec("app.editor") is None:
            QMessageBox.information(self, "Art-set editor", "The art-set editor is not part of this build.")
            return
        args = [sys.executable, "-m", "app", "edit"]
        art = self.current_art()
        if art and not art.startswith(str(Path(__file__).resolve().parent.parent / "art_sets" / "bundled")):
            args.append(art)
        try:
            subprocess.Popen(args)
            self.statusBar().showMessage("Opening the art-set editor…", 4000)
        except OSError as e:
            QMessageBox.warning(self, "Art-set editor", str(e))

    # ----------------------------------------------------------------------------- controls
    def _puppet_spec(self, art: str) -> PuppetSpec:
        spec = getattr(self, "source_spec", None) or SourceSpec()
        return PuppetSpec(
            art=art,
            fps=self.rate(),
            filter=self.filter_combo.currentData() or "one_euro",
            strength=self.strength_slider.value() / 100.0,
            gain=self.gain_slider.value() / 100.0,
            detail=self.detail_check.isChecked(),
            calibration=self._calibration_for(spec),
            session=self._load_session(art),
        )

    def _load_settings_into_controls(self) -> None:
        s = self.settings
        rate = s.get("output/fps")
        b = self.rate_group.button(rate if rate in RATES else 30)
        b.setChecked(True)
        i = self.filter_combo.findData(s.get("filter/name"))
        self.filter_combo.setCurrentIndex(max(0, i))
        self.strength_slider.setValue(int(round(s.get("filter/strength") * 100)))
        self.gain_slider.setValue(int(round(s.get("render/gain") * 100)))
        self.detail_check.setChecked(s.get("render/detail"))
        kind = s.get("render/background")
        self.bg_combo.setCurrentIndex(max(0, self.bg_combo.findData(kind)))
        self.char_view.set_background(kind, s.get("render/background_colour"))
        self.bg_actions.get(kind, self.bg_actions["colour"]).setChecked(True)
        self._paint_colour_button()
        self.overlay_check.setChecked(s.get("view/overlay"))
        self.overlay_action.setChecked(s.get("view/overlay"))
        self.video_view.show_overlay = s.get("view/overlay")
        self.gain_label.setText(f"{self.gain_slider.value() / 100:.2f}×")

    def rate(self) -> int:
        return int(self.rate_group.checkedId()) if self.rate_group.checkedId() in RATES else 30

    def set_rate(self, fps: int) -> None:
        fps = int(fps)
        if fps not in RATES:
            return
        self.rate_group.button(fps).setChecked(True)
        self.settings.set("output/fps", fps)
        self.pipeline.request(fps=fps)

    def _on_filter(self) -> None:
        name = self.filter_combo.currentData() or "one_euro"
        strength = self.strength_slider.value() / 100.0
        self.settings.set("filter/name", name)
        self.settings.set("filter/strength", strength)
        if hasattr(self, "pipeline"):
            self.pipeline.request(filter=name, strength=strength)

    def _on_gain(self, v: int) -> None:
        self.gain_label.setText(f"{v / 100:.2f}×")
        self.settings.set("render/gain", v / 100.0)
        if hasattr(self, "pipeline"):
            self.pipeline.request(gain=v / 100.0)

    def _on_detail(self, on: bool) -> None:
        self.settings.set("render/detail", bool(on))
        if hasattr(self, "pipeline"):
            self.pipeline.request(detail=bool(on))

    def _on_background(self) -> None:
        self._set_background_kind(self.bg_combo.currentData())

    def _set_background_kind(self, kind: str) -> None:
        self.bg_combo.setCurrentIndex(max(0, self.bg_combo.findData(kind)))
        if kind in self.bg_actions:
            self.bg_actions[kind].setChecked(True)
        self.char_view.set_background(kind)
        self.settings.set("render/background", kind)

    def _pick_bg_colour(self) -> None:
        c = QColorDialog.getColor(self.char_view.colour, self, "Background colour")
        if c.isValid():
            self.char_view.set_background("colour", c)
            self.settings.set("render/background_colour", c.name())
            self._set_background_kind("colour")
            self._paint_colour_button()

    def _paint_colour_button(self) -> None:
        self.bg_colour_btn.setStyleSheet(f"background: {self.char_view.colour.name()}; border-radius: 6px;")

    def _on_overlay(self, on: bool) -> None:
        self.video_view.show_overlay = bool(on)
        self.overlay_action.setChecked(bool(on))
        self.settings.set("view/overlay", bool(on))
        self.video_view.update()

    def _toggle_video_panel(self, on: bool) -> None:
        self.splitter.widget(0).setVisible(bool(on))
        if hasattr(self, "pipeline"):
            self.pipeline.set_video(bool(on))

    def _toggle_full_screen(self, on: bool) -> None:
        self.showFullScreen() if on else self.showNormal()

    # ------------------------------------------------------------------------------ frames
    def start(self) -> None:
        self.pipeline.start()

    def _on_frame_ready(self) -> None:
        fr = self.pipeline.take()
        if fr is None:
            return
        self.last = fr
        if fr.video is not None:
            self.video_view.set_frame(fr.video, fr.overlay, fr.params, fr.frame_size, status=fr.status)
        if fr.character is not None:
            self.char_view.set_image(fr.character, fr.art)
            self.char_view.placeholder = "Loading the character…"
        self.frames_shown += 1
        self._feed_children()
        self.frameShown.emit(fr.index)

    def _refresh_status(self) -> None:
        fr = self.last
        if fr is None:
            return
        if self.pause_btn.isChecked():
            self.fps_label.setText("paused")
        else:
            self.fps_label.setText(f"in {fr.fps_in:4.1f} · out {fr.fps_out:4.1f} fps")
        self.fps_label.setToolTip(
            f"in: {fr.fps_in:.1f} frames per second read from the source\n"
            f"tracked: {fr.fps:.1f} frames per second\n"
            f"out: {fr.fps_out:.1f} new character drawings per second (output rate {self.rate()} fps)")
        t = fr.timings_ms or {}
        if t:
            parts = [f"{k} {v:.1f}" for k, v in t.items() if isinstance(v, (int, float))]
            self.stage_label.setText("ms: " + " · ".join(parts))
        if fr.source_id == self.pipeline.source_id:
            dropped = fr.dropped_capture + fr.dropped_display
            pct = f" ({100.0 * dropped / fr.frames_read:.0f} %)" if fr.frames_read else ""
            self.drop_label.setText(f"dropped {dropped}{pct}")
            self.drop_label.setToolTip(f"{DROPPED_TIP}\n\nThis source: {fr.frames_read} frames read, "
                                       f"{fr.dropped_capture} not tracked, {fr.dropped_display} not shown.")

    # ---------------------------------------------------------------------------- record
    def _on_record_toggled(self, on: bool) -> None:
        self.record_action.setChecked(on)
        if on and self.recording is None:
            if not self.start_recording_dialog():
                self.record_btn.setChecked(False)
        elif not on and self.recording is not None:
            self.stop_recording()

    def start_recording_dialog(self) -> bool:
        """Ask where to record, proposing a name no recording uses yet (recordings never replace
        one another: a name in use is refused with a free one proposed)."""
        from app.record import RECORD_FILTERS, free_recording_path

        start = Path(self.settings.get("record/dir") or str(Path.home()))
        try:
            proposal = free_recording_path(start / "inkface.mp4")
        except OSError:
            proposal = start / "inkface.mp4"
        path, _flt = QFileDialog.getSaveFileName(self, "Record the character to…", str(proposal),
                                                 ";;".join(RECORD_FILTERS),
                                                 options=QFileDialog.Option.DontConfirmOverwrite)
        if not path:
            return False
        return self.start_recording(path)

    def start_recording(self, path: str, overwrite: bool = False) -> bool:
        """Record the character (MP4 / GIF / PNG folder by extension) and the track beside it.

        The engine process writes the files; the background is the one on screen. Nothing is
        replaced unless ``overwrite``: the engine refuses a name in use and proposes a free one."""
        from app.record import RecordError, _rgb_tuple, format_of

        try:
            format_of(path)
        except RecordError as e:
            QMessageBox.warning(self, "Record", str(e))
            return False
        if self.recording is not None:
            self.stop_recording()
        self._record_id += 1
        self.recording = str(path)
        bg = _rgb_tuple(self.char_view.background_colour())
        self.pipeline.start_recording(self._record_id, path, self.rate(), bg, overwrite)
        self.settings.set("record/dir", str(Path(path).parent))
        self._set_record_button(True)
        self.record_label.setText(f"Recording to {Path(path).name}…")
        return True

    def stop_recording(self) -> None:
        """Stop recording; the engine closes the files on its own thread while the performance
        plays on, a progress bar shows how far it is, and :attr:`recordingSaved` says when done."""
        if self.recording is None:
            return
        self._saving[self._record_id] = self.recording
        self.pipeline.stop_recording(self._record_id)
        self.recording = None
        self._set_record_button(False)
        self._show_saving()

    def _set_record_button(self, on: bool) -> None:
        self.record_btn.blockSignals(True)
        self.record_btn.setChecked(on)
        self.record_btn.setText("■ Stop recording" if on else "● Record")
        self.record_btn.blockSignals(False)
        self.record_action.setChecked(on)

    def _show_saving(self, done: int = 0, total: int = 0) -> None:
        if not self._saving:
            self.save_progress.setVisible(False)
            return
        names = ", ".join(Path(p).name for p in self._saving.values())
        self.save_progress.setVisible(True)
        self.save_progress.setRange(0, max(1, total))
        self.save_progress.setValue(min(done, max(1, total)))
        self.save_progress.setFormat(f"Saving {names}… %p %")
        if self.recording is None:
            self.record_label.setText(f"Saving {names}… ({done} of {total} frames written)" if total
                                      else f"Saving {names}…")

    def _on_recording(self, rid: int, frames: int, dropped: int) -> None:
        if rid == self._record_id and self.recording is not None:
            extra = f", {dropped} dropped (the disk could not keep up)" if dropped else ""
            self.record_label.setText(f"Recording to {Path(self.recording).name}… {frames} frames{extra}")

    def _on_record_progress(self, rid: int, done: int, total: int) -> None:
        if rid in self._saving:
            self._show_saving(done, total)

    def _on_recorded(self, rid: int, result) -> None:
        self._saving.pop(rid, None)
        self._show_saving()
        if result is not None:
            self.record_result = result
            self.record_label.setText(result.describe())
            self.statusBar().showMessage(result.describe(), 8000)
            self.recordingSaved.emit(result)
        self._close_if_saved()

    def _on_record_failed(self, rid: int, msg: str) -> None:
        self._saving.pop(rid, None)
        self._show_saving()
        if rid == self._record_id and self.recording is not None:
            self.recording = None
            self._set_record_button(False)
        self.record_label.setText(f"Recording failed: {msg}")
        self.statusBar().showMessage(f"Recording failed: {msg}", 10000)
        self._close_if_saved()

    def _close_if_saved(self) -> None:
        if self._close_when_saved and not self._saving:
            self._close_when_saved = False
            QTimer.singleShot(0, self.close)

    def export_snapshot(self) -> None:
        if self.last is None or self.last.character is None:
            return
        path, _ = QFileDialog.getSaveFileName(self, "Save the character as PNG", str(Path.home() / "inkface.png"),
                                              "PNG (*.png)")
        if path:
            self.last.character.save(path, "PNG")

    def rerender_track_dialog(self) -> None:
        from app.record import RerenderDialog

        dlg = RerenderDialog(self.strip.entries(), self.char_view.background_colour(), self.rate(), parent=self)
        self._adopt(dlg)
        dlg.show()

    # ------------------------------------------------------------------------ drag & drop
    def dragEnterEvent(self, ev) -> None:
        if ev.mimeData().hasUrls() and any(self._droppable(u.toLocalFile()) for u in ev.mimeData().urls()):
            ev.acceptProposedAction()

    def dropEvent(self, ev) -> None:
        for u in ev.mimeData().urls():
            if self.open_path(u.toLocalFile()):
                ev.acceptProposedAction()
                return

    @staticmethod
    def _droppable(path: str) -> bool:
        p = Path(path)
        return (p.is_file() and p.suffix.lower() in VIDEO_EXTS) or (p.is_dir() and (p / "artset.json").is_file()) or (
            p.name == "artset.json")

    def open_path(self, path: str) -> bool:
        """Open a dropped video file or art-set folder."""
        p = Path(path)
        if p.name == "artset.json":
            p = p.parent
        if p.is_dir() and (p / "artset.json").is_file():
            return self.add_art_folder(str(p))
        if p.is_file() and p.suffix.lower() in VIDEO_EXTS:
            self.set_source(SourceSpec("video", video=str(p)))
            return True
        return False

    def open_artset_dialog(self) -> None:
        d = QFileDialog.getExistingDirectory(self, "Open an art-set folder (with artset.json)", str(Path.home()))
        if d:
            self.add_art_folder(d)

    # ------------------------------------------------------------------------------- misc
    def about(self) -> None:
        QMessageBox.about(
            self,
            "About Inkface",
            "<h3>Inkface</h3><p>A face on a webcam or video drives a hand-drawn cartoon.</p>"
            "<p>After Buck et al., <i>Performance-Driven Hand-Drawn Animation</i> (NPAR 2000): a colour "
            "tracker reduces each frame to ten numbers; the three nearest drawings of the eyes and of the "
            "mouth are morphed together under a drawn head.</p>",
        )

    def closeEvent(self, ev) -> None:
        if self.recording is not None:
            self.stop_recording()
        if self._saving and self.pipeline.running and not self._close_when_saved:
            # the files are still being closed: close when they are (closing again does not wait)
            self._close_when_saved = True
            self.statusBar().showMessage("Saving the recording… Inkface closes when it is saved", 0)
            ev.ignore()
            return
        self.settings.set_geometry("main", self.saveGeometry())
        self.settings.sync()
        for c in self._children:
            try:
                c.close()
            except RuntimeError:
                pass
        self._status_timer.stop()
        self.pipeline.stop(wait_s=30.0 if self._saving else 3.0)  # the engine finishes a save it started
        super().closeEvent(ev)

    def sizeHint(self) -> QSize:
        return QSize(1360, 820)


def _testing() -> bool:
    return "pytest" in sys.modules
