"""The synthetic performer: a drawn blob face with exact ground truth for the ten parameters.

Every tracker test and accuracy benchmark uses it, so what is drawn and what the truth says
must agree to a fraction of a pixel, in the definitions of ``shared/DESIGN.md``:

* pupils are discs; ``mid_x, mid_y`` is the midpoint of their centres, ``roll_deg`` the angle
  of the pupil segment (positive when the image-right pupil is higher, i.e. has smaller y);
* "up" is perpendicular to the pupil line; ``l`` is the image-left eye;
* ``eye_open`` is the gap between the two lid edges (the eye white's outline) on the line
  through the pupil along up;
* ``brow`` is the distance from the pupil centre to the eyebrow's middle line (half-way
  between its upper and lower edge) on the line through the pupil along up;
* ``mouth_width`` is the distance between the two mouth corners (where the lips meet);
* ``lip_upper`` / ``lip_lower`` run from the mouth centre (midpoint of the corners) along up /
  down to the outer edge of the upper / lower lip (signed: negative if that edge lies on the
  other side of the centre).

The face is built in a face-local frame (origin at the midpoint of the eye centres, x towards
the image-right eye, y towards the chin, pixels) and rotated by the roll and translated into the
frame. The measured features (eyes, brows, lips) are polygons rasterised at 8x and area-averaged,
with a half-sub-pixel inward offset that cancels OpenCV's fill bias, so their edges are
anti-aliased and within about 0.1 px of the truth (``tests/test_synthetic.py`` measures them).
The rigid rest of the head (hair, ears, shaded skin, nose) is a cached sprite warped into place.

Typical use::

    img, truth = render_face(FaceState(roll_deg=10).with_expression("smile"), STYLES["noisy"])
    perf = Performance(seconds=10, seed=3)          # scripted: talking, blinks, roll, drift, ...
    frame, truth = perf.frame(42), perf.truth(42)
    perf.write("clip.mp4", "truth.csv")             # + clip.clicks.json (frame 0 is neutral)
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator, Mapping, Sequence

import cv2
import numpy as np

from tracker import atomic_file
from tracker.clicks import PIXEL_CENTRE
from tracker.params import EYES_CLOSED, LOST, MOUTH_LOST, OK, FaceParams, write_csv

BGR = tuple[int, int, int]

# ---------------------------------------------------------------------------------------------
# Face state and expressions


@dataclass(slots=True)
class FaceState:
    """The performer's pose and expression in one frame.

    ``cx, cy``: pupil midpoint (pixels); ``roll_deg``: head roll (+ = image-right pupil higher);
    ``ipd``: inter-pupil distance (pixels). Expression values are unitless: ``eye_open_*`` 0 closed
    .. 1 normal .. 1.3 wide; ``brow_*`` −1 lowered .. 0 rest .. 1 raised; ``mouth_open`` 0..1 jaw;
    ``smile`` −1 frown .. 1 smile; ``pucker`` 0..1 ("oo": narrow and round); ``teeth`` shows the
    upper teeth when the mouth is open. ``gaze_x, gaze_y`` move both pupils inside the eyes
    (fraction of ``ipd``; the eyes move, the pupils stay at ``cx, cy``); ``light`` is a BGR gain on
    the whole frame (lighting drift); ``visible=False`` renders the empty scene (face gone).
    """

    cx: float = 320.0
    cy: float = 210.0
    roll_deg: float = 0.0
    ipd: float = 80.0
    eye_open_l: float = 1.0
    eye_open_r: float = 1.0
    brow_l: float = 0.0
    brow_r: float = 0.0
    mouth_open: float = 0.0
    smile: float = 0.0
    pucker: float = 0.0
    teeth: bool = False
    visible: bool = True
    gaze_x: float = 0.0
    gaze_y: float = 0.0
    light: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def replace(self, **changes) -> "FaceState":
        """A copy with some fields changed; ``eye_open`` / ``brow`` set both sides."""
        return dataclasses.replace(self, **_expand(changes))

    def with_expression(self, name: str, **changes) -> "FaceState":
        """This pose with the named :data:`EXPRESSIONS` preset (and further changes) applied."""
        if name not in EXPRESSIONS:
            raise KeyError(f"unknown expression {name!r} (known: {', '.join(EXPRESSIONS)})")
        return self.replace(**{**EXPRESSIONS[name], **changes})


def _expand(changes: dict) -> dict:
    out = dict(changes)
    for both in ("eye_open", "brow"):
        if both in out:
            v = out.pop(both)
            out.setdefault(f"{both}_l", v)
            out.setdefault(f"{both}_r", v)
    return out


EXPRESSION_FIELDS = ("eye_open_l", "eye_open_r", "brow_l", "brow_r", "mouth_open", "smile", "pucker", "teeth")
"""The FaceState fields an expression preset sets (pose fields are left alone)."""

_NEUTRAL = {"eye_open_l": 1.0, "eye_open_r": 1.0, "brow_l": 0.0, "brow_r": 0.0,
            "mouth_open": 0.0, "smile": 0.0, "pucker": 0.0, "teeth": False}


def _expr(**kw) -> dict:
    return {**_NEUTRAL, **_expand(kw)}


EXPRESSIONS: dict[str, dict] = {
    "neutral": _expr(),
    "smile": _expr(smile=0.85, eye_open=0.9),
    "frown": _expr(smile=-0.8, brow=-0.4),
    "ah": _expr(mouth_open=0.85, teeth=True, brow=0.2),
    "oo": _expr(mouth_open=0.3, pucker=0.95),
    "ee": _expr(mouth_open=0.25, smile=0.45, teeth=True),
    "grin": _expr(smile=1.0, mouth_open=0.35, teeth=True, eye_open=0.85),
    "blink": _expr(eye_open=0.12),
    "eyes_closed": _expr(eye_open=0.0),
    "brows_up": _expr(brow=1.0, eye_open=1.15),
    "brows_angry": _expr(brow=-1.0, eye_open=0.8, smile=-0.3),
    "squint": _expr(eye_open=0.45, brow=-0.3, smile=0.2),
    "wide": _expr(eye_open=1.3, brow=0.8),
    "surprise": _expr(eye_open=1.3, brow=1.0, mouth_open=0.6),
    "sad": _expr(brow=0.45, smile=-0.55, eye_open=0.85),
    "angry": _expr(brow=-1.0, smile=-0.5, eye_open=0.9),
    "laugh": _expr(smile=1.0, mouth_open=0.7, teeth=True, eye_open=0.55, brow=0.3),
    "wink_l": _expr(eye_open_l=0.0, smile=0.4),
    "wink_r": _expr(eye_open_r=0.0, smile=0.4),
}
"""Named expression presets: complete sets of :data:`EXPRESSION_FIELDS` values."""


# ---------------------------------------------------------------------------------------------
# Style


@dataclass(frozen=True, slots=True)
class Style:
    """How the performer looks and how the "camera" degrades the picture.

    Colours are BGR. ``ipd`` is the default inter-pupil distance in pixels at 640×480 (scaled with
    the frame size by :class:`Performance`); ``roll_max`` the default roll amplitude (degrees).
    ``noise`` is the sigma of gaussian sensor noise (grey levels), ``blur`` a gaussian blur sigma
    (pixels), ``lighting_drift`` the amplitude of the slow global gain / colour change (0.2 = ±20 %),
    ``jpeg_quality`` 1..100 passes each frame through JPEG (0 = off). ``catchlight`` draws a small
    specular highlight on each pupil; ``limbus`` darkens the iris rim (1 = flat iris). ``lash`` (the
    upper lash line, half-width ``lash_width`` × ipd, 0 = none) defaults to the brow colour.
    ``shading`` scales the skin's shading, ``texture`` adds static skin mottling (relative brightness
    sigma, e.g. 0.03), ``blush`` reddens the cheeks towards the lip colour (0..1).
    """

    name: str = "default"
    skin: BGR = (140, 172, 218)
    lip: BGR = (92, 78, 188)
    iris: BGR = (150, 112, 72)
    brow: BGR = (32, 42, 62)
    hair: BGR = (34, 50, 78)
    mouth: BGR = (40, 28, 78)
    teeth: BGR = (222, 232, 236)
    sclera: BGR = (228, 234, 240)
    pupil: BGR = (12, 12, 14)
    lash: BGR | None = None
    shirt: BGR = (140, 92, 58)
    background: BGR = (186, 190, 182)
    ipd: float = 80.0
    roll_max: float = 25.0
    noise: float = 0.0
    blur: float = 0.0
    lighting_drift: float = 0.0
    jpeg_quality: int = 0
    catchlight: bool = True
    limbus: float = 0.65
    lash_width: float = 0.02
    shading: float = 1.0
    texture: float = 0.0
    blush: float = 0.0

    def replace(self, **changes) -> "Style":
        return dataclasses.replace(self, **changes)


STYLES: dict[str, Style] = {
    "default": Style(),
    "dark_skin": Style(name="dark_skin", skin=(48, 66, 104), lip=(58, 52, 112), iris=(30, 48, 78),
                       brow=(18, 18, 22), hair=(16, 16, 20), shirt=(60, 150, 200)),
    "pale_lips": Style(name="pale_lips", lip=(140, 144, 212)),
    "blue_eyes": Style(name="blue_eyes", iris=(190, 130, 70), skin=(170, 196, 232), lip=(120, 110, 205),
                       hair=(80, 150, 200), brow=(60, 100, 140)),
    "noisy": Style(name="noisy", noise=6.0, blur=1.0, jpeg_quality=70),
    "lighting": Style(name="lighting", lighting_drift=0.25),
    "small_far": Style(name="small_far", ipd=48.0),
    "strong_roll": Style(name="strong_roll", roll_max=30.0),
    "webcam": Style(name="webcam", noise=4.0, blur=0.7, lighting_drift=0.12, jpeg_quality=80),
    "realistic": Style(name="realistic", texture=0.015, blush=0.5, noise=3.0, blur=0.6, lighting_drift=0.1,
                       jpeg_quality=85),
}
"""Named styles for tests and benchmarks."""


# ---------------------------------------------------------------------------------------------
# Face geometry (units: fractions of the ipd, face-local frame, y towards the chin)

HEAD_CY, HEAD_A, HEAD_B = 0.30, 1.0, 1.45
EYE_HW = 0.24  # half-width of the eye opening
EYE_H = 0.20  # lid-to-lid gap at eye_open = 1
EYE_UPPER_SHARE = 0.6  # share of the gap above the eye's centre line
IRIS_R, PUPIL_R = 0.095, 0.042
BROW_B0, BROW_UP, BROW_DOWN = 0.40, 0.14, 0.10
BROW_HALF, BROW_ARCH, BROW_T = 0.30, 0.06, 0.07
MOUTH_Y, MOUTH_W0 = 1.02, 0.78
LIP_TU, LIP_TL = 0.085, 0.11
GAP_MIN, GAP_MAX = 0.012, 0.45
FEATURE_SS = 8  # supersampling of the measured features (eyes, brows, lips): edges within 1/16 px
SMILE_UP, FROWN_DOWN = 0.10, 0.08

_T_LIP = np.linspace(-1.0, 1.0, 41)
_T_EYE = np.linspace(-1.0, 1.0, 33)
_T_BROW = np.linspace(-1.0, 1.0, 25)
_ANG = np.linspace(0.0, 2.0 * np.pi, 97)[:-1]
_COS, _SIN = np.cos(_ANG), np.sin(_ANG)


def _lid_profile(t: np.ndarray | float) -> np.ndarray:
    return np.power(np.clip(1.0 - np.square(t), 0.0, None), 0.8)


def _brow_centre(t, b: float, inner: float, u: float):
    """Eyebrow middle line (local y offset from the eye centre line), t in [-1, 1] along it."""
    tilt = (0.06 * max(-b, 0.0) - 0.025 * max(b, 0.0)) * u
    height = (BROW_B0 + (BROW_UP if b > 0 else BROW_DOWN) * b) * u
    return -height + BROW_ARCH * u * np.square(t) + tilt * inner * t


def _brow_thickness(t, inner: float, u: float):
    return BROW_T * u * (0.4 + 0.6 * np.sqrt(np.clip(1.0 - np.square(t), 0.0, None))) * (1.0 + 0.2 * inner * t)


@dataclass(slots=True)
class _Mouth:
    """Mouth shape in face-local pixels; curves are functions of t in [-1, 1] (corner to corner)."""

    half_w: float
    yc: float  # corner height
    y_iu0: float
    y_il0: float
    t_u: float
    t_l: float
    p_in: float
    p_out: float

    def f_in(self, t):
        return np.power(np.clip(1.0 - np.square(t), 0.0, None), self.p_in)

    def f_out(self, t):
        return np.power(np.clip(1.0 - np.square(t), 0.0, None), self.p_out)

    def inner_upper(self, t):
        return self.yc + (self.y_iu0 - self.yc) * self.f_in(t)

    def inner_lower(self, t):
        return self.yc + (self.y_il0 - self.yc) * self.f_in(t)

    def outer_upper(self, t):
        bow = 1.0 + 0.12 * np.square(t / 0.3) * np.exp(1.0 - np.square(t / 0.3))
        return self.inner_upper(t) - self.t_u * self.f_out(t) * bow

    def outer_lower(self, t):
        return self.inner_lower(t) + self.t_l * self.f_out(t)


def _mouth(st: FaceState) -> _Mouth:
    u = st.ipd
    s, p = float(np.clip(st.smile, -1, 1)), float(np.clip(st.pucker, 0, 1))
    o = float(np.clip(st.mouth_open, 0, 1))
    width = MOUTH_W0 * (1.0 + 0.16 * max(s, 0.0) + 0.04 * min(s, 0.0)) * (1.0 - 0.42 * p) * (1.0 - 0.1 * o)
    yc = (MOUTH_Y - SMILE_UP * max(s, 0.0) + FROWN_DOWN * max(-s, 0.0)) * u
    gap = (GAP_MIN + GAP_MAX * o * (1.0 - 0.25 * p)) * u
    y0 = MOUTH_Y * u
    return _Mouth(
        half_w=0.5 * width * u,
        yc=yc,
        y_iu0=y0 - 0.25 * gap,
        y_il0=y0 + 0.75 * gap,
        t_u=LIP_TU * u * (1.0 + 0.35 * p) * (1.0 - 0.25 * max(s, 0.0)),
        t_l=LIP_TL * u * (1.0 + 0.3 * p) * (1.0 - 0.15 * max(s, 0.0)),
        p_in=0.9 - 0.4 * p,
        p_out=0.45 - 0.15 * p,
    )


@dataclass(slots=True)
class _Pose:
    """Face-local → image transform: image = origin + R · local (rotation by −roll on screen)."""

    ox: float
    oy: float
    c: float
    s: float

    @classmethod
    def of(cls, st: FaceState) -> "_Pose":
        th = math.radians(st.roll_deg)
        c, s = math.cos(th), math.sin(th)
        gx, gy = st.gaze_x * st.ipd, st.gaze_y * st.ipd
        return cls(st.cx - (c * gx + s * gy), st.cy - (-s * gx + c * gy), c, s)

    def apply(self, pts: np.ndarray) -> np.ndarray:
        pts = np.asarray(pts, np.float64)
        out = np.empty(pts.shape, np.float64)
        x, y = pts[..., 0], pts[..., 1]
        out[..., 0] = self.ox + self.c * x + self.s * y
        out[..., 1] = self.oy - self.s * x + self.c * y
        return out

    def point(self, x: float, y: float) -> tuple[float, float]:
        return (self.ox + self.c * x + self.s * y, self.oy - self.s * x + self.c * y)

    def local(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        dx, dy = xs - self.ox, ys - self.oy
        return self.c * dx - self.s * dy, self.s * dx + self.c * dy


def _eye_centres(u: float) -> tuple[float, float]:
    return (-0.5 * u, 0.5 * u)  # image-left, image-right


def _eye_gaps(e: float, u: float) -> tuple[float, float]:
    g = max(e, 0.0) * EYE_H * u
    return EYE_UPPER_SHARE * g, (1.0 - EYE_UPPER_SHARE) * g


# ---------------------------------------------------------------------------------------------
# Ground truth


def face_truth(state: FaceState, frame: int = 0, time: float = 0.0,
               frame_size: tuple[int, int] | None = None) -> FaceParams:
    """The exact ten parameters of what :func:`render_face` draws for ``state``.

    Status: ``lost`` when the face is not visible or (given ``frame_size``) a pupil is outside the
    frame; ``mouth_lost`` when the mouth centre is outside the frame; ``eyes_closed`` when both
    lid gaps are under 10 % of normal; else ``ok``. Values always say where the face is (or would be).
    ``mid_x`` / ``mid_y`` are in the files' pixel convention (:data:`~tracker.clicks.PIXEL_CENTRE`),
    like the tracker's; :attr:`FaceState.cx` / ``cy`` and :func:`face_landmarks` in OpenCV's.
    """
    u = state.ipd
    if not (u > 0 and math.isfinite(u)):
        raise ValueError(f"inter-pupil distance must be positive, got {u}")
    gx, gy = state.gaze_x * u, state.gaze_y * u
    hw = EYE_HW * u
    vals = []
    for e in (state.eye_open_l, state.eye_open_r):
        up, lo = _eye_gaps(e, u)
        vals.append((up + lo) * float(_lid_profile(gx / hw)))
    brows = []
    for ex, b in zip(_eye_centres(u), (state.brow_l, state.brow_r)):
        inner = 1.0 if ex < 0 else -1.0
        t = gx / (BROW_HALF * u)
        brows.append(gy - float(_brow_centre(t, float(np.clip(b, -1, 1)), inner, u)))
    m = _mouth(state)
    lip_u = m.yc - float(m.outer_upper(0.0))
    lip_l = float(m.outer_lower(0.0)) - m.yc
    inside = lambda p: frame_size is None or (0 <= p[0] < frame_size[0] and 0 <= p[1] < frame_size[1])
    pose = _Pose.of(state)
    pupils = [(state.cx + sx * 0.5 * u * pose.c, state.cy - sx * 0.5 * u * pose.s) for sx in (-1, 1)]
    if not state.visible or not all(inside(p) for p in pupils):
        status, conf = LOST, 0.0
    elif not inside(pose.point(0.0, m.yc)):
        status, conf = MOUTH_LOST, 0.5
    elif max(state.eye_open_l, state.eye_open_r) < 0.1:
        status, conf = EYES_CLOSED, 1.0
    else:
        status, conf = OK, 1.0
    return FaceParams(
        frame=int(frame), mid_x=float(state.cx) + PIXEL_CENTRE, mid_y=float(state.cy) + PIXEL_CENTRE, roll_deg=float(state.roll_deg),
        eye_open_l=vals[0], eye_open_r=vals[1], brow_l=brows[0], brow_r=brows[1],
        mouth_width=2.0 * m.half_w, lip_upper=lip_u, lip_lower=lip_l,
        time=float(time), status=status, confidence=conf,
    )


def face_landmarks(state: FaceState) -> dict[str, np.ndarray]:
    """Image positions (x, y) of the performer's key points, for tests and overlays, in OpenCV's pixel
    convention (pixel centres at whole numbers, as the tracker's overlays).

    Keys: ``left_pupil``, ``right_pupil``, ``left_brow``, ``right_brow`` (eyebrow middle line on
    the line through the pupil along up), ``mouth`` (centre), ``mouth_left``, ``mouth_right``
    (corners), ``left_lid_upper/lower``, ``right_lid_upper/lower`` (lid edges through the pupil),
    ``lip_upper``, ``lip_lower`` (outer lip edges on the line through the mouth centre), ``up``
    (unit vector of the face's up axis).
    """
    u = state.ipd
    pose = _Pose.of(state)
    gx, gy = state.gaze_x * u, state.gaze_y * u
    out: dict[str, np.ndarray] = {}
    for side, ex, e, b, inner in (("left", -0.5 * u, state.eye_open_l, state.brow_l, 1.0),
                                  ("right", 0.5 * u, state.eye_open_r, state.brow_r, -1.0)):
        px = ex + gx
        out[f"{side}_pupil"] = np.array(pose.point(px, gy))
        yb = float(_brow_centre(gx / (BROW_HALF * u), float(np.clip(b, -1, 1)), inner, u))
        out[f"{side}_brow"] = np.array(pose.point(px, yb))
        up, lo = _eye_gaps(e, u)
        prof = float(_lid_profile(gx / (EYE_HW * u)))
        out[f"{side}_lid_upper"] = np.array(pose.point(px, -up * prof))
        out[f"{side}_lid_lower"] = np.array(pose.point(px, lo * prof))
    m = _mouth(state)
    out["mouth"] = np.array(pose.point(0.0, m.yc))
    out["mouth_left"] = np.array(pose.point(-m.half_w, m.yc))
    out["mouth_right"] = np.array(pose.point(m.half_w, m.yc))
    out["lip_upper"] = np.array(pose.point(0.0, float(m.outer_upper(0.0))))
    out["lip_lower"] = np.array(pose.point(0.0, float(m.outer_lower(0.0))))
    out["up"] = np.array([-pose.s, -pose.c])
    return out


def clicks_for(state: FaceState, frame: int = 0) -> dict:
    """The five calibration clicks of DESIGN.md's CLICKS.json for ``state`` (the files' pixel
    convention, :data:`~tracker.clicks.PIXEL_CENTRE`)."""
    lm = face_landmarks(state)
    r = lambda p: [round(float(p[0]) + PIXEL_CENTRE, 3), round(float(p[1]) + PIXEL_CENTRE, 3)]
    return {"frame": int(frame), "left_pupil": r(lm["left_pupil"]), "right_pupil": r(lm["right_pupil"]),
            "left_brow": r(lm["left_brow"]), "right_brow": r(lm["right_brow"]), "mouth": r(lm["mouth"])}


# ---------------------------------------------------------------------------------------------
# Rasterising


def _inset(pts: np.ndarray, d: float) -> np.ndarray:
    """Move each vertex of a closed polygon ``d`` pixels towards the inside."""
    nxt = np.empty_like(pts)
    nxt[:-1] = pts[1:]
    nxt[-1] = pts[0]
    tan = nxt - np.concatenate([pts[-1:], pts[:-1]])
    x, y = pts[:, 0], pts[:, 1]
    area2 = float(x @ nxt[:, 1] - nxt[:, 0] @ y)
    k = (d if area2 > 0 else -d) / (np.hypot(tan[:, 0], tan[:, 1]) + 1e-12)
    out = np.empty_like(pts)
    out[:, 0] = x - k * tan[:, 1]
    out[:, 1] = y + k * tan[:, 0]
    return out


class _Box:
    """An integer pixel box [x0, x1) × [y0, y1) inside the frame."""

    __slots__ = ("x0", "y0", "x1", "y1")

    def __init__(self, x0, y0, x1, y1):
        self.x0, self.y0, self.x1, self.y1 = x0, y0, x1, y1

    @classmethod
    def around(cls, polys: Sequence[np.ndarray], w: int, h: int, pad: int = 2) -> "_Box | None":
        allp = np.concatenate([p.reshape(-1, 2) for p in polys])
        if not np.all(np.isfinite(allp)):
            return None
        x0 = max(int(math.floor(allp[:, 0].min())) - pad, 0)
        y0 = max(int(math.floor(allp[:, 1].min())) - pad, 0)
        x1 = min(int(math.ceil(allp[:, 0].max())) + pad + 1, w)
        y1 = min(int(math.ceil(allp[:, 1].max())) + pad + 1, h)
        if x1 <= x0 or y1 <= y0:
            return None
        return cls(x0, y0, x1, y1)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.y1 - self.y0, self.x1 - self.x0)


def _coverage(polys: Sequence[np.ndarray], box: _Box, ss: int = 4) -> np.ndarray:
    """Fraction of each pixel of ``box`` covered by the union of ``polys`` (image coords), float32."""
    h, w = box.shape
    big = np.zeros((h * ss, w * ss), np.uint8)
    # sub-pixel j of pixel i has its centre at i - 0.5 + (j + 0.5) / ss; 4 fractional bits
    off = 16.0 * (np.array([(ss - 1) / 2.0, (ss - 1) / 2.0]) - ss * np.array([box.x0, box.y0], np.float64))
    ints = [np.rint(np.clip(_inset(p, 0.5 / ss) * (16.0 * ss) + off, -2e9, 2e9)).astype(np.int32)
            for p in polys if len(p) >= 3]
    if ints:
        cv2.fillPoly(big, ints, 255, cv2.LINE_8, 4)
    if ss == 1:
        return big.astype(np.float32) * (1.0 / 255.0)
    small = cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA)
    return small.astype(np.float32) * (1.0 / 255.0)


def _blend(buf: np.ndarray, bx: _Box, box: _Box, alpha: np.ndarray, colour) -> None:
    """Paint ``colour`` (BGR triple or per-pixel array) with coverage ``alpha`` into ``buf``.

    ``buf`` holds the pixels of ``bx``; ``box`` (inside ``bx``) is where ``alpha`` lives.
    """
    sub = buf[box.y0 - bx.y0 : box.y1 - bx.y0, box.x0 - bx.x0 : box.x1 - bx.x0]
    tmp = np.subtract(np.asarray(colour, np.float32), sub)
    tmp *= alpha[..., None]
    sub += tmp


def _clip_box(inner: _Box | None, outer: _Box) -> _Box | None:
    if inner is None:
        return None
    x0, y0 = max(inner.x0, outer.x0), max(inner.y0, outer.y0)
    x1, y1 = min(inner.x1, outer.x1), min(inner.y1, outer.y1)
    return _Box(x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def _ellipse(cx: float, cy: float, a: float, b: float) -> np.ndarray:
    return np.stack([cx + a * _COS, cy + b * _SIN], axis=1)


def _head_outline(u: float) -> np.ndarray:
    a, b = HEAD_A * u, HEAD_B * u
    narrow = 1.0 - 0.13 * np.clip(_SIN, 0.0, None) ** 1.5  # narrower towards the chin
    return np.stack([a * _COS * narrow, HEAD_CY * u + b * _SIN], axis=1)


# ---------------------------------------------------------------------------------------------
# The scene


@functools.lru_cache(maxsize=8)
def _background(w: int, h: int, colour: BGR) -> np.ndarray:
    """A quiet indoor wall: vertical gradient, a darker door panel, a shelf, soft texture."""
    rng = np.random.default_rng(1234)
    ys = np.linspace(0.0, 1.0, h, dtype=np.float32)[:, None, None]
    base = np.asarray(colour, np.float32)[None, None, :]
    img = base * (1.08 - 0.22 * ys) * np.ones((1, w, 1), np.float32)
    x0, x1 = int(0.04 * w), int(0.2 * w)
    img[int(0.12 * h):, x0:x1] *= np.array([0.78, 0.8, 0.84], np.float32)
    img[int(0.12 * h):int(0.12 * h) + max(2, h // 120), x0:x1] *= 0.8
    sy = int(0.3 * h)
    img[sy:sy + max(3, h // 80), int(0.72 * w):] *= np.array([0.72, 0.74, 0.78], np.float32)
    tex = cv2.GaussianBlur(rng.standard_normal((h, w)).astype(np.float32), (0, 0), 6.0)
    tex /= max(float(tex.std()), 1e-6)
    img += 3.0 * tex[..., None]
    out = np.clip(img, 0, 255).astype(np.uint8)
    out.setflags(write=False)
    return out


@functools.lru_cache(maxsize=4)
def _noise_bank(w: int, h: int, sigma: float) -> np.ndarray:
    """Gaussian noise of ``sigma`` grey levels, rounded to int16: 2 frames plus a margin; each
    frame adds a random window of it (cheap, and different from frame to frame)."""
    rng = np.random.default_rng(99)
    bank = np.rint(rng.standard_normal((2, h + 32, w + 32, 3), dtype=np.float32) * sigma).astype(np.int16)
    bank.setflags(write=False)
    return bank


SPRITE_BOX = (-1.3, -1.35, 1.3, 1.95)
"""Face-local box (units of ipd: x0, y0, x1, y1) of the head sprite: hair, ears, skin, nose."""
_SPRITE_LEVELS = (32, 48, 64, 96, 128, 192, 256, 384, 512)  # sprite scales (px per ipd): warps shrink ≤ 1.5x
FEATURE_BOX = (-0.95, -0.8, 0.95, 1.75)
"""Face-local box (units of ipd) holding every eye, brow and mouth shape at any expression."""


@functools.lru_cache(maxsize=16)
def _head_sprite(k: int, skin: BGR, hair: BGR, shading: float, texture: float = 0.0, blush: float = 0.0,
                 lip: BGR = (92, 78, 188)) -> tuple[np.ndarray, np.ndarray]:
    """The rigid parts of the head drawn once at ``k`` pixels per ipd: straight BGR and alpha, uint8.

    Sprite pixel (0, 0) is the face-local point ``(SPRITE_BOX[0], SPRITE_BOX[1]) · k``. Frames warp
    it into place (rotation, scale, shift), which costs far less than drawing these shapes.
    """
    x0, y0, x1, y1 = SPRITE_BOX
    sw, sh = int(math.ceil((x1 - x0) * k)), int(math.ceil((y1 - y0) * k))
    pose = _Pose(-x0 * k, -y0 * k, 1.0, 0.0)
    L = pose.apply
    box = _Box(0, 0, sw, sh)
    col = np.zeros((sh, sw, 3), np.float32)
    alpha = np.zeros((sh, sw, 1), np.float32)
    sk = np.asarray(skin, np.float32)

    def over(polys, colour):
        a = _coverage([L(p) for p in polys], box, 4)[..., None]
        col[:] = col * (1.0 - a) + a * np.asarray(colour, np.float32)
        alpha[:] = alpha * (1.0 - a) + a

    u = float(k)
    over([_ellipse(0.0, 0.12 * u, 1.1 * u, 1.38 * u)[_SIN < 0.25]], hair)
    over([_ellipse(sx * 0.98 * u, 0.22 * u, 0.14 * u, 0.24 * u) for sx in (-1, 1)], sk * 0.9)
    lx = (np.arange(sw, dtype=np.float32) + x0 * k)[None, :]
    ly = (np.arange(sh, dtype=np.float32) + y0 * k)[:, None]
    rx, ry = lx / (HEAD_A * u), (ly - HEAD_CY * u) / (HEAD_B * u)
    shade = 1.04 - shading * (0.2 * (rx * rx + ry * ry) ** 2 + 0.05 * rx)
    face = shade[..., None] * sk
    if blush > 0:  # redder cheeks: soft blobs pulled towards the lip colour
        cheeks = sum(np.exp(-(((lx - sx * 0.55 * u) ** 2 + (ly - 0.55 * u) ** 2) / (0.2 * u) ** 2)) for sx in (-1, 1))
        face += (0.35 * blush * cheeks)[..., None] * (np.asarray(lip, np.float32) * shade[..., None] - face)
    if texture > 0:  # static mottling of the skin, a few hundredths of its brightness
        rng = np.random.default_rng(4321)
        grain = cv2.GaussianBlur(rng.standard_normal((sh, sw)).astype(np.float32), (0, 0), max(0.025 * k, 0.6))
        grain /= max(float(grain.std()), 1e-6)
        face *= (1.0 + texture * grain)[..., None]
    over([_head_outline(u)], face)
    # hair over the forehead: the top of a slightly larger oval down to a hairline
    top = _ellipse(0.0, 0.12 * u, 1.07 * u, 1.34 * u)
    arc = top[top[:, 1] < 0.05 * u]  # angles π..2π: left side → over the top → right side
    hx = np.linspace(1.0, -1.0, 31) * u
    hairline = np.stack([hx, (-0.74 + 0.32 * (hx / u) ** 4) * u], axis=1)
    over([np.concatenate([arc, hairline])], hair)
    # nose: a soft shadow, a lighter tip, two nostrils
    over([_ellipse(0.0, 0.70 * u, 0.16 * u, 0.05 * u)], sk * 0.93)
    over([_ellipse(0.0, 0.58 * u, 0.12 * u, 0.1 * u)], sk * 1.04)
    over([_ellipse(sx * 0.085 * u, 0.65 * u, 0.04 * u, 0.022 * u) for sx in (-1, 1)], sk * 0.62)
    # straight (un-premultiplied) colour, pushed out past the edges so warping leaves no fringe
    wide_c = cv2.GaussianBlur(col, (0, 0), 0.05 * k)
    wide_a = cv2.GaussianBlur(alpha[..., 0], (0, 0), 0.05 * k)[..., None]
    straight = np.where(alpha > 1e-3, col / np.maximum(alpha, 1e-3), wide_c / np.maximum(wide_a, 1e-3))
    c8 = np.clip(straight + 0.5, 0, 255).astype(np.uint8)
    a8 = np.clip(alpha[..., 0] * 255.0 + 0.5, 0, 255).astype(np.uint8)
    c8.setflags(write=False)
    a8.setflags(write=False)
    return c8, a8


def _mul(c, k: float) -> tuple[float, float, float]:
    return (c[0] * k, c[1] * k, c[2] * k)


def _body_pose(st: FaceState, pose: _Pose) -> _Pose:
    """The torso's frame: origin at the neck's base, turned by a third of the head's roll."""
    pivot = pose.point(0.0, 2.0 * st.ipd)
    th = math.radians(0.3 * st.roll_deg)
    return _Pose(pivot[0], pivot[1], math.cos(th), math.sin(th))


def _draw_body(frame: np.ndarray, st: FaceState, style: Style, pose: _Pose) -> None:
    """Shirt and shoulders; they follow the head's position and a third of its roll."""
    u = st.ipd
    h, w = frame.shape[:2]
    body = _body_pose(st, pose)
    xs = np.linspace(-1.0, 1.0, 41)
    neckline = np.stack([0.55 * u * xs, 0.12 * u + 0.25 * u * (1 - xs ** 2)], axis=1)
    right = np.array([[0.9 * u, 0.25 * u], [1.6 * u, 0.45 * u], [2.3 * u, 0.9 * u], [2.7 * u, 6 * u]])
    left = right[::-1] * np.array([-1.0, 1.0])
    poly = body.apply(np.concatenate([left, neckline, right]))
    if _Box.around([poly], w, h) is None:
        return
    shirt = tuple(float(v) for v in style.shirt)
    cv2.fillPoly(frame, [np.round(np.clip(poly, -1e5, 1e5) * 16).astype(np.int32)], shirt, cv2.LINE_AA, 4)
    collar = body.apply(np.concatenate([neckline, neckline[::-1] + [0.0, 0.06 * u]]))
    cv2.fillPoly(frame, [np.round(np.clip(collar, -1e5, 1e5) * 16).astype(np.int32)],
                 _mul(shirt, 0.75), cv2.LINE_AA, 4)


def _draw_face(frame: np.ndarray, st: FaceState, style: Style) -> None:
    h, w = frame.shape[:2]
    u = st.ipd
    pose = _Pose.of(st)
    _draw_body(frame, st, style, pose)
    L = pose.apply  # local polygon → image polygon

    body = _body_pose(st, pose)
    neck = np.concatenate([L(np.array([[-0.40 * u, 1.2 * u], [0.40 * u, 1.2 * u]])),
                           body.apply(np.array([[0.46 * u, 0.3 * u], [-0.46 * u, 0.3 * u]]))])
    if _Box.around([neck], w, h) is not None:
        cv2.fillPoly(frame, [np.round(np.clip(neck, -1e5, 1e5) * 16).astype(np.int32)],
                     tuple(float(v) * 0.8 for v in style.skin),
                     cv2.LINE_AA, 4)
    # the rigid head (hair, ears, shaded skin, nose): a cached sprite warped into place
    x0, y0, x1, y1 = SPRITE_BOX
    hb = _Box.around([L(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]) * u)], w, h)
    if hb is not None:
        k = next((lv for lv in _SPRITE_LEVELS if lv >= u), _SPRITE_LEVELS[-1])
        s_col, s_alpha = _head_sprite(k, tuple(style.skin), tuple(style.hair), float(style.shading),
                                      float(style.texture), float(style.blush), tuple(style.lip))
        sc = u / k
        m = np.array([[pose.c * sc, pose.s * sc, 0.0], [-pose.s * sc, pose.c * sc, 0.0]])
        m[:, 2] = np.array(pose.point(x0 * u, y0 * u)) - [hb.x0, hb.y0]
        size = (hb.x1 - hb.x0, hb.y1 - hb.y0)
        col = cv2.warpAffine(s_col, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        alpha = cv2.warpAffine(s_alpha, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                               borderValue=0)
        a = alpha.astype(np.float32) * np.float32(1.0 / 255.0)
        sub = frame[hb.y0:hb.y1, hb.x0:hb.x1]
        sub[:] = cv2.blendLinear(sub, col, 1.0 - a, a)

    # eyes, brows and mouth: drawn exactly, in a float buffer around them
    fx0, fy0, fx1, fy1 = FEATURE_BOX
    bx = _Box.around([L(np.array([[fx0, fy0], [fx1, fy0], [fx1, fy1], [fx0, fy1]]) * u)], w, h, pad=3)
    if bx is None:
        return
    buf = frame[bx.y0:bx.y1, bx.x0:bx.x1].astype(np.float32)

    def paint(polys, colour, ss=4, box=None):
        box = box or _clip_box(_Box.around(polys, w, h), bx)
        if box is not None:
            _blend(buf, bx, box, _coverage(polys, box, ss), colour)

    def compose(box, base, layers):
        """``layers`` (polygons, colour[, supersampling]) painted over a ``base`` colour, as a
        (h, w, 3) array over ``box``; a colour may be a (h, w, 3) array over ``box`` too."""
        g = np.empty(box.shape + (3,), np.float32)
        g[:] = np.asarray(base, np.float32)
        for polys, colour, *ss in layers:
            lb = _clip_box(_Box.around(polys, w, h), box)
            if lb is None:
                continue
            col = np.asarray(colour, np.float32)
            if col.ndim == 3:
                col = col[lb.y0 - box.y0:lb.y1 - box.y0, lb.x0 - box.x0:lb.x1 - box.x0]
            _blend(g, box, lb, _coverage(polys, lb, ss[0] if ss else FEATURE_SS), col)
        return g

    def group(box, base, layers, outline):
        """Compose a feature in its own buffer, then paint it inside ``outline``: edge pixels then
        mix the feature with the skin under it exactly once (layers reach past the outline)."""
        _blend(buf, bx, box, _coverage(outline, box, FEATURE_SS), compose(box, base, layers))

    gx, gy = st.gaze_x * u, st.gaze_y * u
    hw = EYE_HW * u
    for ex, e, b, inner in ((-0.5 * u, st.eye_open_l, st.brow_l, 1.0), (0.5 * u, st.eye_open_r, st.brow_r, -1.0)):
        # eyebrow: thick arc around its middle line
        tb = _T_BROW
        xb = ex + tb * BROW_HALF * u
        yb = _brow_centre(tb, float(np.clip(b, -1, 1)), inner, u)
        thk = 0.5 * _brow_thickness(tb, inner, u)
        brow = np.concatenate([np.stack([xb, yb - thk], 1), np.stack([xb, yb + thk], 1)[::-1]])
        paint([L(brow)], style.brow, ss=FEATURE_SS)

        # eye: lash line, white opening, iris, pupil, catch-light — all inside the lids
        up, lo = _eye_gaps(e, u)
        xe = ex + _T_EYE * hw
        prof = _lid_profile(_T_EYE)
        yu, yl = -up * prof, lo * prof
        lash_t = style.lash_width * u * (0.35 + 0.65 * prof ** 0.3)
        lash = np.concatenate([np.stack([xe, yu - lash_t], 1), np.stack([xe, yu + lash_t], 1)[::-1]])
        white = np.concatenate([np.stack([xe, yu], 1), np.stack([xe, yl], 1)[-2:0:-1]])
        iris_pts = L(_ellipse(ex + gx, gy, IRIS_R * u, IRIS_R * u))
        eye_box = _clip_box(_Box.around([L(lash), iris_pts], w, h), bx)
        if eye_box is None:
            continue
        if style.lash_width > 0:
            paint([L(lash)], style.lash if style.lash is not None else style.brow, box=eye_box)
        if up + lo < 0.02:
            continue
        c = ex + gx
        layers = [([iris_pts], _mul(style.iris, style.limbus), 4),
                  ([L(_ellipse(c, gy, 0.8 * IRIS_R * u, 0.8 * IRIS_R * u))], style.iris, 4),
                  ([L(_ellipse(c, gy, PUPIL_R * u, PUPIL_R * u))], style.pupil)]
        if style.catchlight:
            layers.append(([L(_ellipse(c + 0.032 * u, gy - 0.032 * u, 0.016 * u, 0.016 * u))], (245, 248, 250), 4))
        group(eye_box, style.sclera, layers, [L(white)])

    # mouth: dark interior (teeth, tongue) under the two lips
    m = _mouth(st)
    t = _T_LIP
    xm = t * m.half_w
    iu, il = m.inner_upper(t), m.inner_lower(t)
    ou, ol = m.outer_upper(t), m.outer_lower(t)
    hole = np.concatenate([np.stack([xm, iu], 1), np.stack([xm, il], 1)[-2:0:-1]])
    outline = np.concatenate([np.stack([xm, ou], 1), np.stack([xm, ol], 1)[-2:0:-1]])
    mbox = _clip_box(_Box.around([L(outline)], w, h), bx)
    if mbox is not None:
        # lower-lip colour everywhere, the upper lip above the lips' meeting line, the
        # interior (with tongue and teeth) inside the inner edges; all cut to the outline
        mg = max(2.0, 0.05 * u)
        meet = 0.5 * (iu + il)
        upper_ext = np.concatenate([[[-m.half_w - mg, m.yc]], np.stack([xm, ou - mg], 1), [[m.half_w + mg, m.yc]],
                                    np.stack([xm, meet], 1)[::-1]])
        inner = []
        if m.y_il0 - m.y_iu0 > 0.04 * u:
            tongue = _ellipse(0.0, m.y_il0, 0.55 * m.half_w, 0.16 * u)
            inner.append(([L(tongue)], _mul(np.add(style.mouth, style.lip) / 2.0, 0.8), 4))
            if st.teeth:
                tt = t[np.abs(t) <= 0.75]
                band = np.concatenate([np.stack([tt * m.half_w, m.inner_upper(tt) - 0.05 * u], 1),
                                       np.stack([tt * m.half_w, m.inner_upper(tt) + 0.075 * u], 1)[::-1]])
                inner.append(([L(band)], style.teeth, 4))
        interior = compose(mbox, style.mouth, inner)
        group(mbox, style.lip, [([L(upper_ext)], _mul(style.lip, 0.86)), ([L(hole)], interior)], [L(outline)])

    frame[bx.y0:bx.y1, bx.x0:bx.x1] = _to_u8(buf)


def _to_u8(buf: np.ndarray) -> np.ndarray:
    np.clip(buf, 0, 255, out=buf)
    buf += 0.5
    return buf.astype(np.uint8)


def _degrade(frame: np.ndarray, style: Style, light, rng: np.random.Generator) -> np.ndarray:
    """Camera effects in order: lighting gain, blur, sensor noise, JPEG."""
    if tuple(light) != (1.0, 1.0, 1.0):
        lut = np.clip(np.arange(256, dtype=np.float32)[:, None] * np.asarray(light, np.float32)[None, :] + 0.5,
                      0, 255).astype(np.uint8)
        frame = cv2.LUT(frame, lut.reshape(256, 1, 3))
    if style.blur > 0:
        frame = cv2.GaussianBlur(frame, (0, 0), style.blur)
    if style.noise > 0:
        h, w = frame.shape[:2]
        bank = _noise_bank(w, h, round(float(style.noise), 2))
        k, oy, ox = int(rng.integers(2)), int(rng.integers(32)), int(rng.integers(32))
        frame = cv2.add(frame, bank[k, oy:oy + h, ox:ox + w], dtype=cv2.CV_8U)
    if style.jpeg_quality and 0 < style.jpeg_quality <= 100:
        ok, enc = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, int(style.jpeg_quality)])
        if ok:
            frame = cv2.imdecode(enc, cv2.IMREAD_COLOR)
    return frame


def render_face(
    state: FaceState,
    style: Style | None = None,
    frame_size: tuple[int, int] = (640, 480),
    rng: np.random.Generator | None = None,
    frame: int = 0,
    time: float = 0.0,
) -> tuple[np.ndarray, FaceParams]:
    """Draw ``state`` into a ``frame_size`` (w, h) BGR uint8 frame and return it with its truth.

    ``rng`` drives the sensor noise (a fixed seed if omitted, so calls are reproducible);
    ``frame`` and ``time`` are copied into the returned :class:`FaceParams`.
    """
    style = style or STYLES["default"]
    w, h = int(frame_size[0]), int(frame_size[1])
    if w <= 0 or h <= 0:
        raise ValueError(f"frame size must be positive, got {frame_size}")
    truth = face_truth(state, frame=frame, time=time, frame_size=(w, h))
    img = _background(w, h, tuple(int(c) for c in style.background)).copy()
    if state.visible:
        _draw_face(img, state, style)
    img = _degrade(img, style, state.light, rng if rng is not None else np.random.default_rng(0))
    return img, truth


# ---------------------------------------------------------------------------------------------
# Scripted performances


def _smooth_noise(rng: np.random.Generator, t: np.ndarray, f_lo: float, f_hi: float, k: int = 4,
                  gain: float = 0.9) -> np.ndarray:
    """A smooth random curve: ``tanh(gain · v)`` of a unit-variance sum of ``k`` sinusoids."""
    f = rng.uniform(f_lo, f_hi, k)
    ph = rng.uniform(0, 2 * np.pi, k)
    wts = rng.uniform(0.5, 1.0, k)
    v = (wts[:, None] * np.sin(2 * np.pi * f[:, None] * t[None, :] + ph[:, None])).sum(0)
    v /= math.sqrt(float((wts ** 2).sum()) / 2.0)
    return np.tanh(gain * v)


def _bump(t: np.ndarray, t0: float, dur: float, attack: float = 0.3) -> np.ndarray:
    """A smooth 0→1→0 pulse starting at ``t0`` lasting ``dur`` seconds (raised-cosine edges)."""
    a = max(attack * dur, 1e-3)
    x = np.clip((t - t0) / a, 0, 1)
    y = np.clip((t0 + dur - t) / a, 0, 1)
    return (0.5 - 0.5 * np.cos(np.pi * x)) * (0.5 - 0.5 * np.cos(np.pi * y))


class SynthError(RuntimeError):
    """A synthetic clip could not be written (message names the file)."""


class Performance:
    """A scripted, seeded performance of the synthetic performer.

    Frame 0 is always neutral, frontal, eyes open and centred (the calibration frame); the
    expression fades in over the first ``ramp`` seconds, the head's motion over twice that. Options:
    ``talk`` (syllables of ah / ee / oo / eh with pauses), ``blink`` (every 2–5 s, some winks
    and double blinks), ``brows`` (raises and frowns), ``smiles``, ``gaze`` (small eye
    movements), ``roll_amplitude`` (degrees, default ``style.roll_max``), ``drift`` (fraction of
    the frame the face wanders over), ``scale_amplitude`` (leaning in / out, ±fraction of the
    ipd), ``away`` (intervals in seconds when the face is gone: ``away_mode`` "vanish" hides it,
    "slide" moves it out of the frame sideways and back), ``script`` (a function
    ``(index, FaceState) -> FaceState`` applied last, for custom tests).
    """

    def __init__(
        self,
        seconds: float = 10.0,
        fps: float = 30.0,
        seed: int = 0,
        frame_size: tuple[int, int] = (640, 480),
        style: Style | None = None,
        *,
        ipd: float | None = None,
        centre: tuple[float, float] | None = None,
        roll_amplitude: float | None = None,
        drift: float = 0.12,
        scale_amplitude: float = 0.2,
        talk: bool = True,
        blink: bool = True,
        brows: bool = True,
        smiles: bool = True,
        gaze: bool = True,
        away: Sequence[tuple[float, float]] = (),
        away_mode: str = "vanish",
        ramp: float = 0.7,
        script: Callable[[int, FaceState], FaceState] | None = None,
    ):
        if away_mode not in ("vanish", "slide"):
            raise ValueError(f"away_mode must be 'vanish' or 'slide', got {away_mode!r}")
        if fps <= 0:
            raise ValueError(f"fps must be positive, got {fps}")
        if seconds < 0:
            raise ValueError(f"seconds must be >= 0, got {seconds}")
        self.style = style or STYLES["default"]
        self.fps = float(fps)
        self.seed = int(seed)
        self.frame_size = (int(frame_size[0]), int(frame_size[1]))
        w, h = self.frame_size
        self.n = max(1, int(round(seconds * fps)))
        self.script = script
        scale = min(w / 640.0, h / 480.0)
        self.ipd = float(ipd) if ipd is not None else self.style.ipd * scale
        cx0, cy0 = centre if centre is not None else (0.5 * w, 0.44 * h)
        roll_amp = self.style.roll_max if roll_amplitude is None else float(roll_amplitude)

        rng = np.random.default_rng([self.seed, 7])
        t = np.arange(self.n) / self.fps
        T = t[-1] + 1.0 / self.fps
        env = np.clip(t / max(ramp, 1e-6), 0, 1)
        env = env * env * (3 - 2 * env)
        penv = np.clip(t / max(2.0 * ramp, 1e-6), 0, 1)  # the head's pose fades in more slowly
        penv = penv * penv * (3 - 2 * penv)
        n = self.n
        arr = lambda v=0.0: np.full(n, v, np.float64)

        # mostly within ±half the amplitude, reaching the full amplitude now and then
        self._roll = np.clip(roll_amp * penv * _smooth_noise(rng, t, 0.05, 0.25, gain=0.45) / math.tanh(0.45 * 2.4),
                             -roll_amp, roll_amp)
        self._cx = cx0 + drift * w * penv * _smooth_noise(rng, t, 0.03, 0.15)
        self._cy = cy0 + 0.6 * drift * h * penv * _smooth_noise(rng, t, 0.03, 0.15)
        self._ipd = self.ipd * (1.0 + scale_amplitude * penv * _smooth_noise(rng, t, 0.03, 0.12))

        mouth, pucker, smile_t, teeth = arr(), arr(), arr(), np.zeros(n, bool)
        if talk:
            vowels = {"ah": (0.7, 1.0, 0.0, 0.0, True), "eh": (0.4, 0.6, 0.15, 0.0, True),
                      "ee": (0.2, 0.35, 0.45, 0.0, True), "oo": (0.2, 0.35, 0.0, 0.85, False),
                      "mm": (0.0, 0.08, 0.0, 0.0, False)}
            names = list(vowels)
            tc = 0.5 + rng.uniform(0.0, 0.6)
            while tc < T:
                end = min(tc + rng.uniform(1.0, 3.0), T)
                rate = rng.uniform(3.5, 5.5)
                while tc < end:
                    dur = rng.uniform(0.7, 1.3) / rate
                    lo, hi, sm, pk, th = vowels[names[int(rng.choice(5, p=[0.3, 0.25, 0.2, 0.15, 0.1]))]]
                    b = _bump(t, tc, dur, 0.45)
                    amp = rng.uniform(lo, hi)
                    mouth = np.maximum(mouth, amp * b)
                    pucker = np.maximum(pucker, pk * rng.uniform(0.8, 1.0) * b)
                    smile_t += sm * b
                    if th:
                        teeth |= b * amp > 0.12
                    tc += dur
                tc = end + rng.uniform(0.4, 1.5)
        smile = arr()
        if smiles:
            smile += 0.12 * _smooth_noise(rng, t, 0.05, 0.2) * env
            tc = 0.8 + rng.uniform(0.0, 2.0)
            first = True
            while tc < T:
                dur = rng.uniform(1.0, 3.0)
                amp = rng.uniform(0.6, 1.0) if first or rng.random() > 0.25 else -rng.uniform(0.4, 0.8)
                first = False
                smile = smile + amp * _bump(t, tc, dur, 0.3)
                tc += dur + rng.uniform(1.5, 5.0)
        smile = np.clip(smile + smile_t, -1, 1)

        brow_l, brow_r = arr(), arr()
        if brows:
            tc = 0.8 + rng.uniform(0.0, 2.0)
            first = True
            while tc < T:
                dur = rng.uniform(0.6, 1.6)
                amp = rng.uniform(0.5, 1.0) if first or rng.random() > 0.3 else -rng.uniform(0.5, 0.9)
                first = False
                b = amp * _bump(t, tc, dur, 0.3)
                brow_l += b * rng.uniform(0.85, 1.0)
                brow_r += b * rng.uniform(0.85, 1.0)
                tc += dur + rng.uniform(1.5, 5.0)
            brow_l += 0.08 * env * _smooth_noise(rng, t, 0.1, 0.5)
            brow_r += 0.08 * env * _smooth_noise(rng, t, 0.1, 0.5)
        brow_l, brow_r = np.clip(brow_l, -1, 1), np.clip(brow_r, -1, 1)

        base = 1.0 + (0.06 * env * _smooth_noise(rng, t, 0.1, 0.4) if blink else 0.0)
        base += 0.2 * np.clip((brow_l + brow_r) / 2, 0, None) - 0.25 * np.clip(smile, 0, None)
        eye_l, eye_r = base.copy(), base.copy()
        if blink:
            tc = 0.6 + rng.uniform(0.5, 2.5)
            while tc < T:
                kind = rng.random()
                reps = 2 if kind > 0.9 else 1
                for r in range(reps):
                    dur = rng.uniform(0.15, 0.28)
                    close = 1.0 - _bump(t, tc, dur, 0.45)
                    if 0.8 < kind <= 0.9:  # wink
                        (eye_l if rng.random() < 0.5 else eye_r)[:] *= close
                    else:
                        eye_l *= close
                        eye_r *= close
                    tc += dur + 0.08
                tc += rng.uniform(2.0, 5.0)
        self._eye_l, self._eye_r = np.clip(eye_l, 0, 1.3), np.clip(eye_r, 0, 1.3)
        self._brow_l, self._brow_r = brow_l, brow_r
        self._mouth, self._smile = np.clip(mouth, 0, 1), smile
        self._pucker, self._teeth = np.clip(pucker, 0, 1), teeth
        if gaze:
            self._gx = 0.035 * env * _smooth_noise(rng, t, 0.2, 0.8)
            self._gy = 0.012 * env * _smooth_noise(rng, t, 0.2, 0.8)
        else:
            self._gx, self._gy = arr(), arr()
        self._visible = np.ones(n, bool)
        for a, b in away:
            if away_mode == "vanish":
                self._visible &= ~((t >= a) & (t < b))
                continue
            # slide out sideways in 0.8 s, stay out, slide back in
            side = -1.0 if self._cx[min(int(a * self.fps), n - 1)] < 0.5 * w else 1.0
            out = np.clip(np.minimum((t - a) / 0.8, (b - t) / 0.8), 0.0, 1.0)
            out = out * out * (3 - 2 * out)
            self._cx = self._cx + side * out * (0.5 * w + 4.0 * self._ipd)
        amp = self.style.lighting_drift
        if amp > 0:
            g = 1.0 + amp * env * _smooth_noise(rng, t, 0.05, 0.2)
            tint = 0.3 * amp * env[:, None] * np.stack([_smooth_noise(rng, t, 0.05, 0.2) for _ in range(3)], 1)
            self._light = g[:, None] * (1.0 + tint)
        else:
            self._light = np.ones((n, 3))

    def __len__(self) -> int:
        return self.n

    def _check(self, i: int) -> int:
        if not -self.n <= i < self.n:
            raise IndexError(f"frame {i} out of range 0..{self.n - 1}")
        return i % self.n

    def state(self, i: int) -> FaceState:
        """The performer's state in frame ``i``."""
        i = self._check(i)
        st = FaceState(
            cx=float(self._cx[i]), cy=float(self._cy[i]), roll_deg=float(self._roll[i]), ipd=float(self._ipd[i]),
            eye_open_l=float(self._eye_l[i]), eye_open_r=float(self._eye_r[i]),
            brow_l=float(self._brow_l[i]), brow_r=float(self._brow_r[i]),
            mouth_open=float(self._mouth[i]), smile=float(self._smile[i]), pucker=float(self._pucker[i]),
            teeth=bool(self._teeth[i]), visible=bool(self._visible[i]),
            gaze_x=float(self._gx[i]), gaze_y=float(self._gy[i]),
            light=tuple(float(v) for v in self._light[i]),
        )
        return self.script(i, st) if self.script is not None else st

    def time(self, i: int) -> float:
        return self._check(i) / self.fps

    def render(self, i: int) -> tuple[np.ndarray, FaceParams]:
        """Frame ``i`` and its truth (noise seeded by (seed, i), so any frame is reproducible)."""
        i = self._check(i)
        rng = np.random.default_rng([self.seed, i, 11])
        return render_face(self.state(i), self.style, self.frame_size, rng, frame=i, time=i / self.fps)

    def frame(self, i: int) -> np.ndarray:
        """Frame ``i`` as BGR uint8."""
        return self.render(i)[0]

    def truth(self, i: int) -> FaceParams:
        """The exact parameters of frame ``i``."""
        i = self._check(i)
        return face_truth(self.state(i), frame=i, time=i / self.fps, frame_size=self.frame_size)

    def truths(self) -> list[FaceParams]:
        return [self.truth(i) for i in range(self.n)]

    def __iter__(self) -> Iterator[np.ndarray]:
        for i in range(self.n):
            yield self.frame(i)

    def clicks(self) -> dict:
        """CLICKS.json content for frame 0 (neutral, frontal, eyes open)."""
        return clicks_for(self.state(0), frame=0)

    def write(
        self,
        video_path: str | os.PathLike,
        truth_csv_path: str | os.PathLike | None = None,
        progress: Callable[[int, int], None] | None = None,
    ) -> Path:
        """Write the clip, its truth CSV and ``<video stem>.clicks.json`` beside the video.

        The codec follows the suffix: ``.mp4`` → mp4v, ``.avi`` → MJPG, ``.mkv`` → FFV1
        (lossless). Each file is written to a temporary name and renamed when complete.
        ``progress(done, total)`` is called after each frame. Returns the clicks path.
        """
        video_path = Path(video_path)
        fourcc = {".mp4": "mp4v", ".m4v": "mp4v", ".mov": "mp4v", ".avi": "MJPG", ".mkv": "FFV1"}.get(
            video_path.suffix.lower())
        if fourcc is None:
            raise SynthError(f"{video_path}: unsupported video suffix (use .mp4, .avi or .mkv)")
        if not video_path.parent.is_dir():
            raise SynthError(f"{video_path}: folder {video_path.parent} does not exist")
        with atomic_file.replacing(video_path, suffix=video_path.suffix) as tmp:
            writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*fourcc), self.fps, self.frame_size)
            if not writer.isOpened():
                raise SynthError(f"{video_path}: cannot open a {fourcc} video writer")
            try:
                for i in range(self.n):
                    writer.write(self.frame(i))
                    if progress is not None:
                        progress(i + 1, self.n)
            finally:
                writer.release()
        if truth_csv_path is not None:
            write_csv(truth_csv_path, self.truths())
        clicks_path = video_path.with_name(video_path.stem + ".clicks.json")
        _write_json(clicks_path, self.clicks())
        return clicks_path


def _write_json(path: Path, data: Mapping) -> None:
    atomic_file.write_text(path, json.dumps(data, indent=1) + "\n")
