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
        nargs="*",
        metavar="DATA",
        help="simulation files (a folder of softcell simulate, possibly over several radii, "
        "or one file: every simulation of the fit repeats its request), or tracked films "
        "(softcell track; each file a realization: the fit films and tracks its simulations "
        "alike)",
    )
    p.add_argument(
        "--paper",
        action="store_true",
        help="no data: score the paper's findings at every design point instead (each runs "
        "the quick design without its film) and write where they hold",
    )
    p.add_argument(
        "--config",
        type=Path,
        metavar="TOML",
        help="a [priors] table (NAME = {low, high, unit?, scale?}); for films also the model "
        "and components of the fit's simulations ([parameters], [components])",
    )
    p.add_argument(
        "--prior",
        action="append",
        default=[],
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
        "as the data has (with --paper: the quick design)",
    )
    p.add_argument(
        "--discard",
        type=float,
        metavar="SECONDS",
        help="seconds the analysis drops first (default: 15 for simulations, 0 for films)",
    )
    films = p.add_argument_group("films", "how the fit films its simulations, for tracked data")
    films.add_argument(
        "--warmup",
        type=float,
        default=15.0,
        metavar="SECONDS",
        help="seconds simulated before each film starts (default 15)",
    )
    films.add_argument(
        "--camera-scale",
        type=float,
        metavar="PX_PER_CM",
        help="scale of the fit's films (default: the data's, when tracked on a linear scale)",
    )
    films.add_argument(
        "--camera-noise",
        type=float,
        metavar="GREY_LEVELS",
        help="Gaussian noise of the fit's films (default 2)",
    )
    films.add_argument(
        "--camera-blur",
        type=float,
        metavar="PX",
        help="Gaussian blur of the fit's films (default 1)",
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
        p,
        "the fit's root seed (default: the data's seed + 1, never the data's; 1 for films, 0 "
        "with --paper)",
        default=None,
    )
    flags.workers(p, "local worker processes (default: every core)", scheduler=True)
    flags.quiet(p)
    p.set_defaults(func=_cmd_fit)


def _cmd_fit(args: argparse.Namespace) -> int:
    from softcell.fit.fitting import fit

    config, table = _read_config(args.config)
    if args.paper:
        return _cmd_search(args, config, table)
    if not args.data:
        from softcell.errors import ConfigError

        raise ConfigError("give DATA (the files to fit), or --paper")
    camera = {
        name: value
        for name, value in (
            ("px_per_cm", args.camera_scale),
            ("noise", args.camera_noise),
            ("blur", args.camera_blur),
        )
        if value is not None
    }
    out = fit(
        args.data,
        args.prior,
        args.output,
        prior_table=table,
        config=config,
        camera=camera or None,
        warmup=args.warmup,
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


def _cmd_search(args: argparse.Namespace, config, table) -> int:
    """``softcell fit --paper``: the paper's findings across a design of the unknowns."""
    from softcell.errors import ConfigError
    from softcell.fit.picture import search

    if args.data:
        raise ConfigError(f"--paper takes no data: {args.data[0]} given")
    for flag in ("statistics", "discard", "camera_scale", "camera_noise", "camera_blur"):
        if getattr(args, flag) is not None:
            raise ConfigError(f"--{flag.replace('_', '-')} is for data, not --paper")
    out = search(
        args.prior,
        args.output,
        prior_table=table,
        points=args.simulations,
        config=config,
        seed=0 if args.seed is None else args.seed,
        workers=args.workers,
        scheduler=args.scheduler,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=flags.note,
    )
    print(f"done: {out} (and {out.with_suffix('.md')})")
    return 0


def _read_config(path: Path | None):
    """The run configuration (None without tables of one) and the ``[priors]`` table of a
    fit's TOML file."""
    from softcell.errors import ConfigError
    from softcell.io.config_file import read_toml
    from softcell.model.configuration import SECTIONS, config_from_mapping
    from softcell.model.parameters import suggest

    if path is None:
        return None, {}
    tables = read_toml(path)
    priors = tables.pop("priors", {})
    for name in tables:
        if name not in SECTIONS:
            known = (*SECTIONS, "priors")
            raise ConfigError(
                f"{path}: unknown table [{name}]{suggest(name, known)}; tables: {', '.join(known)}"
            )
    if not isinstance(priors, dict):
        raise ConfigError(f"{path}: priors must be a table, [priors]")
    return (config_from_mapping(tables, path) if tables else None), priors


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "fit": (
        "the posterior of unknown parameters from simulation data or tracked films: a "
        "space-filling design of simulations, an emulator of the statistics, MCMC",
        _add_fit,
    ),
}
