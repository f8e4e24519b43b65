"""What the mouth finder learns about one performer from the calibration frame.

Everything lives in the upright, scale-normalised mouth crop of :class:`~tracker.calibration.FaceFrame`
(x along the eye line, y down, ``work_ipd`` px between the eyes), cut with :data:`MOUTH_RECT`
around the mouth click.

The model does not assume what colour lips are. It learns:

* the **skin** around the mouth (a robust Gaussian of the pixels on an ellipse around the
  click, plus any skin samples from elsewhere on the face) and bakes the Mahalanobis distance
  of every colour from it into a 64³ table — the *not-skin* table. Lips, teeth, tongue and the
  dark inside of the mouth are all far from the skin, so the mouth shows up as one region of
  high distance whatever it is doing, even when the lips alone are barely redder than the skin;
* the **mouth outline** on the calibration frame: rays from the click's not-skin region to where
  the not-skin distance first falls to the skin's level (so the gap between closed lips or
  an open mouth's inside count as mouth and the nose or chin shadow above and below do not);
* the **lips** themselves: the outline's outer band minus the dark inside and the bright
  teeth; from them a lip-vs-skin table (a Gaussian classifier, for the score and the overlay)
  and a linear BGR *lip axis* (Fisher's discriminant: 0 on skin, 1 on lip, insensitive to the
  skin's shading) on which the outer lip edges are placed to a fraction of a pixel;
* the **cue** to rely on: ``"colour"`` when the lips stand out from the skin along the lip axis
  (separation d′ ≥ :data:`COLOUR_SEPARATION`), else ``"contrast"`` — the mouth region's
  difference from skin as a whole (its dark line or inside, teeth, shading), with the lip
  edges placed on the not-skin distance instead.

:func:`learn_mouth` never refuses a frontal, lit face: if nothing near the click differs from
the skin it still returns a model (cue ``"contrast"``, low separation) sized from the
inter-eye distance, and the finder's score says how sure each frame is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from tracker.colour_model import (
    TILE_SHAPE,
    ColourClassifier,
    Gaussians,
    _grid_features,
    _grid_quad_forms,
    _lowest,
    features,
    table_to_tile,
    tile_to_table,
)

FORMAT = 1
MOUTH_RECT = (-0.95, -0.6, 1.9, 1.6)
"""Crop rectangle ``(x0, y0, w, h)`` in units of ``work_ipd``, relative to the predicted mouth centre
(face px): wide enough for a grin (1.5× the width), a yawn (the centre drops ~0.3 wi, the lower lip
another 0.6 wi) and the head-motion prediction's error."""
SKIN_YW = 1.0
"""Luminance weight of the skin features (the fitted covariance scales it further)."""
DIST_SCALE = 16.0
"""Not-skin table value = Mahalanobis distance × this (saturating at 255, i.e. distance ~16)."""
COLOUR_SEPARATION = 2.0
"""Lip-vs-skin d′ along the lip axis at and above which the lip colour is the cue."""
N_RAYS = 48
TABLE_NAMES = ("not_skin", "lip")
"""Names of the colour-table images of :meth:`MouthModel.images` (one 512×512 grey tile each)."""


# --------------------------------------------------------------------------------------------- helpers


def _robust_fit(x: np.ndarray, k: int = 1, spread: float = 2.5, min_std=None) -> Gaussians:
    """Gaussians fitted to the rows of ``x`` within ``spread`` robust sigmas of the median."""
    med = np.median(x, axis=0)
    mad = np.median(np.abs(x - med), axis=0) * 1.4826 + 1e-6
    keep = np.all(np.abs(x - med) <= spread * mad, axis=1)
    y = x[keep] if keep.sum() >= 12 else x
    ms = np.asarray(min_std if min_std is not None else [0.02, 0.006, 0.006], dtype=np.float64)
    return Gaussians(y, k, ms)


def _distance_table(model: Gaussians, y_weight: float) -> np.ndarray:
    """Smallest Mahalanobis distance of every 64³ bin centre from ``model``, × :data:`DIST_SCALE`, uint8."""
    d2 = _lowest(_grid_quad_forms(model, y_weight))
    return np.minimum(np.sqrt(np.maximum(d2, 0.0)) * np.float32(DIST_SCALE) + np.float32(0.5), 255.0).astype(np.uint8)


def _inside_table(dark: float, skin_level: float, skin_sat: float) -> np.ndarray:
    """1 for every 64³ bin that looks like the inside of a mouth: darker than ``dark``, or grey
    (teeth: chroma under 55 % of the skin's and not dark, or under 80 % and brighter than the
    skin); else 0 (uint8)."""
    f = _grid_features()
    lum = f[:, 0] * np.float32(255.0)
    sat = np.hypot(f[:, 1], f[:, 2])
    grey = (sat < np.float32(0.55 * skin_sat)) & (lum > np.float32(0.45 * skin_level))
    white = (sat < np.float32(0.8 * skin_sat)) & (lum > np.float32(1.1 * skin_level))
    return ((lum < np.float32(dark)) | grey | white).astype(np.uint8)


def _inside_colours(skin_bgr: np.ndarray, skin_level: float) -> np.ndarray:
    """Colours the lip classifier must call "not lip" though the calibration frame may not show them:
    teeth (greys with a little of the skin's tint, 0.5–1.4 × the skin's luminance) and the black
    inside of an open mouth (the skin's colour at 6–12 % of its brightness; darker lips than that
    are rare, lipstick included)."""
    s = np.asarray(skin_bgr, dtype=np.float64).reshape(3)
    tint = s / max(float(s @ [0.114, 0.587, 0.299]), 1.0)
    out = []
    for k in np.linspace(0.5, 1.4, 10):
        for mix in (0.0, 0.2, 0.4):
            out.append(k * skin_level * ((1 - mix) * np.ones(3) + mix * tint))
    for k in (0.06, 0.12):
        out.append(k * s)
    return np.clip(np.array(out), 0, 255).astype(np.uint8)


def _gauss_dict(m: Gaussians) -> dict:
    return {"means": [mu.tolist() for mu in m.means], "icovs": [ic.tolist() for ic in m.icovs], "logdets": list(m.logdets)}


def _gauss_from(d: dict) -> Gaussians:
    m = Gaussians.__new__(Gaussians)
    m.means = [np.asarray(v, dtype=np.float64) for v in d["means"]]
    m.icovs = [np.asarray(v, dtype=np.float64) for v in d["icovs"]]
    m.logdets = [float(v) for v in d["logdets"]]
    if not m.means or any(mu.shape != (3,) for mu in m.means) or any(ic.shape != (3, 3) for ic in m.icovs):
        raise ValueError("malformed colour model")
    return m


# --------------------------------------------------------------------------------------------- the model


@dataclass
class MouthModel:
    """One performer's mouth (see the module docstring). Lengths are face px (``work_ipd`` between the eyes).

    ``centre`` is the calibrated mouth centre (midpoint of the corners) in the calibration crop's
    pixels; the tracker turns it into a face-frame offset. ``width``, ``lip_upper``, ``lip_lower``
    and ``area`` are the calibration frame's measurements; ``outline`` the mouth outline there,
    relative to the centre. ``axis_up`` / ``axis_down`` (4,) map BGR to the lip value ``w·bgr + c``
    of the upper / lower lip (0 on the skin above / below it, 1 on the lip): upper and lower lips
    differ in colour (one faces the light, one the floor) and so does the skin next to each.
    ``lip`` is the lip-vs-everything-else colour classifier (both lips; teeth, the dark inside,
    skin, nostrils, hair and background are "else"). ``skin`` is the skin's Gaussian (features of
    :func:`~tracker.colour_model.features`), ``skin_level`` / ``skin_sat`` its median luminance
    and chroma; ``dark`` the luminance under which a pixel is the mouth's dark inside;
    ``threshold`` the not-skin distance (table units) that separates the mouth region from skin;
    ``separation`` the smaller lip-vs-skin d′ of the two axes; ``cue`` ``"colour"`` or ``"contrast"``.
    """

    work_ipd: float
    centre: tuple[float, float]
    width: float
    lip_upper: float
    lip_lower: float
    area: float
    outline: np.ndarray
    skin: Gaussians
    lip: ColourClassifier
    axis_up: np.ndarray
    axis_down: np.ndarray
    skin_level: float
    skin_sat: float
    dark: float
    threshold: float
    separation: float
    cue: str
    not_skin_table: np.ndarray = field(repr=False, default=None)
    inside_table: np.ndarray = field(repr=False, default=None)

    def __post_init__(self) -> None:
        if self.not_skin_table is None:
            self.not_skin_table = _distance_table(self.skin, SKIN_YW)
        if self.inside_table is None:
            self.inside_table = _inside_table(self.dark, self.skin_level, self.skin_sat)

    @property
    def lip_table(self) -> np.ndarray:
        """The lip classifier's 64³ table (lip score 0..255)."""
        return self.lip.table

    # ------------------------------------------------------------------ persistence
    def to_dict(self) -> dict:
        """JSON-able description; the two baked tables are in :meth:`images`."""
        return {
            "format": FORMAT,
            "kind": "inkface-mouth",
            "work_ipd": self.work_ipd,
            "centre": [float(v) for v in self.centre],
            "width": self.width,
            "lip_upper": self.lip_upper,
            "lip_lower": self.lip_lower,
            "area": self.area,
            "outline": np.round(np.asarray(self.outline, dtype=np.float64), 3).tolist(),
            "skin": _gauss_dict(self.skin),
            "lip": self.lip.to_dict(),
            "axis_up": [float(v) for v in self.axis_up],
            "axis_down": [float(v) for v in self.axis_down],
            "skin_level": self.skin_level,
            "skin_sat": self.skin_sat,
            "dark": self.dark,
            "threshold": self.threshold,
            "separation": self.separation,
            "cue": self.cue,
            "tables": list(TABLE_NAMES),
        }

    def images(self) -> dict[str, np.ndarray]:
        """The baked colour tables as 512×512 uint8 grey images, by name (:data:`TABLE_NAMES`)."""
        return {"not_skin": table_to_tile(self.not_skin_table), "lip": table_to_tile(self.lip.table)}

    @classmethod
    def from_dict(cls, d: dict, images: dict[str, np.ndarray] | None = None) -> "MouthModel":
        """Rebuild from :meth:`to_dict` (and :meth:`images`, if saved; else the tables are re-baked).

        Raises ``ValueError`` (one line) on a malformed description or table image."""
        try:
            if d.get("format") != FORMAT or d.get("kind") != "inkface-mouth":
                raise ValueError(f"not an Inkface mouth model of format {FORMAT}")
            tables = {}
            for name in TABLE_NAMES:
                img = None if images is None else images.get(name)
                if img is not None:
                    img = np.asarray(img)
                    if img.shape != TILE_SHAPE or img.dtype != np.uint8:
                        raise ValueError(f"mouth colour table {name!r} must be a {TILE_SHAPE[1]}×{TILE_SHAPE[0]} 8-bit grey image")
                    tables[name] = tile_to_table(img)
            return cls(
                work_ipd=float(d["work_ipd"]),
                centre=(float(d["centre"][0]), float(d["centre"][1])),
                width=float(d["width"]),
                lip_upper=float(d["lip_upper"]),
                lip_lower=float(d["lip_lower"]),
                area=float(d["area"]),
                outline=np.asarray(d["outline"], dtype=np.float64).reshape(-1, 2),
                skin=_gauss_from(d["skin"]),
                lip=ColourClassifier.from_dict(d["lip"], tables.get("lip")),
                axis_up=np.asarray(d["axis_up"], dtype=np.float64).reshape(4),
                axis_down=np.asarray(d["axis_down"], dtype=np.float64).reshape(4),
                skin_level=float(d["skin_level"]),
                skin_sat=float(d["skin_sat"]),
                dark=float(d["dark"]),
                threshold=float(d["threshold"]),
                separation=float(d["separation"]),
                cue=str(d["cue"]),
                not_skin_table=tables.get("not_skin"),
            )
        except (KeyError, TypeError, IndexError) as e:
            raise ValueError(f"malformed mouth model ({type(e).__name__}: {e})") from None


# --------------------------------------------------------------------------------------------- learning


def luminance(bgr: np.ndarray) -> np.ndarray:
    """Rec. 601 luminance (float32, 0..255) of uint8 or float BGR pixels ``(..., 3)``."""
    c = np.asarray(bgr, dtype=np.float32)
    return c[..., 0] * np.float32(0.114) + c[..., 1] * np.float32(0.587) + c[..., 2] * np.float32(0.299)


def _smooth_loop(r: np.ndarray) -> np.ndarray:
    """Median of each radius and its two neighbours around the loop (removes one-ray spikes)."""
    return np.median(np.stack([np.roll(r, 1), r, np.roll(r, -1)]), axis=0)


def _fisher_axis(a: np.ndarray, b: np.ndarray, shading_free: bool = True) -> tuple[np.ndarray, float]:
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
        P = np.eye(3) - np.outer(u, u)
        w = P @ np.linalg.pinv(P @ sw @ P) @ P @ d
    else:
        w = np.linalg.solve(sw, d)
    span = float(w @ d)
    if span <= 1e-9:
        w, span = d, float(d @ d) + 1e-9
    sd = math.sqrt(max(float(w @ (0.5 * (ca + cb)) @ w), 1e-12))
    w = w / span
    return np.concatenate([w, [-float(w @ mb)]]), span / sd


def learn_mouth(crop_bgr: np.ndarray, mouth_click_crop: tuple[float, float], work_ipd: float,
                skin_samples: np.ndarray | None = None, _trace: dict | None = None) -> MouthModel:
    """Learn a :class:`MouthModel` from the calibration frame's mouth crop (see the module docstring).

    ``crop_bgr`` is the :data:`MOUTH_RECT` crop around the click, ``mouth_click_crop`` the click in
    its pixels (it may sit a few px off, on the gap between the lips or inside an open mouth),
    ``skin_samples`` optional ``(n, 3)`` BGR skin pixels from elsewhere on the face (cheeks,
    forehead). Never refuses a face; ``model.cue`` says which cue the finder will lean on.
    """
    from tracker.colour_model import lut_index
    from tracker.mouth_finder import MouthFinder, find_blob, outline_from_blob, polygon_measures

    crop = np.ascontiguousarray(crop_bgr)
    if crop.ndim != 3 or crop.shape[2] != 3 or crop.dtype != np.uint8:
        raise ValueError("mouth crop must be a uint8 (H, W, 3) BGR image")
    wi = float(work_ipd)
    H, W = crop.shape[:2]
    cx, cy = float(mouth_click_crop[0]), float(mouth_click_crop[1])
    yy, xx = np.mgrid[0:H, 0:W]
    feats = features(crop.reshape(-1, 3), SKIN_YW).reshape(H, W, 3).astype(np.float32)
    lum = luminance(crop)
    crop32 = crop.astype(np.float32)
    sigma = max(0.012 * wi, 0.6)

    # skin: an ellipse around the click, outside any mouth, plus whatever skin the caller knows
    e = ((xx - cx) / (0.72 * wi)) ** 2 + ((yy - cy) / (0.45 * wi)) ** 2
    ring = (e <= 1.0) & (e >= 0.75**2)
    skin_bgr = crop[ring]
    if skin_samples is not None and len(skin_samples):
        skin_bgr = np.concatenate([skin_bgr, np.asarray(skin_samples, dtype=np.uint8).reshape(-1, 3)])
    fs = features(skin_bgr, SKIN_YW)
    skin = _robust_fit(fs, k=1)
    d_skin = np.sqrt(skin.mahalanobis2(fs))
    skin_in = skin_bgr[d_skin <= np.percentile(d_skin, 90)]
    skin_level = float(np.median(luminance(skin_in)))
    skin_sat = float(np.median(np.hypot(fs[:, 1], fs[:, 2])))
    not_skin = _distance_table(skin, SKIN_YW)
    dist_s = cv2.GaussianBlur(not_skin.take(lut_index(crop)), (0, 0), sigma)
    win = (np.abs(xx - cx) < 0.55 * wi) & (yy - cy > -0.3 * wi) & (yy - cy < 0.45 * wi)
    t_otsu, _ = cv2.threshold(dist_s[win].reshape(-1, 1), 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    thr = float(np.clip(t_otsu, 2.5 * DIST_SCALE, 6.0 * DIST_SCALE))
    idx = lut_index(crop)
    inside = _inside_table(0.3 * skin_level, skin_level, skin_sat).take(idx).astype(bool)

    # first guess at each lip: the rows next to the gap (or the open mouth) above and below the
    # click; its own skin: just beyond its outer edge. One Fisher axis per lip.
    seeds, rows = _seed_lips(crop, lum, inside, (cx, cy), wi)
    # the dark inside is darker than either lip (dark lipstick is darker than skin by far)
    lip_lums = [float(np.median(luminance(v))) for v in seeds.values() if len(v) >= 12]
    dark = 0.6 * min([skin_level] + lip_lums)
    inside = _inside_table(dark, skin_level, skin_sat).take(idx).astype(bool)
    whiten = np.linalg.cholesky(skin.icovs[0]).T
    near = _local_skin(crop, feats, (cx, cy), wi, rows, whiten)
    axes = {}
    for side in ("up", "down"):
        lips_s = seeds.get(side)
        if lips_s is None or len(lips_s) < 12:
            continue
        sk = near.get(side)
        sk = np.concatenate([sk, skin_in[:: max(len(skin_in) // max(len(sk), 1), 1)]]) if sk is not None and len(sk) >= 12 else skin_in
        axes[side] = (_best_axis(lips_s, sk), sk)
    outline = None
    y_line = rows.get("line", int(round(cy)))
    if axes:
        a_up = axes.get("up", axes.get("down"))[0][0]
        a_dn = axes.get("down", axes.get("up"))[0][0]
        v = _lip_value(crop32, a_up, a_dn, y_line, wi)
        v = cv2.GaussianBlur(v, (0, 0), max(0.022 * wi, 0.8))
        found = find_blob(v, 0.6, (cx, cy), wi, 0.8 * wi, 0.12 * wi, max(int(0.004 * wi * wi), 6),
                          lambda: inside | (dist_s >= thr))
        if _trace is not None:
            _trace.update(rows=rows, v0=v)
        if found is not None:
            poly = outline_from_blob(found[0], wi)
            if poly is not None:
                left, right, up, down = polygon_measures(poly)
                if right[0] - left[0] >= 0.25 * wi and up + down >= 0.04 * wi:
                    outline = poly
    if _trace is not None:
        _trace["outline0"] = outline
    seen = outline is not None
    if outline is None:  # nothing near the click stands out from the skin: a typical mouth there
        outline = _typical_outline((cx, cy), wi)

    # the lips inside that outline, above and below the mouth line; the classifier and the axes
    filled = _fill(outline, (H, W))
    depth = cv2.distanceTransform(filled, cv2.DIST_L2, 3)
    lipish = (filled > 0) & (depth >= 1.0) & ~inside
    c_line = polygon_measures(outline)
    y_mid = 0.5 * (c_line[0][1] + c_line[1][1])
    parts = {"up": lipish & (yy < y_mid), "down": lipish & (yy >= y_mid)}
    final_axes, seps = {}, []
    for side in ("up", "down"):
        px = crop[parts[side]]
        sk = axes[side][1] if side in axes else skin_in
        if len(px) < 12:
            px = crop[lipish] if lipish.sum() >= 12 else (seeds.get(side) if seeds.get(side) is not None else crop[filled > 0])
        (ax, sep) = _best_axis(px, sk)
        final_axes[side] = ax
        seps.append(sep)
    lip_px = crop[lipish] if lipish.sum() >= 12 else crop[filled > 0]
    if len(lip_px) < 12:
        lip_px = crop[max(int(cy) - 2, 0) : int(cy) + 3, max(int(cx) - 8, 0) : int(cx) + 9].reshape(-1, 3)
    k = int(round(0.1 * wi)) * 2 + 1
    away = cv2.dilate(filled, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))) == 0
    away[1::2, :] = False
    away[:, 1::2] = False
    other = np.concatenate([crop[away], _inside_colours(np.median(skin_in, axis=0), skin_level)])
    lip = ColourClassifier(lip_px, other, y_weight=0.5, k_target=2, k_other=4, gate=16.0, margin=1.0, name="lip")
    sep = float(min(seps))
    cue = "colour" if seen and sep >= COLOUR_SEPARATION else "contrast"

    def model_for(outline_abs: np.ndarray) -> MouthModel:
        left, right, up, down = polygon_measures(outline_abs)
        centre = (0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]))
        return MouthModel(
            work_ipd=wi, centre=(float(centre[0]), float(centre[1])),
            width=float(math.hypot(right[0] - left[0], right[1] - left[1])), lip_upper=float(up), lip_lower=float(down),
            area=float(_fill(outline_abs, (H, W)).sum()), outline=outline_abs - np.array(centre), skin=skin, lip=lip,
            axis_up=final_axes["up"], axis_down=final_axes["down"], skin_level=skin_level, skin_sat=skin_sat, dark=dark,
            threshold=thr, separation=sep, cue=cue, not_skin_table=not_skin,
        )

    model = model_for(outline)
    # measure the calibration frame the way every frame will be measured
    if seen:
        res = MouthFinder(model, wi)._find(crop, model.centre, cue)
        if _trace is not None:
            _trace["final"] = None if res is None else res.polygon
        if res is not None and res.score >= 0.3 and _overlap(res.polygon, outline, (H, W)) >= 0.6:
            model = model_for(res.polygon)
    return model


def _fill(poly: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    m = np.zeros(shape, np.uint8)
    cv2.fillPoly(m, [np.round(poly * 16).astype(np.int32)], 1, cv2.LINE_8, 4)
    return m


def _best_axis(lips: np.ndarray, skin: np.ndarray) -> tuple[np.ndarray, float]:
    """The shading-free lip axis, or the plain one when the lips differ from the skin mostly in
    brightness (its d′ at least 1.25 × the shading-free one's); and its d′."""
    axis, sep = _fisher_axis(lips, skin)
    axis_b, sep_b = _fisher_axis(lips, skin, shading_free=False)
    return (axis_b, sep_b) if sep_b > 1.25 * sep else (axis, sep)


def lip_weights(h: int, y_line: float, wi: float) -> np.ndarray:
    """Per row (h, 1) float32: 0 above the mouth line ``y_line`` (upper lip's axis), 1 below (lower
    lip's), blended over ±0.03 wi."""
    y = (np.arange(h, dtype=np.float32) - np.float32(y_line)) / np.float32(max(0.03 * wi, 1.0))
    return (1.0 / (1.0 + np.exp(-y))).astype(np.float32).reshape(-1, 1)


def _lip_value(crop32: np.ndarray, a_up: np.ndarray, a_dn: np.ndarray, y_line: float, wi: float) -> np.ndarray:
    """The lip value (float32): the upper lip's axis above the mouth line, the lower lip's below."""
    vu = cv2.transform(crop32, a_up[:3].reshape(1, 3).astype(np.float32)) + np.float32(a_up[3])
    vd = cv2.transform(crop32, a_dn[:3].reshape(1, 3).astype(np.float32)) + np.float32(a_dn[3])
    return vu + lip_weights(crop32.shape[0], y_line, wi) * (vd - vu)


def _seed_lips(crop: np.ndarray, lum: np.ndarray, inside: np.ndarray, click: tuple[float, float], wi: float
               ) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    """BGR pixels that are lip on almost any mouth, per side (``"up"``, ``"down"``), and the rows
    used (``"line"``: the gap; ``"up"``/``"down"``: the outermost seed row on that side).

    In a band 0.24 wi wide through the click, the darkest row near the click is the gap between the
    lips or the open mouth's inside; walking out from it, up and down, past the dark valley (darker
    than a quarter of the way to the band's median: dark lipstick is darker than half-way) and past
    rows that are mostly inside-like (teeth: grey or bright), the next 0.05 wi (above) / 0.06 wi
    (below) of rows are lip."""
    H, W = lum.shape
    cx, cy = click
    x0, x1 = max(int(round(cx - 0.12 * wi)), 0), min(int(round(cx + 0.12 * wi)) + 1, W)
    smooth = lambda v: cv2.GaussianBlur(v.reshape(-1, 1).astype(np.float32), (1, 0), 0.8).ravel()
    rows = smooth(lum[:, x0:x1].mean(axis=1))
    teeth = smooth(inside[:, x0:x1].mean(axis=1))
    ya, yb = max(int(round(cy - 0.1 * wi)), 0), min(int(round(cy + 0.15 * wi)) + 1, H)
    y_min = ya + int(np.argmin(rows[ya:yb]))
    ra, rb = max(int(round(cy - 0.35 * wi)), 0), min(int(round(cy + 0.45 * wi)) + 1, H)
    half = rows[y_min] + 0.25 * (float(np.median(rows[ra:rb])) - rows[y_min])
    skip = (rows < half) | (teeth > 0.5)
    seeds, used = {}, {"line": y_min}
    for side, direction, depth in (("up", -1, 0.05), ("down", 1, 0.06)):
        y, k, limit = y_min, 0, int(round(0.3 * wi))
        while k < limit and 0 <= y < H and skip[y]:
            y += direction
            k += 1
        if k >= limit or not 0 <= y < H:
            continue
        y1 = min(max(y + direction * max(int(round(depth * wi)), 2), 0), H - 1)
        lo, hi = sorted((y, y1))
        sel = (lum[lo : hi + 1, x0:x1] >= half) & ~inside[lo : hi + 1, x0:x1]
        seeds[side] = crop[lo : hi + 1, x0:x1][sel]
        used[side] = y1
    return seeds, used


def _local_skin(crop: np.ndarray, feats: np.ndarray, click: tuple[float, float], wi: float,
                rows: dict[str, int], whiten: np.ndarray) -> dict[str, np.ndarray]:
    """Skin right next to each lip: beyond the first strong colour edge outwards from its seed rows
    (rows of a 0.3 wi band, colour features whitened by ``whiten``), 0.04–0.12 wi past it. The skin
    around the lips can differ from the cheeks (a redder nose and philtrum, stubble, the shadow
    under the lower lip), and it is the lips' contrast with *this* skin that marks their edges."""
    H, W = crop.shape[:2]
    cx = click[0]
    x0, x1 = max(int(round(cx - 0.15 * wi)), 0), min(int(round(cx + 0.15 * wi)) + 1, W)
    prof = cv2.GaussianBlur(feats[:, x0:x1].mean(axis=1).reshape(-1, 1, 3), (1, 0), 1.0).reshape(-1, 3)
    z = prof @ whiten.T
    out = {}
    for side, direction in (("up", -1), ("down", 1)):
        if side not in rows:
            continue
        ys = rows[side] + direction * np.arange(0, int(round(0.3 * wi)))
        ys = ys[(ys >= 1) & (ys < H - 1)]
        if len(ys) < 5:
            continue
        g = np.linalg.norm(z[ys - direction] - z[ys + direction], axis=1)
        peaks = [i for i in range(1, len(g) - 1) if g[i] >= g[i - 1] and g[i] >= g[i + 1]]
        if not peaks:
            continue
        gmax = max(g[i] for i in peaks)
        edge = ys[next(i for i in peaks if g[i] >= 0.4 * gmax)]
        lo, hi = sorted((edge + direction * int(round(0.04 * wi)), edge + direction * int(round(0.12 * wi))))
        lo, hi = max(lo, 0), min(hi + 1, H)
        if hi > lo:
            out[side] = crop[lo:hi, x0:x1].reshape(-1, 3)
    return out


def _overlap(a: np.ndarray, b: np.ndarray, shape: tuple[int, int]) -> float:
    """Intersection over union of two closed polygons (px) rasterised on an image of ``shape``."""
    ma, mb = _fill(a, shape), _fill(b, shape)
    union = int(np.count_nonzero(ma | mb))
    return int(np.count_nonzero(ma & mb)) / union if union else 0.0


def _typical_outline(centre: tuple[float, float], wi: float) -> np.ndarray:
    """A closed mouth of typical size (0.8 wi wide) at ``centre``, on 48 rays."""
    a = np.arange(48) * (2.0 * math.pi / 48)
    s = np.sin(a)
    return np.stack([centre[0] + 0.4 * wi * np.cos(a), centre[1] + np.where(s < 0, 0.09, 0.11) * wi * s], axis=1)
