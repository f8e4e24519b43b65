"""Mesh-sampled warps: corner alignment, exactness for affine fields, error against the exact field."""

from __future__ import annotations

import math

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks.bench_morph import MOUTHS, make_mouth
from morph import beier_neely as bn
from morph import mesh


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 400), st.integers(1, 40))
def test_interpolation_matrix_puts_vertices_on_the_end_pixels(n, cells):
    m = mesh.interpolation_matrix(n, cells).astype(np.float64)
    assert np.allclose(m.sum(axis=1), 1.0)
    assert m[0, 0] == 1.0 and m[-1, -1] == 1.0
    # pixel x has grid coordinate x * cells / (n - 1)
    g = m @ np.arange(cells + 1)
    assert np.allclose(g, np.arange(n) * cells / (n - 1), atol=1e-4)


def test_vertex_grid_corners_are_the_image_corners():
    g = mesh.MeshGrid((217, 133))
    assert g.vertices.shape == (31, 31, 2)
    assert tuple(g.vertices[0, 0]) == (0.0, 0.0)
    assert tuple(g.vertices[0, -1]) == (216.0, 0.0)
    assert tuple(g.vertices[-1, 0]) == (0.0, 132.0)
    assert tuple(g.vertices[-1, -1]) == (216.0, 132.0)
    mx, my = g.upsample(g.vertices)
    ys, xs = np.mgrid[0:133, 0:217]
    assert np.abs(mx - xs).max() < 1e-3 and np.abs(my - ys).max() < 1e-3


@settings(max_examples=25, deadline=None)
@given(
    st.integers(20, 320), st.integers(20, 200),
    st.floats(-0.6, 0.6), st.floats(0.6, 1.6), st.floats(-10, 10), st.floats(-10, 10),
)
def test_single_line_field_is_reproduced_exactly_by_the_mesh(w, h, theta, stretch, tx, ty):
    src = np.array([[0.2 * w, 0.3 * h, 0.7 * w, 0.6 * h]])
    c, s = math.cos(theta), math.sin(theta)
    centre = np.array([w / 2, h / 2])
    p = centre + stretch * np.array([[c, -s], [s, c]]) @ (src[0, :2] - centre) + (tx, ty)
    q = centre + stretch * np.array([[c, -s], [s, c]]) @ (src[0, 2:] - centre) + (tx, ty)
    dst = np.array([[*p, *q]])
    ex, ey = bn.field_map(dst, src, (w, h))
    mx, my = mesh.mesh_map(dst, src, (w, h))
    assert np.abs(mx - ex).max() < 2e-3 and np.abs(my - ey).max() < 2e-3


def test_plain_resize_of_the_grid_would_be_misaligned():
    """The pitfall the mesh avoids: cv2.resize centres vertices on pixel areas."""
    g = mesh.MeshGrid((300, 150))
    vx = g.vertices[:, :, 0].astype(np.float32)
    wrong = cv2.resize(vx, (300, 150), interpolation=cv2.INTER_LINEAR)
    right, _ = g.upsample(g.vertices)
    xs = np.arange(300, dtype=np.float32)[None, :]
    assert np.abs(wrong - xs).mean() > 1.0
    assert np.abs(right - xs).max() < 1e-3


def test_mesh_field_is_close_to_the_exact_field_for_drawn_mouths():
    w, h = 200, 120
    _, la = make_mouth(w, h, *MOUTHS["neutral"])
    _, lb = make_mouth(w, h, *MOUTHS["ah"])
    dst = 0.5 * la + 0.5 * lb
    ex, ey = bn.field_map(dst, la, (w, h))
    mx, my = mesh.mesh_map(dst, la, (w, h))
    err = np.hypot(mx - ex, my - ey)
    assert err.mean() < 0.5 and err.max() < 3.0


def test_warp_mesh_keeps_the_image_when_lines_do_not_move():
    img, lines = make_mouth(200, 120, *MOUTHS["smile"])
    assert np.array_equal(mesh.warp_mesh(img, lines, lines), bn.premultiply(img))


@settings(max_examples=25, deadline=None)
@given(st.integers(2, 90), st.integers(2, 90), st.integers(1, 12), st.integers(1, 40), st.integers(0, 10**6))
def test_banded_upsampling_matches_the_full_interpolation_product(w, h, cells, band, seed):
    g = mesh.MeshGrid((w, h), cells, band_cells=band)
    rng = np.random.default_rng(seed)
    meshes = g.vertices[None] + rng.normal(0, 3, (2, cells + 1, cells + 1, 2))
    ry = mesh.interpolation_matrix(h, cells).astype(np.float64)
    rx = mesh.interpolation_matrix(w, cells).astype(np.float64)
    want = np.einsum("yj,kjic,xi->kcyx", ry, meshes, rx)
    for reuse in (False, True, True):
        g.upsample_many(meshes[:1], reuse=True)
        mx, my = g.upsample_many(meshes, reuse=reuse)
        assert mx.shape == my.shape == (2, h, w) and mx.dtype == np.float32
        np.testing.assert_allclose(mx, want[:, 0], atol=1e-3)
        np.testing.assert_allclose(my, want[:, 1], atol=1e-3)
