"""The verbs of studies beyond the paper: ``study NAME`` (every study, through its protocol)
and ``beyond`` (the same as ``study beyond``)."""

from __future__ import annotations

import argparse
from typing import Any

from softcell.cli import flags
from softcell.errors import SoftcellError
from softcell.studies import WHERE

#: Each design flag: its metavar (None for a switch) and its help.
DESIGN_FLAGS: dict[str, tuple[str | None, str]] = {
    "quick": (
        None,
        "the grid studies: a smaller grid, a look in place of the full one "
        "(what each costs: docs/performance.md)",
    ),
    "radii": ("R1,R2,...", "the grid studies: cell radii R (cm)"),
    "gaps": ("G1,G2,...", "constriction: gap widths w / 2R, in (0, 1.5]; 1.5 is no partition"),
    "fractions": ("F1,F2,...", "crowding: area fractions, in (0, 0.785)"),
    "cells": ("N", "crowding: cells per box (a square number)"),
    "counts": ("K1,K2,...", "bots: numbers of bots in one ring"),
    "strategies": (
        "P1,P2,...",
        "strategies: driving protocols (default: run_and_tumble, graspion, bump_and_turn, "
        "active_brownian, chiral)",
    ),
    "realizations": ("N", "the grid studies: realizations per grid point"),
    "duration": ("SECONDS", "the grid studies: duration of each realization (s)"),
    "only": (
        "NAMES",
        "sensitivity, beyond: comma-separated variants to run beside the reference (default: "
        "all; sensitivity: bot_2.5x1.5, bot_3.5x2.5, k_0.057, k_0.18, cutoff_12, cutoff_19, "
        "lambda_1e-4, pivot, coulomb, gamma_mem_4.7e-5, torque_1e-3, torque_1e-3_k_0.057, "
        "force_x0.5, pivot_coulomb; beyond: "
        "coulomb_3e-05, coulomb_0.0001, coulomb_0.0003, arena)",
    ),
}
#: How the command line reads a design flag's text.
READ = {
    "radii": flags.distinct_numbers,
    "gaps": flags.distinct_numbers,
    "fractions": flags.distinct_numbers,
    "counts": lambda name, raw: _whole(name, flags.distinct_numbers(name, raw)),
    "strategies": lambda name, raw: flags.distinct(name, flags.names(raw)),
    "only": lambda name, raw: flags.distinct(name, flags.names(raw)),
}


def _whole(name: str, values: list[float]) -> list[int]:
    """``values`` as integers; a one-line error naming a value that is not one."""
    for v in values:
        if v != int(v):
            raise SoftcellError(f"{name} {v:g} is not allowed: a number of bots is an integer")
    return [int(v) for v in values]


def _add_common(p: argparse.ArgumentParser) -> None:
    flags.output(p, "results directory (one folder per point or variant inside)")
    flags.overwrite(
        p,
        "recompute what the directory holds from another seed or version, or write "
        "into a non-empty directory the study did not make",
    )
    flags.seed(p, "root seed of every point or variant")
    flags.workers(p, "local worker processes (default: every core)")
    flags.quiet(p)


def _add_study(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "study",
        choices=list(WHERE),
        help="sensitivity: the quick design over one of the paper's unknowns at a time (bot "
        "size, k, Lambda_c, lambda, rotation, friction); beyond: static friction and the "
        "arena; constriction: how often one cell passes a gap in a wall, against the gap's "
        "width and R; crowding: the cells' D hat and <tau_g> against area fraction and R; "
        "strategies: D hat, <tau_g>, <tau_s> and shape index against R for each locomotion "
        "strategy; bots: several bots in one ring against their number, shape and alignment",
    )
    design = p.add_argument_group("the design (each flag belongs to some studies)")
    for name, (metavar, help) in DESIGN_FLAGS.items():
        if metavar is None:
            design.add_argument(f"--{name}", action="store_true", help=help)
        else:
            kind = {"cells": int, "realizations": int, "duration": float}.get(name, str)
            design.add_argument(f"--{name}", metavar=metavar, type=kind, help=help)
    _add_common(p)
    p.set_defaults(func=_cmd_study)


def _cmd_study(args: argparse.Namespace) -> int:
    from softcell.studies import studies

    known = studies()
    study = known[args.study]
    given = [f for f in DESIGN_FLAGS if getattr(args, f) not in (None, False)]
    for name in given:
        if name not in study.offered():
            owners = [f"'study {s}'" for s, other in known.items() if name in other.offered()]
            raise SoftcellError(
                f"--{name} does not belong to 'study {args.study}'; it belongs to "
                + " or ".join(owners)
            )
    changes = {
        name: READ.get(name, lambda _, v: v)(f"--{name}", getattr(args, name))
        for name in given
        if name != "quick"
    }
    changes = {k: tuple(v) if isinstance(v, list) else v for k, v in changes.items()}
    return _run(study, args, study.design(args.quick, **changes))


def _run(study: Any, args: argparse.Namespace, design: Any) -> int:
    report = study.run(
        args.output,
        design=design,
        seed=args.seed,
        workers=args.workers,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=flags.note,
    )
    print(f"done: {report}")
    return 0


def _add_beyond(p: argparse.ArgumentParser) -> None:
    _add_common(p)
    p.set_defaults(func=_cmd_beyond)


def _cmd_beyond(args: argparse.Namespace) -> int:
    from softcell.studies import studies

    study = studies()["beyond"]
    return _run(study, args, study.design(False))


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "beyond": (
        "the same as 'study beyond': the quick design with static friction (3 thresholds) "
        "and in the arena, beside the paper's model",
        _add_beyond,
    ),
    "study": (
        "'study sensitivity': which of the paper's findings its unknowns decide, one "
        "unknown at a time; 'study beyond': static friction and the arena; 'study "
        "constriction': does softness let a cell through a gap; 'study crowding': D hat and "
        "<tau_g> against area fraction; 'study strategies': locomotion strategies",
        _add_study,
    ),
}
