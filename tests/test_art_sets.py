"""Art-set format: loader, writer, validator, library and the ``python -m art_sets`` CLI."""

from __future__ import annotations

import json
import shutil
import struct
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from art_sets.io import ArtSetError, load_artset, save_artset, scan
from art_sets.library import bundled_dir, find_artset, list_all, list_bundled, list_user, thumbnail, user_dir
from art_sets.model import ArtSet, Drawing, Part
from art_sets.validate import validate

ROOT = Path(__file__).resolve().parents[1]


def tiny_artset(n_eyes: int = 3, n_mouths: int = 3, seed: int = 0) -> ArtSet:
    """A small but complete art set made in memory (64×64 canvas)."""
    rng = np.random.default_rng(seed)

    def img(w, h, alpha=255):
        a = rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
        a[..., 3] = alpha
        return a

    def part(name, box, n):
        w, h = box[2], box[3]
        ds = [Drawing(f"d{i}", img(w, h), np.array([[1.0, 1.0, w - 1.5, h / 2], [2, h - 1, w - 2, h - 1.25]]), f"{name}/d{i}.png")
              for i in range(n)]
        return Part(name, box, ds)

    heads = [img(64, 64) for _ in range(2)]
    for hd in heads:  # see-through holes inside the boxes, opaque on their borders
        hd[13:23, 11:53, 3] = 0
        hd[39:47, 23:41, 3] = 60
    return ArtSet(name="Tiny", canvas=(64, 64), pivot=(32.0, 50.5), heads=heads,
                  parts={"eyes": part("eyes", (8, 10, 48, 16), n_eyes), "mouth": part("mouth", (20, 36, 24, 14), n_mouths)},
                  author="tests", head_files=["head-1.png", "head-2.png"], extra={"style": "test", "line_names": {"eyes": ["a", "b"]}})


@pytest.fixture
def tiny(tmp_path) -> Path:
    return save_artset(tiny_artset(), tmp_path / "tiny")


def first_bundled() -> Path:
    sets = list_bundled()
    assert sets, "no bundled art set"
    return sets[0][1]


def format1_copy(src: Path, dst: Path) -> Path:
    """The art set at ``src`` saved as a format-1 set: every drawing flattened to one picture with
    the first of its lines, no body."""
    from art_sets.io import MAX_LINES

    art = load_artset(src).single_pictures()
    for part in art.parts.values():
        for d in part.drawings:
            d.lines = d.lines[:MAX_LINES]  # a format-1 drawing may have at most MAX_LINES
    return save_artset(art, dst)


@pytest.fixture
def bundled_copy(tmp_path) -> Path:
    """A real character as a format-1 set (the validator tests below edit its format-1 manifest)."""
    return format1_copy(first_bundled(), tmp_path / "copy")


@pytest.fixture
def layered_copy(tmp_path) -> Path:
    dst = tmp_path / "layered"
    shutil.copytree(first_bundled(), dst)
    return dst


def edit_manifest(folder: Path, fn) -> None:
    mf = folder / "artset.json"
    data = json.loads(mf.read_text())
    fn(data)
    mf.write_text(json.dumps(data))


def messages(folder: Path) -> str:
    return "\n".join(str(p) for p in validate(folder))


# --- round trip -----------------------------------------------------------------------------
def test_round_trip_is_lossless(tmp_path):
    art = tiny_artset()
    a = load_artset(save_artset(art, tmp_path / "a"))
    b = load_artset(save_artset(a, tmp_path / "b"))
    for x in (art, a, b):
        assert x.name == "Tiny" and x.canvas == (64, 64) and x.pivot == (32.0, 50.5) and x.author == "tests"
    assert b.extra == art.extra
    for h0, h1 in zip(art.heads, b.heads):
        np.testing.assert_array_equal(h0, h1)
    for pname in ("eyes", "mouth"):
        p0, p1 = art.parts[pname], b.parts[pname]
        assert p0.box == p1.box and p0.names() == p1.names()
        for d0, d1 in zip(p0.drawings, p1.drawings):
            np.testing.assert_array_equal(d0.image, d1.image)
            assert d1.lines.dtype == np.float64
            np.testing.assert_array_equal(d0.lines, d1.lines)
            assert d0.file == d1.file
    assert json.loads((tmp_path / "a" / "artset.json").read_text()) == json.loads((tmp_path / "b" / "artset.json").read_text())


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.lists(st.floats(0, 16, allow_nan=False), min_size=4, max_size=4), min_size=1, max_size=6))
def test_line_coordinates_round_trip_exactly(tmp_path_factory, rows):
    art = tiny_artset()
    lines = np.array(rows, np.float64)
    for d in art.mouth.drawings:
        d.lines = lines
    out = tmp_path_factory.mktemp("rt")
    back = load_artset(save_artset(art, out), strict=False)
    for d in back.mouth.drawings:
        np.testing.assert_array_equal(d.lines, lines)


def test_save_is_atomic_and_leaves_no_temp_files(tmp_path):
    folder = save_artset(tiny_artset(), tmp_path / "t")
    save_artset(load_artset(folder), folder)  # overwrite in place
    assert not [p for p in folder.rglob("*") if p.name.endswith(".tmp")]
    assert validate(folder) == []


def test_save_refuses_paths_leaving_the_folder(tmp_path):
    art = tiny_artset()
    art.mouth.drawings[0].file = "../evil.png"
    with pytest.raises(ArtSetError, match="leaves"):
        save_artset(art, tmp_path / "t")
    assert not (tmp_path / "evil.png").exists()


# --- the validator catches each problem on a broken copy ----------------------------------------
def test_bundled_copy_is_clean(bundled_copy):
    assert validate(bundled_copy) == []


def test_wrong_image_size(bundled_copy):
    rel = json.loads((bundled_copy / "artset.json").read_text())["parts"]["mouth"]["drawings"][1]["image"]
    im = Image.open(bundled_copy / rel)
    im.resize((im.width - 3, im.height)).save(bundled_copy / rel)
    msg = messages(bundled_copy)
    assert rel in msg and "mouth box" in msg


def test_unequal_line_counts(bundled_copy):
    edit_manifest(bundled_copy, lambda d: d["parts"]["eyes"]["drawings"][2]["lines"].pop())
    assert "control lines" in messages(bundled_copy)


def test_lines_outside_the_image(bundled_copy):
    def f(d):
        d["parts"]["mouth"]["drawings"][0]["lines"][3][2] = d["parts"]["mouth"]["box"][2] + 10
    edit_manifest(bundled_copy, f)
    msg = messages(bundled_copy)
    assert "line(s) 3 lie outside" in msg and "artset.json" in msg


def test_zero_length_line(bundled_copy):
    def f(d):
        ln = d["parts"]["mouth"]["drawings"][0]["lines"][0]
        ln[2], ln[3] = ln[0], ln[1]
    edit_manifest(bundled_copy, f)
    assert "shorter than" in messages(bundled_copy)


def test_missing_png(bundled_copy):
    rel = json.loads((bundled_copy / "artset.json").read_text())["parts"]["eyes"]["drawings"][0]["image"]
    (bundled_copy / rel).unlink()
    msg = messages(bundled_copy)
    assert rel in msg and "missing image" in msg


def test_unreadable_png(bundled_copy):
    rel = json.loads((bundled_copy / "artset.json").read_text())["heads"][0]
    (bundled_copy / rel).write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    msg = messages(bundled_copy)
    assert rel in msg and "unreadable" in msg


def test_not_a_png(bundled_copy):
    rel = json.loads((bundled_copy / "artset.json").read_text())["heads"][0]
    Image.open(bundled_copy / rel).convert("RGB").save(bundled_copy / rel, format="JPEG")
    assert "not a PNG" in messages(bundled_copy)


@pytest.mark.parametrize("bad", ["../outside.png", "/etc/passwd", "eyes/../../outside.png", "C:/x.png", "~/x.png"])
def test_path_leaving_the_folder(bundled_copy, bad):
    (bundled_copy.parent / "outside.png").write_bytes((bundled_copy / "head-1.png").read_bytes())
    edit_manifest(bundled_copy, lambda d: d["parts"]["mouth"]["drawings"][0].__setitem__("image", bad))
    msg = messages(bundled_copy)
    assert "leaves the art-set folder" in msg or "absolute" in msg
    with pytest.raises(ArtSetError) as e:
        load_artset(bundled_copy)
    assert "\n" not in str(e.value) and "artset.json" in str(e.value)


def test_symlink_leaving_the_folder(bundled_copy, tmp_path):
    outside = tmp_path / "secret.png"
    outside.write_bytes((bundled_copy / "head-1.png").read_bytes())
    (bundled_copy / "link.png").symlink_to(outside)
    edit_manifest(bundled_copy, lambda d: d["heads"].__setitem__(0, "link.png"))
    assert "symlink" in messages(bundled_copy)


def test_too_few_drawings(bundled_copy):
    edit_manifest(bundled_copy, lambda d: d["parts"]["eyes"].__setitem__("drawings", d["parts"]["eyes"]["drawings"][:2]))
    assert "at least 3" in messages(bundled_copy)


def _png_header_only(path: Path, w: int, h: int) -> None:
    """A PNG whose header claims w×h RGBA pixels, with a tiny (truncated) data stream."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b""))


@pytest.mark.parametrize("size", [(5000, 10), (60000, 60000)])
def test_oversized_image_refused_before_decoding(bundled_copy, size):
    rel = json.loads((bundled_copy / "artset.json").read_text())["parts"]["mouth"]["drawings"][0]["image"]
    _png_header_only(bundled_copy / rel, *size)
    t0 = time.perf_counter()
    msg = messages(bundled_copy)
    assert time.perf_counter() - t0 < 30  # a decoded 60000² image would need 14 GB; we never get there
    assert rel in msg and "refused" in msg
    with pytest.raises(ArtSetError, match="refused"):
        load_artset(bundled_copy)


def test_real_decompression_bomb_refused(tmp_path):
    art = tiny_artset()
    folder = save_artset(art, tmp_path / "b")
    big = Image.new("RGBA", (4200, 4200), (0, 0, 0, 0))  # compresses to a few kB, 70 MB decoded
    big.save(folder / "head-1.png")
    assert (folder / "head-1.png").stat().st_size < 200_000
    assert any("refused" in p.message for p in validate(folder))


def test_bad_json(bundled_copy):
    (bundled_copy / "artset.json").write_text('{"format": 1, "name": ')
    msg = messages(bundled_copy)
    assert "not valid JSON" in msg and "artset.json" in msg


def test_missing_keys(bundled_copy):
    edit_manifest(bundled_copy, lambda d: (d.pop("heads"), d.pop("canvas")))
    assert "missing key(s): canvas, heads" in messages(bundled_copy)


def test_missing_part(bundled_copy):
    edit_manifest(bundled_copy, lambda d: d["parts"].pop("mouth"))
    assert "missing part 'mouth'" in messages(bundled_copy)


@pytest.mark.parametrize("fmt", [3, 0, "1", True, None, 1.5])
def test_wrong_format_version(bundled_copy, fmt):
    edit_manifest(bundled_copy, lambda d: d.__setitem__("format", fmt))
    assert "not supported" in messages(bundled_copy)


def test_head_of_wrong_size(bundled_copy):
    Image.open(bundled_copy / "head-1.png").crop((0, 0, 300, 512)).save(bundled_copy / "head-1.png")
    msg = messages(bundled_copy)
    assert "head-1.png" in msg and "canvas" in msg


def test_head_without_alpha(bundled_copy):
    Image.open(bundled_copy / "head-2.png").convert("RGB").save(bundled_copy / "head-2.png")
    assert "no transparency" in messages(bundled_copy)


def test_box_outside_canvas_and_duplicate_names(bundled_copy):
    def f(d):
        d["parts"]["eyes"]["box"][0] = 500
        d["parts"]["mouth"]["drawings"][1]["name"] = d["parts"]["mouth"]["drawings"][0]["name"]
    edit_manifest(bundled_copy, f)
    msg = messages(bundled_copy)
    assert "does not fit inside" in msg and "two drawings are called" in msg


def test_not_a_folder(tmp_path):
    assert "missing manifest" in messages(tmp_path)
    assert "not a folder" in messages(tmp_path / "nope")
    with pytest.raises(ArtSetError):
        load_artset(tmp_path / "nope")


def test_non_strict_load_tolerates_line_problems(bundled_copy):
    edit_manifest(bundled_copy, lambda d: d["parts"]["eyes"]["drawings"][2]["lines"].pop())
    with pytest.raises(ArtSetError, match="control lines"):
        load_artset(bundled_copy)
    assert load_artset(bundled_copy, strict=False).eyes.drawings[2].lines.shape[1] == 4


# --- library -----------------------------------------------------------------------------------
def test_library_finds_bundled_and_user_sets(tmp_path, monkeypatch):
    monkeypatch.setenv("INKFACE_ART_DIR", str(tmp_path / "user"))
    assert user_dir() == tmp_path / "user"
    assert list_user() == []
    save_artset(tiny_artset(), tmp_path / "user" / "tiny-one")
    assert [n for n, _ in list_user()] == ["Tiny"]
    assert find_artset("tiny") == tmp_path / "user" / "tiny-one"
    assert find_artset("TINY-ONE") == tmp_path / "user" / "tiny-one"
    name, path = list_bundled()[0]
    assert path.parent == bundled_dir()
    assert find_artset(name.upper()) == path
    assert find_artset(path) == path and find_artset(path / "artset.json") == path
    assert len(list_all()) == len(list_bundled()) + 1
    with pytest.raises(ArtSetError, match="known:"):
        find_artset("no-such-character")
    with pytest.raises(ArtSetError, match="no artset.json"):
        find_artset(tmp_path)


def test_thumbnail(tiny):
    art = load_artset(tiny)
    th = thumbnail(art, 32)
    assert th.shape == (32, 32, 4) and th.dtype == np.uint8
    th = thumbnail(art, (40, 20))
    assert th.shape == (20, 40, 4) and th[..., 3].max() > 0


def test_bundled_thumbnail_shows_the_face():
    art = load_artset(first_bundled())
    th = thumbnail(art, 96)
    assert th.shape == (96, 96, 4)
    assert th[48, 48, 3] == 255  # the middle of the face is opaque: the holes are filled by the parts


# --- CLI ---------------------------------------------------------------------------------------
def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "art_sets", *args], capture_output=True, text=True, cwd=ROOT, timeout=120)


def test_cli_check_ok_and_broken(bundled_copy):
    r = run_cli("check", str(bundled_copy))
    assert r.returncode == 0 and r.stdout.startswith("OK: ")
    edit_manifest(bundled_copy, lambda d: d["parts"]["eyes"]["drawings"][2]["lines"].pop())
    (bundled_copy / "head-1.png").unlink()
    r = run_cli("check", str(bundled_copy))
    assert r.returncode == 1
    out = r.stdout.strip().splitlines()
    assert len(out) == 2 and all(": " in ln for ln in out)
    assert any(ln.startswith(str(bundled_copy / "head-1.png")) for ln in out)


def test_cli_errors_are_one_line(tmp_path):
    r = run_cli("sheet", str(tmp_path / "missing"), "--out", str(tmp_path / "x.png"))
    assert r.returncode == 2 and r.stderr.startswith("inkface: ") and len(r.stderr.strip().splitlines()) == 1


def test_cli_sheet_without_morph(tiny, tmp_path):
    out = tmp_path / "sheet.png"
    r = run_cli("sheet", str(tiny), "--out", str(out), "--no-morph")
    assert r.returncode == 0, r.stderr
    assert Image.open(out).size[0] > 100


def test_sheet_adds_the_blends_it_is_given(tiny):
    from art_sets.sheet import render_sheet

    art = load_artset(tiny)
    cell = np.zeros((40, 60, 4), np.uint8)
    cell[..., 0], cell[..., 3] = 200, 255
    with_b = render_sheet(art, [("some blends", [("a", cell), ("b", cell)])])
    without = render_sheet(art)
    assert with_b.height > without.height
    assert (np.asarray(with_b)[..., 0] == 200).sum() >= 2 * 40 * 60


def test_scan_returns_partial_results(bundled_copy):
    (bundled_copy / "head-1.png").unlink()
    art, problems = scan(bundled_copy)
    assert art is not None and len(problems) == 1 and len(art.heads) == len(json.loads((bundled_copy / "artset.json").read_text())["heads"]) - 1


def test_visible_box_edge(bundled_copy):
    data = json.loads((bundled_copy / "artset.json").read_text())
    x, y, w, h = data["parts"]["mouth"]["box"]
    im = np.asarray(Image.open(bundled_copy / "head-1.png")).copy()
    im[y:y + h, x:x + w, 3] = 0  # a hard hole the size of the box: its edge shows as a rectangle
    Image.fromarray(im).save(bundled_copy / "head-1.png")
    msg = messages(bundled_copy)
    assert "mouth box edge shows" in msg and "head-1.png" in msg


def test_saved_files_are_readable_by_others(tmp_path):
    import os
    import stat

    folder = save_artset(tiny_artset(), tmp_path / "perm")
    mode = stat.S_IMODE(os.stat(folder / "artset.json").st_mode)
    assert mode & stat.S_IRUSR and mode & stat.S_IWUSR and mode & stat.S_IRGRP == (0o666 & ~_current_umask() & stat.S_IRGRP)


def _current_umask() -> int:
    import os

    m = os.umask(0)
    os.umask(m)
    return m


_json = st.recursive(st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=True) | st.text(max_size=8),
                     lambda ch: st.lists(ch, max_size=4) | st.dictionaries(st.text(max_size=6), ch, max_size=4), max_leaves=12)
_paths = st.sampled_from([("format",), ("name",), ("canvas",), ("pivot",), ("heads",), ("heads", 0), ("parts",),
                          ("parts", "eyes"), ("parts", "eyes", "box"), ("parts", "eyes", "drawings"),
                          ("parts", "mouth", "drawings", 0), ("parts", "mouth", "drawings", 1, "lines"),
                          ("parts", "mouth", "drawings", 2, "image"), ("parts", "eyes", "drawings", 0, "lines", 0)])


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(path=_paths, value=_json)
def test_validator_never_crashes_on_odd_manifests(tmp_path_factory, path, value):
    folder = save_artset(tiny_artset(), tmp_path_factory.mktemp("fz") / "t")
    data = json.loads((folder / "artset.json").read_text())
    node = data
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    (folder / "artset.json").write_text(json.dumps(data))
    problems = validate(folder)  # must not raise
    assert all(isinstance(p.file, str) and "\n" not in p.message for p in problems)
    if problems:
        with pytest.raises(ArtSetError):
            load_artset(folder)


def test_sheet_of_a_set_whose_lines_do_not_correspond(tiny, tmp_path):
    edit_manifest(tiny, lambda d: d["parts"]["mouth"]["drawings"][1]["lines"].pop())
    out = tmp_path / "s.png"
    r = run_cli("sheet", str(tiny), "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert out.exists()
    r = run_cli("check", str(tiny))
    assert r.returncode == 1 and "control lines" in r.stdout


def test_an_absurd_format_value_is_named_briefly(tmp_path):
    """A manifest whose ``format`` is a huge value (a fuzzer's, a broken writer's) gets a one-line
    error of sensible length that still names the file."""
    import json as _json

    import pytest as _pytest

    from art_sets.io import ArtSetError, load_artset

    (tmp_path / "artset.json").write_text(_json.dumps(
        {"format": ["9" * 5000], "name": "x", "canvas": [64, 64], "heads": [], "parts": {}}))
    with _pytest.raises(ArtSetError) as e:
        load_artset(tmp_path)
    msg = str(e.value)
    assert "artset.json" in msg and "format" in msg and len(msg) < 300 and "\n" not in msg
