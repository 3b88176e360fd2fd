"""The generic Rosenbrock step with RODAS4's tableau, on scalar ODEs with known solutions."""

import math

import numpy as np
import pytest
from numba import njit

from softcell.engine.kernels.linalg import lu_solve, lu_workspace
from softcell.engine.kernels.rosenbrock import (
    dense_output,
    dense_value,
    error_norm,
    factor_iteration_matrix,
    stages,
)
from softcell.integrators.rodas4 import RODAS4
from softcell.integrators.rodas4.method import (
    ERR_ACCEPTED,
    GROW_LIMIT,
    H_ACCEPTED,
    SAFETY,
    SHRINK_LIMIT,
    step_factor,
)


@njit
def linear(y, out, rate):
    out[0] = -rate * y[0]


@njit
def riccati(y, out, unused):
    out[0] = -y[0] * y[0]  # y' = -y^2: y(t) = 1 / (1 + t) from y(0) = 1


def step(f, args, u, jac, h):
    """One step; returns (new state, error norm at atol = rtol = 1, dense rows)."""
    s = RODAS4.stages
    mat, pivots = np.zeros((1, 1)), lu_workspace(1)
    k, y, force, ynew, f0 = (np.zeros((s, 1)), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1))
    f(u, f0, args)
    assert factor_iteration_matrix(np.array([[jac]]), h, RODAS4.gamma, mat, pivots)
    stages(f, args, u, f0, h, RODAS4.a, RODAS4.c, mat, pivots, k, y, force)
    err = error_norm(u, y, k, 1.0, 0.0, ynew)
    dense = np.zeros((4, 1))
    dense_output(u, ynew, k, RODAS4.dense, dense)
    return ynew.copy(), err, dense


def test_one_step_of_a_linear_decay_is_accurate_and_l_stable():
    u = np.array([1.0])
    for rate, h in ((1.0, 0.1), (1e4, 0.1), (1e8, 1.0)):
        ynew, _, _ = step(linear, rate, u, -rate, h)
        if rate * h < 1:
            assert ynew[0] == pytest.approx(math.exp(-rate * h), abs=1e-7)
        else:  # L-stable: R(z) = O(1 / z) as z = -rate h -> -infinity (a trapezoidal
            # rule, only A-stable, would give |R| -> 1 here)
            assert abs(ynew[0]) < 10.0 / (rate * h)


def integrate(h, t_end=1.0):
    u = np.array([1.0])
    for _ in range(round(t_end / h)):
        u, _, _ = step(riccati, 0.0, u, -2.0 * u[0], h)
    return u[0]


def test_fourth_order_on_a_nonlinear_scalar_ode():
    errors = [abs(integrate(h) - 0.5) for h in (0.2, 0.1, 0.05)]
    orders = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert all(3.6 < p < 4.6 for p in orders), orders


def test_the_embedded_estimate_is_third_order_and_the_dense_output_interpolates():
    u = np.array([1.0])
    estimates = [step(riccati, 0.0, u, -2.0, h)[1] for h in (0.1, 0.05)]
    assert 2.6 < math.log2(estimates[0] / estimates[1]) < 4.6  # local error h^4: order 3
    h = 0.1
    ynew, _, dense = step(riccati, 0.0, u, -2.0, h)
    out = np.zeros(1)
    dense_value(dense, 0.0, out)
    assert out[0] == u[0]
    dense_value(dense, 1.0, out)
    assert out[0] == ynew[0]
    dense_value(dense, 0.5, out)
    assert out[0] == pytest.approx(1 / (1 + 0.5 * h), abs=1e-5)


@pytest.mark.parametrize("transposed", [False, True])
def test_the_iteration_matrix_solves_the_same_system_in_either_layout(transposed):
    rng = np.random.default_rng(3)
    n, h = 9, 0.01
    jac = rng.normal(size=(n, n)) * 50.0
    b = rng.normal(size=n)
    mat, pivots, x = np.zeros((n, n)), lu_workspace(n, transposed), b.copy()
    assert factor_iteration_matrix(jac, h, RODAS4.gamma, mat, pivots)
    lu_solve(mat, pivots, x)
    expected = np.linalg.solve(np.eye(n) / (h * RODAS4.gamma) - jac, b)
    assert np.allclose(x, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())


def _clock(h_accepted=0.0, err_accepted=1.0):
    clock = np.zeros(7)
    clock[H_ACCEPTED], clock[ERR_ACCEPTED] = h_accepted, err_accepted
    return clock


@pytest.mark.parametrize("err", [1e-6, 0.01, 0.5, 1.0, 3.0, 1e4])
def test_a_first_attempt_follows_the_fourth_root_rule(err):
    expected = min(max(err**0.25 / SAFETY, 1.0 / GROW_LIMIT), 1.0 / SHRINK_LIMIT)
    assert step_factor(err, 0.01, _clock(), 0.0, 0.0) == pytest.approx(expected, rel=1e-14)


def test_an_accepted_step_is_predicted_from_the_last_one_within_a_phase_only():
    h, err = 0.02, 0.5
    plain = err**0.25 / SAFETY
    # the last accepted step was larger with a far smaller error: the error is growing fast
    gus = (0.04 / h) * (err * err / 1e-3) ** 0.25 / SAFETY
    assert gus > plain
    assert step_factor(err, h, _clock(0.04, 1e-3), 0.0, 0.0) == pytest.approx(
        min(gus, 1.0 / SHRINK_LIMIT), rel=1e-14
    )
    assert step_factor(err, h, _clock(0.0, 1e-3), 0.0, 0.0) == pytest.approx(plain, rel=1e-14)


@pytest.mark.parametrize("order", [1.0, 1.5, 2.0, 3.0])
def test_a_second_rejection_lands_on_the_error_s_observed_order(order):
    # err(h) = (h / h0)^order: the step h0 has error 1. From 4 h0, the first rejection
    # shrinks by the fourth root; the second measures the order and lands on SAFETY h0.
    h0 = 1e-3

    def err(h):
        return (h / h0) ** order

    h1 = 4.0 * h0
    h2 = h1 / step_factor(err(h1), h1, _clock(), 0.0, 0.0)
    assert err(h2) > 1.0  # for order < 4 the fourth root shrinks too little
    h3 = h2 / step_factor(err(h2), h2, _clock(), h1, err(h1))
    assert h3 == pytest.approx(SAFETY * h0, rel=1e-12)
    assert err(h3) < 1.0


def test_an_error_that_does_not_fall_falls_back_to_the_fourth_root_rule():
    expected = min(5.0**0.25 / SAFETY, 1.0 / SHRINK_LIMIT)
    assert step_factor(5.0, 0.01, _clock(), 0.02, 4.0) == pytest.approx(expected, rel=1e-14)
    # an observed order above the method's is capped at 4
    assert step_factor(5.0, 0.01, _clock(), 0.02, 5.0 * 2**6) == pytest.approx(expected, rel=1e-14)
