"""Stretching ("surface tension") energy e_st = alpha (l0 / 2 pi) (2 pi |gamma'| - l0)^2
(SI:EQ:Est). With s = |gamma'|: de/dgamma' = 2 alpha l0 (2 pi s - l0) gamma' / s, and
d^2 e / dgamma'^2 = 2 alpha l0 (2 pi - l0 / s) I + (2 alpha l0^2 / s^3) gamma' gamma'^T.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.components.contracts import EnergyTerm
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import MODEL_PARAMETERS
from softcell.settings import JIT


@njit(**JIT)
def tension_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    alpha = coefficients[0]
    l0 = context[0]
    two_pi = 2.0 * math.pi
    for n in range(xp.size):
        s = np.sqrt(xp[n] * xp[n] + yp[n] * yp[n])
        g = 2.0 * alpha * l0 * (two_pi * s - l0) / s
        p1x[n] += g * xp[n]
        p1y[n] += g * yp[n]


@njit(**JIT)
def tension_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    # d P1 / d gamma' = g I + (2 alpha l0^2 / s^3) gamma' gamma'^T
    alpha = coefficients[0]
    l0 = context[0]
    two_pi = 2.0 * math.pi
    for n in range(xp.size):
        s = np.sqrt(xp[n] * xp[n] + yp[n] * yp[n])
        g = 2.0 * alpha * l0 * (two_pi - l0 / s)
        c = 2.0 * alpha * l0 * l0 / (s * s * s)
        hww[n, 2, 2] += g + c * xp[n] * xp[n]
        hww[n, 2, 3] += c * xp[n] * yp[n]
        hww[n, 3, 2] += c * xp[n] * yp[n]
        hww[n, 3, 3] += g + c * yp[n] * yp[n]


class Tension(EnergyTerm):
    """Stretching energy that keeps the membrane length near l0 and its parametrization uniform."""

    name = "tension"
    description = "stretching energy alpha (l0/2pi) (2pi |gamma'| - l0)^2 (SI:EQ:Est)"
    parameters = (MODEL_PARAMETERS["tension"],)
    smooth = True
    derivative_order = 1

    def partials_kernel(self):
        return tension_partials

    def hessian_kernel(self):
        return tension_hessian

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        l0 = self.params.membrane_length
        s = np.hypot(xp, yp)
        return float(self.params["tension"]) * l0 / (2 * np.pi) * (2 * np.pi * s - l0) ** 2


@hookimpl
def softcell_energy_terms() -> list[type[EnergyTerm]]:
    return [Tension]
