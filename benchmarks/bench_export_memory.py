"""Memory of the long-running outputs: a GIF export and ``receive`` over ten minutes of frames.

Each case runs in a fresh child process that reports its resident set (``VmRSS``) after the first
minute of frames and at the end; a writer or receiver that kept something per frame would grow
linearly (the GIF export used to hold ~544 kB a frame, ``receive`` ~450 bytes a frame).
Ten minutes at 30 fps = 18,000 frames, growth from the 1,800th (``--quick``: 900 frames of a
smaller picture, growth from the 300th).
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile

from app.net import Receiver
from benchmarks.harness import Table, benchmark

_RSS = """
def rss():
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS:"))
"""

_GIF = _RSS + """
import json, sys, numpy as np
from app.record import FrameWriter
n, warm, side, out = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
w = FrameWriter(out, fps=30.0, background=(255, 255, 255))
yy, xx = np.mgrid[0:side, 0:side]
img = np.zeros((side, side, 4), np.uint8)
marks = {}
for i in range(n):
    img[:] = 0
    disc = (xx - side / 2 - side / 4 * np.sin(i / 20)) ** 2 + (yy - side / 2) ** 2 < (side / 6) ** 2
    img[disc] = (200, 60, 40, 255)
    img[i % side, :, 3] = 255
    w.write(img)
    if i + 1 in (warm, n):
        marks[i + 1] = rss()
w.close()
print(json.dumps({"first": marks[warm], "last": marks[n], "frames": w.frames}))
"""

_RECEIVE = _RSS + """
import argparse, json, sys
import numpy as np
from pathlib import Path
from app import net_cmd
from app.net import Hello
from tracker.params import FaceParams, ParamCodec, encode_packet
n, warm, folder, outputs = int(sys.argv[1]), int(sys.argv[2]), Path(sys.argv[3]), sys.argv[4] == "all"
frame, ipd = (640, 480), 80.0
codec = ParamCodec(frame, ipd)
base = FaceParams(mid_x=320, mid_y=220, eye_open_l=14, eye_open_r=15, brow_l=30, brow_r=31, mouth_width=62,
                  lip_upper=7, lip_lower=10).values()
codes = [codec.encode(FaceParams.from_values(base + np.sin(i / 9.0) * 5)) for i in range(600)]
hello = Hello(7, frame, ipd, compressed=False, key_interval=30, neutral_codes=codes[0]).encode()

from benchmarks.bench_export_memory import FedReceiver

def datagrams():
    for i in range(n):
        if i % 300 == 0:
            yield hello
        yield encode_packet(codes[i % 600], i, 33 * i)

marks = {}
class Marking(net_cmd._TrackFiles):
    def add(self, rx, f):
        super().add(rx, f)
        if self.frames in (warm, n):
            marks[self.frames] = rss()
names = ("r.csv", "r.ifs", "r.fap") if outputs else (None, None, None)
args = argparse.Namespace(frames=None, timeout=0, wait=0, quiet=True,
                          **{k: (str(folder / v) if v else None) for k, v in zip(("csv", "record", "fap"), names)})
net_cmd._session(args, FedReceiver(datagrams()), None, Marking(args), "benchmark")
print(json.dumps({"first": marks[warm], "last": marks[n], "frames": n}))
"""


class _Clock:
    """A clock the fed receiver advances by one frame (1/30 s) per datagram."""

    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


class FedReceiver(Receiver):
    """The receiver core fed from an iterable of datagrams instead of a socket (``poll`` hands
    out ``per_poll`` at a time; the end of the data stops the session as Ctrl+C does)."""

    def __init__(self, datagrams, per_poll: int = 50) -> None:
        self._clock = _Clock()
        super().__init__(clock=self._clock)
        self._data = iter(datagrams)
        self.per_poll = per_poll
        self.address = ("127.0.0.1", 0)

    def poll(self, timeout: float = 0.0, max_datagrams: int = 1000):
        out = []
        for _ in range(self.per_poll):
            d = next(self._data, None)
            if d is None:
                if not out:
                    raise KeyboardInterrupt
                break
            self._clock.t += 1 / 30
            f = self.handle(d, "A")
            if f is not None:
                out.append(f)
        return out


def _child(code: str, *argv: str) -> dict:
    r = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "child failed")
    return json.loads(r.stdout.strip().splitlines()[-1])


@benchmark("export_memory")
def run(ctx):
    n, warm, side = (900, 300, 128) if ctx.quick else (18000, 1800, 256)
    t = Table("Long outputs: resident memory after the first minute and at the end (fresh process each)",
              ["output", "frames", "RSS first MB", "RSS end MB", "growth", "budget"])
    with tempfile.TemporaryDirectory() as tmp:
        cases = [(f"GIF export, {side}×{side}", _GIF, (str(n), str(warm), str(side), f"{tmp}/a.gif")),
                 ("receive, no outputs", _RECEIVE, (str(n), str(warm), tmp, "none")),
                 ("receive, --csv --record --fap", _RECEIVE, (str(n), str(warm), tmp, "all"))]
        for name, code, argv in cases:
            r = _child(code, *argv)
            growth = (r["last"] - r["first"]) / r["first"]
            t.add(name, str(r["frames"]), f"{r['first'] / 1024:.1f}", f"{r['last'] / 1024:.1f}", f"{100 * growth:+.2f} %",
                  "flat (GIF), < 1 % (receive)")
    t.note = (f"frames {warm + 1}..{n} of a 30 fps stream ({n / 1800:.0f} min); "
              "RSS moves in whole pages, so a flat line reads +0.00 %")
    return t
