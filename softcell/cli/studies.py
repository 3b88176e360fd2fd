"""The verbs of studies beyond the paper: ``study NAME`` and ``beyond``."""

from __future__ import annotations

import argparse
from typing import Any

from softcell.cli import flags
from softcell.errors import SoftcellError


def _add_study(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "study",
        choices=["sensitivity", "constriction", "crowding", "strategies"],
        help="sensitivity: the quick design over one of the paper's unknowns at a "
        "time (bot size, k, Lambda_c, lambda, rotation, friction); constriction: how often "
        "one cell passes a gap in a wall, against the gap's width and R; crowding: the cells' "
        "D hat and <tau_g> against area fraction and R; strategies: D hat, <tau_g>, <tau_s> "
        "and shape index against R for each locomotion strategy",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="the grid studies: a look (constriction ~1 min, crowding ~1 h, strategies "
        "~8 min on 2 cores) instead of the full grid (20 min; ~12 h; ~1.5 h)",
    )
    grid = p.add_argument_group(
        "constriction, crowding and strategies grids (over the full or --quick design)"
    )
    grid.add_argument("--radii", metavar="R1,R2,...", help="cell radii R (cm)")
    grid.add_argument(
        "--gaps",
        metavar="G1,G2,...",
        help="constriction: gap widths w / 2R, in (0, 1.5]; 1.5 is no partition",
    )
    grid.add_argument(
        "--fractions", metavar="F1,F2,...", help="crowding: area fractions, in (0, 0.785)"
    )
    grid.add_argument("--cells", type=int, help="crowding: cells per box (a square number)")
    grid.add_argument(
        "--strategies",
        metavar="P1,P2,...",
        help="strategies: driving protocols (default: run_and_tumble, graspion, "
        "bump_and_turn, active_brownian, chiral)",
    )
    grid.add_argument("--realizations", type=int, help="realizations per grid point")
    grid.add_argument("--duration", type=float, help="duration of each realization (s)")
    p.add_argument(
        "--only",
        metavar="NAMES",
        help="comma-separated variants to run beside the defaults (default: all: "
        "bot_2.5x1.5, bot_3.5x2.5, k_0.057, k_0.18, cutoff_12, cutoff_19, "
        "lambda_1e-4, pivot, coulomb, gamma_mem_4.7e-5, torque_1e-3, pivot_coulomb)",
    )
    _add_beyond(p)
    p.set_defaults(func=_cmd_study)


def _cmd_study(args: argparse.Namespace) -> int:
    from softcell.studies import grid_studies
    from softcell.studies.sensitivity import VARIANTS, sensitivity, variants_named

    grids = grid_studies()
    if args.study in grids:
        return _grid_study(args, grids)
    given = [f for f in (*GRID_FLAGS, *_own_flags(grids)) if getattr(args, f)]
    if given:
        owners = [s for s, study in grids.items() if given[0] in study.flags] or list(grids)
        raise SoftcellError(
            f"--{given[0]} belongs to "
            + " or ".join(f"'study {s}'" for s in owners)
            + "; 'study sensitivity' runs the quick design"
        )
    variants = VARIANTS if args.only is None else variants_named(flags.names(args.only))
    report = sensitivity(
        args.output,
        seed=args.seed,
        workers=args.workers,
        variants=variants,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=flags.note,
    )
    print(f"done: {report}")
    return 0


#: Flags every grid study takes over its design.
GRID_FLAGS = ("quick", "radii", "realizations", "duration")


def _own_flags(grids: dict[str, Any]) -> tuple[str, ...]:
    """The flags that belong to one grid study alone."""
    return tuple(f for study in grids.values() for f in study.flags)


def _grid_changes(args: argparse.Namespace, study: Any, grids: dict[str, Any]) -> dict[str, Any]:
    """The design fields of ``study`` that the grid flags given change (lists as tuples)."""
    changes = {
        "radii": flags.numbers("--radii", args.radii),
        "gaps": flags.numbers("--gaps", args.gaps),
        "fractions": flags.numbers("--fractions", args.fractions),
        "cells": args.cells,
        "strategies": flags.names(args.strategies),
        "realizations": args.realizations,
        "duration": args.duration,
    }
    others = _own_flags(grids)
    return {
        k: tuple(v) if isinstance(v, list) else v
        for k, v in changes.items()
        if v is not None and (k in study.flags or k not in others)
    }


def _grid_study(args: argparse.Namespace, grids: dict[str, Any]) -> int:
    """``softcell study constriction``, ``crowding`` or ``strategies``: the full or quick
    grid, changed by the grid flags given."""
    study = grids[args.study]
    if args.only is not None:
        raise SoftcellError(f"--only names sensitivity variants; 'study {args.study}' has none")
    foreign = [
        f for other in grids.values() if other is not study for f in other.flags
        if getattr(args, f) is not None
    ]  # fmt: skip
    if foreign:
        raise SoftcellError(f"--{foreign[0]} does not belong to 'study {args.study}'")
    report = study.run(
        args.output,
        design=study.design(args.quick, **_grid_changes(args, study, grids)),
        seed=args.seed,
        workers=args.workers,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=flags.note,
    )
    print(f"done: {report}")
    return 0


def _add_beyond(p: argparse.ArgumentParser) -> None:
    flags.output(p, "results directory (one reproduction per variant inside)")
    flags.overwrite(
        p,
        "recompute what the directory holds from another seed or version, or write "
        "into a non-empty directory the study did not make",
    )
    flags.seed(p, "root seed of every variant")
    flags.workers(p, "local worker processes (default: every core)")
    flags.quiet(p)
    p.set_defaults(func=_cmd_beyond)


def _cmd_beyond(args: argparse.Namespace) -> int:
    from softcell.studies.friction_and_arena import beyond

    report = beyond(
        args.output,
        seed=args.seed,
        workers=args.workers,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=flags.note,
    )
    print(f"done: {report}")
    return 0


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "beyond": (
        "the quick design with static friction (3 thresholds) and in the arena, beside "
        "the paper's model",
        _add_beyond,
    ),
    "study": (
        "'study sensitivity': which of the paper's findings its unknowns decide, one "
        "unknown at a time; 'study constriction': does softness let a cell through a gap; "
        "'study crowding': D hat and <tau_g> against area fraction",
        _add_study,
    ),
}
