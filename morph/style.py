"""Expression-driven style (the paper's future work): agitation shows in the drawing itself.

Past a threshold of raised brows the character's lines start to tremble (a small random, smooth
displacement added to every part's mesh warp, renewed every few frames) and its colours warm
towards red. Both scale with a *style level* in 0..1; level 0 (the default) changes nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from morph.mesh import interpolation_matrix


def style_level(brow_raise: float, threshold: float, full: float) -> float:
    """0 below ``threshold``, rising linearly to 1 at ``full`` (any units, e.g. brow/ipd)."""
    if full <= threshold:
        return 1.0 if brow_raise >= threshold else 0.0
    return float(np.clip((brow_raise - threshold) / (full - threshold), 0.0, 1.0))


@dataclass
class ExpressionStyle:
    """Line jitter and reddish tint at full style level; see ``style_level`` for the level."""

    jitter_px: float = 1.5  # largest line displacement, pixels of the part drawing
    tint: float = 0.35  # 0..1: how far colours move towards red
    coarse: int = 4  # jitter varies over coarse×coarse cells of a part
    every: int = 2  # a new jitter pattern every this many frames
    seed: int = 0

    def jitter(self, level: float, frame_no: int, part_no: int = 0, cells: int = 30) -> np.ndarray | None:
        """A smooth random ``(cells+1, cells+1, 2)`` float32 mesh displacement, or None at level 0."""
        if level <= 0 or self.jitter_px <= 0:
            return None
        rng = np.random.default_rng((self.seed, part_no, int(frame_no) // max(1, self.every)))
        knots = rng.uniform(-1.0, 1.0, (2, self.coarse + 1, self.coarse + 1))
        up = interpolation_matrix(cells + 1, self.coarse)  # (cells+1, coarse+1)
        field = np.einsum("ij,cjk,lk->ilc", up, knots, up)
        return (field * (self.jitter_px * min(level, 1.0))).astype(np.float32)

    def tint_matrix(self, level: float) -> np.ndarray:
        """4×4 RGBA colour matrix; keeps colour <= alpha, so premultiplied images stay valid."""
        k = self.tint * float(np.clip(level, 0.0, 1.0))
        return np.array([
            [1 - 0.6 * k, 0, 0, 0.6 * k],
            [0, 1 - 0.5 * k, 0, 0],
            [0, 0, 1 - 0.5 * k, 0],
            [0, 0, 0, 1],
        ], dtype=np.float32)

    def apply_tint(self, image_pm: np.ndarray, level: float) -> np.ndarray:
        """The premultiplied RGBA image warmed towards red by ``level`` (a new array)."""
        if level <= 0 or self.tint <= 0:
            return image_pm.copy()
        return cv2.transform(image_pm, self.tint_matrix(level))
