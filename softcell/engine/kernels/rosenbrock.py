"""One step of a Rosenbrock (linearly implicit Runge-Kutta) method, for any tableau.

In Hairer & Wanner's transformed variables (Solving ODEs II, section IV.7), a step of size h
from u with Jacobian J solves, for each stage s,

    (I / (h gamma) - J) k_s = f(u + sum_{j<s} a_sj k_j) + sum_{j<s} c_sj k_j / h,

and the new state is the last stage's point plus its increment. A method is its
:class:`Tableau`: ``gamma``, the strictly lower triangular ``a`` and ``c``, and the rows of its
continuous extension. Stages past the last row of ``a`` take the previous stage's point plus
the previous increment, as the stiffly accurate RODAS methods do (their last two stages are
the solution and the embedded error estimate). The right-hand side ``f(y, out, args)`` writes
du/dt at y into ``out``; ``args`` is whatever it needs, passed through unchanged.

Nothing here allocates: the caller owns every array.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from softcell.engine.kernels.linalg import holds_transpose, lu_factor, lu_solve
from softcell.settings import JIT_COMPOSED


class Tableau(NamedTuple):
    """The coefficients of a Rosenbrock method in transformed variables."""

    gamma: float  # the diagonal coefficient
    a: np.ndarray  # float64[S - 1, S - 2]: stage points; rows beyond reuse the last point
    c: np.ndarray  # float64[S, S - 1]: the stages' couplings, c[s, j] for j < s
    dense: np.ndarray  # float64[2, S - 1]: the continuous extension's two rows

    @property
    def stages(self) -> int:
        return self.c.shape[0]


# ``stages`` takes the right-hand side as an argument, so it is compiled once per right-hand
# side; these kernels are compiled into the generated loop that calls them (JIT_COMPOSED),
# whose entry in the compiled-model cache keeps them.


@njit(**JIT_COMPOSED)
def factor_iteration_matrix(jac, h, gamma, mat, pivots):
    """mat = I / (h gamma) - jac, factored in place; False if it is singular."""
    nu = jac.shape[0]
    fac = 1.0 / (h * gamma)
    if holds_transpose(pivots, nu):
        for i in range(nu):
            for j in range(nu):
                mat[j, i] = -jac[i, j]
            mat[i, i] += fac
    else:
        for i in range(nu):
            for j in range(nu):
                mat[i, j] = -jac[i, j]
            mat[i, i] += fac
    return lu_factor(mat, pivots)


@njit(**JIT_COMPOSED, inline="always")
def stages(f, args, u, f0, h, a, c, mat, pivots, k, y, force):
    """The increments k[s] of every stage, with ``mat`` factored by
    :func:`factor_iteration_matrix`; ``f0`` is f(u). On return ``y`` holds the last stage's
    point, so the new state is y + k[-1] and k[-1] the embedded error estimate."""
    nu = u.size
    for s in range(c.shape[0]):
        if s == 0:
            for i in range(nu):
                force[i] = f0[i]
        else:
            if s < a.shape[0]:
                for i in range(nu):
                    acc = u[i]
                    for j in range(s):
                        acc += a[s, j] * k[j, i]
                    y[i] = acc
            else:
                for i in range(nu):
                    y[i] += k[s - 1, i]
            f(y, force, args)
            for i in range(nu):
                acc = 0.0
                for j in range(s):
                    acc += c[s, j] * k[j, i]
                force[i] += acc / h
        lu_solve(mat, pivots, force)
        for i in range(nu):
            k[s, i] = force[i]


@njit(**JIT_COMPOSED)
def error_norm(u, y, k, atol, rtol, ynew):
    """ynew = y + k[-1] (the new state) and the RMS norm of the error estimate k[-1],
    scaled by atol + rtol max(|u|, |ynew|) per component."""
    nu = u.size
    last = k.shape[0] - 1
    err = 0.0
    for i in range(nu):
        ynew[i] = y[i] + k[last, i]
        scale = atol + rtol * max(abs(u[i]), abs(ynew[i]))
        err += (k[last, i] / scale) ** 2
    return math.sqrt(err / nu)


@njit(**JIT_COMPOSED)
def dense_output(u, ynew, k, hd, dense):
    """The continuous extension of the step u -> ynew into ``dense`` (4 rows), for
    :func:`dense_value`."""
    for i in range(u.size):
        d1 = 0.0
        d2 = 0.0
        for j in range(hd.shape[1]):
            d1 += hd[0, j] * k[j, i]
            d2 += hd[1, j] * k[j, i]
        dense[0, i] = u[i]
        dense[1, i] = ynew[i]
        dense[2, i] = d1
        dense[3, i] = d2


@njit(**JIT_COMPOSED)
def dense_value(dense, theta, out):
    """The state at the fraction ``theta`` in [0, 1] of the last step."""
    for i in range(out.size):
        out[i] = (1.0 - theta) * dense[0, i] + theta * (
            dense[1, i] + (1.0 - theta) * (dense[2, i] + theta * dense[3, i])
        )
