"""Feature geometry shared by the bundled characters, and the :class:`Character` base class.

Every drawing is generated FROM a few feature curves (lids, brows, lips), and its control
lines are read off the same curves, so line *i* sits on the same feature in every drawing.

Eye control lines, for the image-left eye then the image-right eye, each pointing from the
inner corner outwards: 0 upper lid, 1 lower lid, 2 brow, 3 eye axis (inner to outer corner).
Mouth control lines, left to right: 0 upper lip top, 1 lower lip bottom, 2 left corner,
3 right corner, 4 inner edge of the upper lip (teeth edge), 5 inner edge of the lower lip.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from art_sets.authoring.ink import Surface, Textures, ellipse, point_at
from art_sets.model import ArtSet, Drawing, Part

EYE_LINE_NAMES = [f"{side} {feat}" for side in ("left", "right")
                  for feat in ("upper lid", "lower lid", "brow", "eye axis")]
MOUTH_LINE_NAMES = ["upper lip top", "lower lip bottom", "left corner", "right corner",
                    "upper lip inner edge", "lower lip inner edge"]


# --- eyes ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class EyePose:
    """An eye expression in units of the eye's half-width (so it scales with the character)."""

    up: float = 0.55  # upper lid height above the eye axis
    dn: float = 0.38  # lower lid depth below the axis
    closed: bool = False
    brow: float = 0.0  # brow raise (+ up)
    brow_tilt: float = 0.0  # inner end of the brow pulled down (+ angry, - worried)
    brow_arch: float = 0.18
    lid_drop: float = 0.0  # inner part of the upper lid lowered (angry)
    lower_lift: float = 0.0  # lower lid pushed up (squint, smile)
    gaze: tuple[float, float] = (0.0, 0.0)


@dataclass
class EyeGeom:
    """Curves of one eye in canvas pixels; all run from the inner corner outwards."""

    center: np.ndarray
    hw: float
    inner: np.ndarray
    outer: np.ndarray
    upper: np.ndarray
    lower: np.ndarray
    brow: np.ndarray
    iris_c: np.ndarray
    iris_r: float
    closed: bool
    sgn: float  # +1 when the inner corner is towards +x (the image-left eye)

    def opening(self) -> np.ndarray:
        return np.concatenate([self.upper, self.lower[::-1]])

    def lines(self) -> np.ndarray:
        return np.array([
            [*point_at(self.upper, 0.2), *point_at(self.upper, 0.8)],
            [*point_at(self.lower, 0.2), *point_at(self.lower, 0.8)],
            [*point_at(self.brow, 0.1), *point_at(self.brow, 0.9)],
            [*self.inner, *self.outer],
        ])


def eye_geom(center, hw: float, sgn: float, pose: EyePose, *, brow_gap: float = 0.95,
             brow_len: float = 1.15, iris: float = 0.52, outer_lift: float = 0.08, n: int = 48) -> EyeGeom:
    c = np.asarray(center, np.float64)
    inner = c + (sgn * hw, 0.0)
    outer = c + (-sgn * hw, -outer_lift * hw)
    t = np.linspace(0, 1, n)
    base = inner[None] + (outer - inner)[None] * t[:, None]
    bump_u = np.sin(np.pi * t ** 0.8) ** 0.75
    bump_d = np.sin(np.pi * t ** 1.15) ** 0.85
    if pose.closed:
        sag = 0.16 * hw * np.sin(np.pi * t)
        upper = base + np.stack([0 * t, sag], 1)
        lower = upper + (0, 1.5)
    else:
        up = pose.up * hw * bump_u - pose.lid_drop * hw * (1 - t) ** 1.5 * np.sin(np.pi * t) ** 0.5
        dn = (pose.dn - pose.lower_lift) * hw * bump_d
        upper = base - np.stack([0 * t, up], 1)
        lower = base + np.stack([0 * t, np.maximum(dn, 0.06 * hw * bump_d)], 1)
        upper[:, 1] = np.minimum(upper[:, 1], lower[:, 1])  # a lowered lid rests on the lower one
    by = c[1] - brow_gap * hw - pose.brow * hw
    b_in = np.array([c[0] + sgn * 0.85 * hw, by + pose.brow_tilt * hw])
    b_out = np.array([c[0] - sgn * (brow_len * hw + 0.1 * hw), by + 0.2 * hw - 0.35 * pose.brow_tilt * hw])
    mid = (b_in + b_out) / 2 - (0, (pose.brow_arch + 0.1 * pose.brow) * hw)
    brow = np.array([(1 - s) ** 2 * b_in + 2 * s * (1 - s) * mid + s ** 2 * b_out for s in t])
    clearance = (lid_height_at(upper, brow[:, 0]) - brow[:, 1]).min()
    if clearance < 0.12 * hw:  # keep the brow above the lid, e.g. a wide-open eye under a resting brow
        brow = brow - (0, 0.12 * hw - clearance)
    iris_c = c + np.asarray(pose.gaze, np.float64) * hw + (0, 0.02 * hw)
    return EyeGeom(c, hw, inner, outer, upper, lower, brow, iris_c, iris * hw, pose.closed, sgn)


def lid_height_at(lid: np.ndarray, xs: np.ndarray) -> np.ndarray:
    """y of a lid curve at each x (the lid's end heights beyond its corners)."""
    order = np.argsort(lid[:, 0])
    return np.interp(xs, lid[order, 0], lid[order, 1])


# --- mouth -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class MouthPose:
    """A mouth expression in units of the character's neutral mouth half-width."""

    hw: float = 1.0  # half-width
    smile: float = 0.05  # corner lift (+ smile, - frown)
    open: float = 0.0  # gap between the lips at the middle
    up_ratio: float = 0.32  # share of the opening above the closed-mouth seam
    tu: float = 0.16  # upper lip thickness
    tl: float = 0.22  # lower lip thickness
    round: float = 0.0  # 0 wide/boxy opening .. 1 round (pucker)
    teeth_up: float = 0.0  # visible height of the upper teeth, share of the opening
    teeth_dn: float = 0.0
    tongue: bool = False
    dy: float = 0.0  # shift of the whole mouth (+ down)


@dataclass
class MouthGeom:
    """Curves of the mouth in canvas pixels, all running left to right."""

    left: np.ndarray
    right: np.ndarray
    seam: np.ndarray
    inner_up: np.ndarray
    inner_dn: np.ndarray
    outer_up: np.ndarray
    outer_dn: np.ndarray
    open: float
    pose: MouthPose
    scale: float

    def interior(self) -> np.ndarray:
        return np.concatenate([self.inner_up, self.inner_dn[::-1]])

    def lips(self) -> np.ndarray:
        return np.concatenate([self.outer_up, self.outer_dn[::-1]])

    def lines(self) -> np.ndarray:
        k = 6
        lc = (self.inner_up[k] + self.inner_dn[k]) / 2
        rc = (self.inner_up[-1 - k] + self.inner_dn[-1 - k]) / 2
        iu, idn = self.inner_up, self.inner_dn
        if self.open < 2.0:
            iu, idn = iu - (0, 1.0), idn + (0, 1.0)
        return np.array([
            [*point_at(self.outer_up, 0.3), *point_at(self.outer_up, 0.7)],
            [*point_at(self.outer_dn, 0.3), *point_at(self.outer_dn, 0.7)],
            [*self.left, *lc],
            [*self.right, *rc],
            [*point_at(iu, 0.3), *point_at(iu, 0.7)],
            [*point_at(idn, 0.3), *point_at(idn, 0.7)],
        ])


def mouth_geom(center, scale: float, pose: MouthPose, n: int = 61) -> MouthGeom:
    c = np.asarray(center, np.float64) + (0, pose.dy * scale)
    hw = pose.hw * scale
    t = np.linspace(0, 1, n)
    x = c[0] - hw + 2 * hw * t
    k = pose.smile * scale
    seam = c[1] - k * (2 * t - 1) ** 2
    o = pose.open * scale
    e = 0.62 - 0.22 * pose.round
    g = np.sin(np.pi * t) ** e
    iu = seam - o * pose.up_ratio * g
    idn = seam + o * (1 - pose.up_ratio) * g
    bow = np.exp(-(((t - 0.5) / 0.08) ** 2))
    pad = pose.round * 0.22 * scale
    su = np.sin(np.pi * t) ** (0.55 - 0.35 * pose.round)
    ou = iu - pose.tu * scale * su * (1 - 0.3 * bow)
    od = idn + pose.tl * scale * np.sin(np.pi * t) ** (0.65 - 0.4 * pose.round)
    xo = c[0] - hw - pad + 2 * (hw + pad) * t
    return MouthGeom(left=np.array([x[0], seam[0]]), right=np.array([x[-1], seam[-1]]),
                     seam=np.stack([x, seam], 1), inner_up=np.stack([x, iu], 1), inner_dn=np.stack([x, idn], 1),
                     outer_up=np.stack([xo, ou], 1), outer_dn=np.stack([xo, od], 1), open=o, pose=pose, scale=scale)


# --- the character base class ---------------------------------------------------------------------
DEFAULT_EYES = {
    "open": EyePose(),
    "closed": EyePose(closed=True, brow=-0.05),
    "wide": EyePose(up=0.78, dn=0.5, brow=0.42, brow_arch=0.28),
    "angry": EyePose(up=0.42, dn=0.3, lid_drop=0.32, brow=-0.22, brow_tilt=0.42, brow_arch=0.05),
    "squint": EyePose(up=0.28, dn=0.3, lower_lift=0.2, brow=-0.08),
}

DEFAULT_MOUTHS = {
    "neutral": MouthPose(),
    "smile": MouthPose(hw=1.18, smile=0.36, tl=0.2),
    "ah": MouthPose(hw=0.82, smile=0.02, open=0.95, teeth_up=0.14, tongue=True),
    "oo": MouthPose(hw=0.52, open=0.52, round=1.0, tu=0.2, tl=0.24, up_ratio=0.4),
    "grin": MouthPose(hw=1.28, smile=0.34, open=0.52, up_ratio=0.38, teeth_up=0.5, teeth_dn=0.4),
    "frown": MouthPose(hw=0.95, smile=-0.28, tl=0.18),
    "ee": MouthPose(hw=1.2, smile=0.1, open=0.3, up_ratio=0.45, teeth_up=0.52, teeth_dn=0.48),
}


@dataclass
class Character:
    """What a bundled character module fills in; :meth:`build` turns it into an ArtSet."""

    slug: str
    name: str
    style: str
    description: str
    author: str = "Inkface art-set authoring code"
    canvas: tuple[int, int] = (512, 512)
    pivot: tuple[float, float] = (256.0, 440.0)
    eyes_box: tuple[int, int, int, int] = (100, 144, 312, 136)
    mouth_box: tuple[int, int, int, int] = (166, 316, 180, 128)
    eye_centers: tuple[tuple[float, float], tuple[float, float]] = ((194.0, 228.0), (318.0, 228.0))
    eye_hw: float = 36.0
    mouth_center: tuple[float, float] = (256.0, 362.0)
    mouth_scale: float = 40.0
    skin: tuple[float, float, float] = (1.0, 0.9, 0.8)
    mouth_skin: tuple[float, float, float] | None = None  # background of the mouth drawings, when not skin
    ss: int = 3
    seed: int = 1
    heads: int = 3
    paper_amount: float = 0.015
    grain: float = 0.0
    feather: float = 3.5
    eyes: dict = field(default_factory=lambda: dict(DEFAULT_EYES))
    mouths: dict = field(default_factory=lambda: dict(DEFAULT_MOUTHS))
    eye_kw: dict = field(default_factory=dict)

    # --- hooks the character modules override -------------------------------------------------
    def draw_head(self, s: Surface, rng: np.random.Generator, k: int) -> None:  # pragma: no cover
        raise NotImplementedError

    def draw_eye(self, s: Surface, g: EyeGeom, pose: EyePose, rng: np.random.Generator) -> None:  # pragma: no cover
        raise NotImplementedError

    def draw_brow(self, s: Surface, g: EyeGeom, pose: EyePose, rng: np.random.Generator) -> None:  # pragma: no cover
        raise NotImplementedError

    def draw_mouth(self, s: Surface, g: MouthGeom, rng: np.random.Generator) -> None:  # pragma: no cover
        raise NotImplementedError

    def holes(self, s: Surface) -> np.ndarray:
        """Full-surface feathered mask (1 = see-through) for the eye and mouth holes."""
        m = np.zeros((s.H, s.W), np.float32)
        for box, rnd in ((self.eyes_box, 0.45), (self.mouth_box, 0.5)):
            m = np.maximum(m, s.mask(rounded_rect(box, 2.6 * self.feather, rnd), blur=self.feather))
        return m

    # --- building ---------------------------------------------------------------------------
    def textures(self) -> Textures:
        return Textures.make(self.canvas, self.ss, self.seed, self.paper_amount, self.grain)

    def eye_geoms(self, pose: EyePose) -> list[EyeGeom]:
        return [eye_geom(c, self.eye_hw, sgn, pose, **self.eye_kw)
                for c, sgn in zip(self.eye_centers, (1.0, -1.0))]

    def mouth(self, pose: MouthPose) -> MouthGeom:
        return mouth_geom(self.mouth_center, self.mouth_scale, pose)

    def build(self) -> ArtSet:
        tex = self.textures()
        parts = {}
        for pname, box, poses in (("eyes", self.eyes_box, self.eyes), ("mouth", self.mouth_box, self.mouths)):
            drawings = []
            for i, (dname, pose) in enumerate(poses.items()):
                # the same seed for every drawing of a part: features drawn by the same calls get the
                # same wobble and jitter, so they line up under the morph instead of shimmering
                rng = np.random.default_rng([self.seed, 1 if pname == "eyes" else 2])
                bg = self.mouth_skin if pname == "mouth" and self.mouth_skin else self.skin
                s = Surface(box[:2], box[2:], tex, background=bg)
                if pname == "eyes":
                    geoms = self.eye_geoms(pose)
                    for g in geoms:  # brows first, while every drawing's random stream is still in step
                        self.draw_brow(s, g, pose, rng)
                    for g in geoms:
                        self.draw_eye(s, g, pose, rng)
                    lines = np.concatenate([g.lines() for g in geoms])
                else:
                    g = self.mouth(pose)
                    self.draw_mouth(s, g, rng)
                    lines = g.lines()
                lines = np.round(lines - (box[0], box[1], box[0], box[1]), 2)
                drawings.append(Drawing(dname, s.to_rgba(), lines, f"{pname}/{dname}.png"))
            parts[pname] = Part(pname, tuple(box), drawings)
        heads, files = [], []
        for k in range(self.heads):
            s = Surface((0, 0), self.canvas, tex)
            self.draw_head(s, np.random.default_rng([self.seed, 3, k]), k)
            s.punch(self.holes(s))
            heads.append(s.to_rgba())
            files.append(f"head-{k + 1}.png")
        extra = {"style": self.style, "description": self.description,
                 "line_names": {"eyes": EYE_LINE_NAMES, "mouth": MOUTH_LINE_NAMES}}
        return ArtSet(name=self.name, canvas=self.canvas, pivot=self.pivot, heads=heads, parts=parts,
                      author=self.author, head_files=files, extra=extra)

    def with_(self, **kw) -> "Character":
        return replace(self, **kw)


def rounded_rect(box, inset: float, roundness: float = 0.5, n: int = 18) -> np.ndarray:
    """A rounded rectangle inside ``box`` (x, y, w, h) shrunk by ``inset``; corner radius = roundness × half the short side."""
    x, y, w, h = box
    x0, y0, x1, y1 = x + inset, y + inset, x + w - inset, y + h - inset
    r = roundness * min(x1 - x0, y1 - y0) / 2
    pts = []
    for cx, cy, a0 in ((x1 - r, y0 + r, -90), (x1 - r, y1 - r, 0), (x0 + r, y1 - r, 90), (x0 + r, y0 + r, 180)):
        for a in np.radians(np.linspace(a0, a0 + 90, n)):
            pts.append((cx + r * np.cos(a), cy + r * np.sin(a)))
    return np.array(pts)


def head_outline(cx: float, cy: float, rx: float, ry: float, chin: float = 0.14, jowl: float = 0.0,
                 n: int = 180) -> np.ndarray:
    """A closed egg-shaped face outline: narrower towards the chin by ``chin``."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    s = np.sin(t)
    narrow = 1 - chin * np.clip(s, 0, 1) ** 2 + jowl * np.clip(s, 0, 1) * (1 - np.clip(s, 0, 1))
    return np.stack([cx + rx * np.cos(t) * narrow, cy + ry * s], 1)


def closed(curve: np.ndarray) -> np.ndarray:
    return np.concatenate([curve, curve[:1]])


__all__ = ["EyePose", "MouthPose", "EyeGeom", "MouthGeom", "Character", "eye_geom", "mouth_geom",
           "rounded_rect", "head_outline", "closed", "ellipse", "EYE_LINE_NAMES", "MOUTH_LINE_NAMES"]
