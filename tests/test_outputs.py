"""No command writes over its inputs, or over an existing file unless given ``--force``.

Every case checks three things: the exit code, a single ``inkface:`` line naming the path, and
that every file that was there before is byte-for-byte the same afterwards.
"""

import hashlib
import os
from pathlib import Path

import numpy as np
import pytest

from app.cli import run as app_cli
from art_sets.library import list_bundled
from tracker.__main__ import main as tracker_cli
from tracker.outputs import OutputError, check_outputs, free_name
from tracker.synthetic import Performance

N = 12


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    d = tmp_path_factory.mktemp("clip")
    video, truth = d / "v.mp4", d / "v.truth.csv"
    Performance(seconds=N / 30.0, seed=3).write(video, truth)
    return video, truth, d / "v.clicks.json"


@pytest.fixture(scope="module")
def art():
    return list_bundled()[0][0]


def _digest(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}  # fmt: skip


def _one_line(capsys, *words: str) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    err = [e for e in err if e.startswith("inkface:")]
    assert len(err) == 1, err
    for w in words:
        assert w in err[0], err
    return err[0]


def _work(tmp_path, clip) -> tuple[Path, Path, Path]:
    """A private copy of the clip, its truth track and clicks (the commands must not touch them)."""
    video, truth, clicks = clip
    out = []
    for p in (video, truth, clicks):
        q = tmp_path / p.name
        q.write_bytes(p.read_bytes())
        out.append(q)
    return out[0], out[1], out[2]


@pytest.mark.parametrize("case", ["csv=video", "csv=clicks", "calibration=video", "csv is a folder",
                                  "csv exists", "calibration picture exists", "overlay not empty",
                                  "same csv twice", "name too long"])  # fmt: skip
def test_track_never_writes_over_inputs_or_existing_files(clip, tmp_path, capsys, case):
    video, _, clicks = _work(tmp_path, clip)
    args = ["track", str(video), "--init", str(clicks), "--quiet"]
    named = {
        "csv=video": (["--csv", str(video), "--force"], video.name),
        "csv=clicks": (["--csv", str(clicks), "--force"], clicks.name),
        "calibration=video": (["--csv", str(tmp_path / "t.csv"), "--calibration", str(video), "--force"], video.name),
        "csv is a folder": (["--csv", str(tmp_path)], "is a folder"),
        "csv exists": (["--csv", str(tmp_path / "old.csv")], "old.csv"),
        "calibration picture exists": (["--csv", str(tmp_path / "t.csv"), "--calibration", str(tmp_path / "cal.json")],
                                       "cal.eye_l.png"),
        "overlay not empty": (["--csv", str(tmp_path / "t.csv"), "--overlay", str(tmp_path / "ov")], "not empty"),
        "same csv twice": (["--csv", str(tmp_path / "t.csv"), "--calibration", str(tmp_path / "t.csv")], "two outputs"),
        "name too long": (["--csv", str(tmp_path / ("x" * 300 + ".csv"))], "too long"),
    }
    extra, word = named[case]
    (tmp_path / "old.csv").write_text("keep me\n")
    (tmp_path / "cal.eye_l.png").write_bytes(b"someone's picture")
    (tmp_path / "ov").mkdir()
    (tmp_path / "ov" / "mine.png").write_bytes(b"x")
    before = _digest(tmp_path)
    assert tracker_cli(args + extra) == 2
    _one_line(capsys, word)
    assert _digest(tmp_path) == before
    assert not list(tmp_path.glob(".*"))  # no temporary left behind


def test_track_force_replaces_an_output_and_streams_one_row_per_frame(clip, tmp_path, capsys):
    from tracker.params import read_csv

    video, _, clicks = _work(tmp_path, clip)
    out = tmp_path / "t.csv"
    out.write_text("old\n")
    assert tracker_cli(["track", str(video), "--init", str(clicks), "--csv", str(out), "--quiet", "--force"]) == 0
    rows = read_csv(out)
    assert [r.frame for r in rows] == list(range(N))


def test_synth_refuses_existing_files(tmp_path, capsys):
    clip = tmp_path / "s.mp4"
    (tmp_path / "s.clicks.json").write_text("{}")
    before = _digest(tmp_path)
    assert tracker_cli(["synth", "--out", str(clip), "--seconds", "0.2", "--quiet"]) == 2
    _one_line(capsys, "s.clicks.json", "--force")
    assert _digest(tmp_path) == before
    assert tracker_cli(["synth", "--out", str(clip), "--seconds", "0.2", "--quiet", "--force"]) == 0
    assert clip.is_file() and (tmp_path / "s.clicks.json").read_text() != "{}"


def test_render_never_writes_over_its_input(clip, art, tmp_path, capsys):
    video, truth, clicks = _work(tmp_path, clip)
    before = _digest(tmp_path)
    assert app_cli(["render", "--video", str(video), "--art", art, "--out", str(video), "--force"]) == 2
    _one_line(capsys, video.name, "input")
    link = tmp_path / "link.mp4"
    os.symlink(video, link)
    assert app_cli(["render", "--video", str(video), "--art", art, "--out", str(link), "--force"]) == 2
    _one_line(capsys, "input")
    link.unlink()
    assert _digest(tmp_path) == before


def test_render_replaces_an_existing_output_only_with_force(clip, art, tmp_path, capsys):
    _, truth, _ = _work(tmp_path, clip)
    out = tmp_path / "r.gif"
    out.write_bytes(b"my old gif")
    args = ["render", "--params", str(truth), "--art", art, "--out", str(out), "--max-frames", "2"]
    assert app_cli(args) == 2
    _one_line(capsys, "r.gif", "--force")
    assert out.read_bytes() == b"my old gif"
    assert app_cli(args + ["--force"]) == 0
    assert out.read_bytes()[:6] == b"GIF89a"


def test_png_folder_must_be_new_or_empty_and_force_leaves_no_stale_frames(clip, art, tmp_path, capsys):
    _, truth, _ = _work(tmp_path, clip)
    folder = tmp_path / "frames"
    base = ["render", "--params", str(truth), "--art", art, "--out", str(folder)]
    assert app_cli(base + ["--max-frames", "10"]) == 0
    assert len(list(folder.glob("frame_*.png"))) == 10
    (folder / "notes.txt").write_text("mine")
    assert app_cli(base + ["--max-frames", "3"]) == 2
    _one_line(capsys, "not empty")
    assert len(list(folder.glob("frame_*.png"))) == 10
    assert app_cli(base + ["--max-frames", "3", "--force"]) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["frame_00000.png", "frame_00001.png", "frame_00002.png",
                                                         "notes.txt"]  # fmt: skip


def test_render_errors_name_the_file(clip, art, tmp_path, capsys):
    video, truth, clicks = _work(tmp_path, clip)
    far = tmp_path / "far.clicks.json"
    far.write_text('{"frame": 0, "left_pupil": [5, 5], "right_pupil": [30, 5], "left_brow": [5, 2], '
                   '"right_brow": [30, 2], "mouth": [15, 40]}')
    assert app_cli(["render", "--video", str(video), "--init", str(far), "--art", art, "--out", str(tmp_path / "a.mp4")]) == 2
    _one_line(capsys, str(video), far.name)
    huge = tmp_path / "huge.csv"
    huge.write_text(truth.read_text().splitlines()[0] + "\n" + ",".join(["0"] + ["1e300"] * 10) + "\n")
    assert app_cli(["render", "--params", str(huge), "--art", art, "--out", str(tmp_path / "b.mp4")]) == 2
    _one_line(capsys, "huge.csv", "out of range")
    assert app_cli(["render", "--params", str(truth), "--art", art, "--out", str(tmp_path / ("y" * 5000 + ".mp4"))]) == 2
    _one_line(capsys, "too long")
    assert app_cli(["render", "--video", str(tmp_path / ("z" * 5000 + ".mp4")), "--art", art,
                    "--out", str(tmp_path / "c.mp4")]) == 2  # fmt: skip
    _one_line(capsys)
    assert sorted(p.name for p in tmp_path.glob("*.mp4")) == [video.name]  # nothing written


def test_receive_and_send_refuse_before_they_listen(clip, tmp_path, capsys):
    _, truth, _ = _work(tmp_path, clip)
    (tmp_path / "old.csv").write_text("keep")
    before = _digest(tmp_path)
    assert app_cli(["receive", "--port", "0", "--csv", str(tmp_path / "old.csv"), "--frames", "1"]) == 2
    _one_line(capsys, "old.csv", "--force")
    assert app_cli(["receive", "--port", "0", "--csv", str(tmp_path / "a.x"), "--record", str(tmp_path / "a.x"),
                    "--frames", "1"]) == 2  # fmt: skip
    _one_line(capsys, "two outputs")
    assert app_cli(["send", "--to", "127.0.0.1:9", "--params", str(truth), "--record", str(truth), "--force"]) == 2
    _one_line(capsys, truth.name, "input")
    assert _digest(tmp_path) == before


def test_fap_converter_never_writes_over_its_source(clip, tmp_path, capsys):
    from tracker.fap import main as fap_main

    _, truth, _ = _work(tmp_path, clip)
    before = _digest(tmp_path)
    assert fap_main([str(truth), str(truth), "--force"]) == 2
    _one_line(capsys, "input")
    assert _digest(tmp_path) == before


def test_check_outputs_sees_links_and_folders(tmp_path):
    src = tmp_path / "in.mp4"
    src.write_bytes(b"video")
    os.link(src, tmp_path / "hard.mp4")
    with pytest.raises(OutputError, match="input"):
        check_outputs(files=[tmp_path / "hard.mp4"], inputs=[src], force=True)
    with pytest.raises(OutputError, match="holds the input"):
        check_outputs(folders=[tmp_path], inputs=[src], force=True)
    art = tmp_path / "art"
    art.mkdir()
    (art / "head.png").write_bytes(b"drawing")
    with pytest.raises(OutputError, match="inside the input folder"):
        check_outputs(files=[art / "head.png"], inputs=[art], force=True)
    check_outputs(files=[art / "new.mp4"], inputs=[art])  # a new file beside the drawings is fine
    with pytest.raises(OutputError, match="is a file"):
        check_outputs(files=[src / "x.csv"])


def test_free_name_counts_up(tmp_path):
    (tmp_path / "take.mp4").write_bytes(b"")
    (tmp_path / "take-2.mp4").write_bytes(b"")
    assert free_name(tmp_path / "take.mp4") == tmp_path / "take-3.mp4"
    assert free_name(tmp_path / "take-2.mp4") == tmp_path / "take-3.mp4"
    assert free_name(tmp_path / "new.gif") == tmp_path / "new.gif"


# -------------------------------------------------------------------------- the window's recorder


def _pm(n: int, w: int = 40, h: int = 30) -> list[np.ndarray]:
    out = []
    for i in range(n):
        f = np.zeros((h, w, 4), np.uint8)
        f[5:15, (i % 20) : (i % 20) + 10] = (200, 40, 40, 255)
        out.append(f)
    return out


def test_a_recording_never_overwrites_and_free_names_are_proposed(tmp_path):
    from app.record import RecordError, Recorder, free_recording_path, recording_conflicts
    from tracker.params import FaceParams

    mp4 = tmp_path / "ivy.mp4"
    rec = Recorder(mp4, fps=30)
    for f in _pm(5):
        rec.add_rgba(f, FaceParams(mid_x=1.0))
    rec.finish()
    track = (tmp_path / "ivy.csv").read_bytes()
    before = _digest(tmp_path)
    gif = tmp_path / "ivy.gif"  # its track would be ivy.csv: the MP4's
    assert recording_conflicts(gif) == [tmp_path / "ivy.csv"]
    with pytest.raises(RecordError, match=r"ivy\.csv.*ivy-2\.gif"):
        Recorder(gif, fps=10)
    with pytest.raises(RecordError, match=r"ivy\.mp4"):
        Recorder(mp4, fps=10)
    assert _digest(tmp_path) == before and (tmp_path / "ivy.csv").read_bytes() == track
    free = free_recording_path(gif)
    assert free == tmp_path / "ivy-2.gif"
    rec = Recorder(free, fps=10)
    rec.add_rgba(_pm(1)[0], FaceParams())
    res = rec.finish()
    assert res.track == tmp_path / "ivy-2.csv" and (tmp_path / "ivy.csv").read_bytes() == track
    rec = Recorder(mp4, fps=30, overwrite=True)  # the window asked the user: replace
    rec.add_rgba(_pm(1)[0], FaceParams())
    assert rec.finish().frames == 1
