"""The paper's expression map: one-hot at examples, convex weights, continuity, hull projection,
degenerate training sets."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from morph.expression_map import ExpressionMap


def _random_points(seed, n=6, k=3):
    return np.random.default_rng(seed).normal(size=(n, k))


def _dense(m, x, n):
    return m.weights_full(x, n)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("k", [3, 4])
def test_one_hot_at_training_points(seed, k):
    pts = _random_points(seed, n=6, k=k)
    m = ExpressionMap(pts)
    assert m.mode == "tri"
    for i, p in enumerate(pts):
        idx, w = m.weights(p)
        assert idx[0] == i
        np.testing.assert_allclose(w, [1, 0, 0], atol=1e-9)


def test_labels_are_returned():
    pts = _random_points(1, n=5)
    labels = [7, 3, 9, 0, 4]
    m = ExpressionMap(pts, labels=labels)
    for lab, p in zip(labels, pts):
        assert m.weights(p)[0][0] == lab


finite = st.floats(-5, 5, allow_nan=False, allow_infinity=False)


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 9), q=arrays(np.float64, 3, elements=st.floats(-50, 50)))
def test_weights_convex_everywhere(seed, n, q):
    pts = _random_points(seed, n=n, k=3)
    m = ExpressionMap(pts)
    idx, w = m.weights(q)
    assert idx.shape == (3,) and w.shape == (3,)
    assert np.all(w >= 0)
    assert abs(w.sum() - 1) < 1e-9
    assert np.all((idx >= 0) & (idx < n))
    assert np.all(np.diff(w) <= 1e-12)  # heaviest first


def test_inside_point_reproduces_barycentric_combination():
    # a planar set: PCA keeps the plane exactly, so barycentric weights reproduce the point
    rng = np.random.default_rng(3)
    base = rng.normal(size=(7, 2))
    pts = np.hstack([base, base @ np.array([[0.3], [-0.5]])])
    m = ExpressionMap(pts)
    for tri in m.triangles:
        w_true = rng.dirichlet([2, 2, 2])
        x = w_true @ pts[tri]
        dense = _dense(m, x, 7)
        np.testing.assert_allclose(dense @ pts, x, atol=1e-9)
        assert np.count_nonzero(dense > 1e-12) <= 3


def test_continuous_across_triangle_edges_and_hull():
    pts = _random_points(11, n=8, k=3)
    m = ExpressionMap(pts)
    rng = np.random.default_rng(0)
    # walk many straight lines through and out of the hull in small steps
    for _ in range(20):
        a = rng.normal(size=3) * 2.5
        b = rng.normal(size=3) * 2.5
        ts = np.linspace(0, 1, 2001)
        ws = np.array([_dense(m, a + t * (b - a), 8) for t in ts])
        step = np.abs(np.diff(ws, axis=0)).sum(axis=1)
        path_step = np.linalg.norm(m.project(b) - m.project(a)) / (len(ts) - 1)
        # Lipschitz-like: weights change in proportion to the step (no jumps at edges / hull)
        assert step.max() < 20 * path_step + 1e-9


def test_hull_projection_lands_on_nearest_edge():
    # a square in the first two feature axes (third constant): hull = the square
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.4, 0.5, 0]], dtype=float)
    m = ExpressionMap(pts)
    P = m.project(pts)
    rng = np.random.default_rng(5)
    for _ in range(200):
        q = rng.uniform(-3, 4, size=3)
        q[2] = 0
        loc = m.locate(q)
        dense = _dense(m, q, 5)
        landed = dense @ P  # the point the weights reproduce in the map plane
        qp = m.project(q)
        # brute-force nearest point on the hull (square boundary) in the map plane
        best = None
        for a, b in m.hull_edges:
            pa, pb = P[a], P[b]
            s = np.clip(np.dot(qp - pa, pb - pa) / np.dot(pb - pa, pb - pa), 0, 1)
            c = pa + s * (pb - pa)
            d = np.linalg.norm(qp - c)
            if best is None or d < best[0]:
                best = (d, c)
        inside = np.all((q[:2] >= 0) & (q[:2] <= 1))
        if inside:
            assert loc.outside == 0
            np.testing.assert_allclose(landed, qp, atol=1e-9)
        else:
            assert loc.outside == pytest.approx(best[0], abs=1e-9)
            np.testing.assert_allclose(landed, best[1], atol=1e-9)
            # only the two corners of that edge carry weight
            assert np.count_nonzero(dense > 1e-12) <= 2


def test_single_drawing():
    m = ExpressionMap([[0.1, 0.2, 0.3]])
    assert m.mode == "point"
    idx, w = m.weights([5, 5, 5])
    assert idx[0] == 0 and w[0] == 1 and w.sum() == 1


def test_two_drawings_interpolate_on_the_line_and_clamp():
    m = ExpressionMap([[0, 0, 0], [2, 0, 0]])
    assert m.mode == "line"
    np.testing.assert_allclose(_dense(m, [0.5, 0, 0], 2), [0.75, 0.25])
    np.testing.assert_allclose(_dense(m, [0.5, 3, 0], 2), [0.75, 0.25])  # off-line: projected
    np.testing.assert_allclose(_dense(m, [-4, 0, 0], 2), [1, 0])
    np.testing.assert_allclose(_dense(m, [9, 0, 0], 2), [0, 1])


def test_collinear_points_use_neighbours_on_the_line():
    d = np.array([1.0, -2.0, 0.5])
    ts = np.array([0.0, 3.0, 1.0, 2.0])
    m = ExpressionMap(ts[:, None] * d)
    assert m.mode == "line"
    np.testing.assert_allclose(_dense(m, 1.25 * d, 4), [0, 0, 0.75, 0.25])
    for i, t in enumerate(ts):
        np.testing.assert_allclose(_dense(m, t * d, 4), np.eye(4)[i], atol=1e-12)


def test_duplicates_are_merged():
    pts = _random_points(2, n=5)
    dup = np.vstack([pts, pts[1], pts[3]])
    m = ExpressionMap(dup)
    for i in range(5):
        assert m.weights(pts[i])[0][0] == i
    assert list(m.duplicate_of[5:]) == [1, 3]
    # all points identical: behaves like one drawing
    same = ExpressionMap(np.ones((4, 3)))
    assert same.mode == "point"
    np.testing.assert_allclose(same.weights([3, 3, 3])[1], [1, 0, 0])


def test_query_dimension_is_checked():
    m = ExpressionMap(_random_points(0))
    with pytest.raises(ValueError):
        m.weights([1, 2])
    with pytest.raises(ValueError):
        ExpressionMap(np.zeros((0, 3)))


def test_three_points_in_a_row_on_the_hull_keep_the_map_two_dimensional():
    """Grid points whose projection puts three in a row along the hull's edge: qhull leaves a
    zero-area triangle there (with or without joggling), which is dropped; every drawing is still
    reproduced at its own point (the map used to fall back to a line and blend them)."""
    pts = np.array([[1.0, 2, 2], [1, 2, 1], [0, 2, 1], [2, 1, 2], [0, 1, 0], [2, 2, 0], [1, 1, 0], [0, 1, 1]])
    m = ExpressionMap(pts)
    assert m.mode == "tri"
    for i, p in enumerate(pts):
        np.testing.assert_allclose(m.weights_full(p, len(pts)), np.eye(len(pts))[i], atol=1e-9)
    idx, w = m.weights(pts.mean(axis=0) + 5.0)  # far outside: on the hull, still a valid blend
    assert np.all(w >= 0) and abs(w.sum() - 1) < 1e-9


@settings(max_examples=200, deadline=None)
@given(
    pts=arrays(np.float64, st.tuples(st.integers(1, 8), st.just(3)), elements=st.integers(0, 2).map(float)),
    q=arrays(np.float64, 3, elements=st.floats(-3, 5)),
)
def test_grid_points_with_duplicates_and_collinear_sets(pts, q):
    m = ExpressionMap(pts)
    idx, w = m.weights(q)
    assert np.all(w >= 0) and abs(w.sum() - 1) < 1e-9
    # each training point is reproduced exactly by its group's representative
    for i, p in enumerate(pts):
        dense = m.weights_full(p, len(pts))
        rep = m.duplicate_of[i]
        assert dense[rep] == pytest.approx(1.0, abs=1e-9)
