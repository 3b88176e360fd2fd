"""The bot: signed distance to the ellipse, free-bot kinematics and diffusion
(docs/model.md §4-5)."""

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

from softcell.components.registry import default_registry
from softcell.engine import build_integrator, build_model
from softcell.engine.cell import realization_rng, run_realization
from softcell.engine.free_bot import (
    cycle_displacements,
    diffusion_from_cycles,
    renewal_diffusion,
    turn_correlation,
)
from softcell.engine.kernels.ellipse import signed_distance
from softcell.model.parameters import Parameters


def brute_distance(px, py, a, b):
    """Dense sampling of the ellipse, refined by a bounded 1-d minimisation."""
    s = np.linspace(0, 2 * np.pi, 20001)
    d2 = (a * np.cos(s) - px) ** 2 + (b * np.sin(s) - py) ** 2
    i = int(d2.argmin())
    ds = s[1] - s[0]
    best = minimize_scalar(
        lambda t: (a * np.cos(t) - px) ** 2 + (b * np.sin(t) - py) ** 2,
        bounds=(s[i] - ds, s[i] + ds),
        method="bounded",
        options={"xatol": 1e-13},
    )
    d = np.sqrt(min(best.fun, d2[i]))
    return -d if (px / a) ** 2 + (py / b) ** 2 < 1 else d


near_axis = st.one_of(st.floats(-1e-9, 1e-9), st.just(0.0))


@settings(max_examples=200)
@given(
    st.floats(1.0, 4.0),
    st.floats(0.3, 1.0),
    st.tuples(st.floats(-6, 6), st.floats(-6, 6))
    | st.tuples(st.floats(-6, 6), near_axis)
    | st.tuples(near_axis, st.floats(-6, 6)),
    st.floats(-5, 5),
    st.floats(-5, 5),
    st.floats(-7, 7),
)
def test_signed_distance_matches_brute_force(a, ratio, point, cx, cy, theta):
    b = a * ratio
    px, py = point
    c, s = np.cos(theta), np.sin(theta)
    x, y = cx + c * px - s * py, cy + s * px + c * py
    rho, gx, gy = signed_distance(x, y, cx, cy, theta, a, b)
    assert rho == pytest.approx(brute_distance(px, py, a, b), abs=1e-9)
    assert np.hypot(gx, gy) == pytest.approx(1.0, abs=1e-12)
    # The gradient is the outward normal: a small step along it adds its length to rho.
    h = 1e-6
    assert signed_distance(x + h * gx, y + h * gy, cx, cy, theta, a, b)[0] == pytest.approx(
        rho + h, abs=1e-9
    )


def test_free_bot_runs_at_f0_over_gamma_t():
    params = Parameters({"duration": 1.0, "dt": 1e-5})
    model = build_model(params, [], "run_and_tumble", membrane=False, registry=default_registry())
    stepper = build_integrator("explicit_euler", params, default_registry()).build(model)
    record = run_realization(model, stepper, realization_rng(0, 0, 0))
    speed = np.hypot(*np.diff(record.pose[:, :2], axis=0).T) / np.diff(record.times)
    running = (record.phase[:-1] == 1) & (record.phase[1:] == 1)
    assert running.sum() > 10
    assert speed[running] == pytest.approx(params.drive_force / params.bot_friction, rel=1e-9)
    turning = (record.phase[:-1] == 0) & (record.phase[1:] == 0)
    omega = np.abs(np.diff(record.pose[:, 2]) / np.diff(record.times))
    assert omega[turning] == pytest.approx(
        params.drive_torque / params.bot_rotational_friction, rel=1e-9
    )


@pytest.mark.parametrize("pivot, expected", [(None, 17.43), ("fixed", 17.43), ("inner", 15.56)])
def test_free_bot_diffusion_matches_spec(pivot, expected):
    params = Parameters()
    assert turn_correlation(params) == pytest.approx(-0.1824, abs=1e-4)
    assert renewal_diffusion(params, pivot) == pytest.approx(expected, rel=1e-3)
    displacement, duration = cycle_displacements(params, np.random.default_rng(7), 10**6, pivot)
    assert diffusion_from_cycles(displacement, duration) == pytest.approx(expected, rel=0.03)


@settings(max_examples=10)
@given(
    st.floats(0.05, 1.0),
    st.floats(1.0, 4.0),
    st.floats(20, 400),
    st.floats(0, 2),
    st.sampled_from([None, "fixed", "inner"]),
)
# Nearly fixed phase lengths once broke the formula by cancellation in (hi^3 - lo^3)/(hi - lo).
@example(lo=1.0, spread=1.0000000000000002, torque=33.0, offset=0.0, pivot=None)
def test_renewal_formula_against_exact_kinematics(lo, spread, torque, offset, pivot):
    params = Parameters(
        {"phase_min": lo, "phase_max": lo * spread, "drive_torque": torque, "pivot_offset": offset}
    )
    # The empirical correlation sum converges within 12 lags when turns decorrelate.
    assume(abs(turn_correlation(params)) < 0.5)
    displacement, duration = cycle_displacements(params, np.random.default_rng(1), 4 * 10**5, pivot)
    assert diffusion_from_cycles(displacement, duration, lags=12) == pytest.approx(
        renewal_diffusion(params, pivot), rel=0.03
    )


def test_pivot_drive_turns_the_free_bot_about_its_pivot():
    params = Parameters({"duration": 3.0, "dt": 1e-5, "pivot_side": "fixed"})
    model = build_model(
        params, [], "pivot_run_and_tumble", membrane=False, registry=default_registry()
    )
    stepper = build_integrator("explicit_euler", params, default_registry()).build(model)
    record = run_realization(model, stepper, realization_rng(0, 0, 1))
    x, y, th = record.pose.T
    pivot_x = x - params.pivot_offset * np.sin(th)
    pivot_y = y + params.pivot_offset * np.cos(th)
    turning = np.flatnonzero((record.phase[:-1] == 0) & (record.phase[1:] == 0))
    assert turning.size > 10
    # Explicit Euler's error on the circle is O(dt); the pivot stays put to that order.
    jumps = np.hypot(
        pivot_x[turning + 1] - pivot_x[turning], pivot_y[turning + 1] - pivot_y[turning]
    )
    assert jumps.max() < 1e-3


@settings(max_examples=100)
@given(
    st.floats(1.0, 4.0),
    st.floats(0.3, 1.0),
    st.lists(
        st.tuples(st.floats(-6, 6), st.floats(-6, 6))
        | st.tuples(st.floats(-6, 6), near_axis)
        | st.tuples(near_axis, st.floats(-6, 6)),
        min_size=0,
        max_size=23,
    ),
)
def test_distances_four_roots_at_a_time_are_the_same_numbers(a, ratio, points):
    # The contact finds the roots of four points at a time, interleaved: each point's
    # Newton iterates must be its own, to the last bit (runs keep their bytes).
    from softcell.engine.kernels.ellipse import signed_distance_local, signed_distances_local

    b = a * ratio
    px = np.array([p[0] for p in points] + [0.0])
    py = np.array([p[1] for p in points] + [0.0])
    count = len(points) + 1  # with the centre, the one point of no root and two normals
    rho, nx, ny = np.empty(count), np.empty(count), np.empty(count)
    signed_distances_local(
        px, py, count, a, b, np.empty((6, count)), np.empty(4, np.int64), rho, nx, ny
    )
    one = np.array([signed_distance_local(x, y, a, b) for x, y in zip(px, py, strict=True)])
    assert np.array_equal(np.stack([rho, nx, ny], axis=1), one.reshape(count, 3))
