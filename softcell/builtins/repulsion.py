"""The built-in pair term ``repulsion``: the membranes of two cells repel each other with the
contact's law, e(rho) = (l0 / 2 pi) A exp(-rho / lambda) per unit xi for a point at signed
distance rho from the other membrane (SI:EQ:Eint with the other membrane in the bot's place),
nothing beyond CONTACT_CUTOFF_LENGTHS lambda. Its amplitude A and length lambda are the
contact's (``contact_amplitude``, ``contact_length``)."""

from __future__ import annotations

import math

from numba import njit

from softcell.components.contracts import PairTerm
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import MODEL_PARAMETERS
from softcell.settings import CONTACT_CUTOFF_LENGTHS, JIT


@njit(**JIT)
def repulsion_law(rho, coefficients, out):
    """coefficients = [(l0 / 2 pi) A (N cm), lambda (cm), cut-off (cm)]."""
    scale, length, cutoff = coefficients[0], coefficients[1], coefficients[2]
    if rho > cutoff:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = 0.0
        return
    e = scale * math.exp(-rho / length)
    out[0] = e
    out[1] = -e / length
    out[2] = e / (length * length)


class Repulsion(PairTerm):
    name = "repulsion"
    description = "membrane-membrane repulsion (l0/2pi) A exp(-rho/lambda), the contact's law"
    parameters = (MODEL_PARAMETERS["contact_amplitude"], MODEL_PARAMETERS["contact_length"])

    def coefficients(self):
        import numpy as np

        p = self.params
        return np.array(
            [
                p.membrane_length / (2 * math.pi) * float(p.contact_amplitude),
                float(p.contact_length),
                self.reach(),
            ]
        )

    def law_kernel(self):
        return repulsion_law

    def reach(self) -> float:
        return CONTACT_CUTOFF_LENGTHS * float(self.params.contact_length)


@hookimpl
def softcell_pair_terms() -> list[type[PairTerm]]:
    return [Repulsion]
