"""Timing and table helpers shared by every benchmark.

A benchmark is a function registered with :func:`benchmark`; it returns one or more
:class:`Table` objects. ``python -m benchmarks`` runs them all and prints the tables.
Times are wall-clock on one core (the process pins itself to one CPU where it can).
"""

from __future__ import annotations

import math
import os
import platform
import statistics
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np

_REGISTRY: list[tuple[str, Callable[["Context"], Iterable["Table"]]]] = []


@dataclass
class Context:
    """Options every benchmark receives: ``quick`` shortens runs (for smoke tests)."""

    quick: bool = False

    def runs(self, full: int, quick: int = 3) -> int:
        return quick if self.quick else full


def benchmark(name: str):
    """Register ``fn(ctx) -> Table | list[Table]`` under ``name``."""

    def deco(fn):
        _REGISTRY.append((name, fn))
        return fn

    return deco


def registered() -> list[tuple[str, Callable]]:
    return list(_REGISTRY)


@dataclass
class Timing:
    """Wall-clock times of repeated calls, in milliseconds."""

    samples_ms: list[float]

    @property
    def runs(self) -> int:
        return len(self.samples_ms)

    @property
    def median(self) -> float:
        return statistics.median(self.samples_ms)

    @property
    def lo(self) -> float:
        return min(self.samples_ms)

    @property
    def hi(self) -> float:
        return max(self.samples_ms)

    def cells(self) -> list[str]:
        """``[runs, median, min–max]`` formatted for a table row."""
        return [str(self.runs), f"{self.median:.3f}", f"{self.lo:.3f}–{self.hi:.3f}"]


def time_call(fn: Callable[[], object], runs: int, warmup: int = 2) -> Timing:
    """Call ``fn`` ``warmup`` times untimed, then ``runs`` times timed."""
    for _ in range(warmup):
        fn()
    out = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        out.append((time.perf_counter() - t0) * 1000.0)
    return Timing(out)


def time_each(fn: Callable[[object], object], items: list, warmup: int = 2) -> Timing:
    """Time ``fn(item)`` once per item (e.g. per video frame) after ``warmup`` untimed calls."""
    for it in items[:warmup]:
        fn(it)
    out = []
    for it in items:
        t0 = time.perf_counter()
        fn(it)
        out.append((time.perf_counter() - t0) * 1000.0)
    return Timing(out)


TIMING_COLUMNS = ["runs", "median ms", "min–max ms"]


@dataclass
class Table:
    """A titled table of strings; ``note`` is printed under it."""

    title: str
    columns: list[str]
    rows: list[list[str]] = field(default_factory=list)
    note: str = ""

    def add(self, *cells) -> None:
        self.rows.append([c if isinstance(c, str) else _cell(c) for c in cells])

    def render(self) -> str:
        widths = [len(c) for c in self.columns]
        for r in self.rows:
            for i, c in enumerate(r):
                widths[i] = max(widths[i], len(c))
        line = lambda cells: "  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip()
        out = [f"## {self.title}", line(self.columns), line(["-" * w for w in widths])]
        out += [line(r) for r in self.rows]
        if self.note:
            out.append(self.note)
        return "\n".join(out)


def _cell(v) -> str:
    if isinstance(v, float):
        return f"{v:.3f}" if abs(v) < 1000 else f"{v:.0f}"
    if isinstance(v, list):
        return ", ".join(_cell(x) for x in v)
    return str(v)


def machine() -> str:
    """One line naming the machine the numbers were measured on."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for ln in f:
                if ln.startswith("model name"):
                    cpu = ln.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}; {os.cpu_count()} cores; Python {platform.python_version()}; {platform.system()} {platform.release()}"


def libraries() -> str:
    """One line naming the versions of the libraries the numbers depend on: a new OpenCV build
    decodes the same video a little differently, and the real-face figures move with it."""
    out = [f"numpy {np.__version__}"]
    for name, label in (("cv2", "OpenCV"), ("scipy", "SciPy"), ("PySide6", "PySide6")):
        try:
            out.append(f"{label} {__import__(name).__version__}")
        except Exception:  # pragma: no cover - not installed
            out.append(f"{label} absent")
    return ", ".join(out)


def host_speed(n: int = 1_000_000, repeats: int = 5) -> float:
    """Milliseconds a fixed pure-Python loop (``n`` additions) takes here, best of ``repeats``: a
    yardstick for comparing one host's times with another's (the per-frame cost is mostly Python
    and small numpy calls, which scale with it)."""
    best = math.inf
    for _ in range(repeats):
        t = time.perf_counter()
        s = 0
        for i in range(n):
            s += i
        best = min(best, time.perf_counter() - t)
    return best * 1000.0


def pin_one_core() -> str:
    """Restrict this process (and numpy/OpenCV threads) to one core; say what was done."""
    try:
        import cv2

        cv2.setNumThreads(1)
    except Exception:  # pragma: no cover - OpenCV missing
        pass
    if hasattr(os, "sched_setaffinity"):
        try:
            cpu = sorted(os.sched_getaffinity(0))[0]
            os.sched_setaffinity(0, {cpu})
            return f"pinned to CPU {cpu}"
        except OSError:
            pass
    return "not pinned"
