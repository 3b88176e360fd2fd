"""Signed distance from a point to an ellipse, with its gradient (docs/model.md §4).

In the ellipse's own frame (semi-axes a >= b along x and y), the closest point of the ellipse
to (u, v), u, v >= 0, is q = (a^2 u / (t + a^2), b^2 v / (t + b^2)) where t is the root in
(-b^2, inf) of F(t) = (a u / (t + a^2))^2 + (b v / (t + b^2))^2 - 1 (Eberly, "Distance from a
point to an ellipse"). F is decreasing and convex there, and bracketed by
[max(b v - b^2, a u - a^2), a |p| - b^2]; Newton's method safeguarded by bisection inside that
bracket converges in a few steps. The distance is taken along the outward normal at q, which
keeps it exact to rounding for points on or near the ellipse and on or near either axis.
"""

from __future__ import annotations

import math

from numba import njit

from softcell.settings import ELLIPSE_ITERATIONS, LEAN_JIT


@njit(**LEAN_JIT)
def _bracket(u, v, a, b):
    """The first iterate s = t + b^2 of :func:`_root` and its bracket (lo, hi)."""
    b2, d = b * b, a * a - b * b
    # A bracket: F >= 0 at lo (one term of F is 1, the other >= 0); F <= 0 at hi.
    lo = max(b * v, a * u - d)
    hi = max(a * math.sqrt(u * u + v * v), lo)
    s = lo
    if a * u < d:
        # Near the inner major axis: start from the off-axis solution of v = 0.
        qx = (a * a) * u / d
        qy = b * math.sqrt(max(1.0 - (qx / a) ** 2, 1e-300))
        s = min(max(b2 * v / qy, lo), hi)
    elif lo < b2 < hi:
        # Start from t = 0, the root of a point on the ellipse: the points that matter
        # (within the contact's reach) are near it.
        s = b2
    return s, lo, hi


@njit(**LEAN_JIT)
def _newton(u, v, a, b, s, lo, hi):
    """One safeguarded Newton step of :func:`_root` from s in the bracket (lo, hi):
    ``(s, lo, hi, done)``, with ``done`` when s is the root."""
    d = a * a - b * b
    rx = 1.0 / (s + d)
    ry = 1.0 / s
    ex = a * u * rx
    ey = b * v * ry
    f = ex * ex + ey * ey - 1.0
    if f > 0.0:
        lo = s
    elif f < 0.0:
        hi = s
    else:
        return s, lo, hi, True
    df = -2.0 * (ex * ex * rx + ey * ey * ry)
    s_new = s - f / df
    if not lo < s_new < hi:  # Newton left the bracket: bisect
        s_new = 0.5 * (lo + hi)
    if abs(s_new - s) <= 1e-16 * s or hi - lo <= 1e-16 * hi:
        return s_new, lo, hi, True
    return s_new, lo, hi, False


@njit(**LEAN_JIT)
def _root(u, v, a, b):
    """Root s = t + b^2 > 0 of F for u, v >= 0, off the degenerate inner major-axis segment.

    Solving for s rather than t keeps full relative precision where the root crowds -b^2
    (points near the inner major axis).
    """
    s, lo, hi = _bracket(u, v, a, b)
    for _ in range(ELLIPSE_ITERATIONS):
        s, lo, hi, done = _newton(u, v, a, b, s, lo, hi)
        if done:
            break
    return s


@njit(**LEAN_JIT)
def _four_roots(u, v, a, b, k, out):
    """:func:`_root` of the points k[0..3] of (u, v) into out[k[0..3]], the four
    iterations interleaved (each point's iterates are its own: the same numbers, in a
    quarter of the time the processor waits on its divisions)."""
    s0, lo0, hi0 = _bracket(u[k[0]], v[k[0]], a, b)
    s1, lo1, hi1 = _bracket(u[k[1]], v[k[1]], a, b)
    s2, lo2, hi2 = _bracket(u[k[2]], v[k[2]], a, b)
    s3, lo3, hi3 = _bracket(u[k[3]], v[k[3]], a, b)
    d0 = d1 = d2 = d3 = False
    for _ in range(ELLIPSE_ITERATIONS):
        if not d0:
            s0, lo0, hi0, d0 = _newton(u[k[0]], v[k[0]], a, b, s0, lo0, hi0)
        if not d1:
            s1, lo1, hi1, d1 = _newton(u[k[1]], v[k[1]], a, b, s1, lo1, hi1)
        if not d2:
            s2, lo2, hi2, d2 = _newton(u[k[2]], v[k[2]], a, b, s2, lo2, hi2)
        if not d3:
            s3, lo3, hi3, d3 = _newton(u[k[3]], v[k[3]], a, b, s3, lo3, hi3)
        if d0 and d1 and d2 and d3:
            break
    out[k[0]] = s0
    out[k[1]] = s1
    out[k[2]] = s2
    out[k[3]] = s3


@njit(**LEAN_JIT)
def _axes(px, py, a, b):
    """|px|, |py| with coordinates 1e-100 of the axes put on them, and the closest point
    (qx, qy) where it needs no root (``known``)."""
    u, v = abs(px), abs(py)
    # Coordinates 1e-100 of the axes are on the axis to rounding; zeroing them keeps
    # subnormal numbers (with few significant bits) out of the root finding.
    if u < 1e-100 * a:
        u = 0.0
    if v < 1e-100 * b:
        v = 0.0
    a2, b2 = a * a, b * b
    if v == 0.0 and u * a < a2 - b2:
        # On the major axis inside the evolute: two closest points, off the axis.
        qx = a2 * u / (a2 - b2)
        return u, v, True, qx, b * math.sqrt(max(0.0, 1.0 - (qx / a) ** 2))
    if u == 0.0 and v == 0.0:
        return u, v, True, 0.0, b
    return u, v, False, 0.0, 0.0


@njit(**LEAN_JIT)
def _normal(px, py, u, v, qx, qy, a, b):
    """``(rho, nx, ny)`` of the point from its closest point (qx, qy) in the first quadrant."""
    nx, ny = qx / (a * a), qy / (b * b)
    norm = math.sqrt(nx * nx + ny * ny)
    nx /= norm
    ny /= norm
    rho = (u - qx) * nx + (v - qy) * ny
    return rho, math.copysign(nx, px), math.copysign(ny, py)


@njit(**LEAN_JIT)
def signed_distance_local(px, py, a, b):
    """Signed distance (negative inside) from (px, py) to the ellipse x^2/a^2 + y^2/b^2 = 1,
    in the ellipse's frame, with the outward unit normal at the closest point.

    Returns ``(rho, nx, ny)``: rho in the units of a and b; (nx, ny) = grad rho.
    """
    u, v, known, qx, qy = _axes(px, py, a, b)
    if not known:
        s = _root(u, v, a, b)
        a2, b2 = a * a, b * b
        qx = a2 * u / (s + (a2 - b2))
        qy = b2 * v / s
    return _normal(px, py, u, v, qx, qy, a, b)


@njit(**LEAN_JIT)
def signed_distances_local(px, py, count, a, b, work, lanes, rho, nx, ny):
    """:func:`signed_distance_local` of the points 0..count-1 of (px, py) into ``rho, nx,
    ny``: the same numbers, with the roots of four points found at a time. ``work``:
    float64[6, >= count] and ``lanes``: int64[4], scratch."""
    u, v, qx, qy, s, known = work[0], work[1], work[2], work[3], work[4], work[5]
    a2, b2 = a * a, b * b
    waiting = 0
    for i in range(count):
        u[i], v[i], on_axis, qx[i], qy[i] = _axes(px[i], py[i], a, b)
        known[i] = 1.0 if on_axis else 0.0
        if not on_axis:
            lanes[waiting] = i
            waiting += 1
            if waiting == 4:
                _four_roots(u, v, a, b, lanes, s)
                waiting = 0
    for j in range(waiting):
        s[lanes[j]] = _root(u[lanes[j]], v[lanes[j]], a, b)
    for i in range(count):
        if known[i] == 0.0:
            qx[i] = a2 * u[i] / (s[i] + (a2 - b2))
            qy[i] = b2 * v[i] / s[i]
        rho[i], nx[i], ny[i] = _normal(px[i], py[i], u[i], v[i], qx[i], qy[i], a, b)


@njit(**LEAN_JIT)
def signed_distance(x, y, cx, cy, theta, a, b):
    """Signed distance from the point (x, y) to the ellipse centred at (cx, cy) with its
    semi-major axis a at angle theta (rad), semi-minor axis b.

    Returns ``(rho, gx, gy)``: rho (negative inside) and its gradient with respect to (x, y),
    the outward unit normal at the closest point, in the world frame.
    """
    c, s = math.cos(theta), math.sin(theta)
    dx, dy = x - cx, y - cy
    px = c * dx + s * dy
    py = -s * dx + c * dy
    rho, nx, ny = signed_distance_local(px, py, a, b)
    return rho, c * nx - s * ny, s * nx + c * ny


#: Points of the coarse search of :func:`deepest_point` along an ellipse's boundary.
GAP_SAMPLES = 32


@njit(**LEAN_JIT)
def _boundary_rho(phi, pa, ca, sa, pb, cb, sb, a, b):
    """The signed distance (cm) from the point of ellipse A (pose ``pa``, cos and sin of its
    heading ``ca``, ``sa``) at parameter ``phi`` to ellipse B, with B's outward normal there
    in the world frame, the point's offset e from A's centre and B's curvature term kk:
    ``(rho, gx, gy, ex, ey, kk)``."""
    lx, ly = a * math.cos(phi), b * math.sin(phi)
    ex, ey = ca * lx - sa * ly, sa * lx + ca * ly
    dx, dy = pa[0] + ex - pb[0], pa[1] + ey - pb[1]
    px, py = cb * dx + sb * dy, -sb * dx + cb * dy
    rho, nx, ny = signed_distance_local(px, py, a, b)
    qx, qy = px - rho * nx, py - rho * ny
    kappa = 1.0 / (a * a * b * b * ((qx / (a * a)) ** 2 + (qy / (b * b)) ** 2) ** 1.5)
    kk = kappa / (1.0 + kappa * rho) if 1.0 + kappa * rho > 0.0 else 0.0
    return rho, cb * nx - sb * ny, sb * nx + cb * ny, ex, ey, kk


@njit(**LEAN_JIT)
def coarse_deepest(pa, pb, a, b):
    """The parameter phi (rad) of the point of ellipse A's boundary nearest to, or deepest
    inside, ellipse B among GAP_SAMPLES evenly spaced ones (see :func:`deepest_point`),
    visiting only those whose outward normal faces B's centre (all of them if none does)."""
    ca, sa = math.cos(pa[2]), math.sin(pa[2])
    cb, sb = math.cos(pb[2]), math.sin(pb[2])
    # B's centre in A's frame: a point faces it when its normal (x / a^2, y / b^2) does
    dx, dy = pb[0] - pa[0], pb[1] - pa[1]
    fx, fy = ca * dx + sa * dy, -sa * dx + ca * dy
    spacing = 2.0 * math.pi / GAP_SAMPLES
    best, phi = math.inf, 0.0
    for sweep in range(2):
        for i in range(GAP_SAMPLES):
            angle = i * spacing
            if sweep == 0 and math.cos(angle) * fx / a + math.sin(angle) * fy / b < 0.0:
                continue
            rho = _boundary_rho(angle, pa, ca, sa, pb, cb, sb, a, b)[0]
            if rho < best:
                best, phi = rho, angle
        if best < math.inf:
            break
    return phi


@njit(**LEAN_JIT)
def refine_deepest(phi, pa, pb, a, b):
    """:func:`deepest_point` from the parameter ``phi`` (rad) of a point near it: Newton's
    method on d rho / d phi = 0 within a bracket of one sample spacing on either side.
    Returns ``(rho, gx, gy, ex, ey, phi)``."""
    ca, sa = math.cos(pa[2]), math.sin(pa[2])
    cb, sb = math.cos(pb[2]), math.sin(pb[2])
    spacing = 2.0 * math.pi / GAP_SAMPLES
    lo, hi = phi - spacing, phi + spacing
    for _ in range(ELLIPSE_ITERATIONS):
        rho, gx, gy, ex, ey, kk = _boundary_rho(phi, pa, ca, sa, pb, cb, sb, a, b)
        tx, ty = -a * math.sin(phi), b * math.cos(phi)  # d p / d phi, A's frame
        wx, wy = ca * tx - sa * ty, sa * tx + ca * ty
        first = gx * wx + gy * wy
        # d2 rho / d phi2 = kk (t . p')^2 + g . p'' with p'' = -e
        second = kk * (gx * wy - gy * wx) ** 2 - (gx * ex + gy * ey)
        if first > 0.0:
            hi = phi
        else:
            lo = phi
        step = -first / second if second > 0.0 else -0.5 * spacing * math.copysign(1.0, first)
        new = phi + step
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
        if abs(new - phi) <= 1e-14 * (1.0 + abs(phi)):
            phi = new
            break
        phi = new
    rho, gx, gy, ex, ey, kk = _boundary_rho(phi, pa, ca, sa, pb, cb, sb, a, b)
    return rho, gx, gy, ex, ey, phi


@njit(**LEAN_JIT)
def deepest_point(pa, pb, a, b):
    """The point of ellipse A's boundary (pose ``pa``: x, y in cm, heading in rad) nearest
    to, or deepest inside, ellipse B (pose ``pb``; both of semi-axes a, b in cm): the minimum
    over phi of the signed distance rho_B(p_A(phi)), by a search over GAP_SAMPLES points
    (:func:`coarse_deepest`) and Newton's method on d rho / d phi = 0
    (:func:`refine_deepest`; its second derivative is exact: the distance's Hessian is
    kk t t^T, t the tangent at the closest point).

    Returns ``(rho, gx, gy, ex, ey)``: the distance (cm, negative inside B), B's outward
    normal at the closest point (world frame) and the point's offset from A's centre (cm).
    At the minimum d rho / d phi = 0, so rho's derivatives with respect to the poses are
    those at fixed phi (the envelope theorem): g for A's centre, -g for B's.
    """
    rho, gx, gy, ex, ey, _ = refine_deepest(coarse_deepest(pa, pb, a, b), pa, pb, a, b)
    return rho, gx, gy, ex, ey


@njit(**LEAN_JIT)
def ellipse_gap(pa, pb, a, b):
    """The gap (cm) between two ellipses of semi-axes a, b at poses ``pa``, ``pb``: the mean
    of :func:`deepest_point` both ways, negative when they overlap (each way is the deepest
    penetration of one boundary into the other). It depends on the relative placement only,
    so forces derived from it are equal and opposite and conserve angular momentum."""
    return 0.5 * (deepest_point(pa, pb, a, b)[0] + deepest_point(pb, pa, a, b)[0])
