"""Kill-during-save harness: ``python tests/kill_saves.py SAVER TRIALS SEED FOLDER`` prints JSON.

For each trial a forked child saves two versions of one document into FOLDER in a loop
(the one not on disk first, then the other, …), writing a byte to a pipe after each save that
returned; the parent SIGKILLs it after a random delay (up to a save and a quarter), reaps it, and
loads what is on disk with the document's own loader. The result must be exactly the last
version whose save returned ("old") or the one being saved ("new"); anything else ("mixed", or a
load error) is counted. After the load no temporary file may be left (loaders sweep them) and
the folder may hold no more files than the two versions name.

Forking from this process (imports done once, no threads) keeps a trial at a few milliseconds;
the suite runs it as a subprocess so pytest's own threads never meet a fork.
"""

from __future__ import annotations

import copy
import json
import os
import random
import signal
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import cv2  # noqa: E402

cv2.setNumThreads(0)  # no worker pool in a process that forks

from art_sets.atomic_file import is_temp  # noqa: E402


# --------------------------------------------------------------------------- the documents
def _artset(seed: int, n_mouths: int):
    from test_art_sets import tiny_artset

    art = tiny_artset(3, n_mouths, seed)
    art.pivot = (32.0, 50.5 + seed)
    return art


def _artset_key(art) -> tuple:
    """Everything a loader gives back, as something comparable."""
    parts = tuple((n, tuple(p.box), tuple((d.name, d.image.tobytes(), d.lines.round(6).tobytes()) for d in p.drawings))
                  for n, p in sorted(art.parts.items()))
    return (art.name, tuple(art.canvas), tuple(art.pivot), tuple(h.tobytes() for h in art.heads), parts)


class ArtSetSaver:
    """``art_sets.save_artset`` (the editor's Save goes through it too)."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.versions = [_artset(0, 3), _artset(1, 4)]
        self.keys = [_artset_key(v) for v in self.versions]

    def save(self, i: int) -> None:
        from art_sets.editing import clone
        from art_sets.io import save_artset

        save_artset(clone(self.versions[i]), self.folder)

    def load(self):
        from art_sets.io import load_artset

        return _artset_key(load_artset(self.folder))


class AutosaveSaver(ArtSetSaver):
    """The editor's side copy (``write_side_copy``, with its cache of arrays already written)."""

    def __init__(self, folder: Path):
        super().__init__(folder)
        self.cache: dict = {}

    def save(self, i: int) -> None:
        from app.editor.document import write_side_copy
        from art_sets.editing import clone

        write_side_copy(clone(self.versions[i]), self.folder, self.cache)

    def load(self):
        from app.editor.document import load_tolerant

        return _artset_key(load_tolerant(self.folder))


def _calibrations():
    from tracker.calibration import calibrate
    from tracker.clicks import Clicks
    from tracker.synthetic import FaceState, clicks_for, render_face

    base = FaceState(cx=320.0, cy=210.0, ipd=80.0)
    frame, _ = render_face(base)
    a = calibrate(frame, Clicks.from_dict(clicks_for(base)))
    b = copy.copy(a)
    b.ipd = a.ipd + 1.5
    b.eye_templates = [np.clip(t + 17, 0, 255) for t in a.eye_templates]
    b.pupil = copy.copy(a.pupil)
    b.pupil.table = (255 - a.pupil.table).astype(np.uint8)
    return [a, b]


def _calibration_key(c) -> tuple:
    return (round(c.ipd, 6), tuple(t.tobytes() for t in c.eye_templates), c.pupil.table.tobytes(),
            c.lip.table.tobytes(), c.eye.table.tobytes())


class CalibrationSaver:
    def __init__(self, folder: Path):
        self.path = folder / "me.json"
        self.versions = _calibrations()
        self.keys = [_calibration_key(v) for v in self.versions]

    def save(self, i: int) -> None:
        self.versions[i].save(self.path)

    def load(self):
        from tracker.calibration import Calibration

        return _calibration_key(Calibration.load(self.path))


def _session(k: int):
    from training.features import FeatureSpace
    from training.session import TrainingSession

    s = TrainingSession("Kill", FeatureSpace.from_values(80.0, [320, 240, 0, 12, 12, 30, 30, 64, 10, 12]), autosave=False)
    rng = np.random.default_rng(k)
    for j in range(4 + k):
        v = np.array([320, 240, 0, 12, 12, 30, 30, 64, 10, 12], float) + rng.normal(0, 2, 10)
        s.add_pair("mouth" if j % 2 else "eyes", f"d{j}", v, frame=j * 3 + k, image=rng.integers(0, 256, (48, 64, 3), dtype=np.uint8))
    if k:
        s.remove_pair(0)
    return s


def _session_key(s) -> tuple:
    return tuple((p.part, p.drawing, p.frame, tuple(round(v, 6) for v in p.values),
                  None if p.thumbnail is None else p.thumbnail.tobytes()) for p in s.pairs)


class SessionSaver:
    def __init__(self, folder: Path):
        self.folder = folder
        self.versions = [_session(0), _session(1)]
        self.keys = [_session_key(v) for v in self.versions]

    def save(self, i: int) -> None:
        s = copy.deepcopy(self.versions[i])
        s.path = None
        s.save(self.folder)

    def load(self):
        from training.session import TrainingSession

        return _session_key(TrainingSession.load(self.folder))


class ClicksSaver:
    def __init__(self, folder: Path):
        from tracker.clicks import Clicks

        self.path = folder / "clicks.json"
        base = {"frame": 0, "left_pupil": [280, 210], "right_pupil": [360, 210], "left_brow": [280, 178],
                "right_brow": [360, 178], "mouth": [320, 292]}
        self.versions = [Clicks.from_dict(base), Clicks.from_dict({**base, "frame": 7, "mouth": [321.5, 290]})]
        self.keys = self.versions

    def save(self, i: int) -> None:
        self.versions[i].save(self.path)

    def load(self):
        from tracker.clicks import Clicks

        return Clicks.load(self.path)


SAVERS = {"artset": ArtSetSaver, "autosave": AutosaveSaver, "calibration": CalibrationSaver,
          "session": SessionSaver, "clicks": ClicksSaver}


# --------------------------------------------------------------------------- the trials
def _files(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if p.is_file()]


def _child(saver, first: int, w: int) -> None:
    try:
        i = first
        while True:
            saver.save(i)
            os.write(w, b"x")
            i = 1 - i
    finally:
        os._exit(0)


def run(name: str, trials: int, seed: int, folder: Path) -> dict:
    rnd = random.Random(seed)
    folder.mkdir(parents=True, exist_ok=True)
    saver = SAVERS[name](folder)
    saver.save(1)  # the first save imports what saving needs: not timed
    t0 = time.perf_counter()
    for i in (0, 1, 0, 1):
        saver.save(i)
    per_save = (time.perf_counter() - t0) / 4
    on_disk = 0
    out = {"saver": name, "trials": trials, "old": 0, "new": 0, "mixed": 0, "errors": [], "temp_left": 0,
           "max_files": 0, "save_ms": round(per_save * 1000, 2)}
    both_versions = set()
    for i in (0, 1):
        saver.save(i)
        both_versions |= {p.relative_to(folder) for p in _files(folder)}
    saver.save(0)
    on_disk = 0
    for _ in range(trials):
        r, w = os.pipe()
        first = 1 - on_disk
        pid = os.fork()
        if pid == 0:
            os.close(r)
            _child(saver, first, w)
        os.close(w)
        time.sleep(rnd.uniform(0.0, 1.25 * per_save) + 0.001)
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        done = 0
        while chunk := os.read(r, 65536):
            done += len(chunk)
        os.close(r)
        old = on_disk if done == 0 else (first + done - 1) % 2
        new = 1 - old
        try:
            got = saver.load()
        except Exception as e:  # counted, not raised: the report says what broke
            out["errors"].append(f"{type(e).__name__}: {e}"[:300])
            saver.save(on_disk)
            continue
        if got == saver.keys[old]:
            out["old"] += 1
            on_disk = old
        elif got == saver.keys[new]:
            out["new"] += 1
            on_disk = new
        else:
            out["mixed"] += 1
            saver.save(on_disk)
            continue
        files = _files(folder)
        out["temp_left"] += sum(is_temp(p.name) for p in files)
        out["max_files"] = max(out["max_files"], len(files))
    out["files_of_both_versions"] = len(both_versions)
    return out


if __name__ == "__main__":
    saver, n, seed, where = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), Path(sys.argv[4])
    print(json.dumps(run(saver, n, seed, where)))
