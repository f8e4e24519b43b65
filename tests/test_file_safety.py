"""Crash-safe saves: the generation switch, temporary files, and SIGKILL during every saver."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tracker import atomic_file

ROOT = Path(__file__).resolve().parents[1]
SAVERS = ("artset", "autosave", "calibration", "session", "clicks")


# --------------------------------------------------------------------------- shared modules
@pytest.mark.parametrize("name", ["atomic_file.py", "safe_json.py"])
def test_art_sets_copy_of_the_shared_modules_is_identical(name):
    """art_sets may not import tracker, so it carries a copy: the two must never drift apart."""
    assert (ROOT / "art_sets" / name).read_bytes() == (ROOT / "tracker" / name).read_bytes()


@pytest.mark.parametrize("name", ["atomic_file.py", "safe_json.py"])
def test_shared_modules_use_the_standard_library_only(name):
    text = (ROOT / "tracker" / name).read_text()
    imports = {line.split()[1].split(".")[0] for line in text.splitlines() if line.startswith(("import ", "from "))}
    assert imports <= {"__future__", "contextlib", "json", "math", "numbers", "os", "re", "tempfile", "time",
                       "pathlib", "typing"}


# --------------------------------------------------------------------------- temporary files
def test_temp_files_carry_the_pattern_and_are_swept_when_their_writer_is_gone(tmp_path):
    target = tmp_path / "out.csv"
    with atomic_file.replacing(target, suffix=".csv") as tmp:
        assert atomic_file.is_temp(tmp.name) and tmp.name.endswith(".csv")
        tmp.write_text("a")
        # our own temp file is left alone while we write it
        assert atomic_file.sweep_temp(tmp_path) == 0 and tmp.exists()
    assert target.read_text() == "a" and os.listdir(tmp_path) == ["out.csv"]
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead = int(child.stdout)
    stale = tmp_path / f".out.csv{atomic_file.TEMP_MARK}{dead}-abc123.csv"
    stale.write_text("half")
    live = tmp_path / f".out.csv{atomic_file.TEMP_MARK}{os.getppid()}-abc123.csv"
    live.write_text("still writing")
    user = tmp_path / ".out.csv.tmp"  # not ours: never touched
    user.write_text("x")
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / stale.name).write_text("half")
    assert atomic_file.sweep_temp(tmp_path) == 1
    assert not stale.exists() and live.exists() and user.exists() and (sub / stale.name).exists()
    assert atomic_file.sweep_temp(tmp_path, recursive=True) == 1
    old = time.time() - atomic_file.STALE_SECONDS - 10
    os.utime(live, (old, old))
    assert atomic_file.sweep_temp(tmp_path) == 1 and not live.exists()
    assert atomic_file.sweep_temp(tmp_path / "missing") == 0


def test_a_failed_write_leaves_the_old_file_and_no_temp(tmp_path):
    target = tmp_path / "f.json"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_file.replacing(target) as tmp:
            tmp.write_text("new")
            raise RuntimeError("disk gone")
    assert target.read_text() == "old" and os.listdir(tmp_path) == ["f.json"]


def test_temp_names_fit_beside_a_long_file_name(tmp_path):
    target = tmp_path / ("n" * 250 + ".json")
    atomic_file.write_text(target, "{}")
    assert target.read_text() == "{}"


def test_inside_refuses_what_leaves_the_folder(tmp_path):
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    (tmp_path / "out").symlink_to("/")
    for bad in ("../x.png", "/etc/passwd", "a\\b.png", "C:x.png", "loop/x.png", "out/etc/passwd", "x" * 5000,
                "a\x00b", "", 3):
        assert atomic_file.inside(tmp_path, bad) is None
    assert atomic_file.inside(tmp_path, "eyes/open.png") == tmp_path / "eyes" / "open.png"


# --------------------------------------------------------------------------- generations
def test_generation_never_writes_a_file_the_manifest_on_disk_names(tmp_path):
    g = atomic_file.Generation(tmp_path, "m.json")
    assert g.put("a/x.png", b"one") == "a/x.png"
    assert g.put("a/y.png", b"why") == "a/y.png"
    g.commit(json.dumps(["a/x.png", "a/y.png"]).encode())

    g = atomic_file.Generation(tmp_path, "m.json", ["a/x.png", "a/y.png"])
    before = (tmp_path / "a" / "x.png").stat().st_mtime_ns
    assert g.put("a/x.png", b"one") == "a/x.png"  # unchanged: kept, not rewritten
    assert (tmp_path / "a" / "x.png").stat().st_mtime_ns == before
    assert g.put("a/y.png", b"two") == "a/y.png".replace(".png", ".v2.png")
    assert (tmp_path / "a" / "y.png").read_bytes() == b"why"  # the old generation is intact until commit
    assert g.put("a/z.png", b"new") == "a/z.png"
    g.commit(b"[]")
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["x.png", "y.v2.png", "z.png"]

    g = atomic_file.Generation(tmp_path, "m.json", ["a/x.png", "a/y.v2.png", "a/z.png"])
    assert g.put("a/y.v2.png", b"three") == "a/y.png"  # back to the plain name once it is free
    assert g.keep("a/x.png") == "a/x.png"
    with pytest.raises(KeyError):
        g.keep("a/nope.png")
    assert g.put("a/x.png", b"another image wanting x") == "a/x.v2.png"  # x is taken in this generation
    with pytest.raises(ValueError):
        g.put("../escape.png", b"")
    g.commit(b"[]")
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["x.png", "x.v2.png", "y.png"]


def test_base_name():
    assert atomic_file.base_name("mouth/ah.v2.png") == "mouth/ah.png"
    assert atomic_file.base_name("mouth/ah.png") == "mouth/ah.png"
    assert atomic_file.base_name(".v2.png") == ".v2.png"


# --------------------------------------------------------------------------- SIGKILL during saves
def _kill_run(saver: str, trials: int, seed: int, tmp_path: Path) -> dict:
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    out = subprocess.run([sys.executable, str(ROOT / "tests" / "kill_saves.py"), saver, str(trials), str(seed), str(tmp_path / saver)],
                         capture_output=True, text=True, env=env, timeout=900)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def _check(res: dict) -> None:
    assert res["errors"] == [], res
    assert res["mixed"] == 0, res
    assert res["old"] + res["new"] == res["trials"], res
    assert res["temp_left"] == 0, res  # the loader swept what the killed writer left
    assert res["max_files"] <= res["files_of_both_versions"], res  # no pile-up of half generations


@pytest.mark.parametrize("saver", SAVERS)
def test_sigkill_during_save_leaves_the_old_or_the_new_version(saver, tmp_path):
    _check(_kill_run(saver, 50, 15, tmp_path))


@pytest.mark.slow
@pytest.mark.parametrize("saver", SAVERS)
def test_sigkill_during_save_long(saver, tmp_path, request):
    """500 kills a saver (about a minute each): only when asked for, ``pytest -m slow``."""
    if "slow" not in (request.config.option.markexpr or ""):
        pytest.skip("the long version runs with -m slow")
    _check(_kill_run(saver, 500, 1515, tmp_path))


# --------------------------------------------------------------------------- savers, one by one
def test_resaving_an_art_set_keeps_files_it_does_not_own(tmp_path):
    from art_sets.editing import clone
    from art_sets.io import load_artset, save_artset
    from kill_saves import _artset, _artset_key

    a, b = _artset(0, 3), _artset(1, 4)
    a.extra["preview"] = "preview.png"  # named by a key this version does not read
    folder = save_artset(clone(a), tmp_path / "set")
    (folder / "preview.png").write_bytes(b"not ours")
    (folder / "notes.txt").write_text("the artist's")
    b.extra["preview"] = "preview.png"
    saved = clone(b)
    save_artset(saved, folder)
    assert (folder / "preview.png").read_bytes() == b"not ours" and (folder / "notes.txt").exists()
    assert _artset_key(load_artset(folder)) == _artset_key(b)
    # changed pictures went to their other names, the old ones are gone, unchanged ones stayed
    named = set(saved.head_files) | {d.file for p in saved.parts.values() for d in p.drawings}
    on_disk = {p.relative_to(folder).as_posix() for p in folder.rglob("*.png")}
    assert on_disk == named | {"preview.png"}
    assert any(".v2." in n for n in named)
    save_artset(clone(a), folder)
    assert _artset_key(load_artset(folder)) == _artset_key(a)
    assert not any(".v2." in p.name for p in folder.rglob("*.png"))  # back to the plain names


def test_autosave_cache_skips_unchanged_images_and_recovery_drops_version_names(tmp_path):
    from app.editor.document import _plain_names, write_side_copy
    from art_sets.editing import clone
    from art_sets.io import load_artset
    from kill_saves import _artset, _artset_key

    a = _artset(0, 3)
    cache: dict = {}
    side = tmp_path / ".artset.autosave"
    write_side_copy(clone(a), side, cache)
    stamps = {p: p.stat().st_mtime_ns for p in side.rglob("*.png")}
    b = clone(a)
    b.mouth.drawings[0].image = b.mouth.drawings[0].image.copy()
    b.mouth.drawings[0].image[0, 0] ^= 255
    write_side_copy(clone(b), side, cache)
    back = load_artset(side)
    assert _artset_key(back) == _artset_key(b)
    changed = [p for p in side.rglob("*.png") if stamps.get(p) != p.stat().st_mtime_ns]
    assert [p.name for p in changed] == ["d0.v2.png"]  # one image encoded, the rest kept as they were
    _plain_names(back)
    assert back.mouth.drawings[0].file == "mouth/d0.png"


def test_session_resave_keeps_thumbnails_and_removes_unused_ones(tmp_path):
    from kill_saves import _session, _session_key
    from training.session import TrainingSession

    s = _session(0)
    s.save(tmp_path / "s")
    thumbs = {p.relative_to(tmp_path / "s").as_posix(): p.stat().st_mtime_ns for p in (tmp_path / "s" / "thumbs").iterdir()}
    assert set(thumbs) == {p.thumb_file for p in s.pairs}
    removed = s.remove_pair(0)
    s.save()
    now = {p.relative_to(tmp_path / "s").as_posix(): p.stat().st_mtime_ns for p in (tmp_path / "s" / "thumbs").iterdir()}
    assert set(now) == {p.thumb_file for p in s.pairs} == set(thumbs) - {removed.thumb_file}
    assert all(now[k] == thumbs[k] for k in now)  # kept, not rewritten
    assert _session_key(TrainingSession.load(tmp_path / "s")) == _session_key(s)
