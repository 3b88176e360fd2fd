"""Dense LU factorization with partial pivoting, for the small (~70 x 70) systems of the
linearly implicit integrators.

Written out because numba's ``np.linalg`` offers ``solve`` and ``inv`` but no separate
factorization: a Rosenbrock step solves six systems with one matrix. In place, no allocation.
"""

from __future__ import annotations

from numba import njit

from softcell.config import JIT


@njit(**JIT)
def lu_factor(a, pivots):
    """Factor the square float64 matrix ``a`` in place (L below the diagonal, unit diagonal
    implied; U on and above), recording row swaps in ``pivots`` (int64[n]).

    Returns False if a pivot is exactly zero (a singular matrix), True otherwise.
    """
    n = a.shape[0]
    for k in range(n):
        p = k
        largest = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > largest:
                largest = abs(a[i, k])
                p = i
        pivots[k] = p
        if largest == 0.0:
            return False
        if p != k:
            for j in range(n):
                a[k, j], a[p, j] = a[p, j], a[k, j]
        inv = 1.0 / a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] * inv
            a[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= f * a[k, j]
    return True


@njit(**JIT)
def lu_solve(a, pivots, b):
    """Solve A x = b in place (``b`` becomes x) with the factors of :func:`lu_factor`."""
    n = a.shape[0]
    for k in range(n):
        p = pivots[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= a[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= a[i, j] * b[j]
        b[i] = s / a[i, i]
