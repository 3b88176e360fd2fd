"""An energy term: a 2D pressure P inflating the membrane.

The enclosed area is A = (1/2) integral of (x y' - y x') d xi, so the density per unit xi is
e = -P (x y' - y x') / 2 (N cm) and E = -P A. Its partials are
P0 = de/d(x, y) = -P (y', -x') / 2 and P1 = de/d(x', y') = -P (-y, x) / 2, which give the
force density f = -P0 + D(P1) = P (y', -x'): P |gamma'| along the outward normal.
"""

import numpy as np
from numba import njit

from softcell.plugin import EnergyTerm, ParameterSpec

PRESSURE = ParameterSpec(
    "pressure",
    1e-4,
    "N cm-1",
    "2D pressure inside the membrane",
    minimum=0.0,
    minimum_inclusive=True,
)


@njit(nogil=True, cache=True)
def pressure_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    half = 0.5 * coefficients[0]
    for n in range(x.size):  # add, never overwrite: the engine sums every term's partials
        p0x[n] -= half * yp[n]
        p0y[n] += half * xp[n]
        p1x[n] += half * y[n]
        p1y[n] -= half * x[n]


@njit(nogil=True, cache=True)
def pressure_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    # w = (x, y, x', y', x'', y''): the only second derivatives are d2e/dx dy' = -P/2 and
    # d2e/dy dx' = +P/2 (and their symmetric entries).
    half = 0.5 * coefficients[0]
    for n in range(x.size):
        hww[n, 0, 3] -= half
        hww[n, 3, 0] -= half
        hww[n, 1, 2] += half
        hww[n, 2, 1] += half


class Pressure(EnergyTerm):
    """e = -P (x y' - y x') / 2 per unit xi: E = -P * area (N cm)."""

    name = "pressure"
    description = "2D pressure P inflating the membrane: E = -P * enclosed area"
    parameters = (PRESSURE,)
    reads_pose = False
    smooth = True  # no length scale of its own: rodas4 may use its coarse grid
    derivative_order = 1  # reads gamma and gamma' only

    def partials_kernel(self):
        return pressure_partials

    def hessian_kernel(self):
        return pressure_hessian

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        return -0.5 * float(self.params["pressure"]) * (np.asarray(x) * yp - np.asarray(y) * xp)
