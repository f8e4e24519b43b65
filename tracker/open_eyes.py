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
calibrates on the first later frame whose eyes show (:func:`~tracker.auto_init.eyes_shown`). Where
the head moves too fast for the flow before that (the ``late`` copy of talk_b: a blink on frame 0
as she leans in, the flow lost by frame 2), the points are found afresh on the later frames
(:func:`found_afresh`), near where the clicked face was: calibrated on the shut eyes, that copy's
opening followed the peer at r 0.70; found afresh on frame 4, 0.91.
``--auto`` does the same by finding the face afresh on each frame it tries
(:data:`~tracker.track_cli.AUTO_LOOK`); clicks are a person's choice of points, so they are carried,
not found again.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from tracker.auto_init import EYES_SHOWN, AutoInitError, auto_clicks, eyes_shown
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


AFRESH_NEAR = 1.0
"""Farthest (× the clicked inter-pupil distance) the pupils' midpoint of a face found afresh
(:func:`found_afresh`) may lie from the clicked one's, and the most its eye distance may differ
(as a ratio, 1 + this) — the clicked person, a moment later, not someone else in the picture."""


def found_afresh(frame_bgr: np.ndarray, index: int, clicks: Clicks) -> Clicks | None:
    """The five points found by machine (:func:`~tracker.auto_init.auto_clicks`) on ``frame_bgr``
    (frame ``index``) for the face ``clicks`` were made on, or None: no face there, or the face found
    lies further from the clicked one than a head moves in a moment (:data:`AFRESH_NEAR`)."""
    try:
        found = auto_clicks(frame_bgr, frame_index=index)
    except AutoInitError:
        return None
    ipd, got = clicks.ipd(), found.ipd()
    mid = 0.5 * (np.asarray(clicks.left_pupil) + np.asarray(clicks.right_pupil))
    there = 0.5 * (np.asarray(found.left_pupil) + np.asarray(found.right_pupil))
    if float(np.hypot(*(there - mid))) > AFRESH_NEAR * ipd or not 1.0 / (1.0 + AFRESH_NEAR) < got / max(ipd, 1e-9) < 1.0 + AFRESH_NEAR:
        return None
    return found


def carry_clicks(frame_bgr: np.ndarray, clicks: Clicks, later: Iterable[tuple[int, np.ndarray]],
                 look: tuple[int, int] = LOOK) -> tuple[Clicks, np.ndarray]:
    """The clicks and the frame to calibrate on: ``clicks`` and ``frame_bgr`` (the clicked frame)
    when its eyes show (:data:`~tracker.auto_init.EYES_SHOWN`); else the clicks carried with the
    head's motion through ``later`` ((index, BGR) frames following the clicked one, in order) to
    the first frame within ``look[0]`` frames, every ``look[1]``-th, whose eyes show. Where the head
    moves too fast to follow before such a frame (a blink as the performer leans in), the points
    are found afresh (:func:`found_afresh`) on the frames left in the look instead: the clicked
    points on shut eyes would teach calibration shut eyes. The clicked frame stays when no frame
    shows the eyes (a person whose eyes that measure does not read: the clicks are their choice), or
    when the face is not there to follow or find (covered, gone, cut to another shot)."""
    if eyes_shown(frame_bgr, clicks) >= EYES_SHOWN:
        return clicks, frame_bgr
    flow: HeadMotion | None = HeadMotion()
    flow.set_scale(clicks.ipd(), CARRY_IPD)
    poly = face_polygon(clicks)
    if flow.seed(frame_bgr, poly) < flow.min_inliers:
        flow = None
    total = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    for index, img in later:
        step = index - clicks.frame
        if step <= 0:
            continue
        if step > look[0]:
            break
        if flow is not None:
            motion = flow.step(img, lambda: apply(total, poly))
            if motion is None:
                flow = None
            else:
                total = compose(motion.matrix, total)
        if step % max(look[1], 1):
            continue
        if flow is None:
            moved = found_afresh(img, index, clicks)
            if moved is None:
                continue
        else:
            moved = moved_clicks(clicks, total, index)
            h, w = img.shape[:2]
            if not all(0 <= x < w and 0 <= y < h for x, y in moved.points().values()):
                break
        if eyes_shown(img, moved) >= EYES_SHOWN:
            return moved, img
    return clicks, frame_bgr


def carried_note(given: Clicks, used: Clicks, where: str) -> str | None:
    """The one-line note a command prints when :func:`carry_clicks` moved ``given`` (from ``where``,
    e.g. the clicks file) to ``used``; None when it did not. Carried clicks are the given ones under
    one motion of the head, a similarity to rounding; points found afresh are not."""
    if used.frame == given.frame:
        return None
    zs, zd = (np.array([complex(*c.points()[k]) for k in POINT_KEYS]) for c in (given, used))
    ds, dd = zs - zs.mean(), zd - zd.mean()
    a = complex(np.vdot(ds, dd) / max(float(np.vdot(ds, ds).real), 1e-12))  # least-squares similarity
    off = float(np.abs(a * ds - dd).max())
    how = ("the clicks carried there with the head" if off <= 1e-6 * max(used.ipd(), 1.0)
           else "the points found there afresh (the head moved too fast to carry the clicks)")
    return f"the eyes look shut on frame {given.frame} ({where}): calibrated on frame {used.frame}, {how}"
