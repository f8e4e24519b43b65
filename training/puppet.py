"""The live pipeline: frame → tracker → filter → expression maps → renderer → RGBA frame.

Used by the performance window, the network receiver and the headless ``render`` command.
``Puppet.step(frame_bgr, index, time)`` tracks a camera / video frame; ``Puppet.step_params``
starts from ten values (a recorded track or network packets). Both return a :class:`PuppetFrame`
with the premultiplied RGBA character, the values used, the tracker's overlay, the weights of
each part and per-stage timings in milliseconds.

Per frame: the ten values are made scale-free (:mod:`training.features`), missing values are
held from the last good frame, the temporal filter runs on the 10-vector, then (at the paper's
10 / 15 / 30 fps output rates) the average of the last 3 / 2 / 1 filtered frames goes to the
expression maps of the eyes (k = 4) and mouth (k = 3) and the head pose to the compositor.
Between outputs at a lower rate the previous picture is returned with ``fresh = False``.
When the face is lost the last pose and expression are held for ``hold_s`` seconds, then ease
back to neutral over ``ease_s`` seconds.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tracker.params import LOST, MOUTH_LOST, FaceParams
from training.features import EYES, MOUTH, FeatureSpace
from training.filters import Chain, RateFilter, make_filter

__all__ = ["Puppet", "PuppetFrame"]


@dataclass
class PuppetFrame:
    """One output of the puppet.

    ``rgba_pm``: premultiplied RGBA uint8 ``(h, w, 4)`` of the art set's canvas; ``params``: the
    frame's tracked values (FaceParams, as measured); ``overlay``: the tracker's overlay (None for
    ``step_params``); ``weights``: ``{"eyes": (idx3, w3), "mouth": (idx3, w3)}`` (a part without
    training shows its rest drawing: None); ``timings_ms``: per stage; ``fresh``: False when the
    output rate held the previous picture; ``features``: the filtered scale-free 10-vector.
    """

    rgba_pm: np.ndarray | None
    params: FaceParams
    overlay: Any = None
    weights: dict = field(default_factory=dict)
    timings_ms: dict = field(default_factory=dict)
    fresh: bool = True
    features: np.ndarray | None = None
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0)


def _load_artset(artset):
    if isinstance(artset, (str, Path)):
        from art_sets.io import load_artset
        from art_sets.library import find_artset

        return load_artset(find_artset(artset))
    return artset


class Puppet:
    """Drive a character from a performer.

    ``artset``: an ArtSet (or its name / folder); ``calibration``: a tracker Calibration (None: for
    ``step`` the first frame is auto-initialised; for ``step_params`` the session's performer is
    assumed, else the neutral face is estimated from the first frames); ``session``: a
    TrainingSession (None: the automatic default training); ``fps``: output rate 10, 15 or 30
    (from ``input_fps``); ``filter``: a name from :data:`training.filters.FILTERS` or a filter
    object; ``strength`` 0..1 scales the smoothing; ``mapper``: ``"convex"`` (default),
    ``"delaunay"`` (the paper's), ``"cardinal"`` or ``"ridge"`` — the default is the convex fit
    because the paper's 2-D projection can put the neutral drawing next to a sliver triangle, so
    tracker noise on a still face swings the eyes to a ghostly blend of other drawings; ``gain`` scales head motion (0 = still,
    1 = as performed); ``expression_gain`` scales the expression around neutral (> 1 caricature);
    ``renderer``: a ready ``CharacterRenderer`` (built here if None); ``style``: switch on the
    expression-driven style (tremble and warm tint when the brows are raised high);
    ``follow_scale``: in ``step``, rescale lengths by the tracked pupils' distance so leaning in or
    out does not read as an expression (``step_params`` has no such measurement).
    """

    def __init__(
        self,
        artset,
        calibration=None,
        session=None,
        fps: int = 30,
        filter="gate+one_euro",
        strength: float = 0.5,
        mapper: str = "convex",
        gain: float = 1.0,
        expression_gain: float = 1.0,
        detail: bool = False,
        renderer=None,
        input_fps: float = 30.0,
        style: bool = False,
        hold_s: float = 1.0,
        ease_s: float = 0.5,
        features: FeatureSpace | None = None,
        follow_scale: bool = True,
    ):
        self.artset = _load_artset(artset)
        if session is None:
            from training.defaults import default_session

            session = default_session(self.artset)
        session.check(self.artset)
        self.session = session
        self.calibration = calibration
        self._features_given = features
        self.features: FeatureSpace | None = features
        if self.features is None and calibration is not None:
            self.features = FeatureSpace.from_calibration(calibration)
        self.input_fps = float(input_fps)
        self.fps = int(fps)
        self.filter_name = filter if isinstance(filter, str) else getattr(filter, "name", "custom")
        self._filter_obj = None if isinstance(filter, str) else filter
        self.strength = float(strength)
        self.mapper_name = mapper
        self.expression_gain = float(expression_gain)
        self.style = bool(style)
        self.follow_scale = bool(follow_scale)
        self.hold_frames = max(0, int(round(hold_s * self.input_fps)))
        self.ease_frames = max(1, int(round(ease_s * self.input_fps)))
        if renderer is None:
            from morph.renderer import CharacterRenderer

            renderer = CharacterRenderer(self.artset, gain=gain, detail=detail)
        self.renderer = renderer
        # canvas pixels of head motion per inter-pupil distance the performer moves away from the
        # calibrated (neutral) position: a tenth of the canvas width, so ordinary drift moves the
        # character a little; the renderer's keep-in-frame limit handles the extremes
        self.pose_scale = 0.1 * float(self.artset.canvas[0])
        self.tracker = None
        self._fit()
        self._build_filter()
        self.reset()

    # ------------------------------------------------------------------------ configuration
    def _fit(self) -> None:
        self.maps = self.session.fit(self.artset, mapper=self.mapper_name)

    def _build_filter(self) -> None:
        if self._filter_obj is not None:
            base = self._filter_obj
        else:
            db = None
            if self.filter_name == "chai" and self.session.reference_track is not None:
                db = self.session.feature_space().normalise(self.session.reference_track)
            base = make_filter(self.filter_name, fps=self.input_fps, database=db)
            _apply_strength(base, self.strength)
        self.rate = RateFilter.for_fps(self.fps, self.input_fps)
        self.filter = Chain([base, self.rate])

    def configure(self, fps=None, filter=None, strength=None, gain=None, mapper=None, expression_gain=None, style=None) -> None:
        """Change settings on the fly (the filter restarts when its settings change)."""
        rebuild = False
        if fps is not None and int(fps) != self.fps:
            self.fps = int(fps)
            rebuild = True
        if filter is not None:
            name = filter if isinstance(filter, str) else getattr(filter, "name", "custom")
            if name != self.filter_name or not isinstance(filter, str):
                self.filter_name = name
                self._filter_obj = None if isinstance(filter, str) else filter
                rebuild = True
        if strength is not None and float(strength) != self.strength:
            self.strength = float(strength)
            rebuild = True
        if gain is not None:
            self.renderer.gain = float(gain)
        if expression_gain is not None:
            self.expression_gain = float(expression_gain)
        if style is not None:
            self.style = bool(style)
        if mapper is not None and mapper != self.mapper_name:
            self.mapper_name = mapper
            self._fit()
        if rebuild:
            self._build_filter()
            self.filter.reset()

    def set_session(self, session) -> None:
        """Use another training session (refits the maps)."""
        session.check(self.artset)
        self.session = session
        self._fit()
        if self.filter_name == "chai":
            self._build_filter()

    def reset(self) -> None:
        """Forget the past (filter state, held values, tracker state)."""
        self.filter.reset()
        self._last_good: np.ndarray | None = None
        self._last_out: np.ndarray | None = None
        self._last_frame: PuppetFrame | None = None
        self._lost = 0
        self._frame_no = 0
        self._seen: list[np.ndarray] = []
        self._scale = 1.0
        self._scale_n = 0
        if self.tracker is not None:
            self.tracker.reset()

    # --------------------------------------------------------------------------- stepping
    def _ensure_tracker(self, frame_bgr: np.ndarray) -> bool:
        if self.tracker is not None:
            return True
        from tracker.calibration import calibrate
        from tracker.face_tracker import FaceTracker

        if self.calibration is None:
            try:
                from tracker.auto_init import auto_clicks
            except ImportError:
                return False
            try:
                clicks = auto_clicks(frame_bgr)
            except Exception:  # AutoInitError and friends: try again on a later frame
                return False
            self.calibration = calibrate(frame_bgr, clicks)
        if self._features_given is None:
            self.features = FeatureSpace.from_calibration(self.calibration)
        self.tracker = FaceTracker(self.calibration)
        return True

    def step(self, frame_bgr: np.ndarray, index: int = 0, time: float = 0.0) -> PuppetFrame:
        """Track one camera / video frame (BGR uint8) and draw the character."""
        t0 = _time.perf_counter()
        if not self._ensure_tracker(frame_bgr):
            params = FaceParams.from_values(np.full(10, np.nan), frame=index, time=time, status=LOST, confidence=0.0)
            return self._advance(params, None, {"track": (_time.perf_counter() - t0) * 1000.0})
        res = self.tracker.track(frame_bgr, index=index, time=time)
        overlay = getattr(res, "overlay", None)
        self._update_scale(overlay, res.params)
        t1 = _time.perf_counter()
        return self._advance(res.params, overlay, {"track": (t1 - t0) * 1000.0}, self._scale)

    def _update_scale(self, overlay, params: FaceParams) -> None:
        """Follow the performer leaning in and out: the ten values carry no current inter-pupil
        distance, but the tracker's overlay has both pupils. Lengths are rescaled by calibrated /
        current ipd (smoothed; leaning is slow) before they are made scale-free."""
        if not self.follow_scale or overlay is None or params.status == LOST or self.features is None:
            return
        pupils = getattr(overlay, "pupils", None)
        if pupils is None:
            return
        pupils = np.asarray(pupils, dtype=np.float64)
        if pupils.shape != (2, 2) or not np.all(np.isfinite(pupils)):
            return
        cur = float(np.hypot(*(pupils[1] - pupils[0])))
        if cur <= 0.25 * self.features.ipd or cur >= 4.0 * self.features.ipd:
            return  # a mis-tracked pupil, not a lean
        target = self.features.ipd / cur
        self._scale = target if self._scale_n == 0 else self._scale + 0.3 * (target - self._scale)
        self._scale_n += 1

    def step_params(self, params: FaceParams) -> PuppetFrame:
        """Draw the character for ten already-tracked values (a track row or a network packet)."""
        return self._advance(params, None, {})

    def _feature_space(self, v: np.ndarray) -> FeatureSpace | None:
        if self.features is not None:
            return self.features
        if self.session.features is not None:
            # no calibration of our own: assume the session's performer
            self.features = self.session.features
            return self.features
        if np.all(np.isfinite(v)):
            self._seen.append(v)
        if len(self._seen) >= 1:
            self.features = FeatureSpace.estimate(np.array(self._seen))
        return self.features

    def _advance(self, params: FaceParams, overlay, timings: dict, scale: float = 1.0) -> PuppetFrame:
        t0 = _time.perf_counter()
        v = params.values()
        if scale != 1.0:
            v[3:] *= scale
        fs = self._feature_space(v)
        lost = params.status == LOST or fs is None or not np.any(np.isfinite(v))
        if lost:
            self._lost += 1
            z = self._held_values()
        else:
            self._lost = 0
            z = fs.normalise(np.where(np.isfinite(v), v, np.nan))
            if params.status == MOUTH_LOST:
                z[MOUTH] = np.nan
            bad = ~np.isfinite(z)
            if bad.any():
                z[bad] = self._last_good[bad] if self._last_good is not None else 0.0
            self._last_good = z.copy()
        t = params.time if params.time else None
        zf = self.filter.filters[0].step(z, t)
        z = self.rate.step(zf, t)
        t1 = _time.perf_counter()
        timings["filter"] = (t1 - t0) * 1000.0
        if z is None:  # the output rate holds the previous picture
            last = self._last_frame
            if last is None:  # nothing shown yet: a provisional picture, not an output frame
                return self._draw(zf, params, overlay, timings, t1, fresh=False)
            return PuppetFrame(last.rgba_pm, params, overlay, last.weights, timings, False, last.features, last.pose)
        return self._draw(z, params, overlay, timings, t1, fresh=True)

    def _draw(self, z: np.ndarray, params: FaceParams, overlay, timings: dict, t1: float, fresh: bool) -> PuppetFrame:
        self._last_out = z
        zg = z.copy()
        if self.expression_gain != 1.0:
            zg[3:] *= self.expression_gain
        weights = {}
        for part, sl in (("eyes", EYES), ("mouth", MOUTH)):
            m = self.maps.get(part)
            weights[part] = None if m is None else m.weights(zg[sl])
        pose = (float(z[0]) * self.pose_scale, float(z[1]) * self.pose_scale, float(z[2]) * 180.0 / math.pi)
        t2 = _time.perf_counter()
        timings["map"] = (t2 - t1) * 1000.0
        level = self._style_level(z) if self.style else 0.0
        rgba = self.renderer.render(eyes=weights["eyes"], mouth=weights["mouth"], pose=pose, frame_no=self._frame_no, style_level=level)
        self._frame_no += 1
        t3 = _time.perf_counter()
        timings["render"] = (t3 - t2) * 1000.0
        frame = PuppetFrame(rgba, params, overlay, weights, timings, fresh, z, pose)
        self._last_frame = frame
        return frame

    def _held_values(self) -> np.ndarray | None:
        """What to show while the face is lost: hold, then ease towards neutral (zero)."""
        if self._last_good is None:
            return np.zeros(10)
        if self._lost <= self.hold_frames:
            return self._last_good
        k = min(1.0, (self._lost - self.hold_frames) / self.ease_frames)
        return self._last_good * (1.0 - k)

    def _style_level(self, z: np.ndarray) -> float:
        from morph.style import style_level

        brow = 0.5 * (z[5] + z[6])  # brow raise above neutral, in inter-pupil distances
        return style_level(brow, 0.12, 0.2)


def _apply_strength(f, strength: float) -> None:
    """Scale smoothing by ``strength`` 0..1 (0.5 = the filter's defaults)."""
    s = float(np.clip(strength, 0.0, 1.0))
    for g in getattr(f, "filters", [f]):
        if hasattr(g, "min_cutoff"):
            g.min_cutoff = 1.0 * 10.0 ** (1.0 - 2.0 * s)  # 10 Hz .. 1 Hz .. 0.1 Hz
        others = getattr(g, "others", None)
        if others is not None and hasattr(others, "min_cutoff"):
            others.min_cutoff = 1.0 * 10.0 ** (1.0 - 2.0 * s)
