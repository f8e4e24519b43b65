"""Hostile JSON for every parser: a one-line error of the format's own type, or a valid object.

The fuzzers start from a valid file and damage it the ways people and programs do: a value
replaced by another type (strings and booleans where numbers go, huge, tiny, NaN, Infinity,
nested containers), keys removed or added, the text cut short, numbers of thousands of digits,
nesting thousands deep. The named cases are the ones found by hand in issue 15.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from art_sets.io import MAX_DRAWINGS, MAX_HEADS, MAX_LINES, MAX_SIDE, ArtSetError, load_artset, save_artset
from art_sets.model import ArtSet, Drawing, Part
from art_sets.validate import validate
from tracker import safe_json
from tracker.calibration import Calibration, CalibrationError, calibrate
from tracker.clicks import Clicks, ClicksError
from tracker.synthetic import FaceState, clicks_for, render_face
from training.features import FeatureSpace
from training.session import SessionError, TrainingSession

# INKFACE_FUZZ_EXAMPLES=5000 pytest tests/test_input_fuzz.py --hypothesis-show-statistics: a long run
FUZZ = settings(max_examples=int(os.environ.get("INKFACE_FUZZ_EXAMPLES", "120")), deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

GOOD_CLICKS = {"frame": 0, "left_pupil": [280, 210], "right_pupil": [360, 210], "left_brow": [280, 178],
               "right_brow": [360, 178], "mouth": [320, 292]}

# --------------------------------------------------------------------------- damage
_numbers = st.one_of(
    st.integers(-(10**6), 10**6), st.integers(10**18, 10**60), st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 1e308, -1e308, 5e-324, 2**31, 2**63, 0.5]),
)
_leaf = st.one_of(st.none(), st.booleans(), _numbers, st.text(max_size=12),
                  st.sampled_from(["320", "292.8", "", "NaN", "../x.png", "/etc/passwd", "x" * 300, "head-1.png"]))
_value = st.recursive(_leaf, lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=6), c, max_size=3),
                      max_leaves=8)
_RAW = ["none"] * 8 + ["truncate", "digits", "e400", "nan", "deep", "deep_value", "bom", "binary"]


def _nodes(doc, path=()):
    yield path, doc
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _nodes(v, path + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _nodes(v, path + (i,))


def _damage(data, doc) -> bytes:
    """A damaged copy of ``doc`` (a JSON value) as file bytes."""
    doc = json.loads(json.dumps(doc))
    for _ in range(data.draw(st.integers(0, 3), label="edits")):
        nodes = list(_nodes(doc))
        path, node = data.draw(st.sampled_from(nodes), label="node")
        action = data.draw(st.sampled_from(["replace", "delete", "add", "swap_type"]), label="action")
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        if not path:
            if action == "replace":
                doc = data.draw(_value)
            continue
        key = path[-1]
        if action == "replace":
            parent[key] = data.draw(_value, label="value")
        elif action == "delete":
            del parent[key]
        elif action == "add" and isinstance(node, (dict, list)):
            if isinstance(node, dict):
                node[data.draw(st.text(max_size=6))] = data.draw(_value)
            else:
                node.append(data.draw(_value))
        elif action == "swap_type":  # the number as a string, or True for 1
            if isinstance(node, (int, float)) and not isinstance(node, bool):
                parent[key] = data.draw(st.sampled_from([str(node), True, False, [node], {"v": node}]))
    text = json.dumps(doc, allow_nan=True)
    raw = data.draw(st.sampled_from(_RAW), label="raw")
    if raw == "truncate":
        text = text[: data.draw(st.integers(0, max(len(text) - 1, 0)))]
    elif raw == "digits":
        text = text.replace("0", "9" * data.draw(st.sampled_from([400, 5000])), 1)
    elif raw == "e400":
        text = text.replace("1", "1e400", 1)
    elif raw == "nan":
        text = text.replace("2", data.draw(st.sampled_from(["NaN", "Infinity", "-Infinity"])), 1)
    elif raw == "deep":
        n = data.draw(st.sampled_from([40, 900, 100_000]))
        text = "[" * n + text + "]" * n
    elif raw == "deep_value":
        n = data.draw(st.sampled_from([40, 100_000]))
        text = text.replace("[", "[" + "[" * n + "]" * n + ",", 1) if "[" in text else text
    elif raw == "bom":
        return b"\xef\xbb\xbf" + text.encode()
    elif raw == "binary":
        return text.encode()[: len(text) // 2] + b"\xff\xfe\x00" + text.encode()[len(text) // 2:]
    return text.encode()


def _copy_images(src: Path, dst: Path) -> None:
    """The PNGs of a saved document, so a damaged copy of its JSON finds its pictures."""
    for f in src.rglob("*.png"):
        t = dst / f.relative_to(src)
        t.parent.mkdir(parents=True, exist_ok=True)
        t.write_bytes(f.read_bytes())


def _edited(raw, edit) -> str:
    """``raw`` changed by ``edit``, as JSON text (an overflowing float as the literal 1e400)."""
    d = json.loads(json.dumps(raw))
    edit(d)
    return json.dumps(d).replace("Infinity", "1e400")


def _check_refuses(file: Path, text: str, load, error: type[Exception]) -> str:
    """``load(file)`` of ``text`` raises one line of ``error`` naming ``file``'s folder; its message."""
    file.write_text(text)
    with pytest.raises(error) as e:
        load(file)
    _assert_one_line(e.value, str(file.parent))
    return str(e.value)


def _refused(err: Exception, names: str) -> None:
    """In a fuzzer: the refusal is one line naming the file (counted in hypothesis' statistics)."""
    event(f"refused: {type(err).__name__}")
    _assert_one_line(err, names)


def _fuzz_load(data, folder: Path, doc, src: Path | None, file: str, load, error: type[Exception], what: str):
    """Write a damaged ``doc`` as ``folder/file`` (beside ``src``'s pictures) and ``load`` it:
    the object, or None after checking the refusal is one line of ``error`` naming the folder."""
    if src is not None:
        _copy_images(src, folder)
    (folder / file).write_bytes(_damage(data, doc))
    try:
        obj = load(folder / file)
    except error as e:
        _refused(e, str(folder))
        return None
    event(f"loaded a valid {what}")
    return obj


def _assert_one_line(err: Exception, names: str) -> None:
    msg = str(err)
    assert msg and "\n" not in msg, repr(msg)
    assert names in msg, f"{names!r} not in {msg!r}"
    assert len(msg) < 2000, len(msg)


# --------------------------------------------------------------------------- the JSON layer
@pytest.mark.parametrize("text, words", [
    ("[" * 100_000 + "]" * 100_000, "nested deeper"),
    ("[" * 40 + "]" * 40, "nested deeper"),
    ("1" * 5000, "5000 characters"),
    ("1" * 400, "400 characters"),
    ("[1e400]", "out of range"),
    ('{"frame": NaN}', "NaN"),
    ('{"frame": -Infinity}', "-Infinity"),
    ('{"a": ', "line 1 column 7"),
    (b"\xff\xfe", "not UTF-8"),
])
def test_parse_refuses_with_one_line(text, words):
    with pytest.raises(safe_json.JSONInputError) as e:
        safe_json.parse(text, "user.json")
    _assert_one_line(e.value, "user.json")
    assert words in str(e.value)


def test_parse_keeps_what_is_fine():
    assert safe_json.parse(b'\xef\xbb\xbf{"a": [1, 2.5, -3e2, "x", null, true]}', "f") == {"a": [1, 2.5, -300.0, "x", None, True]}
    assert math.isnan(safe_json.parse("[NaN]", "f", allow_nan=True)[0])
    with pytest.raises(safe_json.JSONInputError):
        safe_json.parse("[Infinity]", "f", allow_nan=True)


def test_read_refuses_big_files_and_folders(tmp_path):
    big = tmp_path / "big.json"
    big.write_bytes(b" " * 2048)
    with pytest.raises(safe_json.JSONInputError, match="larger than"):
        safe_json.read(big, max_bytes=1024)
    with pytest.raises(safe_json.JSONInputError, match="it is a folder"):
        safe_json.read(tmp_path)
    with pytest.raises(safe_json.JSONInputError, match="cannot read"):
        safe_json.read(tmp_path / ("x" * 300 + ".json"))


@pytest.mark.parametrize("v", ["320", True, False, None, [1], math.nan, math.inf, 10**400, 1e308])
def test_number_checks_are_exact(v):
    with pytest.raises(safe_json.JSONInputError) as e:
        safe_json.number(v, "f.json: 'x'")
    _assert_one_line(e.value, "f.json: 'x'")


def test_checkers_take_numpy_numbers_from_python_callers():
    assert safe_json.number(np.float32(2.5), "x") == 2.5
    assert safe_json.integer(np.int64(3), "x") == 3 and safe_json.integer(4.0, "x") == 4
    assert safe_json.numbers((1, np.float64(2)), "x", 2) == (1.0, 2.0)
    for bad in (np.bool_(True), 2.5, "3"):
        with pytest.raises(safe_json.JSONInputError):
            safe_json.integer(bad, "x")


# --------------------------------------------------------------------------- clicks
@pytest.mark.parametrize("change", [
    {"left_pupil": ["320", "292.8"]}, {"mouth": [True, False]}, {"frame": True}, {"frame": "0"},
    {"frame": math.nan}, {"frame": math.inf}, {"mouth": [1e308, 5]}, {"frame": 10**400},
])
def test_clicks_refuse_strings_booleans_and_non_finite(change):
    with pytest.raises(ClicksError) as e:
        Clicks.from_dict({**GOOD_CLICKS, **change}, where="c.json")
    _assert_one_line(e.value, "c.json")


@pytest.mark.parametrize("text", ['{"frame": NaN, "left_pupil": [1, 2]}', '{"frame": Infinity}',
                                  "[" * 100_000, '{"frame": ' + "9" * 5000 + "}", '{"frame": 1e400}'])
def test_clicks_file_refusals_name_the_file(tmp_path, text):
    p = tmp_path / "CLICKS.json"
    p.write_text(text)
    with pytest.raises(ClicksError) as e:
        Clicks.load(p)
    _assert_one_line(e.value, str(p))


@FUZZ
@given(data=st.data())
def test_fuzz_clicks(tmp_path, data):
    c = _fuzz_load(data, tmp_path, GOOD_CLICKS, None, "clicks.json", Clicks.load, ClicksError, "clicks file")
    if c is not None:
        assert all(math.isfinite(v) for pt in c.points().values() for v in pt) and isinstance(c.frame, int)


# --------------------------------------------------------------------------- sessions
def _session_folder(tmp_path: Path) -> Path:
    s = TrainingSession("Fuzz", FeatureSpace.from_values(80.0, [320, 240, 0, 12, 12, 30, 30, 64, 10, 12]),
                        calibration_ref="cal.json", reference_clip="clip.mp4", autosave=False)
    rng = np.random.default_rng(0)
    for j, (part, name) in enumerate([("mouth", "smile"), ("eyes", "open"), ("mouth", "ah")]):
        s.add_pair(part, name, [320, 240, 0, 12, 12, 30, 30, 64 + j, 10, 12], frame=j, image=rng.integers(0, 255, (30, 40, 3), dtype=np.uint8))
    s.add_blend_pair("mouth", {"smile": 0.5, "ah": 0.5}, [320, 240, 0, 12, 12, 30, 30, 70, 10, 12], frame=5)
    s.set_reference("clip.mp4", np.array([[320, 240, 0, 12, 12, 30, 30, 64, 10, 12], [np.nan] * 10]))
    s.notes = ["first try"]
    s.save(tmp_path / "sess")
    return tmp_path / "sess"


@pytest.fixture(scope="module")
def session_doc(tmp_path_factory):
    folder = _session_folder(tmp_path_factory.mktemp("s"))
    return folder, json.loads((folder / "session.json").read_text())


def test_session_with_a_lost_frame_round_trips(session_doc):
    folder, raw = session_doc
    assert raw["reference_track"][1] == [None] * 10  # written as null, not as a bare NaN
    s = TrainingSession.load(folder)
    assert np.isnan(s.reference_track[1]).all() and len(s.pairs) == 4 and s.pairs[0].thumbnail is not None
    (folder / "session.json").write_text(json.dumps(raw).replace("null, null, null, null, null, null, null, null, null, null", ", ".join(["NaN"] * 10)))
    assert np.isnan(TrainingSession.load(folder).reference_track[1]).all()  # as older versions wrote it


@pytest.mark.parametrize("edit", [
    lambda d: d["pairs"][0]["values"].__setitem__("mid_x", "320"),
    lambda d: d["pairs"][0]["values"].__setitem__("mid_x", True),
    lambda d: d["pairs"][0].__setitem__("frame", math.nan),
    lambda d: d["pairs"][3]["blend"].__setitem__("smile", "0.5"),
    lambda d: d.__setitem__("format", True),
    lambda d: d["calibration"].__setitem__("ipd", 1e308),
])
def test_session_refuses_wrong_types(tmp_path, session_doc, edit):
    _check_refuses(tmp_path / "session.json", _edited(session_doc[1], edit), TrainingSession.load, SessionError)


@FUZZ
@given(data=st.data())
def test_fuzz_session(tmp_path_factory, session_doc, data):
    src, raw = session_doc
    s = _fuzz_load(data, tmp_path_factory.mktemp("fz"), raw, src, "session.json", TrainingSession.load, SessionError, "session")
    for p in s.pairs if s is not None else []:
        assert p.part in ("eyes", "mouth") and all(math.isfinite(v) for v in p.values)
        assert p.blend is None or all(math.isfinite(w) and w >= 0 for w in p.blend.values())


# --------------------------------------------------------------------------- calibrations
@pytest.fixture(scope="module")
def calibration_doc(tmp_path_factory):
    base = FaceState(cx=320.0, cy=210.0, ipd=80.0)
    frame, _ = render_face(base)
    folder = tmp_path_factory.mktemp("cal")
    calibrate(frame, Clicks.from_dict(clicks_for(base))).save(folder / "me.json")
    return folder, json.loads((folder / "me.json").read_text())


@pytest.mark.parametrize("edit", [
    lambda d: d.__setitem__("ipd", "80"),
    lambda d: d.__setitem__("ipd", True),
    lambda d: d.__setitem__("frame_size", [640.5, 480]),
    lambda d: d["classifiers"]["lip"].__setitem__("gate", "1"),
    lambda d: d["classifiers"]["eye"]["target"]["means"][0].__setitem__(1, "0.3"),
    lambda d: d.__setitem__("eye_templates", ["../../etc/passwd", "x.png"]),
    lambda d: d["clicks"].__setitem__("mouth", ["320", "292"]),
    lambda d: d["neutral"].__setitem__("mouth_width", "64"),
    lambda d: d.__setitem__("lip_axis", [1e400, 0, 0]),
])
def test_calibration_refuses_wrong_types(tmp_path, calibration_doc, edit):
    src, raw = calibration_doc
    _copy_images(src, tmp_path)
    _check_refuses(tmp_path / "me.json", _edited(raw, edit), Calibration.load, CalibrationError)


@FUZZ
@given(data=st.data())
def test_fuzz_calibration(tmp_path_factory, calibration_doc, data):
    src, raw = calibration_doc
    cal = _fuzz_load(data, tmp_path_factory.mktemp("fz"), raw, src, "me.json", Calibration.load, CalibrationError, "calibration")
    if cal is not None:
        assert math.isfinite(cal.ipd) and cal.pupil.table.dtype == np.uint8 and len(cal.eye_templates) == 2


# --------------------------------------------------------------------------- art sets
def _small_set(n_mouths: int = 3, lines: int = 2, canvas: int = 64, heads: int = 2) -> ArtSet:
    rng = np.random.default_rng(1)

    def part(name, box, n):
        w, h = box[2], box[3]
        ls = np.array([[1.0 + (i % 4), 1.0 + i // 4 % 3, w - 1.5, h / 2] for i in range(lines)])
        return Part(name, box, [Drawing(f"d{i}", rng.integers(0, 256, (h, w, 4), dtype=np.uint8), ls, f"{name}/d{i}.png")
                                for i in range(n)])

    hs = []
    for _ in range(heads):
        hd = rng.integers(0, 256, (canvas, canvas, 4), dtype=np.uint8)
        hd[..., 3] = 255
        hd[13:23, 11:53, 3] = 0
        hs.append(hd)
    return ArtSet("Fuzz", (canvas, canvas), (32.0, 40.0), hs,
                  {"eyes": part("eyes", (8, 10, 48, 16), 3), "mouth": part("mouth", (20, 36, 24, 14), n_mouths)},
                  head_files=[f"head-{i + 1}.png" for i in range(heads)])


@pytest.fixture(scope="module")
def artset_doc(tmp_path_factory):
    folder = save_artset(_small_set(), tmp_path_factory.mktemp("a") / "set")
    return folder, json.loads((folder / "artset.json").read_text())


@FUZZ
@given(data=st.data())
def test_fuzz_artset_manifest(tmp_path_factory, artset_doc, data):
    src, raw = artset_doc
    strict = data.draw(st.booleans(), label="strict")

    def load(manifest: Path):
        assert all("\n" not in str(p) for p in validate(manifest.parent))  # the validator never raises either
        return load_artset(manifest.parent, strict=strict)

    art = _fuzz_load(data, tmp_path_factory.mktemp("fz"), raw, src, "artset.json", load, ArtSetError, "art set")
    if art is None:
        return
    assert all(math.isfinite(v) and abs(v) <= 1e6 for v in art.pivot)
    for p in art.parts.values():
        assert len(p.drawings) <= MAX_DRAWINGS and all(np.isfinite(d.lines).all() for d in p.drawings)


@pytest.mark.parametrize("edit, words", [
    (lambda d: d.__setitem__("pivot", [1e308, 5]), "pivot"),
    (lambda d: d.__setitem__("pivot", ["32", 40]), "pivot"),
    (lambda d: d.__setitem__("canvas", [True, 64]), "canvas"),
    (lambda d: d["parts"]["mouth"]["drawings"][0].__setitem__("lines", [[1, 1, "20", 7]]), "lines"),
    (lambda d: d["parts"]["mouth"]["drawings"][0].__setitem__("image", "x" * 5000 + ".png"), "too long"),
    (lambda d: d["parts"]["mouth"]["drawings"][0].__setitem__("image", "mouth/" + "y" * 300 + ".png"), "too long"),
    (lambda d: d["parts"]["mouth"]["drawings"][0].__setitem__("image", "loop/d0.png"), "cannot be followed"),
])
def test_artset_bad_values_are_one_line_problems(tmp_path, artset_doc, edit, words):
    src, raw = artset_doc
    _copy_images(src, tmp_path)
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    (tmp_path / "artset.json").write_text(_edited(raw, edit))
    with pytest.raises(ArtSetError) as e:
        load_artset(tmp_path)
    _assert_one_line(e.value, str(tmp_path / "artset.json"))
    assert words in str(e.value)


def test_artset_deep_json_and_long_numbers(tmp_path, artset_doc):
    src, raw = artset_doc
    _copy_images(src, tmp_path)
    for text in ("[" * 100_000, json.dumps(raw).replace("64", "6" * 5000, 1), json.dumps(raw).replace("64", "1e400", 1)):
        (tmp_path / "artset.json").write_text(text)
        with pytest.raises(ArtSetError) as e:
            load_artset(tmp_path)
        _assert_one_line(e.value, "artset.json")


# --------------------------------------------------------------------------- art-set limits
def _problems(art: ArtSet, folder: Path) -> list[str]:
    return [p.message for p in validate(save_artset(art, folder))]


def test_a_set_at_every_count_limit_passes(tmp_path):
    art = _small_set(n_mouths=MAX_DRAWINGS, lines=MAX_LINES, heads=MAX_HEADS)
    assert _problems(art, tmp_path / "ok") == []


@pytest.mark.parametrize("kw, words", [
    ({"n_mouths": MAX_DRAWINGS + 1}, "drawings-per-part limit"),
    ({"lines": MAX_LINES + 1}, "lines-per-drawing limit"),
    ({"heads": MAX_HEADS + 1}, "heads limit"),
])
def test_over_a_count_limit_is_one_line_naming_it(tmp_path, kw, words):
    msgs = _problems(_small_set(**kw), tmp_path / "over")
    assert any(words in m for m in msgs), msgs
    with pytest.raises(ArtSetError, match=words):
        load_artset(tmp_path / "over")


def test_canvas_and_image_size_limits(tmp_path, artset_doc):
    src, raw = artset_doc
    _copy_images(src, tmp_path)
    d = json.loads(json.dumps(raw))
    d["canvas"] = [MAX_SIDE + 1, 64]
    (tmp_path / "artset.json").write_text(json.dumps(d))
    with pytest.raises(ArtSetError, match="canvas size limit"):
        load_artset(tmp_path)
    d = json.loads(json.dumps(raw))
    d["parts"]["mouth"]["box"] = [0, 0, 600, 600]
    d["canvas"] = [MAX_SIDE, MAX_SIDE]
    (tmp_path / "artset.json").write_text(json.dumps(d))
    assert any("pixel limit for a part" in str(p) for p in validate(tmp_path))
    from PIL import Image

    Image.new("RGBA", (MAX_SIDE + 100, 64)).save(tmp_path / "head-1.png")
    (tmp_path / "artset.json").write_text(json.dumps(raw))
    with pytest.raises(ArtSetError, match="limit; refused without decoding"):
        load_artset(tmp_path)


# --------------------------------------------------------------------------- the issue's inputs, everywhere
_HOSTILE = {"5000 digits": "1" * 5000, "400 digits": "1" * 400, "1e400": "1e400", "NaN": "NaN",
            "Infinity": "Infinity", "-Infinity": "-Infinity", "a string": '"320"', "a boolean": "true"}
_SET_NUMBER = {  # a number each format needs, where the hostile literal goes
    "clicks": lambda d: d.__setitem__("frame", "@"),
    "session": lambda d: d["pairs"][0]["values"].__setitem__("mid_x", "@"),
    "calibration": lambda d: d.__setitem__("ipd", "@"),
    "artset": lambda d: d["pivot"].__setitem__(0, "@"),
}


@pytest.mark.parametrize("kind", ["deep nesting", *_HOSTILE])
@pytest.mark.parametrize("fmt", ["clicks", "session", "calibration", "artset"])
def test_hostile_numbers_and_nesting_give_one_line_errors(tmp_path, fmt, kind, session_doc, calibration_doc, artset_doc):
    docs = {
        "clicks": (None, GOOD_CLICKS, "clicks.json", Clicks.load, ClicksError),
        "session": (*session_doc, "session.json", TrainingSession.load, SessionError),
        "calibration": (*calibration_doc, "me.json", Calibration.load, CalibrationError),
        "artset": (*artset_doc, "artset.json", lambda f: load_artset(f.parent), ArtSetError),
    }
    src, raw, name, load, error = docs[fmt]
    if src is not None:
        _copy_images(src, tmp_path)
    if kind == "deep nesting":
        text = "[" * 100_000 + "]" * 100_000
    else:
        text = _edited(raw, _SET_NUMBER[fmt]).replace('"@"', _HOSTILE[kind])
    msg = _check_refuses(tmp_path / name, text, load, error)
    assert "@" not in msg
