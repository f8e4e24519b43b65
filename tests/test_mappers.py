"""Alternative mappers share the interface: ≤ 3 non-negative weights summing to one."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from morph.mappers import MAPPERS, ConvexMapper, RidgeRBFMapper, make_mapper, sparsify

KINDS = list(MAPPERS)


def _pts(seed, n=6, k=3):
    return np.random.default_rng(seed).normal(size=(n, k))


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("seed", range(3))
def test_examples_map_to_their_drawing(kind, seed):
    pts = _pts(seed)
    m = make_mapper(kind, pts)
    for i, p in enumerate(pts):
        idx, w = m.weights(p)
        assert idx[0] == i
        if kind == "ridge":  # regularised: close to, not exactly, one-hot
            assert w[0] > 0.6
        else:
            np.testing.assert_allclose(w, [1, 0, 0], atol=1e-6)


@pytest.mark.parametrize("kind", KINDS)
@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 1000), n=st.integers(1, 8), q=arrays(np.float64, 4, elements=st.floats(-20, 20)))
def test_weights_convex_and_at_most_three(kind, seed, n, q):
    m = make_mapper(kind, _pts(seed, n=n, k=4))
    idx, w = m.weights(q)
    assert idx.shape == (3,) and w.shape == (3,)
    assert np.all(w >= 0) and abs(w.sum() - 1) < 1e-9
    assert np.all((idx >= 0) & (idx < n))


@pytest.mark.parametrize("kind", ["cardinal", "convex", "ridge"])
def test_weights_change_smoothly_inside(kind):
    pts = _pts(4, n=6)
    m = make_mapper(kind, pts)
    a, b = pts[0], pts[3]
    ws = np.array([m.weights_full(a + t * (b - a), 6) for t in np.linspace(0, 1, 401)])
    assert np.abs(np.diff(ws, axis=0)).sum(axis=1).max() < 0.25


def test_cardinal_dense_weights_sum_to_one():
    m = make_mapper("cardinal", _pts(7, n=7))
    for q in np.random.default_rng(0).normal(size=(20, 3)):
        assert m.weights_dense(q).sum() == pytest.approx(1.0, abs=1e-9)


def test_convex_minimises_reconstruction_error_inside_hull():
    pts = _pts(9, n=6, k=3)
    m = ConvexMapper(pts, locality=1e-4)
    x = np.array([0.3, 0.3, 0.4]) @ pts[[0, 2, 4]]
    w = m.weights_dense(x)
    assert np.linalg.norm(w @ pts - x) < 0.02


def test_ridge_uses_blend_targets_and_gcv():
    rng = np.random.default_rng(1)
    pts = _pts(2, n=4)
    # 40 noisy frames, each paired with a blend of the two nearest drawings
    X, Y = [], []
    for _ in range(40):
        i, j = rng.choice(4, 2, replace=False)
        a = rng.uniform()
        X.append(a * pts[i] + (1 - a) * pts[j] + rng.normal(scale=0.02, size=3))
        y = np.zeros(4)
        y[i], y[j] = a, 1 - a
        Y.append(y)
    m = RidgeRBFMapper(np.array(X), targets=np.array(Y))
    assert 0 < m.lam <= 100 and np.isfinite(m.gcv)
    idx, w = m.weights(0.5 * pts[1] + 0.5 * pts[2])
    assert set(idx[:2]) == {1, 2}


def test_sparsify():
    idx, w = sparsify(np.array([0.1, -0.3, 0.5, 0.4, 0.3]))
    assert list(idx) == [2, 3, 4]
    np.testing.assert_allclose(w, np.array([0.5, 0.4, 0.3]) / 1.2)
    idx, w = sparsify(np.array([-1.0, -2.0]))
    assert idx[0] == 0 and list(w) == [1, 0, 0]


def test_unknown_mapper():
    with pytest.raises(ValueError, match="unknown mapper"):
        make_mapper("magic", _pts(0))
