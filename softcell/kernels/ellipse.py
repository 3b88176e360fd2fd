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

from softcell.config import ELLIPSE_ITERATIONS, JIT


@njit(**JIT)
def _root(u, v, a, b):
    """Root s = t + b^2 > 0 of F for u, v >= 0, off the degenerate inner major-axis segment.

    Solving for s rather than t keeps full relative precision where the root crowds -b^2
    (points near the inner major axis).
    """
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
    for _ in range(ELLIPSE_ITERATIONS):
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
            return s
        df = -2.0 * (ex * ex * rx + ey * ey * ry)
        s_new = s - f / df
        if not lo < s_new < hi:  # Newton left the bracket: bisect
            s_new = 0.5 * (lo + hi)
        if abs(s_new - s) <= 1e-16 * s or hi - lo <= 1e-16 * hi:
            return s_new
        s = s_new
    return s


@njit(**JIT)
def signed_distance_local(px, py, a, b):
    """Signed distance (negative inside) from (px, py) to the ellipse x^2/a^2 + y^2/b^2 = 1,
    in the ellipse's frame, with the outward unit normal at the closest point.

    Returns ``(rho, nx, ny)``: rho in the units of a and b; (nx, ny) = grad rho.
    """
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
        qy = b * math.sqrt(max(0.0, 1.0 - (qx / a) ** 2))
    elif u == 0.0 and v == 0.0:
        qx, qy = 0.0, b
    else:
        s = _root(u, v, a, b)
        qx = a2 * u / (s + (a2 - b2))
        qy = b2 * v / s
    nx, ny = qx / a2, qy / b2
    norm = math.sqrt(nx * nx + ny * ny)
    nx /= norm
    ny /= norm
    rho = (u - qx) * nx + (v - qy) * ny
    return rho, math.copysign(nx, px), math.copysign(ny, py)


@njit(**JIT)
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
