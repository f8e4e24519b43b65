"""Harder copies of the real clips: what other cameras, rooms and people do to the same faces.

The nine shared clips are well lit, sharp, 480–512 px and mostly still. The clips the tracker is
judged on are not all like that, so this makes variants of each clip with the peer's points moved
along with the pixels, in the same layout as ``../shared/real/`` (``NAME.mp4``, ``.clicks.json``,
``.mp.csv``, ``.points.csv``), ready for ``python -m benchmarks.realfaces --dir OUT/VARIANT``:

======== ==================================================================================
half     half the resolution (a 256 px face crop: a cheap webcam, a face far away)
third    a third of the resolution (about 35 px between the eyes: the smallest face worth tracking)
small    the clip at 0.45× inside a 640×480 frame, drifting slowly (a small face in a room)
shake    shifted and turned every frame (a hand-held phone, a fast-moving head)
jolt     the same kind of wander, each frame smeared along its motion over half the frame time (a
         webcam's exposure in room light: the faster the move, the blurrier the face)
noisy    sensor noise σ 8 and JPEG quality 40 (a dark room's gain, a streaming codec)
dim      the light falls to half over the clip, turning warm (auto-exposure, a lamp)
step     the light jumps between full and 55 % every quarter of the clip (a lamp switched, an
         exposure step)
side     light from one side: full on the frame's left, falling smoothly to 40 % on its right (a
         window beside the desk)
shade    the side light of ``side`` comes up over the clip, from none to all of it (the sun going
         off a window, a lamp on one side): calibration sees even light
pale     colour halved (pale or low-contrast lips, a washed-out camera)
washed   a third of the colour kept (a cheap webcam in a dim room, whose colours are mostly gone)
lowlight a dim room at night: the light at 30 %, sensor noise, the gain bringing it back (a third
         of the grey levels left, the noise tripled) and 40 % of the colour lost, as webcams do
warm     a tungsten lamp's cast from the first frame on: blue at 72 %, red at 115 %, so calibration
         sees it too (a living room in the evening)
blur     out of focus (Gaussian σ 1.6 px)
mirror   flipped left to right (every left/right rule must hold both ways)
tilt     the picture turns slowly about its middle, up to 25° each way and back, a wave of 175
         frames (a head tilted far to one shoulder, a laptop on the knees)
lean     the picture grows and shrinks slowly about its middle, from 0.6× to 1.2×, a wave of 225
         frames (leaning back from the camera and in towards it)
leave    the face slides out of the frame sideways, stays away a second, and slides back
covered  a skin-coloured hand passes over the face and covers it for a second
beard    a dark, full beard and moustache round the mouth, following the face (hair where the
         tracker expects the skin beside the lips)
deep     the face darkened to a deep brown, all of it alike (a washed-out forehead too) but the
         whites of the eyes between the peer's lids and the teeth between its lips, and outside the
         face whatever has skin's colour (a darker-skinned face: the brows, the lashes, a brown iris
         and the mouth's inside barely darker than the skin; a grey or green iris lighter than it)
darkeyes ``deep`` with each iris, where it shows between the peer's lids, darkened to
         :data:`DARK_IRIS` of its light: the usual eye of a darker-skinned face, a dark brown iris
         darker than the skin round it (``deep`` keeps the clip's own, often lighter, irises)
glasses  dark plastic spectacle frames round both eyes, with a bridge, the arms and a glare on
         the lenses that moves as the head moves (a rim between the eye and the brow and under the
         lower lid, a bright streak near or over the eye)
child    a young child's proportions: each eye 25 % larger about its pupil, and the face under the
         eyes drawn up towards them, most just under the lower lids (the mouth about 0.95 of the
         eye distance below the eyes, where an adult's is 1.05-1.2); brows and forehead as they were
late     the clip from 40 % of its length on, with the clicks put on the peer's points there (a
         performance joined in the middle: the first frame, which calibration and ``--auto`` look
         at, shows whatever the face was doing — a grimace, a word, a blink)
cheap    half the resolution, the light at 60 %, sensor noise σ 5 and JPEG quality 50 all at once (a
         cheap laptop webcam in a dim room: each alone is ``half``, ``dim``, ``noisy``; together the
         lips and the skin under the nose blur into one another)
choppy   every other frame dropped, at half the frame rate (a webcam that falls to 12-15 frames a
         second on a slow machine or a busy link: each step of the head twice as long)
======== ==================================================================================

In ``leave`` and ``covered`` the peer's points that are out of the frame or under the hand are
blank (NaN), and a frame with any point blank has no parameters: the face is not in view there,
so it counts neither as lost nor in the correlations, and its return is timed (frames to our first
``ok``). A frame whose two pupils are both blank is one where the face is away: reporting ``ok``
there is a dishonest status.

``python -m benchmarks.stress_clips --out out/stress [--variants half,noisy]`` writes them (a few
seconds a variant). Nothing here is committed data: the variants are made from the shared clips.
The peer's parameters of a variant are recomputed from its moved points with the definitions of
the shared folder's README, so they agree with the points exactly.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path
from typing import Callable, Sequence

import cv2
import numpy as np

from benchmarks.realfaces import clip_names, real_dir
from tracker.clicks import PIXEL_CENTRE
from tracker.params import PARAM_NAMES

POINTS = (
    "left_pupil", "right_pupil", "left_upper_lid", "left_lower_lid", "right_upper_lid", "right_lower_lid",
    "left_brow", "right_brow", "left_mouth_corner", "right_mouth_corner", "upper_lip_top", "lower_lip_bottom",
)
VARIANTS = ("half", "third", "small", "shake", "jolt", "tilt", "lean", "noisy", "dim", "step", "side", "shade", "pale",
            "washed", "lowlight", "warm", "blur", "mirror", "leave", "covered", "beard", "glasses", "deep",
            "darkeyes", "child", "late", "cheap", "choppy")
LATE = 0.4
"""Where in the clip (share of its frames) the ``late`` variant starts."""
STEP_LIGHT = 0.55
"""The light in the dark quarters of ``step`` (× the clip's)."""
WASHED_COLOUR = 0.35
"""Share of the colour the ``washed`` variant keeps (the rest is the pixel's grey)."""
LOW_LIGHT = (0.3, 2.5, 0.6)
"""The ``lowlight`` variant: the light's share, the sensor noise (σ, grey levels, before the gain
brings the level back by the light's inverse) and the share of the colour left."""
WARM_BGR = (0.72, 0.95, 1.15)
"""The ``warm`` variant's cast: each channel's factor (B, G, R), a tungsten lamp's."""
SIDE_LIGHT = 0.4
"""The light on the frame's right edge in ``side`` (× the clip's; the left edge keeps all of it)."""
CHEAP = (0.5, 0.6, 5.0, 50)
"""The ``cheap`` variant: its scale, the light's share, the sensor noise (σ, grey levels, after the
light falls) and the JPEG quality."""
SHRUNK = {"half": 0.5, "third": 1.0 / 3.0, "cheap": CHEAP[0]}
"""The variants whose whole picture is shrunk (area-averaged), and by how much."""
EXPOSURE = (0.5, 8)
"""The ``jolt`` variant's exposure (share of the frame time, ending at the frame) and the warped
copies averaged over it."""
AWAY = (0.4, 15, 25)
"""The away variants' event: it starts at this share of the clip, takes this many frames to go (and
as many to come back) and stays away this many frames. Leaving the frame in 15 frames moves the
face about 0.4 IPD a frame (a brisk lean out of view, 0.6 m/s); in 6 frames it was a whole IPD a
frame (1.5 m/s), faster than any frame-to-frame search can follow on re-entry."""


def _away_curve(n: int) -> np.ndarray:
    """(n,) 0 → 1 → 0: how far the face has gone (``leave``) or the hand has come (``covered``)."""
    a, ramp, hold = int(AWAY[0] * n), AWAY[1], AWAY[2]
    t = np.zeros(n)
    for i in range(n):
        k = i - a
        if 0 <= k < ramp:
            t[i] = (k + 1) / ramp
        elif ramp <= k < ramp + hold:
            t[i] = 1.0
        elif ramp + hold <= k < 2 * ramp + hold:
            t[i] = 1.0 - (k - ramp - hold + 1) / ramp
    return t


def _affine_frames(n: int, kind: str, size: tuple[int, int], seed: int) -> tuple[list[np.ndarray], tuple[int, int]]:
    """Per-frame 2×3 maps (source px → output px) and the output size (w, h) of a geometric variant."""
    w, h = size
    rng = np.random.default_rng(seed)
    eye = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    if kind in SHRUNK:
        s = SHRUNK[kind]
        m = np.array([[s, 0.0, 0.5 * s - 0.5], [0.0, s, 0.5 * s - 0.5]])
        return [m] * n, (int(round(w * s)), int(round(h * s)))
    if kind == "mirror":
        return [np.array([[-1.0, 0.0, w - 1.0], [0.0, 1.0, 0.0]])] * n, (w, h)
    if kind == "small":
        s, W, H = 0.45, 640, 480
        t = np.arange(n) / 25.0
        ox = 0.5 * (W - s * w) + 0.25 * (W - s * w) * np.sin(2 * math.pi * t / 9.0 + rng.uniform(0, 6.28))
        oy = 0.5 * (H - s * h) + 0.2 * (H - s * h) * np.sin(2 * math.pi * t / 7.0 + rng.uniform(0, 6.28))
        return [np.array([[s, 0.0, ox[i]], [0.0, s, oy[i]]]) for i in range(n)], (W, H)
    if kind in ("shake", "jolt"):
        # a hand-held camera: a smooth random wander of ±30 px and ±8° with quick jolts
        def wander(amp: float) -> np.ndarray:
            k = np.cumsum(rng.normal(0.0, 1.0, n + 30))
            k = np.convolve(k, np.ones(9) / 9.0, mode="same")[15 : 15 + n]
            k -= k.mean()
            return amp * k / max(np.abs(k).max(), 1e-6)

        dx, dy, da = wander(30.0), wander(24.0), wander(8.0)
        out = []
        for i in range(n):
            m = cv2.getRotationMatrix2D((0.5 * w, 0.5 * h), float(da[i]), 1.0)
            m[:, 2] += (dx[i], dy[i])
            out.append(m)
        return out, (w, h)
    if kind in ("tilt", "lean"):
        # slow and smooth waves (7 s and 9 s at 25 frames a second), none on the first frame, where calibration looks
        t = np.arange(n) / 25.0
        out = []
        for i in range(n):
            if kind == "tilt":
                m = cv2.getRotationMatrix2D((0.5 * w, 0.5 * h), 25.0 * math.sin(2 * math.pi * t[i] / 7.0), 1.0)
            else:
                m = cv2.getRotationMatrix2D((0.5 * w, 0.5 * h), 0.0, 0.9 + 0.3 * math.sin(2 * math.pi * t[i] / 9.0 + math.asin(1.0 / 3.0)))
            out.append(m)
        return out, (w, h)
    if kind == "leave":  # slides out to the left, past the frame's edge, and back
        t = _away_curve(n)
        return [np.array([[1.0, 0.0, -1.15 * w * t[i]], [0.0, 1.0, 0.0]]) for i in range(n)], (w, h)
    return [eye] * n, (w, h)


def _room(first: np.ndarray) -> np.ndarray:
    """A background for a frame the face has left: the first frame's top-left corner (away from the
    face), blown up and blurred — the room's colours, no face."""
    h, w = first.shape[:2]
    corner = first[: max(h // 6, 4), : max(w // 6, 4)]
    return cv2.GaussianBlur(cv2.resize(corner, (w, h), interpolation=cv2.INTER_LINEAR), (0, 0), 6.0)


def _eye_line(lp: np.ndarray, rp: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The face's frame from its pupils (image px): their distance, the unit vector along the eye
    line (towards the image-right eye) and the face's down (across it, y down)."""
    d = float(np.hypot(*(rp - lp)))
    u = (rp - lp) / max(d, 1e-6)
    return d, u, np.array([-u[1], u[0]])


def _fixed(pts) -> np.ndarray:
    """Points (image px, float) in the fixed point with 3 fractional bits that OpenCV's drawing
    takes with ``shift=3``: outlines placed to an eighth of a pixel."""
    return np.round(np.asarray(pts) * 8).astype(np.int32)


def _hand(frames: list[np.ndarray], points: dict[str, np.ndarray], seed: int):
    """What ``covered`` draws: a per-frame function painting a hand (a shaded, textured ellipse of
    the face's own skin colour, about the face's size) that comes in from the right, covers the face
    and leaves; and per frame the hand's centre and axes (px) to tell which points it hides."""
    n = len(frames)
    h, w = frames[0].shape[:2]
    t = _away_curve(n)
    lp, rp = points["left_pupil"], points["right_pupil"]
    ipd = float(np.nanmedian(np.hypot(*(rp - lp).T)))
    centre = 0.5 * (lp + rp) + np.array([0.0, 0.45 * ipd])  # between the eyes and the mouth
    centre = np.where(np.isfinite(centre), centre, np.nanmedian(centre, axis=0))
    ax = (1.25 * ipd, 1.6 * ipd)
    start_x = w + ax[0] + 2.0
    cx = start_x + (centre[:, 0] - start_x) * t
    cy = centre[:, 1]
    box = frames[0][int(max(centre[0, 1] - 0.6 * ipd, 0)) : int(centre[0, 1] + 0.6 * ipd),
                    int(max(centre[0, 0] - 0.6 * ipd, 0)) : int(centre[0, 0] + 0.6 * ipd)].reshape(-1, 3)
    skin = np.median(box, axis=0).astype(np.float32) * 0.92
    rng = np.random.default_rng(seed)
    texture = cv2.GaussianBlur(rng.normal(0.0, 1.0, (h, w)).astype(np.float32), (0, 0), 2.0) * 12.0

    def paint(img: np.ndarray, i: int) -> np.ndarray:
        return img if t[i] <= 0.0 else paint_hand(img, (cx[i], cy[i]), ax, skin, texture)

    return paint, cx, cy, ax


def paint_hand(img: np.ndarray, centre, axes: tuple[float, float], skin: np.ndarray,
               texture: np.ndarray | None = None) -> np.ndarray:
    """``img`` (uint8 BGR) with a hand painted over it: an ellipse (``centre``, semi-axes ``axes``,
    px) of the colour ``skin`` (BGR), shaded like a rounded thing lit from the left, with a soft edge
    of a few px and ``texture`` (float, the image's size: added grey levels) on it."""
    h, w = img.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    u, v = (xx - centre[0]) / axes[0], (yy - centre[1]) / axes[1]
    r2 = u * u + v * v
    inside = np.clip((1.0 - r2) * 12.0, 0.0, 1.0)[..., None]  # a soft edge of a few px
    shade = (1.05 - 0.25 * np.clip(r2, 0.0, 1.0) + 0.1 * u)[..., None]  # lit from the left
    colour = skin[None, None, :] * shade
    if texture is not None:
        colour = colour + texture[..., None]
    return np.clip(img * (1.0 - inside) + colour * inside, 0, 255).astype(np.uint8)


BEARD_BGR = (38.0, 48.0, 62.0)
"""Colour (BGR) of the ``beard`` variant's hair: dark brown."""


def _beard(points: dict[str, np.ndarray], shape: tuple[int, int], seed: int):
    """What ``beard`` draws: a per-frame function painting a full beard and moustache round the
    mouth, placed on each frame from the peer's points (the pupils give the face's scale and tilt,
    the corners and the outer lip edges the lips, which stay bare)."""
    h, w = shape
    rng = np.random.default_rng(seed)
    # strands: noise stretched along the face's down direction (roughly vertical), about ±14 grey levels
    strands = cv2.GaussianBlur(rng.normal(0.0, 1.0, (h, w)).astype(np.float32), (0, 0), sigmaX=0.8, sigmaY=4.0)
    strands *= np.float32(14.0 / max(float(strands.std()), 1e-6))
    colour = np.array(BEARD_BGR, np.float32)

    def outline(c: np.ndarray, u: np.ndarray, dn: np.ndarray, pts: list[tuple[float, float]]) -> np.ndarray:
        return np.array([c + x * u + y * dn for x, y in pts], np.float32)

    def paint(img: np.ndarray, i: int) -> np.ndarray:
        lp, rp = points["left_pupil"][i], points["right_pupil"][i]
        lc, rc = points["left_mouth_corner"][i], points["right_mouth_corner"][i]
        top, bottom = points["upper_lip_top"][i], points["lower_lip_bottom"][i]
        if not all(np.all(np.isfinite(q)) for q in (lp, rp, lc, rc, top, bottom)):
            return img
        d, u, dn = _eye_line(lp, rp)
        c = 0.5 * (lc + rc)
        half = 0.5 * float(np.dot(rc - lc, u))
        t_up, t_dn = float(np.dot(c - top, dn)), float(np.dot(bottom - c, dn))
        hair = np.zeros((h, w), np.float32)
        # moustache from under the nose down past the corners, and the beard from the corners round
        # the chin (face units: x along the eye line, y down, from the mouth's centre)
        ms = [(-half - 0.12 * d, 0.08 * d), (-half - 0.05 * d, -t_up - 0.12 * d), (0.0, -t_up - 0.2 * d),
              (half + 0.05 * d, -t_up - 0.12 * d), (half + 0.12 * d, 0.08 * d)]
        bd = [(-half - 0.2 * d, -0.05 * d), (-half - 0.25 * d, 0.35 * d), (-0.3 * d, t_dn + 0.55 * d), (0.0, t_dn + 0.62 * d),
              (0.3 * d, t_dn + 0.55 * d), (half + 0.25 * d, 0.35 * d), (half + 0.2 * d, -0.05 * d)]
        for poly in (ms, bd):
            cv2.fillPoly(hair, [_fixed(outline(c, u, dn, poly))], 1.0, cv2.LINE_AA, shift=3)
        # the lips stay bare: a lens through the corners and the outer lip edges
        th = np.linspace(0.0, np.pi, 16)
        lens = [(-half * np.cos(a), -t_up * np.sin(a)) for a in th] + [(half * np.cos(a), t_dn * np.sin(a)) for a in th]
        cv2.fillPoly(hair, [_fixed(outline(c, u, dn, lens))], 0.0, cv2.LINE_AA, shift=3)
        hair = cv2.GaussianBlur(hair, (0, 0), max(0.03 * d, 0.7))[..., None] * np.float32(0.88)
        fur = colour[None, None, :] + strands[..., None]
        return np.clip(img * (1.0 - hair) + fur * hair, 0, 255).astype(np.uint8)

    return paint


CHILD = (0.75, 1.6, 0.15)
"""The ``child`` variant's squeeze ``(k, D, v0)``: a point at distance v below the eye line (× the
inter-pupil distance) past ``v0`` (under the lower lids: the eyes keep their shape) goes to
v − (1 − k)·(v − v0)·exp(−((v − v0) / D)²): distances just under the eyes shrink by k and the squeeze
fades out past the chin. An adult's mouth 1.15 below the eyes lands at 0.98."""


def child_squeeze(v: np.ndarray) -> np.ndarray:
    """Where the ``child`` variant puts a point ``v`` (× the inter-pupil distance, down from the eye
    line; above :data:`CHILD`'s ``v0`` it stays) — increasing, so each output row has one source."""
    k, reach, v0 = CHILD
    v = np.asarray(v, dtype=np.float64)
    pos = np.maximum(v - v0, 0.0)
    return v - (1.0 - k) * pos * np.exp(-((pos / reach) ** 2))


CHILD_EYES = (1.25, 0.22)
"""The ``child`` variant's eyes ``(m, R)``: a point at distance r from a pupil (× the inter-pupil
distance) goes to r·(1 + (m − 1)·exp(−(r / R)²)) — the eye 25 % larger about its pupil, the brow
nearly where it was (a child's iris is nearly an adult's, 11-12 mm, between eyes 48-55 mm apart)."""


def child_eye(r: np.ndarray) -> np.ndarray:
    """Where the ``child`` variant puts a point ``r`` from a pupil (× the inter-pupil distance, along
    the same direction) — increasing, so each output distance has one source."""
    m, reach = CHILD_EYES
    r = np.asarray(r, dtype=np.float64)
    return r * (1.0 + (m - 1.0) * np.exp(-((r / reach) ** 2)))


def _child(points: dict[str, np.ndarray], shape: tuple[int, int]):
    """What ``child`` does: per frame, the picture and a point (image px) moved by :func:`child_eye`
    about each of the peer's pupils of that frame, then by :func:`child_squeeze` across the eye
    line through them."""
    h, w = shape
    table = np.linspace(CHILD[2], CHILD[2] + 8.0 * CHILD[1], 4001)
    squeezed = child_squeeze(table)
    radii = np.linspace(0.0, 6.0 * CHILD_EYES[1], 4001)
    grown = child_eye(radii)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)

    def frame(i: int):
        lp, rp = points["left_pupil"][i] - PIXEL_CENTRE, points["right_pupil"][i] - PIXEL_CENTRE
        if not (np.all(np.isfinite(lp)) and np.all(np.isfinite(rp))):
            return None
        d, u, dn = _eye_line(lp, rp)
        return lp, rp, d, dn

    def image(img: np.ndarray, i: int) -> np.ndarray:
        f = frame(i)
        if f is None:
            return img
        lp, rp, d, dn = f
        v = ((xs - lp[0]) * dn[0] + (ys - lp[1]) * dn[1]) / d
        src = np.where(v > CHILD[2], np.interp(v, squeezed, table), v)  # the output row's source
        shift = (src - v) * d
        mx, my = xs + shift * dn[0], ys + shift * dn[1]
        for c in (lp, rp):  # then the eyes, each about its pupil (the two hardly overlap)
            dx, dy = mx - c[0], my - c[1]
            r = np.hypot(dx, dy) / d
            k = np.where(r < grown[-1], np.interp(r, grown, radii) / np.maximum(r, 1e-9), 1.0)  # far out: as it was
            mx, my = c[0] + dx * k, c[1] + dy * k
        return cv2.remap(img, mx.astype(np.float32), my.astype(np.float32), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)

    def point(p: np.ndarray, i: int) -> np.ndarray:
        f = frame(i)
        if f is None or not np.all(np.isfinite(p)):
            return p
        lp, rp, d, dn = f
        q = np.asarray(p, dtype=np.float64) - PIXEL_CENTRE
        for c in (lp, rp):
            r = float(np.hypot(*(q - c))) / d
            if r > 0:
                q = c + (q - c) * (float(child_eye(r)) / r)
        v = float(np.dot(q - lp, dn)) / d
        return q + (float(child_squeeze(v)) - v) * d * dn + PIXEL_CENTRE

    return image, point


DEEP_SKIN = (0.34, 0.41, 0.52)
"""Factors (B, G, R) the ``deep`` variant takes skin and lips by: a pale or olive face's colours to a
deep brown one's (a cheek at (150, 170, 210) to (51, 70, 109)), its shading and features kept."""
GLASSES_BGR = (28.0, 26.0, 30.0)
"""Colour (BGR) of the ``glasses`` variant's frames: near-black plastic."""
LENS = (0.38, 0.25, 0.05)
"""The ``glasses`` lenses' half-width and half-height and the rim's thickness (× the inter-pupil
distance): 48 × 32 mm lenses in 3 mm rims on a 63 mm IPD, each centred a little outside and below
its pupil, so the upper rim runs between the eye and the brow and the lower one under the lid."""
GLARE_SHIFT = 1.0
"""How far the ``glasses`` glare moves across a lens (× its half-width) per eye distance the head
moves sideways, or per 10° it rolls."""


def _glasses(points: dict[str, np.ndarray], shape: tuple[int, int]):
    """What ``glasses`` draws: a per-frame function painting spectacle frames placed on each frame
    from the peer's pupils (the face's scale and tilt), with a glare streak on each lens: the
    reflection of a light in front of the face, which moves across the lens as the head moves
    against it (:data:`GLARE_SHIFT` of the lens's half-width per eye distance the eyes' midpoint
    has moved, and per 10° of roll, from the first frame's)."""
    h, w = shape
    a, b, t = LENS
    th = np.linspace(0.0, 2.0 * np.pi, 48, endpoint=False)
    # a rounded rectangle: the superellipse |x/a|^4 + |y/b|^4 = 1
    cs, sn = np.cos(th), np.sin(th)
    ring = np.stack([a * np.sign(cs) * np.abs(cs) ** 0.5, b * np.sign(sn) * np.abs(sn) ** 0.5], axis=1)
    colour = np.array(GLASSES_BGR, np.float32)
    seen = np.isfinite(points["left_pupil"]).all(axis=1) & np.isfinite(points["right_pupil"]).all(axis=1)
    first = int(np.argmax(seen))
    v0 = points["right_pupil"][first] - points["left_pupil"][first]
    d0, roll0 = max(float(np.hypot(*v0)), 1e-6), math.atan2(v0[1], v0[0])
    mid0 = 0.5 * (points["left_pupil"][first] + points["right_pupil"][first])

    def paint(img: np.ndarray, i: int) -> np.ndarray:
        lp, rp = points["left_pupil"][i], points["right_pupil"][i]
        if not (np.all(np.isfinite(lp)) and np.all(np.isfinite(rp))):
            return img
        d, u, dn = _eye_line(lp, rp)
        to_img = lambda c, pts: np.array([c + x * u * d + y * dn * d for x, y in pts], np.float32)
        rim = np.zeros((h, w), np.float32)
        glare = np.zeros((h, w), np.float32)
        thick = max(int(round(t * d)), 1)
        # the glare's place across the lens (lens units, −1..1): a reflection moves as the head moves
        mid = 0.5 * (lp + rp)
        roll = math.atan2(u[1], u[0]) - roll0
        s = float(np.clip(GLARE_SHIFT * ((mid[0] - mid0[0]) / d0 + math.degrees(roll) / 10.0) - 0.2, -0.8, 0.8))
        for side, p in ((-1.0, lp), (1.0, rp)):
            c = p + side * 0.03 * d * u + 0.03 * d * dn
            cv2.polylines(rim, [_fixed(to_img(c, ring))], True, 1.0, thick, cv2.LINE_AA, shift=3)
            # the arm: from the lens's outer edge near its top, out towards the ear
            arm = [(side * a, -0.6 * b), (side * (a + 0.3), -0.55 * b)]
            cv2.polylines(rim, [_fixed(to_img(c, arm))], False, 1.0, thick, cv2.LINE_AA, shift=3)
            streak = [(s * a - 0.1, -0.9 * b), (s * a + 0.02, -0.9 * b), (s * a - 0.12, 0.9 * b), (s * a - 0.24, 0.9 * b)]
            cv2.fillPoly(glare, [_fixed(to_img(c, streak))], 1.0, cv2.LINE_AA, shift=3)
        bridge = [(-0.5 + a + 0.03 - 0.01, -0.35 * b + 0.03), (0.0, -0.45 * b + 0.03), (0.5 - a - 0.03 + 0.01, -0.35 * b + 0.03)]
        cv2.polylines(rim, [_fixed(to_img(0.5 * (lp + rp), bridge))], False, 1.0, thick, cv2.LINE_AA, shift=3)
        glare = cv2.GaussianBlur(glare, (0, 0), max(0.02 * d, 0.6))[..., None] * np.float32(0.35)
        out = img * (1.0 - glare) + np.float32(255.0) * glare
        rim = rim[..., None]
        return np.clip(out * (1.0 - rim) + colour * rim, 0, 255).astype(np.uint8)

    return paint


def _photometric(kind: str, n: int, seed: int,
                 points: dict[str, np.ndarray] | None = None) -> Callable[[np.ndarray, int], np.ndarray]:
    """The per-frame pixel change of a photometric variant: ``f(frame, index) -> frame``. With the
    peer's ``points``, ``deep`` darkens the whole face oval but the eye openings and the teeth, and
    ``darkeyes`` also the irises inside the openings; without them only what has skin's colour."""
    rng = np.random.default_rng(seed)
    if kind == "noisy":
        def noisy(img: np.ndarray, i: int) -> np.ndarray:
            noise = rng.normal(0.0, 8.0, img.shape)
            out = np.clip(img.astype(np.float32) + noise, 0, 255).astype(np.uint8)
            ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, 40])
            return cv2.imdecode(buf, cv2.IMREAD_COLOR)
        return noisy
    if kind == "cheap":
        _, light, sigma, quality = CHEAP

        def cheap(img: np.ndarray, i: int) -> np.ndarray:
            out = img.astype(np.float32) * np.float32(light) + rng.normal(0.0, sigma, img.shape).astype(np.float32)
            ok, buf = cv2.imencode(".jpg", np.clip(out + 0.5, 0, 255).astype(np.uint8), [cv2.IMWRITE_JPEG_QUALITY, quality])
            return cv2.imdecode(buf, cv2.IMREAD_COLOR)
        return cheap
    if kind == "dim":
        def dim(img: np.ndarray, i: int) -> np.ndarray:
            t = i / max(n - 1, 1)
            gain = np.array([1.0 - 0.6 * t, 1.0 - 0.5 * t, 1.0 - 0.4 * t], np.float32)  # B, G, R: warmer
            return np.clip(img.astype(np.float32) * gain, 0, 255).astype(np.uint8)
        return dim
    if kind == "step":
        quarter = max(n // 4, 1)
        def step(img: np.ndarray, i: int) -> np.ndarray:
            gain = STEP_LIGHT if (i // quarter) % 2 else 1.0
            return np.clip(img.astype(np.float32) * np.float32(gain), 0, 255).astype(np.uint8)
        return step
    if kind in ("side", "shade"):
        falls: dict[tuple[int, int], np.ndarray] = {}
        def side(img: np.ndarray, i: int) -> np.ndarray:
            h, w = img.shape[:2]
            if (h, w) not in falls:
                x = np.linspace(0.0, 1.0, w, dtype=np.float32)
                fall = (1.0 - SIDE_LIGHT) * x * x * (3.0 - 2.0 * x)  # smoothstep: flat at both edges
                falls[(h, w)] = np.repeat(fall[None, :, None], h, axis=0)
            t = 1.0 if kind == "side" else i / max(n - 1, 1)
            return np.clip(img.astype(np.float32) * (1.0 - np.float32(t) * falls[(h, w)]), 0, 255).astype(np.uint8)
        return side
    if kind == "lowlight":
        light, sigma, keep = LOW_LIGHT

        def lowlight(img: np.ndarray, i: int) -> np.ndarray:
            f = np.round(img.astype(np.float32) * np.float32(light))  # what the sensor's levels keep
            f += rng.normal(0.0, sigma, f.shape).astype(np.float32)
            f = cv2.GaussianBlur(f, (0, 0), 0.7) * np.float32(1.0 / light)  # denoised a little, gained back
            grey = cv2.cvtColor(np.clip(f, 0, 255), cv2.COLOR_BGR2GRAY)[..., None]
            return np.clip(keep * f + (1.0 - keep) * grey, 0, 255).astype(np.uint8)
        return lowlight
    if kind == "warm":
        cast = np.array(WARM_BGR, np.float32)
        return lambda img, i: np.clip(img.astype(np.float32) * cast, 0, 255).astype(np.uint8)
    if kind in ("pale", "washed"):
        keep = 0.5 if kind == "pale" else WASHED_COLOUR
        def pale(img: np.ndarray, i: int) -> np.ndarray:
            grey = cv2.cvtColor(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
            return cv2.addWeighted(img, keep, grey, 1.0 - keep, 0.0)
        return pale
    if kind in ("deep", "darkeyes"):
        tone = np.array(DEEP_SKIN, np.float32)

        def deep(img: np.ndarray, i: int) -> np.ndarray:
            ycc = cv2.cvtColor(img, cv2.COLOR_BGR2YCrCb).astype(np.float32)
            y, cr, cb = ycc[..., 0], ycc[..., 1], ycc[..., 2]
            ramp = lambda v, a, b: np.clip((v - a) / (b - a), 0.0, 1.0)
            # skin and lips by their chroma (any light skin's: red above the grey, blue below it),
            # soft at the edges; the whites of the eyes, the teeth, hair and most backgrounds are not
            skin = ramp(cr, 130.0, 137.0) * ramp(-np.abs(cb - 108.0), -30.0, -22.0) * ramp(y, 40.0, 60.0)
            skin = cv2.GaussianBlur(skin, (0, 0), 1.0)
            iris_keep = None  # darkeyes: the share of its light each pixel keeps for its iris
            if points is not None and i < len(points["left_pupil"]):
                # the whole face alike (a washed-out cheek has lost its chroma, a shadow its light,
                # and both are skin all the same) but for the whites of the eyes and the teeth:
                # bright and nearly grey inside the mouth
                face, mouth = _face_ovals(points, i, skin.shape)
                np.maximum(skin, face, out=skin)
                sat = np.abs(cr - 128.0) + np.abs(cb - 128.0)
                skin *= 1.0 - mouth * ramp(y, 120.0, 160.0) * (1.0 - ramp(sat, 25.0, 40.0))
                openings = _eye_openings(points, i, skin.shape)
                skin *= 1.0 - openings
                if kind == "darkeyes":  # the irises where they show, darker than the darkened skin
                    iris_keep = 1.0 - np.float32(1.0 - DARK_IRIS) * (_iris_discs(points, i, skin.shape) * openings)
            skin = skin[..., None]
            out = img * (1.0 - skin + skin * tone)
            if iris_keep is not None:
                out *= iris_keep[..., None]
            return np.clip(out, 0, 255).astype(np.uint8)
        return deep
    if kind == "blur":
        return lambda img, i: cv2.GaussianBlur(img, (0, 0), 1.6)
    return lambda img, i: img


def peer_params(points: dict[str, np.ndarray]) -> np.ndarray:
    """The ten parameters and the IPD, (n, 11), from the peer's points, as the shared README defines them."""
    lp, rp = points["left_pupil"], points["right_pupil"]
    d = rp - lp
    ipd = np.hypot(d[:, 0], d[:, 1])
    u = d / np.where(ipd > 0, ipd, np.nan)[:, None]
    up = np.stack([u[:, 1], -u[:, 0]], axis=1)  # perpendicular, pointing up in the image (y down)
    along = lambda v: (v * up).sum(axis=1)
    mid = 0.5 * (lp + rp)
    roll = np.degrees(np.arctan2(-d[:, 1], d[:, 0]))
    lc, rc = points["left_mouth_corner"], points["right_mouth_corner"]
    mc = 0.5 * (lc + rc)
    cols = [
        mid[:, 0], mid[:, 1], roll,
        along(points["left_upper_lid"] - points["left_lower_lid"]),
        along(points["right_upper_lid"] - points["right_lower_lid"]),
        along(points["left_brow"] - lp), along(points["right_brow"] - rp),
        np.hypot(*(rc - lc).T),
        along(points["upper_lip_top"] - mc), along(mc - points["lower_lip_bottom"]),
        ipd,
    ]
    return np.stack(cols, axis=1)


EYE_HALF_WIDTH = 0.23
"""Half the length of an eye's opening, corner to corner (× the inter-pupil distance): a 29 mm
opening on a 63 mm IPD."""


def _eye_openings(points: dict[str, np.ndarray], i: int, shape: tuple[int, int]) -> np.ndarray:
    """Frame ``i``'s two eye openings, 1 inside and 0 outside (float32, ``shape``, softened by a
    pixel): almond shapes from corner to corner (:data:`EYE_HALF_WIDTH` either side of the pupil
    along the eye line) through the peer's upper and lower lid points. A real sclera is pinkish
    in a webcam's chroma (Cr 137–147 on the shared clips), as red as skin, and a darker face's
    eyes are as white as a light one's: ``deep`` must not darken them."""
    mask = np.zeros(shape, np.float32)
    lp, rp = points["left_pupil"][i], points["right_pupil"][i]
    ipd, e, _ = _eye_line(lp, rp)
    if not (np.all(np.isfinite(lp)) and np.all(np.isfinite(rp))) or ipd < 4:
        return mask
    t = np.linspace(0.0, 1.0, 12)[:, None]
    for side in ("left", "right"):
        p, up, lo = points[f"{side}_pupil"][i], points[f"{side}_upper_lid"][i], points[f"{side}_lower_lid"][i]
        if not (np.all(np.isfinite(up)) and np.all(np.isfinite(lo))):
            continue
        a, b = p - EYE_HALF_WIDTH * ipd * e, p + EYE_HALF_WIDTH * ipd * e
        # each lid a quadratic curve from corner to corner through its lid point (at t = ½)
        curves = [(1 - t) ** 2 * a + 2 * t * (1 - t) * (2 * q - (a + b) / 2) + t * t * b for q in (up, lo)]
        poly = np.vstack([curves[0], curves[1][::-1]])
        cv2.fillPoly(mask, [_fixed(poly)], 1.0, cv2.LINE_AA, shift=3)
    return cv2.GaussianBlur(mask, (0, 0), 1.0)


FACE_OVAL = (1.05, 1.3, 0.35)
"""The ``deep`` variant's face oval, darkened throughout (× the inter-pupil distance): half its
width, half its height, and how far below the eyes' midpoint its centre lies (towards the mouth):
cheek to cheek, forehead to chin."""


DARK_IRIS = 0.45
"""Share of its light each iris keeps in ``darkeyes``: a clip's brown, grey or blue iris to a dark
brown one, darker than the ``deep`` skin round it."""
IRIS_SIZE = 0.095
"""An iris's radius (× the inter-pupil distance): 12 mm across on a 63 mm IPD."""


def _iris_discs(points: dict[str, np.ndarray], i: int, shape: tuple[int, int]) -> np.ndarray:
    """Frame ``i``'s two irises as discs (:data:`IRIS_SIZE`) about the peer's pupils, 1 inside and 0
    outside (float32, ``shape``, softened by a tenth of the radius); the lids over them are not cut
    out here (see :func:`_eye_openings`)."""
    mask = np.zeros(shape, np.float32)
    lp, rp = points["left_pupil"][i], points["right_pupil"][i]
    if not (np.all(np.isfinite(lp)) and np.all(np.isfinite(rp))):
        return mask
    r = IRIS_SIZE * float(np.hypot(*(rp - lp)))
    if r < 1.0:
        return mask
    for p in (lp, rp):
        cv2.circle(mask, tuple(_fixed(p).tolist()), int(round(r * 8)), 1.0, -1, cv2.LINE_AA, 3)
    return cv2.GaussianBlur(mask, (0, 0), max(0.1 * r, 0.7))


def _face_ovals(points: dict[str, np.ndarray], i: int, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Frame ``i``'s face oval (:data:`FACE_OVAL`, on the eye line's tilt) and the oval inside its
    lips (where teeth can show: between the lips' outer edges less a lip's thickness, and short
    of the corners; empty when the mouth is closed), each 1 inside and 0 outside, soft-edged
    (float32, ``shape``)."""
    face, mouth = np.zeros(shape, np.float32), np.zeros(shape, np.float32)
    lp, rp = points["left_pupil"][i], points["right_pupil"][i]
    lips = [points[k][i] for k in ("left_mouth_corner", "right_mouth_corner", "upper_lip_top", "lower_lip_bottom")]
    ipd, e, down = _eye_line(lp, rp)
    if not all(np.all(np.isfinite(q)) for q in [lp, rp, *lips]) or ipd < 4:
        return face, mouth
    ang = math.degrees(math.atan2(e[1], e[0]))
    hw, hh, below = FACE_OVAL
    at = lambda c: tuple(_fixed(c).tolist())
    cv2.ellipse(face, at(0.5 * (lp + rp) + below * ipd * down), (int(hw * ipd * 8), int(hh * ipd * 8)), ang, 0, 360, 1.0, -1, cv2.LINE_AA, 3)
    soft = max(0.05 * ipd, 1.0)
    lc, rc, top, bottom = lips
    # inside the lips: the teeth and the dark, a lip's thickness (about 0.1 ipd) in from their outline
    mw = 0.4 * float(np.hypot(*(rc - lc)))
    mh = 0.5 * float(abs(np.dot(bottom - top, down))) - 0.1 * ipd
    if mh > 0.5:
        cv2.ellipse(mouth, at(0.5 * (top + bottom)), (int(mw * 8), int(mh * 8)), ang, 0, 360, 1.0, -1, cv2.LINE_AA, 3)
        mouth = cv2.GaussianBlur(mouth, (0, 0), 0.5 * soft)
    return cv2.GaussianBlur(face, (0, 0), soft), mouth


def _read_points(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    val = lambda s: float(s) if s not in ("", "nan") else np.nan
    return {p: np.array([[val(r[f"{p}_x"]), val(r[f"{p}_y"])] for r in rows]) for p in POINTS}


def _num(v: float, fmt: str) -> str:
    return format(v, fmt) if math.isfinite(v) else "nan"


def _move(p: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Points of the files (the peer's, the clicks: :data:`~tracker.clicks.PIXEL_CENTRE`) through a map
    made for the pictures (OpenCV's convention, pixel centres at whole numbers)."""
    return (p - PIXEL_CENTRE) @ m[:, :2].T + m[:, 2] + PIXEL_CENTRE


def read_frames(path: Path) -> tuple[list[np.ndarray], float]:
    """Every frame of a video (BGR) and its frame rate (25 when the file does not say)."""
    cap = cv2.VideoCapture(str(path))
    fps = cap.get(cv2.CAP_PROP_FPS) or 25.0
    frames = []
    while True:
        ok, img = cap.read()
        if not ok:
            break
        frames.append(img)
    cap.release()
    return frames, fps


def make_variant(src: Path, name: str, kind: str, out: Path, seed: int = 0) -> Path:
    """Write variant ``kind`` of clip ``name`` (from folder ``src``) into folder ``out``; its video path."""
    out.mkdir(parents=True, exist_ok=True)
    frames, fps = read_frames(src / f"{name}.mp4")
    points = _read_points(src / f"{name}.points.csv")
    if kind == "late":
        start = int(LATE * len(frames))
        frames, points = frames[start:], {p: q[start:] for p, q in points.items()}
    if kind == "choppy":
        frames, points, fps = frames[::2], {p: q[::2] for p, q in points.items()}, 0.5 * fps
    n = len(frames)
    h, w = frames[0].shape[:2]
    seed = seed + sum(map(ord, name)) + sum(map(ord, kind))
    maps, (W, H) = _affine_frames(n, kind, (w, h), seed)
    smear = None
    if kind == "jolt":
        # each frame's exposure runs over the last EXPOSURE[0] of the motion from the frame before; the
        # points sit where its middle puts them
        share, k = EXPOSURE
        spans = [(maps[max(i - 1, 0)], maps[i]) for i in range(n)]
        smear = [[a + (b - a) * (1.0 - share * (j + 0.5) / k) for j in range(k)] for a, b in spans]
        maps = [a + (b - a) * (1.0 - 0.5 * share) for a, b in spans]
    pix = _photometric(kind, n, seed, points)
    room = _room(frames[0]) if kind == "leave" else None
    hand = _hand(frames, points, seed) if kind == "covered" else None
    worn = _beard(points, (h, w), seed) if kind == "beard" else _glasses(points, (h, w)) if kind == "glasses" else None
    squeeze = _child(points, (h, w)) if kind == "child" else None
    writer = cv2.VideoWriter(str(out / f"{name}.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), fps, (W, H))
    if not writer.isOpened():
        raise RuntimeError(f"{out / name}.mp4: cannot open a video writer")
    border = (40, 40, 40)
    for i, img in enumerate(frames):
        m = maps[i]
        if kind != "mirror" and not np.allclose(m, [[1, 0, 0], [0, 1, 0]]):
            interp = cv2.INTER_AREA if kind in SHRUNK else cv2.INTER_LINEAR
            if kind in SHRUNK:
                img = cv2.resize(img, (W, H), interpolation=interp)
            elif smear is not None:
                acc = np.zeros((H, W, 3), np.float32)
                for mj in smear[i]:
                    acc += cv2.warpAffine(img, mj, (W, H), flags=interp, borderMode=cv2.BORDER_CONSTANT, borderValue=border)
                img = np.clip(acc * np.float32(1.0 / len(smear[i])) + 0.5, 0, 255).astype(np.uint8)
            elif room is not None:
                img = cv2.warpAffine(img, m, (W, H), dst=room.copy(), flags=interp, borderMode=cv2.BORDER_TRANSPARENT)
            else:
                img = cv2.warpAffine(img, m, (W, H), flags=interp, borderMode=cv2.BORDER_CONSTANT, borderValue=border)
        elif kind == "mirror":
            img = img[:, ::-1]
        if hand is not None:
            img = hand[0](img, i)
        if worn is not None and i < len(points["left_pupil"]):
            img = worn(img, i)
        if squeeze is not None and i < len(points["left_pupil"]):
            img = squeeze[0](img, i)
        writer.write(np.ascontiguousarray(pix(img, i)))
    writer.release()

    n = min(n, len(points["left_pupil"]))
    moved = {p: np.array([_move(points[p][i], maps[i]) for i in range(n)]) for p in POINTS}
    if squeeze is not None:
        moved = {p: np.array([squeeze[1](q[i], i) for i in range(n)]) for p, q in moved.items()}
    for p in POINTS if kind in ("leave", "covered") else ():  # out of the frame or under the hand: unseen
        q = moved[p]
        hidden = ~((q[:, 0] >= 0) & (q[:, 0] <= W - 1) & (q[:, 1] >= 0) & (q[:, 1] <= H - 1))
        if hand is not None:
            _, cx, cy, (axx, axy) = hand
            hidden |= ((q[:, 0] - cx[:n]) / axx) ** 2 + ((q[:, 1] - cy[:n]) / axy) ** 2 <= 1.0
        q[hidden] = np.nan
    if kind == "mirror":  # image-left is now what was image-right
        for a in ("pupil", "upper_lid", "lower_lid", "brow", "mouth_corner"):
            moved[f"left_{a}"], moved[f"right_{a}"] = moved[f"right_{a}"], moved[f"left_{a}"]
    with open(out / f"{name}.points.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["frame"] + [f"{p}_{c}" for p in POINTS for c in "xy"])
        for i in range(n):
            wr.writerow([i] + [_num(v, ".2f") for p in POINTS for v in moved[p][i]])
    vals = peer_params(moved)
    with open(out / f"{name}.mp.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["frame", *PARAM_NAMES, "ipd"])
        for i in range(n):
            row = vals[i] if np.isfinite(vals[i]).all() else np.full(len(vals[i]), np.nan)  # any point unseen: no face
            wr.writerow([i] + [_num(v, ".3f") for v in row])

    if kind == "late":
        (out / f"{name}.clicks.json").write_text(json.dumps(_clicks_from_points(moved, 0)))
        return out / f"{name}.mp4"
    clicks = json.loads((src / f"{name}.clicks.json").read_text())
    if kind == "choppy" and int(clicks.get("frame", 0)) % 2:
        # the clicked frame was dropped: clicks on the peer's points of the kept frame before it
        (out / f"{name}.clicks.json").write_text(json.dumps(_clicks_from_points(moved, int(clicks["frame"]) // 2)))
        return out / f"{name}.mp4"
    if kind == "choppy":
        clicks["frame"] = int(clicks.get("frame", 0)) // 2
    m0 = maps[int(clicks.get("frame", 0))]
    new = {"frame": clicks.get("frame", 0)}
    for k in ("left_pupil", "right_pupil", "left_brow", "right_brow", "mouth"):
        q = _move(np.array(clicks[k], float), m0)
        if squeeze is not None:
            q = squeeze[1](q, int(clicks.get("frame", 0)))
        new[k] = [round(float(v), 1) for v in q]
    if kind == "mirror":
        new["left_pupil"], new["right_pupil"] = new["right_pupil"], new["left_pupil"]
        new["left_brow"], new["right_brow"] = new["right_brow"], new["left_brow"]
    (out / f"{name}.clicks.json").write_text(json.dumps(new))
    return out / f"{name}.mp4"


def _clicks_from_points(points: dict[str, np.ndarray], i: int) -> dict:
    """The five clicks a careful person would make on frame ``i``, from the peer's points there, as the
    shared clips' clicks were made on their frame 0: the pupils, the brows, and the mouth's centre
    (the midpoint of its corners)."""
    mouth = 0.5 * (points["left_mouth_corner"][i] + points["right_mouth_corner"][i])
    out = {"frame": i, "mouth": mouth}
    for k in ("left_pupil", "right_pupil", "left_brow", "right_brow"):
        out[k] = points[k][i]
    return {k: v if k == "frame" else [round(float(c), 1) for c in v] for k, v in out.items()}


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.stress_clips", description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="out/stress", help="folder to write one sub-folder per variant into")
    ap.add_argument("--variants", default=",".join(VARIANTS), help=f"comma-separated, of {', '.join(VARIANTS)}")
    ap.add_argument("--dir", default=None, help="folder of real clips (default ../shared/real)")
    ap.add_argument("--clips", default=None, help="comma-separated clip names (default: all)")
    args = ap.parse_args(argv)
    src = real_dir(args.dir)
    if src is None:
        print("stress_clips: no folder of real clips (../shared/real); nothing to do")
        return 0
    kinds = [k for k in args.variants.split(",") if k]
    bad = [k for k in kinds if k not in VARIANTS]
    if bad:
        print(f"stress_clips: unknown variant {bad[0]!r} (known: {', '.join(VARIANTS)})", file=sys.stderr)
        return 2
    names = args.clips.split(",") if args.clips else clip_names(src)
    for k in kinds:
        for nm in names:
            make_variant(src, nm, k, Path(args.out) / k)
        print(f"{k}: {len(names)} clips in {Path(args.out) / k}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
