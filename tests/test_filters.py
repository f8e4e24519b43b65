"""Temporal filters: rates and averaging, smoothing vs lag, outlier gate, Chai data-driven filter."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from training.filters import (
    Chain,
    ChaiFilter,
    GatedOneEuro,
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
    for f in [Identity(), OneEuroFilter(), OutlierGate(), Chain([OutlierGate(), OneEuroFilter()]), GatedOneEuro(), ChaiFilter(db, window=5)]:
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


def _blink(n_before: int = 40, depth: float = 0.2):
    """A lid channel (ipd units, relative to neutral) with a fast blink: closing over two
    frames, shut for one, opening over two (about 170 ms, a real blink)."""
    prof = [-0.08, -0.66, -1.0, -0.89, -0.31]
    xs = [0.0] * n_before + [p * depth for p in prof] + [0.0] * 20
    return [np.array([x, 0.0]) for x in xs], n_before + 2


@settings(max_examples=20, deadline=None)
@given(depth=st.floats(0.12, 0.4), seed=st.integers(0, 1000))
def test_gated_one_euro_lets_a_fast_blink_close_fully(depth, seed):
    xs, shut = _blink(depth=depth)
    rng = np.random.default_rng(seed)
    xs = [x + rng.normal(scale=0.005, size=2) for x in xs]
    gated = np.array(run(GatedOneEuro(), xs))[:, 0]
    plain = np.array(run(Chain([OutlierGate(), OneEuroFilter()]), xs))[:, 0]
    # the closed frame is shown (at most one frame late) nearly fully closed
    assert gated[shut:shut + 2].min() < -0.85 * depth
    assert gated[shut:shut + 2].min() < plain[shut:shut + 2].min() - 0.05 * depth
    assert abs(gated[-1]) < 0.03  # and it opens again


def test_gated_one_euro_is_as_smooth_as_one_euro_on_a_still_face_and_drops_glitches():
    rng = np.random.default_rng(4)
    still = [rng.normal(scale=0.01, size=3) for _ in range(300)]
    a = np.array(run(GatedOneEuro(), still))
    b = np.array(run(OneEuroFilter(), still))
    assert np.std(np.diff(a[20:], axis=0)) <= 1.05 * np.std(np.diff(b[20:], axis=0))
    glitchy = [x.copy() for x in still]
    for i in range(30, 300, 25):
        glitchy[i][1] += 0.3
    g = np.array(run(GatedOneEuro(), glitchy))
    assert np.abs(g[20:, 1]).max() < 0.06


def test_make_filter_gate_one_euro_is_the_cooperating_pair():
    f = make_filter("gate+one_euro")
    assert isinstance(f, GatedOneEuro) and f.name == "gate+one_euro"


def test_gate_does_not_take_two_opposite_glitches_for_a_persistent_jump():
    xs = [np.zeros(1)] * 10 + [np.array([0.3]), np.array([-0.3])] + [np.zeros(1)] * 5
    out = np.array(run(OutlierGate(), xs))[:, 0]
    assert np.abs(out).max() < 1e-9
    # while a jump that stays is accepted after one held frame
    xs = [np.zeros(1)] * 10 + [np.array([0.3])] * 5
    out = np.array(run(OutlierGate(), xs))[:, 0]
    assert out[10] == 0.0 and out[11] == pytest.approx(0.3)
