"""The verb ``analyze``: MSD, stop/go, fits and theory of simulated or tracked files."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from softcell.cli import flags
from softcell.io.config_file import load_config
from softcell.model.parameters import ParameterSpec


def _add_analyze(p: argparse.ArgumentParser) -> None:
    from softcell.analysis.collective import CROWD_OPTIONS
    from softcell.analysis.options import ANALYSIS_OPTIONS

    p.add_argument(
        "inputs",
        nargs="+",
        type=Path,
        metavar="INPUT",
        help="NetCDF files or directories of one sweep (softcell simulate / track)",
    )
    flags.output(p, "analysis file (.nc)")
    flags.overwrite(p, "replace an existing file that is not a softcell analysis")
    flags.no_verify(p)
    flags.quiet(p)
    p.add_argument(
        "--config",
        type=Path,
        help="TOML file whose [analysis] table sets options (flags override it)",
    )
    flags.parameters(
        p,
        list(ANALYSIS_OPTIONS.values()),
        "analysis options",
        "see docs/analysis.md; stored in the output file",
    )
    flags.parameters(
        p,
        list(CROWD_OPTIONS.values()),
        "assembly options",
        "what many cells do together: clusters, g(r), Voronoi (docs/analysis.md); an error "
        "for a file of one cell",
    )
    flags.parameters(
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
    ds = open_inputs(args.inputs, chunks={}, verify=args.verify)  # one point at a time
    try:
        result = analyze(ds, options, progress=not args.quiet)
    except (OSError, RuntimeError) as exc:  # netCDF's "HDF error" names no file
        raise read_failure(args.inputs, exc) from None
    path = write_dataset(result, args.output)
    print(f"analysis of {_describe(ds)} written to {path}")
    return 0


def _describe(ds: Any) -> str:
    swept = [d for d in ds["cell_x"].dims if d not in ("realization", "time", "cell")]
    points = " x ".join(f"{ds.sizes[d]} {d}" for d in swept)
    cells = f" of {ds.sizes['cell']} cells" if "cell" in ds.dims else ""
    return f"{ds.sizes['realization']} realization(s){cells}" + (f" at {points}" if points else "")


#: The verbs of this module: the one-line help of each, and what adds its flags.
VERBS = {
    "analyze": (
        "MSD, stop/go, fits and theory of simulated or tracked files, as one NetCDF file",
        _add_analyze,
    ),
}
