"""The model's friction law, compiled for the integrators: the velocity modes of the force
modes and the matching rows of the Jacobian (:mod:`softcell.engine.kernels.friction_modes`)."""

from __future__ import annotations

from collections import namedtuple
from types import ModuleType

import numpy as np

from softcell.engine.compiled import compile_module
from softcell.engine.compose import template

LawWorkspace = namedtuple(
    "LawWorkspace",
    [
        "scale",
        "spec",
        "field",
        "x",
        "y",
        "tx",
        "ty",
        "fx",
        "fy",
        "vx",
        "vy",
        "vx_plus",
        "vy_plus",
        "fx_step",
        "fy_step",
        "dxx",
        "dxy",
        "dyx",
        "dyy",
        "buf",
        "a_hat",
        "b_hat",
        "law",
        "rows",
        "fhat",
        "vhat",
        "coefficients",
    ],
)


def workspace(
    nodes: int, cutoff: int, unknowns: int, scale: float, coefficients: np.ndarray
) -> LawWorkspace:
    """Scratch arrays of the law on ``nodes`` points for 2 ``cutoff`` + 1 modes and a
    Jacobian of ``unknowns`` columns; ``scale`` = 2 pi / l0 (cm^-1); ``coefficients`` the
    law's."""
    m = 2 * cutoff + 1
    c = np.complex128
    return LawWorkspace(
        scale=np.array([scale]),
        spec=np.zeros(nodes, c),
        field=np.zeros(nodes, c),
        **{
            k: np.zeros(nodes)
            for k in (
                "x",
                "y",
                "tx",
                "ty",
                "fx",
                "fy",
                "vx",
                "vy",
                "vx_plus",
                "vy_plus",
                "fx_step",
                "fy_step",
                "dxx",
                "dxy",
                "dyx",
                "dyy",
            )
        },
        buf=np.zeros(nodes, c),
        a_hat=np.zeros(4 * cutoff + 1, c),
        b_hat=np.zeros(4 * cutoff + 1, c),
        law=np.zeros((2 * m, 2 * m)),
        rows=np.zeros((2 * m, unknowns)),
        fhat=np.zeros(m, c),
        vhat=np.zeros(m, c),
        coefficients=np.ascontiguousarray(coefficients, dtype=np.float64),
    )


def compiled_friction(law) -> ModuleType:
    """The module of ``templates/friction_law.py`` for the friction law ``law`` (a
    :class:`~softcell.components.contracts.FrictionLaw`): ``velocity(modes, fhat,
    vhat, lw)`` and ``jacobian(jac, lw)``, with ``lw`` from :func:`workspace`."""
    derivative = law.derivative_kernel()
    velocity = law.velocity_kernel()
    return compile_module(
        "friction",
        template(__package__ + ".templates", "friction_law.py"),
        {
            "law_velocity": velocity,
            "law_derivative": derivative if derivative is not None else velocity,
            "ANALYTIC": derivative is not None,
        },
        f"friction law {law.name}",
    )


def law_nodes(nodes: int, cutoff: int) -> int:
    """Points the law is evaluated at: the smallest power of two >= 8 Lc (128 at Lc = 16),
    at most N. The force there has modes |k| <= Lc, and the velocity keeps |k| <= Lc, so a
    harmonic of the law's output aliases onto them only from |k| >= M - Lc (7 Lc): the same
    dynamics, to that aliasing, at an eighth of the cost of the N = 1024 points."""
    return min(nodes, 1 << max(3, (8 * cutoff - 1).bit_length()))


def model_workspace(model, unknowns: int) -> LawWorkspace:
    """:func:`workspace` for ``model``'s law on :func:`law_nodes` points."""
    return workspace(
        law_nodes(model.nodes, model.cutoff),
        model.cutoff,
        unknowns,
        model.force_scale,
        model.friction_coefficients,
    )


def mobility(model) -> float:
    """What an integrator multiplies the force modes by: 2 pi / (gamma_mem l0) with the linear
    law, 1 with another (the law then maps the force modes to velocity modes)."""
    return 1.0 if model.nonlinear_friction else model.membrane_mobility
