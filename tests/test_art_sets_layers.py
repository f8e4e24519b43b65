"""Art-set format 2: layered drawings and the body (reading, writing, checking); the format knows no renderer."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from art_sets.io import ArtSetError, load_artset, save_artset
from art_sets.model import Body, Drawing, Layer, flatten, layer_names
from art_sets.validate import validate
from test_art_sets import ROOT, edit_manifest, first_bundled, messages, tiny_artset


def layered_tiny(shared_file: bool = True):
    """``tiny_artset`` with every drawing split into two layers: a static opaque ``under`` with its
    own lines and an ``over`` (half see-through) that moves with the drawing's lines; and a body."""
    art = tiny_artset()
    for pname, part in art.parts.items():
        w, h = part.size
        under = np.zeros((h, w, 4), np.uint8)
        under[..., 1], under[..., 3] = 90, 255
        own = np.array([[1.0, 2.0, w - 2.0, 2.0]])
        new = []
        for d in part.drawings:
            over = d.image.copy()
            over[: h // 2, :, 3] = 0
            layers = [Layer("under", under, own, f"{pname}/under.png" if shared_file else ""), Layer("over", over)]
            new.append(Drawing.from_layers(d.name, layers, d.lines))
        part.drawings = new
    body = np.zeros((64, 64, 4), np.uint8)
    body[48:, :, :] = (30, 60, 200, 255)
    art.body = Body(body, "body.png", follow=0.25, roll=0.1)
    return art


def test_layered_round_trip(tmp_path):
    art = layered_tiny()
    folder = save_artset(art, tmp_path / "lay")
    data = json.loads((folder / "artset.json").read_text())
    assert data["format"] == 2 and data["body"] == {"image": "body.png", "follow": 0.25, "roll": 0.1}
    d0 = data["parts"]["eyes"]["drawings"][0]
    assert "image" not in d0 and [ly["name"] for ly in d0["layers"]] == ["under", "over"]
    assert "lines" in d0["layers"][0] and "lines" not in d0["layers"][1]
    assert d0["layers"][1]["image"] == "eyes/d0/over.png" and d0["layers"][0]["image"] == "eyes/under.png"
    assert validate(folder) == []
    back = load_artset(folder)
    assert back.body.follow == 0.25 and back.body.roll == 0.1 and back.body.pivot is None
    np.testing.assert_array_equal(back.body.image, art.body.image)
    for pname in ("eyes", "mouth"):
        assert layer_names(back.parts[pname]) == ["under", "over"]
        for a, b in zip(art.parts[pname].drawings, back.parts[pname].drawings):
            np.testing.assert_array_equal(a.lines, b.lines)
            for la, lb in zip(a.layers, b.layers):
                np.testing.assert_array_equal(la.image, lb.image)
                assert (la.lines is None) == (lb.lines is None)
            np.testing.assert_array_equal(b.image, flatten([ly.image for ly in a.layers]))
    # a second save of what was loaded writes the same manifest
    again = save_artset(back, tmp_path / "again")
    assert json.loads((again / "artset.json").read_text()) == data


def test_flatten_lays_each_layer_over_the_ones_below():
    under = np.full((2, 2, 4), (200, 0, 0, 255), np.uint8)
    over = np.zeros((2, 2, 4), np.uint8)
    over[0, 0] = (0, 0, 250, 255)
    over[1, 1] = (0, 0, 250, 128)
    out = flatten([under, over])
    assert tuple(out[0, 0]) == (0, 0, 250, 255) and tuple(out[0, 1]) == (200, 0, 0, 255)
    assert out[1, 1, 3] == 255 and 90 < out[1, 1, 0] < 110 and 115 < out[1, 1, 2] < 135


def test_a_format_1_set_is_written_as_format_1_byte_for_byte(tmp_path):
    folder = save_artset(tiny_artset(), tmp_path / "one")
    text = (folder / "artset.json").read_bytes()
    assert json.loads(text)["format"] == 1
    again = save_artset(load_artset(folder), tmp_path / "two")
    assert (again / "artset.json").read_bytes() == text


def test_body_in_a_format_1_manifest_is_just_an_extra_key(tmp_path):
    folder = save_artset(tiny_artset(), tmp_path / "one")
    edit_manifest(folder, lambda d: d.__setitem__("body", {"image": "nowhere.png"}))
    art = load_artset(folder)
    assert art.body is None and art.extra["body"] == {"image": "nowhere.png"}


def test_layers_need_format_2(tmp_path):
    folder = save_artset(layered_tiny(), tmp_path / "lay")
    edit_manifest(folder, lambda d: d.__setitem__("format", 1))
    assert "needs 'name', 'image' and 'lines'" in messages(folder)


@pytest.fixture
def layered(tmp_path) -> Path:
    return save_artset(layered_tiny(), tmp_path / "lay")


def _first(d, part="mouth", k=0):
    return d["parts"][part]["drawings"][k]


@pytest.mark.parametrize("edit, expected", [
    (lambda d: _first(d)["layers"].reverse(), "same layers in the same order"),
    (lambda d: _first(d)["layers"].pop(), "same layers in the same order"),
    (lambda d: _first(d).__setitem__("image", "mouth/x.png"), "both 'image' and 'layers'"),
    (lambda d: _first(d).__setitem__("layers", []), "layers must be a non-empty list"),
    (lambda d: _first(d)["layers"][1].__setitem__("name", ""), "name must be a non-empty string"),
    (lambda d: _first(d)["layers"][1].__setitem__("name", "under"), "two layers are called 'under'"),
    (lambda d: _first(d)["layers"][0].pop("lines"), "own control lines in"),
    (lambda d: _first(d)["layers"][0]["lines"].append([1, 1, 5, 5]), "layer 'under' control lines"),
    (lambda d: _first(d)["layers"][0].__setitem__("lines", [[1, 1, 500, 5]]), "layer 'under' line(s) 0 lie outside"),
    (lambda d: _first(d)["layers"][0].__setitem__("lines", "x"), "lines must be a list"),
    (lambda d: _first(d)["layers"][1].__setitem__("image", "../x.png"), "leaves the art-set folder"),
    (lambda d: _first(d)["layers"][1].__setitem__("image", "mouth/missing.png"), "missing image"),
    (lambda d: d["parts"]["mouth"]["drawings"].__setitem__(1, {"name": "flat", "image": "eyes/under.png", "lines": []}),
     "is a single picture but"),
    (lambda d: d["body"].__setitem__("follow", 1.5), "body.follow must be a number from 0 to 1"),
    (lambda d: d["body"].__setitem__("roll", -0.1), "body.roll must be a number from 0 to 1"),
    (lambda d: d["body"].__setitem__("pivot", [1]), "body.pivot must be [x, y]"),
    (lambda d: d.__setitem__("body", "body.png"), "body must be an object"),
    (lambda d: d["body"].__setitem__("image", "head-1.png") or None, None),  # any canvas-sized image will do
])
def test_each_layer_and_body_problem_is_named(layered, edit, expected):
    edit_manifest(layered, edit)
    msg = messages(layered)
    if expected is None:
        assert msg == ""
    else:
        assert expected in msg, msg
        assert all("\n" not in p.message for p in validate(layered))
        with pytest.raises(ArtSetError):
            load_artset(layered)


def test_layer_and_body_images_of_the_wrong_size(layered):
    Image.new("RGBA", (7, 7)).save(layered / "mouth" / "d1" / "over.png")
    Image.new("RGBA", (30, 64)).save(layered / "body.png")
    msg = messages(layered)
    assert "layer 'over' is 7x7, the mouth box is 24x14" in msg
    assert str(layered / "body.png") in msg and "body is 30x64" in msg


def test_two_different_images_for_one_file_are_refused(tmp_path):
    art = layered_tiny()
    art.eyes.drawings[1].layers[0].image = art.eyes.drawings[1].layers[0].image.copy()
    art.eyes.drawings[1].layers[0].image[0, 0] = (1, 2, 3, 255)
    with pytest.raises(ArtSetError, match="two different images would be written"):
        save_artset(art, tmp_path / "x")


def test_bundled_characters_are_layered_with_bodies():
    art = load_artset(first_bundled())
    assert layer_names(art.eyes) == ["eyeball", "lower-lid", "upper-lid"]
    assert layer_names(art.mouth)[:3] == ["inside", "lower-lip", "upper-lip"]
    assert art.body is not None and 0 < art.body.follow < 1 and 0 <= art.body.roll < 0.5


def test_check_cli_reads_a_layered_set(tmp_path):
    dst = tmp_path / "c"
    shutil.copytree(first_bundled(), dst)
    r = subprocess.run([sys.executable, "-m", "art_sets", "check", str(dst)], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith("OK: ")
    assert "note: layers of eyes: eyeball, lower-lid, upper-lid" in r.stdout


def test_the_format_knows_no_renderer(tmp_path):
    """Nothing in art_sets imports morph: not the library, not its CLI drawing a sheet."""
    code = ("import sys, runpy\n"
            "import art_sets, art_sets.io, art_sets.validate, art_sets.sheet, art_sets.library, art_sets.editing\n"
            f"sys.argv = ['art_sets', 'sheet', {str(first_bundled())!r}, '--out', {str(tmp_path / 's.png')!r}]\n"
            "try:\n    runpy.run_module('art_sets', run_name='__main__')\nexcept SystemExit as e:\n    assert not e.code\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('morph', 'training', 'tracker', 'app', 'cv2'))\n"
            "assert not bad, bad\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "s.png").is_file()


def test_app_sheet_draws_the_rendered_blends(tmp_path):
    folder = save_artset(layered_tiny(), tmp_path / "lay")
    out = tmp_path / "sheet.png"
    r = subprocess.run([sys.executable, "-m", "app", "sheet", str(folder), "--out", str(out)],
                       capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stderr
    plain = tmp_path / "plain.png"
    r = subprocess.run([sys.executable, "-m", "app", "sheet", str(folder), "--out", str(plain), "--no-blends"],
                       capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stderr
    assert Image.open(out).height > Image.open(plain).height
    r = subprocess.run([sys.executable, "-m", "app", "sheet", str(tmp_path / "nope"), "--out", str(out)],
                       capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert r.returncode == 2 and r.stderr.startswith("inkface: ") and len(r.stderr.strip().splitlines()) == 1


def test_editing_fits_every_layer_and_refuses_to_flatten_one(tmp_path):
    from art_sets import editing as ed

    art = layered_tiny()
    d = art.eyes.drawings[0]
    nd = ed.fit_drawing(d, (40, 20))
    assert nd.size == (40, 20) and all(ly.image.shape == (20, 40, 4) for ly in nd.layers)
    np.testing.assert_allclose(nd.layers[0].lines, d.layers[0].lines * [40 / 48, 20 / 16, 40 / 48, 20 / 16])
    assert nd.layers[1].lines is None
    with pytest.raises(ed.EditError, match="drawn in layers"):
        ed.replace_drawing_image(art, "eyes", 0, d.image)
    ed.set_box(art, "eyes", (8, 10, 40, 20))
    back = load_artset(save_artset(art, tmp_path / "fitted"))  # loads: every layer has the new box's size
    assert all(ly.image.shape == (20, 40, 4) for d in back.eyes.drawings for ly in d.layers)


def test_limits_on_layers_and_on_line_work(tmp_path):
    from art_sets.io import MAX_LAYER_LINES, MAX_LAYERS, MAX_LINE_WORK

    folder = save_artset(layered_tiny(), tmp_path / "lay")

    def many_layers(d):
        ly = _first(d)["layers"]
        ly += [dict(ly[1], name=f"extra{k}") for k in range(MAX_LAYERS)]
    edit_manifest(folder, many_layers)
    assert "the layers limit" in messages(folder)

    art = layered_tiny()
    big = tiny_artset(n_eyes=9)
    w, h = art.eyes.size
    rows = np.array([[1.0, 1.0 + (k % 12), w - 2.0, 2.0 + (k % 12)] for k in range(MAX_LAYER_LINES)])
    art.eyes.drawings = [Drawing.from_layers(d.name, [Layer("only", d.image)], rows) for d in big.eyes.drawings]
    assert 9 * 8 * MAX_LAYER_LINES > MAX_LINE_WORK
    folder = save_artset(art, tmp_path / "work")
    assert "the line-work limit" in messages(folder)
