"""Calibration from the five clicks: everything the tracker learns about one performer.

From the clicked frame ``calibrate`` learns colour classifiers (pupil vs. its surroundings,
lip vs. skin, skin vs. eye interior for the lids), a stored grey picture of each eye, a
vertical cross-section of each eyebrow, the inter-pupil distance and the neutral values.
Clicks may be a few pixels off; pupils, brows and the mouth are snapped to the features.

All pictures and profiles live in the *face frame*: an upright crop centred on the pupil
midpoint, x along the pupil line, y along the face's down axis, scaled so the inter-pupil
distance is ``work_ipd`` pixels (:data:`WORK_IPD_MIN` to :data:`WORK_IPD_MAX`). The tracker crops every
frame the same way, so rolling or leaning in changes nothing the finders see.

Saved as JSON (``format`` 2) with PNGs beside it: the two eye pictures and the three baked
colour tables (one grey image, three 512×512 tiles stacked top to bottom), so loading is a
file read rather than a rebuild (the image is what classifies; the colour models stay in
the JSON to inspect and to rebuild from). ``format`` 1 files (no table image) still load:
their tables are rebuilt from the models.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from tracker import atomic_file, safe_json
from tracker.brows import brow_centre, column_profile
from tracker.clicks import PIXEL_CENTRE, Clicks, ClicksError
from tracker.colour_model import TILE_SHAPE, ColourClassifier, Gaussians, features, table_to_tile, tile_to_table
from tracker.eyes import EyeModel, EyeModelError, learn_eyes, refine_pupils, side_glance
from tracker.eyes import calibration_crop as eye_calibration_crop
from tracker.mouth_finder import SCORE_OK, MouthFinder, MouthResult
from tracker.mouth_model import MOUTH_RECT, MouthModel, learn_mouth
from tracker.params import FaceParams

FORMAT = 2
READABLE_FORMATS = (1, 2)
CLASSIFIERS = ("pupil", "lip", "eye")
"""Order of the colour tables in the table image."""
WORK_IPD_MAX = 80.0
"""Largest inter-pupil distance (px) the finders work at; bigger faces are scaled down."""
WORK_IPD_MIN = 80.0
"""Smallest inter-pupil distance (px) the finders work at; smaller faces (a low-resolution camera, a
face far away) are scaled up, bilinearly. At 35–55 px between the eyes a lid gap is two or three
pixels and the finders' whole-pixel floors (walks, bands, templates) take over; on the upsampled
crop the lids, pupils and lips fall between pixels smoothly (the shared real clips at a half and a
third of their size: eye-opening target met on 22 of 27 clip runs instead of 18, fewer lost frames
and mouths off the mouth). Small faces then cost what a large one does."""
SNAP_REACH = 0.12
"""Farthest (× the clicked inter-pupil distance) a clicked pupil is snapped to a dark disc."""
CONSENSUS_SHIFTS = ((0.0, 0.0), (0.7, 0.7), (-0.7, 0.7), (0.7, -0.7), (-0.7, -0.7))
"""Shifts (face px) of the crops the eye and mouth models are each learned from; the model kept
is the one whose measurements sit in the middle of all (:func:`consensus`). One frame's lid gap
and lip thicknesses can come out in one of two readings (a walk that stops at the lash line or at
the lid's margin, a lower lip read with or without its shaded half), and which one depended on
where the crop's pixels fell: on the shared clips, clicks moved by one pixel read expr_d6's lower
lip as 16 or as 5 px and expr_d19's lid gap as 1.15 or 1.34 iris radii — and the tracker's results
with them. Measured over eight one-pixel moves of the clicks on the nine shared clips (realfaces
--jitter, misses of 72 runs, clicks / --auto): 24 / 25 with both models by consensus, 23 / 28 with
the eyes only; the stress matrix 186 and 182 clip-modes of 324 meeting every target. expr_d19's eyes
(lost on 0-1.2 % of the frames, her lid gap either side of the blind-gap rule's threshold) are lost
on none with it; expr_d6's mouth opening is the one figure that was better without the mouth's
consensus (r 0.53 / 0.56 against 0.46 / 0.50)."""
RIGID_OPEN = 0.1
"""How far (× wi) below an open calibration mouth's upper inner lip edge the line of that mouth at
rest may lie; the rigid place moves up to there (None: it stays on the open mouth's line)."""
RIGID_STEPS = 3
"""Looks the mouth finder takes on the calibration frame for the height of the mouth's rigid place: each
with the crop and the prediction where the last one put its line's centre, as the tracker will look on
that frame. Only the height: an open mouth at calibration moves it, and across the face the corners'
midpoint is as good as the finder's (moving it too left a bearded grin's corners a pixel past the
search's reach: two of eight one-pixel moves of --auto's points lost a quarter of the frames)."""
WHOLE_MOUTH = 0.1
"""How far (× wi) outside its lips' outer edges the line between a calibration look's corners may lie
for the look to have found the mouth (:func:`found_mouth`). A look along a moustache's lower edge
lies up to 0.07 wi over the lips' top (the painted beards round expr_d0 and expr_d18): the tracker's
finder takes that edge too, and a rigid place kept off it refused the tracked line as too high
(bearded expr_d0 with ``--auto``: 19 % of its frames lost with no tolerance; bearded expr_d18 with
the clicks: opening r 0.97 -> 0.90 with 0.05 wi). A look along the shadow under the nose lies 0.11
(a laughing man's photo) to 0.16 wi (a smiling astronaut's) over them."""


class CalibrationError(ValueError):
    """Calibration failed or a calibration file is unusable (one-line message)."""


# ---------------------------------------------------------------------------------------------
# the face frame


@dataclass
class FaceFrame:
    """An upright, scale-normalised frame attached to the face.

    ``mid`` is the pupil midpoint (frame px), ``angle`` the roll in radians (positive when
    the image-right pupil is higher), ``scale`` face-frame px per frame px. Face
    coordinates: x along the pupil line towards the image-right pupil, y along the face's
    down axis, origin at ``mid``.
    """

    mid: tuple[float, float]
    angle: float
    scale: float

    @classmethod
    def from_pupils(cls, left: tuple[float, float], right: tuple[float, float], work_ipd: float) -> "FaceFrame":
        dx, dy = right[0] - left[0], right[1] - left[1]
        ipd = math.hypot(dx, dy)
        return cls(
            mid=(0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1])),
            angle=math.atan2(-dy, dx),
            scale=work_ipd / max(ipd, 1e-6),
        )

    def __post_init__(self) -> None:
        c, s = math.cos(self.angle), math.sin(self.angle)
        self._cs = (c, s)
        self._R = np.array([[c, -s], [s, c]])  # rows: the face's x and down axes
        self._u, self._d = self._R
        self._m = np.array([float(self.mid[0]), float(self.mid[1])])
        # frame px = mid + (face x, face y) @ _back
        self._back = self._R / self.scale

    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit vectors (frame px) of the face's x and down axes."""
        return self._u, self._d

    def matrix(self, origin: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """2×3 affine from frame px to crop px, where a crop's (0,0) is face point ``origin``."""
        c, s = self._cs
        k = self.scale
        mx, my = float(self.mid[0]), float(self.mid[1])
        return np.array(
            [
                [k * c, k * -s, -k * (mx * c + my * -s) - origin[0]],
                [k * s, k * c, -k * (mx * s + my * c) - origin[1]],
            ]
        )

    def crop(self, image: np.ndarray, rect: tuple[int, int, int, int], out: np.ndarray | None = None) -> np.ndarray:
        """The face-frame crop ``(x0, y0, w, h)`` (face px) of ``image``, bilinear.

        ``out`` (optional) is a buffer of the crop's shape and dtype to write into and return.
        """
        x0, y0, w, h = rect
        return cv2.warpAffine(
            image, self.matrix((x0, y0)), (int(w), int(h)), dst=out, flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )

    def to_image(self, pts: np.ndarray) -> np.ndarray:
        """Face coordinates ``(n, 2)`` to frame px."""
        return self._m + np.asarray(pts, dtype=np.float64).reshape(-1, 2) @ self._back

    def to_face(self, pts: np.ndarray) -> np.ndarray:
        """Frame px ``(n, 2)`` to face coordinates."""
        p = np.asarray(pts, dtype=np.float64).reshape(-1, 2) - self._m
        return self.scale * (p @ self._R.T)


# ---------------------------------------------------------------------------------------------
# the calibration record


@dataclass
class Calibration:
    """What the tracker knows about one performer (lengths in face-frame px unless noted).

    ``ipd`` and ``frame_size`` are in frame px; ``work_ipd`` is the inter-pupil distance in
    the face frame. ``clicks`` (the refined pupils and mouth centre) are in OpenCV's pixel
    convention, as everything the tracker keeps: half a pixel from the clicks file's
    (:data:`~tracker.clicks.PIXEL_CENTRE`). Geometry (``brow_height``, ``mouth_offset`` …) is
    measured on the calibration frame relative to the pupils.
    """

    frame_size: tuple[int, int]
    ipd: float
    roll_deg: float
    work_ipd: float
    clicks: Clicks
    eye_templates: list[np.ndarray]
    brow_profiles: list[np.ndarray]
    brow_centres: list[float]
    brow_heights: list[float]
    lid_up: list[float]
    lid_down: list[float]
    mouth_offset: tuple[float, float]
    mouth_width: float
    mouth_height: float
    mouth_area: float
    pupil_radius: float
    pupil_threshold: float
    pupil: ColourClassifier
    lip: ColourClassifier
    eye: ColourClassifier
    lip_axis: np.ndarray
    neutral: FaceParams = field(default_factory=FaceParams)
    white_threshold: float | None = None
    iris_level: float | None = None
    eye_ref: tuple[float, float, float] | None = None
    mouth_ref: tuple[float, float, float] | None = None
    face_patch: np.ndarray | None = None
    """The upright grey face picture (brows, eyes, nose; :func:`tracker.face_finder.face_patch`)
    that tells this face from anything else; None in files from before it existed."""
    face_box_eyes: tuple[tuple[float, float], tuple[float, float]] | None = None
    """Where the pupils sat inside the face detector's box on the calibration frame (fractions)."""
    eye_model: EyeModel | None = None
    """This performer's eyes for :class:`tracker.eyes.EyeFinder`; None in older files, which
    track with the eye-picture, lid-walk and brow finders of ``pupils``, ``lids`` and ``brows``."""
    mouth_model: MouthModel | None = None
    """This performer's lips, gap and inside (:mod:`tracker.mouth_model`); None in older files,
    which track with the plain lip-blob finder of :mod:`tracker.mouth`."""

    @property
    def classifiers(self) -> dict[str, object]:
        """The colour classes the tracker tells apart, each with ``mask(bgr) -> bool array``
        (for showing what calibration learned): the eye's inside, the lips and the mouth's
        inside for a calibration with eye and mouth models, else the first tracker's pupil,
        lip and eye colours."""
        if self.eye_model is None or self.mouth_model is None:
            return {"pupil": self.pupil, "lip": self.lip, "eye": self.eye}
        return {"eye": _EyeInsideMask(self.eye_model), "lip": _LipMask(self.mouth_model),
                "mouth inside": _MouthInsideMask(self.mouth_model)}

    # -------------------------------------------------------------- persistence
    def to_dict(self, stem: str) -> dict:
        return {
            "format": FORMAT,
            "kind": "inkface-calibration",
            "frame_size": list(self.frame_size),
            "ipd": self.ipd,
            "roll_deg": self.roll_deg,
            "work_ipd": self.work_ipd,
            "clicks": self.clicks.to_dict(),
            "eye_templates": [f"{stem}.eye_l.png", f"{stem}.eye_r.png"],
            "brow_profiles": [p.astype(float).round(4).tolist() for p in self.brow_profiles],
            "brow_centres": list(self.brow_centres),
            "brow_heights": list(self.brow_heights),
            "lid_up": list(self.lid_up),
            "lid_down": list(self.lid_down),
            "mouth_offset": list(self.mouth_offset),
            "mouth_width": self.mouth_width,
            "mouth_height": self.mouth_height,
            "mouth_area": self.mouth_area,
            "pupil_radius": self.pupil_radius,
            "pupil_threshold": self.pupil_threshold,
            "classifiers": {"pupil": self.pupil.to_dict(), "lip": self.lip.to_dict(), "eye": self.eye.to_dict()},
            "colour_tables": {"image": f"{stem}.colour_tables.png", "order": list(CLASSIFIERS)},
            "lip_axis": [float(v) for v in self.lip_axis],
            "neutral": {k: v for k, v in self.neutral.as_dict().items()},
            "white_threshold": self.white_threshold,
            "iris_level": self.iris_level,
            "eye_ref": list(self.eye_ref) if self.eye_ref is not None else None,
            "mouth_ref": list(self.mouth_ref) if self.mouth_ref is not None else None,
            "face_patch": f"{stem}.face.png" if self.face_patch is not None else None,
            "mouth_model": self.mouth_model.to_dict() if self.mouth_model is not None else None,
            "eye_model": self.eye_model.to_dict() if self.eye_model is not None else None,
            "eye_model_pictures": {k: f"{stem}.{k}.png" for k in EyeModel.IMAGE_NAMES} if self.eye_model is not None else None,
            "face_box_eyes_flat": [float(v) for p in self.face_box_eyes for v in p] if self.face_box_eyes is not None else None,
        }

    def save(self, path: str | os.PathLike) -> None:
        """Write ``path`` (JSON) and, beside it, the two eye pictures and the colour tables as
        PNGs (``<stem>.eye_l.png`` …), as one :class:`~tracker.atomic_file.Generation`: a crash
        at any moment leaves the previous calibration or this one, never a mix."""
        path = Path(path)
        d = self.to_dict(path.stem)
        gen = atomic_file.Generation(path.parent, path.name, files_named_by(path))
        names = []
        for name, t in zip(d["eye_templates"], self.eye_templates):
            ok, buf = cv2.imencode(".png", np.clip(np.rint(t), 0, 255).astype(np.uint8))
            if not ok:
                raise CalibrationError(f"{path}: could not encode the eye picture")
            names.append(gen.put(name, buf.tobytes()))
        d["eye_templates"] = names
        tiles = np.concatenate([table_to_tile(getattr(self, c).table) for c in CLASSIFIERS])
        ok, buf = cv2.imencode(".png", tiles, [cv2.IMWRITE_PNG_COMPRESSION, 1])
        if not ok:
            raise CalibrationError(f"{path}: could not encode the colour tables")
        d["colour_tables"]["image"] = gen.put(d["colour_tables"]["image"], buf.tobytes())
        if self.face_patch is not None:
            ok, buf = cv2.imencode(".png", np.clip(np.rint(self.face_patch), 0, 255).astype(np.uint8))
            if not ok:
                raise CalibrationError(f"{path}: could not encode the face picture")
            d["face_patch"] = gen.put(d["face_patch"], buf.tobytes())
        if self.eye_model is not None:
            for k, img in self.eye_model.images().items():
                ok, buf = cv2.imencode(".png", img)
                if not ok:
                    raise CalibrationError(f"{path}: could not encode the eye model's {k} picture")
                d["eye_model_pictures"][k] = gen.put(d["eye_model_pictures"][k], buf.tobytes())
        gen.commit((json.dumps(d, indent=1) + "\n").encode("utf-8"))

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Calibration":
        """Read a calibration written by :meth:`save`; :class:`CalibrationError` names the file."""
        path = Path(path)
        atomic_file.sweep_temp(path.parent)
        d = safe_json.read(path, "calibration", max_bytes=MAX_FILE_BYTES, allow_nan=True, error=CalibrationError)
        r = _Fields(path, d)
        fmt = d.get("format") if isinstance(d, dict) else None
        if isinstance(fmt, bool) or fmt not in READABLE_FORMATS:
            raise CalibrationError(
                f"{path}: not an Inkface calibration of format {' or '.join(map(str, READABLE_FORMATS))}"
            )
        tables = _load_tables(path, d, r)
        temps = [_load_picture(path, name) for name in r.names("eye_templates", 2)]
        face_patch = None
        if d.get("face_patch") is not None:
            face_patch = _load_picture(path, d["face_patch"], "face picture")
        box_eyes = r.optional_numbers("face_box_eyes_flat", 4)
        try:
            clicks = Clicks.from_dict(r.get("clicks", dict), where=f"{path}: clicks")
        except ClicksError as e:
            raise CalibrationError(str(e)) from None
        classifiers = r.get("classifiers", dict)
        models = {c: _classifier(path, classifiers.get(c), c, tables.get(c)) for c in CLASSIFIERS}
        neutral = r.get("neutral", dict)
        cal = cls(
            frame_size=tuple(int(v) for v in r.numbers("frame_size", 2, 1, 100_000, whole=True)),
            ipd=r.number("ipd", 0.5, 1e5),
            roll_deg=r.number("roll_deg", -360.0, 360.0),
            work_ipd=r.number("work_ipd", 0.5, 1e5),
            clicks=clicks,
            eye_templates=temps,
            brow_profiles=[np.asarray(p, dtype=np.float32) for p in r.profiles("brow_profiles")],
            brow_centres=list(r.numbers("brow_centres", 2)),
            brow_heights=list(r.numbers("brow_heights", 2)),
            lid_up=list(r.numbers("lid_up", 2, nan_ok=True)),
            lid_down=list(r.numbers("lid_down", 2, nan_ok=True)),
            mouth_offset=r.numbers("mouth_offset", 2),
            mouth_width=r.number("mouth_width", 0.0),
            mouth_height=r.number("mouth_height", 0.0),
            mouth_area=r.number("mouth_area", 0.0),
            pupil_radius=r.number("pupil_radius", 0.0),
            pupil_threshold=r.number("pupil_threshold"),
            pupil=models["pupil"],
            lip=models["lip"],
            eye=models["eye"],
            lip_axis=np.asarray(r.numbers("lip_axis", 3), dtype=np.float64),
            neutral=_face_params(path, neutral),
            white_threshold=r.optional_number("white_threshold"),
            iris_level=r.optional_number("iris_level"),
            eye_ref=r.optional_numbers("eye_ref", 3),
            mouth_ref=r.optional_numbers("mouth_ref", 3),
            face_patch=face_patch,
            face_box_eyes=None if box_eyes is None else ((box_eyes[0], box_eyes[1]), (box_eyes[2], box_eyes[3])),
            mouth_model=_mouth_model(path, d.get("mouth_model")),
            eye_model=_eye_model(path, d.get("eye_model"), d.get("eye_model_pictures")),
        )
        return cal


# ---------------------------------------------------------------------------------------------
# calibrate


# grey-level spread (0–255) below which an eye picture is a flat wall, not an eye: real eyes on the
# clips measure 17–62 (5–30 on darkened, noisy copies), a flat background under codec noise 1–2
MIN_EYE_CONTRAST = 3.0

def _odd(v: float, lo: int = 3) -> int:
    n = max(int(round(v)), lo)
    return n if n % 2 else n + 1


def _refine_pupil(grey: np.ndarray, click: tuple[float, float], ipd: float) -> tuple[tuple[float, float], float]:
    """Snap a clicked pupil to the centre of the dark disc under it; also return its radius (px).

    First the darkest disc of radius ~0.04 ipd within 0.1 ipd of the click (box-filtered
    mean), then the darkness-weighted centroid of the pixels darker than half-way between
    that disc and the ring around it — so a dark iris or dark skin does not pull it off.
    """
    h, w = grey.shape
    r = max(int(round(0.16 * ipd)), 5)
    xi, yi = int(round(click[0])), int(round(click[1]))
    x0, x1 = max(xi - r, 0), min(xi + r + 1, w)
    y0, y1 = max(yi - r, 0), min(yi + r + 1, h)
    rp = max(0.04 * ipd, 1.0)
    win = grey[y0:y1, x0:x1]
    kd = _odd(2 * rp, 3)
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kd, kd)).astype(np.float32)
    disc /= disc.sum()
    mean = cv2.filter2D(win, -1, disc, borderType=cv2.BORDER_REPLICATE)
    yy, xx = np.mgrid[y0:y1, x0:x1]
    near = (xx - click[0]) ** 2 + (yy - click[1]) ** 2 <= (0.1 * ipd + 1) ** 2
    cand = np.where(near, mean, np.inf)
    ky, kx = np.unravel_index(int(np.argmin(cand)), cand.shape)
    cx, cy = float(xx[ky, kx]), float(yy[ky, kx])
    d2 = (xx - cx) ** 2 + (yy - cy) ** 2
    dark = float(mean[ky, kx])
    ring = (d2 >= (1.6 * rp) ** 2) & (d2 <= (2.6 * rp) ** 2)
    around = float(np.median(win[ring])) if ring.any() else float(win.max())
    thr = dark + 0.5 * (around - dark)
    mask = ((win < thr) & (d2 <= (2.0 * rp) ** 2)).astype(np.uint8)
    n, lab = cv2.connectedComponents(mask, connectivity=8)
    comp = lab == lab[ky, kx]
    if not mask[ky, kx] or comp.sum() < 2:
        return (cx, cy), rp
    # the centre of the dark disc's convex hull: a highlight biting into its edge is a
    # concavity the hull fills, so it does not pull the centre away
    cnts, _ = cv2.findContours(comp.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    hull = cv2.convexHull(max(cnts, key=len))
    m = cv2.moments(hull)
    if m["m00"] <= 1.0:
        wgt = np.clip(thr - win, 0, None) * comp
        return (float((wgt * xx).sum() / wgt.sum()), float((wgt * yy).sum() / wgt.sum())), rp
    x = x0 + m["m10"] / m["m00"]
    y = y0 + m["m01"] / m["m00"]
    return (float(x), float(y)), math.sqrt(comp.sum() / math.pi)


def _two_means(v: np.ndarray) -> tuple[float, float] | None:
    """Means of the dark and the bright group of 1-D values (2-means), or None if too few."""
    v = np.sort(np.asarray(v, dtype=np.float64))
    if len(v) < 8:
        return None
    t = 0.5 * (v[0] + v[-1])
    for _ in range(20):
        lo, hi = v[v < t], v[v >= t]
        if not len(lo) or not len(hi):
            return None
        nt = 0.5 * (lo.mean() + hi.mean())
        if abs(nt - t) < 1e-3:
            break
        t = nt
    return float(lo.mean()), float(hi.mean())


def _patch(img: np.ndarray, cx: float, cy: float, hw: float, hh: float) -> np.ndarray:
    h, w = img.shape[:2]
    x0, x1 = int(max(round(cx - hw), 0)), int(min(round(cx + hw) + 1, w))
    y0, y1 = int(max(round(cy - hh), 0)), int(min(round(cy + hh) + 1, h))
    return img[y0:y1, x0:x1].reshape(-1, img.shape[2]) if img.ndim == 3 else img[y0:y1, x0:x1].ravel()


def _ellipse_pixels(img: np.ndarray, cx: float, cy: float, ax: float, ay: float, inner: float = 0.0) -> np.ndarray:
    h, w = img.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    e = ((xx - cx) / ax) ** 2 + ((yy - cy) / ay) ** 2
    return img[(e <= 1.0) & (e >= inner**2)]


def consensus(measures: list[list[float]]) -> int:
    """Index of the measurement vector nearest all the others (the least sum of absolute
    differences; the first such): the middle reading of a few, never a blend of two."""
    m = np.asarray(measures, dtype=np.float64)
    return int(np.abs(m[:, None, :] - m[None, :, :]).sum(axis=(1, 2)).argmin())


def rest_height(line_y: float, gap_top: float, wi: float) -> float:
    """The height (px, down) of the mouth's line at rest, from the line ``line_y`` of the mouth the
    calibration frame shows and the upper lip's inner edge ``gap_top`` above it (``wi``: px between
    the eyes).

    An open mouth's line runs through the middle of the opening, while the line of that mouth closed
    lies about where its upper lip's inner edge is now: the upper lip hardly moves as the jaw drops.
    So the line stands at most :data:`RIGID_OPEN` wi below that edge. A yawn on the calibration frame
    had put the rigid place 0.3-0.4 wi below every closed mouth after it, and each was refused as the
    philtrum (the ``late`` copy of expr_d18: mouth lost on 45 % of the frames)."""
    if RIGID_OPEN is None:
        return line_y
    return min(line_y, gap_top + RIGID_OPEN * wi)


def between_lips(line_y: float, top: float, model: MouthModel, wi: float) -> bool:
    """Whether a calibration look's line at height ``line_y`` (face px, down) lies on the mouth the
    model measured in its crop (whose top is at ``top``): no further outside its lips' outer edges
    than :data:`WHOLE_MOUTH` × ``wi``. Each look starts where the last one put its line, so without
    this bound a grin's looks climbed from the teeth to the upper lip's top and on to the shadow under
    the nose, each sure of a mouth there (a grinning man's photo: the rigid place 0.32 eye distances
    over the teeth, and the tracker read the nostrils' shadow as the mouth line)."""
    centre = top + model.centre[1]
    return centre - model.lip_upper - WHOLE_MOUTH * wi <= line_y <= centre + model.lip_lower + WHOLE_MOUTH * wi


def found_mouth(found: MouthResult | None, wi: float) -> bool:
    """Whether a look of the mouth finder on the calibration frame found the mouth: sure of it
    (:data:`~tracker.mouth_finder.SCORE_OK`) and whole — the line between its corners no further
    outside its two lips' outer edges than :data:`WHOLE_MOUTH` × ``wi`` (px between the eyes; a broad
    smile's corners rise to about its upper lip's top, so a lip's height from them may be a little
    under 0 on a real mouth). On a grin the look from the gap's middle can trace the shadow under the
    nose, corners on the nose's wings 0.16 eye distances over the top of the lips split from the
    teeth below: sure, but not a mouth (a smiling astronaut's photo: the rigid place went 0.26 eye
    distances up, onto the nostrils, and the tracker followed them)."""
    return (found is not None and found.score >= SCORE_OK
            and min(found.lip_upper, found.lip_lower) >= -WHOLE_MOUTH * wi)


def calibrate(frame_bgr: np.ndarray, clicks: Clicks) -> Calibration:
    """Learn a :class:`Calibration` from one frame and the five clicks on it.

    Raises :class:`CalibrationError` (one line) when the frame or the clicks are unusable
    (a point outside the frame, points that are not a face's proportions); a real face with
    weak lip colour is not refused (the mouth model leans on its gap and inside instead).
    """
    if not (isinstance(frame_bgr, np.ndarray) and frame_bgr.ndim == 3 and frame_bgr.shape[2] == 3 and frame_bgr.dtype == np.uint8):
        raise CalibrationError("calibration frame must be a uint8 (H, W, 3) BGR image")
    H, W = frame_bgr.shape[:2]
    try:
        clicks.check_inside((W, H))
    except ClicksError as e:
        raise CalibrationError(str(e)) from None
    given, clicks = clicks, clicks.moved(-PIXEL_CENTRE, -PIXEL_CENTRE)  # to OpenCV's pixel convention
    grey_full = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2GRAY).astype(np.float32)
    ipd0 = clicks.ipd()
    # the iris centres near the clicks (the clicks stay when nothing iris-like is there)
    lp, rp = refine_pupils(grey_full, clicks.left_pupil, clicks.right_pupil)
    # a careful click is trusted over a snap that wandered (onto lashes, a lid crease, make-up)
    if math.dist(lp, clicks.left_pupil) > SNAP_REACH * ipd0:
        lp = clicks.left_pupil
    if math.dist(rp, clicks.right_pupil) > SNAP_REACH * ipd0:
        rp = clicks.right_pupil
    _, rl = _refine_pupil(grey_full, lp, ipd0)
    _, rr = _refine_pupil(grey_full, rp, ipd0)
    ipd = math.hypot(rp[0] - lp[0], rp[1] - lp[1])
    work_ipd = min(max(ipd, WORK_IPD_MIN), WORK_IPD_MAX)
    ff = FaceFrame.from_pupils(lp, rp, work_ipd)
    k = ff.scale
    wi = work_ipd

    # one generous crop of the whole face in the face frame
    mouth_f = ff.to_face(np.array([clicks.mouth]))[0]
    brows_f = ff.to_face(np.array([clicks.left_brow, clicks.right_brow]))
    # generous bounds on a face's proportions (real faces: mouth 1.0–1.4 ipd below the eyes,
    # brows 0.2–0.55 above): clicks outside them are not on one face
    if not (0.55 * wi < mouth_f[1] < 2.2 * wi and abs(mouth_f[0]) < 0.5 * wi):
        raise CalibrationError(
            f"clicks: the mouth ({given.mouth[0]:g}, {given.mouth[1]:g}) must be below the middle of the eyes, "
            "about one eye distance down"
        )
    if not all(-1.0 * wi < b[1] < -0.05 * wi for b in brows_f):
        raise CalibrationError("clicks: the brows must be above the pupils")
    if not all(abs(b[0] - px) < 0.6 * wi for b, px in zip(brows_f, (-0.5 * wi, 0.5 * wi))):
        raise CalibrationError("clicks: each brow must be above its own eye")
    ox, oy = -1.3 * wi, min(brows_f[:, 1].min(), 0) - 0.6 * wi
    cw = int(round(2.6 * wi))
    ch = int(round(mouth_f[1] + 0.9 * wi - oy))
    crop = ff.crop(frame_bgr, (ox, oy, cw, ch))
    grey = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY).astype(np.float32)

    def at(fx: float, fy: float) -> tuple[float, float]:
        return fx - ox, fy - oy

    pupils = [at(-0.5 * wi, 0.0), at(0.5 * wi, 0.0)]
    prad = max(0.5 * (rl + rr) * k, 1.5)

    # eye pictures: the iris and a margin of white and lids around it
    tw, th = _odd(0.36 * wi, 7), _odd(0.24 * wi, 5)
    temps = []
    for px, py in pupils:
        x0, y0 = int(round(px)) - tw // 2, int(round(py)) - th // 2
        if x0 < 0 or y0 < 0 or x0 + tw > cw or y0 + th > ch:
            raise CalibrationError("clicks: an eye is too close to the frame's edge")
        # the pupil sits at a fractional crop position: cut with that sub-pixel shift so it is centred exactly
        M = np.float32([[1, 0, px - tw // 2], [0, 1, py - th // 2]])
        t = cv2.warpAffine(grey, M, (tw, th), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
        temps.append(np.rint(t).astype(np.float32))
    for t, side, c in zip(temps, ("left", "right"), (given.left_pupil, given.right_pupil)):
        if float(t.std()) < MIN_EYE_CONTRAST:
            raise CalibrationError(
                f"clicks: nothing eye-like at the {side} pupil click ({c[0]:g}, {c[1]:g}): the picture there is flat"
            )

    # --- samples
    def region(fx, fy, hw, hh):
        return _patch(crop, *at(fx, fy), hw, hh)

    skin_parts = [
        region(-0.5 * wi, 0.42 * wi, 0.12 * wi, 0.05 * wi),
        region(0.5 * wi, 0.42 * wi, 0.12 * wi, 0.05 * wi),
        region(0.0, 0.0, 0.05 * wi, 0.05 * wi),
        region(0.0, float(brows_f[:, 1].mean()), 0.06 * wi, 0.04 * wi),
    ]
    skin_px = np.concatenate(skin_parts)
    mx, my = at(*mouth_f)
    ring = _ellipse_pixels(crop, mx, my, 0.75 * wi, 0.42 * wi, inner=0.72)
    # along the pupil line, from beyond the pupil to near the eye's corners: iris and white
    eye_interior = np.concatenate(
        [_patch(crop, px + s * (1.5 * prad + 0.09 * wi), py, 0.09 * wi, 1) for px, py in pupils for s in (-1, 1)]
    )
    pupil_px = np.concatenate([_ellipse_pixels(crop, px, py, 0.7 * prad, 0.7 * prad) for px, py in pupils])
    eye_box = np.concatenate(
        [_ellipse_pixels(crop, px, py, 0.3 * wi, 0.2 * wi, inner=min(0.9, 1.8 * prad / (0.2 * wi))) for px, py in pupils]
    )
    brow_px = np.concatenate([_patch(crop, *at(*b), 0.08 * wi, 0.02 * wi) for b in brows_f])

    try:
        pupil_cls = ColourClassifier(pupil_px, np.concatenate([eye_box, skin_px, brow_px]), y_weight=4.0, name="pupil")
        eye_cls = ColourClassifier(eye_interior, np.concatenate([skin_px, brow_px]), y_weight=3.0, name="eye")
    except ValueError as e:
        raise CalibrationError(f"calibration: {e}") from None

    # luminance threshold between the eye's white and the rest (iris, lashes), if there is a white
    ilum = features(eye_interior, 1.0)[:, 0] * 255.0
    lab = _two_means(ilum)
    white_threshold = iris_level = None
    if lab is not None:
        lo_m, hi_m = lab
        iris_level = lo_m
        if hi_m - lo_m > 40:
            white_threshold = 0.5 * (lo_m + hi_m)

    # --- the eyes: irises, lids, brows, the whole eye's picture (:mod:`tracker.eyes`)
    # (each learned on a few crops shifted by less than a pixel, the middle one kept: CONSENSUS_SHIFTS)
    erect0 = eye_calibration_crop(wi)
    eyes = []
    for dx, dy in CONSENSUS_SHIFTS:
        erect = (erect0[0] + dx, erect0[1] + dy, erect0[2], erect0[3])
        ecrop = ff.crop(frame_bgr, erect)
        egrey = cv2.cvtColor(ecrop, cv2.COLOR_BGR2GRAY).astype(np.float32)
        eo = np.array(erect[:2], dtype=np.float64)
        try:
            eyes.append(learn_eyes(ecrop, egrey, np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]]) - eo, brows_f - eo, wi))
        except EyeModelError as e:
            raise CalibrationError(f"calibration: {e}") from None
    learned = eyes[consensus([[math.log(g / r) for g, r in zip(m.lid_open, m.radius)] + [math.log(r) for r in m.radius]
                              for m in eyes])]
    # the pictures are kept as 8-bit PNGs: round now, so a loaded calibration tracks like this one
    eye_model = EyeModel.from_dict(learned.to_dict(), learned.images())

    # --- the mouth: this performer's lips, gap and inside (never refuses a face; says which cue it uses)
    mrect0 = mouth_rect(mouth_f, wi)
    mouths = []
    for dx, dy in CONSENSUS_SHIFTS:
        mrect = (mrect0[0] + dx, mrect0[1] + dy, mrect0[2], mrect0[3])
        mcrop = ff.crop(frame_bgr, mrect)
        mouths.append((learn_mouth(mcrop, (mouth_f[0] - mrect[0], mouth_f[1] - mrect[1]), wi), mrect, mcrop))
    mouth_model, mrect, mcrop = mouths[consensus([[math.log(max(v, 0.5)) for v in (m.thick_up, m.thick_down, m.width)]
                                                  for m, _, _ in mouths])]
    # the mouth's rigid place is as high as the finder puts the centre of its line on this frame: the
    # tracker's jaw is measured by the finder against it, so the calibration frame itself has no jaw (the
    # model's centre is the corners' midpoint on the line traced through the gap, which in an open mouth
    # runs below corners that sit higher: talk_b's frame 0 had a jaw 0.12 wi up, and a mouth was then
    # allowed to rise that much further from a place already too low)
    mcx = mrect[0] + mouth_model.centre[0]
    mcy = mrect[1] + mouth_model.centre[1]
    finder = MouthFinder(mouth_model, wi)
    seen = None  # the last look that found the mouth: its place, result and crop
    for _ in range(RIGID_STEPS):  # as the tracker will look on this frame: the crop and the prediction at the place
        rect = mouth_rect((mcx, mcy), wi)
        found = finder.find(ff.crop(frame_bgr, rect), (mcx - rect[0], mcy - rect[1]))
        if not found_mouth(found, wi) or not between_lips(rect[1] + found.line_centre[1], mrect[1], mouth_model, wi):
            # the look from the new place found no mouth, or a line off the lips the model measured (on
            # a grin, the upper lip's top and then the shadow under the nose can be nearer than the
            # gap): back to the last place that found it, where the tracker will find it again on this
            # frame
            if seen is not None:
                mcy, found, rect = seen
            break
        seen = (mcy, found, rect)
        step = rect[1] + found.line_centre[1] - mcy
        mcy += step
        if abs(step) < 0.25:
            break
    if found_mouth(found, wi):
        mcy = rest_height(mcy, rect[1] + found.gap_top, wi)

    # lips as a colour class too (the whole-frame search by lip colour after a loss): the pixels
    # inside the mouth's outline that are neither skin-like nor the dark inside
    lips = _lip_pixels(mcrop, mouth_model)
    yw = 0.3
    skin_g = Gaussians(features(np.concatenate([skin_px, ring]), yw), 3, np.array([0.035 * yw, 0.012, 0.012]))
    if len(lips) >= 12:
        distinct = lips[skin_g.mahalanobis2(features(lips, yw)) > 6.0]
        lips = distinct if len(distinct) >= 12 else lips
    else:  # no outline to speak of: the reddest pixels round the click
        cand = _ellipse_pixels(crop, mx, my, 0.28 * wi, 0.1 * wi)
        red = features(cand, 1.0)[:, 1]
        lips = cand[red >= np.percentile(red, 80)]
    # a BGR direction that reads ~0 on skin and ~1 on lip, linear in colour mixtures (sub-pixel edges)
    diff = lips.astype(np.float64).mean(0) - ring.astype(np.float64).mean(0)
    lip_axis = diff / max(float(diff @ diff), 1e-6)
    lip_cls = ColourClassifier(
        lips, np.concatenate([skin_px, ring, pupil_px, brow_px, eye_interior]), y_weight=0.5, name="lip"
    )

    # --- brows: cross-section through each pupil, centred on the brow's middle line
    brow_profiles, brow_centres, brow_heights = [], [], []
    half = max(int(round(0.13 * wi)), 4)
    for (px, py), b in zip(pupils, brows_f):
        top = int(math.floor(py - 1.1 * wi))
        prof = column_profile(grey, px, top, int(py), 2)
        guess = int(round(b[1] - oy - top))
        radius = max(int(round(0.08 * wi)), 3)
        c = brow_centre(prof, guess, radius)
        if not 0.08 * wi < py - (top + c) < 1.0 * wi:
            # the dark band found is the lashes or the lid crease (low, sparse brows; a click close
            # to the eye): look again above them, and failing that take the click itself — a real
            # face always has a brow where the person clicked it
            limit = len(prof) - int(math.ceil(0.12 * wi))
            c = brow_centre(prof[:limit], min(max(guess, 0), limit - 1), radius) if limit > 2 * radius else float(guess)
            if not 0.08 * wi < py - (top + c) < 1.0 * wi:
                c = float(min(max(guess, 0.0), py - top - 0.1 * wi))
        cy_b = top + c
        height = py - cy_b
        start = int(math.floor(cy_b)) - half
        frac = cy_b - math.floor(cy_b)
        seg = column_profile(grey, px, start, start + 2 * half + 1, 2)
        brow_profiles.append(seg)
        brow_centres.append(half + frac)
        brow_heights.append(float(height))

    cal = Calibration(
        frame_size=(W, H),
        ipd=float(ipd),
        roll_deg=math.degrees(ff.angle),
        work_ipd=float(work_ipd),
        clicks=Clicks(
            frame=clicks.frame, left_pupil=lp, right_pupil=rp, left_brow=clicks.left_brow, right_brow=clicks.right_brow,
            mouth=tuple(ff.to_image(np.array([[mcx, mcy]]))[0]),
        ),
        eye_templates=temps,
        brow_profiles=brow_profiles,
        brow_centres=brow_centres,
        brow_heights=brow_heights,
        lid_up=[0.0, 0.0],
        lid_down=[0.0, 0.0],
        mouth_offset=(float(mcx), float(mcy)),
        mouth_width=float(mouth_model.width),
        mouth_height=float(mouth_model.lip_upper + mouth_model.lip_lower),
        mouth_area=float(mouth_model.area),
        pupil_radius=float(prad),
        pupil_threshold=0.5,
        pupil=pupil_cls,
        lip=lip_cls,
        eye=eye_cls,
        lip_axis=lip_axis,
        white_threshold=white_threshold,
        iris_level=iris_level,
        mouth_model=mouth_model,
        eye_model=eye_model,
    )
    # the face as a whole, to tell it from anything else and to find it again
    from tracker.face_finder import face_patch, learn_eyes_in_box
    from tracker.face_tracker import FaceTracker
    from tracker.head_motion import HeadMotion

    hm = HeadMotion()
    hm.set_scale(ipd)
    pupil_px = np.array([lp, rp], dtype=np.float64)
    # stored as 8-bit grey: round now, so a loaded calibration tracks exactly like this one
    cal.face_patch = np.clip(np.rint(face_patch(hm.grey(frame_bgr), hm.scale, pupil_px)), 0, 255).astype(np.float32)
    cal.face_box_eyes = learn_eyes_in_box(frame_bgr, pupil_px)
    # lids and the neutral values: measure the calibration frame the way the tracker will

    tr = FaceTracker(cal)
    r = tr.track(frame_bgr, index=clicks.frame)
    cal.lid_up = list(r.debug.get("lid_up", [0.0, 0.0]))
    cal.lid_down = list(r.debug.get("lid_down", [0.0, 0.0]))
    cal.neutral = r.params.replace(status="ok")
    cal.eye_ref, cal.mouth_ref = tr.colour_refs()
    return cal


SMALL_FACE = 45.0
"""Inter-pupil distance (px) under which calibration advises coming closer or a higher resolution:
the lids and lips are then a few pixels tall. On copies of the shared clips at a third of their
size (30-37 px between the eyes) the eye opening's correlation with the peer is 0.74 on average,
against 0.86 at full size and 0.83 at half size (46-55 px)."""


def calibration_hints(cal: Calibration) -> list[str]:
    """Advice on the calibration frame for the person calibrating (one sentence each, no trailing
    full stop; [] when there is none). Calibration never refuses a real face; this only says what
    would make the track steadier: the eyes turned aside (:func:`~tracker.eyes.side_glance`) leave
    the iris pictures with white on one side only, and a face under :data:`SMALL_FACE` px between
    the eyes has lids and lips only a few pixels tall."""
    hints = []
    model = getattr(cal, "eye_model", None)  # (a calibration of the paper's tracker has none)
    if model is not None and side_glance(model):
        hints.append("the eyes look to one side in the calibration frame; for a steadier track, "
                     "calibrate on a frame where you look into the camera")
    if cal.ipd < SMALL_FACE:
        hints.append(f"the face is small in the picture ({cal.ipd:.0f} px between the eyes); for a finer "
                     "track of the eyelids and lips, come closer to the camera or use a higher resolution")
    return hints


# ---------------------------------------------------------------------------------------------
# reading a calibration file: every value checked (types exact, finite, in range)

MAX_FILE_BYTES = 8 * 1024 * 1024
MAX_PROFILE = 4096
"""Longest brow profile (samples) a calibration file may hold."""


def files_named_by(path: Path) -> list[str]:
    """The picture files the calibration at ``path`` names now (none if it is missing or unreadable)."""
    try:
        d = safe_json.read(path, "calibration", max_bytes=MAX_FILE_BYTES, allow_nan=True, error=CalibrationError)
    except CalibrationError:
        return []
    if not isinstance(d, dict):
        return []
    names = list(d.get("eye_templates") or []) if isinstance(d.get("eye_templates"), list) else []
    spec = d.get("colour_tables")
    if isinstance(spec, dict):
        names.append(spec.get("image"))
    names.append(d.get("face_patch"))
    if isinstance(d.get("eye_model_pictures"), dict):
        names.extend(d["eye_model_pictures"].values())
    return [n for n in names if isinstance(n, str) and _plain_name(n)]


def _plain_name(name: str) -> bool:
    """A file name with no folder part, which :func:`atomic_file.inside` accepts."""
    return bool(name) and "/" not in name and name not in (".", "..") and atomic_file.inside(".", name) is not None


class _Fields:
    """Typed access to the top-level keys of a calibration dictionary; errors name ``path``."""

    def __init__(self, path: Path, d):
        self.path = path
        self.d = safe_json.mapping(d, f"{path}: the calibration", CalibrationError)

    def where(self, key: str) -> str:
        return f"{self.path}: '{key}'"

    def get(self, key: str, kind: type):
        if key not in self.d:
            raise CalibrationError(f"{self.path}: malformed calibration (missing key '{key}')")
        v = self.d[key]
        if kind is dict:
            return safe_json.mapping(v, self.where(key), CalibrationError)
        return v

    def number(self, key: str, lo: float = -safe_json.MAGNITUDE, hi: float = safe_json.MAGNITUDE) -> float:
        return safe_json.number(self.get(key, float), self.where(key), CalibrationError, lo, hi)

    def numbers(self, key: str, n: int, lo: float = -safe_json.MAGNITUDE, hi: float = safe_json.MAGNITUDE,
                whole: bool = False, nan_ok: bool = False) -> tuple[float, ...]:
        v = self.get(key, list)
        if whole:
            if not isinstance(v, list) or len(v) != n:
                raise CalibrationError(f"{self.where(key)} must be a list of {n} whole numbers, got {safe_json.show(v)}")
            return tuple(safe_json.integer(x, self.where(key), CalibrationError, int(lo), int(hi)) for x in v)
        if not isinstance(v, list) or len(v) != n:
            raise CalibrationError(f"{self.where(key)} must be a list of {n} numbers, got {safe_json.show(v)}")
        return tuple(safe_json.number(x, self.where(key), CalibrationError, lo, hi, nan_ok=nan_ok) for x in v)

    def optional_number(self, key: str) -> float | None:
        v = self.d.get(key)
        return None if v is None else safe_json.number(v, self.where(key), CalibrationError)

    def optional_numbers(self, key: str, n: int) -> tuple[float, ...] | None:
        return None if self.d.get(key) is None else self.numbers(key, n)

    def names(self, key: str, n: int) -> list[str]:
        v = self.get(key, list)
        if not isinstance(v, list) or len(v) != n or not all(isinstance(x, str) for x in v):
            raise CalibrationError(f"{self.where(key)} must be a list of {n} file names, got {safe_json.show(v)}")
        return v

    def profiles(self, key: str) -> list[list[float]]:
        v = self.get(key, list)
        if not isinstance(v, list) or len(v) != 2:
            raise CalibrationError(f"{self.where(key)} must be a list of two profiles, got {safe_json.show(v)}")
        out = []
        for p in v:
            if not isinstance(p, list) or not 1 <= len(p) <= MAX_PROFILE:
                raise CalibrationError(f"{self.where(key)}: a profile must be a list of 1 to {MAX_PROFILE} numbers")
            out.append([safe_json.number(x, self.where(key), CalibrationError) for x in p])
        return out


def _beside(path: Path, name, what: str) -> Path:
    """The file ``name`` next to the calibration ``path``; it may not lie in another folder."""
    if not isinstance(name, str) or not _plain_name(name):
        raise CalibrationError(f"{path}: {what} {safe_json.show(name)} must be a file name beside the calibration")
    return path.parent / name


def _png_size(p: Path) -> tuple[int, int] | None:
    """(width, height) from a PNG's header, read before any pixels are decoded; None if not a PNG."""
    try:
        with open(p, "rb") as f:
            head = f.read(24)
    except OSError:
        return None
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def _read_png(p: Path, flags: int, max_side: int) -> np.ndarray | None:
    size = _png_size(p) if p.is_file() else None
    if size is None or not (1 <= size[0] <= max_side and 1 <= size[1] <= max_side):
        return None
    return cv2.imread(str(p), flags)


class _EyeInsideMask:
    """What the eye finder counts as the inside of an eye (white, iris, lashes): not this skin."""

    def __init__(self, model: EyeModel):
        self.model = model

    def mask(self, bgr: np.ndarray) -> np.ndarray:
        return self.model.skin.interior(np.asarray(bgr)) >= 0.5


class _LipMask:
    """Pixels either lip's colour axis puts nearer the lip than the skin beside it."""

    def __init__(self, model: MouthModel):
        self.model = model

    def mask(self, bgr: np.ndarray) -> np.ndarray:
        f = np.asarray(bgr, dtype=np.float32)
        out = np.zeros(f.shape[:2], bool)
        for a in (self.model.axis_up, self.model.axis_down):
            v = cv2.transform(f, np.asarray(a[:3], dtype=np.float32).reshape(1, 3)) + np.float32(a[3])
            out |= v.reshape(f.shape[:2]) >= 0.5
        return out


class _MouthInsideMask:
    """The dark gap, inside and teeth as the mouth model sees them."""

    def __init__(self, model: MouthModel):
        self.model = model

    def mask(self, bgr: np.ndarray) -> np.ndarray:
        from tracker.colour_model import lut_index

        return self.model.inside_table.take(lut_index(np.ascontiguousarray(bgr))).astype(bool)


def _eye_model(path: Path, d, names) -> EyeModel | None:
    if d is None:
        return None
    if not isinstance(names, dict):
        raise CalibrationError(f"{path}: eye_model_pictures must name the eye model's pictures")
    pics = {k: _load_picture(path, names.get(k), f"eye model {k} picture") for k in EyeModel.IMAGE_NAMES}
    try:
        return EyeModel.from_dict(d, pics)
    except EyeModelError as e:
        raise CalibrationError(f"{path}: {e}") from None
    except (KeyError, TypeError, ValueError, IndexError) as e:
        raise CalibrationError(f"{path}: malformed eye model ({type(e).__name__}: {e})") from None


def _mouth_model(path: Path, d) -> MouthModel | None:
    """The calibration's mouth model, or None when it has none or one of the first format (its
    measurements mean something else to today's finder: the lip-blob finder tracks that calibration)."""
    if d is None or (isinstance(d, dict) and d.get("format") == 1):
        return None
    try:
        return MouthModel.from_dict(d)
    except ValueError as e:
        raise CalibrationError(f"{path}: mouth_model: {e}") from None


def mouth_rect(centre_face: tuple[float, float], work_ipd: float) -> tuple[int, int, int, int]:
    """The mouth crop ``(x0, y0, w, h)`` (face px) around a mouth centre in face coordinates."""
    x0, y0, w, h = MOUTH_RECT
    return (int(math.floor(centre_face[0] + x0 * work_ipd)), int(math.floor(centre_face[1] + y0 * work_ipd)),
            int(math.ceil(w * work_ipd)), int(math.ceil(h * work_ipd)))


def _lip_pixels(crop: np.ndarray, model: MouthModel) -> np.ndarray:
    """BGR pixels inside the model's mouth outline that are not the mouth's dark inside."""
    from tracker.colour_model import lut_index

    mask = np.zeros(crop.shape[:2], np.uint8)
    poly = np.asarray(model.outline, dtype=np.float64) + np.asarray(model.centre, dtype=np.float64)
    if len(poly) >= 3:
        cv2.fillPoly(mask, [np.round(poly).astype(np.int32)], 1)
    inside = model.inside_table.take(lut_index(crop)).astype(bool)
    return crop[(mask > 0) & ~inside]


def _load_picture(path: Path, name, what: str = "eye picture") -> np.ndarray:
    p = _beside(path, name, what)
    img = _read_png(p, cv2.IMREAD_GRAYSCALE, 1024)
    if img is None:
        raise CalibrationError(f"{p}: missing or unreadable {what} (named by {path})")
    return img.astype(np.float32)


def _load_tables(path: Path, d: dict, r: _Fields) -> dict[str, np.ndarray]:
    """The baked colour tables named by a format-2 file (empty for format 1: they are rebuilt)."""
    spec = d.get("colour_tables")
    if d["format"] < 2 or spec is None:
        return {}
    spec = safe_json.mapping(spec, r.where("colour_tables"), CalibrationError)
    order = spec.get("order")
    if not isinstance(order, list) or sorted(o for o in order if isinstance(o, str)) != sorted(CLASSIFIERS) or len(order) != len(CLASSIFIERS):
        raise CalibrationError(f"{r.where('colour_tables')}: 'order' must list {', '.join(CLASSIFIERS)}, got {safe_json.show(order)}")
    p = _beside(path, spec.get("image"), "colour table image")
    th, tw = TILE_SHAPE
    img = _read_png(p, cv2.IMREAD_UNCHANGED, th * len(order))
    if img is None or img.dtype != np.uint8 or img.shape != (th * len(order), tw):
        raise CalibrationError(f"{p}: missing or unreadable colour tables (need {tw}×{th * len(order)} 8-bit grey)")
    return {c: tile_to_table(img[i * th : (i + 1) * th]) for i, c in enumerate(order)}


def _classifier(path: Path, d, name: str, table: np.ndarray | None) -> ColourClassifier:
    """A colour classifier from its dictionary, every number checked before it is used."""
    where = f"{path}: classifiers.{name}"
    d = safe_json.mapping(d, where, CalibrationError)
    for key in ("y_weight", "gate", "margin"):
        safe_json.number(d.get(key), f"{where}.{key}", CalibrationError)
    for side in ("target", "other"):
        g = safe_json.mapping(d.get(side), f"{where}.{side}", CalibrationError)
        means, icovs, logdets = (safe_json.sequence(g.get(k), f"{where}.{side}.{k}", CalibrationError, 64)
                                 for k in ("means", "icovs", "logdets"))
        if not means or not len(means) == len(icovs) == len(logdets):
            raise CalibrationError(f"{where}.{side}: needs as many means, icovs and logdets, at least one")
        for mu in means:
            safe_json.numbers(mu, f"{where}.{side}.means", 3, CalibrationError)
        for ic in icovs:
            if not isinstance(ic, list) or len(ic) != 3:
                raise CalibrationError(f"{where}.{side}.icovs must hold 3x3 matrices, got {safe_json.show(ic)}")
            for row in ic:
                safe_json.numbers(row, f"{where}.{side}.icovs", 3, CalibrationError)
        for v in logdets:
            safe_json.number(v, f"{where}.{side}.logdets", CalibrationError)
    if "name" in d:
        safe_json.string(d["name"], f"{where}.name", CalibrationError, 64)
    try:
        return ColourClassifier.from_dict(d, table)
    except (KeyError, TypeError, ValueError) as e:
        raise CalibrationError(f"{where}: malformed colour model ({' '.join(str(e).split())})") from None


def _face_params(path: Path, d: dict) -> FaceParams:
    """The neutral face: the ten values (NaN allowed: not measured) and the bookkeeping fields."""
    where = f"{path}: neutral"
    kw = {}
    for name, default in FaceParams().as_dict().items():
        if name not in d:
            continue
        v = d[name]
        if isinstance(default, str):
            kw[name] = safe_json.string(v, f"{where}.{name}", CalibrationError, 64)
        elif name == "frame":
            kw[name] = safe_json.integer(v, f"{where}.{name}", CalibrationError, 0, int(safe_json.MAGNITUDE))
        else:
            kw[name] = safe_json.number(v, f"{where}.{name}", CalibrationError, nan_ok=True)
    unknown = sorted(set(d) - set(FaceParams().as_dict()))
    if unknown:
        raise CalibrationError(f"{where}: unknown value(s) {', '.join(map(str, unknown[:5]))}")
    return FaceParams(**kw)
