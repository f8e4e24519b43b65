"""The scripted drive of the performance window, and the soak that repeats it for minutes.

The real :class:`app.main_window.MainWindow` plays a fake camera at full rate (30 fps) while a
script fires what a busy user does: calibrations (the calibration window's Accept and the
one-key recalibration), training sessions (Use this training), source switches (the fake camera,
a video file, the bundled performance, a camera that does not exist), characters, output rates,
pause / resume, and recordings that are stopped while the performance plays. Meanwhile

* a :class:`Heartbeat` QTimer on the GUI event loop records the longest silence between its
  beats (the window froze for that long), and
* a :class:`Watchdog` thread dumps every thread's stack — the window's and, by ``SIGUSR1``, the
  engine's — when the heartbeat has been silent for ``hang_s`` seconds, then kills the engine
  so a GUI thread blocked on it is released and the run fails instead of hanging.

``python -m benchmarks.soak_window --minutes 10`` runs the soak and prints the event loop's worst
gap and the memory growth (resident set of window + engine, from the end of the first drive to
the end). ``tests/test_window_drive.py`` runs one drive in ``make test`` and the 10-minute soak
under ``-m slow``.
"""

from __future__ import annotations

import argparse
import contextlib
import faulthandler
import os
import signal
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# ------------------------------------------------------------------------------------------
# watching the event loop


class Heartbeat:
    """A QTimer on the GUI event loop; ``worst_gap_s`` is the longest silence between beats."""

    def __init__(self, interval_ms: int = 20):
        from PySide6.QtCore import QTimer

        self.interval_ms = interval_ms
        self.last = time.monotonic()
        self.worst_gap_s = 0.0
        self.worst_at = ""  # what the drive was doing when the worst gap ended
        self.beats = 0
        self.doing = ""
        self._timer = QTimer()
        self._timer.setInterval(interval_ms)
        self._timer.timeout.connect(self._beat)

    def start(self) -> None:
        self.last = time.monotonic()
        self._timer.start()

    def stop(self) -> None:
        self._timer.stop()

    def reset(self) -> None:
        self.last = time.monotonic()
        self.worst_gap_s, self.worst_at = 0.0, ""

    def _beat(self) -> None:
        now = time.monotonic()
        gap = now - self.last
        if gap > self.worst_gap_s:
            self.worst_gap_s, self.worst_at = gap, self.doing
        self.last = now
        self.beats += 1


class Watchdog(threading.Thread):
    """Dumps every thread's stack when the heartbeat is silent for ``hang_s``, then kills the
    engine process (which frees a GUI thread blocked on it) so the test can fail instead of hang."""

    def __init__(self, heartbeat: Heartbeat, engine_pid=lambda: None, hang_s: float = 10.0, out=None,
                 stall_s: float = 0.5):
        super().__init__(name="inkface-watchdog", daemon=True)
        self.heartbeat = heartbeat
        self.engine_pid = engine_pid
        self.hang_s = hang_s
        self.stall_s = stall_s
        self.out = out or sys.stderr
        self.hung = False
        self._held = False
        self.stalls: list[tuple[str, str]] = []  # (what the drive was doing, the GUI thread's stack) per stall
        self._main = threading.main_thread().ident
        self._halt = threading.Event()

    def stop(self) -> None:
        self._halt.set()

    @contextlib.contextmanager
    def hold(self):
        """Not watching while the test itself blocks the event loop (setting up a drive)."""
        self._held = True
        try:
            yield
        finally:
            self.heartbeat.reset()
            self._held = False

    def _sample_stall(self, last_seen: float) -> float:
        """The GUI thread's Python stack once per silence longer than ``stall_s`` (a poor man's
        profiler for the freezes that are shorter than a hang)."""
        import traceback

        beat = self.heartbeat.last
        if beat == last_seen or time.monotonic() - beat < self.stall_s:
            return last_seen
        frame = sys._current_frames().get(self._main)
        if frame is not None:
            self.stalls.append((self.heartbeat.doing, "".join(traceback.format_stack(frame)[-8:])))
        return beat

    def run(self) -> None:
        sampled = 0.0
        while not self._halt.wait(0.1):
            if self._held:
                sampled = self.heartbeat.last
                continue
            silent = time.monotonic() - self.heartbeat.last
            if silent < self.hang_s:
                sampled = self._sample_stall(sampled)
                continue
            self.hung = True
            print(f"\n=== watchdog: the GUI event loop has been silent for {silent:.1f} s "
                  f"(while: {self.heartbeat.doing}); stacks follow ===", file=self.out, flush=True)
            faulthandler.dump_traceback(file=self.out, all_threads=True)
            pid = self.engine_pid()
            if pid:
                if hasattr(signal, "SIGUSR1"):
                    try:
                        print(f"=== engine process {pid}: ===", file=self.out, flush=True)
                        os.kill(pid, signal.SIGUSR1)  # the engine prints its own stacks (to its stderr)
                        time.sleep(1.0)
                    except OSError:
                        pass
                try:
                    os.kill(pid, getattr(signal, "SIGKILL", signal.SIGTERM))
                except OSError:
                    pass
            if self._halt.wait(20.0):
                return
            if time.monotonic() - self.heartbeat.last > 20.0:
                print("=== watchdog: still hung after killing the engine; exiting ===", file=self.out, flush=True)
                faulthandler.dump_traceback(file=self.out, all_threads=True)
                os._exit(3)
            return


def rss_bytes(pid: int | None = None) -> int:
    """Resident set size of a process (this one by default) from /proc; 0 where unavailable."""
    try:
        with open(f"/proc/{pid or 'self'}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


# ------------------------------------------------------------------------------------------
# the script


@dataclass
class DriveReport:
    """What a drive saw."""

    actions: int = 0
    calibrations: int = 0
    sessions: int = 0
    sources: int = 0
    characters: int = 0
    pauses: int = 0
    recordings: list = field(default_factory=list)  # (path, frames the window reported, frames in the file)
    frames_shown: int = 0
    worst_gap_s: float = 0.0
    worst_at: str = ""
    max_frames_to_reach: int = 0  # frames received before a request showed in the engine's frames
    slowest_action_s: float = 0.0  # the longest the GUI thread spent in one scripted call
    slowest_action: str = ""
    failures: list = field(default_factory=list)
    seconds: float = 0.0


def count_video_frames(path: str | os.PathLike) -> int:
    """Frames in a recording as a reader sees them (MP4 / AVI / GIF / PNG folder)."""
    p = Path(path)
    if p.suffix.lower() == ".gif":
        from PIL import Image

        with Image.open(p) as im:
            return int(getattr(im, "n_frames", 1))
    if p.is_dir() or not p.suffix:
        return len(list(Path(p).glob("*.png")))
    import cv2

    cap = cv2.VideoCapture(str(p))
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    return n


class WindowDrive:
    """Fires the script at ``window`` from a QTimer, one action every ``spacing_ms``.

    ``calibrations`` etc. are the counts of one drive. Everything the window is asked to do
    returns at once; what comes back is checked as it arrives."""

    def __init__(self, window, performer: dict, workdir: Path, calibrations: int = 50, sessions: int = 50,
                 sources: int = 20, spacing_ms: int = 150, heartbeat: Heartbeat | None = None,
                 cache: dict | None = None, takes: tuple[str, str] = ("take.mp4", "take.gif")):
        from PySide6.QtCore import QTimer

        self.w = window
        self.performer = performer
        self.workdir = Path(workdir)
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.heartbeat = heartbeat
        self.takes = takes
        self.report = DriveReport()
        self.video = self._make_video()
        self.arts = window.strip.paths()[:3]
        self._sessions: dict[str, list] = (cache if cache is not None else {}).setdefault("sessions", {})
        for art in self.arts:  # made now, not on the clock: the drive's own work is not the window's
            self._sessions_for(art)
        self._saved_cal = self._save_calibration()
        self.plan = self._plan(calibrations, sessions, sources)
        self._i = 0
        self._recording: str | None = None
        self._takes = 0
        self._saved: list = []  # RecordResults, read back after the drive
        self._busy = 0  # calibration windows still being clicked through
        self._pending: list[tuple[int, int]] = []  # (request seq, frames received when sent)
        self._t0 = 0.0
        self._timer = QTimer()
        self._timer.setInterval(spacing_ms)
        self._timer.timeout.connect(self._next)
        window.pipeline.frameReady.connect(self._on_frame)
        window.recordingSaved.connect(self._on_saved)
        window.calibrationOpened.connect(self._on_calibration_window)

    # setup --------------------------------------------------------------------------------
    def _make_video(self) -> str:
        import cv2

        path = self.workdir / "face.avi"
        if not path.is_file():
            vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30, (640, 480))
            for f in self.performer["frames"]:
                vw.write(f)
            vw.release()
        return str(path)

    def _save_calibration(self) -> str:
        path = self.workdir / "performer" / "calibration.json"
        path.parent.mkdir(parents=True, exist_ok=True)
        self.performer["calibration"].save(path)
        return str(path)

    def _sessions_for(self, art: str) -> list:
        if art not in self._sessions:
            from training.defaults import default_session
            from training.session import TrainingSession

            from app.workers import load_artset

            # as the training window hands them over: saved in the performer's folder first
            folder = self.workdir / "sessions" / Path(art).name
            s = default_session(load_artset(art))
            s.save(folder / "a")
            again = TrainingSession.load(folder / "a", autosave=False)
            again.save(folder / "b")
            self._sessions[art] = [s, again]
        return self._sessions[art]

    def _plan(self, calibrations: int, sessions: int, sources: int) -> list[tuple[str, object]]:
        """The actions, interleaved so that every kind happens throughout the drive."""
        kinds = ["camera", "video", "performance", "missing"]
        tracks = {
            "calibrate": [("calibrate", i) for i in range(calibrations)],
            "session": [("session", i) for i in range(sessions)],
            "source": [("source", kinds[i % len(kinds)]) for i in range(sources)],
            "other": [("character", 1), ("rate", 10), ("pause", True), ("pause", False), ("record", self.takes[0]),
                      ("recalibrate", None), ("rate", 15), ("character", -1), ("stop", None), ("record", self.takes[1]),
                      ("rate", 30), ("pause", True), ("recalibrate", None), ("pause", False), ("stop", None)],
        }
        total = sum(len(v) for v in tracks.values())
        out: list[tuple[str, object]] = []
        pos = {k: 0 for k in tracks}
        for n in range(total):
            # the track furthest behind its share of the drive goes next
            k = min((k for k in tracks if pos[k] < len(tracks[k])),
                    key=lambda k: (pos[k] + 1) / len(tracks[k]))
            out.append(tracks[k][pos[k]])
            pos[k] += 1
        return out

    # running ------------------------------------------------------------------------------
    def start(self) -> None:
        self._t0 = time.monotonic()
        self._timer.start()

    @property
    def done(self) -> bool:
        return self._i >= len(self.plan) and self._recording is None

    @property
    def settled(self) -> bool:
        """Done, every recording saved, and every request seen in a frame."""
        return self.done and not self.w._saving and not self._pending and not self._busy and not self.w._snapshot_wanted

    def _note_request(self) -> None:
        self._pending.append((self.w.pipeline.requests_sent, self.w.pipeline.frames_received))

    def _on_frame(self) -> None:
        pl = self.w.pipeline
        fr = pl._latest or self.w.last
        if fr is None:
            return
        keep = []
        for seq, at in self._pending:
            if fr.requests_seen >= seq:
                self.report.max_frames_to_reach = max(self.report.max_frames_to_reach, pl.frames_received - at)
            else:
                keep.append((seq, at))
        self._pending = keep

    def _next(self) -> None:
        if self._i >= len(self.plan):
            if self._recording is not None:
                self._do("stop", None)
            if self.heartbeat is not None:
                self.heartbeat.doing = "waiting for the recordings to be saved"
            self._timer.stop()
            self.report.seconds = time.monotonic() - self._t0
            return
        kind, arg = self.plan[self._i]
        self._i += 1
        if self.heartbeat is not None:
            self.heartbeat.doing = f"{kind} {arg}"
        t0 = time.perf_counter()
        try:
            self._do(kind, arg)
        except Exception as e:  # recorded, and the drive goes on
            self.report.failures.append(f"{kind} {arg}: {type(e).__name__}: {e}")
        dt = time.perf_counter() - t0
        if dt > self.report.slowest_action_s:
            self.report.slowest_action_s, self.report.slowest_action = dt, f"{kind} {arg}"
        self.report.actions += 1

    def _do(self, kind: str, arg) -> None:  # noqa: C901 - the script's vocabulary
        w, r = self.w, self.report
        if kind == "calibrate":
            r.calibrations += 1
            if arg % 10 == 9:
                w.open_calibration()  # the real window: frame → Auto → Accept (see _on_calibration_window)
            elif arg % 2:
                w._on_calibrated(self.performer["calibration"], self._saved_cal)  # saved by the window, sent by path
            else:
                w._on_calibrated(self.performer["calibration2"])  # an object: the pipeline writes it once
        elif kind == "session":
            r.sessions += 1
            w._on_session_saved(self._sessions_for(w.current_art())[arg % 2])
        elif kind == "source":
            r.sources += 1
            from tracker.sources import FakeCamera

            from app.workers import SourceSpec

            if arg == "camera":
                w.set_source(SourceSpec("camera"), FakeCamera(self.performer["frames"], fps=30, loop=True))
            elif arg == "video":
                w.open_path(self.video)
            elif arg == "performance":
                w.set_source(SourceSpec("performance"))
            else:
                w.set_source(SourceSpec("camera", camera=9))  # no such camera: the window falls back
        elif kind == "character":
            r.characters += 1
            if len(self.arts) > 1:
                cur = w.current_art()
                i = self.arts.index(cur) if cur in self.arts else 0
                w.set_art(self.arts[(i + arg) % len(self.arts)])
        elif kind == "rate":
            w.set_rate(arg)
        elif kind == "pause":
            r.pauses += int(bool(arg))
            w.pause_btn.setChecked(bool(arg))
        elif kind == "recalibrate":
            w.recalibrate()
        elif kind == "record":
            if self._recording is None:
                self._takes += 1
                path = self.workdir / "rec" / f"{os.getpid()}-{time.monotonic_ns()}-{self._takes}-{arg}"
                if w.start_recording(str(path)):
                    self._recording = str(path)
        elif kind == "stop":
            if self._recording is not None:
                w.stop_recording()
                self._recording = None
        self._note_request()

    def _on_calibration_window(self, dlg) -> None:
        """The calibration window opened on the snapshot: Accept, a turn of the event loop later,
        hands over a calibration as its Accept and save does. (Its own point fitting and Auto run
        on the GUI thread inside that window and are not part of this drive.)"""
        from PySide6.QtCore import QTimer

        def accept():
            self._guard("calibration window: accept", lambda: (dlg.calibrated.emit(self.performer["calibration"]),
                                                               dlg.close()), dlg)

        self._busy += 1
        QTimer.singleShot(50, accept)

    def _guard(self, what: str, fn, dlg) -> None:
        self._busy -= 1
        if self.heartbeat is not None:
            self.heartbeat.doing = what
        try:
            fn()
        except Exception as e:
            self.report.failures.append(f"{what}: {type(e).__name__}: {e}")
            dlg.close()

    def _on_saved(self, result) -> None:
        self._saved.append(result)  # read back in finish(): decoding a GIF here would freeze the window

    def _read_back(self) -> None:
        for result in self._saved:
            try:
                in_file = count_video_frames(result.output)
            except Exception as e:
                in_file = -1
                self.report.failures.append(f"reading back {result.output}: {e}")
            self.report.recordings.append((str(result.output), int(result.frames), in_file))
            for p in [result.output, result.track, *getattr(result, "extra", [])]:  # keep the disk from filling up
                if p is not None and Path(p).is_file():
                    Path(p).unlink()
        self._saved = []

    def finish(self) -> DriveReport:
        self._timer.stop()
        r = self.report
        r.frames_shown = self.w.frames_shown
        if self.heartbeat is not None:
            r.worst_gap_s, r.worst_at = self.heartbeat.worst_gap_s, self.heartbeat.worst_at
        self._read_back()
        self.w.pipeline.frameReady.disconnect(self._on_frame)
        self.w.recordingSaved.disconnect(self._on_saved)
        self.w.calibrationOpened.disconnect(self._on_calibration_window)
        return r


def drive_performer(seed: int = 5) -> dict:
    """Frames of a short synthetic performance, its five clicks and two calibrations made from it."""
    from tracker.calibration import calibrate
    from tracker.clicks import Clicks
    from tracker.synthetic import Performance

    from app.workers import performance_calibration

    perf = Performance(seconds=1.0, seed=seed)
    frames = [perf.frame(i) for i in range(len(perf))]
    clicks = Clicks.from_dict(perf.clicks())
    other = min(len(frames) - 1, clicks.frame + 5)
    return {"perf": perf, "frames": frames, "clicks": perf.clicks(), "calibration": performance_calibration(perf),
            "calibration2": calibrate(frames[other], clicks)}


def watched_window(performer: dict, hang_s: float = 10.0):
    """The performance window playing a fake camera at full rate, with a :class:`Heartbeat`
    and a :class:`Watchdog` running: returns (window, heartbeat, watchdog)."""
    from tracker.sources import FakeCamera

    from app.main_window import MainWindow
    from app.settings import Settings
    from app.workers import SourceSpec

    w = MainWindow(settings=Settings(), source=SourceSpec("camera"),
                   fake_source=FakeCamera(performer["frames"], fps=30, loop=True), calibration=performer["calibration"])
    w.resize(1360, 820)
    w.show()
    beat = Heartbeat()
    dog = Watchdog(beat, lambda: w.pipeline.engine_pid, hang_s=hang_s)
    beat.start()
    dog.start()
    return w, beat, dog


# ------------------------------------------------------------------------------------------
# the soak


def soak(minutes: float, out=sys.stdout, spacing_ms: int = 150, workdir: str | None = None,
         takes: tuple[str, str] = ("take.mp4", "take.gif")) -> dict:
    """Repeat the drive for ``minutes``; print and return the worst gap and memory growth."""
    import app.qt_env  # noqa: F401  (offscreen without a display)

    from PySide6.QtWidgets import QApplication

    tmp = Path(workdir or tempfile.mkdtemp(prefix="inkface-soak-"))
    for k, sub in (("INKFACE_SETTINGS", "settings.ini"), ("INKFACE_DATA", "data"), ("INKFACE_CACHE", "cache"),
                   ("INKFACE_ART_DIR", "user-art")):
        os.environ.setdefault(k, str(tmp / sub))
    from app.window_cmd import make_app

    qapp = make_app()
    performer = drive_performer()
    w, beat, dog = watched_window(performer)

    def pump(until, limit_s: float) -> bool:
        end = time.monotonic() + limit_s
        while not until() and time.monotonic() < end and not dog.hung:
            qapp.processEvents()
            time.sleep(0.002)
        return until()

    pump(lambda: w.last is not None and w.last.character is not None, 120)
    t_start = time.monotonic()
    end = t_start + minutes * 60.0
    samples: list[tuple[float, int, int]] = []
    baseline = None
    drives = 0
    worst = 0.0
    worst_at = ""
    reports = []
    cache: dict = {}
    print(f"soak: {minutes:g} min of scripted drives (50 calibrations, 50 sessions, 20 sources, characters, pause, "
          f"recordings each), one action every {spacing_ms} ms", file=out, flush=True)
    while time.monotonic() < end and not dog.hung:
        with dog.hold():  # the drive's own setup is not the window's
            d = WindowDrive(w, performer, tmp / f"drive-{drives % 2}", spacing_ms=spacing_ms, heartbeat=beat,
                            cache=cache, takes=takes)
        dog.stalls.clear()
        d.start()
        pump(lambda: d.settled, 600)
        rep = d.finish()
        reports.append(rep)
        drives += 1
        mem = (rss_bytes(), rss_bytes(w.pipeline.engine_pid))
        t = time.monotonic() - t_start
        samples.append((t, *mem))
        if baseline is None:
            baseline = sum(mem)
        if rep.worst_gap_s > worst:
            worst, worst_at = rep.worst_gap_s, rep.worst_at
        beat.reset()
        for doing, stack in dog.stalls:
            print(f"    stall while {doing}:\n{stack}", file=out, flush=True)
        dog.stalls.clear()
        print(f"  drive {drives:3d} at {t / 60:5.1f} min: {rep.actions} actions in {rep.seconds:5.1f} s, "
              f"worst gap {rep.worst_gap_s * 1000:6.0f} ms, requests reached the engine within "
              f"{rep.max_frames_to_reach} frames, RSS window {mem[0] / 2**20:6.1f} MB + engine "
              f"{mem[1] / 2**20:6.1f} MB, recordings {[(Path(p).name, a, b) for p, a, b in rep.recordings]}"
              + (f", FAILURES {rep.failures}" if rep.failures else ""), file=out, flush=True)
    dog.stop()
    beat.stop()
    final = samples[-1][1] + samples[-1][2] if samples else 0
    # warmed up: every character, source, rate and recording format has been used and the
    # buffers are at their working size (the first quarter of the run, at least two drives).
    # One sample lands anywhere in a drive (±5 % while a character loads), so the growth compares
    # the median of the first third of the warmed-up drives with the median of the last third.
    warm_t = max(samples[min(1, len(samples) - 1)][0], samples[-1][0] / 4) if samples else 0
    totals = [a + b for t, a, b in samples if t >= warm_t] or [final]
    third = max(1, len(totals) // 3)
    warm = float(np.median(totals[:third]))
    end_med = float(np.median(totals[-third:]))
    growth = (end_med - warm) / warm * 100.0 if warm else 0.0
    growth_first = (final - baseline) / baseline * 100.0 if baseline else 0.0
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    result = {"minutes": (time.monotonic() - t_start) / 60.0, "drives": drives, "worst_gap_s": worst,
              "worst_at": worst_at, "rss_first_mb": (baseline or 0) / 2**20, "rss_warm_mb": warm / 2**20,
              "warm_min": warm_t / 60.0, "rss_end_mb": final / 2**20, "growth_pct": growth,
              "growth_from_first_pct": growth_first, "hung": dog.hung, "frames_shown": w.frames_shown,
              "load": load, "failures": [f for r in reports for f in r.failures],
              "mismatched_recordings": [x for r in reports for x in r.recordings if x[1] != x[2]]}
    print(f"soak result: {result['minutes']:.1f} min, {drives} drives, {w.frames_shown} frames shown, "
          f"{sum(len(r.recordings) for r in reports)} recordings ({len(result['mismatched_recordings'])} whose "
          f"reported count differs from the file), {len(result['failures'])} failures; "
          f"event loop worst gap {worst * 1000:.0f} ms (during: {worst_at}); RSS window+engine "
          f"{result['rss_first_mb']:.1f} MB after the first drive, {result['rss_warm_mb']:.1f} MB warmed up "
          f"(median of the first {third} drives from {result['warm_min']:.1f} min), {end_med / 2**20:.1f} MB at the end "
          f"(median of the last {third}; last drive {result['rss_end_mb']:.1f} MB): growth {growth:+.1f} % after warm-up "
          f"({growth_first:+.1f} % from the first drive to the last); load average {load:.1f} on "
          f"{os.cpu_count()} cores" + ("; HUNG" if dog.hung else ""), file=out, flush=True)
    w.close()
    qapp.processEvents()
    return result


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.soak_window", description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=10.0, help="how long to keep driving (default 10)")
    ap.add_argument("--spacing-ms", type=int, default=150, help="time between two scripted actions")
    ap.add_argument("--takes", default="take.mp4,take.gif", help="the two recordings of each drive (by extension)")
    args = ap.parse_args(argv)
    res = soak(args.minutes, spacing_ms=args.spacing_ms, takes=tuple(args.takes.split(",")[:2]))
    ok = not res["hung"] and res["worst_gap_s"] < 1.0 and res["growth_pct"] < 5.0 and not res["mismatched_recordings"]
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
