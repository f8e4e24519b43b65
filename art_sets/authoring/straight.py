"""Ivy — the "Straight" style: clean, even black ink over flat colour, like a tidy comic."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from art_sets.authoring.face import Character, EyeGeom, EyePose, MouthGeom, closed, head_outline
from art_sets.authoring.ink import Surface, bez, ellipse, hex_rgb, offset, sub_curve

INK = hex_rgb("#1d1a22")
SKIN = hex_rgb("#f6d6bd")
SKIN_SHADE = hex_rgb("#e9b99c")
HAIR = hex_rgb("#3a2a3f")
HAIR_HI = hex_rgb("#5a4563")
IRIS = hex_rgb("#3f7f74")
MOUTH = hex_rgb("#6e2b35")
TONGUE = hex_rgb("#d9707a")
LIP = hex_rgb("#dd8d8a")
BLUSH = hex_rgb("#f0a39a")
SHIRT = hex_rgb("#4f9db8")
CLIP = hex_rgb("#f6c343")
CLIP_MID = hex_rgb("#e8734f")
WHITE = (1.0, 1.0, 0.99)


@dataclass
class Straight(Character):
    def pen(self, s: Surface, pts, w: float, rng, color=INK, **kw) -> None:
        opts = dict(taper=(0.22, 0.22), tip=0.2, pressure=0.06)
        opts.update(kw)
        s.stroke(pts, w, color, rng=rng, **opts)

    # --- parts ---------------------------------------------------------------------------------
    def draw_eye(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        hw = g.hw
        if not g.closed:
            opening = g.opening()
            clip = s.mask(opening)
            s.fill(opening, WHITE)
            s.fill(ellipse(g.iris_c, g.iris_r, g.iris_r), IRIS, clip=clip)
            s.stroke(ellipse(g.iris_c, g.iris_r * 0.97, g.iris_r * 0.97, n=90), 1.6, INK, rng=rng, taper=(0, 0), clip=clip)
            s.fill(ellipse(g.iris_c, g.iris_r * 0.5, g.iris_r * 0.5), INK, clip=clip)
            hl = g.iris_c + (-0.35 * g.iris_r, -0.4 * g.iris_r)
            s.fill(ellipse(hl, g.iris_r * 0.22, g.iris_r * 0.22), WHITE, clip=clip)
            # lash line: heavy upper lid with a flick at the outer corner
            self.pen(s, g.upper, 4.2, rng, taper=(0.12, 0.05), tip=0.3)
            flick = np.array([g.outer, g.outer + (-g.sgn * 0.28 * hw, -0.22 * hw)])
            self.pen(s, bez(flick[0], flick[0] + (-g.sgn * 0.15 * hw, -0.02 * hw), flick[1]), 3.2, rng, taper=(0.0, 0.8), tip=0.1)
            self.pen(s, sub_curve(g.lower, 0.18, 0.92), 1.7, rng, taper=(0.4, 0.4))
            if pose.up > 0.6:
                self.pen(s, sub_curve(g.upper - (0, 0.32 * hw), 0.25, 0.85), 1.4, rng, taper=(0.5, 0.5))
        else:
            self.pen(s, g.upper, 4.0, rng, taper=(0.15, 0.1), tip=0.3)
            for u in (0.55, 0.75, 0.92):
                p = sub_curve(g.upper, u, u, 2)[0]
                d = np.array([-g.sgn * 0.12 * hw, 0.22 * hw]) * (0.6 + u)
                self.pen(s, [p, p + d], 2.2, rng, taper=(0.0, 0.9))

    def draw_brow(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        upper = offset(g.brow, -2.6)
        lower = offset(g.brow, 2.6)
        u = np.linspace(0, 1, len(g.brow))
        thick = 0.35 + 0.65 * np.sin(np.pi * np.clip(u * 0.9 + 0.05, 0, 1)) ** 0.6
        top = g.brow + (upper - g.brow) * thick[:, None]
        bot = g.brow + (lower - g.brow) * thick[:, None]
        shape = np.concatenate([top, bot[::-1]])
        s.fill(shape, HAIR)
        self.pen(s, closed(shape), 1.3, rng, taper=(0, 0))

    def draw_mouth(self, s: Surface, g: MouthGeom, rng) -> None:
        p, sc = g.pose, g.scale
        if g.open > 2:
            interior = g.interior()
            clip = s.mask(interior)
            s.fill(interior, MOUTH)
            if p.tongue:
                c = sub_curve(g.inner_dn, 0.5, 0.5, 2)[0]
                s.fill(ellipse(c + (0, -0.08 * sc), 0.55 * (g.right[0] - g.left[0]) / 2, 0.3 * g.open), TONGUE, clip=clip)
            self.teeth(s, g, clip, rng)
            s.fill(_band(g.outer_dn, g.inner_dn), LIP, opacity=0.55)
            self.pen(s, closed(interior), 2.8, rng, taper=(0, 0))
        else:
            self.pen(s, g.seam, 3.2, rng, taper=(0.2, 0.2), tip=0.35)
            s.fill(_band(g.outer_dn, g.seam + (0, 1.5)), LIP, opacity=0.35)
        self.pen(s, sub_curve(g.outer_dn, 0.36, 0.64), 1.8, rng, taper=(0.5, 0.5))
        if p.smile > 0.2:
            for end, sgn in ((g.left, -1), (g.right, 1)):
                tick = bez(end + (sgn * 0.05 * sc, 0.12 * sc), end + (sgn * 0.14 * sc, -0.02 * sc), end + (sgn * 0.1 * sc, -0.16 * sc))
                self.pen(s, tick, 2.0, rng, taper=(0.4, 0.6))

    def teeth(self, s: Surface, g: MouthGeom, clip, rng) -> None:
        p = g.pose
        if p.teeth_up > 0:
            edge = g.inner_up + (0, p.teeth_up * g.open + 0.5)
            s.fill(np.concatenate([g.inner_up - (0, 2), edge[::-1]]), WHITE, clip=clip)
            self.pen(s, edge, 1.2, rng, taper=(0.2, 0.2), color=SKIN_SHADE, clip=clip)
        if p.teeth_dn > 0:
            edge = g.inner_dn - (0, p.teeth_dn * g.open * 0.8 + 0.5)
            s.fill(np.concatenate([edge, (g.inner_dn + (0, 2))[::-1]]), WHITE, clip=clip)
            self.pen(s, edge, 1.2, rng, taper=(0.2, 0.2), color=SKIN_SHADE, clip=clip)

    # --- head -----------------------------------------------------------------------------------
    def draw_head(self, s: Surface, rng, k: int) -> None:
        j = lambda sd=0.7: rng.normal(0, sd, 2)
        cx = 256.0
        face = head_outline(cx, 256, 180, 216, chin=0.14) + j()
        # hair behind the head (bob)
        back = np.concatenate([
            bez((52, 350), (20, 130), (140, 22), (256, 24), n=50),
            bez((256, 24), (372, 22), (492, 130), (460, 350), n=50),
            bez((460, 350), (448, 392), (400, 388), (386, 350), n=20),
            bez((126, 350), (112, 388), (64, 392), (52, 350), n=20),
        ]) + j()
        s.fill(back, HAIR)
        self.pen(s, closed(back), 3.0, rng, taper=(0, 0))
        # neck and ears
        neck = np.array([(206, 420), (202, 512), (310, 512), (306, 420)]) + j()
        s.fill(neck, SKIN)
        s.fill(np.array([(206, 430), (306, 430), (300, 470), (212, 470)]), SKIN_SHADE, blur=8)
        self.pen(s, [(206, 420), (203, 512)], 3.0, rng, taper=(0, 0.3))
        self.pen(s, [(306, 420), (309, 512)], 3.0, rng, taper=(0, 0.3))
        # shirt with a rounded collar, in front of the neck, behind the chin
        shirt = np.array([(40, 512), (70, 486), (150, 466), (212, 458), (256, 480), (300, 458), (362, 466), (442, 486), (472, 512)]) + j()
        s.fill(shirt, SHIRT)
        self.pen(s, shirt, 3.0, rng, taper=(0, 0))
        for sgn in (-1, 1):
            collar = np.concatenate([bez((256, 482), (256 + sgn * 20, 470), (256 + sgn * 46, 456), (256 + sgn * 60, 456), n=20),
                                     bez((256 + sgn * 60, 456), (256 + sgn * 80, 476), (256 + sgn * 70, 500), (256 + sgn * 30, 504), n=20),
                                     bez((256 + sgn * 30, 504), (256 + sgn * 8, 500), (256, 482), n=10)]) + j(0.4)
            s.fill(collar, WHITE)
            self.pen(s, closed(collar), 2.6, rng, taper=(0, 0))
        for sgn in (-1, 1):
            ear = ellipse((cx + sgn * 178, 262), 22, 34) + j()
            s.fill(ear, SKIN)
            self.pen(s, closed(ear), 3.0, rng, taper=(0, 0))
            self.pen(s, bez((cx + sgn * 182, 245), (cx + sgn * 170, 258), (cx + sgn * 182, 280)), 2.0, rng)
        s.fill(face, SKIN)
        self.pen(s, closed(face), 3.6, rng, taper=(0, 0), pressure=0.1)
        # cheeks and nose
        for sgn in (-1, 1):
            s.fill(ellipse((cx + sgn * 112, 306), 24, 12), BLUSH, opacity=0.55, blur=5)
        self.pen(s, bez((252, 282), (245, 296), (249, 304), (262, 302)), 2.6, rng, taper=(0.5, 0.3))
        # fringe in front of the forehead
        fringe = np.concatenate([
            bez((70, 250), (52, 100), (160, 30), (262, 32), n=40),
            bez((262, 32), (366, 34), (460, 100), (442, 250), n=40),
            bez((442, 250), (420, 200), (402, 160), (380, 150), n=12),
            bez((380, 150), (330, 150), (290, 128), (262, 110), n=20),
            bez((262, 110), (230, 140), (170, 152), (130, 150), n=20),
            bez((130, 150), (104, 170), (84, 205), (70, 250), n=12),
        ]) + j()
        s.fill(fringe, HAIR)
        for a, b, c in (((150, 78), (200, 70), (240, 80)), ((300, 76), (350, 82), (392, 110))):
            self.pen(s, bez(a, b, c), 5.0, rng, color=HAIR_HI, taper=(0.5, 0.5))
        self.pen(s, closed(fringe), 3.4, rng, taper=(0, 0))
        # a flower hair clip on the fringe
        c = np.array([372.0, 104.0]) + j(0.4)
        for a in np.linspace(0, 2 * np.pi, 5, endpoint=False):
            petal = ellipse(c + 11 * np.array([np.cos(a), np.sin(a)]), 9, 6, rot=a)
            s.fill(petal, CLIP)
            self.pen(s, closed(petal), 1.8, rng, taper=(0, 0))
        s.fill(ellipse(c, 5, 5), CLIP_MID)
        self.pen(s, closed(ellipse(c, 5, 5)), 1.6, rng, taper=(0, 0))
        for a, b, c in (((262, 110), (270, 90), (262, 62)), ((200, 140), (215, 115), (218, 90)), ((340, 140), (322, 118), (318, 92))):
            self.pen(s, bez(np.add(a, j()), b, c), 2.0, rng, taper=(0.1, 0.6))


def _band(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    return np.concatenate([outer, inner[::-1]])


def character() -> Straight:
    return Straight(slug="ivy", name="Ivy", style="straight",
                    description="Clean, even black ink over flat colour (the paper's 'Straight' style).", seed=11, skin=SKIN, paper_amount=0.006, eye_hw=40.0, eye_centers=((192.0, 232.0), (320.0, 232.0)),
                    eyes_box=(100, 150, 312, 132), eye_kw={"brow_gap": 0.85, "iris": 0.56},
                    mouth_box=(172, 310, 168, 124), mouth_center=(256.0, 354.0), mouth_scale=44.0)
