"""Per-performer colour classifiers, learned from pixels around the calibration clicks.

Each classifier separates one *target* class (pupil, lip, skin) from the colours seen around
it. Both sides are modelled as small Gaussian mixtures in a feature space of luminance and
brightness-normalised chroma; the decision is baked once into a 64³ lookup table indexed by
the top six bits of B, G and R, so classifying a region of interest costs one table lookup
per pixel and no colour conversion. A colour that both sides claim (the target is not
clearly more likely) is background, as in Guenter et al.'s 32³ tables.

Nothing here knows what colour lips or pupils "should" be: dark skin with brown lips works
as long as the two differ somewhat in chroma or brightness on the calibration frame.
"""

from __future__ import annotations

import cv2
import numpy as np

BITS = 6
"""Bits per channel of the lookup table (64 levels, 262 144 entries)."""
_SHIFT = 8 - BITS
_N = 1 << BITS


CHROMA_PAD = 24.0
"""Added to ``b + g + r`` (grey levels) under the chroma ratios (:func:`features`,
:func:`tracker.mouth_model.profile_features`): it keeps near-black pixels from getting wild chroma
from sensor noise."""


def features(bgr: np.ndarray, y_weight: float) -> np.ndarray:
    """Colour features ``(n, 3)`` of ``(n, 3)`` BGR values (any float or int dtype).

    Luminance ``Y/255`` scaled by ``y_weight`` and two chroma ratios that do not change
    when the light gets brighter or dimmer (over ``b + g + r`` plus :data:`CHROMA_PAD`).
    """
    c = np.asarray(bgr, dtype=np.float64).reshape(-1, 3)
    b, g, r = c[:, 0], c[:, 1], c[:, 2]
    s = b + g + r + CHROMA_PAD
    y = 0.114 * b + 0.587 * g + 0.299 * r
    return np.stack([y / 255.0 * y_weight, (r - g) / s, (r + g - 2.0 * b) / (2.0 * s)], axis=1)


SKIN_CHROMA = 0.1
"""Least chroma (the median length of :func:`features`' two chroma ratios over the skin round the
mouth: ``MouthModel.skin_sat``) of skin in a colour camera's picture of a lit face: the nine
shared clips' skins round the mouth have 0.106-0.29. A camera or a dim room that washes the colours
out leaves less (those clips with 35 % of their colour, the ``washed`` stress copies: 0.037-0.098),
and every chroma rule of the mouth then reads lips as skin — the lips' red lead, a column's
unlikeness to the cheek, the split's lip rows (6 of those 18 clip-modes met every target, their mean
mouth-opening correlation 0.79): :func:`chroma_gain` scales the mouth's chroma back up. (The eyes'
skin model is left as it is: with its chroma scaled alike, those clips' eye-opening correlations
fell, 0.77 -> 0.73 on average.)"""
CHROMA_GAIN_MAX = 3.0
"""Most :func:`chroma_gain` scales chroma by: a picture with next to no colour (a monochrome camera,
skin chroma 0.007) has none to bring back, only noise."""


def chroma_gain(skin_sat: float) -> float:
    """The factor the mouth's colour features take chroma by, for skin of chroma ``skin_sat``
    (see :data:`SKIN_CHROMA`): 1 for skin with at least :data:`SKIN_CHROMA`, more where the camera or
    the light washed the colours out, at most :data:`CHROMA_GAIN_MAX`."""
    return min(max(SKIN_CHROMA / max(float(skin_sat), 1e-6), 1.0), CHROMA_GAIN_MAX)


_MIN_STD = np.array([0.035, 0.012, 0.012])
"""Floor on each feature's standard deviation (before the luminance weight)."""


def _kmeans(x: np.ndarray, k: int, seed: int = 0, iters: int = 12) -> np.ndarray:
    """Labels of a tiny deterministic k-means (farthest-point start)."""
    n = len(x)
    if k <= 1 or n <= k:
        return np.zeros(n, dtype=np.int64)
    centres = [x[np.argmin(x[:, 0])]]
    for _ in range(1, k):
        d = np.min([((x - c) ** 2).sum(1) for c in centres], axis=0)
        centres.append(x[int(np.argmax(d))])
    c = np.array(centres)
    lab = np.zeros(n, dtype=np.int64)
    for _ in range(iters):
        lab = np.argmin(((x[:, None, :] - c[None]) ** 2).sum(2), axis=1)
        for j in range(k):
            m = lab == j
            if m.any():
                c[j] = x[m].mean(0)
    return lab


class Gaussians:
    """A few Gaussian components (means, inverse covariances) fitted by k-means."""

    def __init__(self, x: np.ndarray, k: int, min_std: np.ndarray, min_count: int = 6):
        lab = _kmeans(x, k)
        self.means: list[np.ndarray] = []
        self.icovs: list[np.ndarray] = []
        self.logdets: list[float] = []
        for j in range(int(lab.max()) + 1 if len(lab) else 0):
            pts = x[lab == j]
            if len(pts) < min_count and j > 0:
                continue
            mu = pts.mean(0)
            cov = np.cov(pts.T) if len(pts) > 3 else np.zeros((3, 3))
            cov = cov + np.diag(min_std**2)
            self.means.append(mu)
            self.icovs.append(np.linalg.inv(cov))
            self.logdets.append(float(np.linalg.slogdet(cov)[1]))

    def d2(self, x: np.ndarray) -> np.ndarray:
        """Smallest Mahalanobis distance² (plus log-det, i.e. a negative log-likelihood) of each row."""
        out = np.full(len(x), np.inf)
        for mu, ic, ld in zip(self.means, self.icovs, self.logdets):
            d = x - mu
            out = np.minimum(out, np.einsum("ni,ij,nj->n", d, ic, d) + ld)
        return out

    def mahalanobis2(self, x: np.ndarray) -> np.ndarray:
        out = np.full(len(x), np.inf)
        for mu, ic in zip(self.means, self.icovs):
            d = x - mu
            out = np.minimum(out, np.einsum("ni,ij,nj->n", d, ic, d))
        return out


_GRID_CACHE: np.ndarray | None = None
_GRID_FEATURES: np.ndarray | None = None


def _bin_colours() -> np.ndarray:
    """BGR centre of every table bin, ``(64³, 3)`` float, in table index order."""
    global _GRID_CACHE
    if _GRID_CACHE is None:
        v = (np.arange(_N) << _SHIFT) + (1 << _SHIFT) / 2.0 - 0.5
        b, g, r = np.meshgrid(v, v, v, indexing="ij")
        _GRID_CACHE = np.stack([b.ravel(), g.ravel(), r.ravel()], axis=1)
    return _GRID_CACHE


def grid_features() -> np.ndarray:
    """:func:`features` (luminance weight 1) of every bin centre, ``(64³, 3)`` float32, computed once."""
    global _GRID_FEATURES
    if _GRID_FEATURES is None:
        _GRID_FEATURES = np.ascontiguousarray(features(_bin_colours(), 1.0), dtype=np.float32)
    return _GRID_FEATURES


def _grid_quad_forms(model: "Gaussians", y_weight: float) -> list[np.ndarray]:
    """Mahalanobis distance² (float32) of every bin centre from each component of ``model``.

    The luminance weight is folded into the component (mean and inverse covariance) instead
    of rescaling the grid, so the cached grid features serve every classifier. With the
    Cholesky factor ``L`` of the inverse covariance the distance² is ``|Lᵀ(f − μ)|²``: one
    affine ``cv2.transform`` and a row-wise dot product.
    """
    f = grid_features()
    f3 = f.reshape(-1, 1, 3)
    scale = np.array([y_weight, 1.0, 1.0])
    out = []
    for mu, ic in zip(model.means, model.icovs):
        ic_s = np.asarray(ic, dtype=np.float64) * scale[:, None] * scale[None, :]
        mu_s = np.asarray(mu, dtype=np.float64) / scale
        try:
            lt = np.linalg.cholesky(ic_s).T
        except np.linalg.LinAlgError:  # not positive definite (a hand-edited file): the plain form
            d = f - mu_s.astype(np.float32)
            out.append(np.einsum("ni,ni->n", d @ ic_s.astype(np.float32), d))
            continue
        m = np.concatenate([lt, -(lt @ mu_s)[:, None]], axis=1).astype(np.float32)
        z = cv2.transform(f3, m).reshape(-1, 3)
        out.append(np.einsum("ni,ni->n", z, z))
    return out


def _lowest(arrays: list[np.ndarray]) -> np.ndarray:
    out = arrays[0].copy()
    for a in arrays[1:]:
        np.minimum(out, a, out=out)
    return out


_KEEP = (0xFF << _SHIFT) & 0xFF
_INDEX_WEIGHTS = np.array([[1 << 2 * BITS, 1 << BITS, 1]], dtype=np.float32) / np.float32(1 << _SHIFT)
"""Table index = Σ weight × (channel with its low bits cleared); every term is exact in float32."""


def lut_index(bgr: np.ndarray) -> np.ndarray:
    """Table index of every pixel of a ``(..., 3)`` uint8 BGR array (int32, same leading shape)."""
    q = np.bitwise_and(bgr, _KEEP).astype(np.float32)
    if q.ndim != 3:
        q = q.reshape(1, -1, 3) if q.ndim == 2 else q.reshape(-1, 1, 3)
        return cv2.transform(q, _INDEX_WEIGHTS).astype(np.int32).reshape(bgr.shape[:-1])
    return cv2.transform(q, _INDEX_WEIGHTS).astype(np.int32)


TILE_SHAPE = (_N * 8, _N * _N // 8)
"""A table as a grey image: the 64 slices of constant B (64 G rows × 64 R columns), 8 across."""


def table_to_tile(table: np.ndarray) -> np.ndarray:
    """A baked ``(64³,)`` table as a ``(512, 512)`` uint8 image (see :data:`TILE_SHAPE`)."""
    return np.ascontiguousarray(table.reshape(8, 8, _N, _N).transpose(0, 2, 1, 3).reshape(TILE_SHAPE))


def tile_to_table(tile: np.ndarray) -> np.ndarray:
    """Inverse of :func:`table_to_tile`."""
    if tile.shape != TILE_SHAPE or tile.dtype != np.uint8:
        raise ValueError(f"colour table image must be {TILE_SHAPE[1]}×{TILE_SHAPE[0]} 8-bit grey")
    return np.ascontiguousarray(tile.reshape(8, _N, 8, _N).transpose(0, 2, 1, 3).reshape(-1))


class ColourClassifier:
    """Target-vs-rest colour classifier baked into a lookup table.

    ``prob(bgr)`` gives a soft target score in 0..1 (float32), ``mask(bgr)`` the hard tags
    (score ≥ 0.5). ``gate`` is the largest Mahalanobis distance² from the target model a
    colour may have and still be tagged; ``margin`` how much more likely (in units of
    −2·log-likelihood) the target must be than the rest.
    """

    def __init__(
        self,
        target_bgr: np.ndarray,
        other_bgr: np.ndarray,
        y_weight: float = 1.0,
        k_target: int = 2,
        k_other: int = 3,
        gate: float = 18.0,
        margin: float = 2.0,
        name: str = "",
    ):
        self.name = name
        self.y_weight = float(y_weight)
        self.gate = float(gate)
        self.margin = float(margin)
        tgt = np.asarray(target_bgr).reshape(-1, 3)
        oth = np.asarray(other_bgr).reshape(-1, 3)
        if len(tgt) < 4:
            raise ValueError(f"{name or 'colour'} classifier: too few target pixels ({len(tgt)})")
        if len(oth) < 4:
            raise ValueError(f"{name or 'colour'} classifier: too few background pixels ({len(oth)})")
        ms = _MIN_STD * np.array([self.y_weight, 1.0, 1.0])
        self.target = Gaussians(features(tgt, self.y_weight), k_target, ms)
        self.other = Gaussians(features(oth, self.y_weight), k_other, ms)
        self.table = self._bake()

    def score_colours(self, bgr: np.ndarray) -> np.ndarray:
        """Soft target score 0..1 of ``(n, 3)`` colours, computed from the models (no table)."""
        f = features(bgr, self.y_weight)
        dt = self.target.d2(f)
        do = self.other.d2(f)
        inside = self.target.mahalanobis2(f)
        z = np.clip((do - dt - self.margin) * 0.5, -30, 30)
        s = 1.0 / (1.0 + np.exp(-z))
        # fade out colours far from every target component
        s *= 1.0 / (1.0 + np.exp(np.clip(inside - self.gate, -30, 30)))
        return s

    def _bake(self) -> np.ndarray:
        """The 64³ table: :meth:`score_colours` of every bin centre, in one float32 pass."""
        qt = _grid_quad_forms(self.target, self.y_weight)
        qo = _grid_quad_forms(self.other, self.y_weight)
        dt = _lowest([q + np.float32(ld) for q, ld in zip(qt, self.target.logdets)])
        do = _lowest([q + np.float32(ld) for q, ld in zip(qo, self.other.logdets)])
        inside = _lowest(qt)
        # target score × fade-out far from every target component, as two logistic terms
        z = np.clip((do - dt - np.float32(self.margin)) * np.float32(0.5), -30, 30)
        g = np.clip(inside - np.float32(self.gate), -30, 30)
        s = 1.0 / ((1.0 + np.exp(-z)) * (1.0 + np.exp(g)))
        return (s * np.float32(255.0) + np.float32(0.5)).astype(np.uint8)

    def prob_u8(self, bgr: np.ndarray) -> np.ndarray:
        """Target score of every pixel as uint8 0..255 (same leading shape as ``bgr``)."""
        return self.table.take(lut_index(bgr))

    def prob_at(self, index: np.ndarray) -> np.ndarray:
        """Target score (uint8) of pixels already turned into table indices by :func:`lut_index`
        (several classifiers looking at the same pixels share one index computation)."""
        return self.table.take(index)

    def prob(self, bgr: np.ndarray) -> np.ndarray:
        return self.prob_u8(bgr).astype(np.float32) * (1.0 / 255.0)

    def mask(self, bgr: np.ndarray) -> np.ndarray:
        """Boolean tags (score ≥ 0.5)."""
        return self.prob_u8(bgr) >= 128

    # --- persistence: the models go to JSON; the table to a PNG tile (or is rebuilt) ----
    def to_dict(self) -> dict:
        def g(m: Gaussians) -> dict:
            return {
                "means": [mu.tolist() for mu in m.means],
                "icovs": [ic.tolist() for ic in m.icovs],
                "logdets": list(m.logdets),
            }

        return {
            "name": self.name,
            "y_weight": self.y_weight,
            "gate": self.gate,
            "margin": self.margin,
            "target": g(self.target),
            "other": g(self.other),
        }

    @classmethod
    def from_dict(cls, d: dict, table: np.ndarray | None = None) -> "ColourClassifier":
        """Rebuild from :meth:`to_dict`; ``table`` is the baked table if stored (else it is rebuilt)."""
        self = cls.__new__(cls)
        self.name = str(d.get("name", ""))
        self.y_weight = float(d["y_weight"])
        self.gate = float(d["gate"])
        self.margin = float(d["margin"])

        def g(dd: dict) -> Gaussians:
            m = Gaussians.__new__(Gaussians)
            m.means = [np.asarray(v, dtype=np.float64) for v in dd["means"]]
            m.icovs = [np.asarray(v, dtype=np.float64) for v in dd["icovs"]]
            m.logdets = [float(v) for v in dd["logdets"]]
            if not m.means or any(mu.shape != (3,) for mu in m.means) or any(ic.shape != (3, 3) for ic in m.icovs):
                raise ValueError("malformed colour model")
            return m

        self.target = g(d["target"])
        self.other = g(d["other"])
        if table is None:
            self.table = self._bake()
        else:
            table = np.asarray(table)
            if table.dtype != np.uint8 or table.size != _N**3:
                raise ValueError(f"colour table must be {_N**3} uint8 values")
            self.table = np.ascontiguousarray(table).reshape(-1)
        return self
