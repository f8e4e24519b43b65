"""The eye finder on real faces (``../shared/real/``) and on the synthetic performer.

For every frame of a real clip the face frame is built from the peer's two iris centres
(MediaPipe, see the clips' README), perturbed the way the tracker's motion prediction is
wrong (translation N(0, 0.04·wi) plus a uniform gaze-like ±0.1·wi along x, roll N(0, 2°),
scale N(0, 3 %); fixed seed), the eye region is cut in that frame, and the finder runs
on the crop. Its iris centres, lids and brows are mapped back to frame pixels and compared
with the peer's: iris and pupil-midpoint error in % of the peer's inter-pupil distance,
roll error, and the Pearson correlation over the clip of eye opening and brow height (mean
of both eyes) with the peer's ``mp.csv`` values. Calibration is from frame 0 and the clip's
five clicks.

The score column shows what the lead's lost/ok decision sees: the 5th percentile of the
lower of the two eye scores on the face, and the 95th percentile of the higher one when the
crop is put on the wrong place (nose, brows, cheeks, beside the face).

Synthetic clips (:class:`tracker.synthetic.Performance`) are run the same way against
their exact truth, in frame pixels.

Contact sheets (eye crops with our points in colour and the peer's in white) go to
``out/real_eyes/``.
"""

from __future__ import annotations

import csv
import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from benchmarks.harness import Table, benchmark
from tracker.calibration import FaceFrame
from tracker.clicks import PIXEL_CENTRE, Clicks

REAL = Path(os.environ.get("INKFACE_REAL", Path(__file__).resolve().parents[2] / "shared" / "real"))
OUT = Path(__file__).resolve().parents[1] / "out" / "real_eyes"
CLIPS = ("expr_d0", "expr_d3", "expr_d6", "expr_d10", "expr_d11", "expr_d18", "expr_d19", "talk_a", "talk_b")
QUICK_CLIPS = ("expr_d0", "expr_d19")
TARGETS = {"iris_med": 3.0, "iris_p95": 8.0, "roll": 1.5, "r_eye": 0.7, "r_brow": 0.6}
ADAPT = True
"""Whether the "after" finder adapts slowly from confident frames (as the tracker would)."""
WRONG_PLACES = ((0.0, 0.65), (0.0, -0.45), (-0.55, 0.45), (0.55, 0.45), (1.0, 0.0), (0.0, 1.1))
"""Crop offsets (× work ipd, face frame) that put the eye windows on the nose, the brows,
the cheeks, beside the face and on the mouth."""


# ---------------------------------------------------------------------------------------------
# clips


@dataclass
class RealClip:
    name: str
    clicks: Clicks
    points: dict[str, np.ndarray]  # key → (n, 2) frame px
    peer: dict[str, np.ndarray]  # mp.csv column → (n,)

    def frames(self, every: int = 1):
        """``(index, frame)`` for every ``every``-th decoded frame."""
        cap = cv2.VideoCapture(str(REAL / f"{self.name}.mp4"))
        i = 0
        try:
            while True:
                ok, f = cap.read()
                if not ok:
                    break
                if i % every == 0:
                    yield i, f
                i += 1
        finally:
            cap.release()


def load_clip(name: str) -> RealClip:
    clicks = Clicks.from_dict(json.loads((REAL / f"{name}.clicks.json").read_text()), where=name)
    with open(REAL / f"{name}.points.csv") as f:
        rows = list(csv.DictReader(f))
    keys = sorted({k[:-2] for k in rows[0] if k.endswith("_x")})
    points = {k: np.array([[float(r[k + "_x"]), float(r[k + "_y"])] for r in rows]) - PIXEL_CENTRE for k in keys}
    with open(REAL / f"{name}.mp.csv") as f:
        rows = list(csv.DictReader(f))
    peer = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    return RealClip(name, clicks, points, peer)


def available() -> bool:
    return all((REAL / f"{c}.mp4").exists() for c in CLIPS)


# ---------------------------------------------------------------------------------------------
# the finders under test, behind one small interface


@dataclass
class Found:
    """One frame's eye results in crop px: pupils (2,2), lid distances up/down (2,), brow heights (2,)."""

    pupils: np.ndarray
    up: np.ndarray
    down: np.ndarray
    brow: np.ndarray
    score: np.ndarray
    closed: np.ndarray


class After:
    """The eye finder of :mod:`tracker.eyes`."""

    name = "after"

    def __init__(self, frame0: np.ndarray, clicks: Clicks):
        from tracker.eyes import EyeFinder, calibration_crop, learn_eyes, refine_pupils

        grey0 = cv2.cvtColor(frame0, cv2.COLOR_BGR2GRAY)
        clicks = clicks.moved(-PIXEL_CENTRE, -PIXEL_CENTRE)  # the finders count as OpenCV does
        lp, rp = refine_pupils(grey0, clicks.left_pupil, clicks.right_pupil)
        self.pupils_cal = (lp, rp)
        ipd = math.hypot(rp[0] - lp[0], rp[1] - lp[1])
        self.wi = min(ipd, 80.0)
        ff = FaceFrame.from_pupils(lp, rp, self.wi)
        rect = calibration_crop(self.wi)
        crop = ff.crop(frame0, rect)
        o = np.array(rect[:2], dtype=np.float64)
        pupils = np.array([[-0.5 * self.wi, 0.0], [0.5 * self.wi, 0.0]]) - o
        brows = ff.to_face(np.array([clicks.left_brow, clicks.right_brow])) - o
        model = learn_eyes(crop, cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY), pupils, brows, self.wi)
        # what a saved calibration gives back
        model = type(model).from_dict(json.loads(json.dumps(model.to_dict())), model.images())
        self.finder = EyeFinder(model, self.wi)
        self.rect = self.finder.rect

    def find(self, crop: np.ndarray, grey: np.ndarray, centres: np.ndarray, adapt: bool = True) -> Found:
        r = self.finder.find(crop, grey, centres)
        if adapt and ADAPT:
            self.finder.adapt(crop, grey, r)
        e = r.eyes
        return Found(
            np.array([[q.x, q.y] for q in e]), np.array([q.upper for q in e]), np.array([q.lower for q in e]),
            np.array([q.brow for q in e]), np.array([q.score for q in e]), np.array([not q.open for q in e]),
        )


FINDERS = {"after": After}
"""The finders compared ("before", the first tracker's pupil, lid and brow finders, was retired with
them: they live on only behind :mod:`tracker.legacy` for old calibrations)."""


# ---------------------------------------------------------------------------------------------
# one clip


def perturbed(ff: FaceFrame, wi: float, rng: np.random.Generator, spread: float = 1.0) -> FaceFrame:
    """``ff`` moved the way a motion prediction misses (see the module docstring)."""
    tx = spread * (rng.normal(0.0, 0.04) + rng.uniform(-0.1, 0.1)) * wi
    ty = spread * rng.normal(0.0, 0.04) * wi
    mid = ff.to_image(np.array([[tx, ty]]))[0]
    return FaceFrame((float(mid[0]), float(mid[1])), ff.angle + math.radians(spread * rng.normal(0.0, 2.0)),
                     ff.scale * (1.0 + spread * rng.normal(0.0, 0.03)))


def _crop(finder, frame: np.ndarray, ff: FaceFrame):
    x0, y0, w, h = finder.rect
    crop = ff.crop(frame, finder.rect)
    grey = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY)
    centres = np.array([[-0.5 * finder.wi - x0, -y0], [0.5 * finder.wi - x0, -y0]], dtype=np.float64)
    return crop, grey, centres


@dataclass
class ClipResult:
    name: str
    iris_err: np.ndarray  # (n, 2) % ipd
    mid_err: np.ndarray  # (n,) % ipd
    roll_err: np.ndarray  # (n,) degrees
    eye: np.ndarray  # (n,) ours, frame px
    brow: np.ndarray
    peer_eye: np.ndarray
    peer_brow: np.ndarray
    score_on: np.ndarray  # (n,) lower of the two
    score_off: np.ndarray  # (m,) higher of the two, wrong places
    closed: np.ndarray  # (n, 2)
    ms: list[float]
    cpu: list[float]
    sheet: list[np.ndarray]

    def r(self, a: np.ndarray, b: np.ndarray) -> float:
        ok = np.isfinite(a) & np.isfinite(b)
        if ok.sum() < 3 or np.std(a[ok]) == 0 or np.std(b[ok]) == 0:
            return float("nan")
        return float(np.corrcoef(a[ok], b[ok])[0, 1])


def _to_frame(ff: FaceFrame, rect, pts: np.ndarray) -> np.ndarray:
    return ff.to_image(np.asarray(pts, dtype=np.float64) + np.array(rect[:2], dtype=np.float64))


def _draw(crop: np.ndarray, found: Found, peer_crop: dict[str, np.ndarray], label: str, zoom: int = 3) -> np.ndarray:
    img = cv2.resize(crop, None, fx=zoom, fy=zoom, interpolation=cv2.INTER_LINEAR)
    S = 4

    def P(p):
        return (int(round((p[0] + 0.5) * zoom * 16 - 8)), int(round((p[1] + 0.5) * zoom * 16 - 8)))

    for k, p in peer_crop.items():
        cv2.circle(img, P(p), 3 << S, (255, 255, 255), 1, cv2.LINE_AA, S)
    for i in range(2):
        px, py = found.pupils[i]
        col = (0, 0, 255) if found.closed[i] else (255, 0, 255)
        cv2.drawMarker(img, (int(round(px * zoom)), int(round(py * zoom))), col, cv2.MARKER_CROSS, 11, 1)
        for dy, c in ((-found.up[i], (0, 255, 255)), (found.down[i], (0, 200, 0)), (-found.brow[i], (255, 128, 0))):
            cv2.circle(img, P((px, py + dy)), 3 << S, c, 1, cv2.LINE_AA, S)
        cv2.putText(img, f"{found.score[i]:.2f}", (int(px * zoom) - 14, int((py + 0.3 * crop.shape[0] / 2) * zoom)),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.4, col, 1, cv2.LINE_AA)
    cv2.putText(img, label, (4, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 255, 0), 1, cv2.LINE_AA)
    return img


def run_clip(name: str, kind: str = "after", every: int = 1, sheet_every: int = 0, seed: int = 13) -> ClipResult:
    clip = load_clip(name)
    rng = np.random.default_rng([seed, sum(map(ord, name))])
    it = clip.frames(every)
    frames0 = next(it)
    finder = FINDERS[kind](frames0[1], clip.clicks)
    wi = finder.wi
    n = len(clip.peer["frame"])
    iris_err, mid_err, roll_err, eye, brow, s_on, s_off, closed, ms, cpu, idx = ([] for _ in range(11))
    sheet = []

    def one(i, frame):
        pl, pr = clip.points["left_pupil"][i], clip.points["right_pupil"][i]
        ipd = float(np.hypot(*(pr - pl)))
        ff = perturbed(FaceFrame.from_pupils(tuple(pl), tuple(pr), wi), wi, rng)
        crop, grey, centres = _crop(finder, frame, ff)
        c0, t0 = time.process_time(), time.perf_counter()
        f = finder.find(crop, grey, centres)
        ms.append((time.perf_counter() - t0) * 1000.0)
        cpu.append((time.process_time() - c0) * 1000.0)
        pupils = _to_frame(ff, finder.rect, f.pupils)
        e = np.hypot(*(pupils - np.array([pl, pr])).T) / ipd * 100.0
        iris_err.append(e)
        mid_err.append(float(np.hypot(*(pupils.mean(0) - 0.5 * (pl + pr)))) / ipd * 100.0)
        d = pupils[1] - pupils[0]
        roll = math.degrees(math.atan2(-d[1], d[0]))
        roll_err.append(abs((roll - clip.peer["roll_deg"][i] + 180.0) % 360.0 - 180.0))
        eye.append(float(np.mean(f.up + f.down)) / ff.scale)
        brow.append(float(np.mean(f.brow)) / ff.scale)
        s_on.append(float(f.score.min()))
        closed.append(f.closed.copy())
        idx.append(i)
        if sheet_every and i % sheet_every == 0:
            keys = ("left_pupil", "right_pupil", "left_upper_lid", "left_lower_lid", "right_upper_lid",
                    "right_lower_lid", "left_brow", "right_brow")
            pc = ff.to_face(np.array([clip.points[k][i] for k in keys])) - np.array(finder.rect[:2])
            sheet.append(_draw(crop, f, dict(zip(keys, pc)), f"{name} {i}"))
        # the same finder on wrong places, now and then
        if i % 5 == 0:
            j = (i // 5) % len(WRONG_PLACES)
            ox, oy = WRONG_PLACES[j]
            mid = ff.to_image(np.array([[ox * wi, oy * wi]]))[0]
            off = FaceFrame((float(mid[0]), float(mid[1])), ff.angle, ff.scale)
            c2, g2, cen2 = _crop(finder, frame, off)
            s_off.append(float(finder.find(c2, g2, cen2, adapt=False).score.min()))

    one(*frames0)
    for i, frame in it:
        if i < n:
            one(i, frame)
    idx = np.array(idx)
    peer_eye = 0.5 * (clip.peer["eye_open_l"][idx] + clip.peer["eye_open_r"][idx])
    peer_brow = 0.5 * (clip.peer["brow_l"][idx] + clip.peer["brow_r"][idx])
    return ClipResult(name, np.array(iris_err), np.array(mid_err), np.array(roll_err), np.array(eye), np.array(brow),
                      peer_eye, peer_brow, np.array(s_on), np.array(s_off), np.array(closed), ms, cpu, sheet)


def write_sheet(res: ClipResult, path: Path, cols: int = 4) -> None:
    if not res.sheet:
        return
    h = max(s.shape[0] for s in res.sheet)
    w = max(s.shape[1] for s in res.sheet)
    tiles = [np.pad(s, ((0, h - s.shape[0]), (0, w - s.shape[1]), (0, 0))) for s in res.sheet]
    tiles += [np.zeros_like(tiles[0])] * (-len(tiles) % cols)
    rows = [np.hstack(tiles[k : k + cols]) for k in range(0, len(tiles), cols)]
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), np.vstack(rows))


def real_row(res: ClipResult) -> list[str]:
    ie = res.iris_err
    return [
        res.name, str(len(res.mid_err)),
        f"{np.median(ie):.1f} / {np.percentile(ie, 95):.1f}",
        f"{np.median(res.mid_err):.1f} / {np.percentile(res.mid_err, 95):.1f}",
        f"{np.median(res.roll_err):.2f}",
        f"{res.r(res.eye, res.peer_eye):.2f}", f"{res.r(res.brow, res.peer_brow):.2f}",
        f"{np.percentile(res.score_on, 5):.2f} / {np.percentile(res.score_off, 95):.2f}",
        f"{100.0 * res.closed.any(axis=1).mean():.0f}",
        f"{np.median(res.ms):.3f} / {np.percentile(res.ms, 95):.3f}", f"{np.median(res.cpu):.3f}",
    ]


REAL_COLUMNS = ["clip", "frames", "iris err med/p95 %", "mid err med/p95 %", "roll err °", "r eye", "r brow",
                "score on p5 / off p95", "closed %", "ms med/p95", "cpu ms med"]


# ---------------------------------------------------------------------------------------------
# synthetic


SYNTH = ("default", "noisy", "dark_skin", "small_far", "strong_roll", "lighting", "blue_eyes")


def run_synth(style: str, kind: str = "after", seconds: float = 8.0, seed: int = 5) -> list[str]:
    from tracker.synthetic import STYLES, Performance, face_landmarks

    perf = Performance(seconds=seconds, seed=seed, style=STYLES[style])
    rng = np.random.default_rng([seed, 99])
    frame0 = perf.frame(0)
    finder = FINDERS[kind](frame0, Clicks.from_dict(perf.clicks()))
    wi = finder.wi
    pe, le, be, ms, eyes, t_eyes = [], [], [], [], [], []
    for i in range(len(perf)):
        img, truth = perf.render(i)
        st = perf.state(i)
        lm = face_landmarks(st)
        pl, pr = lm["left_pupil"], lm["right_pupil"]
        # the synthetic gaze moves the pupils inside the eyes: the crop follows the eye centres
        ff = perturbed(FaceFrame.from_pupils(tuple(pl), tuple(pr), wi), wi, rng, spread=0.5)
        crop, grey, centres = _crop(finder, img, ff)
        t0 = time.perf_counter()
        f = finder.find(crop, grey, centres)
        ms.append((time.perf_counter() - t0) * 1000.0)
        pupils = _to_frame(ff, finder.rect, f.pupils)
        pe.append(float(np.hypot(*(pupils.mean(0) - 0.5 * (pl + pr)))))
        k = ff.scale
        ours_eye = (f.up + f.down) / k
        tr_eye = np.array([truth.eye_open_l, truth.eye_open_r])
        le.append(np.abs(ours_eye - tr_eye))
        be.append(np.abs(f.brow / k - np.array([truth.brow_l, truth.brow_r])))
        eyes.append(ours_eye.mean())
        t_eyes.append(tr_eye.mean())
    le, be = np.array(le), np.array(be)
    r = float(np.corrcoef(eyes, t_eyes)[0, 1])
    return [style, str(len(perf)), f"{np.median(pe):.2f} / {np.percentile(pe, 95):.2f}",
            f"{np.median(le):.2f} / {np.percentile(le, 95):.2f}", f"{np.median(be):.2f} / {np.percentile(be, 95):.2f}",
            f"{r:.3f}", f"{np.median(ms):.3f}"]


SYNTH_COLUMNS = ["style", "frames", "pupil mid err px med/p95", "lid err px med/p95", "brow err px med/p95", "r eye",
                 "ms med"]


@benchmark("real_eyes")
def run(ctx):
    kinds = ("after",)
    tables = []
    if not available():
        print(f"real_eyes: {REAL} not found; real clips skipped")
    else:
        for kind in kinds:
            t = Table("Eye finder on real faces vs the peer (perturbed crop frames)", REAL_COLUMNS)
            for name in QUICK_CLIPS if ctx.quick else CLIPS:
                res = run_clip(name, kind, every=4 if ctx.quick else 1, sheet_every=0 if ctx.quick else 25)
                t.add(*real_row(res))
                if kind == "after":
                    write_sheet(res, OUT / f"{name}.png")
            t.note = (f"targets: iris / mid err median ≤ {TARGETS['iris_med']:g} % ipd, p95 ≤ {TARGETS['iris_p95']:g} %; "
                      f"roll ≤ {TARGETS['roll']:g}°; r eye ≥ {TARGETS['r_eye']:g}; r brow ≥ {TARGETS['r_brow']:g}. "
                      "ms = one find() for both eyes with adapt(), wall clock and this process's CPU time; "
                      "score: lower of the two eyes on the face (p5) and on wrong places (p95: nose, brows, cheeks, "
                      "beside the face, mouth).")
            tables.append(t)
    for kind in kinds:
        t = Table("Eye finder on the synthetic performer vs exact truth (frame px)", SYNTH_COLUMNS)
        for style in SYNTH[:2] if ctx.quick else SYNTH:
            t.add(*run_synth(style, kind, seconds=1.5 if ctx.quick else 8.0))
        t.note = "targets (bench_tracker): medians ≤ 1 px pupils, ≤ 1.5 px lids and brows; p95 ≤ 3× those"
        tables.append(t)
    return tables
