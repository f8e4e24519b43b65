"""Automatic default training, so the demo works with no set-up.

For an art set, each drawing is paired with the synthetic performer (``tracker.synthetic``) making
the matching expression, found by the drawing's name: a mouth called ``"smile"`` is paired with
``EXPRESSIONS["smile"]``, an eyes drawing called ``"open"`` with the neutral face, and so on
(:data:`ALIASES` lists the names that differ). The ten values of those frames are the synthetic
performer's exact truth, so nothing is tracked or cached: a session takes a few milliseconds.
The performer's calibration (ipd, neutral face) comes with it, and a scripted performance serves
as the reference clip (for diagnostics and the Chai filter's database).

Drawings whose name matches no expression are left unpaired (listed in the session's notes):
the map never picks them.
"""

from __future__ import annotations

import numpy as np

from training.features import FeatureSpace
from training.session import TrainingSession

__all__ = ["ALIASES", "default_session", "expression_for", "synthetic_reference"]

ALIASES: dict[str, dict[str, str]] = {
    "eyes": {
        "open": "neutral",
        "rest": "neutral",
        "normal": "neutral",
        "closed": "eyes_closed",
        "shut": "eyes_closed",
        "wide": "wide",
        "surprised": "wide",
        "raised": "brows_up",
        "up": "brows_up",
        "angry": "brows_angry",
        "frown": "brows_angry",
        "half": "blink",
        "sleepy": "blink",
    },
    "mouth": {
        "rest": "neutral",
        "closed": "neutral",
        "a": "ah",
        "o": "oo",
        "e": "ee",
        "u": "oo",
        "open": "ah",
        "sad": "frown",
        "surprise": "surprise",
    },
}
"""Drawing names (lower case) that are not themselves synthetic expression names."""

REFERENCE_SECONDS = 20.0
REFERENCE_SEED = 101


def expression_for(part: str, drawing_name: str) -> str | None:
    """The synthetic expression that matches drawing ``drawing_name`` of ``part``, or None."""
    from tracker.synthetic import EXPRESSIONS

    key = drawing_name.strip().lower()
    alias = ALIASES.get(part, {}).get(key)
    if alias is not None:
        return alias
    if key in EXPRESSIONS:
        return key
    return None


def _neutral_state():
    from tracker.synthetic import FaceState, Performance

    perf = Performance(seconds=1.0 / 30.0)
    return perf.state(0) if hasattr(perf, "state") else FaceState()


def synthetic_reference(seconds: float = REFERENCE_SECONDS, seed: int = REFERENCE_SEED) -> np.ndarray:
    """Ten values per frame of a scripted synthetic performance (the default reference clip)."""
    from tracker.synthetic import Performance

    perf = Performance(seconds=seconds, seed=seed)
    return np.array([perf.truth(i).values() for i in range(len(perf))])


def default_session(artset, thumbnails: bool = False, reference: bool = True) -> TrainingSession:
    """A training session of ``artset`` against the synthetic performer (in memory, no path).

    ``thumbnails`` renders each paired synthetic frame for the pair's thumbnail (slower);
    ``reference`` adds a scripted performance's values as the reference track.
    """
    from tracker.synthetic import face_truth, render_face

    base = _neutral_state()
    neutral = face_truth(base)
    fs = FeatureSpace.from_values(base.ipd, neutral)
    s = TrainingSession(artset.name, fs, calibration_ref="synthetic", reference_clip="", autosave=False)
    frame = 0
    for part in ("eyes", "mouth"):
        for d in artset.parts[part].drawings:
            expr = expression_for(part, d.name)
            if expr is None:
                s.notes.append(f"{part}/{d.name}: no synthetic expression of that name; left unpaired")
                continue
            state = base.with_expression(expr)
            truth = face_truth(state, frame=frame)
            image = render_face(state)[0] if thumbnails else None
            s.add_pair(part, d.name, truth, frame=frame, image=image)
            frame += 1
    if reference:
        s.reference_clip = f"synthetic:seconds={REFERENCE_SECONDS:g},seed={REFERENCE_SEED}"
        s.reference_track = synthetic_reference()
    return s
