"""The components' kernels composed into single compiled functions, through the on-disk cache
of :mod:`softcell.engine.compiled`: the sum of the energy terms' partials, the sum of
their second derivatives (with the central-difference fallback for terms that have none), and
the drive's pose derivative.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from importlib import resources

from softcell.engine.compiled import compile_module, compiled_function

#: The arguments of a term's partials kernel (and of the composed sum).
PARTIALS_ARGS = (
    "x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose"
)

#: The arguments of the composed second derivatives (and of the central-difference fallback).
HESSIAN_ARGS = (
    "w, pose, context, coefficients, steps, saved, plus, minus, dplus, dminus, "
    "pose_tmp, hww, hwp, hpp"
)


def _term_call(kernel: str, arguments: str, i: int) -> str:
    """The line that calls ``kernel`` with ``arguments`` (a signature's names), the
    coefficients being term ``i``'s: ``    k0(x, ..., coefficients[0], ...)``."""
    names = [a.strip() for a in arguments.split(",")]
    passed = [f"coefficients[{i}]" if a == "coefficients" else a for a in names]
    return f"    {kernel}({', '.join(passed)})"


_PREAMBLE = "from numba import njit\n\n\n"


class Template(str):
    """The text of a template, with ``path``: where it was read from (errors name it)."""

    path: str

    def __new__(cls, text: str, path: str) -> Template:
        self = super().__new__(cls, text)
        self.path = path
        return self


@functools.cache
def template(package: str, name: str) -> Template:
    """The text of the template ``name`` (a file of ``package``, never imported); read once
    per process."""
    resource = resources.files(package).joinpath(name)
    return Template(resource.read_text(encoding="utf-8"), str(resource))


def _names(kernels: Sequence[Callable[..., object]]) -> str:
    return " + ".join(getattr(getattr(k, "py_func", k), "__qualname__", "?") for k in kernels)


def compose_partials(kernels: Sequence[Callable[..., None]]) -> Callable[..., None]:
    """One compiled function that calls every term's partials kernel in turn.

    Its signature is that of a term kernel, except that ``coefficients`` is a tuple holding
    one coefficient array per term.
    """
    calls = [_term_call(f"k{i}", PARTIALS_ARGS, i) for i in range(len(kernels))] or ["    pass"]
    source = (
        _PREAMBLE
        + f"@njit(**LEAN_JIT_FLAGS)\ndef total_partials({PARTIALS_ARGS}):\n"
        + "\n".join(calls)
        + "\n"
    )
    bindings = {f"k{i}": k for i, k in enumerate(kernels)}
    return compiled_function(
        "partials", source, "total_partials", bindings, _names(kernels) or "no energy terms"
    )


def fd_hessian(partials: Callable[..., None]) -> Callable[..., None]:
    """The documented fallback for an energy term without analytic second derivatives:
    central differences of its partials kernel, ``fd_hessian(HESSIAN_ARGS)`` (see the
    template's docstring for the steps), *adding* into ``hww``, ``hwp`` and ``hpp``."""
    return compiled_function(
        "fd-hessian",
        template(__package__ + ".templates", "fd_hessian.py"),
        "fd_hessian",
        {"partials": partials},
        _names([partials]),
    )


def compose_hessians(terms) -> Callable[..., None]:
    """One compiled function that adds every term's second derivatives into ``hww, hwp, hpp``
    (which :func:`~softcell.engine.kernels.jacobian.assemble_jacobian` leaves at zero after
    use): its ``hessian_kernel`` where it has one, :func:`fd_hessian` of its partials otherwise.
    ``coefficients`` is the tuple of the terms' arrays; ``w`` is float64[6, N]
    (x, y, x', y', x'', y''); the other arguments are those of the fallback.
    """
    bindings: dict[str, object] = {}
    lines = [f"@njit(**LEAN_JIT_FLAGS)\ndef total_hessian({HESSIAN_ARGS}):"]
    names = []
    for i, term in enumerate(terms):
        kernel = term.hessian_kernel()
        if kernel is not None:
            bindings[f"h{i}"] = kernel
            lines.append(
                f"    h{i}(w[0], w[1], w[2], w[3], w[4], w[5], pose, context, "
                f"coefficients[{i}], hww, hwp, hpp)"
            )
            names.append(_names([kernel]))
        else:
            bindings[f"h{i}"] = fd_hessian(term.partials_kernel())
            lines.append(_term_call(f"h{i}", HESSIAN_ARGS, i))
            names.append(f"differences of {_names([term.partials_kernel()])}")
    if len(lines) == 1:
        lines.append("    pass")
    source = _PREAMBLE + "\n".join(lines) + "\n"
    return compiled_function(
        "hessians", source, "total_hessian", bindings, " + ".join(names) or "no energy terms"
    )


def fd_drive_jacobian(drive: Callable[..., None]) -> Callable[..., None]:
    """d drive / d pose by central differences of the drive kernel, ``drive_jacobian(phase,
    datum, pose, context, drive_coefficients, steps, pose_tmp, plus, minus, out)`` with
    ``out[c, d]`` = d drive_c / d pose_d (steps ``steps[6:9]`` in cm, cm, rad)."""
    return compiled_function(
        "fd-drive",
        template(__package__ + ".templates", "fd_drive_jacobian.py"),
        "drive_jacobian",
        {"drive": drive},
        _names([drive]),
    )


BOT_ARGS = "pose, context, coefficients, dpose"
BOT_HESSIAN_ARGS = "pose, context, coefficients, steps, pose_tmp, plus, minus, hpp"


def compose_bot(terms) -> tuple[Callable[..., None], Callable[..., None]]:
    """The terms' energies of the bot alone (:meth:`EnergyTerm.bot_kernel`), summed:
    ``bot_forces(BOT_ARGS)`` adds dU/dpose into ``dpose`` and ``bot_hessians(BOT_HESSIAN_ARGS)``
    adds d^2 U / dpose^2 into ``hpp`` (the term's ``bot_hessian_kernel``, or central
    differences of its ``bot_kernel`` with the steps ``steps[6:9]``). ``coefficients`` is the
    tuple of the terms' arrays; terms without a bot kernel are skipped."""
    bindings: dict[str, object] = {}
    forces = [f"@njit(**LEAN_JIT_FLAGS)\ndef bot_forces({BOT_ARGS}):"]
    hessians = [f"@njit(**LEAN_JIT_FLAGS)\ndef bot_hessians({BOT_HESSIAN_ARGS}):"]
    names = []
    for i, term in enumerate(terms):
        kernel = term.bot_kernel()
        if kernel is None:
            continue
        bindings[f"b{i}"] = kernel
        forces.append(f"    b{i}(pose, context, coefficients[{i}], dpose)")
        hessian = term.bot_hessian_kernel()
        if hessian is None:
            bindings[f"bh{i}"] = compiled_function(
                "fd-bot-hessian",
                template(__package__ + ".templates", "fd_bot_hessian.py"),
                "fd_bot_hessian",
                {"bot": kernel},
                _names([kernel]),
            )
            hessians.append(_term_call(f"bh{i}", BOT_HESSIAN_ARGS, i))
        else:
            bindings[f"bh{i}"] = hessian
            hessians.append(f"    bh{i}(pose, context, coefficients[{i}], hpp)")
        names.append(_names([kernel]))
    for lines in (forces, hessians):
        if len(lines) == 1:
            lines.append("    pass")
    source = _PREAMBLE + "\n".join(forces) + "\n\n\n" + "\n".join(hessians) + "\n"
    module = compile_module("bot-energies", source, bindings, " + ".join(names) or "none")
    return module.bot_forces, module.bot_hessians


def compose_pair_laws(terms) -> Callable[..., None]:
    """The pair terms' laws summed: ``pair_law(rho, coefficients, out, scratch)`` writes the
    sum of e, de/drho and d^2 e / drho^2 (N cm, N, N cm^-1) at the signed distance ``rho``
    (cm) into ``out[0:3]``; ``coefficients`` is the tuple of the terms' arrays, ``scratch``
    float64[3]."""
    bindings: dict[str, object] = {}
    lines = ["@njit(**LEAN_JIT_FLAGS)\ndef pair_law(rho, coefficients, out, scratch):"]
    lines.append("    out[0] = 0.0\n    out[1] = 0.0\n    out[2] = 0.0")
    for i, term in enumerate(terms):
        bindings[f"p{i}"] = term.law_kernel()
        lines.append(f"    p{i}(rho, coefficients[{i}], scratch)")
        lines.append("    for j in range(3):\n        out[j] += scratch[j]")
    source = _PREAMBLE + "\n".join(lines) + "\n"
    names = _names([t.law_kernel() for t in terms]) or "no pair terms"
    return compiled_function("pair-laws", source, "pair_law", bindings, names)


def compose_interactions(interactions) -> Callable[..., None]:
    """The bot interactions' kernels summed: ``interact(pose_a, pose_b, context,
    coefficients, out)`` adds every interaction's generalized forces on bots a and b (N, N,
    N cm) into ``out[0:6]``; ``coefficients`` is the tuple of their arrays."""
    bindings = {f"i{n}": c.pair_kernel() for n, c in enumerate(interactions)}
    lines = ["@njit(**JIT_FLAGS)\ndef interact(pose_a, pose_b, context, coefficients, out):"]
    lines += [
        f"    i{n}(pose_a, pose_b, context, coefficients[{n}], out)"
        for n in range(len(interactions))
    ] or ["    pass"]
    source = _PREAMBLE + "\n".join(lines) + "\n"
    names = _names(list(bindings.values())) or "no bot interactions"
    return compiled_function("bot-interactions", source, "interact", bindings, names)


def compose_interaction_jacobians(interactions) -> Callable[..., None]:
    """The bot interactions' Jacobians summed: ``interact_jacobian(pose_a, pose_b, context,
    coefficients, steps, scratch, jac)`` adds each one's d out / d (pose_a, pose_b) into
    ``jac`` (float64[6, 6]): its ``jacobian_kernel``, or central differences of its
    ``pair_kernel`` (``templates/fd_interaction.py``)."""
    bindings: dict[str, object] = {}
    lines = [
        "@njit(**JIT_FLAGS)\ndef interact_jacobian(pose_a, pose_b, context, coefficients, "
        "steps, scratch, jac):"
    ]
    names = []
    for n, interaction in enumerate(interactions):
        kernel = interaction.jacobian_kernel()
        if kernel is None:
            kernel = compiled_function(
                "fd-interaction",
                template(__package__ + ".templates", "fd_interaction.py"),
                "fd_interaction",
                {"pair": interaction.pair_kernel()},
                _names([interaction.pair_kernel()]),
            )
            names.append(f"differences of {_names([interaction.pair_kernel()])}")
        else:
            names.append(_names([kernel]))
        bindings[f"j{n}"] = kernel
        lines.append(f"    j{n}(pose_a, pose_b, context, coefficients[{n}], steps, scratch, jac)")
    if len(lines) == 1:
        lines.append("    pass")
    source = _PREAMBLE + "\n".join(lines) + "\n"
    return compiled_function(
        "bot-interaction-jacobians",
        source,
        "interact_jacobian",
        bindings,
        " + ".join(names) or "no bot interactions",
    )
