"""Calibrations saved by earlier versions keep tracking (with the finders they were made for)."""

from __future__ import annotations

import json

from tracker.calibration import Calibration, calibrate
from tracker.clicks import Clicks
from tracker.face_tracker import FaceTracker
from tracker.legacy import LegacyMouth
from tracker.synthetic import Performance


def test_a_first_format_mouth_model_falls_back_to_the_lip_blob_finder(tmp_path):
    perf = Performance(seconds=0.5, seed=2)
    frames = [perf.frame(i) for i in range(len(perf))]
    cal = calibrate(frames[0], Clicks.from_dict(perf.clicks()))
    path = tmp_path / "old.calibration.json"
    cal.save(path)
    d = json.loads(path.read_text())
    d["mouth_model"] = {**d["mouth_model"], "format": 1}  # as saved before the 1-D mouth finder
    path.write_text(json.dumps(d))
    old = Calibration.load(path)
    assert old.mouth_model is None
    tracker = FaceTracker(old)
    assert isinstance(tracker.mouth_finder, LegacyMouth)
    statuses = [str(tracker.track(f).overlay.status) for f in frames]
    assert statuses.count("ok") >= len(frames) - 2, statuses
