"""Training sessions: features, pairs, save/load round trip, refusals, diagnostics."""

import json

import numpy as np
import pytest

from art_sets.model import ArtSet, Drawing, Part
from tracker.params import FaceParams
from training.diagnostics import coverage, leave_one_out, report
from training.features import FeatureSpace
from training.session import SessionError, TrainingSession

MOUTHS = ["neutral", "smile", "ah", "oo", "frown"]
EYES = ["open", "closed", "wide", "angry"]

# ten values per expression (pixels): mid_x, mid_y, roll, lid l, lid r, brow l, brow r, width, upper, lower
NEUTRAL = np.array([320, 240, 0, 12, 12, 30, 30, 64, 10, 12], dtype=float)
DELTAS = {
    ("mouth", "neutral"): [0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
    ("mouth", "smile"): [0, 0, 0, 0, 0, 0, 0, 16, 0, 2],
    ("mouth", "ah"): [0, 0, 0, 0, 0, 0, 0, -6, 4, 28],
    ("mouth", "oo"): [0, 0, 0, 0, 0, 0, 0, -24, 3, 8],
    ("mouth", "frown"): [0, 0, 0, 0, 0, 0, 0, 4, -3, -2],
    ("eyes", "open"): [0] * 10,
    ("eyes", "closed"): [0, 0, 0, -12, -12, -3, -3, 0, 0, 0],
    ("eyes", "wide"): [0, 0, 0, 5, 5, 10, 10, 0, 0, 0],
    ("eyes", "angry"): [0, 0, 0, -3, -3, -8, -8, 0, 0, 0],
}
IPD = 80.0


def fake_artset(name="Fake", mouths=MOUTHS, eyes=EYES):
    def part(pname, names):
        img = np.zeros((8, 10, 4), np.uint8)
        return Part(pname, (0, 0, 10, 8), [Drawing(n, img, np.zeros((1, 4))) for n in names])

    head = np.zeros((32, 32, 4), np.uint8)
    return ArtSet(name, (32, 32), (16, 16), [head], {"eyes": part("eyes", eyes), "mouth": part("mouth", mouths)})


def values(part, name, noise=0.0, rng=None):
    v = NEUTRAL + np.array(DELTAS[(part, name)], dtype=float)
    if noise:
        v = v + rng.normal(scale=noise, size=10)
    return v


def make_session(path=None, frames_per_drawing=1, noise=0.0):
    rng = np.random.default_rng(0)
    s = TrainingSession("Fake", FeatureSpace.from_values(IPD, NEUTRAL), calibration_ref="cal.json", reference_clip="clip.mp4", path=path)
    frame = 0
    for (part, name) in DELTAS:
        for _ in range(frames_per_drawing):
            img = np.full((48, 64, 3), frame % 255, np.uint8)
            s.add_pair(part, name, values(part, name, noise, rng), frame=frame, image=img)
            frame += 1
    return s


def test_features_are_scale_free_and_relative_to_neutral():
    fs = FeatureSpace.from_values(IPD, NEUTRAL)
    np.testing.assert_allclose(fs.normalise(NEUTRAL), 0)
    v = values("mouth", "ah")
    # the same face at twice the distance scale: same features
    n2 = NEUTRAL.copy()
    n2[3:] *= 2
    fs2 = FeatureSpace.from_values(2 * IPD, n2)
    v2 = v.copy()
    v2[3:] = 2 * v[3:]
    np.testing.assert_allclose(fs.mouth(v), fs2.mouth(v2))
    assert fs.mouth(v).shape == (3,) and fs.eyes(v).shape == (4,)
    np.testing.assert_allclose(fs.denormalise(fs.normalise(v)), v)
    assert fs.pose(NEUTRAL + [8, 0, 5, 0, 0, 0, 0, 0, 0, 0]) == pytest.approx((0.1, 0.0, 5.0))
    assert FeatureSpace.from_dict(fs.to_dict()) == fs
    with pytest.raises(ValueError):
        FeatureSpace.from_values(0.0, NEUTRAL)


def test_estimated_feature_space_uses_the_first_frames():
    rows = [FaceParams.from_values(NEUTRAL, frame=i) for i in range(20)]
    fs = FeatureSpace.estimate(rows)
    np.testing.assert_allclose(fs.neutral, NEUTRAL)
    assert fs.ipd > 0


def test_round_trip(tmp_path):
    s = make_session(tmp_path / "sess")
    s.add_blend_pair("mouth", {"smile": 3, "ah": 1}, values("mouth", "smile"), frame=99, image=np.zeros((10, 10, 3), np.uint8))
    s.set_reference("clip.mp4", np.tile(NEUTRAL, (5, 1)))
    # autosaved on every change: the file on disk already has everything
    t = TrainingSession.load(tmp_path / "sess", artset=fake_artset())
    assert t.artset == "Fake" and t.calibration_ref == "cal.json" and t.reference_clip == "clip.mp4"
    assert t.features == s.features
    assert len(t.pairs) == len(s.pairs)
    for a, b in zip(s.pairs, t.pairs):
        assert (a.part, a.drawing, a.frame, a.blend) == (b.part, b.drawing, b.frame, b.blend)
        np.testing.assert_allclose(a.values, b.values, atol=1e-9)
        np.testing.assert_array_equal(a.thumbnail, b.thumbnail)
    assert t.pairs[-1].blend == {"smile": 0.75, "ah": 0.25}
    np.testing.assert_allclose(t.reference_track, s.reference_track)
    raw = json.loads((tmp_path / "sess" / "session.json").read_text())
    assert raw["format"] == 1
    assert len(list((tmp_path / "sess" / "thumbs").glob("*.png"))) == len(s.pairs)
    # removing a pair removes its thumbnail, and no temp files are left behind
    t.remove_pair(0)
    assert len(list((tmp_path / "sess" / "thumbs").glob("*.png"))) == len(s.pairs) - 1
    assert not list((tmp_path / "sess").rglob("*.tmp"))
    assert len(TrainingSession.load(tmp_path / "sess" / "session.json").pairs) == len(s.pairs) - 1


def test_refuses_another_art_set_and_missing_drawings(tmp_path):
    make_session(tmp_path / "s")
    with pytest.raises(SessionError, match="made for art set 'Fake', not 'Other'") as e:
        TrainingSession.load(tmp_path / "s", artset=fake_artset("Other"))
    assert "\n" not in str(e.value)
    with pytest.raises(SessionError, match="mouth/'oo'") as e:
        TrainingSession.load(tmp_path / "s", artset=fake_artset(mouths=["neutral", "smile", "ah", "frown"]))
    assert "\n" not in str(e.value)


def test_load_errors_are_one_line(tmp_path):
    with pytest.raises(SessionError, match="no training session"):
        TrainingSession.load(tmp_path / "nowhere")
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "session.json").write_text("{not json")
    with pytest.raises(SessionError, match="not valid JSON"):
        TrainingSession.load(tmp_path / "bad")
    (tmp_path / "bad" / "session.json").write_text(json.dumps({"format": 99, "artset": "x"}))
    with pytest.raises(SessionError, match="unsupported session format"):
        TrainingSession.load(tmp_path / "bad")
    (tmp_path / "bad" / "session.json").write_text(json.dumps({"format": 1, "artset": "x", "pairs": [{"part": "mouth"}]}))
    with pytest.raises(SessionError, match="malformed"):
        TrainingSession.load(tmp_path / "bad")


def test_pair_values_are_checked():
    s = TrainingSession("Fake")
    with pytest.raises(SessionError):
        s.add_pair("mouth", "smile", [1, 2, 3])
    with pytest.raises(SessionError):
        s.add_pair("mouth", "smile", np.full(10, np.nan))
    with pytest.raises(SessionError):
        s.add_pair("nose", "big", NEUTRAL)


@pytest.mark.parametrize("mapper", ["delaunay", "cardinal", "ridge", "convex"])
def test_fit_maps_each_training_frame_to_its_drawing(mapper):
    art = fake_artset()
    s = make_session()
    maps = s.fit(art, mapper=mapper)
    fs = s.feature_space()
    for (part, name) in DELTAS:
        idx, w = maps[part].weights(fs.part(part, values(part, name)))
        assert art.parts[part].names()[idx[0]] == name


def test_fit_skips_unpaired_parts_and_drawings():
    art = fake_artset()
    s = TrainingSession("Fake", FeatureSpace.from_values(IPD, NEUTRAL))
    for name in ["neutral", "ah", "oo"]:
        s.add_pair("mouth", name, values("mouth", name))
    maps = s.fit(art)
    assert maps["eyes"] is None
    names = art.mouth.names()
    idx, w = maps["mouth"].weights(s.feature_space().mouth(values("mouth", "smile")))
    assert all(names[i] in ("neutral", "ah", "oo") for i, a in zip(idx, w) if a > 0)


def test_leave_one_out_and_coverage():
    s = make_session(frames_per_drawing=3, noise=0.3)
    art = fake_artset()
    X, Y = s.training_data("mouth", art.mouth.names())
    y = Y.argmax(axis=1)
    loo = leave_one_out(X, y, art.mouth.names())
    assert len(loo) == len(X)
    assert all(not r.alone for r in loo)
    # distinct expressions, small noise: each frame is still recognised by the others
    assert max(r.weight_error for r in loo) < 0.5
    # a single frame per drawing: the held-out drawing cannot be chosen
    X1, Y1 = make_session().training_data("mouth", art.mouth.names())
    loo1 = leave_one_out(X1, Y1.argmax(axis=1), art.mouth.names())
    assert all(r.alone and r.weight_error == pytest.approx(1.0) for r in loo1)
    assert all(r.recon_error > 0 for r in loo1)

    # coverage: a reference clip with a far-out "yell" frame (wide open, wider than any drawing)
    track = np.array([values("mouth", n) for n in ["neutral", "smile", "ah", "oo"]])
    yell = NEUTRAL + [0, 0, 0, 0, 0, 0, 0, 30, 15, 60]
    track = np.vstack([track, yell, values("mouth", "smile")])
    s = make_session()
    s.set_reference("clip.mp4", track)
    rep = report(s, art)
    cov = rep["mouth"]["coverage"]
    assert cov.frames == 6
    assert cov.worst_frame == 4
    assert 0 < cov.outside_share <= 2 / 6
    assert "frame 4" in cov.suggestion and "\n" not in cov.suggestion
    assert rep["eyes"]["coverage"].outside_share == 0.0


def test_coverage_when_all_inside():
    from morph.expression_map import ExpressionMap

    pts = np.array([[0, 0], [1, 0], [0, 1.0]])
    c = coverage(ExpressionMap(pts), np.array([[0.2, 0.2], [0.1, 0.3]]), "mouth")
    assert c.outside_share == 0 and c.worst_frame == -1
