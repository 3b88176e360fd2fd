"""The findings' statistics against independent computations: the renewal theory of D hat
against a Monte Carlo walk, the duration test against samples of known law, and the trend
rule on sequences whose answer is known."""

import numpy as np
import pytest

from softcell.core.analysis.fits import renewal_msd_slope
from softcell.workflows.findings import Finding, _trend_test, exponential_test


def _walk_slope(go, stop, speed, walkers, total, rng) -> float:
    """MSD / time of walkers alternating go phases (speed, a new random direction each) and
    stops, drawn by ``go(n)`` and ``stop(n)``, after ``total`` seconds."""
    x = np.zeros(walkers)
    y = np.zeros(walkers)
    t = np.zeros(walkers)
    while True:
        active = t < total
        if not active.any():
            break
        n = int(active.sum())
        run = np.minimum(go(n), total - t[active])
        angle = rng.uniform(0, 2 * np.pi, n)
        x[active] += speed * run * np.cos(angle)
        y[active] += speed * run * np.sin(angle)
        t[active] += run + stop(n)
    return float(np.mean(x**2 + y**2) / total)


@pytest.mark.parametrize("law", ["uniform", "exponential"])
def test_the_renewal_slope_is_that_of_a_walk(law):
    rng = np.random.default_rng(7)
    speed, mean_stop = 2.0, 0.3
    if law == "uniform":  # the drive's U[0.4, 1.2] s
        go, mean_go, second = (lambda n: rng.uniform(0.4, 1.2, n)), 0.8, 0.8**2 + 0.8**2 / 12
    else:
        go, mean_go, second = (lambda n: rng.exponential(0.8, n)), 0.8, 2 * 0.8**2
    walked = _walk_slope(go, lambda n: rng.exponential(mean_stop, n), speed, 40_000, 400.0, rng)
    v0_hat = speed * np.sqrt(mean_go / (mean_go + mean_stop))  # RMS speed, stops included
    assert renewal_msd_slope(v0_hat, mean_go, second) == pytest.approx(walked, rel=0.03)
    exponential_theory = 2 * v0_hat**2 * mean_go
    if law == "exponential":
        assert exponential_theory == pytest.approx(walked, rel=0.03)
    else:  # the paper's theory misses a plateau-shaped law by a factor ~0.54
        assert abs(exponential_theory / walked - 1) > 0.5


def test_the_duration_test_tells_an_exponential_from_a_uniform_law():
    rng = np.random.default_rng(3)
    dt = 0.01
    exponential = dt * np.floor(rng.exponential(0.5, 5000) / dt)
    _, p = exponential_test(exponential, dt, seed=1)
    assert p > 0.05
    uniform = dt * np.floor(rng.uniform(0.4, 1.2, 5000) / dt)
    distance, p = exponential_test(uniform, dt, seed=1)
    assert p < 0.01 and distance > 0.1


def test_the_trend_rule_sees_a_step_against_it_beyond_its_errors():
    radii = np.arange(4.0, 14.0)
    rising = 0.3 + 0.05 * radii
    tau, p, against = _trend_test(radii, rising, np.full(10, 0.01), +1)
    assert tau == pytest.approx(1.0) and p == pytest.approx(1 / 3628800) and against == []
    noisy = rising.copy()
    noisy[2] = noisy[1] - 0.005  # a step down within 2 SE: noise
    assert _trend_test(radii, noisy, np.full(10, 0.01), +1)[2] == []
    noisy[2] = noisy[1] - 0.2  # far beyond
    assert len(_trend_test(radii, noisy, np.full(10, 0.01), +1)[2]) == 1
    assert _trend_test(radii, rising[::-1], np.full(10, 0.01), +1)[1] > 0.99


def test_a_miss_must_state_its_cause():
    with pytest.raises(ValueError, match="states no cause"):
        Finding("t", "p", "m", "differs", "r")
    with pytest.raises(ValueError, match="is not one of"):
        Finding("t", "p", "m", "fine", "r", cause="x")
