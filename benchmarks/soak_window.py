"""Drive the real performance window hard and watch its event loop (draft for the repro)."""

from __future__ import annotations

import faulthandler
import os
import signal
import sys
import threading
import time


class Heartbeat:
    """A QTimer on the GUI event loop; ``worst_gap_s`` is the longest silence between beats."""

    def __init__(self, interval_ms: int = 20):
        from PySide6.QtCore import QTimer

        self.interval_ms = interval_ms
        self.last = time.monotonic()
        self.worst_gap_s = 0.0
        self.beats = 0
        self._timer = QTimer()
        self._timer.setInterval(interval_ms)
        self._timer.timeout.connect(self._beat)

    def start(self) -> None:
        self.last = time.monotonic()
        self._timer.start()

    def stop(self) -> None:
        self._timer.stop()

    def _beat(self) -> None:
        now = time.monotonic()
        self.worst_gap_s = max(self.worst_gap_s, now - self.last)
        self.last = now
        self.beats += 1


class Watchdog(threading.Thread):
    """Dumps every thread's stack when the heartbeat is silent for ``hang_s``, then kills the
    engine process (which frees a GUI thread blocked on it) so the test can fail instead of hang."""

    def __init__(self, heartbeat: Heartbeat, engine_pid=lambda: None, hang_s: float = 10.0, out=None):
        super().__init__(name="inkface-watchdog", daemon=True)
        self.heartbeat = heartbeat
        self.engine_pid = engine_pid
        self.hang_s = hang_s
        self.out = out or sys.stderr
        self.hung = False
        self._stop = threading.Event()

    def stop(self) -> None:
        self._stop.set()

    def run(self) -> None:
        while not self._stop.wait(0.25):
            silent = time.monotonic() - self.heartbeat.last
            if silent < self.hang_s:
                continue
            self.hung = True
            print(f"\n=== watchdog: the GUI event loop has been silent for {silent:.1f} s; stacks follow ===",
                  file=self.out, flush=True)
            faulthandler.dump_traceback(file=self.out, all_threads=True)
            pid = self.engine_pid()
            if pid:
                if hasattr(signal, "SIGUSR1"):
                    try:
                        os.kill(pid, signal.SIGUSR1)  # the engine dumps its own stacks
                        time.sleep(1.0)
                    except OSError:
                        pass
                try:
                    os.kill(pid, signal.SIGKILL if hasattr(signal, "SIGKILL") else signal.SIGTERM)
                except OSError:
                    pass
            if self._stop.wait(20.0):
                return
            if time.monotonic() - self.heartbeat.last > 20.0:
                print("=== watchdog: still hung after killing the engine; exiting ===", file=self.out, flush=True)
                faulthandler.dump_traceback(file=self.out, all_threads=True)
                os._exit(3)
            return
