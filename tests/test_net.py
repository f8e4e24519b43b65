"""UDP sender/receiver: loopback, fuzzing the packet handler, loss/reorder, hold and ease, CLI."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.net import (
    HELLO_SIZE,
    Hello,
    NetError,
    Receiver,
    Sender,
    UdpReceiver,
    check_port,
    parse_address,
)
from tracker.params import FaceParams, ParamCodec, encode_packet
from tracker.stream_codec import StreamEncoder, encode_stream_packet

FRAME = (640, 480)
IPD = 80.0
NEUTRAL = FaceParams(
    mid_x=320, mid_y=220, eye_open_l=14, eye_open_r=15, brow_l=30, brow_r=31, mouth_width=62, lip_upper=7, lip_lower=10
)  # fmt: skip


def track(n: int, seed: int = 0) -> list[FaceParams]:
    rng = np.random.default_rng(seed)
    t = np.arange(n)[:, None]
    base = NEUTRAL.values()
    wave = np.sin(t / 9.0 + rng.uniform(0, 6, 10)) * np.array([20, 10, 5, 3, 3, 3, 3, 6, 3, 8])
    return [FaceParams.from_values(base + wave[i] + rng.normal(0, 0.3, 10), frame=i, time=i / 30) for i in range(n)]


def codes_of(rows):
    codec = ParamCodec(FRAME, IPD)
    return [codec.encode(r) for r in rows]


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


@pytest.mark.parametrize("compress", [False, True])
def test_loopback_send_receive(compress):
    rows = track(60)
    with UdpReceiver(0) as rx, Sender(("127.0.0.1", rx.address[1]), FRAME, IPD, compress=compress, neutral=NEUTRAL) as tx:
        got = []
        deadline = time.monotonic() + 10.0
        for r in rows:
            tx.send(r)
            got += rx.poll(0.0)
        while len(got) < len(rows) and time.monotonic() < deadline:
            got += rx.poll(0.05)
    # loopback may in principle drop a datagram; whatever arrives must be exact and counted
    assert len(got) >= len(rows) - 3
    assert rx.stats.frames == len(got) and rx.stats.malformed == 0 and rx.stats.foreign == 0
    want = dict(zip(range(len(rows)), codes_of(rows)))
    codec = ParamCodec(FRAME, IPD)
    for f in got:
        assert codec.encode(f) == want[f.frame]
        assert abs(f.time - rows[f.frame].time) < 1e-3
    assert rx.neutral is not None and codec.encode(rx.neutral) == codec.encode(NEUTRAL)
    assert rx.stats.bits_per_frame == pytest.approx(tx.stats.payload_bits_per_frame, rel=0.2)
    if compress:
        assert rx.stats.bits_per_frame < 80
    else:
        assert rx.stats.bits_per_frame == 80
    assert rx.stats.bits_per_second > 0 and rx.stats.mean_bits_per_second > 0


def _packets(compress: bool, n: int = 40) -> tuple[bytes, list[bytes]]:
    hello = Hello(7, FRAME, IPD, compressed=compress).encode()
    enc = StreamEncoder(10)
    out = []
    for i, c in enumerate(codes_of(track(n, seed=2))):
        out.append(encode_stream_packet(*enc.encode(c), i, 33 * i) if compress else encode_packet(c, i, 33 * i))
    return hello, out


def test_loss_duplicates_and_reordering_are_counted():
    clock = Clock()
    rx = Receiver(clock=clock)
    hello, pk = _packets(False)
    assert rx.handle(pk[0], "A") is None and rx.stats.waiting == 1  # no hello yet
    rx.handle(hello, "A")
    order = [0, 1, 2, 5, 3, 6, 6, 7, 4, 9]  # 3, 4 arrive late, 6 twice, 8 never
    got = [rx.handle(pk[i], "A") for i in order]
    delivered = [f.frame for f in got if f is not None]
    assert delivered == [0, 1, 2, 5, 6, 7, 9]
    s = rx.stats
    assert (s.late, s.duplicates, s.lost, s.frames) == (2, 1, 1, 7)


def test_compressed_stream_waits_for_key_frame_after_loss():
    rx = Receiver(clock=Clock())
    hello, pk = _packets(True)
    rx.handle(hello, "A")
    want = codes_of(track(40, seed=2))
    codec = ParamCodec(FRAME, IPD)
    out = {}
    for i, p in enumerate(pk):
        if i == 13:
            continue  # lost: frames 14..19 cannot be decoded, 20 is the next key frame
        f = rx.handle(p, "A")
        if f is not None:
            out[f.frame] = codec.encode(f)
    assert sorted(out) == [i for i in range(40) if not 13 <= i < 20]
    assert all(out[i] == want[i] for i in out)
    assert rx.stats.lost == 1 and rx.stats.waiting == 6


def test_foreign_sender_and_session_restart():
    clock = Clock()
    rx = Receiver(clock=clock, switch_after_s=2.0)
    hello, pk = _packets(False)
    rx.handle(hello, "A")
    rx.handle(pk[0], "A")
    assert rx.handle(pk[1], "B") is None and rx.stats.foreign == 1
    rx.handle(Hello(8, FRAME, IPD).encode(), "B")
    assert rx.stats.foreign == 2 and rx.sender == "A"
    clock.t += 3.0  # A went quiet: B may take over
    rx.handle(Hello(8, FRAME, IPD).encode(), "B")
    assert rx.sender == "B" and rx.stats.sessions == 2
    assert rx.handle(pk[0], "B") is not None  # a new session starts its own sequence


def test_holds_then_eases_to_neutral():
    clock = Clock()
    rx = Receiver(hold_s=0.5, ease_s=1.0, clock=clock)
    codec = ParamCodec(FRAME, IPD)
    rx.handle(Hello(1, FRAME, IPD, neutral_codes=codec.encode(NEUTRAL)).encode(), "A")
    far = NEUTRAL.replace(mid_x=500.0, eye_open_l=2.0)
    last = rx.handle(encode_packet(codec.encode(far), 0, 0), "A")
    assert rx.pose() is last
    clock.t += 0.4
    held = rx.pose()
    assert np.array_equal(held.values(), last.values()) and held.status == last.status
    assert held.time == pytest.approx(last.time + 0.4)  # time moves on while the pose is held
    clock.t += 0.6  # halfway through the ease
    mid = rx.pose()
    assert mid.status == "lost" and 0 < mid.confidence < 1
    assert NEUTRAL.mid_x < mid.mid_x < last.mid_x
    clock.t += 1.0
    end = rx.pose()
    assert np.allclose(end.values(), codec.decode(codec.encode(NEUTRAL)).values()) and end.confidence == 0


def test_undecodable_packets_hold_the_pose_instead_of_easing():
    clock = Clock()
    rx = Receiver(hold_s=0.5, ease_s=1.0, clock=clock)
    hello, pk = _packets(True, n=40)  # key frames every 10
    rx.handle(hello, "A")
    for i in range(3):
        rx.handle(pk[i], "A")
        clock.t += 0.1
    last = rx.last_frame
    for i in range(4, 10):  # 3 is lost: 4..9 wait for the key frame at 10
        assert rx.handle(pk[i], "A") is None
        clock.t += 0.2
    held = rx.pose()
    assert held.status == last.status and np.array_equal(held.values(), last.values())
    assert rx.handle(pk[10], "A") is not None
    clock.t += 2.0  # now the stream really stopped
    assert rx.pose().status == "lost" and rx.pose().confidence == 0.0


def test_gap_poses_keep_the_senders_rate_then_rest():
    clock = Clock()
    rx = Receiver(hold_s=0.5, ease_s=1.0, clock=clock)
    codec = ParamCodec(FRAME, IPD)
    rx.handle(Hello(1, FRAME, IPD, fps=10.0, neutral_codes=codec.encode(NEUTRAL)).encode(), "A")
    assert rx.gap_poses() == []  # nothing received yet
    rx.handle(encode_packet(codec.encode(NEUTRAL.replace(mid_x=500.0)), 0, 0), "A")
    clock.t += 0.12
    assert rx.gap_poses() == []  # the next frame is not late yet (1.5 periods)
    clock.t += 0.04
    assert len(rx.gap_poses()) == 1  # one frame period overdue: the held pose
    clock.t += 5.0
    poses = rx.gap_poses()
    assert poses[-1].confidence == 0.0 and poses[-1].status == "lost"
    assert 13 <= len(poses) <= 16  # 0.5 s hold + 1 s ease at 10 fps, then rest
    xs = [p.mid_x for p in poses]
    assert all(a >= b for a, b in zip(xs, xs[1:]))
    clock.t += 1.0
    assert rx.gap_poses() == []  # at rest
    rx.handle(encode_packet(codec.encode(NEUTRAL), 1, 100), "A")
    clock.t += 0.2
    assert len(rx.gap_poses()) == 1  # a new gap starts counting again


def _mutations(base: list[bytes]):
    return st.tuples(
        st.sampled_from(base),
        st.lists(st.tuples(st.integers(0, 40), st.integers(0, 255)), max_size=4),
        st.integers(-3, 3),
    ).map(_mutate)


def _mutate(args) -> bytes:
    data, flips, cut = args
    b = bytearray(data)
    for pos, val in flips:
        if pos < len(b):
            b[pos] = val
    if cut < 0:
        b = b[:cut]
    elif cut > 0:
        b += bytes(cut)
    return bytes(b)


_HELLO_C, _PK_C = _packets(True)
_HELLO_P, _PK_P = _packets(False)
_ALL = [_HELLO_C, _HELLO_P] + _PK_C + _PK_P


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    datagrams=st.lists(
        st.one_of(st.binary(max_size=64), _mutations(_ALL), st.sampled_from(_ALL)), min_size=1, max_size=30
    ),
    senders=st.lists(st.sampled_from(["A", "B", None]), min_size=30, max_size=30),
)
def test_fuzzed_datagrams_never_raise_and_are_all_counted(datagrams, senders):
    clock = Clock()
    rx = Receiver(clock=clock)
    for i, d in enumerate(datagrams):
        clock.t += 0.01
        f = rx.handle(d, senders[i])
        assert f is None or (isinstance(f, FaceParams) and np.all(np.isfinite(f.values())))
        rx.pose()
        rx.update_rates()
    s = rx.stats
    assert s.datagrams == len(datagrams)
    assert s.frames + s.hellos + s.malformed + s.foreign + s.duplicates + s.late + s.waiting + s.anomalies == s.datagrams


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(st.binary(max_size=80), _mutations(_ALL)))
def test_packet_parsers_give_their_own_error_or_a_valid_object(data):
    from tracker.params import PACKET_SIZE, Packet, PacketError, decode_packet
    from tracker.stream_codec import StreamError, StreamPacket, decode_stream_packet

    for parse, error, kind in ((decode_packet, PacketError, Packet), (decode_stream_packet, StreamError, StreamPacket),
                               (Hello.decode, PacketError, Hello)):  # fmt: skip
        try:
            got = parse(data)
        except error as e:
            assert str(e) and "\n" not in str(e)
            continue
        assert isinstance(got, kind)
        if kind is Hello:
            assert got.frame_size[0] > 0 and got.ipd > 0 and np.isfinite(got.ipd) and got.fps > 0
        elif kind is Packet:
            assert len(data) == PACKET_SIZE and len(got.payload) == 10


@settings(max_examples=100, deadline=None)
@given(order=st.permutations(range(40)), drop=st.sets(st.integers(0, 39), max_size=8),
       dup=st.lists(st.integers(0, 39), max_size=5), compress=st.booleans())  # fmt: skip
def test_any_arrival_order_decodes_only_exact_frames(order, drop, dup, compress):
    hello, pk = _HELLO_C if compress else _HELLO_P, _PK_C if compress else _PK_P
    want = codes_of(track(40, seed=2))
    codec = ParamCodec(FRAME, IPD)
    rx = Receiver(clock=Clock())
    rx.handle(hello, "A")
    seen = set()
    for i in [i for i in order if i not in drop] + dup:
        f = rx.handle(pk[i], "A")
        if f is not None:
            assert codec.encode(f) == want[f.frame]
            assert f.frame not in seen  # never the same frame twice
            seen.add(f.frame)
    s = rx.stats
    assert s.frames == len(seen)
    assert s.frames + s.duplicates + s.late + s.waiting + s.anomalies == s.datagrams - 1


def test_hello_round_trip_and_size():
    h = Hello(123, (1920, 1080), 96.5, fps=29.97, compressed=True, key_interval=60, neutral_codes=bytes(range(10)))
    assert Hello.decode(h.encode()) == h
    assert len(h.encode()) == HELLO_SIZE


@pytest.mark.parametrize(
    "text, message",
    [("localhost", "HOST:PORT"), ("127.0.0.1:http", "not a number"), ("127.0.0.1:70000", "out of range"),
     ("127.0.0.1:0", "out of range"), (":9000", "no host")],
)  # fmt: skip
def test_bad_addresses(text, message):
    with pytest.raises(NetError, match=message):
        parse_address(text)


def test_good_addresses():
    assert parse_address("127.0.0.1:9000") == ("127.0.0.1", 9000)
    assert parse_address("[::1]:9000") == ("::1", 9000)
    assert check_port("0") == 0


def _cli(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "app", *args], capture_output=True, text=True, timeout=timeout, cwd=None
    )


@pytest.mark.parametrize(
    "args, message",
    [
        (["send", "--to", "nowhere", "--params", "x.csv"], "HOST:PORT"),
        (["send", "--to", "127.0.0.1:99999", "--params", "x.csv"], "out of range"),
        (["receive", "--port", "-5", "--frames", "1"], "out of range"),
        (["receive", "--port", "abc", "--frames", "1"], "not a number"),
        (["receive", "--port", "0", "--art", "no-such-character", "--frames", "1"], "no-such-character"),
        (["send", "--to", "127.0.0.1:9", "--params", "x.csv", "--frame-size", "big"], "WxH"),
    ],
)
def test_cli_bad_address_or_port_is_one_line(args, message, capsys):
    from app.cli import run

    assert run(args) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("inkface: ") and message in lines[0], lines


def test_cli_send_track_to_receive_csv(tmp_path):
    from tracker.params import read_csv, write_csv

    rows = track(45, seed=4)
    src = tmp_path / "in.csv"
    write_csv(src, rows)
    out = tmp_path / "out.csv"
    with UdpReceiver(0) as probe:  # find a free port, then hand it to the receiving process
        port = probe.address[1]
    rx = subprocess.Popen(
        [sys.executable, "-m", "app", "receive", "--port", str(port), "--csv", str(out), "--frames", "45", "--timeout", "20"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        time.sleep(1.0)
        r = _cli("send", "--to", f"127.0.0.1:{port}", "--params", str(src), "--compress", "--fps", "120")
        assert r.returncode == 0, r.stderr
        _, err = rx.communicate(timeout=30)
    finally:
        rx.kill()
    assert rx.returncode == 0, err
    got = read_csv(out)
    assert len(got) >= 40
    codec = ParamCodec(FRAME, IPD)
    want = {r.frame: r for r in rows}
    for g in got:
        assert np.allclose(g.values(), want[g.frame].values(), atol=codec.step().max())


def _send_in_process(argv: list[str], port: int) -> tuple[int, list[FaceParams], UdpReceiver]:
    """Run ``python -m app send ...`` in this process against a receiver of the test's own."""
    from app.cli import run

    with UdpReceiver(port) as rx:
        rc = run(["send", "--to", f"127.0.0.1:{rx.address[1]}", "--quiet", *argv])
        got: list[FaceParams] = []
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            new = rx.poll(0.2)
            if not new and got:
                break
            got += new
    return rc, got, rx


def test_replay_csv_then_recorded_stream_then_fap(tmp_path):
    from tracker.fap import write_fap
    from tracker.params import write_csv

    rows = track(40, seed=6)
    src = tmp_path / "in.csv"
    write_csv(src, rows)
    rec = tmp_path / "sent.ifs"
    args = ["--params", str(src), "--ipd", "80", "--frame-size", "640x480", "--fps", "200", "--compress"]
    rc, got1, rx = _send_in_process(args + ["--record", str(rec)], 0)
    assert rc == 0 and len(got1) >= 38
    assert rx.hello.compressed and rx.hello.ipd == IPD
    codec = ParamCodec(FRAME, IPD)
    # the recorded stream replays to the same codes, plain this time
    rc, got2, _ = _send_in_process(["--params", str(rec), "--fps", "200"], 0)
    assert rc == 0 and len(got2) >= 38
    first = {f.frame: codec.encode(f) for f in got1}
    assert all(codec.encode(f) == first[f.frame] for f in got2 if f.frame in first)
    fap = tmp_path / "take.fap"
    write_fap(fap, rows, NEUTRAL, IPD, fps=30)
    rc, got3, _ = _send_in_process(["--params", str(fap), "--fps", "200"], 0)
    assert rc == 0 and len(got3) >= 38
    f = got3[5]
    assert abs(f.mouth_width - rows[5].mouth_width) < 1.0 and abs(f.roll_deg - rows[5].roll_deg) < 0.5


def test_cli_track_errors_are_one_line(tmp_path, capsys):
    from app.cli import run

    bad = tmp_path / "bad.csv"
    bad.write_text("not,a,track\n")
    assert run(["send", "--to", "127.0.0.1:9", "--params", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.csv" in err[0]
    assert run(["send", "--to", "127.0.0.1:9", "--params", str(tmp_path / "none.ifs")]) == 2
    assert "none.ifs" in capsys.readouterr().err
    assert run(["send", "--to", "127.0.0.1:9", "--video", str(tmp_path / "none.avi")]) == 2
    assert "none.avi" in capsys.readouterr().err


def test_send_video_through_the_tracker(tmp_path):
    pytest.importorskip("tracker.face_tracker")
    from tracker.synthetic import Performance

    perf = Performance(seconds=1.0, seed=3)
    video = tmp_path / "clip.avi"
    perf.write(video)
    rc, got, rx = _send_in_process(["--video", str(video), "--fps", "200"], 0)
    assert rc == 0 and len(got) >= len(perf) - 2
    assert rx.neutral is not None
    truth = perf.truth(10)
    f = next(g for g in got if g.frame == 10)
    assert abs(f.mid_x - truth.mid_x) < 3 and abs(f.mid_y - truth.mid_y) < 3


def test_send_auto_starts_where_a_late_face_comes(tmp_path):
    """``--auto`` on a clip that opens on an empty wall: the start is where the face first shows, and
    the whole clip is sent from its first frame."""
    pytest.importorskip("tracker.face_tracker")
    from late_face import write_late_face_clip
    from tracker.synthetic import Performance

    video = tmp_path / "late.avi"
    perf = write_late_face_clip(video, 20, Performance(seconds=0.5, seed=3))
    rc, got, rx = _send_in_process(["--video", str(video), "--auto", "--fps", "200"], 0)
    assert rc == 0 and len(got) >= 20 + len(perf) - 2
    truth = perf.truth(10)
    f = next(g for g in got if g.frame == 30)
    assert abs(f.mid_x - truth.mid_x) < 3 and abs(f.mid_y - truth.mid_y) < 3


def test_unmeasured_values_travel_as_the_last_value_sent():
    with UdpReceiver(0) as rx, Sender(("127.0.0.1", rx.address[1]), FRAME, IPD, neutral=NEUTRAL) as tx:
        rows = track(3)
        rows[1] = rows[1].replace(mouth_width=float("nan"), lip_lower=float("nan"), status="mouth_lost")
        for r in rows:
            tx.send(r)
        got: list[FaceParams] = []
        deadline = time.monotonic() + 5
        while len(got) < 3 and time.monotonic() < deadline:
            got += rx.poll(0.05)
    codec = ParamCodec(FRAME, IPD)
    by = {f.frame: f for f in got}
    assert 0 in by and 1 in by  # three datagrams on loopback
    assert by[1].status == "mouth_lost"
    assert by[1].mouth_width == by[0].mouth_width and by[1].lip_lower == by[0].lip_lower
    assert codec.encode(by[1].replace(mouth_width=0, lip_lower=0)) != codec.encode(by[0].replace(mouth_width=0, lip_lower=0))


@pytest.mark.slow
def test_cli_receive_draws_the_character(tmp_path):
    pytest.importorskip("training.puppet")
    import cv2

    from art_sets.library import list_bundled

    bundled = list_bundled()
    if not bundled:
        pytest.skip("no bundled character")
    out = tmp_path / "rx.mp4"
    with UdpReceiver(0) as probe:
        port = probe.address[1]
    rx = subprocess.Popen(
        [sys.executable, "-m", "app", "receive", "--port", str(port), "--art", str(bundled[0][1]), "--out", str(out),
         "--frames", "20", "--timeout", "20", "--wait", "60", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        # the receiver loads the character before it listens; keep sending until it has 20 frames
        with Sender(("127.0.0.1", port), FRAME, IPD, neutral=NEUTRAL, compress=True) as tx:
            rows = track(600, seed=8)
            for r in rows:
                tx.send(r)
                time.sleep(1 / 30)
                if rx.poll() is not None:
                    break
        out_text, err = rx.communicate(timeout=60)
    finally:
        rx.kill()
    assert rx.returncode == 0, err
    assert "(20 frames)" in out_text and "0 malformed" in out_text
    cap = cv2.VideoCapture(str(out))
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    ok, img = cap.read()
    cap.release()
    assert ok and n >= 20
    assert img.std() > 10  # a drawing, not a blank page


def test_loopback_with_simulated_loss_recovers_at_key_frames():
    rows = track(120, seed=11)
    want = codes_of(rows)
    codec = ParamCodec(FRAME, IPD)
    with UdpReceiver(0) as rx, Sender(("127.0.0.1", rx.address[1]), FRAME, IPD, compress=True, key_interval=10,
                                      simulate_loss=0.1, seed=5) as tx:  # fmt: skip
        got = []
        for r in rows:
            tx.send(r)
            got += rx.poll(0.0)
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            new = rx.poll(0.1)
            got += new
            if not new and rx.stats.datagrams >= tx.stats.frames - tx.stats.dropped + tx.stats.hellos:
                break
    s = rx.stats
    assert tx.stats.dropped > 0 and s.lost > 0 and s.waiting > 0
    assert all(codec.encode(f) == want[f.frame] for f in got)  # whatever decodes is exact
    assert s.late == s.duplicates == 0  # loopback keeps order
    assert s.frames + s.waiting + s.lost == rx.last_seq + 1  # every sequence number accounted for
    assert len(got) > 60
