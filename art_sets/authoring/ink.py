"""A small hand-drawn stroke renderer (numpy + Pillow) used to author the bundled characters.

A :class:`Surface` is a rectangle of a character's canvas (the whole head, or one part's box),
painted at ``ss``× resolution and downsampled with Lanczos at the end. All drawing calls take
**design** coordinates, which a :class:`Placement` (scale and offset, the same for every surface
of a character) maps to the canvas, so a part drawn on its own surface lines up pixel for pixel
with the head, and canvas-level textures (paper, pencil grain) match across the seams of the
feathered holes. Widths, radii and blurs are in design pixels too. Colours are RGB floats in
0..1; paint is accumulated premultiplied.

Strokes are tapered polylines with pressure (width) variation, optional wobble (a loose,
wavy line), jitter, pencil grain and feathering; fills are polygons with optional clipping.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw, ImageFilter

Color = tuple[float, float, float]


def hex_rgb(h: str) -> Color:
    h = h.lstrip("#")
    return tuple(int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4))  # type: ignore[return-value]


def value_noise(shape: tuple[int, int], cell: float, rng: np.random.Generator) -> np.ndarray:
    """Smooth noise in about -1..1 with features of ``cell`` pixels, shape (h, w) float32."""
    h, w = shape
    gh, gw = max(2, int(h / cell) + 3), max(2, int(w / cell) + 3)
    grid = rng.uniform(-1, 1, (gh, gw)).astype(np.float32)
    im = Image.fromarray(grid, "F").resize((int(gw * cell), int(gh * cell)), Image.BICUBIC)
    arr = np.asarray(im, dtype=np.float32)
    return np.ascontiguousarray(arr[int(cell):int(cell) + h, int(cell):int(cell) + w])


def fractal_noise(shape: tuple[int, int], cells: list[float], rng: np.random.Generator) -> np.ndarray:
    """Sum of octaves of :func:`value_noise`, normalised to unit standard deviation."""
    acc = np.zeros(shape, np.float32)
    for i, c in enumerate(cells):
        acc += value_noise(shape, c, rng) / (1.0 + i)
    return acc / (acc.std() + 1e-6)


@dataclass(frozen=True)
class Placement:
    """Design coordinates → canvas pixels: ``canvas = offset + scale · design``."""

    scale: float = 1.0
    offset: tuple[float, float] = (0.0, 0.0)

    def __call__(self, pts) -> np.ndarray:
        """Points ``(..., 2)`` in design coordinates, in canvas pixels."""
        return np.asarray(pts, np.float64) * self.scale + np.asarray(self.offset, np.float64)

    def lines(self, lines) -> np.ndarray:
        """Control lines ``(n, 4)`` in design coordinates, in canvas pixels."""
        return self(np.asarray(lines, np.float64).reshape(-1, 2, 2)).reshape(-1, 4)

    def box(self, box) -> tuple[int, int, int, int]:
        """A design ``(x, y, w, h)`` box as the whole canvas pixels it covers (rounded)."""
        x0, y0 = self((box[0], box[1]))
        x1, y1 = self((box[0] + box[2], box[1] + box[3]))
        x0, y0, x1, y1 = (int(round(v)) for v in (x0, y0, x1, y1))
        return x0, y0, x1 - x0, y1 - y0


@dataclass
class Textures:
    """Canvas-level textures, so every surface of a character samples the same paper.

    ``paper`` (canvas size, ~1.0 mean) multiplies the final colours; ``grain`` (canvas size
    × ss, 0..1) thins pencil strokes where the paper's tooth is low.
    """

    paper: np.ndarray
    grain: np.ndarray
    ss: int

    @staticmethod
    def make(canvas: tuple[int, int], ss: int, seed: int, paper_amount: float = 0.04,
             grain_contrast: float = 0.0) -> "Textures":
        rng = np.random.default_rng(seed)
        w, h = canvas
        fibres = fractal_noise((h, w), [9, 3, 1.5], rng)
        speck = rng.normal(0, 1, (h, w)).astype(np.float32)
        paper = 1.0 + paper_amount * (0.85 * fibres + 0.15 * speck)
        if grain_contrast > 0:
            g = fractal_noise((h * ss, w * ss), [6.0 * ss / 3, 1.6 * ss / 3], rng)
            grain = np.clip(0.55 + grain_contrast * 0.35 * g, 0, 1).astype(np.float32)
        else:
            grain = np.ones((1, 1), np.float32)
        return Textures(paper.astype(np.float32), grain, ss)


class Surface:
    """A supersampled RGBA painting surface covering ``size`` canvas pixels at ``origin``."""

    def __init__(self, origin: tuple[int, int], size: tuple[int, int], textures: Textures,
                 background: Color | None = None, place: Placement = Placement(), wobble_ref: float | None = None,
                 grain_ref: list | None = None):
        """``origin`` and ``size`` in canvas pixels; drawing calls in design coordinates (``place``).

        ``wobble_ref`` (design px): when set, every stroke's wobble has ``wobble_ref / wobble_len``
        waves whatever its length, so the same stroke drawn longer or shorter in another drawing
        of a part wobbles alike and lines up under the morph.

        ``grain_ref``: the :attr:`strokes` of the same layer of another drawing of the part (made by
        the same drawing calls in the same order). Stroke *i* then takes its pencil grain from where
        stroke *i* of that drawing lies on the paper, carried along in the stroke's own frame (the
        fraction of its length, the distance across it), instead of from the paper under it: the
        grain moves with the stroke, as the morph moves the stroke, so the same stroke of two
        drawings lands on itself grain for grain, where paper grain would give two different grains
        that blend to a grey smear. The drawing the reference comes from keeps the paper's grain."""
        self.wobble_ref = wobble_ref
        self.grain_ref = grain_ref
        self.strokes: list[tuple[np.ndarray, np.ndarray]] = []  # per stroke: centre line and arc length, grain pixels
        self.ox, self.oy = origin
        self.w, self.h = size
        self.tex = textures
        self.ss = textures.ss
        self.place = place
        self.k = self.ss * place.scale  # surface pixels per design pixel
        self.W, self.H = self.w * self.ss, self.h * self.ss
        self.rgb = np.zeros((self.H, self.W, 3), np.float32)
        self.a = np.zeros((self.H, self.W), np.float32)
        if background is not None:
            self.rgb[:] = background
            self.a[:] = 1.0

    # --- coordinates and masks ------------------------------------------------------------
    def px(self, pts) -> np.ndarray:
        """Canvas points -> supersampled surface pixels."""
        p = self.place(np.asarray(pts, np.float64).reshape(-1, 2))
        return (p - (self.ox, self.oy)) * self.ss

    def _bbox(self, p: np.ndarray, pad: float) -> tuple[int, int, int, int] | None:
        x0 = max(0, int(np.floor(p[:, 0].min() - pad)))
        y0 = max(0, int(np.floor(p[:, 1].min() - pad)))
        x1 = min(self.W, int(np.ceil(p[:, 0].max() + pad)) + 1)
        y1 = min(self.H, int(np.ceil(p[:, 1].max() + pad)) + 1)
        if x1 <= x0 or y1 <= y0:
            return None
        return x0, y0, x1, y1

    def mask(self, poly, blur: float = 0.0) -> np.ndarray:
        """Full-surface float mask (0..1) of a polygon, optionally feathered (design px)."""
        m = Image.new("L", (self.W, self.H), 0)
        ImageDraw.Draw(m).polygon([tuple(q) for q in self.px(poly)], fill=255)
        if blur > 0:
            m = m.filter(ImageFilter.GaussianBlur(blur * self.k))
        return np.asarray(m, np.float32) / 255.0

    def _grain(self, bb) -> np.ndarray:
        g = self.tex.grain
        if g.size == 1:
            return g
        x0, y0, x1, y1 = bb
        gx, gy = self.ox * self.ss + x0, self.oy * self.ss + y0
        H, W = g.shape
        out = np.ones((y1 - y0, x1 - x0), np.float32)
        sx0, sy0 = max(gx, 0), max(gy, 0)
        sx1, sy1 = min(gx + x1 - x0, W), min(gy + y1 - y0, H)
        if sx1 > sx0 and sy1 > sy0:
            out[sy0 - gy:sy1 - gy, sx0 - gx:sx1 - gx] = g[sy0:sy1, sx0:sx1]
        return out

    def paint(self, m: np.ndarray, color: Color, opacity: float = 1.0, bb=None,
              grain: float = 0.0, clip: np.ndarray | None = None, grain_map: np.ndarray | None = None) -> None:
        """Lay ``color`` through mask ``m`` (whole surface, or the region ``bb``); ``grain_map``
        (the region's size) replaces the paper's grain there."""
        if bb is None:
            bb = (0, 0, self.W, self.H)
        x0, y0, x1, y1 = bb
        k = m * opacity
        if grain > 0:
            k = k * (1 - grain + grain * (self._grain(bb) if grain_map is None else grain_map))
        if clip is not None:
            k = k * clip[y0:y1, x0:x1]
        k = k[..., None] if k.ndim == 2 else k
        rgb = self.rgb[y0:y1, x0:x1]
        rgb *= 1 - k
        rgb += k * np.asarray(color, np.float32)
        a = self.a[y0:y1, x0:x1]
        a *= 1 - k[..., 0]
        a += k[..., 0]

    def _stroke_grain(self, q: np.ndarray, bb, m: np.ndarray, grain: float) -> np.ndarray | None:
        """Record a stroke's centre line ``q`` (surface px, relative to ``bb``) and, with a
        ``grain_ref``, return its grain over ``bb`` carried from the reference stroke (None: the paper's)."""
        x0, y0 = bb[0], bb[1]
        here = resample(np.asarray(q, np.float64) + (x0 + self.ox * self.ss, y0 + self.oy * self.ss), 1.5)  # grain-texture pixels
        s = np.concatenate([[0], np.cumsum(np.hypot(*np.diff(here, axis=0).T))]) if len(here) > 1 else np.zeros(1)
        k = len(self.strokes)
        self.strokes.append((here, s))
        g = self.tex.grain
        if grain <= 0 or g.size == 1 or self.grain_ref is None or k >= len(self.grain_ref) or len(here) < 2 or s[-1] <= 0:
            return None
        ref, rs = self.grain_ref[k]
        if len(ref) < 2 or rs[-1] <= 0:
            return None
        ys, xs = np.nonzero(m > 0)
        if len(ys) == 0:
            return None
        pix = np.stack([xs, ys], 1).astype(np.float64) + (x0 + self.ox * self.ss, y0 + self.oy * self.ss)
        tan, ref_tan = _tangents(here), _tangents(ref)
        nearest = np.empty(len(pix), np.int64)
        for i in range(0, len(pix), 4096):
            d = pix[i:i + 4096, None, :] - here[None]
            nearest[i:i + 4096] = np.argmin((d ** 2).sum(-1), axis=1)
        rel = pix - here[nearest]
        t = tan[nearest]
        along = (rel * t).sum(1)
        across = rel[:, 0] * -t[:, 1] + rel[:, 1] * t[:, 0]
        si = s[nearest] / s[-1] * rs[-1]
        rp = np.stack([np.interp(si, rs, ref[:, 0]), np.interp(si, rs, ref[:, 1])], 1)
        rt = np.stack([np.interp(si, rs, ref_tan[:, 0]), np.interp(si, rs, ref_tan[:, 1])], 1)
        rt /= np.maximum(np.hypot(rt[:, 0], rt[:, 1]), 1e-9)[:, None]
        src = rp + rt * along[:, None] + np.stack([-rt[:, 1], rt[:, 0]], 1) * across[:, None]
        H, W = g.shape
        sx, sy = np.clip(src[:, 0], 0, W - 1.001), np.clip(src[:, 1], 0, H - 1.001)
        ix, iy = sx.astype(np.int64), sy.astype(np.int64)
        fx, fy = sx - ix, sy - iy
        val = (g[iy, ix] * (1 - fx) * (1 - fy) + g[iy, ix + 1] * fx * (1 - fy)
               + g[iy + 1, ix] * (1 - fx) * fy + g[iy + 1, ix + 1] * fx * fy)
        out = np.ones(m.shape, np.float32)
        out[ys, xs] = val
        return out

    # --- primitives --------------------------------------------------------------------------
    def fill(self, poly, color: Color, opacity: float = 1.0, blur: float = 0.0,
             clip: np.ndarray | None = None, grain: float = 0.0) -> None:
        p = self.px(poly)
        pad = 3 * blur * self.k + 2
        bb = self._bbox(p, pad)
        if bb is None:
            return
        x0, y0, x1, y1 = bb
        m = Image.new("L", (x1 - x0, y1 - y0), 0)
        ImageDraw.Draw(m).polygon([(q[0] - x0, q[1] - y0) for q in p], fill=255)
        if blur > 0:
            m = m.filter(ImageFilter.GaussianBlur(blur * self.k))
        self.paint(np.asarray(m, np.float32) / 255.0, color, opacity, bb, grain, clip)

    def stroke(self, pts, width: float, color: Color, *, rng: np.random.Generator | None = None,
               taper: tuple[float, float] = (0.3, 0.3), tip: float = 0.15, pressure: float = 0.0,
               wobble: float = 0.0, wobble_len: float = 40.0, jitter: float = 0.0,
               opacity: float = 1.0, grain: float = 0.0, blur: float = 0.0,
               clip: np.ndarray | None = None) -> None:
        """A tapered ink/pencil stroke along a canvas polyline.

        ``width`` in canvas px at full pressure; ``taper`` = fractions of the length over
        which each end thins to ``tip``×width; ``pressure`` = relative random width
        variation; ``wobble`` = amplitude (px) of a slow sideways waver with wavelength
        about ``wobble_len`` px; ``jitter`` = random offset (px) of the whole stroke.
        """
        rng = rng or np.random.default_rng(0)
        if pressure == 0 and wobble == 0 and tuple(taper) == (0, 0):
            self._plain_line(np.asarray(pts, np.float64).reshape(-1, 2), width, color, rng, jitter, opacity, grain, blur, clip)
            return
        p = resample(np.asarray(pts, np.float64).reshape(-1, 2), 0.75)
        if len(p) < 2:
            return
        if jitter > 0:
            p = p + rng.normal(0, jitter, 2)
        seg = np.diff(p, axis=0)
        s = np.concatenate([[0], np.cumsum(np.hypot(seg[:, 0], seg[:, 1]))])
        L = max(s[-1], 1e-6)
        t = np.gradient(p, axis=0)
        t /= np.maximum(np.hypot(t[:, 0], t[:, 1]), 1e-9)[:, None]
        n = np.stack([-t[:, 1], t[:, 0]], 1)
        if wobble > 0:
            off = np.zeros(len(p))
            base = wobble_len if self.wobble_ref is None else L * wobble_len / self.wobble_ref
            for k in range(3):
                wl = base * (0.55 + 0.9 * rng.random()) / (1 + k)
                off += wobble / (1 + k) ** 2 * np.sin(2 * np.pi * s / wl + rng.uniform(0, 2 * np.pi))
            p = p + n * off[:, None]
        u = s / L
        prof = np.ones_like(u)
        if taper[0] > 0:
            prof = np.minimum(prof, tip + (1 - tip) * _smooth(np.clip(u / taper[0], 0, 1)))
        if taper[1] > 0:
            prof = np.minimum(prof, tip + (1 - tip) * _smooth(np.clip((1 - u) / taper[1], 0, 1)))
        if pressure > 0:
            wl = max(20.0, L / 2)
            prof = prof * (1 + pressure * np.sin(2 * np.pi * s / wl + rng.uniform(0, 6.3)))
        half = np.maximum(width * prof / 2, 0.12)
        q = self.px(p)
        hq = half * self.k
        bb = self._bbox(q, hq.max() + 3 * blur * self.k + 2)
        if bb is None:
            return
        x0, y0, x1, y1 = bb
        q = q - (x0, y0)
        nl = n * hq[:, None]
        left, right = q + nl, q - nl
        m = Image.new("L", (x1 - x0, y1 - y0), 0)
        d = ImageDraw.Draw(m)
        for i in range(len(q) - 1):
            d.polygon([tuple(left[i]), tuple(left[i + 1]), tuple(right[i + 1]), tuple(right[i])], fill=255)
        for i in range(0, len(q), 2):
            r = hq[i]
            if r > 0.8:
                d.ellipse([q[i, 0] - r, q[i, 1] - r, q[i, 0] + r, q[i, 1] + r], fill=255)
        for i in (0, len(q) - 1):
            r = hq[i]
            d.ellipse([q[i, 0] - r, q[i, 1] - r, q[i, 0] + r, q[i, 1] + r], fill=255)
        if blur > 0:
            m = m.filter(ImageFilter.GaussianBlur(blur * self.k))
        m = np.asarray(m, np.float32) / 255.0
        self.paint(m, color, opacity, bb, grain, clip, self._stroke_grain(q, bb, m, grain))

    def hatch(self, region, angle: float, spacing: float, width: float, color: Color, rng: np.random.Generator,
              opacity: float = 0.7, grain: float = 0.0, clip_blur: float = 0.0, **kw) -> None:
        """Parallel pencil strokes at ``angle`` degrees, ``spacing`` px apart, clipped to ``region``."""
        clip = self.mask(region, blur=clip_blur)
        p = np.asarray(region, np.float64)
        c = p.mean(0)
        r = np.hypot(*(p - c).T).max()
        d = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
        nrm = np.array([-d[1], d[0]])
        for o in np.arange(-r, r, spacing):
            o2 = o + rng.normal(0, spacing * 0.12)
            a = c + nrm * o2 - d * r * (1 + 0.1 * rng.random())
            b = c + nrm * o2 + d * r * (1 + 0.1 * rng.random())
            self.stroke([a, b], width * (0.8 + 0.4 * rng.random()), color, rng=rng, opacity=opacity, grain=grain,
                        clip=clip, taper=(0.0, 0.0), **kw)

    def _plain_line(self, p, width, color, rng, jitter, opacity, grain, blur, clip) -> None:
        """Constant-width polyline (fast path for hatching and outlines)."""
        if jitter > 0:
            p = p + rng.normal(0, jitter, 2)
        q = self.px(p)
        r = max(width * self.k / 2, 0.5)
        bb = self._bbox(q, r + 3 * blur * self.k + 2)
        if bb is None:
            return
        x0, y0, x1, y1 = bb
        q = q - (x0, y0)
        m = Image.new("L", (x1 - x0, y1 - y0), 0)
        d = ImageDraw.Draw(m)
        d.line([tuple(v) for v in q], fill=255, width=max(1, int(round(2 * r))), joint="curve")
        for v in (q[0], q[-1]):
            d.ellipse([v[0] - r, v[1] - r, v[0] + r, v[1] + r], fill=255)
        if blur > 0:
            m = m.filter(ImageFilter.GaussianBlur(blur * self.k))
        m = np.asarray(m, np.float32) / 255.0
        self.paint(m, color, opacity, bb, grain, clip, self._stroke_grain(q, bb, m, grain))

    def dot(self, c, r: float, color: Color, opacity: float = 1.0, blur: float = 0.0,
            clip: np.ndarray | None = None) -> None:
        self.fill(ellipse(c, r, r), color, opacity, blur, clip)

    def punch(self, m: np.ndarray) -> None:
        """Make the surface transparent where the full-surface mask ``m`` is 1 (feathered holes)."""
        self.rgb *= (1 - m)[..., None]
        self.a *= 1 - m

    # --- output -------------------------------------------------------------------------------
    def to_rgba(self, paper: bool = True) -> np.ndarray:
        """Downsample (area average of the ``ss``×``ss`` samples, premultiplied) to straight RGBA uint8 (h, w, 4).

        An area average never rings: a filter with negative lobes (Lanczos) leaves a faint light or
        dark line along the edge of a layer where it turns see-through, which shows once layers
        are stacked."""
        chans = []
        for c in [self.rgb[..., 0], self.rgb[..., 1], self.rgb[..., 2], self.a]:
            im = Image.fromarray(np.ascontiguousarray(c), "F").resize((self.w, self.h), Image.BOX)
            chans.append(np.asarray(im, np.float32))
        rgb = np.stack(chans[:3], -1)
        a = np.clip(chans[3], 0, 1)
        rgb = np.clip(rgb, 0, None) / np.maximum(a, 1e-4)[..., None]
        rgb = np.where(a[..., None] > 1e-4, rgb, 0)
        if paper:
            tex = self.tex.paper[self.oy:self.oy + self.h, self.ox:self.ox + self.w]
            rgb = rgb * tex[..., None]
        out = np.concatenate([np.clip(rgb, 0, 1), a[..., None]], -1)
        return (out * 255 + 0.5).astype(np.uint8)


# --- geometry helpers ------------------------------------------------------------------------
def _tangents(p: np.ndarray) -> np.ndarray:
    t = np.gradient(p, axis=0)
    return t / np.maximum(np.hypot(t[:, 0], t[:, 1]), 1e-9)[:, None]


def _smooth(x: np.ndarray) -> np.ndarray:
    return x * x * (3 - 2 * x)


def resample(p: np.ndarray, step: float) -> np.ndarray:
    """Points every ``step`` px along a polyline (keeps both ends)."""
    if len(p) < 2:
        return p
    seg = np.hypot(*np.diff(p, axis=0).T)
    s = np.concatenate([[0], np.cumsum(seg)])
    if s[-1] < 1e-9:
        return p[:1]
    n = max(2, int(np.ceil(s[-1] / step)) + 1)
    si = np.linspace(0, s[-1], n)
    return np.stack([np.interp(si, s, p[:, 0]), np.interp(si, s, p[:, 1])], 1)


def ellipse(c, rx: float, ry: float, n: int = 72, rot: float = 0.0) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x, y = rx * np.cos(t), ry * np.sin(t)
    cr, sr = np.cos(rot), np.sin(rot)
    return np.stack([c[0] + x * cr - y * sr, c[1] + x * sr + y * cr], 1)


def bez(*ctrl, n: int = 60) -> np.ndarray:
    """Bézier points (n, 2) by de Casteljau over the control points."""
    P = np.asarray(ctrl, np.float64)
    t = np.linspace(0, 1, n)
    pts = np.repeat(P[None], n, 0)
    for _ in range(len(P) - 1):
        pts = pts[:, :-1] * (1 - t)[:, None, None] + pts[:, 1:] * t[:, None, None]
    return pts[:, 0]


def point_at(curve: np.ndarray, u: float) -> np.ndarray:
    """The point a fraction ``u`` of the arc length along a polyline."""
    seg = np.hypot(*np.diff(curve, axis=0).T)
    s = np.concatenate([[0], np.cumsum(seg)])
    si = u * s[-1]
    return np.array([np.interp(si, s, curve[:, 0]), np.interp(si, s, curve[:, 1])])


def on_curve(curve: np.ndarray, u, up=0.0, along=0.0) -> np.ndarray:
    """Points ``(len(u), 2)`` placed in a curve's own frame: at arc-length fractions ``u``, moved
    ``up`` px along its normal (to the left of travel in y-down: up for a curve running left to
    right) and ``along`` px along its tangent (scalars or one per point).

    A Beier–Neely warp keeps a pixel's place in the frame of the control lines along a curve (its
    fraction along them, its distance from them in pixels), so a feature drawn in this frame lands
    on itself when drawings whose curves bend and stretch differently are morphed into each other;
    one drawn at fixed canvas offsets from the curve (a vertical shift, a fixed width) does not."""
    u = np.atleast_1d(np.asarray(u, np.float64))
    seg = np.hypot(*np.diff(curve, axis=0).T)
    s = np.concatenate([[0], np.cumsum(seg)])
    si = np.clip(u, 0, 1) * s[-1]
    p = np.stack([np.interp(si, s, curve[:, 0]), np.interp(si, s, curve[:, 1])], 1)
    tv = np.gradient(curve, axis=0)
    tv /= np.maximum(np.hypot(tv[:, 0], tv[:, 1]), 1e-9)[:, None]
    t = np.stack([np.interp(si, s, tv[:, 0]), np.interp(si, s, tv[:, 1])], 1)
    t /= np.maximum(np.hypot(t[:, 0], t[:, 1]), 1e-9)[:, None]
    n = np.stack([t[:, 1], -t[:, 0]], 1)
    up = np.broadcast_to(np.asarray(up, np.float64), u.shape)[:, None]
    along = np.broadcast_to(np.asarray(along, np.float64), u.shape)[:, None]
    return p + n * up + t * along


def sub_curve(curve: np.ndarray, u0: float, u1: float, n: int = 40) -> np.ndarray:
    return np.array([point_at(curve, u) for u in np.linspace(u0, u1, n)])


def offset(curve: np.ndarray, d) -> np.ndarray:
    """Shift a polyline sideways by ``d`` (scalar or per point; + is to the left of travel in y-down)."""
    t = np.gradient(curve, axis=0)
    t /= np.maximum(np.hypot(t[:, 0], t[:, 1]), 1e-9)[:, None]
    n = np.stack([t[:, 1], -t[:, 0]], 1)
    return curve + n * np.asarray(d, np.float64).reshape(-1, 1)
