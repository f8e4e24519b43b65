"""One data folder: decided once at start-up, agreed on by every part, old folders moved in once
without losing or overwriting anything. Everything happens under tmp_path (a fake home)."""

from __future__ import annotations

import errno
import hashlib
import os
import sys
import time
import types
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from app import data_dir as dd

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="XDG folders are Linux's")


@pytest.fixture
def home(tmp_path, monkeypatch):
    """A fake home with XDG folders, no INKFACE_* folders chosen, settings in tmp_path."""
    h = tmp_path / "home"
    (h / ".local" / "share").mkdir(parents=True)
    monkeypatch.setenv("HOME", str(h))
    monkeypatch.setenv("XDG_DATA_HOME", str(h / ".local" / "share"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(h / ".cache"))
    monkeypatch.setenv("INKFACE_SETTINGS", str(tmp_path / "settings.ini"))
    for var in (dd.ENV_DATA, dd.ENV_ART, dd.ENV_CACHE):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setattr(dd, "_decided", None)
    return h


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def _files(root: Path) -> dict[str, str]:
    return {p.relative_to(root).as_posix(): p.read_text() for p in sorted(root.rglob("*")) if p.is_file()}


def _contents(*roots: Path) -> list[str]:
    """Every file's bytes under ``roots`` (a multiset as a sorted list of digests)."""
    out = []
    for r in roots:
        if r.is_dir():
            out += [hashlib.sha1(p.read_bytes()).hexdigest() for p in r.rglob("*")
                    if p.is_file() and not p.name.startswith(".migration")]
    return sorted(out)


@linux_only
def test_the_folder_is_qts_app_data_location_for_inkface_and_the_core_agrees(home, qapp):
    from art_sets.library import default_data_dir, user_dir

    want = home / ".local" / "share" / "Inkface"
    names = qapp.organizationName(), qapp.applicationName()
    qapp.setOrganizationName("Inkface")  # what the performance window sets: not doubled any more
    qapp.setApplicationName("__main__.py")  # what the editor had: no longer decides anything
    try:
        assert dd.platform_data_dir() == want
        assert (qapp.organizationName(), qapp.applicationName()) == ("Inkface", "__main__.py")
    finally:
        qapp.setOrganizationName(names[0])
        qapp.setApplicationName(names[1])
    assert default_data_dir() == want  # worked out without Qt
    assert user_dir() == want / "characters"


@linux_only
def test_setup_hands_one_folder_to_every_user_of_a_path(home, monkeypatch):
    from app.editor.document import autosave_dir_for
    from app.settings import performer_dir, user_data_dir
    from app.workers import cache_dir
    from art_sets.library import user_dir

    root = dd.setup()  # the home fixture's monkeypatch puts the variables it writes back afterwards
    assert root == home / ".local" / "share" / "Inkface"
    assert user_data_dir() == root
    assert performer_dir("Ann Lee") == root / "performers" / "ann-lee"
    assert user_dir() == root / "characters"
    assert cache_dir() == root / "cache"
    assert autosave_dir_for(None) == root / "editor-autosave" / "untitled"
    assert dd.setup() == root  # decided once


def test_a_chosen_folder_is_used_as_is_and_nothing_is_migrated_into_it(home, monkeypatch, tmp_path):
    _write(home / ".local" / "share" / "inkface" / "art_sets" / "mine" / "artset.json", "{}")
    monkeypatch.setenv(dd.ENV_DATA, str(tmp_path / "chosen"))
    monkeypatch.setenv(dd.ENV_ART, str(tmp_path / "chosen-art"))
    monkeypatch.setenv(dd.ENV_CACHE, str(tmp_path / "chosen-cache"))
    assert dd.setup() == tmp_path / "chosen"
    assert os.environ[dd.ENV_ART] == str(tmp_path / "chosen-art")  # set ones are kept
    assert (home / ".local" / "share" / "inkface" / "art_sets" / "mine" / "artset.json").is_file()
    assert not (tmp_path / "chosen" / dd.MARKER).exists()


def _old_layout(home: Path) -> dict[str, Path]:
    share = home / ".local" / "share"
    return {
        "calibration": _write(share / "Inkface" / "Inkface" / "performers" / "ann" / "calibration.json", "cal-ann"),
        "session": _write(share / "Inkface" / "Inkface" / "performers" / "ann" / "sessions" / "noodle" / "session.json", "s"),
        "character": _write(share / "inkface" / "art_sets" / "mine" / "artset.json", "mine"),
        "drawing": _write(share / "inkface" / "art_sets" / "mine" / "eyes" / "open.png", "png"),
        "autosave": _write(share / "__main__.py" / "inkface" / "editor-autosave" / "untitled" / "artset.json", "wip"),
        "cache": _write(home / ".cache" / "inkface" / "performance-20s-seed0-abc.avi", "video"),
    }


@linux_only
def test_old_folders_are_moved_into_the_new_one_once(home, monkeypatch):
    from app.settings import Settings

    old = _old_layout(home)
    st = Settings()
    st.set("art/user_dirs", [str(old["character"].parent.resolve()), "/elsewhere/theirs"])
    st.set("art/current", str(old["character"].parent.resolve()))
    st.sync()
    before = _contents(home)

    root = dd.setup()
    assert _files(root) == {
        "performers/ann/calibration.json": "cal-ann",
        "performers/ann/sessions/noodle/session.json": "s",
        "characters/mine/artset.json": "mine",
        "characters/mine/eyes/open.png": "png",
        "editor-autosave/untitled/artset.json": "wip",
        "cache/performance-20s-seed0-abc.avi": "video",
        dd.MARKER: (root / dd.MARKER).read_text(),
    }
    assert _contents(home) == before  # nothing lost, nothing doubled
    share = home / ".local" / "share"
    for gone in (share / "Inkface" / "Inkface", share / "inkface", share / "__main__.py", home / ".cache" / "inkface"):
        assert not gone.exists(), gone
    st = Settings()
    mine = str((root / "characters" / "mine").resolve())
    assert st.user_art_dirs() == [mine, "/elsewhere/theirs"]
    assert st.get("art/current") == mine

    # once: a later start moves nothing, even what an old version wrote meanwhile
    late = _write(share / "inkface" / "art_sets" / "later" / "artset.json", "later")
    monkeypatch.setattr(dd, "_decided", None)
    monkeypatch.delenv(dd.ENV_DATA)
    assert dd.setup() == root
    assert late.is_file() and not (root / "characters" / "later").exists()


@linux_only
def test_nothing_is_overwritten_when_names_are_taken(home):
    old = _old_layout(home)
    root = home / ".local" / "share" / "Inkface"
    _write(root / "performers" / "ann" / "calibration.json", "cal-ann-newer")
    _write(root / "characters" / "mine" / "artset.json", "mine")  # the very same character: a duplicate
    _write(root / "characters" / "mine" / "eyes" / "open.png", "png")
    _write(root / "cache" / "performance-20s-seed0-abc.avi", "other video")
    before = _contents(home)
    report = dd.migrate(dd.legacy_sources(root), root)
    assert report is not None and not report["left"]
    assert (root / "performers" / "ann" / "calibration.json").read_text() == "cal-ann-newer"
    assert (root / "performers" / "ann-old" / "calibration.json").read_text() == "cal-ann"
    assert (root / "performers" / "ann-old" / "sessions" / "noodle" / "session.json").read_text() == "s"
    assert not (root / "characters" / "mine-old").exists()  # identical: kept once
    assert (root / "cache" / "performance-20s-seed0-abc.avi").read_text() == "other video"
    assert (root / "cache" / "performance-20s-seed0-abc-old.avi").read_text() == "video"
    after = _contents(home)
    dupes = [hashlib.sha1(b).hexdigest() for b in (b"mine", b"png")]
    assert sorted(after + dupes) == before
    assert not old["calibration"].exists()


@linux_only
def test_a_move_across_file_systems_copies_under_a_temporary_name(home, monkeypatch):
    old = _old_layout(home)
    root = home / ".local" / "share" / "Inkface"
    real_rename = os.rename

    def rename(a, b):
        if Path(a).name == "performers":  # the performers folder lies on "another disk"
            raise OSError(errno.EXDEV, "Invalid cross-device link")
        return real_rename(a, b)

    monkeypatch.setattr(dd.os, "rename", rename)
    report = dd.migrate(dd.legacy_sources(root), root)
    assert not report["left"]
    assert (root / "performers" / "ann" / "calibration.json").read_text() == "cal-ann"
    assert not old["calibration"].exists()
    assert not list(root.rglob(f"{dd.PARTIAL}*"))


@linux_only
def test_a_copy_that_fails_half_way_loses_nothing_and_is_tried_again(home, monkeypatch):
    old = _old_layout(home)
    root = home / ".local" / "share" / "Inkface"
    real_rename, real_copytree = os.rename, dd.shutil.copytree

    def rename(a, b):
        if dd.PARTIAL not in str(a):
            raise OSError(errno.EXDEV, "Invalid cross-device link")
        return real_rename(a, b)

    def copytree(src, dst, symlinks=False):
        Path(dst).mkdir()
        (Path(dst) / "half").write_text("x")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(dd.os, "rename", rename)
    monkeypatch.setattr(dd.shutil, "copytree", copytree)
    report = dd.migrate(dd.legacy_sources(root), root)
    assert report["left"] and any("No space left" in line for line in report["left"])
    assert old["calibration"].read_text() == "cal-ann"  # still where it was
    assert not list(root.rglob(f"{dd.PARTIAL}*")) and not (root / "performers").exists()
    assert (root / dd.FAILED).is_file() and not (root / dd.MARKER).exists()
    monkeypatch.setattr(dd.shutil, "copytree", real_copytree)  # the disk has room again: the next start
    report = dd.migrate(dd.legacy_sources(root), root)
    assert report is not None and not report["left"]
    assert (root / "performers" / "ann" / "calibration.json").read_text() == "cal-ann"
    assert (root / dd.MARKER).is_file() and not (root / dd.FAILED).exists()


def test_another_start_holding_the_lock_is_left_to_it(tmp_path):
    old, root = tmp_path / "old", tmp_path / "new"
    _write(old / "performers" / "ann" / "calibration.json", "c")
    root.mkdir()
    (root / dd.LOCK).write_text("123")
    assert dd.migrate([(old, root)], root) is None
    assert (old / "performers" / "ann" / "calibration.json").is_file()
    stale = time.time() - 3600
    os.utime(root / dd.LOCK, (stale, stale))  # left behind by a crash: taken over
    assert dd.migrate([(old, root)], root) is not None
    assert (root / "performers" / "ann" / "calibration.json").read_text() == "c"
    assert not (root / dd.LOCK).exists()


names = st.sampled_from(["ann", "bob", "noodle", "a.json", "b.png", "c.txt"])
trees = st.recursive(st.text("xyz", min_size=0, max_size=3), lambda kids: st.dictionaries(names, kids, max_size=3),
                     max_leaves=8)


def _make(root: Path, tree) -> None:
    for name, sub in tree.items():
        if isinstance(sub, dict):
            (root / name).mkdir(parents=True, exist_ok=True)
            _make(root / name, sub)
        else:
            root.mkdir(parents=True, exist_ok=True)
            (root / name).write_text(sub)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.dictionaries(names, trees, max_size=4), st.dictionaries(names, trees, max_size=4))
@example({"noodle": {"ann": ""}}, {"noodle": {"ann": {}}})  # a file where the new folder has a folder of that name
def test_any_two_trees_merge_without_losing_or_changing_a_file(tmp_path_factory, old_tree, new_tree):
    base = tmp_path_factory.mktemp("merge")
    old, root = base / "old", base / "new"
    _make(old, old_tree)
    _make(root, new_tree)
    root.mkdir(exist_ok=True)
    new_before = _files(root)
    before = _contents(old, root)
    report = dd.migrate([(old, root)], root)
    assert report is not None and not report["left"]
    after_files = _files(root)
    for rel, text in new_before.items():  # what was in the new folder is untouched
        assert after_files[rel] == text
    after = _contents(old, root)
    # every file's content is still there; only exact duplicates of files already present are dropped
    assert set(after) == set(before)
    assert not old.exists() or not any(p.is_file() for p in old.rglob("*"))


def test_start_up_sets_the_folder_before_a_command_runs(home, monkeypatch):
    from app import cli

    seen = {}
    probe = types.ModuleType("inkface_probe_cmd")
    probe.add_arguments = lambda parser, command: None
    probe.run = lambda args: seen.update({v: os.environ.get(v) for v in (dd.ENV_DATA, dd.ENV_ART, dd.ENV_CACHE)}) or 0
    monkeypatch.setitem(sys.modules, "inkface_probe_cmd", probe)
    monkeypatch.setitem(cli.COMMANDS, "probe", ("inkface_probe_cmd", "test probe"))
    _old_layout(home)
    assert cli.run(["probe"]) == 0
    root = Path(seen[dd.ENV_DATA])
    assert seen[dd.ENV_ART] == str(root / "characters") and seen[dd.ENV_CACHE] == str(root / "cache")
    if sys.platform.startswith("linux"):
        assert root == home / ".local" / "share" / "Inkface"
        assert (root / "characters" / "mine" / "artset.json").read_text() == "mine"
