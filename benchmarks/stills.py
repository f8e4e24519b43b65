"""Still faces under a known camera motion: what the tracker reads when nothing on the face moves.

A photo of a face, shifted, turned and scaled smoothly the way a hand-held camera or a leaning
body moves it, is a clip whose face does nothing, and whose motion is known exactly. On it the
pupils must follow the motion, and every shape value must hold still once the motion's scale is
taken out. Whatever the numbers do besides is flicker the cartoon would show, or a start that
read the face wrong. No peer is needed, so any photo of anyone will do: the faces the shared clips
do not have (other people, other cameras, hats, glasses, a grin at the first frame) are a folder
of photos away.

Sources (each becomes one still clip of :data:`FRAMES` frames at :data:`FPS`):

* **photos** in a folder (``--photos DIR`` or ``$INKFACE_STILLS_DIR``): each face the bundled
  face detector finds (largest first, up to ``--faces`` a photo, at least :data:`MIN_FACE` px
  wide), cropped square to :data:`FACE_SPAN` face widths and scaled to :data:`SIZE` px;
* **frames of the shared clips** (``../shared/real``, :func:`benchmarks.realfaces.real_dir`) at
  :data:`CLIP_SHARES` of each clip's length, whole: a grin, a pout, a squint, a word. There the
  peer's points give the truth on the still (where the pupils and the mouth are) and the clicks
  a careful person would make (``clicks`` mode, beside ``--auto``).

What is measured, per still and mode (:func:`still_metrics`), on the frames reported ``ok``,
everything mapped back through the known motion to the still's own pixels:

* **ok %** of all frames (the face is in view in every one);
* **pupil drift**: each pupil's distance from its median place, the larger of the two, in % of
  the inter-pupil distance (p95 and max); **mouth drift** likewise for the mouth's centre;
* **flicker** of each shape value (mouth opening, mouth width, eye opening and brow height, as in
  :mod:`benchmarks.realfaces`), divided by the motion's scale: its standard deviation, and the
  number of frame-to-frame changes over :data:`JUMP` (jumps), in % of the inter-pupil distance;
* with the peer (shared frames): the pupil midpoint's and the mouth centre's median error from
  the peer's, in % of its inter-pupil distance (a start that read the wrong feature shows here).

``python -m benchmarks.stills [--photos DIR] [--sheets]`` prints the table; contact sheets (the
overlay at the start, a third, two thirds and the end, and each value's trace) go to
``out/stills/``. Nothing here is committed data.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # before numpy loads: one thread per process
    for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_v, "1")

import argparse
import json
import math
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

from benchmarks import realfaces as rf
from tracker.face_finder import detect_faces
from tracker.params import OK, PARAM_NAMES
from tracker.track_cli import TrackCliError, _Video

STILLS_DIR_ENV = "INKFACE_STILLS_DIR"
OUT_DIR = rf.REPO_ROOT / "out" / "stills"
SIZE = 512
"""Side (px) of a photo's still clip."""
FACE_SPAN = 2.4
"""Face-box widths a photo's crop spans (the shared clips' faces fill about as much of theirs)."""
MIN_FACE = 48
"""Narrowest face box (photo px) taken from a photo: smaller ones are crowds in the background."""
FRAMES, FPS = 100, 25.0
CLIP_SHARES = (0.0, 0.25, 0.5, 0.75)
"""Where in each shared clip (share of its frames) a still is taken."""
MOTION = (8.0, 4.0, 0.05)
"""The camera's motion at :data:`SIZE` px: shift amplitude (px; 0.6 of it vertically), turn (°) and
scale (± share), each a sine of its own period (:data:`PERIODS`), all zero at frame 0."""
PERIODS = (2.9, 2.1, 3.7, 3.1)
"""Periods (s) of the horizontal shift, the vertical shift, the turn and the scale."""
JUMP = 4.0
"""A frame-to-frame change of a shape value (% of the inter-pupil distance, the motion's scale taken
out) over which the value jumped: a still face gives none, and the peer's own per-frame change on the
shared clips' moving faces has its median at 0.1-2.7."""
SHAPES = ("open", "width", "eye", "brow")

# What a still face should give (issue 13's spirit: the numbers move with the face, and only then).
STILL_TARGETS: dict[str, tuple[str, float]] = {
    "ok_pct": ("min", 99.0),
    "pupil_drift_p95": ("max", 1.5),
    "mouth_drift_p95": ("max", 4.0),
    "sd_open": ("max", 1.5),
    "sd_width": ("max", 1.5),
    "sd_eye": ("max", 1.5),
    "sd_brow": ("max", 1.5),
    "jumps": ("max", 0.0),
}
"""Per still and mode. Pupil drift within 1.5 % of the eye distance (about a pixel on a 70 px face),
the mouth's centre within 4 %; each value's spread within 1.5 % (the synthetic performer's still:
under 0.5); no jump at all."""


# ---------------------------------------------------------------------------------------------
# The motion


def motion(i: int, fps: float = FPS, size: int = SIZE, amp: tuple[float, float, float] = MOTION) -> np.ndarray:
    """The camera's 2×3 affine matrix at frame ``i``: from the still's pixels to the frame's, about
    the middle of a ``size``-px square; the identity at frame 0. ``amp`` as :data:`MOTION`, its shift
    scaled with ``size``."""
    t = i / fps
    s = size / SIZE
    dx = amp[0] * s * math.sin(2 * math.pi * t / PERIODS[0])
    dy = 0.6 * amp[0] * s * math.sin(2 * math.pi * t / PERIODS[1])
    ang = amp[1] * math.sin(2 * math.pi * t / PERIODS[2])
    sc = 1.0 + amp[2] * math.sin(2 * math.pi * t / PERIODS[3])
    m = cv2.getRotationMatrix2D((0.5 * (size - 1), 0.5 * (size - 1)), ang, sc)
    m[:, 2] += (dx, dy)
    return m


def inverse(m: np.ndarray) -> np.ndarray:
    """The 2×3 inverse of an affine 2×3 matrix."""
    return cv2.invertAffineTransform(np.asarray(m, dtype=np.float64))


def apply(m: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Points ``(..., 2)`` (pixel centres at integers) through the 2×3 matrix ``m``."""
    p = np.asarray(pts, dtype=np.float64)
    return p @ m[:, :2].T + m[:, 2]


def scale_of(m: np.ndarray) -> float:
    """The isotropic scale of a similarity's 2×3 matrix."""
    return math.sqrt(abs(float(np.linalg.det(np.asarray(m)[:, :2]))))


def write_still_clip(path: Path, still: np.ndarray, frames: int = FRAMES, fps: float = FPS) -> np.ndarray:
    """Write ``still`` (square BGR) moved by :func:`motion` to ``path`` (mp4) and return the
    matrices (frames, 2, 3). Borders repeat the edge, as a crop from a larger frame would show."""
    size = still.shape[0]
    if still.shape[1] != size:
        raise ValueError(f"a still must be square, got {still.shape[1]}x{size}")
    mats = np.array([motion(i, fps, size) for i in range(frames)])
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (size, size))
    if not vw.isOpened():
        raise OSError(f"{path}: cannot write video")
    try:
        for m in mats:
            vw.write(cv2.warpAffine(still, m, (size, size), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE))
    finally:
        vw.release()
    return mats


# ---------------------------------------------------------------------------------------------
# Sources


@dataclass
class Still:
    """One still: its picture (square BGR), where it came from, its size (``face_px``: a photo's face box
    width in the photo, a real frame's inter-pupil distance), and — from a shared clip — the peer's
    points on it (name → (2,) px) and the clicks a careful person would make."""

    name: str
    source: str
    image: np.ndarray = field(repr=False)
    face_px: float = math.nan
    truth: dict[str, np.ndarray] | None = field(default=None, repr=False)
    clicks: dict | None = None


def photo_stills(folder: Path, faces: int = 1, size: int = SIZE) -> list[Still]:
    """The faces in every photo of ``folder`` (``.jpg``, ``.jpeg``, ``.png``, sorted), up to ``faces``
    a photo, each cropped square (:data:`FACE_SPAN`) round its box and scaled to ``size``. A photo
    that cannot be read or has no face is skipped with a line on stderr."""
    out = []
    for p in sorted(folder.iterdir()):
        if p.suffix.lower() not in (".jpg", ".jpeg", ".png"):
            continue
        img = cv2.imread(str(p), cv2.IMREAD_COLOR)
        if img is None:
            print(f"{p}: not a picture OpenCV can read; skipped", file=sys.stderr)
            continue
        boxes = [b for b in detect_faces(img, None) if b[2] >= MIN_FACE][:faces]
        if not boxes:
            print(f"{p}: no face found; skipped", file=sys.stderr)
        for k, (x, y, w, h) in enumerate(boxes):
            cx, cy = x + 0.5 * w, y + 0.55 * h
            s = size / (FACE_SPAN * w)
            a = np.array([[s, 0.0, 0.5 * (size - 1) - s * cx], [0.0, s, 0.5 * (size - 1) - s * cy]])
            crop = cv2.warpAffine(img, a, (size, size), flags=cv2.INTER_AREA if s < 1 else cv2.INTER_CUBIC,
                                  borderMode=cv2.BORDER_REPLICATE)
            name = p.stem if len(boxes) == 1 else f"{p.stem}_{k}"
            out.append(Still(name, "photo", crop, face_px=float(w)))
    return out


def clip_stills(folder: Path, names: Sequence[str] | None = None, shares: Sequence[float] = CLIP_SHARES) -> list[Still]:
    """Frames of the shared clips at ``shares`` of their length, whole and square (the shared clips
    are), with the peer's points there and the clicks made from them; a frame where the peer does
    not see the face is skipped."""
    from benchmarks.stress_clips import POINTS, _clicks_from_points

    out = []
    for name in names or rf.clip_names(folder):
        peer = rf.load_peer(folder, name)
        want = sorted({min(int(round(s * (len(peer) - 1))), len(peer) - 1) for s in shares})
        video = _Video(folder / f"{name}.mp4", threads=1)
        try:
            for i, img in video.frames():
                if i > want[-1]:
                    break
                if i not in want or not peer.visible[i]:
                    continue
                h, w = img.shape[:2]
                if h != w:
                    side = min(h, w)
                    img = img[(h - side) // 2 : (h - side) // 2 + side, (w - side) // 2 : (w - side) // 2 + side]
                    off = np.array([(w - side) // 2, (h - side) // 2], float)
                else:
                    off = np.zeros(2)
                pts = {k: peer.points[k][i] - off for k in POINTS if k in peer.points}
                clicks = _clicks_from_points({k: p[None, :] for k, p in pts.items()}, 0)
                out.append(Still(f"{name}@{i}", "clip", img.copy(), face_px=float(peer.ipd[i]),
                                 truth=pts, clicks=clicks))
        finally:
            video.close()
    return out


# ---------------------------------------------------------------------------------------------
# Measuring


@dataclass
class StillRun:
    """The tracker on one still clip: per-frame statuses, pupils (n, 2, 2), mouth centres (n, 2) and
    parameters (n, 10), all in frame px; or the one-line ``error`` of a start that failed."""

    name: str
    mode: str
    statuses: list[str] = field(default_factory=list)
    pupils: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))
    mouths: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    values: np.ndarray = field(default_factory=lambda: np.zeros((0, len(PARAM_NAMES))))
    error: str | None = None
    overlays: dict[int, np.ndarray] = field(default_factory=dict, repr=False)


def track_still(video: Path, clicks: Path | None, name: str, keep: Sequence[int] = ()) -> StillRun:
    """Track a still clip from frame 0, with ``clicks`` or (None) ``--auto``, keeping the overlay of
    the frames ``keep`` (:func:`benchmarks.realfaces.run_clip`)."""
    clip = rf.run_clip(video, clicks, auto=clicks is None, keep=keep, name=name)
    run = StillRun(name, clip.mode, error=clip.error)
    if clip.error is None:
        run.statuses, run.pupils, run.mouths, run.overlays = clip.statuses, clip.pupils, clip.mouth_centres, clip.overlays
        run.values = np.array([p.values() for p in clip.params], dtype=np.float64).reshape(-1, len(PARAM_NAMES))
    return run


def shape_series(values: np.ndarray) -> dict[str, np.ndarray]:
    """The four shape values per frame from parameter rows (n, 10), as :mod:`benchmarks.realfaces`
    compares them."""
    s = rf._shapes(values)
    return {"open": s["r_open"], "width": s["r_width"], "eye": s["r_eye"], "brow": s["r_brow"]}


def still_metrics(run: StillRun, mats: np.ndarray, truth: dict[str, np.ndarray] | None = None) -> dict[str, float]:
    """The figures of one still run (module docstring), given the motion's matrices (n, 2, 3) and the
    peer's points on the still (or None). Distances are in % of our median inter-pupil distance on
    the still (the peer's for its errors); nan where no frame is ``ok``."""
    n = min(len(run.statuses), len(mats))
    out = {k: math.nan for k in ("ok_pct", "pupil_drift_p95", "pupil_drift_max", "mouth_drift_p95", "jumps",
                                 "pupil_err", "mouth_err", *(f"sd_{s}" for s in SHAPES))}
    if n == 0:
        return out
    ok = np.array([s == OK for s in run.statuses[:n]])
    out["ok_pct"] = 100.0 * ok.sum() / n
    if not ok.any():
        return out
    inv = np.array([inverse(m) for m in mats[:n]])
    back = np.einsum("nij,npj->npi", inv[:, :, :2], run.pupils[:n]) + inv[:, None, :, 2]  # (n, 2, 2)
    ipd = float(np.median(np.linalg.norm(back[ok, 1] - back[ok, 0], axis=1)))
    if not ipd > 0:
        return out
    med = np.median(back[ok], axis=0)
    drift = np.linalg.norm(back[ok] - med, axis=2).max(axis=1) / ipd * 100.0
    out["pupil_drift_p95"], out["pupil_drift_max"] = float(np.percentile(drift, 95)), float(drift.max())
    mouth = np.einsum("nij,nj->ni", inv[:, :, :2], run.mouths[:n]) + inv[:, :, 2]
    mok = ok & np.isfinite(mouth).all(axis=1)
    if mok.any():
        md = np.linalg.norm(mouth[mok] - np.median(mouth[mok], axis=0), axis=1) / ipd * 100.0
        out["mouth_drift_p95"] = float(np.percentile(md, 95))
    scale = np.array([scale_of(m) for m in mats[:n]])
    jumps = 0
    for k, v in shape_series(run.values[:n]).items():
        v = v / scale / ipd * 100.0
        good = ok & np.isfinite(v)
        out[f"sd_{k}"] = float(np.std(v[good])) if good.sum() > 1 else math.nan
        pair = good[1:] & good[:-1]
        jumps += int((np.abs(np.diff(v))[pair] > JUMP).sum())
    out["jumps"] = float(jumps)
    if truth is not None and "left_pupil" in truth and "right_pupil" in truth:
        tl, tr = np.asarray(truth["left_pupil"], float), np.asarray(truth["right_pupil"], float)
        tipd = float(np.linalg.norm(tr - tl))
        if tipd > 0:
            mid = 0.5 * (back[ok, 0] + back[ok, 1])
            out["pupil_err"] = float(np.median(np.linalg.norm(mid - 0.5 * (tl + tr), axis=1)) / tipd * 100.0)
            lc, rc = truth.get("left_mouth_corner"), truth.get("right_mouth_corner")
            if lc is not None and rc is not None and mok.any():
                pm = 0.5 * (np.asarray(lc, float) + np.asarray(rc, float))
                out["mouth_err"] = float(np.median(np.linalg.norm(mouth[mok] - pm, axis=1)) / tipd * 100.0)
    return out


def still_misses(m: dict[str, float]) -> dict[str, bool]:
    """Target name → whether the figures miss it (nan misses)."""
    return rf.target_misses(m, STILL_TARGETS)


# ---------------------------------------------------------------------------------------------
# Sheets

STRIP_H = 56
STRIP_COLOURS = {"open": (80, 200, 255), "width": (80, 255, 120), "eye": (255, 180, 80), "brow": (220, 120, 255)}


def sheet_frames(n: int) -> list[int]:
    """The start, a third, two thirds and the last frame."""
    return sorted({0, n // 3, (2 * n) // 3, max(n - 1, 0)})


def still_sheet(run: StillRun, mats: np.ndarray, m: dict[str, float], tile: int = 256) -> np.ndarray:
    """The kept overlays side by side over each shape value's trace across the clip (motion's scale
    taken out, ±5 % of the inter-pupil distance about its median per strip; grey frames: not ok)."""
    idx = sorted(run.overlays)
    tiles = []
    for i in idx:
        t = cv2.resize(run.overlays[i], (tile, tile), interpolation=cv2.INTER_AREA)
        cv2.putText(t, f"#{i} {run.statuses[i]}", (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 255, 255), 1, cv2.LINE_AA)
        tiles.append(t)
    width = tile * max(len(tiles), 1)
    head = np.full((22, width, 3), 32, np.uint8)
    title = (f"{run.name} ({run.mode})   ok {m['ok_pct']:.0f}%   pupil drift p95 {m['pupil_drift_p95']:.2f}%   "
             f"jumps {m['jumps']:.0f}   sd " + " ".join(f"{k} {m[f'sd_{k}']:.2f}" for k in SHAPES))
    cv2.putText(head, title, (4, 15), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (230, 230, 230), 1, cv2.LINE_AA)
    body = np.hstack(tiles) if tiles else np.zeros((tile, width, 3), np.uint8)
    n = min(len(run.statuses), len(mats))
    strips = np.full((STRIP_H * len(SHAPES), width, 3), 24, np.uint8)
    if n > 1:
        ok = np.array([s == OK for s in run.statuses[:n]])
        ipd = np.median(np.linalg.norm(run.pupils[:n, 1] - run.pupils[:n, 0], axis=1))
        scale = np.array([scale_of(q) for q in mats[:n]])
        x = np.round(np.arange(n) * (width - 1) / (n - 1)).astype(np.int32)
        for r, (k, v) in enumerate(shape_series(run.values[:n]).items()):
            y0 = r * STRIP_H
            v = v / scale / ipd * 100.0
            good = ok & np.isfinite(v)
            for i in np.flatnonzero(~ok):
                cv2.line(strips, (int(x[i]), y0), (int(x[i]), y0 + STRIP_H - 1), (60, 60, 60), 1)
            cv2.putText(strips, f"{k} (+-5% ipd)", (4, y0 + 14), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (200, 200, 200), 1)
            if good.any():
                mid = float(np.median(v[good]))
                y = y0 + 0.5 * STRIP_H - (v - mid) / 5.0 * 0.45 * STRIP_H
                pts = np.stack([x, np.clip(y, y0, y0 + STRIP_H - 1)], axis=1)
                for a in range(n - 1):
                    if good[a] and good[a + 1]:
                        cv2.line(strips, tuple(int(c) for c in pts[a]), tuple(int(c) for c in pts[a + 1]), STRIP_COLOURS[k], 1)
    return np.vstack([head, body, strips])


# ---------------------------------------------------------------------------------------------
# Jobs and the table


@dataclass
class StillResult:
    name: str
    source: str
    mode: str
    face_px: float
    metrics: dict[str, float]
    error: str | None = None
    sheet: str | None = None


def measure_still(still: Still, auto: bool, frames: int = FRAMES, sheets: bool = False,
                  out_dir: Path = OUT_DIR) -> StillResult:
    """Make the still's clip in a temporary folder, track it (``auto`` or with the still's clicks),
    measure it and (``sheets``) write its contact sheet."""
    mode = "auto" if auto else "clicks"
    with tempfile.TemporaryDirectory(prefix="inkface-still-") as tmp:
        video = Path(tmp) / "still.mp4"
        mats = write_still_clip(video, still.image, frames)
        clicks = None
        if not auto:
            if still.clicks is None:
                return StillResult(still.name, still.source, mode, still.face_px, {}, error="no clicks for a photo")
            clicks = Path(tmp) / "still.clicks.json"
            clicks.write_text(json.dumps(still.clicks))
        run = track_still(video, clicks, still.name, keep=sheet_frames(frames) if sheets else ())
    if run.error is not None:
        return StillResult(still.name, still.source, mode, still.face_px, {}, error=run.error)
    m = still_metrics(run, mats, still.truth)
    sheet = None
    if sheets:
        safe = still.name.replace("@", "_at")
        path = out_dir / (f"{safe}.auto.png" if auto else f"{safe}.png")
        rf.write_png(path, still_sheet(run, mats, m))
        sheet = str(path)
    return StillResult(still.name, still.source, mode, still.face_px, m, sheet=sheet)


def measure_stills(stills: Sequence[Still], modes: Sequence[bool] = (True,), frames: int = FRAMES,
                   sheets: bool = False, workers: int = 2) -> list[StillResult]:
    """Every still in every mode (``True``: ``--auto``; clicks only where the still has them)."""
    jobs = [(s, auto, frames, sheets) for auto in modes for s in stills if auto or s.clicks is not None]
    return rf._map(measure_still, jobs, workers)


def stills_table(results: Sequence[StillResult], note: str = "") -> "Table":
    """One row per still and mode; misses of :data:`STILL_TARGETS` starred; a last line per mode
    counts the stills meeting every target."""
    from benchmarks.harness import Table

    t = Table("Still faces under a known camera motion (no face movement: every figure should stay put)",
              ["still", "mode", "box / ipd px", "ok %", "pupil drift p95/max %IPD", "mouth drift p95",
               "sd open/width/eye/brow %IPD", "jumps", "vs peer: pupil/mouth %IPD"])
    t.add("target", "", "", f"≥ {STILL_TARGETS['ok_pct'][1]:.0f}", f"≤ {STILL_TARGETS['pupil_drift_p95'][1]}",
          f"≤ {STILL_TARGETS['mouth_drift_p95'][1]}", f"each ≤ {STILL_TARGETS['sd_open'][1]}", "0", "")
    counts: dict[str, list[int]] = {}
    for r in results:
        c = counts.setdefault(r.mode, [0, 0])
        c[1] += 1
        if r.error is not None:
            t.add(r.name, r.mode, f"{r.face_px:.0f}", f"start failed: {r.error}", "", "", "", "", "")
            continue
        m, x = r.metrics, still_misses(r.metrics)
        c[0] += not any(x.values())
        sds = "/".join(rf._c(m[f"sd_{k}"], ".2f", x[f"sd_{k}"]) for k in SHAPES)
        t.add(r.name, r.mode, f"{r.face_px:.0f}", rf._c(m["ok_pct"], ".0f", x["ok_pct"]),
              f"{rf._c(m['pupil_drift_p95'], '.2f', x['pupil_drift_p95'])}/{m['pupil_drift_max']:.2f}",
              rf._c(m["mouth_drift_p95"], ".1f", x["mouth_drift_p95"]), sds, rf._c(m["jumps"], ".0f", x["jumps"]),
              "" if not math.isfinite(m.get("pupil_err", math.nan)) else f"{m['pupil_err']:.1f}/{m['mouth_err']:.1f}")
    summary = "; ".join(f"{mode}: {a}/{b} stills meet every target" for mode, (a, b) in counts.items())
    t.note = "\n".join(x for x in (summary, note) if x)
    return t


def stills_dir(folder: str | os.PathLike | None = None) -> Path | None:
    """The folder of photos: ``folder``, else ``$INKFACE_STILLS_DIR``; None when neither is a folder."""
    for cand in (folder, os.environ.get(STILLS_DIR_ENV)):
        if cand:
            p = Path(cand)
            return p if p.is_dir() else None
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.stills", description=__doc__.split("\n\n")[0])
    ap.add_argument("--photos", default=None, help=f"folder of face photos (default ${STILLS_DIR_ENV})")
    ap.add_argument("--faces", type=int, default=1, help="faces taken from each photo, largest first")
    ap.add_argument("--dir", default=None, help="folder of real clips (default ../shared/real)")
    ap.add_argument("--no-clips", action="store_true", help="photos only, no frames of the shared clips")
    ap.add_argument("--clips", default=None, help="comma-separated clip names (default: all)")
    ap.add_argument("--frames", type=int, default=FRAMES, help="frames per still clip")
    ap.add_argument("--clicks", action="store_true", help="also with the clicks (shared frames only)")
    ap.add_argument("--sheets", action="store_true", help=f"write contact sheets to {OUT_DIR}")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    stills: list[Still] = []
    photos = stills_dir(args.photos)
    if args.photos and photos is None:
        print(f"{args.photos}: no such folder", file=sys.stderr)
        return 2
    if photos is not None:
        stills += photo_stills(photos, args.faces)
    real = None if args.no_clips else rf.real_dir(args.dir)
    if real is not None:
        stills += clip_stills(real, args.clips.split(",") if args.clips else None)
    if not stills:
        print("no stills: give --photos DIR (or $INKFACE_STILLS_DIR), or have ../shared/real", file=sys.stderr)
        return 2
    modes = (True, False) if args.clicks else (True,)
    results = measure_stills(stills, modes, args.frames, args.sheets, args.workers)
    print(stills_table(results, f"contact sheets: {OUT_DIR}/" if args.sheets else "").render())
    return 0


if __name__ == "__main__":
    sys.exit(main())
