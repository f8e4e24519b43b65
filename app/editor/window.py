"""The art-set editor's main window: lists on the left, canvases in the middle, preview on the
right, lines and problems below. Every action here calls an :class:`EditorDocument` method, so
menus, drag-and-drop, the canvases and the tests all take the same path."""

from __future__ import annotations

import re
from pathlib import Path

from PySide6.QtCore import QDir, QSize, Qt
from PySide6.QtGui import QKeySequence
from PySide6.QtWidgets import (
    QCheckBox, QComboBox, QDialog, QDialogButtonBox, QDockWidget, QDoubleSpinBox, QFileDialog,
    QFormLayout, QGroupBox, QHBoxLayout, QInputDialog, QLabel, QLineEdit, QMainWindow, QMessageBox,
    QPushButton, QRadioButton, QSpinBox, QSplitter, QTabWidget, QToolBar, QVBoxLayout, QWidget,
)

from art_sets import editing as ed
from art_sets.model import PART_NAMES

from .canvas import HeadCanvas, LineCanvas
from .document import EditorDocument, is_bundled, recoverable
from .panels import (
    DropList, LinesList, PartStrip, ProblemsList, cached_icon, dropped_paths, image_paths, thumb_icon,
)
from .layers_panel import LayersPanel
from .preview import PreviewPanel

IMAGE_FILTER = "Images (*.png *.jpg *.jpeg *.bmp *.gif *.tif *.tiff *.webp)"


def _user_art_dir() -> Path | None:
    """Where the program looks for the user's characters (``art_sets.library.user_dir``), created."""
    try:
        from art_sets.library import user_dir

        d = Path(user_dir())
        d.mkdir(parents=True, exist_ok=True)
        return d
    except Exception:  # library missing or the folder cannot be made: let the dialog start anywhere
        return None


_COPY = re.compile(r"^(?P<base>.*?)\s*\(copy(?:\s+(?P<n>\d+))?\)$", re.IGNORECASE)


def unique_copy_name(name: str, taken) -> str:
    """``name`` itself when no other character is called that (case-insensitively), else the
    first free one of "Name (copy)", "Name (copy 2)", "Name (copy 3)"… — a copy of a copy
    counts on from the same base, it does not become "Name (copy) (copy)"."""
    names = {t.strip().lower() for t in taken}
    if name.strip().lower() not in names:
        return name
    m = _COPY.match(name.strip())
    base = m.group("base") if m and m.group("base") else name.strip()
    k = 1
    while True:
        cand = f"{base} (copy)" if k == 1 else f"{base} (copy {k})"
        if cand.lower() not in names:
            return cand
        k += 1


def known_characters() -> list[tuple[str, Path]]:
    """``(name, folder)`` of every character the performance window lists: the bundled ones,
    those in the user folder and those remembered from elsewhere."""
    out: list[tuple[str, Path]] = []
    try:
        from art_sets.library import list_all

        out += list_all()
    except Exception:  # a broken user folder must not stop a save
        pass
    try:
        import json

        from app.settings import Settings

        seen = {Path(f).resolve() for _, f in out}
        for d in Settings().user_art_dirs():
            p = Path(d)
            if p.resolve() not in seen and (p / "artset.json").is_file():
                name = json.loads((p / "artset.json").read_text(encoding="utf-8")).get("name") or p.name
                out.append((str(name), p))
    except Exception:
        pass
    return out


class SaveFolderDialog(QFileDialog):
    """Where to save a character: type the name of a new folder (made on saving) or of an
    existing one, or pick one in the list. Qt's own folder chooser refuses a name that does not
    exist yet ("Directory not found"), so this is a save dialog that lists folders only and
    takes the folder typed, new or not, instead of opening it."""

    def __init__(self, parent, start: Path | None, suggested: str = ""):
        super().__init__(parent, "Save the character in a folder — type a new folder's name, or choose one")
        self.setOption(QFileDialog.DontUseNativeDialog, True)
        self.setOption(QFileDialog.DontConfirmOverwrite, True)  # save_as asks before replacing a character
        self.setFileMode(QFileDialog.AnyFile)
        self.setAcceptMode(QFileDialog.AcceptSave)
        self.setFilter(QDir.AllDirs | QDir.NoDotAndDotDot | QDir.Drives)
        self.setLabelText(QFileDialog.Accept, "Save")
        self.setLabelText(QFileDialog.FileName, "Folder:")
        if start is not None:
            self.setDirectory(str(start))
        if suggested:
            self.selectFile(suggested)
        self.chosen: Path | None = None
        self.problem = ""
        box = self.findChild(QDialogButtonBox)
        self._ok = (box.button(QDialogButtonBox.Save) or box.button(QDialogButtonBox.Open)) if box else None
        self._edit = self.findChild(QLineEdit, "fileNameEdit")

    def typed(self) -> Path | None:
        """The folder named in the name field (relative to the folder shown), None if empty."""
        text = self._edit.text().strip() if self._edit is not None else ""
        if not text:
            return None
        p = Path(text).expanduser()
        return p if p.is_absolute() else Path(self.directory().absolutePath()) / p

    def accept(self):
        p = self.typed()
        if p is None:
            p = Path(self.directory().absolutePath())  # nothing typed: the folder shown
        parent = p.parent
        while not parent.exists() and parent != parent.parent:
            parent = parent.parent
        if p.exists() and not p.is_dir():
            self.problem = f"{p.name} is a file: type a folder's name"
        elif not p.exists() and not parent.is_dir():
            self.problem = f"cannot make a folder inside {parent}"
        else:
            self.chosen, self.problem = p, ""
            QDialog.accept(self)
            return
        QMessageBox.information(self, "Inkface", self.problem)


def _remember_user_folder(folder: Path) -> None:
    """Tell the performance window about a character saved outside the user art folder."""
    base = _user_art_dir()
    try:
        if base is not None and folder.resolve().parent == base.resolve():
            return
        from app.settings import Settings

        st = Settings()
        st.add_user_art_dir(folder)
        st.sync()
    except Exception:  # remembering is a convenience; the save itself succeeded
        pass


def _use_the_main_windows_theme() -> None:
    """Give the application the performance window's dark theme (``app.views``), unless it has a
    style already (the editor opened from a program that chose its own look)."""
    from PySide6.QtWidgets import QApplication

    from app.views import apply_theme

    qapp = QApplication.instance()
    if qapp is not None and not qapp.styleSheet():
        apply_theme(qapp)


class NewCharacterDialog(QDialog):
    """Name, author and the image files of a new character (file dialogs or drag-and-drop)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setWindowTitle("New character from images")
        form = QFormLayout(self)
        self.name = QLineEdit("My character")
        self.author = QLineEdit("")
        form.addRow("Name", self.name)
        form.addRow("Author", self.author)
        self.lists: dict[str, DropList] = {}
        for key, label in (("heads", "Head image(s)"), ("eyes", "Eye drawings"), ("mouth", "Mouth drawings")):
            box = QWidget()
            h = QHBoxLayout(box)
            h.setContentsMargins(0, 0, 0, 0)
            lst = DropList()
            lst.setMinimumHeight(70)
            lst.filesDropped.connect(lambda paths, k=key: self._add(k, paths))
            btn = QPushButton("Add…")
            btn.clicked.connect(lambda _=False, k=key: self._browse(k))
            clr = QPushButton("Clear")
            clr.clicked.connect(lambda _=False, k=key: self._clear(k))
            col = QVBoxLayout()
            col.addWidget(btn)
            col.addWidget(clr)
            col.addStretch(1)
            h.addWidget(lst, 1)
            h.addLayout(col)
            self.lists[key] = lst
            form.addRow(label, box)
        from_folder = QPushButton("Fill from a folder…")
        from_folder.setToolTip("sorts the images of a folder (and its sub-folders) by the words head/face, "
                               "eye/brow and mouth/lip in their file or folder names")
        from_folder.clicked.connect(self._from_folder)
        form.addRow(from_folder)
        self.fit = QComboBox()
        self.fit.addItems(["resize", "crop"])
        form.addRow("Drawings of another size", self.fit)
        hint = QLabel("Drop image files on the lists. Drawing names come from the file names "
                      "(open, closed, wide, angry; neutral, smile, ah, oo, grin, frown).")
        hint.setWordWrap(True)
        form.addRow(hint)
        bb = QDialogButtonBox(QDialogButtonBox.Ok | QDialogButtonBox.Cancel)
        bb.accepted.connect(self._accept)
        bb.rejected.connect(self.reject)
        form.addRow(bb)
        self.paths: dict[str, list[Path]] = {k: [] for k in self.lists}

    def _from_folder(self):
        d = QFileDialog.getExistingDirectory(self, "Folder with head, eye and mouth images")
        if d:
            self.fill_from_folder(Path(d))

    def fill_from_folder(self, folder: Path) -> dict:
        """Sort a folder's images (one level of sub-folders too) into the three lists."""
        files = [p for p in Path(folder).rglob("*") if p.suffix.lower() in ed.IMAGE_SUFFIXES
                 and len(p.relative_to(folder).parts) <= 2]
        sorted_ = ed.sort_images(files)
        for key in ("heads", "eyes", "mouth"):
            self._clear(key)
            self._add(key, sorted_[key])
        if not self.name.text().strip() or self.name.text() == "My character":
            self.name.setText(Path(folder).name.replace("_", " ").replace("-", " ").title())
        return sorted_

    def _clear(self, key):
        self.lists[key].clear()
        self.paths[key] = []

    def _browse(self, key):
        files, _ = QFileDialog.getOpenFileNames(self, "Choose images", "", IMAGE_FILTER)
        self._add(key, [Path(f) for f in files])

    def _add(self, key, paths):
        for p in image_paths(paths):
            try:
                icon = thumb_icon(ed.load_image(p), 40)
            except ed.EditError as e:
                QMessageBox.warning(self, "Inkface", str(e))
                continue
            self.paths[key].append(p)
            self.lists[key].addItem(p.name)
            self.lists[key].item(self.lists[key].count() - 1).setIcon(icon)

    def _accept(self):
        if not self.paths["heads"]:
            QMessageBox.information(self, "Inkface", "Add at least one head image.")
            return
        self.accept()


class EditorWindow(QMainWindow):
    """The art-set editor."""

    def __init__(self, parent=None, autosave_delay_ms: int = 1500):
        super().__init__(parent)
        _use_the_main_windows_theme()
        self.doc = EditorDocument(self, autosave_delay_ms=autosave_delay_ms)
        self.setAcceptDrops(True)
        self.resize(1360, 860)
        # hooks the tests replace to answer questions without modal dialogs
        self.ask_save_folder = self._ask_save_folder_dialog
        self.ask_fit = self._ask_fit_dialog
        self.ask_recover = self._ask_recover_dialog
        self.confirm_close = self._confirm_close_dialog
        self._build()
        self.doc.changed.connect(self._on_changed)
        self.doc.selectionChanged.connect(self._on_selection)
        self.doc.message.connect(self._show_message)
        self.doc.autosaved.connect(self._show_autosaved)
        self.doc.undo_stack.cleanChanged.connect(self._update_title)
        self._on_changed()
        self._on_selection()
        self._restore_geometry()

    def _settings(self):
        try:
            from app.settings import Settings

            return Settings()
        except Exception:  # settings are a convenience
            return None

    def _restore_geometry(self):
        st = self._settings()
        if st is None:
            return
        g, s = st.geometry("editor"), st.geometry("editor-state")
        if g is not None:
            self.restoreGeometry(g)
        if s is not None:
            self.restoreState(s)

    def _save_geometry(self):
        st = self._settings()
        if st is not None:
            st.set_geometry("editor", self.saveGeometry())
            st.set_geometry("editor-state", self.saveState())
            st.sync()

    # ------------------------------------------------------------------ layout
    def _build(self):
        self.line_canvas = LineCanvas(self.doc)
        self.head_canvas = HeadCanvas(self.doc)
        self.strip = PartStrip(self.doc)
        self.strip.drawingClicked.connect(lambda i: self.doc.select(drawing=i))

        lines_page = QWidget()
        lv = QVBoxLayout(lines_page)
        lv.setContentsMargins(0, 0, 0, 0)
        bar = QHBoxLayout()
        self.part_buttons = {}
        for name in PART_NAMES:
            b = QRadioButton(name.capitalize())
            b.toggled.connect(lambda on, n=name: on and self.doc.select(part=n))
            self.part_buttons[name] = b
            bar.addWidget(b)
        bar.addSpacing(16)
        bar.addWidget(QLabel("Ghost:"))
        self.ghost_combo = QComboBox()
        self.ghost_combo.setToolTip("show another drawing faintly underneath, with its lines dotted")
        self.ghost_combo.currentIndexChanged.connect(self._ghost_changed)
        bar.addWidget(self.ghost_combo)
        self.copy_button = QPushButton("Copy lines from…")
        self.copy_button.clicked.connect(self._copy_lines_menu)
        bar.addWidget(self.copy_button)
        self.starter_button = QPushButton("Starter lines")
        self.starter_button.setToolTip("frame the ink of every drawing of this part with lines "
                                       "(top, bottom, left, right of each feature): a quick start to refine")
        self.starter_button.clicked.connect(self._starter_lines)
        bar.addWidget(self.starter_button)
        self.accept_button = QPushButton("Accept dashed lines")
        self.accept_button.setToolTip("the copied (dashed) lines already sit on their features here")
        self.accept_button.clicked.connect(self._safe(lambda: self.doc.accept_lines(self.doc.part, self.doc.drawing)))
        bar.addWidget(self.accept_button)
        bar.addStretch(1)
        lv.addLayout(bar)
        split = QSplitter(Qt.Vertical)
        split.addWidget(self.line_canvas)
        split.addWidget(self.strip)
        split.setStretchFactor(0, 4)
        split.setStretchFactor(1, 1)
        lv.addWidget(split, 1)

        head_page = QWidget()
        hv = QVBoxLayout(head_page)
        hv.setContentsMargins(0, 0, 0, 0)
        hb = QHBoxLayout()
        self.mode_arrange = QRadioButton("Arrange boxes")
        self.mode_paint = QRadioButton("Paint holes")
        self.mode_arrange.setChecked(True)
        self.mode_arrange.toggled.connect(lambda on: self._set_head_mode("arrange" if on else "paint"))
        hb.addWidget(self.mode_arrange)
        hb.addWidget(self.mode_paint)
        hb.addSpacing(10)
        hb.addWidget(QLabel("brush"))
        self.brush_spin = QSpinBox()
        self.brush_spin.setRange(1, 200)
        self.brush_spin.setValue(10)
        self.brush_spin.setSuffix(" px")
        self.brush_spin.valueChanged.connect(lambda v: setattr(self.head_canvas, "brush_radius", float(v)))
        hb.addWidget(self.brush_spin)
        self.all_heads = QCheckBox("all heads")
        self.all_heads.setChecked(True)
        self.all_heads.toggled.connect(lambda v: setattr(self.head_canvas, "paint_all_heads", v))
        hb.addWidget(self.all_heads)
        hb.addStretch(1)
        hv.addLayout(hb)
        hb = QHBoxLayout()  # a second row, so the editor fits a 1366-pixel-wide screen
        hb.addWidget(QLabel("feather"))
        self.radius_spin = QDoubleSpinBox()
        self.radius_spin.setRange(0, 100)
        self.radius_spin.setValue(8)
        self.radius_spin.setSuffix(" px")
        self.radius_spin.setToolTip("how far inside each box the hole fades in; changing it right after cutting re-cuts")
        self.radius_spin.valueChanged.connect(self._radius_changed)
        hb.addWidget(self.radius_spin)
        self.holes_button = QPushButton("Cut holes from boxes")
        self.holes_button.setToolTip("open each part box in every head, soft-edged over the feather radius")
        self.holes_button.clicked.connect(self.cut_holes)
        hb.addWidget(self.holes_button)
        self.head_only = QCheckBox("head only")
        self.head_only.toggled.connect(self._head_only)
        hb.addWidget(self.head_only)
        hb.addStretch(1)
        prev_h = QPushButton("◀ head")
        next_h = QPushButton("head ▶")
        prev_h.clicked.connect(lambda: self._step_head(-1))
        next_h.clicked.connect(lambda: self._step_head(1))
        hb.addWidget(prev_h)
        hb.addWidget(next_h)
        hv.addLayout(hb)
        hv.addWidget(self.head_canvas, 1)

        self.tabs = QTabWidget()
        self.tabs.addTab(lines_page, "Control lines")
        self.tabs.addTab(head_page, "Head, boxes and holes")
        self.setCentralWidget(self.tabs)

        # left: the character
        left = QWidget()
        ll = QVBoxLayout(left)
        ll.setContentsMargins(4, 4, 4, 4)
        info = QFormLayout()
        self.name_edit = QLineEdit()
        self.author_edit = QLineEdit()
        self.name_edit.editingFinished.connect(self._info_edited)
        self.author_edit.editingFinished.connect(self._info_edited)
        info.addRow("Name", self.name_edit)
        info.addRow("Author", self.author_edit)
        ll.addLayout(info)
        self.lists: dict[str, DropList] = {}
        for key, title in (("heads", "Heads"), ("eyes", "Eyes"), ("mouth", "Mouth")):
            g = QGroupBox(title)
            gl = QVBoxLayout(g)
            gl.setContentsMargins(4, 4, 4, 4)
            lst = DropList()
            lst.setToolTip("drop image files here")
            if key == "heads":
                lst.setViewMode(DropList.IconMode)
                lst.setFlow(DropList.LeftToRight)
                lst.setWrapping(False)
                lst.setIconSize(QSize(56, 56))
                lst.setFixedHeight(96)
                lst.setMovement(DropList.Static)
            lst.filesDropped.connect(lambda paths, k=key: self.add_files(k, paths))
            lst.currentRowChanged.connect(lambda row, k=key: self._list_picked(k, row))
            lst.itemDoubleClicked.connect(lambda it, k=key: self._rename(k))
            gl.addWidget(lst)
            row = QHBoxLayout()
            add = QPushButton("Add…")
            add.clicked.connect(lambda _=False, k=key: self._browse_add(k))
            rem = QPushButton("Remove")
            rem.clicked.connect(lambda _=False, k=key: self._remove(k))
            row.addWidget(add)
            row.addWidget(rem)
            if key != "heads":
                ren = QPushButton("Rename")
                ren.clicked.connect(lambda _=False, k=key: self._rename(k))
                row.addWidget(ren)
            gl.addLayout(row)
            ll.addWidget(g, 0 if key == "heads" else 1)
            self.lists[key] = lst
        self._filling_lists = False
        dock = self._dock("Character", "character", left, Qt.LeftDockWidgetArea)
        self.preview = PreviewPanel(self.doc)
        pd = self._dock("Preview", "preview", self.preview, Qt.RightDockWidgetArea)
        self.layers_panel = LayersPanel(self.doc)
        self.layers_panel.ask_fit = lambda key, names: self.ask_fit(key, names)
        lyd = self._dock("Layers", "layers", self.layers_panel, Qt.RightDockWidgetArea)
        self.splitDockWidget(lyd, pd, Qt.Vertical)
        self.lines_list = LinesList(self.doc)
        ld = self._dock("Lines", "lines", self.lines_list, Qt.BottomDockWidgetArea)
        self.problems = ProblemsList(self.doc)
        self.problems.issueActivated.connect(self._issue_activated)
        prd = self._dock("Problems", "problems", self.problems, Qt.BottomDockWidgetArea)
        self.splitDockWidget(ld, prd, Qt.Horizontal)
        self.resizeDocks([dock, pd], [250, 330], Qt.Horizontal)
        self.resizeDocks([ld], [150], Qt.Vertical)
        self.resizeDocks([lyd, pd], [330, 500], Qt.Vertical)
        self._build_menus()

    def _dock(self, title: str, name: str, widget: QWidget, area) -> QDockWidget:
        """``widget`` in a movable, floatable dock at ``area`` (``name`` keys its saved place)."""
        d = QDockWidget(title, self)
        d.setObjectName(name)
        d.setWidget(widget)
        d.setFeatures(QDockWidget.DockWidgetMovable | QDockWidget.DockWidgetFloatable)
        self.addDockWidget(area, d)
        return d

    def _build_menus(self):
        mb = self.menuBar()
        f = mb.addMenu("&File")
        self.act_new = f.addAction("&New character from images…", self.new_character_dialog, QKeySequence.New)
        f.addAction("&Open…", self.open_dialog, QKeySequence.Open)
        self.bundled_menu = f.addMenu("Open a &bundled character")
        self.bundled_menu.aboutToShow.connect(self._fill_bundled)
        f.addSeparator()
        self.act_save = f.addAction("&Save", self.save, QKeySequence.Save)
        f.addAction("Save &as…", self.save_as, QKeySequence.SaveAs)
        f.addSeparator()
        f.addAction("&Close", self.close, QKeySequence.Close)
        e = mb.addMenu("&Edit")
        undo = self.doc.undo_stack.createUndoAction(self, "&Undo")
        undo.setShortcut(QKeySequence.Undo)
        redo = self.doc.undo_stack.createRedoAction(self, "&Redo")
        redo.setShortcut(QKeySequence.Redo)
        e.addAction(undo)
        e.addAction(redo)
        e.addSeparator()
        e.addAction("Delete selected line", self._safe(lambda: self.doc.line >= 0 and self.doc.delete_line(self.doc.part, self.doc.line)))
        e.addAction("Accept dashed lines in this drawing", self._safe(lambda: self.doc.accept_lines(self.doc.part, self.doc.drawing)))
        e.addAction("Add starter lines to this part", self._starter_lines)
        e.addAction("Resize drawings to the box", self._safe(lambda: self.doc.fit_part(self.doc.part, "resize")))
        e.addAction("Crop drawings to the box", self._safe(lambda: self.doc.fit_part(self.doc.part, "crop")))
        e.addAction("Resize heads to the canvas", self._safe(lambda: self.doc.fit_heads("resize")))
        e.addAction("Crop heads to the canvas", self._safe(lambda: self.doc.fit_heads("crop")))
        a = mb.addMenu("&Add")
        a.addAction("Head images…", lambda: self._browse_add("heads"))
        a.addAction("Eye drawings…", lambda: self._browse_add("eyes"))
        a.addAction("Mouth drawings…", lambda: self._browse_add("mouth"))
        tb = QToolBar("Main")
        tb.setObjectName("main-toolbar")
        tb.setIconSize(QSize(16, 16))
        tb.addAction(self.act_new)
        tb.addAction(self.act_save)
        tb.addSeparator()
        tb.addAction(undo)
        tb.addAction(redo)
        self.addToolBar(tb)

    def _safe(self, fn):
        """A menu slot that reports an impossible edit in the status bar instead of raising."""
        def run(*_):
            try:
                fn()
            except (ed.EditError, IndexError, KeyError) as e:
                self.statusBar().showMessage(str(e) if isinstance(e, ed.EditError) else "nothing to do here", 6000)
        return run

    # ------------------------------------------------------------------ refresh
    def _show_message(self, text: str):
        self.statusBar().showMessage(text, 6000)

    def _show_autosaved(self, where: str):
        self.statusBar().showMessage(f"autosaved to {where}", 2500)

    def _update_title(self, *_):
        art = self.doc.artset
        name = art.name if art else "no character"
        where = f" — {self.doc.path}" if self.doc.path else " — not saved yet"
        self.setWindowTitle(f"Inkface editor — {name}[*]{where if art else ''}")
        self.setWindowModified(self.doc.dirty or (art is not None and self.doc.path is None))

    def _on_changed(self):
        art = self.doc.artset
        self._update_title()
        self._filling_lists = True
        try:
            if art is not None:
                if self.name_edit.text() != art.name:
                    self.name_edit.setText(art.name)
                if self.author_edit.text() != art.author:
                    self.author_edit.setText(art.author)
            for key, lst in self.lists.items():
                lst.clear()
                if art is None:
                    continue
                if key == "heads":
                    for i, h in enumerate(art.heads):
                        lst.addItem(f"head {i + 1}")
                        lst.item(i).setIcon(cached_icon(h))
                    continue
                part = art.parts[key]
                miss = ed.missing_lines(art, key)
                for i, d in enumerate(part.drawings):
                    todo = sum(d.name in names for names in miss.values())
                    label = d.name
                    if d.size != part.size:
                        label += f"   ⚠ {d.size[0]}×{d.size[1]}"
                    if todo:
                        label += f"   ({todo} line{'s' if todo > 1 else ''} to place)"
                    lst.addItem(label)
                    lst.item(i).setIcon(cached_icon(d.image))
        finally:
            self._filling_lists = False
        self._on_selection()

    def _on_selection(self):
        art = self.doc.artset
        self._filling_lists = True
        try:
            for name, b in self.part_buttons.items():
                b.blockSignals(True)
                b.setChecked(name == self.doc.part)
                b.blockSignals(False)
            if art is not None:
                self.lists[self.doc.part].setCurrentRow(self.doc.drawing)
                other = [k for k in PART_NAMES if k != self.doc.part]
                for k in other:
                    self.lists[k].setCurrentRow(-1)
                self.lists["heads"].setCurrentRow(self.doc.head)
                names = art.parts[self.doc.part].names()
                cur = self.ghost_combo.currentText()
                self.ghost_combo.blockSignals(True)
                self.ghost_combo.clear()
                self.ghost_combo.addItem("none")
                self.ghost_combo.addItems(names)
                self.ghost_combo.setCurrentIndex(names.index(cur) + 1 if cur in names else 0)
                self.ghost_combo.blockSignals(False)
                self._ghost_changed()
                has = 0 <= self.doc.drawing < len(art.parts[self.doc.part].drawings)
                self.accept_button.setEnabled(has and bool(ed.unplaced(art, self.doc.part, self.doc.drawing)))
            else:
                self.accept_button.setEnabled(False)
        finally:
            self._filling_lists = False

    def _issue_activated(self, issue):
        about_head = issue.head is not None or "box" in issue.message or "head" in issue.message
        self.tabs.setCurrentIndex(1 if about_head and issue.line is None else 0)

    def _ghost_changed(self, *_):
        self.line_canvas.ghost = self.ghost_combo.currentIndex() - 1
        self.line_canvas.update()

    def _list_picked(self, key, row):
        if self._filling_lists or row < 0:
            return
        if key == "heads":
            self.doc.select(head=row)
        else:
            self.doc.select(part=key, drawing=row)

    # ------------------------------------------------------------------ actions
    def new_character(self, name: str, heads, eyes=(), mouths=(), author: str = "", fit: str = "resize"):
        """Start a new character from image files (what File ▸ New does after its dialog)."""
        art = self.doc.new_character(name, heads, eyes, mouths, author=author, fit=fit)
        self.tabs.setCurrentIndex(1)
        self.statusBar().showMessage("New character: arrange the boxes, cut the holes, then draw control lines.", 8000)
        return art

    def new_character_dialog(self):
        if not self._maybe_save():
            return
        dlg = NewCharacterDialog(self)
        if dlg.exec() != QDialog.Accepted:
            return
        try:
            self.new_character(dlg.name.text(), dlg.paths["heads"], dlg.paths["eyes"], dlg.paths["mouth"],
                               author=dlg.author.text(), fit=dlg.fit.currentText())
        except ed.EditError as e:
            QMessageBox.warning(self, "Inkface", str(e))

    def open_path(self, path) -> bool:
        """Open an art-set folder (offering to recover a newer autosave). False if it failed."""
        from art_sets.io import ArtSetError

        path = Path(path)
        if path.name == "artset.json":
            path = path.parent
        side = recoverable(path)
        recover = bool(side) and self.ask_recover(path, side)
        try:
            self.doc.open(path, recover=recover)
        except (ArtSetError, OSError) as e:
            QMessageBox.warning(self, "Inkface", " ".join(str(e).split()))
            return False
        if side and not recover:
            self.doc.discard_autosave()
        self.tabs.setCurrentIndex(0)
        self.offer_fit()
        return True

    def offer_fit(self) -> None:
        """Offer to resize or crop heads and drawings whose size does not match (as on opening)."""
        art = self.doc.artset
        if art is None:
            return
        odd = ed.head_mismatches(art)
        if odd:
            mode = self.ask_fit("heads", [art.head_files[i] for i in odd])
            if mode:
                self.doc.fit_heads(mode)
        for pname, part in self.doc.artset.parts.items():
            odd = ed.size_mismatches(part)
            if odd:
                mode = self.ask_fit(pname, [part.drawings[i].name for i in odd])
                if mode:
                    self.doc.fit_part(pname, mode)

    def offer_untitled_recovery(self) -> bool:
        """If a never-saved character was autosaved, offer to reopen it (True if reopened)."""
        from art_sets.io import ArtSetError

        side = recoverable(None)
        if side is None or not self.ask_recover("The character you had not saved yet", side):
            return False
        try:
            self.doc.open_recovered_untitled()
        except (ArtSetError, OSError) as e:
            self.statusBar().showMessage(f"could not recover: {' '.join(str(e).split())}", 8000)
            return False
        return True

    def open_dialog(self):
        if not self._maybe_save():
            return
        d = QFileDialog.getExistingDirectory(self, "Open an art-set folder")
        if d:
            self.open_path(d)

    def _fill_bundled(self):
        self.bundled_menu.clear()
        try:
            from art_sets.library import list_bundled

            items = list_bundled()
        except Exception:
            items = []
        for name, path in items:
            self.bundled_menu.addAction(name, lambda p=path: self._maybe_save() and self.open_path(p))
        if not items:
            self.bundled_menu.addAction("(none found)").setEnabled(False)

    def save(self) -> bool:
        if self.doc.artset is None:
            return False
        if self.doc.path is None or is_bundled(self.doc.path):
            if self.doc.path is not None:
                self.statusBar().showMessage("bundled characters are not changed in place: choose a folder for your copy", 8000)
            return self.save_as()
        return self._save_to(self.doc.path)

    def copy_name(self, target: Path) -> str:
        """The name the character gets when saved into ``target``: its own, unless another known
        character (a bundled one it was copied from, say) is called that — then "Name (copy)"."""
        here = {Path(target).resolve()}
        taken = [n for n, f in known_characters() if Path(f).resolve() not in here]
        return unique_copy_name(self.doc.artset.name, taken)

    def _ask_save_folder_dialog(self, start: Path | None, suggested: str) -> Path | None:
        dlg = SaveFolderDialog(self, start, suggested)
        return dlg.chosen if dlg.exec() == QDialog.Accepted else None

    def save_as(self) -> bool:
        """Ask for a folder (an existing one, or a new one by typing its name) and save there."""
        if self.doc.artset is None:
            return False
        start = _user_art_dir()
        suggested = ed.slug(unique_copy_name(self.doc.artset.name, [n for n, _ in known_characters()]))
        if start is not None and (start / suggested).exists():
            k = 2
            while (start / f"{suggested}-{k}").exists():
                k += 1
            suggested = f"{suggested}-{k}"
        chosen = self.ask_save_folder(start, suggested)
        if chosen is None:
            return False
        folder = Path(chosen)
        if folder.exists() and not folder.is_dir():
            QMessageBox.information(self, "Inkface", f"{folder} is a file; choose or name a folder.")
            return False
        has_set = (folder / "artset.json").exists()
        if not has_set and folder.is_dir() and (any(folder.iterdir()) or (start is not None and folder.resolve() == start.resolve())):
            # a folder of other things (or of all the characters): a new sub-folder for this one
            base = ed.slug(self.copy_name(folder / ".new"))
            sub, k = folder / base, 2
            while sub.exists():
                sub, k = folder / f"{base}-{k}", k + 1
            folder, has_set = sub, False
        if is_bundled(folder):
            QMessageBox.information(self, "Inkface", "Bundled characters are not changed in place; choose another folder.")
            return False
        if has_set and folder != self.doc.path:
            ans = QMessageBox.question(self, "Replace character?", f"{folder} already holds a character. Replace it?",
                                       QMessageBox.Yes | QMessageBox.No, QMessageBox.No)
            if ans != QMessageBox.Yes:
                return False
        return self._save_to(folder, rename=True)

    def _save_to(self, folder, rename: bool = False) -> bool:
        """Save into ``folder``; with ``rename`` (a save-as), first give the character a name no
        other character has ("Noodle (copy)")."""
        from art_sets.io import ArtSetError

        old = self.doc.artset.name
        new = self.copy_name(Path(folder)) if rename else old
        renamed = new != old
        if renamed:
            self.doc.set_info(new)  # an undoable step, like typing the name
        try:
            self.doc.save(folder, runner=self._run_busy)
        except (ArtSetError, OSError, ed.EditError) as e:
            if renamed:
                self.doc.undo_stack.undo()
            QMessageBox.warning(self, "Inkface", f"Could not save: {' '.join(str(e).split())}")
            return False
        self._update_title()
        _remember_user_folder(Path(folder))
        if renamed:
            self.statusBar().showMessage(f"Saved as “{new}” in {folder}: another character is already called “{old}”", 10000)
        return True

    def _run_busy(self, fn, text: str = "Saving…"):
        """Run ``fn`` on a thread behind a modal busy dialog (the window keeps painting)."""
        import threading

        from PySide6.QtWidgets import QApplication, QProgressDialog

        box: dict = {}

        def work():
            try:
                box["result"] = fn()
            except BaseException as e:  # handed back to the GUI thread below
                box["error"] = e

        t = threading.Thread(target=work, name="editor-save", daemon=True)
        dlg = QProgressDialog(text, None, 0, 0, self)
        dlg.setWindowModality(Qt.WindowModal)
        dlg.setMinimumDuration(400)
        t.start()
        while t.is_alive():
            QApplication.processEvents()
            t.join(0.03)
        dlg.close()
        if "error" in box:
            raise box["error"]
        return box["result"]

    def add_files(self, key: str, paths) -> None:
        """Add image files as heads or drawings of a part, offering resize/crop for other sizes."""
        paths = image_paths(paths)
        if not paths or self.doc.artset is None:
            if paths and self.doc.artset is None and key == "heads":
                self.new_character("Untitled", paths)
            return
        try:
            if key == "heads":
                fit = "resize"
                sizes = {ed.load_image(p).shape[1::-1] for p in paths}
                if any(tuple(s) != tuple(self.doc.artset.canvas) for s in sizes):
                    fit = self.ask_fit("heads", [p.name for p in paths])
                    if fit is None:
                        return
                self.doc.add_heads(paths, fit)
                return
            part = self.doc.artset.parts[key]
            images = [ed.load_image(p) for p in paths]
            odd = [p.name for p, im in zip(paths, images) if (im.shape[1], im.shape[0]) != part.size]
            fit = "resize"
            if odd and part.drawings:
                fit = self.ask_fit(key, odd)
                if fit is None:
                    return
            if not part.drawings and images:
                # the first drawings set the box size
                box = ed.default_box(self.doc.artset.canvas, key, (images[0].shape[1], images[0].shape[0]))
                self.doc.set_box(key, box)
            self.doc.add_drawings(key, paths, fit)
        except ed.EditError as e:
            QMessageBox.warning(self, "Inkface", str(e))

    def _browse_add(self, key):
        if self.doc.artset is None and key != "heads":
            QMessageBox.information(self, "Inkface", "Make a new character first (File ▸ New).")
            return
        files, _ = QFileDialog.getOpenFileNames(self, f"Add {key}", "", IMAGE_FILTER)
        if files:
            self.add_files(key, [Path(f) for f in files])

    def _remove(self, key):
        art = self.doc.artset
        if art is None:
            return
        row = self.lists[key].currentRow()
        if row < 0:
            return
        try:
            if key == "heads":
                self.doc.remove_head(row)
            else:
                self.doc.remove_drawing(key, row)
        except ed.EditError as e:
            QMessageBox.information(self, "Inkface", str(e))

    def _rename(self, key):
        art = self.doc.artset
        if art is None or key == "heads":
            return
        row = self.lists[key].currentRow()
        if row < 0:
            return
        old = art.parts[key].drawings[row].name
        try:
            from art_sets.validate import RECOMMENDED

            usual = [n for n in RECOMMENDED.get(key, ()) if n not in art.parts[key].names()]
        except ImportError:
            usual = []
        new, ok = QInputDialog.getItem(
            self, "Rename drawing",
            f"New name for {key} drawing {old!r}\n(the usual names let the default training pair it with an expression):",
            [old] + usual, 0, True)
        if ok and new.strip() and new != old:
            self.doc.rename_drawing(key, row, new)

    def _info_edited(self):
        art = self.doc.artset
        if art is None:
            return
        name, author = self.name_edit.text(), self.author_edit.text()
        if (name.strip() or art.name) != art.name or author != art.author:
            self.doc.set_info(name, author)

    def _copy_lines_menu(self):
        from PySide6.QtWidgets import QMenu

        art = self.doc.artset
        if art is None:
            return
        m = QMenu(self)
        for j, d in enumerate(art.parts[self.doc.part].drawings):
            if j != self.doc.drawing:
                m.addAction(d.name, lambda j=j: self.doc.copy_lines(self.doc.part, j, self.doc.drawing))
        m.exec(self.copy_button.mapToGlobal(self.copy_button.rect().bottomLeft()))

    def _starter_lines(self):
        art = self.doc.artset
        if art is None:
            return
        try:
            n = self.doc.add_starter_lines(self.doc.part)
        except ed.EditError as e:
            self.statusBar().showMessage(str(e), 6000)
            return
        self.statusBar().showMessage(f"added {n} starter lines to every {self.doc.part} drawing: drag them onto the features", 8000)

    def cut_holes(self):
        if self.doc.artset is not None:
            self.doc.make_holes(self.radius_spin.value())

    def _radius_changed(self, _value):
        st = self.doc.undo_stack
        if st.index() > 0 and st.command(st.index() - 1).text().startswith("cut holes"):
            st.undo()  # replace the cut just made, so trying radii does not stack up undo steps
            self.cut_holes()

    def _set_head_mode(self, mode):
        self.head_canvas.mode = mode
        self.head_canvas.update()

    def _head_only(self, on):
        self.head_canvas.head_only = on
        self.head_canvas._invalidate()

    def _step_head(self, step):
        art = self.doc.artset
        if art is not None and art.heads:
            self.doc.select(head=(self.doc.head + step) % len(art.heads))

    # ------------------------------------------------------------------ questions (replaceable in tests)
    def _ask_fit_dialog(self, key, names) -> str | None:
        box = QMessageBox(self)
        box.setWindowTitle("Drawings of another size")
        target = "the canvas" if key == "heads" else f"the {key} box"
        box.setText(f"{len(names)} image(s) are not the size of {target}: {', '.join(names[:6])}"
                    f"{'…' if len(names) > 6 else ''}.\nResize them (scale to fit) or crop them (keep the centre)?")
        resize = box.addButton("Resize", QMessageBox.AcceptRole)
        crop = box.addButton("Crop", QMessageBox.AcceptRole)
        box.addButton(QMessageBox.Cancel)
        box.exec()
        return "resize" if box.clickedButton() is resize else "crop" if box.clickedButton() is crop else None

    def _ask_recover_dialog(self, path, side) -> bool:
        return QMessageBox.question(
            self, "Recover unsaved changes?",
            f"{path} has unsaved changes from an earlier session (autosaved).\nRecover them?",
            QMessageBox.Yes | QMessageBox.No, QMessageBox.Yes) == QMessageBox.Yes

    def _confirm_close_dialog(self) -> str:
        r = QMessageBox.question(self, "Unsaved changes", "Save the changes to this character?",
                                 QMessageBox.Save | QMessageBox.Discard | QMessageBox.Cancel, QMessageBox.Save)
        return {QMessageBox.Save: "save", QMessageBox.Discard: "discard"}.get(r, "cancel")

    def _maybe_save(self) -> bool:
        if not self.doc.dirty and not (self.doc.artset is not None and self.doc.path is None and self.doc.undo_stack.count()):
            return True
        ans = self.confirm_close()
        if ans == "save":
            return self.save()
        if ans == "discard":
            self.doc.undo_stack.setClean()
            self.doc.discard_autosave()
            return True
        return False

    # ------------------------------------------------------------------ window events
    def closeEvent(self, ev):
        if not self._maybe_save():
            ev.ignore()
            return
        self.preview.stop()
        self.doc.close()
        self._save_geometry()
        ev.accept()

    def dragEnterEvent(self, ev):
        paths = dropped_paths(ev.mimeData())
        if any((p / "artset.json").is_file() or p.name == "artset.json" for p in paths) or image_paths(paths):
            ev.acceptProposedAction()

    def dropEvent(self, ev):
        paths = dropped_paths(ev.mimeData())
        sets = [p for p in paths if (p / "artset.json").is_file() or p.name == "artset.json"]
        if sets:
            if self._maybe_save():
                self.open_path(sets[0])
            return
        imgs = image_paths(paths)
        if imgs:
            target = "heads" if self.doc.artset is None or self.tabs.currentIndex() == 1 and not self.doc.artset.parts[self.doc.part].drawings else self.doc.part
            self.add_files(target, imgs)
