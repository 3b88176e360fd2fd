"""The ``softcell`` command: a thin layer over the public API.

Every parameter of the model is a flag (``--radius 4,8,12`` sweeps it); a TOML file may set
them too (flags win). Bad input is reported as one line on stderr with exit status 2.
"""

from __future__ import annotations

import argparse
import atexit
import json
import math
import os
import signal
import sys
import warnings
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, NoReturn

from softcell._version import __version__
from softcell.engine.interrupt import exit_status, received, stop_signals
from softcell.errors import CacheWarning, PluginWarning, SchemaError, SoftcellError
from softcell.io.config_file import load_config
from softcell.model.configuration import (
    RunConfig,
    terms_with_obstacles,
    with_assembly_terms,
    with_obstacle_term,
)
from softcell.model.obstacle_layout import check_clear_of_start
from softcell.model.parameters import MODEL_PARAMETERS, ParameterSpec, expand_sweep, suggest
from softcell.settings import CHECKPOINT_EVERY


class _Parser(argparse.ArgumentParser):
    """argparse, but a bad command line is one line on stderr (exit status 2), like every
    other bad input."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)  # --arena-sid is not --arena-side
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        if message.startswith("unrecognized arguments: "):
            flags = _option_strings(self)
            given = message.removeprefix("unrecognized arguments: ").split()[0]
            message += suggest(given.split("=")[0], flags)
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _option_strings(parser: argparse.ArgumentParser) -> list[str]:
    """Every flag of ``parser`` and of its subcommands' parsers."""
    flags = []
    for action in parser._actions:
        flags += action.option_strings
        for sub in (getattr(action, "choices", None) or {}).values():
            if isinstance(sub, argparse.ArgumentParser):
                flags += _option_strings(sub)
    return flags


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _add_parameter_flags(
    parser: argparse.ArgumentParser,
    specs: Sequence[ParameterSpec],
    title: str = "model parameters",
    description: str = "override the defaults (softcell params lists "
    "them; docs/model.md explains them); a comma-separated list sweeps a "
    "parameter",
) -> None:
    group = parser.add_argument_group(title, description)
    for spec in specs:
        unit = "" if spec.unit == "1" else f" [{spec.unit}]"
        default = "derived" if spec.default is None else spec.default
        group.add_argument(
            _flag(spec.name),
            dest=f"param_{spec.name}",
            metavar="VALUE",
            help=f"{spec.long_name}{unit} (default {default})",
        )


def _add_component_flags(parser: argparse.ArgumentParser, specs: Sequence[ParameterSpec]) -> None:
    """Flags for the parameters that the components in use declare beyond the model's
    (e.g. rodas4's --atol and --rtol)."""
    _add_parameter_flags(
        parser,
        specs,
        "component parameters",
        "parameters of the components this run uses (integrator, protocol, energy terms, detector)",
    )


def _component_specs(components: dict[str, Any] | None) -> dict[str, tuple[ParameterSpec, str]]:
    """The parameters beyond the model's that ``components`` (kind -> name or names; None for
    every registered component) declare, by name, each with the first component declaring it
    (``"integrator 'rodas4'"``)."""
    from softcell.components.contracts import kind_name
    from softcell.components.registry import chosen, default_registry

    registry = default_registry()
    found: dict[str, tuple[ParameterSpec, str]] = {}
    for entry in registry:
        cls = entry.component
        if components is None or chosen(cls, components):
            for spec in cls.parameters:
                if spec.name not in MODEL_PARAMETERS:
                    found.setdefault(spec.name, (spec, f"{kind_name(cls.kind)} {cls.name!r}"))
    return found


def _flag_values(args: argparse.Namespace) -> dict[str, Any]:
    values: dict[str, Any] = {}
    for key, raw in vars(args).items():
        if key.startswith("param_") and raw is not None:
            items = [s.strip() for s in raw.split(",")]
            values[key.removeprefix("param_")] = items if len(items) > 1 else items[0]
    return values


def _config(args: argparse.Namespace) -> RunConfig:
    base = load_config(args.config) if getattr(args, "config", None) else RunConfig()
    values = _flag_values(args)
    placed = _obstacle_flags(args)
    if placed:
        if "obstacles" in values:
            raise SoftcellError("--obstacles and --obstacle / --wall both place obstacles: use one")
        values["obstacles"] = placed
    return base.updated(parameters=values, assembly=_assembly_flags(args))


def _assembly_flags(args: argparse.Namespace) -> dict[str, Any]:
    """The ``[assembly]`` settings given as flags (--cells, --box, --boundary, --placement,
    --gap, --pair-terms)."""
    flags = {
        key: getattr(args, f"assembly_{key}")
        for key in ("cells", "box", "boundary", "placement", "gap", "pair_terms")
        if getattr(args, f"assembly_{key}", None) is not None
    }
    if "pair_terms" in flags:
        flags["pair_terms"] = [n.strip() for n in flags["pair_terms"].split(",")]
    return flags


def _obstacle_flags(args: argparse.Namespace) -> str:
    """The parameter ``obstacles`` from ``--obstacle X,Y,RADIUS`` and
    ``--wall X0,Y0,X1,Y1,WIDTH`` (cm), or "" when neither is given."""
    from softcell.model.obstacle_layout import FIELDS, obstacle_text

    tables = []
    for flag, kind in (("obstacle", "post"), ("wall", "wall")):
        for raw in getattr(args, flag, None) or ():
            words = [w.strip() for w in raw.split(",")]
            fields = FIELDS[kind]
            try:
                if len(words) != len(fields):
                    raise ValueError
                tables.append(dict(zip(fields, (float(w) for w in words), strict=True)))
            except ValueError:
                raise SoftcellError(
                    f"--{flag} {raw} is not allowed: must be "
                    f"{','.join(f.upper() for f in fields)} (numbers in cm)"
                ) from None
    return obstacle_text(tables) if tables else ""


def _cmd_plugins(args: argparse.Namespace) -> int:
    from softcell.components.registry import KINDS, default_registry

    registry = default_registry()
    for kind in KINDS.values():
        entries = registry.entries(kind)
        print(f"{kind} ({len(entries)})")
        if not entries:
            print("    (none registered)")
        for entry in entries:
            cls = entry.component
            print(f"    {cls.name}: {cls.description}")
            print(f"        origin: {entry.origin}")
            for spec in cls.parameters:
                unit = "" if spec.unit == "1" else f" {spec.unit}"
                print(f"        {spec.name} = {spec.default}{unit}  ({spec.long_name})")
    print(f"skipped ({len(registry.skipped)})")
    if not registry.skipped:
        print("    (none)")
    for plugin, reason in registry.skipped:
        print(f"    {plugin}: {reason}")
        print(f"        origin: {registry.skipped_origins.get(plugin, 'unknown')}")
    return 0


def _cmd_params(args: argparse.Namespace) -> int:
    from softcell.components.registry import check_in_use, check_point, default_registry
    from softcell.model.limits import check_run

    registry = default_registry()
    config = with_obstacle_term(_config(args).updated(components=_component_flags(args)))
    config = with_assembly_terms(config)
    config.check_components(registry)
    check_in_use(config.parameters, registry, config.components)
    points = expand_sweep(
        config.parameters, list(registry.parameter_specs(config.components).values())
    )
    for _, params in points:
        check_run(params)
        # the checks simulate makes, so params accepts no less
        check_point(params, registry, config.components)
        if not config.assembly:
            check_clear_of_start(params)
    _, first = points[0]
    swept = {k: v for k, v in config.parameters.items() if isinstance(v, list)}
    width = max(len(n) for n in first)
    for name, value in first.items():
        spec = first.specs[name]
        shown = ", ".join(map(str, swept[name])) if name in swept else value
        unit = "" if spec.unit == "1" else spec.unit
        print(f"{name:<{width}}  {shown!s:<12} {unit:<10} {spec.long_name}")
    if swept:
        print(f"# {len(points)} parameter points, swept: {', '.join(swept)}")
    return 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    from softcell.runner.ensemble import simulate

    config = with_obstacle_term(_config(args).updated(components=_component_flags(args)))
    run = config.run
    realizations = (
        args.realizations if args.realizations is not None else run.get("realizations", 1)
    )
    seed = args.seed if args.seed is not None else run.get("seed", 0)
    if args.workers is not None and args.workers < 1:
        raise SoftcellError(f"--workers = {args.workers} is not allowed: must be >= 1")
    if not (math.isfinite(args.checkpoint_every) and args.checkpoint_every > 0):
        raise SoftcellError(
            f"--checkpoint-every = {args.checkpoint_every} s is not allowed: "
            "must be finite and > 0 s"
        )
    paths = simulate(
        config,
        args.output,
        realizations=realizations,
        seed=seed,
        workers=args.workers or 1,
        scheduler=args.scheduler,
        membrane=not args.free_bot,
        overwrite=args.overwrite,
        log=_note,
        progress=not args.quiet,
        checkpoint_every=args.checkpoint_every,
    )
    print(f"{len(paths)} files in {args.output}")
    return 0


def _cmd_analyze(args: argparse.Namespace) -> int:
    from softcell.analysis import analyze
    from softcell.io.files import check_output
    from softcell.io.netcdf import open_inputs, read_failure, write_dataset

    options = dict(load_config(args.config).analysis) if args.config else {}
    options.update(
        (k.removeprefix("param_"), v)
        for k, v in vars(args).items()
        if k.startswith("param_") and v is not None
    )
    check_output(args.output, "analysis", inputs=args.inputs, overwrite=args.overwrite)
    ds = open_inputs(args.inputs, chunks={})  # one point in memory at a time
    try:
        result = analyze(ds, options, progress=not args.quiet)
    except (OSError, RuntimeError) as exc:  # netCDF's "HDF error" names no file
        raise read_failure(args.inputs, exc) from None
    path = write_dataset(result, args.output)
    print(f"analysis of {_describe(ds)} written to {path}")
    return 0


def _cmd_render(args: argparse.Namespace) -> int:
    from softcell.io.files import check_output
    from softcell.io.netcdf import open_inputs, read_failure
    from softcell.model.limits import check_seed
    from softcell.schema import validate
    from softcell.video.render import parse_point, parse_size, render

    check_seed(args.seed)  # before anything is read
    check_output(args.output, "video", inputs=[args.input], overwrite=args.overwrite)
    ds = open_inputs([args.input])
    point = parse_point(args.point, "--point") if args.point else {}
    size = parse_size(args.size, "--size") if args.size else None
    try:
        validate(ds)
    except SchemaError as exc:
        raise SoftcellError(f"{args.input} cannot be rendered: {exc}") from None
    if "cell" in ds.dims:
        raise SoftcellError(
            f"{args.input} is an assembly of {ds.sizes['cell']} cells: render films one cell "
            "(the camera's view of the paper's experiments)"
        )
    try:
        info = render(
            ds,
            args.output,
            realization=args.realization,
            point=point,
            px_per_cm=args.px_per_cm,
            fps=args.fps,
            size=size,
            start=args.start,
            end=args.end,
            noise=args.noise,
            blur=args.blur,
            illumination=args.illumination,
            seed=args.seed,
            head_mark=not args.no_head_mark,
            progress=not args.quiet,
        )
    except (OSError, RuntimeError) as exc:  # netCDF's "HDF error" names no file
        raise read_failure([args.input], exc) from None
    for note in info.notes:
        print(f"note: {note}")
    print(
        f"{info.times.size} frames of {info.frame.width}x{info.frame.height} px written to "
        f"{info.path}; lower-left corner at {info.frame.x0:.6f},{info.frame.y0:.6f} cm "
        f"(track it with --px-per-cm {info.frame.px_per_cm:g} "
        f"--origin={info.frame.x0:.6f},{info.frame.y0:.6f})"
    )
    return 0


def _cmd_track(args: argparse.Namespace) -> int:
    from softcell.io.files import check_output, no_input
    from softcell.io.netcdf import write_dataset
    from softcell.video.track import codec, parse_origin, track

    origin = parse_origin(args.origin, "--origin") if args.origin else (0.0, 0.0)
    if not args.video.is_file():
        raise no_input(args.video, "video file")
    check_output(args.output, "tracking", inputs=[args.video], overwrite=args.overwrite)
    if args.overlay is not None:
        if os.path.abspath(args.overlay) == os.path.abspath(args.output):
            raise SoftcellError(
                f"--overlay {args.overlay} is the tracked file -o: give another name"
            )
        codec(args.overlay)  # a video suffix, or a clear error
        check_output(
            args.overlay, "video", inputs=[args.video], overwrite=args.overwrite, option="--overlay"
        )
    ds = track(
        args.video,
        px_per_cm=args.px_per_cm,
        arena_size=args.arena_size,
        origin=origin,
        plate_size=args.plate_size,
        camera=args.camera,
        camera_height=args.camera_height,
        ring_height=args.ring_height,
        bot_height=args.bot_height,
        ring_color=args.ring_color,
        ring_threshold=args.ring_threshold,
        dark_fraction=args.dark_fraction,
        fps=args.fps,
        nodes=args.nodes,
        radius=args.radius,
        overlay=args.overlay,
        progress=not args.quiet,
    )
    path = write_dataset(ds, args.output)
    print(
        f"{ds.sizes['time']} frames tracked, {ds.attrs['softcell_tracking_summary']}, "
        f"written to {path}"
    )
    failures = json.loads(ds.attrs["softcell_tracking_failures"])
    for reason, count in failures.items():
        print(f"  {count} frame(s) lost: {reason}")
    if args.overlay is not None:
        print(f"overlay written to {args.overlay}")
    return 0


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


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from softcell.paper.reproduce import DESIGNS, reproduce

    outcome = reproduce(
        args.output,
        DESIGNS["full" if args.full else "quick"],
        seed=args.seed,
        workers=args.workers,
        scheduler=args.scheduler,
        overwrite=args.overwrite,
        progress=not args.quiet,
    )
    print(f"done in {sum(outcome.steps.values()):.0f} s: {outcome.report}")
    return 0


def _cmd_beyond(args: argparse.Namespace) -> int:
    from softcell.studies.friction_and_arena import beyond

    report = beyond(
        args.output,
        seed=args.seed,
        workers=args.workers,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=_note,
    )
    print(f"done: {report}")
    return 0


def _add_beyond(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="results directory (one reproduction per variant inside)",
    )
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="recompute what the directory holds from another seed or version, or write "
        "into a non-empty directory the study did not make",
    )
    p.add_argument("--seed", type=int, default=0, help="root seed of every variant")
    p.add_argument("--workers", type=int, help="local worker processes (default: every core)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_beyond)


def _cmd_study(args: argparse.Namespace) -> int:
    from softcell.studies.sensitivity import VARIANTS, sensitivity, variants_named

    if args.study in GRID_STUDIES:
        return _cmd_grid_study(args)
    flags = (*GRID_FLAGS, *(f for _, own in GRID_STUDIES.values() for f in own))
    given = [f for f in flags if getattr(args, f)]
    if given:
        owners = [s for s, (_, own) in GRID_STUDIES.items() if given[0] in own] or list(
            GRID_STUDIES
        )
        raise SoftcellError(
            f"--{given[0]} belongs to "
            + " or ".join(f"'study {s}'" for s in owners)
            + "; 'study sensitivity' runs the quick design"
        )
    variants = (
        VARIANTS
        if args.only is None
        else variants_named([n.strip() for n in args.only.split(",") if n.strip()])
    )
    report = sensitivity(
        args.output,
        seed=args.seed,
        workers=args.workers,
        variants=variants,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=_note,
    )
    print(f"done: {report}")
    return 0


#: The grid studies: each one's module, and the flags that belong to it alone.
GRID_STUDIES = {
    "constriction": ("softcell.studies.constriction", ("gaps",)),
    "crowding": ("softcell.studies.crowding", ("fractions", "cells")),
    "strategies": ("softcell.studies.locomotion", ("strategies",)),
}
#: Flags every grid study takes over its design.
GRID_FLAGS = ("quick", "radii", "realizations", "duration")
#: The flags that belong to one grid study alone.
OWN_FLAGS = tuple(f for _, own in GRID_STUDIES.values() for f in own)


def _grid_changes(args: argparse.Namespace, own: tuple[str, ...]) -> dict[str, Any]:
    """The design fields the grid flags given change (lists as tuples), for a study whose
    own flags are ``own``."""
    changes = {
        "radii": _numbers("--radii", args.radii),
        "gaps": _numbers("--gaps", args.gaps),
        "fractions": _numbers("--fractions", args.fractions),
        "cells": args.cells,
        "strategies": None
        if args.strategies is None
        else [n.strip() for n in args.strategies.split(",") if n.strip()],
        "realizations": args.realizations,
        "duration": args.duration,
    }
    return {
        k: tuple(v) if isinstance(v, list) else v
        for k, v in changes.items()
        if v is not None and (k in own or k not in OWN_FLAGS)
    }


def _cmd_grid_study(args: argparse.Namespace) -> int:
    """``softcell study constriction``, ``crowding`` or ``strategies``: the full or quick
    grid, changed by the grid flags given."""
    from softcell.studies import constriction, crowding, locomotion

    own = GRID_STUDIES[args.study][1]
    if args.only is not None:
        raise SoftcellError(f"--only names sensitivity variants; 'study {args.study}' has none")
    foreign = [
        f for s, (_, flags) in GRID_STUDIES.items() if s != args.study for f in flags
        if getattr(args, f) is not None
    ]  # fmt: skip
    if foreign:
        raise SoftcellError(f"--{foreign[0]} does not belong to 'study {args.study}'")
    module = {"constriction": constriction, "crowding": crowding, "strategies": locomotion}[
        args.study
    ]
    design = module.QUICK if args.quick else module.FULL
    changes = _grid_changes(args, own)
    if changes:
        design = replace(design, name=f"{design.name}, changed", **changes)
    report = getattr(module, args.study)(
        args.output,
        design=design,
        seed=args.seed,
        workers=args.workers,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=_note,
    )
    print(f"done: {report}")
    return 0


def _add_study(p: argparse.ArgumentParser, strict: bool, specs) -> None:
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
    _add_beyond(p, strict, specs)
    p.set_defaults(func=_cmd_study)


def _numbers(flag: str, raw: str | None) -> list[float] | None:
    if raw is None:
        return None
    try:
        return [float(v) for v in raw.split(",") if v.strip()]
    except ValueError:
        raise SoftcellError(f"{flag} {raw!r} is not a comma-separated list of numbers") from None


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

    radius = _numbers("--radius", args.radius)
    ipr, ipr_error = _numbers("--ipr", args.ipr), _numbers("--ipr-error", args.ipr_error)
    _check_calibration_request(args, radius, ipr)
    config = load_config(args.config) if args.config else RunConfig()
    if args.workers is not None and args.workers < 1:
        raise SoftcellError(f"--workers = {args.workers} is not allowed: must be >= 1")
    workers = args.workers or 1
    options = {"seed": args.seed, "workers": workers, "log": None if args.quiet else _note}
    results = []
    if args.push_speed is not None:
        push_radius, radius = radius[0], radius[1:]
        found = calibrate_friction(
            args.push_speed,
            push_radius,
            config=config,
            push_speed_error=args.push_speed_error or 0.0,
            **_given(realizations=args.realizations, duration=args.duration, settle=args.settle),
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
            **_given(realizations=args.realizations, duration=args.duration, settle=args.settle),
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


def _given(**values: Any) -> dict[str, Any]:
    return {k: v for k, v in values.items() if v is not None}


def _add_calibrate(p: argparse.ArgumentParser, strict: bool, specs) -> None:
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
        required=strict,
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
    p.add_argument("--seed", type=int, default=0, help="root seed (every evaluation uses it)")
    p.add_argument("--workers", type=int, help="local worker processes (default 1)")
    p.add_argument("-o", "--output", type=Path, help="also write the results as JSON")
    p.add_argument("--overwrite", action="store_true", help="replace an existing JSON file")
    p.add_argument("--quiet", action="store_true", help="no line per evaluation")
    p.set_defaults(func=_cmd_calibrate)


def _add_cluster_flags(parser: argparse.ArgumentParser, workers_help: str) -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--workers", type=int, help=workers_help)
    group.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run the realizations on the dask.distributed cluster whose "
        "scheduler listens at ADDRESS (e.g. tcp://10.0.0.5:8786), one task "
        "per realization; its workers must see the output directory",
    )


def _describe(ds: Any) -> str:
    swept = [d for d in ds["cell_x"].dims if d not in ("realization", "time", "cell")]
    points = " x ".join(f"{ds.sizes[d]} {d}" for d in swept)
    cells = f" of {ds.sizes['cell']} cells" if "cell" in ds.dims else ""
    return f"{ds.sizes['realization']} realization(s){cells}" + (f" at {points}" if points else "")


def _add_plugins(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.set_defaults(func=_cmd_plugins)


def _add_component_choice(p: argparse.ArgumentParser) -> None:
    p.add_argument("--protocol", help="driving protocol (default run_and_tumble)")
    p.add_argument(
        "--integrator",
        help="integrator (default rodas4; explicit_euler is the paper's scheme, the reference)",
    )
    p.add_argument(
        "--friction-law",
        help="the membrane's friction law (default viscous, the "
        "paper's; coulomb adds a static threshold)",
    )
    p.add_argument("--energy-terms", help="comma-separated energy terms")
    p.add_argument(
        "--obstacle",
        action="append",
        metavar="X,Y,RADIUS",
        help="a fixed circular post (cm; repeatable); the energy term obstacles joins the terms",
    )
    p.add_argument(
        "--wall",
        action="append",
        metavar="X0,Y0,X1,Y1,WIDTH",
        help="a fixed straight wall of thickness WIDTH from (X0, Y0) to (X1, Y1) (cm; "
        "repeatable; write --wall=-10,... when the first number is negative)",
    )


def _add_assembly_flags(p: argparse.ArgumentParser) -> None:
    group = p.add_argument_group(
        "assembly", "many cells, each with its own bot, repelling each other's membranes"
    )
    group.add_argument(
        "--cells", dest="assembly_cells", type=int, metavar="M", help="number of cells"
    )
    group.add_argument(
        "--box",
        dest="assembly_box",
        type=float,
        metavar="L",
        help="side of the square box centred on the origin (cm); none: the open plane",
    )
    group.add_argument(
        "--boundary",
        dest="assembly_boundary",
        choices=("periodic", "walls", "open"),
        help="the box's boundary (default periodic with --box, open without)",
    )
    group.add_argument(
        "--placement",
        dest="assembly_placement",
        choices=("lattice", "random"),
        help="starting places: a square lattice (default) or at random",
    )
    group.add_argument(
        "--gap",
        dest="assembly_gap",
        type=float,
        metavar="CM",
        help="smallest starting gap between rings, walls and obstacles (cm, default 1)",
    )
    group.add_argument(
        "--pair-terms",
        dest="assembly_pair_terms",
        metavar="A,B",
        help="how the membranes meet: comma-separated pair terms (default repulsion)",
    )


def _add_params(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument("config", nargs="?", type=Path, help="TOML configuration file")
    _add_component_choice(p)
    _add_parameter_flags(p, list(MODEL_PARAMETERS.values()))
    _add_component_flags(p, specs)
    p.set_defaults(func=_cmd_params)


def _add_simulate(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument("config", nargs="?", type=Path, help="TOML configuration file")
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        required=strict,
        help="directory for the files, one per (parameter point, realization)",
    )
    p.add_argument("--realizations", type=int, help="realizations per parameter point")
    p.add_argument("--seed", type=int, help="root seed of every random stream (default 0)")
    _add_cluster_flags(p, "local worker processes (default 1; more: a local dask cluster)")
    _add_component_choice(p)
    p.add_argument("--free-bot", action="store_true", help="no membrane: the free bot")
    _add_assembly_flags(p)
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="recompute files in OUT made with other settings (and remove "
        "simulation files that are no part of this request) instead of "
        "stopping",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--checkpoint-every",
        type=float,
        default=CHECKPOINT_EVERY,
        metavar="SECONDS",
        help="wall seconds between checkpoints of a running realization "
        f"(default {CHECKPOINT_EVERY:g}); a killed run resumes from the last one",
    )
    _add_parameter_flags(p, list(MODEL_PARAMETERS.values()))
    _add_component_flags(p, specs)
    p.set_defaults(func=_cmd_simulate)


def _add_analyze(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    from softcell.analysis.collective import CROWD_OPTIONS
    from softcell.analysis.options import ANALYSIS_OPTIONS

    p.add_argument(
        "inputs",
        nargs="+",
        type=Path,
        metavar="INPUT",
        help="NetCDF files or directories of one sweep (softcell simulate / track)",
    )
    p.add_argument("-o", "--output", type=Path, required=True, help="analysis file (.nc)")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an existing file that is not a softcell analysis",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--config",
        type=Path,
        help="TOML file whose [analysis] table sets options (flags override it)",
    )
    _add_parameter_flags(
        p,
        list(ANALYSIS_OPTIONS.values()),
        "analysis options",
        "see docs/analysis.md; stored in the output file",
    )
    _add_parameter_flags(
        p,
        list(CROWD_OPTIONS.values()),
        "assembly options",
        "what many cells do together: clusters, g(r), Voronoi (docs/analysis.md); an error "
        "for a file of one cell",
    )
    _add_parameter_flags(
        p,
        _detector_specs(),
        "stop/go detector parameters",
        "parameters of the detectors (default: the value the input was made with, else the "
        "detector's default); one of a detector the analysis does not use is an error",
    )
    p.set_defaults(func=_cmd_analyze)


def _detector_specs() -> list[ParameterSpec]:
    """Every registered detector's parameters beyond the analysis options."""
    from softcell.analysis.options import ANALYSIS_OPTIONS
    from softcell.components.registry import default_registry

    specs: dict[str, ParameterSpec] = {}
    for entry in default_registry().entries("stopgo_detector"):
        for spec in entry.component.parameters:
            if spec.name not in ANALYSIS_OPTIONS:
                specs.setdefault(spec.name, spec)
    return list(specs.values())


def _add_render(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument("input", type=Path, help="simulation file or sweep directory")
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="video: .mkv/.avi (lossless, for tracking) or .mp4",
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing video")
    p.add_argument("--realization", type=int, default=0)
    p.add_argument("--point", help="sweep point, e.g. radius=1 (an index)")
    p.add_argument("--px-per-cm", type=float, default=10.0, help="scale [px/cm] (default 10)")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--size", help="frame size WIDTHxHEIGHT [px] (default: fits the cell)")
    p.add_argument("--start", type=float, help="first frame time [s]")
    p.add_argument("--end", type=float, help="last frame time [s]")
    p.add_argument("--noise", type=float, default=0.0, help="Gaussian noise [grey levels]")
    p.add_argument("--blur", type=float, default=0.0, help="Gaussian blur [px]")
    p.add_argument(
        "--illumination", type=float, default=0.0, help="relative amplitude of uneven illumination"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the noise")
    p.add_argument("--no-head-mark", action="store_true", help="no mark at the bot's head")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_render)


def _add_animate(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument("input", type=Path, help="simulation file or directory")
    p.add_argument(
        "-o", "--output", type=Path, required=True, help="movie: .mp4 (H.264) or .gif (slides)"
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing movie")
    p.add_argument(
        "--realizations",
        help="realizations side by side, e.g. 0,1,2 (default: the first up to 4; one for an "
        "assembly, all its cells in one panel)",
    )
    p.add_argument("--point", help="sweep point, e.g. radius=1 (an index)")
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument(
        "--speed", type=float, default=1.0, help="simulated seconds per movie second (default 1)"
    )
    p.add_argument("--start", type=float, default=0.0, help="first frame time [s] (default 0)")
    p.add_argument("--end", type=float, help="last frame time [s] (default: the record's end)")
    p.add_argument("--trail", type=float, default=5.0, help="trail length [s] (default 5)")
    p.add_argument("--height", type=int, default=480, help="frame height [px] (default 480)")
    p.add_argument(
        "--crf",
        type=int,
        default=20,
        help="H.264 quality: 0 lossless .. 51 smallest (default 20; 28 for the web)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_animate)


def _cmd_animate(args: argparse.Namespace) -> int:
    from softcell.io.files import check_output
    from softcell.io.netcdf import open_inputs
    from softcell.video.animate import animate
    from softcell.video.render import parse_point

    check_output(args.output, "video", inputs=[args.input], overwrite=args.overwrite)
    realizations = None
    if args.realizations:
        try:
            realizations = [int(v) for v in args.realizations.split(",")]
        except ValueError:
            raise SoftcellError(
                f"--realizations {args.realizations} is not allowed: must be indices, e.g. 0,1"
            ) from None
    ds = open_inputs([args.input])
    if args.point:
        ds = ds.isel(parse_point(args.point, "--point"))
    movie = animate(
        ds,
        args.output,
        realizations=realizations,
        fps=args.fps,
        speed=args.speed,
        start=args.start,
        end=args.end,
        trail=args.trail,
        height=args.height,
        crf=args.crf,
        progress=not args.quiet,
    )
    print(
        f"{movie.path}: {movie.frames} frames at {movie.fps:g}/s, {movie.size[0]}x"
        f"{movie.size[1]} px, t = {movie.span[0]:g} .. {movie.span[1]:.6g} s"
    )
    return 0


def _add_export(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument(
        "input", type=Path, help="simulation or tracking file, or a folder of one point's files"
    )
    p.add_argument(
        "-o", "--output", type=Path, required=True, help="trajectory: .gsd, or .nc for movement"
    )
    p.add_argument(
        "--to",
        choices=["gsd", "movement"],
        help="gsd (OVITO, freud, MDAnalysis; a simulation) or movement's poses dataset "
        "(netCDF; a tracked video or a simulation); default: from the output's suffix",
    )
    p.add_argument(
        "--overwrite", action="store_true", help="replace an existing file softcell did not export"
    )
    p.add_argument(
        "--realization", type=int, help="which realization (needed when the input holds several)"
    )
    p.add_argument(
        "--every", type=int, default=1, help="gsd: write every N-th stored sample (default 1)"
    )
    p.set_defaults(func=_cmd_export)


def _export_format(args: argparse.Namespace) -> str:
    """``--to``, or the format the output's suffix names; refused in one line when neither
    says."""
    suffix = args.output.suffix.lower()
    implied = {".gsd": "gsd", ".nc": "movement"}.get(suffix)
    if args.to is None and implied is None:
        raise SoftcellError(
            f"-o {args.output}: give a .gsd (GSD) or .nc (movement) file, or --to gsd|movement"
        )
    to = args.to or implied
    if to == "movement" and args.every != 1:
        raise SoftcellError("--every belongs to --to gsd; movement keeps every sample")
    return to


def _cmd_export(args: argparse.Namespace) -> int:
    from softcell.io.export import check_gsd_path, to_gsd, to_movement
    from softcell.io.files import check_output, no_input
    from softcell.io.netcdf import open_inputs

    if not args.input.exists():
        raise no_input(args.input, "simulation or tracking file")
    to = _export_format(args)
    if to == "gsd":
        check_gsd_path(args.output)
    check_output(args.output, "export", inputs=[args.input], overwrite=args.overwrite)
    with open_inputs([args.input]) as ds:
        if to == "gsd":
            done = to_gsd(ds, args.output, realization=args.realization, every=args.every)
        else:
            done = to_movement(ds, args.output, realization=args.realization)
    what = "particles" if to == "gsd" else "keypoints x individuals"
    print(
        f"{done.path}: {done.frames} frames of {done.particles} {what}, "
        f"t = {done.span[0]:g} .. {done.span[1]:.6g} s"
    )
    return 0


def _add_track(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument("video", type=Path)
    p.add_argument("-o", "--output", type=Path, required=True, help="tracked file (.nc)")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an existing file that is not a softcell tracking file",
    )
    p.add_argument("--px-per-cm", type=float, help="scale [px/cm]")
    p.add_argument(
        "--arena-size", type=float, help="world width of the frame [cm], to derive the scale"
    )
    p.add_argument("--origin", help="world position X,Y [cm] of the lower-left corner")
    camera = p.add_argument_group(
        "camera",
        "calibrate from the plate seen in the first frame (perspective, lens, "
        "parallax) instead of a linear scale; positions in plate coordinates, origin "
        "at the plate corner seen at the lower left",
    )
    camera.add_argument("--plate-size", type=float, help="side of the square plate [cm]")
    camera.add_argument(
        "--camera",
        type=Path,
        help="OpenCV calibration file (camera_matrix, distortion_coefficients)",
    )
    camera.add_argument(
        "--camera-height",
        type=float,
        help="camera height above the plate [cm] (default: from --camera, or "
        "estimated from the plate when the camera is tilted)",
    )
    camera.add_argument(
        "--ring-height",
        type=float,
        default=0.0,
        help="height of the membrane's wall [cm] (parallax; default 0)",
    )
    camera.add_argument(
        "--bot-height", type=float, default=0.0, help="height of the bot [cm] (parallax; default 0)"
    )
    p.add_argument(
        "--ring-color",
        default="red",
        help="the paper's colour: red (also orange), green, blue, yellow",
    )
    p.add_argument(
        "--ring-threshold",
        type=float,
        help="colourfulness of paper, (R - max(G, B)) / R for red (default: per frame)",
    )
    p.add_argument(
        "--dark-fraction",
        type=float,
        default=0.5,
        help="bot pixels are darker than this fraction of the plate (default 0.5)",
    )
    p.add_argument(
        "--overlay",
        type=Path,
        help="also write the frames with what was tracked drawn on them (.mkv/.avi/.mp4)",
    )
    p.add_argument("--fps", type=float, help="frame rate [1/s] (default: the file's)")
    p.add_argument("--nodes", type=int, default=64, help="membrane points (default 64)")
    p.add_argument(
        "--radius",
        type=float,
        help="membrane radius R [cm]: expected perimeter 2 pi R (default: learned)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_track)


def _add_figures(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument("analysis", type=Path, help="analysis file of a radius sweep (.nc)")
    p.add_argument("-o", "--output", type=Path, required=True, help="directory for the figures")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace existing fig*.png/pdf files that softcell did not draw",
    )
    p.add_argument(
        "--simulations", type=Path, help="the sweep's simulation directory (trajectories of Fig. 2)"
    )
    p.add_argument("--free-bot", type=Path, help="analysis of free-bot runs (Fig. S1)")
    p.add_argument(
        "--tracked", type=Path, help="analysis of a tracked video (the experiments' markers)"
    )
    p.set_defaults(func=_cmd_figures)


def _add_reproduce(p: argparse.ArgumentParser, strict: bool, specs) -> None:
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
    p.add_argument("-o", "--output", type=Path, required=True, help="results directory")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="recompute what the directory holds from another design, seed or "
        "version (or use a directory softcell did not make) instead of stopping",
    )
    p.add_argument("--seed", type=int, default=0, help="root seed of every random stream")
    _add_cluster_flags(p, "local worker processes (default: every core)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_reproduce)


def _add_cache(p: argparse.ArgumentParser, strict: bool, specs) -> None:
    p.add_argument(
        "action",
        nargs="?",
        choices=("show", "clear"),
        default="show",
        help="show (the default): location, size and entries; clear: remove every entry",
    )
    p.add_argument(
        "--stale",
        action="store_true",
        help="with clear: only the entries another softcell build or numba, numpy "
        "or Python version made (never read again)",
    )
    p.set_defaults(func=_cmd_cache)


def _cmd_cache(args: argparse.Namespace) -> int:
    from softcell.io import model_cache as compiled

    root = compiled.cache_dir()
    if args.stale and args.action != "clear":
        raise SoftcellError("--stale goes with 'clear': softcell cache clear --stale")
    if args.action == "clear":
        count = compiled.clear(root, stale_only=args.stale)
        print(f"removed {count} {'stale ' if args.stale else ''}entries from {root}")
        return 0
    found = compiled.entries(root)
    total = sum(e.size for e in found)
    source = (
        f"${compiled.CACHE_ENV}"
        if os.environ.get(compiled.CACHE_ENV)
        else "the user cache directory"
    )
    print(f"location: {root}  (from {source})")
    stale = sum(e.stale for e in found)
    print(
        f"size: {total / 2**20:.1f} MiB in {len(found)} entries ({stale} stale: made by "
        "another softcell build or numba, numpy, Python version; 'softcell cache clear "
        "--stale' removes them)"
    )
    strangers = compiled.foreign(root)
    if strangers:
        print(
            f"not a cache: {len(strangers)} item(s) softcell did not make "
            f"(e.g. {strangers[0].name}); 'cache clear' refuses this folder"
        )
    for entry in found:
        mark = "  stale" if entry.stale else ""
        print(
            f"    {entry.name}  {entry.size / 2**10:.0f} KiB  {entry.created}{mark}  "
            f"{entry.description}"
        )
    return 0


#: Each command: its one-line help and what adds its arguments. A command's arguments are
#: built only when it runs, so ``softcell --version`` and ``--help`` import nothing heavy.
COMMANDS: dict[str, tuple[str, Callable[..., None]]] = {
    "plugins": ("list every component by kind, with origin and parameters", _add_plugins),
    "params": ("validate and print the parameters of a configuration", _add_params),
    "simulate": ("simulate an ensemble: parameter points x realizations", _add_simulate),
    "analyze": (
        "MSD, stop/go, fits and theory of simulated or tracked files, as one NetCDF file",
        _add_analyze,
    ),
    "render": ("a top-view movie of one simulated realization", _add_render),
    "animate": (
        "a movie to watch (MP4 or GIF): realizations side by side, or an assembly's cells, "
        "with trails, stop and go",
        _add_animate,
    ),
    "export": (
        "a simulation as a GSD trajectory (OVITO, freud, MDAnalysis), or a tracked video or "
        "simulation as movement's poses dataset (napari)",
        _add_export,
    ),
    "track": ("track a top-view video into the simulation schema", _add_track),
    "figures": (
        "the paper's figures (PNG and PDF) from an analysis of a radius sweep",
        _add_figures,
    ),
    "reproduce": (
        "the paper end to end: simulate, analyze, render and track, figures, report",
        _add_reproduce,
    ),
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
    "calibrate": (
        "gamma_mem from a pushed cell's speed, k from the mean IPR, as the paper calibrated them",
        _add_calibrate,
    ),
    "cache": (
        "the compiled-model cache: where it is, what it holds; 'cache clear' empties it",
        _add_cache,
    ),
}
#: Commands whose flags include the parameters of the components in use.
WITH_COMPONENTS = ("params", "simulate")


#: The top-level help's epilog: the workflows, an example each, where to read on.
WORKFLOWS = """\
workflows:
  the paper end to end (about 5 min on 2 cores, ~430 MB; --full: the paper's
  design, about 1 h on 2 cores with --workers 2, ~5 GB):
    softcell reproduce --quick -o results
  your own runs: simulate -> analyze -> figures
    softcell simulate --radius 4,8,12 --realizations 5 --duration 120 -o run
    softcell analyze run -o analysis.nc
    softcell figures analysis.nc --simulations run -o figures
  watch them: realizations side by side, or a crowd of cells
    softcell animate run --point radius=0 -o cells.mp4 --end 30
    softcell simulate --cells 16 --box 60 --duration 60 -o crowd
    softcell animate crowd -o crowd.mp4
  a camera's view and back: render -> track -> analyze
    softcell render run --point radius=2 -o cell.mkv --start 15 --end 45
    softcell track cell.mkv --px-per-cm 10 --origin=X0,Y0 -o tracked.nc  (render
      prints the --origin to give)
    softcell analyze tracked.nc -o tracked_analysis.nc
  in other tools: OVITO, freud, MDAnalysis (GSD); movement and napari (poses)
    softcell export run/point000_realization0000.nc -o cell.gsd
    softcell export tracked.nc -o poses.nc
  studies beyond the paper: a cell at a gap; crowds
    softcell study constriction --quick -o gap
    softcell study crowding --quick -o crowding

'softcell COMMAND --help' lists a command's options. The documentation
(docs/getting-started.md in the source, first) explains the model, the analysis
and how to write a plugin.
"""


def build_parser(
    command: str | None = None, *, strict: bool = True, specs: Sequence[ParameterSpec] = ()
) -> argparse.ArgumentParser:
    """The argument parser of the ``softcell`` command, with the arguments of ``command`` (of
    every command when None); ``specs`` are the component parameters offered as flags, and a
    parser that is not ``strict`` requires nothing (to read the component choice first)."""
    parser = _Parser(
        prog="softcell",
        add_help=strict,
        description="Simulate, track and analyse a soft robotic cell.",
        epilog=WORKFLOWS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"softcell {__version__}")
    sub = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=_Parser
    )
    for name, (help_line, add) in COMMANDS.items():
        p = sub.add_parser(name, help=help_line, add_help=strict)
        if command is None or command == name:
            add(p, strict, specs)
    return parser


def parse_arguments(argv: Sequence[str]) -> argparse.Namespace:
    """Parse a command line. For ``params`` and ``simulate`` the component choice (flags and
    the TOML file) is read first, and only the chosen components' parameters become flags:
    one given for a component the run does not use is an error naming that component."""
    command = next((a for a in argv if not a.startswith("-")), None)
    if command not in WITH_COMPONENTS:
        return build_parser(command if command in COMMANDS else "").parse_args(argv)
    every = _component_specs(None)
    first, unknown = build_parser(
        command, strict=False, specs=[s for s, _ in every.values()]
    ).parse_known_args(argv)
    if set(unknown) - {"-h", "--help"}:  # a mistyped flag: say so, with every flag known
        build_parser(command, specs=[s for s, _ in every.values()]).parse_args(argv)
    in_use = _chosen_components(first)
    specs = _component_specs(in_use)
    for name, (_, owner) in every.items():
        if name not in specs and getattr(first, f"param_{name}", None) is not None:
            raise SoftcellError(
                f"{_flag(name)} is a parameter of {owner}, which this run does "
                f"not use (components: {_shown_components(in_use)})"
            )
    return build_parser(command, specs=[s for s, _ in specs.values()]).parse_args(argv)


def _chosen_components(args: argparse.Namespace) -> dict[str, Any]:
    """The components a command line chooses: its TOML file's, then its flags'."""
    base = load_config(args.config) if getattr(args, "config", None) else RunConfig()
    chosen = {**base.components, **_component_flags(args)}
    if any(getattr(args, f, None) for f in ("obstacle", "wall", "param_obstacles")):
        chosen["energy_terms"] = terms_with_obstacles(chosen["energy_terms"])
    boundary = getattr(args, "assembly_boundary", None) or base.assembly.get("boundary")
    if boundary == "walls" and "arena" not in chosen["energy_terms"]:
        chosen["energy_terms"] = [*chosen["energy_terms"], "arena"]
    return chosen


def _component_flags(args: argparse.Namespace) -> dict[str, Any]:
    components: dict[str, Any] = {
        k: v
        for k, v in (
            ("driving_protocol", getattr(args, "protocol", None)),
            ("friction_law", getattr(args, "friction_law", None)),
            ("integrator", getattr(args, "integrator", None)),
        )
        if v
    }
    if getattr(args, "energy_terms", None):
        components["energy_terms"] = [s.strip() for s in args.energy_terms.split(",")]
    return components


def _shown_components(components: dict[str, Any]) -> str:
    return "; ".join(
        f"{kind} {', '.join(v) if isinstance(v, list) else v}" for kind, v in components.items()
    )


def _note(line: str) -> None:
    print(f"softcell: {line}", file=sys.stderr)


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"softcell: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``softcell`` command; returns the exit status (2 for bad input, 130 when
    interrupted)."""
    with warnings.catch_warnings():
        warnings.simplefilter("once", PluginWarning)
        warnings.simplefilter("once", CacheWarning)
        original, warnings.showwarning = warnings.showwarning, _plugin_warning(_show_warning)
        try:
            with stop_signals():  # SIGTERM (batch schedulers) as Ctrl-C
                try:
                    args = parse_arguments(sys.argv[1:] if argv is None else list(argv))
                    status = int(args.func(args))
                    if received():  # swallowed on the way (Python only prints it in a finaliser)
                        raise KeyboardInterrupt(
                            "interrupted as the command ended; what it wrote is complete"
                        )
                    return status
                except KeyboardInterrupt as exc:
                    return _interrupted(exc)
        except SoftcellError as exc:
            print(f"softcell: error: {_one_line(exc)}", file=sys.stderr)
            return 2
        finally:
            warnings.showwarning = original


def _interrupted(exc: KeyboardInterrupt) -> int:
    """Say where a run stopped by Ctrl-C or SIGTERM stood; the exit status (130, 143)."""
    text = str(exc) or "interrupted; rerun the same command to resume"
    if received() == signal.SIGTERM:
        text = f"{text} (SIGTERM)"
    print(f"softcell: {_one_line(text)}", file=sys.stderr)
    return exit_status()


def entry() -> None:
    """The console script: :func:`main`, then an exit that skips the interpreter's teardown
    of compiled code (~0.6 s after a simulation), once output is flushed and exit handlers
    have run."""
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:  # the reader went away (`softcell cache | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 141
    sys.stderr.flush()
    atexit._run_exitfuncs()
    os._exit(code)


def _plugin_warning(show):
    """Plugin warnings as one line each; other warnings as Python shows them."""
    default = warnings.showwarning

    def dispatch(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, PluginWarning | CacheWarning):
            show(message, category, filename, lineno, file, line)
        else:
            default(message, category, filename, lineno, file, line)

    return dispatch


def _one_line(exc: object) -> str:
    return " ".join(str(exc).split())
