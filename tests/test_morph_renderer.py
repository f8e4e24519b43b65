"""CharacterRenderer over a whole art set, and the expression-driven style."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.bench_morph import generated_artset
from morph.beier_neely import premultiply
from morph.compositor import Compositor
from morph.renderer import CharacterRenderer
from morph.style import ExpressionStyle, style_level


@pytest.fixture(scope="module")
def artset():
    return generated_artset()


@pytest.fixture(scope="module")
def renderer(artset):
    return CharacterRenderer(artset, alpha_steps=6)


def _valid_pm(img):
    return img.dtype == np.uint8 and np.all(img[:, :, :3] <= img[:, :, 3:4])


def test_render_gives_a_premultiplied_canvas(renderer, artset):
    out = renderer.render(eyes=((0, 1, 2), (0.5, 0.3, 0.2)), mouth=((3, 4, 5), (0.2, 0.2, 0.6)),
                          pose=(4, -3, 12), frame_no=5)
    assert out.shape == (artset.canvas[1], artset.canvas[0], 4)
    assert renderer.canvas == artset.canvas
    assert _valid_pm(out)


def test_single_drawings_compose_exactly(renderer, artset):
    out = renderer.render(eyes=((2, 0, 1), (1.0, 0.0, 0.0)), mouth=((4, 0, 1), (1.0, 0.0, 0.0)))
    c = Compositor(artset.canvas, artset.pivot, artset.heads, {n: p.box for n, p in artset.parts.items()})
    want = c.compose({"eyes": premultiply(artset.eyes.drawings[2].image),
                      "mouth": premultiply(artset.mouth.drawings[4].image)})
    assert np.array_equal(out, want)


def test_default_weights_show_the_rest_drawings(renderer, artset):
    rest = renderer.render()
    named = renderer.render(eyes=((artset.eyes.index("open"),), (1.0,)),
                            mouth=((artset.mouth.index("neutral"),), (1.0,)))
    assert np.array_equal(rest, named)


def test_gain_scales_the_pose(artset):
    r = CharacterRenderer(artset, gain=0.0, alpha_steps=3, keep_in_frame=False)
    assert np.array_equal(r.render(pose=(20, 10, 30)), r.render())
    r.gain = 2.0
    assert np.array_equal(r.render(pose=(5, 0, 0))[:, 20:], r.render(pose=(0, 0, 0))[:, 10:-10])


def test_style_is_off_by_default_and_warms_and_shakes_when_on(renderer):
    args = dict(eyes=((0, 1, 2), (0.5, 0.3, 0.2)), mouth=((0, 1, 2), (0.5, 0.3, 0.2)), frame_no=3)
    plain = renderer.render(**args)
    assert np.array_equal(plain, renderer.render(**args, style_level=0.0))
    hot = renderer.render(**args, style_level=1.0)
    assert _valid_pm(hot)
    opaque = plain[:, :, 3] == 255
    ratio = lambda im: im[opaque][:, 0].astype(float).mean() / max(1.0, im[opaque][:, 1].astype(float).mean())
    assert ratio(hot) > ratio(plain) * 1.2
    # the lines tremble: the same weights give a different jitter a few frames later
    args2 = dict(args, frame_no=9)
    assert not np.array_equal(renderer.render(**args2, style_level=1.0), hot)


def test_style_level_threshold():
    assert style_level(0.1, threshold=0.3, full=0.6) == 0.0
    assert style_level(0.45, threshold=0.3, full=0.6) == pytest.approx(0.5)
    assert style_level(2.0, threshold=0.3, full=0.6) == 1.0
    s = ExpressionStyle(jitter_px=2.0)
    assert s.jitter(0.0, 0) is None
    j = s.jitter(1.0, 0)
    assert j.shape == (31, 31, 2) and 0.2 < np.abs(j).max() <= 2.0
    assert np.array_equal(j, s.jitter(1.0, 1))  # renewed every `every` frames


def test_bundled_art_sets_render_if_present():
    io = pytest.importorskip("art_sets.io")
    library = pytest.importorskip("art_sets.library")
    sets = library.list_bundled()
    if not sets:
        pytest.skip("no bundled art sets yet")
    _, path = sets[0]
    art = io.load_artset(path)
    r = CharacterRenderer(art, alpha_steps=3)
    out = r.render(eyes=((0, 1, 2), (0.4, 0.3, 0.3)), mouth=((0, 1, 2), (0.4, 0.3, 0.3)), pose=(3, 2, 8))
    assert out.shape == (art.canvas[1], art.canvas[0], 4) and _valid_pm(out) and out[:, :, 3].max() == 255


# --- a part asked for again is not rendered again ------------------------------------------------------------
def _counting(r):
    calls = []
    orig = r.render_part

    def counted(name, *a, **k):
        calls.append(name)
        return orig(name, *a, **k)

    r.render_part = counted
    return calls


def test_a_repeated_part_is_reused_and_equals_a_fresh_render(artset):
    r, fresh = CharacterRenderer(artset, alpha_steps=6), CharacterRenderer(artset, alpha_steps=6)
    calls = _counting(r)
    eyes, mouth = ((0, 1, 2), (0.5, 0.3, 0.2)), ((3, 4, 5), (0.2, 0.2, 0.6))
    r.render(eyes=eyes, mouth=mouth, pose=(1.0, 2.0, 3.0), frame_no=0)
    calls.clear()
    still = ((0, 1, 2), (0.5 + 1e-9, 0.3, 0.2))
    got = r.render(eyes=still, mouth=mouth, pose=(-2.0, 1.0, -4.0), frame_no=1)
    assert calls == []
    np.testing.assert_array_equal(got, fresh.render(eyes=eyes, mouth=mouth, pose=(-2.0, 1.0, -4.0), frame_no=1))


@pytest.mark.parametrize("change", ["weight", "order", "drawing", "rest", "detail"])
def test_a_change_in_drawings_weights_or_detail_renders_the_part_again(artset, change):
    r = CharacterRenderer(artset, alpha_steps=6)
    calls = _counting(r)
    eyes, mouth = ((0, 1, 2), (0.5, 0.3, 0.2)), ((3, 4, 5), (0.2, 0.2, 0.6))
    r.render(eyes=eyes, mouth=mouth)
    new = {"weight": ((0, 1, 2), (0.5, 0.3 + 1e-3, 0.2)), "order": ((1, 0, 2), (0.3, 0.5, 0.2)),
           "drawing": ((0, 1, 3), (0.5, 0.3, 0.2)), "rest": None, "detail": eyes}[change]
    if change == "detail":
        r.detail = True
    calls.clear()
    got = r.render(eyes=new, mouth=mouth)
    assert calls == (["eyes", "mouth"] if change == "detail" else ["eyes"])
    fresh = CharacterRenderer(artset, alpha_steps=6, detail=change == "detail")
    np.testing.assert_array_equal(got, fresh.render(eyes=new, mouth=mouth))


def test_the_style_renders_every_frame(artset):
    r = CharacterRenderer(artset, alpha_steps=6)
    calls = _counting(r)
    w = ((0, 1, 2), (0.5, 0.3, 0.2))
    for k in range(3):
        r.render(eyes=w, mouth=w, frame_no=k, style_level=0.8)
    assert calls == ["eyes", "mouth"] * 3
