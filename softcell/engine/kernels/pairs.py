"""Membrane-membrane contact between the cells of an assembly: forces on the modes and their
Jacobian, for rodas4's group loop (``integrators/rodas4/templates/group.py``).

Each point of membrane c has the energy density e(rho) per unit xi (the pair terms' laws,
summed: ``law(rho, coefficients, out, scratch)`` writes e, de/drho and d^2 e / drho^2), with
rho the signed distance from the point to d's polygon (its N points joined by segments;
positive outside d, negative inside), within ``reach``. Both ways: c's points against d's
polygon and d's points against c's. The distance to a segment depends on the point and on
the segment's two ends, so every contact pushes the point and pulls the segment's ends with
the opposite total force: the pair forces conserve momentum exactly.

The partials de/dq = e'(rho) grad rho land on the modes as the bot's contact does
(docs/model.md §3): dg_k/dt += mobility f_hat_k with f_hat_k = -(1/N) sum_n P_n
e^{-i k xi_n}, P_n = de/dz_n as x + i y. Their second derivatives, e'' grad rho grad rho^T +
e' hess rho, take hess rho from central differences of the analytic grad rho (the contact's
segment held fixed), and map onto the modes through dz_n = sum_l dg_l e^{i l xi_n}: a real
2 x 2 block H acts on dz as alpha dz + beta conj(dz), which makes two complex m x m matrices
per pair of cells.

The functions that take ``law`` are compiled into their caller (``JIT_COMPOSED``), rodas4's
group loop, whose cache entry keeps them.

Images: a shift (cm) is added to cell d's points as seen from cell c (the minimum image of a
periodic box, fixed over a sampling interval); the forces do not depend on it otherwise.
Every length is in cm, every force in N.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from rocket_fft import c2c

from softcell.engine.kernels.spectral import AXES, derivative_spectrum
from softcell.settings import JIT, JIT_COMPOSED


@njit(**JIT)
def membrane_points(modes, spec, z):
    """The membrane's N = len(z) points z_n = sum_k g_k e^{i k xi_n} (complex128, cm)."""
    derivative_spectrum(modes, 0, spec)
    c2c(spec, z, AXES, False, 1.0, 1)


@njit(**JIT)
def segment_distance(px, py, bx, by, cx, cy, grad):
    """The signed distance rho (cm) from p to the segment b -> c of a counter-clockwise
    polygon (positive on its right, the outside), and its gradient with respect to
    (p_x, p_y, b_x, b_y, c_x, c_y) into ``grad`` (float64[6])."""
    vx, vy = cx - bx, cy - by
    ux, uy = px - bx, py - by
    l2 = vx * vx + vy * vy
    cross = ux * vy - uy * vx
    t = (ux * vx + uy * vy) / l2
    if 0.0 < t < 1.0:
        length = math.sqrt(l2)
        rho = cross / length
        grad[0] = vy / length
        grad[1] = -vx / length
        gx = -uy / length - rho * vx / l2
        gy = ux / length - rho * vy / l2
        grad[4] = gx
        grad[5] = gy
        grad[2] = -grad[0] - gx
        grad[3] = -grad[1] - gy
        return rho
    grad[:] = 0.0
    if t <= 0.0:
        dx, dy, end = ux, uy, 2
    else:
        dx, dy, end = px - cx, py - cy, 4
    d = math.sqrt(dx * dx + dy * dy)
    sign = 1.0 if cross >= 0.0 else -1.0
    if d > 0.0:
        grad[0] = sign * dx / d
        grad[1] = sign * dy / d
        grad[end] = -grad[0]
        grad[end + 1] = -grad[1]
    return sign * d


@njit(**JIT)
def _unsigned(px, py, bx, by, cx, cy):
    """|p - segment b c|^2 (cm^2)."""
    vx, vy = cx - bx, cy - by
    ux, uy = px - bx, py - by
    t = (ux * vx + uy * vy) / (vx * vx + vy * vy)
    t = min(max(t, 0.0), 1.0)
    dx, dy = ux - t * vx, uy - t * vy
    return dx * dx + dy * dy


@njit(**JIT)
def _box(z, sx, sy, margin):
    x0, x1, y0, y1 = np.inf, -np.inf, np.inf, -np.inf
    for n in range(z.size):
        x, y = z[n].real + sx, z[n].imag + sy
        x0, x1, y0, y1 = min(x0, x), max(x1, x), min(y0, y), max(y1, y)
    return x0 - margin, x1 + margin, y0 - margin, y1 + margin


@njit(**JIT)
def _longest_segment(z):
    n = z.size
    longest = 0.0
    for i in range(n):
        longest = max(longest, abs(z[(i + 1) % n] - z[i]))
    return longest


@njit(**JIT)
def find_contacts(z, shifts, cutoff, contacts):  # noqa: C901
    """Every point within ``cutoff`` (cm) of another cell's polygon, with the segment it is
    nearest to: row t of ``contacts`` (int64[K, 4]) is (cell c, point a, cell d, segment s),
    segment s joining d's points s and s + 1 (mod N). ``z``: complex128[G, N] (cm);
    ``shifts``: float64[G, G, 2], the shift of d's points seen from c (cm). Returns the
    number of contacts, or -1 if ``contacts`` is too short."""
    g, n = z.shape
    count = 0
    for d in range(g):
        seg = _longest_segment(z[d])
        reach = cutoff + seg
        for c in range(g):
            if c == d:
                continue
            sx, sy = shifts[c, d, 0], shifts[c, d, 1]
            bx0, bx1, by0, by1 = _box(z[d], sx, sy, reach)
            cx0, cx1, cy0, cy1 = _box(z[c], 0.0, 0.0, reach)
            if bx0 > cx1 or cx0 > bx1 or by0 > cy1 or cy0 > by1:
                continue
            # d's points near c's box, sorted by x; c's points near d's box look them up.
            near = np.empty(n, np.int64)
            k = 0
            for b in range(n):
                x, y = z[d, b].real + sx, z[d, b].imag + sy
                if cx0 <= x <= cx1 and cy0 <= y <= cy1:
                    near[k] = b
                    k += 1
            if k == 0:
                continue
            near = near[:k]
            xs = np.empty(k)
            for i in range(k):
                xs[i] = z[d, near[i]].real + sx
            order = np.argsort(xs)
            xs = xs[order]
            near = near[order]
            for a in range(n):
                px, py = z[c, a].real, z[c, a].imag
                if not (bx0 <= px <= bx1 and by0 <= py <= by1):
                    continue
                lo = np.searchsorted(xs, px - reach)
                hi = np.searchsorted(xs, px + reach, side="right")
                best, best_s = np.inf, -1
                for i in range(lo, hi):
                    b = near[i]
                    if abs(z[d, b].imag + sy - py) > reach:
                        continue
                    for s in ((b - 1) % n, b):
                        e = (s + 1) % n
                        q = _unsigned(
                            px,
                            py,
                            z[d, s].real + sx,
                            z[d, s].imag + sy,
                            z[d, e].real + sx,
                            z[d, e].imag + sy,
                        )
                        if q < best:
                            best, best_s = q, s
                if best_s < 0 or best > reach * reach:
                    continue
                if count >= contacts.shape[0]:
                    return -1
                contacts[count, 0] = c
                contacts[count, 1] = a
                contacts[count, 2] = d
                contacts[count, 3] = best_s
                count += 1
    return count


@njit(**JIT)
def _ends(z, shifts, contact):
    """The contact's point p and segment ends b, c as six coordinates (cm)."""
    c, a, d, s = contact[0], contact[1], contact[2], contact[3]
    n = z.shape[1]
    sx, sy = shifts[c, d, 0], shifts[c, d, 1]
    e = (s + 1) % n
    return (
        z[c, a].real,
        z[c, a].imag,
        z[d, s].real + sx,
        z[d, s].imag + sy,
        z[d, e].real + sx,
        z[d, e].imag + sy,
    )


@njit(**JIT_COMPOSED, inline="always")
def pair_forces(z, shifts, contacts, count, law, coefficients, mobility, twiddle, out, nu):
    """Add the pair forces' mode rates to ``out`` (float64[G nu]: each cell's Re g, Im g,
    pose, cm s^-1); ``law`` and ``coefficients`` are the pair terms' (module docstring),
    ``mobility`` 2 pi / (gamma_mem l0), ``twiddle`` = exp(-2 pi i n / N)."""
    n = z.shape[1]
    m = (nu - 3) // 2
    lc = (m - 1) // 2
    grad = np.empty(6)
    values = np.empty(3)
    scratch = np.empty(3)
    inv = mobility / n
    for t in range(count):
        row = contacts[t]
        px, py, bx, by, cx, cy = _ends(z, shifts, row)
        rho = segment_distance(px, py, bx, by, cx, cy, grad)
        law(rho, coefficients, values, scratch)
        if values[1] == 0.0:
            continue
        for node in range(3):
            cell = row[0] if node == 0 else row[2]
            index = row[1] if node == 0 else (row[3] + node - 1) % n
            p = values[1] * complex(grad[2 * node], grad[2 * node + 1])
            base = cell * nu
            cursor = (-lc * index) % n
            for j in range(m):
                f = -p * twiddle[cursor] * inv
                out[base + j] += f.real
                out[base + m + j] += f.imag
                cursor += index
                if cursor >= n:
                    cursor -= n


@njit(**JIT)
def distance_hessian(q, step, grad, hessian):
    """rho at the six coordinates q (cm), its gradient into ``grad`` and d^2 rho / dq^2
    (cm^-1) into ``hessian`` by central differences of the gradient with the segment held
    fixed (step ``step``, cm); returns rho."""
    plus = np.empty(6)
    minus = np.empty(6)
    shifted = q.copy()
    rho = segment_distance(q[0], q[1], q[2], q[3], q[4], q[5], grad)
    for j in range(6):
        shifted[j] = q[j] + step
        segment_distance(
            shifted[0], shifted[1], shifted[2], shifted[3], shifted[4], shifted[5], plus
        )
        shifted[j] = q[j] - step
        segment_distance(
            shifted[0], shifted[1], shifted[2], shifted[3], shifted[4], shifted[5], minus
        )
        shifted[j] = q[j]
        for i in range(6):
            hessian[i, j] = (plus[i] - minus[i]) / (2.0 * step)
    return rho


@njit(**JIT_COMPOSED, inline="always")
def contact_hessian(q, law, coefficients, step, hessian):
    """d^2 e / dq^2 (N cm^-1, float64[6, 6]) of one contact at the six coordinates q (cm):
    e'' grad rho grad rho^T + e' hess rho. Returns False where the law vanishes."""
    grad = np.empty(6)
    values = np.empty(3)
    scratch = np.empty(3)
    rho = distance_hessian(q, step, grad, hessian)
    law(rho, coefficients, values, scratch)
    if values[1] == 0.0 and values[2] == 0.0:
        return False
    for i in range(6):
        for j in range(6):
            hessian[i, j] = values[2] * grad[i] * grad[j] + values[1] * hessian[i, j]
    return True


@njit(**JIT)
def _flush_cross(cross_a, cross_b, c, d, nu, m, jac):
    """Add the real form of dz_d -> A dz_d + B conj(dz_d) (complex m x m) to block (c, d) of
    ``jac`` and its transpose to block (d, c) (the pair Jacobian is -(mobility / N) D^T H D,
    symmetric, with D the map from modes to points)."""
    rows, cols = c * nu, d * nu
    for j in range(m):
        for i in range(m):
            a, b = cross_a[j, i], cross_b[j, i]
            rr = a.real + b.real
            ri = -a.imag + b.imag
            ir = a.imag + b.imag
            ii = a.real - b.real
            jac[rows + j, cols + i] += rr
            jac[rows + j, cols + m + i] += ri
            jac[rows + m + j, cols + i] += ir
            jac[rows + m + j, cols + m + i] += ii
            jac[cols + i, rows + j] += rr
            jac[cols + m + i, rows + j] += ri
            jac[cols + i, rows + m + j] += ir
            jac[cols + m + i, rows + m + j] += ii
    cross_a[:, :] = 0.0
    cross_b[:, :] = 0.0


@njit(**JIT)
def _flush_self(sums_a, sums_b, nu, m, n, jac):
    """Add each cell's own block from its sums over points (see :func:`pair_jacobian`):
    A[k, l] = sum_delta SA[delta][k - l] e^{i l delta 2 pi / N},
    B[k, l] = sum_delta SB[delta][k + l] e^{-i l delta 2 pi / N}."""
    lc = (m - 1) // 2
    for c in range(sums_a.shape[0]):
        base = c * nu
        for j in range(m):
            k = j - lc
            for i in range(m):
                ll = i - lc
                a = 0.0 + 0.0j
                b = 0.0 + 0.0j
                for delta in range(3):
                    phase = complex(math.cos(ll * (delta - 1) * 2.0 * math.pi / n),
                                    math.sin(ll * (delta - 1) * 2.0 * math.pi / n))  # fmt: skip
                    a += sums_a[c, delta, k - ll + 2 * lc] * phase
                    b += sums_b[c, delta, k + ll + 2 * lc] * phase.conjugate()
                jac[base + j, base + i] += a.real + b.real
                jac[base + j, base + m + i] += -a.imag + b.imag
                jac[base + m + j, base + i] += a.imag + b.imag
                jac[base + m + j, base + m + i] += a.real - b.real


@njit(**JIT_COMPOSED, inline="always")
def pair_jacobian(z, shifts, contacts, count, law, coefficients, mobility, twiddle, step, jac):
    """Add the pair forces' Jacobian (s^-1) to ``jac`` (float64[G nu, G nu]), for the
    contacts found at this state (see :func:`pair_forces` for the arguments).

    A real 2 x 2 block H between points P and Q acts on dz_Q as alpha dz + beta conj(dz);
    it adds f alpha e^{-i k xi_P} e^{i l xi_Q} to A[k, l] and f beta e^{-i k xi_P}
    e^{-i l xi_Q} to B[k, l], f = -mobility / N. Between a point and its own cell (P and Q
    the same point or neighbours, Q = P + delta) these depend on k - l and k + l alone and
    are summed over points first (4 Lc + 1 numbers, not m^2); between cells, each contact
    adds one product of two m-vectors, and the block (d, c) is the transpose of (c, d)."""
    g, n = z.shape
    nu = jac.shape[0] // g
    m = (nu - 3) // 2
    lc = (m - 1) // 2
    q = np.empty(6)
    hessian = np.empty((6, 6))
    f = -mobility / n
    sums_a = np.zeros((g, 3, 4 * lc + 1), np.complex128)
    sums_b = np.zeros((g, 3, 4 * lc + 1), np.complex128)
    cross_a = np.zeros((m, m), np.complex128)
    cross_b = np.zeros((m, m), np.complex128)
    u = np.empty(m, np.complex128)
    v = np.empty(m, np.complex128)
    w = np.empty(m, np.complex128)
    current = -1
    for t in range(count):
        row = contacts[t]
        pair = row[0] * g + row[2]
        if pair != current:
            if current >= 0:
                _flush_cross(cross_a, cross_b, current // g, current % g, nu, m, jac)
            current = pair
        q[0], q[1], q[2], q[3], q[4], q[5] = _ends(z, shifts, row)
        if not contact_hessian(q, law, coefficients, step, hessian):
            continue
        index = (row[1], row[3], (row[3] + 1) % n)
        for p in range(3):
            for r in range(3):
                if (p == 0) != (r == 0):
                    continue  # between cells: below
                hxx, hxy = hessian[2 * p, 2 * r], hessian[2 * p, 2 * r + 1]
                hyx, hyy = hessian[2 * p + 1, 2 * r], hessian[2 * p + 1, 2 * r + 1]
                alpha = f * complex(0.5 * (hxx + hyy), 0.5 * (hyx - hxy))
                beta = f * complex(0.5 * (hxx - hyy), 0.5 * (hyx + hxy))
                cell = row[0] if p == 0 else row[2]
                delta = r - p + 1  # 0, 1, 2 for Q = P - 1, P, P + 1
                xi = index[p]
                for qq in range(-2 * lc, 2 * lc + 1):
                    e = twiddle[(qq * xi) % n]
                    sums_a[cell, delta, qq + 2 * lc] += alpha * e
                    sums_b[cell, delta, qq + 2 * lc] += beta * e
        # between cells: rows of the point a, columns of the segment's ends s and s + 1
        for j in range(m):
            u[j] = twiddle[((j - lc) * index[0]) % n]  # e^{-i k xi_a}
            v[j] = 0.0
            w[j] = 0.0
        for r in (1, 2):
            hxx, hxy = hessian[0, 2 * r], hessian[0, 2 * r + 1]
            hyx, hyy = hessian[1, 2 * r], hessian[1, 2 * r + 1]
            alpha = f * complex(0.5 * (hxx + hyy), 0.5 * (hyx - hxy))
            beta = f * complex(0.5 * (hxx - hyy), 0.5 * (hyx + hxy))
            for i in range(m):
                e = twiddle[((i - lc) * index[r]) % n]  # e^{-i l xi}
                v[i] += alpha * e.conjugate()
                w[i] += beta * e
        for j in range(m):
            uj = u[j]
            for i in range(m):
                cross_a[j, i] += uj * v[i]
                cross_b[j, i] += uj * w[i]
    if current >= 0:
        _flush_cross(cross_a, cross_b, current // g, current % g, nu, m, jac)
    _flush_self(sums_a, sums_b, nu, m, n, jac)
