"""The four bundled characters: valid, complete, features inside the holes, lines on the features."""

from __future__ import annotations

import numpy as np
import pytest

from art_sets.authoring.ink import Surface, Textures
from art_sets.io import load_artset
from art_sets.library import list_bundled
from art_sets.validate import validate

BUNDLED = list_bundled()
IDS = [name for name, _ in BUNDLED]
EYES = ("open", "closed", "wide", "angry")
MOUTHS = ("neutral", "smile", "ah", "oo", "grin", "frown")


@pytest.fixture(scope="module", params=BUNDLED, ids=IDS)
def art(request):
    return load_artset(request.param[1])


def test_four_characters_in_four_styles():
    from art_sets.library import find_artset

    assert len(BUNDLED) >= 4
    styles = {load_artset(p).extra.get("style"): p for _, p in BUNDLED}
    assert {"straight", "wavy", "blue", "monster"} <= set(styles)
    for style, path in styles.items():
        assert find_artset(style.upper()) == path
    assert [load_artset(p).extra["style"] for _, p in BUNDLED][:4] == ["straight", "wavy", "blue", "monster"]


@pytest.mark.parametrize("path", [p for _, p in BUNDLED], ids=IDS)
def test_bundled_set_passes_the_validator(path):
    assert validate(path) == []
    size = sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    assert size < 1.5e6


def test_expected_drawings_and_heads(art):
    assert art.canvas == (512, 512)
    assert set(EYES) <= set(art.eyes.names())
    assert set(MOUTHS) <= set(art.mouth.names())
    assert len(art.heads) >= 2
    for part in (art.eyes, art.mouth):
        for d in part.drawings:
            assert d.image[..., 3].min() == 255, f"{part.name}/{d.name} should be opaque (drawn on the face colour)"


def test_heads_shimmer_but_keep_the_design(art):
    a, b = (h.astype(np.int16) for h in art.heads[:2])
    diff = np.abs(a - b).mean()
    assert 0.05 < diff < 12.0  # redrawn, not copied; the same design, not a different one


def test_features_show_through_the_holes(art):
    """Every control-line endpoint lies where every head is (nearly) transparent."""
    for part in (art.eyes, art.mouth):
        x, y = part.box[:2]
        for d in part.drawings:
            pts = d.lines.reshape(-1, 2) + (x, y)
            for k, head in enumerate(art.heads):
                a = head[pts[:, 1].astype(int), pts[:, 0].astype(int), 3]
                assert a.max() < 40, f"{part.name}/{d.name}: head {k + 1} covers a control line (alpha {a.max()})"


def test_line_order_means_the_same_feature(art):
    w = art.eyes.size[0]
    for d in art.eyes.drawings:
        L = d.lines
        assert L.shape == (8, 4)
        assert (L[:4, [0, 2]] < w / 2).all() and (L[4:, [0, 2]] > w / 2).all(), d.name  # left eye, right eye
        for e in (0, 4):
            upper, lower, brow = L[e, [1, 3]].mean(), L[e + 1, [1, 3]].mean(), L[e + 2, [1, 3]].mean()
            assert brow < upper <= lower, d.name
            inner_x = L[e + 3, 0]
            assert abs(L[e, 0] - inner_x) < abs(L[e, 2] - inner_x), f"{d.name}: lines run from the inner corner out"
    for d in art.mouth.drawings:
        L = d.lines
        assert L.shape == (6, 4)
        assert L[0, [1, 3]].mean() < L[1, [1, 3]].mean(), d.name  # upper lip above lower lip
        assert L[2, 0] < L[3, 0], d.name  # left corner left of the right one
        assert L[4, [1, 3]].mean() <= L[5, [1, 3]].mean(), d.name
        assert L[0, [1, 3]].mean() <= L[4, [1, 3]].mean() and L[5, [1, 3]].mean() <= L[1, [1, 3]].mean(), d.name


def test_lines_sit_on_drawn_features(art):
    """The upper-lid and lip-seam lines lie on ink/colour, not on bare face."""
    for part, rows in ((art.eyes, [0, 4]), (art.mouth, [4])):
        for d in part.drawings:
            bg = np.median(d.image[..., :3].reshape(-1, 3), axis=0)
            dist = np.linalg.norm(d.image[..., :3].astype(float) - bg, axis=2)
            for r in rows:
                x0, y0, x1, y1 = d.lines[r]
                ts = np.linspace(0, 1, 9)
                xs, ys = (x0 + (x1 - x0) * ts).astype(int), (y0 + (y1 - y0) * ts).astype(int)
                near = [dist[max(0, y - 6):y + 7, max(0, x - 2):x + 3].max() for x, y in zip(xs, ys)]
                assert np.median(near) > 40, f"{part.name}/{d.name} line {r} is on bare face"


def test_morph_is_cleaner_than_dissolve(art):
    bn = pytest.importorskip("morph.beier_neely")
    from benchmarks.bench_art_sets import ghosting
    from art_sets.sheet import cross_dissolve, to_straight

    pairs = ((art.mouth, "neutral", "ah"), (art.mouth, "neutral", "oo"), (art.mouth, "smile", "ah"),
             (art.eyes, "open", "wide"), (art.eyes, "open", "angry"), (art.eyes, "wide", "squint"))
    morphed = dissolved = 0
    for part, n0, n1 in pairs:
        a, b = part.drawings[part.index(n0)], part.drawings[part.index(n1)]
        m = to_straight(bn.polymorph_exact([a.image, b.image], [a.lines, b.lines], [0.5, 0.5]))
        morphed += ghosting(a.image, b.image, m)
        dissolved += ghosting(a.image, b.image, cross_dissolve(a.image, b.image))
    assert morphed < 0.75 * dissolved, (morphed, dissolved)


# --- the ink renderer -------------------------------------------------------------------------------
def _surface():
    return Surface((10, 20), (80, 40), Textures.make((128, 128), 3, seed=1), background=(1.0, 1.0, 1.0))


def test_stroke_tapers_and_is_deterministic():
    imgs = []
    for _ in range(2):
        s = _surface()
        s.stroke([(15, 40), (85, 40)], 6.0, (0, 0, 0), rng=np.random.default_rng(3), taper=(0.3, 0.3), tip=0.1)
        imgs.append(s.to_rgba(paper=False))
    np.testing.assert_array_equal(imgs[0], imgs[1])
    ink = 255 - imgs[0][..., 0].astype(int)
    col = lambda x: (ink[:, x - 10] > 128).sum()
    assert col(50) >= 5 and col(17) < col(50)
    assert imgs[0].shape == (40, 80, 4) and imgs[0][..., 3].min() == 255


def test_punch_makes_feathered_holes():
    s = _surface()
    m = s.mask([(30, 25), (70, 25), (70, 55), (30, 55)], blur=3)
    s.punch(m)
    a = s.to_rgba()[..., 3]
    assert a[20, 40] < 10 and a[0, 0] == 255 and 10 < a[20, 18] < 245


# --- feature geometry the drawings and their lines are generated from -------------------------------
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from art_sets.authoring.face import EyePose, MouthPose, eye_geom, lid_height_at, mouth_geom  # noqa: E402


@settings(max_examples=60, deadline=None)
@given(up=st.floats(0.1, 1.1), dn=st.floats(0.1, 0.9), closed=st.booleans(), brow=st.floats(-0.3, 0.5),
       tilt=st.floats(-0.5, 0.6), drop=st.floats(0, 0.5), lift=st.floats(0, 0.3), sgn=st.sampled_from([-1.0, 1.0]))
def test_eye_geometry_gives_usable_lines(up, dn, closed, brow, tilt, drop, lift, sgn):
    g = eye_geom((100.0, 100.0), 36.0, sgn, EyePose(up=up, dn=dn, closed=closed, brow=brow, brow_tilt=tilt,
                                                   lid_drop=drop, lower_lift=lift))
    L = g.lines()
    assert L.shape == (4, 4) and np.isfinite(L).all()
    assert (np.hypot(L[:, 2] - L[:, 0], L[:, 3] - L[:, 1]) > 5).all()
    assert (g.upper[:, 1] <= g.lower[:, 1] + 1e-9).all()  # lids never cross
    assert (g.brow[:, 1] < lid_height_at(g.upper, g.brow[:, 0])).all()  # the brow stays above the lid


@settings(max_examples=60, deadline=None)
@given(hw=st.floats(0.4, 1.4), smile=st.floats(-0.4, 0.5), open_=st.floats(0, 1.1), rnd=st.floats(0, 1),
       up=st.floats(0.2, 0.5))
def test_mouth_geometry_gives_usable_lines(hw, smile, open_, rnd, up):
    g = mouth_geom((100.0, 100.0), 40.0, MouthPose(hw=hw, smile=smile, open=open_, round=rnd, up_ratio=up))
    L = g.lines()
    assert L.shape == (6, 4) and np.isfinite(L).all()
    assert (np.hypot(L[:, 2] - L[:, 0], L[:, 3] - L[:, 1]) > 1).all()
    assert (g.outer_up[:, 1] <= g.inner_up[:, 1] + 1e-9).all() and (g.inner_up[:, 1] <= g.inner_dn[:, 1] + 1e-9).all()
    assert (g.inner_dn[:, 1] <= g.outer_dn[:, 1] + 1e-9).all()


def test_no_drawn_feature_is_covered_by_the_head(art):
    """Every inked/coloured pixel of every drawing falls where the heads are (nearly) see-through."""
    for part in (art.eyes, art.mouth):
        x, y, w, h = part.box
        for d in part.drawings:
            bg = np.median(d.image[..., :3].reshape(-1, 3), axis=0)
            feature = np.linalg.norm(d.image[..., :3].astype(float) - bg, axis=2) > 40
            for k, head in enumerate(art.heads):
                covered = head[y:y + h, x:x + w, 3][feature]
                assert covered.max() < 100, f"{part.name}/{d.name} under head {k + 1}: alpha {covered.max()}"
