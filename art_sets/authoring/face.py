"""Feature geometry shared by the bundled characters, and the :class:`Character` base class.

Every drawing is generated FROM a few feature curves (lids, brows, lips), and its control
lines are read off the same curves, so line *i* sits on the same feature in every drawing.
The characters are drawn in layers (format 2), so that an opaque lid or lip covers what lies
under it instead of being blended with it:

* eyes, bottom first: ``eyeball`` (the white and iris, the same in every drawing: it never
  moves), ``lower-lid`` (the skin below each lower lid and its line) and ``upper-lid`` (the skin
  of the face with a slot below each upper lid, the lid lines, lashes and brows). The two lids
  are separate layers with separate control lines: a closed eye brings them together, and lines
  of one layer that touch in one drawing and part in another would stretch whatever lies between.
* mouth, bottom first: ``inside`` (the dark of the mouth and the upper teeth, fixed to the skull:
  it never moves), ``lower-lip`` (the lower lip and the skin below it, with the lower teeth and
  the tongue riding on it) and ``upper-lip`` (the skin of the face with a slot below the upper
  lip, and the upper lip). As with the lids, the two lips are separate layers with separate
  lines: closed, they touch.

Eye control lines of the drawing (the ``upper-lid`` layer), image-left eye then image-right eye,
each running from the inner corner outwards: chords along the upper lid, along a curve just above
it, along the brow and along curves just under and over the brow. ``lower-lid``: chords along each
lower lid and along a curve just under it. Mouth lines of the drawing (``upper-lip``), left to
right: chords along the upper lip's inner edge, along a curve just above it and along its outer
edge; ``lower-lip`` the same for the lower lip. Lines that follow a curve just beside an inked one
carry no ink themselves: they make the strip between them move as one piece (see ``upper_lines``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from art_sets.authoring.ink import Placement, Surface, Textures, ellipse, point_at
from art_sets.model import ArtSet, Body, Drawing, Layer, Part

LID_U = (0.0, 0.25, 0.5, 0.75, 1.0)  # arc-length fractions of the lid chords' ends
BROW_U = (0.05, 0.35, 0.65, 0.95)
BAND_U = (0.0, 0.25, 0.5, 0.75, 1.0)
LID_BAND = 0.14  # eye half-widths from a lid to the line that holds its stroke
FOLD_U = (0.1, 0.5, 0.9)
FOLD = 0.12  # the fold line's distance under the brow, in eye half-widths (brows keep 0.4 above the lid)
# Lips curve much more than lids, and Beier–Neely keeps a pixel's distance from its line in pixels:
# a stroke that bows 2 px off a long chord in an open mouth and lies on it in a closed one lands
# 2 px apart in the blend (a doubled lip line). Short chords keep that under a pixel.
LIP_INNER_U = tuple(np.linspace(0.0, 1.0, 9))
LIP_OUTER_U = tuple(np.linspace(0.0, 1.0, 7))
LIP_BAND_U = BAND_U  # the lines that hold a stroke, beside it
CORNER_OUT, CORNER_HALF = 0.08, 0.12  # mouth-scale units: where the corner lines sit beyond each corner, their half-length

EYE_LINE_NAMES = [f"{side} {feat} {i + 1}" for side in ("left", "right")
                  for feat, us in (("upper lid", LID_U), ("above the upper lid", BAND_U), ("brow", BROW_U),
                                   ("fold under the brow", FOLD_U), ("over the brow", FOLD_U))
                  for i in range(len(us) - 1)]
LOWER_LID_LINE_NAMES = [f"{side} {feat} {i + 1}" for side in ("left", "right")
                        for feat, us in (("lower lid", LID_U), ("under the lower lid", BAND_U)) for i in range(len(us) - 1)]
MOUTH_LINE_NAMES = [f"{feat} {i + 1}" for feat, us in (("upper lip inner edge", LIP_INNER_U),
                                                       ("above the upper lip's inner edge", LIP_BAND_U),
                                                       ("upper lip outer edge", LIP_OUTER_U))
                    for i in range(len(us) - 1)]
CORNER_LINE_NAMES = [f"{side} mouth corner {what}" for side in ("left", "right") for what in ("upright", "across")]
LOWER_LIP_LINE_NAMES = ([n.replace("upper", "lower").replace("above", "under") for n in MOUTH_LINE_NAMES]
                        + [f"lower teeth tops {i + 1}" for i in range(len(LIP_BAND_U) - 1)] + CORNER_LINE_NAMES)
MOUTH_LINE_NAMES = MOUTH_LINE_NAMES + CORNER_LINE_NAMES
EYE_LAYERS = ("eyeball", "lower-lid", "upper-lid")
MOUTH_LAYERS = ("inside", "lower-lip", "upper-lip")


def chords(curve: np.ndarray, us) -> np.ndarray:
    """Control lines ``(len(us) − 1, 4)`` between the points at arc-length fractions ``us``."""
    pts = [point_at(curve, u) for u in us]
    return np.array([[*a, *b] for a, b in zip(pts[:-1], pts[1:])])


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

    def upper_lines(self, band: float = LID_BAND) -> np.ndarray:
        """The ``upper-lid`` layer's lines: chords along the upper lid, along a curve ``band`` eye
        half-widths above it, along the brow, and along curves just under and over the brow.

        Lines without ink of their own hold what lies between them: the lid's stroke (and any
        shading on the lid) between the lid and the band line moves with the lid instead of being
        stretched where the lid moves away from the brow; the two beside the brow keep it whole."""
        return np.concatenate([chords(self.upper, LID_U), chords(self.upper - (0, band * self.hw), BAND_U),
                               chords(self.brow, BROW_U), chords(self.brow + (0, FOLD * self.hw), FOLD_U),
                               chords(self.brow - (0, FOLD * self.hw), FOLD_U)])

    def lower_lines(self, band: float = LID_BAND) -> np.ndarray:
        """The ``lower-lid`` layer's lines: chords along the lower lid and along a curve ``band``
        eye half-widths under it."""
        return np.concatenate([chords(self.lower, LID_U), chords(self.lower + (0, band * self.hw), BAND_U)])


def eye_geom(center, hw: float, sgn: float, pose: EyePose, *, brow_gap: float = 0.95,
             brow_len: float = 1.15, iris: float = 0.52, outer_lift: float = 0.08, brow_clear: float = 0.4,
             n: int = 48) -> EyeGeom:
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
    if clearance < brow_clear * hw:  # keep skin between brow and lid: a brow touching the lid in one
        brow = brow - (0, brow_clear * hw - clearance)  # drawing would be stretched when they part in another
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

    def upper_lines(self, band: float) -> np.ndarray:
        """The ``upper-lip`` layer's lines: chords along the inner edge, along a curve ``band``
        mouth-scale units above it (holding the edge's stroke), along the outer edge, and the
        corners' lines."""
        d = (0, band * self.scale)
        return np.concatenate([chords(self.inner_up, LIP_INNER_U), chords(self.inner_up - d, LIP_BAND_U),
                               chords(self.outer_up, LIP_OUTER_U), self.corner_lines()])

    def corner_lines(self) -> np.ndarray:
        """Two short lines crossing just beyond each corner of the mouth (upright, and across pointing
        out), the same in every mouth: the crease drawn there moves with its corner as one piece
        instead of turning with the ends of the lips' chains (up in a smile, down in a frown)."""
        h, d = CORNER_HALF * self.scale, CORNER_OUT * self.scale
        out = []
        for (x, y), sgn in ((self.left, -1), (self.right, 1)):
            cx = x + sgn * d
            out += [[cx, y + h, cx, y - h], [cx - sgn * h / 2, y, cx + sgn * h, y]]
        return np.array(out)

    def lower_lines(self, band: float, teeth: float) -> np.ndarray:
        """The ``lower-lip`` layer's lines, as :meth:`upper_lines` for the lower lip (the holding
        curve under the inner edge), chords along a curve ``teeth`` mouth-scale units above the inner
        edge (the lower teeth and tongue standing on the lip move with it), and the corners'."""
        d = (0, band * self.scale)
        return np.concatenate([chords(self.inner_dn, LIP_INNER_U), chords(self.inner_dn + d, LIP_BAND_U),
                               chords(self.outer_dn, LIP_OUTER_U),
                               chords(self.inner_dn - (0, teeth * self.scale), LIP_BAND_U), self.corner_lines()])


def mouth_geom(center, scale: float, pose: MouthPose, n: int = 61) -> MouthGeom:
    """The mouth's curves in design pixels (a closed mouth's inner edges coincide on the seam)."""
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
    "ah": MouthPose(hw=0.82, smile=0.02, open=0.95),
    "oo": MouthPose(hw=0.52, open=0.52, round=1.0, tu=0.2, tl=0.24, up_ratio=0.4),
    "grin": MouthPose(hw=1.28, smile=0.34, open=0.6, up_ratio=0.5),
    "frown": MouthPose(hw=0.95, smile=-0.28, tl=0.18),
    "ee": MouthPose(hw=1.2, smile=0.1, open=0.36, up_ratio=0.6),
}


@dataclass
class Character:
    """What a bundled character module fills in; :meth:`build` turns it into a layered ArtSet.

    Coordinates of the drawing code are *design* pixels (the 512×512 space the characters were
    first drawn in); ``scale`` and ``lift`` place them on the canvas (``Placement``), small
    enough that the head, rolled ±30° about ``pivot`` (design px, the top of the neck), stays
    inside the canvas. The body (neck, shoulders) is a separate image under the head.
    """

    slug: str
    name: str
    style: str
    description: str
    author: str = "Inkface art-set authoring code"
    canvas: tuple[int, int] = (512, 512)
    pivot: tuple[float, float] = (256.0, 420.0)
    scale: float = 1.0  # design -> canvas, about the canvas's vertical centre line
    lift: float = 0.0  # canvas px the drawing is moved down (+) after scaling
    eyes_box: tuple[int, int, int, int] = (100, 144, 312, 136)
    mouth_box: tuple[int, int, int, int] = (166, 316, 180, 128)
    eye_centers: tuple[tuple[float, float], tuple[float, float]] = ((194.0, 228.0), (318.0, 228.0))
    eye_hw: float = 36.0
    mouth_center: tuple[float, float] = (256.0, 362.0)
    mouth_scale: float = 40.0
    teeth_hw: float = 1.3  # half-width of the upper teeth row, in mouth_scale units
    lip_band: float = 0.08  # mouth-scale units of each lip's inner edge that move rigidly with it
    teeth_top: float = 0.3  # mouth-scale units above the lower lip's edge that its teeth and tongue reach
    tusks: float = 0.0  # mouth-scale height of tusks drawn in front of both lips (``draw_tusks``), 0: none
    skin: tuple[float, float, float] = (1.0, 0.9, 0.8)
    mouth_skin: tuple[float, float, float] | None = None  # background of the mouth drawings, when not skin
    mouth_dark: tuple[float, float, float] = (0.3, 0.1, 0.12)  # the inside of the mouth
    ss: int = 3
    seed: int = 1
    heads: int = 3
    paper_amount: float = 0.015
    grain: float = 0.0
    feather: float = 3.5
    body_follow: float = 0.3
    body_roll: float = 0.0  # a body that does not roll moves by whole pixels: no warp (see morph.compositor)
    eyes: dict = field(default_factory=lambda: dict(DEFAULT_EYES))
    mouths: dict = field(default_factory=lambda: dict(DEFAULT_MOUTHS))
    eye_kw: dict = field(default_factory=dict)
    lid_band: float = LID_BAND  # eye half-widths: how much of each lid moves rigidly with it (its stroke, shading)

    # --- hooks the character modules override -------------------------------------------------
    def draw_head(self, s: Surface, rng: np.random.Generator, k: int) -> None:  # pragma: no cover
        """The head without neck and shoulders (those are the body)."""
        raise NotImplementedError

    def draw_body(self, s: Surface, rng: np.random.Generator) -> None:  # pragma: no cover
        """Neck, shoulders and collar on the whole canvas; the neck reaches up under the jaw, the
        clothes run off the canvas's bottom and sides."""
        raise NotImplementedError

    def draw_eyeball(self, s: Surface, g: EyeGeom, socket: np.ndarray, rng: np.random.Generator) -> None:  # pragma: no cover
        """The white and iris of one eye, inside ``socket`` (a full-surface mask: every opening of every pose)."""
        raise NotImplementedError

    def draw_lower_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng: np.random.Generator) -> None:  # pragma: no cover
        """The lower lid's line (its skin is filled already)."""
        raise NotImplementedError

    def draw_upper_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng: np.random.Generator) -> None:  # pragma: no cover
        """The upper lid's line, lashes, lid shading (the skin is filled and the slot cut already)."""
        raise NotImplementedError

    def draw_brow(self, s: Surface, g: EyeGeom, pose: EyePose, rng: np.random.Generator) -> None:  # pragma: no cover
        raise NotImplementedError

    def draw_inside(self, s: Surface, rest: MouthGeom, rng: np.random.Generator) -> None:  # pragma: no cover
        """The upper teeth on the dark of the mouth (filled already): the same in every drawing,
        seen where the lips part."""
        raise NotImplementedError

    def draw_lower_lip(self, s: Surface, g: MouthGeom, rng: np.random.Generator) -> None:  # pragma: no cover
        """The lower lip, its line, and the lower teeth and tongue standing on its inner edge (the
        skin below the edge is filled already; above it the surface is see-through)."""
        raise NotImplementedError

    def draw_upper_lip(self, s: Surface, g: MouthGeom, rng: np.random.Generator) -> None:  # pragma: no cover
        """The upper lip and its line (the skin is filled and the slot below the lip cut already)."""
        raise NotImplementedError

    def draw_tusks(self, s: Surface, g: MouthGeom, rng: np.random.Generator) -> None:  # pragma: no cover
        """With ``tusks`` > 0: what stands on the lower lip in front of the upper one (a top layer)."""
        raise NotImplementedError

    def holes(self, s: Surface) -> np.ndarray:
        """Full-surface feathered mask (1 = see-through) for the eye and mouth holes."""
        m = np.zeros((s.H, s.W), np.float32)
        for box, rnd in ((self.eyes_box, 0.45), (self.mouth_box, 0.5)):
            m = np.maximum(m, s.mask(rounded_rect(box, 2.6 * self.feather, rnd), blur=self.feather))
        return m

    # --- building ---------------------------------------------------------------------------
    @property
    def place(self) -> Placement:
        cx = self.canvas[0] / 2
        return Placement(self.scale, (cx * (1 - self.scale), self.lift))

    def textures(self) -> Textures:
        return Textures.make(self.canvas, self.ss, self.seed, self.paper_amount, self.grain)

    def eye_geoms(self, pose: EyePose) -> list[EyeGeom]:
        return [eye_geom(c, self.eye_hw, sgn, pose, **self.eye_kw)
                for c, sgn in zip(self.eye_centers, (1.0, -1.0))]

    def mouth(self, pose: MouthPose) -> MouthGeom:
        return mouth_geom(self.mouth_center, self.mouth_scale, pose)

    def _surface(self, box, tex, background=None, wobble_ref: float | None = None, grain_ref: list | None = None) -> Surface:
        return Surface(box[:2], box[2:], tex, background=background, place=self.place, wobble_ref=wobble_ref,
                       grain_ref=grain_ref)

    def _part_surface(self, box, tex, background=None, grain_ref: list | None = None) -> Surface:
        """A surface for one layer of a part drawing: strokes wobble by their share of their length,
        and with ``grain_ref`` (the first drawing's :attr:`Surface.strokes` of this layer) carry that
        drawing's pencil grain."""
        return self._surface(box, tex, background, wobble_ref=box[2] / self.scale / 2, grain_ref=grain_ref)

    def _to_box(self, lines, box) -> np.ndarray:
        """Design-space lines in pixels of the part drawing at canvas ``box``."""
        return np.round(self.place.lines(lines) - (box[0], box[1], box[0], box[1]), 2)

    def _rng(self, part: int, layer: int) -> np.random.Generator:
        # the same seed for every drawing of a part and layer: features drawn by the same calls get the
        # same wobble and jitter, so they line up under the morph instead of shimmering
        return np.random.default_rng([self.seed, part, layer])

    def build_eyes(self, tex) -> Part:
        box = self.place.box(self.eyes_box)
        geoms = {name: self.eye_geoms(pose) for name, pose in self.eyes.items()}
        s = self._part_surface(box, tex, self.skin)
        rest = next(iter(geoms.values()))
        rng = self._rng(1, 0)
        for e in range(2):
            socket = np.max([s.mask(gs[e].opening(), blur=0.6) for gs in geoms.values()], axis=0)
            self.draw_eyeball(s, rest[e], np.clip(3.0 * socket, 0, 1), rng)
        eyeball = Layer("eyeball", s.to_rgba(), self._to_box([[*g.inner, *g.outer] for g in rest], box), "eyes/eyeball.png")
        deepest = max(float(g.lower[:, 1].max()) for gs in geoms.values() for g in gs)
        drawings = []
        for dname, pose in self.eyes.items():
            gs = geoms[dname]
            low = self._part_surface(box, tex)
            rng = self._rng(1, 1)
            for g in gs:
                m = 0.12 * g.hw
                patch = np.concatenate([g.lower, [g.outer + (-g.sgn * m, 0), g.outer + (-g.sgn * m, deepest - g.outer[1] + 0.3 * g.hw),
                                                  g.inner + (g.sgn * m, deepest - g.inner[1] + 0.3 * g.hw), g.inner + (g.sgn * m, 0)]])
                low.fill(patch, self.skin)
                self.draw_lower_lid(low, g, pose, rng)
            up = self._part_surface(box, tex, self.skin)
            bottom = self.eyes_box[1] + self.eyes_box[3] + 10
            for g in gs:
                up.punch(up.mask(np.concatenate([g.upper, [(g.outer[0], bottom), (g.inner[0], bottom)]])))
            rng = self._rng(1, 2)
            for g in gs:  # brows first, while every drawing's random stream is still in step
                self.draw_brow(up, g, pose, rng)
            for g in gs:
                self.draw_upper_lid(up, g, pose, rng)
            layers = [eyeball,
                      Layer("lower-lid", low.to_rgba(), self._to_box(np.concatenate([g.lower_lines(self.lid_band) for g in gs]), box),
                            f"eyes/{dname}/lower-lid.png"),
                      Layer("upper-lid", up.to_rgba(), None, f"eyes/{dname}/upper-lid.png")]
            drawings.append(Drawing.from_layers(dname, layers, self._to_box(np.concatenate([g.upper_lines(self.lid_band) for g in gs]), box)))
        return Part("eyes", box, drawings)

    def build_mouth(self, tex) -> Part:
        box = self.place.box(self.mouth_box)
        rest = self.mouth(MouthPose())
        s = self._part_surface(box, tex, self.mouth_dark)
        self.draw_inside(s, rest, self._rng(2, 0))
        inside = Layer("inside", s.to_rgba(), self._to_box([[rest.left[0], rest.left[1], rest.right[0], rest.right[1]]], box),
                       "mouth/inside.png")
        skin = self.mouth_skin or self.skin
        geoms = {name: self.mouth(pose) for name, pose in self.mouths.items()}
        bottom = self.mouth_box[1] + self.mouth_box[3] + 10
        drawings = []
        # the first mouth's strokes per layer: every mouth's pencil grain follows them (``Surface``'s
        # ``grain_ref``). Lips travel far between mouths, so paper grain under them would differ. The eyes
        # keep the paper's grain: their lines move less, and there carrying it measured no cleaner.
        ref: dict[str, list] = {}
        for dname, pose in self.mouths.items():
            g = geoms[dname]
            low = self._part_surface(box, tex, grain_ref=ref.get("lower-lip"))
            # the lower skin runs out to the sides and the bottom of the box, under the upper layer's
            # skin: the corners move a lot between mouths, the two layers follow them a little
            # differently, and that must never open a gap onto the dark inside
            x0, x1 = self.mouth_box[0] - 10, self.mouth_box[0] + self.mouth_box[2] + 10
            low.fill(np.concatenate([g.inner_dn, [(x1, g.right[1]), (x1, bottom), (x0, bottom), (x0, g.left[1])]]), skin)
            self.draw_lower_lip(low, g, self._rng(2, 1))
            up = self._part_surface(box, tex, skin, grain_ref=ref.get("upper-lip"))
            up.punch(up.mask(np.concatenate([g.inner_up, [(g.right[0], bottom), (g.left[0], bottom)]])))
            self.draw_upper_lip(up, g, self._rng(2, 2))
            for name, srf in (("lower-lip", low), ("upper-lip", up)):
                if len(ref.setdefault(name, srf.strokes)) != len(srf.strokes):
                    raise ValueError(f"{self.slug}: mouth {dname!r} draws {len(srf.strokes)} strokes on its {name}, "
                                     f"mouth {next(iter(self.mouths))!r} {len(ref[name])}: their grain cannot follow each other")
            layers = [inside,
                      Layer("lower-lip", low.to_rgba(), self._to_box(g.lower_lines(self.lip_band, self.teeth_top), box),
                            f"mouth/{dname}/lower-lip.png"),
                      Layer("upper-lip", up.to_rgba(), None, f"mouth/{dname}/upper-lip.png")]
            if self.tusks > 0:
                ts = self._part_surface(box, tex, grain_ref=ref.get("tusks"))
                self.draw_tusks(ts, g, self._rng(2, 3))
                ref.setdefault("tusks", ts.strokes)
                held = np.concatenate([chords(g.inner_dn, LIP_INNER_U), chords(g.inner_dn - (0, self.tusks * g.scale), LIP_BAND_U)])
                layers.append(Layer("tusks", ts.to_rgba(), self._to_box(held, box), f"mouth/{dname}/tusks.png"))
            drawings.append(Drawing.from_layers(dname, layers, self._to_box(g.upper_lines(self.lip_band), box)))
        return Part("mouth", box, drawings)

    def build(self) -> ArtSet:
        tex = self.textures()
        parts = {"eyes": self.build_eyes(tex), "mouth": self.build_mouth(tex)}
        heads, files = [], []
        full = (0, 0, *self.canvas)
        for k in range(self.heads):
            s = self._surface(full, tex)
            self.draw_head(s, np.random.default_rng([self.seed, 3, k]), k)
            s.punch(self.holes(s))
            heads.append(s.to_rgba())
            files.append(f"head-{k + 1}.png")
        b = self._surface(full, tex)
        self.draw_body(b, np.random.default_rng([self.seed, 4]))
        body = Body(b.to_rgba(), "body.png", follow=self.body_follow, roll=self.body_roll)
        extra = {"style": self.style, "description": self.description,
                 "line_names": {"eyes": EYE_LINE_NAMES, "mouth": MOUTH_LINE_NAMES,
                                "eyes/lower-lid": LOWER_LID_LINE_NAMES, "mouth/lower-lip": LOWER_LIP_LINE_NAMES}}
        pivot = tuple(float(v) for v in self.place(self.pivot))
        return ArtSet(name=self.name, canvas=self.canvas, pivot=pivot, heads=heads, parts=parts,
                      author=self.author, head_files=files, extra=extra, body=body)

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


__all__ = ["EyePose", "MouthPose", "EyeGeom", "MouthGeom", "Character", "eye_geom", "mouth_geom", "chords",
           "rounded_rect", "head_outline", "closed", "ellipse", "EYE_LINE_NAMES", "LOWER_LID_LINE_NAMES",
           "MOUTH_LINE_NAMES", "LOWER_LIP_LINE_NAMES", "EYE_LAYERS", "MOUTH_LAYERS"]
