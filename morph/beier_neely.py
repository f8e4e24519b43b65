"""The exact Beier–Neely field warp (SIGGRAPH 1992), the reference the mesh warps are measured on.

For a destination point X and a line pair — P'Q' in the destination, PQ in the source — ::

    u  = (X − P')·(Q' − P') / |Q' − P'|²          (position along the line, 0..1 between ends)
    v  = (X − P')·perp(Q' − P') / |Q' − P'|       (signed distance from the line, pixels)
    X' = P + u (Q − P) + v perp(Q − P) / |Q − P|   (the same (u, v) relative to the source line)

with ``perp(x, y) = (−y, x)``. Each line proposes the displacement X' − X; they are averaged with
weights ``(length^p / (a + dist))^b`` where ``length`` is |Q' − P'| and ``dist`` is |v| when
0 <= u <= 1, else the distance from X to the nearer endpoint. Defaults: ``a = 1`` pixel (how
strongly a line grips the pixels right on it: small ``a`` = precise control), ``b = 2`` (how fast
influence falls off with distance), ``p = 0.5`` (longer lines count somewhat more).
No lines (or only zero-length lines) give the identity. One line pair gives an affine map:
translation and rotation of the line move the image rigidly; a longer line stretches it along the
line only (``v`` is in pixels, so distances across the line are kept).

The result is a *backward* map: for each destination pixel, where to sample the source image,
ready for ``cv2.remap``. Images are warped and blended in premultiplied alpha (see ``morph``).
"""

from __future__ import annotations

from typing import Sequence

import cv2
import numpy as np

DEFAULT_A = 1.0
DEFAULT_B = 2.0
DEFAULT_P = 0.5
_EPS_LEN = 1e-6


def as_lines(lines) -> np.ndarray:
    """``lines`` as a float64 ``(n, 4)`` array (an empty list gives shape ``(0, 4)``)."""
    arr = np.asarray(lines, dtype=np.float64)
    if arr.size == 0:
        return np.zeros((0, 4))
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"control lines must have shape (n, 4), got {arr.shape}")
    return arr


def field_at(
    points: np.ndarray,
    dst_lines,
    src_lines,
    a: float = DEFAULT_A,
    b: float = DEFAULT_B,
    p: float = DEFAULT_P,
) -> np.ndarray:
    """Source positions ``(N, 2)`` float64 for destination ``points`` ``(N, 2)``.

    Vectorised over points, looping over lines.
    """
    dst = as_lines(dst_lines)
    src = as_lines(src_lines)
    if dst.shape != src.shape:
        raise ValueError(f"line sets differ in shape: {dst.shape} vs {src.shape}")
    return field_at_batch(points, dst[None], src[None], a, b, p)[0]


def field_at_batch(
    points: np.ndarray,
    dst_lines: np.ndarray,
    src_lines: np.ndarray,
    a: float = DEFAULT_A,
    b: float = DEFAULT_B,
    p: float = DEFAULT_P,
) -> np.ndarray:
    """``field_at`` for ``K`` line-set pairs at once: lines ``(K, n, 4)``, result ``(K, N, 2)``.

    Used to precompute many warps of the same points (the α tables) in one pass per line.
    """
    dst = np.asarray(dst_lines, dtype=np.float64)
    src = np.asarray(src_lines, dtype=np.float64)
    if dst.ndim != 3 or dst.shape[2] != 4 or dst.shape != src.shape:
        raise ValueError(f"batched line sets must both have shape (K, n, 4), got {dst.shape} and {src.shape}")
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    k = dst.shape[0]
    x, y = pts[None, :, 0], pts[None, :, 1]  # (1, N)
    dsum_x = np.zeros((k, len(pts)))
    dsum_y = np.zeros((k, len(pts)))
    wsum = np.zeros((k, len(pts)))
    for i in range(dst.shape[1]):
        px_, py_, qx_, qy_ = (dst[:, i, j, None] for j in range(4))  # (K, 1)
        px, py, qx, qy = (src[:, i, j, None] for j in range(4))
        ex_, ey_ = qx_ - px_, qy_ - py_
        ex, ey = qx - px, qy - py
        len_d = np.hypot(ex_, ey_)
        len_s = np.hypot(ex, ey)
        usable = (len_d >= _EPS_LEN) & (len_s >= _EPS_LEN)  # zero-length lines carry no weight
        if not usable.any():
            continue
        len_d = np.where(usable, len_d, 1.0)
        len_s = np.where(usable, len_s, 1.0)
        rx, ry = x - px_, y - py_  # (K, N)
        u = (rx * ex_ + ry * ey_) / (len_d * len_d)
        v = (ry * ex_ - rx * ey_) / len_d
        sx = px + u * ex - v * ey / len_s
        sy = py + u * ey + v * ex / len_s
        dist = np.abs(v)
        before = u < 0.0
        after = u > 1.0
        dist = np.where(before, np.hypot(rx, ry), dist)
        dist = np.where(after, np.hypot(x - qx_, y - qy_), dist)
        w = (len_d**p / (a + dist)) ** b
        w *= usable
        dsum_x += w * (sx - x)
        dsum_y += w * (sy - y)
        wsum += w
    out = np.broadcast_to(pts, (k,) + pts.shape).copy()
    safe = np.where(wsum > 0, wsum, 1.0)
    out[..., 0] += dsum_x / safe
    out[..., 1] += dsum_y / safe
    return out


def pixel_grid(size: tuple[int, int]) -> np.ndarray:
    """All pixel centres of a ``(w, h)`` image as ``(h*w, 2)`` float64 (x, y), row-major."""
    w, h = int(size[0]), int(size[1])
    ys, xs = np.mgrid[0:h, 0:w]
    return np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)


def field_map(
    dst_lines,
    src_lines,
    size: tuple[int, int],
    a: float = DEFAULT_A,
    b: float = DEFAULT_B,
    p: float = DEFAULT_P,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact per-pixel backward map of a ``(w, h)`` destination: ``(map_x, map_y)`` float32 (h, w)."""
    w, h = int(size[0]), int(size[1])
    src = field_at(pixel_grid((w, h)), dst_lines, src_lines, a, b, p)
    return (
        src[:, 0].reshape(h, w).astype(np.float32),
        src[:, 1].reshape(h, w).astype(np.float32),
    )


def premultiply(rgba: np.ndarray) -> np.ndarray:
    """Straight RGBA uint8 -> premultiplied RGBA uint8 (rounded)."""
    rgba = np.asarray(rgba)
    if rgba.dtype != np.uint8 or rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(f"expected an RGBA uint8 image (h, w, 4), got {rgba.dtype} {rgba.shape}")
    out = rgba.copy()
    a = rgba[:, :, 3:4].astype(np.uint16)
    out[:, :, :3] = (rgba[:, :, :3].astype(np.uint16) * a + 127) // 255
    return out


BORDERS = {"edge": cv2.BORDER_REPLICATE, "transparent": cv2.BORDER_CONSTANT}
DEFAULT_BORDER = "edge"


def border_mode(border: str) -> int:
    """OpenCV border flag for ``"edge"`` or ``"transparent"``.

    A Beier–Neely field does not fade to zero away from the lines (far pixels move by a weighted
    mean of the line displacements), so a warped part samples a few pixels outside its drawing
    along the box edges. ``"edge"`` repeats the drawing's edge pixels there (right for parts drawn
    on skin, and for transparent margins); ``"transparent"`` leaves see-through slivers that
    show through a head's feathered holes.
    """
    try:
        return BORDERS[border]
    except KeyError:
        raise ValueError(f"border must be one of {sorted(BORDERS)}, got {border!r}") from None


def remap_pm(
    image_pm: np.ndarray, map_x: np.ndarray, map_y: np.ndarray | None = None, border: str = DEFAULT_BORDER
) -> np.ndarray:
    """Resample a premultiplied image along a backward map (bilinear)."""
    return cv2.remap(
        image_pm, map_x, map_y, interpolation=cv2.INTER_LINEAR,
        borderMode=border_mode(border), borderValue=(0, 0, 0, 0),
    )


def warp(
    image: np.ndarray,
    src_lines,
    dst_lines,
    a: float = DEFAULT_A,
    b: float = DEFAULT_B,
    p: float = DEFAULT_P,
    premultiplied: bool = False,
    border: str = DEFAULT_BORDER,
) -> np.ndarray:
    """Warp a drawing whose features sit on ``src_lines`` so they sit on ``dst_lines``.

    ``image`` is straight RGBA (``premultiplied=False``, as in PNG) or premultiplied; the result
    is premultiplied RGBA uint8 of the same size. ``border``: see ``border_mode``.
    """
    pm = image if premultiplied else premultiply(image)
    h, w = pm.shape[:2]
    mx, my = field_map(dst_lines, src_lines, (w, h), a, b, p)
    return remap_pm(pm, mx, my, border)


def normalise_weights(weights: Sequence[float]) -> np.ndarray:
    """Weights clipped at 0 and scaled to sum to 1 (ValueError when nothing positive is left)."""
    w = np.clip(np.asarray(weights, dtype=np.float64).ravel(), 0.0, None)
    if not np.all(np.isfinite(w)) or w.sum() <= 0:
        raise ValueError(f"morph weights must be finite with a positive sum, got {list(weights)}")
    return w / w.sum()


def blend_pm(images_pm: Sequence[np.ndarray], weights: Sequence[float]) -> np.ndarray:
    """The true weighted sum ``Σ w_i · I_i`` of premultiplied images, rounded once to uint8."""
    acc = None
    for img, wt in zip(images_pm, weights):
        if wt <= 0:
            continue
        if acc is None:
            acc = img.astype(np.float32) * np.float32(wt)
        else:
            cv2.scaleAdd(img.astype(np.float32), float(wt), acc, dst=acc)
    if acc is None:
        raise ValueError("blend_pm needs at least one positive weight")
    out = np.empty(acc.shape, np.uint8)
    np.clip(np.rint(acc), 0, 255, out=acc)
    out[...] = acc
    return out


def polymorph_exact(
    images: Sequence[np.ndarray],
    lines_list: Sequence,
    weights: Sequence[float],
    a: float = DEFAULT_A,
    b: float = DEFAULT_B,
    p: float = DEFAULT_P,
    premultiplied: bool = False,
    border: str = DEFAULT_BORDER,
) -> np.ndarray:
    """Exact n-way polymorph (Lee et al.) with per-pixel Beier–Neely warps.

    The line sets are interpolated by the weights, every drawing with positive weight is warped
    from its own lines to the interpolated ones, and the warped drawings are summed with the
    weights in premultiplied alpha. Weights are clipped at 0 and normalised to sum 1.
    ``images`` are straight RGBA unless ``premultiplied``; the result is premultiplied RGBA uint8.
    """
    if not (len(images) == len(lines_list) == len(weights)) or len(images) == 0:
        raise ValueError("polymorph_exact needs as many images, line sets and weights (at least one)")
    w = normalise_weights(weights)
    lines = [as_lines(l) for l in lines_list]
    target = sum(wi * li for wi, li in zip(w, lines))
    pms = [img if premultiplied else premultiply(img) for img in images]
    h, wd = pms[0].shape[:2]
    warped, used = [], []
    for img, li, wi in zip(pms, lines, w):
        if wi <= 0:
            continue
        if img.shape[:2] != (h, wd):
            raise ValueError(f"drawings differ in size: {img.shape[:2]} vs {(h, wd)}")
        if wi >= 1.0:
            return img.copy()
        mx, my = field_map(target, li, (wd, h), a, b, p)
        warped.append(remap_pm(img, mx, my, border))
        used.append(wi)
    return blend_pm(warped, used)
