"""Friction laws: the physics of static friction (docs/model.md §3), against closed forms.

A membrane pushed by a uniform force density f (N cm^-1) translates rigidly at the law's
speed: 0 below the threshold f_s, (|f| - f_s) / gamma_mem above it for the sharp law, and
g(|f|) = (eps / gamma) [sp((|f| - f_s) / eps) - sp((-|f| - f_s) / eps)] for the regularised
one (sp(x) = log(1 + e^x), written here with numpy's logaddexp, independently of the kernel).
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from softcell.builtins.friction_laws import coulomb_derivative, coulomb_velocity
from softcell.components.registry import default_registry
from softcell.engine import build_integrator, build_model, circle_modes, total_energy
from softcell.integrators.rodas4 import pack
from softcell.model.parameters import Parameters
from softcell.plugin import (
    MODEL_PARAMETERS,
    EnergyTerm,
    FrictionLaw,
    ParameterSpec,
    Schedule,
    hookimpl,
    registered,
)
from softcell.testing.compare import rodas4_jacobians

GAMMA = float(MODEL_PARAMETERS["membrane_friction"].default)


def regularised_speed(f, threshold, width, gamma=GAMMA):
    f = np.abs(np.asarray(f, dtype=float))
    return (
        width
        / gamma
        * (np.logaddexp(0.0, (f - threshold) / width) - np.logaddexp(0.0, (-f - threshold) / width))
    )


def sharp_speed(f, threshold, gamma=GAMMA):
    return np.maximum(np.abs(f) - threshold, 0.0) / gamma


# -- a uniform push, as a third-party energy term -------------------------------------------


@njit(cache=True)
def push_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    # e = -(l0 / 2 pi) f . gamma: the force density per unit length is f everywhere
    scale = context[0] / (2.0 * math.pi)
    for n in range(x.size):
        p0x[n] -= scale * coefficients[0]
        p0y[n] -= scale * coefficients[1]


@njit(cache=True)
def push_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    pass


class Push(EnergyTerm):
    name = "uniform_push"
    description = "a uniform force density (push_x, push_y) on the membrane"
    parameters = (
        ParameterSpec("push_x", 0.0, "N cm-1", "push along x"),
        ParameterSpec("push_y", 0.0, "N cm-1", "push along y"),
    )
    derivative_order = 0

    def partials_kernel(self):
        return push_partials

    def hessian_kernel(self):
        return push_hessian

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        p = self.params
        return -p.membrane_length / (2 * np.pi) * (p.push_x * x + p.push_y * y)


class CoulombByDifferences(FrictionLaw):
    """The coulomb law without its derivative: rodas4 takes the documented fallback."""

    name = "coulomb_differences"
    description = "coulomb, derivative by central differences"
    parameters = default_registry().get("friction_law", "coulomb").parameters

    def velocity_kernel(self):
        return coulomb_velocity


@njit
def radial_velocity(x, y, tx, ty, fx, fy, coefficients, vx, vy):
    for n in range(x.size):  # v = c (x, y): the force is ignored, the position read
        vx[n] = coefficients[0] * x[n]
        vy[n] = coefficients[0] * y[n]


@njit
def tangential_velocity(x, y, tx, ty, fx, fy, coefficients, vx, vy):
    for n in range(x.size):  # v = c t: the membrane slides along itself
        vx[n] = coefficients[0] * tx[n]
        vy[n] = coefficients[0] * ty[n]


class RadialDrift(FrictionLaw):
    """Reads the points the law receives: a circle about the origin grows as e^{ct}."""

    name = "radial_drift"
    description = "v = c (x, y), whatever the force (a test of the points a law receives)"
    parameters = (ParameterSpec("drift_rate", 0.02, "s-1", "growth rate c"),)

    def velocity_kernel(self):
        return radial_velocity


class TangentialDrift(FrictionLaw):
    """Reads the tangents: a circle of radius R turns rigidly at c / R."""

    name = "tangential_drift"
    description = "v = c t, whatever the force (a test of the tangents a law receives)"
    parameters = (ParameterSpec("drift_speed", 0.5, "cm s-1", "sliding speed c"),)

    def velocity_kernel(self):
        return tangential_velocity


class Plugin:
    @hookimpl
    def softcell_energy_terms(self):
        return [Push]

    @hookimpl
    def softcell_friction_laws(self):
        return [CoulombByDifferences, RadialDrift, TangentialDrift]


@pytest.fixture(scope="module")
def plugin():
    with registered(Plugin(), name="friction_tests") as registry:
        yield registry


def _schedule(duration):
    """The bot at rest (a tumble with no torque would still turn it: run with zero force)."""
    return Schedule(np.array([0.0]), np.array([1], dtype=np.int8), np.array([1.0]))


def _params(registry, **values):
    return Parameters(
        {"radius": 4.0, "duration": 1.0, "drive_force": 1e-12, "drive_torque": 1e-12, **values},
        registry.parameter_specs().values(),
    )


def _run(registry, terms, law, integrator, times, modes=None, **values):
    params = _params(registry, **values)
    model = build_model(
        params, terms, "run_and_tumble", friction_law=law, registry=default_registry()
    )
    stepper = build_integrator(integrator, params, default_registry()).build(model)
    if modes is None:
        modes = circle_modes(4.0, model.cutoff)
    state = stepper.start(modes, np.array([0.0, 0.0, 0.0]), _schedule(times[-1]))
    return model, stepper.sample(state, _schedule(times[-1]), np.asarray(times))


# -- what a law sees --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "integrator", [pytest.param("rodas4", marks=pytest.mark.slow), "explicit_euler"]
)
def test_a_law_receives_the_membranes_points_and_unit_tangents(plugin, integrator):
    # Points: v = c (x, y) grows the circle about the origin as R e^{ct}. Tangents: v = c t
    # turns it rigidly, g_1 = R e^{i c t / R}. Both exact; the modes k != 1 stay zero.
    times = np.linspace(0.0, 1.0, 11)
    small = {"cutoff": 4, "nodes": 64, "stored_nodes": 16, "dt": 1e-5, "rtol": 1e-10, "atol": 1e-12}
    terms = ["bending", "tension"]
    model, (modes, _) = _run(plugin, terms, "radial_drift", integrator, times, **small)
    np.testing.assert_allclose(modes[:, model.cutoff + 1], 4.0 * np.exp(0.02 * times), rtol=1e-6)
    others = np.delete(modes, model.cutoff + 1, axis=1)
    assert np.abs(others).max() <= 1e-9
    model, (modes, _) = _run(plugin, terms, "tangential_drift", integrator, times, **small)
    np.testing.assert_allclose(
        modes[:, model.cutoff + 1], 4.0 * np.exp(1j * 0.5 * times / 4.0), rtol=1e-6
    )
    assert np.abs(np.delete(modes, model.cutoff + 1, axis=1)).max() <= 1e-9


# -- the law itself -------------------------------------------------------------------------


def shape(n):
    """Points and unit tangents of n membrane points (the coulomb law reads neither)."""
    return np.zeros(n), np.zeros(n), np.ones(n), np.zeros(n)


def test_the_kernel_is_the_closed_form_and_converges_to_the_sharp_law():
    f = np.linspace(-5e-4, 5e-4, 2001)
    threshold = 1e-4
    errors = []
    for width in (1e-5, 1e-6, 1e-7):
        vx, vy = np.zeros_like(f), np.zeros_like(f)
        coulomb_velocity(
            *shape(f.size), f, np.zeros_like(f), np.array([GAMMA, threshold, width]), vx, vy
        )
        assert np.all(vy == 0.0)
        closed = np.sign(f) * regularised_speed(f, threshold, width)
        assert np.abs(vx - closed).max() <= 1e-12 * np.abs(closed).max()
        error = np.abs(vx - np.sign(f) * sharp_speed(f, threshold)).max()
        assert error <= width * math.log(2) / GAMMA * (1 + 1e-9)  # the bound at |f| = f_s
        errors.append(error)
    assert errors[0] > 5 * errors[1] > 25 * errors[2]


@settings(max_examples=50, deadline=None)
@given(st.floats(-1e-3, 1e-3), st.floats(-1e-3, 1e-3), st.floats(0.0, 3e-4), st.floats(1e-7, 1e-4))
def test_the_derivative_matches_differences_and_the_law_dissipates(fx, fy, threshold, width):
    c = np.array([GAMMA, threshold, width])
    f = np.array([[fx, fy]]).T.copy()
    v = [np.zeros(1), np.zeros(1)]
    coulomb_velocity(*shape(1), f[0], f[1], c, *v)
    assert v[0][0] * fx + v[1][0] * fy >= 0.0  # the law never feeds energy in
    d = [np.zeros(1) for _ in range(4)]
    coulomb_derivative(*shape(1), f[0], f[1], c, *d)
    h = 1e-4 * width
    for b in range(2):
        plus, minus = f.copy(), f.copy()
        plus[b] += h
        minus[b] -= h
        vp, vm = [np.zeros(1), np.zeros(1)], [np.zeros(1), np.zeros(1)]
        coulomb_velocity(*shape(1), plus[0], plus[1], c, *vp)
        coulomb_velocity(*shape(1), minus[0], minus[1], c, *vm)
        for a in range(2):
            fd = (vp[a][0] - vm[a][0]) / (2 * h)
            analytic = d[2 * a + b][0]
            assert analytic == pytest.approx(fd, rel=1e-4, abs=1e-6 / GAMMA)


# -- a uniformly pushed membrane ------------------------------------------------------------


@pytest.mark.parametrize(
    "integrator", [pytest.param("rodas4", marks=pytest.mark.slow), "explicit_euler"]
)
@pytest.mark.parametrize("ratio", [0.5, 0.9, 1.5, 3.0])
def test_a_uniformly_pushed_membrane_moves_at_the_laws_speed(plugin, integrator, ratio):
    threshold, width = 1e-4, 1e-6
    push = ratio * threshold
    times = [0.1, 0.2]
    model, (modes, _) = _run(
        plugin,
        ["uniform_push"],
        "coulomb",
        integrator,
        times,
        push_x=0.6 * push,
        push_y=0.8 * push,
        membrane_static_friction=threshold,
        static_friction_width=width,
        dt=1e-4,
    )
    lc = model.cutoff
    velocity = (modes[1, lc] - modes[0, lc]) / 0.1  # the centre's mode, cm/s
    expected = regularised_speed(push, threshold, width)
    assert abs(velocity) == pytest.approx(expected, rel=1e-9, abs=1e-15)
    if ratio > 1:
        assert np.angle(velocity) == pytest.approx(math.atan2(0.8, 0.6), abs=1e-9)
        assert expected == pytest.approx((push - threshold) / GAMMA, rel=2e-2)
    else:  # below the threshold: still, to (eps / gamma) exp(-(f_s - |f|) / eps)
        assert abs(velocity) <= width / GAMMA * math.exp(-(threshold - push) / width) * (1 + 1e-9)
    # a rigid translation: the shape does not change
    assert np.abs(np.delete(modes[1] - circle_modes(4.0, lc), lc)).max() < 1e-12


def test_the_sharp_limit_of_the_push_speed(plugin):
    """Simulated: at |f| = f_s, where the regularisation matters most, the speed is
    eps log 2 / gamma (to O(e^{-2 f_s / eps})) and goes to the sharp law's 0 linearly in eps;
    at |f| = 2 f_s it is (|f| - f_s) / gamma to O(e^{-f_s / eps})."""
    threshold = 1e-4
    for push, widths in ((threshold, (1e-5, 1e-6, 1e-7)), (2 * threshold, (1e-5,))):
        speeds = []
        for width in widths:
            model, (modes, _) = _run(
                plugin,
                ["uniform_push"],
                "coulomb",
                "rodas4",
                [0.1, 0.2],
                push_x=push,
                membrane_static_friction=threshold,
                static_friction_width=width,
            )
            speeds.append(abs(modes[1, model.cutoff] - modes[0, model.cutoff]) / 0.1)
        sharp = (push - threshold) / GAMMA
        for width, speed in zip(widths, speeds, strict=True):
            if push == threshold:
                assert speed - sharp == pytest.approx(width * math.log(2) / GAMMA, rel=1e-6)
            else:
                assert speed == pytest.approx(sharp, rel=1e-4)


# -- f_s -> 0 is the viscous law ------------------------------------------------------------


@pytest.mark.parametrize(
    "integrator, times",
    [
        pytest.param("rodas4", [0.5, 1.0], marks=pytest.mark.slow),
        ("explicit_euler", [0.002, 0.004]),
    ],
)
def test_zero_threshold_is_the_viscous_law_to_rounding(integrator, times):
    registry = default_registry()
    runs = []
    for law, extra in (("viscous", {}), ("coulomb", {"membrane_static_friction": 0.0})):
        params = Parameters(
            {"radius": 4.0, "duration": 1.0, **extra}, registry.parameter_specs().values()
        )
        model = build_model(
            params,
            ["bending", "tension", "contact"],
            "run_and_tumble",
            friction_law=law,
            registry=default_registry(),
        )
        stepper = build_integrator(integrator, params, default_registry()).build(model)
        schedule = Schedule(
            np.array([0.0, 0.3]), np.array([1, 0], dtype=np.int8), np.array([1.0, 1.0])
        )
        modes = circle_modes(4.0, model.cutoff)
        # the bot's tip 0.005 cm into the membrane: in contact from the start
        state = stepper.start(modes, np.array([0.995, 0.0, 0.0]), schedule)
        runs.append(stepper.sample(state, schedule, np.array(times)))
    (m0, p0), (m1, p1) = runs
    assert np.abs(p0 - p1).max() < 1e-9 and np.abs(m0 - m1).max() < 1e-9
    assert np.abs(m0[-1] - circle_modes(4.0, len(m0[-1]) // 2)).max() > 1e-4  # pushed


# -- a released ellipse ---------------------------------------------------------------------


def _ellipse(cutoff, radius=4.0, delta=0.3):
    modes = circle_modes(radius, cutoff)
    modes[cutoff - 1] = delta  # z = R e^{i xi} + delta e^{-i xi}
    return modes


def _largest_restoring_force(registry, modes):
    """max |f| (N cm^-1) of the released ellipse, from the engine's numpy forces."""
    from softcell.engine import force_modes
    from softcell.engine.reference import _curve

    model = build_model(
        _params(registry), ["bending", "tension"], "run_and_tumble", registry=default_registry()
    )
    fhat, _ = force_modes(model, modes, np.zeros(3))
    field = _curve(fhat, model.nodes)[0] * model.force_scale
    return float(np.abs(field).max())


@pytest.mark.slow
def test_a_released_ellipse_relaxes_with_viscous_friction_and_stays_with_coulomb(plugin):
    cutoff = int(_params(plugin).cutoff)
    start = _ellipse(cutoff)
    f_max = _largest_restoring_force(plugin, start)
    times = [1.0, 2.0]
    _, (viscous, _) = _run(
        plugin, ["bending", "tension"], "viscous", "rodas4", times, modes=start.copy()
    )
    threshold, width = 2.0 * f_max, 0.01 * f_max
    _, (coulomb, _) = _run(
        plugin,
        ["bending", "tension"],
        "coulomb",
        "rodas4",
        times,
        modes=start.copy(),
        membrane_static_friction=threshold,
        static_friction_width=width,
    )
    assert abs(viscous[-1, cutoff - 1]) < 0.5 * abs(start[cutoff - 1])  # relaxes
    # coulomb: every point moves at most g(f_max) (the law below its threshold) for 2 s
    bound = 2.0 * regularised_speed(f_max, threshold, width)
    moved = np.abs(coulomb[-1] - start).sum()  # bounds every point's displacement
    assert moved <= bound + 1e-12
    assert bound < 1e-30


@pytest.mark.parametrize("law", ["coulomb", "coulomb_differences"])
def test_rodas4_jacobian_with_static_friction_matches_differences(plugin, law):
    params = _params(plugin, membrane_static_friction=1e-4, static_friction_width=3e-5)
    model = build_model(
        params,
        ["bending", "tension", "contact"],
        "run_and_tumble",
        friction_law=law,
        registry=default_registry(),
    )
    stepper = build_integrator("rodas4", params, default_registry()).build(model)
    rng = np.random.default_rng(3)
    modes = _ellipse(model.cutoff, delta=0.05)
    lc = model.cutoff
    modes += (
        (rng.normal(size=modes.size) + 1j * rng.normal(size=modes.size))
        * 0.01
        / (1 + np.abs(np.arange(-lc, lc + 1))) ** 2
    )
    u = pack(modes, np.array([4.3 - 3.0 - 0.005, 0.1, 0.2]))

    jac, diff = rodas4_jacobians(model, stepper, u)
    assert np.abs(jac - diff).max() <= 1e-6 * np.abs(diff).max()


# -- energy decreases in a free relaxation under both laws ----------------------------------


@settings(max_examples=12, deadline=None)
@given(
    st.lists(st.complex_numbers(max_magnitude=0.15), min_size=4, max_size=4),
    st.sampled_from(["viscous", "coulomb"]),
    st.floats(0.0, 3e-4),
    st.floats(1e-6, 1e-4),
)
def test_energy_decreases_in_a_free_relaxation(plugin, shape, law, threshold, width):
    cutoff = int(_params(plugin).cutoff)
    modes = circle_modes(4.0, cutoff)
    for k, amplitude in zip((-1, 2, -2, 3), shape, strict=True):
        modes[cutoff + k] += amplitude
    times = np.linspace(0.05, 1.0, 20)
    extra = (
        {"membrane_static_friction": threshold, "static_friction_width": width}
        if law == "coulomb"
        else {}
    )
    model, (record, _) = _run(
        plugin, ["bending", "tension"], law, "rodas4", times, modes=modes, **extra
    )
    energy = [total_energy(model, m, np.zeros(3)) for m in [modes, *record]]
    assert np.all(np.diff(energy) <= 1e-12 * abs(energy[0]))
