"""rodas4's single-bot loop, compiled per component set: the collocation grids' scratch,
the workspace of the compiled loop, the energy terms split into the coarse grid's and the
others, and the loop of ``templates/loop.py`` compiled from them. The group loop of many
cells (:mod:`softcell.integrators.rodas4`) and the loop of several bots in one ring
(:mod:`softcell.integrators.rodas4.several`) are built on it.
"""

from __future__ import annotations

import math
from collections import namedtuple
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from softcell.components.contracts import SENSE_SIZE
from softcell.engine import (
    Model,
    compose_hessians,
    compose_partials,
    fd_drive_jacobian,
    nonlinear_friction,
    placeholders,
)
from softcell.engine.compiled import compile_module
from softcell.engine.compose import compose_bot, template
from softcell.engine.kernels.jacobian import spectral_factors
from softcell.engine.kernels.linalg import lu_workspace

#: Where the templates are (the package's, wherever this module is imported from).
TEMPLATES = "softcell.integrators.rodas4.templates"


Grid = namedtuple(
    "Grid",
    [
        "spec",
        "curve",
        "w",
        "parts",
        "q",
        "fhat",
        "dpose",
        "saved",
        "plus",
        "minus",
        "hww",
        "hwp",
        "hpp",
        "twiddle",
        "index",
        "active",
        "n_active",
        "touched",
        "n_touched",
        "buf_a",
        "buf_b",
        "scratch",
    ],
)

Workspace = namedtuple(
    "Workspace",
    [
        "modes",
        "smooth",
        "fine",
        "drv",
        "steps",
        "dplus",
        "dminus",
        "pose_tmp",
        "djac",
        "drv_plus",
        "drv_minus",
        "a_hat",
        "b_hat",
        "g_hat",
        "cal_a",
        "cal_b",
        "factors",
        "orders",
        "magnitudes",
        "rotated",
        "jac",
        "mat",
        "pivots",
        "k",
        "f0",
        "y",
        "ynew",
        "force",
        "drag",
        "law",
        "bot_hpp",
        "sense",
    ],
)


def grid(n: int, m: int) -> Grid:
    """Scratch arrays of one collocation grid of n points (m = 2 Lc + 1 modes). ``spec``
    holds the curve's spectrum only: just the modes' bins are ever written, the others stay
    zero."""
    c = np.complex128
    return Grid(
        spec=np.zeros(n, c),
        curve=np.zeros((3, n), c),
        w=np.zeros((6, n)),
        parts=np.zeros((6, n)),
        q=np.zeros((3, n), c),
        fhat=np.zeros(m, c),
        dpose=np.zeros(3),
        saved=np.zeros(n),
        plus=np.zeros((6, n)),
        minus=np.zeros((6, n)),
        hww=np.zeros((n, 6, 6)),
        hwp=np.zeros((n, 6, 3)),
        hpp=np.zeros((3, 3)),
        twiddle=np.exp(-2j * np.pi * np.arange(n) / n),
        index=np.zeros(n, np.int64),
        active=np.zeros(n, np.int64),
        n_active=np.zeros(1, np.int64),
        touched=np.zeros(n, np.int64),
        n_touched=np.zeros(1, np.int64),
        buf_a=np.zeros(n, c),
        buf_b=np.zeros(n, c),
        scratch=np.zeros(n, c),
    )


def workspace(model: Model, smooth_nodes: int) -> Workspace:
    """Every scratch array of the compiled loop, allocated once per stepper."""
    n, lc = model.nodes, model.cutoff
    m = 2 * lc + 1
    nu = 2 * m + 3
    scale = model.params.membrane_length / (2 * math.pi)
    c = np.complex128
    factors, orders, magnitudes = np.zeros((3, m), c), np.zeros((3, m), c), np.zeros((3, m))
    spectral_factors(lc, factors, orders, magnitudes)
    return Workspace(
        modes=np.zeros(m, c),
        smooth=grid(smooth_nodes, m),
        fine=grid(n, m),
        drv=np.zeros(3),
        steps=np.array([1e-7 * scale] * 8 + [1e-7]),
        dplus=np.zeros(3),
        dminus=np.zeros(3),
        pose_tmp=np.zeros(3),
        djac=np.zeros((3, 3)),
        drv_plus=np.zeros(3),
        drv_minus=np.zeros(3),
        a_hat=np.zeros(4 * lc + 1, c),
        b_hat=np.zeros(4 * lc + 1, c),
        g_hat=np.zeros(m, c),
        cal_a=np.zeros((m, m), c),
        cal_b=np.zeros((m, m), c),
        factors=factors,
        orders=orders,
        magnitudes=magnitudes,
        rotated=np.zeros((8, 4 * lc + 1)),
        jac=np.zeros((nu, nu)),
        mat=np.zeros((nu, nu)),
        pivots=lu_workspace(nu, transposed=True),
        k=np.zeros((6, nu)),
        f0=np.zeros(nu),
        y=np.zeros(nu),
        ynew=np.zeros(nu),
        force=np.zeros(nu),
        drag=np.zeros(3),
        law=nonlinear_friction.model_workspace(model, nu),
        bot_hpp=np.zeros((3, 3)),
        sense=np.zeros(SENSE_SIZE),
    )


def groups(model: Model) -> tuple[list, list]:
    """The model's terms split into those evaluated on the coarse grid (``smooth``) and the
    others, each as a list of (index, term)."""
    smooth = [(i, t) for i, t in enumerate(model.terms) if t.smooth]
    other = [(i, t) for i, t in enumerate(model.terms) if not t.smooth]
    return smooth, other


def _names(terms) -> str:
    return " + ".join(t.name for t in terms) or "none"


class _Group(NamedTuple):
    """What the loop template binds for one group of terms (the smooth terms on the coarse
    grid, or the others on the N points)."""

    forces: Callable[..., None]
    jacobian: Callable[..., None]
    has_terms: bool
    order: int
    has_bot: bool
    bot_forces: Callable[..., None]
    bot_hessians: Callable[..., None]


def _group(terms: list, coarse: bool) -> _Group:
    """The compiled grid module of ``templates/grid.py`` for ``terms`` (the coarse
    grid is always scanned; the others are unless every term has an analytic Hessian),
    with the terms' energies of the bot alone (stubs when there are none)."""
    grid_module = compile_module(
        "rodas4-grid",
        template(TEMPLATES, "grid.py"),
        {
            "partials": compose_partials([t.partials_kernel() for t in terms]),
            "hessian": compose_hessians(terms),
            "SCAN": coarse or any(t.hessian_kernel() is None for t in terms),
        },
        _names(terms),
    )
    has_bot = any(t.has_bot_energy for t in terms)
    bot_forces, bot_hessians = (
        compose_bot(terms)
        if has_bot
        else (placeholders.no_bot_forces, placeholders.no_bot_hessians)
    )
    return _Group(
        forces=grid_module.forces,
        jacobian=grid_module.grid_jacobian,
        has_terms=bool(terms),
        order=max([t.derivative_order for t in terms], default=0),
        has_bot=has_bot,
        bot_forces=bot_forces,
        bot_hessians=bot_hessians,
    )


def compiled_loop(model: Model) -> tuple:
    """(rhs, jacobian, integrate) compiled for the model's terms and drive: generated modules
    from ``templates/grid.py`` (once per group of terms) and
    ``templates/loop.py``, cached on disk (:mod:`softcell.engine.compiled`), with
    the model's friction law when it is nonlinear
    (:mod:`softcell.engine.nonlinear_friction`)."""
    smooth_terms, other_terms = ([t for _, t in group] for group in groups(model))
    smooth = _group(smooth_terms, coarse=True)
    other = _group(other_terms, coarse=False)
    law = nonlinear_friction.compiled_friction(model.friction) if model.nonlinear_friction else None
    loop = compile_module(
        "rodas4-loop",
        template(TEMPLATES, "loop.py"),
        {
            "forces_s": smooth.forces,
            "jacobian_s": smooth.jacobian,
            "HAS_S": smooth.has_terms,
            "ORDER_S": smooth.order,
            "HAS_BOT_S": smooth.has_bot,
            "bot_forces_s": smooth.bot_forces,
            "bot_hessians_s": smooth.bot_hessians,
            "forces_f": other.forces,
            "jacobian_f": other.jacobian,
            "HAS_F": other.has_terms,
            "ORDER_F": other.order,
            "HAS_BOT_F": other.has_bot,
            "bot_forces_f": other.bot_forces,
            "bot_hessians_f": other.bot_hessians,
            "drive": model.drive,
            "drive_jacobian": fd_drive_jacobian(model.drive),
            "event": model.event if model.event is not None else placeholders.no_event,
            "HAS_EVENT": model.event is not None,
            "LAW": law is not None,
            "friction_velocity": law.velocity if law else placeholders.no_friction_velocity,
            "friction_jacobian": law.jacobian if law else placeholders.no_friction_jacobian,
        },
        f"{_names(model.terms)}; {model.protocol.name}"
        + (f"; {model.friction.name}" if law else ""),
    )
    return loop.rhs, loop.jacobian, loop.integrate


def group_coefficients(model: Model) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """The terms' coefficient arrays, split like :func:`groups`."""
    out = []
    for group in groups(model):
        out.append(tuple(model.coefficients[i] for i, _ in group) or (np.zeros(1),))
    return out[0], out[1]
