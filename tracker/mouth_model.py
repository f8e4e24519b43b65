"""What the mouth finder learns about one performer from the calibration frame.

Everything lives in the upright, scale-normalised mouth crop of :class:`~tracker.calibration.FaceFrame`
(x along the eye line, y down, ``work_ipd`` px between the eyes), cut with :data:`MOUTH_RECT`
around the mouth click.

Nothing here assumes what colour lips or skin are. From the calibration crop the model learns

* the mouth's **outline**: a first guess at each lip is the rows right above and below the gap
  between the lips (or the open mouth) at the click; three kinds of evidence — those rows' colour
  against the skin next to them, anything unlike the skin, redness — are each traced the way the
  finder traces a mouth, and the outline lying on the strongest colour boundary wins;
* one **lip axis** per lip: Fisher's linear discriminant of the lip's pixels inside that outline
  against the skin just outside it (the upper lip faces the floor and the lower lip the light, and
  the skin above and below them differs too), kept orthogonal to the skin's colour so shading
  does not move it — a linear colour classifier, 0 on skin and 1 on lip, linear in BGR so outer
  lip edges can be placed to a fraction of a pixel;
* what the **inside** of a mouth looks like next to this skin (a 64³ table): dark and colourless,
  or the greys of teeth — so an open mouth, teeth and the gap between closed lips add to the mouth
  instead of splitting it;
* the calibrated mouth's **geometry** (centre, width, lip heights, outline).

The **cue** is ``"colour"`` when both lips stand out from their skin along their axes (d′ ≥
:data:`COLOUR_SEPARATION`), else ``"contrast"``: the lips barely differ in colour, so the finder
leans on what else sets the mouth apart — its dark gap or inside and teeth — and on the weak lip
edges its axes still see. :func:`learn_mouth` never refuses a face; a face with no visible mouth
gets a typical mouth at the click, and the finder's score says how sure each frame is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from tracker.colour_model import TILE_SHAPE, Gaussians, _grid_features, features, lut_index, table_to_tile

FORMAT = 1
MOUTH_RECT = (-0.95, -0.6, 1.9, 1.6)
"""Crop rectangle ``(x0, y0, w, h)`` in units of ``work_ipd``, relative to the predicted mouth centre
(face px): wide enough for a grin (1.5× the width), a yawn (the centre drops ~0.3 wi, the lower lip
another 0.6 wi) and the head-motion prediction's error."""
N_RAYS = 48
COLOUR_SEPARATION = 2.0
"""Lip-vs-skin d′ along the lip axes at and above which the lip colour is the cue."""
TABLE_NAMES = ("inside",)
"""Names of the colour-table images of :meth:`MouthModel.images` (512×512 grey tiles, 255 = inside-like)."""


# --------------------------------------------------------------------------------------------- tables


def _inside(dark: float, skin_level: float, skin_sat: float) -> np.ndarray:
    """Bool per 64³ bin: looks like the inside of a mouth — dark (under ``dark``) with little colour
    (absolute chroma under 60 % of the skin's: dark lipstick is dark but strongly coloured), or grey
    (teeth: chroma under 55 % of the skin's and not dark, or under 80 % and brighter than the skin)."""
    f = _grid_features()
    lum = f[:, 0] * np.float32(255.0)
    sat = np.hypot(f[:, 1], f[:, 2])
    black = (lum < np.float32(dark)) & (sat * lum < np.float32(0.6 * skin_sat * skin_level))
    grey = (sat < np.float32(0.55 * skin_sat)) & (lum > np.float32(0.45 * skin_level))
    white = (sat < np.float32(0.8 * skin_sat)) & (lum > np.float32(1.1 * skin_level))
    return black | grey | white


# --------------------------------------------------------------------------------------------- the model


@dataclass
class MouthModel:
    """One performer's mouth (see the module docstring). Lengths are face px (``work_ipd`` between the eyes).

    ``centre`` is the calibrated mouth centre (midpoint of the corners) in the calibration crop's
    pixels; the tracker turns it into a face-frame offset. ``width``, ``lip_upper``, ``lip_lower``
    and ``area`` are the calibration frame's measurements; ``outline`` the mouth outline there,
    relative to the centre. ``axis_up`` / ``axis_down`` (4,) map BGR to the lip value ``w·bgr + c``
    of the upper / lower lip (0 on the skin next to it, 1 on the lip). ``skin_level`` /
    ``skin_sat`` are the skin's median luminance and chroma (:func:`~tracker.colour_model.features`),
    ``dark`` the luminance under which a colourless pixel is the mouth's dark inside; they define
    ``inside_table`` (64³, 1 = inside-like). ``separation`` is the smaller lip-vs-skin d′ of the two
    axes; ``cue`` ``"colour"`` or ``"contrast"``. ``crop_median`` is the calibration crop's median
    BGR (mostly skin), the reference the finder matches each frame's light to.
    """

    work_ipd: float
    centre: tuple[float, float]
    width: float
    lip_upper: float
    lip_lower: float
    area: float
    outline: np.ndarray
    axis_up: np.ndarray
    axis_down: np.ndarray
    skin_level: float
    skin_sat: float
    dark: float
    separation: float
    cue: str
    crop_median: tuple[float, float, float] | None = None
    inside_table: np.ndarray = field(repr=False, default=None)

    def __post_init__(self) -> None:
        if self.inside_table is None:
            self.inside_table = _inside(self.dark, self.skin_level, self.skin_sat).view(np.uint8)

    # ------------------------------------------------------------------ persistence
    def to_dict(self) -> dict:
        """JSON-able description (the table is rebuilt from it; :meth:`images` shows it)."""
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
            "axis_up": [float(v) for v in self.axis_up],
            "axis_down": [float(v) for v in self.axis_down],
            "skin_level": self.skin_level,
            "skin_sat": self.skin_sat,
            "dark": self.dark,
            "separation": self.separation,
            "cue": self.cue,
            "crop_median": None if self.crop_median is None else [float(v) for v in self.crop_median],
            "tables": list(TABLE_NAMES),
        }

    def images(self) -> dict[str, np.ndarray]:
        """The baked table as a 512×512 uint8 grey image, by name (:data:`TABLE_NAMES`)."""
        return {"inside": table_to_tile(self.inside_table * np.uint8(255))}

    @classmethod
    def from_dict(cls, d: dict, images: dict[str, np.ndarray] | None = None) -> "MouthModel":
        """Rebuild from :meth:`to_dict` (``images`` are accepted and checked but not needed: the
        table is rebuilt from the description). Raises ``ValueError`` (one line) when malformed."""
        if not isinstance(d, dict) or d.get("format") != FORMAT or d.get("kind") != "inkface-mouth":
            raise ValueError(f"not an Inkface mouth model of format {FORMAT}")
        img = None if images is None else images.get("inside")
        if img is not None and (np.asarray(img).shape != TILE_SHAPE or np.asarray(img).dtype != np.uint8):
            raise ValueError(f"mouth table image must be {TILE_SHAPE[1]}×{TILE_SHAPE[0]} 8-bit grey")
        try:
            return cls(
                work_ipd=float(d["work_ipd"]),
                centre=(float(d["centre"][0]), float(d["centre"][1])),
                width=float(d["width"]),
                lip_upper=float(d["lip_upper"]),
                lip_lower=float(d["lip_lower"]),
                area=float(d["area"]),
                outline=np.asarray(d["outline"], dtype=np.float64).reshape(-1, 2),
                axis_up=np.asarray(d["axis_up"], dtype=np.float64).reshape(4),
                axis_down=np.asarray(d["axis_down"], dtype=np.float64).reshape(4),
                skin_level=float(d["skin_level"]),
                skin_sat=float(d["skin_sat"]),
                dark=float(d["dark"]),
                separation=float(d["separation"]),
                cue=str(d["cue"]),
                crop_median=None if d.get("crop_median") is None else tuple(float(v) for v in d["crop_median"]),
            )
        except (KeyError, TypeError, IndexError, ValueError) as e:
            raise ValueError(f"malformed mouth model ({type(e).__name__}: {e})") from None


# --------------------------------------------------------------------------------------------- learning


def luminance(bgr: np.ndarray) -> np.ndarray:
    """Rec. 601 luminance (float32, 0..255) of uint8 or float BGR pixels ``(..., 3)``."""
    c = np.asarray(bgr, dtype=np.float32)
    return c[..., 0] * np.float32(0.114) + c[..., 1] * np.float32(0.587) + c[..., 2] * np.float32(0.299)


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


def _fill(poly: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    m = np.zeros(shape, np.uint8)
    cv2.fillPoly(m, [np.round(poly * 16).astype(np.int32)], 1, cv2.LINE_8, 4)
    return m


def _overlap(a: np.ndarray, b: np.ndarray, shape: tuple[int, int]) -> float:
    """Intersection over union of two closed polygons (px) rasterised on an image of ``shape``."""
    ma, mb = _fill(a, shape), _fill(b, shape)
    union = int(np.count_nonzero(ma | mb))
    return int(np.count_nonzero(ma & mb)) / union if union else 0.0


def _typical_outline(centre: tuple[float, float], wi: float) -> np.ndarray:
    """A closed mouth of typical size (0.8 wi wide) at ``centre``, on :data:`N_RAYS` rays."""
    a = np.arange(N_RAYS) * (2.0 * math.pi / N_RAYS)
    s = np.sin(a)
    return np.stack([centre[0] + 0.4 * wi * np.cos(a), centre[1] + np.where(s < 0, 0.09, 0.11) * wi * s], axis=1)


def _seed_lips(crop: np.ndarray, lum: np.ndarray, inside: np.ndarray, click: tuple[float, float], wi: float
               ) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    """BGR pixels that are lip on almost any mouth, per side (``"up"``, ``"down"``), and the rows
    used (``"line"``: the gap; ``"up"`` / ``"down"``: the outermost seed row on that side).

    In a band 0.24 wi wide through the click, the darkest row near the click is the gap between the
    lips or the open mouth's inside; walking out from it, up and down, past the dark valley (darker
    than a quarter of the way to the band's median: dark lipstick is darker than half-way) and past
    rows that are mostly inside-like (teeth) — and, below, past a tongue on the lower teeth — the
    next 0.05 wi (above) / 0.06 wi (below) of rows are lip."""
    H, W = lum.shape
    cx, cy = click
    x0, x1 = max(int(round(cx - 0.12 * wi)), 0), min(int(round(cx + 0.12 * wi)) + 1, W)
    smooth = lambda v: cv2.GaussianBlur(v.reshape(-1, 1).astype(np.float32), (1, 0), 0.8).ravel()
    rows = smooth(lum[:, x0:x1].mean(axis=1))
    teeth = smooth(inside[:, x0:x1].mean(axis=1))
    ya, yb = max(int(round(cy - 0.1 * wi)), 0), min(int(round(cy + 0.15 * wi)) + 1, H)
    y_min = ya + int(np.argmin(rows[ya:yb]))
    ra, rb = max(int(round(cy - 0.35 * wi)), 0), min(int(round(cy + 0.45 * wi)) + 1, H)
    level = rows[y_min] + 0.25 * (float(np.median(rows[ra:rb])) - rows[y_min])
    skip = (rows < level) | (teeth > 0.5)
    seeds, used = {}, {"line": y_min}
    for side, direction, depth in (("up", -1, 0.05), ("down", 1, 0.06)):
        y, k, limit = y_min, 0, int(round(0.3 * wi))
        while k < limit and 0 <= y < H and skip[y]:
            y += direction
            k += 1
        if k >= limit or not 0 <= y < H:
            continue
        # a tongue on the lower teeth is not the lower lip: if more teeth follow below it within
        # 0.15 wi, the lip is past them (not past a shadow: only teeth count here)
        reach = [y + direction * j for j in range(1, int(round(0.15 * wi)))] if direction > 0 else []
        reach = [v for v in reach if 0 <= v < H]
        flags = [bool(teeth[v] > 0.5) for v in reach]
        for j in range(len(flags) - 1):
            if flags[j] and flags[j + 1]:
                v = reach[j]
                while 0 <= v < H and skip[v] and abs(v - y) < int(round(0.35 * wi)):
                    v += direction
                if 0 <= v < H and not skip[v]:
                    y = v
                break
        y1 = min(max(y + direction * max(int(round(depth * wi)), 2), 0), H - 1)
        lo, hi = sorted((y, y1))
        sel = (lum[lo : hi + 1, x0:x1] >= level) & ~inside[lo : hi + 1, x0:x1]
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


def _plausible(poly: np.ndarray, click: tuple[float, float], wi: float) -> float:
    """How much a calibration outline looks like a mouth at the click (0..1): 0.35–1.3 wi wide,
    0.06–0.7 wi tall, no more than 0.3 wi above the corners, centred within ~0.2 wi of the click."""
    from tracker.mouth_finder import polygon_measures

    left, right, up, down = polygon_measures(poly)
    w, h = right[0] - left[0], up + down
    ramp = lambda v, a, b: float(np.clip((v - a) / (b - a), 0.0, 1.0))
    c = (0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]) + 0.5 * (down - up))
    d = math.hypot(c[0] - click[0], c[1] - click[1]) / wi
    return (ramp(w, 0.3 * wi, 0.4 * wi) * ramp(-w, -1.4 * wi, -1.2 * wi) * ramp(h, 0.04 * wi, 0.08 * wi)
            * ramp(-h, -0.8 * wi, -0.6 * wi) * ramp(-up, -0.35 * wi, -0.25 * wi) * ramp(-d, -0.3 * wi / wi, -0.15))


def _boundary_contrast(crop: np.ndarray, poly: np.ndarray, inside: np.ndarray, wi: float) -> float:
    """Fisher separation (d′ along the best direction, colour features) between a band just inside
    the outline (without the mouth's inside) and a band just outside it: largest on the lips' outer
    edge — smaller if the outline cuts through the lips or runs out into skin."""
    H, W = crop.shape[:2]
    filled = _fill(poly, (H, W))
    depth = cv2.distanceTransform(filled, cv2.DIST_L2, 3)
    out_depth = cv2.distanceTransform(1 - filled, cv2.DIST_L2, 3)
    band_in = (filled > 0) & (depth >= 1.0) & (depth <= max(0.06 * wi, 2.5)) & (inside == 0)
    band_out = (filled == 0) & (out_depth >= 1.5) & (out_depth <= max(0.1 * wi, 4.0))
    if band_in.sum() < 12 or band_out.sum() < 12:
        return 0.0
    a, b = features(crop[band_in], 1.0), features(crop[band_out], 1.0)
    d = a.mean(0) - b.mean(0)
    sw = 0.5 * (np.cov(a.T) + np.cov(b.T)) + np.diag([1e-4, 1e-5, 1e-5])
    return float(np.sqrt(max(d @ np.linalg.solve(sw, d), 0.0)))


def _every(px: np.ndarray, n: int) -> np.ndarray:
    """At most about ``n`` rows of ``px``, evenly spaced."""
    return px[:: max(len(px) // max(n, 1), 1)]


def learn_mouth(crop_bgr: np.ndarray, mouth_click_crop: tuple[float, float], work_ipd: float,
                skin_samples: np.ndarray | None = None, _trace: dict | None = None) -> MouthModel:
    """Learn a :class:`MouthModel` from the calibration frame's mouth crop (see the module docstring).

    ``crop_bgr`` is the :data:`MOUTH_RECT` crop around the click, ``mouth_click_crop`` the click in
    its pixels (it may sit a few px off, on the gap between the lips or inside an open mouth),
    ``skin_samples`` optional ``(n, 3)`` BGR skin pixels from elsewhere on the face (cheeks,
    forehead). Never refuses a face; ``model.cue`` says which cue the finder will lean on.
    """
    from tracker.mouth_finder import MouthFinder, polygon_measures

    crop = np.ascontiguousarray(crop_bgr)
    if crop.ndim != 3 or crop.shape[2] != 3 or crop.dtype != np.uint8:
        raise ValueError("mouth crop must be a uint8 (H, W, 3) BGR image")
    wi = float(work_ipd)
    H, W = crop.shape[:2]
    cx, cy = float(mouth_click_crop[0]), float(mouth_click_crop[1])
    yy, xx = np.mgrid[0:H, 0:W]
    feats = features(crop.reshape(-1, 3), 1.0).reshape(H, W, 3).astype(np.float32)
    lum = luminance(crop)
    idx = lut_index(crop)
    crop32 = crop.astype(np.float32)
    sub = crop[::4, ::4].reshape(-1, 3)
    crop_median = tuple(float(v) for v in np.partition(sub, len(sub) // 2, axis=0)[len(sub) // 2])

    # skin: an ellipse around the click, outside any mouth (its 90 % most typical pixels)
    e = ((xx - cx) / (0.72 * wi)) ** 2 + ((yy - cy) / (0.45 * wi)) ** 2
    ring = crop[(e <= 1.0) & (e >= 0.75**2)]
    if skin_samples is not None and len(skin_samples):
        ring = np.concatenate([ring, np.asarray(skin_samples, dtype=np.uint8).reshape(-1, 3)])
    fs = features(ring, 1.0)
    med = np.median(fs, axis=0)
    dev = np.abs(fs - med) / (np.median(np.abs(fs - med), axis=0) * 1.4826 + 1e-6)
    skin_in = ring[dev.max(axis=1) <= np.percentile(dev.max(axis=1), 90)]
    fs_in = features(skin_in, 1.0)
    skin_level = float(np.median(fs_in[:, 0]) * 255.0)
    skin_sat = float(np.median(np.hypot(fs_in[:, 1], fs_in[:, 2])))
    inside0 = _inside(0.5 * skin_level, skin_level, skin_sat).take(idx)

    # first guess at each lip: the rows next to the gap (or the open mouth) above and below the click;
    # its own skin: just beyond its outer edge
    seeds, rows = _seed_lips(crop, lum, inside0, (cx, cy), wi)
    cov = np.cov(fs_in.T) + np.diag([1e-4, 1e-5, 1e-5])
    near = _local_skin(crop, feats, (cx, cy), wi, rows, np.linalg.cholesky(np.linalg.inv(cov)).T)
    lip_lums = [float(np.median(luminance(v))) for v in seeds.values() if len(v) >= 12]
    dark = 0.6 * min([skin_level] + lip_lums)  # the inside is darker than either lip
    inside = _inside(dark, skin_level, skin_sat).take(idx)

    def skin_next_to(side: str) -> np.ndarray:
        sk = near.get(side)
        if sk is None or len(sk) < 12:
            return skin_in
        return np.concatenate([sk, _every(skin_in, len(sk))])

    # pass 1: candidate outlines from three kinds of evidence, each traced the way the finder traces
    # a mouth; the one on the strongest colour boundary wins
    finder0 = MouthFinder(_provisional(wi, skin_level, skin_sat, dark), wi)
    evidence = []
    if len(seeds.get("up", ())) >= 6 or len(seeds.get("down", ())) >= 6:
        a_up = best_axis(seeds.get("up") if len(seeds.get("up", ())) >= 6 else seeds["down"], skin_next_to("up"))[0]
        a_dn = best_axis(seeds.get("down") if len(seeds.get("down", ())) >= 6 else seeds["up"], skin_next_to("down"))[0]
        evidence.append(lip_evidence(lip_value(crop32, a_up, a_dn, rows["line"], wi)))
    d_skin = np.sqrt(Gaussians(fs_in, 1, np.array([0.02, 0.006, 0.006])).mahalanobis2(features(crop.reshape(-1, 3), 1.0)))
    evidence.append((d_skin.reshape(H, W).astype(np.float32) - 3.0) * 0.5)
    rg = features(skin_next_to("up"), 1.0)[:, 1]
    evidence.append((feats[..., 1] - np.float32(np.median(rg))) / np.float32(max(float(np.std(rg)), 0.004)) * 0.5 - 1.0)
    candidates = []
    for ev in evidence:
        ev = cv2.GaussianBlur(np.clip(ev, -2.0, 2.0).astype(np.float32), (0, 0), finder0.sigma)
        res = finder0.outline_on(ev, inside, (cx, cy), fill=False)
        if res is not None:
            q = _plausible(res[0], (cx, cy), wi)
            if q > 0:
                candidates.append((q * _boundary_contrast(crop, res[0], inside, wi), res[0]))
    if _trace is not None:
        _trace.update(rows=rows, candidates=candidates)
    outline = max(candidates, key=lambda c: c[0])[1] if candidates else None
    seen = outline is not None
    if outline is None:  # nothing near the click stands out from the skin: a typical mouth there
        outline = _typical_outline((cx, cy), wi)

    # pass 2: each lip's axis, from its pixels inside the outline against the skin just outside it
    axes, sep = _axes_for(crop, outline, inside, wi, skin_next_to)
    cue = "colour" if seen and sep >= COLOUR_SEPARATION else "contrast"

    def model_for(poly: np.ndarray, axes: dict, sep: float, measured=None) -> MouthModel:
        left, right, up, down = polygon_measures(poly) if measured is None else measured
        centre = (0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]))
        return MouthModel(
            work_ipd=wi, centre=(float(centre[0]), float(centre[1])),
            width=float(math.hypot(right[0] - left[0], right[1] - left[1])), lip_upper=float(up), lip_lower=float(down),
            area=float(_fill(poly, (H, W)).sum()), outline=poly - np.array(centre), axis_up=axes["up"],
            axis_down=axes["down"], skin_level=skin_level, skin_sat=skin_sat, dark=dark, separation=sep, cue=cue,
            crop_median=crop_median,
        )

    model = model_for(outline, axes, sep)
    # measure the calibration frame the way every frame will be measured (and learn the axes again
    # from that outline if it agrees with the first)
    if seen:
        res = MouthFinder(model, wi).find(crop, model.centre)
        if _trace is not None:
            _trace["final"] = None if res is None else res.polygon
        if res is not None and res.score >= 0.3 and _overlap(res.polygon, outline, (H, W)) >= 0.7:
            axes2, sep2 = _axes_for(crop, res.polygon, inside, wi, skin_next_to)
            model = model_for(res.polygon, axes2, sep2, (res.left, res.right, res.lip_upper, res.lip_lower))
    return model


def _axes_for(crop: np.ndarray, outline: np.ndarray, inside: np.ndarray, wi: float, skin_next_to) -> tuple[dict, float]:
    """Lip axes for the upper and lower lip of ``outline`` (pixels inside it, neither its rim nor the
    mouth's inside, above / below the corners' line, against a band 1.5 px to 0.1 wi outside it on the
    same side), and the smaller of their d′."""
    from tracker.mouth_finder import polygon_measures

    H, W = crop.shape[:2]
    yy = np.arange(H)[:, None]
    filled = _fill(outline, (H, W))
    depth = cv2.distanceTransform(filled, cv2.DIST_L2, 3)
    out_depth = cv2.distanceTransform(1 - filled, cv2.DIST_L2, 3)
    lipish = (filled > 0) & (depth >= 1.0) & (inside == 0)
    skin = (filled == 0) & (out_depth >= 1.5) & (out_depth <= max(0.1 * wi, 4.0))
    left, right, _, _ = polygon_measures(outline)
    y_line = 0.5 * (left[1] + right[1])
    xs = (np.arange(W)[None, :] >= left[0]) & (np.arange(W)[None, :] <= right[0])
    axes, seps = {}, []
    for side, half in (("up", yy < y_line), ("down", yy >= y_line)):
        lp = lipish & half
        sk = skin & half & xs
        lips = crop[lp] if lp.sum() >= 12 else crop[lipish] if lipish.sum() >= 12 else crop[filled > 0]
        sk_px = crop[sk] if sk.sum() >= 12 else skin_next_to(side)
        axes[side], s = best_axis(lips, sk_px)
        seps.append(s)
    return axes, float(min(seps))


def lip_value(crop32: np.ndarray, a_up: np.ndarray, a_dn: np.ndarray, y_line: float, wi: float) -> np.ndarray:
    """The lip value (float32; 0 skin, 1 lip) of a float32 BGR crop: the upper lip's axis above the
    mouth line ``y_line``, the lower lip's below, blended over about ±0.03 wi."""
    vu = cv2.transform(crop32, a_up[:3].reshape(1, 3).astype(np.float32))
    vd = cv2.transform(crop32, a_dn[:3].reshape(1, 3).astype(np.float32))
    vu += np.float32(a_up[3])
    vd += np.float32(a_dn[3])
    vd -= vu
    y = (np.arange(crop32.shape[0], dtype=np.float32) - np.float32(y_line)) / np.float32(max(0.03 * wi, 1.0))
    vd *= (1.0 / (1.0 + np.exp(-y))).astype(np.float32).reshape(-1, 1)
    vd += vu
    return vd


def lip_evidence(v: np.ndarray) -> np.ndarray:
    """Evidence (+1 lip, −1 skin, float32) from a lip value map: ``2·v − 1`` clipped to [−2, 2]."""
    return np.clip(np.float32(2.0) * v - np.float32(1.0), -2.0, 2.0)


def _provisional(wi: float, skin_level: float, skin_sat: float, dark: float) -> MouthModel:
    """A model with only the sizes and the inside known (for the calibration's first outlines)."""
    zero = np.zeros(4)
    return MouthModel(
        work_ipd=wi, centre=(0.0, 0.0), width=0.8 * wi, lip_upper=0.1 * wi, lip_lower=0.12 * wi, area=0.15 * wi * wi,
        outline=_typical_outline((0.0, 0.0), wi), axis_up=zero, axis_down=zero, skin_level=skin_level,
        skin_sat=skin_sat, dark=dark, separation=0.0, cue="contrast",
    )
