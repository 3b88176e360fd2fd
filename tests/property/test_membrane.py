"""The membrane model against docs/model.md §3: analytic forces, energies, gradients and
time scales."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softcell.components.registry import default_registry
from softcell.engine import (
    build_model,
    circle_modes,
    equilibrium_radius,
    force_modes,
    membrane_jacobian,
    total_energy,
)
from softcell.model.parameters import Parameters

TERMS = ["bending", "tension", "contact"]
radii = st.floats(3.5, 13.0)


def model_for(radius, terms=TERMS, **values):
    return build_model(
        Parameters({"radius": radius, **values}),
        terms,
        "run_and_tumble",
        registry=default_registry(),
    )


@settings(max_examples=20)
@given(radii, st.floats(0.9, 1.1))
def test_circle_forces_are_normal_and_match_the_si(radius_param, scale):
    m = model_for(radius_param, ["bending", "tension"])
    p = m.params
    r = scale * radius_param
    fhat, dpose = force_modes(m, circle_modes(r, m.cutoff), np.array([0.0, 0.0, 0.3]))
    l0 = p.membrane_length
    expected = p.bending_stiffness / r**2 + 2 * p.tension * l0 * (l0 - 2 * math.pi * r)
    # f = c n_hat with n_hat = e^{i xi}: only the k = 1 mode, equal to c.
    assert fhat[m.cutoff + 1] == pytest.approx(expected, rel=1e-9, abs=1e-12)
    others = np.delete(fhat, m.cutoff + 1)
    assert np.abs(others).max() <= 1e-9 * abs(expected) + 1e-14


@given(radii)
def test_equilibrium_radius_solves_the_corrected_cubic(radius):
    m = model_for(radius)
    r_eq = equilibrium_radius(m.params)
    fhat, _ = force_modes(m, circle_modes(r_eq, m.cutoff), np.zeros(3))
    bending_scale = m.params.bending_stiffness / r_eq**2
    assert abs(fhat[m.cutoff + 1]) < 1e-7 * bending_scale
    l0, k, alpha = m.params.membrane_length, m.params.bending_stiffness, m.params.tension
    first_order = l0 / (2 * math.pi) * (1 + 2 * math.pi**2 * k / (alpha * l0**4))
    assert r_eq == pytest.approx(first_order, rel=1e-4)


@settings(max_examples=25)
@given(radii, st.floats(1e-4, 1e-2))
def test_bending_energy_of_an_ellipse_scales_as_r_minus_3(radius, relative_eps):
    m = model_for(radius, ["bending"])
    eps = relative_eps * radius
    modes = circle_modes(radius, m.cutoff)
    modes[m.cutoff - 1] = eps  # x = (R + eps) cos xi, y = (R - eps) sin xi
    energy = total_energy(m, modes, np.zeros(3))
    k, l0 = m.params.bending_stiffness, m.params.membrane_length
    assert energy - 2 * math.pi * k / radius == pytest.approx(
        68 * math.pi**4 * k * eps**2 / l0**3, rel=10 * relative_eps
    )


def random_shape(m, rng, amplitude):
    modes = circle_modes(equilibrium_radius(m.params), m.cutoff)
    k = np.arange(-m.cutoff, m.cutoff + 1)
    noise = rng.normal(size=k.size) + 1j * rng.normal(size=k.size)
    return modes + amplitude * noise / (1 + np.abs(k)) ** 3


@settings(max_examples=12)
@given(st.integers(0, 10**6), st.sampled_from([4.0, 8.0, 12.0]), st.booleans())
def test_forces_are_minus_the_gradient_of_the_discrete_energy(seed, radius, touching):
    rng = np.random.default_rng(seed)
    m = model_for(radius, cutoff=8, nodes=256, stored_nodes=20)
    modes = random_shape(m, rng, 0.05)
    a = m.params.bot_semi_major
    # Touching: put the bot's tip a few contact lengths from the membrane.
    heading = rng.uniform(0, 2 * np.pi)
    reach = (equilibrium_radius(m.params) - a - 3 * m.params.contact_length) if touching else 0
    pose = np.array([reach * np.cos(heading), reach * np.sin(heading), heading])
    fhat, dpose = force_modes(m, modes, pose)
    if touching:
        assert np.any(dpose != 0)
    h = 1e-7
    for j in rng.choice(modes.size, 4, replace=False):
        grad = 0j
        for unit in (1.0, 1j):
            delta = np.zeros_like(modes)
            delta[j] = h * unit
            diff = total_energy(m, modes + delta, pose) - total_energy(m, modes - delta, pose)
            grad += unit * diff / (2 * h) if unit == 1.0 else 1j * diff / (2 * h)
        scale = np.abs(fhat).max()
        assert abs(grad - (-2 * np.pi * fhat[j])) <= 1e-5 * 2 * np.pi * scale
    # The reaction on the bot is minus the energy's gradient in the bot's pose (a fourth-order
    # stencil: the contact energy varies on lambda = 0.01 cm).
    for i in range(3):
        step = np.zeros(3)
        step[i] = 1e-5

        def energy(j, step=step):
            return total_energy(m, modes, pose + j * step)

        diff = (-energy(2) + 8 * energy(1) - 8 * energy(-1) + energy(-2)) / 12e-5
        # abs: the stencil's rounding error, ~1e-16 E / h
        assert diff == pytest.approx(
            2 * np.pi / m.nodes * dpose[i],
            rel=1e-5,
            abs=max(1e-7 * 2 * np.pi / m.nodes * np.abs(dpose).max(), 1e-9),
        )


@settings(max_examples=15)
@given(st.integers(0, 10**6), st.floats(-5, 5), st.floats(-5, 5), st.floats(0, 2 * np.pi))
def test_energy_is_invariant_under_translation_and_rotation(seed, dx, dy, angle):
    rng = np.random.default_rng(seed)
    m = model_for(4.0, cutoff=8, nodes=256, stored_nodes=20)
    modes = random_shape(m, rng, 0.05)
    pose = np.array([0.9, 0.2, 0.3])  # in contact
    moved = modes * np.exp(1j * angle)
    moved[m.cutoff] += dx + 1j * dy
    c = complex(pose[0], pose[1]) * np.exp(1j * angle) + dx + 1j * dy
    moved_pose = np.array([c.real, c.imag, pose[2] + angle])
    e0 = total_energy(m, modes, pose)
    assert total_energy(m, moved, moved_pose) == pytest.approx(e0, rel=1e-10)


@settings(max_examples=15)
@given(st.integers(0, 10**6), radii)
def test_internal_forces_sum_to_zero(seed, radius):
    m = model_for(radius, ["bending", "tension"])
    modes = random_shape(m, np.random.default_rng(seed), 0.1)
    fhat, _ = force_modes(m, modes, np.zeros(3))
    assert abs(fhat[m.cutoff]) <= 1e-12 * np.abs(fhat).max()


@pytest.mark.parametrize("radius", [4.0, 12.0])
def test_breathing_and_shape_relaxation_times(radius):
    m = model_for(radius, ["bending", "tension"])
    p = m.params
    jac, size = membrane_jacobian(m), 2 * m.cutoff + 1
    # The breathing mode Re g_1 is an eigenvector by symmetry; its rate is 1 / t_mem.
    breathing = -jac[m.cutoff + 1, m.cutoff + 1]
    assert 1 / breathing == pytest.approx(
        p.membrane_friction / (8 * np.pi**2 * p.tension), rel=0.01
    )
    # The slowest non-zero rate is the n = 2 shape mode: 72 k / (5 gamma_mem R^4).
    rates = np.sort(-np.linalg.eigvals(jac).real)
    slow = rates[rates > 1e-6 * rates.max()][0]
    assert 1 / slow == pytest.approx(
        5 * p.membrane_friction * radius**4 / (72 * p.bending_stiffness), rel=0.02
    )
    assert jac.shape == (2 * size, 2 * size)
