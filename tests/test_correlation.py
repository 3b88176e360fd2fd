"""Velocity correlations, the renewal theory's curves and the membrane's reaction on the bot,
against closed forms, an independent simulation of the renewal process, and finite
differences of the model's energy."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from softcell.analysis import correlation, fits
from softcell.analysis.series import segment_index


def test_constant_velocity_is_correlated_at_every_lag():
    t = 0.1 * np.arange(200)
    r = np.stack([3.0 * t, -4.0 * t], axis=-1)
    sums, pairs = correlation.velocity_autocorrelation(r, 0.1, 20)
    np.testing.assert_allclose(sums / pairs, 25.0, rtol=1e-9)
    np.testing.assert_array_equal(pairs, 199 - np.arange(21))


def test_a_missing_sample_removes_the_pairs_of_both_velocities_next_to_it():
    t = 0.1 * np.arange(50)
    r = np.stack([t, 0 * t], axis=-1)
    r[10] = np.nan
    sums, pairs = correlation.velocity_autocorrelation(r, 0.1, 3)
    assert pairs[0] == 49 - 2
    np.testing.assert_allclose(sums / pairs, 1.0, rtol=1e-9)


def test_green_kubo_sum_gives_the_msd_slope_of_a_random_walk():
    # Independent steps of variance s^2 per axis: C(0) = 2 s^2 / dt^2, C(k > 0) = 0, and
    # MSD(n dt) = 2 s^2 n, so D hat = 2 s^2 / dt.
    rng = np.random.default_rng(1)
    steps = rng.normal(0, 0.3, (200_000, 2))
    r = np.cumsum(steps, axis=0)
    sums, pairs = correlation.velocity_autocorrelation(r, 0.5, 10)
    slope = correlation.green_kubo_slope(sums / pairs, 0.5)
    assert slope == pytest.approx(2 * 0.3**2 / 0.5, rel=0.03)


def test_renewal_msd_of_one_duration_is_its_closed_form():
    # Every go phase lasts d: C(u) = (v0^2 / d)(d - u)+, so MSD = v0^2 (tau^2 - tau^3 / (3 d))
    # for tau <= d and v0^2 (tau d - d^2 / 3) beyond.
    d, v0 = 0.8, 2.0
    tau = np.array([0.1, 0.5, 0.8, 2.0, 50.0])
    expected = np.where(tau <= d, v0**2 * (tau**2 - tau**3 / (3 * d)), v0**2 * (tau * d - d**2 / 3))
    got = correlation.renewal_msd(tau, v0, np.full(7, d))
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    slope = fits.renewal_msd_slope(v0, d, d**2)
    assert (got[-1] - got[-2]) / (tau[-1] - tau[-2]) == pytest.approx(slope, rel=1e-12)


def test_renewal_msd_of_exponential_durations_is_the_papers_formula():
    rng = np.random.default_rng(2)
    durations = rng.exponential(0.4, 400_000)
    tau = np.array([0.05, 0.4, 2.0, 20.0])
    got = correlation.renewal_msd(tau, 1.5, durations)
    paper = fits.run_and_tumble_msd(tau, 1.5, durations.mean())
    np.testing.assert_allclose(got, paper, rtol=0.01)


def _renewal_walk(rng, total: float, dt: float, speed: float) -> np.ndarray:
    """An independent simulation of the renewal process: go phases U[0.4, 1.2] s at
    ``speed`` in uniformly random directions, stops U[0.4, 1.2] s, sampled every dt."""
    t_edges, velocity = [0.0], []
    while t_edges[-1] < total:
        angle = rng.uniform(0, 2 * np.pi)
        for v in (speed * np.array([np.cos(angle), np.sin(angle)]), np.zeros(2)):
            t_edges.append(t_edges[-1] + rng.uniform(0.4, 1.2))
            velocity.append(v)
    t = dt * np.arange(int(total / dt))
    phase = np.searchsorted(np.array(t_edges), t, side="right") - 1
    v = np.array(velocity)[phase]
    return np.vstack([np.zeros(2), np.cumsum(v[:-1] * dt, axis=0)])


def test_renewal_theory_matches_a_simulated_renewal_walk():
    rng = np.random.default_rng(3)
    dt, speed = 0.01, 2.0
    walks = [_renewal_walk(rng, 400.0, dt, speed) for _ in range(12)]
    go = rng.uniform(0.4, 1.2, 200_000)
    v0_hat = speed * math.sqrt(0.5)  # the go fraction is 1/2
    for lag in (10, 100, 1000):
        measured = np.mean([np.mean(np.sum((w[lag:] - w[:-lag]) ** 2, axis=1)) for w in walks])
        theory = correlation.renewal_msd(np.array([lag * dt]), v0_hat, go)[0]
        assert measured == pytest.approx(theory, rel=0.06), lag
    # ... and its velocity autocorrelation on a coarse grid, in the measured form
    coarse = [w[::10] for w in walks]
    measured = np.mean(
        [np.divide(*correlation.velocity_autocorrelation(w, 0.1, 20)) for w in coarse], axis=0
    )
    theory = correlation.renewal_autocorrelation(0.1, 20, v0_hat, go)
    np.testing.assert_allclose(measured, theory, atol=0.04 * theory[0])
    beyond = (np.arange(21) - 1) * 0.1 >= go.max()  # the longest go phase and one interval
    assert beyond.sum() >= 6 and np.all(theory[beyond] == 0) and np.all(theory[~beyond] > 0)


def test_turn_statistics_of_go_phases_turning_by_sixty_degrees():
    # go 5 samples along theta_n, stop 3 samples, theta_(n+1) = theta_n + 60 degrees
    pos, labels = [np.zeros(2)], []
    for n in range(12):
        step = 0.2 * np.array([np.cos(n * np.pi / 3), np.sin(n * np.pi / 3)])
        for _ in range(5):
            pos.append(pos[-1] + step)
            labels.append(1)
        for _ in range(3):
            pos.append(pos[-1])
            labels.append(0)
    labels.append(0)
    r, lab = np.array(pos), np.array(labels, dtype=np.int8)
    stats = correlation.turn_statistics(r, lab, segment_index(0.01 * np.arange(lab.size)), 0)
    # the first go phase touches the start and the last stop the end: 11 go phases
    # complete, 10 consecutive pairs
    assert stats.phases == 11
    assert stats.pairs == 10
    assert stats.cosine_sum / stats.pairs == pytest.approx(0.5, rel=1e-12)
    assert stats.length_sum / stats.phases == pytest.approx(1.0, rel=1e-12)


def test_contact_reaction_is_minus_the_energy_gradient(tmp_path):
    """The reaction on the bot from a stored membrane equals -dE/d(x, y, theta) by central
    differences of the model's total energy at a touching state."""
    from softcell.components.registry import default_registry
    from softcell.engine.kernels.spectral import resample
    from softcell.engine.model import build_model
    from softcell.engine.reference import total_energy
    from softcell.engine.state import circle_modes
    from softcell.paper.reaction import bot_reaction

    registry = default_registry()
    components = {
        "driving_protocol": "run_and_tumble",
        "energy_terms": ["bending", "tension", "contact"],
        "friction_law": "viscous",
        "membrane": True,
    }
    params = registry.parameters({"radius": 4.0}, components)
    model = build_model(params, components["energy_terms"], "run_and_tumble", registry=registry)
    modes = circle_modes(3.05, model.cutoff)
    modes[model.cutoff + 2] = 0.15  # an oval that touches the bot unevenly
    pose = np.array([0.2, -0.1, 0.3])
    x, y = resample(modes, 64)
    ds = xr.Dataset(
        {
            "membrane_x": (("realization", "time", "node"), x[None, None]),
            "membrane_y": (("realization", "time", "node"), y[None, None]),
            **{
                name: (("realization", "time"), np.array([[value]]))
                for name, value in zip(("bot_x", "bot_y", "bot_angle"), pose, strict=True)
            },
        },
        coords={"time": [0.0]},
        attrs={
            "softcell_components": __import__("json").dumps(components),
            "softcell_parameters": __import__("json").dumps({"radius": 4.0}),
        },
    )
    r = bot_reaction(ds, stride=1)
    got = np.array(
        [float(r[v][0]) for v in ("contact_force_x", "contact_force_y", "contact_torque")]
    )
    assert np.abs(got).max() > 0  # it touches
    h = 1e-6
    grad = np.zeros(3)
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        grad[k] = (total_energy(model, modes, pose + e) - total_energy(model, modes, pose - e)) / (
            2 * h
        )
    np.testing.assert_allclose(got, -grad, rtol=1e-4, atol=1e-9 * np.abs(grad).max())
