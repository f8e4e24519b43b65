"""Compositor: boxes, head over parts, shimmer, rotation about the pivot; colour helpers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from morph.beier_neely import premultiply
from morph.compositor import Compositor, over_background, to_straight

CANVAS = (120, 100)


def _clear_head():
    return np.zeros((CANVAS[1], CANVAS[0], 4), np.uint8)


def _part(w, h, colour):
    p = np.zeros((h, w, 4), np.uint8)
    p[:] = colour
    return p


def _centroid(img):
    a = img[:, :, 3].astype(np.float64)
    ys, xs = np.mgrid[0:a.shape[0], 0:a.shape[1]]
    return np.array([(a * xs).sum() / a.sum(), (a * ys).sum() / a.sum()])


def test_parts_land_in_their_boxes_under_a_clear_head():
    boxes = {"eyes": (10, 20, 30, 10), "mouth": (50, 60, 40, 20)}
    c = Compositor(CANVAS, (60, 50), [_clear_head()], boxes)
    eyes = _part(30, 10, (0, 0, 255, 255))
    mouth = _part(40, 20, (128, 0, 0, 128))
    out = c.compose({"eyes": eyes, "mouth": mouth})
    assert np.array_equal(out[20:30, 10:40], eyes)
    assert np.array_equal(out[60:80, 50:90], mouth)
    rest = out.copy()
    rest[20:30, 10:40] = 0
    rest[60:80, 50:90] = 0
    assert rest.max() == 0


def test_head_lies_over_the_parts_with_its_soft_alpha():
    head = _clear_head()
    head[:] = (200, 100, 50, 255)
    head[20:30, 10:40, 3] = 0  # a hole: the part shows fully
    head[20:30, 25:40, 3] = 128  # half-feathered: half part, half head
    c = Compositor(CANVAS, (60, 50), [head], {"eyes": (10, 20, 30, 10)})
    out = c.compose({"eyes": _part(30, 10, (0, 0, 255, 255))})
    hp = premultiply(head)
    assert tuple(out[25, 15]) == (0, 0, 255, 255)
    assert tuple(out[50, 50]) == tuple(hp[50, 50])
    r, g, b, a = (int(v) for v in out[25, 30])
    assert a == 255 and abs(b - (255 * 127 / 255 + hp[25, 30, 2])) <= 1 and abs(r - hp[25, 30, 0]) <= 1


def test_heads_cycle_every_few_frames():
    heads = [_clear_head(), _clear_head()]
    heads[0][:, :, 3] = 255
    heads[1][:, :, 3] = 255
    heads[1][:, :, 0] = 255
    c = Compositor(CANVAS, (60, 50), heads, {}, shimmer_every=3)
    reds = [c.compose({}, frame_no=i)[0, 0, 0] for i in range(7)]
    assert reds == [0, 0, 0, 255, 255, 255, 0]


@settings(max_examples=25, deadline=None)
@given(st.floats(-90, 90), st.floats(-10, 10), st.floats(-10, 10), st.floats(0.0, 2.0))
def test_character_rotates_about_the_pivot_and_translates(roll, dx, dy, gain):
    pivot = (60.0, 50.0)
    head = _clear_head()
    head[36:44, 76:84] = (255, 255, 255, 255)  # a blob centred at (79.5, 39.5)
    c = Compositor(CANVAS, pivot, [head], {}, gain=gain)
    out = c.compose({}, pose=(dx, dy, roll))
    t = math.radians(roll * gain)
    rel = np.array([79.5 - pivot[0], 39.5 - pivot[1]])
    # positive roll turns counter-clockwise on screen (y down): the right side goes up
    want = np.array(pivot) + [rel[0] * math.cos(t) + rel[1] * math.sin(t),
                              -rel[0] * math.sin(t) + rel[1] * math.cos(t)] + np.array([dx, dy]) * gain
    assert np.allclose(_centroid(out), want, atol=0.05)
    # bilinear resampling of a hard-edged square, rounded to uint8, keeps its mass only to a few
    # per cent at oblique angles (worst seen over a fine sweep of roll × gain × sub-pixel shifts:
    # 1.57 of 64, at 134.6°); a lost or doubled blob is off by 64
    assert abs(out[:, :, 3].sum() / 255.0 - 64) < 2.0


def test_positive_roll_raises_the_right_side():
    head = _clear_head()
    head[48:52, 90:100] = 255
    c = Compositor(CANVAS, (60, 50), [head], {})
    assert _centroid(c.compose({}, pose=(0, 0, 20)))[1] < 49


def test_overlapping_boxes_layer_parts_in_order():
    boxes = {"a": (10, 10, 20, 20), "b": (20, 20, 20, 20)}
    c = Compositor(CANVAS, (60, 50), [_clear_head()], boxes)
    out = c.compose({"a": _part(20, 20, (255, 0, 0, 255)), "b": _part(20, 20, (0, 255, 0, 255))})
    assert tuple(out[15, 15]) == (255, 0, 0, 255)
    assert tuple(out[25, 25]) == (0, 255, 0, 255)


def test_boxes_partly_off_the_canvas_are_clipped():
    c = Compositor(CANVAS, (60, 50), [_clear_head()], {"m": (100, 90, 40, 20)})
    out = c.compose({"m": _part(40, 20, (9, 9, 9, 255))})
    assert (out[90:, 100:, 3] == 255).all() and out[:90, :, 3].max() == 0


def test_bad_parts_and_heads_raise():
    c = Compositor(CANVAS, (60, 50), [_clear_head()], {"m": (0, 0, 10, 10)})
    with pytest.raises(ValueError, match="its box needs"):
        c.compose({"m": _part(5, 5, (0, 0, 0, 0))})
    with pytest.raises(KeyError):
        c.compose({"x": _part(5, 5, (0, 0, 0, 0))})
    with pytest.raises(ValueError, match="head 0"):
        Compositor(CANVAS, (0, 0), [np.zeros((5, 5, 4), np.uint8)], {})


def test_straight_and_premultiplied_round_trip():
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, (20, 20, 4), dtype=np.uint8)
    img[..., 3] = np.maximum(img[..., 3], 128)
    back = to_straight(premultiply(img))
    assert np.abs(back.astype(int) - img).max() <= 1
    assert (to_straight(np.zeros((2, 2, 4), np.uint8)) == 0).all()


def test_over_background_colour_and_image():
    pm = np.zeros((4, 4, 4), np.uint8)
    pm[0, 0] = (255, 0, 0, 255)  # opaque red
    pm[1, 1] = (0, 0, 64, 128)  # half-transparent blue (premultiplied)
    out = over_background(pm, (0, 255, 0))  # BGR green
    assert tuple(out[0, 0]) == (0, 0, 255)
    assert tuple(out[2, 2]) == (0, 255, 0)
    assert tuple(out[1, 1]) == (64, 127, 0)
    bg = np.full((4, 4, 3), 10, np.uint8)
    assert tuple(over_background(pm, bg)[3, 3]) == (10, 10, 10)


def test_frames_do_not_leak_into_each_other():
    head = _clear_head()
    head[:, :, 3] = 255
    head[30:40, 30:40, 3] = 0
    c = Compositor(CANVAS, (60, 50), [head], {"m": (30, 30, 10, 10)})
    first = c.compose({"m": _part(10, 10, (0, 255, 0, 255))})
    kept = first.copy()
    second = c.compose({})  # no part: the hole is empty again
    assert second[35, 35, 3] == 0
    assert np.array_equal(first, kept)  # earlier results are not reused buffers
    tilted = c.compose({"m": _part(10, 10, (0, 0, 255, 255))}, pose=(1, 2, 3))
    assert tilted is not c.compose({"m": _part(10, 10, (0, 0, 255, 255))}, pose=(1, 2, 3))


def test_content_bounding_box_warp_matches_a_full_warp():
    import cv2

    rng = np.random.default_rng(0)
    head = _clear_head()
    head[10:90, 20:100] = rng.integers(0, 256, (80, 80, 4), dtype=np.uint8)
    head[..., :3] = np.minimum(head[..., :3], head[..., 3:])
    c = Compositor(CANVAS, (60, 50), [head], {}, heads_premultiplied=True)
    for pose in ((3.3, -2.1, 17.0), (-30, 12, -40), (200, 0, 0)):
        got = c.compose({}, pose=pose)
        want = cv2.warpAffine(head, c.matrix(pose), CANVAS, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        d = np.abs(got.astype(int) - want.astype(int))
        assert np.mean(d) < 0.05 and d.max() <= 16


def test_bad_pose_is_a_clear_error():
    c = Compositor(CANVAS, (60, 50), [_clear_head()], {})
    with pytest.raises(ValueError, match="finite"):
        c.compose({}, pose=(0, float("nan"), 3))
    with pytest.raises(ValueError, match="roll_deg"):
        c.compose({}, pose=(1, 2))


def _head_bbox_after(c: Compositor, head: np.ndarray, pose):
    """Bounding box (x0, y0, x1, y1) in canvas pixels of the head's pixels above the pivot after
    ``pose`` (pixel centres mapped by the compositor's matrix, so content off the edge counts)."""
    a = head[:, :, 3] > 0
    a[int(c.pivot[1]) + 1:] = False
    ys, xs = np.nonzero(a)
    m = c.matrix(pose)
    pts = np.stack([xs, ys], axis=1) @ m[:, :2].T + m[:, 2]
    return (*pts.min(axis=0), *pts.max(axis=0))


def _big_head():
    """A round head nearly as wide as the canvas, a neck down to the bottom edge."""
    import cv2

    head = _clear_head()
    cv2.ellipse(head, (60, 42), (50, 38), 0, 0, 360, (200, 150, 120, 255), -1)
    cv2.rectangle(head, (50, 70), (70, 99), (200, 150, 120, 255), -1)
    return head


@settings(max_examples=40, deadline=None)
@given(st.floats(-5000, 5000), st.floats(-5000, 5000), st.floats(-60, 60), st.floats(0.0, 3.0))
def test_keep_in_frame_holds_the_head_within_the_margin(dx, dy, roll, gain):
    head = _big_head()
    c = Compositor(CANVAS, (60, 80), [head], {}, gain=gain, keep_in_frame=True, margin=4)
    x0, y0, x1, y1 = _head_bbox_after(c, head, (dx, dy, roll))
    assert x0 >= -4 - 1 and y0 >= -4 - 1 and x1 <= CANVAS[0] - 1 + 4 + 1 and y1 <= CANVAS[1] - 1 + 4 + 1
    # the unlimited compositor really would have left the canvas for the big moves
    if max(abs(dx), abs(dy)) * gain > 200:
        free = Compositor(CANVAS, (60, 80), [head], {}, gain=gain)
        fx0, fy0, fx1, fy1 = _head_bbox_after(free, head, (dx, dy, roll))
        assert fx0 < -5 or fy0 < -5 or fx1 > CANVAS[0] + 4 or fy1 > CANVAS[1] + 4


def test_keep_in_frame_is_gentle_near_rest_and_monotonic():
    head = _big_head()
    c = Compositor(CANVAS, (60, 80), [head], {}, keep_in_frame=True, margin=4)
    assert np.allclose(c.matrix((0, 0, 0)), [[1, 0, 0], [0, 1, 0]])
    xs = [c.matrix((d, 0, 0))[0, 2] for d in np.linspace(-100, 100, 81)]
    assert np.all(np.diff(xs) > 0)
    assert c.matrix((0.5, 0, 0))[0, 2] == pytest.approx(0.5, abs=0.02)  # small moves pass
    # rotation is never altered by the limit
    assert np.allclose(c.matrix((500, 0, 20))[:, :2], Compositor(CANVAS, (60, 80), [head], {}).matrix((0, 0, 20))[:, :2])


def test_bundled_head_stays_on_the_canvas_for_an_extreme_pose():
    from art_sets.io import load_artset
    from art_sets.library import find_artset

    art = load_artset(find_artset("ivy"))
    c = Compositor(art.canvas, art.pivot, art.heads, {}, keep_in_frame=True)
    for pose in ((300, 300, 25), (-300, -300, -25), (150, 80, -30), (0, 0, 0)):
        x0, y0, x1, y1 = _head_bbox_after(c, art.heads[0], pose)
        m = c.margin + 1
        assert x0 >= -m and y0 >= -m and x1 <= art.canvas[0] - 1 + m and y1 <= art.canvas[1] - 1 + m, pose


@settings(max_examples=25, deadline=None)
@given(st.integers(-130, 130), st.integers(-110, 110), st.integers(0, 10**6))
def test_whole_pixel_moves_match_the_bilinear_warp(dx, dy, seed):
    import cv2

    rng = np.random.default_rng(seed)
    head = rng.integers(0, 256, (CANVAS[1], CANVAS[0], 4), dtype=np.uint8)
    c = Compositor(CANVAS, (60, 50), [head], {"eyes": (10, 20, 30, 10)})
    eyes = _part(30, 10, (0, 0, 200, 200))
    flat = c.flat({"eyes": eyes}).copy()
    out = c.compose({"eyes": eyes}, pose=(dx, dy, 0.0))
    want = cv2.warpAffine(flat, np.array([[1.0, 0, dx], [0, 1.0, dy]]), CANVAS, flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0, 0))
    assert np.array_equal(out, want)
    assert out is not c.compose({"eyes": eyes}, pose=(dx, dy, 0.0))


# ------------------------------------------------------------------ banded warp vs a full warp


def _odd_head(seed: int = 0) -> np.ndarray:
    """Premultiplied, non-convex: a ring with an eye hole, an L-shaped arm, shoulders cut by the
    bottom edge; smooth colours inside, hard anti-aliased edges."""
    import cv2

    rng = np.random.default_rng(seed)
    colour = cv2.GaussianBlur(rng.integers(0, 256, (CANVAS[1], CANVAS[0], 3)).astype(np.float32), (0, 0), 6)
    colour = cv2.normalize(colour, None, 0, 255, cv2.NORM_MINMAX)
    alpha = np.zeros((CANVAS[1], CANVAS[0]), np.uint8)
    cv2.circle(alpha, (55, 38), 30, 255, 12, cv2.LINE_AA)
    cv2.rectangle(alpha, (88, 8), (98, 60), 255, -1)
    cv2.rectangle(alpha, (88, 50), (115, 60), 255, -1)
    cv2.ellipse(alpha, (60, 100), (55, 25), 0, 180, 360, 200, -1, cv2.LINE_AA)
    head = np.dstack([colour.astype(np.uint8), alpha])
    return premultiply(head)


def _full_warp(flat: np.ndarray, m: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.warpAffine(flat, m, (flat.shape[1], flat.shape[0]), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0, 0))


def _origin_tolerance(flat: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Per output pixel and channel: how far a warp of a sub-rectangle may differ from the full
    warp. OpenCV samples on a 1/32-px grid found in fixed point from the destination origin, so
    another origin can move a sample one step in x and y: at most (source contrast)/16 + 1."""
    import cv2

    pad = cv2.copyMakeBorder(flat, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(0, 0, 0, 0))
    k = np.ones((3, 3), np.uint8)
    contrast = cv2.dilate(pad, k) - cv2.erode(pad, k)
    shifted = m.copy()
    shifted[:, 2] -= m[:, :2] @ [2.0, 2.0]
    near = cv2.warpAffine(contrast, shifted, (flat.shape[1], flat.shape[0]), flags=cv2.INTER_NEAREST,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0, 0))
    return near.astype(int) / 16 + 1


def _assert_matches_full_warp(c: Compositor, flat: np.ndarray, pose) -> np.ndarray:
    m = c.matrix(pose)
    got = c.transform(flat, pose)
    want = _full_warp(flat, m)
    d = np.abs(got.astype(int) - want.astype(int))
    assert (d <= _origin_tolerance(flat, m)).all()
    assert (d > 0).mean() < 0.02  # the differences are rare sampling steps, not a shift
    covered = np.zeros(flat.shape[:2], bool)
    for y0, y1, x0, x1 in c._bands(m):
        covered[y0:y1, x0:x1] = True
    assert not want[~covered].any()  # nothing the full warp shows lies outside the bands
    return got


@settings(max_examples=40, deadline=None)
@given(st.floats(-45, 45), st.floats(-60, 60), st.floats(-60, 60), st.floats(0.3, 1.5), st.integers(0, 3))
def test_banded_warp_matches_a_full_warp_of_a_non_convex_head(roll, dx, dy, gain, seed):
    head = _odd_head(seed)
    c = Compositor(CANVAS, (60, 80), [head], {"eyes": (40, 30, 30, 16)}, gain=gain, heads_premultiplied=True)
    eyes = _part(30, 16, (0, 90, 180, 200))
    flat = c.flat({"eyes": eyes}).copy()
    got = _assert_matches_full_warp(c, flat, (dx, dy, roll))
    if abs(dx * gain) < 30 and abs(dy * gain) < 30:
        assert got[:, :, 3].any()


@pytest.mark.parametrize("pose", [(130, 0, 0.5), (-100, 45, 30), (0, -115, -20), (70, 70, 44), (400, 0, 10)])
def test_banded_warp_with_content_moving_off_the_canvas(pose):
    c = Compositor(CANVAS, (60, 80), [_odd_head(1)], {}, heads_premultiplied=True)
    _assert_matches_full_warp(c, c.heads[0], pose)


@pytest.mark.parametrize("band_rows", [12, 16, 48, 100, 1000])
def test_banded_warp_for_any_band_height_including_one_band(band_rows):
    c = Compositor(CANVAS, (60, 80), [_odd_head(2)], {}, heads_premultiplied=True, band_rows=band_rows)
    for pose in ((3.5, -7.25, 12.0), (-20.2, 4.1, -33.0)):
        _assert_matches_full_warp(c, c.heads[0], pose)
    if band_rows >= CANVAS[1]:
        assert len(c._bands(c.matrix((0.5, 0, 3)))) == 1


def test_empty_heads_give_an_empty_frame_and_boxes_still_move():
    c = Compositor(CANVAS, (60, 50), [_clear_head()], {})
    assert c._bands(c.matrix((2.5, 1, 10))) == []
    assert not c.compose({}, pose=(2.5, 1, 10)).any()
    c = Compositor(CANVAS, (60, 50), [_clear_head()], {"m": (30, 30, 20, 10)})
    flat = c.flat({"m": _part(20, 10, (0, 200, 0, 255))}).copy()
    got = _assert_matches_full_warp(c, flat, (2.5, 1, 10))
    assert got[:, :, 3].sum() / 255 == pytest.approx(200, abs=2)


def test_band_height_must_cover_the_bilinear_reach():
    with pytest.raises(ValueError, match="band_rows"):
        Compositor(CANVAS, (60, 50), [_odd_head()], {}, band_rows=4)


def test_shimmer_through_one_flat_buffer_matches_a_fresh_composite():
    rng = np.random.default_rng(3)
    heads = [rng.integers(0, 256, (CANVAS[1], CANVAS[0], 4), dtype=np.uint8) for _ in range(3)]
    boxes = {"eyes": (10, 20, 30, 10), "mouth": (50, 60, 40, 20)}
    c = Compositor(CANVAS, (60, 50), heads, boxes, shimmer_every=1)
    for frame in (0, 1, 1, 2, 0, 2, 5, 3):
        parts = {"eyes": _part(30, 10, (0, 0, 99, 99))} if frame % 2 else {"mouth": _part(40, 20, (9, 9, 9, 9))}
        fresh = Compositor(CANVAS, (60, 50), [heads[frame % 3]], boxes)
        assert np.array_equal(c.flat(parts, frame), fresh.flat(parts))
