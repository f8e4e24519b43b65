"""Read the shared real clips: frames, the peer's per-frame points and parameters, the clicks.

The clips live in ``../shared/real/`` (relative to the project root) or wherever
``INKFACE_REAL`` points; every reader returns ``None`` / an empty list when they are absent,
so benchmarks and tests skip cleanly on a clone without them.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

POINT_NAMES = (
    "left_pupil", "right_pupil", "left_upper_lid", "left_lower_lid", "right_upper_lid", "right_lower_lid",
    "left_brow", "right_brow", "left_mouth_corner", "right_mouth_corner", "upper_lip_top", "lower_lip_bottom",
)


def real_dir() -> Path | None:
    """The folder of real clips, or None when it is not there."""
    env = os.environ.get("INKFACE_REAL")
    cands = [Path(env)] if env else []
    cands.append(Path(__file__).resolve().parent.parent.parent / "shared" / "real")
    cands.append(Path("../shared/real"))
    for c in cands:
        if c.is_dir() and any(c.glob("*.mp4")):
            return c
    return None


def clip_names() -> list[str]:
    d = real_dir()
    if d is None:
        return []
    return sorted(p.stem for p in d.glob("*.mp4") if (d / f"{p.stem}.points.csv").exists())


@dataclass
class RealClip:
    """One clip: ``frames`` (BGR uint8), ``points[name]`` (n, 2) frame px, ``params[col]`` (n,), ``clicks`` dict."""

    name: str
    frames: list[np.ndarray]
    points: dict[str, np.ndarray]
    params: dict[str, np.ndarray]
    clicks: dict

    def __len__(self) -> int:
        return len(self.frames)


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) if r[k] not in ("", "nan") else np.nan for r in rows]) for k in rows[0]}


def load_clip(name: str, max_frames: int | None = None) -> RealClip | None:
    """Decode clip ``name`` (all frames, or the first ``max_frames``) with its peer data."""
    d = real_dir()
    if d is None:
        return None
    cap = cv2.VideoCapture(str(d / f"{name}.mp4"))
    frames = []
    while max_frames is None or len(frames) < max_frames:
        ok, img = cap.read()
        if not ok:
            break
        frames.append(img)
    cap.release()
    pts = _read_csv(d / f"{name}.points.csv")
    params = _read_csv(d / f"{name}.mp.csv")
    n = min(len(frames), len(pts["frame"]))
    points = {p: np.stack([pts[f"{p}_x"][:n], pts[f"{p}_y"][:n]], axis=1) for p in POINT_NAMES}
    params = {k: v[:n] for k, v in params.items()}
    clicks = json.loads((d / f"{name}.clicks.json").read_text())
    return RealClip(name, frames[:n], points, params, clicks)
