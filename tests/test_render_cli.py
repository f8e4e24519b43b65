"""``python -m app render`` on a short generated clip: frame counts, formats, errors."""

import subprocess
import sys

import cv2
import numpy as np
import pytest
from PIL import Image

from app.cli import run as cli
from art_sets.library import list_bundled
from tracker.synthetic import Performance

N = 20


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    d = tmp_path_factory.mktemp("clip")
    video, truth = d / "p.mp4", d / "p.csv"
    Performance(seconds=N / 30.0, seed=4).write(video, truth)
    assert (d / "p.clicks.json").is_file()
    return video, truth


@pytest.fixture(scope="module")
def art():
    return list_bundled()[0][0]


def _frames(path):
    cap = cv2.VideoCapture(str(path))
    out = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        out.append(f)
    cap.release()
    return out


def test_render_mp4_side_by_side(clip, art, tmp_path, capsys):
    video, _ = clip
    out = tmp_path / "r.mp4"
    assert cli(["render", "--video", str(video), "--art", art, "--out", str(out), "--side-by-side"]) == 0
    frames = _frames(out)
    assert len(frames) == N
    h, w = frames[0].shape[:2]
    assert w > h  # performer left, character right
    err = capsys.readouterr().err
    assert "render: frame" in err
    # the character half is not empty paper
    assert np.std(frames[5][:, w // 2 + 10 :]) > 10


@pytest.mark.parametrize("fps", [10, 15])
def test_render_lower_rate_from_track(clip, art, tmp_path, fps):
    video, truth = clip
    out = tmp_path / "r.mp4"
    assert cli(["render", "--video", str(video), "--params", str(truth), "--art", art, "--out", str(out), "--fps", str(fps)]) == 0
    frames = _frames(out)
    assert len(frames) == N // (30 // fps)
    cap = cv2.VideoCapture(str(out))
    assert cap.get(cv2.CAP_PROP_FPS) == pytest.approx(fps, abs=0.01)
    cap.release()


def test_render_png_folder_keeps_alpha_and_gif(clip, art, tmp_path):
    video, truth = clip
    folder = tmp_path / "pngs"
    assert cli(["render", "--params", str(truth), "--art", art, "--out", str(folder), "--max-frames", "4"]) == 0
    pngs = sorted(folder.glob("frame_*.png"))
    assert len(pngs) == 4
    im = np.asarray(Image.open(pngs[0]))
    assert im.shape[2] == 4 and im[..., 3].min() == 0 and im[..., 3].max() == 255
    gif = tmp_path / "r.gif"
    assert cli(["render", "--params", str(truth), "--art", art, "--out", str(gif), "--max-frames", "3"]) == 0
    with Image.open(gif) as g:
        assert g.n_frames == 3


def test_errors_are_one_line(clip, art, tmp_path, capsys):
    video, _ = clip
    cases = [
        ["--video", str(tmp_path / "missing.mp4"), "--art", art],
        ["--video", str(video), "--art", "no-such-character"],
        ["--video", str(video), "--art", art, "--init", str(tmp_path / "nope.json")],
        ["--video", str(video), "--art", art, "--training", str(tmp_path / "nosession")],
    ]
    for extra in cases:
        rc = cli(["render", *extra, "--out", str(tmp_path / "x.mp4")])
        err = capsys.readouterr().err.strip()
        assert rc == 2
        assert err.startswith("inkface: ") and "\n" not in err, err
        assert "Traceback" not in err
    assert not (tmp_path / "x.mp4").exists()


@pytest.mark.slow
def test_module_entry_point(clip, art, tmp_path):
    _, truth = clip
    out = tmp_path / "r.mp4"
    r = subprocess.run([sys.executable, "-m", "app", "render", "--params", str(truth), "--art", art,
                        "--out", str(out), "--max-frames", "3"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert len(_frames(out)) == 3


def test_no_face_and_no_clicks_is_a_one_line_error(art, tmp_path, capsys):
    blank = tmp_path / "blank.mp4"
    w = cv2.VideoWriter(str(blank), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (160, 120))
    for _ in range(5):
        w.write(np.full((120, 160, 3), 90, np.uint8))
    w.release()
    rc = cli(["render", "--video", str(blank), "--art", art, "--out", str(tmp_path / "o.mp4")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and err.startswith("inkface: ") and "\n" not in err
    assert "--init" in err


def test_render_starts_where_a_late_face_comes(art, tmp_path, capsys):
    """No clicks, and the clip opens on 15 frames of an empty wall: the start is found where the face
    first shows (not refused on frame 0), and every frame is rendered."""
    from late_face import write_late_face_clip

    video = tmp_path / "late.avi"
    perf = write_late_face_clip(video, 15, Performance(seconds=0.5, seed=4))
    out = tmp_path / "r.mp4"
    assert cli(["render", "--video", str(video), "--art", art, "--out", str(out)]) == 0, capsys.readouterr().err
    assert len(_frames(out)) == 15 + len(perf)


def _track_files(truth, d):
    """The truth CSV re-written as a packet stream (.ifs) and an MPEG-4 FAP file (.fap)."""
    from tracker.fap import write_fap
    from tracker.params import read_csv
    from tracker.stream_codec import write_track_stream

    rows = read_csv(truth)
    ipd = 80.0  # Performance's default inter-pupil distance
    write_track_stream(d / "t.ifs", rows, (640, 480), ipd, fps=30.0, neutral=rows[0])
    write_fap(d / "t.fap", rows, rows[0], ipd, fps=30.0)
    return d / "t.ifs", d / "t.fap"


def test_params_accepts_any_track_file(clip, art, tmp_path):
    _, truth = clip
    ifs, fap = _track_files(truth, tmp_path)
    pics = {}
    for src in (truth, ifs, fap):
        out = tmp_path / f"png_{src.suffix[1:]}"
        # gain 0: a FAP file has no head translation, so compare the expression only
        assert cli(["render", "--params", str(src), "--art", art, "--out", str(out), "--gain", "0"]) == 0
        frames = sorted(out.glob("frame_*.png"))
        assert len(frames) == N
        pics[src.suffix] = [np.asarray(Image.open(frames[i])).astype(np.int16) for i in (0, -1)]
    moved = np.mean(np.abs(pics[".csv"][1] - pics[".csv"][0]))
    # the same performance through any file gives (up to quantisation) the same character
    for suffix in (".ifs", ".fap"):
        assert np.mean(np.abs(pics[suffix][1] - pics[".csv"][1])) < 0.3 * moved, suffix


def test_params_bad_track_file_is_a_one_line_error(art, tmp_path, capsys):
    bad = tmp_path / "bad.ifs"
    bad.write_bytes(b"\x00garbage\n")
    for path in (bad, tmp_path / "missing.fap"):
        rc = cli(["render", "--params", str(path), "--art", art, "--out", str(tmp_path / "x.mp4")])
        err = capsys.readouterr().err.strip()
        assert rc == 2 and err.startswith("inkface: ") and "\n" not in err and path.name in err, err


def test_render_calibrates_past_a_blink_on_the_clicked_frame_and_still_renders_every_frame(clip, art, tmp_path, capsys,
                                                                                           monkeypatch):
    """``render`` reads its clicks as ``track --init`` does: on a clicked frame whose eyes look shut they
    are carried with the head to a frame whose eyes show (tracker.open_eyes), and the whole clip, from
    its first frame, is still rendered."""
    import tracker.open_eyes as oe

    video, _ = clip
    monkeypatch.setattr(oe, "eyes_shown", lambda img, c: 5.0 if c.frame == 4 else 0.5)
    out = tmp_path / "r.mp4"
    assert cli(["render", "--video", str(video), "--art", art, "--out", str(out)]) == 0
    assert len(_frames(out)) == N
    err = capsys.readouterr().err
    assert "eyes look shut on frame 0" in err and "calibrated on frame 4" in err
