"""training.constellation: five points shaped like a face pass, a detector's mistakes do not."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from training.constellation import constellation_problems, face_frame, lip_contrast

REAL = Path(__file__).resolve().parents[1] / ".." / "shared" / "real"

# a frontal face in a 640×480 frame: ipd 80 px
FACE = {"left_pupil": (280.0, 200.0), "right_pupil": (360.0, 200.0), "left_brow": (275.0, 166.0),
        "right_brow": (365.0, 166.0), "mouth": (320.0, 296.0)}
SIZE = (640, 480)
# what the Haar-cascade auto start found on a tilted, open-mouthed frame of the bundled
# performance (frame 320): all five round the image-left eye and brow
CLUSTER = {"left_pupil": (235.0, 162.0), "right_pupil": (275.0, 150.0), "left_brow": (228.0, 140.0),
           "right_brow": (267.0, 122.0), "mouth": (273.0, 197.0)}


def _moved(pts, angle_deg=0.0, scale=1.0, shift=(0.0, 0.0), about=(320.0, 240.0)):
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    out = {}
    for k, (x, y) in pts.items():
        dx, dy = x - about[0], y - about[1]
        out[k] = (about[0] + scale * (c * dx + s * dy) + shift[0], about[1] + scale * (-s * dx + c * dy) + shift[1])
    return out


def test_a_frontal_face_is_plausible_and_its_frame_is_upright():
    assert constellation_problems(FACE, frame_size=SIZE) == []
    ipd, roll, u, up = face_frame(FACE)
    assert ipd == pytest.approx(80.0) and roll == pytest.approx(0.0)
    assert u == pytest.approx((1.0, 0.0)) and up == pytest.approx((0.0, -1.0))
    # roll is positive when the image-right pupil is higher (DESIGN.md)
    assert face_frame(_moved(FACE, 20.0))[1] == pytest.approx(20.0)


@settings(max_examples=80, deadline=None)
@given(st.floats(-40, 40), st.floats(0.5, 1.6), st.floats(-60, 60), st.floats(-30, 30))
def test_tilted_scaled_and_moved_faces_stay_plausible(angle, scale, dx, dy):
    assert constellation_problems(_moved(FACE, angle, scale, (dx, dy)), frame_size=SIZE) == []


@pytest.mark.parametrize("change, words", [
    ({"left_pupil": (360.0, 200.0), "right_pupil": (280.0, 200.0)}, "swapped"),
    ({"mouth": (320.0, 150.0)}, "mouth is not below"),
    ({"mouth": (320.0, 220.0)}, "too close under"),
    ({"mouth": (320.0, 480.0 - 1)}, "below the eyes"),
    ({"mouth": (420.0, 296.0)}, "side of the face"),
    ({"left_brow": (275.0, 215.0)}, "image-left eyebrow is not above"),
    ({"right_brow": (365.0, 80.0)}, "image-right eyebrow is"),
    ({"right_brow": (440.0, 166.0)}, "far to the side"),
    ({"left_brow": (275.0, 190.0), "right_brow": (365.0, 130.0)}, "much higher"),
    ({"mouth": (320.0, 500.0)}, "outside the frame"),
])
def test_mistakes_are_named(change, words):
    problems = constellation_problems({**FACE, **change}, frame_size=SIZE)
    assert problems and any(words in p for p in problems), problems
    assert all("\n" not in p for p in problems)


def test_points_bunched_round_one_feature_are_too_small_for_a_face():
    tiny = _moved(FACE, 0.0, 0.15, about=(280.0, 200.0))  # the whole face shrunk onto one eye
    problems = constellation_problems(tiny, frame_size=SIZE)
    assert problems and "bunched" in problems[0]
    assert constellation_problems(_moved(FACE, 90.0), frame_size=SIZE)  # head on its side


def test_missing_or_broken_points_are_not_judged_or_named():
    assert constellation_problems({k: v for k, v in FACE.items() if k != "mouth"}) == []
    assert constellation_problems({**FACE, "mouth": (float("nan"), 1.0)}) == ["some points are not numbers"]


@pytest.fixture(scope="module")
def performance():
    from tracker.synthetic import Performance

    return Performance(seconds=20.0, seed=0)  # the bundled performance the window plays first


def test_the_synthetic_performers_true_points_pass_on_every_kind_of_frame(performance):
    """Tilted, open-mouthed, blinking frames: the truth is always plausible, lips included."""
    from tracker.synthetic import clicks_for

    for i in range(0, len(performance), 15):
        frame = performance.frame(i)
        pts = clicks_for(performance.state(i), i)
        assert constellation_problems(pts, frame) == [], i


def test_the_cluster_round_one_eye_on_a_tilted_open_mouthed_frame_is_caught(performance):
    frame = performance.frame(320)
    t = performance.truth(320)
    assert abs(t.roll_deg) > 15 and t.lip_lower > 15  # the frame of the report: tilted, mouth open
    problems = constellation_problems(CLUSTER, frame)
    assert problems and "lips" in " ".join(problems)
    # the same constellation without the picture is not caught: the lips are what gives it away
    assert constellation_problems(CLUSTER, frame_size=(frame.shape[1], frame.shape[0])) == []
    ipd = math.dist(CLUSTER["left_pupil"], CLUSTER["right_pupil"])
    from tracker.synthetic import clicks_for

    truth = clicks_for(performance.state(320), 320)
    true_ipd = math.dist(truth["left_pupil"], truth["right_pupil"])
    mid = np.add(truth["left_pupil"], truth["right_pupil"]) / 2
    centre = (mid + np.asarray(truth["mouth"])) / 2
    assert lip_contrast(frame, truth["mouth"], true_ipd, centre) > 10
    assert lip_contrast(frame, CLUSTER["mouth"], ipd, (np.asarray(CLUSTER["mouth"]) + CLUSTER["left_pupil"]) / 2) < 4


@pytest.mark.skipif(not REAL.is_dir(), reason="the real clips of ../shared/real are not here")
def test_every_frame_of_the_real_clips_is_plausible():
    """A landmark tracker's points on nine real faces (expressions, head turns, a child, glasses)."""
    import cv2

    n = 0
    for f in sorted(REAL.glob("*.points.csv")):
        rows = list(csv.DictReader(f.open()))
        cap = cv2.VideoCapture(str(f.with_name(f.name.replace(".points.csv", ".mp4"))))
        for i, r in enumerate(rows):
            ok, frame = cap.read()
            if not ok:
                break
            g = lambda k: (float(r[k + "_x"]), float(r[k + "_y"]))  # noqa: E731
            pts = {k: g(k) for k in ("left_pupil", "right_pupil", "left_brow", "right_brow")}
            pts["mouth"] = tuple(np.add(g("left_mouth_corner"), g("right_mouth_corner")) / 2)
            problems = constellation_problems(pts, frame if i % 10 == 0 else None,
                                              frame_size=(frame.shape[1], frame.shape[0]))
            assert problems == [], (f.name, i, problems)
            n += 1
    assert n > 2000
