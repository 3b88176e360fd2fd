"""The verb ``fit``: the unknowns' posterior from data and priors."""

from __future__ import annotations

import argparse
from pathlib import Path

from softcell.cli import flags


def _add_fit(p: argparse.ArgumentParser) -> None:
    from softcell.fit.statistics import DEFAULT_STATISTICS

    p.add_argument(
        "data",
        type=Path,
        metavar="DATA",
        help="simulation files: a folder of softcell simulate (possibly over several radii) "
        "or one file; every simulation of the fit repeats its request",
    )
    p.add_argument(
        "--prior",
        action="append",
        required=True,
        metavar="NAME=LOW:HIGH",
        help="an unknown and its range (repeatable), in the parameter's unit (softcell "
        "params), or 'NAME=LOW:HIGH UNIT' in another unit; log-uniform when HIGH / LOW > 10, "
        "else uniform",
    )
    p.add_argument(
        "--statistics",
        metavar="S1,S2,...",
        help=f"analysis quantities compared (default: {','.join(DEFAULT_STATISTICS)})",
    )
    p.add_argument(
        "--simulations",
        type=int,
        default=32,
        metavar="N",
        help="design points, a power of two (default 32); each runs as many realizations "
        "as the data has",
    )
    p.add_argument(
        "--discard", type=float, metavar="SECONDS", help="seconds the analysis drops first"
    )
    p.add_argument(
        "--check-draws",
        type=int,
        default=16,
        metavar="K",
        help="posterior draws re-simulated for the predictive check (default 16; 0: none)",
    )
    flags.output(p, "the fit's file (.nc); its simulations go to <name>_design/")
    flags.overwrite(p, "replace an existing file that is not a softcell fit")
    flags.seed(
        p, "the fit's root seed (default: the data's seed + 1; never the data's)", default=None
    )
    flags.workers(p, "local worker processes (default: every core)", scheduler=True)
    flags.quiet(p)
    p.set_defaults(func=_cmd_fit)


def _cmd_fit(args: argparse.Namespace) -> int:
    from softcell.fit.fitting import fit

    out = fit(
        args.data,
        args.prior,
        args.output,
        statistics=flags.names(args.statistics) or None,
        simulations=args.simulations,
        seed=args.seed,
        discard=args.discard,
        check_draws=args.check_draws,
        workers=args.workers,
        scheduler=args.scheduler,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=flags.note,
    )
    print(f"done: {out}")
    return 0


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "fit": (
        "the posterior of unknown parameters from simulation data: a space-filling design of "
        "simulations, an emulator of the statistics, MCMC",
        _add_fit,
    ),
}
