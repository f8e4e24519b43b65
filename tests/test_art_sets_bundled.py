"""The four bundled characters: valid, complete, features inside the holes, lines on the features."""

from __future__ import annotations

import numpy as np
import pytest

from art_sets.authoring.face import BAND_U, BROW_U, FOLD_U, LID_U, LIP_INNER_U, LIP_OUTER_U
from art_sets.authoring.ink import Surface, Textures, on_curve
from art_sets.io import load_artset
from art_sets.library import list_bundled
from art_sets.validate import validate

BUNDLED = list_bundled()
IDS = [name for name, _ in BUNDLED]
EYES = ("open", "closed", "wide", "angry")
MOUTHS = ("neutral", "smile", "ah", "oo", "grin", "frown")
N_LID, N_BAND, N_BROW, N_FOLD = len(LID_U) - 1, len(BAND_U) - 1, len(BROW_U) - 1, len(FOLD_U) - 1
PER_EYE = N_LID + N_BAND + N_BROW + 2 * N_FOLD  # upper-lid layer (the drawing's lines), per eye
N_INNER, N_OUTER = len(LIP_INNER_U) - 1, len(LIP_OUTER_U) - 1


def inked_lines(part, d):
    """The drawing's lines that run along ink: the upper lids and brows; the upper lip's inner edge."""
    if part.name == "eyes":
        rows = [e * PER_EYE + i for e in (0, 1) for i in list(range(N_LID)) + list(range(N_LID + N_BAND, N_LID + N_BAND + N_BROW))]
    else:
        rows = list(range(N_INNER))
    return d.lines[rows]


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
            pts = inked_lines(part, d).reshape(-1, 2) + (x, y)
            for k, head in enumerate(art.heads):
                a = head[pts[:, 1].astype(int), pts[:, 0].astype(int), 3]
                assert a.max() < 40, f"{part.name}/{d.name}: head {k + 1} covers a control line (alpha {a.max()})"


_corner_ref: dict = {}


def test_line_order_means_the_same_feature(art):
    w = art.eyes.size[0]
    for d in art.eyes.drawings:
        L = d.lines
        assert L.shape == (2 * PER_EYE, 4)
        left, right = L[:PER_EYE], L[PER_EYE:]
        assert (left[:, [0, 2]] < w / 2).all() and (right[:, [0, 2]] > w / 2).all(), d.name  # left eye, right eye
        for eye, low in ((left, d.layers[1].lines[: len(d.layers[1].lines) // 2]), (right, d.layers[1].lines[len(d.layers[1].lines) // 2:])):
            lid, band = eye[:N_LID], eye[N_LID:N_LID + N_BAND]
            brow = eye[N_LID + N_BAND:N_LID + N_BAND + N_BROW]
            under, over = eye[-2 * N_FOLD:-N_FOLD], eye[-N_FOLD:]
            y = lambda ls: ls[:, [1, 3]].mean()
            assert y(over) < y(brow) < y(under) < y(band) < y(lid) <= y(low[:N_LID]) + 1e-6, d.name
            assert np.allclose(lid[1:, :2], lid[:-1, 2:]), "the lid's chords join end to end"
            inner = lid[0, :2]
            assert np.hypot(*(low[0, :2] - inner)) < 2.0, "both lids start at the inner corner (a closed eye's lower lid 1.5 px under it)"
    for d in art.mouth.drawings:
        up, low = d.lines, d.layers[1].lines
        inner_up, inner_dn = up[:N_INNER], low[:N_INNER]
        assert inner_up[0, 0] < inner_up[-1, 2], d.name  # left to right
        assert np.allclose(inner_up[0, :2], inner_dn[0, :2]) and np.allclose(inner_up[-1, 2:], inner_dn[-1, 2:]), d.name
        assert inner_up[:, [1, 3]].mean() <= inner_dn[:, [1, 3]].mean() + 1e-6, d.name  # upper lip above lower lip
        outer_up, outer_dn = up[N_INNER + N_BAND:N_INNER + N_BAND + N_OUTER], low[N_INNER + N_BAND:N_INNER + N_BAND + N_OUTER]
        assert outer_up[:, [1, 3]].mean() < inner_up[:, [1, 3]].mean() and outer_dn[:, [1, 3]].mean() > inner_dn[:, [1, 3]].mean()
        # the last lines of both lip layers cross just beyond each corner, the same shape in every mouth
        for lines in (up, low):
            corners = lines[-4:].reshape(2, 2, 4) - np.tile([inner_up[0, :2], inner_up[-1, 2:]], (1, 1, 2)).reshape(2, 1, 4)
            ref = _corner_ref.setdefault(art.name, corners)
            np.testing.assert_allclose(corners, ref, atol=0.03, err_msg=d.name)  # the manifest keeps 0.01 px


def test_lines_sit_on_drawn_features(art):
    """The upper-lid and lip-seam lines lie on ink/colour, not on bare face."""
    for part, rows in ((art.eyes, [1, 2, PER_EYE + 1, PER_EYE + 2]), (art.mouth, [1, 2])):
        for d in part.drawings:
            bg = np.median(d.image[..., :3].reshape(-1, 3), axis=0)
            dist = np.linalg.norm(d.image[..., :3].astype(float) - bg, axis=2)
            for r in rows:
                x0, y0, x1, y1 = d.lines[r]
                ts = np.linspace(0, 1, 9)
                xs, ys = (x0 + (x1 - x0) * ts).astype(int), (y0 + (y1 - y0) * ts).astype(int)
                near = [dist[max(0, y - 6):y + 7, max(0, x - 2):x + 3].max() for x, y in zip(xs, ys)]
                assert np.median(near) > 40, f"{part.name}/{d.name} line {r} is on bare face"


def test_blends_are_much_cleaner_than_dissolves(art):
    """The renderer's halfway blends of a few telling pairs leave a fraction of a cross-dissolve's
    stray half-strength ink (``python -m benchmarks`` measures every pair and three-way blends)."""
    from benchmarks.bench_art_sets import ghosting
    from morph.compositor import to_straight
    from morph.contact import cross_dissolve
    from morph.renderer import CharacterRenderer

    r = CharacterRenderer(art, alpha_steps=6)
    pairs = ((art.mouth, "neutral", "ah"), (art.mouth, "smile", "oo"), (art.mouth, "frown", "grin"),
             (art.eyes, "open", "closed"), (art.eyes, "wide", "angry"), (art.eyes, "closed", "squint"))
    totals = {"eyes": [0, 0], "mouth": [0, 0]}
    for part, n0, n1 in pairs:
        i, j = part.index(n0), part.index(n1)
        a, b = part.drawings[i].image, part.drawings[j].image
        blend = ghosting([a, b], to_straight(r.render_part(part.name, ((i, j), (0.5, 0.5)))))
        dissolve = ghosting([a, b], cross_dissolve(a, b))
        assert blend <= max(dissolve, 0) + 60, (part.name, n0, n1, blend, dissolve)
        totals[part.name][0] += blend
        totals[part.name][1] += dissolve
    for name, (blend, dissolve) in totals.items():
        assert blend < 0.25 * dissolve, (name, blend, dissolve)


def test_a_closing_eye_is_a_lid_over_an_eyeball(art):
    """Halfway between open and closed the eye shows white and iris at full strength under an
    opaque lid: no pixel mixes the lid's skin half and half with the white."""
    from morph.compositor import to_straight
    from morph.renderer import CharacterRenderer

    r = CharacterRenderer(art, alpha_steps=6)
    e = art.eyes
    i, j = e.index("open"), e.index("closed")
    half = to_straight(r.render_part("eyes", ((i, j), (0.5, 0.5))))[..., :3].astype(float)
    skin = np.median(e.drawings[j].image[..., :3].reshape(-1, 3), axis=0)
    white = e.drawings[i].layers[0].image[..., :3].reshape(-1, 3).astype(float)
    white = white[np.argmax(white.sum(1))]  # the eyeball's lightest colour
    span = np.linalg.norm(white - skin)
    if span < 60:
        pytest.skip("the eyeball is drawn on the face's own colour: a half-and-half mix would not show")
    mid = (skin + white) / 2
    near_mid = np.linalg.norm(half - mid, axis=2) < 0.15 * span
    assert near_mid.sum() < 0.002 * near_mid.size, near_mid.sum()


def test_the_head_fits_the_canvas_at_30_degrees_of_roll(art):
    """No part of any head leaves the canvas when it rolls ±30° about the pivot (nothing clips),
    so keeping it in frame never has to push it off its neck."""
    from morph.renderer import CharacterRenderer

    c = CharacterRenderer(art, alpha_steps=2).compositor
    hull = c._content_hull(above_pivot=False)
    for roll in (-30.0, 30.0):
        m = c.matrix((0, 0, roll))
        q = hull @ m[:, :2].T + m[:, 2]
        assert q[:, 0].min() >= -0.5 and q[:, 0].max() <= c.w + 0.5 and q[:, 1].min() >= -0.5, (roll, q.min(0), q.max(0))
        assert np.allclose(m, c.matrix.__func__(_no_limit(c), (0, 0, roll)))


def _no_limit(c):
    import copy

    d = copy.copy(c)
    d.keep_in_frame = False
    return d


def test_bodies_run_off_the_canvas_and_reach_under_the_chin(art):
    body = art.body
    assert body is not None and body.image.shape == (512, 512, 4)
    assert (body.image[-1, :, 3] == 255).mean() > 0.9  # clothes to the bottom edge
    chin = max(int(np.nonzero(h[:, 256, 3] > 200)[0].max()) for h in art.heads)
    neck = np.nonzero(body.image[:, 256, 3] == 255)[0]
    assert neck.min() < chin - 20  # the neck starts well under the jaw: a moving head shows no gap


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


def _grainy(shift=(0.0, 0.0), ref=None, bend=0.0):
    s = Surface((0, 0), (96, 64), Textures.make((128, 128), 3, seed=2, grain_contrast=1.0), grain_ref=ref)
    pts = np.array([(16.0, 30.0), (48.0, 30.0 - bend), (80.0, 30.0)]) + shift
    s.stroke(pts, 4.0, (0, 0, 0), grain=0.8, taper=(0, 0), tip=1.0)
    return s


def test_a_stroke_carries_the_grain_of_its_reference_stroke():
    """With ``grain_ref`` a stroke drawn elsewhere (as in another drawing of a part) has the grain of the
    reference stroke, moved with it; without, it takes the paper's grain at its own place."""
    ref = _grainy()
    moved, paper = _grainy((7.0, 5.0), ref.strokes), _grainy((7.0, 5.0))
    a = ref.a[:-15, :-21]  # shifted back by (7, 5) design px = (21, 15) surface px
    core = a > 0.05
    assert np.corrcoef(a[core], moved.a[15:, 21:][core])[0, 1] > 0.99
    assert abs(np.corrcoef(a[core], paper.a[15:, 21:][core])[0, 1]) < 0.5
    np.testing.assert_array_equal(_grainy(ref=ref.strokes).a, ref.a)  # the reference itself keeps the paper's grain
    bent = _grainy(ref=ref.strokes, bend=6.0)  # a stroke of another shape: grain carried along it, no holes
    assert bent.a.max() > 0.5 and len(bent.strokes) == 1


def test_on_curve_places_points_in_the_curves_frame():
    flat = np.array([(0.0, 10.0), (40.0, 10.0)])
    np.testing.assert_allclose(on_curve(flat, [0.25, 0.5], [3.0, 0.0], [0.0, 2.0]), [(10.0, 7.0), (22.0, 10.0)])
    arc = np.stack([np.cos(np.linspace(np.pi, 0, 200)) * 20, -np.sin(np.linspace(np.pi, 0, 200)) * 20], 1)  # over the top, left to right
    p = on_curve(arc, [0.0, 0.5, 1.0], 5.0)  # up = away from the centre of this arc
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 25.0, atol=0.1)


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
    for L in (g.upper_lines(), g.lower_lines()):
        assert np.isfinite(L).all() and (np.hypot(L[:, 2] - L[:, 0], L[:, 3] - L[:, 1]) > 1).all()
    assert (g.upper[:, 1] <= g.lower[:, 1] + 1e-9).all()  # lids never cross
    assert (g.brow[:, 1] < lid_height_at(g.upper, g.brow[:, 0])).all()  # the brow stays above the lid


@settings(max_examples=60, deadline=None)
@given(hw=st.floats(0.4, 1.4), smile=st.floats(-0.4, 0.5), open_=st.floats(0, 1.1), rnd=st.floats(0, 1),
       up=st.floats(0.2, 0.5))
def test_mouth_geometry_gives_usable_lines(hw, smile, open_, rnd, up):
    g = mouth_geom((100.0, 100.0), 40.0, MouthPose(hw=hw, smile=smile, open=open_, round=rnd, up_ratio=up))
    for L in (g.upper_lines(0.08), g.lower_lines(0.08, 0.3)):
        assert np.isfinite(L).all() and (np.hypot(L[:, 2] - L[:, 0], L[:, 3] - L[:, 1]) > 0.5).all()
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
