"""A DISPLAY that points at nothing: one line and a non-zero exit for the windows, a headless
render for the demo — never Qt's abort in the xcb plugin."""

from __future__ import annotations

import os
import socket
import subprocess
import sys

import pytest


def _dead_display() -> str:
    """A display number with no X server (neither its socket file nor its abstract socket)."""
    for n in range(99, 300):
        path = f"/tmp/.X11-unix/X{n}"
        if os.path.exists(path):
            continue
        try:
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
                s.connect("\0" + path)
            continue
        except OSError:
            return f":{n}"
    pytest.skip("no free X display number")


def _run(*args: str, cwd=None, timeout: float = 120) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env.pop("QT_QPA_PLATFORM", None)
    env.pop("WAYLAND_DISPLAY", None)
    env["DISPLAY"] = _dead_display()
    return subprocess.run([sys.executable, "-m", "app", *args], capture_output=True, text=True, timeout=timeout,
                          env=env, cwd=cwd)  # fmt: skip


@pytest.mark.parametrize("args, words", [([], ["cannot open a window", "X display"]),
                                         (["edit"], ["needs a screen", "X display"])])  # fmt: skip
def test_windows_say_one_line_and_exit(args, words):
    r = _run(*args)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("inkface: "), lines
    assert all(w in lines[0] for w in words)


def test_demo_renders_headless_instead(tmp_path):
    out = tmp_path / "demo.mp4"
    r = _run("demo", "--seconds", "1", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert "rendering the demo to a file instead" in r.stderr and out.stat().st_size > 1000


def test_display_problem_without_a_display(monkeypatch):
    from app import qt_env

    monkeypatch.delenv("QT_QPA_PLATFORM", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setenv("DISPLAY", _dead_display())
    assert not qt_env.has_display() and "X display" in qt_env.display_problem()
    monkeypatch.setenv("DISPLAY", "not a display")
    assert "not an X display name" in qt_env.display_problem()
    monkeypatch.delenv("DISPLAY")
    assert "DISPLAY" in qt_env.display_problem()
    monkeypatch.setenv("QT_QPA_PLATFORM", "offscreen")
    assert not qt_env.has_display()
