"""Alternative expression mappers with the :class:`~morph.expression_map.ExpressionMap` interface.

Every mapper is fitted on training points ``(n, k)`` (row *i* belongs to drawing ``labels[i]``)
and answers ``.weights(x) -> (idx3, w3)``: at most three drawings, non-negative weights summing
to one, heaviest first. Mappers that produce a dense weight vector (possibly with negative entries)
are clamped at zero, cut to their three largest entries and renormalised (:func:`sparsify`).

* ``"delaunay"`` — the paper's mapper (PCA to 2-D, Delaunay, barycentric), :class:`ExpressionMap`.
* ``"cardinal"`` — cardinal-basis RBF (online expression mapping, ICEC 2007): a linear part fitted
  by least squares to w_i(p_j) = δ_ij plus cubic B-spline radial terms on the residuals, each
  scaled by the distance from its example to the nearest other example. Exact at the examples.
* ``"ridge"`` — Gaussian RBF ridge regression (Deng et al. 2006), λ chosen by generalised
  cross-validation. Accepts soft targets (a training frame paired with a *blend* of drawings).
* ``"convex"`` — the paper's stated objective solved directly: non-negative α summing to one that
  minimise ‖m − Σ α_i m_i‖², with a small locality term Σ α_i² ‖m − m_i‖² that makes the answer
  unique and exact at the examples (non-negative least squares).
"""

from __future__ import annotations

import math

import numpy as np

from morph.expression_map import ExpressionMap

__all__ = [
    "MAPPERS",
    "CardinalRBFMapper",
    "ConvexMapper",
    "ExpressionMap",
    "RidgeRBFMapper",
    "make_mapper",
    "sparsify",
]


def sparsify(w: np.ndarray, labels: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Dense weights ``(n,)`` -> ``(idx3, w3)``: clamp at 0, keep the three largest, renormalise.

    ``labels`` maps positions to drawing indices. If nothing positive is left, the largest entry
    wins outright. With fewer than three drawings, indices repeat with weight 0.
    """
    w = np.asarray(w, dtype=np.float64)
    n = len(w)
    lab = np.arange(n) if labels is None else labels
    if n <= 3:
        order = np.argsort(-w, kind="stable")
    else:
        top = np.argpartition(-w, 2)[:3]
        order = top[np.argsort(-w[top], kind="stable")]
    ww = np.maximum(w[order], 0.0)
    s = ww.sum()
    if not s > 0 or not math.isfinite(s):
        ww = np.zeros(len(order))
        ww[0] = 1.0
    else:
        ww /= s
    idx = lab[order]
    if len(idx) < 3:
        pad = 3 - len(idx)
        idx = np.concatenate([idx, np.full(pad, idx[0])])
        ww = np.concatenate([ww, np.zeros(pad)])
    return idx.astype(np.intp), ww


def _pca_reduce(pts: np.ndarray, rel_tol: float = 1e-3, max_dims: int | None = None):
    """Mean and basis of the principal axes whose variance exceeds ``rel_tol`` of the largest."""
    mean = pts.mean(axis=0)
    c = pts - mean
    if len(pts) < 2 or not np.any(c):
        return mean, np.zeros((0, pts.shape[1]))
    _, s, vt = np.linalg.svd(c, full_matrices=False)
    var = s**2
    keep = var > rel_tol * var[0]
    basis = vt[keep]
    if max_dims is not None:
        basis = basis[:max_dims]
    return mean, basis


def _check_points(points, labels):
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim == 1:
        pts = pts[:, None]
    if pts.ndim != 2 or len(pts) == 0 or not np.all(np.isfinite(pts)):
        raise ValueError(f"expected a finite (n, k) array of training points with n >= 1, got shape {pts.shape}")
    lab = np.arange(len(pts)) if labels is None else np.asarray(labels, dtype=np.intp)
    if len(lab) != len(pts):
        raise ValueError(f"{len(lab)} labels for {len(pts)} training points")
    return pts, lab


class _DenseMapper:
    """Shared query path: reduce, evaluate dense weights, sparsify."""

    points: np.ndarray
    labels: np.ndarray

    def weights_dense(self, x) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def weights(self, x) -> tuple[np.ndarray, np.ndarray]:
        """``(idx3, w3)`` for one feature vector ``(k,)``."""
        return sparsify(self.weights_dense(x), self.labels)

    def weights_full(self, x, n: int | None = None) -> np.ndarray:
        """The sparsified weights as a dense vector over drawing labels."""
        idx, w = self.weights(x)
        out = np.zeros(int(self.labels.max()) + 1 if n is None else n)
        np.add.at(out, idx, w)
        return out


def _bspline3(t: np.ndarray) -> np.ndarray:
    """Cubic B-spline on [0, 2), scaled so that B(0) = 1."""
    t = np.abs(t)
    out = np.where(t < 1.0, 2.0 / 3.0 - t**2 + 0.5 * t**3, np.where(t < 2.0, (2.0 - t) ** 3 / 6.0, 0.0))
    return out * 1.5


class CardinalRBFMapper(_DenseMapper):
    """Cardinal-basis RBF: w_i(p) = Σ_l a_il A_l(p) + Σ_j r_ji B(‖p − p_j‖ / α_j).

    ``p`` are the PCA coordinates of the features; axes with variance below ``rel_tol`` of the
    largest are dropped (the 2007 paper drops eigenvalues under 1e-5 in its units; relative 1e-3
    here, because the linear part extrapolates steeply along a nearly empty axis, so tracker noise
    along it would swing the weights); ``A = (1, p)``; α_j is the distance from example j to its nearest other example.
    The dense weights sum to one (the constant is in the linear basis) and are exact at the
    examples; they can be negative, hence :func:`sparsify`.
    """

    def __init__(self, points, labels=None, rel_tol: float = 1e-3):
        pts, self.labels = _check_points(points, labels)
        self.points = pts
        n = len(pts)
        self.mean, self.basis = _pca_reduce(pts, rel_tol)
        p = (pts - self.mean) @ self.basis.T
        A = np.hstack([np.ones((n, 1)), p])
        eye = np.eye(n)
        self.a, *_ = np.linalg.lstsq(A, eye, rcond=None)  # (1+d, n)
        resid = eye - A @ self.a
        if n > 1:
            d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2)
            np.fill_diagonal(d, np.inf)
            alpha = d.min(axis=1)
            alpha = np.where(np.isfinite(alpha) & (alpha > 0), alpha, 1.0)
            dd = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2)
            phi = _bspline3(dd / alpha[None, :])  # phi[j, m] = B(|p_j - p_m| / alpha_m)
            self.r, *_ = np.linalg.lstsq(phi, resid, rcond=None)  # (n centres, n outputs)
        else:
            alpha = np.ones(1)
            self.r = np.zeros((1, 1))
        self.alpha = alpha
        self._p = p

    def weights_dense(self, x) -> np.ndarray:
        q = (np.asarray(x, dtype=np.float64) - self.mean) @ self.basis.T
        lin = self.a[0] + q @ self.a[1:]
        if len(self._p) > 1:
            dist = np.sqrt(((self._p - q) ** 2).sum(axis=1))
            lin = lin + _bspline3(dist / self.alpha) @ self.r
        return lin


class RidgeRBFMapper(_DenseMapper):
    """Gaussian RBF ridge regression with λ chosen by generalised cross-validation.

    F(X) = Σ_c w_c exp(−‖X − X_c‖² / 2σ²) over the training points as centres, in PCA coordinates
    (up to ``max_dims`` axes, Deng et al. used 4). σ is the mean distance to the nearest other
    training point. ``targets`` ``(n, n_drawings)`` may hold blends (rows summing to one);
    by default row i is one-hot at ``labels[i]``. λ minimises
    GCV(λ) = n ‖(I − P_λ) Y‖² / trace(I − P_λ)² over a log grid, P_λ = H (HᵀH + λI)⁻¹ Hᵀ.
    """

    def __init__(self, points, labels=None, targets=None, max_dims: int = 4, sigma: float | None = None):
        pts, lab = _check_points(points, labels)
        self.points = pts
        n = len(pts)
        if targets is None:
            uniq = np.unique(lab)
            self.labels = uniq
            Y = (lab[:, None] == uniq[None, :]).astype(np.float64)
        else:
            Y = np.asarray(targets, dtype=np.float64)
            if Y.shape[0] != n:
                raise ValueError(f"targets has {Y.shape[0]} rows for {n} training points")
            self.labels = np.arange(Y.shape[1])
        self.mean, self.basis = _pca_reduce(pts, max_dims=max_dims)
        p = (pts - self.mean) @ self.basis.T
        self._p = p
        d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2)
        if sigma is None:
            if n > 1:
                dn = d + np.diag(np.full(n, np.inf))
                nn = dn.min(axis=1)
                nn = nn[np.isfinite(nn) & (nn > 0)]
                sigma = float(nn.mean()) if len(nn) else 1.0
            else:
                sigma = 1.0
        self.sigma = sigma
        H = np.exp(-(d**2) / (2.0 * sigma**2))
        self.lam, self.gcv = self._choose_lambda(H, Y)
        self.w = np.linalg.solve(H.T @ H + self.lam * np.eye(n), H.T @ Y)  # (n centres, m outputs)

    @staticmethod
    def _choose_lambda(H: np.ndarray, Y: np.ndarray, max_fit_error: float = 0.05) -> tuple[float, float]:
        """λ with the lowest GCV among those whose fit stays within ``max_fit_error`` (RMS) of the
        targets. With one training point per drawing, leave-one-out cannot predict a drawing no
        other point shows, so unconstrained GCV would always choose the heaviest smoothing."""
        n = len(H)
        U, s, _ = np.linalg.svd(H, full_matrices=False)
        UtY = U.T @ Y
        resid_out = max(float((Y**2).sum() - (UtY**2).sum()), 0.0)  # part of Y outside span(U)
        best = (1e-8, math.inf)
        for lam in np.logspace(-8, 2, 41):
            f = s**2 / (s**2 + lam)  # eigenvalues of the hat matrix P
            r = float((((1 - f)[:, None] * UtY) ** 2).sum()) + resid_out
            if math.sqrt(r / Y.size) > max_fit_error:
                continue
            tr = n - float(f.sum())
            if tr <= 1e-9:
                continue
            g = n * r / tr**2
            if g < best[1]:
                best = (float(lam), g)
        return best

    def weights_dense(self, x) -> np.ndarray:
        q = (np.asarray(x, dtype=np.float64) - self.mean) @ self.basis.T
        h = np.exp(-((self._p - q) ** 2).sum(axis=1) / (2.0 * self.sigma**2))
        return h @ self.w


class ConvexMapper(_DenseMapper):
    """Non-negative α with Σα = 1 minimising ‖m − Σ α_i m_i‖² + μ Σ α_i² ‖m − m_i‖² (scipy NNLS).

    The sum-to-one constraint is a heavily weighted extra row; μ (``locality``, relative to the
    spread of the training points) prefers nearby drawings, which makes the solution unique,
    continuous and one-hot at the examples.
    """

    def __init__(self, points, labels=None, locality: float = 0.1, sum_weight: float = 100.0):
        pts, self.labels = _check_points(points, labels)
        self.points = pts
        n, k = pts.shape
        spread = float(np.linalg.norm(pts - pts.mean(axis=0), axis=1).max()) if n > 1 else 1.0
        self.spread = spread if spread > 0 else 1.0
        self.locality = locality
        self.rho = sum_weight
        self._A = np.zeros((k + 1 + n, n))
        self._A[:k] = pts.T / self.spread
        self._A[k] = self.rho
        self._b = np.zeros(k + 1 + n)
        self._b[k] = self.rho
        self._diag = np.arange(n)

    def weights_dense(self, x) -> np.ndarray:
        from scipy.optimize import nnls

        x = np.asarray(x, dtype=np.float64)
        k = self.points.shape[1]
        A = self._A
        b = self._b
        b[:k] = x / self.spread
        d = np.sqrt(((self.points - x) ** 2).sum(axis=1)) / self.spread
        A[k + 1 + self._diag, self._diag] = math.sqrt(self.locality) * d
        w, _ = nnls(A, b)
        s = w.sum()
        return w / s if s > 0 else w


MAPPERS: dict[str, type] = {
    "delaunay": ExpressionMap,
    "cardinal": CardinalRBFMapper,
    "ridge": RidgeRBFMapper,
    "convex": ConvexMapper,
}
"""Selectable mappers by name; ``"delaunay"`` is the paper's."""


def make_mapper(kind: str, points, labels=None, targets=None):
    """Fit the mapper called ``kind`` (see :data:`MAPPERS`). ``targets`` (soft blends per point)
    is used by ``"ridge"`` only; the others need one drawing per point (``labels``)."""
    try:
        cls = MAPPERS[kind]
    except KeyError:
        raise ValueError(f"unknown mapper {kind!r} (choose from {', '.join(MAPPERS)})") from None
    if kind == "ridge":
        return cls(points, labels=labels, targets=targets)
    return cls(points, labels=labels)
