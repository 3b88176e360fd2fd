"""A nonlinear friction law between the force modes and the velocity modes (docs/model.md §3).

The force modes f_hat_k (|k| <= Lc, N per unit xi) give the force density on the membrane at
M points, f(xi_n) = s sum_k f_hat_k e^{i k xi_n} with s = 2 pi / l0 (N cm^-1); the law's
kernel maps it to the velocity v(xi_n) (cm s^-1); the velocity's modes |k| <= Lc,
v_hat_k = M^-1 sum_n v(xi_n) e^{-i k xi_n}, are dg_k / dt.

Linearised, delta v = D delta f with D the law's 2 x 2 derivative at each point. In complex
form delta v = A delta f + B conj(delta f), A = (D_xx + D_yy) / 2 + i (D_yx - D_xy) / 2,
B = (D_xx - D_yy) / 2 + i (D_yx + D_xy) / 2, so

    delta v_hat_k = s sum_j [A_hat(k - j) delta f_hat_j + B_hat(k + j) conj(delta f_hat_j)],

the same Toeplitz-plus-Hankel structure as :mod:`softcell.engine.kernels.jacobian`;
:func:`law_matrix` writes it as a real matrix on (Re f_hat, Im f_hat).
"""

from __future__ import annotations

from numba import njit
from rocket_fft import c2c

from softcell.engine.kernels.spectral import AXES
from softcell.settings import JIT


@njit(**JIT)
def force_field(fhat, scale, spec, field, fx, fy):
    """fx, fy (float64[M], N cm^-1): the force density of the modes ``fhat``
    (complex128[2 Lc + 1], N per unit xi) at the M points; ``spec, field`` complex128[M]
    scratch."""
    n = fx.size
    lc = (fhat.size - 1) // 2
    spec[:] = 0.0
    for j in range(fhat.size):
        spec[(j - lc) % n] = fhat[j]
    c2c(spec, field, AXES, False, 1.0, 1)
    for i in range(n):
        fx[i] = scale * field[i].real
        fy[i] = scale * field[i].imag


@njit(**JIT)
def shape_field(modes, spec, field, x, y, tx, ty):
    """x, y (float64[M], cm): the membrane at the M points, from its modes ``modes``
    (complex128[2 Lc + 1], cm); tx, ty (float64[M]): its unit tangent there, along
    increasing xi. ``spec, field`` complex128[M] scratch."""
    n = x.size
    lc = (modes.size - 1) // 2
    for part in range(2):
        spec[:] = 0.0
        for j in range(modes.size):
            spec[(j - lc) % n] = modes[j] if part == 0 else 1j * (j - lc) * modes[j]
        c2c(spec, field, AXES, False, 1.0, 1)
        for i in range(n):
            if part == 0:
                x[i] = field[i].real
                y[i] = field[i].imag
            else:
                speed = abs(field[i])
                inv = 1.0 / speed if speed > 0.0 else 0.0
                tx[i] = field[i].real * inv
                ty[i] = field[i].imag * inv


@njit(**JIT)
def velocity_modes(vx, vy, spec, field, vhat):
    """vhat (complex128[2 Lc + 1], cm s^-1): the modes |k| <= Lc of the velocity vx, vy at
    the N points."""
    n = vx.size
    lc = (vhat.size - 1) // 2
    for i in range(n):
        field[i] = complex(vx[i], vy[i])
    c2c(field, spec, AXES, True, 1.0 / n, 1)
    for j in range(vhat.size):
        vhat[j] = spec[(j - lc) % n]


@njit(**JIT)
def law_matrix(dxx, dxy, dyx, dyy, scale, lc, buf, spec, a_hat, b_hat, out):
    """``out`` (float64[2 m, 2 m], m = 2 Lc + 1): d (Re v_hat, Im v_hat) / d (Re f_hat,
    Im f_hat) for the law's derivative ``dab`` (float64[M], cm^2 N^-1 s^-1) at the M points.
    ``buf, spec`` complex128[M] and ``a_hat, b_hat`` complex128[4 Lc + 1] are scratch."""
    n = dxx.size
    m = 2 * lc + 1
    for part in range(2):
        for i in range(n):
            if part == 0:
                buf[i] = complex(0.5 * (dxx[i] + dyy[i]), 0.5 * (dyx[i] - dxy[i]))
            else:
                buf[i] = complex(0.5 * (dxx[i] - dyy[i]), 0.5 * (dyx[i] + dxy[i]))
        c2c(buf, spec, AXES, True, scale / n, 1)
        target = a_hat if part == 0 else b_hat
        for d in range(-2 * lc, 2 * lc + 1):
            target[d + 2 * lc] = spec[d % n]
    for i in range(m):
        for j in range(m):
            a = a_hat[i - j + 2 * lc]
            b = b_hat[i + j]
            s = a + b
            d = a - b
            out[i, j] = s.real
            out[m + i, j] = s.imag
            out[i, m + j] = -d.imag
            out[m + i, m + j] = d.real


@njit(**JIT)
def apply_to_rows(law, jac, rows):
    """jac[:2 m, :] = law @ jac[:2 m, :] (the force modes' rows of a Jacobian become the
    velocity modes' rows); ``rows`` float64[2 m, n_u] is scratch."""
    m2 = law.shape[0]
    nu = jac.shape[1]
    for r in range(m2):
        for c in range(nu):
            rows[r, c] = jac[r, c]
    for r in range(m2):
        for c in range(nu):
            jac[r, c] = 0.0
        for q in range(m2):
            w = law[r, q]
            if w != 0.0:
                for c in range(nu):
                    jac[r, c] += w * rows[q, c]
