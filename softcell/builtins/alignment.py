"""The built-in bot interaction ``alignment``, Vicsek-like: a torque J sin(theta_b - theta_a)
w(d) on bot a toward bot b's heading and its opposite on b, with w(d) = (1 - d^2 / r^2)^2 a
weight of the distance d between their centres that falls smoothly to zero at the reach r (a
hard cut-off would jump the torque as bots part, and the step control would pay for every
jump). The torques are equal and opposite and there is no force, so a pair conserves momentum
and angular momentum. Like Vicsek's rule it is not the gradient of an energy where w varies:
that gradient would add forces, which it leaves out.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.components.contracts import BotInteraction
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import ParameterSpec
from softcell.settings import LEAN_JIT


@njit(**LEAN_JIT)
def alignment_kernel(pose_a, pose_b, context, coefficients, out):
    """coefficients = [J (N cm), r (cm)]."""
    strength, reach = coefficients[0], coefficients[1]
    dx, dy = pose_b[0] - pose_a[0], pose_b[1] - pose_a[1]
    d2 = dx * dx + dy * dy
    if d2 >= reach * reach:
        return
    weight = (1.0 - d2 / (reach * reach)) ** 2
    torque = strength * weight * math.sin(pose_b[2] - pose_a[2])
    out[2] += torque
    out[5] -= torque


class Alignment(BotInteraction):
    name = "alignment"
    description = "a torque toward the other bot's heading, J sin(dtheta) (1 - d^2/r^2)^2"
    parameters = (
        ParameterSpec(
            "alignment_strength",
            500.0,
            "N cm",
            "aligning torque J (the tumble's is 151 N cm)",
            minimum=0.0,
        ),
        ParameterSpec(
            "alignment_reach",
            10.0,
            "cm",
            "distance between centres within which bots align",
            minimum=0.0,
        ),
    )

    def coefficients(self) -> np.ndarray:
        p = self.params
        return np.array([float(p.alignment_strength), float(p.alignment_reach)])

    def pair_kernel(self):
        return alignment_kernel

    def reach(self) -> float:
        return float(self.params.alignment_reach)


@hookimpl
def softcell_bot_interactions() -> list[type[BotInteraction]]:
    return [Alignment]
