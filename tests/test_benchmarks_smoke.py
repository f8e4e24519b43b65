"""`python -m benchmarks --quick` runs every registered benchmark without failing."""

import subprocess
import sys

import pytest


@pytest.mark.slow
def test_benchmarks_quick_run_exits_zero():
    r = subprocess.run([sys.executable, "-m", "benchmarks", "--quick"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "## " in r.stdout and "machine:" in r.stdout and "libraries: numpy " in r.stdout


def test_the_header_names_the_libraries_and_a_host_yardstick():
    """The header says which numpy and OpenCV made the figures (a new OpenCV decodes the same clip a
    little differently) and how fast this host runs plain Python (the per-frame cost scales with it)."""
    import cv2
    import numpy as np

    from benchmarks.harness import host_speed, libraries

    line = libraries()
    assert f"numpy {np.__version__}" in line and f"OpenCV {cv2.__version__}" in line
    ms = host_speed(n=20_000, repeats=2)
    assert 0.0 < ms < 10_000.0
