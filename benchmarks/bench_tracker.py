"""Face tracker: accuracy against the synthetic performer's truth, speed, loss and recovery.

Each clip is generated here (nothing is read from disk), calibrated from its own frame-0
clicks, and tracked frame by frame. Errors are absolute differences to the exact truth, in
pixels of the 640×480 frame (degrees for roll); "lost" counts frames reported ``lost``
while the face is in view.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from benchmarks.harness import TIMING_COLUMNS, Table, Timing, benchmark, time_call
from tracker.calibration import Calibration, calibrate
from tracker.clicks import PIXEL_CENTRE, Clicks
from tracker.face_tracker import FaceTracker
from tracker.params import PARAM_NAMES
from tracker.synthetic import STYLES, Performance

# clip name → (style, extra Performance options)
CLIPS: dict[str, tuple[str, dict]] = {
    "clean": ("default", {}),
    "noisy+blurred": ("noisy", {}),
    "lighting drift": ("lighting", {}),
    "dark skin, brown lips": ("dark_skin", {}),
    "pale pink lips": ("pale_lips", {}),
    "small far (ipd 48)": ("small_far", {}),
    "strong roll (±30°)": ("strong_roll", {}),
}
QUICK_CLIPS = ("clean", "dark skin, brown lips")

# median targets per parameter (px or degrees); the 95th percentile target is 3×
TARGETS = {
    "mid_x": 1.0, "mid_y": 1.0, "roll_deg": 1.0,
    "eye_open_l": 1.5, "eye_open_r": 1.5, "brow_l": 1.5, "brow_r": 1.5,
    "mouth_width": 2.0, "lip_upper": 1.5, "lip_lower": 1.5,
}
SHORT = {"mid_x": "mid_x", "mid_y": "mid_y", "roll_deg": "roll°", "eye_open_l": "eye_l", "eye_open_r": "eye_r",
         "brow_l": "brow_l", "brow_r": "brow_r", "mouth_width": "width", "lip_upper": "lip_up", "lip_lower": "lip_lo"}


def _track_clip(perf: Performance):
    frames = [perf.render(i) for i in range(len(perf))]
    cal = calibrate(frames[0][0], Clicks.from_dict(perf.clicks()))
    tr = FaceTracker(cal)
    errs, statuses, times, cpu = [], [], [], []
    visible = []
    for i, (img, truth) in enumerate(frames):
        c0 = time.process_time()
        t0 = time.perf_counter()
        r = tr.track(img, index=i, time=i / perf.fps)
        times.append((time.perf_counter() - t0) * 1000.0)
        cpu.append((time.process_time() - c0) * 1000.0)
        statuses.append(r.params.status)
        visible.append(truth.status != "lost")
        errs.append(np.abs(r.params.values() - truth.values()))
    return np.array(errs), statuses, np.array(visible), times, cpu


def _fastest_of_3(cal: Calibration, frames: list[np.ndarray], prepare=None) -> np.ndarray:
    """Each frame's fastest ``track`` time (ms, wall clock) over three passes of ``frames``, each pass
    a new tracker from ``cal``: what a quiet core does. ``prepare`` (optional) makes each frame what
    the tracker is given, outside the timing."""
    best = np.full(len(frames), np.inf)
    for _ in range(3):
        tr = FaceTracker(cal)
        for i, img in enumerate(frames):
            if prepare is not None:
                img = prepare(img)
            t0 = time.perf_counter()
            tr.track(img, index=i)
            best[i] = min(best[i], (time.perf_counter() - t0) * 1000.0)
    return best


@benchmark("tracker")
def run(ctx):
    names = QUICK_CLIPS if ctx.quick else tuple(CLIPS)
    seconds = 40 / 30.0 if ctx.quick else 8.0
    acc = Table(
        f"Tracker accuracy vs synthetic truth: median / p95 absolute error ({int(round(seconds * 30))} frames a clip)",
        ["clip"] + [SHORT[n] for n in PARAM_NAMES] + ["lost", "closed"],
    )
    all_times: list[float] = []
    all_cpu: list[float] = []
    misses = []
    for name in names:
        style, opts = CLIPS[name]
        perf = Performance(seconds=seconds, seed=5, style=STYLES[style], **opts)
        err, statuses, visible, times, cpu = _track_clip(perf)
        all_times += times[2:]
        all_cpu += cpu[2:]
        med, p95 = np.median(err, axis=0), np.percentile(err, 95, axis=0)
        lost = int(sum(s == "lost" and v for s, v in zip(statuses, visible)))
        closed = int(sum(s == "eyes_closed" for s in statuses))
        acc.add(name, *[f"{m:.2f}/{p:.2f}" for m, p in zip(med, p95)], str(lost), str(closed))
        for n, m, p in zip(PARAM_NAMES, med, p95):
            if m > TARGETS[n] or p > 3 * TARGETS[n]:
                misses.append(f"{name}:{SHORT[n]} {m:.2f}/{p:.2f}")
        if lost:
            misses.append(f"{name}: {lost} frames lost in view")
    acc.note = (
        "targets: median ≤ 1 px pupils (mid_x/y), ≤ 1° roll, ≤ 1.5 px lids and brows, ≤ 2 px mouth width, "
        "≤ 1.5 px lips; p95 ≤ 3× the median target; 0 frames lost in view.\n"
        + ("all targets met" if not misses else "missed: " + "; ".join(misses))
    )

    speed = Table("Tracker speed, one 640×480 frame (one core)", ["stage"] + TIMING_COLUMNS + ["paper (450 MHz PIII)"])
    speed.add("track one frame, wall clock (all clips above)", *Timing(all_times).cells(), "29 ms")
    speed.add("track one frame, CPU time of this process", *Timing(all_cpu).cells(), "")
    speed.note = (
        "targets: track median ≤ 3 ms; calibrate ≤ 500 ms, load ≤ 200 ms. Wall clock includes time stolen by other processes on a shared machine; "
        "CPU time counts only this process (clock resolution about 1 µs)."
    )

    # the same clip tracked three times: each frame's fastest pass is what a quiet core does
    perf = Performance(seconds=seconds, seed=5, style=STYLES["default"])
    frames = [perf.frame(i) for i in range(len(perf))]
    cal = calibrate(frames[0], Clicks.from_dict(perf.clicks()))
    best = _fastest_of_3(cal, frames)
    speed.add("track one frame, wall clock, fastest of 3 passes (clean clip)", *Timing(list(best[2:])).cells(), "")
    # the same clip as a 1080p webcam sends it (the face 2.25× larger, in a 1920×1080 frame): the
    # finders and the flow work at a fixed face size, so only the whole frame's grey copy grows
    s, ox = 2.25, (1920 - 2.25 * 640) / 2
    big = np.array([[s, 0.0, ox], [0.0, s, 0.0]])
    hd = lambda img: cv2.warpAffine(img, big, (1920, 1080), flags=cv2.INTER_LINEAR)
    c = PIXEL_CENTRE  # the clicks' pixel centres, OpenCV's at whole numbers
    hd_clicks = Clicks.from_dict({k: ([s * (v[0] - c) + ox + c, s * (v[1] - c) + c] if isinstance(v, (list, tuple)) else v)
                                  for k, v in perf.clicks().items()})
    best_hd = _fastest_of_3(calibrate(hd(frames[0]), hd_clicks), frames, hd)
    speed.add("the same, each frame scaled into 1920×1080 (a 1080p webcam)", *Timing(list(best_hd[2:])).cells(), "")

    # starting a performer: learning the calibration from the clicks, or loading a saved one
    clicks = Clicks.from_dict(perf.clicks())
    speed.add("calibrate from five clicks (clean clip, frame 0)",
              *time_call(lambda: calibrate(frames[0], clicks), ctx.runs(7, 2), warmup=1).cells(), "")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "performer.calibration.json"
        cal.save(path)
        speed.add("Calibration.load (JSON + eye and colour-table PNGs)",
                  *time_call(lambda: Calibration.load(path), ctx.runs(7, 2), warmup=1).cells(), "")

    rec = _recovery(ctx)
    return [acc, speed, rec]


def _recovery(ctx) -> Table:
    """Faces leave the frame and come back (somewhere else, with some roll)."""
    t = Table("Tracker loss and re-acquisition", ["clip", "away (s)", "frames to recover", "lost in view", "false ok while away"])
    cases = [("clean", "default", [(1.0, 1.5)])] if ctx.quick else [
        ("clean", "default", [(2.0, 2.6), (5.0, 5.4)]),
        ("dark skin", "dark_skin", [(2.0, 2.6), (5.0, 5.4)]),
        ("small far", "small_far", [(2.0, 2.6), (5.0, 5.4)]),
        ("lighting drift", "lighting", [(2.0, 2.6), (5.0, 5.4)]),
        ("strong roll", "strong_roll", [(2.0, 2.6), (5.0, 5.4)]),
    ]
    for name, style, away in cases:
        seconds = 2.2 if ctx.quick else 7.0
        perf = Performance(seconds=seconds, seed=9, style=STYLES[style], away=away)
        frames = [perf.render(i) for i in range(len(perf))]
        cal = calibrate(frames[0][0], Clicks.from_dict(perf.clicks()))
        tr = FaceTracker(cal)
        st = [tr.track(img, i, i / perf.fps).params.status for i, (img, _) in enumerate(frames)]
        vis = [tru.status != "lost" for _, tru in frames]
        recov = []
        for a, b in away:
            back = int(np.ceil(b * perf.fps))
            k = back
            while k < len(st) and st[k] == "lost":
                k += 1
            recov.append(str(k - back) if k < len(st) else "never")
        lost_in_view = sum(s == "lost" and v for s, v in zip(st, vis))
        # frames away that are within one frame after leaving may still be "ok"
        false_ok = sum(s != "lost" and not v for s, v in zip(st, vis))
        t.add(name, ", ".join(f"{a:g}–{b:g}" for a, b in away), ", ".join(recov), str(lost_in_view), str(false_ok))
    t.note = "target: recover within 5 frames of the face returning"
    return t
