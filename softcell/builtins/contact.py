"""Bot-membrane contact e_int = (l0 / 2 pi) A exp(-rho / lambda) (SI:EQ:Eint), with rho the
signed distance from the membrane point to the bot's ellipse (negative inside).

de/dgamma = -(l0 / 2 pi)(A / lambda) exp(-rho / lambda) grad rho; with d = gamma - r_bot,
de/dr_bot = -de/dgamma and
de/dtheta_bot = (l0 / 2 pi)(A / lambda) exp(-rho / lambda) (d x grad rho),
so the reaction torque is taken about the bot's center (docs/model.md §4; the paper's
gamma x f_int about the origin is a typo). Points farther than CONTACT_CUTOFF_LENGTHS lambda
from the ellipse feel nothing; two cheap tests skip them before any distance is computed.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.components.contracts import EnergyTerm
from softcell.components.hookspecs import hookimpl
from softcell.engine.kernels.ellipse import signed_distance, signed_distances_local
from softcell.model.parameters import MODEL_PARAMETERS
from softcell.settings import CONTACT_CUTOFF_LENGTHS, JIT, LEAN_JIT


@njit(**LEAN_JIT)
def _candidate(dx, dy, c, s, a, b, cutoff):
    """Whether the point d = gamma - r_bot may lie within ``cutoff`` of the ellipse, and its
    coordinates in the bot's frame: ``(maybe, px, py)``. Two cheap tests: the circle of
    radius a + cutoff, then the ellipse scaled by 1 + cutoff / b (outside it the distance is
    at least cutoff)."""
    if dx * dx + dy * dy > (a + cutoff) ** 2:
        return False, 0.0, 0.0
    px = c * dx + s * dy
    py = -s * dx + c * dy
    if (px / a) ** 2 + (py / b) ** 2 > (1.0 + cutoff / b) ** 2:
        return False, 0.0, 0.0
    return True, px, py


#: Candidate points whose distances are found together (four roots at a time).
CHUNK = 32


@njit(**JIT)
def _scratch():
    """The scratch of :func:`_gather`: float64[13, CHUNK] and int64[CHUNK + 4]."""
    return np.empty((13, CHUNK)), np.empty(CHUNK + 4, np.int64)


@njit(**LEAN_JIT)
def _gather(x, y, start, pose, c, s, a, b, cutoff, floats, ints):
    """From point ``start`` on, the next (up to CHUNK) points that pass the cheap tests of
    :func:`_candidate`, with their distances: ``ints[:count]`` their indices and
    ``floats[:7, :count]`` their px, py, dx, dy, rho, nx, ny (one column each). Returns
    (count, the point to go on from)."""
    count = 0
    n = start
    while n < x.size and count < CHUNK:
        dx, dy = x[n] - pose[0], y[n] - pose[1]
        maybe, px, py = _candidate(dx, dy, c, s, a, b, cutoff)
        if maybe:
            ints[count] = n
            floats[0, count], floats[1, count] = px, py
            floats[2, count], floats[3, count] = dx, dy
            count += 1
        n += 1
    signed_distances_local(
        floats[0], floats[1], count, a, b, floats[7:], ints[CHUNK:], floats[4], floats[5], floats[6]
    )
    return count, n


@njit(**LEAN_JIT)
def _setup(pose, context, coefficients):
    """The bot's semi-axes a, b (cm), the cut-off (cm), the force scale (l0 / 2 pi) A /
    lambda (N), lambda (cm), and cos, sin of the bot's heading."""
    amplitude, length = coefficients[0], coefficients[1]
    l0, a, b = context[0], context[1], context[2]
    cutoff = CONTACT_CUTOFF_LENGTHS * length
    scale = l0 / (2.0 * math.pi) * amplitude / length
    return a, b, cutoff, scale, length, math.cos(pose[2]), math.sin(pose[2])


@njit(**JIT)
def contact_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    a, b, cutoff, scale, length, c, s = _setup(pose, context, coefficients)
    # The points near the bot are gathered CHUNK at a time and their distances found
    # together; their forces are added in the order of the points.
    floats, ints = _scratch()
    start = 0
    while start < x.size:
        count, start = _gather(x, y, start, pose, c, s, a, b, cutoff, floats, ints)
        for k in range(count):
            rho = floats[4, k]
            if not rho <= cutoff:
                continue
            n = ints[k]
            dx, dy, nx, ny = floats[2, k], floats[3, k], floats[5, k], floats[6, k]
            gx, gy = c * nx - s * ny, s * nx + c * ny
            w = scale * math.exp(-rho / length)
            p0x[n] -= w * gx
            p0y[n] -= w * gy
            dpose[0] += w * gx
            dpose[1] += w * gy
            dpose[2] += w * (dx * gy - dy * gx)


@njit(**JIT)
def contact_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    # e = S exp(-rho / lambda) with rho(gamma, r_bot, theta). With n the outward normal and
    # t = z x n the tangent at the closest point q, kappa the ellipse's curvature there,
    # kk = kappa / (1 + kappa rho) and d = gamma - r_bot:
    #   rho_gamma = n, rho_r = -n, rho_theta = tau = n_x d_y - n_y d_x,
    #   rho_gamma_gamma = kk t t^T = rho_rr = -rho_gamma_r,
    #   rho_gamma_theta = t (1 - kk n.d) = -rho_r_theta, rho_theta_theta = kk (n.d)^2 - n.d,
    # and d2e = (S / lambda) exp(-rho / lambda) (rho_i rho_j / lambda - rho_ij).
    a, b, cutoff, scale, length, c, s = _setup(pose, context, coefficients)
    a2b2 = a * a * b * b
    floats, ints = _scratch()
    start = 0
    while start < x.size:
        count, start = _gather(x, y, start, pose, c, s, a, b, cutoff, floats, ints)
        for k in range(count):
            if floats[4, k] <= cutoff:
                _add_hessian(ints[k], floats[:, k], c, s, a, b, a2b2, scale, length, hww, hwp, hpp)


@njit(**LEAN_JIT)
def _add_hessian(n, point, c, s, a, b, a2b2, scale, length, hww, hwp, hpp):
    """Add the second derivatives at point n (``point``: its column of :func:`_gather`)."""
    px, py, dx, dy = point[0], point[1], point[2], point[3]
    rho, nx, ny = point[4], point[5], point[6]
    qx, qy = px - rho * nx, py - rho * ny
    kappa = 1.0 / (a2b2 * ((qx / (a * a)) ** 2 + (qy / (b * b)) ** 2) ** 1.5)
    kk = kappa / (1.0 + kappa * rho)
    gx, gy = c * nx - s * ny, s * nx + c * ny
    tx, ty = -gy, gx
    nd = gx * dx + gy * dy
    tau = gx * dy - gy * dx
    rgt = 1.0 - kk * nd
    w = scale * math.exp(-rho / length)
    il = 1.0 / length
    g = (gx, gy)
    t = (tx, ty)
    for i in range(2):
        for j in range(2):
            h = w * (g[i] * g[j] * il - kk * t[i] * t[j])
            hww[n, i, j] += h
            hwp[n, i, j] -= h
            hpp[i, j] += h
        m = w * (g[i] * tau * il - t[i] * rgt)
        hwp[n, i, 2] += m
        hpp[i, 2] -= m
        hpp[2, i] -= m
    hpp[2, 2] += w * (tau * tau * il - (kk * nd * nd - nd))


class Contact(EnergyTerm):
    """Soft repulsion between the membrane and the elliptical bot."""

    name = "contact"
    description = "bot-membrane repulsion (l0/2pi) A exp(-rho/lambda) (SI:EQ:Eint)"
    parameters = (MODEL_PARAMETERS["contact_amplitude"], MODEL_PARAMETERS["contact_length"])
    derivative_order = 0
    reads_pose = True

    def partials_kernel(self):
        return contact_partials

    def hessian_kernel(self):
        return contact_hessian

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        p = self.params
        cutoff = CONTACT_CUTOFF_LENGTHS * p.contact_length
        rho = np.array(
            [
                signed_distance(
                    xn, yn, pose[0], pose[1], pose[2], p.bot_semi_major, p.bot_semi_minor
                )[0]
                for xn, yn in zip(x, y, strict=True)
            ]
        )
        e = p.membrane_length / (2 * np.pi) * p.contact_amplitude * np.exp(-rho / p.contact_length)
        return np.where(rho > cutoff, 0.0, e)


@hookimpl
def softcell_energy_terms() -> list[type[EnergyTerm]]:
    return [Contact]
