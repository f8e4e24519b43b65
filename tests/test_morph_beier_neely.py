"""The exact Beier–Neely field: identity, similarity transforms, the distance rule, polymorph."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from morph import beier_neely as bn

W, H = 48, 36


def _image(seed: int = 0, w: int = W, h: int = H) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
    return cv2.GaussianBlur(img, (0, 0), 1.5)


coord = st.floats(-10.0, 60.0, allow_nan=False)
line = st.tuples(coord, coord, coord, coord).filter(lambda l: math.hypot(l[2] - l[0], l[3] - l[1]) > 2.0)
line_sets = st.lists(line, min_size=1, max_size=5)


@settings(max_examples=25, deadline=None)
@given(line_sets)
def test_unchanged_lines_give_identity(lines):
    mx, my = bn.field_map(lines, lines, (W, H))
    ys, xs = np.mgrid[0:H, 0:W]
    assert np.abs(mx - xs).max() < 1e-3 and np.abs(my - ys).max() < 1e-3
    img = _image()
    assert np.array_equal(bn.warp(img, lines, lines), bn.premultiply(img))


def test_no_lines_and_zero_length_lines_are_identity():
    ys, xs = np.mgrid[0:H, 0:W]
    for src, dst in (([], []), ([[5, 5, 5, 5]], [[9, 2, 9, 2]])):
        mx, my = bn.field_map(dst, src, (W, H))
        assert np.array_equal(mx, xs.astype(np.float32)) and np.array_equal(my, ys.astype(np.float32))


def _line_transform(src, theta: float, stretch: float, tx: float, ty: float) -> np.ndarray:
    """2×3 affine: stretch along the line's own direction, rotate by ``theta``, translate.

    A single Beier–Neely line pair reproduces exactly this family: the position along the line
    scales with the line's length, the perpendicular distance stays in pixels.
    """
    d = np.array([src[2] - src[0], src[3] - src[1]], float)
    d /= np.linalg.norm(d)
    c, s = math.cos(theta), math.sin(theta)
    lin = np.array([[c, -s], [s, c]]) @ (np.eye(2) + (stretch - 1.0) * np.outer(d, d))
    return np.hstack([lin, [[tx], [ty]]])


@settings(max_examples=30, deadline=None)
@given(line, st.floats(-math.pi, math.pi), st.floats(0.5, 2.0), st.floats(-8, 8), st.floats(-8, 8))
def test_single_line_moves_the_image_exactly_like_the_line(src, theta, stretch, tx, ty):
    m = _line_transform(src, theta, stretch, tx, ty)
    p = m @ [src[0], src[1], 1.0]
    q = m @ [src[2], src[3], 1.0]
    mx, my = bn.field_map([[*p, *q]], [src], (W, H))
    inv = cv2.invertAffineTransform(m)
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float64)
    ex = inv[0, 0] * xs + inv[0, 1] * ys + inv[0, 2]
    ey = inv[1, 0] * xs + inv[1, 1] * ys + inv[1, 2]
    tol = 1e-4 * (1 + np.abs(ex).max() + np.abs(ey).max())
    assert np.abs(mx - ex).max() < tol and np.abs(my - ey).max() < tol


def test_translated_rotated_scaled_image_matches_warp_affine():
    img = _image(3)
    src = [10.0, 12.0, 30.0, 20.0]
    for args in ((0, 1, 5, -3), (0.4, 1.0, 2, 1), (-0.2, 1.3, -4, 2)):
        m = _line_transform(src, *args)
        p, q = m @ [src[0], src[1], 1], m @ [src[2], src[3], 1]
        got = bn.warp(img, [src], [[*p, *q]], border="transparent")
        want = cv2.warpAffine(bn.premultiply(img), m, (W, H), flags=cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_CONSTANT)
        inv = cv2.invertAffineTransform(m)
        ys, xs = np.mgrid[0:H, 0:W]
        sx = inv[0, 0] * xs + inv[0, 1] * ys + inv[0, 2]
        sy = inv[1, 0] * xs + inv[1, 1] * ys + inv[1, 2]
        inside = (sx > 1) & (sx < W - 2) & (sy > 1) & (sy < H - 2)
        diff = np.abs(got.astype(int) - want.astype(int))[inside]
        assert inside.sum() > W * H // 2 and diff.max() <= 1


def _expected(point, dst_lines, shifts, a=1.0, b=2.0, p=0.5):
    """Hand rule: pure translations of lines, so each line proposes its own shift."""
    num, den = np.zeros(2), 0.0
    for (x0, y0, x1, y1), s in zip(dst_lines, shifts):
        length = math.hypot(x1 - x0, y1 - y0)
        u = ((point[0] - x0) * (x1 - x0) + (point[1] - y0) * (y1 - y0)) / length**2
        if u < 0:
            dist = math.hypot(point[0] - x0, point[1] - y0)
        elif u > 1:
            dist = math.hypot(point[0] - x1, point[1] - y1)
        else:
            dist = abs(((point[1] - y0) * (x1 - x0) - (point[0] - x0) * (y1 - y0)) / length)
        wt = (length**p / (a + dist)) ** b
        num += wt * np.asarray(s)
        den += wt
    return np.asarray(point) + num / den


def test_distance_rule_on_hand_computed_cases():
    dst = [[0.0, 0.0, 10.0, 0.0], [0.0, 20.0, 4.0, 20.0]]
    shifts = [(1.0, 0.0), (0.0, 2.0)]
    src = [[l[0] + s[0], l[1] + s[1], l[2] + s[0], l[3] + s[1]] for l, s in zip(dst, shifts)]
    # between the ends of line 0 (dist = |v| = 3), beyond its end (dist 5), before its start (dist 10)
    for pt in [(5.0, 3.0), (13.0, 4.0), (-6.0, 8.0), (2.0, 10.0)]:
        got = bn.field_at(np.array([pt]), dst, src)[0]
        assert np.allclose(got, _expected(pt, dst, shifts), atol=1e-9)
    # concrete numbers for (13, 4): line 0 dist 5 -> w = (sqrt(10)/6)^2 = 10/36;
    # line 1 (0,20)-(4,20): u = 13/4 > 1, dist to (4,20) = sqrt(81+256) -> w = 4/(1+sqrt(337))^2
    w0, w1 = 10 / 36, 4 / (1 + math.sqrt(337)) ** 2
    want = np.array([13 + w0 / (w0 + w1), 4 + 2 * w1 / (w0 + w1)])
    assert np.allclose(bn.field_at(np.array([(13.0, 4.0)]), dst, src)[0], want, atol=1e-9)


def test_signed_distance_alone_would_differ():
    """A point below the line and one above at equal |v| get the same weight (|v|, not v)."""
    dst = [[0.0, 0.0, 10.0, 0.0], [0.0, 30.0, 10.0, 30.0]]
    src = [[1.0, 0.0, 11.0, 0.0], [0.0, 30.0, 10.0, 30.0]]
    up = bn.field_at(np.array([(5.0, -3.0)]), dst, src)[0] - (5.0, -3.0)
    down = bn.field_at(np.array([(5.0, 3.0)]), dst, src)[0] - (5.0, 3.0)
    # the far line is 33 vs 27 away: both shifts are dominated by line 0 with weight (√10/4)^2
    assert up[0] == pytest.approx(_expected((5, -3), dst, [(1, 0), (0, 0)])[0] - 5)
    assert down[0] == pytest.approx(_expected((5, 3), dst, [(1, 0), (0, 0)])[0] - 5)


def test_polymorph_exact_single_weight_returns_the_drawing():
    imgs = [_image(i) for i in range(3)]
    lines = [[[5 + i, 5, 30, 20 + i]] for i in range(3)]
    for k in range(3):
        w = [0.0, 0.0, 0.0]
        w[k] = 1.0
        assert np.array_equal(bn.polymorph_exact(imgs, lines, w), bn.premultiply(imgs[k]))


@settings(max_examples=20, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3).filter(lambda w: sum(w) > 1e-3))
def test_polymorph_exact_keeps_opaque_drawings_opaque(w):
    imgs = [_image(i) for i in range(3)]
    for img in imgs:
        img[:, :, 3] = 255
    lines = [[[5 + 2 * i, 5, 30, 20 + 3 * i], [40, 30 - i, 10, 30]] for i in range(3)]
    out = bn.polymorph_exact(imgs, lines, w)
    assert out[:, :, 3].min() == 255


def test_blend_is_the_weighted_sum():
    a = np.full((4, 4, 4), 200, np.uint8)
    b = np.full((4, 4, 4), 100, np.uint8)
    c = np.zeros((4, 4, 4), np.uint8)
    out = bn.blend_pm([a, b, c], [0.25, 0.5, 0.25])
    assert (out == 100).all()  # not the result of drawing one over the other


def test_bad_inputs_raise_one_line_errors():
    with pytest.raises(ValueError, match="shape"):
        bn.field_map([[0, 0, 1]], [[0, 0, 1]], (W, H))
    with pytest.raises(ValueError, match="positive sum"):
        bn.polymorph_exact([_image()], [[[0, 0, 5, 5]]], [0.0])
    with pytest.raises(ValueError, match="border"):
        bn.warp(_image(), [], [], border="mirror")
