"""Bleu — the "Blue" style: a blue-pencil sketch on cream paper, grainy strokes and hatching."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from art_sets.authoring.face import DEFAULT_EYES, Character, EyeGeom, EyePose, MouthGeom, closed, head_outline
from art_sets.authoring.ink import Surface, bez, ellipse, hex_rgb, on_curve, point_at, sub_curve

PAPER = hex_rgb("#f6f0e1")
BLUE = hex_rgb("#1f3d8f")
LIGHT = hex_rgb("#6f8fd4")
DARK = hex_rgb("#142a6b")

BLUE_EYES = dict(DEFAULT_EYES)
BLUE_EYES.update({"open": EyePose(up=0.6, dn=0.42), "wide": EyePose(up=0.84, dn=0.56, brow=0.42, brow_arch=0.28)})


@dataclass
class Blue(Character):
    eyes: dict = field(default_factory=lambda: dict(BLUE_EYES))

    def pen(self, s: Surface, pts, w: float, rng, color=BLUE, passes: int = 2, **kw) -> None:
        """Pencil: grainy passes that do not quite coincide, the first a light construction line."""
        pts = np.asarray(pts, np.float64)
        for i in range(passes):
            opts = dict(taper=(0.3, 0.3), tip=0.1, pressure=0.25, wobble=0.5, wobble_len=90, jitter=0.45,
                        grain=0.8, opacity=0.8 if i else 0.55)
            opts.update(kw)
            c = LIGHT if (i == 0 and passes > 1) else color
            s.stroke(pts, w * (1.35 if i == 0 else 1.2), c, rng=rng, **opts)

    def scribble_fill(self, s: Surface, poly, rng, color=BLUE, angle=60.0, spacing=2.6, opacity=0.55, clip_blur=0.0):
        s.hatch(poly, angle, spacing, 1.2, color, rng, opacity=opacity, grain=0.8, clip_blur=clip_blur)

    # --- eyes ----------------------------------------------------------------------------------
    def draw_eyeball(self, s: Surface, g: EyeGeom, socket, rng) -> None:
        iris = ellipse(g.iris_c, g.iris_r, g.iris_r)
        s.fill(iris, LIGHT, opacity=0.6, clip=socket, grain=0.7)
        for a in np.linspace(0, 2 * np.pi, 22, endpoint=False):
            d = np.array([np.cos(a), np.sin(a)])
            s.stroke([g.iris_c + d * g.iris_r * 0.5, g.iris_c + d * g.iris_r * 0.95], 1.0, BLUE, rng=rng,
                     opacity=0.6, grain=0.6, clip=socket, taper=(0.2, 0.5))
        s.stroke(closed(iris), 1.6, BLUE, rng=rng, clip=socket, grain=0.6, taper=(0, 0), opacity=0.85)
        s.fill(ellipse(g.iris_c, g.iris_r * 0.45, g.iris_r * 0.45), DARK, clip=socket, grain=0.5)
        s.fill(ellipse(g.iris_c + (-0.35 * g.iris_r, -0.35 * g.iris_r), g.iris_r * 0.18, g.iris_r * 0.18), PAPER, clip=socket)

    def draw_lower_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        self.pen(s, sub_curve(g.lower, 0.1, 0.95), 1.5, rng, passes=1, opacity=0.7)

    def draw_upper_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        hw = g.hw
        self.pen(s, g.upper, 4.6, rng, taper=(0.1, 0.15))
        self.pen(s, sub_curve(g.upper - (0, 0.24 * hw), 0.2, 0.8), 1.2, rng, passes=1, opacity=0.45)  # the lid's crease
        for u in (0.72, 0.84, 0.95):  # lashes at the outer corner
            p = point_at(g.upper, u)
            s.stroke([p, p + (-g.sgn * 0.16 * hw, -0.2 * hw)], 1.6, BLUE, rng=rng, grain=0.6, taper=(0.0, 0.9), opacity=0.85)

    def draw_brow(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        hw = g.hw
        # brow: a band of short diagonal strokes
        n = 16
        for i, u in enumerate(np.linspace(0.02, 0.98, n)):
            p = point_at(g.brow, u)
            h = 0.22 * hw * (0.55 + 0.45 * np.sin(np.pi * min(1.0, u * 1.1)))
            d = np.array([-g.sgn * 0.08 * hw, -h])
            s.stroke([p - d * 0.5, p + d * 0.5], 1.7, BLUE, rng=rng, grain=0.7, taper=(0.2, 0.4), opacity=0.85, jitter=0.3)
        self.pen(s, g.brow, 1.4, rng, passes=1, opacity=0.6)

    # --- mouth ---------------------------------------------------------------------------------
    def draw_inside(self, s: Surface, rest: MouthGeom, rng) -> None:
        sc, (cx, cy) = rest.scale, rest.seam[len(rest.seam) // 2]
        x0, y0, w, h = self.mouth_box
        box = np.array([(x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h)], np.float64)
        s.fill(box, BLUE, opacity=0.55, grain=0.7)
        self.scribble_fill(s, box, rng, color=DARK, angle=35, spacing=2.2, opacity=0.5)
        hw = self.teeth_hw * sc
        x = np.linspace(cx - hw, cx + hw, 60)
        edge = np.stack([x, cy - 0.06 * sc - 0.3 * sc * ((x - cx) / hw) ** 2], 1)
        root = edge - (0, 0.7 * sc)
        s.fill(np.concatenate([edge, root[::-1]]), PAPER)
        s.stroke(edge, 1.0, BLUE, rng=rng, grain=0.6, opacity=0.45)
        for u in np.linspace(0.2, 0.8, 9):
            s.stroke([point_at(edge, u), point_at(root, u)], 0.9, BLUE, rng=rng, grain=0.6, opacity=0.5, taper=(0, 0.5))

    def draw_lower_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        c = point_at(g.inner_dn, 0.5)
        tongue = ellipse(c + (0, -0.14 * sc), 0.34 * sc, 0.22 * sc)
        s.fill(tongue, PAPER, opacity=0.85)
        s.stroke(closed(tongue), 1.2, BLUE, rng=rng, grain=0.6, taper=(0, 0))
        edge0 = sub_curve(g.inner_dn, 0.18, 0.82)
        edge = edge0 - (0, 0.14 * sc)
        s.fill(np.concatenate([edge0 + (0, 2.0), edge[::-1]]), PAPER)
        s.stroke(edge, 1.0, BLUE, rng=rng, grain=0.6, opacity=0.45)
        for u in np.linspace(0.2, 0.8, 6):
            s.stroke([point_at(edge0, u), point_at(edge, u)], 0.9, BLUE, rng=rng, grain=0.6, opacity=0.5, taper=(0, 0.5))
        self.pen(s, g.inner_dn, 2.8, rng, taper=(0.08, 0.08))
        self.pen(s, sub_curve(g.outer_dn, 0.32, 0.68), 1.5, rng, passes=1, opacity=0.7)
        # hatched lower lip: strokes placed along the lip and standing across it (``on_curve``), where
        # they keep their place among the lip's control lines in every mouth, so they line up under the morph
        for u in np.linspace(0.3, 0.7, 14):
            a, b = on_curve(g.outer_dn, [u, u], [0.12 * sc, 0.0], [0.02 * sc, -0.01 * sc])
            s.stroke([a, b], 1.0, LIGHT, rng=rng, opacity=0.5, grain=0.7, taper=(0, 0))

    def draw_upper_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        self.pen(s, g.inner_up, 3.4, rng, taper=(0.08, 0.08))
        # corner creases: the same shape in every mouth, so they line up, and drawn like every other line
        # (a light pass under a firm one): a lone faint hairline turns grey and twice as wide wherever
        # the morph puts it between pixels
        for end, sgn in ((g.left, -1), (g.right, 1)):
            self.pen(s, bez(end + (sgn * 0.02 * sc, 0.1 * sc), end + (sgn * 0.13 * sc, 0),
                            end + (sgn * 0.07 * sc, -0.1 * sc)), 1.6, rng)

    # --- body ----------------------------------------------------------------------------------
    def draw_body(self, s: Surface, rng) -> None:
        cx = 256.0
        jit = lambda sd=1.0: rng.normal(0, sd, 2)
        neck = np.array([(196, 380), (188, 560), (324, 560), (316, 380)])
        s.fill(neck, PAPER)
        self.pen(s, [(200, 400), (192, 520)], 2.2, rng)
        self.pen(s, [(312, 400), (320, 520)], 2.2, rng)
        s.hatch(np.array([(196, 420), (316, 420), (318, 470), (194, 470)]), 60, 3.2, 1.2, BLUE, rng, opacity=0.55, grain=0.8, clip_blur=6)
        # a hatched jumper with a ribbed roll neck, running off the canvas
        jumper = np.array([(-130, 640), (-130, 540), (-20, 500), (100, 474), (208, 456), (304, 456), (412, 474), (532, 500),
                           (642, 540), (642, 640)]) + jit()
        s.fill(jumper, PAPER)
        s.hatch(jumper, 70, 4.2, 1.2, LIGHT, rng, opacity=0.55, grain=0.8)
        s.hatch(jumper, 110, 7.0, 1.0, BLUE, rng, opacity=0.3, grain=0.8)
        self.pen(s, jumper[1:-1], 2.4, rng, taper=(0.05, 0.05))
        roll = np.array([(186, 440), (326, 440), (334, 486), (178, 486)]) + jit(0.5)
        s.fill(roll, PAPER)
        for x in np.arange(190, 326, 7.0):
            s.stroke([(x, 444 + rng.normal(0, 1)), (x - 1 + rng.normal(0, 1), 482)], 1.3, BLUE, rng=rng, grain=0.7, opacity=0.7,
                     taper=(0.2, 0.2))
        self.pen(s, closed(roll), 2.2, rng, taper=(0, 0))
        for sgn in (-1, 1):  # folds at the shoulders
            self.pen(s, bez((cx + sgn * 150, 478), (cx + sgn * 170, 520), (cx + sgn * 166, 600)), 1.6, rng, passes=1, opacity=0.7)

    # --- head ----------------------------------------------------------------------------------
    def draw_head(self, s: Surface, rng, k: int) -> None:
        cx = 256.0
        jit = lambda sd=1.0: rng.normal(0, sd, 2)
        face = head_outline(cx, 262, 178, 214, chin=0.22) + jit()
        hair, strands = messy_hair(rng)
        for poly in [face] + [ellipse((cx + sg * 178, 262), 24, 36) for sg in (-1, 1)]:
            s.fill(poly, PAPER)
        for sgn in (-1, 1):
            ear = ellipse((cx + sgn * 178, 262), 24, 36) + jit()
            self.pen(s, closed(ear)[::-1] if sgn > 0 else closed(ear), 2.2, rng)
            self.pen(s, bez((cx + sgn * 182, 246), (cx + sgn * 168, 260), (cx + sgn * 184, 282)), 1.4, rng, passes=1)
        # hatched shade along the image-right cheek, then the outline
        s.hatch(face, 62, 3.4, 1.1, BLUE, rng, opacity=0.45, grain=0.8)
        s.fill(head_outline(cx - 18, 254, 168, 208, chin=0.22), PAPER, blur=5.0, clip=s.mask(face))
        self.pen(s, closed(face), 2.8, rng, taper=(0.02, 0.02))
        # freckles and nose
        for sgn in (-1, 1):
            for _ in range(9):
                p = np.array([cx + sgn * 110, 300]) + rng.normal(0, [14, 7])
                s.dot(p, rng.uniform(1.0, 1.8), BLUE, opacity=0.6)
        self.pen(s, bez((250, 272), (244, 292), (240, 300), (256, 304)), 2.2, rng)
        self.pen(s, bez((262, 296), (268, 302), (264, 306)), 1.6, rng, passes=1)
        # messy hair: an opaque mass lightly hatched, then strands fanning out from the crown
        s.fill(hair, PAPER, blur=1.0)
        s.hatch(hair, 100, 3.6, 1.1, LIGHT, rng, opacity=0.4, grain=0.8, clip_blur=2.0)
        self.pen(s, hair[:40], 2.0, rng, taper=(0.1, 0.1))
        for i, (root, tip, bend) in enumerate(strands * 2):
            d = tip - root
            perp = np.array([-d[1], d[0]])
            mid = (root + tip) / 2 + perp * bend * (0.7 + 0.6 * rng.random()) + rng.normal(0, 3, 2)
            self.pen(s, bez(root, mid, tip + rng.normal(0, 2.5, 2)), rng.uniform(1.2, 2.3) if i < len(strands) else 1.0,
                     rng, passes=1, taper=(0.5, 0.3), tip=0.05, opacity=0.9 if i < len(strands) else 0.6)
        # a few light construction lines, as if left from the sketch
        self.pen(s, bez((cx - 170, 100), (cx, 60), (cx + 170, 100)), 1.0, rng, passes=1, color=LIGHT, opacity=0.4)


def messy_hair(rng) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray, float]]]:
    """A mop of hair: the smooth mass (polygon) and strands (root, tip, bend) fanning from the crown.

    Outer strands overshoot the mass as loose tufts; fringe strands end in pointed locks on the forehead.
    """
    th = np.linspace(np.pi * 0.97, np.pi * 2.03, 40)
    top = np.stack([256 + 196 * np.cos(th), 252 + 212 * np.sin(th)], 1)
    fringe = np.concatenate([bez((448, 264), (424, 150), (336, 126), (256, 132), n=20),
                             bez((256, 132), (176, 126), (88, 150), (64, 264), n=20)[1:]])
    poly = np.concatenate([top, fringe])
    crown = np.array([236.0, 66.0])
    strands = []
    for t in np.linspace(0.0, 1.0, 34):  # over the top, overshooting the mass
        p = top[int(round(t * (len(top) - 1)))]
        d = p - crown
        tip = p + d / np.hypot(*d) * rng.uniform(4, 22)
        strands.append((crown + rng.normal(0, 8, 2), tip, 0.12 * np.sign(d[0] + 1e-6)))
    for t in np.linspace(0.04, 0.96, 15):  # fringe locks
        p = fringe[int(round(t * (len(fringe) - 1)))]
        tip = p + (rng.normal(0, 4), rng.uniform(10, 20) if abs(p[0] - 256) < 150 else rng.uniform(8, 26))
        if abs(tip[0] - 256) < 150:
            tip[1] = min(tip[1], 150)
        strands.append((crown + rng.normal(0, 10, 2), tip, 0.18 * np.sign(tip[0] - crown[0] + 1e-6)))
    return poly, strands


def character() -> Blue:
    return Blue(slug="bleu", name="Bleu", style="blue",
                description="A blue-pencil sketch on cream paper: grainy strokes, hatching, construction lines (the paper's 'Blue').",
                seed=37, skin=PAPER, paper_amount=0.018, grain=1.0, eye_hw=38.0,
                eye_centers=((194.0, 228.0), (318.0, 228.0)), eyes_box=(104, 150, 304, 132), eye_kw={"brow_gap": 0.85, "brow_clear": 0.52},
                mouth_box=(168, 312, 176, 118), mouth_center=(256.0, 354.0), mouth_scale=47.0, mouth_dark=PAPER,
                lid_band=0.3, scale=0.8, lift=52.0, pivot=(256.0, 420.0))
