"""`python -m benchmarks --quick` runs every registered benchmark without failing."""

import subprocess
import sys

import pytest


@pytest.mark.slow
def test_benchmarks_quick_run_exits_zero():
    r = subprocess.run([sys.executable, "-m", "benchmarks", "--quick"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "## " in r.stdout and "machine:" in r.stdout
