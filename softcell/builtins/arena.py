"""The experiments' arena: a square plate of side L (``arena_side``, 100 cm in the paper's
experiments) centred on the start, whose walls repel the membrane and the bot as the bot
repels the membrane (SI:EQ:Eint).

Membrane: each point at distance rho = L/2 - |x| (or L/2 - |y|) from a wall has the energy
density (l0 / 2 pi) A exp(-rho / lambda), with the contact's amplitude A and length lambda.

Bot: each wall adds U = A b exp(-rho_b / lambda) (N cm), with rho_b the distance from the
bot's ellipse to the wall: for the wall x = +-L/2, rho_b = L/2 -+ x_bot - h_x(theta), with
h_x = sqrt(a^2 cos^2 theta + b^2 sin^2 theta) the ellipse's half-width along x (h_y likewise
with cos and sin exchanged). At contact the wall pushes with A b / lambda (0.057 N with the
defaults), more than the drive F0 (0.043 N): the bot stops within ~lambda of a wall.

Beyond CONTACT_CUTOFF_LENGTHS lambda from a wall nothing is felt, as for the contact.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.components.contracts import EnergyTerm
from softcell.components.hookspecs import hookimpl
from softcell.errors import ParameterError
from softcell.model.parameters import MODEL_PARAMETERS, ParameterSpec
from softcell.settings import CONTACT_CUTOFF_LENGTHS, JIT


@njit(**JIT)
def arena_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    half, amplitude, length = 0.5 * coefficients[0], coefficients[1], coefficients[2]
    cutoff = CONTACT_CUTOFF_LENGTHS * length
    scale = context[0] / (2.0 * math.pi) * amplitude / length
    edge = half - cutoff
    for n in range(x.size):
        ax, ay = abs(x[n]), abs(y[n])
        if ax < edge and ay < edge:
            continue
        if ax >= edge:
            push = scale * math.exp(-(half - ax) / length)
            p0x[n] += push if x[n] > 0.0 else -push
        if ay >= edge:
            push = scale * math.exp(-(half - ay) / length)
            p0y[n] += push if y[n] > 0.0 else -push


@njit(**JIT)
def arena_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    half, amplitude, length = 0.5 * coefficients[0], coefficients[1], coefficients[2]
    cutoff = CONTACT_CUTOFF_LENGTHS * length
    scale = context[0] / (2.0 * math.pi) * amplitude / (length * length)
    edge = half - cutoff
    for n in range(x.size):
        ax, ay = abs(x[n]), abs(y[n])
        if ax >= edge:
            hww[n, 0, 0] += scale * math.exp(-(half - ax) / length)
        if ay >= edge:
            hww[n, 1, 1] += scale * math.exp(-(half - ay) / length)


@njit(**JIT)
def _half_width(a, b, c, s):
    """The ellipse's half-width h along a direction at cos c, sin s in its frame, and
    dh/dtheta, d^2h/dtheta^2 as the ellipse turns."""
    h = math.sqrt(a * a * c * c + b * b * s * s)
    d1 = (b * b - a * a) * s * c / h
    d2 = ((b * b - a * a) * (c * c - s * s) - d1 * d1) / h
    return h, d1, d2


@njit(**JIT)
def arena_bot(pose, context, coefficients, dpose):
    half, amplitude, length = 0.5 * coefficients[0], coefficients[1], coefficients[2]
    cutoff = CONTACT_CUTOFF_LENGTHS * length
    a, b = context[1], context[2]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for axis in range(2):
        # walls normal to x see the ellipse's extent along x: (cos, sin); normal to y: (sin, -cos)
        h, d1, _ = _half_width(a, b, c, s) if axis == 0 else _half_width(a, b, s, -c)
        for sign in (-1.0, 1.0):
            rho = half - sign * pose[axis] - h
            if rho > cutoff:
                continue
            u = amplitude * b * math.exp(-rho / length) / length
            dpose[axis] += sign * u
            dpose[2] += u * d1


@njit(**JIT)
def arena_bot_hessian(pose, context, coefficients, hpp):
    half, amplitude, length = 0.5 * coefficients[0], coefficients[1], coefficients[2]
    cutoff = CONTACT_CUTOFF_LENGTHS * length
    a, b = context[1], context[2]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for axis in range(2):
        h, d1, d2 = _half_width(a, b, c, s) if axis == 0 else _half_width(a, b, s, -c)
        for sign in (-1.0, 1.0):
            rho = half - sign * pose[axis] - h
            if rho > cutoff:
                continue
            u = amplitude * b * math.exp(-rho / length) / length
            hpp[axis, axis] += u / length
            hpp[axis, 2] += u * sign * d1 / length
            hpp[2, axis] += u * sign * d1 / length
            hpp[2, 2] += u * (d1 * d1 / length + d2)


class Arena(EnergyTerm):
    """The square plate's walls, repelling the membrane and the bot."""

    name = "arena"
    description = "walls of a square plate of side arena_side centred on the start"
    parameters = (
        ParameterSpec("arena_side", 100.0, "cm", "side of the square arena", minimum=0.0),
        MODEL_PARAMETERS["contact_amplitude"],
        MODEL_PARAMETERS["contact_length"],
    )
    derivative_order = 0
    has_bot_energy = True

    @classmethod
    def check(cls, params):
        side = float(params.arena_side)
        inner = 2 * (
            max(float(params.radius), float(params.bot_semi_major))
            + CONTACT_CUTOFF_LENGTHS * float(params.contact_length)
        )
        if side <= inner:
            raise ParameterError(
                "arena_side",
                side,
                f"must be > {inner:g} cm, so that the "
                "membrane (radius) and the bot start clear of the walls",
                "cm",
            )

    def partials_kernel(self):
        return arena_partials

    def hessian_kernel(self):
        return arena_hessian

    def bot_kernel(self):
        return arena_bot

    def bot_hessian_kernel(self):
        return arena_bot_hessian

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        p = self.params
        half, length = p.arena_side / 2, p.contact_length
        cutoff = CONTACT_CUTOFF_LENGTHS * length
        e = np.zeros_like(x)
        for rho in (half - np.abs(x), half - np.abs(y)):
            e += np.where(rho > cutoff, 0.0, np.exp(-rho / length))
        return p.membrane_length / (2 * np.pi) * p.contact_amplitude * e


@hookimpl
def softcell_energy_terms() -> list[type[EnergyTerm]]:
    return [Arena]
