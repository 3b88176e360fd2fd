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

from softcell.engine.kernels.spectral import AXES
from softcell.settings import LEAN_JIT

#: Blocks nonzero at no more than this many points are transformed by direct sums, not FFTs.
SPARSE_POINTS = 48


@njit(**LEAN_JIT)
def _transform(buf, index, count, twiddle, lo, hi, scratch, out):
    """out[m - lo] = N^-1 sum_n buf[n] e^{-i m xi_n} for m = lo..hi; ``index[:count]`` lists
    the points where ``buf`` may be nonzero (all of them when count == N, a power of two).
    The twiddle index (m i) mod N is stepped without a division per term."""
    n = buf.size
    if count <= SPARSE_POINTS:
        # Point by point, each adding its term to every m: the sum of each m still runs over
        # the points in order.
        inv = 1.0 / n
        mask = n - 1  # N is a power of two: (m i) mod N without a division or a branch
        for m in range(hi - lo + 1):
            out[m] = 0.0 + 0.0j
        for t in range(count):
            i = index[t]
            value = buf[i]
            c = (lo * i) & mask
            for m in range(hi - lo + 1):
                out[m] += value * twiddle[c]
                c = (c + i) & mask
        for m in range(hi - lo + 1):
            out[m] = out[m] * inv
    else:
        c2c(buf, scratch, AXES, True, 1.0 / n, 1)
        for m in range(lo, hi + 1):
            out[m - lo] = scratch[m % n]


@njit(**LEAN_JIT)
def _transform_pair(buf_a, buf_b, index, count, twiddle, lo, hi, scratch, out_a, out_b):
    """:func:`_transform` of two buffers nonzero at the same points; the direct sums share
    their twiddle factors (each sum still runs over the points in order)."""
    n = buf_a.size
    if count > SPARSE_POINTS:
        _transform(buf_a, index, count, twiddle, lo, hi, scratch, out_a)
        _transform(buf_b, index, count, twiddle, lo, hi, scratch, out_b)
        return
    inv = 1.0 / n
    mask = n - 1
    for m in range(hi - lo + 1):
        out_a[m] = 0.0 + 0.0j
        out_b[m] = 0.0 + 0.0j
    for t in range(count):
        i = index[t]
        value_a = buf_a[i]
        value_b = buf_b[i]
        c = (lo * i) & mask
        for m in range(hi - lo + 1):
            w = twiddle[c]
            out_a[m] += value_a * w
            out_b[m] += value_b * w
            c = (c + i) & mask
    for m in range(hi - lo + 1):
        out_a[m] = out_a[m] * inv
        out_b[m] = out_b[m] * inv


@njit(**LEAN_JIT)
def _dense_if_many(index, count, n):
    """Past SPARSE_POINTS points, list every point (the block is then transformed by an FFT,
    which reads the whole buffer); return the new count."""
    if count <= SPARSE_POINTS:
        return count
    for i in range(n):
        index[i] = i
    return n


@njit(**LEAN_JIT)
def _count_pose_points(hwp, al, c, active, n_active, index):
    """List in ``index`` the active points where block (al, pose c) of ``hwp`` is nonzero;
    return how many there are."""
    count = 0
    for t in range(n_active):
        i = active[t]
        if hwp[i, 2 * al, c] != 0.0 or hwp[i, 2 * al + 1, c] != 0.0:
            index[count] = i
            count += 1
    return count


@njit(**LEAN_JIT)
def _shared_pose_points(hwp, al, active, n_active, index):
    """Where the three pose columns of order ``al`` in ``hwp`` are nonzero among the active
    points: 0 if at none; if at the same points, no more than SPARSE_POINTS of them, their
    number (listed in ``index``); otherwise -1."""
    count = 0
    for t in range(n_active):
        i = active[t]
        nonzero = 0
        for c in range(3):
            if hwp[i, 2 * al, c] != 0.0 or hwp[i, 2 * al + 1, c] != 0.0:
                nonzero += 1
        if nonzero == 0:
            continue
        if nonzero < 3 or count == SPARSE_POINTS:
            return -1
        index[count] = i
        count += 1
    return count


@njit(**LEAN_JIT)
def _direct_triple(buf_0, buf_1, buf_2, index, count, twiddle, lo, hi, out_0, out_1, out_2):
    """The direct sums of :func:`_transform` of three buffers nonzero at the same ``count``
    (<= SPARSE_POINTS) points, sharing their twiddle factors (each sum still runs over the
    points in order: the same numbers as three calls)."""
    inv = 1.0 / buf_0.size
    mask = buf_0.size - 1
    for m in range(hi - lo + 1):
        out_0[m] = 0.0 + 0.0j
        out_1[m] = 0.0 + 0.0j
        out_2[m] = 0.0 + 0.0j
    for t in range(count):
        i = index[t]
        value_0, value_1, value_2 = buf_0[i], buf_1[i], buf_2[i]
        c = (lo * i) & mask
        for m in range(hi - lo + 1):
            w = twiddle[c]
            out_0[m] += value_0 * w
            out_1[m] += value_1 * w
            out_2[m] += value_2 * w
            c = (c + i) & mask
    for m in range(hi - lo + 1):
        out_0[m] = out_0[m] * inv
        out_1[m] = out_1[m] * inv
        out_2[m] = out_2[m] * inv


@njit(**LEAN_JIT)
def _pose_coupling(
    al, c, g_hat, m_count, base, mobility, bot_mobility, weight, n, factors, orders, jac
):
    """Add to ``jac`` the coupling of the modes and pose coordinate c through the transform
    ``g_hat`` (complex128[2 Lc + 1]) of block (al, c) of the mixed derivatives: the column
    of c (the force modes' response) and its row (the pose's response to the modes;
    ``weight`` = 2 pi / n, the weight of each of the n points)."""
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


@njit(**LEAN_JIT)
def _order_factor(order, k):
    """(i k)^order for order 0, 1, 2."""
    if order == 0:
        return 1.0 + 0.0j
    if order == 1:
        return 1j * k
    return -(k * k) + 0.0j


@njit(**LEAN_JIT)
def _force_factor(order, k):
    """c_order(k): the factor of P_hat^order in f_hat_k (-1, i k, k^2)."""
    if order == 0:
        return -1.0 + 0.0j
    if order == 1:
        return 1j * k
    return (k * k) + 0.0j


@njit(**LEAN_JIT)
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


@njit(**LEAN_JIT)
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


@njit(**LEAN_JIT)
def _couple(al, be, lc, magnitudes, a_hat, b_hat, rotated, cal_a, cal_b):
    """Add block (alpha, beta) (and, for alpha != beta, its transpose) to cal_A, cal_B:
    cal_A_ij += c_al(k_i) (i k_j)^be A_hat(k_i - k_j), cal_B_ij += c_al(k_i) conj((i k_j)^be)
    B_hat(k_i + k_j), with each factor c (i k)^o a real number times a fixed power of i, so
    the powers of i turn the transforms once per block and the entries cost real products
    (``rotated``: float64[8, 4 Lc + 1], the turned transforms' real and imaginary parts)."""
    size = a_hat.size
    ea, eb = FORCE_TURNS[al], FORCE_TURNS[be]
    fa, fb = ORDER_TURNS[al], ORDER_TURNS[be]
    for q in range(size):
        _split(_turn(a_hat[q], ea + fb), rotated, 0, q)
        _split(_turn(b_hat[q], ea - fb), rotated, 2, q)
        _split(_turn(a_hat[size - 1 - q].conjugate(), eb + fa), rotated, 4, q)
        _split(_turn(b_hat[q], eb - fa), rotated, 6, q)
    m_count = cal_a.shape[0]
    for i in range(m_count):
        ra = magnitudes[al, i]
        rb = magnitudes[be, i]
        if be == al:
            for j in range(m_count):
                wa = ra * magnitudes[be, j]
                q = i - j + 2 * lc
                cal_a[i, j] += complex(wa * rotated[0, q], wa * rotated[1, q])
                cal_b[i, j] += complex(wa * rotated[2, i + j], wa * rotated[3, i + j])
        else:
            for j in range(m_count):
                wa = ra * magnitudes[be, j]
                wb = rb * magnitudes[al, j]
                q = i - j + 2 * lc
                cal_a[i, j] += complex(
                    wa * rotated[0, q] + wb * rotated[4, q],
                    wa * rotated[1, q] + wb * rotated[5, q],
                )
                cal_b[i, j] += complex(
                    wa * rotated[2, i + j] + wb * rotated[6, i + j],
                    wa * rotated[3, i + j] + wb * rotated[7, i + j],
                )


@njit(**LEAN_JIT)
def _split(z, out, row, q):
    """out[row, q], out[row + 1, q] = the real and imaginary parts of z."""
    out[row, q] = z.real
    out[row + 1, q] = z.imag


@njit(**LEAN_JIT)
def spectral_factors(lc, factors, orders, magnitudes):
    """The tables :func:`assemble_jacobian` reads, for k = -Lc..Lc (column k + Lc):
    ``factors[o]`` = c_o(k) (-1, i k, k^2), ``orders[o]`` = (i k)^o (1, i k, -k^2) and
    ``magnitudes[o]`` = k^o, for o = 0, 1, 2."""
    for o in range(3):
        for i in range(2 * lc + 1):
            factors[o, i] = _force_factor(o, i - lc)
            orders[o, i] = _order_factor(o, i - lc)
            magnitudes[o, i] = float(i - lc) ** o


# A compiled inner loop: exempt from the complexity limit of the rest of the code.
@njit(**LEAN_JIT)
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

    ``twiddle``: complex128[N], e^{-2 pi i n / N}; ``factors, orders`` (complex128[3, 2 Lc + 1])
    and ``magnitudes`` (float64[3, 2 Lc + 1]): the tables of :func:`spectral_factors`. The
    rest are scratch arrays: ``index`` int64[N]; ``buf_a, buf_b, scratch`` complex128[N];
    ``a_hat, b_hat`` complex128[4 Lc + 1]; ``g_hat`` complex128[2 Lc + 1]; ``cal_a, cal_b``
    complex128[2 Lc + 1, 2 Lc + 1]; ``rotated`` float64[8, 4 Lc + 1].
    """
    n = hww.shape[0]
    m_count = 2 * lc + 1
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
            _transform_pair(
                buf_a, buf_b, index, count, twiddle, -2 * lc, 2 * lc, scratch, a_hat, b_hat
            )
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
        count = _shared_pose_points(hwp, al, active, n_active, index)
        if count == 0:
            continue
        if count > 0:
            # All three pose columns nonzero at the same few points (the contact, whose
            # every point depends on the pose): their direct sums share the twiddle factors.
            for t in range(count):
                i = index[t]
                buf_a[i] = complex(hwp[i, 2 * al, 0], hwp[i, 2 * al + 1, 0])
                buf_b[i] = complex(hwp[i, 2 * al, 1], hwp[i, 2 * al + 1, 1])
                scratch[i] = complex(hwp[i, 2 * al, 2], hwp[i, 2 * al + 1, 2])
            _direct_triple(
                buf_a, buf_b, scratch, index, count, twiddle, -lc, lc, g_hat, a_hat, b_hat
            )
            transforms = (g_hat, a_hat, b_hat)
            for c in range(3):
                _pose_coupling(
                    al,
                    c,
                    transforms[c],
                    m_count,
                    base,
                    mobility,
                    bot_mobility,
                    weight,
                    n,
                    factors,
                    orders,
                    jac,
                )
            continue
        for c in range(3):
            count = _count_pose_points(hwp, al, c, active, n_active, index)
            if count == 0:
                continue
            count = _dense_if_many(index, count, n)
            for t in range(count):
                i = index[t]
                buf_a[i] = complex(hwp[i, 2 * al, c], hwp[i, 2 * al + 1, c])
            _transform(buf_a, index, count, twiddle, -lc, lc, scratch, g_hat)
            _pose_coupling(
                al,
                c,
                g_hat,
                m_count,
                base,
                mobility,
                bot_mobility,
                weight,
                n,
                factors,
                orders,
                jac,
            )
    for c in range(3):
        for d in range(3):
            jac[base + c, base + d] -= bot_mobility[c] * weight * hpp[c, d]
    hpp[:, :] = 0.0
    for t in range(n_active):
        hww[active[t]] = 0.0
        hwp[active[t]] = 0.0
