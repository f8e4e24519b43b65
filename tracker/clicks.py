"""The five calibration clicks (CLICKS.json in ``shared/DESIGN.md``).

``left_*`` is the feature on the image's left. Points are ``(x, y)`` float pixels of frame
``frame`` of the video; ``mouth`` is the mouth centre, the brows are the middle of each brow.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

from tracker import atomic_file, safe_json

POINT_KEYS: tuple[str, ...] = ("left_pupil", "right_pupil", "left_brow", "right_brow", "mouth")
"""The clicked points, in file order."""
MAX_COORD = 1e6
"""Largest coordinate (px) accepted; points outside the frame are refused later by ``check_inside``."""
MAX_FILE_BYTES = 1024 * 1024


PIXEL_CENTRE = 0.5
"""Where a pixel's centre lies in the coordinates of files and the command line (CLICKS.json, the
track CSV): pixel ``(i, j)`` covers ``[i, i + 1) × [j, j + 1)`` measured from the image's top-left
corner, as in MediaPipe, Qt and most drawing tools. The tracker works inside in OpenCV's convention
(pixel centres at whole numbers) and moves points by this on the way in and out."""


class ClicksError(ValueError):
    """A clicks file or dictionary is unusable; the message is one line naming the problem."""


Point = tuple[float, float]


def _point(d: dict, key: str, where: str) -> Point:
    x, y = safe_json.numbers(d[key], f"{where}: '{key}' [x, y]", 2, ClicksError, -MAX_COORD, MAX_COORD)
    return (x, y)


@dataclass(frozen=True)
class Clicks:
    """Where a person clicked on the calibration frame."""

    frame: int
    left_pupil: Point
    right_pupil: Point
    left_brow: Point
    right_brow: Point
    mouth: Point

    @classmethod
    def from_dict(cls, d: dict, where: str = "clicks") -> "Clicks":
        """Parse the CLICKS.json dictionary; ``where`` names the source in error messages."""
        if not isinstance(d, dict):
            raise ClicksError(f"{where}: expected a JSON object, got {type(d).__name__}")
        missing = [k for k in ("frame",) + POINT_KEYS if k not in d]
        if missing:
            raise ClicksError(f"{where}: missing key(s) {', '.join(missing)}")
        fr = safe_json.integer(d["frame"], f"{where}: 'frame' (a frame index)", ClicksError, 0, int(safe_json.MAGNITUDE))
        pts = {k: _point(d, k, where) for k in POINT_KEYS}
        c = cls(frame=fr, **pts)
        if c.left_pupil[0] >= c.right_pupil[0]:
            raise ClicksError(f"{where}: left_pupil must be left of right_pupil in the image (x {c.left_pupil[0]:g} >= {c.right_pupil[0]:g})")
        if c.ipd() < 4.0:
            raise ClicksError(f"{where}: the pupils are only {c.ipd():.1f} px apart")
        return c

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Clicks":
        """Read a CLICKS.json file; raises :class:`ClicksError` naming the file."""
        path = Path(path)
        atomic_file.sweep_temp(path.parent)
        d = safe_json.read(path, "clicks file", max_bytes=MAX_FILE_BYTES, error=ClicksError)
        return cls.from_dict(d, where=str(path))

    def to_dict(self) -> dict:
        d: dict = {"frame": self.frame}
        for k in POINT_KEYS:
            d[k] = [float(getattr(self, k)[0]), float(getattr(self, k)[1])]
        return d

    def save(self, path: str | os.PathLike) -> None:
        """Write CLICKS.json atomically."""
        atomic_file.write_text(Path(path), json.dumps(self.to_dict(), indent=2) + "\n")

    def moved(self, dx: float, dy: float) -> "Clicks":
        """These clicks with every point moved by ``(dx, dy)`` px."""
        return Clicks(frame=self.frame, **{k: (x + dx, y + dy) for k, (x, y) in self.points().items()})

    def points(self) -> dict[str, Point]:
        return {k: getattr(self, k) for k in POINT_KEYS}

    def ipd(self) -> float:
        """Distance between the clicked pupils, in pixels."""
        (x0, y0), (x1, y1) = self.left_pupil, self.right_pupil
        return math.hypot(x1 - x0, y1 - y0)

    def check_inside(self, frame_size: tuple[int, int], where: str = "clicks") -> None:
        """Raise :class:`ClicksError` if a point lies outside a ``(w, h)`` frame."""
        w, h = frame_size
        for k, (x, y) in self.points().items():
            if not (0 <= x < w and 0 <= y < h):
                raise ClicksError(f"{where}: '{k}' ({x:g}, {y:g}) is outside the {w}x{h} frame")
