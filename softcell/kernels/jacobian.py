"""The Jacobian of the coupled membrane-bot right-hand side, from the energy terms' pointwise
second derivatives (docs/model.md §3; docs/plugins.md, "Jacobians").

Unknowns, in order: Re g_k and Im g_k for k = -Lc..Lc (cm), then the bot's x, y (cm) and
heading (rad); ``n_u = 2 (2 Lc + 1) + 3``. The right-hand side is
dg_k/dt = mu f_hat_k with mu = 2 pi / (gamma_mem l0), and
d pose_c/dt = (drive_c - (2 pi / N) dpose_c) / gamma_c.

Per point n, the energy terms supply the Hessian of e_n in w = (x, y, x', y', x'', y'')
(``hww[n, a, b]``), the mixed derivatives in w and the pose (``hwp[n, a, c]``) and the summed
pose-pose block (``hpp[c, d]``). Writing the 2 x 2 block of orders (alpha, beta) in complex form,
delta P^alpha = A delta z^beta + B conj(delta z^beta) with
A = (h_xx + h_yy)/2 + i (h_yx - h_xy)/2 and B = (h_xx - h_yy)/2 + i (h_yx + h_xy)/2,
the force modes respond as

    delta f_hat_k = sum_j [ cal_A_kj delta g_j + cal_B_kj conj(delta g_j) ],
    cal_A_kj = sum_{alpha, beta} c_alpha(k) (i k_j)^beta A_hat_{alpha beta}(k - k_j),
    cal_B_kj = sum_{alpha, beta} c_alpha(k) conj((i k_j)^beta) B_hat_{alpha beta}(k + k_j),

with c_0 = -1, c_1 = i k, c_2 = k^2 and X_hat(m) = N^-1 sum_n X_n e^{-i m xi_n}: a handful of
FFTs instead of one force evaluation per unknown. Blocks that vanish everywhere are skipped;
blocks nonzero at a few points only (the contact) are transformed by direct sums.
"""

from __future__ import annotations

import math

from numba import njit
from rocket_fft import c2c

from softcell.config import JIT
from softcell.kernels.spectral import AXES

#: Blocks nonzero at no more than this many points are transformed by direct sums, not FFTs.
SPARSE_POINTS = 48


@njit(**JIT)
def _transform(buf, index, count, twiddle, lo, hi, scratch, cursor, out):
    """out[m - lo] = N^-1 sum_n buf[n] e^{-i m xi_n} for m = lo..hi; ``index[:count]`` lists
    the points where ``buf`` may be nonzero (all of them when count == N). ``cursor``
    (int64[>= count]) is scratch for the twiddle indices (m i) mod N, stepped without a
    division per term."""
    n = buf.size
    if count <= SPARSE_POINTS:
        inv = 1.0 / n
        for t in range(count):
            cursor[t] = (lo * index[t]) % n
        for m in range(lo, hi + 1):
            s = 0.0 + 0.0j
            for t in range(count):
                i = index[t]
                s += buf[i] * twiddle[cursor[t]]
                c = cursor[t] + i
                cursor[t] = c - n if c >= n else c
            out[m - lo] = s * inv
    else:
        c2c(buf, scratch, AXES, True, 1.0 / n, 1)
        for m in range(lo, hi + 1):
            out[m - lo] = scratch[m % n]


@njit(**JIT)
def _dense_if_many(index, count, n):
    """Past SPARSE_POINTS points, list every point (the block is then transformed by an FFT,
    which reads the whole buffer); return the new count."""
    if count <= SPARSE_POINTS:
        return count
    for i in range(n):
        index[i] = i
    return n


@njit(**JIT)
def _order_factor(order, k):
    """(i k)^order for order 0, 1, 2."""
    if order == 0:
        return 1.0 + 0.0j
    if order == 1:
        return 1j * k
    return -(k * k) + 0.0j


@njit(**JIT)
def _force_factor(order, k):
    """c_order(k): the factor of P_hat^order in f_hat_k (-1, i k, k^2)."""
    if order == 0:
        return -1.0 + 0.0j
    if order == 1:
        return 1j * k
    return (k * k) + 0.0j


@njit(**JIT)
def active_points(hww, hwp, active):
    """Write into ``active`` the points where any second derivative is nonzero; return how
    many there are."""
    n = hww.shape[0]
    n_active = 0
    flat_w = hww.reshape(n * 36)
    flat_p = hwp.reshape(n * 18)
    for i in range(n):
        nonzero = False
        for a in range(36):
            if flat_w[36 * i + a] != 0.0:
                nonzero = True
                break
        if not nonzero:
            for a in range(18):
                if flat_p[18 * i + a] != 0.0:
                    nonzero = True
                    break
        if nonzero:
            active[n_active] = i
            n_active += 1
    return n_active


#: c_alpha(k) = k^alpha i^FORCE_TURNS[alpha] (-1, i k, k^2), and
#: (i k)^beta = k^beta i^ORDER_TURNS[beta] (1, i k, -k^2).
FORCE_TURNS = (2, 1, 0)
ORDER_TURNS = (0, 1, 2)


@njit(**JIT)
def _turn(z, p):
    """z i^p, exactly (a quarter turn swaps and negates parts)."""
    p %= 4
    if p == 0:
        return z
    if p == 1:
        return complex(-z.imag, z.real)
    if p == 2:
        return -z
    return complex(z.imag, -z.real)


@njit(**JIT)
def _couple(al, be, lc, magnitudes, a_hat, b_hat, rotated, cal_a, cal_b):
    """Add block (alpha, beta) (and, for alpha != beta, its transpose) to cal_A, cal_B:
    cal_A_ij += c_al(k_i) (i k_j)^be A_hat(k_i - k_j), cal_B_ij += c_al(k_i) conj((i k_j)^be)
    B_hat(k_i + k_j), with each factor c (i k)^o a real number times a fixed power of i, so
    the powers of i turn the transforms once per block and the entries cost real products."""
    size = a_hat.size
    ea, eb = FORCE_TURNS[al], FORCE_TURNS[be]
    fa, fb = ORDER_TURNS[al], ORDER_TURNS[be]
    for q in range(size):
        rotated[0, q] = _turn(a_hat[q], ea + fb)
        rotated[1, q] = _turn(b_hat[q], ea - fb)
        rotated[2, q] = _turn(a_hat[size - 1 - q].conjugate(), eb + fa)
        rotated[3, q] = _turn(b_hat[q], eb - fa)
    m_count = cal_a.shape[0]
    for i in range(m_count):
        ra = magnitudes[al, i]
        rb = magnitudes[be, i]
        for j in range(m_count):
            wa = ra * magnitudes[be, j]
            q = i - j + 2 * lc
            va = wa * rotated[0, q]
            vb = wa * rotated[1, i + j]
            if be != al:
                wb = rb * magnitudes[al, j]
                va += wb * rotated[2, q]
                vb += wb * rotated[3, i + j]
            cal_a[i, j] += va
            cal_b[i, j] += vb


# A compiled inner loop: exempt from the complexity limit of the rest of the code.
@njit(**JIT)
def assemble_jacobian(  # noqa: C901
    hww,
    hwp,
    hpp,
    lc,
    mobility,
    bot_mobility,
    twiddle,
    index,
    active,  # noqa: C901
    n_active,
    buf_a,
    buf_b,
    scratch,
    cursor,
    a_hat,
    b_hat,
    g_hat,
    cal_a,
    cal_b,
    factors,
    orders,
    magnitudes,
    rotated,
    jac,
):
    """Add to ``jac`` (float64[n_u, n_u], 1/s) the energy terms' part of the Jacobian, from
    their pointwise second derivatives at the N = len(hww) points of one grid, and reset
    ``hww, hwp, hpp`` to zero (they must be zero before the terms add into them).
    ``active[:n_active]`` lists the points where they may be nonzero (see
    :func:`active_points`).

    ``twiddle``: complex128[N], e^{-2 pi i n / N}. The rest are scratch arrays: ``index``
    int64[N];
    ``buf_a, buf_b, scratch`` complex128[N]; ``a_hat, b_hat`` complex128[4 Lc + 1]; ``g_hat``
    complex128[2 Lc + 1]; ``cal_a, cal_b`` complex128[2 Lc + 1, 2 Lc + 1]; ``factors, orders``
    complex128[3, 2 Lc + 1]; ``magnitudes`` float64[3, 2 Lc + 1] (k^order); ``rotated``
    complex128[4, 4 Lc + 1].
    """
    n = hww.shape[0]
    m_count = 2 * lc + 1
    for o in range(3):
        for i in range(m_count):
            factors[o, i] = _force_factor(o, i - lc)
            orders[o, i] = _order_factor(o, i - lc)
            magnitudes[o, i] = float(i - lc) ** o
    base = 2 * m_count
    weight = 2.0 * math.pi / n
    cal_a[:, :] = 0.0
    cal_b[:, :] = 0.0
    # The Hessian is symmetric: block (beta, alpha) is the transpose of (alpha, beta), so
    # A_{beta alpha} = conj(A_{alpha beta}) and B_{beta alpha} = B_{alpha beta}; the
    # upper blocks serve both.
    for al in range(3):
        for be in range(al, 3):
            count = 0
            for t in range(n_active):
                i = active[t]
                if (
                    hww[i, 2 * al, 2 * be] != 0.0
                    or hww[i, 2 * al, 2 * be + 1] != 0.0
                    or hww[i, 2 * al + 1, 2 * be] != 0.0
                    or hww[i, 2 * al + 1, 2 * be + 1] != 0.0
                ):
                    index[count] = i
                    count += 1
            if count == 0:
                continue
            count = _dense_if_many(index, count, n)
            for t in range(count):
                i = index[t]
                hxx = hww[i, 2 * al, 2 * be]
                hxy = hww[i, 2 * al, 2 * be + 1]
                hyx = hww[i, 2 * al + 1, 2 * be]
                hyy = hww[i, 2 * al + 1, 2 * be + 1]
                buf_a[i] = complex(0.5 * (hxx + hyy), 0.5 * (hyx - hxy))
                buf_b[i] = complex(0.5 * (hxx - hyy), 0.5 * (hyx + hxy))
            _transform(buf_a, index, count, twiddle, -2 * lc, 2 * lc, scratch, cursor, a_hat)
            _transform(buf_b, index, count, twiddle, -2 * lc, 2 * lc, scratch, cursor, b_hat)
            _couple(al, be, lc, magnitudes, a_hat, b_hat, rotated, cal_a, cal_b)
    for i in range(m_count):
        for j in range(m_count):
            s = cal_a[i, j] + cal_b[i, j]
            d = cal_a[i, j] - cal_b[i, j]
            jac[i, j] += mobility * s.real
            jac[m_count + i, j] += mobility * s.imag
            jac[i, m_count + j] -= mobility * d.imag
            jac[m_count + i, m_count + j] += mobility * d.real
    for al in range(3):
        for c in range(3):
            count = 0
            for t in range(n_active):
                i = active[t]
                if hwp[i, 2 * al, c] != 0.0 or hwp[i, 2 * al + 1, c] != 0.0:
                    index[count] = i
                    count += 1
            if count == 0:
                continue
            count = _dense_if_many(index, count, n)
            for t in range(count):
                i = index[t]
                buf_a[i] = complex(hwp[i, 2 * al, c], hwp[i, 2 * al + 1, c])
            _transform(buf_a, index, count, twiddle, -lc, lc, scratch, cursor, g_hat)
            for i in range(m_count):
                v = factors[al, i] * g_hat[i]
                jac[i, base + c] += mobility * v.real
                jac[m_count + i, base + c] += mobility * v.imag
            # d dpose_c = Re(N conj(G_hat(k_j)) (i k_j)^al delta g_j)
            scale = bot_mobility[c] * weight * n
            for j in range(m_count):
                t = g_hat[j].conjugate() * orders[al, j]
                jac[base + c, j] -= scale * t.real
                jac[base + c, m_count + j] += scale * t.imag
    for c in range(3):
        for d in range(3):
            jac[base + c, base + d] -= bot_mobility[c] * weight * hpp[c, d]
    hpp[:, :] = 0.0
    for t in range(n_active):
        hww[active[t]] = 0.0
        hwp[active[t]] = 0.0
