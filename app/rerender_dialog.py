"""The window for re-rendering a recorded parameter track with another character (Qt).

Kept apart from :mod:`app.record` so that recording and the headless commands load no Qt
widgets; :class:`RerenderDialog` is still importable from there.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QMessageBox,
    QProgressBar,
    QPushButton,
    QVBoxLayout,
)

from app.record import RECORD_FILTERS, RecordResult, render_task


class RerenderDialog(QDialog):
    """Pick a recorded track, a character (``characters``: (name, folder) pairs) and an output;
    render with a progress bar."""

    def __init__(self, characters: list[tuple[str, str]], background=None, fps: int = 30, parent=None, track: str = ""):
        super().__init__(parent)
        self.setWindowTitle("Re-render a track with another character")
        self.setMinimumWidth(520)
        self.background = background
        self.thread = None  # app.workers.ProcessTask while rendering
        self.result_: RecordResult | None = None
        v = QVBoxLayout(self)
        v.setContentsMargins(18, 18, 18, 18)
        v.setSpacing(12)
        f = QFormLayout()
        self.track_edit = QLineEdit(track)
        b = QPushButton("…")
        b.clicked.connect(self._pick_track)
        row = QHBoxLayout()
        row.addWidget(self.track_edit, 1)
        row.addWidget(b)
        f.addRow("Track (CSV)", row)
        self.art_combo = QComboBox()
        for name, p in characters:
            self.art_combo.addItem(name, p)
        f.addRow("Character", self.art_combo)
        self.out_edit = QLineEdit("")
        b = QPushButton("…")
        b.clicked.connect(self._pick_out)
        row = QHBoxLayout()
        row.addWidget(self.out_edit, 1)
        row.addWidget(b)
        f.addRow("Output", row)
        self.fps_combo = QComboBox()
        for r in (10, 15, 30):
            self.fps_combo.addItem(f"{r} fps", r)
        self.fps_combo.setCurrentIndex(max(0, self.fps_combo.findData(fps)))
        f.addRow("Rate", self.fps_combo)
        v.addLayout(f)
        self.bar = QProgressBar()
        self.bar.setRange(0, 100)
        self.bar.setValue(0)
        v.addWidget(self.bar)
        self.msg = QLabel("")
        self.msg.setObjectName("hint")
        self.msg.setWordWrap(True)
        v.addWidget(self.msg)
        self.buttons = QDialogButtonBox()
        self.start_btn = self.buttons.addButton("Render", QDialogButtonBox.ButtonRole.AcceptRole)
        self.start_btn.setObjectName("primary")
        self.close_btn = self.buttons.addButton("Close", QDialogButtonBox.ButtonRole.RejectRole)
        self.start_btn.clicked.connect(self.start)
        self.close_btn.clicked.connect(self._close_or_cancel)
        v.addWidget(self.buttons)

    def _pick_track(self) -> None:
        p, _ = QFileDialog.getOpenFileName(self, "A recorded parameter track", "", "Tracks (*.csv)")
        if p:
            self.track_edit.setText(p)
            if not self.out_edit.text():
                self.out_edit.setText(str(Path(p).with_name(Path(p).stem + "-rerender.mp4")))

    def _pick_out(self) -> None:
        p, _ = QFileDialog.getSaveFileName(self, "Render to…", self.out_edit.text(), ";;".join(RECORD_FILTERS))
        if p:
            self.out_edit.setText(p)

    def start(self) -> None:
        track, out = self.track_edit.text().strip(), self.out_edit.text().strip()
        if not track or not out:
            self.msg.setText("Choose a track and an output file first.")
            return
        from app.record import check_render_output
        from tracker.outputs import OutputError

        overwrite = False
        try:
            check_render_output(out, [track, self.art_combo.currentData()], overwrite=False)
        except OutputError as e:
            try:
                check_render_output(out, [track, self.art_combo.currentData()], overwrite=True)
            except OutputError as e2:
                self.msg.setText(str(e2))
                return
            answer = QMessageBox.question(self, "Replace?", f"{Path(out).name} already exists. Replace it?")
            if answer != QMessageBox.StandardButton.Yes:
                self.msg.setText(str(e))
                return
            overwrite = True
        self.start_btn.setEnabled(False)
        self.close_btn.setText("Cancel")
        self.msg.setText("Rendering…")
        self.thread = render_task(track, self.art_combo.currentData(), out, self.fps_combo.currentData(),
                                  self.background, overwrite)
        self.thread.progress.connect(self._on_progress)
        self.thread.done.connect(self._on_done)
        self.thread.failed.connect(self._on_failed)
        self.thread.start()

    def _on_progress(self, i: int, n: int) -> None:
        self.bar.setRange(0, n)
        self.bar.setValue(i)

    def _on_done(self, res: RecordResult) -> None:
        self.result_ = res
        self.msg.setText(res.describe())
        self._finish()

    def _on_failed(self, msg: str) -> None:
        self.msg.setText(f"Could not render: {msg}")
        self._finish()

    def _finish(self) -> None:
        self.start_btn.setEnabled(True)
        self.close_btn.setText("Close")

    def _close_or_cancel(self) -> None:
        if self.thread is not None and self.thread.isRunning():
            self.thread.cancel()
            return
        self.close()

    def closeEvent(self, ev) -> None:
        if self.thread is not None and self.thread.isRunning():
            self.thread.cancel()
            self.thread.wait(5000)
        super().closeEvent(ev)
