"""Temporal filters for the parameter stream, applied before mapping.

All filters run on the scale-free 10-vector of :meth:`training.features.FeatureSpace.normalise`
(lengths in inter-pupil distances, roll in radians), so their settings do not depend on camera
resolution or distance. Interface: ``step(z, t) -> z' | None`` (``None``: no output this frame,
only :class:`RateFilter` does that) and ``reset()``.

* :class:`RateFilter` — the paper's lower output rates: 10 / 15 fps from 30 fps input, each
  output the average of the 3 / 2 tracked frames since the last one.
* :class:`OneEuroFilter` — adaptive low-pass (Casiez et al. 2012): smooth when still, quick when moving.
* :class:`OutlierGate` — Williams 1990: replace a sample only when it is far from a smoothed
  estimate of the recent past; a jump that persists is accepted after ``max_hold`` frames.
* :class:`GatedOneEuro` — the gate, then One-Euro; a jump the gate has confirmed as real (it
  persisted) is passed straight through instead of being smoothed again, so fast motion such
  as a blink reaches the drawing while a still face stays as smooth as with One-Euro alone.
* :class:`ChaiFilter` — data-driven filter (Chai, Xiao & Hodgins 2003): the last W frames are
  projected onto a local PCA model of the K most similar windows of the performer's own training
  clip (99 % variance kept); overlapping windows' estimates are cross-faded.
* :class:`Chain` — filters in sequence.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Sequence

import numpy as np

__all__ = [
    "FILTERS",
    "Chain",
    "GatedOneEuro",
    "ChaiFilter",
    "Identity",
    "OneEuroFilter",
    "OutlierGate",
    "RateFilter",
    "make_filter",
]


class Identity:
    """No filtering."""

    name = "none"
    lag_frames = 0

    def step(self, z: np.ndarray, t: float | None = None) -> np.ndarray:
        return np.asarray(z, dtype=np.float64)

    def reset(self) -> None:
        pass


class RateFilter:
    """Output every ``group``-th input frame, the mean of the last ``group`` frames (paper §4)."""

    def __init__(self, group: int):
        if group < 1:
            raise ValueError(f"group must be >= 1, got {group}")
        self.group = int(group)
        self.name = f"rate/{group}"
        self.lag_frames = (group - 1) / 2.0
        self.reset()

    @classmethod
    def for_fps(cls, out_fps: float, in_fps: float = 30.0) -> "RateFilter":
        """The paper's 10 / 15 / 30 fps: average 3 / 2 / 1 frames of a 30 fps input."""
        if not out_fps > 0:
            raise ValueError(f"output frame rate must be positive, got {out_fps}")
        return cls(max(1, int(round(in_fps / out_fps))))

    def reset(self) -> None:
        self._sum = None
        self._count = 0

    def step(self, z: np.ndarray, t: float | None = None) -> np.ndarray | None:
        z = np.asarray(z, dtype=np.float64)
        self._sum = z.copy() if self._sum is None else self._sum + z
        self._count += 1
        if self._count < self.group:
            return None
        out = self._sum / self._count
        self._sum = None
        self._count = 0
        return out


class OneEuroFilter:
    """One-Euro filter per channel.

    ``min_cutoff`` (Hz) sets the smoothing of a still signal; ``beta`` (per unit/s) raises the
    cutoff with speed so fast motion is not delayed; ``d_cutoff`` (Hz) smooths the speed estimate.
    Times come from ``t`` (seconds) or, when missing, from ``fps``.
    """

    name = "one_euro"

    def __init__(self, min_cutoff: float = 1.0, beta: float = 4.0, d_cutoff: float = 1.0, fps: float = 30.0):
        self.min_cutoff = float(min_cutoff)
        self.beta = float(beta)
        self.d_cutoff = float(d_cutoff)
        self.fps = float(fps)
        self.lag_frames = 0
        self.reset()

    def reset(self) -> None:
        self._x = None
        self._dx = None
        self._t = None

    @staticmethod
    def _alpha(cutoff, dt):
        tau = 1.0 / (2.0 * math.pi * cutoff)
        return 1.0 / (1.0 + tau / dt)

    def step(self, z: np.ndarray, t: float | None = None) -> np.ndarray:
        z = np.asarray(z, dtype=np.float64)
        if self._x is None:
            self._x = z.copy()
            self._dx = np.zeros_like(z)
            self._t = t
            return self._x.copy()
        dt = (t - self._t) if (t is not None and self._t is not None and t > self._t) else 1.0 / self.fps
        self._t = t
        dx = (z - self._x) / dt
        a_d = self._alpha(self.d_cutoff, dt)
        self._dx = self._dx + a_d * (dx - self._dx)
        cutoff = self.min_cutoff + self.beta * np.abs(self._dx)
        a = 1.0 / (1.0 + 1.0 / (2.0 * math.pi * cutoff * dt))
        self._x = self._x + a * (z - self._x)
        return self._x.copy()


class OutlierGate:
    """Williams-style outlier gate.

    The estimate is the median of the last ``window`` outputs. A channel whose new sample differs
    from it by more than ``max(floor, k · noise)`` is replaced by the estimate; ``noise`` is a
    running mean absolute deviation of accepted samples (×1.25 ≈ σ for Gaussian noise). A change
    still present after ``max_hold`` replaced frames is real motion and is accepted: present means
    on the same side of the estimate and at least half as far as the last replaced sample (two
    glitches in opposite directions are not a persistent change).
    ``floor`` is in the filter's units (inter-pupil distances / radians).
    """

    name = "gate"

    def __init__(self, window: int = 3, k: float = 4.0, floor: float = 0.04, max_hold: int = 1, rate: float = 0.05):
        self.window = int(window)
        self.k = float(k)
        self.floor = float(floor)
        self.max_hold = int(max_hold)
        self.rate = float(rate)
        self.lag_frames = 0
        self.reset()

    def reset(self) -> None:
        self._hist: deque = deque(maxlen=self.window)
        self._noise = None
        self._held = None
        self._rej = None
        self.confirmed: np.ndarray | None = None
        """Channels whose last step accepted a held-back jump as real motion (bool mask)."""

    def step(self, z: np.ndarray, t: float | None = None) -> np.ndarray:
        z = np.asarray(z, dtype=np.float64)
        if not self._hist:
            self._hist.append(z.copy())
            self._noise = np.zeros_like(z)
            self._held = np.zeros(len(z), dtype=np.int64)
            self._rej = np.zeros(len(z))
            self.confirmed = np.zeros(len(z), dtype=bool)
            return z.copy()
        est = np.median(np.array(self._hist), axis=0)
        sdev = z - est
        dev = np.abs(sdev)
        thr = np.maximum(self.floor, self.k * 1.25 * self._noise)
        bad = dev > thr
        persists = (sdev * self._rej > 0) & (dev >= 0.5 * np.abs(self._rej))
        force = bad & (self._held >= self.max_hold) & persists
        bad &= ~force
        self._rej = np.where(bad, sdev, 0.0)
        self.confirmed = force
        out = np.where(bad, est, z)
        self._held = np.where(bad, self._held + 1, 0)
        good = ~bad & ~force
        self._noise = np.where(good, self._noise + self.rate * (dev - self._noise), self._noise)
        if force.any():
            # a persistent jump: restart the estimate at the new level for those channels
            for h in self._hist:
                h[force] = z[force]
        self._hist.append(out.copy())
        return out


class GatedOneEuro:
    """:class:`OutlierGate` then :class:`OneEuroFilter`, cooperating.

    The gate already holds back a large change for ``max_hold`` frames and accepts it only when
    it persists; smoothing that confirmed change again with One-Euro (whose speed estimate needs
    several frames to open its cutoff) would halve a fast blink. So on the channels where the
    gate has just confirmed a jump the output takes the new value and the One-Euro state
    restarts there. A still face never triggers the gate, so it is smoothed exactly as by
    One-Euro alone. ``filters`` = ``[gate, one_euro]`` for callers that tune the parts.
    """

    name = "gate+one_euro"

    def __init__(self, gate: OutlierGate | None = None, smooth: OneEuroFilter | None = None, fps: float = 30.0):
        self.gate = gate if gate is not None else OutlierGate()
        self.smooth = smooth if smooth is not None else OneEuroFilter(fps=fps)
        self.filters = [self.gate, self.smooth]
        self.lag_frames = 0

    def reset(self) -> None:
        self.gate.reset()
        self.smooth.reset()

    def step(self, z: np.ndarray, t: float | None = None) -> np.ndarray:
        g = self.gate.step(z, t)
        out = self.smooth.step(g, t)
        jump = self.gate.confirmed
        if jump is not None and jump.any():
            self.smooth._x[jump] = g[jump]
            self.smooth._dx[jump] = 0.0
            out[jump] = g[jump]
        return out


def _gauss_smooth(x: np.ndarray, sigma: float) -> np.ndarray:
    if sigma <= 0 or len(x) < 3:
        return x
    r = int(math.ceil(3 * sigma))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    pad = np.pad(x, ((r, r), (0, 0)), mode="edge")
    out = np.empty_like(x)
    for c in range(x.shape[1]):
        out[:, c] = np.convolve(pad[:, c], k, mode="valid")
    return out


class ChaiFilter:
    """Data-driven filter over windows of the performer's training clip.

    ``database`` ``(N, d)``: the training clip in the same units as the input (scale-free
    10-vectors); it is smoothed offline (zero-phase Gaussian, ``db_smooth`` frames) and cut into
    all windows of ``window`` frames. Each step takes the last ``window`` input frames, finds the
    ``k`` nearest database windows, fits a PCA to them keeping ``variance`` of their variance,
    projects and reconstructs the input window. The output frame is ``delay`` frames back; its
    estimates from the ``delay + 1`` most recent windows are cross-faded with raised-cosine
    weights by their position in the window. Until ``window`` frames have arrived the input
    passes through.

    ``channels`` (indices) limits the data-driven part to those channels, e.g. the expression
    values: head position differs from take to take, so windows of it rarely have near
    neighbours in the database. The other channels go through ``others`` (default: a One-Euro
    filter).
    """

    name = "chai"

    def __init__(
        self,
        database: np.ndarray,
        window: int = 10,
        k: int = 100,
        variance: float = 0.99,
        delay: int = 1,
        db_smooth: float = 1.0,
        channels: Sequence[int] | None = None,
        others=None,
    ):
        db = np.asarray(database, dtype=np.float64)
        self.n_in = db.shape[1] if db.ndim == 2 else 0
        self.channels = None if channels is None else np.asarray(channels, dtype=np.intp)
        if self.channels is not None:
            db = db[:, self.channels]
            self.others = others if others is not None else OneEuroFilter()
            self._rest = np.setdiff1d(np.arange(self.n_in), self.channels)
        if db.ndim != 2 or len(db) < window + 2:
            raise ValueError(f"the Chai filter needs a training clip of at least {window + 2} frames, got {len(db)}")
        db = db[np.all(np.isfinite(db), axis=1)]
        if len(db) < window + 2:
            raise ValueError("the Chai filter's training clip has too few finite frames")
        self.window = int(window)
        self.delay = max(0, min(int(delay), self.window - 1))
        self.variance = float(variance)
        self.lag_frames = self.delay
        db = _gauss_smooth(db, db_smooth)
        n, d = db.shape
        self.dim = d
        idx = np.arange(n - self.window + 1)[:, None] + np.arange(self.window)[None, :]
        self._windows = db[idx].reshape(len(idx), self.window * d)
        self._wnorm = (self._windows**2).sum(axis=1)
        self.k = int(min(k, len(self._windows)))
        pos = np.arange(self.window)
        self._pos_w = 0.5 - 0.5 * np.cos(2.0 * math.pi * (pos + 1) / (self.window + 1))
        self.reset()

    def reset(self) -> None:
        self._buf: deque = deque(maxlen=self.window)
        self._recs: deque = deque(maxlen=self.delay + 1)
        if self.channels is not None:
            self.others.reset()

    def _reconstruct(self, x: np.ndarray) -> np.ndarray:
        d2 = self._wnorm - 2.0 * (self._windows @ x)
        nn = np.argpartition(d2, self.k - 1)[: self.k] if self.k < len(d2) else np.arange(len(d2))
        local = self._windows[nn]
        mu = local.mean(axis=0)
        c = local - mu
        _, s, vt = np.linalg.svd(c, full_matrices=False)
        var = s**2
        total = var.sum()
        if total <= 0:
            return mu
        m = int(np.searchsorted(np.cumsum(var) / total, self.variance) + 1)
        B = vt[:m]
        return mu + ((x - mu) @ B.T) @ B

    def step(self, z: np.ndarray, t: float | None = None) -> np.ndarray:
        z = np.asarray(z, dtype=np.float64)
        if self.channels is None:
            return self._step(z)
        out = np.empty_like(z)
        out[self.channels] = self._step(z[self.channels])
        out[self._rest] = self.others.step(z[self._rest], t)
        return out

    def _step(self, z: np.ndarray) -> np.ndarray:
        self._buf.append(z.copy())
        if len(self._buf) < self.window:
            return z.copy()
        x = np.concatenate(self._buf)
        rec = self._reconstruct(x).reshape(self.window, self.dim)
        self._recs.append(rec)
        # frame `delay` back sits at position window-1-delay of the newest window,
        # and one position later in each older window
        acc = np.zeros(self.dim)
        wsum = 0.0
        for age, r in enumerate(reversed(self._recs)):
            pos = self.window - 1 - self.delay + age
            if pos >= self.window:
                break
            w = self._pos_w[pos]
            acc += w * r[pos]
            wsum += w
        return acc / wsum


class Chain:
    """Apply filters in order; a ``None`` from any stage ends the step with ``None``."""

    def __init__(self, filters: Sequence):
        self.filters = list(filters)
        self.name = "+".join(f.name for f in self.filters)
        self.lag_frames = sum(getattr(f, "lag_frames", 0) for f in self.filters)

    def reset(self) -> None:
        for f in self.filters:
            f.reset()

    def step(self, z: np.ndarray, t: float | None = None):
        for f in self.filters:
            z = f.step(z, t)
            if z is None:
                return None
        return z


FILTERS: tuple[str, ...] = ("none", "one_euro", "gate", "gate+one_euro", "chai")
"""Filter names accepted by :func:`make_filter` (the paper's rate reduction is the puppet's ``fps``)."""


def make_filter(name: str, fps: float = 30.0, database: np.ndarray | None = None):
    """A filter by name (see :data:`FILTERS`); ``"chai"`` needs ``database`` (the performer's
    training clip as scale-free 10-vectors) and falls back to ``one_euro`` without one."""
    if name in ("none", "", None):
        return Identity()
    if name == "one_euro":
        return OneEuroFilter(fps=fps)
    if name == "gate":
        return OutlierGate()
    if name == "gate+one_euro":
        return GatedOneEuro(fps=fps)
    if name == "chai":
        if database is None or len(database) < 12:
            return OneEuroFilter(fps=fps)
        # expression channels only (see ChaiFilter): pose through One-Euro
        return ChaiFilter(database, channels=range(3, 10), others=OneEuroFilter(fps=fps))
    raise ValueError(f"unknown filter {name!r} (choose from {', '.join(FILTERS)})")
