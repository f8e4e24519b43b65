"""The layers panel: the stack of the selected part's drawings, as in a paint program.

Rows run top layer first (the way Krita and Photoshop list them; the manifest stores them
bottom first). Each row shows the layer's picture in the selected drawing, its name, whether
it moves with its own control lines or the drawing's, and a check box that shows or hides it
while you draw lines. Every drawing of a part has the same layers, so adding, removing,
renaming and reordering act on all of them; a picture belongs to one drawing (or to all).
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QSize, Qt, QTimer
from PySide6.QtWidgets import (
    QCheckBox, QFileDialog, QGridLayout, QInputDialog, QLabel, QListWidget, QListWidgetItem, QMenu,
    QPushButton, QSizePolicy, QVBoxLayout, QWidget,
)

from art_sets import editing as ed

from .document import EditorDocument
from .panels import cached_icon

IMAGE_FILTER = "Images (*.png *.jpg *.jpeg *.bmp *.gif *.tif *.tiff *.webp)"


class LayerList(QListWidget):
    """The rows of the stack; dragging a row reorders the layers (one undo step)."""

    def __init__(self, panel: "LayersPanel"):
        super().__init__(panel)
        self.panel = panel
        self.setIconSize(QSize(44, 30))
        self.setDragDropMode(QListWidget.InternalMove)
        self.setDefaultDropAction(Qt.MoveAction)
        self.setSizePolicy(QSizePolicy.Preferred, QSizePolicy.Expanding)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarAlwaysOff)
        self.setTextElideMode(Qt.ElideRight)
        self.setMinimumHeight(4 * 38 + 6)  # four rows: a character's eyes or mouth seldom need more

        self.model().rowsMoved.connect(self._rows_moved)

    def _rows_moved(self, _parent, start: int, _end: int, _dest, row: int) -> None:
        """A row dragged to another place: move the layer in the model, after Qt's drop ends
        (the list is then refilled from the model)."""
        dst = row - 1 if row > start else row
        if dst != start:
            QTimer.singleShot(0, lambda: self.panel.move_row(start, dst))


class LayersPanel(QWidget):
    """Layers of the selected part: show, hide, solo, add, remove, rename, reorder, duplicate,
    own or shared control lines, pictures, import of layered drawings, conversion."""

    def __init__(self, doc: EditorDocument, parent=None):
        super().__init__(parent)
        self.doc = doc
        # questions the tests answer without modal dialogs
        self.ask_text = self._ask_text_dialog
        self.ask_folder = lambda title: QFileDialog.getExistingDirectory(self, title)
        self.ask_files = lambda title: QFileDialog.getOpenFileNames(self, title, "", IMAGE_FILTER)[0]
        self.ask_file = lambda title: QFileDialog.getOpenFileName(self, title, "", IMAGE_FILTER)[0]
        self.ask_fit = lambda key, names: "resize"
        self._filling = False

        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        self.title = QLabel("")
        self.title.setWordWrap(True)
        lay.addWidget(self.title)
        self.list = LayerList(self)
        self.list.currentRowChanged.connect(self._row_picked)
        self.list.itemChanged.connect(self._item_changed)
        self.list.itemDoubleClicked.connect(lambda _it: self.rename())
        lay.addWidget(self.list, 1)

        grid = QGridLayout()
        grid.setSpacing(3)
        self.add_button = self._button("Add", "a new transparent layer above the selected one, in every drawing", self._add_menu)
        self.dup_button = self._button("Duplicate", "a copy of the selected layer just above it", self.duplicate)
        self.remove_button = self._button("Remove", "remove the selected layer from every drawing", self.remove)
        self.up_button = self._button("Up ▲", "move the selected layer up the stack (in front)", lambda: self.step(1))
        self.down_button = self._button("Down ▼", "move the selected layer down the stack (behind)", lambda: self.step(-1))
        self.rename_button = self._button("Rename", "rename the selected layer (or double-click it)", self.rename)
        for i, b in enumerate([self.add_button, self.dup_button, self.remove_button,
                               self.up_button, self.down_button, self.rename_button]):
            grid.addWidget(b, i // 3, i % 3)
        lay.addLayout(grid)
        self.own_lines = QCheckBox("Own control lines")
        self.own_lines.setToolTip("checked: the layer moves with control lines of its own (drawn while it is selected);\n"
                                  "unchecked: it moves with the drawing's lines")
        self.own_lines.toggled.connect(self._own_toggled)
        self.solo = QCheckBox("Solo")
        self.solo.setToolTip("show only the selected layer while drawing lines")
        self.solo.toggled.connect(lambda on: self.doc.set_solo(on))
        row = QGridLayout()
        row.addWidget(self.own_lines, 0, 0)
        row.addWidget(self.solo, 0, 1)
        lay.addLayout(row)
        grid = QGridLayout()
        grid.setSpacing(3)
        self.picture_button = self._button("Picture…", "replace the selected layer's picture (this drawing or every drawing)",
                                           self._picture_menu)
        self.import_button = self._button("Import…", "a new drawing of this part made of layers: a folder of images "
                                                     "(10-eyeball.png under 20-lids.png) or chosen files", self._import_menu)
        self.convert_button = self._button("Convert to layers", "make each picture of this part a drawing of one layer",
                                           self.convert)
        grid.addWidget(self.picture_button, 0, 0)
        grid.addWidget(self.import_button, 0, 1)
        grid.addWidget(self.convert_button, 1, 0, 1, 2)
        lay.addLayout(grid)

        doc.changed.connect(self.refill)
        doc.selectionChanged.connect(self.refill)
        doc.viewChanged.connect(self.refill)
        self.refill()

    def _button(self, text: str, tip: str, slot) -> QPushButton:
        b = QPushButton(text)
        b.setToolTip(tip)
        b.clicked.connect(lambda _=False: self._safely(slot))
        return b

    def _safely(self, fn) -> None:
        try:
            fn()
        except ed.EditError as e:
            self.doc.message.emit(str(e))

    def sizeHint(self):
        return QSize(280, 300)

    # ---------------------------------------------------------------- model access
    def _part(self):
        return self.doc.artset.parts[self.doc.part] if self.doc.artset is not None else None

    def layers(self) -> list:
        """The selected drawing's layers, bottom first ([] for single pictures)."""
        p = self._part()
        if p is None or not p.drawings:
            return []
        return p.drawings[min(self.doc.drawing, len(p.drawings) - 1)].layers

    def row_of(self, k: int) -> int:
        return len(self.layers()) - 1 - k

    def layer_of(self, row: int) -> int:
        return len(self.layers()) - 1 - row

    def describe(self, k: int) -> str:
        """A row's second line: what the layer moves with, and whether it changes between drawings."""
        p = self._part()
        ly = self.layers()[k]
        what = f"own lines ({len(ly.lines)})" if ly.lines is not None else "drawing's lines"
        same = all(d.layers[k].image is ly.image or (d.layers[k].image.shape == ly.image.shape
                                                    and (d.layers[k].image == ly.image).all()) for d in p.drawings)
        return what + (" · same in every drawing" if same and len(p.drawings) > 1 else "")

    # ---------------------------------------------------------------- refresh
    def refill(self) -> None:
        p = self._part()
        layers = self.layers()
        self._filling = True
        try:
            self.list.clear()
            if p is None:
                self.title.setText("No character open.")
            elif not p.drawings:
                self.title.setText(f"No {self.doc.part} drawings yet: add pictures, or import a drawing made of layers.")
            elif not layers:
                self.title.setText(f"The {self.doc.part} drawings are single pictures. Convert them to layers to "
                                   "stack an eyeball under lids (or a mouth's inside under lips), or import a layered drawing.")
            else:
                d = p.drawings[min(self.doc.drawing, len(p.drawings) - 1)]
                self.title.setText(f"{self.doc.part} ▸ {d.name}: {len(layers)} layer(s), top first")
            for k in range(len(layers) - 1, -1, -1):
                ly = layers[k]
                it = QListWidgetItem(cached_icon(ly.image, 44), f"{ly.name}\n{self.describe(k)}")
                it.setFlags(it.flags() | Qt.ItemIsUserCheckable | Qt.ItemIsDragEnabled)
                it.setCheckState(Qt.Checked if self.doc.layer_visible(self.doc.part, ly.name) else Qt.Unchecked)
                it.setToolTip("check box: show while drawing · double-click: rename · drag: reorder")
                self.list.addItem(it)
            if layers and 0 <= self.doc.layer < len(layers):
                self.list.setCurrentRow(self.row_of(self.doc.layer))
            has = bool(layers)
            sel = has and 0 <= self.doc.layer < len(layers)
            for b in (self.dup_button, self.remove_button, self.rename_button, self.picture_button):
                b.setEnabled(sel)
            self.up_button.setEnabled(sel and self.doc.layer < len(layers) - 1)
            self.down_button.setEnabled(sel and self.doc.layer > 0)
            self.add_button.setEnabled(p is not None and bool(p.drawings))
            self.import_button.setEnabled(p is not None)
            self.convert_button.setEnabled(p is not None and bool(p.drawings))
            self.convert_button.setText("Flatten to single pictures" if has else "Convert to layers")
            self.convert_button.setToolTip("stack each drawing's layers into one picture (layers' own lines are dropped)"
                                           if has else "make each picture of this part a drawing of one layer")
            self.own_lines.blockSignals(True)
            self.own_lines.setEnabled(sel)
            self.own_lines.setChecked(sel and layers[self.doc.layer].lines is not None)
            self.own_lines.blockSignals(False)
            self.solo.blockSignals(True)
            self.solo.setEnabled(has)
            self.solo.setChecked(self.doc.solo)
            self.solo.blockSignals(False)
        finally:
            self._filling = False

    # ---------------------------------------------------------------- actions
    def _row_picked(self, row: int) -> None:
        if not self._filling and row >= 0:
            self.doc.select(layer=self.layer_of(row))

    def _item_changed(self, item: QListWidgetItem) -> None:
        if self._filling:
            return
        k = self.layer_of(self.list.row(item))
        if 0 <= k < len(self.layers()):
            self.doc.set_layer_visible(self.doc.part, self.layers()[k].name, item.checkState() == Qt.Checked)

    def _own_toggled(self, on: bool) -> None:
        if not self._filling and self.layers():
            self._safely(lambda: self.doc.set_layer_own_lines(self.doc.part, self.doc.layer, on))

    def _add_menu(self) -> None:
        m = QMenu(self)
        m.addAction("Empty layer", lambda: self._safely(self.add))
        m.addAction("Layer from an image (in every drawing)…", lambda: self._safely(self.add_from_file))
        m.exec(self.add_button.mapToGlobal(self.add_button.rect().bottomLeft()))

    def add(self, name: str | None = None) -> int | None:
        """A new transparent layer just above the selected one (the first layer of a part of single
        pictures converts it first)."""
        if name is None:
            name = self.ask_text("Add layer", "Name of the new layer:", "layer")
            if not name:
                return None
        at = self.doc.layer + 1 if self.layers() else None
        return self.doc.add_layer(self.doc.part, name, index=at)

    def add_from_file(self, path: str | None = None) -> int | None:
        path = path or self.ask_file("Picture of the new layer (the same in every drawing)")
        if not path:
            return None
        at = self.doc.layer + 1 if self.layers() else None
        return self.doc.add_layer(self.doc.part, ed.layer_order([path])[0][0], index=at, image_path=path,
                                  fit=self._fit([path]) or "resize")

    def remove(self) -> None:
        if self.layers():
            self.doc.remove_layer(self.doc.part, self.doc.layer)

    def duplicate(self) -> None:
        if self.layers():
            self.doc.duplicate_layer(self.doc.part, self.doc.layer)

    def rename(self, name: str | None = None) -> None:
        layers = self.layers()
        if not layers or not 0 <= self.doc.layer < len(layers):
            return
        old = layers[self.doc.layer].name
        if name is None:
            name = self.ask_text("Rename layer", f"New name for layer {old!r} (in every drawing):", old)
        if name and name != old:
            self.doc.rename_layer(self.doc.part, self.doc.layer, name)

    def step(self, direction: int) -> None:
        """Move the selected layer one place up (+1, in front) or down (−1)."""
        if self.layers():
            self.doc.move_layer(self.doc.part, self.doc.layer, self.doc.layer + direction)

    def move_row(self, src_row: int, dst_row: int) -> None:
        """Move the layer shown in row ``src_row`` to row ``dst_row`` (rows run top layer first)."""
        self._safely(lambda: self.doc.move_layer(self.doc.part, self.layer_of(src_row), self.layer_of(dst_row)))
        self.refill()

    def convert(self) -> None:
        p = self._part()
        if p is None or not p.drawings:
            return
        if ed.is_layered(p):
            self.doc.flatten_part(self.doc.part)
        else:
            self.doc.make_layered(self.doc.part)

    def _picture_menu(self) -> None:
        m = QMenu(self)
        m.addAction("In this drawing…", lambda: self._safely(lambda: self.set_picture(every=False)))
        m.addAction("In every drawing…", lambda: self._safely(lambda: self.set_picture(every=True)))
        m.exec(self.picture_button.mapToGlobal(self.picture_button.rect().bottomLeft()))

    def set_picture(self, path: str | None = None, every: bool = False) -> None:
        if not self.layers():
            return
        path = path or self.ask_file("Picture of the layer" + (" in every drawing" if every else " in this drawing"))
        if path:
            self.doc.set_layer_image(self.doc.part, self.doc.drawing, self.doc.layer, path, every_drawing=every,
                                     fit=self._fit([path]) or "resize")

    def _import_menu(self) -> None:
        m = QMenu(self)
        m.addAction("From a folder of images…", lambda: self._safely(self.import_folder))
        m.addAction("From image files…", lambda: self._safely(self.import_files))
        m.exec(self.import_button.mapToGlobal(self.import_button.rect().bottomLeft()))

    def _fit(self, paths) -> str | None:
        """Ask how to fit images of another size than the part's box (None: cancelled)."""
        p = self._part()
        if p is None or not p.drawings:
            return "resize"
        images = [(path, ed.load_image(path)) for path in paths]
        ed.check_layer_sizes(images)
        odd = [Path(path).name for path, img in images if (img.shape[1], img.shape[0]) != p.size]
        return self.ask_fit(self.doc.part, odd) if odd else "resize"

    def import_folder(self, folder: str | None = None) -> int | None:
        """A new drawing from a folder of layer images (the folder's name names the drawing)."""
        folder = folder or self.ask_folder(f"Folder with the layers of one {self.doc.part} drawing")
        if not folder:
            return None
        files = [p for _, p in ed.layer_files_in(folder)]
        fit = self._fit(files)
        if fit is None:
            return None
        i = self.doc.import_layered_folder(self.doc.part, folder, fit)
        self._report_import(i)
        return i

    def import_files(self, paths=None, name: str | None = None) -> int | None:
        """A new drawing from chosen layer images, ordered by their names (``10-eyeball.png`` first)."""
        paths = list(paths or self.ask_files(f"Layers of one {self.doc.part} drawing (bottom first by name)"))
        if not paths:
            return None
        if name is None:
            name = self.ask_text("Name of the drawing", "Name of the new drawing (its expression):",
                                 ed.name_from_path(Path(paths[0]).parent.name, self.doc.part))
            if not name:
                return None
        fit = self._fit(paths)
        if fit is None:
            return None
        i = self.doc.import_layered(self.doc.part, name, paths, fit)
        self._report_import(i)
        return i

    def _report_import(self, i: int) -> None:
        d = self._part().drawings[i]
        self.doc.message.emit(f"imported {self.doc.part} drawing {d.name!r}: layers {', '.join(ly.name for ly in d.layers)}"
                              " (bottom first)")

    def _ask_text_dialog(self, title: str, label: str, text: str) -> str | None:
        value, ok = QInputDialog.getText(self, title, label, text=text)
        return value.strip() if ok and value.strip() else None
