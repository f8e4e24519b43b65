"""The eye finder for real faces: iris centre, lids and brow of both eyes in an upright face crop.

Works in the face frame of :class:`tracker.calibration.FaceFrame` (x along the eye line
towards the image-right eye, y down, inter-eye distance ``work_ipd`` px). Per eye:

* **iris** — a dark disc of the calibrated radius: the darkness of a disc against the
  skin around it, the agreement of the grey gradients pointing away from one centre at
  that radius (radial symmetry), and the normalised correlation with the calibrated
  iris picture (iris plus the white beside it). Both eyes are searched together: gaze and
  a badly predicted crop shift both irises alike, so the pair maximises the sum of both
  score maps with a small slack between the eyes. Eye corners, lash lines, brows and
  nostrils do not look like a disc of that size on both sides at once.
* **lids** — the *interior* of the eye is what is not this person's skin (sclera, iris,
  pupil, lashes; a Mahalanobis distance from the skin colour learned at calibration). The
  upper and lower lid distances are the lengths of the interior run up and down from the
  iris centre in a strip of columns through it; soft membership makes them sub-pixel
  and blurred edges count by halves.
* **closed eyes** — when the run is short against the calibrated opening, the eye is
  closed and its point moves to the middle of what is visible of the eye (the slit
  between the lids), as a landmark tracker does.
* **brow** — the calibrated vertical cross-section of the brow matched above the eye.
* **score** — how much the region around the eye looks like the calibrated eye picture
  (0..1, normalised correlation), the "this is this person's eye" test.

All lengths are crop pixels; lid and brow distances are along up (−y) from the eye point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from tracker.brows import brow_centre, column_profile
from tracker.pupils import parabola_offset

FORMAT = 1

# geometry, as fractions of the work ipd
SEARCH_X, SEARCH_Y = 0.22, 0.12
FINE = 3
SOCKET_SEARCH = (0.17, 0.05)
BROW_ABS = True
BROW_DOWN, BROW_UP = 0.15, 0.3
BROW_HW = 0.03
SNAP_LOWER = 0
LASH_STEP = 0.05
PRIOR = (0.2, 0.1)
COARSE_VOTES = True
COARSE_NCC = True
"""Half-size (full px) of the neighbourhood the iris is refined in at full resolution."""
"""Half-size of the window the iris centre is searched in, around the predicted eye centre."""
PAIR_SLACK_X, PAIR_SLACK_Y = 0.06, 0.08
"""How far one eye's iris may move relative to the other's when both are searched together."""
LID_RANGE = 0.3
"""How far the lid runs go up and down from the eye point."""
LID_HW = 0.3
LID_AT_MIDDLE = False
VISIBLE_CENTROID = False
MIDDLE_RANGE = 0.32
SOCKET_HW, SOCKET_HH = 0.3, 0.17
"""Half-size of the stored eye picture used for the score."""
BROW_LO, BROW_HI = 0.55, 1.6
"""Brow search range, × the calibrated brow height."""
RADIUS_LO, RADIUS_HI, RADIUS_DEFAULT = 0.065, 0.135, 0.1
"""Plausible iris radii (× work ipd) and the one used when none is measurable."""
CLOSED_BELOW = 0.6
"""An eye whose lid gap is below this fraction of the calibrated one is closed."""

# YCrCb from BGR (linear part of OpenCV's conversion; the offsets cancel in the whitening)
_YCC = np.array(
    [[0.114, 0.587, 0.299], [-0.081312, -0.418688, 0.5], [0.5, -0.331264, -0.168736]], dtype=np.float64
)
_YCC_FLOOR = np.array([6.0, 2.0, 2.0])
"""Smallest skin spread (std, grey levels) per YCrCb channel: noise and shading always add this."""


class EyeModelError(ValueError):
    """The calibration crop cannot give an eye model (one-line message)."""


# ---------------------------------------------------------------------------------------------
# small image helpers


def _odd(v: float, lo: int = 3) -> int:
    n = max(int(round(v)), lo)
    return n if n % 2 else n + 1


def ring_kernels(radius: float, width: float = 0.35) -> tuple[np.ndarray, np.ndarray]:
    """Kernels ``(kx, ky)`` that sum, at each centre, the unit gradient components pointing
    away from it on a ring of ``radius`` (±``width``×radius): filtered with the unit gradient
    field, a dark disc's rim adds up at its centre (a soft Hough transform for one radius)."""
    k = int(math.ceil(radius * (1.0 + width))) + 1
    yy, xx = np.mgrid[-k : k + 1, -k : k + 1].astype(np.float64)
    d = np.hypot(xx, yy)
    ring = np.clip(1.0 - np.abs(d - radius) / (width * radius + 0.5), 0.0, None)
    ring[k, k] = 0.0
    ring /= ring.sum()
    with np.errstate(invalid="ignore", divide="ignore"):
        ux, uy = np.where(d > 0, xx / d, 0.0), np.where(d > 0, yy / d, 0.0)
    # filter2D correlates: out(c) = sum_d K(d) f(c + d); the gradient at c + d should point along +d
    return (ring * ux).astype(np.float32), (ring * uy).astype(np.float32)


def _disc_boxes(radius: float) -> tuple[tuple[int, int], ...]:
    """Sizes ``(w, h)`` of centred boxes whose average weighs about like a disc of ``radius``
    (a wide and a tall box and a square: box filters cost the same at any size)."""
    a = max(int(round(radius)), 1)
    b = max(int(round(0.5 * radius)), 0)
    c = max(int(round(0.75 * radius)), 1)
    return ((2 * a + 1, 2 * b + 1), (2 * b + 1, 2 * a + 1), (2 * c + 1, 2 * c + 1))


def disc_kernel(radius: float) -> np.ndarray:
    """A normalised disc of ``radius`` px with anti-aliased rim (float32, odd square)."""
    k = int(math.ceil(radius + 0.5))
    yy, xx = np.mgrid[-k : k + 1, -k : k + 1]
    w = np.clip(radius + 0.5 - np.hypot(xx, yy), 0.0, 1.0).astype(np.float32)
    return w / w.sum()


def brow_half_width(work_ipd: float) -> int:
    """Half-width (px) of the strip of columns the brow's cross-section averages."""
    return max(int(round(BROW_HW * work_ipd)), 2)


def _standardised(v: np.ndarray) -> np.ndarray:
    """``v`` with zero mean and unit standard deviation (float32; a flat ``v`` stays flat)."""
    v = np.asarray(v, dtype=np.float32).ravel()
    d = v - v.mean()
    return (d / max(float(d.std()), 1e-6)).astype(np.float32)


def _even(v: float, lo: int = 2) -> int:
    """``v`` rounded to an even integer of at least ``lo`` (pictures of side 4k+1 halve to a centred 2k+1)."""
    return max(2 * int(round(v / 2.0)), lo)


def _even_picture(p: np.ndarray) -> np.ndarray:
    """``p`` (odd sides) trimmed by a pixel each side where a half-size is odd, so it halves to a
    centred picture."""
    h, w = p.shape[0] // 2, p.shape[1] // 2
    return np.ascontiguousarray(p[h % 2 : p.shape[0] - h % 2, w % 2 : p.shape[1] - w % 2], dtype=np.float32)


def iris_picture_size(r: float) -> tuple[int, int]:
    """Half-width and half-height (even) of the iris picture for radius ``r``: the iris and the
    white beside it."""
    return _even(1.5 * r), _even(0.8 * r)


def subpixel_cut(grey: np.ndarray, cx: float, cy: float, hw: int, hh: int) -> np.ndarray:
    """The ``(2hh+1, 2hw+1)`` patch of ``grey`` centred exactly on ``(cx, cy)`` (bilinear, float32)."""
    M = np.float32([[1, 0, cx - hw], [0, 1, cy - hh]])
    return cv2.warpAffine(
        np.asarray(grey, dtype=np.float32), M, (2 * hw + 1, 2 * hh + 1),
        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE,
    )


def iris_radius(grey: np.ndarray, centre: tuple[float, float], work_ipd: float) -> float:
    """Iris radius (px) from the strongest dark-to-light steps left and right of ``centre``.

    The limbus is the largest rise of brightness going outwards along the rows through the
    centre (a catch-light only makes falls); the two sides are averaged, or the one that is
    plausible is taken. Falls back to :data:`RADIUS_DEFAULT` × ``work_ipd``.
    """
    wi = work_ipd
    h, w = grey.shape
    x, y = int(round(centre[0])), int(round(centre[1]))
    lo, hi = max(int(math.floor(RADIUS_LO * wi)), 2), int(math.ceil(RADIUS_HI * wi)) + 1
    if not (hi + 1 <= x < w - hi - 1 and 2 <= y < h - 2):
        return RADIUS_DEFAULT * wi
    row = grey[y - 2 : y + 3].astype(np.float32).mean(0)
    row = np.convolve(row, [0.25, 0.5, 0.25], mode="same")
    d = np.diff(row)  # d[k]: step between k and k+1
    found = []
    for seg, sign in ((d[x + lo : x + hi], 1.0), (d[x - hi : x - lo][::-1], -1.0)):
        s = sign * seg
        k = int(np.argmax(s))
        if s[k] <= 4.0:
            continue
        off = parabola_offset(s[k - 1], s[k], s[k + 1]) if 0 < k < len(s) - 1 else 0.0
        found.append(lo + k + off + 0.5)
    if not found:
        return RADIUS_DEFAULT * wi
    r = float(np.mean(found)) if len(found) == 1 or abs(found[0] - found[1]) < 0.3 * max(found) else min(found)
    return float(np.clip(r, RADIUS_LO * wi, RADIUS_HI * wi))


# ---------------------------------------------------------------------------------------------
# colours: what is the eye's interior


NOT_SKIN_LO, NOT_SKIN_HI = 2.0, 5.0
"""Mahalanobis distances from the nearest skin colour at which a pixel starts to be / is fully
the eye's interior."""


POOL = True
FLOOR = (2.0, 1.0, 1.0)
TRIM = 100.0
LEVELS = True
LEVEL_MAX = 10.0
DARK_MIN = 30.0
"""Shading factors of the extra skin components: the same skin, darker (an eye socket in shadow)."""


@dataclass
class EyeColours:
    """Gaussian colour components (YCrCb, grey levels) of the skin around the eyes, learned
    at calibration: below the eyes, on the upper lids (make-up included), between the eyes.

    :meth:`interior` ramps each pixel's Mahalanobis distance from the nearest component
    from :data:`NOT_SKIN_LO` (skin) to :data:`NOT_SKIN_HI` (surely not skin): sclera, iris,
    pupil and lashes are far from every skin colour, lids are not.
    """

    names: list[str]
    means: np.ndarray  # (k, 3)
    covs: np.ndarray  # (k, 3, 3)
    lo: float = NOT_SKIN_LO
    hi: float = NOT_SKIN_HI
    dark: float = -1.0
    dark_ramp: float = 1.0

    def __post_init__(self) -> None:
        self.means = np.asarray(self.means, dtype=np.float64).reshape(-1, 3)
        self.covs = np.asarray(self.covs, dtype=np.float64).reshape(-1, 3, 3)
        if not len(self.means) or not (len(self.means) == len(self.covs) == len(self.names)):
            raise EyeModelError("eye colours: need at least one skin component with a mean and a covariance each")
        ws, cs = [], []
        for mu, cov in zip(self.means, self.covs):
            L = np.linalg.cholesky(np.linalg.inv(cov))  # z = L^T (ycc - mu) is whitened
            ws.append(L.T @ _YCC)
            cs.append(L.T @ mu)
        self._W = np.concatenate(ws).astype(np.float32)  # (3k, 3)
        self._W4 = np.concatenate([self._W, _YCC[:1].astype(np.float32)])  # and the luminance
        self._c = np.concatenate(cs).astype(np.float32)
        self._starts = np.arange(0, 3 * len(self.means), 3)

    def interior(self, bgr: np.ndarray, gain: np.ndarray | None = None) -> np.ndarray:
        """Interior membership 0..1 (float32, leading shape of ``bgr``) of each pixel.

        ``gain`` (3,) multiplies the pixels' BGR first (the light relative to calibration).
        """
        x = np.asarray(bgr, dtype=np.float32).reshape(-1, 3)
        W = self._W4 if gain is None else self._W4 * np.asarray(gain, dtype=np.float32)[None, :]
        z = x @ W.T  # whitened components, then luminance
        k = len(self.means)
        if k == 1:
            d = z[:, :3] - self._c
            d2 = np.einsum("ij,ij->i", d, d)
        else:
            d = z[:, : 3 * k] - self._c
            d2 = np.add.reduceat(d * d, self._starts, axis=1).min(axis=1)
        e = (np.sqrt(d2) - self.lo) * (1.0 / (self.hi - self.lo))
        if self.dark > 0:
            e = np.maximum(e, (self.dark - z[:, -1]) * (1.0 / self.dark_ramp) + 0.5)
        return np.clip(e, 0.0, 1.0).reshape(np.shape(bgr)[:-1])

    def set_dark(self, skin: list[np.ndarray], iris: np.ndarray) -> None:
        """Also count as interior what is much darker than any skin (a dark iris, the pupil,
        lashes): half-way between the iris's brightness and the darkest skin's, when the two
        differ by at least :data:`DARK_MIN` grey levels."""
        yi = float(np.median(np.asarray(iris, dtype=np.float64).reshape(-1, 3) @ _YCC[0]))
        ys = min(float(np.percentile(np.asarray(g, dtype=np.float64).reshape(-1, 3) @ _YCC[0], 10)) for g in skin if len(g))
        if ys - yi >= DARK_MIN:
            self.dark, self.dark_ramp = yi + 0.5 * (ys - yi), 0.25 * (ys - yi)

    def distance(self, bgr: np.ndarray) -> np.ndarray:
        """Mahalanobis distance of each pixel (``(n, 3)`` BGR) from the nearest skin component."""
        z = np.asarray(bgr, dtype=np.float32).reshape(-1, 3) @ self._W.T - self._c
        return np.sqrt(np.add.reduceat(z * z, self._starts, axis=1).min(axis=1))

    def set_levels(self, parts: list[np.ndarray]) -> None:
        """Centre the interior ramp half-way between the skin and the nearer of the interior's
        ``parts`` (BGR samples: iris, sclera): a blurred lid edge crosses half-way exactly at
        the edge, and colour that bleeds past it stays on the skin side. At least
        :data:`NOT_SKIN_LO` + 1.5, at most :data:`LEVEL_MAX`."""
        if not LEVELS:
            return
        ds = [float(np.median(self.distance(p))) for p in parts if len(p) >= 3]
        if not ds:
            return
        mid = float(np.clip(0.5 * min(ds), NOT_SKIN_LO + 1.5, LEVEL_MAX))
        self.lo, self.hi = mid - 1.5, mid + 1.5

    def to_dict(self) -> dict:
        return {"names": list(self.names), "means": self.means.round(4).tolist(), "covs": self.covs.round(4).tolist(),
                "levels": [self.lo, self.hi], "dark": [self.dark, self.dark_ramp]}

    @classmethod
    def from_dict(cls, d: dict) -> "EyeColours":
        lo, hi = (float(v) for v in d.get("levels", (NOT_SKIN_LO, NOT_SKIN_HI)))
        dk, dr = (float(v) for v in d.get("dark", (-1.0, 1.0)))
        return cls([str(n) for n in d["names"]], np.asarray(d["means"]), np.asarray(d["covs"]), lo, hi, dk, dr)

    @classmethod
    def fit(cls, groups: dict[str, np.ndarray], interior: np.ndarray, doubtful: tuple[str, ...] = ()) -> "EyeColours":
        """Skin components from named groups of BGR skin pixels.

        Each group is trimmed to the :data:`TRIM` % of its pixels nearest its median (a patch
        that caught a lash or a shadow keeps its skin); a group of fewer than 6 pixels, or a
        ``doubtful`` one whose component would call the ``interior`` colours (BGR, e.g. the
        irises) skin, is left out. With :data:`POOL` the groups left make one component.
        """
        inner = np.asarray(interior, dtype=np.float64).reshape(-1, 3) @ _YCC.T
        floor = np.diag(np.asarray(FLOOR, dtype=np.float64) ** 2)
        kept: dict[str, np.ndarray] = {}
        for name, px in groups.items():
            ycc = np.asarray(px, dtype=np.float64).reshape(-1, 3) @ _YCC.T
            if len(ycc) < 6:
                continue
            dist = (np.abs(ycc - np.median(ycc, axis=0)) / _YCC_FLOOR).max(axis=1)
            ycc = ycc[dist <= np.percentile(dist, TRIM)]
            if name in doubtful and len(inner):
                mu, cov = ycc.mean(0), np.cov(ycc.T) + floor
                dv = inner - mu
                if np.median(np.sqrt(np.einsum("ni,ij,nj->n", dv, np.linalg.inv(cov), dv))) < NOT_SKIN_HI + 1.0:
                    continue
            kept[name] = ycc
        if not kept:
            raise EyeModelError("eye model: no skin around the eyes in the calibration crop")
        if POOL:
            kept = {"skin": np.concatenate(list(kept.values()))}
        names = list(kept)
        means = [v.mean(0) for v in kept.values()]
        covs = [np.cov(v.T) + floor for v in kept.values()]
        return cls(names, np.array(means).reshape(-1, 3), np.array(covs).reshape(-1, 3, 3))


# ---------------------------------------------------------------------------------------------
# the model


@dataclass
class EyeModel:
    """What the eye finder learned from the calibration crop (crop px at ``work_ipd``).

    Per eye (lists of two, image-left first): ``radius`` iris radius; ``iris_pictures`` grey
    picture of the iris and the white beside it (iris at its centre); ``eye_pictures`` grey
    picture of the whole eye (the score); ``brow_profiles`` / ``brow_centres`` /
    ``brow_heights`` the brow cross-section through the iris, its middle line's index and
    its height above the iris; ``lid_open`` the calibrated upper + lower lid distance;
    ``lash`` the thickness of the upper lash line where it lies on the white or a light iris
    (the interior run ends on its top; the lid's margin is its bottom).
    ``colours`` the skin and interior colour components; ``skin_bgr`` the median BGR of the
    skin below the eyes (to follow the light) and ``skin_offsets`` where (relative to each
    eye centre) that skin was sampled.
    """

    work_ipd: float
    radius: list[float]
    iris_pictures: list[np.ndarray]
    eye_pictures: list[np.ndarray]
    brow_profiles: list[np.ndarray]
    brow_centres: list[float]
    brow_heights: list[float]
    lid_open: list[float]
    colours: EyeColours
    skin_bgr: np.ndarray
    skin_offsets: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    lash: list[float] = field(default_factory=lambda: [0.0, 0.0])

    IMAGE_NAMES = ("iris_l", "iris_r", "eye_l", "eye_r")
    """Keys of :meth:`images` (grey pictures, saved as 8-bit PNGs beside the calibration)."""

    def images(self) -> dict[str, np.ndarray]:
        """The pictures to save as PNGs (uint8 grey), by name."""
        pics = self.iris_pictures + self.eye_pictures
        return {k: np.clip(np.rint(p), 0, 255).astype(np.uint8) for k, p in zip(self.IMAGE_NAMES, pics)}

    def to_dict(self) -> dict:
        """JSON-able description (pictures are in :meth:`images`)."""
        return {
            "format": FORMAT,
            "work_ipd": self.work_ipd,
            "radius": [float(v) for v in self.radius],
            "images": list(self.IMAGE_NAMES),
            "brow_profiles": [np.asarray(p, dtype=float).round(3).tolist() for p in self.brow_profiles],
            "brow_centres": [float(v) for v in self.brow_centres],
            "brow_heights": [float(v) for v in self.brow_heights],
            "lid_open": [float(v) for v in self.lid_open],
            "lash": [float(v) for v in self.lash],
            "colours": self.colours.to_dict(),
            "skin_bgr": np.asarray(self.skin_bgr, dtype=float).round(3).tolist(),
            "skin_offsets": np.asarray(self.skin_offsets, dtype=float).round(3).tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict, images: dict[str, np.ndarray]) -> "EyeModel":
        """Rebuild from :meth:`to_dict` and the pictures of :meth:`images`; :class:`EyeModelError` if malformed."""
        try:
            if d.get("format") != FORMAT:
                raise EyeModelError(f"eye model: unknown format {d.get('format')!r} (need {FORMAT})")
            pics = []
            for k in cls.IMAGE_NAMES:
                if k not in images or images[k] is None:
                    raise EyeModelError(f"eye model: picture {k!r} is missing")
                p = np.asarray(images[k], dtype=np.float32)
                if p.ndim != 2 or p.shape[0] % 2 == 0 or p.shape[1] % 2 == 0:
                    raise EyeModelError(f"eye model: picture {k!r} must be grey with odd sides, got {p.shape}")
                pics.append(p)
            m = cls(
                work_ipd=float(d["work_ipd"]),
                radius=[float(v) for v in d["radius"]],
                iris_pictures=pics[:2],
                eye_pictures=pics[2:],
                brow_profiles=[np.asarray(p, dtype=np.float32) for p in d["brow_profiles"]],
                brow_centres=[float(v) for v in d["brow_centres"]],
                brow_heights=[float(v) for v in d["brow_heights"]],
                lid_open=[float(v) for v in d["lid_open"]],
                lash=[float(v) for v in d.get("lash", (0.0, 0.0))],
                colours=EyeColours.from_dict(d["colours"]),
                skin_bgr=np.asarray(d["skin_bgr"], dtype=np.float64).reshape(3),
                skin_offsets=np.asarray(d.get("skin_offsets", []), dtype=np.float64).reshape(-1, 2),
            )
        except EyeModelError:
            raise
        except (KeyError, TypeError, ValueError) as e:
            raise EyeModelError(f"eye model: malformed ({type(e).__name__}: {e})") from None
        if len(m.radius) != 2 or len(m.brow_profiles) != 2 or len(m.lid_open) != 2:
            raise EyeModelError("eye model: every per-eye list must have two entries")
        return m


# ---------------------------------------------------------------------------------------------
# results


@dataclass
class EyeObservation:
    """One eye in one frame (crop px).

    ``x, y`` the eye point: the iris centre when the eye is open, the middle of the slit
    between the lids when it is closed; ``score`` 0..1 how much the eye region looks like
    the calibrated eye; ``open`` whether the iris is visible; ``upper`` / ``lower`` the lid
    distances from the eye point along up / down; ``brow`` the brow's middle line above the
    eye point; ``iris`` the iris centre found (even when closed: where the darkest disc was)
    and ``radius`` its radius.
    """

    x: float
    y: float
    score: float
    open: bool
    upper: float
    lower: float
    brow: float
    iris: tuple[float, float]
    radius: float
    brow_score: float = 0.0
    iris_match: float = 0.0

    def points(self) -> dict[str, tuple[float, float]]:
        """Overlay points (crop px): eye point, upper and lower lid, brow."""
        return {
            "eye": (self.x, self.y),
            "upper_lid": (self.x, self.y - self.upper),
            "lower_lid": (self.x, self.y + self.lower),
            "brow": (self.x, self.y - self.brow),
        }


@dataclass
class EyeResult:
    """Both eyes (image-left first)."""

    eyes: tuple[EyeObservation, EyeObservation]

    @property
    def score(self) -> float:
        """The lower of the two eye scores."""
        return min(e.score for e in self.eyes)


# ---------------------------------------------------------------------------------------------
# learning


def calibration_crop(work_ipd: float) -> tuple[int, int, int, int]:
    """A face-frame rectangle ``(x0, y0, w, h)`` that holds everything :func:`learn_eyes` looks at
    when the brows sit up to one work ipd above the eyes (a generous crop also works)."""
    wi = work_ipd
    return (int(math.floor(-1.05 * wi)), int(math.floor(-1.2 * wi)), int(math.ceil(2.1 * wi)), int(math.ceil(1.7 * wi)))


def _skin_offsets(wi: float) -> np.ndarray:
    """Where skin is sampled relative to each eye centre (crop px): below the eye, under the brow
    middle is avoided (it may be a brow), beside the eye towards the nose bridge."""
    return np.array([[-0.12, 0.27], [0.0, 0.3], [0.12, 0.27], [-0.2, 0.2], [0.2, 0.2]]) * wi


def _skin_pixels(crop: np.ndarray, centres: np.ndarray, offsets: np.ndarray, half: int) -> np.ndarray:
    h, w = crop.shape[:2]
    out = []
    for c in centres:
        for o in offsets:
            x, y = int(round(c[0] + o[0])), int(round(c[1] + o[1]))
            x0, x1, y0, y1 = max(x - half, 0), min(x + half + 1, w), max(y - half, 0), min(y + half + 1, h)
            if x1 > x0 and y1 > y0:
                out.append(crop[y0:y1, x0:x1].reshape(-1, 3))
    return np.concatenate(out) if out else np.zeros((0, 3), np.uint8)


BAND = dict(below=(0.15, 0.3), above=(0.14, 0.3), half=0.15)


def _colour_groups(crop, pupils, radius, brow_heights, wi) -> tuple[dict, np.ndarray, np.ndarray, np.ndarray]:
    """BGR samples of the calibration crop for :class:`EyeColours`.

    Skin groups: a band below each eye, a band above it (up to the brow's lower edge) and
    the bridge between the eyes. Also the irises' middles (which no skin component may
    claim), a ring of each iris around its pupil and the sclera beside them.
    """
    h, w = crop.shape[:2]
    below, above, iris, ring, sclera = [], [], [], [], []
    grey = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY).astype(np.float32)
    hx = max(int(round(BAND["half"] * wi)), 2)
    for (px, py), r, hb in zip(pupils, radius, brow_heights):
        xi, yi = int(round(px)), int(round(py))
        x0, x1 = max(xi - hx, 0), min(xi + hx + 1, w)
        b0, b1 = int(round(py + BAND["below"][0] * wi)), int(round(py + BAND["below"][1] * wi)) + 1
        below.append(crop[max(b0, 0) : min(b1, h), x0:x1].reshape(-1, 3))
        a1 = int(round(py - BAND["above"][0] * wi))
        a0 = int(round(py - min(BAND["above"][1] * wi, hb - 0.08 * wi)))
        a0 = min(a0, a1 - 2)
        above.append(crop[max(a0, 0) : max(a1, 0), x0:x1].reshape(-1, 3))
        k = max(int(round(0.4 * r)), 1)
        iris.append(crop[yi - k : yi + k + 1, xi - k : xi + k + 1].reshape(-1, 3))
        # the iris's own colour: a ring around the pupil on the middle rows
        yy, xx = np.mgrid[yi - k : yi + k + 1, xi - int(r) : xi + int(r) + 1]
        rr = np.hypot(xx - px, yy - py)
        ring.append(crop[yy[(rr >= 0.55 * r) & (rr <= 0.85 * r)], xx[(rr >= 0.55 * r) & (rr <= 0.85 * r)]])
        sy = max(int(round(0.2 * r)), 1)
        sa, sb = int(round(1.4 * r)), int(round(1.4 * r + 0.08 * wi))
        ig = float(grey[yi - k : yi + k + 1, xi - k : xi + k + 1].mean())
        for c0, c1 in ((xi - sb, xi - sa), (xi + sa, xi + sb)):
            c0, c1 = max(c0, 0), min(c1 + 1, w)
            pix = crop[yi - sy : yi + sy + 1, c0:c1].reshape(-1, 3)
            g = grey[yi - sy : yi + sy + 1, c0:c1].ravel()
            sclera.append(pix[g > ig + 20.0])
    mx, my = 0.5 * (pupils[0] + pupils[1])
    bx, y0, y1 = max(int(round(0.06 * wi)), 1), int(round(my - 0.05 * wi)), int(round(my + 0.1 * wi)) + 1
    bridge = crop[max(y0, 0) : y1, max(int(round(mx)) - bx, 0) : int(round(mx)) + bx + 1].reshape(-1, 3)
    skin = {"below the eyes": np.concatenate(below), "above the eyes": np.concatenate(above), "between the eyes": bridge}
    return skin, np.concatenate(iris), np.concatenate(ring), np.concatenate(sclera)


def learn_eyes(
    crop_bgr: np.ndarray, crop_grey: np.ndarray, pupils_crop, brows_crop, work_ipd: float
) -> EyeModel:
    """Learn an :class:`EyeModel` from the calibration frame's face crop.

    ``pupils_crop`` (2, 2) the refined iris centres and ``brows_crop`` (2, 2) the brow
    clicks, crop px, image-left first; the crop is in the face frame of ``work_ipd``.
    Raises :class:`EyeModelError` only for unusable input (not a BGR crop, eyes outside it).
    """
    crop = np.asarray(crop_bgr)
    if crop.ndim != 3 or crop.shape[2] != 3 or crop.dtype != np.uint8:
        raise EyeModelError("eye model: the calibration crop must be uint8 BGR")
    grey = np.asarray(crop_grey, dtype=np.float32)
    wi = float(work_ipd)
    pupils = np.asarray(pupils_crop, dtype=np.float64).reshape(2, 2)
    brows = np.asarray(brows_crop, dtype=np.float64).reshape(2, 2)
    h, w = grey.shape
    mx, my = int(math.ceil((SOCKET_HW + 0.05) * wi)), int(math.ceil((LID_RANGE + 0.05) * wi))
    for p in pupils:
        if not (mx <= p[0] < w - mx and my <= p[1] < h - my):
            raise EyeModelError(f"eye model: an eye ({p[0]:.0f}, {p[1]:.0f}) is too close to the crop's edge")

    radius = [iris_radius(grey, tuple(p), wi) for p in pupils]
    iris_pics, eye_pics = [], []
    for p, r in zip(pupils, radius):
        iris_pics.append(subpixel_cut(grey, p[0], p[1], *iris_picture_size(r)))
        eye_pics.append(subpixel_cut(grey, p[0], p[1], _even(SOCKET_HW * wi), _even(SOCKET_HH * wi)))

    # skin below the eyes (also what the light is followed on)
    offs = _skin_offsets(wi)
    skin = _skin_pixels(crop, pupils, offs, max(int(round(0.04 * wi)), 1)).astype(np.float64)
    if len(skin) < 8:
        raise EyeModelError("eye model: no skin around the eyes in the calibration crop")
    skin_bgr = np.median(skin, axis=0)

    # brows: cross-section through each iris, centred on the brow's middle line
    brow_profiles, brow_centres, brow_heights = [], [], []
    half = max(int(round(0.13 * wi)), 4)
    for (px, py), b in zip(pupils, brows):
        top = int(math.floor(py - 1.1 * wi))
        prof = column_profile(grey, px, top, int(py), 2)
        guess = int(round(b[1] - top))
        c = brow_centre(prof, min(max(guess, 0), len(prof) - 1), max(int(round(0.08 * wi)), 3))
        height = py - (top + c)
        if not (0.08 * wi < height < 1.0 * wi):
            height = float(np.clip(py - b[1], 0.15 * wi, 0.9 * wi))
        cy_b = py - height
        start = int(math.floor(cy_b)) - half
        brow_profiles.append(column_profile(grey, px, start, start + 2 * half + 1, brow_half_width(wi)))
        brow_centres.append(half + (cy_b - math.floor(cy_b)))
        brow_heights.append(float(height))

    groups, iris_px, ring_px, sclera_px = _colour_groups(crop, pupils, radius, brow_heights, wi)
    colours = EyeColours.fit(groups, iris_px, doubtful=("above the eyes",))
    colours.set_levels([ring_px, sclera_px])
    if DARK_MIN > 0:
        colours.set_dark(list(groups.values()), iris_px)
    model = EyeModel(
        work_ipd=wi, radius=radius, iris_pictures=iris_pics, eye_pictures=eye_pics, brow_profiles=brow_profiles,
        brow_centres=brow_centres, brow_heights=brow_heights, lid_open=[0.0, 0.0], colours=colours,
        skin_bgr=skin_bgr, skin_offsets=offs,
    )
    # the calibrated lid gap: measured the way the finder measures it
    f = EyeFinder(model, wi)
    for i, p in enumerate(pupils):
        at = (float(p[0]), float(p[1]))
        model.lash[i] = f.lids(crop, i, at, measure_lash=True)[0]
        up, down = f.lids(crop, i, at)
        model.lid_open[i] = max(up + down, 0.05 * wi)
    return model


# ---------------------------------------------------------------------------------------------
# finding


class EyeFinder:
    """Find both eyes in a face crop (see the module docstring).

    ``rect`` is the face-frame rectangle ``(x0, y0, w, h)`` (eye centres at ``(±work_ipd/2, 0)``)
    whose crop holds everything :meth:`find` looks at when the eyes are where predicted.
    """

    def __init__(self, model: EyeModel, work_ipd: float, search: tuple[float, float] = (SEARCH_X, SEARCH_Y)):
        self.model = model
        self.wi = wi = float(work_ipd)
        if abs(wi - model.work_ipd) > 1e-6 * max(wi, 1.0):
            raise ValueError(f"eye model was learned at work ipd {model.work_ipd:g}, not {wi:g}")
        # the coarse search runs at half resolution (pyrDown: half px k is full px 2k), the
        # fine one at full resolution within FINE px of the coarse peak
        self.sx, self.sy = _even(search[0] * wi), _even(search[1] * wi)
        self.slack = (max(int(round(PAIR_SLACK_X * wi / 2)), 1), max(int(round(PAIR_SLACK_Y * wi / 2)), 1))
        self._dilate = np.ones((2 * self.slack[1] + 1, 2 * self.slack[0] + 1), np.uint8)
        self.radius = [float(r) for r in model.radius]
        self._iris = [_even_picture(np.asarray(p, dtype=np.float32)) for p in model.iris_pictures]
        self._iris_half = [cv2.pyrDown(t) for t in self._iris]
        self._box = [max(2 * int(round(0.75 * r)) + 1, 3) for r in self.radius]
        self._cross = [_disc_boxes(0.75 * r) for r in self.radius]
        # both eyes are searched in one half-resolution strip, with the mean radius
        rm = 0.5 * (self.radius[0] + self.radius[1])
        self._cross_half = _disc_boxes(0.375 * rm)
        kx, ky = ring_kernels(0.5 * rm)
        self._ring2 = cv2.merge([kx, ky])
        # a mild preference for irises near the predicted eye centres (half px grid)
        u = np.arange(-(self.sx // 2), self.sx // 2 + 1) * (2.0 / (PRIOR[0] * wi))
        v = np.arange(-(self.sy // 2), self.sy // 2 + 1) * (2.0 / (PRIOR[1] * wi))
        self._prior = np.exp(-0.5 * (v[:, None] ** 2 + u[None, :] ** 2)).astype(np.float32)
        # pads (full px, even) around the candidate centres: the ring, the disc, the iris picture
        self.pad = [
            _even(max(1.4 * r + 4, t.shape[1] // 2 + 2, t.shape[0] // 2 + 2)) for r, t in zip(self.radius, self._iris)
        ]
        self._eye = [_even_picture(np.asarray(p, dtype=np.float32)) for p in model.eye_pictures]
        self._eye_half = [cv2.pyrDown(t) for t in self._eye]
        self._socket_search = (max(int(round(SOCKET_SEARCH[0] * wi / 2)), 1), max(int(round(SOCKET_SEARCH[1] * wi / 2)), 1))
        self.lid_range = int(math.ceil(LID_RANGE * wi))
        self.lid_hw = [max(1, int(round(LID_HW * r))) for r in self.radius]
        self.colours = model.colours
        self._luma = _YCC[:1].astype(np.float32).reshape(1, 3)
        # a step this large (grey levels) from the lash line to what is under it is a lid margin
        self._lash_contrast = 25.0
        self._skin_half = max(int(round(0.04 * wi)), 1)
        if BROW_ABS:
            self.brow_lo = [max(h - BROW_DOWN * wi, 0.1 * wi) for h in model.brow_heights]
            self.brow_hi = [h + BROW_UP * wi for h in model.brow_heights]
        else:
            self.brow_lo = [BROW_LO * h for h in model.brow_heights]
            self.brow_hi = [BROW_HI * h for h in model.brow_heights]
        # the brow cross-sections, zero mean and unit spread (the correlation is then one product)
        self._brow_hw = brow_half_width(wi)
        self._brow_z = [_standardised(np.asarray(p, dtype=np.float32)) for p in model.brow_profiles]
        # crop rectangle
        hw_e = max(self.sx + self.pad[i] for i in range(2))
        hh_e = max(self.sy + self.pad[i] for i in range(2))
        top = max(self.brow_hi[i] + len(model.brow_profiles[i]) for i in range(2)) + self.sy + 3
        top = max(top, hh_e, self.lid_range + self.sy + 2, SOCKET_HH * wi + self.sy + 2)
        bottom = max(hh_e, self.lid_range + self.sy + 2, SOCKET_HH * wi + self.sy + 2, 0.32 * wi + self.sy + 2)
        left = 0.5 * wi + max(hw_e, SOCKET_HW * wi + self.sx + 2, 0.25 * wi + self.sx + 2) + 1
        self.rect = (int(math.floor(-left)), int(math.floor(-top)), int(math.ceil(2 * left)), int(math.ceil(top + bottom)))

    # ------------------------------------------------------------------ pieces
    @staticmethod
    def _disc_mean(img: np.ndarray, boxes: tuple[tuple[int, int], ...]) -> np.ndarray:
        """Mean of ``img`` over a disc at every pixel, as the average of a few centred boxes."""
        out = cv2.boxFilter(img, -1, boxes[0])
        for b in boxes[1:]:
            out += cv2.boxFilter(img, -1, b)
        return out * (1.0 / len(boxes))

    @staticmethod
    def _cut(img: np.ndarray, x0: int, y0: int, w: int, h: int) -> np.ndarray:
        """``img[y0:y0+h, x0:x0+w]`` as float32, the border repeated where it reaches outside."""
        H, W = img.shape[:2]
        if x0 < 0 or y0 < 0 or x0 + w > W or y0 + h > H:
            a, b = max(x0, 0), max(y0, 0)
            part = img[b : min(y0 + h, H), a : min(x0 + w, W)]
            if part.size == 0:
                return np.zeros((h, w), np.float32)
            part = cv2.copyMakeBorder(
                np.ascontiguousarray(part), b - y0, max(y0 + h - H, 0), a - x0, max(x0 + w - W, 0), cv2.BORDER_REPLICATE
            )
            return part.astype(np.float32, copy=False)
        return np.asarray(img[y0 : y0 + h, x0 : x0 + w], dtype=np.float32)

    def fine(self, grey: np.ndarray, i: int, x: int, y: int) -> tuple[float, float, float]:
        """Sub-pixel iris centre near full-res ``(x, y)``: darkness of a box of the iris's size ×
        (1 + correlation with the iris picture) on the candidates within :data:`FINE` px, a
        parabola through the best; also the correlation there."""
        t = self._iris[i]
        th, tw = t.shape[0] // 2, t.shape[1] // 2
        b = self._box[i] // 2
        m = max(th, tw, b)
        win = self._cut(grey, x - FINE - m, y - FINE - m, 2 * (FINE + m) + 1, 2 * (FINE + m) + 1)
        n = 2 * FINE + 1
        ncc = cv2.matchTemplate(win[m - th : m + n + th, m - tw : m + n + tw], t, cv2.TM_CCOEFF_NORMED)
        D = self._disc_mean(win, self._cross[i])[m : m + n, m : m + n]
        level = max(float(np.max(win[m : m + n, m : m + n])), 8.0)
        s = np.maximum(level - D, 0.0) * (1.0 + np.maximum(ncc, 0.0))
        ky, kx = divmod(int(np.argmax(s)), s.shape[1])
        fx = parabola_offset(s[ky, kx - 1], s[ky, kx], s[ky, kx + 1]) if 0 < kx < n - 1 else 0.0
        fy = parabola_offset(s[ky - 1, kx], s[ky, kx], s[ky + 1, kx]) if 0 < ky < n - 1 else 0.0
        return x - FINE + kx + fx, y - FINE + ky + fy, float(ncc[ky, kx])

    def coarse_maps(self, grey: np.ndarray, centres: np.ndarray):
        """Half-resolution iris score maps of both eyes' candidate windows, and the crop px of
        each map's (0, 0). Score: darkness of a disc against the strip's median × (1 + ring
        votes: gradients pointing away from the centre on the calibrated ring) × (1 +
        correlation with the eye's iris picture)."""
        p = max(self.pad)
        cs = [(2 * int(round(c[0] / 2)), 2 * int(round(c[1] / 2))) for c in centres]
        x0 = min(c[0] for c in cs) - self.sx - p
        y0 = min(c[1] for c in cs) - self.sy - p
        x1 = max(c[0] for c in cs) + self.sx + p
        y1 = max(c[1] for c in cs) + self.sy + p
        strip = self._cut(grey, x0, y0, x1 - x0 + 2, y1 - y0 + 2)
        half = cv2.resize(strip, (strip.shape[1] // 2, strip.shape[0] // 2), interpolation=cv2.INTER_AREA)
        ph = p // 2
        sub = half[::2, ::2].ravel()
        k = sub.size // 2
        level = max(float(np.partition(sub, k)[k]), 8.0)
        dark = np.maximum(level - self._disc_mean(half, self._cross_half), 0.0) * (1.0 / level)
        # ring votes over the strip's inner part (ph from its border)
        gx = cv2.Sobel(half, cv2.CV_32F, 1, 0, ksize=3)
        gy = cv2.Sobel(half, cv2.CV_32F, 0, 1, ksize=3)
        mag = cv2.magnitude(gx, gy)
        m = mag.size // 2
        t = max(float(np.partition(mag.ravel(), m)[m]), 1.0)
        wgt = np.minimum(mag * (1.0 / t), 3.0) / (mag + 1e-3)
        kh, kw = self._ring2.shape[0] // 2, self._ring2.shape[1] // 2
        g2 = cv2.merge([gx * wgt, gy * wgt])[ph - kh : half.shape[0] - ph + kh, ph - kw : half.shape[1] - ph + kw]
        votes = np.maximum(cv2.matchTemplate(g2, self._ring2, cv2.TM_CCORR), 0.0) * (1.0 / 3.0)
        maps, origins = [], []
        sxh, syh = self.sx // 2, self.sy // 2
        for i, (cx, cy) in enumerate(cs):
            # candidate (u, v) of this eye in the inner part <-> half px (ph + u, ph + v)
            u0, v0 = (cx - x0) // 2 - sxh - ph, (cy - y0) // 2 - syh - ph
            ws, hs = 2 * sxh + 1, 2 * syh + 1
            tpl = self._iris_half[i]
            th, tw = tpl.shape[0] // 2, tpl.shape[1] // 2
            win = half[ph + v0 - th : ph + v0 + hs + th, ph + u0 - tw : ph + u0 + ws + tw]
            ncc = cv2.matchTemplate(win, tpl, cv2.TM_CCOEFF_NORMED)
            sc = dark[ph + v0 : ph + v0 + hs, ph + u0 : ph + u0 + ws] * (1.0 + votes[v0 : v0 + hs, u0 : u0 + ws])
            maps.append(sc * (1.0 + np.maximum(ncc, 0.0)) * self._prior)
            # half px k is the mean of full px 2k and 2k+1 of the strip
            origins.append((x0 + 2 * (ph + u0) + 0.5, y0 + 2 * (ph + v0) + 0.5))
        return maps, origins

    def locate_irises(self, grey: np.ndarray, centres: np.ndarray) -> list[tuple[float, float, float]]:
        """The two iris centres (crop px, sub-pixel) and their iris-picture correlations near the
        predicted eye ``centres``: the best pair of the two half-resolution score maps, each eye
        free to move by the slack against the other, then each refined at full resolution."""
        maps, origins = self.coarse_maps(grey, centres)
        J = cv2.dilate(maps[0], self._dilate) + cv2.dilate(maps[1], self._dilate)
        jy, jx = divmod(int(np.argmax(J)), J.shape[1])
        sx, sy = self.slack
        out = []
        for i, (m, (ox, oy)) in enumerate(zip(maps, origins)):
            ya, xa = max(jy - sy, 0), max(jx - sx, 0)
            sub = m[ya : jy + sy + 1, xa : jx + sx + 1]
            ky, kx = divmod(int(np.argmax(sub)), sub.shape[1])
            out.append(self.fine(grey, i, int(round(ox + 2 * (kx + xa))), int(round(oy + 2 * (ky + ya)))))
        return out

    def middle(self, crop: np.ndarray, at: tuple[float, float], gain: np.ndarray | None = None) -> float:
        """x (crop px) of the middle of the visible eye on the row of ``at``: halfway between the
        ends of the interior run left and right of it (``at[0]`` when a run reaches its limit)."""
        h, w = crop.shape[:2]
        H = int(round(MIDDLE_RANGE * self.wi))
        xi, yi = int(round(at[0])), min(max(int(round(at[1])), 1), h - 2)
        x0, x1 = max(xi - H, 0), min(xi + H + 1, w)
        e = self.colours.interior(crop[yi - 1 : yi + 2, x0:x1], gain).mean(axis=0)
        c = xi - x0
        left, right = _run(e[c::-1]), _run(e[c:])
        if left >= c - 1 or right >= x1 - xi - 2:
            return float(at[0])
        return float(xi + 0.5 * (right - left))

    def lids(
        self, crop: np.ndarray, i: int, at: tuple[float, float], gain: np.ndarray | None = None,
        column: float | None = None, measure_lash: bool = False,
    ) -> tuple[float, float]:
        """``(upper, lower)`` lid distances (crop px) from ``at`` of eye ``i``: soft lengths of the
        eye-interior runs up and down a strip of columns through ``column`` (default ``at[0]``),
        starting on the row of ``at``; the calibrated lash line is taken off the upper one.
        With ``measure_lash`` (calibration) it returns ``(lash line thickness, 0)`` instead."""
        h, w = crop.shape[:2]
        hw, R = self.lid_hw[i], self.lid_range
        xi = min(max(int(round(at[0] if column is None else column)), hw), w - 1 - hw)
        yi = min(max(int(round(at[1])), 0), h - 1)
        y0, y1 = max(yi - R, 0), min(yi + R + 1, h)
        strip = crop[y0:y1, xi - hw : xi + hw + 1]
        # classify each row's mean colour (the strip's columns average the noise away)
        e = self.colours.interior(strip.mean(axis=1, dtype=np.float32), gain)
        c = yi - y0
        dy = yi - at[1]
        up = _run(e[c::-1])
        if measure_lash:
            return up - self._below_lashes(strip, c, up), 0.0
        down = _run(e[c:])
        if SNAP_LOWER:
            down = self._snap_edge(strip, c, down)
        return max(up - self.model.lash[i] - dy, 0.0), max(down + dy, 0.0)

    def _snap_edge(self, strip: np.ndarray, c: int, down: float) -> float:
        """The lower run's end moved to the strongest brightness step within a few px inside it
        (colour bleeds a little past the lid in compressed video; brightness does not)."""
        lum = cv2.transform(np.ascontiguousarray(strip), self._luma).mean(axis=1).ravel()
        k = int(c + math.floor(down))
        lo, hi = max(k - SNAP_LOWER, c + 1), min(k + 1, len(lum) - 1)
        if hi <= lo:
            return down
        steps = np.abs(lum[lo + 1 : hi + 1] - lum[lo:hi])
        j = int(np.argmax(steps))
        if steps[j] < 0.5 * self._lash_contrast:
            return down
        return float(lo + j + 0.5 - c)

    def _below_lashes(self, strip: np.ndarray, c: int, up: float) -> float:
        """The upper run ``up`` (from row ``c`` of ``strip`` upwards) ended on the lash line's top;
        the lid's margin is its bottom where the line sits on the white or a light iris: the
        strongest step from light (below) to dark (above) within :data:`LASH_STEP` × work ipd
        under the run's end, if it is a clear one."""
        lum = cv2.transform(np.ascontiguousarray(strip), self._luma).mean(axis=1).ravel()
        k = int(c - math.floor(up))
        m = int(math.ceil(LASH_STEP * self.wi))
        lo, hi = max(k, 1), min(k + m, c)
        if hi <= lo:
            return up
        steps = lum[lo + 1 : hi + 1] - lum[lo:hi]  # brighter going down
        j = int(np.argmax(steps))
        if steps[j] < self._lash_contrast:
            return up
        return float(c - (lo + j + 0.5))

    def _gain(self, crop: np.ndarray, centres: np.ndarray) -> np.ndarray | None:
        """Per-channel gain that brings the skin below the eyes back to its calibrated colour
        (median over the sampled patches' means); None when within 2 %."""
        h, w = crop.shape[:2]
        b = self._skin_half
        means = []
        for cx, cy in centres:
            for ox, oy in self.model.skin_offsets:
                x, y = int(round(cx + ox)), int(round(cy + oy))
                if b <= x < w - b and b <= y < h - b:
                    means.append(cv2.mean(crop[y - b : y + b + 1, x - b : x + b + 1])[:3])
        if len(means) < 3:
            return None
        med = np.median(np.asarray(means), axis=0)
        g = np.clip(np.asarray(self.model.skin_bgr) / np.maximum(med, 1.0), 0.5, 2.0)
        return None if np.all(np.abs(g - 1.0) < 0.02) else g

    def _socket_score(self, grey: np.ndarray, at: tuple[float, float], i: int) -> float:
        """Best normalised correlation (0..1) of the calibrated eye picture around ``at``, at half
        resolution: as far sideways as a gaze moves the iris in the eye, a little up and down."""
        t = self._eye_half[i]
        th, tw = t.shape[0] // 2, t.shape[1] // 2
        sx, sy = self._socket_search
        x, y = 2 * int(round(at[0] / 2)), 2 * int(round(at[1] / 2))
        w, h = 2 * (tw + sx) + 2, 2 * (th + sy) + 2
        win = self._cut(grey, x - w // 2, y - h // 2, w, h)
        half = cv2.resize(win, (w // 2, h // 2), interpolation=cv2.INTER_AREA)
        ncc = cv2.matchTemplate(half, t, cv2.TM_CCOEFF_NORMED)
        return float(np.clip(ncc.max(), 0.0, 1.0))

    def _slit(self, crop: np.ndarray, at: tuple[float, float], gain) -> tuple[float, float]:
        """Centroid of what is not skin around ``at`` (a closed eye: the slit between the lids)."""
        h, w = crop.shape[:2]
        hx, hy = int(round(0.22 * self.wi)), int(round(0.1 * self.wi))
        x, y = at
        for _ in range(2):
            xi, yi = int(round(x)), int(round(y))
            x0, x1, y0, y1 = max(xi - hx, 0), min(xi + hx + 1, w), max(yi - hy, 0), min(yi + hy + 1, h)
            e = self.colours.interior(crop[y0:y1, x0:x1], gain)
            tot = float(e.sum())
            if tot < 1.0:
                break
            x = x0 + float((e.sum(axis=0) * np.arange(x1 - x0)).sum()) / tot
            y = y0 + float((e.sum(axis=1) * np.arange(y1 - y0)).sum()) / tot
        return x, y

    def _brow(self, grey: np.ndarray, at: tuple[float, float], i: int) -> tuple[float, float]:
        """Brow height above ``at`` (crop px) and the match there: the calibrated cross-section
        slid along a strip of columns above ``at``, normalised correlation, parabola refined."""
        px, py = at
        t = self._brow_z[i]
        n = len(t)
        c = self.model.brow_centres[i]
        top = int(math.floor(py - self.brow_hi[i] - c)) - 1
        bot = int(math.ceil(py - self.brow_lo[i] - c)) + n + 1
        prof = column_profile(grey, px, top, bot, self._brow_hw)
        if len(prof) < n + 2:
            return self.model.brow_heights[i], 0.0
        win = sliding_window_view(prof, n)
        mu = win.mean(axis=1)
        sd = np.sqrt(np.maximum((win * win).mean(axis=1) - mu * mu, 1e-6))
        score = (win @ t) * (1.0 / n) / sd
        k = int(np.argmax(score))
        d = parabola_offset(score[k - 1], score[k], score[k + 1]) if 0 < k < len(score) - 1 else 0.0
        return float(py - (top + k + d + c)), float(score[k])

    # ------------------------------------------------------------------ main entry
    def find(self, crop_bgr: np.ndarray, crop_grey: np.ndarray, eye_centres_crop) -> EyeResult:
        """Both eyes in a face crop (uint8 BGR and its grey, any dtype), searched around the
        predicted eye centres ``eye_centres_crop`` (2, 2) crop px, image-left first."""
        centres = np.asarray(eye_centres_crop, dtype=np.float64).reshape(2, 2)
        found = self.locate_irises(crop_grey, centres)
        gain = self._gain(crop_bgr, centres)
        grey = crop_grey
        eyes = []
        for i in range(2):
            iris = found[i][:2]
            up, down = self.lids(crop_bgr, i, iris, gain, self.middle(crop_bgr, iris, gain) if LID_AT_MIDDLE else None)
            is_open = up + down >= CLOSED_BELOW * self.model.lid_open[i]
            pt = iris
            if is_open and VISIBLE_CENTROID:
                off = visible_offset(self.radius[i], up, down)
                pt = (iris[0], iris[1] + off)
                up, down = up + off, down - off
            if not is_open:
                pt = self._slit(crop_bgr, iris, gain)
                up, down = self.lids(crop_bgr, i, pt, gain, self.middle(crop_bgr, pt, gain) if LID_AT_MIDDLE else None)
            score = self._socket_score(grey, pt, i)
            brow, bscore = self._brow(grey, pt, i)
            eyes.append(EyeObservation(
                x=float(pt[0]), y=float(pt[1]), score=score, open=bool(is_open), upper=float(up), lower=float(down),
                brow=brow, iris=(float(iris[0]), float(iris[1])), radius=self.radius[i], brow_score=bscore,
                iris_match=float(found[i][2]),
            ))
        return EyeResult((eyes[0], eyes[1]))


RUN_MODE = "run"
RUN_GAIN = 2.0
def visible_offset(r: float, upper: float, lower: float) -> float:
    """Offset (down, px) from a disc's centre to the centroid of its part between ``upper``
    above and ``lower`` below the centre (the visible iris between the lids)."""
    t, b = -min(max(upper, 0.0), r), min(max(lower, 0.0), r)
    if b - t < 1e-3:
        return 0.5 * (t + b)

    def area(y):  # integral of 2 sqrt(r^2 - y^2)
        return y * math.sqrt(max(r * r - y * y, 0.0)) + r * r * math.asin(max(min(y / r, 1.0), -1.0))

    def moment(y):  # integral of 2 y sqrt(r^2 - y^2)
        return -(2.0 / 3.0) * max(r * r - y * y, 0.0) ** 1.5

    a = area(b) - area(t)
    return (moment(b) - moment(t)) / a if a > 1e-9 else 0.5 * (t + b)


def _run(e: np.ndarray) -> float:
    """Soft length of the interior run starting at ``e[0]``: each sample counts as much as it
    and every sample before it are interior (membership doubled, so half-interior counts
    fully); the start sample counts by half (the run starts in its middle)."""
    if not len(e):
        return 0.0
    if RUN_MODE == "product":
        s = np.cumprod(np.minimum(RUN_GAIN * e, 1.0))
        return float(s.sum() - 0.5 * s[0])
    bad = e < 0.5
    stop = bad[1:-1] & bad[2:] if len(e) > 2 else bad[1:]
    k = int(np.argmax(stop)) + 1 if stop.any() else len(e)
    return 0.5 * float(e[0]) + float(e[1:k].sum())


# ---------------------------------------------------------------------------------------------
# calibration help


_NO_COLOURS = EyeColours(["skin"], np.zeros((1, 3)), np.array([np.eye(3)]))
"""Placeholder colours of the throw-away model :func:`refine_pupils` searches irises with
(it never looks at lids)."""


def refine_pupils(
    frame_grey: np.ndarray, left: tuple[float, float], right: tuple[float, float], iterations: int = 2
) -> tuple[tuple[float, float], tuple[float, float]]:
    """Snap two clicked pupils (frame px) to the iris centres near them (sub-pixel, frame px).

    Searches within about a fifth of the clicked inter-pupil distance, both eyes together,
    with the radius measured at the clicks. Returns the clicks unchanged if nothing
    iris-like is found (a real face is never refused).
    """
    grey = np.asarray(frame_grey)
    if grey.ndim == 3:
        grey = cv2.cvtColor(grey, cv2.COLOR_BGR2GRAY)
    from tracker.calibration import FaceFrame

    lp, rp = (float(left[0]), float(left[1])), (float(right[0]), float(right[1]))
    for _ in range(iterations):
        ipd = math.hypot(rp[0] - lp[0], rp[1] - lp[1])
        if ipd < 8:
            return lp, rp
        wi = min(ipd, 80.0)
        ff = FaceFrame.from_pupils(lp, rp, wi)
        rect = (int(math.floor(-0.9 * wi)), int(math.floor(-0.4 * wi)), int(math.ceil(1.8 * wi)), int(math.ceil(0.8 * wi)))
        crop = ff.crop(grey, rect).astype(np.float32)
        o = np.array(rect[:2], dtype=np.float64)
        centres = np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]]) - o
        radius = [iris_radius(crop, tuple(c), wi) for c in centres]
        iris_pics = [subpixel_cut(crop, c[0], c[1], *iris_picture_size(r)) for c, r in zip(centres, radius)]
        model = EyeModel(
            work_ipd=wi, radius=radius, iris_pictures=iris_pics, eye_pictures=[np.zeros((3, 3), np.float32)] * 2,
            brow_profiles=[np.zeros(3, np.float32)] * 2, brow_centres=[1.0, 1.0], brow_heights=[0.4 * wi] * 2,
            lid_open=[1.0, 1.0], colours=_NO_COLOURS, skin_bgr=np.ones(3),
        )
        f = EyeFinder(model, wi, search=(0.12, 0.08))
        found = np.array([q[:2] for q in f.locate_irises(crop, centres)]) + o
        img = ff.to_image(np.array(found))
        nl, nr = (float(img[0, 0]), float(img[0, 1])), (float(img[1, 0]), float(img[1, 1]))
        nipd = math.hypot(nr[0] - nl[0], nr[1] - nl[1])
        if not (0.8 * ipd < nipd < 1.25 * ipd):
            return lp, rp
        lp, rp = nl, nr
    return lp, rp
