"""Layered parts (morph.layers) and the body under the head (morph.compositor)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from art_sets.model import ArtSet, Body, Drawing, Layer
from benchmarks.bench_morph import generated_artset
from morph.beier_neely import premultiply
from morph.compositor import Compositor, over_u8
from morph.layers import LayeredMorpher
from morph.polymorph import PartMorpher
from morph.renderer import CharacterRenderer


@pytest.fixture(scope="module")
def artset():
    return generated_artset()


def _one_layer(part):
    return [Drawing.from_layers(d.name, [Layer("all", d.image)], d.lines) for d in part.drawings]


def _weights(draw, n):
    k = draw(st.integers(1, 3))
    idx = draw(st.lists(st.integers(0, n - 1), min_size=k, max_size=k, unique=True))
    w = draw(st.lists(st.floats(0.05, 1.0), min_size=k, max_size=k))
    return tuple(idx), tuple(w)


@st.composite
def weights5(draw):
    return _weights(draw, 6)


@pytest.fixture(scope="module")
def one_layer_pair(artset):
    part = artset.mouth
    return PartMorpher([d.image for d in part.drawings], [d.lines for d in part.drawings], alpha_steps=6, cross_terms=True), \
        LayeredMorpher(_one_layer(part), alpha_steps=6)


@settings(max_examples=25, deadline=None)
@given(w=weights5())
def test_a_single_layer_sharing_the_lines_renders_exactly_as_one_picture(one_layer_pair, w):
    plain, layered = one_layer_pair
    np.testing.assert_array_equal(plain.render(*w), layered.render(*w))


def _stack_part(artset, top_alpha: int):
    """Each drawing of the mouth as: a static green under-layer (own lines), the drawing (shared
    lines), and a top layer with its own lines that is opaque blue where ``top_alpha`` says."""
    part = artset.mouth
    h, w = part.drawings[0].image.shape[:2]
    under = np.zeros((h, w, 4), np.uint8)
    under[..., 1], under[..., 3] = 200, 255
    out = []
    for k, d in enumerate(part.drawings):
        top = np.zeros((h, w, 4), np.uint8)
        top[10:30, 20 + 3 * k:60 + 3 * k] = (0, 0, 255, top_alpha)
        own = np.array([[20.0 + 3 * k, 10.0, 60.0 + 3 * k, 10.0], [20.0 + 3 * k, 30.0, 60.0 + 3 * k, 30.0]])
        out.append(Drawing.from_layers(d.name, [Layer("under", under, np.array([[0.0, 0, 5, 5]])), Layer("mid", d.image),
                                                Layer("top", top, own)], d.lines))
    return out


def test_static_layers_are_not_warped_and_tables_are_shared_per_line_set(artset):
    m = LayeredMorpher(_stack_part(artset, 255), alpha_steps=4)
    assert [ly.group for ly in m.layers] == [-1, 0, 1] and len(m.groups) == 2
    same = [Drawing.from_layers(d.name, [Layer("a", d.image), Layer("b", d.image[::-1].copy())], d.lines)
            for d in artset.mouth.drawings]
    m2 = LayeredMorpher(same, alpha_steps=4)
    assert [ly.group for ly in m2.layers] == [0, 0] and len(m2.groups) == 1


def test_an_opaque_top_layer_hides_what_is_under_it(artset):
    m = LayeredMorpher(_stack_part(artset, 255), alpha_steps=6)
    out = m.render((0, 1, 2), (0.3, 0.3, 0.4))
    # the top rectangle sits at the same place relative to its own lines in every drawing, so the
    # blend puts it, opaque, where the lines meet: pure blue there, no green or drawing through it
    k_mean = 0.3 * 0 + 0.3 * 1 + 0.4 * 2
    x0 = int(np.ceil(20 + 3 * k_mean)) + 2
    core = out[14:26, x0:x0 + 30]
    assert (core[..., 2] >= 250).all() and (core[..., 1] <= 3).all() and (core[..., 3] == 255).all()
    # where the top layer is see-through the drawings show, stacked over the static under-layer
    far = out[-8:, :]
    single = m.render((0,), (1.0,))
    assert single[-8:, :, 3].min() == 255 and far[..., 3].min() == 255


def test_half_transparent_layers_compose_with_over(artset):
    m = LayeredMorpher(_stack_part(artset, 128), alpha_steps=6)
    for k in range(m.n):
        layers = [premultiply(ly.image) for ly in _stack_part(artset, 128)[k].layers]
        want = layers[0].copy()
        for img in layers[1:]:
            over_u8(img, want, want)
        np.testing.assert_array_equal(m.render((k,), (1.0,)), want)
    out = m.render((0, 3), (0.5, 0.5))
    assert out.dtype == np.uint8 and (out[..., :3] <= out[..., 3:]).all()


def _layer_by_layer(drawings, alpha_steps):
    """The definition, done naively: each layer warped over the whole box by a ``PartMorpher`` of
    its own (a static layer kept as drawn), the blended layers stacked bottom first."""
    morphers = []
    for k in range(len(drawings[0].layers)):
        images = [d.layers[k].image for d in drawings]
        lines = [d.layer_lines(k) for d in drawings]
        static = all(np.array_equal(im, images[0]) for im in images[1:]) and \
            all(np.array_equal(l, lines[0]) for l in lines[1:])
        morphers.append(premultiply(images[0]) if static else PartMorpher(images, lines, alpha_steps=alpha_steps, cross_terms=True))

    def render(idx, w, jitter=None):
        layers = [m if isinstance(m, np.ndarray) else m.render(idx, w, jitter=jitter) for m in morphers]
        acc = layers[0].copy()
        for img in layers[1:]:
            over_u8(img, acc, acc)
        return acc

    return render


@settings(max_examples=20, deadline=None)
@given(w=weights5(), jitter=st.booleans())
def test_per_frame_rectangles_change_no_pixel(artset, w, jitter):
    """A moving layer warped only where its content can land gives the full-box warp exactly."""
    fast = LayeredMorpher(_stack_part(artset, 200), alpha_steps=5)
    full = _layer_by_layer(_stack_part(artset, 200), alpha_steps=5)
    jit = np.random.default_rng(len(w[0])).normal(0, 1.5, (31, 31, 2)).astype(np.float32) if jitter else None
    np.testing.assert_array_equal(fast.render(*w, jitter=jit), full(*w, jitter=jit))


def test_layers_must_match_across_drawings(artset):
    ds = _stack_part(artset, 255)
    ds[1].layers = ds[1].layers[:2]
    with pytest.raises(ValueError, match="needs the layers"):
        LayeredMorpher(ds)


def test_renderer_uses_plain_morphers_for_single_pictures(artset):
    r = CharacterRenderer(artset, alpha_steps=4)
    assert all(type(m) is PartMorpher for m in r.morphers.values())
    assert r.compositor.body is None


# --- the body -----------------------------------------------------------------------------------------------
def _head_and_body(w=160, h=128):
    head = np.zeros((h, w, 4), np.uint8)
    yy, xx = np.mgrid[0:h, 0:w]
    face = (xx - w / 2) ** 2 / 40 ** 2 + (yy - 50) ** 2 / 36 ** 2 <= 1
    head[face] = (230, 190, 160, 255)
    body = np.zeros((h, w, 4), np.uint8)
    body[84:, :] = (40, 90, 200, 255)
    body[84:, ::7] = (20, 40, 100, 255)  # stripes: a body edge made of repeated pixels would smear them
    return head, body


@pytest.mark.parametrize("roll", [0.0, 0.25])
def test_the_body_stays_when_the_head_rolls(roll):
    head, body = _head_and_body()
    c = Compositor((160, 128), (80, 84), [head], {}, body=body, body_follow=0.3, body_roll=roll)
    rest = c.transform(c.flat({}, 0), (0, 0, 0))
    tilted = c.transform(c.flat({}, 0), (0, 0, 30))
    shoulders = (slice(110, 128), slice(0, 20))  # far from the head
    if roll == 0:
        np.testing.assert_array_equal(rest[shoulders], tilted[shoulders])
    else:  # rolls by a quarter: 7.5 degrees, so the shoulder's stripe pattern shifts a little, not 30 degrees' worth
        assert np.abs(rest[shoulders].astype(int) - tilted[shoulders]).mean() < 60
    assert tilted[-1, :, 3].min() == 255 and tilted[:, 0][100:].min() > 0  # no gap at the canvas edges


def test_the_body_follows_the_head_by_a_fraction_without_gaps():
    head, body = _head_and_body()
    c = Compositor((160, 128), (80, 84), [head], {}, body=body, body_follow=0.5, body_roll=0.0)
    moved = c.transform(c.flat({}, 0), (20, -16, 0))
    # the body's top edge (row 84) moved up by 8 px, its stripes right by 10 px
    assert moved[75, 5, 3] == 0 and moved[77, 5, 3] == 255
    col = np.nonzero((moved[120, :, 2] < 150) & (moved[120, :, 3] == 255))[0]
    assert (col % 7 == 3).all()  # 0 + 10 mod 7
    assert moved[-10:, :, 3].min() == 255  # the bottom stays covered: mirrored, not cut off


def test_the_head_lies_over_the_body():
    head, body = _head_and_body()
    c = Compositor((160, 128), (80, 84), [head], {}, body=body, body_follow=0.3)
    out = c.transform(c.flat({}, 0), (0, 12, 0))
    assert tuple(out[84, 80]) == tuple(premultiply(head)[72, 80])  # head pixel, not body, where they overlap


def test_body_with_keep_in_frame_keeps_the_whole_head_on_the_canvas():
    head, body = _head_and_body()
    c = Compositor((160, 128), (80, 84), [head], {}, body=body, body_follow=0.3, keep_in_frame=True)
    for pose in [(200, 0, 0), (-200, 80, 20), (0, -300, -30)]:
        out = c.transform(c.flat({}, 0), pose)
        skin = (out[..., 0] > 150) & (out[..., 3] > 200)
        assert skin.sum() >= 0.97 * (head[..., 3] > 0).sum()


def test_renderer_passes_the_body_from_the_art_set(artset):
    h, w = artset.canvas[1], artset.canvas[0]
    body = np.zeros((h, w, 4), np.uint8)
    body[-60:] = (10, 20, 30, 255)
    art = ArtSet(artset.name, artset.canvas, artset.pivot, artset.heads, artset.parts, body=Body(body, follow=0.4, roll=0.1))
    r = CharacterRenderer(art, alpha_steps=4)
    assert r.compositor.body is not None and r.compositor.body_follow == 0.4 and r.compositor.body_roll == 0.1
    frame = r.render(pose=(0, 0, 25))
    assert frame[-1, :, 3].min() == 255


@pytest.fixture(scope="module")
def bundled_parts():
    """Ivy's eyes and mouth, and Gnash's mouth (tusks, a small layer, over the upper lip)."""
    from art_sets.io import load_artset
    from art_sets.library import bundled_dir

    ivy, gnash = (load_artset(bundled_dir() / name) for name in ("ivy", "gnash"))
    out = {}
    for key, part in (("ivy eyes", ivy.eyes), ("ivy mouth", ivy.mouth), ("gnash mouth", gnash.mouth)):
        out[key] = LayeredMorpher(part.drawings, alpha_steps=5), _layer_by_layer(part.drawings, alpha_steps=5)
    return out


@st.composite
def weights_of_five(draw):
    return _weights(draw, 5)


@settings(max_examples=30, deadline=None)
@given(w=weights_of_five(), jitter=st.booleans(), part=st.sampled_from(["ivy eyes", "ivy mouth", "gnash mouth"]))
def test_a_bundled_character_renders_exactly_as_layer_by_layer_over_the_whole_box(bundled_parts, w, jitter, part):
    """Per-frame rectangles (Ivy's lower lid and lower lip reach the box's edges: the warp reads
    past them there), batched meshes and maps, and the lower lip warped only where the upper lip
    lets light through change no pixel."""
    fast, slow = bundled_parts[part]
    jit = np.random.default_rng(sum(w[0])).normal(0, 1.5, (31, 31, 2)).astype(np.float32) if jitter else None
    np.testing.assert_array_equal(fast.render(*w, jitter=jit), slow(*w, jitter=jit))


def test_an_opaque_top_layer_leaves_nothing_to_warp_below_it(artset):
    """A top layer opaque everywhere: the layers under it are not warped, the frame is that layer."""
    part = _stack_part(artset, 255)
    for d in part:
        d.layers[2].image[...] = (0, 0, 255, 255)
    m = LayeredMorpher(part, alpha_steps=4)
    assert 2 in m._sees
    warped = []
    orig = m._warp_blend
    m._warp_blend = lambda k, *a: warped.append(k) or orig(k, *a)
    out = m.render((0, 1, 2), (0.3, 0.3, 0.4))
    assert warped == [2]
    np.testing.assert_array_equal(out, _layer_by_layer(part, alpha_steps=4)((0, 1, 2), (0.3, 0.3, 0.4)))


def test_every_line_sets_meshes_come_from_one_product(bundled_parts):
    m = bundled_parts["gnash mouth"][0]
    for idx, w in (((0, 3, 5), (0.2, 0.5, 0.3)), ((1, 2), (0.7, 0.3)), ((4,), (1.0,))):
        act = m.active(idx, w)
        np.testing.assert_array_equal(m._all_mesh_planes(act), np.stack([g._mesh_planes(act) for g in m.groups]))


def test_see_through_box():
    from morph.layers import _see_through

    img = np.full((20, 30, 4), 255, np.uint8)
    assert _see_through(img, 5, 7) is None
    img[3:6, 10:12, 3] = 254
    img[8, 4, 3] = 0
    assert _see_through(img, 5, 7) == (5 + 4, 7 + 3, 5 + 12, 7 + 9)


def test_four_way_blends_equal_the_layer_by_layer_render_too(bundled_parts):
    for key in ("ivy eyes", "gnash mouth"):
        fast, slow = bundled_parts[key]
        w = ((0, 1, 2, 3), (0.4, 0.3, 0.2, 0.1))
        np.testing.assert_array_equal(fast.render(*w), slow(*w))
