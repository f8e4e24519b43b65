"""PartMorpher: exact corners, opacity, continuity, agreement with the exact polymorph, detail blend."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks.bench_morph import MOUTHS, SKIN, make_mouth
from morph import beier_neely as bn
from morph.detail import detail_blend, high_pass_energy
from morph.polymorph import PartMorpher, blend_u8

W, H = 160, 96
NAMES = ["neutral", "ah", "smile", "oo"]


@pytest.fixture(scope="module")
def mouths():
    out = [make_mouth(W, H, *MOUTHS[n], seed=i) for i, n in enumerate(NAMES)]
    return [img for img, _ in out], [lines for _, lines in out]


@pytest.fixture(scope="module")
def opaque_mouths():
    out = [make_mouth(W, H, *MOUTHS[n], seed=i, bg=SKIN) for i, n in enumerate(NAMES)]
    return [img for img, _ in out], [lines for _, lines in out]


@pytest.fixture(scope="module")
def morpher(mouths):
    return PartMorpher(*mouths)


@pytest.fixture(scope="module")
def opaque_morpher(opaque_mouths):
    return PartMorpher(*opaque_mouths)


def test_tables_have_one_mesh_per_ordered_pair_and_alpha(morpher):
    assert morpher.tables.shape == (4, 4, 11, 31, 31, 2)
    assert np.abs(morpher.tables[:, :, 0]).max() < 1e-4  # α = 0 is the identity
    assert np.all(morpher.tables[np.arange(4), np.arange(4)] == 0)


def test_single_weight_returns_the_drawing_exactly(morpher, mouths):
    for k in range(4):
        others = [i for i in range(4) if i != k][:2]
        out = morpher.render((k, *others), (1.0, 0.0, 0.0))
        assert np.array_equal(out, bn.premultiply(mouths[0][k]))
        out = morpher.render((others[0], k, others[1]), (0.0, 1.0, 0.0))
        assert np.array_equal(out, bn.premultiply(mouths[0][k]))


@settings(max_examples=20, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3).filter(lambda w: sum(w) > 1e-3),
       st.permutations([0, 1, 2, 3]))
def test_weights_summing_to_one_keep_opaque_drawings_opaque(opaque_morpher, w, order):
    out = opaque_morpher.render(order[:3], w)
    assert out[:, :, 3].min() == 255
    assert np.all(out[:, :, :3] <= out[:, :, 3:4])


@settings(max_examples=15, deadline=None)
@given(st.lists(st.floats(0.05, 1.0), min_size=3, max_size=3), st.integers(0, 2))
def test_small_weight_change_gives_small_image_change(morpher, w, k):
    w = np.array(w) / np.sum(w)
    w2 = w.copy()
    w2[k] += 0.01
    w2 /= w2.sum()
    a = morpher.render((0, 1, 2), w).astype(np.float32)
    b = morpher.render((0, 1, 2), w2).astype(np.float32)
    d = np.abs(a - b)
    assert d.mean() < 0.5 and np.percentile(d, 99.5) < 16


def test_two_way_mesh_morph_matches_the_exact_morph(morpher, mouths):
    imgs, lines = mouths
    for wt in (0.3, 0.5, 0.8):
        mesh_out = morpher.render((0, 1, 2), (1 - wt, wt, 0.0)).astype(np.float32)
        exact = bn.polymorph_exact([imgs[0], imgs[1]], [lines[0], lines[1]], [1 - wt, wt]).astype(np.float32)
        assert np.abs(mesh_out - exact).mean() < 1.0


def test_three_way_mesh_morph_is_close_to_the_exact_morph(morpher, mouths):
    imgs, lines = mouths
    w = (0.4, 0.35, 0.25)
    mesh_out = morpher.render((0, 1, 2), w).astype(np.float32)
    exact = bn.polymorph_exact(imgs[:3], lines[:3], w).astype(np.float32)
    assert np.abs(mesh_out - exact).mean() < 2.0


def test_sum_of_two_way_meshes_targets_the_blended_lines(morpher, mouths):
    """The approximation's field carries each line of A to the weighted mean of the line sets."""
    _, lines = mouths
    w = (0.5, 0.3, 0.2)
    target = sum(wi * lines[i] for i, wi in zip(range(3), w))
    for ia, _, m in morpher.meshes((0, 1, 2), w):
        mx, my = morpher.grid.upsample(m)
        exact = bn.field_map(target, lines[ia], morpher.size)
        err = np.hypot(mx - exact[0], my - exact[1])
        assert err.mean() < 1.5


@settings(max_examples=25, deadline=None)
@given(st.permutations(range(4)), st.lists(st.floats(0.05, 1.0), min_size=3, max_size=3))
def test_meshes_are_the_vertices_plus_interpolated_two_way_tables(morpher, order, raw):
    """Each active drawing's mesh is V + D_AB(w_B) + D_AC(w_C), the tables read at those α."""
    idx = tuple(order[:3])
    w = np.array(raw) / sum(raw)
    for ia, wa, mesh in morpher.meshes(idx, w):
        want = morpher.vertices.astype(np.float64)
        for ib, wb in zip(idx, w):
            if ib != ia:
                want = want + morpher.displacement(ia, ib, float(wb))
        assert wa == pytest.approx(w[idx.index(ia)])
        np.testing.assert_allclose(mesh, want, atol=2e-3)


def test_duplicate_and_negative_weights_are_normalised(morpher):
    a = morpher.render((1, 1, 2), (0.3, 0.3, 0.4))
    b = morpher.render((1, 2, 0), (0.6, 0.4, 0.0))
    assert np.array_equal(a, b)
    c = morpher.render((1, 2, 0), (0.6, 0.4, -0.1))
    assert np.array_equal(b, c)


def test_bad_inputs_raise_value_errors(mouths):
    imgs, lines = mouths
    m = PartMorpher(imgs[:2], lines[:2], alpha_steps=3)
    with pytest.raises(ValueError, match="out of range"):
        m.render((0, 5, 1), (0.3, 0.3, 0.4))
    with pytest.raises(ValueError, match="positive sum"):
        m.render((0, 1, 0), (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="same number of control lines"):
        PartMorpher(imgs[:2], [lines[0], lines[1][:3]])
    with pytest.raises(ValueError, match="expected uint8"):
        PartMorpher([imgs[0], imgs[1][:50]], lines[:2])


def test_one_drawing_part_renders_it(mouths):
    imgs, lines = mouths
    m = PartMorpher(imgs[:1], lines[:1])
    assert np.array_equal(m.render((0, 0, 0), (0.2, 0.3, 0.5)), bn.premultiply(imgs[0]))


def test_jitter_moves_lines_and_zero_jitter_does_not(morpher):
    base = morpher.render((0, 1, 2), (0.5, 0.3, 0.2))
    zero = np.zeros((31, 31, 2), np.float32)
    assert np.array_equal(morpher.render((0, 1, 2), (0.5, 0.3, 0.2), jitter=zero), base)
    shaken = morpher.render((0, 1, 2), (0.5, 0.3, 0.2), jitter=zero + 1.5)
    assert np.abs(shaken.astype(int) - base.astype(int)).mean() > 0.5
    single = morpher.render((2, 0, 1), (1.0, 0.0, 0.0), jitter=zero + 1.5)
    assert not np.array_equal(single, morpher.render((2, 0, 1), (1.0, 0.0, 0.0)))


def test_detail_blend_is_sharper_than_the_plain_blend(morpher):
    w = (0.34, 0.33, 0.33)
    plain = morpher.render((0, 1, 3), w)
    crisp = morpher.render((0, 1, 3), w, detail=True)
    assert high_pass_energy(crisp) > 1.3 * high_pass_energy(plain)
    assert np.all(crisp[:, :, :3] <= crisp[:, :, 3:4])
    # with one dominant drawing the detail blend still looks like the blend at large scale
    assert np.abs(crisp.astype(int) - plain.astype(int)).mean() < 12


def test_detail_blend_of_identical_images_is_the_image():
    img = bn.premultiply(make_mouth(W, H, *MOUTHS["grin"])[0])
    assert np.abs(detail_blend([img, img], [0.5, 0.5]).astype(int) - img).max() <= 1


def test_blend_u8_is_the_weighted_sum():
    imgs = [np.full((3, 3, 4), v, np.uint8) for v in (250, 100, 10)]
    out = blend_u8(imgs, [0.2, 0.5, 0.3])
    assert (out == round(0.2 * 250 + 0.5 * 100 + 0.3 * 10)).all()


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3).filter(lambda w: sum(w) > 1e-6))
def test_blend_u8_keeps_full_alpha_for_any_weights(w):
    w = np.array(w) / np.sum(w)
    imgs = [np.full((2, 2, 4), 255, np.uint8), np.full((2, 2, 4), 255, np.uint8), np.full((2, 2, 4), 255, np.uint8)]
    assert (blend_u8(imgs, w) == 255).all()
    # the exact tie the ordering guards against: a partial sum of exactly k + 0.5
    tie = [0.5 / 255 * 3, 0.5 - 0.5 / 255 * 3, 0.5]
    assert (blend_u8(imgs, tie) == 255).all()


def test_exact_three_way_option_matches_the_exact_field(mouths):
    imgs, lines = mouths
    m = PartMorpher(imgs, lines, alpha_steps=3, exact_three_way=True)
    w = (0.5, 0.3, 0.2)
    target = sum(wi * lines[i] for i, wi in zip(range(3), w))
    for ia, _, mesh in m.meshes((0, 1, 2), w):
        mx, my = m.grid.upsample(mesh)
        ex, ey = bn.field_map(target, lines[ia], m.size)
        assert np.hypot(mx - ex, my - ey).mean() < 0.1
    exact = bn.polymorph_exact(imgs[:3], lines[:3], w).astype(np.float32)
    assert np.abs(m.render((0, 1, 2), w).astype(np.float32) - exact).mean() < 0.5


@pytest.fixture(scope="module")
def cross_morpher(mouths):
    return PartMorpher(*mouths, cross_terms=True)


def test_cross_terms_bring_three_way_meshes_close_to_the_exact_field(morpher, cross_morpher, mouths):
    _, lines = mouths
    for idx, w in (((0, 1, 2), (0.5, 0.3, 0.2)), ((1, 3, 2), (0.2, 0.4, 0.4)), ((3, 0, 1), (0.1, 0.45, 0.45))):
        target = sum(wi * lines[i] for i, wi in zip(idx, w))
        for (ia, _, plain), (ib, _, cross) in zip(morpher.meshes(idx, w), cross_morpher.meshes(idx, w)):
            assert ia == ib
            ex, ey = bn.field_map(target, lines[ia], morpher.size)
            errs = [np.hypot(mx - ex, my - ey) for mx, my in (morpher.grid.upsample(m) for m in (plain, cross))]
            assert errs[1].mean() < 0.5 * errs[0].mean()
            assert np.percentile(errs[1], 99) < np.percentile(errs[0], 99)


@settings(max_examples=20, deadline=None)
@given(st.permutations(range(4)), st.lists(st.floats(0.05, 1.0), min_size=2, max_size=2))
def test_cross_terms_leave_one_and_two_drawing_frames_as_they_were(morpher, cross_morpher, order, raw):
    idx = tuple(order[:2])
    np.testing.assert_array_equal(cross_morpher.render(idx, raw), morpher.render(idx, raw))
    np.testing.assert_array_equal(cross_morpher.render(idx[:1], raw[:1]), morpher.render(idx[:1], raw[:1]))
    np.testing.assert_array_equal(cross_morpher.tables, morpher.tables)


def test_cross_terms_are_zero_where_one_of_the_pair_has_no_weight(cross_morpher):
    """A three-way frame with a vanishing weight tends to the two-way frame (the term grows as w_B·w_C)."""
    near = cross_morpher.meshes((0, 1, 2), (0.6, 0.4 - 1e-7, 1e-7))
    two = cross_morpher.meshes((0, 1), (0.6, 0.4))
    for (ia, _, a), (ib, _, b) in zip(near, two):
        assert ia == ib
        np.testing.assert_allclose(a, b, atol=1e-3)


def test_parts_without_control_lines_cross_dissolve(mouths):
    imgs, _ = mouths
    m = PartMorpher(imgs[:2], [np.zeros((0, 4)), np.zeros((0, 4))], alpha_steps=3)
    got = m.render((0, 1), (0.5, 0.5)).astype(int)
    want = bn.blend_pm([bn.premultiply(imgs[0]), bn.premultiply(imgs[1])], [0.5, 0.5]).astype(int)
    assert np.abs(got - want).max() <= 1


@settings(max_examples=15, deadline=None)
@given(st.lists(st.integers(0, 3), min_size=1, max_size=3), st.lists(st.floats(0.05, 1.0), min_size=3, max_size=3))
def test_rendering_into_a_buffer_gives_the_same_image(morpher, idx, w):
    buf = np.full(morpher.pm[0].shape, 7, np.uint8)
    want = morpher.render(idx, w[: len(idx)])
    got = morpher.render(idx, w[: len(idx)], out=buf)
    assert got is buf
    assert np.array_equal(got, want)
