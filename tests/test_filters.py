"""Temporal filters: rates and averaging, smoothing vs lag, outlier gate, Chai data-driven filter."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from training.filters import (
    Chain,
    ChaiFilter,
    Identity,
    OneEuroFilter,
    OutlierGate,
    RateFilter,
    make_filter,
)


def run(f, xs):
    out = []
    for i, x in enumerate(xs):
        y = f.step(x, i / 30.0)
        out.append(None if y is None else np.array(y))
    return out


@pytest.mark.parametrize("fps,group", [(10, 3), (15, 2), (30, 1)])
def test_rate_filter_averages_the_paper_groups(fps, group):
    f = RateFilter.for_fps(fps, 30)
    assert f.group == group
    xs = [np.full(2, float(i)) for i in range(12)]
    out = [y for y in run(f, xs) if y is not None]
    assert len(out) == 12 // group
    for j, y in enumerate(out):
        np.testing.assert_allclose(y, np.mean(range(j * group, (j + 1) * group)))


@settings(max_examples=30, deadline=None)
@given(c=st.floats(-5, 5), n=st.integers(1, 40))
def test_filters_keep_a_constant_signal(c, n):
    db = np.random.default_rng(0).normal(scale=0.05, size=(80, 3)) + c
    for f in [Identity(), OneEuroFilter(), OutlierGate(), Chain([OutlierGate(), OneEuroFilter()]), ChaiFilter(db, window=5)]:
        out = run(f, [np.full(3, c)] * n)
        for y in out:
            np.testing.assert_allclose(y, c, atol=0.05 + 1e-9)


def test_one_euro_smooths_still_noise_and_follows_motion():
    rng = np.random.default_rng(1)
    noisy = [np.array([rng.normal(scale=0.02)]) for _ in range(300)]
    out = np.array(run(OneEuroFilter(), noisy))[:, 0]
    assert np.std(np.diff(out[50:])) < 0.3 * np.std(np.diff(np.array(noisy)[50:, 0]))
    # a fast ramp is followed closely (adaptive cutoff)
    ramp = [np.array([min(i, 30) * 0.05]) for i in range(60)]
    out = np.array(run(OneEuroFilter(), ramp))[:, 0]
    assert abs(out[-1] - 1.5) < 0.02
    assert abs(out[25] - 1.25) < 0.3


def test_outlier_gate_removes_spikes_but_accepts_steps():
    xs = [np.array([0.0])] * 20
    xs[10] = np.array([1.0])  # a one-frame tracking glitch
    out = np.array(run(OutlierGate(), xs))[:, 0]
    assert np.all(np.abs(out) < 1e-12)
    step = [np.array([0.0])] * 10 + [np.array([1.0])] * 10
    out = np.array(run(OutlierGate(max_hold=2), step))[:, 0]
    assert np.all(out[13:] == 1.0)  # accepted after at most two held frames
    # small changes pass untouched
    small = [np.array([0.01 * i]) for i in range(20)]
    np.testing.assert_allclose(np.array(run(OutlierGate(), small))[:, 0], 0.01 * np.arange(20))


def test_chai_filter_denoises_a_signal_like_its_training_clip():
    rng = np.random.default_rng(2)
    t = np.arange(600) / 30.0
    clean = np.stack([np.sin(2 * np.pi * 0.7 * t), 0.5 * np.cos(2 * np.pi * 0.4 * t)], axis=1)
    f = ChaiFilter(clean[:400], window=10, k=40, delay=2)
    test = clean[400:]
    noisy = test + rng.normal(scale=0.05, size=test.shape)
    out = np.array(run(f, list(noisy)))
    d = f.delay
    err_f = np.sqrt(np.mean((out[20:, :] - test[20 - d : len(test) - d]) ** 2))
    err_n = np.sqrt(np.mean((noisy[20:] - test[20:]) ** 2))
    assert err_f < 0.7 * err_n


def test_chai_needs_a_long_enough_clip():
    with pytest.raises(ValueError):
        ChaiFilter(np.zeros((5, 3)), window=10)


def test_make_filter():
    for name in ["none", "one_euro", "gate", "gate+one_euro"]:
        assert make_filter(name).step(np.zeros(10), 0.0).shape == (10,)
    assert isinstance(make_filter("chai", database=np.zeros((100, 10))), ChaiFilter)
    assert isinstance(make_filter("chai"), OneEuroFilter)  # no clip: falls back
    with pytest.raises(ValueError, match="unknown filter"):
        make_filter("kalman")
