"""Kernels bound into a generated module for a part the model does not have (no nonlinear
friction law, no energy of the bot alone). They are never called: the template guards each
call with a bound bool (``LAW``, ``HAS_BOT_S``, ...) that numba prunes, but every name the
template declares is bound to a function of the right arguments, not to a placeholder.
"""

from __future__ import annotations

from numba import njit

from softcell.settings import JIT


@njit(**JIT)
def no_friction_velocity(modes, fhat, vhat, lw):
    """Stands for a nonlinear friction law's velocity (the law is linear): does nothing."""


@njit(**JIT)
def no_friction_jacobian(jac, lw):
    """Stands for a nonlinear friction law's Jacobian rows (the law is linear): does
    nothing."""


@njit(**JIT)
def no_bot_forces(pose, context, coefficients, dpose):
    """Stands for the energies of the bot alone (there are none): adds nothing to ``dpose``."""


@njit(**JIT)
def no_bot_hessians(pose, context, coefficients, steps, pose_tmp, plus, minus, hpp):
    """Stands for the second derivatives of the bot's own energies (there are none): adds
    nothing to ``hpp``."""


@njit(**JIT)
def no_event(phase, datum, sense, coefficients):
    """Stands for a protocol's event kernel (it has none): never ends a phase."""
    return -1.0


@njit(**JIT)
def no_interaction(pose_a, pose_b, context, coefficients, out):
    """Stands for the bots' interactions (there are none): adds nothing to ``out``."""


@njit(**JIT)
def no_interaction_jacobian(pose_a, pose_b, context, coefficients, steps, scratch, jac):
    """Stands for the bots' interactions' Jacobian (there are none): adds nothing."""
