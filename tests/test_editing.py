"""Pure editing operations on art sets (art_sets.editing): no Qt."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image, ImageDraw

from art_sets import editing as ed
from art_sets.io import load_artset
from art_sets.validate import validate


def head_image(size=(200, 240), seed=0) -> np.ndarray:
    im = Image.new("RGBA", size, (0, 0, 0, 0))
    dr = ImageDraw.Draw(im)
    dr.ellipse([10, 10, size[0] - 10, size[1] - 10], fill=(240, 200 - seed * 10, 170, 255), outline=(20, 20, 20, 255), width=4)
    return np.asarray(im).copy()


def part_image(size, kind: str, k: int) -> np.ndarray:
    w, h = size
    im = Image.new("RGBA", size, (255, 255, 255, 255))
    dr = ImageDraw.Draw(im)
    if kind == "mouth":
        dr.arc([w * 0.15, h * 0.1, w * 0.85, h * (0.5 + 0.1 * k)], 10, 170, fill=(0, 0, 0, 255), width=3)
    else:
        for cx in (w * 0.3, w * 0.7):
            dr.ellipse([cx - 12, h * 0.5 - 4 - 3 * k, cx + 12, h * 0.5 + 4 + 3 * k], outline=(0, 0, 0, 255), width=3)
    return np.asarray(im).copy()


def small_set():
    eyes = [(n, part_image((100, 40), "eyes", k)) for k, n in enumerate(["open", "closed", "wide"])]
    mouths = [(n, part_image((60, 30), "mouth", k)) for k, n in enumerate(["neutral", "smile", "ah"])]
    return ed.new_artset("Test", [head_image(), head_image(seed=1)], eyes, mouths, author="me")


def test_new_artset_boxes_and_sizes():
    art = small_set()
    assert art.canvas == (200, 240)
    assert len(art.heads) == 2 and art.head_files == ["head-1.png", "head-2.png"]
    for p in art.parts.values():
        x, y, w, h = p.box
        assert 0 <= x and x + w <= 200 and 0 <= y and y + h <= 240
        assert all(d.size == p.size for d in p.drawings)
    assert art.eyes.box[1] < art.mouth.box[1]
    assert art.mouth.names() == ["neutral", "smile", "ah"]
    assert art.mouth.drawings[0].file == "mouth/neutral.png"


def test_mismatched_sizes_are_fitted_not_refused():
    art = small_set()
    big = part_image((120, 60), "mouth", 2)
    i = ed.add_drawing(art, "mouth", "Grin", big, fit="resize")
    assert art.mouth.drawings[i].size == art.mouth.size
    assert art.mouth.drawings[i].name == "grin"
    j = ed.add_drawing(art, "mouth", "grin", big, fit="crop")
    assert art.mouth.drawings[j].name == "grin-2"
    # crop keeps the centre pixels unscaled
    w, h = art.mouth.size
    np.testing.assert_array_equal(art.mouth.drawings[j].image[h // 2, :], big[30 - h // 2 + h // 2, 60 - w // 2:60 - w // 2 + w])


def test_fit_drawing_moves_lines_with_pixels():
    d = ed.Drawing("a", part_image((100, 50), "mouth", 0), np.array([[10.0, 10, 90, 40]]))
    r = ed.fit_drawing(d, (50, 25), "resize")
    np.testing.assert_allclose(r.lines, [[5, 5, 45, 20]])
    c = ed.fit_drawing(d, (80, 50), "crop")
    np.testing.assert_allclose(c.lines, [[0, 10, 80, 40]])
    assert c.size == (80, 50) and r.size == (50, 25)


def test_resize_keeps_transparent_edges_clean():
    img = np.zeros((20, 20, 4), np.uint8)
    img[5:15, 5:15] = (255, 0, 0, 255)  # red square; transparent black around it
    out = ed.resize_image(img, (40, 40))
    edge = out[(out[:, :, 3] > 20) & (out[:, :, 3] < 235)]
    assert len(edge) > 0
    assert edge[:, 0].min() > 200  # no dark fringe from the transparent black


def test_add_move_delete_lines_keep_counts_equal():
    art = small_set()
    i0 = ed.add_line(art, "mouth", 0, [5, 5, 40, 20])
    i1 = ed.add_line(art, "mouth", 1, [10, 10, 50, 12])
    assert (i0, i1) == (0, 1)
    assert {len(d.lines) for d in art.mouth.drawings} == {2}
    miss = ed.missing_lines(art, "mouth")
    assert miss[0] == ["smile", "ah"] and miss[1] == ["neutral", "ah"]
    ed.move_line(art, "mouth", 2, 0, [6, 6, 41, 21])
    assert "ah" not in ed.missing_lines(art, "mouth")[0]
    ed.delete_line(art, "mouth", 0)
    assert {len(d.lines) for d in art.mouth.drawings} == {1}
    assert ed.missing_lines(art, "mouth") == {0: ["neutral", "ah"]}
    ed.mark_placed(art, "mouth", 0)
    ed.mark_placed(art, "mouth", 2)
    assert ed.missing_lines(art, "mouth") == {0: []}
    assert "editor" not in art.extra  # nothing left to remember


def test_lines_are_clamped_and_short_lines_refused():
    art = small_set()
    i = ed.add_line(art, "eyes", 0, [-20, 5, 500, 30])
    w, h = art.eyes.size
    ln = art.eyes.drawings[0].lines[i]
    assert ln[0] == 0 and ln[2] == w - 1
    with pytest.raises(ed.EditError):
        ed.add_line(art, "eyes", 0, [3, 3, 3.2, 3.2])


def test_edits_never_mutate_arrays_in_place():
    art = small_set()
    ed.add_line(art, "mouth", 0, [5, 5, 40, 20])
    snap = ed.clone(art)
    before = [d.lines.copy() for d in art.mouth.drawings]
    ed.move_line(art, "mouth", 0, 0, [1, 1, 30, 20])
    ed.add_line(art, "mouth", 1, [2, 2, 20, 20])
    ed.set_box(art, "mouth", (10, 10, 80, 40))
    ed.make_holes(art, 6)
    for d, b in zip(snap.mouth.drawings, before):
        np.testing.assert_array_equal(d.lines, b)
    assert snap.mouth.size == (60, 30) and not ed.same_artset(snap, art)
    assert ed.same_artset(snap, ed.clone(snap))


def test_copy_lines_and_make_consistent():
    art = small_set()
    ed.add_line(art, "eyes", 0, [5, 5, 40, 20])
    ed.add_line(art, "eyes", 0, [50, 5, 90, 20])
    ed.move_line(art, "eyes", 1, 0, [7, 7, 30, 30])
    ed.copy_lines(art, "eyes", 0, 1)
    np.testing.assert_array_equal(art.eyes.drawings[1].lines, art.eyes.drawings[0].lines)
    assert ed.unplaced(art, "eyes", 1) == {0, 1}
    # a hand-edited set with unequal counts is padded from the fullest drawing
    art.eyes.drawings[2].lines = np.zeros((0, 4))
    ed.make_consistent(art, "eyes")
    assert len(art.eyes.drawings[2].lines) == 2 and ed.unplaced(art, "eyes", 2) == {0, 1}


def test_snap_and_hit():
    lines = np.array([[0.0, 0, 10, 0], [20, 20, 30, 30]])
    assert ed.snap_point((9, 1), lines, 3) == ((10.0, 0.0), (0, 1))
    assert ed.snap_point((15, 15), lines, 3) == ((15.0, 15.0), None)
    assert ed.snap_point((10, 0.5), lines, 3, exclude=(0, 1))[1] is None
    assert ed.hit_line((5, 1), lines, 2) == (0, -1)
    assert ed.hit_line((20.5, 20), lines, 2) == (1, 0)
    assert ed.hit_line((50, 50), lines, 2) is None


def test_hole_mask_is_feathered_and_inside_boxes():
    m = ed.hole_mask((100, 80), [(20, 10, 40, 30)], radius=8)
    assert m.shape == (80, 100) and m.dtype == np.float32
    assert m[25, 40] == 1.0  # box centre fully open
    assert m[:12].max() == 0 and m[:, :22].max() == 0 and m[:, 58:].max() == 0  # 2 px edge stays closed
    row = m[25, 20:40]
    assert np.all(np.diff(row) >= 0) and 0 < row[5] < 1  # soft ramp inward
    hard = ed.hole_mask((100, 80), [(20, 10, 40, 30)], radius=0, margin=0)
    assert hard[10:40, 20:60].min() == 1 and hard.sum() == 40 * 30


@settings(max_examples=25, deadline=None)
@given(r1=st.floats(0, 20), r2=st.floats(0, 20))
def test_bigger_radius_never_opens_more(r1, r2):
    lo, hi = sorted((r1, r2))
    a = ed.hole_mask((60, 50), [(5, 5, 40, 30)], lo)
    b = ed.hole_mask((60, 50), [(5, 5, 40, 30)], hi)
    assert np.all(b <= a + 1e-6)


def test_make_holes_and_paint():
    art = small_set()
    base = list(art.heads)
    ed.make_holes(art, 10, base_heads=base)
    x, y, w, h = art.mouth.box
    assert art.heads[0][y + h // 2, x + w // 2, 3] == 0
    ed.make_holes(art, 2, base_heads=base)  # re-cut from the base, no accumulation
    assert art.heads[1][y + 3, x + w // 2, 3] < base[1][y + 3, x + w // 2, 3]
    painted = ed.paint_alpha(base[0], [(100, 60), (120, 60)], radius=6, erase=True)
    assert painted[60, 110, 3] == 0 and painted[60, 150, 3] == base[0][60, 150, 3]
    np.testing.assert_array_equal(painted[:, :, :3], base[0][:, :, :3])
    filled = ed.paint_alpha(painted, [(110, 60)], radius=6, erase=False)
    assert filled[60, 110, 3] == 255


def test_compose_preview_head_over_parts():
    art = small_set()
    ed.make_holes(art, 4)
    img = ed.compose_preview(art)
    assert img.shape == (240, 200, 4) and img[:, :, 3].min() == 255
    x, y, w, h = art.mouth.box
    # inside the hole the mouth drawing shows (its white paper), elsewhere the head's colour
    np.testing.assert_array_equal(img[y + h // 2, x + w // 2, :3], art.mouth.drawings[0].image[h // 2, w // 2, :3])
    np.testing.assert_array_equal(img[30, 100, :3], art.heads[0][30, 100, :3])


def test_triangle_weights():
    c = [(0, 0), (1, 0), (0, 1)]
    np.testing.assert_allclose(ed.triangle_weights((0, 0), c), [1, 0, 0])
    np.testing.assert_allclose(ed.triangle_weights((0.25, 0.25), c), [0.5, 0.25, 0.25])
    w = ed.triangle_weights((5, 5), c)
    assert np.isclose(w.sum(), 1) and np.all(w >= 0)


def test_line_colours_distinct():
    cols = np.array([ed.line_color(i) for i in range(12)], float)
    d = np.linalg.norm(cols[:, None] - cols[None, :], axis=2) + np.eye(12) * 1e9
    assert d.min() > 60  # no two of the first twelve lines look alike
    assert len({ed.line_color(i) for i in range(40)}) == 40


def _finish(art):
    for pname in art.parts:
        ed.add_line(art, pname, 0, [3, 3, 20, 10])
        ed.add_line(art, pname, 0, [25, 5, 28, 20])
        for i in range(len(art.parts[pname].drawings)):
            ed.mark_placed(art, pname, i)
    ed.make_holes(art, 5)


def test_save_reload_validate(tmp_path):
    art = small_set()
    _finish(art)
    ed.move_line(art, "mouth", 1, 1, [26, 6, 29, 22])
    ed.add_line(art, "mouth", 2, [1, 20, 30, 25])  # one unplaced line survives the round trip
    saved = ed.save_safely(art, tmp_path / "set")
    assert validate(tmp_path / "set") == []
    back = load_artset(tmp_path / "set")
    assert ed.same_artset(back, saved)
    assert ed.missing_lines(back, "mouth")[2] == ["neutral", "smile"]


def test_resave_never_overwrites_files_the_old_manifest_uses(tmp_path, monkeypatch):
    art = small_set()
    _finish(art)
    folder = tmp_path / "set"
    saved = ed.save_safely(art, folder)
    old_json = (folder / "artset.json").read_text()
    # change a drawing's pixels and the box size, then crash after the first PNG is written
    ed.set_box(saved, "mouth", (50, 150, 90, 45))
    ed.replace_drawing_image(saved, "mouth", 0, part_image((90, 45), "mouth", 3))
    from art_sets import atomic_file

    real = atomic_file.write_bytes
    calls = []

    def flaky(path, data):
        calls.append(path)
        if len(calls) == 2:
            raise OSError("disk full")
        real(path, data)

    monkeypatch.setattr(atomic_file, "write_bytes", flaky)
    with pytest.raises(OSError):
        ed.save_safely(saved, folder)
    monkeypatch.setattr(atomic_file, "write_bytes", real)
    assert (folder / "artset.json").read_text() == old_json
    assert validate(folder) == []
    assert ed.same_artset(load_artset(folder), load_artset(folder))
    again = ed.save_safely(saved, folder)
    assert validate(folder) == []
    assert ed.same_artset(load_artset(folder), again)
    assert again.mouth.drawings[0].file != "mouth/neutral.png"  # the other name of the pair
    assert not (folder / "mouth" / "neutral.png").exists()  # stale file removed after the swap


_op = st.one_of(
    st.tuples(st.just("add"), st.integers(0, 2), st.lists(st.floats(0, 59), min_size=4, max_size=4)),
    st.tuples(st.just("move"), st.integers(0, 2), st.integers(0, 5), st.lists(st.floats(-10, 70), min_size=4, max_size=4)),
    st.tuples(st.just("delete"), st.integers(0, 5)),
    st.tuples(st.just("copy"), st.integers(0, 2), st.integers(0, 2)),
    st.tuples(st.just("accept"), st.integers(0, 2)),
)


@settings(max_examples=40, deadline=None)
@given(ops=st.lists(_op, max_size=12))
def test_any_sequence_of_line_edits_keeps_the_part_consistent(ops):
    art = small_set()
    snap = ed.clone(art)
    for op in ops:
        n = ed.line_count(art.mouth)
        try:
            if op[0] == "add":
                ed.add_line(art, "mouth", op[1], op[2])
            elif op[0] == "move" and op[2] < n:
                ed.move_line(art, "mouth", op[1], op[2], op[3])
            elif op[0] == "delete" and op[1] < n:
                ed.delete_line(art, "mouth", op[1])
            elif op[0] == "copy":
                ed.copy_lines(art, "mouth", op[1], op[2])
            elif op[0] == "accept":
                ed.mark_placed(art, "mouth", op[1])
        except ed.EditError:
            pass
        counts = {len(d.lines) for d in art.mouth.drawings}
        assert len(counts) == 1
        n = counts.pop()
        w, h = art.mouth.size
        for di, d in enumerate(art.mouth.drawings):
            assert d.lines.shape == (n, 4) and d.lines.dtype == np.float64
            assert np.all((d.lines[:, 0::2] >= 0) & (d.lines[:, 0::2] <= w - 1))
            assert np.all((d.lines[:, 1::2] >= 0) & (d.lines[:, 1::2] <= h - 1))
            assert all(0 <= i < n for i in ed.unplaced(art, "mouth", di))
        assert set(ed.missing_lines(art, "mouth")) == set(range(n))
    assert ed.same_artset(snap, small_set())  # the starting snapshot was never touched


@pytest.mark.parametrize("paper", [(255, 255, 255, 255), (240, 200, 160, 255), (0, 0, 0, 0)])
def test_suggest_lines_frame_the_ink(paper):
    im = Image.new("RGBA", (120, 60), paper)
    dr = ImageDraw.Draw(im)
    dr.ellipse([20, 20, 50, 40], fill=(30, 20, 20, 255))  # left eye
    dr.ellipse([75, 15, 100, 45], fill=(30, 20, 20, 255))  # right eye
    rng = np.random.default_rng(0)
    arr = np.asarray(im).astype(np.int16)
    if paper[3]:
        arr[:, :, :3] += rng.integers(-12, 13, arr[:, :, :3].shape)  # paper grain
    arr = np.clip(arr, 0, 255).astype(np.uint8)
    eyes = ed.suggest_lines(arr, "eyes")
    assert eyes.shape == (8, 4)
    np.testing.assert_allclose(eyes[0], [20, 20, 51, 20], atol=1.5)  # top of the left eye
    np.testing.assert_allclose(eyes[5], [75, 46, 101, 46], atol=1.5)  # bottom of the right eye
    mouth = ed.suggest_lines(arr, "mouth")
    assert mouth.shape == (4, 4)
    np.testing.assert_allclose(mouth[2], [20, 15, 20, 46], atol=1.5)  # left side, top to bottom


def test_add_starter_lines_to_a_part():
    art = small_set()
    n = ed.add_starter_lines(art, "eyes")
    assert n == 8 and {len(d.lines) for d in art.eyes.drawings} == {8}
    assert all(not v for v in ed.missing_lines(art, "eyes").values())
    # the open eyes are taller than the closed ones
    h_open = art.eyes.drawings[2].lines[1, 1] - art.eyes.drawings[2].lines[0, 1]
    h_closed = art.eyes.drawings[0].lines[1, 1] - art.eyes.drawings[0].lines[0, 1]
    assert h_open > h_closed
    blank = np.full((40, 100, 4), 255, np.uint8)
    assert ed.suggest_lines(blank, "eyes").shape == (8, 4)


def test_names_and_sorting_from_file_names(tmp_path):
    assert ed.name_from_path("scans/Mouth_AH.png", "mouth") == "ah"
    assert ed.name_from_path("eyes-open.png", "eyes") == "open"
    assert ed.name_from_path("mouth.png", "mouth") == "mouth"
    assert ed.name_from_path("Grin 2.PNG") == "grin-2"
    s = ed.sort_images([tmp_path / "head-1.png", tmp_path / "mouths" / "ah.png", tmp_path / "Eye_wide.png",
                        tmp_path / "brows_angry.png", tmp_path / "lip_oo.png", tmp_path / "cat.png"])
    assert [p.name for p in s["heads"]] == ["head-1.png"]
    assert [p.name for p in s["eyes"]] == ["Eye_wide.png", "brows_angry.png"]
    assert sorted(p.name for p in s["mouth"]) == ["ah.png", "lip_oo.png"]
    assert [p.name for p in s["unsorted"]] == ["cat.png"]
