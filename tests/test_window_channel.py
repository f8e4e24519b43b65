"""The window ↔ engine channel: requests never wait on frames, frames never wait on the window."""

from __future__ import annotations

import pytest

pytest.importorskip("pytestqt")

from app.settings import Settings  # noqa: E402
from app.workers import SourceSpec  # noqa: E402
from benchmarks.soak_window import Heartbeat, Watchdog  # noqa: E402

WAIT = 60_000


@pytest.fixture(autouse=True)
def _isolated(tmp_path, monkeypatch):
    monkeypatch.setenv("INKFACE_SETTINGS", str(tmp_path / "settings.ini"))
    monkeypatch.setenv("INKFACE_DATA", str(tmp_path / "data"))
    monkeypatch.setenv("INKFACE_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("INKFACE_ART_DIR", str(tmp_path / "user-art"))


@pytest.fixture(scope="module")
def performer():
    from tracker.synthetic import Performance

    from app.workers import performance_calibration

    perf = Performance(seconds=1.0, seed=5)
    frames = [perf.frame(i) for i in range(len(perf))]
    return {"perf": perf, "frames": frames, "calibration": performance_calibration(perf)}


def _art():
    from art_sets.library import list_bundled

    items = [str(p) for _, p in list_bundled()]
    if not items:
        pytest.skip("no bundled characters installed")
    return items[0]


def test_requests_while_frames_flow_never_block_the_window(qtbot, performer):
    """Calibrations, sessions and source switches sent while frames play (the deadlock of issue 14)."""
    from tracker.sources import FakeCamera
    from training.defaults import default_session

    from app.main_window import MainWindow
    from app.workers import load_artset

    art = _art()
    w = MainWindow(settings=Settings(), source=SourceSpec("camera"), art=art,
                   fake_source=FakeCamera(performer["frames"], fps=30, loop=True), calibration=performer["calibration"])
    qtbot.addWidget(w)
    w.show()
    beat = Heartbeat()
    dog = Watchdog(beat, lambda: w.pipeline._proc.pid if w.pipeline._proc is not None else None)
    beat.start()
    dog.start()
    try:
        qtbot.waitUntil(lambda: w.last is not None and w.last.character is not None, timeout=WAIT)
        session = default_session(load_artset(art))
        for i in range(12):
            w._on_calibrated(performer["calibration"])
            w._on_session_saved(session)
            if i % 4 == 3:
                w.set_source(SourceSpec("camera"), FakeCamera(performer["frames"], fps=30, loop=True))
            start = w.frames_shown
            qtbot.waitUntil(lambda: w.frames_shown >= start + 2 or dog.hung, timeout=WAIT)
            assert not dog.hung, "the window hung (stacks above)"
    finally:
        dog.stop()
        beat.stop()
    assert not dog.hung, "the window hung (stacks above)"
    w.close()
