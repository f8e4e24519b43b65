"""The parameter record: CSV round trip, 8-bit codec, packet framing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tracker.params import (
    CSV_COLUMNS,
    PACKET_SIZE,
    PARAM_NAMES,
    FaceParams,
    PacketError,
    ParamCodec,
    TrackFormatError,
    decode_packet,
    encode_packet,
    read_csv,
    write_csv,
)

SIZES = st.tuples(st.integers(32, 4096), st.integers(32, 4096))


@settings(max_examples=200, deadline=None)
@given(size=SIZES, ipd=st.floats(8, 600), codes=st.lists(st.floats(0, 1), min_size=10, max_size=10))
def test_codec_round_trip_within_half_a_step(size, ipd, codes):
    codec = ParamCodec(size, ipd)
    lo, hi = codec.dequantise(np.zeros(10)), codec.dequantise(np.full(10, 255))
    vals = lo + np.array(codes) * (hi - lo)
    back = codec.decode(codec.encode(FaceParams.from_values(vals))).values()
    assert np.all(np.abs(back - vals) <= codec.step() / 2 + 1e-9)


def test_codec_clips_out_of_range_and_nan():
    codec = ParamCodec((640, 480), 80)
    p = FaceParams.from_values([-50, 1e6, 90, 0, float("nan"), 0, 0, 0, 0, 0])
    codes = np.frombuffer(codec.encode(p), np.uint8)
    assert codes[0] == 0 and codes[1] == 255 and codes[2] == 255 and codes[4] == 0


def test_codec_units():
    codec = ParamCodec((640, 480), 80)
    # positions as a fraction of the frame, lengths as a fraction of the inter-pupil distance
    assert codec.step()[0] == pytest.approx(640 / 255)
    assert codec.step()[1] == pytest.approx(480 / 255)
    assert codec.step()[7] == pytest.approx(1.6 * 80 / 255)


@given(seq=st.integers(0, 2**32 - 1), ts=st.integers(0, 2**32 - 1), payload=st.binary(min_size=10, max_size=10),
       status=st.sampled_from(["ok", "eyes_closed", "mouth_lost", "lost"]))
def test_packet_round_trip(seq, ts, payload, status):
    pkt = decode_packet(encode_packet(payload, seq, ts, status))
    assert (pkt.seq, pkt.timestamp_ms, pkt.payload, pkt.status) == (seq, ts, payload, status)


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda b: b[:-1], "bytes"),
        (lambda b: b + b"\0", "bytes"),
        (lambda b: b"", "bytes"),
        (lambda b: b"XX" + b[2:], "magic"),
        (lambda b: b[:2] + bytes([9]) + b[3:], "version"),
        (lambda b: b[:3] + bytes([200]) + b[4:], "status"),
    ],
)
def test_packet_rejects_bad_packets(mutate, message):
    good = encode_packet(bytes(10), 5, 100)
    assert len(good) == PACKET_SIZE
    with pytest.raises(PacketError, match=message):
        decode_packet(mutate(good))


@settings(max_examples=50, deadline=None)
@given(st.lists(st.lists(st.floats(-1000, 1000, allow_nan=False), min_size=10, max_size=10), min_size=0, max_size=20))
def test_csv_round_trip(tmp_path_factory, rows):
    path = tmp_path_factory.mktemp("csv") / "t.csv"
    recs = [FaceParams.from_values(v, frame=i, time=i / 30, status="ok" if i % 3 else "lost", confidence=0.5)
            for i, v in enumerate(rows)]
    write_csv(path, recs)
    back = read_csv(path)
    assert [r.frame for r in back] == [r.frame for r in recs]
    assert [r.status for r in back] == [r.status for r in recs]
    for a, b in zip(back, recs):
        np.testing.assert_allclose(a.values(), b.values(), atol=1e-4)


def test_csv_header_is_the_contract(tmp_path):
    path = tmp_path / "t.csv"
    write_csv(path, [FaceParams(frame=3, mid_x=1.5)])
    header = path.read_text().splitlines()[0].split(",")
    assert tuple(header[:11]) == CSV_COLUMNS == ("frame",) + PARAM_NAMES
    assert header[11:] == ["time", "status", "confidence"]


def test_csv_reads_contract_only_columns(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text(",".join(CSV_COLUMNS) + "\n0,1,2,3,4,5,6,7,8,9,10\n")
    (r,) = read_csv(path)
    assert r.values().tolist() == list(range(1, 11)) and r.status == "ok"


@pytest.mark.parametrize("text, message", [("", "empty"), ("a,b\n", "header"),
                                           (",".join(CSV_COLUMNS) + "\n0,1,2\n", "columns"),
                                           (",".join(CSV_COLUMNS) + "\n0,x,2,3,4,5,6,7,8,9,10\n", "number")])
def test_csv_errors_name_the_file(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(TrackFormatError, match=message) as e:
        read_csv(path)
    assert "bad.csv" in str(e.value) and "\n" not in str(e.value)


def test_csv_missing_file(tmp_path):
    with pytest.raises(TrackFormatError, match="nope.csv"):
        read_csv(tmp_path / "nope.csv")
