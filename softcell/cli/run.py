"""The verbs of the model and its runs: ``plugins``, ``params``, ``simulate`` and ``cache``."""

from __future__ import annotations

import argparse
import math
import os
from typing import Any

from softcell.cli import flags
from softcell.errors import SoftcellError
from softcell.model.configuration import (
    RunConfig,
    assembly_of,
    bots_of,
    with_assembly_defaults,
    with_obstacle_term,
)
from softcell.model.obstacle_layout import check_clear_of_start
from softcell.model.parameters import MODEL_PARAMETERS, ParameterSpec, expand_sweep
from softcell.settings import CHECKPOINT_EVERY


def _add_plugins(p: argparse.ArgumentParser) -> None:
    p.set_defaults(func=_cmd_plugins)


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


def _add_params(p: argparse.ArgumentParser) -> None:
    flags.config_file(p)
    flags.components(p)
    flags.assembly(p)
    flags.bots(p)
    flags.parameters(p, list(MODEL_PARAMETERS.values()))
    flags.component_parameters(p, [spec for spec, _ in _component_specs(None).values()])
    p.set_defaults(func=_cmd_params, help_filter=_hide_unused)


def _cmd_params(args: argparse.Namespace) -> int:
    from softcell.analysis.collective import split_crowd_options
    from softcell.analysis.detector import split_options
    from softcell.analysis.options import analysis_options
    from softcell.components.registry import check_in_use, check_point, default_registry
    from softcell.model.limits import check_realizations, check_run, check_seed

    registry = default_registry()
    config = with_assembly_defaults(_request(args))
    config.check_components(registry)
    check_in_use(config.parameters, registry, _in_use(config))
    # the checks simulate and analyze make of the [run] and [analysis] tables
    check_realizations(config.run.get("realizations", 1))
    check_seed(config.run.get("seed", 0))
    analysis_options(split_options(split_crowd_options(config.analysis)[1], registry)[0])
    in_use = _in_use(config)
    points = expand_sweep(config.parameters, list(registry.parameter_specs(in_use).values()))
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


def _add_simulate(p: argparse.ArgumentParser) -> None:
    flags.config_file(p)
    flags.output(p, "directory for the files, one per (parameter point, realization)")
    p.add_argument("--realizations", type=int, help="realizations per parameter point")
    flags.seed(p, "root seed of every random stream (default 0)", default=None)
    flags.workers(
        p, scheduler=True, help="local worker processes (default 1; more: a local dask cluster)"
    )
    flags.components(p)
    p.add_argument("--free-bot", action="store_true", help="no membrane: the free bot")
    flags.assembly(p)
    flags.bots(p)
    flags.overwrite(
        p,
        "recompute files in OUT made with other settings (and remove "
        "simulation files that are no part of this request) instead of "
        "stopping",
    )
    flags.quiet(p)
    p.add_argument(
        "--checkpoint-every",
        type=float,
        default=CHECKPOINT_EVERY,
        metavar="SECONDS",
        help="wall seconds between checkpoints of a running realization "
        f"(default {CHECKPOINT_EVERY:g}); a killed run resumes from the last one",
    )
    flags.parameters(p, list(MODEL_PARAMETERS.values()))
    flags.component_parameters(p, [spec for spec, _ in _component_specs(None).values()])
    p.set_defaults(func=_cmd_simulate, help_filter=_hide_unused)


def _cmd_simulate(args: argparse.Namespace) -> int:
    from softcell.runner.ensemble import simulate

    config = _request(args)
    run = config.run
    realizations = (
        args.realizations if args.realizations is not None else run.get("realizations", 1)
    )
    seed = args.seed if args.seed is not None else run.get("seed", 0)
    workers = flags.check_workers(args.workers)
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
        workers=workers,
        scheduler=args.scheduler,
        membrane=not args.free_bot,
        overwrite=args.overwrite,
        log=flags.note,
        progress=not args.quiet,
        checkpoint_every=args.checkpoint_every,
    )
    print(f"{len(paths)} files in {args.output}")
    return 0


def _request(args: argparse.Namespace) -> RunConfig:
    """The run a command line asks for, with the obstacles' energy term when it places
    obstacles; a flag of a parameter of a component the run does not use is refused, naming
    that component."""
    config = with_obstacle_term(flags.run_config(args))
    in_use = _in_use(config)
    used = _component_specs(in_use)
    for name, (_, owner) in _component_specs(None).items():
        if name not in used and getattr(args, f"param_{name}", None) is not None:
            raise SoftcellError(
                f"{flags.flag(name)} is a parameter of {owner}, which this run does "
                f"not use (components: {_shown_components(in_use)})"
            )
    return config


def _in_use(config: RunConfig) -> dict[str, Any]:
    """The components ``config`` uses: its own, the assembly's terms (an arena's walls) and,
    for many cells, the assembly's pair terms."""
    in_use = dict(with_assembly_defaults(config).components)
    if config.assembly:
        in_use["assembly"] = assembly_of(config).as_dict()
    several = bots_of(config)
    if several is not None:
        in_use["bots"] = several.as_dict()
    return in_use


def _hide_unused(parser: argparse.ArgumentParser, namespace: argparse.Namespace) -> None:
    """Leave out of the help the parameters of the components that the flags before ``-h``
    (and the configuration file) do not choose."""
    try:
        in_use = _in_use(with_obstacle_term(flags.run_config(namespace)))
    except SoftcellError:  # the help is still worth showing, with every parameter
        return
    used = _component_specs(in_use)
    for action in parser._actions:
        name = action.dest.removeprefix("param_")
        if action.dest.startswith("param_") and name not in MODEL_PARAMETERS and name not in used:
            action.help = argparse.SUPPRESS


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


def _shown_components(components: dict[str, Any]) -> str:
    def shown(kind: str, v: Any) -> str:
        if isinstance(v, dict):  # the settings of an assembly or of several bots
            v = ", ".join(f"{k} {', '.join(map(str, x)) if isinstance(x, list) else x}"
                          for k, x in v.items())  # fmt: skip
            return f"{kind} ({v})"
        return f"{kind} {', '.join(v) if isinstance(v, list) else v}"

    return "; ".join(shown(kind, v) for kind, v in components.items())


def _add_cache(p: argparse.ArgumentParser) -> None:
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
        "or Python version made (never read again), and the damaged ones",
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
    damaged = sum(bool(e.damaged) for e in found)
    print(
        f"size: {total / 2**20:.1f} MiB in {len(found)} entries ({stale} stale: made by "
        f"another softcell build or numba, numpy, Python version; {damaged} damaged: a file "
        "does not match its checksum, rebuilt when next used; 'softcell cache clear "
        "--stale' removes both)"
    )
    strangers = compiled.foreign(root)
    if strangers:
        print(
            f"not a cache: {len(strangers)} item(s) softcell did not make "
            f"(e.g. {strangers[0].name}); 'cache clear' refuses this folder"
        )
    for entry in found:
        mark = ("  stale" if entry.stale else "") + (
            f"  damaged ({entry.damaged})" if entry.damaged else ""
        )
        print(
            f"    {entry.name}  {entry.size / 2**10:.0f} KiB  {entry.created}{mark}  "
            f"{entry.description}"
        )
    return 0


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "plugins": ("list every component by kind, with origin and parameters", _add_plugins),
    "params": ("validate and print the parameters of a configuration", _add_params),
    "simulate": ("simulate an ensemble: parameter points x realizations", _add_simulate),
    "cache": (
        "the compiled-model cache: where it is, what it holds; 'cache clear' empties it",
        _add_cache,
    ),
}
