"""Noodle — the "Wavy" style: a loose, wobbly sepia line over watercolour washes that miss the lines."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from art_sets.authoring.face import DEFAULT_MOUTHS, Character, EyeGeom, EyePose, MouthGeom, MouthPose, closed
from art_sets.authoring.ink import Surface, bez, ellipse, hex_rgb, point_at, sub_curve

INK = hex_rgb("#2e1d14")
SKIN = hex_rgb("#f7cf9c")
WASH = hex_rgb("#eaa877")
NOSE = hex_rgb("#e8785f")
HAIR = hex_rgb("#c8642a")
MOUTH = hex_rgb("#5a1f1c")
TONGUE = hex_rgb("#e06b62")
WHITE = hex_rgb("#fffdf6")
STUBBLE = hex_rgb("#8a6a55")

WAVY_EYES = {
    "open": EyePose(up=0.8, dn=0.64, brow_arch=0.25),
    "closed": EyePose(closed=True, brow=-0.05, brow_arch=0.2),
    "wide": EyePose(up=1.0, dn=0.76, brow=0.3, brow_arch=0.36),
    "angry": EyePose(up=0.6, dn=0.66, lid_drop=0.45, brow=-0.25, brow_tilt=0.5, brow_arch=0.05),
    "squint": EyePose(up=0.34, dn=0.5, lower_lift=0.3, brow=-0.1, brow_arch=0.15),
}

WAVY_MOUTHS = dict(DEFAULT_MOUTHS)
WAVY_MOUTHS.update({
    "smile": MouthPose(hw=1.2, smile=0.42, tl=0.2),
    "grin": MouthPose(hw=1.3, smile=0.4, open=0.6, up_ratio=0.45),
})
SHIRT = hex_rgb("#7da66a")
SHIRT_WASH = hex_rgb("#5e8a52")


@dataclass
class Wavy(Character):
    eyes: dict = field(default_factory=lambda: dict(WAVY_EYES))
    mouths: dict = field(default_factory=lambda: dict(WAVY_MOUTHS))

    def pen(self, s: Surface, pts, w: float, rng, color=INK, passes: int = 2, **kw) -> None:
        """Two loose passes of a wobbly line; the second thinner, wandering off the first."""
        pts = np.asarray(pts, np.float64)
        for i in range(passes):
            opts = dict(taper=(0.25, 0.3), tip=0.15, pressure=0.3, wobble=1.3 + 0.6 * i, wobble_len=55,
                        jitter=0.5 * i, opacity=1.0 if i == 0 else 0.65)
            opts.update(kw)
            s.stroke(_overshoot(pts, 0.04 * (1 + i), rng), w * (1.0 if i == 0 else 0.5), color, rng=rng, **opts)

    def wash(self, s: Surface, poly, color, rng, opacity=0.9, **kw) -> None:
        """A watercolour wash: slightly off-register, soft-edged, with a darker pooled rim."""
        poly = np.asarray(poly) + rng.normal(0, 1.6, 2)
        s.fill(poly, color, opacity=opacity, blur=1.2, **kw)
        s.stroke(closed(poly), 2.5, tuple(np.array(color) * 0.85), rng=rng, opacity=0.35 * opacity, blur=1.5,
                 taper=(0, 0), wobble=0.8, clip=kw.get("clip"))

    # --- eyes ----------------------------------------------------------------------------------
    def draw_eyeball(self, s: Surface, g: EyeGeom, socket, rng) -> None:
        s.paint(socket, WHITE)
        s.fill(ellipse(g.iris_c, g.iris_r, g.iris_r * 1.05), INK, clip=socket)
        s.fill(ellipse(g.iris_c + (-0.3 * g.iris_r, -0.35 * g.iris_r), 0.28 * g.iris_r, 0.28 * g.iris_r), WHITE, clip=socket)

    def draw_lower_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        self.pen(s, sub_curve(g.lower + (0, 0.2 * g.hw + 1), 0.2, 0.85), 1.6, rng, passes=1, opacity=0.6)  # baggy lids
        self.pen(s, g.lower, 2.0, rng)

    def draw_upper_lid(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        self.pen(s, g.upper, 3.6, rng, taper=(0.15, 0.2))

    def draw_brow(self, s: Surface, g: EyeGeom, pose: EyePose, rng) -> None:
        # a brow made of a few short scratchy strokes
        for k in range(4):
            u0 = 0.02 + 0.22 * k + rng.uniform(-0.03, 0.03)
            seg = sub_curve(g.brow, max(0.0, u0), min(1.0, u0 + 0.34), 12)
            self.pen(s, seg + rng.normal(0, 0.8, 2), 6.0 - 0.6 * k, rng, passes=1, taper=(0.3, 0.5))

    # --- mouth ---------------------------------------------------------------------------------
    def draw_inside(self, s: Surface, rest: MouthGeom, rng) -> None:
        sc, (cx, cy) = rest.scale, rest.seam[len(rest.seam) // 2]
        hw = self.teeth_hw * sc
        x = np.linspace(cx - hw, cx + hw, 60)
        edge = np.stack([x, cy - 0.06 * sc - 0.3 * sc * ((x - cx) / hw) ** 2], 1)
        s.fill(np.concatenate([edge, (edge - (0, 0.7 * sc))[::-1]]), WHITE)
        self.pen(s, sub_curve(edge, 0.1, 0.9), 1.2, rng, passes=1, opacity=0.6)

    def draw_lower_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        c = point_at(g.inner_dn, 0.5)
        self.wash(s, ellipse(c + (0, -0.14 * sc), 0.34 * sc, 0.22 * sc), TONGUE, rng)
        teeth = sub_curve(g.inner_dn, 0.18, 0.82)
        s.fill(np.concatenate([teeth + (0, 1.0), (teeth - (0, 0.14 * sc))[::-1]]), WHITE)
        self.pen(s, sub_curve(teeth - (0, 0.14 * sc), 0.15, 0.85), 1.2, rng, passes=1, opacity=0.6)
        self.pen(s, g.inner_dn, 2.8, rng, taper=(0.1, 0.1))
        self.pen(s, sub_curve(g.outer_dn, 0.3, 0.7), 2.0, rng, passes=1)
        self.wash(s, np.concatenate([sub_curve(g.outer_dn, 0.25, 0.75), sub_curve(g.outer_dn, 0.25, 0.75)[::-1] - (0, 0.12 * sc)]),
                  WASH, rng, opacity=0.5)

    def draw_upper_lip(self, s: Surface, g: MouthGeom, rng) -> None:
        sc = g.scale
        self.pen(s, g.inner_up, 3.2, rng, taper=(0.1, 0.1))
        for end, sgn in ((g.left, -1), (g.right, 1)):  # corner creases (the same shape in every mouth, so they line up)
            tick = bez(end + (sgn * 0.02 * sc, 0.1 * sc), end + (sgn * 0.14 * sc, 0),
                       end + (sgn * 0.08 * sc, -0.1 * sc))
            self.pen(s, tick, 2.2, rng, passes=1, taper=(0.4, 0.5))

    # --- body ----------------------------------------------------------------------------------
    def draw_body(self, s: Surface, rng) -> None:
        cx = 256.0
        neck = np.array([(cx - 70, 380), (cx - 76, 600), (cx + 76, 600), (cx + 70, 380)])
        self.wash(s, neck, SKIN, rng, opacity=1.0)
        s.fill(np.array([(cx - 70, 470), (cx + 70, 470), (cx + 66, 530), (cx - 66, 530)]), WASH, opacity=0.5, blur=10)
        self.pen(s, [(cx - 70, 420), (cx - 75, 600)], 3.0, rng)
        self.pen(s, [(cx + 70, 420), (cx + 75, 600)], 3.0, rng)
        # a baggy T-shirt: a wash that misses the line, and a wobbly round neckline
        shirt = np.concatenate([[(-140, 700), (-140, 600)], bez((-140, 600), (-40, 540), (120, 530), (cx - 78, 536), n=30),
                                bez((cx - 78, 536), (cx, 580), (cx + 78, 536), n=20),
                                bez((cx + 78, 536), (392, 530), (552, 540), (652, 600), n=30), [(652, 700)]])
        self.wash(s, shirt, SHIRT, rng, opacity=1.0)
        for y in (600, 640, 680):  # stripes
            self.pen(s, bez((-140, y + 10), (cx, y - 20), (652, y + 10)), 5.0, rng, color=SHIRT_WASH, passes=1, opacity=0.6)
        self.pen(s, shirt[2:-1], 3.4, rng)
        self.pen(s, bez((cx - 84, 540), (cx, 592), (cx + 84, 540)), 2.4, rng, passes=1)

    # --- head ----------------------------------------------------------------------------------
    def draw_head(self, s: Surface, rng, k: int) -> None:
        cx = 256.0
        jit = lambda sd=1.2: rng.normal(0, sd, 2)
        t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
        sn = np.sin(t)
        widen = 1 - 0.08 * np.clip(-sn, 0, 1) + 0.1 * np.clip(sn, 0, 1) * (1 - np.clip(sn, 0, 1)) * 2
        face = np.stack([cx + 206 * np.cos(t) * widen, 292 + 214 * sn], 1) + jit()
        for sgn in (-1, 1):  # ears
            ear = ellipse((cx + sgn * 212, 270), 34, 48, rot=sgn * 0.2) + jit()
            self.wash(s, ear, SKIN, rng, opacity=1.0)
            self.wash(s, ellipse((cx + sgn * 220, 272), 14, 26, rot=sgn * 0.2), WASH, rng, opacity=0.7)
            self.pen(s, closed(ear)[8:] if sgn < 0 else closed(ear)[:-8], 3.0, rng)
        self.wash(s, face, SKIN, rng, opacity=1.0)
        # shading wash down one side and under the jowls
        inner = np.stack([cx - 14 + 186 * np.cos(t) * widen, 282 + 200 * sn], 1)
        s.paint(s.mask(face, blur=1.0) * (1 - s.mask(inner, blur=6.0)), WASH, opacity=0.55)
        # stubble on the jowls, outside the mouth hole
        for _ in range(70):
            ang = rng.uniform(0.15, np.pi - 0.15)
            r = rng.uniform(0.78, 0.95)
            x, y = cx + 200 * r * np.cos(ang) * 0.96, 292 + 212 * r * np.sin(ang)
            if abs(x - cx) > 112 or y > 462:
                s.dot((x, y), rng.uniform(0.8, 1.4), STUBBLE, opacity=0.8)
        self.pen(s, closed(face), 4.0, rng, taper=(0.02, 0.02), pressure=0.35)
        # nose: a big round bulb
        nose = ellipse((cx + 2, 298), 34, 28, rot=0.1) + jit(0.8)
        self.wash(s, nose, NOSE, rng, opacity=0.95)
        s.fill(ellipse((cx - 9, 288), 8, 6), WHITE, opacity=0.5, blur=2)
        self.pen(s, closed(nose), 3.0, rng)
        for sgn in (-1, 1):
            self.pen(s, bez((cx + sgn * 10, 318), (cx + sgn * 16, 322), (cx + sgn * 22, 316)), 2.0, rng, passes=1)
        # three curly tufts of hair and forehead wrinkles
        for (x0, y0, sz, rot) in ((cx - 44, 88, 28, -0.4), (cx + 4, 78, 34, 0.0), (cx + 50, 92, 26, 0.5)):
            a = np.linspace(0, 4.2, 60)
            curl = np.stack([x0 + sz * 0.5 * np.sin(a + rot) * (1 - a / 6), y0 - sz * a / 4.2 + sz * 0.25 * np.cos(a)], 1)
            self.pen(s, curl + jit(0.6), 5.0, rng, color=HAIR, taper=(0.1, 0.6))
            self.pen(s, curl + jit(0.6), 1.6, rng, passes=1, taper=(0.1, 0.6))
        for y, w in ((118, 56), (130, 70)):
            self.pen(s, bez((cx - w, y + 4), (cx, y - 6), (cx + w, y + 4)), 1.6, rng, passes=1, opacity=0.7)


def _overshoot(p: np.ndarray, frac: float, rng) -> np.ndarray:
    """Extend both ends a little along their tangents, as a quick hand does."""
    if len(p) < 3:
        return p
    L = np.hypot(*np.diff(p, axis=0).T).sum()
    out = []
    for end, nxt in ((p[0], p[min(3, len(p) - 1)]), (p[-1], p[max(-4, -len(p))])):
        d = end - nxt
        d = d / max(np.hypot(*d), 1e-9)
        out.append(end + d * frac * L * rng.uniform(0.3, 1.0))
    return np.concatenate([[out[0]], p, [out[1]]])


def character() -> Wavy:
    return Wavy(slug="noodle", name="Noodle", style="wavy",
                description="A loose, wobbly sepia line over off-register watercolour washes (the paper's 'Wavy').",
                seed=23, skin=SKIN, paper_amount=0.02, eye_hw=38.0, eye_centers=((200.0, 216.0), (312.0, 216.0)),
                eyes_box=(128, 136, 256, 134), mouth_box=(150, 330, 212, 122), mouth_center=(256.0, 380.0),
                mouth_scale=54.0, eye_kw={"iris": 0.3, "brow_gap": 0.95}, mouth_dark=MOUTH,
                scale=0.78, lift=44.0, pivot=(256.0, 440.0))
