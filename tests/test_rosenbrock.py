"""The generic Rosenbrock step with RODAS4's tableau, on scalar ODEs with known solutions."""

import math

import numpy as np
import pytest
from numba import njit

from softcell.kernels.linalg import lu_workspace
from softcell.kernels.rosenbrock import (
    dense_output,
    dense_value,
    error_norm,
    factor_iteration_matrix,
    stages,
)
from softcell.plugins.rodas4 import RODAS4


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
