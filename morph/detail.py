"""Detail-keeping blend: a two-level Laplacian split of the warped drawings.

A plain weighted sum of three aligned drawings averages their strokes, and thin lines that do
not coincide exactly turn grey and doubled. Here each warped drawing ``I_i`` is split into a
low-pass layer ``G(I_i)`` (Gaussian, ``sigma`` pixels ≈ stroke width) and a high-pass layer
``I_i − G(I_i)``; the low-pass layers are blended with the weights and the high-pass layer is
taken from the heaviest drawing ``H`` alone::

    out = Σ w_i G(I_i) + (H − G(H)) = G(Σ w_i I_i) + H − G(H)

(the blur is linear, so only two blurs are needed). The result is clamped to a valid
premultiplied image (0 <= colour <= alpha <= 255). It is crisp, at the price of a visible switch
of stroke detail where two weights cross — hence an option, off by default.
"""

from __future__ import annotations

from typing import Sequence

import cv2
import numpy as np


def detail_blend(
    images_pm: Sequence[np.ndarray], weights: Sequence[float], sigma: float = 2.0, plain: np.ndarray | None = None
) -> np.ndarray:
    """Blend aligned premultiplied RGBA uint8 images keeping the heaviest one's fine detail.

    ``plain`` may pass the already computed weighted sum ``Σ w_i I_i`` (uint8).
    """
    heaviest = int(np.argmax(weights))
    if plain is None:
        plain = np.zeros(images_pm[0].shape, np.float32)
        for img, wt in zip(images_pm, weights):
            cv2.scaleAdd(img.astype(np.float32), float(wt), plain, dst=plain)
        plain = np.clip(np.rint(plain), 0, 255).astype(np.uint8)
    top = images_pm[heaviest]
    acc = cv2.add(cv2.GaussianBlur(plain, (0, 0), sigma), top, dtype=cv2.CV_16S)
    acc = cv2.subtract(acc, cv2.GaussianBlur(top, (0, 0), sigma), dtype=cv2.CV_16S)
    out = cv2.convertScaleAbs(np.maximum(acc, 0))  # clamp to 0..255
    alpha = np.ascontiguousarray(out[:, :, 3])
    return cv2.min(out, cv2.merge((alpha, alpha, alpha, alpha)))  # colour <= alpha


def high_pass_energy(image_pm: np.ndarray, sigma: float = 1.0) -> float:
    """Sharpness: mean squared difference between an image and its Gaussian blur (all channels)."""
    f = np.asarray(image_pm, np.float32)
    d = f - cv2.GaussianBlur(f, (0, 0), sigma)
    return float(np.mean(d * d))
