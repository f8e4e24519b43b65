"""Warps sampled on a coarse quad mesh and upsampled to a dense map (Buck et al. §3.2).

The mesh has ``cells × cells`` quads (default 30×30, i.e. 31×31 vertices). Vertex ``(i, j)``
sits at pixel ``(i·(W−1)/cells, j·(H−1)/cells)``, so the corner vertices are exactly the corner
pixel centres and pixel ``x`` has grid coordinate ``x·cells/(W−1)``. The dense map is the
separable bilinear interpolation of the vertex values at those grid coordinates, computed with
small matrix products whose interpolation weights are precomputed per image size (an x pass in
bands of columns, then a y pass in bands of rows, each band needing only the few vertex columns
or rows around it). (A plain
``cv2.resize`` of the 31×31 grid would put vertex centres on pixel-area centres and shift the
map by pixels; ``cv2.remap`` or ``cv2.warpAffine`` of the grid quantise weights to 1/32 of a
cell — measured 0.4 px off for a 312×132 part, and no faster than the banded products.)

Mesh values here are always *source positions* (absolute pixel coordinates), so the identity
mesh is the vertex grid itself and bilinear upsampling of an affine field is exact.
"""

from __future__ import annotations

import numpy as np

from morph.beier_neely import DEFAULT_A, DEFAULT_B, DEFAULT_BORDER, DEFAULT_P, field_at, premultiply, remap_pm

DEFAULT_CELLS = 30


def interpolation_matrix(n_pixels: int, cells: int) -> np.ndarray:
    """``(n_pixels, cells+1)`` float32 linear-interpolation weights from vertices to pixels."""
    if n_pixels < 2:
        raise ValueError(f"mesh warps need images at least 2 pixels wide and high, got {n_pixels}")
    g = np.arange(n_pixels, dtype=np.float64) * cells / (n_pixels - 1)
    i0 = np.minimum(np.floor(g).astype(np.int64), cells - 1)
    f = g - i0
    m = np.zeros((n_pixels, cells + 1), dtype=np.float64)
    rows = np.arange(n_pixels)
    m[rows, i0] = 1.0 - f
    m[rows, i0 + 1] += f
    return m.astype(np.float32)


class MeshGrid:
    """The vertex positions and upsampling weights for one image size ``(w, h)``."""

    def __init__(self, size: tuple[int, int], cells: int = DEFAULT_CELLS, band_cells: int = 6):
        self.w, self.h = int(size[0]), int(size[1])
        self.cells = int(cells)
        n = self.cells + 1
        xs = np.arange(n, dtype=np.float64) * (self.w - 1) / self.cells
        ys = np.arange(n, dtype=np.float64) * (self.h - 1) / self.cells
        gx, gy = np.meshgrid(xs, ys)
        self.vertices = np.stack([gx, gy], axis=-1)  # (n, n, 2) float64, [row j, col i] = (x, y)
        self._cols: np.ndarray | None = None  # scratch for upsample_planes(reuse=True)
        self._dense: np.ndarray | None = None
        # Banded x pass of ``upsample_planes``: output columns [x0, x1) use vertex columns
        # [j0, j0 + band] only; weights stored transposed, (band+1, x1−x0).
        self._col_bands = [
            (x0, x1, j0, np.ascontiguousarray(wts.T)) for x0, x1, j0, wts in self._bands_of(self.w, band_cells)
        ]
        # ... and of the y pass: output rows [y0, y1) from vertex rows [j0, j0 + band], (y1−y0, band+1).
        self._row_bands = self._bands_of(self.h, band_cells)

    def _bands_of(self, n_pixels: int, band_cells: int, lo: int = 0, hi: int | None = None
                  ) -> list[tuple[int, int, int, np.ndarray]]:
        """``(p0, p1, j0, weights (p1−p0, band+1))``: pixels ``[p0, p1)`` of a side of
        ``n_pixels`` interpolate only vertices ``j0 .. j0+band`` (groups of ``band_cells`` cells).

        With ``lo``/``hi`` only pixels ``[lo, hi)`` are covered and ``p0, p1`` count from ``lo``."""
        hi = n_pixels if hi is None else hi  # (lo, hi): a sub-range, e.g. for a window of the image
        band = max(1, min(int(band_cells), self.cells))
        full = interpolation_matrix(n_pixels, self.cells)
        cell = np.minimum(np.floor(np.arange(n_pixels) * self.cells / (n_pixels - 1)).astype(np.int64), self.cells - 1)
        inside = (np.arange(n_pixels) >= lo) & (np.arange(n_pixels) < hi)
        out = []
        for c0 in range(0, self.cells, band):
            c1 = min(c0 + band, self.cells)  # cells [c0, c1) use vertices c0..c1
            ps = np.nonzero((cell >= c0) & (cell < c1) & inside)[0]
            if len(ps):
                p0, p1 = int(ps[0]), int(ps[-1]) + 1
                out.append((p0 - lo, p1 - lo, c0, np.ascontiguousarray(full[p0:p1, c0:c1 + 1])))
        return out

    @property
    def size(self) -> tuple[int, int]:
        return self.w, self.h

    def sample(
        self, dst_lines, src_lines, a: float = DEFAULT_A, b: float = DEFAULT_B, p: float = DEFAULT_P
    ) -> np.ndarray:
        """Exact Beier–Neely source positions at the vertices: ``(n, n, 2)`` float64."""
        n = self.cells + 1
        return field_at(self.vertices.reshape(-1, 2), dst_lines, src_lines, a, b, p).reshape(n, n, 2)

    def upsample(self, mesh: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Dense ``(map_x, map_y)`` float32 ``(h, w)`` from one ``(n, n, 2)`` mesh."""
        mx, my = self.upsample_many(np.asarray(mesh)[None])
        return mx[0], my[0]

    def upsample_many(self, meshes: np.ndarray, reuse: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Dense maps for ``k`` meshes ``(k, n, n, 2)``; see :meth:`upsample_planes`."""
        meshes = np.asarray(meshes, dtype=np.float32)
        return self.upsample_planes(np.moveaxis(meshes, -1, 1), reuse=reuse)

    def upsample_planes(self, planes: np.ndarray, reuse: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Dense maps for ``k`` meshes given as planes ``(k, 2, n, n)`` (x plane, y plane).

        An x pass on the mesh rows, then a y pass, each banded: a band of output columns (rows)
        takes only the few vertex columns (rows) around it (``band_cells`` + 1 taps instead of
        all ``n``; the skipped weights are exact zeros). Returns ``(map_x, map_y)``, each
        ``(k, h, w)`` float32 with contiguous ``[i]`` slices. With ``reuse`` the result lives in
        buffers of this grid that the next call overwrites (the per-frame path: no fresh
        megabytes to fault in every frame).
        """
        k, n = planes.shape[0], self.cells + 1
        comps = np.ascontiguousarray(planes, dtype=np.float32).reshape(k * 2, n, n)
        if reuse:
            if self._cols is None or self._cols.shape[0] < 2 * k:
                self._cols = np.empty((2 * k, n, self.w), np.float32)
                self._dense = np.empty((2 * k, self.h, self.w), np.float32)
            cols, dense = self._cols[: 2 * k], self._dense[: 2 * k]
        else:
            cols = np.empty((2 * k, n, self.w), np.float32)
            dense = np.empty((2 * k, self.h, self.w), np.float32)
        for x0, x1, j0, wts in self._col_bands:
            np.matmul(comps[:, :, j0:j0 + wts.shape[0]], wts, out=cols[:, :, x0:x1])
        for y0, y1, j0, wts in self._row_bands:
            np.matmul(wts, cols[:, j0:j0 + wts.shape[1], :], out=dense[:, y0:y1, :])
        dense = dense.reshape(k, 2, self.h, self.w)
        return dense[:, 0], dense[:, 1]

    def cell_spans(self) -> tuple[np.ndarray, np.ndarray]:
        """Per mesh cell, the pixel columns ``[x0, x1)`` (first array, ``(cells, 2)``) and rows
        ``[y0, y1)`` (second) whose values interpolate that cell's four vertices."""
        out = []
        for n_pixels in (self.w, self.h):
            cell = np.minimum(np.floor(np.arange(n_pixels) * self.cells / (n_pixels - 1)).astype(np.int64), self.cells - 1)
            spans = np.zeros((self.cells, 2), np.int64)
            for c in range(self.cells):
                ps = np.nonzero(cell == c)[0]
                spans[c] = (ps[0], ps[-1] + 1) if len(ps) else (0, 0)
            out.append(spans)
        return out[0], out[1]

    def upsample_rect(self, planes: np.ndarray, rect: tuple[int, int, int, int]) -> tuple[np.ndarray, np.ndarray]:
        """Like :meth:`upsample_planes`, for the pixels ``[x0, x1) × [y0, y1)`` only: maps
        ``(k, y1−y0, x1−x0)`` (the same values as the full maps there, up to float rounding).

        Only the vertex rows and columns around the rectangle are used. The result lives in
        buffers of this grid that the next call overwrites.
        """
        x0, y0, x1, y1 = (int(v) for v in rect)
        k, n = planes.shape[0], self.cells + 1
        rows = [(max(p0, y0), min(p1, y1), j0, wts[max(p0, y0) - p0:min(p1, y1) - p0])
                for p0, p1, j0, wts in self._row_bands if p0 < y1 and p1 > y0]
        cols = [(max(p0, x0), min(p1, x1), j0, wts[:, max(p0, x0) - p0:min(p1, x1) - p0])
                for p0, p1, j0, wts in self._col_bands if p0 < x1 and p1 > x0]
        v0 = rows[0][2]
        v1 = rows[-1][2] + rows[-1][3].shape[1]
        comps = np.ascontiguousarray(planes, dtype=np.float32).reshape(k * 2, n, n)[:, v0:v1]
        rw, rh = x1 - x0, y1 - y0
        size_c, size_d = 2 * k * (v1 - v0) * rw, 2 * k * rh * rw
        if getattr(self, "_flat", None) is None or self._flat.size < size_c + size_d:
            self._flat = np.empty(max(size_c + size_d, 2 * 3 * (n * self.w + self.h * self.w)), np.float32)
        col = self._flat[:size_c].reshape(2 * k, v1 - v0, rw)
        dense = self._flat[size_c:size_c + size_d].reshape(2 * k, rh, rw)
        for q0, q1, j0, wts in cols:
            np.matmul(comps[:, :, j0:j0 + wts.shape[0]], wts, out=col[:, :, q0 - x0:q1 - x0])
        for q0, q1, j0, wts in rows:
            np.matmul(wts, col[:, j0 - v0:j0 - v0 + wts.shape[1], :], out=dense[:, q0 - y0:q1 - y0, :])
        dense = dense.reshape(k, 2, rh, rw)
        return dense[:, 0], dense[:, 1]


def mesh_map(
    dst_lines,
    src_lines,
    size: tuple[int, int],
    cells: int = DEFAULT_CELLS,
    a: float = DEFAULT_A,
    b: float = DEFAULT_B,
    p: float = DEFAULT_P,
) -> tuple[np.ndarray, np.ndarray]:
    """Backward map of a ``(w, h)`` destination from the field sampled on the mesh (float32)."""
    grid = MeshGrid(size, cells)
    return grid.upsample(grid.sample(dst_lines, src_lines, a, b, p))


def warp_mesh(
    image: np.ndarray,
    src_lines,
    dst_lines,
    cells: int = DEFAULT_CELLS,
    a: float = DEFAULT_A,
    b: float = DEFAULT_B,
    p: float = DEFAULT_P,
    premultiplied: bool = False,
    border: str = DEFAULT_BORDER,
) -> np.ndarray:
    """Like ``beier_neely.warp`` but with the mesh-sampled field; premultiplied RGBA out."""
    pm = image if premultiplied else premultiply(image)
    h, w = pm.shape[:2]
    mx, my = mesh_map(dst_lines, src_lines, (w, h), cells, a, b, p)
    return remap_pm(pm, mx, my, border)
