"""The paper's expression map (Buck et al. 2000, §3.1): feature point -> three drawings and weights.

Fit: the training points (one per drawing, ``(n, k)`` scale-free features) are reduced to two
dimensions by PCA (SVD of the centred points) and triangulated (Delaunay, scipy). Query: the point
is projected, its triangle found, and the barycentric coordinates of that triangle's corners are
the weights of the three corresponding drawings. A point outside the convex hull is moved to the
nearest point on the hull and takes the triangle that abuts that hull edge, so the weights are
continuous everywhere (also across the hull boundary).

Degenerate training sets work: one drawing (always that drawing), two drawings or collinear points
(1-D interpolation between neighbours on the line, clamped at the ends), duplicate points (merged:
the first drawing of a group of coincident points represents it).

The per-query path is plain Python floats over tables precomputed at fit time: the last triangle
is tried first, then a visibility walk over triangle neighbours; scipy is not called per query.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ExpressionMap", "Location"]

# Relative tolerances (of the spread of the training points).
_DUP_TOL = 1e-9
_FLAT_TOL = 1e-6


@dataclass(frozen=True, slots=True)
class Location:
    """Where a query fell: three drawing indices and weights (weights sorted high to low),
    the triangle (``-1`` in the 0-/1-D cases) and the distance outside the hull in
    projected units (0 inside)."""

    indices: tuple[int, int, int]
    weights: tuple[float, float, float]
    triangle: int
    outside: float


class ExpressionMap:
    """Fit on ``points`` ``(n, k)``: row *i* is the training point of drawing ``labels[i]``.

    ``labels`` defaults to ``range(n)``; returned indices are labels, so a map fitted on a subset
    of a part's drawings still answers in that part's drawing indices. ``dims`` is the PCA
    dimension (the paper's j = 2; 1 is allowed).
    """

    def __init__(self, points, labels=None, dims: int = 2):
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim == 1:
            pts = pts[:, None]
        if pts.ndim != 2 or len(pts) == 0:
            raise ValueError(f"expected an (n, k) array of training points with n >= 1, got shape {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise ValueError("training points must be finite")
        if dims not in (1, 2):
            raise ValueError(f"dims must be 1 or 2, got {dims}")
        n, k = pts.shape
        self.labels = np.arange(n) if labels is None else np.asarray(labels, dtype=np.intp)
        if len(self.labels) != n:
            raise ValueError(f"{len(self.labels)} labels for {n} training points")
        self.points = pts
        self.k = k
        self.mean = pts.mean(axis=0)
        centred = pts - self.mean
        spread = float(np.sqrt((centred**2).sum(axis=1).max())) if n > 1 else 0.0
        self.scale = spread if spread > 0 else 1.0

        # PCA by SVD; keep up to `dims` axes that carry real spread.
        if n > 1 and spread > 0:
            _, s, vt = np.linalg.svd(centred, full_matrices=False)
            keep = [i for i in range(min(dims, len(s))) if s[i] > _FLAT_TOL * s[0]]
            self.basis = vt[keep]
            self.singular_values = s
        else:
            self.basis = np.zeros((0, k))
            self.singular_values = np.zeros(0)
        self.dim = len(self.basis)
        proj = centred @ self.basis.T  # (n, dim)

        # Merge coincident projected points (first one represents the group).
        rep = np.arange(n)
        tol = _DUP_TOL * self.scale + 1e-300
        for i in range(n):
            for j in range(i):
                if rep[j] == j and np.all(np.abs(proj[i] - proj[j]) <= tol):
                    rep[i] = j
                    break
        self._unique = np.flatnonzero(rep == np.arange(n))
        self.duplicate_of = rep
        self.points2d = np.zeros((n, 2))
        self.points2d[:, : self.dim] = proj
        self.triangles = np.zeros((0, 3), dtype=np.intp)
        self.hull_edges = np.zeros((0, 2), dtype=np.intp)

        self._mode = "point"
        uniq = self._unique
        if len(uniq) >= 2 and self.dim >= 1:
            up = self.points2d[uniq]
            if self.dim == 2 and len(uniq) >= 3 and self._fit_delaunay(up, uniq):
                self._mode = "tri"
            else:
                self._fit_line(up, uniq)
                self._mode = "line"
        self._last = 0
        # projection as Python-float rows, for the scalar query path
        self._P = [list(map(float, row)) for row in self.basis]
        self._m = list(map(float, self.mean))

    # ------------------------------------------------------------------------------------ fit
    def _fit_delaunay(self, up: np.ndarray, uniq: np.ndarray) -> bool:
        from scipy.spatial import Delaunay, QhullError

        # A nearly flat cloud (second axis tiny vs first) gives sliver triangles: use a line.
        ext = up.max(axis=0) - up.min(axis=0)
        if ext[1] <= _FLAT_TOL * max(ext[0], 1e-300):
            return False
        # Three or more collinear points on the hull can leave a zero-area simplex along that edge
        # (joggling the input, "QJ", does not always remove it): such slivers are dropped, and the
        # triangles beside them then abut the hull.
        area_tol = _FLAT_TOL * float((ext * ext).sum())
        for options in (None, "QJ"):
            try:
                tri = Delaunay(up, qhull_options=options)
            except (QhullError, ValueError):
                continue
            e1 = up[tri.simplices[:, 1]] - up[tri.simplices[:, 0]]
            e2 = up[tri.simplices[:, 2]] - up[tri.simplices[:, 0]]
            area2 = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])  # twice each triangle's area
            keep = (area2 > area_tol) & np.all(np.isfinite(tri.transform), axis=(1, 2))
            if keep.any() and np.isin(np.arange(len(up)), tri.simplices[keep]).all():
                break
        else:
            return False
        renumber = np.full(len(keep) + 1, -1, dtype=np.intp)  # old simplex (or -1) -> kept index or -1
        renumber[:-1][keep] = np.arange(int(keep.sum()))
        simp = tri.simplices[keep]
        T = tri.transform[keep]
        neighbours = renumber[tri.neighbors[keep]]
        self._delaunay = tri
        self._renumber = renumber
        self.triangles = uniq[simp]  # in training-point indices
        # Barycentric tables: c = T[:2] @ (p - T[2]); b = (c0, c1, 1 - c0 - c1)
        self._tri_T = [
            (float(t[0, 0]), float(t[0, 1]), float(t[1, 0]), float(t[1, 1]), float(t[2, 0]), float(t[2, 1])) for t in T
        ]
        self._tri_lab = [tuple(int(self.labels[v]) for v in s) for s in self.triangles]
        self._nbr = [tuple(int(v) for v in row) for row in neighbours]
        # Hull edges: (a, b) training indices, the triangle abutting it and which corner is opposite.
        edges = []
        for t, row in enumerate(neighbours):
            for c in range(3):
                if row[c] == -1:
                    a, b = [simp[t][j] for j in range(3) if j != c]
                    edges.append((a, b, t, c))
        self.hull_edges = np.array([(uniq[a], uniq[b]) for a, b, _, _ in edges], dtype=np.intp)
        self._edges = []
        for a, b, t, c in edges:
            ax, ay = map(float, up[a])
            bx, by = map(float, up[b])
            dx, dy = bx - ax, by - ay
            L2 = dx * dx + dy * dy
            # corner positions of a and b inside triangle t
            ca = int(np.flatnonzero(simp[t] == a)[0])
            cb = int(np.flatnonzero(simp[t] == b)[0])
            self._edges.append((ax, ay, dx, dy, 1.0 / L2, t, ca, cb))
        return True

    def _fit_line(self, up: np.ndarray, uniq: np.ndarray) -> None:
        # Points on (or near) a line: the first PCA axis orders them.
        u = up[:, 0]
        order = np.argsort(u, kind="stable")
        self._line_u = [float(u[i]) for i in order]
        self._line_lab = [int(self.labels[uniq[i]]) for i in order]
        self._line_idx = uniq[order]

    # --------------------------------------------------------------------------------- query
    def project(self, x) -> np.ndarray:
        """Project feature vector(s) ``(k,)`` or ``(m, k)`` to the 2-D map plane (zeros on unused axes)."""
        x = np.asarray(x, dtype=np.float64)
        p = (x - self.mean) @ self.basis.T
        out = np.zeros(p.shape[:-1] + (2,))
        out[..., : self.dim] = p
        return out

    def _proj2(self, x) -> tuple[float, float]:
        m = self._m
        if self.dim == 0:
            return 0.0, 0.0
        d = [float(a) - b for a, b in zip(x, m)]
        P = self._P
        px = sum(a * b for a, b in zip(P[0], d))
        py = sum(a * b for a, b in zip(P[1], d)) if self.dim > 1 else 0.0
        return px, py

    def locate(self, x) -> Location:
        """Full answer for one feature vector ``(k,)``: see :class:`Location`."""
        if len(x) != self.k:
            raise ValueError(f"expected a feature vector of length {self.k}, got {len(x)}")
        px, py = self._proj2(x)
        return self.locate2d(px, py)

    def locate2d(self, px: float, py: float) -> Location:
        """As :meth:`locate`, for a point already in the map plane."""
        mode = self._mode
        if mode == "tri":
            return self._locate_tri(px, py)
        if mode == "line":
            return self._locate_line(px, py)
        lab = int(self.labels[self._unique[0]])
        dist = math.hypot(px, py)
        return Location((lab, lab, lab), (1.0, 0.0, 0.0), -1, dist)

    def weights(self, x) -> tuple[np.ndarray, np.ndarray]:
        """``(idx3, w3)``: three drawing indices (int) and non-negative weights summing to 1,
        heaviest first. Indices may repeat with weight 0 when fewer than three drawings blend."""
        loc = self.locate(x)
        return np.array(loc.indices, dtype=np.intp), np.array(loc.weights)

    def weights_full(self, x, n: int | None = None) -> np.ndarray:
        """Dense weight vector over drawing labels (length ``n``, default ``max(label) + 1``)."""
        loc = self.locate(x)
        w = np.zeros(int(self.labels.max()) + 1 if n is None else n)
        for i, a in zip(loc.indices, loc.weights):
            w[i] += a
        return w

    def _locate_tri(self, px: float, py: float) -> Location:
        T = self._tri_T
        nbr = self._nbr
        t = self._last
        ntri = len(T)
        # visibility walk from the last triangle
        for _ in range(ntri + 2):
            a, b, c, d, rx, ry = T[t]
            qx, qy = px - rx, py - ry
            b0 = a * qx + b * qy
            b1 = c * qx + d * qy
            b2 = 1.0 - b0 - b1
            eps = -1e-12
            if b0 >= eps and b1 >= eps and b2 >= eps:
                self._last = t
                return self._finish(t, b0, b1, b2, 0.0)
            # step across the edge opposite the most negative coordinate
            if b0 <= b1 and b0 <= b2:
                j = 0
            elif b1 <= b2:
                j = 1
            else:
                j = 2
            nt = nbr[t][j]
            if nt == -1:
                return self._to_hull(px, py)
            t = nt
        # (a Delaunay walk does not cycle; this is a guard for numerical ties)
        s = int(self._renumber[int(self._delaunay.find_simplex(np.array([px, py])))])
        if s < 0:
            return self._to_hull(px, py)
        self._last = s
        a, b, c, d, rx, ry = T[s]
        qx, qy = px - rx, py - ry
        b0 = a * qx + b * qy
        b1 = c * qx + d * qy
        return self._finish(s, b0, b1, 1.0 - b0 - b1, 0.0)

    def _to_hull(self, px: float, py: float) -> Location:
        best = None
        for ax, ay, dx, dy, inv, t, ca, cb in self._edges:
            s = ((px - ax) * dx + (py - ay) * dy) * inv
            s = 0.0 if s < 0.0 else 1.0 if s > 1.0 else s
            ex, ey = ax + s * dx - px, ay + s * dy - py
            d2 = ex * ex + ey * ey
            if best is None or d2 < best[0]:
                best = (d2, s, t, ca, cb)
        d2, s, t, ca, cb = best
        bary = [0.0, 0.0, 0.0]
        bary[ca] = 1.0 - s
        bary[cb] = s
        self._last = t
        return self._finish(t, bary[0], bary[1], bary[2], math.sqrt(d2))

    def _finish(self, t: int, b0: float, b1: float, b2: float, outside: float) -> Location:
        b0 = b0 if b0 > 0.0 else 0.0
        b1 = b1 if b1 > 0.0 else 0.0
        b2 = b2 if b2 > 0.0 else 0.0
        s = b0 + b1 + b2
        b0, b1, b2 = b0 / s, b1 / s, b2 / s
        l0, l1, l2 = self._tri_lab[t]
        # sort heaviest first (three elements: a tiny network)
        if b1 > b0:
            b0, b1, l0, l1 = b1, b0, l1, l0
        if b2 > b1:
            b1, b2, l1, l2 = b2, b1, l2, l1
            if b1 > b0:
                b0, b1, l0, l1 = b1, b0, l1, l0
        return Location((l0, l1, l2), (b0, b1, b2), t, outside)

    def _locate_line(self, px: float, py: float) -> Location:
        us = self._line_u
        labs = self._line_lab
        off = abs(py)
        if px <= us[0]:
            return Location((labs[0], labs[0], labs[0]), (1.0, 0.0, 0.0), -1, math.hypot(us[0] - px, off))
        if px >= us[-1]:
            return Location((labs[-1], labs[-1], labs[-1]), (1.0, 0.0, 0.0), -1, math.hypot(px - us[-1], off))
        lo = 0
        hi = len(us) - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if us[mid] <= px:
                lo = mid
            else:
                hi = mid
        s = (px - us[lo]) / (us[hi] - us[lo])
        a, b = labs[lo], labs[hi]
        if s > 0.5:
            return Location((b, a, b), (s, 1.0 - s, 0.0), -1, off)
        return Location((a, b, a), (1.0 - s, s, 0.0), -1, off)

    # ------------------------------------------------------------------------------- helpers
    @property
    def mode(self) -> str:
        """``"tri"`` (Delaunay), ``"line"`` (collinear or two drawings) or ``"point"`` (one)."""
        return self._mode

    def outside_distance(self, x) -> float:
        """How far the projected point lies outside the hull (projected units; 0 inside)."""
        return self.locate(x).outside
