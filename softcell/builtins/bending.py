"""Bending energy e_b = k kappa^2 |gamma'| (SI:EQ:Eel), kappa = (x' y'' - y' x'') / |gamma'|^3.

With s = |gamma'| and c = x' y'' - y' x'', e_b = k c^2 / s^5, so
de/dx' = k (2 c y'' / s^5 - 5 c^2 x' / s^7),  de/dy' = k (-2 c x'' / s^5 - 5 c^2 y' / s^7),
de/dx'' = -2 k c y' / s^5,                   de/dy'' = 2 k c x' / s^5;
the second derivatives follow from e = k c^2 q, q = s^-5 (see ``bending_hessian``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softcell.components.contracts import EnergyTerm
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import MODEL_PARAMETERS
from softcell.settings import JIT


@njit(**JIT)
def bending_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    k = coefficients[0]
    for n in range(xp.size):
        s2 = xp[n] * xp[n] + yp[n] * yp[n]
        s = np.sqrt(s2)
        inv5 = 1.0 / (s2 * s2 * s)
        c = xp[n] * ypp[n] - yp[n] * xpp[n]
        two_kc = 2.0 * k * c * inv5
        five_kc2 = 5.0 * k * c * c * inv5 / s2
        p1x[n] += two_kc * ypp[n] - five_kc2 * xp[n]
        p1y[n] += -two_kc * xpp[n] - five_kc2 * yp[n]
        p2x[n] -= two_kc * yp[n]
        p2y[n] += two_kc * xp[n]


@njit(**JIT)
def bending_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    # e = k c^2 q over v = (X, Y, U, V) = (x', y', x'', y''), q = s^-5, c = X V - Y U:
    # d2e/dv_i dv_j = k (2 c_i c_j q + 2 c (c_i q_j + c_j q_i) + c^2 q_ij + 2 c q c_ij),
    # c_v = (V, -U, -Y, X), q_v = -5 s^-7 (X, Y, 0, 0), c_XV = 1, c_YU = -1.
    k = coefficients[0]
    for n in range(xp.size):
        X, Y, U, V = xp[n], yp[n], xpp[n], ypp[n]
        s2 = X * X + Y * Y
        q = 1.0 / (s2 * s2 * np.sqrt(s2))
        q7 = q / s2
        q9 = q7 / s2
        c = X * V - Y * U
        c2 = c * c
        xx = k * (2.0 * V * V * q - 20.0 * c * V * X * q7 + c2 * (35.0 * X * X * q9 - 5.0 * q7))
        xy = k * (-2.0 * V * U * q + 10.0 * c * (U * X - V * Y) * q7 + 35.0 * c2 * X * Y * q9)
        yy = k * (2.0 * U * U * q + 20.0 * c * U * Y * q7 + c2 * (35.0 * Y * Y * q9 - 5.0 * q7))
        xu = k * (-2.0 * V * Y * q + 10.0 * c * X * Y * q7)
        xv = k * (2.0 * V * X * q - 10.0 * c * X * X * q7 + 2.0 * c * q)
        yu = k * (2.0 * U * Y * q + 10.0 * c * Y * Y * q7 - 2.0 * c * q)
        yv = k * (-2.0 * U * X * q - 10.0 * c * X * Y * q7)
        uu = k * 2.0 * Y * Y * q
        uv = -k * 2.0 * X * Y * q
        vv = k * 2.0 * X * X * q
        hww[n, 2, 2] += xx
        hww[n, 2, 3] += xy
        hww[n, 3, 2] += xy
        hww[n, 3, 3] += yy
        hww[n, 2, 4] += xu
        hww[n, 4, 2] += xu
        hww[n, 2, 5] += xv
        hww[n, 5, 2] += xv
        hww[n, 3, 4] += yu
        hww[n, 4, 3] += yu
        hww[n, 3, 5] += yv
        hww[n, 5, 3] += yv
        hww[n, 4, 4] += uu
        hww[n, 4, 5] += uv
        hww[n, 5, 4] += uv
        hww[n, 5, 5] += vv


class Bending(EnergyTerm):
    """Bending energy of the membrane, k kappa^2 per unit length."""

    name = "bending"
    description = "bending energy k kappa^2 |gamma'| (SI:EQ:Eel)"
    parameters = (MODEL_PARAMETERS["bending_stiffness"],)
    smooth = True

    def partials_kernel(self):
        return bending_partials

    def hessian_kernel(self):
        return bending_hessian

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        s = np.hypot(xp, yp)
        c = xp * ypp - yp * xpp
        return float(self.params["bending_stiffness"]) * c * c / s**5


@hookimpl
def softcell_energy_terms() -> list[type[EnergyTerm]]:
    return [Bending]
