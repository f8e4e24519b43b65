"""Gnash — the "Monster" style: a green horned creature, thick brush outlines, cel shading, fangs."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from art_sets.authoring.face import (DEFAULT_EYES, Character, EyeGeom, EyePose, MouthGeom, MouthPose, closed,
                                     head_outline)
from art_sets.authoring.ink import Surface, bez, ellipse, hex_rgb, point_at, sub_curve

INK = hex_rgb("#1b1426")
SKIN = hex_rgb("#74c06a")
SHADE = hex_rgb("#4e9a57")
DEEP = hex_rgb("#3b7a4a")
MUZZLE = hex_rgb("#b9df8e")
SPOT = hex_rgb("#5fae62")
HORN = hex_rgb("#f1e4c3")
HORN_SHADE = hex_rgb("#c9b68c")
RING = hex_rgb("#8f7d5c")
EYE = hex_rgb("#ffd54a")
EYE_RIM = hex_rgb("#f29a2e")
MOUTH = hex_rgb("#45112e")
TONGUE = hex_rgb("#e2507a")
TOOTH = hex_rgb("#fffbea")
TOOTH_SHADE = hex_rgb("#d8ccb0")

MONSTER_MOUTHS = {
    "neutral": MouthPose(hw=1.0, smile=0.04, tu=0.12, tl=0.16),
    "smile": MouthPose(hw=1.12, smile=0.34, tu=0.12, tl=0.16),
    "ah": MouthPose(hw=0.86, smile=0.0, open=0.9, up_ratio=0.3),
    "oo": MouthPose(hw=0.5, open=0.5, round=1.0, tu=0.14, tl=0.18, up_ratio=0.42),
    "grin": MouthPose(hw=1.2, smile=0.32, open=0.62, up_ratio=0.45),
    "frown": MouthPose(hw=0.98, smile=-0.26, tu=0.12, tl=0.16),
    "ee": MouthPose(hw=1.12, smile=0.06, open=0.34, up_ratio=0.5),
}
SHIRT = hex_rgb("#7a4fa0")
SHIRT_SHADE = hex_rgb("#5d3a80")

MONSTER_EYES = dict(DEFAULT_EYES)
MONSTER_EYES.update({
    "open": EyePose(up=0.62, dn=0.5, brow_arch=0.1),
    "wide": EyePose(up=0.86, dn=0.66, brow=0.4, brow_arch=0.2),
    "angry": EyePose(up=0.5, dn=0.42, lid_drop=0.42, brow=-0.2, brow_tilt=0.5, brow_arch=0.0),
    "squint": EyePose(up=0.3, dn=0.36, lower_lift=0.2, brow=-0.1, brow_arch=0.05),
})


@dataclass
class Monster(Character):
    mouths: dict = field(default_factory=lambda: dict(MONSTER_MOUTHS))
    eyes: dict = field(default_factory=lambda: dict(MONSTER_EYES))

    def pen(self, s: Surface, pts, w: float, rng, color=INK, **kw) -> None:
        opts = dict(taper=(0.18, 0.18), tip=0.3, pressure=0.18, wobble=0.35, wobble_len=60)
        opts.update(kw)
        s.stroke(pts, w, color, rng=rng, **opts)

    # --- eyes -----------------------------------------------------------------------------------
    def draw_eyeball(self, s: Surface, g: EyeGeom, socket, rng) -> None:
        hw = g.hw
        s.paint(socket, EYE)
        s.fill(ellipse(g.iris_c, 0.95 * hw, 0.9 * hw), EYE_RIM, opacity=0.55, clip=socket, blur=4)
        s.fill(ellipse(g.iris_c, 0.58 * hw, 0.58 * hw), EYE, opacity=0.9, clip=socket, blur=3)
        s.fill(ellipse(g.iris_c, 0.12 * hw, 0.44 * hw), INK, clip=socket)
        s.fill(ellipse(g.iris_c + (-0.28 * hw, -0.22 * hw), 0.1 * hw, 0.1 * hw), (1, 1, 1), clip=socket)

    def draw_lower_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        self.pen(s, g.lower, 3.2, rng, taper=(0.05, 0.05), pressure=0.1)

    def draw_upper_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        hw = g.hw
        # heavy upper lid: a shaded band above the lid line, a soft shadow cast below it
        t = np.linspace(0, 1, len(g.upper))
        lid_top = g.upper - np.stack([0 * t, 0.22 * hw * np.sin(np.pi * t) ** 0.6 + 1.0], 1)
        s.fill(np.concatenate([lid_top, g.upper[::-1]]), SHADE)
        s.fill(np.concatenate([g.upper, (g.upper + (0, 0.16 * hw))[::-1]]), DEEP, opacity=0.3, blur=1.5)
        self.pen(s, g.upper, 5.5, rng, taper=(0.1, 0.1))

    def draw_brow(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        hw = g.hw
        # bony brow ridge
        top = g.brow - (0, 0.2 * hw)
        bot = g.brow + (0, 0.16 * hw)
        u = np.linspace(0, 1, len(g.brow))
        k = (0.2 + 0.8 * np.sin(np.pi * np.clip(u * 0.9 + 0.05, 0, 1)) ** 0.7)[:, None]
        ridge = np.concatenate([g.brow + (top - g.brow) * k, (g.brow + (bot - g.brow) * k)[::-1]])
        s.fill(ridge, DEEP)
        self.pen(s, closed(ridge), 3.0, rng, taper=(0, 0))

    # --- mouth ----------------------------------------------------------------------------------
    def draw_inside(self, s: Surface, rest: MouthGeom, rng) -> None:
        sc, (cx, cy) = rest.scale, rest.seam[len(rest.seam) // 2]
        hw = self.teeth_hw * sc
        x = np.linspace(cx - hw, cx + hw, 60)
        gum = np.stack([x, cy - 0.3 * sc - 0.3 * sc * ((x - cx) / hw) ** 2], 1)
        s.fill(np.concatenate([gum, (gum - (0, 0.5 * sc))[::-1]]), DEEP)
        self.teeth_row(s, gum, +1, sc, 0.1, 0.9, 9, rng)

    def draw_lower_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        c = point_at(g.inner_dn, 0.5)
        s.fill(ellipse(c + (0, -0.14 * sc), 0.36 * sc, 0.24 * sc), TONGUE)
        self.pen(s, [c + (0, -0.34 * sc), c + (0, -0.16 * sc)], 2.0, rng, color=MOUTH)
        self.teeth_row(s, g.inner_dn + (0, 2.0), -1, sc, 0.16, 0.84, 6, rng)
        s.fill(np.concatenate([g.inner_dn, g.outer_dn[::-1]]), SHADE)
        self.pen(s, g.inner_dn, 4.0, rng, taper=(0.05, 0.05))
        self.pen(s, g.outer_dn, 2.4, rng, taper=(0.2, 0.2), color=DEEP, opacity=0.9)

    def draw_upper_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        s.fill(np.concatenate([g.outer_up, g.inner_up[::-1]]), SHADE)
        self.pen(s, g.outer_up, 2.4, rng, taper=(0.2, 0.2), color=DEEP, opacity=0.9)
        self.pen(s, g.inner_up, 5.0, rng, taper=(0.08, 0.08), tip=0.5)

    def draw_tusks(self, s: Surface, g: MouthGeom, rng) -> None:
        for u in (0.24, 0.76):  # two tusks stand on the lower lip, in front of the upper one
            self.fang(s, point_at(g.inner_dn, u) + (0, 1.5), -1, self.tusks * g.scale, 0.11 * g.scale, rng)

    def teeth_row(self, s: Surface, edge: np.ndarray, direction: int, sc: float, u0: float, u1: float, n: int, rng) -> None:
        """``n`` fangs along ``edge`` between fractions ``u0`` and ``u1``, pointing down (+1) or up (−1)."""
        for i, u in enumerate(np.linspace(u0, u1, n)):
            big = i in (0, n - 1)
            h = (0.34 if big else 0.2) * sc * (1 if direction > 0 else 0.85)
            self.fang(s, point_at(edge, u), direction, h, (0.1 if big else 0.08) * sc, rng)

    def fang(self, s: Surface, base: np.ndarray, direction: int, h: float, half: float, rng, clip=None) -> None:
        tip = base + (rng.normal(0, 0.4), direction * h)  # a triangle from ``base``, pointing down (+1) or up (−1)
        tri = np.array([base + (-half, -direction * 2), base + (half, -direction * 2), tip])
        s.fill(tri, TOOTH, clip=clip)
        s.fill(np.array([base + (half * 0.2, 0), base + (half, -direction * 2), tip]), TOOTH_SHADE, clip=clip, opacity=0.6)
        self.pen(s, [tri[0], tri[2], tri[1]], 1.8, rng, taper=(0.1, 0.1), clip=clip, pressure=0.0, wobble=0.0)

    # --- body ----------------------------------------------------------------------------------
    def draw_body(self, s: Surface, rng) -> None:
        cx = 256.0
        neck = np.array([(176, 380), (160, 600), (352, 600), (336, 380)])
        s.fill(neck, SHADE)
        s.fill(np.array([(170, 440), (342, 440), (348, 500), (164, 500)]), DEEP, opacity=0.45, blur=8)
        self.pen(s, [(176, 420), (162, 600)], 4.0, rng, taper=(0, 0))
        self.pen(s, [(336, 420), (350, 600)], 4.0, rng, taper=(0, 0))
        # a hoodie over big shoulders, running off the canvas
        hoodie = np.concatenate([[(-150, 720), (-150, 580)], bez((-150, 580), (-60, 500), (90, 478), (170, 480), n=30),
                                 bez((170, 480), (cx, 540), (342, 480), n=20),
                                 bez((342, 480), (422, 478), (572, 500), (662, 580), n=30), [(662, 720)]])
        s.fill(hoodie, SHIRT)
        s.fill(np.concatenate([bez((-150, 620), (0, 540), (120, 530), n=20), bez((120, 530), (60, 640), (-150, 700), n=20)]),
               SHIRT_SHADE, opacity=0.8)
        self.pen(s, hoodie[2:-1], 4.2, rng, taper=(0, 0))
        for sgn in (-1, 1):  # hood strings
            self.pen(s, [(cx + sgn * 40, 512), (cx + sgn * 46, 600)], 3.0, rng, color=HORN, taper=(0, 0))
            s.fill(ellipse((cx + sgn * 46, 604), 6, 8), HORN)

    # --- head ----------------------------------------------------------------------------------
    def draw_head(self, s: Surface, rng, k: int) -> None:
        j = lambda sd=0.8: rng.normal(0, sd, 2)
        cx = 256.0
        # horns behind the head: curved cones with growth rings
        for sgn in (-1, 1):
            m = lambda *pts: [np.array([cx + sgn * x, y]) for x, y in pts]
            outer = bez(*m((150, 132), (204, 104), (214, 50), (178, 14)), n=40)
            inner = bez(*m((178, 14), (176, 52), (150, 84), (88, 104)), n=40)
            horn = np.concatenate([outer, inner]) + j()
            s.fill(horn, HORN)
            shade_edge = np.array([point_at(outer, u) * 0.6 + point_at(inner[::-1], u) * 0.4 for u in np.linspace(0, 1, 30)])
            s.fill(np.concatenate([outer, shade_edge[::-1]]), HORN_SHADE, opacity=0.75)
            for t in (0.22, 0.42, 0.6, 0.76):
                a, b = point_at(outer, t), point_at(inner[::-1], t)
                self.pen(s, bez(a, (a + b) / 2 + (0, 5), b, n=12), 2.2, rng, color=RING, taper=(0.3, 0.3))
            self.pen(s, closed(horn), 4.2, rng, taper=(0, 0))
        # ears: pointed fins
        for sgn in (-1, 1):
            ear = np.concatenate([bez((cx + sgn * 196, 200), (cx + sgn * 262, 170), (cx + sgn * 250, 230), n=20),
                                  bez((cx + sgn * 250, 230), (cx + sgn * 240, 270), (cx + sgn * 200, 300), n=20)]) + j()
            s.fill(ear, SKIN)
            s.fill(np.concatenate([bez((cx + sgn * 204, 214), (cx + sgn * 240, 200), (cx + sgn * 236, 236), n=12),
                                   bez((cx + sgn * 236, 236), (cx + sgn * 226, 262), (cx + sgn * 204, 278), n=12)]), SHADE)
            self.pen(s, ear, 4.2, rng, taper=(0.05, 0.05))
        face = head_outline(cx, 270, 206, 196, chin=-0.08, jowl=0.25) + j()
        s.fill(face, SKIN)
        # cel shade on the image-right side and under the jaw
        inset = head_outline(cx - 14, 262, 196, 188, chin=-0.08, jowl=0.25)
        band = s.mask(face) * (1 - s.mask(inset, blur=1.0))
        s.paint(band, SHADE)
        # muzzle (the mouth's background colour) and spots
        muzzle = ellipse((cx, 368), 166, 100)
        s.fill(muzzle, MUZZLE, clip=s.mask(face))
        self.pen(s, sub_curve(closed(muzzle), 0.52, 0.98), 2.0, rng, color=SHADE, taper=(0.3, 0.3), clip=s.mask(face))
        for (x, y, r) in ((140, 150, 10), (160, 126, 6), (360, 142, 12), (384, 170, 7), (112, 320, 9), (400, 318, 11), (414, 350, 6)):
            s.fill(ellipse(np.array((x, y)) + j(0.5), r, r * 0.8), SPOT)
            s.fill(ellipse(np.array((x, y)) + (-r * 0.2, -r * 0.2), r * 0.4, r * 0.3), MUZZLE, opacity=0.35)
        # nostrils on a snout bump
        for sgn in (-1, 1):
            s.fill(ellipse((cx + sgn * 15, 290), 7, 4.5, rot=sgn * 0.4), DEEP)
        self.pen(s, bez((cx - 32, 296), (cx - 28, 276), (cx, 268), (cx + 28, 276), (cx + 32, 296)), 2.4, rng, color=DEEP, taper=(0.4, 0.4))
        self.pen(s, closed(face), 5.5, rng, taper=(0, 0), pressure=0.25)
        # brow furrow above the eyes hole
        self.pen(s, bez((cx - 10, 134), (cx, 128), (cx + 10, 134)), 2.4, rng, color=DEEP)


def character() -> Monster:
    return Monster(slug="gnash", name="Gnash", style="monster",
                   description="A green horned creature with fangs: thick brush ink, flat cel shading (the paper's 'Monster').",
                   seed=44, skin=SKIN, mouth_skin=MUZZLE, eye_hw=38.0, eye_centers=((194.0, 216.0), (318.0, 216.0)),
                   eyes_box=(100, 146, 312, 132), mouth_box=(136, 304, 240, 126), mouth_center=(256.0, 350.0),
                   mouth_scale=66.0, paper_amount=0.012, eye_kw={"brow_gap": 0.8, "brow_len": 1.05, "brow_clear": 0.45},
                   mouth_dark=MOUTH, lid_band=0.27, teeth_hw=1.15, tusks=0.34, scale=0.72, lift=80.0, pivot=(256.0, 400.0))
