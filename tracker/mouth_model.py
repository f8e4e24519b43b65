"""What the mouth finder learns about one performer from the calibration frame.

Everything lives in the upright, scale-normalised mouth crop of :class:`~tracker.calibration.FaceFrame`
(x along the eye line, y down, ``work_ipd`` px between the eyes), cut with :data:`MOUTH_RECT`
around the mouth click.

A mouth has the same structure on every face, whatever the colour of lips and skin: from the
nose down, skin, the upper lip, the gap between the lips (a dark line when they are closed; the
dark inside, teeth or a tongue when open), the lower lip, skin; and along the gap, from the middle
out, lips above and below it until the corners, then cheek. Lip *thickness* changes little while
the gap opens and closes, and the gap is the high-contrast part. So calibration learns

* the **gap** at the click: the darkest row near it and the rows around it that look like the
  inside of a mouth (dark and colourless, or the greys of teeth; past a tongue on the lower teeth,
  and past a tongue filling a yawn to the dark band in front of the lower teeth; where teeth end
  the gap, over their soft edge to the first row as red as the skin, :func:`_past_teeth`);
* the **outer lip edges**: on the vertical profile through the click, the strongest change of
  colour above the gap within an upper lip's thickness, and below it within a lower lip's — the
  lower one then where the lip's own colour gives way to the skin's along a shading-free axis
  (the shadow under a lower lip is often the strongest change);
* the **corners**: the mouth line traced from the click outwards along its darkest row, and on
  each side where its columns (the bands above, on and below it) stop differing from the cheek
  further out (:func:`corner_search`) — where the lips are redder than the skin, no further than
  :data:`LIP_END` past the last column that shows them (:func:`lip_end`: a beard round the lips
  differs from the cheek as much as they do);
* what the **rows** of the profile through the centre look like — the skin above the upper lip
  (:data:`SKIN_ROWS`), the upper lip, the lower lip, the skin below — for the finder to split
  every frame's profile into the same five parts; and what the **cheek** beside each corner looks
  like along the line;
* one **lip axis** per lip (Fisher's linear discriminant of that lip's pixels against the skin
  next to it, kept orthogonal to the skin's colour) — how clearly the lips differ in colour
  (``separation``, the ``cue``) — and what the **inside** of a mouth looks like next to this
  skin (a 64³ table).

Profiles are means of small bands of pixels in colour features (:func:`profile_features`):
luminance relative to the skin's, and two brightness-free chroma ratios, each in units of a just
noticeable difference (in a picture whose colours the camera washed out, the chroma is scaled back
up by the skin's own: :func:`~tracker.colour_model.chroma_gain`). :func:`learn_mouth` never refuses
a face: a crop with no visible mouth gets a typical one at the click, and the finder's score says
how sure each frame is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from tracker.colour_model import CHROMA_PAD, TILE_SHAPE, chroma_gain, features, grid_features, lut_index, table_to_tile

FORMAT = 2
MOUTH_RECT = (-0.95, -0.6, 1.9, 1.6)
"""Crop rectangle ``(x0, y0, w, h)`` in units of ``work_ipd``, relative to the predicted mouth centre
(face px): wide enough for a grin (1.5× the width), a yawn (the centre drops ~0.3 wi, the lower lip
another 0.6 wi) and the head-motion prediction's error."""
N_RAYS = 48
"""Points on a mouth outline (half on the upper lip, half on the lower)."""
COLOUR_SEPARATION = 2.0
"""Lip-vs-skin d′ along the lip axes at and above which the lip colour is the cue."""
TABLE_NAMES = ("inside",)
"""Names of the colour-table images of :meth:`MouthModel.images` (512×512 grey tiles, 255 = inside-like)."""
BAND = 0.06
"""Half-width (× wi) of the column band a vertical profile averages."""
SKIN_ROWS = 0.12
"""Rows (× wi) of skin beyond each lip's outer edge in the vertical templates."""
LINE_BANDS = (0.03, 0.09)
"""Rows (× wi) above and below the mouth line that a column's "above" and "below" bands cover."""
L_UNIT, C_UNIT = 0.05, 0.012
"""One unit of the profile features: 5 % of the skin's luminance; 0.012 of a chroma ratio."""
_FEATURE_MIX = np.array([[0.114, 0.0, -1.0, 1.0], [0.587, -1.0, 0.5, 1.0], [0.299, 1.0, 0.5, 1.0]], np.float32)
"""BGR → (luminance, r − g, (r + g − 2b) / 2, b + g + r), the numerators of :func:`profile_features`
and the sum its chroma ratios are taken over."""
RED_PARTS = np.ascontiguousarray(_FEATURE_MIX[:, 1::2])
"""BGR → (r − g, b + g + r): the lip-red chroma's numerator and its sum, the second feature of
:func:`profile_features` taken apart (the finder's per-pixel lip-red map)."""


# --------------------------------------------------------------------------------------------- features


def luminance(bgr: np.ndarray) -> np.ndarray:
    """Rec. 601 luminance (float32, 0..255) of uint8 or float BGR pixels ``(..., 3)``."""
    c = np.asarray(bgr, dtype=np.float32)
    return c[..., 0] * np.float32(0.114) + c[..., 1] * np.float32(0.587) + c[..., 2] * np.float32(0.299)


def profile_features(bgr: np.ndarray, skin_level: float, chroma: float = 1.0) -> np.ndarray:
    """Colour features (float32 ``(..., 3)``) of mean BGR values ``(..., 3)``: luminance in units of
    :data:`L_UNIT` × the skin's, and the chroma ratios of :func:`~tracker.colour_model.features` in
    units of :data:`C_UNIT` — a squared distance of about 1 is a just visible difference — times
    ``chroma`` (:func:`~tracker.colour_model.chroma_gain`: a washed-out picture's colours brought back
    up)."""
    c = np.asarray(bgr, dtype=np.float32)
    if c.ndim == 2:
        out = c @ _FEATURE_MIX  # luminance, r − g, (r + g − 2b) / 2, b + g + r
    else:  # one product for all rows (a stack of matrices is one BLAS call per matrix)
        out = (c.reshape(-1, 3) @ _FEATURE_MIX).reshape(c.shape[:-1] + (4,))
    den = out[..., 3:]
    den += np.float32(CHROMA_PAD)
    np.divide(out[..., 1:3], den, out=out[..., 1:3])
    out[..., 0] *= np.float32(1.0 / (L_UNIT * max(skin_level, 8.0)))
    out[..., 1:3] *= np.float32(chroma / C_UNIT)
    return out[..., :3]


def band_columns(x: float, half: float, width: int) -> tuple[int, int]:
    """Columns ``[x0, x1)`` of a band ``half`` px either side of column ``x``, inside ``[0, width)``."""
    x0 = min(max(int(round(x - half)), 0), width - 1)
    return x0, min(max(int(round(x + half)) + 1, x0 + 1), width)


# --------------------------------------------------------------------------------------------- tables


TEETH = (1.1, 0.8)
"""White teeth: at least ``TEETH[0]`` times the skin's luminance with under ``TEETH[1]`` times its
chroma — per pixel in the inside table (:func:`_inside`), and per band mean along the mouth line
(:func:`lip_columns`: a grin's lips are stretched too thin to show their colour there)."""


def _inside(dark: float, skin_level: float, skin_sat: float, skin_bins: np.ndarray | None = None) -> np.ndarray:
    """Bool per 64³ bin: looks like the inside of a mouth — dark (under ``dark``) with little colour
    (absolute chroma under 60 % of the skin's: dark lipstick is dark but strongly coloured), or grey
    (teeth: chroma under 55 % of the skin's and not dark, or under 80 % and brighter than the skin).

    ``skin_bins`` (table indices) are colours the calibration saw on the skin round the mouth: they
    and their neighbouring bins are never teeth — a lit philtrum or chin under studio light is as
    bright and as colourless as teeth, but it was there at calibration and teeth were not."""
    f = grid_features()
    lum = f[:, 0] * np.float32(255.0)
    sat = np.hypot(f[:, 1], f[:, 2])
    black = (lum < np.float32(dark)) & (sat * lum < np.float32(0.6 * skin_sat * skin_level))
    grey = (sat < np.float32(0.55 * skin_sat)) & (lum > np.float32(0.45 * skin_level))
    white = (sat < np.float32(TEETH[1] * skin_sat)) & (lum > np.float32(TEETH[0] * skin_level))
    teeth = grey | white
    if skin_bins is not None and len(skin_bins):
        seen = np.zeros(len(lum), bool)
        seen[np.asarray(skin_bins, dtype=np.int64)] = True
        n = round(len(lum) ** (1 / 3))
        teeth &= ~_grow(seen.reshape(n, n, n)).reshape(-1)
    return black | teeth


def _grow(cube: np.ndarray) -> np.ndarray:
    """A boolean cube grown by one cell along each axis and diagonal (3×3×3 dilation, separable)."""
    v = cube
    for ax in range(3):
        w = v.copy()
        hi = [slice(None)] * 3
        lo = [slice(None)] * 3
        hi[ax], lo[ax] = slice(1, None), slice(None, -1)
        w[tuple(hi)] |= v[tuple(lo)]
        w[tuple(lo)] |= v[tuple(hi)]
        v = w
    return v


SKIN_BIN_COUNT = 3
"""Pixels of one colour bin on the skin round the calibration's mouth that make it a skin colour."""


def round_mouth(shape: tuple[int, ...], outline: np.ndarray, centre: tuple[float, float], wi: float) -> np.ndarray:
    """The skin round the mouth in a crop of ``shape`` (bool (H, W)): an ellipse 0.75 × 0.6 wi about
    the mouth centre (the face, not the background or hair at the crop's sides), outside the mouth
    ``outline`` (crop px) grown by 0.1 wi."""
    H, W = shape[:2]
    near = np.zeros((H, W), np.uint8)
    cv2.ellipse(near, (int(round(centre[0])), int(round(centre[1]))), (int(round(0.75 * wi)), int(round(0.6 * wi))),
                0.0, 0.0, 360.0, 1, -1)
    mouth = np.zeros((H, W), np.uint8)
    cv2.fillPoly(mouth, [np.round(outline).astype(np.int32)], 1)
    r = max(int(round(0.1 * wi)), 1)
    mouth = cv2.dilate(mouth, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
    return (near > 0) & (mouth == 0)


def chin_band(shape: tuple[int, ...], outline: np.ndarray, wi: float) -> tuple[int, int, int, int]:
    """The chin under the mouth in a crop of ``shape``: rows from 0.08 to 0.3 wi under the
    ``outline``'s lowest point (crop px) and the middle half of its width, as ``(y0, y1, x0, x1)``
    (clipped to the crop; empty when the mouth is at its edge). Below the lower lip's own shadow,
    and between the smile's folds."""
    H, W = shape[:2]
    x_lo, x_hi = float(outline[:, 0].min()), float(outline[:, 0].max())
    mx, hw, yb = 0.5 * (x_lo + x_hi), 0.25 * (x_hi - x_lo), float(outline[:, 1].max())
    y0, y1 = min(max(int(round(yb + 0.08 * wi)), 0), H), min(max(int(round(yb + 0.3 * wi)), 0), H)
    x0, x1 = min(max(int(round(mx - hw)), 0), W), min(max(int(round(mx + hw)), 0), W)
    return y0, y1, x0, x1


def skin_colour_bins(index: np.ndarray, round_px: np.ndarray) -> np.ndarray:
    """Table indices (sorted int32) of the colours on the skin round the mouth in the calibration
    crop (``index``: its :func:`~tracker.colour_model.lut_index`; ``round_px``: :func:`round_mouth`),
    the bins with at least :data:`SKIN_BIN_COUNT` pixels."""
    counts = np.bincount(index[round_px].ravel(), minlength=1)
    return np.flatnonzero(counts >= SKIN_BIN_COUNT).astype(np.int32)


OPEN_DARK = 0.75
"""Pixels darker than this share of the calibrated lips' luminance count as an open mouth's inside
where its corners are looked for (:meth:`~tracker.mouth_finder.MouthFinder.inside_ends`), whatever
their colour: the shaded triangles at a grin's corners on a dark face are as brown as the skin round
them, not the inside's colours, but far darker than the lips."""
DARK_ROUND = 0.05
"""Largest share of the skin round the mouth at calibration (:func:`round_mouth`) darker than
:data:`OPEN_DARK` × the lips for that rule to apply: a beard there (0.1-0.6 of it on the bearded
copies of the shared clips; clean faces 0-0.03, the nostrils' shadows) is as dark as a grin's shaded
corners, and the corners ran on into the hair. Hair also needs a dark chin (:data:`DARK_CHIN`), so a
moustache with no beard under the lips is not hair to the tracker."""
DARK_CHIN = 0.15
"""Least share of the chin under the lower lip (:func:`chin_band`) darker than :data:`OPEN_DARK` ×
the lips for the dark skin round the mouth to be hair (:func:`~tracker.mouth_finder.hair_round`).
A smile calibrated on has its own dark skin round the mouth: the folds beside it and the nostrils'
shadow over it, 0.05-0.21 of the round on seven of the fourteen still photos, none of them
bearded, while their chins are 0-0.07 dark; the bearded copies of the shared clips whose round is
dark have chins 0.30-0.94 dark, and the clean clips 0."""


def lips_grey(classes: np.ndarray, skin_level: float) -> float:
    """The darker lip's luminance in grey levels (BT.601) from a model's row ``classes``."""
    return float(min(classes[1, 0, 0], classes[2, 0, 0])) * L_UNIT * max(skin_level, 8.0)


# --------------------------------------------------------------------------------------------- the model


@dataclass
class MouthModel:
    """One performer's mouth (see the module docstring). Lengths are face px (``work_ipd`` between the eyes).

    ``centre`` is the calibrated mouth centre (midpoint of the corners) in the calibration crop's
    pixels; the tracker turns it into a face-frame offset. ``width``, ``lip_upper``, ``lip_lower``
    and ``area`` are the calibration frame's measurements; ``outline`` the mouth outline there,
    relative to the centre. ``gap`` is the calibration's gap height at the centre (0: closed lips)
    and ``line`` the gap's middle below the centre; ``thick_up`` / ``thick_down`` the lips'
    thicknesses there (inner to outer edge); ``half_left`` / ``half_right`` the corners' distances
    from the centre along the line.

    ``classes`` (5, 2, 3) describe the rows of the vertical profile through the centre, from the
    top: the skin above the upper lip, the upper lip, the lower lip, the skin below it — each the
    median and the spread of its rows' :func:`profile_features` — and the skin round the mouth
    (which a bulging chin or a lit philtrum looks like better than the skin next to the lips did); ``cheek_left`` / ``cheek_right`` (2, 9) the cheek beside each corner
    along the line (median and spread of :func:`line_columns`' features). ``axis_up`` /
    ``axis_down`` (4,) map BGR to the lip value ``w·bgr + c`` of the upper / lower lip (0 on the skin
    next to it, 1 on the lip); ``separation`` is their smaller d′, ``cue`` ``"colour"`` (≥
    :data:`COLOUR_SEPARATION`) or ``"contrast"``. ``skin_level`` / ``skin_sat`` are the skin's median
    luminance and chroma, ``dark`` the luminance under which a colourless pixel is the mouth's dark
    inside; they define ``inside_table`` (64³, 1 = inside-like). ``crop_median`` is the calibration
    crop's median BGR (mostly skin), the reference each frame's light is matched to. ``dark_round``
    is the share of the skin round the mouth there darker than :data:`OPEN_DARK` × the lips (hair:
    see :data:`DARK_ROUND`; None in calibrations older than it), ``dark_chin`` that share of the chin
    under the lower lip (:func:`chin_band`, :data:`DARK_CHIN`; None in calibrations older than it, or
    when the chin is outside the crop: the round alone then says hair).
    """

    work_ipd: float
    centre: tuple[float, float]
    width: float
    lip_upper: float
    lip_lower: float
    area: float
    outline: np.ndarray
    gap: float
    line: float
    thick_up: float
    thick_down: float
    half_left: float
    half_right: float
    classes: np.ndarray
    cheek_left: np.ndarray
    cheek_right: np.ndarray
    axis_up: np.ndarray
    axis_down: np.ndarray
    skin_level: float
    skin_sat: float
    dark: float
    separation: float
    cue: str
    crop_median: tuple[float, float, float] | None = None
    dark_round: float | None = None
    dark_chin: float | None = None
    skin_bins: np.ndarray | None = field(repr=False, default=None)
    inside_table: np.ndarray = field(repr=False, default=None)

    def __post_init__(self) -> None:
        if self.inside_table is None:
            self.inside_table = _inside(self.dark, self.skin_level, self.skin_sat, self.skin_bins).view(np.uint8)

    # ------------------------------------------------------------------ persistence
    _ARRAYS = ("outline", "classes", "cheek_left", "cheek_right")
    _FLOATS = ("work_ipd", "width", "lip_upper", "lip_lower", "area", "gap", "line", "thick_up", "thick_down",
               "half_left", "half_right", "skin_level", "skin_sat", "dark", "separation")

    def to_dict(self) -> dict:
        """JSON-able description (the table is rebuilt from it; :meth:`images` shows it)."""
        d = {"format": FORMAT, "kind": "inkface-mouth"}
        d.update({k: float(getattr(self, k)) for k in self._FLOATS})
        d.update({k: np.round(np.asarray(getattr(self, k), dtype=np.float64), 4).tolist() for k in self._ARRAYS})
        d.update(
            centre=[float(v) for v in self.centre],
            axis_up=[float(v) for v in self.axis_up], axis_down=[float(v) for v in self.axis_down], cue=self.cue,
            crop_median=None if self.crop_median is None else [float(v) for v in self.crop_median],
            tables=list(TABLE_NAMES),
        )
        if self.dark_round is not None:
            d["dark_round"] = float(self.dark_round)
        if self.dark_chin is not None:
            d["dark_chin"] = float(self.dark_chin)
        if self.skin_bins is not None:
            d["skin_bins"] = [int(v) for v in self.skin_bins]
        return d

    def images(self) -> dict[str, np.ndarray]:
        """The baked table as a 512×512 uint8 grey image, by name (:data:`TABLE_NAMES`)."""
        return {"inside": table_to_tile(self.inside_table * np.uint8(255))}

    @classmethod
    def from_dict(cls, d: dict, images: dict[str, np.ndarray] | None = None) -> "MouthModel":
        """Rebuild from :meth:`to_dict` (``images`` are accepted and checked but not needed: the
        table is rebuilt from the description). Raises ``ValueError`` (one line) when malformed."""
        if not isinstance(d, dict) or d.get("kind") != "inkface-mouth":
            raise ValueError("not an Inkface mouth model")
        if d.get("format") != FORMAT:
            raise ValueError(f"mouth model of format {d.get('format')!r}, this Inkface reads format {FORMAT}: "
                             "calibrate again")
        img = None if images is None else images.get("inside")
        if img is not None and (np.asarray(img).shape != TILE_SHAPE or np.asarray(img).dtype != np.uint8):
            raise ValueError(f"mouth table image must be {TILE_SHAPE[1]}×{TILE_SHAPE[0]} 8-bit grey")
        try:
            kw = {k: float(d[k]) for k in cls._FLOATS}
            shapes = {"outline": (-1, 2), "classes": (5, 2, 3), "cheek_left": (2, 9), "cheek_right": (2, 9)}
            for k, shape in shapes.items():
                a = np.asarray(d[k], dtype=np.float64).reshape(shape)
                kw[k] = a if k == "outline" else a.astype(np.float32)
            return cls(
                centre=(float(d["centre"][0]), float(d["centre"][1])),
                axis_up=np.asarray(d["axis_up"], dtype=np.float64).reshape(4),
                axis_down=np.asarray(d["axis_down"], dtype=np.float64).reshape(4), cue=str(d["cue"]),
                crop_median=None if d.get("crop_median") is None else tuple(float(v) for v in d["crop_median"]),
                skin_bins=_bins(d.get("skin_bins")), dark_round=_share(d.get("dark_round")),
                dark_chin=_share(d.get("dark_chin"), "dark_chin"),
                **kw,
            )
        except (KeyError, TypeError, IndexError, ValueError) as e:
            raise ValueError(f"malformed mouth model ({type(e).__name__}: {e})") from None


def _share(v, name: str = "dark_round") -> float | None:
    """A share (``dark_round``, ``dark_chin``) from a file (absent in calibrations older than it: None)."""
    if v is None:
        return None
    x = float(v)
    if not 0.0 <= x <= 1.0:
        raise ValueError(f"{name} must be a share from 0 to 1, not {x}")
    return x


def _bins(v) -> np.ndarray | None:
    """``skin_bins`` from a file (absent in calibrations older than it: None)."""
    if v is None:
        return None
    a = np.asarray(v, dtype=np.int64).reshape(-1)
    if a.size and (a.min() < 0 or a.max() >= 1 << 18):
        raise ValueError("skin_bins must be colour-table indices (0 … 262143)")
    return a.astype(np.int32)


# --------------------------------------------------------------------------------------------- lip colour


def fisher_axis(a: np.ndarray, b: np.ndarray, shading_free: bool = True) -> tuple[np.ndarray, float]:
    """Linear map ``w·x + c`` (4,) of BGR with mean of ``b`` (skin) → 0 and mean of ``a`` (lip) → 1
    that best separates the two (Fisher's discriminant), and the separation d′ along it.

    With ``shading_free`` the axis is kept orthogonal to the skin's colour (``w·mean(b) = 0``, so
    ``c = 0``): skin in shadow or brighter light still reads 0 — the lip value is then a contrast
    of colour, not of brightness."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 3)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 3)
    ma, mb = a.mean(0), b.mean(0)
    ca = np.cov(a.T) if len(a) > 3 else np.eye(3)
    cb = np.cov(b.T) if len(b) > 3 else np.eye(3)
    sw = ca + cb + np.eye(3) * 4.0  # + 2 grey levels of noise per channel and class
    d = ma - mb
    if shading_free:
        u = mb / max(float(np.linalg.norm(mb)), 1e-6)
        p = np.eye(3) - np.outer(u, u)
        w = p @ np.linalg.pinv(p @ sw @ p) @ p @ d
    else:
        w = np.linalg.solve(sw, d)
    span = float(w @ d)
    if span <= 1e-9:
        w, span = d, float(d @ d) + 1e-9
    sd = math.sqrt(max(float(w @ (0.5 * (ca + cb)) @ w), 1e-12))
    w = w / span
    return np.concatenate([w, [-float(w @ mb)]]), span / sd


def best_axis(lips: np.ndarray, skin: np.ndarray) -> tuple[np.ndarray, float]:
    """The shading-free lip axis, or the plain one when the lips differ from the skin mostly in
    brightness (its d′ at least 1.25 × the shading-free one's); and its d′."""
    axis, sep = fisher_axis(lips, skin)
    axis_b, sep_b = fisher_axis(lips, skin, shading_free=False)
    return (axis_b, sep_b) if sep_b > 1.25 * sep else (axis, sep)


# --------------------------------------------------------------------------------------------- geometry


def lens_outline(left, right, top: float, bottom: float, x_mid: float, n: int = N_RAYS) -> np.ndarray:
    """A closed mouth outline (n, 2) through the corners ``left`` / ``right`` (x, y) and, on the
    column ``x_mid``, the outer lip edges at rows ``top`` and ``bottom``: the upper lip from left to
    right, then the lower lip back, each an arc ``(1 − t²)^0.7`` above / below the corners' line."""
    return lens_outlines(left, right, (top,), (bottom,), x_mid, n)[0]


_ARC_T: dict[int, np.ndarray] = {}
"""The arc parameters ``linspace(0, 1, half + 1)`` of :func:`lens_outlines`, by ``half``."""


def lens_outlines(left, right, tops, bottoms, x_mid: float, n: int = N_RAYS) -> np.ndarray:
    """:func:`lens_outline` for several pairs of edges through the same corners at once: (k, n, 2)."""
    (xl, yl), (xr, yr) = left, right
    half = n // 2
    t = _ARC_T.get(half)
    if t is None:
        t = _ARC_T[half] = np.linspace(0.0, 1.0, half + 1)
    s = min(max((x_mid - xl) / max(xr - xl, 1e-6), 0.05), 0.95)
    u = np.where(t <= s, t * (1.0 / s) - 1.0, (t - s) * (1.0 / (1.0 - s)))
    shape = np.clip(1.0 - u * u, 0.0, 1.0) ** 0.7  # 1 at x_mid, 0 at the corners
    base = yl + t * (yr - yl)
    base_mid = yl + s * (yr - yl)
    tops, bottoms = np.asarray(tops, dtype=np.float64), np.asarray(bottoms, dtype=np.float64)
    out = np.empty((len(tops), 2 * half, 2))
    xs = xl + t * (xr - xl)
    out[:, :half, 0] = xs[:-1]
    out[:, half:, 0] = xs[:0:-1]
    out[:, :half, 1] = base[:-1] - (base_mid - tops)[:, None] * shape[:-1]
    out[:, half:, 1] = (base + (bottoms - base_mid)[:, None] * shape)[:, :0:-1]
    return out[:, :n]


def polygon_area(poly: np.ndarray) -> float:
    """Area (px²) of a closed polygon (shoelace)."""
    x, y = poly[:, 0], poly[:, 1]
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


# --------------------------------------------------------------------------------------------- the line


def trace_line(lum: np.ndarray, x0: int, y0: float, step: int, n: int) -> np.ndarray:
    """Rows (float, length ``n + 1``) of the mouth line from column ``x0`` (row ``y0``) over ``n``
    columns in direction ``step`` (±1), along a valley of ``lum`` (a smoothed luminance image): in
    each next column, of the row above, the same row and the row below, the darkest that is darker
    than both rows next to it in that column — the gap between the lips, or the middle of an open
    mouth, bending with a smile; where no such row is there (even skin, a slope of shading) the
    line goes straight on. Columns past the image's edge keep the last row."""
    h, w = lum.shape
    lo, hi = 2, h - 3
    y = min(max(int(round(y0)), lo), hi)
    # the columns inside the image are steps ka..kb (a run: the columns go one way)
    ka, kb = (max(1, -x0), min(n, w - 1 - x0)) if step > 0 else (max(1, x0 - w + 1), min(n, x0))
    out = [y] * min(ka, n + 1)
    if kb >= ka:
        block = lum[:, x0 + ka : x0 + kb + 1] if step > 0 else lum[:, x0 - kb : x0 - ka + 1][:, ::-1]
        cols = np.ascontiguousarray(block.T)  # one column after the other, in the walk's order
        vals = cols.tobytes() if cols.dtype == np.uint8 else cols.ravel().tolist()
        step_to = out.append
        for base in range(0, len(vals), h):
            # rows y-2 .. y+2 exist (y stays in [2, h-3]); a valley at y excludes one at y±1; down wins
            # over up when it is darker or up is no valley
            m2, m1, c0, p1, p2 = vals[base + y - 2 : base + y + 3]
            if not (c0 < m1 and c0 < p1):
                if p1 < c0 and p1 < p2 and (p1 < m1 or not (m1 < m2 and m1 < c0)):
                    if y < hi:
                        y += 1
                elif m1 < m2 and m1 < c0:
                    if y > lo:
                        y -= 1
            step_to(y)
    out += [y] * (n + 1 - len(out))
    return np.array(out, dtype=np.float64)


def line_columns(strip: np.ndarray, x0: int, ys: np.ndarray, step: int, a1: int, a2: int, skin_level: float,
                 gains: np.ndarray | None = None, chroma: float = 1.0) -> np.ndarray:
    """Features (len(ys), 9) of the columns along a traced line: :func:`profile_features` of the mean
    BGR of the band ``a1..a2`` rows above the line, of the line's own three rows, and of the band
    ``a1..a2`` rows below, per column ``x0 + step·k``."""
    h, w = strip.shape[:2]
    n = len(ys)
    xs = np.clip(x0 + step * np.arange(n), 0, w - 1)
    offs = np.concatenate([-np.arange(a1, a2 + 1), np.arange(-1, 2), np.arange(a1, a2 + 1)])
    rows = np.clip(ys.astype(np.int32)[:, None] + offs[None, :], 0, h - 1)
    px = strip[rows, xs[:, None]].astype(np.float32)  # (n, m, 3)
    m = a2 - a1 + 1
    means = np.stack([px[:, :m].mean(1), px[:, m : m + 3].mean(1), px[:, m + 3 :].mean(1)], axis=1)  # (n, 3, 3)
    if gains is not None:
        means *= gains.astype(np.float32)
    return profile_features(means, skin_level, chroma).reshape(n, 9)


def line_geometry(wi: float) -> tuple[int, int]:
    """Rows ``(a1, a2)`` of the above / below bands of :func:`line_columns` at this scale."""
    a1 = max(int(round(LINE_BANDS[0] * wi)), 1)
    return a1, max(int(round(LINE_BANDS[1] * wi)), a1 + 2)


# --------------------------------------------------------------------------------------------- learning


def _skin(crop: np.ndarray, cx: float, cy: float, wi: float, skin_samples) -> np.ndarray:
    """The skin round the mouth: an elliptic ring about the click outside any mouth, its 90 % most
    typical pixels (plus ``skin_samples`` from elsewhere on the face)."""
    H, W = crop.shape[:2]
    yy, xx = np.mgrid[0:H, 0:W]
    e = ((xx - cx) / (0.72 * wi)) ** 2 + ((yy - cy) / (0.45 * wi)) ** 2
    ring = crop[(e <= 1.0) & (e >= 0.75**2)]
    if skin_samples is not None and len(skin_samples):
        ring = np.concatenate([ring, np.asarray(skin_samples, dtype=np.uint8).reshape(-1, 3)])
    fs = features(ring, 1.0)
    med = np.median(fs, axis=0)
    dev = np.abs(fs - med) / (np.median(np.abs(fs - med), axis=0) * 1.4826 + 1e-6)
    return ring[dev.max(axis=1) <= np.percentile(dev.max(axis=1), 90)]


GAP_RED = (2.0, 0.35)
"""How much redder than the skin (chroma units; at least the first, and the second share of the
reddest row's lead near the click) the rows above and below a dark valley must be for it to lie
between two lips (:func:`_between_lips`)."""


def lip_red_need(lead: float) -> float:
    """How much redder than the skin a row must be to be lip (:data:`GAP_RED`), for lips ``lead``
    (r − g chroma units) redder than it."""
    return max(GAP_RED[0], GAP_RED[1] * lead)


def lip_sides(red: np.ndarray, ys, rows: int, need: float, any_row: bool = False) -> list[tuple[bool, bool]]:
    """Per row ``y`` of ``ys``: whether the ``rows`` rows above it and the ``rows`` rows below it are
    lip-red (``red`` at least ``need``; a profile's r − g chroma per row) — on average, or with
    ``any_row`` anywhere there. No rows on a side (the profile's end): not lip-red."""
    H = len(red)
    if any_row:
        v = red.tolist()
        if math.isfinite(sum(v)):  # plain lists (a few rows a side): np.max's value, without its overhead
            out = []
            for y in ys:
                above, below = v[max(y - rows, 0) : y], v[y + 1 : min(y + 1 + rows, H)]
                out.append((len(above) > 0 and max(above) >= need, len(below) > 0 and max(below) >= need))
            return out
    pick = np.max if any_row else np.mean
    out = []
    for y in ys:
        above, below = red[max(y - rows, 0) : y], red[y + 1 : min(y + 1 + rows, H)]
        out.append((len(above) > 0 and float(pick(above)) >= need, len(below) > 0 and float(pick(below)) >= need))
    return out


def _between_lips(red_rows: np.ndarray, ys: list[int], cy: float, wi: float, reach: float = 0.04,
                  any_row: bool = False) -> list[bool]:
    """Per row ``y`` of ``ys``: whether the rows above it and below it (``reach`` wi each) are both
    lip-red (``red_rows``: each row's r − g chroma minus the skin's; the lips' lead is the reddest
    row's near the click ``cy``; :func:`lip_sides`) — an open mouth's dark inside lies between lips
    further off (``any_row``)."""
    H = len(red_rows)
    ra, rb = max(int(round(cy - 0.35 * wi)), 0), min(int(round(cy + 0.45 * wi)) + 1, H)
    need = lip_red_need(float(red_rows[ra:rb].max(initial=0.0)))
    return [up and down for up, down in lip_sides(red_rows, ys, max(int(round(reach * wi)), 2), need, any_row)]


def _gap(lum_rows: np.ndarray, inside_rows: np.ndarray, cy: float, wi: float,
         red_rows: np.ndarray | None = None, past_tongue: bool = False) -> tuple[int, int, int]:
    """The gap on the profile through the click: ``(top, bottom, darkest)`` rows.

    The darkest row within −0.12…+0.15 wi of the click is in the gap between the lips or in the open
    mouth — unless the lips' colour (``red_rows``, :func:`_between_lips`) says otherwise: when that row
    has no lip-red rows above and below it within 0.2 wi and another dark valley there has them right
    next to it, that valley is (a moustache over thin closed lips is darker than the line between
    them; the inside of an open mouth has its lips further off). The gap spreads up and down over
    rows nearly as dark (15 % of the way from that row to the profile's median: a dark lip is not
    that dark; none where the median is darker than that row — a light line between lips in a
    beard, where the gap ran up through the moustache) or teeth (``inside_rows``: the share of
    teeth-like pixels), across a row or two of neither (the blurred edge between them), at most
    0.35 wi each way; below, past a tongue on the lower teeth: lip-like rows followed by more teeth
    within 0.15 wi are inside too.

    ``past_tongue``: the mouth is open round a tongue (the caller found the lip below the gap
    thicker than any lip): the gap goes on down over the lighter rows to a second band of dark rows,
    within :data:`OPEN_SPAN` wi of its top and at its darkest no lighter than the gap (the inside in
    front of the lower teeth; a shade on a full lower lip is lighter than the mouth's inside), when
    lip-red rows (``red_rows``) follow that band within :data:`LIP_MAX`, redder than any row between
    — the lower lip; without one, the gap stays."""
    H = len(lum_rows)
    ya, yb = max(int(round(cy - 0.12 * wi)), 0), min(int(round(cy + 0.15 * wi)) + 1, H)
    y_min = ya + int(np.argmin(lum_rows[ya:yb]))
    if red_rows is not None and yb - ya >= 3 and not _between_lips(red_rows, [y_min], cy, wi, reach=0.2, any_row=True)[0]:
        valleys = [y for y in range(max(ya, 1), min(yb, H - 1)) if lum_rows[y] < lum_rows[y - 1] and lum_rows[y] <= lum_rows[y + 1]]
        lips = [y for y, ok in zip(valleys, _between_lips(red_rows, valleys, cy, wi)) if ok]
        if lips:
            y_min = min(lips, key=lambda y: lum_rows[y])
    ra, rb = max(int(round(cy - 0.35 * wi)), 0), min(int(round(cy + 0.45 * wi)) + 1, H)
    spread = float(np.median(lum_rows[ra:rb])) - lum_rows[y_min]
    skip = (lum_rows < lum_rows[y_min] + 0.15 * spread) if spread > 0 else np.zeros(H, bool)
    skip |= inside_rows > 0.5
    limit = int(round(0.35 * wi))
    bridge = max(int(round(0.025 * wi)), 1)

    def walk(y: int, step: int) -> int:
        """From ``y`` over gap rows, across up to ``bridge`` rows that are not (a blurred edge
        between the dark inside and teeth)."""
        while True:
            nxt = [y + step * j for j in range(1, bridge + 2) if 0 <= y + step * j < H and abs(y + step * j - y_min) <= limit]
            hit = next((v for v in nxt if skip[v]), None)
            if hit is None:
                return y
            y = hit

    top = walk(y_min, -1)
    bottom = y_min
    while True:
        bottom = walk(bottom, +1)
        reach = range(bottom + 2, min(bottom + int(round(0.15 * wi)), H - 1))
        teeth = [v for v in reach if inside_rows[v] > 0.5 and inside_rows[v + 1] > 0.5]
        if not teeth or teeth[0] - y_min > limit:
            break
        bottom = teeth[0]
    if past_tongue and red_rows is not None:
        end = min(top + int(round(OPEN_SPAN * wi)), H - 1)
        band = next((v for v in range(bottom + bridge + 2, end + 1) if skip[v]), None)
        if band is not None:
            far = band
            while far + 1 <= end and skip[far + 1]:
                far += 1
            ra, rb = max(int(round(cy - 0.35 * wi)), 0), min(int(round(cy + 0.45 * wi)) + 1, H)
            need = lip_red_need(float(red_rows[ra:rb].max(initial=0.0)))
            lip = red_rows[far + 1 : min(far + 1 + int(round(LIP_MAX[1] * wi)), H)]
            # the lip past the band redder than anything that lay between (a tongue is no redder than
            # the lips; where those rows are a full lower lip, and the band the shade under it, the
            # chin past the shade is paler than the lip)
            if (far < end and len(lip) and float(lum_rows[band : far + 1].min()) <= float(lum_rows[y_min])
                    and float(lip.max()) >= max(need, float(red_rows[bottom + 1 : band].max()))):
                bottom = far
    return top, bottom, y_min


TEETH_BLUR = 0.05
"""Most rows (× wi) past the teeth's end that still belong to the gap (see :func:`_past_teeth`)."""


def _past_teeth(red_rows: np.ndarray, end: int, direction: int, wi: float) -> int:
    """The gap's end row ``end`` (its last row; ``direction`` −1 up, +1 down) moved past the blur
    between teeth and a lip: rows less red than the skin (``red_rows`` < 0, the teeth's grey mixed with
    the lip) up to the first row at least as red, within :data:`TEETH_BLUR` wi. A grin's teeth end
    on a soft edge a few rows tall, and the lip's outer edge measured from the teeth's last clear row
    took that edge for the whole lip (a lower lip 0.04 wi thick that the tracker then looked for)."""
    n = len(red_rows)
    for j in range(1, max(int(round(TEETH_BLUR * wi)), 1) + 1):
        y = end + direction * j
        if not 0 <= y < n:
            break
        if red_rows[y] >= 0.0:
            return y - direction
    return end


OPEN_SPAN = 0.6
"""Tallest inside of an open mouth (× wi, from the upper lip's inner edge down; a yawn's is about
half the eye distance)."""


LIP_SEEN = 1.5
"""Shading-free d′ of a lip's inner half against the skin at and above which its colour places its
outer edge (:func:`_colour_edge`)."""


def _colour_edge(rows_bgr: np.ndarray, start: int, direction: int, first: float, skin_bgr: np.ndarray,
                 reach: tuple[float, float], wi: float) -> float:
    """A lip's outer edge on a profile of mean BGR rows (``rows_bgr`` (n, 3)) by its colour: where the
    rows past the gap (``start``, the gap's last row; ``direction`` −1 up, +1 down) stop looking like
    the lip's inner half and start looking like the skin along a shading-free axis (Fisher's
    discriminant kept orthogonal to the skin's colour, :func:`fisher_axis`) — a shadow on the skin
    (under the lower lip, a moustache's shade) is darker skin, not lip. ``first`` is the edge from
    the mean-contrast split (:func:`_outer_edge`, a row): the lip's inner half is
    taken from it, and it is kept when the lip's colour is not clearly apart from the skin
    (:data:`LIP_SEEN`) or no crossing lies within ``reach`` (× wi from ``start``)."""
    n = len(rows_bgr)
    half = max(int(round(0.5 * abs(first - start))), 2)
    idx = [start + direction * j for j in range(1, half + 1) if 0 <= start + direction * j < n]
    if len(idx) < 2 or len(skin_bgr) < 8:
        return first
    # the skin: round the mouth, and just past the first edge (a philtrum or chin redder than the cheeks)
    far = [int(round(first)) + direction * j for j in range(2, 2 + max(int(round(0.1 * wi)), 2))]
    far = [y for y in far if 0 <= y < n]
    skin = skin_bgr if not far else np.concatenate([skin_bgr, np.repeat(rows_bgr[far], max(len(skin_bgr) // (4 * len(far)), 1), axis=0)])
    axis, sep = fisher_axis(rows_bgr[idx], skin)
    if sep < LIP_SEEN:
        return first
    lv = rows_bgr @ axis[:3] + axis[3]
    lo, hi = max(int(math.floor(reach[0] * wi)), 2), int(math.ceil(reach[1] * wi))
    prev = None
    for j in range(1, hi + 1):
        y = start + direction * j
        if not 0 <= y < n:
            return first
        v = float(lv[y])
        if v < 0.5 and j >= lo:
            t = 0.0 if prev is None else min(max((prev - 0.5) / max(prev - v, 1e-6), 0.0), 1.0)
            return float(start + direction * (j - 1 + t))
        prev = v
    return first


EDGE_INTERIOR = 0.5
"""A lip's outer edge found at the thinnest lip the search allows, with the split still improving
towards the gap, gives way to a peak further out scoring at least this share of it
(:func:`_outer_edge`); without one, an upper lip's edge is not seen (:data:`UPPER_UNSEEN`) and a
lower lip's stays where it is (its colour places it next, :func:`_colour_edge`). The two splits are
often a near tie (on expr_d6's first frame 61 against 54), so a pixel of the click decided which one
won: of the calibrations of the 22 unbearded harder copies of the shared clips (clicks and
``--auto``), 8 lay more than 0.05 IPD from their clip's median lower lip, 2 with the rule for both
lips (mean spread over the copies 0.012 → 0.007 IPD). The tracker then looked for a lower lip of 4 px
at 80 px between the eyes all clip long: expr_d6 smeared by a hand-held camera's motion, ``--auto``,
opening r .45 → .82. The dark-skinned copy of expr_d19 with ``--auto``, whose lower lip barely differs
from the skin, followed the peer better with the thin lip it had calibrated (.89; .78 with the lip as
thick as the other copies of the clip calibrate it)."""
EDGE_CHROMA = True
"""Whether an upper lip edge the split on all the features does not show is looked for on the colour
alone (see :func:`_outer_edge`)."""
UPPER_FLOOR = 0.8
"""Least share of the centre column's upper-lip thickness the calibration keeps when the columns to
either side measure it thinner. Their votes stop one column's crease or highlight from deciding,
but on a noisy or low-contrast picture the side columns lose the upper lip's soft top edge first.
expr_d19's calibration measured 12.2 / 10.6 / 11.8 px (centre, left, right) on the clip and
12.5 / 7.4 / 5.7 on its noisy copy, and the tracker, expecting a lip 40 % thinner, laid the
stretched upper lip of a smile onto the skin above it (the opening's r 0.73 there, 0.69 on the
pale copy). The clip's own sides are within 0.87 of its centre, so the floor leaves it be. The
price: a crease over the centre column's lip now carries the thickness up to this share of the
thickness it reads there, where the sides' votes used to overrule it."""
UPPER_UNSEEN = 0.075
"""Thickness (× wi) taken for an upper lip whose outer edge the calibration frame does not show: the
split improves all the way to the gap and no peak further out stands up (:data:`EDGE_INTERIOR`) —
the gap's own blurred shade decides, as it does on a soft or low-resolution picture and on pale
lips. The search's thinnest lip (0.03 wi) then stood for a measurement, and the tracker looked for
an upper lip of one to three px at its working scale for the whole clip: expr_d19 at half its
resolution read 0.03 where the full picture gave 0.14 (the peer: 0.05), and its opening's
correlation fell from .92 to .70. A thin lip's thickness here (the peer's upper lips on the shared
clips' first frames: 0.03–0.23 IPD, median 0.13) lets the lip lengths the tracker tries reach a
real lip's; where the lip really is that thin (expr_d18's first frame, 0.03 by the peer) the
tracker still finds it so. Only when none of the three columns calibration measures shows the edge:
an unseen column is no vote (the glasses, pale and half-size copies of expr_d19 had one or two of
the three unseen, the median fell on 0.075 where the full picture reads 0.13-0.16, and the glasses
copy's opening followed the peer at r 0.76; 0.92 with this)."""


def upper_thickness(columns: list[float], wi: float) -> float:
    """The calibrated upper lip's thickness (px) from its thickness on each measured column, the
    centre column first (NaN: that column did not show the lip's outer edge, and is no vote): the
    median of the columns that show it, at least :data:`UPPER_FLOOR` of the centre's, or
    :data:`UPPER_UNSEEN` wi when none does."""
    seen = [float(u) for u in columns if math.isfinite(u)]
    if not seen:
        return UPPER_UNSEEN * wi
    thick = float(np.median(seen))
    return max(thick, UPPER_FLOOR * float(columns[0])) if math.isfinite(columns[0]) else thick


def _outer_edge(f: np.ndarray, start: int, direction: int, lo: float, hi: float, wi: float,
                unseen: float | None = None) -> float:
    """The outer edge of a lip on a profile ``f`` (rows, c), from its inner edge ``start`` (the gap's
    last row) in ``direction`` (−1 up, +1 down), ``lo``..``hi`` wi away: the row that best splits the
    rows past the gap into a lip (all rows from the gap to it) and skin (:data:`SKIN_ROWS` beyond it)
    — where the whole lip's mean differs most from the skin's just past it. A lip's window grows
    with the candidate, so a soft edge, a highlight on the lip or a crease in the skin do not pull
    the edge the way the steepest local change would. Sub-pixel. A split best at the thinnest lip is
    the gap's blurred shade: a peak further out wins (:data:`EDGE_INTERIOR`); for an upper lip without
    one, such a peak on the colour alone (:data:`EDGE_CHROMA`). An upper lip whose edge the profile
    does not show either way comes back :data:`UPPER_UNSEEN` thick, or as ``unseen`` when that is
    given (NaN: no measurement, for a caller that has other columns)."""
    n = len(f)
    s_rows = max(int(round(SKIN_ROWS * wi)), 3)
    cs = np.concatenate([np.zeros((1, f.shape[1])), np.cumsum(f, axis=0, dtype=np.float64)])

    def mean(a: int, b: int) -> np.ndarray:  # rows a..b-1
        return (cs[b] - cs[a]) / max(b - a, 1)

    first = start + direction  # the lip's first row
    es = np.arange(max(int(math.floor(lo * wi)), 2), int(math.ceil(hi * wi)) + 1)
    score = np.full(len(es), -np.inf)
    chroma = np.full(len(es), -np.inf)
    for j, e in enumerate(es):
        edge = start + direction * e  # first skin row
        if direction < 0:
            la, lb, sa, sb = edge + 1, first + 1, edge - s_rows + 1, edge + 1
        else:
            la, lb, sa, sb = first, edge, edge, edge + s_rows
        if sa < 0 or sb > n or la >= lb:
            continue
        d = mean(la, lb) - mean(sa, sb)
        score[j] = float(d @ d)
        chroma[j] = float(d[1:] @ d[1:])
    if not np.isfinite(score).any():
        return float(start + direction * 0.5 * (lo + hi) * wi)
    j = int(np.argmax(score))
    if j == 0:
        # a lip split best at the thinnest lip allowed, better still towards the gap: that is the gap's
        # own blurred edge (rows next to the line are its shade), not the lip's outer edge; a peak
        # further out is the edge where there is one
        peaks = _further_peaks(score)
        if peaks:
            j = max(peaks, key=lambda k: score[k])
        elif direction < 0 and EDGE_CHROMA and (tints := _further_peaks(chroma, 1.0)):
            # the shade is mostly the gap's darkness, the lip's own edge where its colour ends: the same
            # peak on the colour alone (a soft, small or noisy picture spreads the gap's shade over a
            # pale upper lip, and the split on everything peaked at the gap on all three columns); at
            # least a just visible difference of colour (a squared feature distance of 1)
            j = max(tints, key=lambda k: chroma[k])
            score = chroma
        elif direction < 0:
            return float(start) - max(UPPER_UNSEEN * wi, es[0] - 0.5) if unseen is None else unseen
    y = float(start + direction * es[j]) - 0.5 * direction  # between the last lip row and the first skin row
    if 0 < j < len(es) - 1 and np.isfinite(score[j - 1]) and np.isfinite(score[j + 1]):
        y += direction * _vertex(score[j - 1], score[j], score[j + 1])
    return y


def _further_peaks(score: np.ndarray, least: float = 0.0) -> list[int]:
    """Indices of a split score's local peaks past its first one that reach :data:`EDGE_INTERIOR` of
    the score at the first (thinnest) split, and ``least``."""
    return [k for k in range(1, len(score) - 1) if score[k] >= score[k - 1] and score[k] >= score[k + 1]
            and score[k] >= max(EDGE_INTERIOR * score[0], least)]


def _vertex(a: float, b: float, c: float) -> float:
    """Offset (−0.5…0.5) of the extreme of a parabola through three equally spaced values."""
    den = a - 2.0 * b + c
    return min(max(0.5 * (a - c) / den, -0.5), 0.5) if abs(den) > 1e-12 else 0.0


TONGUE = True
"""Whether calibration looks past a tongue for the inside's lower end (see :func:`_gap`)."""
LIP_MAX = (0.15, 0.2)
"""Thickest upper and lower lip (× wi): a lip's red is about 0.1–0.15 of the inter-eye distance high."""
SHUT_GAP = 0.05
"""Gap (× wi) at or under which the calibration's lips are closed: a lip thicker than
:data:`LIP_MAX` then has its outer edge wrong, not the gap (see :func:`learn_mouth`)."""
CHEEK = (0.62, 0.8)
"""Distances (× wi) from the click along the line whose columns are cheek at calibration."""
CHEEK_FAR = 1.5
"""A column is cheek-like within this factor of the most cheek-like column on its side (see
:func:`corner_distance`)."""
CHEEK_LEVEL = 4.0
"""Mean squared distance (per feature, in the cheek's own spread) above which a column is never
cheek-like: two spreads per feature (a cheek column is about 1). Only a floor under the levels that
follow the mouth's own contrast (:data:`BODY_SHARE`) and the side's cheek (:data:`CHEEK_FAR`): pale
lips or a camera with little colour leave the whole mouth at 5-10, and a floor of 6 ended the
corner where the lips begin to taper (pale expr_d0's grin: 20 columns short on one side)."""
BODY_SHARE = 0.3
"""A corner is where the columns are less unlike the cheek than this share of the lips' body."""
CORNER_HOLD = 0.15
"""Share of the corner level (above and below it) over which a corner holds its last frame's place
(:func:`corner_distance`)."""
CORNER_BIAS = 1.0
"""Columns a corner from :func:`corner_distance` is moved outwards: the columns about the line turn
to cheek where the lips have tapered to a point, one column (at any scale: measured on synthetic
faces whose corners are known, 80 and 40 px between the eyes) inside where the corner is. A
constant, so it moves no correlation."""


def mouth_body(wi: float) -> tuple[int, int]:
    """Columns (from the centre) along the line that are the body of the lips on any mouth."""
    return max(int(round(0.06 * wi)), 1), max(int(round(0.22 * wi)), 3)


def cheek_run(wi: float) -> int:
    """Columns in a row that must look like the cheek past a corner (0.08 wi)."""
    return max(int(round(0.08 * wi)), 3)


def cheek_model(cols: np.ndarray, wi: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Median and spread (9,) of the line columns :data:`CHEEK` wi out (None when the line is shorter)."""
    j = np.arange(len(cols))
    cheek = cols[(j >= CHEEK[0] * wi) & (j <= CHEEK[1] * wi)]
    if len(cheek) < 3:
        return None
    mu = np.median(cheek, axis=0)
    return mu, np.maximum(1.4826 * np.median(np.abs(cheek - mu), axis=0), 1.0)


CHEEK_SKIN = 1.0
"""Mean squared distance (in twice the skin's spread) above which a calibrated cheek is not skin."""
CHEEK_SKIN_PART, CHEEK_SKIN_RATIO = 0.5, 8.0
"""A calibrated cheek at least this share of :data:`CHEEK_SKIN` from the skin, and this many times
farther from it than the other side's, is not skin either. The absolute level alone depends on how
much colour the camera shows: a child's shadowed mouth fold, lip-dark beside the left corner, fitted
the skin 1.16 on the shared clip but 0.82 with the colours halved (the other side: 0.02), and the
lips on that side then looked like cheek (the corner ran off, 3.6 % of the frames lost)."""


def cheek_skin_distance(cheek: tuple[np.ndarray, np.ndarray] | None, skin_f: np.ndarray) -> float:
    """How unlike the skin round the mouth (``skin_f``, per-pixel features (n, 3)) a cheek model's
    three bands are: mean squared distance of their medians from the skin's, in twice the skin's
    spread (band means vary less than pixels; shading is allowed for). ``inf`` without a cheek."""
    if cheek is None or len(skin_f) < 8:
        return math.inf
    med = np.median(skin_f, axis=0)
    spread = np.maximum(1.4826 * np.median(np.abs(skin_f - med), axis=0), 1.0)
    z = (np.asarray(cheek[0], dtype=np.float64).reshape(3, 3) - med) / (2.0 * spread)
    return float((z * z).mean())


def borrows_cheek(fit: float, other: float) -> bool:
    """Whether a side of the mouth takes the other side's cheek at calibration, from how unlike the
    skin round the mouth each side's cheek columns are (:func:`cheek_skin_distance`): the other's
    is skin, and this one is not (hair, a collar, the background beside a small or turned face) or
    fits the skin far worse (a shadowed fold beside a child's mouth; see :data:`CHEEK_SKIN_RATIO`)."""
    return other <= CHEEK_SKIN and fit > min(CHEEK_SKIN, max(CHEEK_SKIN_PART * CHEEK_SKIN, CHEEK_SKIN_RATIO * other))


def unlike_cheek(cols: np.ndarray, cheek: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Per column: mean squared distance of its features from the cheek's, in the cheek's spread."""
    z = (cols - cheek[0]) / cheek[1]
    z *= z
    return np.add.reduce(z, axis=1) / np.float32(z.shape[1])  # the mean, without mean's Python overhead


def _cheek_from(v: list[float], level: float, a: int, b: int, need: int) -> int | None:
    """The first column ``k`` in ``[a, b]`` at or above ``level`` with ``need`` columns under it
    after it (None when there is none)."""
    # a column whose ``need`` columns after it are not all inside the list never qualifies; a column
    # that does not qualify hands on to the first one at or above the level after it
    last = min(b, len(v) - 1 - max(need, 0))
    i = a
    while i <= last:
        if v[i] >= level:
            j, stop = i + 1, i + need
            while j <= stop and v[j] < level:
                j += 1
            if j > stop:
                return i
            i = j
        else:
            i += 1
    return None


def _crossing(v: list[float], k: int, level: float) -> float:
    """Column ``k`` moved sub-pixel to where ``v`` falls through ``level`` after it."""
    d0, d1 = v[k], v[k + 1]
    return k + (d0 - level) / (d0 - d1) if d0 >= level > d1 else float(k)


def corner_distance(d: np.ndarray, lo: float, hi: float, run: int, body: tuple[int, int],
                    previous: float | None = None) -> tuple[float, float]:
    """:func:`corner_search` without whether the cheek was seen: ``(distance, gain)``."""
    x, g, _ = corner_search(d, lo, hi, run, body, previous)
    return x, g


def corner_search(d: np.ndarray, lo: float, hi: float, run: int, body: tuple[int, int],
                  previous: float | None = None) -> tuple[float, float, bool]:
    """Where the mouth ends along one side of the line, from the columns' unlikeness to the cheek
    ``d`` (column 0 at the centre): the first column in ``[lo, hi]`` after which ``run`` columns in a
    row are less unlike the cheek than :data:`BODY_SHARE` of the mouth's body (the median over columns
    ``body``; at least :data:`CHEEK_LEVEL`) — a short crease or blotch beyond the corner does not
    move it, nor hair, a collar or the background further out — placed sub-pixel where ``d``
    crosses that level (when the columns from ``lo`` on are cheek already, the lips ended before
    it: after the last column before it that is not); and how clearly the mouth's columns up to it
    differed from the cheek (``Σ min(d, 5·level) − level``); and whether the cheek was seen past
    it. Without such a run, where that sum is largest (the cheek not seen: the line ran off the
    mouth into hair, a beard or a collar as unlike the cheek as lips, and the corner is only where
    the sum stopped).

    ``previous`` (the last frame's distance on this side, columns): where the columns past the lips
    are about as unlike the cheek as that level (a crease running on from the corner), the corner
    with the level :data:`CORNER_HOLD` higher and the one with it that much lower can lie apart;
    the corner then stays as near the last one as that range allows instead of jumping from one
    end to the other with the noise."""
    v = d.tolist()  # short (one side of a mouth): plain Python is quicker than numpy here
    n = len(v)
    body_d = sorted(v[max(body[0], 0) : min(max(body[1], body[0] + 1), n)])
    level = max(CHEEK_LEVEL, BODY_SHARE * body_d[len(body_d) // 2]) if body_d else CHEEK_LEVEL
    a, b = max(int(lo), 1), min(int(hi), n - 2)
    if b > a:
        # the cheek as this frame shows it: a turned head shades it, the light changes it — the best
        # match out here may stay above a level set by the calibration alone
        level = max(level, CHEEK_FAR * min(v[a : b + 1]))
    if b <= a:
        return float(min(max(0.5 * (lo + hi), 0.0), n - 1)), 0.0, False
    cap = 5.0 * level
    need = min(run, n - 1 - b + run)
    k = _cheek_from(v, level, a, b, need)
    if k is None and all(q < level for q in v[a : a + need + 1]):
        # the line started off the mouth's middle (it moved sideways, or pursed): the cheek was seen
        k = next((j for j in range(a - 1, 0, -1) if v[j] >= level), None)
    if k is None:
        gain, g = [], 0.0
        for q in v[: b + 1]:
            g += (q if q < cap else cap) - level
            gain.append(g)
        k = max(range(a, b + 1), key=gain.__getitem__)
        return _crossing(v, k, level), float(gain[k]), False
    x = _crossing(v, k, level)
    if previous is not None and CORNER_HOLD > 0:
        k_in = _cheek_from(v, (1.0 + CORNER_HOLD) * level, a, b, need)
        k_out = _cheek_from(v, (1.0 - CORNER_HOLD) * level, a, b, need)
        if k_in is not None and k_out is not None:
            x_in = _crossing(v, k_in, (1.0 + CORNER_HOLD) * level)
            x_out = _crossing(v, k_out, (1.0 - CORNER_HOLD) * level)
            lo_x, hi_x = min(x_in, x_out, x), max(x_in, x_out, x)
            x = min(max(float(previous), lo_x), hi_x)
            k = min(int(x), b)
    g = 0.0
    for q in v[: k + 1]:
        g += (q if q < cap else cap) - level
    return x, float(g), True


LIP_END = 0.03
"""Farthest (× wi) a corner may lie past the last column along the line that shows the lips
(:func:`lip_columns`), where the lips are redder than the skin: hair round the mouth (a beard, a
moustache) and skin beside the lips redder than the cheek further out are as unlike that cheek as
the lips are, and the corner search ran on through them — to a beard's edge (calibrated mouths
1.2–1.6 times too wide on bearded copies of the shared clips), or along expr_d6's reddened right
cheek up to half the eye distance. On the shared clips the lips end within 0.03 wi of the corner
the cheek gives wherever neither happens."""
LIP_LEAD = 4.0
"""Least lead (r − g chroma units) of the lips' red over the skin's for :data:`LIP_END` to apply: twice
the least lead that makes rows lip-red at all (:data:`GAP_RED`), so the lips' columns stand clear of
the need. Paler lips are read column by column at the need's edge, and a grin's thin pale lips then
ended early (the washed-out copy of expr_d0, lead 2.9: its opening 0.96 -> 0.80)."""
LIP_RUN = 0.05
"""Columns (× wi) along the line whose mean redness counts for each column in :func:`lip_columns`
(a beard's hairs are as red as lips here and there, one column at a time); see :func:`lip_run`."""


def lip_run(wi: float) -> int:
    """:data:`LIP_RUN` in columns at this scale, odd (centred on the column): 3 at 40 px between the
    eyes, 5 at 80."""
    return 2 * int(round(0.5 * LIP_RUN * wi)) + 1


def lip_columns(cols: np.ndarray, need: float, skin_f: np.ndarray, run: int = 1) -> list[bool]:
    """Per column along the line (:func:`line_columns`' features, (n, 9), from the middle out): whether
    it shows the mouth — one of its three bands at least ``need`` red (r − g chroma,
    :func:`lip_red_need` over the skin's) on the mean of ``run`` columns centred on it, or teeth in
    one of them (:data:`TEETH`, against the skin's features ``skin_f`` (3,))."""
    red = cols[:, 1::3].max(axis=1)  # the reddest of the band above, the line's rows and the band below
    if run > 1 and len(red):  # the running mean, ends repeated (as scipy's uniform_filter1d in "nearest" mode)
        red = cv2.blur(red.reshape(1, -1), (run, 1), borderType=cv2.BORDER_REPLICATE).reshape(-1)
    lum, sat = TEETH[0] * float(skin_f[0]), TEETH[1] * math.hypot(float(skin_f[1]), float(skin_f[2]))
    sq = cols * cols
    teeth = ((cols[:, 0::3] >= lum) & (sq[:, 1::3] + sq[:, 2::3] < sat * sat)).any(axis=1)
    return ((red >= need) | teeth).tolist()


LIP_ROWS = (0.12, 0.15)
"""Rows (× wi) above and below the line through which :func:`lip_rows` looks for the lips, about the
thickest upper and lower lip at a corner's columns (calibrated lips: 0.04-0.14 wi above, 0.11-0.2 wi
below, thinning towards the corners). Where the line runs along a moustache's lower edge, or the lips
have thinned towards a corner, the lips lie off :func:`lip_columns`' bands and the lips' end went
unseen: the corners ran on through the hair to the beard's edge (the bearded copy of expr_d18: corners
9 % of the eye distance out)."""


def lip_rows(red: np.ndarray, need: float) -> np.ndarray:
    """Per column (rows of ``red``, (n, m): the r − g chroma of each of the ``m`` rows across the line,
    :data:`LIP_ROWS`), whether two rows next to each other are lip-red (at least ``need``): one row is
    as often a hair's or a crease's colour."""
    if red.shape[1] < 2:
        return red.max(axis=1, initial=-np.inf) >= need
    return np.minimum(red[:, 1:], red[:, :-1]).max(axis=1) >= need


LIP_BODY = 0.5
"""Least share of the lips' body columns (:func:`mouth_body`) that must show the lips for their end to
bound a corner: a hand or a scarf over the mouth shows none, and a speck of red on it is no lip."""


def _lips_in_body(lips: list[bool], k: int, body: tuple[int, int]) -> int | None:
    """The last column of the lips' body ``body`` up to column ``k`` when :data:`LIP_BODY` of those
    columns show the lips (``lips``, :func:`lip_columns`), else None."""
    a, b = min(body[0], k), min(body[1], k)
    return b if b > a and sum(lips[a : b + 1]) >= LIP_BODY * (b + 1 - a) else None


def lip_end(lips: list[bool], half: float, reach: float, body: tuple[int, int]) -> float:
    """``half`` (a corner's distance from the line's middle column, in columns) brought to at most
    ``reach`` columns past the last column up to it that shows the lips (``lips`` per column from the
    middle out, :func:`lip_columns`); unchanged unless :data:`LIP_BODY` of the columns ``body`` do."""
    k = min(int(half), len(lips) - 1)
    if _lips_in_body(lips, k, body) is None:
        return half
    last = next((j for j in range(k, -1, -1) if lips[j]), None)
    return half if last is None else min(half, last + reach)


def lip_gap(lips: list[bool], half: float, reach: float, body: tuple[int, int], run: int) -> float | None:
    """Where the lips end along one side of a mouth whose corners saw no cheek (:func:`corner_search`
    ran to its end through hair, a beard or a collar): ``reach`` columns past the last lip column
    before the first ``run`` columns in a row past the body ``body`` that do not show the lips
    (``lips`` per column from the middle out, :func:`lip_columns`). None when under
    :data:`LIP_BODY` of the body's columns show the lips, or no such gap comes before ``half``. The
    first gap, not the last lip column (:func:`lip_end`): beyond a beard, bright skin or a wall can
    pass for teeth."""
    k = min(int(half), len(lips) - 1)
    b = _lips_in_body(lips, k, body)
    if b is None:
        return None
    for j in range(b + 1, k - run + 2):
        if not any(lips[j : j + run]):
            return min(half, j - 1 + reach)
    return None


def _row_classes(f: np.ndarray, y_top: float, top: int, bottom: int, y_bottom: float, wi: float,
                 skin: np.ndarray) -> np.ndarray:
    """Median and spread (5, 2, 3) of the profile's rows in each part — skin above (:data:`SKIN_ROWS`
    above the outer edge), upper lip, lower lip, skin below — and of ``skin`` (features of the skin
    round the mouth, pixel by pixel: its spread is halved for a profile's band means). The spread is
    at least a just visible difference, and 12 % of how far the lip's median is from its skin's
    (strong lipstick varies more in absolute terms than pale lips)."""
    n = len(f)
    skin_n = max(SKIN_ROWS * wi, 3.0)

    def rows(a: float, b: float) -> np.ndarray:
        i0, i1 = int(math.ceil(a)), int(math.floor(b))
        i0, i1 = min(max(i0, 0), n - 1), min(max(i1, 0), n - 1)
        return f[i0 : max(i1, i0) + 1]

    parts = [rows(y_top - skin_n, y_top - 0.5), rows(y_top + 0.5, top - 0.5 if bottom > top else top),
             rows(bottom + 0.5 if bottom > top else bottom + 1, y_bottom - 0.5), rows(y_bottom + 0.5, y_bottom + skin_n)]
    med = [np.median(p, axis=0) for p in parts]
    out = np.empty((5, 2, 3), np.float32)
    for i, p in enumerate(parts):
        lip_skin = abs(med[1] - med[0]) if i < 2 else abs(med[2] - med[3])
        out[i, 0] = med[i]
        out[i, 1] = np.maximum(np.maximum(1.4826 * np.median(np.abs(p - med[i]), axis=0), 1.0), 0.12 * lip_skin)
    ms = np.median(skin, axis=0)
    out[4, 0] = ms
    out[4, 1] = np.maximum(0.5 * 1.4826 * np.median(np.abs(skin - ms), axis=0), 1.0)
    return out


def learn_mouth(crop_bgr: np.ndarray, mouth_click_crop: tuple[float, float], work_ipd: float,
                skin_samples: np.ndarray | None = None, _trace: dict | None = None) -> MouthModel:
    """Learn a :class:`MouthModel` from the calibration frame's mouth crop (see the module docstring).

    ``crop_bgr`` is the :data:`MOUTH_RECT` crop around the click, ``mouth_click_crop`` the click in
    its pixels (it may sit a few px off, on the gap between the lips or inside an open mouth),
    ``skin_samples`` optional ``(n, 3)`` BGR skin pixels from elsewhere on the face (cheeks,
    forehead). Never refuses a face; ``model.cue`` says which cue the finder will lean on.
    """
    crop = np.ascontiguousarray(crop_bgr)
    if crop.ndim != 3 or crop.shape[2] != 3 or crop.dtype != np.uint8:
        raise ValueError("mouth crop must be a uint8 (H, W, 3) BGR image")
    wi = float(work_ipd)
    H, W = crop.shape[:2]
    cx, cy = float(mouth_click_crop[0]), float(mouth_click_crop[1])
    sub = crop[::4, ::4].reshape(-1, 3)
    crop_median = tuple(float(v) for v in np.partition(sub, len(sub) // 2, axis=0)[len(sub) // 2])

    skin = _skin(crop, cx, cy, wi, skin_samples)
    fs = features(skin, 1.0)
    skin_level = float(np.median(fs[:, 0]) * 255.0)
    skin_sat = float(np.median(np.hypot(fs[:, 1], fs[:, 2])))
    chroma = chroma_gain(skin_sat)
    idx = lut_index(crop)
    inside0 = _inside(0.5 * skin_level, skin_level, skin_sat).view(np.uint8).take(idx)
    teeth0 = _inside(0.0, skin_level, skin_sat).view(np.uint8).take(idx)

    band = max(BAND * wi, 1.5)
    skin_f = profile_features(skin.astype(np.float32), skin_level, chroma)  # per pixel (n, 3)
    skin_red = float(np.median(skin_f[:, 1]))

    def column(x: float, y: float):
        """The gap and the outer lip edges on the profile through column ``x`` near row ``y``, and
        that profile's features and luminance."""
        b0, b1 = band_columns(x, band, W)
        rows_bgr = cv2.GaussianBlur(crop[:, b0:b1].astype(np.float32).mean(axis=1).reshape(-1, 1, 3), (1, 0), 0.8).reshape(-1, 3)
        lum_rows = luminance(rows_bgr)
        f_rows = profile_features(rows_bgr, skin_level, chroma)
        teeth_rows, red_rows = teeth0[:, b0:b1].mean(axis=1), f_rows[:, 1] - skin_red
        top, bottom, y_min = _gap(lum_rows, teeth_rows, y, wi, red_rows)
        if TEETH_BLUR > 0 and float(teeth_rows[top : bottom + 1].max(initial=0.0)) > 0.5:
            top, bottom = _past_teeth(red_rows, top, -1, wi), _past_teeth(red_rows, bottom, +1, wi)

        def lower_edge(gap_end: int) -> float:
            # the lower lip by its colour: the shadow under it is darker skin, not lip (not the upper
            # lip: on pale lips the skin just above is as red as they are)
            return _colour_edge(rows_bgr, gap_end, +1, _outer_edge(f_rows, gap_end, +1, 0.05, 0.3, wi), skin, (0.05, 0.3), wi)

        e_up, e_dn = _outer_edge(f_rows, top, -1, 0.04, 0.22, wi, math.nan), lower_edge(bottom)
        if TONGUE and e_dn - bottom > LIP_MAX[1] * wi:
            # a lower lip thicker than any lip: the tongue of an open mouth, between the gap and the
            # dark inside in front of the lower teeth, taken for lip (a yawn on the calibration frame:
            # the tracker then looked for the upper lip and the top of the inside all clip long)
            _, deeper, _ = _gap(lum_rows, teeth_rows, y, wi, red_rows, past_tongue=True)
            if deeper > bottom and (e2 := lower_edge(deeper)) - deeper < e_dn - bottom:
                bottom, e_dn = deeper, e2
        return (top, bottom, y_min, e_up, e_dn, lum_rows, f_rows)

    # the gap through the click
    top, bottom, y_min, y_top, y_bottom, lum_rows, f_click = column(cx, cy)

    # the line through the middle of the gap, traced out to both sides; the corners on it
    y_line = 0.5 * (top + bottom)
    a1, a2 = line_geometry(wi)
    lum = cv2.GaussianBlur(luminance(crop), (0, 0), max(0.015 * wi, 1.0))
    n_side = int(min(0.95 * wi, W - 2))
    x0 = int(round(cx))
    traced = {}
    for name, step in (("left", -1), ("right", +1)):
        n = min(n_side, x0 if step < 0 else W - 1 - x0)
        ys = trace_line(lum, x0, y_line, step, max(n, 1))
        cols = line_columns(crop, x0, ys, step, a1, a2, skin_level, chroma=chroma)
        traced[name] = (ys, cols, step, cheek_model(cols, wi))
    fit = {name: cheek_skin_distance(t[3], skin_f) for name, t in traced.items()}
    # the lips' lead in red over the skin on the click's column: where they are clearly redder, a
    # corner lies no further than LIP_END past the last column along the line that shows them
    lips_red = [float(np.median(rows)) for a, b in ((y_top, top), (bottom, y_bottom)) if math.isfinite(a)
                and len(rows := f_click[max(int(math.ceil(a)), 0) : int(b) + 1, 1])]
    lead = min(lips_red) - skin_red if lips_red else 0.0
    need = skin_red + lip_red_need(lead) if lead >= LIP_LEAD else None
    skin_mid = np.median(skin_f, axis=0)
    if _trace is not None:
        _trace["cheek_skin"] = dict(fit)
    for name, other in (("left", "right"), ("right", "left")):
        if borrows_cheek(fit[name], fit[other]):
            ys, cols, step, _ = traced[name]
            traced[name] = (ys, cols, step, traced[other][3])
    sides = {}
    for name, (ys, cols, step, cheek) in traced.items():
        if cheek is None:
            half = 0.4 * wi
        else:
            half, _, cheek_seen = corner_search(unlike_cheek(cols, cheek), 0.2 * wi, 0.75 * wi, cheek_run(wi), mouth_body(wi))
            if need is not None and cheek_seen and LIP_END > 0:
                half = lip_end(lip_columns(cols, need, skin_mid, lip_run(wi)), half, LIP_END * wi, mouth_body(wi))
            half += CORNER_BIAS
        sides[name] = (ys, cols, half, step, cheek)
    # a mouth is seen when the gap is clearly darker than the profile round it
    ra, rb = max(int(round(cy - 0.35 * wi)), 0), min(int(round(cy + 0.45 * wi)) + 1, H)
    seen = float(np.median(lum_rows[ra:rb])) - float(lum_rows[y_min]) > 0.06 * skin_level

    def corner_point(name):
        ys, _, half, step, _ = sides[name]
        k = min(int(round(half)), len(ys) - 1)
        return (x0 + step * half, float(ys[k]))

    left, right = corner_point("left"), corner_point("right")
    centre = (0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]))
    width = math.hypot(right[0] - left[0], right[1] - left[1])

    # the gap and the lips' thickness through the centre, and a little to either side (a Cupid's
    # bow, a highlight or a crease on one column does not decide it)
    ys_l, ys_r = sides["left"][0], sides["right"][0]

    def line_row(x: float) -> float:
        k = int(round(x - x0))
        ys, k = (ys_r, k) if k >= 0 else (ys_l, -k)
        return float(ys[min(k, len(ys) - 1)])

    if seen:
        measured = [column(x, line_row(x)) for x in (centre[0], centre[0] - 0.12 * wi, centre[0] + 0.12 * wi)]
        top, bottom, y_min = measured[0][:3]
    else:
        measured = [(top, bottom, y_min, y_top, y_bottom)]
    thick_up = upper_thickness([c[0] - c[3] for c in measured], wi)
    thick_down = float(np.median([c[4] - c[1] for c in measured]))
    thick_up, thick_down = max(thick_up, 1.0), max(thick_down, 1.0)
    y_top, y_bottom = top - thick_up, bottom + thick_down
    # a lip thicker than any lip is: in an open mouth the gap reached less far than the mouth is open
    # (a tongue or the lower teeth next to the lip were taken for lip) — the outer edge stands, the
    # inner one moves; between closed lips the line is sure and the outer edge ran on into skin (the
    # shadow under a full lower lip can be as brown as the lip) — the outer edge moves
    shut = bottom - top <= SHUT_GAP * wi
    if thick_up > LIP_MAX[0] * wi:
        thick_up = LIP_MAX[0] * wi
        if shut:
            y_top = top - thick_up
        else:
            top = min(int(round(y_top + thick_up)), int(y_min))
    if thick_down > LIP_MAX[1] * wi:
        thick_down = LIP_MAX[1] * wi
        if shut:
            y_bottom = bottom + thick_down
        else:
            bottom = max(int(round(y_bottom - thick_down)), int(y_min))
    thick_up, thick_down = top - y_top, y_bottom - bottom

    # what the rows through the centre look like: skin, upper lip, (gap), lower lip, skin
    b0, b1 = band_columns(centre[0], band, W)
    f_centre = profile_features(crop[:, b0:b1].astype(np.float32).mean(axis=1), skin_level, chroma)
    classes = _row_classes(f_centre, y_top, top, bottom, y_bottom, wi, skin_f)
    typical = np.stack([np.zeros(9), np.full(9, 10.0)])  # no cheek seen: nothing is much unlike it
    cheeks = {name: np.stack(sides[name][4]) if sides[name][4] is not None else typical for name in ("left", "right")}

    outline = lens_outline(left, right, y_top, y_bottom, centre[0])
    if not seen:  # nothing near the click looks like a mouth: a typical mouth there
        outline = lens_outline((cx - 0.4 * wi, cy), (cx + 0.4 * wi, cy), cy - 0.09 * wi, cy + 0.11 * wi, cx)

    # lip colour: each lip's pixels (between its inner and outer edge, the middle 60 % of the mouth)
    # against the skin just beyond its outer edge
    xa, xb = int(round(centre[0] - 0.3 * width)), int(round(centre[0] + 0.3 * width)) + 1
    xa = min(max(xa, 0), W - 1)
    xb = min(max(xb, xa + 1), W)

    def rows_px(y0, y1):
        y0, y1 = int(round(min(y0, y1))), int(round(max(y0, y1)))
        y0 = min(max(y0, 0), H - 1)  # a lip or skin past the crop's edge: its last row stands in
        y1 = min(max(y1, y0 + 1), H)
        blk = crop[y0:y1, xa:xb]
        keep = inside0[y0:y1, xa:xb] == 0
        return blk[keep] if keep.sum() >= 12 else blk.reshape(-1, 3)
    skin_up = rows_px(y_top - 0.1 * wi, y_top - 0.02 * wi)
    skin_dn = rows_px(y_bottom + 0.02 * wi, y_bottom + 0.1 * wi)
    lip_up = rows_px(y_top + 0.2 * thick_up, top - 0.15 * thick_up)
    lip_dn = rows_px(bottom + 0.15 * thick_down, y_bottom - 0.2 * thick_down)
    axis_up, sep_up = best_axis(lip_up, np.concatenate([skin_up, skin[:: max(len(skin) // max(len(skin_up), 1), 1)]]))
    axis_dn, sep_dn = best_axis(lip_dn, np.concatenate([skin_dn, skin[:: max(len(skin) // max(len(skin_dn), 1), 1)]]))
    sep = float(min(sep_up, sep_dn))
    cue = "colour" if seen and sep >= COLOUR_SEPARATION else "contrast"
    lip_lums = [float(np.median(luminance(v))) for v in (lip_up, lip_dn) if len(v) >= 12]
    dark = 0.6 * min([skin_level] + lip_lums)  # the inside is darker than either lip

    if _trace is not None:
        _trace.update(gap=(top, bottom, y_min), edges=(y_top, y_bottom), left=left, right=right, sides=sides)
    round_px = round_mouth(crop.shape, outline, centre, wi)
    dark_level = OPEN_DARK * lips_grey(classes, skin_level)
    dark_round = float(np.count_nonzero(luminance(crop[round_px]) < dark_level))
    dark_round /= max(int(np.count_nonzero(round_px)), 1)
    y0, y1, x0, x1 = chin_band(crop.shape, outline, wi)
    chin = luminance(crop[y0:y1, x0:x1].reshape(-1, 3))
    dark_chin = float(np.count_nonzero(chin < dark_level)) / len(chin) if len(chin) else None
    return MouthModel(
        work_ipd=wi, centre=(float(centre[0]), float(centre[1])), width=float(width),
        lip_upper=float(centre[1] - y_top), lip_lower=float(y_bottom - centre[1]), area=polygon_area(outline),
        outline=outline - np.array(centre), gap=float(bottom - top), line=float(y_line - centre[1]),
        thick_up=float(thick_up), thick_down=float(thick_down),
        half_left=float(centre[0] - left[0]), half_right=float(right[0] - centre[0]),
        classes=classes,
        cheek_left=cheeks["left"].astype(np.float32), cheek_right=cheeks["right"].astype(np.float32),
        axis_up=axis_up, axis_down=axis_dn, skin_level=skin_level, skin_sat=skin_sat, dark=dark, separation=sep,
        cue=cue, crop_median=crop_median, skin_bins=skin_colour_bins(idx, round_px), dark_round=dark_round,
        dark_chin=dark_chin,
    )
