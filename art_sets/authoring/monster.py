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
    "ah": MouthPose(hw=0.86, smile=0.0, open=0.9, up_ratio=0.3, tongue=True, teeth_up=1, teeth_dn=1),
    "oo": MouthPose(hw=0.46, open=0.5, round=1.0, tu=0.2, tl=0.22, up_ratio=0.42, teeth_up=1, teeth_dn=1),
    "grin": MouthPose(hw=1.2, smile=0.32, open=0.62, up_ratio=0.4, teeth_up=1, teeth_dn=1, tongue=True),
    "frown": MouthPose(hw=0.98, smile=-0.26, tu=0.12, tl=0.16),
    "ee": MouthPose(hw=1.12, smile=0.06, open=0.34, up_ratio=0.5, teeth_up=1, teeth_dn=1),
}

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
    def draw_eye(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        hw = g.hw
        # heavy upper lid: a shaded band above the lid line
        t = np.linspace(0, 1, len(g.upper))
        if not g.closed:
            lid_top = g.upper - np.stack([0 * t, 0.22 * hw * np.sin(np.pi * t) ** 0.6 + 1.0], 1)
            s.fill(np.concatenate([lid_top, g.upper[::-1]]), SHADE)
            opening = g.opening()
            clip = s.mask(opening)
            s.fill(opening, EYE)
            s.fill(ellipse(g.iris_c, 0.95 * hw, 0.9 * hw), EYE_RIM, opacity=0.55, clip=clip, blur=4)
            s.fill(ellipse(g.iris_c, 0.58 * hw, 0.58 * hw), EYE, opacity=0.9, clip=clip, blur=3)
            s.fill(ellipse(g.iris_c, 0.12 * hw, 0.44 * hw), INK, clip=clip)
            s.fill(ellipse(g.iris_c + (-0.28 * hw, -0.22 * hw), 0.1 * hw, 0.1 * hw), (1, 1, 1), clip=clip)
            s.fill(np.concatenate([g.upper, (g.upper + (0, 0.18 * hw))[::-1]]), DEEP, opacity=0.35, clip=clip, blur=1.5)
            self.pen(s, closed(opening), 3.2, rng, taper=(0, 0), pressure=0.1)
            self.pen(s, g.upper, 5.5, rng, taper=(0.1, 0.1))
        else:  # a heavy, bulging closed lid
            base = g.inner + (g.outer - g.inner) * t[:, None]
            dome = base - np.stack([0 * t, 0.45 * hw * np.sin(np.pi * t ** 0.8) ** 0.75], 1)
            s.fill(np.concatenate([dome, g.upper[::-1]]), SHADE)
            s.fill(np.concatenate([dome, (dome + (0, 0.14 * hw))[::-1]]), MUZZLE, opacity=0.35, blur=1.5)
            self.pen(s, dome, 2.6, rng, color=DEEP, taper=(0.2, 0.2))
            self.pen(s, g.upper, 5.5, rng, taper=(0.15, 0.15))

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
    def draw_mouth(self, s: Surface, g: MouthGeom, rng) -> None:
        p, sc = g.pose, g.scale
        # lips: a darker band all round
        s.fill(g.lips(), SHADE)
        if g.open > 2:
            interior = g.interior()
            clip = s.mask(interior)
            s.fill(interior, MOUTH)
            if p.tongue:
                c = point_at(g.inner_dn, 0.5)
                s.fill(ellipse(c + (0, -0.12 * sc), 0.42 * (g.right[0] - g.left[0]) / 2 + 6, 0.34 * g.open + 4), TONGUE, clip=clip)
                self.pen(s, [c + (0, -0.3 * g.open), c + (0, -0.05 * g.open)], 2.0, rng, color=MOUTH, clip=clip)
            self.teeth_row(s, g.inner_up, +1, g, clip, rng)
            self.teeth_row(s, g.inner_dn, -1, g, clip, rng)
            self.pen(s, closed(interior), 4.0, rng, taper=(0, 0))
        else:
            self.pen(s, g.seam, 5.0, rng, taper=(0.12, 0.12), tip=0.5)
            for u, h in ((0.24, 0.34), (0.76, 0.34)):
                self.fang(s, point_at(g.seam, u), -1, h * sc, 0.11 * sc, rng)
        self.pen(s, closed(g.lips()), 2.4, rng, taper=(0, 0), color=DEEP, opacity=0.9)

    def teeth_row(self, s: Surface, edge: np.ndarray, direction: int, g: MouthGeom, clip, rng) -> None:
        sc = g.scale
        n = max(3, int(round((g.right[0] - g.left[0]) / (0.3 * sc))))
        us = np.linspace(0.1, 0.9, n)
        for i, u in enumerate(us):
            big = i in (0, n - 1)
            h = (0.42 if big else 0.22) * sc * (1 if direction > 0 else 0.85)
            h = min(h, 0.55 * g.open + 2)
            self.fang(s, point_at(edge, u), direction, h, (0.12 if big else 0.09) * sc, rng, clip=clip)

    def fang(self, s: Surface, base: np.ndarray, direction: int, h: float, half: float, rng, clip=None) -> None:
        tip = base + (rng.normal(0, 0.4), direction * h)
        tri = np.array([base + (-half, -direction * 2), base + (half, -direction * 2), tip])
        s.fill(tri, TOOTH, clip=clip)
        s.fill(np.array([base + (half * 0.2, 0), base + (half, -direction * 2), tip]), TOOTH_SHADE, clip=clip, opacity=0.6)
        self.pen(s, [tri[0], tri[2], tri[1]], 1.8, rng, taper=(0.1, 0.1), clip=clip, pressure=0.0, wobble=0.0)

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
        # neck
        neck = np.array([(176, 430), (160, 512), (352, 512), (336, 430)]) + j()
        s.fill(neck, SHADE)
        self.pen(s, [(176, 430), (160, 512)], 4.0, rng, taper=(0, 0))
        self.pen(s, [(336, 430), (352, 512)], 4.0, rng, taper=(0, 0))
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
                   mouth_scale=66.0, paper_amount=0.012, eye_kw={"brow_gap": 0.8, "brow_len": 1.05})
