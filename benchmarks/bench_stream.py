"""Temporal compression of the 8-bit parameter stream: bits per frame and coder speed.

Tracks: the synthetic performer's exact truth for a few styles (they differ in face size and
roll; the truth carries no image noise) and seeds, the same with
tracker-like jitter added, and (when the tracker is installed) the FaceTracker's own output on
a rendered performance. Bits count frame payloads only (raw: 80 a frame); packet headers and
IP/UDP headers are extra and reported in the note.
"""

from __future__ import annotations

import numpy as np

from benchmarks.harness import Table, benchmark, time_each
from tracker.params import FaceParams, ParamCodec
from tracker.stream_codec import STREAM_HEADER_SIZE, StreamDecoder, StreamEncoder, compress_frames


def _bits(frames: list[bytes], key_interval: int) -> float:
    coded = compress_frames(frames, key_interval)
    return 8.0 * sum(len(p) for _, p in coded) / len(frames)


def _worst_delta(frames: list[bytes]) -> int:
    return max((8 * len(p) for k, p in compress_frames(frames, 30) if not k), default=0)


def _truth(style: str, seed: int, seconds: float):
    from tracker.synthetic import STYLES, Performance

    perf = Performance(seconds=seconds, seed=seed, style=STYLES[style])
    return perf, perf.truths()


def _jitter(rows: list[FaceParams], sigma_px: float, seed: int) -> list[FaceParams]:
    """Tracker-like noise: ``sigma_px`` on positions and lengths, 0.3 degrees on the roll."""
    rng = np.random.default_rng(seed)
    sigma = np.full(10, sigma_px)
    sigma[2] = 0.3
    return [FaceParams.from_values(r.values() + rng.normal(0, sigma), frame=r.frame, time=r.time, status=r.status)
            for r in rows]  # fmt: skip


def _tracked(seconds: float, seed: int, style: str = "webcam") -> list[FaceParams] | None:
    try:
        from tracker.calibration import calibrate
        from tracker.clicks import Clicks
        from tracker.face_tracker import FaceTracker
        from tracker.synthetic import STYLES, Performance
    except ImportError:
        return None
    perf = Performance(seconds=seconds, seed=seed, style=STYLES[style])
    clicks = Clicks.from_dict(perf.clicks())
    tracker = FaceTracker(calibrate(perf.frame(clicks.frame), clicks))
    return [tracker.track(perf.frame(i), i, perf.time(i)).params for i in range(len(perf))]


# (label, synthetic style, jitter sigma in px): the truth is scale-free in the codes, so the
# styles that matter are those changing the motion (roll) or the face size under a fixed jitter
TRUTH_TRACKS = (
    ("truth", "default", 0.0),
    ("truth, strong roll", "strong_roll", 0.0),
    ("truth + 0.3 px jitter", "default", 0.3),
    ("truth + 0.3 px jitter, small face (ipd 48)", "small_far", 0.3),
)


@benchmark("stream")
def run(ctx):
    seconds = 3.0 if ctx.quick else 20.0
    seeds = [0] if ctx.quick else [0, 1, 2, 3, 4]
    t = Table(
        f"Temporal compression, payload bits per frame ({seconds:g} s at 30 fps per track; raw = 80)",
        ["track", "seeds", "key 15", "key 30", "key 60", "max delta-frame bits (key 30)"],
    )
    all30 = []
    for label, style, sigma in TRUTH_TRACKS:
        per = {15: [], 30: [], 60: []}
        worst = 0
        for seed in seeds:
            perf, rows = _truth(style, seed, seconds)
            if sigma:
                rows = _jitter(rows, sigma, seed)
            codec = ParamCodec(perf.frame_size, perf.ipd)
            frames = [codec.encode(r) for r in rows]
            for k in per:
                per[k].append(_bits(frames, k))
            worst = max(worst, _worst_delta(frames))
        all30 += per[30]
        t.add(label, str(len(seeds)), *(float(np.mean(per[k])) for k in (15, 30, 60)), str(worst))
    for style in ("webcam",) if ctx.quick else ("webcam", "noisy"):
        tracked = _tracked(2.0 if ctx.quick else 10.0, seed=0, style=style)
        if tracked is None:
            t.note = "FaceTracker rows missing: the tracker is not installed. "
            break
        from tracker.synthetic import STYLES, Performance

        perf = Performance(seconds=1, seed=0, style=STYLES[style])
        codec = ParamCodec(perf.frame_size, perf.ipd)
        frames = [codec.encode(r) for r in tracked]
        vals = [_bits(frames, k) for k in (15, 30, 60)]
        all30.append(vals[1])
        t.add(f"FaceTracker output, '{style}' video", "1", *vals, str(_worst_delta(frames)))
    t.note += (
        f"Mean over all tracks at key interval 30: {np.mean(all30):.1f} bits/frame (goal <= 40; "
        f"{np.mean(all30) * 30:.0f} bit/s at 30 fps vs 2400 raw). Each packet adds a {STREAM_HEADER_SIZE}-byte "
        "header and IP/UDP 28 bytes; the file format adds 2 bytes a frame."
    )

    loss_t = Table(f"Frames decoded under random packet loss (truth 'default', {seconds:g} s; {3 if ctx.quick else 10} loss patterns each)",
                   ["loss", "plain", "compressed key 15", "compressed key 30", "compressed key 60"])  # fmt: skip
    rng = np.random.default_rng(0)
    perf, rows = _truth("default", 0, seconds)
    codec = ParamCodec(perf.frame_size, perf.ipd)
    sample = [codec.encode(r) for r in rows]
    coded_k = {k: compress_frames(sample, k) for k in (15, 30, 60)}
    for loss in (0.001, 0.01, 0.05):
        shown = {"plain": [], 15: [], 30: [], 60: []}
        for _ in range(3 if ctx.quick else 10):
            keep = rng.random(len(sample)) >= loss
            shown["plain"].append(keep.mean())
            for k in (15, 30, 60):
                dec = StreamDecoder()
                ok = sum(dec.decode(kk, p, seq=i) is not None
                         for i, ((kk, p), kept) in enumerate(zip(coded_k[k], keep)) if kept)  # fmt: skip
                shown[k].append(ok / len(sample))
        loss_t.add(f"{100 * loss:g}%", *(f"{100 * np.mean(v):.1f}%" for v in shown.values()))
    loss_t.note = ("a delta frame needs its predecessor, so after a loss the compressed stream holds until the next key "
                   "frame (about key/2 frames per loss); on lossy links send plain or lower --key-interval")

    enc_t = Table("Stream coder speed per frame (key interval 30, truth track 'default')",
                  ["operation", "runs", "median µs", "min–max µs"])  # fmt: skip
    enc = StreamEncoder(30)
    coded = compress_frames(sample, 30)
    dec = StreamDecoder()
    for name, timing in (("encode", time_each(enc.encode, sample)),
                         ("decode", time_each(lambda kp: dec.decode(*kp), coded, warmup=0))):  # fmt: skip
        us = [1000.0 * v for v in timing.samples_ms]
        enc_t.add(name, str(len(us)), f"{np.median(us):.1f}", f"{min(us):.1f}–{max(us):.1f}")
    enc_t.note = "pure Python; decoding must see every frame in order, so it is not warmed up"
    return [t, loss_t, enc_t]
