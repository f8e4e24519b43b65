"""Ivy — the "Straight" style: clean, even black ink over flat colour, like a tidy comic."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from art_sets.authoring.face import Character, EyeGeom, EyePose, MouthGeom, closed, head_outline
from art_sets.authoring.ink import Surface, bez, ellipse, hex_rgb, offset, point_at, sub_curve

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

    # --- eyes --------------------------------------------------------------------------------
    def draw_eyeball(self, s: Surface, g: EyeGeom, socket, rng) -> None:
        s.paint(socket, WHITE)
        s.fill(ellipse(g.iris_c, g.iris_r, g.iris_r), IRIS, clip=socket)
        s.stroke(ellipse(g.iris_c, g.iris_r * 0.97, g.iris_r * 0.97, n=90), 1.6, INK, rng=rng, taper=(0, 0), clip=socket)
        s.fill(ellipse(g.iris_c, g.iris_r * 0.5, g.iris_r * 0.5), INK, clip=socket)
        hl = g.iris_c + (-0.35 * g.iris_r, -0.4 * g.iris_r)
        s.fill(ellipse(hl, g.iris_r * 0.22, g.iris_r * 0.22), WHITE, clip=socket)

    def draw_lower_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        self.pen(s, sub_curve(g.lower, 0.18, 0.92), 1.7, rng, taper=(0.4, 0.4))

    def draw_upper_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        hw = g.hw
        # lash line: heavy upper lid with a flick at the outer corner
        self.pen(s, g.upper, 4.2, rng, taper=(0.12, 0.05), tip=0.3)
        flick = np.array([g.outer, g.outer + (-g.sgn * 0.28 * hw, -0.22 * hw)])
        self.pen(s, bez(flick[0], flick[0] + (-g.sgn * 0.15 * hw, -0.02 * hw), flick[1]), 3.2, rng, taper=(0.0, 0.8), tip=0.1)

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

    # --- mouth ---------------------------------------------------------------------------------
    def draw_inside(self, s: Surface, rest: MouthGeom, rng) -> None:
        sc, cx = rest.scale, float(rest.seam[len(rest.seam) // 2, 0])
        hw = self.teeth_hw * sc
        x = np.linspace(cx - hw, cx + hw, 60)
        u = (x - cx) / hw
        edge = np.stack([x, rest.seam[len(rest.seam) // 2, 1] - 0.08 * sc - 0.3 * sc * u ** 2], 1)
        s.fill(np.concatenate([edge, [(cx + hw, edge[-1, 1] - 0.6 * sc), (cx - hw, edge[0, 1] - 0.6 * sc)]]), WHITE)
        self.pen(s, edge, 1.2, rng, taper=(0.2, 0.2), color=SKIN_SHADE)

    def draw_lower_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        # lower teeth and tongue stand on the lip's inner edge; the upper lip hides them when closed
        mid = point_at(g.inner_dn, 0.5)
        s.fill(ellipse(mid + (0, -0.16 * sc), 0.36 * sc, 0.22 * sc), TONGUE)
        self.pen(s, bez(mid + (0, -0.33 * sc), mid + (0.02 * sc, -0.26 * sc), mid + (0, -0.2 * sc)), 1.2, rng,
                 color=MOUTH, taper=(0.3, 0.5))
        teeth = sub_curve(g.inner_dn, 0.16, 0.84)
        s.fill(np.concatenate([teeth + (0, 1.0), (teeth - (0, 0.16 * sc))[::-1]]), WHITE)
        self.pen(s, teeth - (0, 0.16 * sc), 1.2, rng, taper=(0.2, 0.2), color=SKIN_SHADE)
        s.fill(_band(g.outer_dn, g.inner_dn), LIP, opacity=0.5)
        self.pen(s, g.inner_dn, 1.8, rng, taper=(0.08, 0.08), tip=0.5)
        self.pen(s, sub_curve(g.outer_dn, 0.36, 0.64), 1.8, rng, taper=(0.5, 0.5))

    def draw_upper_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        self.pen(s, g.inner_up, 2.6, rng, taper=(0.1, 0.1), tip=0.4)
        for end, sgn in ((g.left, -1), (g.right, 1)):  # corner accents (the same shape in every mouth, so they line up)
            tick = bez(end + (sgn * 0.05 * sc, 0.1 * sc), end + (sgn * 0.13 * sc, -0.02 * sc),
                       end + (sgn * 0.1 * sc, -0.1 * sc))
            self.pen(s, tick, 1.6, rng, taper=(0.4, 0.6))

    # --- body ---------------------------------------------------------------------------------
    def draw_body(self, s: Surface, rng) -> None:
        j = lambda sd=0.7: rng.normal(0, sd, 2)
        neck = np.array([(210, 360), (204, 560), (308, 560), (302, 360)]) + j()
        s.fill(neck, SKIN)
        s.fill(np.array([(206, 420), (306, 420), (300, 466), (212, 466)]), SKIN_SHADE, blur=8)
        self.pen(s, [(209, 380), (204, 560)], 3.0, rng, taper=(0, 0))
        self.pen(s, [(303, 380), (308, 560)], 3.0, rng, taper=(0, 0))
        # shirt with a rounded collar, running off the canvas at the bottom and sides
        shirt = np.array([(-120, 640), (-120, 536), (-20, 498), (70, 478), (150, 462), (212, 456), (256, 480), (300, 456),
                          (362, 462), (442, 478), (532, 498), (632, 536), (632, 640)]) + j()
        s.fill(shirt, SHIRT)
        self.pen(s, shirt[1:-1], 3.0, rng, taper=(0, 0))
        for sgn in (-1, 1):
            collar = np.concatenate([bez((256, 482), (256 + sgn * 20, 470), (256 + sgn * 46, 456), (256 + sgn * 60, 456), n=20),
                                     bez((256 + sgn * 60, 456), (256 + sgn * 80, 476), (256 + sgn * 70, 500), (256 + sgn * 30, 504), n=20),
                                     bez((256 + sgn * 30, 504), (256 + sgn * 8, 500), (256, 482), n=10)]) + j(0.4)
            s.fill(collar, WHITE)
            self.pen(s, closed(collar), 2.6, rng, taper=(0, 0))
        for sgn in (-1, 1):  # a fold where the sleeve meets the shoulder
            self.pen(s, bez((256 + sgn * 170, 470), (256 + sgn * 190, 500), (256 + sgn * 186, 560)), 2.2, rng, taper=(0.3, 0.6))

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
        # ears
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
                    description="Clean, even black ink over flat colour (the paper's 'Straight' style).", seed=11, skin=SKIN,
                    paper_amount=0.006, eye_hw=40.0, eye_centers=((192.0, 232.0), (320.0, 232.0)),
                    eyes_box=(100, 150, 312, 132), eye_kw={"brow_gap": 0.85, "iris": 0.56},
                    mouth_box=(172, 310, 168, 124), mouth_center=(256.0, 354.0), mouth_scale=44.0, mouth_dark=MOUTH,
                    scale=0.84, lift=44.0, pivot=(256.0, 420.0))
