"""The membrane's friction laws: ``viscous`` (the paper's, the default) and ``coulomb`` (a
static threshold, which the paper names as the ingredient its model lacks).

Both map the force density f on a membrane element (N cm^-1, per unit length) to its velocity:

- ``viscous``: v = f / gamma_mem.
- ``coulomb``: the element stays put while |f| <= f_s and otherwise slides along f at
  (|f| - f_s) / gamma_mem. Implicit integrators need a law with a derivative, so the sharp
  law is regularised with a width eps (N cm^-1):

      v = g(|f|) f / |f|,   g(r) = (eps / gamma_mem) [sp((r - f_s) / eps) - sp((-r - f_s) / eps)],

  with sp(x) = log(1 + e^x). g is odd and smooth, g(r) -> max(r - f_s, 0) / gamma_mem as
  eps -> 0 (the error is at most eps log 2 / gamma_mem, at r = f_s), and with f_s = 0 it is
  r / gamma_mem exactly (sp(x) - sp(-x) = x): the viscous law, to rounding.
"""

from __future__ import annotations

import math

from numba import njit

from softcell.components.contracts import FrictionLaw
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import MODEL_PARAMETERS, ParameterSpec
from softcell.settings import JIT

#: Below this |f| / eps the regularised law is evaluated by its Taylor expansion at f = 0
#: (relative error ~ (|f| / eps)^2 there), not by a difference of two nearly equal softplus.
_TAYLOR = 1e-5


@njit(**JIT)
def viscous_velocity(x, y, tx, ty, fx, fy, coefficients, vx, vy):
    inv = 1.0 / coefficients[0]
    for n in range(fx.size):
        vx[n] = fx[n] * inv
        vy[n] = fy[n] * inv


@njit(**JIT)
def viscous_derivative(x, y, tx, ty, fx, fy, coefficients, dxx, dxy, dyx, dyy):
    inv = 1.0 / coefficients[0]
    for n in range(fx.size):
        dxx[n] = inv
        dxy[n] = 0.0
        dyx[n] = 0.0
        dyy[n] = inv


@njit(**JIT)
def _softplus(x):
    return max(x, 0.0) + math.log1p(math.exp(-abs(x)))


@njit(**JIT)
def _logistic(x):
    if x >= 0.0:
        return 1.0 / (1.0 + math.exp(-x))
    e = math.exp(x)
    return e / (1.0 + e)


@njit(**JIT)
def _ratio_and_slope(r, gamma, threshold, width):
    """g(r) / r and g'(r) of the regularised law (1 / (N s cm^-2))."""
    u, c = r / width, threshold / width
    slope = (_logistic(u - c) + _logistic(-u - c)) / gamma
    if u < _TAYLOR:
        return 2.0 * _logistic(-c) / gamma, slope
    return (_softplus(u - c) - _softplus(-u - c)) / (u * gamma), slope


@njit(**JIT)
def coulomb_velocity(x, y, tx, ty, fx, fy, coefficients, vx, vy):
    gamma, threshold, width = coefficients[0], coefficients[1], coefficients[2]
    for n in range(fx.size):
        ratio, _ = _ratio_and_slope(math.hypot(fx[n], fy[n]), gamma, threshold, width)
        vx[n] = ratio * fx[n]
        vy[n] = ratio * fy[n]


@njit(**JIT)
def coulomb_derivative(x, y, tx, ty, fx, fy, coefficients, dxx, dxy, dyx, dyy):
    # d v_a / d f_b = (g / r) delta_ab + (g' - g / r) f_a f_b / r^2
    gamma, threshold, width = coefficients[0], coefficients[1], coefficients[2]
    for n in range(fx.size):
        r = math.hypot(fx[n], fy[n])
        ratio, slope = _ratio_and_slope(r, gamma, threshold, width)
        extra = 0.0 if r / width < _TAYLOR else (slope - ratio) / (r * r)
        dxx[n] = ratio + extra * fx[n] * fx[n]
        dxy[n] = extra * fx[n] * fy[n]
        dyx[n] = dxy[n]
        dyy[n] = ratio + extra * fy[n] * fy[n]


def coulomb_speed(force: float, gamma: float, threshold: float, width: float) -> float:
    """g(|f|) (cm s^-1): the speed of an element under the force density ``force`` (N cm^-1)
    with the regularised law; ``width`` = 0 gives the sharp law max(|f| - f_s, 0) / gamma."""
    r = abs(force)
    if width == 0.0:
        return max(r - threshold, 0.0) / gamma
    return float(_ratio_and_slope(r, gamma, threshold, width)[0]) * r


class Viscous(FrictionLaw):
    """v = f / gamma_mem: the paper's law."""

    name = "viscous"
    description = "viscous friction v = f / gamma_mem (the paper's)"
    parameters = (MODEL_PARAMETERS["membrane_friction"],)
    linear = True

    def velocity_kernel(self):
        return viscous_velocity

    def derivative_kernel(self):
        return viscous_derivative


class Coulomb(FrictionLaw):
    """Static friction: no motion while |f| <= f_s, then (|f| - f_s) / gamma_mem along f."""

    name = "coulomb"
    description = (
        "static threshold f_s, then viscous sliding at (|f| - f_s) / gamma_mem; "
        "regularised over a width eps"
    )
    parameters = (
        MODEL_PARAMETERS["membrane_friction"],
        ParameterSpec(
            "membrane_static_friction",
            1e-4,
            "N cm-1",
            "static friction f_s of the membrane, per unit length",
            minimum=0.0,
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "static_friction_width",
            1e-5,
            "N cm-1",
            "regularisation width eps of the static friction law",
            minimum=0.0,
        ),
    )

    def velocity_kernel(self):
        return coulomb_velocity

    def derivative_kernel(self):
        return coulomb_derivative


@hookimpl
def softcell_friction_laws() -> list[type[FrictionLaw]]:
    return [Viscous, Coulomb]
