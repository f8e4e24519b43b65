"""CLICKS.json parsing and validation, and the colour classifiers."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tracker.clicks import Clicks, ClicksError
from tracker.colour_model import ColourClassifier, features, lut_index

GOOD = {
    "frame": 0,
    "left_pupil": [280, 210],
    "right_pupil": [360, 210],
    "left_brow": [280, 178],
    "right_brow": [360, 178],
    "mouth": [320, 292],
}


def test_round_trip(tmp_path):
    c = Clicks.from_dict(GOOD)
    p = tmp_path / "c.json"
    c.save(p)
    assert Clicks.load(p) == c
    assert json.loads(p.read_text())["mouth"] == [320.0, 292.0]
    assert c.ipd() == pytest.approx(80.0)


@pytest.mark.parametrize(
    "change, words",
    [
        ({"mouth": None}, "mouth"),
        ({"frame": -1}, "frame"),
        ({"frame": 1.5}, "frame"),
        ({"left_pupil": [1, 2, 3]}, "left_pupil"),
        ({"left_pupil": ["a", 2]}, "left_pupil"),
        ({"left_pupil": [400, 210]}, "left of"),
    ],
)
def test_bad_dicts_name_the_problem(change, words):
    d = dict(GOOD)
    for k, v in change.items():
        if v is None:
            d.pop(k)
        else:
            d[k] = v
    with pytest.raises(ClicksError) as e:
        Clicks.from_dict(d, where="x.json")
    msg = str(e.value)
    assert words in msg and "x.json" in msg and "\n" not in msg


def test_load_errors_are_one_line(tmp_path):
    with pytest.raises(ClicksError, match="cannot read"):
        Clicks.load(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ClicksError, match="not valid JSON"):
        Clicks.load(bad)


def test_points_outside_the_frame():
    c = Clicks.from_dict({**GOOD, "mouth": [320, 500]})
    with pytest.raises(ClicksError, match="outside the 640x480 frame"):
        c.check_inside((640, 480))
    Clicks.from_dict(GOOD).check_inside((640, 480))


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0, 600, allow_nan=False), min_size=10, max_size=10), st.integers(0, 10_000))
def test_dict_round_trip(vals, frame):
    d = {"frame": frame}
    keys = ["left_pupil", "right_pupil", "left_brow", "right_brow", "mouth"]
    for i, k in enumerate(keys):
        d[k] = [vals[2 * i], vals[2 * i + 1]]
    d["right_pupil"][0] = d["left_pupil"][0] + 10.0
    c = Clicks.from_dict(d)
    assert Clicks.from_dict(c.to_dict()) == c


# --------------------------------------------------------------------------- colour classifiers


def _samples(rng, colour, n, sigma=6.0):
    return np.clip(rng.normal(colour, sigma, (n, 3)), 0, 255)


def test_lut_index_matches_bit_layout():
    c = np.random.default_rng(0).integers(0, 256, (9, 7, 3), dtype=np.uint8)
    q = (c >> 2).astype(np.int32)
    assert np.array_equal(lut_index(c), (q[..., 0] << 12) | (q[..., 1] << 6) | q[..., 2])


@settings(max_examples=12, deadline=None)
@given(
    st.tuples(st.integers(30, 225), st.integers(30, 225), st.integers(30, 225)),
    st.tuples(st.integers(-60, 60), st.integers(-60, 60), st.integers(-60, 60)),
)
def test_classifier_separates_learned_colours(target, delta):
    """Any two colours that differ clearly are told apart (no colours are hard-coded). Clearly: by
    40 grey levels in a channel, and with their samples at least four spreads apart in the
    classifier's own features — those are normalised by brightness, so a camera's noise on a dark
    colour spreads them wide (dark blue (136, 30, 30) against (176, 30, 35), σ 6: 1.5 spreads)."""
    other = tuple(int(np.clip(t + d, 0, 255)) for t, d in zip(target, delta))
    if np.abs(np.subtract(target, other)).max() < 40:
        return
    rng = np.random.default_rng(1)
    a, b = _samples(rng, target, 300), _samples(rng, other, 300)
    fa, fb = features(a, 1.5), features(b, 1.5)
    if (np.abs(fa.mean(axis=0) - fb.mean(axis=0)) / np.maximum(fa.std(axis=0), fb.std(axis=0))).max() < 4.0:
        return
    clf = ColourClassifier(a, b, y_weight=1.5)
    img = np.array([[target, other]], dtype=np.uint8)
    assert clf.mask(img).tolist() == [[True, False]]


def test_colour_claimed_by_both_classes_is_background():
    rng = np.random.default_rng(2)
    shared = _samples(rng, (80, 80, 160), 200)
    lip = np.concatenate([_samples(rng, (70, 60, 190), 200), shared])
    skin = np.concatenate([_samples(rng, (130, 160, 210), 200), shared])
    clf = ColourClassifier(lip, skin)
    assert not clf.mask(np.array([[[80, 80, 160]]], np.uint8))[0, 0]
    assert clf.mask(np.array([[[70, 60, 190]]], np.uint8))[0, 0]


def test_classifier_round_trip_and_table_agree():
    rng = np.random.default_rng(3)
    clf = ColourClassifier(_samples(rng, (58, 52, 112), 300), _samples(rng, (48, 66, 104), 300), name="lip")
    back = ColourClassifier.from_dict(json.loads(json.dumps(clf.to_dict())))
    assert np.array_equal(back.table, clf.table)
    cols = rng.integers(0, 256, (500, 3))
    centre = (cols >> 2 << 2) + 1.5
    assert np.allclose(clf.prob_u8(cols.astype(np.uint8)) / 255.0, clf.score_colours(centre), atol=0.01)
