"""The mouth finder alone, on real faces (and the synthetic performer), against a peer.

For every frame the upright face crop is built from that frame's pupils — the peer's on the
real clips, the exact ones on synthetic clips — with a random error like the head-motion
prediction's (translation N(0, 0.04·wi), roll N(0, 2°), scale N(0, 3 %); fixed seed), the
mouth centre is predicted from the calibration alone, and the finder runs on the crop.
Results are mapped back to frame pixels and compared with the peer's points
(``NAME.points.csv``) and parameters (``NAME.mp.csv``); on synthetic clips with the truth.

Columns: corner and outer-lip-edge errors (median / p95, % of the peer's inter-pupil
distance; edges along the face's up axis), Pearson r of mouth opening (``lip_upper +
lip_lower``) and width with the peer over the clip (frames without a confident result hold
the last value, as the tracker does), % of frames with no confident result, "wrong ok" (%
of results that claim this mouth but are more than 15 % IPD off, counted over the normal
crops and over crops predicted 0.6 wi too low / too high and 1 wi to the side; in brackets:
% of the frames whose normal crop gave such a result), and the
finder's CPU time per call (this process only: other processes on a shared machine do not count,
though they still slow it through the caches). ``python -m benchmarks --only real_mouth``; the real clips are read
from ``../shared/real/`` (skipped with one line when absent). Set ``INKFACE_MOUTH_SHEETS=1``
to write contact sheets of crops with the results drawn to ``out/real_mouth/``.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from benchmarks.harness import Table, benchmark
from benchmarks.real_clips import clip_names, load_clip
from tracker.calibration import WORK_IPD_MAX, FaceFrame

WRONG = 0.15
"""A result farther than this (fraction of the IPD) from the peer is not on the mouth."""
DISPLACED = ((0.0, 0.6), (0.0, -0.6), (1.0, 0.0))
"""Deliberately wrong mouth predictions (face px / wi) for the honesty check."""


@dataclass
class Case:
    """One clip to run: frames, per-frame reference points (frame px), the clicks."""

    name: str
    frames: list[np.ndarray]
    pupils: np.ndarray  # (n, 2, 2) left, right
    corners: np.ndarray  # (n, 2, 2) left, right
    top: np.ndarray  # (n, 2)
    bottom: np.ndarray  # (n, 2)
    clicks: dict
    ref_open: np.ndarray  # (n,) the reference's lip_upper + lip_lower (frame px)
    ref_width: np.ndarray
    synthetic: bool = False


@dataclass
class Found:
    """A finder's answer in crop px (y down)."""

    left: tuple[float, float]
    right: tuple[float, float]
    lip_upper: float
    lip_lower: float
    score: float
    cue: str = ""
    polygon: np.ndarray | None = None


@dataclass
class _Env:
    """What a calibration may look at besides its crop: the frame, the crop's face frame and
    origin (face px), the clip's clicks (frame px)."""

    frame: np.ndarray
    ff: FaceFrame
    origin: tuple[int, int]
    clicks: dict


@dataclass
class Method:
    """A mouth finder under test.

    ``rect(wi)`` is the crop rectangle relative to the predicted mouth centre (face px);
    ``learn(crop, click_crop, wi, env)`` returns an opaque state whose ``centre`` (crop
    px) is the calibrated mouth centre; ``find(state, crop, predicted_centre_crop)`` returns a
    :class:`Found` or None. ``threshold``: the score at or above which a result is confident.
    """

    name: str
    rect: Callable[[float], tuple[float, float, float, float]]
    learn: Callable
    find: Callable
    threshold: float = 0.5


# ----------------------------------------------------------------------------- cases


def real_case(name: str, max_frames: int | None = None) -> Case | None:
    clip = load_clip(name, max_frames)
    if clip is None:
        return None
    P = clip.points
    return Case(
        name=name,
        frames=clip.frames,
        pupils=np.stack([P["left_pupil"], P["right_pupil"]], axis=1),
        corners=np.stack([P["left_mouth_corner"], P["right_mouth_corner"]], axis=1),
        top=P["upper_lip_top"],
        bottom=P["lower_lip_bottom"],
        clicks=clip.clicks,
        ref_open=clip.params["lip_upper"] + clip.params["lip_lower"],
        ref_width=clip.params["mouth_width"],
    )


def synthetic_case(style: str, seconds: float, seed: int = 5) -> Case:
    from tracker.synthetic import STYLES, Performance, face_landmarks

    perf = Performance(seconds=seconds, seed=seed, style=STYLES[style])
    frames, pupils, corners, top, bottom, op, wd = [], [], [], [], [], [], []
    for i in range(len(perf)):
        img, truth = perf.render(i)
        lm = face_landmarks(perf.state(i))
        frames.append(img)
        pupils.append([lm["left_pupil"], lm["right_pupil"]])
        corners.append([lm["mouth_left"], lm["mouth_right"]])
        top.append(lm["lip_upper"])
        bottom.append(lm["lip_lower"])
        op.append(truth.lip_upper + truth.lip_lower)
        wd.append(truth.mouth_width)
    return Case(
        name=f"synthetic {style}", frames=frames, pupils=np.array(pupils), corners=np.array(corners),
        top=np.array(top), bottom=np.array(bottom), clicks=perf.clicks(),
        ref_open=np.array(op), ref_width=np.array(wd), synthetic=True,
    )


def variant(case: Case, kind: str) -> Case:
    """A harder copy of a clip: ``desaturate`` (pale, low-contrast lips), ``lowres`` (a small noisy
    camera: half size, blur, noise, JPEG, scaled back up), ``dim`` (a quarter of the light, noisy),
    ``drift`` (the light falls to 55 % and turns warmer over the clip, after calibration)."""
    rng = np.random.default_rng(17)
    out = []
    n = len(case.frames)
    for i, f in enumerate(case.frames):
        x = f.astype(np.float32)
        if kind == "desaturate":
            g = cv2.cvtColor(f, cv2.COLOR_BGR2GRAY).astype(np.float32)[..., None]
            x = g + 0.35 * (x - g)
        elif kind == "lowres":
            h, w = f.shape[:2]
            s = cv2.resize(f, (w // 2, h // 2), interpolation=cv2.INTER_AREA).astype(np.float32)
            s += rng.normal(0, 5.0, s.shape).astype(np.float32)
            s = np.clip(s, 0, 255).astype(np.uint8)
            ok, buf = cv2.imencode(".jpg", s, [cv2.IMWRITE_JPEG_QUALITY, 60])
            s = cv2.imdecode(buf, cv2.IMREAD_COLOR)
            x = cv2.resize(s, (w, h), interpolation=cv2.INTER_LINEAR).astype(np.float32)
        elif kind == "dim":
            x = x * 0.28 + rng.normal(0, 2.5, x.shape).astype(np.float32)
        elif kind == "drift":
            t = i / max(n - 1, 1)
            x = x * np.array([1.0 - 0.55 * t, 1.0 - 0.45 * t, 1.0 - 0.35 * t], np.float32)
        else:
            raise ValueError(kind)
        out.append(np.clip(x + 0.5, 0, 255).astype(np.uint8))
    return Case(**{**case.__dict__, "frames": out, "name": f"{case.name} {kind}"})


# ----------------------------------------------------------------------------- running


@dataclass
class ClipResult:
    name: str
    corner_err: list[float] = field(default_factory=list)
    top_err: list[float] = field(default_factory=list)
    bottom_err: list[float] = field(default_factory=list)
    open_px: list[float] = field(default_factory=list)
    width_px: list[float] = field(default_factory=list)
    open_abs: list[float] = field(default_factory=list)  # synthetic: |ours − truth| px
    width_abs: list[float] = field(default_factory=list)
    upper_abs: list[float] = field(default_factory=list)
    lower_abs: list[float] = field(default_factory=list)
    none: int = 0
    wrong_ok: int = 0
    judged: int = 0
    wrong_ok_here: int = 0  # of the wrong ok: on the normal crops (the rest: deliberately misplaced ones)
    ms: list[float] = field(default_factory=list)
    cues: dict = field(default_factory=dict)
    learn_error: str = ""
    frames: int = 0


def _perturbed_frame(pupils: np.ndarray, wi: float, rng: np.random.Generator) -> FaceFrame:
    ff = FaceFrame.from_pupils(tuple(pupils[0]), tuple(pupils[1]), wi)
    u, d = ff.axes()
    t = rng.normal(0.0, 0.04 * wi, 2) / ff.scale
    mid = (ff.mid[0] + t[0] * u[0] + t[1] * d[0], ff.mid[1] + t[0] * u[1] + t[1] * d[1])
    return FaceFrame(mid=mid, angle=ff.angle + math.radians(rng.normal(0.0, 2.0)), scale=ff.scale * (1.0 + rng.normal(0.0, 0.03)))


def _crop(frame, ff: FaceFrame, centre_face, rel) -> tuple[np.ndarray, tuple[int, int]]:
    x0 = int(math.floor(centre_face[0] + rel[0]))
    y0 = int(math.floor(centre_face[1] + rel[1]))
    w, h = int(math.ceil(rel[2])), int(math.ceil(rel[3]))
    return ff.crop(frame, (x0, y0, w, h)), (x0, y0)


def _errors(case: Case, i: int, ff: FaceFrame, f: Found, origin) -> tuple[float, float, float, float, float, np.ndarray]:
    """corner error, top and bottom edge errors (along up, frame px), opening and width (frame px)."""
    o = np.array(origin, dtype=np.float64)
    cx, cy = 0.5 * (f.left[0] + f.right[0]), 0.5 * (f.left[1] + f.right[1])
    pts = ff.to_image(np.array([f.left, f.right, (cx, cy - f.lip_upper), (cx, cy + f.lip_lower)]) + o)
    up = -ff.axes()[1]
    ce = 0.5 * (np.hypot(*(pts[0] - case.corners[i, 0])) + np.hypot(*(pts[1] - case.corners[i, 1])))
    te = float((pts[2] - case.top[i]) @ up)
    be = float((pts[3] - case.bottom[i]) @ up)
    opening = (f.lip_upper + f.lip_lower) / ff.scale
    width = float(np.hypot(*(pts[1] - pts[0])))
    return ce, te, be, opening, width, pts


def run_case(case: Case, method: Method, seed: int = 3, sheet_every: int = 0, sheet_dir: Path | None = None) -> ClipResult:
    res = ClipResult(case.name, frames=len(case.frames))
    rng = np.random.default_rng(seed)
    # calibration: frame 0, exact pupils, the mouth click
    p0 = case.pupils[0]
    ipd0 = float(np.hypot(*(p0[1] - p0[0])))
    wi = min(ipd0, WORK_IPD_MAX)
    ff0 = FaceFrame.from_pupils(tuple(p0[0]), tuple(p0[1]), wi)
    click_f = ff0.to_face(np.array([case.clicks["mouth"]]))[0]
    rel = method.rect(wi)
    crop0, o0 = _crop(case.frames[0], ff0, click_f, rel)
    try:
        env = _Env(case.frames[0], ff0, o0, case.clicks)
        state = method.learn(crop0, (click_f[0] - o0[0], click_f[1] - o0[1]), wi, env)
    except Exception as e:  # a refusal is a result too
        res.learn_error = f"{type(e).__name__}: {e}"
        return res
    centre_f = (state.centre[0] + o0[0], state.centre[1] + o0[1])
    last_open = last_width = np.nan
    tiles = []
    for i, frame in enumerate(case.frames):
        pup = case.pupils[i]
        ipd = float(np.hypot(*(pup[1] - pup[0])))
        wi_i = min(ipd, WORK_IPD_MAX)
        ff = _perturbed_frame(pup, wi_i, rng)
        crop, origin = _crop(frame, ff, centre_f, rel)
        pred = (centre_f[0] - origin[0], centre_f[1] - origin[1])
        t0 = time.process_time()
        f = method.find(state, crop, pred)
        res.ms.append((time.process_time() - t0) * 1000.0)
        ok = f is not None and f.score >= method.threshold
        if f is not None:
            res.cues[f.cue] = res.cues.get(f.cue, 0) + 1
        if ok:
            ce, te, be, opening, width, pts = _errors(case, i, ff, f, origin)
            res.corner_err.append(100 * ce / ipd)
            res.top_err.append(100 * abs(te) / ipd)
            res.bottom_err.append(100 * abs(be) / ipd)
            last_open, last_width = opening, width
            res.judged += 1
            if max(ce, abs(te), abs(be)) > WRONG * ipd:
                res.wrong_ok += 1
                res.wrong_ok_here += 1
        else:
            res.none += 1
        res.open_px.append(last_open)
        res.width_px.append(last_width)
        if case.synthetic and ok:
            res.open_abs.append(abs(last_open - case.ref_open[i]))
            res.width_abs.append(abs(last_width - case.ref_width[i]))
            cx, cy = 0.5 * (f.left[0] + f.right[0]), 0.5 * (f.left[1] + f.right[1])
            res.upper_abs.append(abs(f.lip_upper / ff.scale - _ref_lip(case, i, +1)))
            res.lower_abs.append(abs(f.lip_lower / ff.scale - _ref_lip(case, i, -1)))
        if sheet_every and i % sheet_every == 0:
            tiles.append(_tile(crop, f, method.threshold, i, case, ff, origin))
        # the honesty check: the same frame with the mouth predicted in the wrong place
        if i % 4 == 2:
            for dx, dy in DISPLACED:
                c2 = (centre_f[0] + dx * wi_i, centre_f[1] + dy * wi_i)
                crop2, o2 = _crop(frame, ff, c2, rel)
                f2 = method.find(state, crop2, (c2[0] - o2[0], c2[1] - o2[1]))
                if f2 is not None and f2.score >= method.threshold:
                    ce, te, be, *_ = _errors(case, i, ff, f2, o2)
                    res.judged += 1
                    if max(ce, abs(te), abs(be)) > WRONG * ipd:
                        res.wrong_ok += 1
    if tiles and sheet_dir is not None:
        sheet_dir.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(sheet_dir / f"{method.name}_{case.name.replace(' ', '_')}.png"), _grid(tiles))
    return res


def _ref_lip(case: Case, i: int, sign: int) -> float:
    c = 0.5 * (case.corners[i, 0] + case.corners[i, 1])
    p = case.pupils[i]
    u = (p[1] - p[0]) / np.hypot(*(p[1] - p[0]))
    up = np.array([u[1], -u[0]])
    return float((case.top[i] - c) @ up) if sign > 0 else float((c - case.bottom[i]) @ up)


def _tile(crop, f: Found | None, thr: float, i: int, case: Case, ff: FaceFrame, origin, scale: int = 2) -> np.ndarray:
    img = cv2.resize(crop, None, fx=scale, fy=scale, interpolation=cv2.INTER_LINEAR)
    o = np.array(origin, dtype=np.float64)
    ref = ff.to_face(np.concatenate([case.corners[i], case.top[i : i + 1], case.bottom[i : i + 1]])) - o
    for p in ref:
        cv2.drawMarker(img, (int(p[0] * scale), int(p[1] * scale)), (255, 0, 255), cv2.MARKER_TILTED_CROSS, 7, 1)
    if f is not None:
        col = (0, 255, 0) if f.score >= thr else (0, 0, 255)
        if f.polygon is not None and len(f.polygon):
            cv2.polylines(img, [np.round(f.polygon * scale * 16).astype(np.int32)], True, col, 1, cv2.LINE_AA, 4)
        cx, cy = 0.5 * (f.left[0] + f.right[0]), 0.5 * (f.left[1] + f.right[1])
        for p in (f.left, f.right, (cx, cy - f.lip_upper), (cx, cy + f.lip_lower)):
            cv2.circle(img, (int(round(p[0] * scale * 16)), int(round(p[1] * scale * 16))), 3 * 16, (255, 255, 0), 1, cv2.LINE_AA, 4)
        txt = f"{i} {f.cue} {f.score:.2f}"
    else:
        txt = f"{i} none"
    cv2.putText(img, txt, (3, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def _grid(tiles: list[np.ndarray], cols: int = 8) -> np.ndarray:
    h, w = tiles[0].shape[:2]
    rows = (len(tiles) + cols - 1) // cols
    out = np.zeros((rows * h, cols * w, 3), np.uint8)
    for k, t in enumerate(tiles):
        out[(k // cols) * h : (k // cols + 1) * h, (k % cols) * w : (k % cols + 1) * w] = t
    return out


def _pearson(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    m = np.isfinite(a) & np.isfinite(b)
    if m.sum() < 3 or np.std(a[m]) < 1e-9 or np.std(b[m]) < 1e-9:
        return float("nan")
    return float(np.corrcoef(a[m], b[m])[0, 1])


def _mp(v) -> str:
    if not len(v):
        return "–"
    return f"{np.median(v):.1f}/{np.percentile(v, 95):.0f}"


# ----------------------------------------------------------------------------- methods


def old_method() -> Method:
    """Today's mouth finder (:mod:`tracker.mouth` with the lip classifier of :func:`tracker.calibration.calibrate`)."""
    from tracker.calibration import calibrate
    from tracker.clicks import Clicks
    from tracker.face_tracker import MOUTH_DOWN, MOUTH_HALF_W, MOUTH_UP
    from tracker.mouth import MouthFinder

    class State:
        pass

    def rect(wi):
        # the tracker sizes its crop by the calibrated width: a typical one (0.8 wi) here
        w = math.ceil(2 * MOUTH_HALF_W * 0.8 * wi + 0.1 * wi)
        return (-w / 2, -MOUTH_UP * wi, w, (MOUTH_UP + MOUTH_DOWN) * wi)

    def learn(crop, click, wi, env):
        s = State()
        s.cal = cal = calibrate(env.frame, Clicks.from_dict(env.clicks))
        s.finder = MouthFinder()
        s.axis = np.asarray(cal.lip_axis, np.float32).reshape(1, 3)
        s.min_area = max(int(0.12 * cal.mouth_area), 6)
        ffc = FaceFrame.from_pupils(tuple(cal.clicks.left_pupil), tuple(cal.clicks.right_pupil), cal.work_ipd)
        mc = env.ff.to_face(ffc.to_image(np.array([cal.mouth_offset])))[0] - np.array(env.origin)
        s.centre = (float(mc[0]), float(mc[1]))
        return s

    def find(s, crop, pred):
        score = s.cal.lip.prob_u8(crop)
        value = cv2.transform(crop.astype(np.float32), s.axis)
        r = s.finder.find(score, value=value, seed=pred, min_area=s.min_area, lip_level=1.0)
        if r is None or not (0.2 * s.cal.mouth_width <= r.width <= 2.2 * s.cal.mouth_width):
            return None
        return Found(r.left, r.right, r.lip_upper, r.lip_lower, 1.0, "colour", r.polygon)

    return Method("old", rect, learn, find, threshold=0.5)


def new_method() -> Method:
    """The mouth finder of :mod:`tracker.mouth_finder` with :func:`tracker.mouth_model.learn_mouth`."""
    from tracker.mouth_finder import SCORE_OK, MouthFinder
    from tracker.mouth_model import MOUTH_RECT, learn_mouth

    class State:
        pass

    def rect(wi):
        return tuple(v * wi for v in MOUTH_RECT)

    def learn(crop, click, wi, env):
        s = State()
        s.model = learn_mouth(crop, click, wi)
        s.finder = MouthFinder(s.model, wi)
        s.centre = s.model.centre
        return s

    def find(s, crop, pred):
        r = s.finder.find(crop, pred)
        if r is None:
            return None
        return Found(r.left, r.right, r.lip_upper, r.lip_lower, r.score, r.cue, r.polygon)

    return Method("new", rect, learn, find, threshold=SCORE_OK)


# ----------------------------------------------------------------------------- the benchmark

SYNTH_STYLES = ("default", "dark_skin", "pale_lips", "noisy", "small_far")
VARIANT_CLIPS = ("talk_a", "expr_d3", "expr_d18")
VARIANTS = ("desaturate", "lowres", "dim", "drift")


def cases(quick: bool) -> list[Case]:
    out: list[Case] = []
    names = clip_names()
    if quick:
        names = names[:2]
    for n in names:
        c = real_case(n, 40 if quick else None)
        if c is not None:
            out.append(c)
    for s in SYNTH_STYLES[:1] if quick else SYNTH_STYLES:
        out.append(synthetic_case(s, 1.5 if quick else 8.0))
    if not quick:
        for n in VARIANT_CLIPS:
            base = next((c for c in out if c.name == n), None)
            if base is not None:
                out += [variant(base, k) for k in VARIANTS]
    return out


def table(method: Method, cs: list[Case], sheets: bool = False) -> Table:
    t = Table(
        f"Mouth finder '{method.name}' vs the peer (real) / truth (synthetic), crop frame perturbed",
        ["clip", "frames", "cue", "corner %", "top %", "bottom %", "r open", "r width", "no result %", "wrong ok % (on crops %)",
         "cpu ms med/p95"],
    )
    misses = []
    all_ms: list[float] = []
    synth = []
    sheet_dir = Path("out/real_mouth") if sheets else None
    for c in cs:
        r = run_case(c, method, sheet_every=max(len(c.frames) // 40, 1) if sheets else 0, sheet_dir=sheet_dir)
        if r.learn_error:
            t.add(c.name, str(r.frames), "refused: " + r.learn_error[:60], *["–"] * 8)
            misses.append(f"{c.name}: calibration refused")
            continue
        ro, rw = _pearson(r.open_px, c.ref_open), _pearson(r.width_px, c.ref_width)
        all_ms += r.ms[2:]
        cue = ",".join(f"{k}:{100 * v / r.frames:.0f}" for k, v in sorted(r.cues.items(), key=lambda kv: -kv[1]))
        wrong = f"{100.0 * r.wrong_ok / max(r.judged, 1):.1f} ({100.0 * r.wrong_ok_here / max(r.frames, 1):.1f})"
        t.add(c.name, str(r.frames), cue, _mp(r.corner_err), _mp(r.top_err), _mp(r.bottom_err), f"{ro:.2f}", f"{rw:.2f}",
              f"{100.0 * r.none / r.frames:.1f}", wrong,
              f"{np.median(r.ms):.2f}/{np.percentile(r.ms, 95):.2f}")
        if not c.synthetic and " " not in c.name:
            if not ro >= 0.85:
                misses.append(f"{c.name}: r open {ro:.2f}")
            if not rw >= 0.7:
                misses.append(f"{c.name}: r width {rw:.2f}")
        if c.synthetic:
            synth.append((c.name, r))
    t.note = (
        "corner / top / bottom: median/p95 error in % of the inter-pupil distance (edges along up); r: Pearson with "
        "the reference over the clip; targets on the real clips: r open ≥ 0.85, r width ≥ 0.7, wrong ok ≈ 0.\n"
        + (f"finder time per call over all clips: median {np.median(all_ms):.3f} ms, p95 {np.percentile(all_ms, 95):.3f} ms; "
           if all_ms else "")
        + ("all real-clip targets met on the clips run" if not misses else "missed: " + "; ".join(misses))
    )
    if synth:
        for name, r in synth:
            t.note += (
                f"\n{name}: |error| px median/p95 width {np.median(r.width_abs):.2f}/{np.percentile(r.width_abs, 95):.2f}, "
                f"lip_upper {np.median(r.upper_abs):.2f}/{np.percentile(r.upper_abs, 95):.2f}, "
                f"lip_lower {np.median(r.lower_abs):.2f}/{np.percentile(r.lower_abs, 95):.2f}"
                if r.width_abs else f"\n{name}: no confident result"
            )
    return t


@benchmark("real_mouth")
def run(ctx):
    if not clip_names():
        print("real_mouth: ../shared/real/ not found; real clips skipped")
    cs = cases(ctx.quick)
    sheets = bool(os.environ.get("INKFACE_MOUTH_SHEETS"))
    methods = [new_method()]
    if os.environ.get("INKFACE_MOUTH_OLD"):
        methods.insert(0, old_method())
    return [table(m, cs, sheets) for m in methods]
