"""The pose columns and rows of the Jacobian from the mixed second derivatives, against a
numpy evaluation of their formula: both the shared direct sums (all three pose columns
nonzero at the same few points) and the column-by-column path."""

from __future__ import annotations

import numpy as np
import pytest

from softcell.engine.kernels.jacobian import SPARSE_POINTS, assemble_jacobian, spectral_factors

LC = 4
N = 64


def _assembled(hwp, mobility, bot_mobility):
    m = 2 * LC + 1
    n_u = 2 * m + 3
    factors = np.zeros((3, m), complex)
    orders = np.zeros((3, m), complex)
    magnitudes = np.zeros((3, m))
    spectral_factors(LC, factors, orders, magnitudes)
    active = np.flatnonzero(np.abs(hwp).sum(axis=(1, 2))).astype(np.int64)
    active = np.concatenate([active, np.zeros(N - active.size, np.int64)])
    jac = np.zeros((n_u, n_u))
    assemble_jacobian(
        np.zeros((N, 6, 6)),
        hwp.copy(),
        np.zeros((3, 3)),
        LC,
        mobility,
        bot_mobility,
        np.exp(-2j * np.pi * np.arange(N) / N),
        np.zeros(N, np.int64),
        active,
        int(np.count_nonzero(np.abs(hwp).sum(axis=(1, 2)))),
        np.zeros(N, complex),
        np.zeros(N, complex),
        np.zeros(N, complex),
        np.zeros(4 * LC + 1, complex),
        np.zeros(4 * LC + 1, complex),
        np.zeros(m, complex),
        np.zeros((m, m), complex),
        np.zeros((m, m), complex),
        factors,
        orders,
        magnitudes,
        np.zeros((8, 4 * LC + 1)),
        jac,
    )
    return jac


def _expected(hwp, mobility, bot_mobility):
    """d f_hat_k / d pose_c = -mu c_al(k) G_hat(k) and d dpose_c / d g_j =
    -(2 pi) mu_c conj(G_hat(k_j)) (i k_j)^al, G_hat(k) = N^-1 sum_n G_n e^{-i k xi_n}."""
    m = 2 * LC + 1
    k = np.arange(-LC, LC + 1)
    xi = 2 * np.pi * np.arange(N) / N
    phase = np.exp(-1j * np.outer(k, xi))
    force = [-np.ones(m), 1j * k, k**2.0]
    order = [np.ones(m), 1j * k, -(k**2.0)]
    jac = np.zeros((2 * m + 3, 2 * m + 3))
    for al in range(3):
        for c in range(3):
            g = phase @ (hwp[:, 2 * al, c] + 1j * hwp[:, 2 * al + 1, c]) / N
            column = mobility * force[al] * g
            jac[:m, 2 * m + c] += column.real
            jac[m : 2 * m, 2 * m + c] += column.imag
            row = bot_mobility[c] * 2 * np.pi * np.conj(g) * order[al]
            jac[2 * m + c, :m] -= row.real
            jac[2 * m + c, m : 2 * m] += row.imag
    return jac


@pytest.mark.parametrize("case", ["shared", "not shared", "many"])
def test_pose_coupling_matches_its_formula(case):
    """Order 0 nonzero at a few points in every pose column (shared direct sums), or with
    a point only column 2 has, or at more points than direct sums take (FFTs); order 1 at
    a few shared points; order 2 nowhere."""
    rng = np.random.default_rng(5)
    hwp = np.zeros((N, 6, 3))
    count = SPARSE_POINTS + 1 if case == "many" else 12
    assert count < N
    points = rng.choice(N, count, replace=False)
    hwp[points, 0:2, :] = rng.standard_normal((count, 2, 3))
    hwp[points[:5], 2:4, :] = rng.standard_normal((5, 2, 3))
    if case == "not shared":
        extra = np.setdiff1d(np.arange(N), points)[0]
        hwp[extra, 0, 2] = 0.7
    mobility, bot_mobility = 0.37, np.array([1.3, 0.8, 2.1])
    jac = _assembled(hwp, mobility, bot_mobility)
    expected = _expected(hwp, mobility, bot_mobility)
    assert np.abs(expected).max() > 0
    np.testing.assert_allclose(jac, expected, rtol=0, atol=1e-13 * np.abs(expected).max())
