"""The built-in bot interaction ``bot_repulsion``: two bots in one ring repel each other with a
soft law of their gap, e = F_c lambda_b exp(-gap / lambda_b), nothing beyond
CONTACT_CUTOFF_LENGTHS lambda_b (docs/model.md, "Several bots in one ring").

The gap is that of :func:`softcell.engine.kernels.ellipse.ellipse_gap`: the mean, both
ways, of the signed distance from the point of one ellipse's boundary deepest into (or
nearest to) the other. Each way's derivatives with respect to the two poses are those at the
fixed boundary point (the envelope theorem): along B's outward normal g at the closest point,
d rho / d r_A = g, d rho / d theta_A = e x g (e the point's offset from A's centre),
d rho / d r_B = -g and d rho / d theta_B = -(d x g) (d its offset from B's centre). The gap
depends on the bots' relative placement only, so the forces are equal and opposite and the
torques balance about any point.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.components.contracts import BotInteraction
from softcell.components.hookspecs import hookimpl
from softcell.engine.kernels.ellipse import coarse_deepest, refine_deepest
from softcell.model.parameters import ParameterSpec
from softcell.settings import CONTACT_CUTOFF_LENGTHS, LEAN_JIT


@njit(**LEAN_JIT)
def _add_forces(pose_a, pose_b, phi_a, phi_b, a, b, coefficients, out):
    """Add the forces on both bots into ``out[0:6]``, each way's deepest point found by
    Newton's method from the parameters ``phi_a`` (on A) and ``phi_b`` (on B)."""
    force, length, cutoff = coefficients[0], coefficients[1], coefficients[2]
    rho_a, gax, gay, eax, eay, _ = refine_deepest(phi_a, pose_a, pose_b, a, b)  # A vs B
    rho_b, gbx, gby, ebx, eby, _ = refine_deepest(phi_b, pose_b, pose_a, a, b)  # B vs A
    gap = 0.5 * (rho_a + rho_b)
    if gap > cutoff:
        return
    # -dE/dgap = F_c exp(-gap / lambda_b), and d gap = (d rho_a + d rho_b) / 2
    w = 0.5 * force * math.exp(-gap / length)
    # offsets of each point from the other bot's centre
    dax, day = pose_a[0] + eax - pose_b[0], pose_a[1] + eay - pose_b[1]
    dbx, dby = pose_b[0] + ebx - pose_a[0], pose_b[1] + eby - pose_a[1]
    out[0] += w * (gax - gbx)
    out[1] += w * (gay - gby)
    out[2] += w * ((eax * gay - eay * gax) - (dbx * gby - dby * gbx))
    out[3] += w * (gbx - gax)
    out[4] += w * (gby - gay)
    out[5] += w * ((ebx * gby - eby * gbx) - (dax * gay - day * gax))


@njit(**LEAN_JIT)
def _far(pose_a, pose_b, a, b, coefficients):
    """Whether the bots are surely beyond the cut-off: centres farther apart than the reach,
    or the ellipses separated along the line of their centres by more than the cut-off (each
    one's extent along a unit n is sqrt(a^2 (n.u)^2 + b^2 (n.v)^2), u, v its axes; the
    separation along any line bounds the gap of separated ellipses from below)."""
    dx, dy = pose_b[0] - pose_a[0], pose_b[1] - pose_a[1]
    d2 = dx * dx + dy * dy
    reach = coefficients[3]
    if d2 > reach * reach:
        return True
    d = math.sqrt(d2)
    if d == 0.0:
        return False
    nx, ny = dx / d, dy / d
    extent = 0.0
    for heading in (pose_a[2], pose_b[2]):
        along = nx * math.cos(heading) + ny * math.sin(heading)
        across = -nx * math.sin(heading) + ny * math.cos(heading)
        extent += math.sqrt(a * a * along * along + b * b * across * across)
    return d - extent > coefficients[2]


@njit(**LEAN_JIT)
def bot_repulsion_kernel(pose_a, pose_b, context, coefficients, out):
    """coefficients = [F_c (N), lambda_b (cm), cut-off (cm), reach (cm)]; context[1:3] = a, b."""
    a, b = context[1], context[2]
    if _far(pose_a, pose_b, a, b, coefficients):
        return
    phi_a = coarse_deepest(pose_a, pose_b, a, b)
    phi_b = coarse_deepest(pose_b, pose_a, a, b)
    _add_forces(pose_a, pose_b, phi_a, phi_b, a, b, coefficients, out)


@njit(**LEAN_JIT)
def bot_repulsion_jacobian(pose_a, pose_b, context, coefficients, steps, scratch, jac):
    """Central differences of :func:`bot_repulsion_kernel`, each perturbed evaluation's
    deepest points found by Newton's method from the unperturbed ones (the same minimum
    as the kernel's search finds, without the search)."""
    a, b = context[1], context[2]
    if _far(pose_a, pose_b, a, b, coefficients):
        return
    phi_a = refine_deepest(coarse_deepest(pose_a, pose_b, a, b), pose_a, pose_b, a, b)[5]
    phi_b = refine_deepest(coarse_deepest(pose_b, pose_a, a, b), pose_b, pose_a, a, b)[5]
    plus, minus = scratch[0:6], scratch[6:12]
    qa, qb = scratch[12:15], scratch[15:18]
    for j in range(6):
        for c in range(3):
            qa[c] = pose_a[c]
            qb[c] = pose_b[c]
        h = steps[6 + j % 3]
        moved = qa if j < 3 else qb
        moved[j % 3] += h
        plus[:] = 0.0
        _add_forces(qa, qb, phi_a, phi_b, a, b, coefficients, plus)
        moved[j % 3] -= 2.0 * h
        minus[:] = 0.0
        _add_forces(qa, qb, phi_a, phi_b, a, b, coefficients, minus)
        for c in range(6):
            jac[c, j] += (plus[c] - minus[c]) / (2.0 * h)


class BotRepulsion(BotInteraction):
    name = "bot_repulsion"
    description = (
        "bot-bot repulsion F_c lambda_b exp(-gap/lambda_b) of the ellipses' gap (both ways' "
        "deepest boundary point)"
    )
    parameters = (
        ParameterSpec(
            "bot_contact_force",
            0.4275,
            "N",
            "bot-bot repulsion force F_c at zero gap (ten drive forces)",
            minimum=0.0,
        ),
        ParameterSpec(
            "bot_contact_length",
            0.05,
            "cm",
            "bot-bot repulsion length lambda_b",
            minimum=0.0,
        ),
    )

    def coefficients(self) -> np.ndarray:
        p = self.params
        length = float(p.bot_contact_length)
        return np.array(
            [float(p.bot_contact_force), length, CONTACT_CUTOFF_LENGTHS * length, self.reach()]
        )

    def pair_kernel(self):
        return bot_repulsion_kernel

    def jacobian_kernel(self):
        return bot_repulsion_jacobian

    def reach(self) -> float:
        """Two semi-major axes and the cut-off: bots whose centres are farther apart cannot
        be within the cut-off of each other."""
        p = self.params
        return 2 * float(p.bot_semi_major) + CONTACT_CUTOFF_LENGTHS * float(p.bot_contact_length)


@hookimpl
def softcell_bot_interactions() -> list[type[BotInteraction]]:
    return [BotRepulsion]
