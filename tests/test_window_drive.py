"""The scripted drive: the real performance window, hammered at full rate, never freezes.

One drive (50 calibrations, 50 training sessions, 20 source switches — the fake camera, a
video file, the bundled performance and a camera that does not exist — characters, rates,
pause, recordings stopped while playing) runs in ``make test``; the 10-minute soak runs with
``-m slow``. A heartbeat on the GUI event loop measures the longest freeze; a watchdog dumps
every thread's stack and fails the test on a hang (see ``benchmarks/soak_window.py``).
"""

from __future__ import annotations

import pytest

pytest.importorskip("pytestqt")

from benchmarks.soak_window import WindowDrive, drive_performer, watched_window  # noqa: E402

WAIT = 120_000


pytestmark = pytest.mark.usefixtures("isolated_user_dirs")  # settings, data and cache in tmp_path


def test_scripted_drive_never_freezes_the_window(qtbot, tmp_path):
    performer = drive_performer()
    w, beat, dog = watched_window(performer)
    qtbot.addWidget(w)
    try:
        qtbot.waitUntil(lambda: (w.last is not None and w.last.character is not None) or dog.hung, timeout=WAIT)
        with dog.hold():  # the drive's own setup (sessions, a video file) is not the window's
            drive = WindowDrive(w, performer, tmp_path / "drive", heartbeat=beat)
        drive.start()
        qtbot.waitUntil(lambda: drive.settled or dog.hung, timeout=300_000)
        rep = drive.finish()
        assert not dog.hung, "the window hung (every thread's stack is printed above)"
        # frames keep coming from whatever source the script ended on
        n = w.frames_shown
        qtbot.waitUntil(lambda: w.frames_shown >= n + 5 or dog.hung, timeout=WAIT)
    finally:
        dog.stop()
        beat.stop()
    assert not dog.hung, "the window hung (every thread's stack is printed above)"
    print(rep)
    assert rep.failures == []
    assert (rep.calibrations, rep.sessions, rep.sources) == (50, 50, 20)
    assert rep.characters >= 2 and rep.pauses >= 2
    assert rep.worst_gap_s < 1.0, f"the event loop was silent for {rep.worst_gap_s:.2f} s during {rep.worst_at}"
    # every request showed in the engine's frames within the frames already on their way
    assert 0 < rep.max_frames_to_reach <= 3
    # each stopped recording says how many frames its file has
    assert len(rep.recordings) == 2
    for path, reported, in_file in rep.recordings:
        assert reported == in_file > 0, path
    # the camera that does not exist fell back to the bundled performance, and said so
    assert w.source_spec.kind in ("camera", "video", "performance")
    w.close()


@pytest.mark.slow
def test_ten_minute_soak(request):
    """The drive again and again for 10 minutes (``INKFACE_SOAK_MINUTES`` to change): the event loop
    is never silent for 1 s and window + engine hold their memory (growth after warm-up < 5 %)."""
    import os

    if "slow" not in (request.config.getoption("markexpr") or ""):
        pytest.skip("the 10-minute soak runs with -m slow (or: python -m benchmarks.soak_window)")
    from benchmarks.soak_window import soak

    res = soak(float(os.environ.get("INKFACE_SOAK_MINUTES", "10")))
    assert not res["hung"], "the window hung (every thread's stack is printed above)"
    assert res["failures"] == [] and res["mismatched_recordings"] == []
    assert res["worst_gap_s"] < 1.0, f"the event loop was silent for {res['worst_gap_s']:.2f} s ({res['worst_at']})"
    assert res["growth_pct"] < 5.0, res
