"""A test clip whose face comes late: an empty wall first, then the synthetic performer."""

from pathlib import Path

import cv2
import numpy as np

from tracker.synthetic import Performance


def write_late_face_clip(path: Path, empty: int, perf: Performance, faces: int | None = None, fps: float = 30.0) -> Performance:
    """Write ``empty`` frames of a plain wall, then the first ``faces`` (default: all) frames of
    ``perf``, to ``path`` (lossless FFV1 in .avi); returns ``perf``."""
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), fps, perf.frame_size)
    assert w.isOpened()
    wall = np.full((perf.frame_size[1], perf.frame_size[0], 3), (150, 160, 170), np.uint8)
    try:
        for _ in range(empty):
            w.write(wall)
        for i in range(len(perf) if faces is None else faces):
            w.write(perf.frame(i))
    finally:
        w.release()
    return perf
