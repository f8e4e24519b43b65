"""Temporal compression of the 8-bit stream: exact round trip, recovery after loss, the file."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tracker.params import FaceParams, ParamCodec, encode_packet
from tracker.stream_codec import (
    StreamDecoder,
    StreamEncoder,
    StreamError,
    StreamHeader,
    compress_frames,
    decode_stream_packet,
    decompress_frames,
    encode_stream_packet,
    read_stream,
    read_track_stream,
    write_stream,
    write_track_stream,
)


def smooth_frames(n: int, seed: int, noise: float = 0.0, amp: float = 30.0) -> list[bytes]:
    """Slowly wandering codes with optional jitter, like a tracked face."""
    rng = np.random.default_rng(seed)
    walk = np.cumsum(rng.normal(0, 1, (n + 14, 10)), axis=0)
    walk = np.array([np.convolve(walk[:, c], np.ones(15) / 15, "valid") for c in range(10)]).T
    walk = walk - walk.mean(axis=0)
    x = 128 + amp * walk / (np.abs(walk).max(axis=0) + 1e-9) + rng.normal(0, noise, walk.shape)
    return [bytes(r) for r in np.clip(np.rint(x), 0, 255).astype(np.uint8)]


frames_st = st.lists(st.binary(min_size=10, max_size=10), min_size=1, max_size=60)


@settings(max_examples=100, deadline=None)
@given(frames=frames_st, key_interval=st.integers(1, 40))
def test_arbitrary_frames_round_trip_exactly(frames, key_interval):
    coded = compress_frames(frames, key_interval)
    assert decompress_frames(coded) == frames
    assert all(len(p) <= 10 for _, p in coded)
    assert [k for k, _ in coded][:: key_interval] == [True] * len(coded[::key_interval])


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    noise=st.sampled_from([0.0, 0.5, 2.0]),
    steps=st.lists(st.tuples(st.integers(0, 9), st.integers(-128, 127)), max_size=8),
)
def test_smooth_frames_with_jumps_round_trip(seed, noise, steps):
    frames = [bytearray(f) for f in smooth_frames(90, seed, noise)]
    rng = np.random.default_rng(seed)
    for c, d in steps:  # sudden jumps (blinks, lost tracking) including wrap-around
        i = int(rng.integers(0, len(frames)))
        for f in frames[i:]:
            f[c] = (f[c] + d) & 0xFF
    frames = [bytes(f) for f in frames]
    assert decompress_frames(compress_frames(frames, 30)) == frames


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), key_interval=st.integers(2, 20), lost=st.sets(st.integers(0, 79), max_size=12))
def test_lost_packets_recover_at_the_next_key_frame(seed, key_interval, lost):
    frames = smooth_frames(80, seed, noise=0.7)
    enc = StreamEncoder(key_interval)
    packets = [encode_stream_packet(*enc.encode(f), seq=i, timestamp_ms=33 * i) for i, f in enumerate(frames)]
    dec = StreamDecoder()
    missing_since: int | None = None
    for i, data in enumerate(packets):
        if i in lost:
            missing_since = i if missing_since is None else missing_since
            continue
        p = decode_stream_packet(data)
        out = dec.decode(p.key, p.payload, p.seq)
        if p.key:
            missing_since = None
        if missing_since is None:
            assert out == frames[i]  # decoded frames are always exact
        else:
            assert out is None  # never a wrong frame after a loss, only a wait for the key frame


def test_compresses_smooth_tracks_below_half_the_raw_rate():
    frames = smooth_frames(600, seed=3, noise=0.5)
    coded = compress_frames(frames, 30)
    bits = 8 * sum(len(p) for _, p in coded) / len(frames)
    assert bits < 40
    still = compress_frames([frames[0]] * 60, 30)
    assert sum(len(p) for k, p in still if not k) <= 2  # a still face costs (almost) nothing


def test_incompressible_frames_never_cost_more_than_raw():
    rng = np.random.default_rng(0)
    frames = [bytes(rng.integers(0, 256, 10, dtype=np.uint8)) for _ in range(100)]
    coded = compress_frames(frames, 50)
    assert max(len(p) for _, p in coded) == 10
    assert decompress_frames(coded) == frames


def test_reordered_delta_frame_waits_for_key():
    frames = smooth_frames(10, seed=1, noise=1.0)
    enc = StreamEncoder(5)
    coded = [enc.encode(f) for f in frames]
    dec = StreamDecoder()
    assert dec.decode(*coded[0], seq=0) == frames[0]
    assert dec.decode(*coded[2], seq=2) is None  # 1 is missing
    assert dec.decode(*coded[1], seq=1) is None  # late: the state moved on
    assert dec.decode(*coded[5], seq=5) == frames[5]
    assert dec.decode(*coded[6], seq=6) == frames[6]


@settings(max_examples=300, deadline=None)
@given(data=st.binary(max_size=40))
def test_decoder_never_crashes_on_garbage(data):
    dec = StreamDecoder()
    dec.decode(True, bytes(10), seq=0)
    try:
        p = decode_stream_packet(data)
        out = dec.decode(p.key, p.payload, p.seq)
    except StreamError:
        return
    assert out is None or len(out) == 10


def test_packet_errors_are_one_line():
    with pytest.raises(StreamError, match="too short"):
        decode_stream_packet(b"IZ")
    with pytest.raises(StreamError, match="magic"):
        decode_stream_packet(encode_packet(bytes(10), 1, 2))
    good = encode_stream_packet(False, b"\x01\x02", 7, 99, "eyes_closed")
    p = decode_stream_packet(good)
    assert (p.seq, p.timestamp_ms, p.status, p.key, p.payload) == (7, 99, "eyes_closed", False, b"\x01\x02")
    with pytest.raises(StreamError, match="version"):
        decode_stream_packet(good[:2] + b"\x09" + good[3:])
    with pytest.raises(StreamError, match="key frame"):
        decode_stream_packet(encode_stream_packet(True, bytes(10), 0, 0)[:-1])


@pytest.mark.parametrize("compressed", [True, False])
def test_track_stream_file_round_trip(tmp_path, compressed):
    codec = ParamCodec((640, 480), 80.0)
    codes = smooth_frames(70, seed=5, noise=0.5)
    rows = [codec.decode(c, frame=i, time=i / 30, status="ok" if i % 9 else "eyes_closed") for i, c in enumerate(codes)]
    path = tmp_path / "track.ifs"
    write_track_stream(path, rows, (640, 480), 80.0, fps=30, compressed=compressed, key_interval=25, neutral=rows[0])
    header, back = read_track_stream(path)
    assert header.frame_size == (640, 480) and header.ipd == 80.0 and header.compressed == compressed
    assert header.neutral == list(codes[0])
    assert len(back) == len(rows)
    for a, b in zip(rows, back):
        assert codec.encode(a) == codec.encode(b)
        assert np.allclose(a.values(), b.values())
        assert a.status == b.status and a.frame == b.frame and abs(a.time - b.time) < 1e-3
    assert isinstance(back[0], FaceParams)


def test_stream_file_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.ifs"
    bad.write_bytes(b"hello")
    with pytest.raises(StreamError, match="bad.ifs"):
        read_stream(bad)
    with pytest.raises(StreamError, match="missing.ifs"):
        read_stream(tmp_path / "missing.ifs")
    path = tmp_path / "cut.ifs"
    write_stream(path, StreamHeader((64, 48), 10.0), [b"abc", b"defg"])
    assert read_stream(path)[1] == [b"abc", b"defg"]
    path.write_bytes(path.read_bytes()[:-1])
    with pytest.raises(StreamError, match="truncated"):
        read_stream(path)
    hdr = tmp_path / "hdr.ifs"
    hdr.write_bytes(b'{"format": 1, "kind": "inkface-packet-stream", "frame_size": [0, 4], "ipd": 3}\n')
    with pytest.raises(StreamError, match="header"):
        read_stream(hdr)


def test_read_track_reads_all_three_formats(tmp_path):
    from tracker.fap import write_fap
    from tracker.params import write_csv
    from tracker.stream_codec import read_track

    codec = ParamCodec((640, 480), 80.0)
    rows = [codec.decode(c, frame=i, time=i / 25) for i, c in enumerate(smooth_frames(30, seed=9, noise=0.5))]
    write_csv(tmp_path / "t.csv", rows)
    write_track_stream(tmp_path / "t.ifs", rows, (640, 480), 80.0, fps=25, neutral=rows[0])
    write_fap(tmp_path / "t.fap", rows, rows[0], 80.0, fps=25)
    csv_t, ifs_t, fap_t = (read_track(tmp_path / f"t.{ext}") for ext in ("csv", "ifs", "fap"))
    assert len(csv_t.rows) == len(ifs_t.rows) == len(fap_t.rows) == 30
    assert csv_t.ipd is None and ifs_t.ipd == 80.0 and fap_t.ipd == 80.0
    assert ifs_t.frame_size == (640, 480) and ifs_t.fps == 25 and fap_t.fps == 25
    assert np.allclose(ifs_t.rows[7].values(), rows[7].values())
    assert abs(fap_t.rows[7].mouth_width - rows[7].mouth_width) < 0.1
