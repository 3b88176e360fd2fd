"""The verbs of the paper: ``reproduce`` (end to end), ``figures`` (from an analysis) and
``calibrate`` (gamma_mem and k, as the paper calibrated them)."""

from __future__ import annotations

import argparse
from pathlib import Path

from softcell.cli import flags
from softcell.errors import SoftcellError
from softcell.io.config_file import load_config
from softcell.model.configuration import RunConfig


def _add_figures(p: argparse.ArgumentParser) -> None:
    p.add_argument("analysis", type=Path, help="analysis file of a radius sweep (.nc)")
    flags.output(p, "directory for the figures")
    flags.overwrite(p, "replace existing fig*.png/pdf files that softcell did not draw")
    p.add_argument(
        "--simulations", type=Path, help="the sweep's simulation directory (trajectories of Fig. 2)"
    )
    p.add_argument("--free-bot", type=Path, help="analysis of free-bot runs (Fig. S1)")
    p.add_argument(
        "--tracked", type=Path, help="analysis of a tracked video (the experiments' markers)"
    )
    p.set_defaults(func=_cmd_figures)


def _cmd_figures(args: argparse.Namespace) -> int:
    from softcell.io.files import check_output
    from softcell.io.netcdf import open_dataset, read_dataset
    from softcell.paper.figures import FIGURES, FORMATS, make_figures

    inputs = [p for p in (args.analysis, args.simulations, args.free_bot, args.tracked) if p]
    check_output(args.output, "figure", inputs=inputs, directory=True)
    for name in FIGURES:
        for fmt in FORMATS:
            check_output(
                args.output / f"{name}.{fmt}", "figure", inputs=inputs, overwrite=args.overwrite
            )
    made = make_figures(
        read_dataset(args.analysis),
        args.output,
        simulations=open_dataset(args.simulations, chunks={}) if args.simulations else None,
        free_bot=read_dataset(args.free_bot) if args.free_bot else None,
        tracked=read_dataset(args.tracked) if args.tracked else None,
    )
    for name, files in made.files.items():
        print(f"{name}: {', '.join(str(f) for f in files)}")
    for name, why in made.skipped.items():
        print(f"note: {name} not drawn: {why}")
    return 0


def _add_reproduce(p: argparse.ArgumentParser) -> None:
    design = p.add_mutually_exclusive_group()
    design.add_argument(
        "--quick",
        action="store_true",
        help="every radius, 5 realizations of 240 s (the default; minutes)",
    )
    design.add_argument(
        "--full",
        action="store_true",
        help="the paper's design: 25 realizations of 900/1800 s per radius",
    )
    p.add_argument(
        "--config",
        type=Path,
        metavar="TOML",
        help="model parameters ([parameters]) and components ([components]) other than the "
        "defaults, e.g. a point `softcell fit --paper` found; the design sets the radii and "
        "durations",
    )
    flags.output(p, "results directory")
    flags.overwrite(
        p,
        "recompute what the directory holds from another design, seed or "
        "version (or use a directory softcell did not make) instead of stopping",
    )
    flags.seed(p, "root seed of every random stream")
    flags.workers(p, scheduler=True, help="local worker processes (default: every core)")
    flags.quiet(p)
    p.set_defaults(func=_cmd_reproduce)


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from softcell.paper.reproduce import DESIGNS, reproduce

    design = DESIGNS["full" if args.full else "quick"]
    if args.config is not None:
        design = _configured(design, args.config)
    outcome = reproduce(
        args.output,
        design,
        seed=args.seed,
        workers=args.workers,
        scheduler=args.scheduler,
        overwrite=args.overwrite,
        progress=not args.quiet,
    )
    print(f"done in {sum(outcome.steps.values()):.0f} s: {outcome.report}")
    return 0


def _configured(design, path: Path):
    """``design`` with the parameters and components of the TOML file ``path``."""
    from dataclasses import replace

    from softcell.io.config_file import load_config

    config = load_config(path)
    other = {"run": config.run, "analysis": config.analysis, "assembly": config.assembly,
             "obstacles": config.parameters.get("obstacles")}  # fmt: skip
    for table, value in other.items():
        if value:
            raise SoftcellError(
                f"{path}: reproduce takes [parameters] and [components], not [{table}]: "
                "the paper's design is one cell in its ring, analysed as the paper did"
            )
    for name in ("radius", "duration"):
        if name in config.parameters:
            raise SoftcellError(f"{path}: the design sets {name} (--quick or --full), not the file")
    return replace(
        design,
        components={**design.components, **config.components},
        parameters={**design.parameters, **config.parameters},
    )


def _add_calibrate(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "config",
        nargs="?",
        type=Path,
        help="TOML configuration: every other parameter and the components",
    )
    p.add_argument(
        "--push-speed",
        type=float,
        metavar="V",
        help="measured time-averaged GC speed of a constantly pushed cell (cm/s): "
        "calibrates gamma_mem",
    )
    p.add_argument("--push-speed-error", type=float, metavar="DV", help="its standard error (cm/s)")
    p.add_argument(
        "--ipr",
        metavar="I1,I2,...",
        help="measured time-averaged shape index P / sqrt(A) at each radius: calibrates k",
    )
    p.add_argument("--ipr-error", metavar="E1,E2,...", help="their standard errors")
    p.add_argument(
        "--radius",
        required=True,
        metavar="R1,R2,...",
        help="radii (cm): the push's, then one per IPR value",
    )
    p.add_argument(
        "--realizations",
        type=int,
        help="realizations per evaluation and radius (default 2 for the push, 4 for the IPR)",
    )
    p.add_argument(
        "--duration",
        type=float,
        help="simulated seconds per realization (default 15 for the push, 120 for the IPR)",
    )
    p.add_argument(
        "--settle",
        type=float,
        help="seconds left out before averaging (default 5 for the push, 15 for the IPR)",
    )
    flags.seed(p, "root seed (every evaluation uses it)")
    flags.workers(p, "local worker processes (default 1)")
    flags.output(p, "also write the results as JSON", required=False)
    flags.overwrite(p, "replace an existing JSON file")
    flags.quiet(p, "no line per evaluation")
    p.set_defaults(func=_cmd_calibrate)


def _check_calibration_request(args: argparse.Namespace, radius, ipr) -> None:
    """One line, before anything runs, for a calibration that cannot be done as asked."""
    from softcell.io.files import check_output

    if args.push_speed is None and ipr is None:
        raise SoftcellError(
            "nothing to calibrate: give --push-speed V (for gamma_mem) and/or "
            "--ipr I1,I2,... (for k), with --radius"
        )
    if args.push_speed is not None and ipr is not None and len(radius) != 1 + len(ipr):
        raise SoftcellError(
            f"--radius has {len(radius)} value(s): with both calibrations give "
            "the push's radius first, then one radius per IPR value"
        )
    if args.push_speed is not None and ipr is None and len(radius or []) > 1:
        raise SoftcellError("--push-speed calibrates at one radius: give one --radius")
    if args.output is not None:
        check_output(
            args.output,
            "report",
            overwrite=args.overwrite,
            inputs=[args.config] if args.config else [],
        )


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from softcell.paper.calibrate import (
        calibrate_bending,
        calibrate_friction,
        write_calibration,
    )

    radius = flags.distinct_numbers("--radius", args.radius)
    ipr, ipr_error = flags.numbers("--ipr", args.ipr), flags.numbers("--ipr-error", args.ipr_error)
    _check_calibration_request(args, radius, ipr)
    config = load_config(args.config) if args.config else RunConfig()
    workers = flags.check_workers(args.workers)
    options = {"seed": args.seed, "workers": workers, "log": None if args.quiet else flags.note}
    results = []
    if args.push_speed is not None:
        push_radius, radius = radius[0], radius[1:]
        found = calibrate_friction(
            args.push_speed,
            push_radius,
            config=config,
            push_speed_error=args.push_speed_error or 0.0,
            **flags.given(
                realizations=args.realizations, duration=args.duration, settle=args.settle
            ),
            **options,
        )
        print(found.summary())
        results.append(found)
        config = config.updated(parameters={"membrane_friction": found.value})
    if ipr is not None:
        found = calibrate_bending(
            ipr,
            radius,
            config=config,
            ipr_error=ipr_error,
            **flags.given(
                realizations=args.realizations, duration=args.duration, settle=args.settle
            ),
            **options,
        )
        print(found.summary())
        results.append(found)
    if not (args.push_speed_error or ipr_error):
        print(
            "(uncertainty: the simulations' spread across realizations and the search's "
            "tolerance; give --push-speed-error / --ipr-error to add the measurements')"
        )
    if args.output is not None:
        print(f"written: {write_calibration(results, args.output, config)}")
    return 0


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "figures": (
        "the paper's figures (PNG and PDF) from an analysis of a radius sweep",
        _add_figures,
    ),
    "reproduce": (
        "the paper end to end: simulate, analyze, render and track, figures, report",
        _add_reproduce,
    ),
    "calibrate": (
        "gamma_mem from a pushed cell's speed, k from the mean IPR, as the paper calibrated them",
        _add_calibrate,
    ),
}
