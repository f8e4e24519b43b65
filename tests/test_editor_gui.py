"""The art-set editor window, driven through the same actions and canvases its UI uses (offscreen)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageDraw

pytest.importorskip("PySide6")
pytest.importorskip("pytestqt")

import app.editor  # noqa: E402,F401  (applies the PySide6 None/True/False reference workaround for this process)
from PySide6.QtCore import QPoint, Qt  # noqa: E402
from PySide6.QtTest import QTest  # noqa: E402

from art_sets import editing as ed  # noqa: E402
from art_sets.io import load_artset  # noqa: E402
from art_sets.validate import validate  # noqa: E402


# ----------------------------------------------------------------------------- generated images


def _head(path: Path, size=(240, 280), tint=0) -> Path:
    im = Image.new("RGBA", size, (0, 0, 0, 0))
    dr = ImageDraw.Draw(im)
    dr.ellipse([12, 8, size[0] - 12, size[1] - 8], fill=(245, 205 - tint, 170, 255), outline=(30, 20, 20, 255), width=5)
    dr.arc([40, 20, size[0] - 40, 120], 200, 340, fill=(60, 40, 20, 255), width=8)
    im.save(path)
    return path


def _eyes(path: Path, k: int, size=(120, 48)) -> Path:
    w, h = size
    im = Image.new("RGBA", size, (245, 205, 170, 255))
    dr = ImageDraw.Draw(im)
    for cx in (w * 0.28, w * 0.72):
        dr.ellipse([cx - 14, h * 0.55 - 3 - 4 * k, cx + 14, h * 0.55 + 3 + 4 * k], fill=(255, 255, 255, 255), outline=(0, 0, 0, 255), width=2)
        dr.line([cx - 16, h * 0.2 - 2 * k, cx + 16, h * 0.2 - 2 * k + (4 if k == 2 else 0)], fill=(40, 20, 10, 255), width=3)
    im.save(path)
    return path


def _mouth(path: Path, k: int, size=(90, 44)) -> Path:
    w, h = size
    im = Image.new("RGBA", size, (245, 205, 170, 255))
    dr = ImageDraw.Draw(im)
    dr.chord([w * 0.15, h * 0.2, w * 0.85, h * (0.45 + 0.15 * k)], 0, 180, fill=(120, 20, 30, 255), outline=(0, 0, 0, 255), width=2)
    im.save(path)
    return path


@pytest.fixture
def images(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    heads = [_head(src / "head_a.png"), _head(src / "head_b.png", tint=12)]
    eyes = [_eyes(src / f"{n}.png", k) for k, n in enumerate(["open", "closed", "wide"])]
    mouths = [_mouth(src / f"{n}.png", k) for k, n in enumerate(["neutral", "smile", "ah"])]
    return heads, eyes, mouths


@pytest.fixture
def make_window(qtbot, tmp_path, monkeypatch):
    monkeypatch.setenv("INKFACE_DATA", str(tmp_path / "userdata"))
    monkeypatch.setenv("INKFACE_SETTINGS", str(tmp_path / "settings.ini"))
    monkeypatch.setenv("INKFACE_ART_DIR", str(tmp_path / "user_art"))
    monkeypatch.setenv("INKFACE_CACHE", str(tmp_path / "cache"))
    from app.editor.window import EditorWindow

    from PySide6.QtWidgets import QApplication

    qapp = QApplication.instance()
    look = qapp.style().name(), qapp.styleSheet(), qapp.palette()

    def make():
        win = EditorWindow(autosave_delay_ms=30)
        win.confirm_close = lambda: "discard"
        win.ask_recover = lambda path, side: False
        win.ask_fit = lambda key, names: "resize"
        qtbot.addWidget(win)
        win.show()
        qtbot.waitExposed(win)
        return win

    yield make
    qapp.setStyleSheet(look[1])  # the editor gives the application its dark theme: not to later tests
    qapp.setPalette(look[2])
    qapp.setStyle(look[0])


def _drag(qtbot, widget, pts_image, buttons=Qt.LeftButton):
    """Press at the first image point, move through the rest, release at the last."""
    wpts = [widget.to_widget(x, y).toPoint() for x, y in pts_image]
    QTest.mousePress(widget, buttons, Qt.NoModifier, wpts[0])
    for p in wpts[1:]:
        QTest.mouseMove(widget, p)
    QTest.mouseRelease(widget, buttons, Qt.NoModifier, wpts[-1])


def _lines_everywhere(doc, part):
    """Give a part three lines and place them in every drawing (what an artist would do)."""
    w, h = doc.artset.parts[part].size
    base = [[0.2 * w, 0.3 * h, 0.45 * w, 0.3 * h], [0.55 * w, 0.3 * h, 0.8 * w, 0.3 * h], [0.3 * w, 0.7 * h, 0.7 * w, 0.7 * h]]
    first = [doc.add_line(part, 0, ln) for ln in base]
    for di in range(1, len(doc.artset.parts[part].drawings)):
        for i, ln in zip(first, base):
            doc.move_line(part, di, i, np.add(ln, [0, di, 0, di]))


def _finished(win, name, images, holes=5):
    """``win`` with a new character from ``images``: lines in every drawing, holes cut (valid)."""
    heads, eyes, mouths = images
    win.new_character(name, heads, eyes, mouths)
    _lines_everywhere(win.doc, "eyes")
    _lines_everywhere(win.doc, "mouth")
    win.doc.make_holes(holes)
    return win


# ----------------------------------------------------------------------------- tests


def test_build_character_draw_save_reload_validate(make_window, images, tmp_path, qtbot):
    heads, eyes, mouths = images
    win = make_window()
    doc = win.doc
    win.new_character("Blob", heads, eyes, mouths, author="tests")
    art = doc.artset
    assert [d.name for d in art.eyes.drawings] == ["open", "closed", "wide"]
    assert len(art.heads) == 2 and art.canvas == (240, 280)

    # draw the first mouth line with the mouse on the lines canvas, then move one end
    win.tabs.setCurrentIndex(0)
    doc.select(part="mouth", drawing=0)
    canvas = win.line_canvas
    qtbot.waitUntil(lambda: canvas.width() > 300)
    _drag(qtbot, canvas, [(10, 10), (30, 12), (60, 14)])
    assert ed.line_count(doc.artset.mouth) == 1
    np.testing.assert_allclose(doc.artset.mouth.drawings[0].lines[0], [10, 10, 60, 14], atol=0.6 / canvas.scale() + 0.5)
    assert doc.line == 0
    assert ed.missing_lines(doc.artset, "mouth")[0] == ["smile", "ah"]
    doc.select(drawing=1)
    _drag(qtbot, canvas, [(60, 14), (70, 30)])  # grab the end of the copied line in "smile"
    ln = doc.artset.mouth.drawings[1].lines[0]
    assert abs(ln[2] - 70) < 1 and abs(ln[3] - 30) < 1 and abs(ln[0] - 10) < 1
    assert "smile" not in ed.missing_lines(doc.artset, "mouth")[0]
    doc.select(drawing=2)
    doc.accept_lines("mouth", 2)
    _lines_everywhere(doc, "eyes")
    _lines_everywhere(doc, "mouth")
    # the problems panel lists nothing left to place
    assert not [i for i in doc.issues if "not placed" in i.message]

    win.radius_spin.setValue(6)
    win.cut_holes()
    x, y, w, h = doc.artset.mouth.box
    assert doc.artset.heads[0][y + h // 2, x + w // 2, 3] == 0

    folder = tmp_path / "blob"
    doc.save(folder)
    assert validate(folder) == []
    back = load_artset(folder)
    assert ed.same_artset(back, doc.artset)
    try:  # the renderer takes what the editor made
        from morph.renderer import CharacterRenderer
    except ImportError:
        CharacterRenderer = None
    if CharacterRenderer is not None:
        frame = CharacterRenderer(back).render(eyes=([0, 1, 2], [0.2, 0.3, 0.5]), mouth=([0, 1, 2], [0.5, 0.5, 0.0]))
        assert frame.shape == (280, 240, 4) and frame[:, :, 3].max() == 255
    assert not doc.dirty and not (folder / ".artset.autosave").exists()
    win.problems.refill()
    assert "no problems" in win.problems.item(0).text()
    # advice (not errors) still shows: e.g. the drawing names default training pairs by
    advice = [i for i in doc.issues if i.severity == "advice"]
    assert any(i.message.startswith("mouth: no drawing named oo, grin, frown") and i.part == "mouth" for i in advice)


def test_undo_redo_restore_exactly(make_window, images, qtbot):
    heads, eyes, mouths = images
    win = make_window()
    doc = win.doc
    win.new_character("Undo", heads, eyes, mouths)
    states = [ed.clone(doc.artset)]
    steps = [
        lambda: doc.add_line("eyes", 0, [5, 5, 50, 9]),
        lambda: doc.add_line("eyes", 1, [60, 5, 100, 20]),
        lambda: doc.move_line("eyes", 2, 0, [6, 7, 48, 12]),
        lambda: doc.copy_lines("eyes", 0, 2),
        lambda: doc.set_box("mouth", (70, 170, 110, 50)),
        lambda: doc.make_holes(5.0),
        lambda: doc.paint(0, [(120, 60), (140, 70)], 9, erase=True),
        lambda: doc.rename_drawing("mouth", 1, "Grin"),
        lambda: doc.delete_line("eyes", 0),
        lambda: doc.set_pivot((100, 200)),
        lambda: doc.remove_head(1),
    ]
    for step in steps:
        step()
        states.append(ed.clone(doc.artset))
    assert doc.artset.mouth.names()[1] == "grin" and len(doc.artset.heads) == 1
    for k in range(len(steps), 0, -1):
        assert ed.same_artset(doc.artset, states[k])
        doc.undo_stack.undo()
    assert ed.same_artset(doc.artset, states[0])
    for k in range(1, len(steps) + 1):
        doc.undo_stack.redo()
        assert ed.same_artset(doc.artset, states[k])


def test_crash_mid_save_leaves_previous_set_intact(make_window, images, tmp_path, monkeypatch):
    heads, eyes, mouths = images
    win = make_window()
    doc = win.doc
    win.new_character("Crash", heads, eyes, mouths)
    _lines_everywhere(doc, "eyes")
    _lines_everywhere(doc, "mouth")
    doc.make_holes(6)
    folder = tmp_path / "crash"
    doc.save(folder)
    old_json = (folder / "artset.json").read_bytes()
    old = load_artset(folder)
    # edits that change pixels of files the old manifest names
    doc.replace_image("mouth", 1, _mouth(tmp_path / "src" / "other.png", 2, size=(100, 50)))
    doc.paint(None, [(100, 40), (140, 40)], 12, erase=True)
    doc.move_line("eyes", 1, 0, [3, 3, 40, 20])

    real_replace = os.replace
    calls = {"n": 0}

    def dying_replace(src, dst):
        calls["n"] += 1
        if calls["n"] == 4:
            raise OSError("simulated crash while saving")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", dying_replace)
    with pytest.raises(OSError):
        doc.save(folder)
    monkeypatch.setattr(os, "replace", real_replace)
    assert calls["n"] == 4
    assert (folder / "artset.json").read_bytes() == old_json
    assert validate(folder) == []
    assert ed.same_artset(load_artset(folder), old)
    assert doc.dirty
    doc.save(folder)  # and a later save succeeds
    assert validate(folder) == []
    assert ed.same_artset(load_artset(folder), doc.artset)


def test_autosave_appears_and_is_offered_back(make_window, images, tmp_path, qtbot):
    win = _finished(make_window(), "Auto", images, holes=6)
    folder = tmp_path / "auto"
    win.doc.save(folder)
    side = folder / ".artset.autosave" / "artset.json"
    assert not side.exists()
    win.doc.move_line("mouth", 2, 1, [30, 20, 60, 30])
    qtbot.waitUntil(side.exists, timeout=10000)
    win.doc.wait_autosave()
    edited = ed.clone(win.doc.artset)
    # a new window opening the folder is offered the newer side copy
    asked = []
    win2 = make_window()
    win2.ask_recover = lambda path, s: asked.append(path) or True
    assert win2.open_path(folder)
    assert asked == [folder]
    np.testing.assert_array_equal(win2.doc.artset.mouth.drawings[2].lines, edited.mouth.drawings[2].lines)
    assert win2.doc.dirty
    # declining the offer opens the saved set and drops the side copy
    win3 = make_window()
    win3.ask_recover = lambda path, s: False
    assert win3.open_path(folder)
    assert not win3.doc.dirty and not side.exists()
    assert not np.array_equal(win3.doc.artset.mouth.drawings[2].lines, edited.mouth.drawings[2].lines)


def test_other_sizes_offered_resize_or_crop(make_window, images, tmp_path):
    heads, eyes, mouths = images
    win = make_window()
    win.new_character("Sizes", heads, eyes, mouths)
    big = _mouth(tmp_path / "src" / "grin.png", 2, size=(180, 70))
    same = _mouth(tmp_path / "src" / "frown.png", 0)
    asked = []
    win.ask_fit = lambda key, names: asked.append((key, names)) or None
    win.add_files("mouth", [big])
    assert asked == [("mouth", ["grin.png"])] and "grin" not in win.doc.artset.mouth.names()
    win.ask_fit = lambda key, names: "crop"
    win.add_files("mouth", [big, same])
    m = win.doc.artset.mouth
    assert m.names()[-2:] == ["grin", "frown"]
    assert all(d.size == m.size for d in m.drawings)
    # a cropped drawing keeps its centre pixels unscaled
    src = np.asarray(Image.open(big).convert("RGBA"))
    w, h = m.size
    np.testing.assert_array_equal(m.drawings[-2].image[h // 2], src[35 - h // 2 + h // 2, 90 - w // 2:90 - w // 2 + w])
    win.add_files("heads", [_head(tmp_path / "src" / "head_c.png", size=(300, 350))])
    assert len(win.doc.artset.heads) == 3 and win.doc.artset.heads[2].shape[:2] == (280, 240)


def test_head_canvas_drags_boxes_and_paints_holes(make_window, images, qtbot):
    heads, eyes, mouths = images
    win = make_window()
    doc = win.doc
    win.new_character("Head", heads, eyes, mouths)
    win.tabs.setCurrentIndex(1)
    hc = win.head_canvas
    qtbot.waitUntil(lambda: hc.width() > 300)
    x, y, w, h = doc.artset.mouth.box
    _drag(qtbot, hc, [(x + w / 2, y + h / 2), (x + w / 2 + 10, y + h / 2 + 5), (x + w / 2 + 20, y + h / 2 + 10)])
    nx, ny, nw, nh = doc.artset.mouth.box
    assert (nw, nh) == (w, h) and abs(nx - (x + 20)) <= 2 and abs(ny - (y + 10)) <= 2
    assert doc.part == "mouth"
    # resize from the bottom-right corner: the drawings follow the box
    _drag(qtbot, hc, [(nx + nw, ny + nh), (nx + nw + 20, ny + nh + 8)])
    assert doc.artset.mouth.size[0] > nw and all(d.size == doc.artset.mouth.size for d in doc.artset.mouth.drawings)
    doc.undo_stack.undo()
    assert doc.artset.mouth.box == (nx, ny, nw, nh)
    # the tilt pivot is a cross you drag
    px, py = doc.artset.pivot
    _drag(qtbot, hc, [(px, py), (px + 10, py + 30)])
    assert abs(doc.artset.pivot[0] - (px + 10)) < 1.5 and abs(doc.artset.pivot[1] - (py + 30)) < 1.5
    # paint a hole in every head
    win.mode_paint.setChecked(True)
    win.brush_spin.setValue(8)
    before = [hd[:, :, 3].copy() for hd in doc.artset.heads]
    _drag(qtbot, hc, [(100, 150), (130, 150)])
    for hd, b in zip(doc.artset.heads, before):
        assert hd[150, 115, 3] < b[150, 115] // 4
        assert hd[30, 120, 3] == b[30, 120]
    _drag(qtbot, hc, [(100, 150), (130, 150)], buttons=Qt.RightButton)  # and close it again
    assert doc.artset.heads[0][150, 115, 3] > 200


def test_problems_panel_and_line_selection(make_window, images, qtbot):
    heads, eyes, mouths = images
    win = make_window()
    doc = win.doc
    win.new_character("Probs", heads, eyes[:2], mouths)
    doc.add_line("mouth", 0, [5, 5, 40, 9])
    doc.add_line("mouth", 0, [5, 20, 40, 25])
    qtbot.waitUntil(lambda: any(i.severity == "error" for i in doc.issues), timeout=10000)
    texts = [win.problems.item(k).text() for k in range(win.problems.count())]
    assert any("at least 3" in t and "eyes" in t for t in texts)  # the validator's problem
    todo = [k for k, i in enumerate(doc.issues) if i.part == "mouth" and "lines 0, 1 not placed yet in 'ah'" in i.message]
    assert todo
    row = next(r for r in range(win.problems.count()) if win.problems.item(r).data(Qt.UserRole) == todo[0])
    doc.select(part="eyes")
    win.problems.itemClicked.emit(win.problems.item(row))
    assert (doc.part, doc.drawing, doc.line) == ("mouth", 2, 0)
    assert doc.artset.mouth.drawings[doc.drawing].name == "ah"
    # the lines list shows where each line is missing and selects it everywhere
    assert "to place in smile, ah" in win.lines_list.item(0).text()
    win.lines_list.setCurrentRow(0)
    assert doc.line == 0
    # Delete removes the selected line from every drawing
    win.line_canvas.setFocus()
    QTest.keyClick(win.line_canvas, Qt.Key_Delete)
    assert {len(d.lines) for d in doc.artset.mouth.drawings} == {1}


def test_preview_slider_triangle_and_fallback(make_window, images, qtbot, monkeypatch):
    heads, eyes, mouths = images
    win = make_window()
    doc = win.doc
    win.new_character("Prev", heads, eyes, mouths)
    _lines_everywhere(doc, "mouth")
    pv = win.preview
    pv.tabs.setCurrentIndex(0)
    pv.refresh()  # tables are built on a worker thread; the panel polls until they are ready
    qtbot.waitUntil(lambda: pv.morph_view.caption == "morph" and pv.morph_view._img is not None, timeout=20000)
    pv.wait_for_morph = True
    pv.combo_a.setCurrentIndex(0)
    pv.combo_b.setCurrentIndex(2)
    pv.slider.setValue(0)
    pv.refresh()
    part = doc.artset.mouth
    img, pm = pv.engine.render(part, [0, 2], [1.0, 0.0])
    if pm:  # a weight-1 morph is the drawing itself (premultiplied)
        a = part.drawings[0].image.astype(np.float32)
        np.testing.assert_allclose(img[:, :, 3], a[:, :, 3], atol=1)
    assert pv.current_blend() == ([0, 2], [1.0, 0.0])
    pv.slider.setValue(50)
    assert pv.current_blend()[1] == [0.5, 0.5]
    pv.tabs.setCurrentIndex(1)
    pv.triangle.set_weights([0.2, 0.3, 0.5])
    idx, w = pv.current_blend()
    assert idx == [0, 1, 2]
    np.testing.assert_allclose(w, [0.2, 0.3, 0.5], atol=0.02)
    pv.refresh()
    assert pv.morph_view._img is not None
    # without the morph engine the preview still works and says so
    from app.editor import preview as pvmod

    eng = pvmod.MorphEngine()
    eng._PartMorpher = eng._exact = None
    out, premult = eng.render(part, [0, 1], [0.5, 0.5])
    assert not premult and out.shape == part.drawings[0].image.shape
    assert pvmod.MorphEngine().note == "" or "not available" in pvmod.MorphEngine().note


def test_edit_command_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("INKFACE_DATA", str(tmp_path / "userdata"))
    monkeypatch.setenv("INKFACE_SETTINGS", str(tmp_path / "settings.ini"))
    from app import editor_cmd

    ns = argparse.Namespace(dir=str(tmp_path / "nope"), screenshot=None, command="edit")
    assert editor_cmd.run(ns) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("inkface:") and "\n" not in err
    (tmp_path / "empty").mkdir()
    ns.dir = str(tmp_path / "empty")
    assert editor_cmd.run(ns) == 2
    assert "artset.json" in capsys.readouterr().err
    ns.dir = None  # offscreen: no screen to show a window on, so say so instead of hanging
    assert editor_cmd.run(ns) == 2
    assert "screen" in capsys.readouterr().err
    ns.screenshot = str(tmp_path / "shot.png")
    assert editor_cmd.run(ns) == 0
    assert Image.open(ns.screenshot).size[0] > 600


def test_open_editor_on_bundled_character(qtbot, tmp_path, monkeypatch):
    monkeypatch.setenv("INKFACE_DATA", str(tmp_path / "userdata"))
    monkeypatch.setenv("INKFACE_SETTINGS", str(tmp_path / "settings.ini"))
    try:
        from art_sets.library import list_bundled

        bundled = list_bundled()
    except Exception:
        bundled = []
    if not bundled:
        pytest.skip("no bundled characters yet")
    from app.editor import open_editor

    win = open_editor(bundled[0][1])
    qtbot.addWidget(win)
    win.confirm_close = lambda: "discard"
    assert win.doc.artset is not None and win.doc.artset.name
    assert len([i for i in win.doc.issues if i.severity == "error"]) == len(validate(bundled[0][1]))
    assert not win.doc.dirty


def test_recutting_holes_after_moving_a_box_moves_the_hole(make_window, images):
    heads, eyes, mouths = images
    win = make_window()
    doc = win.doc
    win.new_character("Move", heads, eyes, mouths)
    doc.make_holes(5)
    x, y, w, h = doc.artset.mouth.box
    assert doc.artset.heads[0][y + h // 2, x + w // 2, 3] == 0
    # changing the feather radius right after a cut re-cuts instead of stacking holes
    n = doc.undo_stack.count()
    win.radius_spin.setValue(5)  # replaces the cut just made (same radius): no new undo step
    assert doc.undo_stack.count() == n
    win.cut_holes()
    soft = doc.artset.heads[0][y + 4, x + w // 2, 3]
    win.radius_spin.setValue(15)
    assert doc.undo_stack.count() == n + 1
    assert doc.artset.heads[0][y + 4, x + w // 2, 3] > soft
    doc.set_box("mouth", (x, y + 40, w, h))
    doc.make_holes(5)
    assert doc.artset.heads[0][y + 5, x + w // 2, 3] == 255  # the old hole is closed again
    assert doc.artset.heads[0][y + 40 + h // 2, x + w // 2, 3] == 0


def test_unsaved_new_character_is_autosaved_and_recovered(make_window, images, qtbot, tmp_path):
    heads, eyes, mouths = images
    win = make_window()
    win.new_character("Fresh", heads, eyes, mouths)
    win.doc.add_line("mouth", 0, [5, 5, 40, 20])
    side = tmp_path / "userdata" / "editor-autosave" / "untitled" / "artset.json"
    qtbot.waitUntil(side.exists, timeout=10000)
    win.doc.wait_autosave()
    win2 = make_window()
    win2.ask_recover = lambda what, s: True
    assert win2.offer_untitled_recovery()
    assert win2.doc.artset.name == "Fresh" and win2.doc.path is None
    np.testing.assert_array_equal(win2.doc.artset.mouth.drawings[0].lines, [[5, 5, 40, 20]])


def test_window_save_runs_behind_busy_dialog(make_window, images, tmp_path, monkeypatch):
    win = _finished(make_window(), "Busy", images)
    asked = []
    win.ask_save_folder = lambda start, suggested: asked.append((start, suggested)) or tmp_path / "busy"
    assert win.save()  # no folder yet: asks for one (Save as)
    assert asked == [(tmp_path / "user_art", "busy")]  # starts in the user's characters, suggests a name
    assert validate(tmp_path / "busy") == [] and not win.doc.dirty
    assert "busy" in win.windowTitle() and not win.isWindowModified()
    from app.settings import Settings

    assert str((tmp_path / "busy").resolve()) in Settings().user_art_dirs()
    # picking the user art folder itself saves into a sub-folder named after the character,
    # where the performance window's character strip finds it
    from art_sets.library import list_user

    win.ask_save_folder = lambda start, suggested: tmp_path / "user_art"
    assert win.save_as()
    assert win.doc.path == tmp_path / "user_art" / "busy-copy"
    # saved again elsewhere: the copy must not share the name of the one in tmp_path / "busy"
    assert [n for n, _ in list_user()] == ["Busy (copy)"]


def test_drop_image_files_on_a_part_list(make_window, images, tmp_path, qtbot):
    from PySide6.QtCore import QMimeData, QPointF, QUrl
    from PySide6.QtGui import QDropEvent

    heads, eyes, mouths = images
    win = make_window()
    win.new_character("Drop", heads, eyes, mouths)
    extra = [_eyes(tmp_path / "src" / "angry.png", 1), tmp_path / "src" / "notes.txt"]
    extra[1].write_text("not an image")
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(p)) for p in extra])
    lst = win.lists["eyes"]
    ev = QDropEvent(QPointF(10, 10), Qt.CopyAction, mime, Qt.LeftButton, Qt.NoModifier)
    lst.dropEvent(ev)
    assert win.doc.artset.eyes.names() == ["open", "closed", "wide", "angry"]
    assert (win.doc.part, win.doc.drawing) == ("eyes", 3)
    assert lst.count() == 4 and "to place" not in lst.item(3).text()


def test_open_editor_with_parent_is_its_own_window(qtbot, tmp_path, monkeypatch):
    monkeypatch.setenv("INKFACE_DATA", str(tmp_path / "userdata"))
    monkeypatch.setenv("INKFACE_SETTINGS", str(tmp_path / "settings.ini"))
    from PySide6.QtWidgets import QWidget

    from app.editor import open_editor

    parent = QWidget()
    qtbot.addWidget(parent)
    win = open_editor(None, parent)
    win.confirm_close = lambda: "discard"
    assert win.isWindow() and win.isVisible() and win.doc.artset is None
    win.close()


def test_live_mode_runs_or_says_why_not(make_window, images, qtbot):
    win = _finished(make_window(), "Live", images)
    pv = win.preview
    pv.tabs.setCurrentIndex(2)
    pv.live_button.setChecked(True)
    assert pv.live is not None and pv.live_status.text().startswith("starting")
    # frames arrive from a worker thread, or it stops with a one-line reason (core missing)
    qtbot.waitUntil(lambda: pv.morph_view.caption == "live" or pv.live is None, timeout=50000)
    if pv.live is None:
        assert not pv.live_button.isChecked()
        assert pv.live_status.text().startswith("live preview stopped:") and "\n" not in pv.live_status.text()
        return
    assert pv.morph_view._img is not None and pv.morph_view._img.width() == 240
    win.doc.move_line("mouth", 1, 0, [10, 12, 40, 13])  # edits keep the GUI live; the puppet follows later
    pv.live_button.setChecked(False)
    assert pv.live is None and not pv.live_button.isChecked()

def test_opening_a_set_with_wrong_sizes_offers_to_fit(make_window, images, tmp_path):
    win = _finished(make_window(), "Odd", images)
    folder = tmp_path / "odd"
    win.doc.save(folder)
    # an artist replaces a drawing and a head with bigger scans outside the editor
    _mouth(folder / win.doc.artset.mouth.drawings[1].file, 1, size=(180, 88))
    Image.fromarray(np.zeros((300, 260, 4), np.uint8)).save(folder / win.doc.artset.head_files[1])
    assert any("box is" in p.message for p in validate(folder))
    win2 = make_window()
    asked = []
    win2.ask_fit = lambda key, names: asked.append((key, names)) or "resize"
    assert win2.open_path(folder)
    assert asked == [("heads", [win.doc.artset.head_files[1]]), ("mouth", ["smile"])]
    art = win2.doc.artset
    assert not ed.head_mismatches(art) and not ed.size_mismatches(art.mouth)
    win2.doc.undo_stack.undo()  # the fit is an undoable edit
    assert ed.size_mismatches(win2.doc.artset.mouth) == [1]
    assert any("resize or crop" in i.message for i in win2.doc.issues)


def test_zoom_about_the_cursor_then_draw(make_window, images, qtbot):
    from PySide6.QtCore import QPointF
    from PySide6.QtGui import QWheelEvent

    heads, eyes, mouths = images
    win = make_window()
    win.new_character("Zoom", heads, eyes, mouths)
    win.tabs.setCurrentIndex(0)
    c = win.line_canvas
    qtbot.waitUntil(lambda: c.width() > 300)
    anchor = c.to_widget(30, 20)
    ev = QWheelEvent(anchor, c.mapToGlobal(anchor), QPoint(0, 0), QPoint(0, 240), Qt.NoButton, Qt.NoModifier,
                     Qt.NoScrollPhase, False)
    fit = c.scale()
    c.wheelEvent(ev)
    assert c.scale() == pytest.approx(fit * 1.5625)
    x, y = c.to_image(anchor)
    assert abs(x - 30) < 0.01 and abs(y - 20) < 0.01
    _drag(qtbot, c, [(28, 18), (34, 22)])
    np.testing.assert_allclose(win.doc.artset.mouth.drawings[0].lines[0], [28, 18, 34, 22], atol=0.2)
    c.setFocus()
    QTest.keyClick(c, Qt.Key_0)
    assert c.scale() == pytest.approx(fit)


def test_starter_lines_button(make_window, images):
    heads, eyes, mouths = images
    win = make_window()
    win.new_character("Start", heads, eyes, mouths)
    win.doc.select(part="mouth")
    win.starter_button.click()
    assert {len(d.lines) for d in win.doc.artset.mouth.drawings} == {4}
    assert not any(win.doc.artset.eyes.drawings[0].lines.shape[0] for _ in [0])
    win.doc.undo_stack.undo()
    assert {len(d.lines) for d in win.doc.artset.mouth.drawings} == {0}


def test_every_menu_action_is_safe_with_or_without_a_character(make_window, monkeypatch, images):
    from PySide6.QtWidgets import QDialog, QFileDialog, QMenu

    win = make_window()
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", lambda *a, **k: "")
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: ([], ""))
    monkeypatch.setattr(QDialog, "exec", lambda self: 0)
    from PySide6.QtWidgets import QMessageBox

    monkeypatch.setattr(QMessageBox, "information", lambda *a, **k: 0)
    skip = {"&Close"}

    def trigger_all():
        for menu in win.menuBar().findChildren(QMenu):
            for act in menu.actions():
                if act.menu() is None and not act.isSeparator() and act.text() not in skip and act.isEnabled():
                    act.trigger()

    trigger_all()
    assert win.doc.artset is None
    heads, eyes, mouths = images
    win.new_character("Menus", heads, eyes, mouths)
    trigger_all()
    assert win.doc.artset is not None


def test_new_character_dialog_fills_from_a_folder(make_window, tmp_path, qtbot):
    from app.editor.window import NewCharacterDialog

    folder = tmp_path / "my_monster"
    (folder / "mouths").mkdir(parents=True)
    _head(folder / "head.png")
    for k, n in enumerate(["open", "closed", "wide"]):
        _eyes(folder / f"eyes_{n}.png", k)
    for k, n in enumerate(["neutral", "smile", "ah"]):
        _mouth(folder / "mouths" / f"mouth-{n}.png", k)
    dlg = NewCharacterDialog()
    qtbot.addWidget(dlg)
    dlg.fill_from_folder(folder)
    assert dlg.name.text() == "My Monster"
    assert [len(dlg.paths[k]) for k in ("heads", "eyes", "mouth")] == [1, 3, 3]
    win = make_window()
    win.new_character(dlg.name.text(), dlg.paths["heads"], dlg.paths["eyes"], dlg.paths["mouth"])
    assert win.doc.artset.eyes.names() == ["closed", "open", "wide"]
    assert win.doc.artset.mouth.names() == ["ah", "neutral", "smile"]


def test_none_survives_many_void_qt_calls():
    """PySide6 6.12 on CPython 3.11 takes a reference from None on every void call; the editor's
    workaround must keep the process alive (without it this test aborts the interpreter)."""
    import sys

    import app.editor
    from PySide6.QtCore import QObject, Signal
    from PySide6.QtGui import QColor

    class Emitter(QObject):
        flag = Signal(bool)

    c, e = QColor(), Emitter()
    e.flag.connect(lambda v: None)
    for _ in range(50000):
        c.setRed(0)
        e.flag.emit(True)
        e.flag.emit(False)
    assert min(sys.getrefcount(x) for x in (None, True, False)) > 1000
    assert isinstance(app.editor.NONE_WORKAROUND, bool)


def test_edits_of_a_bundled_character_never_touch_its_folder(make_window, tmp_path, qtbot):
    from art_sets.library import list_bundled

    bundled = list_bundled()
    if not bundled:
        pytest.skip("no bundled characters yet")
    folder = bundled[0][1]
    before = sorted(p.relative_to(folder) for p in folder.rglob("*"))
    win = make_window()
    assert win.open_path(folder)
    win.doc.move_line("mouth", 0, 0, [3, 3, 30, 8])
    side = tmp_path / "userdata" / "editor-autosave" / f"bundled-{folder.name}" / "artset.json"
    qtbot.waitUntil(side.exists, timeout=15000)
    win.doc.wait_autosave()
    assert sorted(p.relative_to(folder) for p in folder.rglob("*")) == before


# ----------------------------------------------------------------------------- issue 14: save-as, names, theme, strip


def _answer_modal(qtbot, act, timeout_ms=20_000):
    """Run ``act(widget)`` on the next modal dialog as soon as it is up (from the event loop)."""
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    seen = []

    def poll():
        w = QApplication.activeModalWidget()
        if w is None or w in seen:
            QTimer.singleShot(20, poll)
            return
        seen.append(w)
        act(w)

    QTimer.singleShot(0, poll)
    return seen


def _type_folder_and_press_enter(name):
    def act(dlg):
        from PySide6.QtWidgets import QLineEdit, QMessageBox

        assert not isinstance(dlg, QMessageBox), dlg.text()
        edit = dlg.findChild(QLineEdit, "fileNameEdit")
        edit.selectAll()
        QTest.keyClicks(edit, name)  # typing replaces the suggested name
        act.ok_enabled = dlg._ok.isEnabled()
        QTest.keyClick(edit, Qt.Key_Return)
    act.ok_enabled = None
    return act


def test_save_as_into_a_new_folder_by_typing_its_name(make_window, images, tmp_path, qtbot):
    from PySide6.QtWidgets import QApplication, QMessageBox

    win = _finished(make_window(), "Typed", images)
    act = _type_folder_and_press_enter("brand-new")
    seen = _answer_modal(qtbot, act)
    assert win.save_as()  # the real dialog: typed a folder that does not exist yet, pressed Enter
    assert seen and not any(isinstance(w, QMessageBox) for w in seen)  # no "Directory not found"
    assert act.ok_enabled is True  # the Save button was usable for the new name too
    target = tmp_path / "user_art" / "brand-new"
    assert win.doc.path == target and validate(target) == []
    assert QApplication.activeModalWidget() is None


def test_the_save_dialog_takes_existing_and_new_folders(qtbot, tmp_path):
    from PySide6.QtWidgets import QDialog

    from app.editor.window import SaveFolderDialog

    (tmp_path / "empty").mkdir()
    for name, want in (("empty", tmp_path / "empty"), ("fresh", tmp_path / "fresh"),
                       ("deeper/still", tmp_path / "deeper" / "still")):
        dlg = SaveFolderDialog(None, tmp_path, "")
        qtbot.addWidget(dlg)
        dlg.open()
        act = _type_folder_and_press_enter(name)
        act(dlg)
        assert dlg.result() == QDialog.Accepted and dlg.chosen == want, name
        assert act.ok_enabled
    assert not (tmp_path / "fresh").exists()  # nothing is made until the character is saved
    # the suggested name is filled in: pressing Save at once takes it
    dlg = SaveFolderDialog(None, tmp_path, "noodle-copy")
    qtbot.addWidget(dlg)
    dlg.open()
    dlg.accept()
    assert dlg.chosen == tmp_path / "noodle-copy"


def test_unique_copy_names():
    from hypothesis import given
    from hypothesis import strategies as st

    from app.editor.window import unique_copy_name

    assert unique_copy_name("Noodle", ["Ivy", "Bleu"]) == "Noodle"
    assert unique_copy_name("Noodle", ["Ivy", "noodle"]) == "Noodle (copy)"
    assert unique_copy_name("Noodle", ["Noodle", "Noodle (copy)"]) == "Noodle (copy 2)"
    assert unique_copy_name("Noodle (copy)", ["Noodle", "Noodle (copy)"]) == "Noodle (copy 2)"
    assert unique_copy_name("Noodle (copy 2)", ["Noodle (copy 2)", "Noodle (copy)"]) == "Noodle (copy 3)"

    @given(st.text(min_size=1, max_size=12).filter(str.strip), st.lists(st.text(max_size=16), max_size=8))
    def check(name, taken):
        got = unique_copy_name(name, taken + [name])
        assert got.lower() not in {t.strip().lower() for t in taken + [name]}

    check()


def test_a_copy_of_a_bundled_character_gets_a_unique_name(make_window, tmp_path):
    from art_sets.io import ArtSetError
    from art_sets.library import find_artset, list_all, list_bundled

    bundled = list_bundled()
    if not bundled:
        pytest.skip("no bundled characters yet")
    name, folder = bundled[1] if len(bundled) > 1 else bundled[0]
    win = make_window()
    assert win.open_path(folder)
    asked = []
    win.ask_save_folder = lambda start, suggested: asked.append(suggested) or tmp_path / "user_art" / suggested
    assert win.save()  # a bundled character is saved as a copy
    assert asked == [ed.slug(f"{name} (copy)")]
    assert load_artset(win.doc.path).name == f"{name} (copy)"
    assert win.name_edit.text() == f"{name} (copy)"
    assert "another character is already called" in win.statusBar().currentMessage()
    assert win.open_path(folder)
    assert win.save()
    assert load_artset(win.doc.path).name == f"{name} (copy 2)"
    names = [n for n, _ in list_all()]
    assert len(names) == len(set(names)), names  # the character strip never shows a name twice
    with pytest.raises(ArtSetError) as err:
        find_artset("nobody")
    assert str(err.value).count(f"{name},") + str(err.value).count(f"{name})") == 1
    # saving a character in its own folder keeps its name
    win.doc.set_info(author="me")
    assert win.save() and load_artset(win.doc.path).name == f"{name} (copy 2)"


def test_the_editor_uses_the_main_windows_dark_theme(make_window, images, qtbot):
    from PySide6.QtWidgets import QApplication

    from app import views

    heads, eyes, mouths = images
    win = make_window()
    win.new_character("Dark", heads, eyes, mouths)
    qapp = QApplication.instance()
    assert qapp.styleSheet() == views.STYLE_SHEET
    assert win.palette().color(win.backgroundRole()).name() == "#1e1f22"
    img = win.grab().toImage()
    grey = [img.pixelColor(x, y).lightness() for x in range(0, img.width(), 17) for y in range(0, img.height(), 17)]
    assert np.median(grey) < 70  # the window looks dark, not just its palette
    assert win.minimumSizeHint().width() <= 1366  # the theme's padding still fits a common laptop screen
    assert win.problems.item(0).foreground().color() in (views.OK_GREEN, views.BAD, views.WARN, views.ACCENT)


def test_strip_captions_never_overlap(make_window, images, tmp_path, qtbot):
    """Eight drawings with long names, lines still to place, in a narrow strip."""
    heads, eyes, mouths = images
    src = tmp_path / "long"
    src.mkdir()
    many = [_mouth(src / f"a-rather-long-drawing-name-{k}.png", k % 3) for k in range(8)]
    win = make_window()
    win.new_character("Strip", heads, eyes, many)
    win.doc.select(part="mouth", drawing=0)
    win.doc.add_line("mouth", 0, [5, 5, 40, 20])  # now missing in the seven others
    for width in (1100, 560, 300):
        win.strip.resize(width, 120)
        for line in (-1, 0):
            win.doc.select(line=line)
            caps = win.strip.captions()
            assert len(caps) == 8
            fm = win.strip.fontMetrics()
            for (text, box), (_, nxt) in zip(caps, caps[1:]):
                assert box.right() <= nxt.left()  # neighbouring cells do not overlap
            for text, box in caps:
                assert fm.horizontalAdvance(text) <= box.width() + 0.5, (width, text)
            missing = [t for t, _ in caps[1:]]
            assert len({"to place" in t for t in missing}) == 1  # every caption says it the same way
            if width >= 1100:
                assert all(("to place" in t) or ("·" in t) for t in missing), missing
    win.strip.resize(1100, 120)
    win.strip.repaint()


def test_empty_canvases_read_right(make_window, images, tmp_path):
    heads, _eyes_, mouths = images
    win = make_window()
    text = win.line_canvas.empty_text()
    assert text.startswith("No character open.") and "No a " not in text
    win.new_character("No eyes", heads, [], mouths)
    win.doc.select(part="eyes")
    assert win.line_canvas.empty_text().startswith("No eye drawings yet.")
    assert "Add ▸ Eye drawings" in win.line_canvas.empty_text()
    win.line_canvas.repaint()
