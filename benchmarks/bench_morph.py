"""Morph engine: mesh polymorph vs exact Beier–Neely, the paper's approximation, render speed.

Uses a bundled art set when ``art_sets.io`` and ``art_sets/bundled`` exist, else drawings
generated here with OpenCV (``generated_artset``, also used by the morph tests).
"""

from __future__ import annotations

import time

import cv2
import numpy as np

from benchmarks.harness import TIMING_COLUMNS, Table, benchmark, time_call

# ---------------------------------------------------------------- generated drawings


SKIN = (240, 200, 160, 255)


def _blank(w: int, h: int, bg=None) -> np.ndarray:
    img = np.zeros((h, w, 4), np.uint8)
    if bg is not None:
        img[:] = bg
    return img


def _smooth(img: np.ndarray) -> np.ndarray:
    """Drawn at 4× and shrunk: anti-aliased, straight RGBA."""
    h, w = img.shape[:2]
    pm = img.astype(np.float32)
    pm[:, :, :3] *= pm[:, :, 3:4] / 255.0
    small = cv2.resize(pm, (w // 4, h // 4), interpolation=cv2.INTER_AREA)
    a = small[:, :, 3:4]
    rgb = np.where(a > 0, small[:, :, :3] * 255.0 / np.maximum(a, 1e-6), 0)
    return np.clip(np.rint(np.dstack([rgb, a])), 0, 255).astype(np.uint8)


def make_mouth(w: int, h: int, width: float, open_: float, smile: float, seed: int = 0, bg=None) -> tuple[np.ndarray, np.ndarray]:
    """A drawn mouth (straight RGBA; transparent around it, or on colour ``bg``) and 6 control lines.

    ``width`` in 0..1 of the box, ``open_`` 0..1, ``smile`` −1..1. Lines: left corner → top of
    upper lip → right corner, right corner → bottom of lower lip → left corner, and the opening
    (inner upper lip → inner lower lip), the upper lip's centre line.
    """
    s = 4
    rng = np.random.default_rng(seed)
    cx, cy = w / 2, h / 2
    half = width * w / 2
    lift = -smile * 0.18 * h
    lx, ly = cx - half, cy + lift
    rx, ry = cx + half, cy + lift
    top = cy - 0.08 * h - 0.10 * h * open_
    bot = cy + 0.08 * h + 0.32 * h * open_
    inner_t = cy - 0.02 * h - 0.04 * h * open_
    inner_b = cy + 0.02 * h + 0.26 * h * open_
    img = _blank(w * s, h * s, bg)

    def curve(p0, pm_, p1, n=24):
        t = np.linspace(0, 1, n)[:, None]
        pts = (1 - t) ** 2 * np.array(p0) + 2 * (1 - t) * t * np.array(pm_) + t**2 * np.array(p1)
        return pts + rng.normal(0, 0.25, pts.shape)

    outer = np.vstack([curve((lx, ly), (cx, 2 * top - cy), (rx, ry)), curve((rx, ry), (cx, 2 * bot - cy), (lx, ly))])
    inner = np.vstack([curve((lx + 3, ly), (cx, 2 * inner_t - cy), (rx - 3, ry)),
                       curve((rx - 3, ry), (cx, 2 * inner_b - cy), (lx + 3, ly))])
    lip = (200, 60, 70, 255)
    cv2.fillPoly(img, [np.int32(outer * s)], lip, cv2.LINE_AA)
    if open_ > 0.05:
        cv2.fillPoly(img, [np.int32(inner * s)], (60, 15, 25, 255), cv2.LINE_AA)
    else:
        cv2.polylines(img, [np.int32(inner[:24] * s)], False, (60, 15, 25, 255), 2 * s, cv2.LINE_AA)
    cv2.polylines(img, [np.int32(outer * s)], True, (30, 20, 20, 255), int(2.2 * s), cv2.LINE_AA)
    lines = np.array([
        [lx, ly, cx, top], [cx, top, rx, ry], [rx, ry, cx, bot], [cx, bot, lx, ly],
        [cx, inner_t, cx, inner_b], [cx - half * 0.5, (top + inner_t) / 2, cx + half * 0.5, (top + inner_t) / 2],
    ], dtype=np.float64)
    return _smooth(img), lines


MOUTHS = {  # name: (width, open, smile)
    "neutral": (0.55, 0.0, 0.0), "smile": (0.70, 0.05, 0.8), "ah": (0.50, 0.9, 0.0),
    "oo": (0.30, 0.5, 0.0), "grin": (0.75, 0.35, 0.6), "frown": (0.55, 0.0, -0.8),
}

EYES = {  # name: (open, brow raise, brow tilt)
    "open": (0.7, 0.0, 0.0), "closed": (0.0, -0.1, 0.0), "wide": (1.0, 0.8, 0.0), "angry": (0.5, -0.5, 0.6),
}


def make_eyes(w: int, h: int, open_: float, brow: float, tilt: float, seed: int = 0, bg=None) -> tuple[np.ndarray, np.ndarray]:
    """A pair of drawn eyes with brows (straight RGBA) and 12 control lines (per eye: 4 lid chords, 2 brow)."""
    s = 4
    rng = np.random.default_rng(seed)
    img = _blank(w * s, h * s, bg)
    lines = []
    for side in (-1, 1):
        cx, cy = w / 2 + side * w * 0.24, h * 0.6
        ew, eh = w * 0.15, h * 0.20 * open_
        if open_ > 0.05:
            cv2.ellipse(img, (int(cx * s), int(cy * s)), (int(ew * s), int(max(eh, 1) * s)), 0, 0, 360,
                        (255, 255, 255, 255), -1, cv2.LINE_AA)
            r = min(eh, ew) * 0.6
            cv2.circle(img, (int(cx * s), int(cy * s)), int(r * s), (40, 30, 90, 255), -1, cv2.LINE_AA)
            cv2.ellipse(img, (int(cx * s), int(cy * s)), (int(ew * s), int(max(eh, 1) * s)), 0, 0, 360,
                        (20, 20, 20, 255), int(2 * s), cv2.LINE_AA)
        else:
            cv2.ellipse(img, (int(cx * s), int(cy * s)), (int(ew * s), int(0.25 * ew * s)), 0, 0, 180,
                        (20, 20, 20, 255), int(2.2 * s), cv2.LINE_AA)
        by = cy - h * 0.32 - h * 0.15 * brow
        inner_x, outer_x = cx - side * ew * 1.1, cx + side * ew * 1.2
        inner_y, outer_y = by + tilt * h * 0.12, by - tilt * h * 0.04
        pts = np.array([[outer_x, outer_y], [cx, by - h * 0.05], [inner_x, inner_y]]) + rng.normal(0, 0.2, (3, 2))
        cv2.polylines(img, [np.int32(pts * s)], False, (50, 35, 25, 255), int(4 * s), cv2.LINE_AA)
        lid_t = cy - eh if open_ > 0.05 else cy + 0.05 * ew
        lid_b = cy + eh if open_ > 0.05 else cy + 0.25 * ew
        lines += [[cx - ew, cy, cx, lid_t], [cx, lid_t, cx + ew, cy], [cx + ew, cy, cx, lid_b],
                  [cx, lid_b, cx - ew, cy], [outer_x, outer_y, cx, by - h * 0.05], [cx, by - h * 0.05, inner_x, inner_y]]
    return _smooth(img), np.array(lines, dtype=np.float64)


def make_head(canvas: tuple[int, int], boxes: dict, variant: int = 0) -> np.ndarray:
    """A head (straight RGBA) with feathered transparent holes over the part boxes."""
    w, h = canvas
    s = 2
    rng = np.random.default_rng(100 + variant)
    img = _blank(w * s, h * s)
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    r = 1 + rng.normal(0, 0.006, t.shape)
    pts = np.stack([w / 2 + 0.40 * w * r * np.cos(t), h * 0.52 + 0.46 * h * r * np.sin(t)], 1)
    cv2.fillPoly(img, [np.int32(pts * s)], SKIN, cv2.LINE_AA)
    cv2.polylines(img, [np.int32(pts * s)], True, (40, 25, 20, 255), 3 * s, cv2.LINE_AA)
    img = cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)
    hole = np.zeros((h, w), np.float32)
    for (x, y, bw, bh) in boxes.values():
        cv2.ellipse(hole, (int(x + bw / 2), int(y + bh / 2)), (int(bw * 0.42), int(bh * 0.40)), 0, 0, 360, 1.0, -1)
    hole = cv2.GaussianBlur(hole, (0, 0), 6)
    img[:, :, 3] = np.rint(img[:, :, 3] * (1 - hole)).astype(np.uint8)
    return img


def generated_artset():
    """A complete character drawn here: 6 mouths, 4 eye pairs, 2 heads on a 512×512 canvas."""
    from art_sets.model import ArtSet, Drawing, Part

    canvas = (512, 512)
    boxes = {"eyes": (106, 150, 300, 140), "mouth": (156, 320, 200, 120)}
    parts = {}
    for pname, table, maker in (("eyes", EYES, make_eyes), ("mouth", MOUTHS, make_mouth)):
        x, y, bw, bh = boxes[pname]
        drawings = []
        for k, (name, args) in enumerate(table.items()):
            img, lines = maker(bw, bh, *args, seed=k, bg=SKIN)
            drawings.append(Drawing(name, img, lines, f"{pname}/{name}.png"))
        parts[pname] = Part(pname, boxes[pname], drawings)
    heads = [make_head(canvas, boxes, v) for v in range(2)]
    return ArtSet("Generated", canvas, (256.0, 300.0), heads, parts, head_files=["head-1.png", "head-2.png"])
