"""Calibrating on open eyes: clicks made on a blink carried on to a frame where the eyes show.

A blink lasts 3-5 frames and comes every few seconds, so one clicked frame in ten or twenty
catches the lids down (a user clicking a live picture, or the first frame of a clip that starts
mid-blink). Calibration cuts the eye pictures and learns the lids from that frame, and an eye
model learned from shut eyes misreads the whole clip: of the shared clips started 40 % of the way
in, two first frames had the eyes shut, and on the one whose eyes open within a second (expr_d19)
the pupils were 5 % of the eye distance off at the median, where calibrating on its open eyes
leaves 1.4 %.

:func:`carry_clicks` follows the head from the clicked frame with the tracker's own sparse optical
flow (:class:`~tracker.head_motion.HeadMotion`), moves all five clicks with its rigid motion, and
calibrates on the first later frame whose eyes show (:func:`~tracker.auto_init.eyes_shown`).
``--auto`` does the same by finding the face afresh on each frame it tries
(:data:`~tracker.track_cli.AUTO_LOOK`); clicks are a person's choice of points, so they are carried,
not found again.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from tracker.auto_init import EYES_SHOWN, eyes_shown
from tracker.clicks import PIXEL_CENTRE, POINT_KEYS, Clicks
from tracker.face_tracker import face_outline
from tracker.head_motion import FLOW_IPD, HeadMotion, apply, compose

LOOK = (30, 2)
"""Frames after the clicked one to look at for open eyes, and every how many frames to test them
(the head is followed on every frame): a blink is over within a few frames, and a second is as far
as a head turned away or a hand in front of the face should carry the clicks."""
CARRY_IPD = 2.0 * FLOW_IPD
"""Inter-pupil distance (px) the head is followed at while carrying clicks (the tracker follows it at
:data:`~tracker.head_motion.FLOW_IPD`, and the finders put it right on every frame): the motions of a
second's frames add up, and at the tracker's scale their small errors in the head's turn had the
synthetic performer's brow clicks 2.5 px off after eight frames (0.3 px at this one)."""


def face_polygon(clicks: Clicks) -> np.ndarray:
    """The region (polygon, tracker px) whose corners the flow follows: the tracker's own
    (:func:`~tracker.face_tracker.face_outline`) about the clicked pupils."""
    return face_outline(np.asarray(clicks.left_pupil) - PIXEL_CENTRE, np.asarray(clicks.right_pupil) - PIXEL_CENTRE)


def moved_clicks(clicks: Clicks, matrix: np.ndarray, frame: int) -> Clicks:
    """``clicks`` moved by a 2×3 motion (tracker px → tracker px), now on frame ``frame``."""
    pts = np.array([clicks.points()[k] for k in POINT_KEYS], dtype=np.float64) - PIXEL_CENTRE
    q = apply(matrix, pts) + PIXEL_CENTRE
    return Clicks(frame=int(frame), **{k: (float(x), float(y)) for k, (x, y) in zip(POINT_KEYS, q.tolist())})


def carry_clicks(frame_bgr: np.ndarray, clicks: Clicks, later: Iterable[tuple[int, np.ndarray]],
                 look: tuple[int, int] = LOOK) -> tuple[Clicks, np.ndarray]:
    """The clicks and the frame to calibrate on: ``clicks`` and ``frame_bgr`` (the clicked frame)
    when its eyes show (:data:`~tracker.auto_init.EYES_SHOWN`); else the clicks carried with the
    head's motion through ``later`` ((index, BGR) frames following the clicked one, in order) to
    the first frame within ``look[0]`` frames, every ``look[1]``-th, whose eyes show. The clicked
    frame stays when none does (a person whose eyes that measure does not read: the clicks are
    their choice), or when the head could not be followed (covered, gone, cut to another shot)."""
    if eyes_shown(frame_bgr, clicks) >= EYES_SHOWN:
        return clicks, frame_bgr
    flow = HeadMotion()
    flow.set_scale(clicks.ipd(), CARRY_IPD)
    poly = face_polygon(clicks)
    if flow.seed(frame_bgr, poly) < flow.min_inliers:
        return clicks, frame_bgr
    total = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    for index, img in later:
        step = index - clicks.frame
        if step <= 0:
            continue
        if step > look[0]:
            break
        motion = flow.step(img, lambda: apply(total, poly))
        if motion is None:
            break
        total = compose(motion.matrix, total)
        if step % max(look[1], 1):
            continue
        moved = moved_clicks(clicks, total, index)
        h, w = img.shape[:2]
        if not all(0 <= x < w and 0 <= y < h for x, y in moved.points().values()):
            break
        if eyes_shown(img, moved) >= EYES_SHOWN:
            return moved, img
    return clicks, frame_bgr


def carried_note(given: Clicks, used: Clicks, where: str) -> str | None:
    """The one-line note a command prints when :func:`carry_clicks` moved ``given`` (from ``where``,
    e.g. the clicks file) to ``used``; None when it did not."""
    if used.frame == given.frame:
        return None
    return (f"the eyes look shut on frame {given.frame} ({where}): calibrated on frame {used.frame}, "
            "the clicks carried there with the head")
