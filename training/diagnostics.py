"""How good is a training session? Numbers that tell the user what to fix.

* :func:`leave_one_out` — for each training pair, fit the map on the *other* pairs and ask
  it about this pair's frame: the weight its own drawing does not get (1 − w_own; 0 = perfect,
  1 when only other drawings are chosen, always so when no other pair shows that drawing) and
  the reconstruction error ‖m − Σ α_i m_i‖ (how well the chosen drawings stand in for it;
  None for the only pair of a part, which has no others to stand in for it).
* :func:`coverage` — the reference clip's frames against the paper's map: share of frames
  that project outside the hull of the training points, how far (mean / max, in the map's
  scale-free units) and the farthest-outside frame — the expression to add next.
* :func:`report` — both, for both parts, as plain data plus one-line messages.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from morph.expression_map import ExpressionMap
from morph.mappers import make_mapper

__all__ = ["Coverage", "LooResult", "coverage", "leave_one_out", "report"]


@dataclass
class LooResult:
    """Leave-one-out of one training pair."""

    pair: int  # index of the pair among the rows given
    drawing: int
    name: str
    weight_error: float  # 1 − weight the others' map gives to this pair's drawing
    recon_error: float | None  # ‖m − Σ α_i m_i‖ with that map's weights (scale-free units); None: no other pair
    alone: bool  # no other pair shows this drawing, so the weight error is 1 by construction
    predicted: list[tuple[str, float]] = field(default_factory=list)


@dataclass
class Coverage:
    """Reference clip frames against the map of one part."""

    part: str
    frames: int
    outside_share: float
    mean_outside: float  # mean distance of the outside frames (0 if none)
    max_outside: float
    worst_frame: int  # index in the reference track (-1 if none outside)
    suggestion: str
    hull: bool = True  # False while fewer than three drawings are paired: no area to be outside of


def _mean_points(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    labs = np.unique(y)
    return np.array([X[y == l].mean(axis=0) for l in labs]), labs


def leave_one_out(X: np.ndarray, y, names: list[str], mapper: str = "delaunay") -> list[LooResult]:
    """Leave-one-out over training pairs: rows ``X`` ``(m, k)`` paired with drawings ``y``.

    For each pair, the map is fitted on the other pairs (one point per drawing, the mean of its
    frames) and asked about this pair's features. ``names[d]`` names drawing ``d``. Every number
    in the results is finite: a pair with no other pair to fit on gets ``recon_error=None``.
    """
    X = np.asarray(X, dtype=np.float64)
    y = np.asarray(y, dtype=np.intp)
    out = []
    for i in range(len(X)):
        keep = np.arange(len(X)) != i
        alone = not np.any(y[keep] == y[i])
        if not keep.any():
            out.append(LooResult(i, int(y[i]), names[y[i]], 1.0, None, True))
            continue
        pts, labs = _mean_points(X[keep], y[keep])
        m = make_mapper(mapper, pts, labels=labs)
        idx, w = m.weights(X[i])
        lut = {int(l): pts[j] for j, l in enumerate(labs)}
        recon = sum(a * lut[int(j)] for j, a in zip(idx, w))
        own = sum(a for j, a in zip(idx, w) if j == y[i])
        pred = [(names[j], float(a)) for j, a in zip(idx, w) if a > 1e-6]
        out.append(LooResult(i, int(y[i]), names[y[i]], 1.0 - own, float(np.linalg.norm(X[i] - recon)), alone, pred))
    return out


def coverage(emap: ExpressionMap, feats: np.ndarray, part: str = "", frame_ids=None, tol: float = 0.02) -> Coverage:
    """Project the reference clip's features ``(m, k)`` with the paper's map; see :class:`Coverage`.

    ``frame_ids`` names the rows (default: their index). A frame counts as outside when it lies
    more than ``tol`` × the spread of the training points (largest distance from their mean)
    outside the hull in the map plane: the paper notes that points just outside map well.
    """
    feats = np.asarray(feats, dtype=np.float64).reshape(-1, emap.k)
    ok = np.all(np.isfinite(feats), axis=1)
    ids = np.arange(len(feats)) if frame_ids is None else np.asarray(frame_ids)
    feats, ids = feats[ok], ids[ok]
    if len(feats) == 0:
        return Coverage(part, 0, 0.0, 0.0, 0.0, -1, f"{part}: no tracked frames in the reference clip to check")
    if getattr(emap, "mode", "tri") != "tri":  # one drawing, or drawings on a line: no hull yet
        return Coverage(part, len(feats), 0.0, 0.0, 0.0, -1,
                        f"{part}: pair at least three different drawings to see which frames no drawing covers",
                        hull=False)
    dist = np.array([emap.locate(x).outside for x in feats])
    out = dist > tol * emap.scale
    share = float(out.mean())
    if not out.any():
        return Coverage(part, len(feats), 0.0, 0.0, 0.0, -1, f"{part}: every reference frame is inside the drawings' hull")
    worst = int(np.argmax(dist))
    frame = int(ids[worst])
    idx, w = emap.weights(feats[worst])
    near = ", ".join(f"{emap_name(emap, j)}" for j, a in zip(idx, w) if a > 0.05)
    msg = (
        f"{part}: {share:.0%} of reference frames fall outside the drawings' hull "
        f"(max {dist[worst]:.3f}); add a drawing for the expression of frame {frame} (now shown as {near})"
    )
    return Coverage(part, len(feats), share, float(dist[out].mean()), float(dist[worst]), frame, msg)


def emap_name(emap, j: int) -> str:
    names = getattr(emap, "names", None)
    return names[j] if names is not None and j < len(names) else f"drawing {j}"


def report(session, artset, mapper: str = "delaunay") -> dict:
    """Leave-one-out and coverage of both parts of ``session`` for ``artset``.

    Returns ``{part: {"loo": [LooResult], "coverage": Coverage | None}}``.
    """
    session.check(artset)
    fs = session.feature_space()
    out = {}
    for part in ("eyes", "mouth"):
        names = artset.parts[part].names()
        X, Y = session.training_data(part, names)
        drawing_rows = np.flatnonzero(np.isclose(Y.max(axis=1), 1.0)) if len(Y) else np.zeros(0, dtype=np.intp)
        X, y = X[drawing_rows], Y[drawing_rows].argmax(axis=1) if len(drawing_rows) else np.zeros(0, dtype=np.intp)
        loo = leave_one_out(X, y, names, mapper) if len(X) else []
        pts, labels = session.training_points(part, names)
        cov = None
        if len(pts) and session.reference_track is not None and len(session.reference_track):
            em = ExpressionMap(pts, labels=labels)
            em.names = names
            cov = coverage(em, fs.part(part, session.reference_track), part)
        out[part] = {"loo": loo, "coverage": cov}
    return out
