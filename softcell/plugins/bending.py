"""Bending energy e_b = k kappa^2 |gamma'| (SI:EQ:Eel), kappa = (x' y'' - y' x'') / |gamma'|^3.

With s = |gamma'| and c = x' y'' - y' x'', e_b = k c^2 / s^5, so
de/dx' = k (2 c y'' / s^5 - 5 c^2 x' / s^7),  de/dy' = k (-2 c x'' / s^5 - 5 c^2 y' / s^7),
de/dx'' = -2 k c y' / s^5,                   de/dy'' = 2 k c x' / s^5.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softcell.core.components import EnergyTerm
from softcell.core.config import JIT
from softcell.core.hookspecs import hookimpl
from softcell.core.params import MODEL_PARAMETERS


@njit(**JIT)
def bending_partials(x, y, xp, yp, xpp, ypp, pose, context, coefficients,
                     p0x, p0y, p1x, p1y, p2x, p2y, dpose):
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


class Bending(EnergyTerm):
    """Bending energy of the membrane, k kappa^2 per unit length."""

    name = "bending"
    description = "bending energy k kappa^2 |gamma'| (SI:EQ:Eel)"
    parameters = (MODEL_PARAMETERS["bending_stiffness"],)

    def partials_kernel(self):
        return bending_partials

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        s = np.hypot(xp, yp)
        c = xp * ypp - yp * xpp
        return float(self.params["bending_stiffness"]) * c * c / s**5


@hookimpl
def softcell_energy_terms() -> list[type]:
    return [Bending]
