"""The editor's layers (format 2), driven through the real window's layers panel and preview (offscreen)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageDraw

pytest.importorskip("PySide6")
pytest.importorskip("pytestqt")

import app.editor  # noqa: E402,F401
from PySide6.QtCore import Qt  # noqa: E402

from art_sets import editing as ed  # noqa: E402
from art_sets.io import load_artset  # noqa: E402
from tests.test_editor_gui import _drag, _finished, images, make_window  # noqa: E402,F401  (fixtures)


def _layer_folder(folder: Path, size, k: int) -> Path:
    """A layered eyes drawing on disk: an eyeball (opaque, the bottom) and lids over it, numbered
    so that the file order is the stack order."""
    folder.mkdir(parents=True)
    w, h = size
    ball = Image.new("RGBA", size, (245, 205, 170, 255))
    dr = ImageDraw.Draw(ball)
    for cx in (w * 0.28, w * 0.72):
        dr.ellipse([cx - 14, h * 0.4, cx + 14, h * 0.75], fill=(255, 255, 255, 255))
        dr.ellipse([cx - 5, h * 0.5, cx + 5, h * 0.65], fill=(40, 30, 90, 255))
    ball.save(folder / "10-eyeball.png")
    lids = Image.new("RGBA", size, (0, 0, 0, 0))
    dr = ImageDraw.Draw(lids)
    for cx in (w * 0.28, w * 0.72):
        dr.rectangle([cx - 16, 0, cx + 16, h * 0.42 + 3 * k], fill=(245, 205, 170, 255))
        dr.line([cx - 16, h * 0.42 + 3 * k, cx + 16, h * 0.42 + 3 * k], fill=(0, 0, 0, 255), width=2)
    lids.save(folder / "20-lids.png")
    return folder


def _manifest(folder: Path) -> dict:
    return json.loads((folder / "artset.json").read_text(encoding="utf-8"))


def test_layers_panel_create_reorder_import_save_reload(make_window, images, tmp_path, qtbot):
    win = _finished(make_window(), "Layered", images)
    doc, panel = win.doc, win.layers_panel
    start = ed.clone(doc.artset)
    doc.select(part="eyes", drawing=0)
    assert panel.list.count() == 0 and panel.convert_button.text() == "Convert to layers"

    # a new layer on single pictures converts them to one layer each, then stacks the new one on top
    panel.add(name="shine")
    eyes = doc.artset.eyes
    assert [ly.name for ly in eyes.drawings[0].layers] == ["drawing", "shine"]
    assert all([ly.name for ly in d.layers] == ["drawing", "shine"] for d in eyes.drawings)
    assert panel.list.count() == 2 and panel.list.item(0).text().startswith("shine")  # top layer first
    assert doc.layer == 1
    np.testing.assert_array_equal(eyes.drawings[1].image, start.eyes.drawings[1].image)  # renders as before

    # reorder with the buttons (one undo step each), and as a drag of rows does
    qtbot.mouseClick(panel.down_button, Qt.LeftButton)
    assert [ly.name for ly in doc.artset.eyes.drawings[2].layers] == ["shine", "drawing"]
    assert doc.layer == 0 and panel.list.item(1).text().startswith("shine")
    qtbot.mouseClick(panel.up_button, Qt.LeftButton)
    assert [ly.name for ly in doc.artset.eyes.drawings[2].layers] == ["drawing", "shine"]
    from PySide6.QtCore import QModelIndex

    assert panel.list.model().moveRow(QModelIndex(), 0, QModelIndex(), 2)  # what dropping a dragged row does
    qtbot.waitUntil(lambda: [ly.name for ly in doc.artset.eyes.drawings[0].layers] == ["shine", "drawing"])
    assert panel.list.item(0).text().startswith("drawing")
    doc.undo_stack.undo()
    assert [ly.name for ly in doc.artset.eyes.drawings[0].layers] == ["drawing", "shine"]
    panel.rename(name="Glint")
    assert [ly.name for ly in doc.artset.eyes.drawings[1].layers] == ["drawing", "glint"]

    # import a drawing from a folder of PNGs: numbered files give the order, the folder the name
    folder = _layer_folder(tmp_path / "src" / "half", eyes.size, 1)
    i = panel.import_folder(str(folder))
    eyes = doc.artset.eyes
    assert eyes.drawings[i].name == "half" and doc.drawing == i
    names = [ly.name for ly in eyes.drawings[i].layers]
    assert names.index("eyeball") < names.index("lids")
    assert all([ly.name for ly in d.layers] == names for d in eyes.drawings)  # one stack for the part
    k = names.index("lids")
    np.testing.assert_array_equal(eyes.drawings[i].layers[k].image, ed.load_image(folder / "20-lids.png"))
    assert not eyes.drawings[0].layers[k].image[:, :, 3].any()  # transparent in the drawings without it
    for li in [None] + list(range(len(names))):
        doc.accept_lines("eyes", i, layer=li)

    # save, reload: identical; the manifest is format 2 with the layers in order
    out = tmp_path / "layered"
    edited = ed.clone(doc.artset)
    doc.save(out)
    data = _manifest(out)
    assert data["format"] == 2 and data["parts"]["mouth"]["drawings"][0].get("layers") is None
    saved = data["parts"]["eyes"]["drawings"][i]
    assert [ly["name"] for ly in saved["layers"]] == names
    back = load_artset(out)
    assert ed.same_artset(back, doc.artset)
    win2 = make_window()
    assert win2.open_path(out)
    assert ed.same_artset(win2.doc.artset, doc.artset)
    win2.doc.select(part="eyes", drawing=i)
    assert win2.layers_panel.list.count() == len(names)

    # every layer edit is undone, back to the character as it was before them
    while doc.undo_stack.canUndo() and not ed.same_artset(doc.artset, start):
        doc.undo_stack.undo()
    assert ed.same_artset(doc.artset, start)
    assert not doc.artset.eyes.drawings[0].layers
    while doc.undo_stack.canRedo():
        doc.undo_stack.redo()
    assert ed.same_artset(doc.artset, edited)  # (file names a save chose are not an edit)


def test_layer_edits_are_autosaved(make_window, images, tmp_path, qtbot):
    win = _finished(make_window(), "Auto", images)
    doc = win.doc
    out = tmp_path / "auto"
    doc.save(out)
    doc.select(part="mouth")
    win.layers_panel.add(name="teeth")
    doc.autosave_now(wait=True)
    side = out / ".artset.autosave"
    assert side.is_dir()
    rec = load_artset(side)
    assert [ly.name for ly in rec.mouth.drawings[0].layers] == ["drawing", "teeth"]


def test_format_1_set_saved_unchanged_stays_format_1(make_window, images, tmp_path):
    win = _finished(make_window(), "Plain", images)
    out = tmp_path / "plain"
    win.doc.save(out)
    first = (out / "artset.json").read_bytes()
    assert _manifest(out)["format"] == 1
    win2 = make_window()
    assert win2.open_path(out)
    win2.doc.select(part="eyes")
    win2.layers_panel.add(name="shine")  # layers tried, then undone: nothing layered remains
    win2.doc.undo_stack.undo()
    win2.doc.save(out)
    assert (out / "artset.json").read_bytes() == first
    assert sorted(p.name for p in out.rglob("*.png")) == sorted(p.name for p in out.rglob("*.png"))
    assert ed.same_artset(load_artset(out), win.doc.artset)


def test_import_refuses_layers_of_different_sizes_in_one_line(make_window, images, tmp_path):
    win = _finished(make_window(), "Sizes", images)
    doc, panel = win.doc, win.layers_panel
    folder = _layer_folder(tmp_path / "src" / "odd", doc.artset.eyes.size, 0)
    Image.new("RGBA", (33, 21), (0, 0, 0, 0)).save(folder / "30-brows.png")
    notes = []
    doc.message.connect(notes.append)
    doc.select(part="eyes")
    before, steps = ed.clone(doc.artset), doc.undo_stack.count()
    qt_import = panel.ask_folder
    panel.ask_folder = lambda title: str(folder)
    try:
        panel._safely(panel.import_folder)
    finally:
        panel.ask_folder = qt_import
    assert ed.same_artset(doc.artset, before) and doc.undo_stack.count() == steps
    assert len(notes) == 1 and "\n" not in notes[0]
    assert "30-brows.png is 33x21" in notes[0] and "same size" in notes[0]


def test_own_lines_per_layer_drawn_on_the_canvas(make_window, images, qtbot):
    win = _finished(make_window(), "Own", images)
    doc, panel = win.doc, win.layers_panel
    doc.select(part="mouth", drawing=0)
    panel.add(name="lip")
    n_shared = len(doc.artset.mouth.drawings[0].lines)
    panel.own_lines.setChecked(True)
    ly = doc.artset.mouth.drawings[0].layers[doc.layer]
    assert ly.lines is not None and len(ly.lines) == n_shared
    win.tabs.setCurrentIndex(0)
    canvas = win.line_canvas
    qtbot.waitUntil(lambda: canvas.width() > 300)
    _drag(qtbot, canvas, [(10, 30), (40, 32), (70, 34)])
    mouth = doc.artset.mouth
    assert len(mouth.drawings[0].layers[doc.layer].lines) == n_shared + 1  # the layer's own set grew
    assert len(mouth.drawings[0].lines) == n_shared  # the drawing's lines did not
    assert all(len(d.layers[doc.layer].lines) == n_shared + 1 for d in mouth.drawings)  # copies, to place
    assert ed.unplaced(doc.artset, "mouth", 1, doc.layer) == {n_shared}
    panel.own_lines.setChecked(False)  # back to the drawing's lines: the own set is dropped
    assert doc.artset.mouth.drawings[0].layers[doc.layer].lines is None


def test_preview_slider_renders_the_layered_blend(make_window, images, tmp_path, qtbot):
    from morph.layers import LayeredMorpher

    win = _finished(make_window(), "Blend", images)
    doc, panel, prev = win.doc, win.layers_panel, win.preview
    doc.select(part="eyes", drawing=0)
    panel.add(name="shine")
    prev.wait_for_morph = True
    prev.tabs.setCurrentIndex(0)
    prev.combo_a.setCurrentIndex(0)
    prev.combo_b.setCurrentIndex(2)
    prev.slider.setValue(30)
    prev.refresh()
    eyes = doc.artset.eyes
    want = LayeredMorpher([eyes.drawings[0], eyes.drawings[2]]).render([0, 1], [0.7, 0.3])
    got = prev.morph_view._img
    assert got is not None and (got.width(), got.height()) == eyes.size
    from PySide6.QtGui import QImage

    q = got.convertToFormat(QImage.Format_RGBA8888_Premultiplied)
    shown = np.frombuffer(q.constBits(), np.uint8).reshape(q.height(), q.bytesPerLine())[:, :q.width() * 4]
    np.testing.assert_array_equal(shown.reshape(q.height(), q.width(), 4), want)
    assert prev.engine.note == ""
    # beside it the plain cross-dissolve of the same two drawings (from the morpher's pictures)
    d = prev.dissolve_view._img.convertToFormat(QImage.Format_RGBA8888)
    dis = np.frombuffer(d.constBits(), np.uint8).reshape(d.height(), d.bytesPerLine())[:, :d.width() * 4]
    ref = ed.cross_dissolve([eyes.drawings[0].image, eyes.drawings[2].image], [0.7, 0.3])
    assert np.abs(dis.reshape(ref.shape).astype(int) - ref).max() <= 3
