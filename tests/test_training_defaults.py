"""Automatic default training against the synthetic performer, for every bundled art set."""

import numpy as np
import pytest

from art_sets.io import load_artset
from art_sets.library import list_bundled
from tracker.synthetic import EXPRESSIONS, FaceState, face_truth
from training.defaults import default_session, expression_for
from training.diagnostics import report

BUNDLED = list_bundled()


def fake_artset(mouths, eyes=("open", "closed")):
    from art_sets.model import ArtSet, Drawing, Part

    def part(pname, names):
        img = np.zeros((8, 10, 4), np.uint8)
        return Part(pname, (0, 0, 10, 8), [Drawing(n, img, np.zeros((1, 4))) for n in names])

    return ArtSet("Fake", (32, 32), (16, 16), [np.zeros((32, 32, 4), np.uint8)],
                  {"eyes": part("eyes", eyes), "mouth": part("mouth", mouths)})


def test_expression_names():
    assert expression_for("mouth", "smile") == "smile"
    assert expression_for("mouth", "Ah") == "ah"
    assert expression_for("eyes", "open") == "neutral"
    assert expression_for("eyes", "closed") == "eyes_closed"
    assert expression_for("mouth", "yell") is None
    assert all(expression_for("mouth", n) in EXPRESSIONS for n in ["neutral", "smile", "ah", "oo", "grin", "frown", "ee"])
    assert all(expression_for("eyes", n) in EXPRESSIONS for n in ["open", "closed", "wide", "angry", "squint"])


@pytest.mark.parametrize("name,folder", BUNDLED, ids=[n for n, _ in BUNDLED])
def test_default_session_pairs_every_named_drawing(name, folder):
    art = load_artset(folder)
    s = default_session(art)
    s.check(art)
    assert s.features is not None and s.reference_track is not None and len(s.reference_track) > 100
    maps = s.fit(art)
    base = FaceState()
    for part in ("eyes", "mouth"):
        names = art.parts[part].names()
        paired = {p.drawing for p in s.pairs_of(part)}
        for n in names:
            expr = expression_for(part, n)
            assert (n in paired) == (expr is not None)
            if expr is None:
                continue
            idx, w = maps[part].weights(s.features.part(part, face_truth(base.with_expression(expr))))
            assert names[idx[0]] == n and w[0] == pytest.approx(1.0, abs=1e-6)
    rep = report(s, art)
    assert 0 <= rep["mouth"]["coverage"].outside_share <= 1


def test_unknown_drawing_names_are_noted():
    art = fake_artset(mouths=["neutral", "smile", "yell"])
    s = default_session(art, reference=False)
    assert {p.drawing for p in s.pairs_of("mouth")} == {"neutral", "smile"}
    assert any("yell" in n for n in s.notes)


def test_thumbnails_are_synthetic_frames():
    s = default_session(fake_artset(mouths=["ah"], eyes=["open"]), thumbnails=True, reference=False)
    assert all(p.thumbnail is not None and p.thumbnail.ndim == 3 for p in s.pairs)
    assert np.ptp(s.pairs[0].thumbnail) > 0
