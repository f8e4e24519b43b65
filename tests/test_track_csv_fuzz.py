"""The track-CSV parser under fuzzing: its own one-line error naming the file, or a valid track."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tracker.params import CSV_COLUMNS, PARAM_NAMES, STATUSES, VALUE_LIMIT, TrackFormatError, read_csv, write_csv

HEADER = ",".join(CSV_COLUMNS) + ",time,status,confidence"

_NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**6, 10**6).map(str),
    st.sampled_from(["1e300", "-1e300", "1e400", "nan", "NaN", "inf", "-Infinity", "9" * 5000, "1" * 400,
                     "0x10", "1_000", " 3 ", "", "3.5.1", "١٢", "1e-400", "+0", "-0.0"]),
)  # fmt: skip
_TOKENS = st.one_of(_NUMBERS, st.text(max_size=12), st.sampled_from(STATUSES), st.just('"a,b"'), st.just("\x00"))


def _row(tokens: list[str]) -> str:
    return ",".join(tokens)


_FILES = st.one_of(
    st.lists(st.lists(_TOKENS, min_size=0, max_size=16).map(_row), max_size=6).map(lambda rows: "\n".join([HEADER] + rows)),
    st.lists(st.lists(_NUMBERS, min_size=14, max_size=14).map(_row), max_size=6).map(lambda rows: "\n".join([HEADER] + rows)),
    st.text(max_size=300),
    st.binary(max_size=300).map(lambda b: b.decode("latin-1")),
)


def _valid(rows) -> None:
    for r in rows:
        assert isinstance(r.frame, int) and abs(r.frame) < 2**31
        for n in PARAM_NAMES:
            v = getattr(r, n)
            assert math.isnan(v) or abs(v) <= VALUE_LIMIT
        assert math.isfinite(r.time) and 0.0 <= r.confidence <= 1.0
        assert isinstance(r.status, str) and 0 < len(r.status) <= 32


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=_FILES)
def test_fuzzed_track_csv_gives_a_track_or_one_line_naming_the_file(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("fuzz") / "take.csv"
    path.write_bytes(text.encode("utf-8", errors="replace"))
    try:
        rows = read_csv(path)
    except TrackFormatError as e:
        msg = str(e)
        assert "\n" not in msg and msg.startswith(str(path)) and len(msg) < 400
        return
    _valid(rows)


@pytest.mark.parametrize("value, word", [("1e300", "out of range"), ("1e400", "out of range"), ("inf", "out of range"),
                                         ("9" * 5000, "too long"), ("abc", "not a number")])  # fmt: skip
def test_bad_values_are_named(tmp_path, value, word):
    path = tmp_path / "t.csv"
    path.write_text(HEADER + "\n" + ",".join(["0"] + ["1.0"] * 9 + [value, "0", "ok", "1"]) + "\n")
    with pytest.raises(TrackFormatError, match=rf"t\.csv:2: lip_lower .*{word}"):
        read_csv(path)


def test_what_we_write_we_read(tmp_path):
    from tracker.params import FaceParams

    rows = [FaceParams(frame=i, mid_x=1.5 * i, eye_open_l=math.nan, time=i / 30, confidence=0.5) for i in range(5)]
    write_csv(tmp_path / "t.csv", rows)
    back = read_csv(tmp_path / "t.csv")
    assert [r.frame for r in back] == list(range(5)) and all(math.isnan(r.eye_open_l) for r in back)
