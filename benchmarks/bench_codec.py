"""Parameter codec: encode/decode speed and worst round-trip error."""

from __future__ import annotations

import numpy as np

from benchmarks.harness import TIMING_COLUMNS, Table, benchmark, time_call
from tracker.params import FaceParams, ParamCodec, decode_packet, encode_packet


@benchmark("codec")
def run(ctx):
    codec = ParamCodec((640, 480), ipd=80.0)
    rng = np.random.default_rng(0)
    lo, hi = codec.dequantise(np.zeros(10)), codec.dequantise(np.full(10, 255))
    vals = rng.uniform(lo, hi, size=(2000, 10))
    rows = [FaceParams.from_values(v, frame=i) for i, v in enumerate(vals)]
    p = rows[0]
    t = Table("8-bit parameter codec (640×480, ipd 80 px)", ["operation"] + TIMING_COLUMNS)
    n = ctx.runs(2000, 50)
    t.add("encode 10 values + packet", *time_call(lambda: encode_packet(codec.encode(p), 1, 33), n).cells())
    pkt = encode_packet(codec.encode(p), 1, 33)
    t.add("decode packet + 10 values", *time_call(lambda: codec.decode(decode_packet(pkt).payload), n).cells())
    err = np.abs(np.array([codec.decode(codec.encode(r)).values() for r in rows]) - vals)
    worst = err.max(axis=0) / codec.step()
    t.note = f"worst round-trip error over {len(rows)} random frames: {worst.max():.3f} quantisation steps (bound 0.5)"
    return t
