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


def test_the_lip_blob_finder_takes_no_second_look(tmp_path, monkeypatch):
    """A mouth the old lip-blob finder puts too high is refused as it always was: the second looks
    (from the last line, or from the valleys under the refused one) belong to the 1-D mouth finder,
    whose ``find`` takes them, and the old one is not asked for them (it does not know them)."""
    from tracker import face_tracker as ftm
    from tracker.params import MOUTH_LOST

    perf = Performance(seconds=0.2, seed=2)
    frames = [perf.frame(i) for i in range(len(perf))]
    cal = calibrate(frames[0], Clicks.from_dict(perf.clicks()))
    cal.mouth_model = None
    for hair in (False, True):
        tracker = FaceTracker(cal)
        assert isinstance(tracker.mouth_finder, LegacyMouth)
        tracker._hair = hair
        assert str(tracker.track(frames[0]).overlay.status) == "ok"
        calls = []
        real = LegacyMouth.find

        def find(self, crop, at):
            calls.append(at)
            return real(self, crop, at)

        monkeypatch.setattr(LegacyMouth, "find", find)
        monkeypatch.setattr(ftm.FaceTracker, "_misplaced", lambda self, *a, **k: "high")
        assert tracker.track(frames[1]).params.status == MOUTH_LOST
        assert len(calls) == 1
        monkeypatch.undo()
