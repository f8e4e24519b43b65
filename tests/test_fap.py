"""MPEG-4 FAP export/import: the mapped subset survives a round trip, the file reads cleanly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tracker.fap import (
    AU,
    EXPORTED,
    N_FAPS,
    Fapu,
    FapError,
    faps_to_params,
    generic_neutral,
    params_to_faps,
    read_fap,
    write_fap,
)
from tracker.params import PARAM_NAMES, FaceParams

IPD = 80.0
NEUTRAL = FaceParams(
    mid_x=320, mid_y=220, roll_deg=0, eye_open_l=14, eye_open_r=15, brow_l=30, brow_r=31,
    mouth_width=62, lip_upper=7, lip_lower=10,
)  # fmt: skip
MAPPED = [n for n in PARAM_NAMES if n not in ("mid_x", "mid_y")]


def tolerance(fapu: Fapu) -> dict[str, float]:
    """Half a unit of the FAP(s) carrying each value (two units for a value split over two FAPs)."""
    return {
        "roll_deg": math.degrees(AU),
        "eye_open_l": fapu.irisd,
        "eye_open_r": fapu.irisd,
        "brow_l": fapu.ens,
        "brow_r": fapu.ens,
        "mouth_width": fapu.mw,
        "lip_upper": fapu.mns,
        "lip_lower": fapu.mns,
    }


def track(n: int, seed: int) -> list[FaceParams]:
    rng = np.random.default_rng(seed)
    base = NEUTRAL.values()
    spread = np.array([40, 30, 20, 8, 8, 10, 10, 20, 10, 25])
    rows = []
    for i in range(n):
        v = base + rng.uniform(-1, 1, 10) * spread
        rows.append(FaceParams.from_values(v, frame=i, time=i / 30))
    return rows


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 10_000), mirrored=st.booleans())
def test_frame_round_trip_within_half_a_unit(seed, mirrored):
    fapu = Fapu.from_neutral(NEUTRAL, IPD)
    tol = tolerance(fapu)
    for p in track(5, seed):
        faps = params_to_faps(p, NEUTRAL, fapu, mirrored)
        assert set(faps) == set(EXPORTED)
        back = faps_to_params(faps, NEUTRAL, fapu, mirrored=mirrored)
        for n in MAPPED:
            assert abs(getattr(back, n) - getattr(p, n)) <= tol[n] * 0.5 + 1e-9, n
        assert (back.mid_x, back.mid_y) == (NEUTRAL.mid_x, NEUTRAL.mid_y)


def test_directions_follow_mpeg4():
    fapu = Fapu.from_neutral(NEUTRAL, IPD)
    # the image-right eye is the performer's left: closing it raises close_t_l_eyelid (19)
    shut = NEUTRAL.replace(eye_open_r=0.0, roll_deg=10.0, lip_lower=NEUTRAL.lip_lower + 20, brow_l=40)
    f = params_to_faps(shut, NEUTRAL, fapu)
    assert f[19] == round(15 / fapu.irisd) > 0
    assert f[20] == 0
    assert f[3] > 0 and f[52] == 0  # jaw opens downwards
    assert f[34] > 0 and f[33] == 0  # image-left brow = performer's right brow, raised
    assert f[50] == round(math.radians(10) / AU)
    assert params_to_faps(NEUTRAL, NEUTRAL, fapu) == {k: 0 for k in EXPORTED}
    assert params_to_faps(NEUTRAL.replace(status="lost"), NEUTRAL, fapu) == {}


def test_file_round_trip(tmp_path):
    rows = track(40, seed=1)
    rows[7] = rows[7].replace(status="lost")
    rows[12] = rows[12].replace(eye_open_l=float("nan"))
    path = tmp_path / "take.fap"
    fapu = write_fap(path, rows, NEUTRAL, IPD, fps=30, name="my take")
    text = path.read_text().splitlines()
    assert text[4] == "2.1 my_take 30 40"
    assert len(text[5].split()) == N_FAPS
    got = read_fap(path)
    assert got.fps == 30 and got.name == "my_take" and got.fapu == fapu
    assert len(got.rows) == 40
    tol = tolerance(got.fapu)
    for i, (a, b) in enumerate(zip(rows, got.rows)):
        assert b.frame == a.frame
        if i == 7:
            assert b.status == "lost"
            assert np.allclose(b.values(), got.rows[6].values())  # held
            continue
        for n in MAPPED:
            if i == 12 and n == "eye_open_l":
                assert b.eye_open_l == got.rows[11].eye_open_l  # missing FAP holds
                continue
            assert abs(getattr(a, n) - getattr(b, n)) <= tol[n] * 0.5 + 1e-6, (i, n)


def test_foreign_file_needs_a_neutral_face(tmp_path):
    path = tmp_path / "other.fap"
    mask = ["0"] * N_FAPS
    for i in (3, 6, 19, 21, 31, 35):
        mask[i - 1] = "1"
    path.write_text("2.1 other 25 1\n" + " ".join(mask) + "\n0 100 200 100 50 70 30\n")  # values in FAP order
    with pytest.raises(FapError, match="other.fap"):
        read_fap(path)
    neutral = generic_neutral((640, 480), IPD)
    fapu = Fapu.from_neutral(neutral, IPD)
    got = read_fap(path, neutral=neutral, fapu=fapu)
    p = got.rows[0]
    # performer's left eye = image-right: upper + lower lid close it together
    assert p.eye_open_r == pytest.approx(neutral.eye_open_r - 150 * fapu.irisd)
    assert p.eye_open_l == neutral.eye_open_l
    assert p.brow_r == pytest.approx(neutral.brow_r + 50 * fapu.ens)  # mean of inner and outer
    assert p.mouth_width == pytest.approx(neutral.mouth_width + 200 * fapu.mw)  # inner corner stands in
    assert p.lip_lower == pytest.approx(neutral.lip_lower + 100 * fapu.mns)


@pytest.mark.parametrize(
    "body, message",
    [
        ("", "empty"),
        ("2.1 x 30\n", "expected '2.1"),
        ("2.1 x 30 1\n" + "1 " * 3 + "\n0 1\n", "mask line"),
        ("2.1 x 30 1\n" + "0 " * 68 + "\n", "without its value line"),
        ("2.1 x 30 1\n" + "1 " + "0 " * 67 + "\n0 a\n", "integers"),
        ("2.1 x 30 1\n" + "1 " + "0 " * 67 + "\n0\n", "expected a frame number and 1 values"),
        ("2.1 x 30 2\n" + "0 " * 68 + "\n0\n", "header says 2 frames"),
    ],
)
def test_bad_files_give_one_line_errors(tmp_path, body, message):
    path = tmp_path / "bad.fap"
    write_fap(path, [], NEUTRAL, IPD)
    header = "\n".join(path.read_text().splitlines()[:4]) + "\n"
    path.write_text(header + body)
    with pytest.raises(FapError, match=message) as e:
        read_fap(path)
    assert "\n" not in str(e.value) and "bad.fap" in str(e.value)


def test_command_line_converts_both_ways(tmp_path, capsys):
    from tracker.fap import main
    from tracker.params import read_csv, write_csv

    rows = track(20, seed=3)
    src = tmp_path / "in.csv"
    write_csv(src, rows)
    assert main([str(src), str(tmp_path / "out.fap"), "--ipd", "80"]) == 0
    assert main([str(tmp_path / "out.fap"), str(tmp_path / "back.csv")]) == 0
    back = read_csv(tmp_path / "back.csv")
    assert len(back) == 20
    assert max(abs(a.mouth_width - b.mouth_width) for a, b in zip(rows, back)) < 0.05
    capsys.readouterr()
    assert main([str(tmp_path / "missing.csv"), str(tmp_path / "x.fap")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "missing.csv" in err[0]
