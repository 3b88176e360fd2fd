"""The simulation Dataset schema, as code (ARCHITECTURE.md, "The data model").

One simulation, or one tracked video, is one :class:`xarray.Dataset` with dims
``realization``, ``time`` and ``node``. A sweep adds one leading dimension per swept
parameter (e.g. ``radius``). :func:`validate` names every missing or malformed variable or
attribute. :func:`simulation_dataset` builds a conforming Dataset from arrays.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.errors import SchemaError

CONVENTIONS = "CF-1.8"

#: bot_phase flag values and meanings (CF flag_values / flag_meanings).
PHASE_UNKNOWN, PHASE_TUMBLE, PHASE_RUN = -1, 0, 1
PHASE_FLAGS = np.array([PHASE_UNKNOWN, PHASE_TUMBLE, PHASE_RUN], dtype=np.int8)
PHASE_MEANINGS = "unknown tumble run"

#: Stop/go labels of a speed series (the analysis' ``stopgo`` variable, CF flags).
STOPGO_UNKNOWN, STOP, GO = -1, 0, 1
STOPGO_FLAGS = np.array([STOPGO_UNKNOWN, STOP, GO], dtype=np.int8)
STOPGO_MEANINGS = "unknown stop go"

#: Coupling regimes of a parameter point (the analysis' ``regime`` variable, CF flags).
REGIMES = {"unknown": -1, "coupled": 0, "intermediate": 1, "decoupled": 2}
REGIME_NAMES = {code: name for name, code in REGIMES.items()}

#: tracking_flag values of a tracked video, by meaning.
TRACKING_FLAGS = {"ok": 0, "membrane_lost": 1, "bot_lost": 2, "both_lost": 3}


@dataclass(frozen=True)
class VariableSpec:
    """One variable of the schema: its dims, dtype kind ('f' float, 'i' integer), CF attributes."""

    name: str
    dims: tuple[str, ...]
    kind: str
    units: str
    long_name: str
    attrs: Mapping[str, Any] = field(default_factory=dict)

    def cf_attrs(self) -> dict[str, Any]:
        return {"units": self.units, "long_name": self.long_name, **self.attrs}


COORDINATES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec("realization", ("realization",), "i", "1", "realization index"),
        VariableSpec("time", ("time",), "f", "s", "time since the start of the record"),
        VariableSpec("node", ("node",), "i", "1", "membrane node index"),
    )
}

#: The coordinate of an assembly's cells: a file of many cells has the variables of one
#: with ``cell`` after its time dim ((realization, time, cell, node) for the membrane).
CELL_COORDINATE = VariableSpec("cell", ("cell",), "i", "1", "cell index in the assembly")

#: An assembly's domain: the side of its square box (NaN for the open plane), with its
#: boundary (open, walls, periodic) as an attribute; and where each cell started (both per
#: realization, so that the files of a sweep concatenate along it).
DOMAIN_VARIABLES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec(
            "domain_box",
            ("realization",),
            "f",
            "cm",
            "side of the square box (NaN: the open plane)",
        ),
        VariableSpec(
            "cell_start_x", ("realization", "cell"), "f", "cm", "cell starting center x coordinate"
        ),
        VariableSpec(
            "cell_start_y", ("realization", "cell"), "f", "cm", "cell starting center y coordinate"
        ),
    )
}


def with_cell(dims: tuple[str, ...]) -> tuple[str, ...]:
    """``dims`` of a one-cell variable as an assembly stores it: ``cell`` after the time
    dim (``time`` or ``fine_time``); dims without a time dim are unchanged."""
    for i, d in enumerate(dims):
        if d in ("time", "fine_time"):
            return (*dims[: i + 1], "cell", *dims[i + 1 :])
    return dims


VARIABLES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec(
            "membrane_x", ("realization", "time", "node"), "f", "cm", "membrane point x coordinate"
        ),
        VariableSpec(
            "membrane_y", ("realization", "time", "node"), "f", "cm", "membrane point y coordinate"
        ),
        VariableSpec(
            "cell_x", ("realization", "time"), "f", "cm", "cell geometric center x coordinate"
        ),
        VariableSpec(
            "cell_y", ("realization", "time"), "f", "cm", "cell geometric center y coordinate"
        ),
        VariableSpec("bot_x", ("realization", "time"), "f", "cm", "bot center x coordinate"),
        VariableSpec("bot_y", ("realization", "time"), "f", "cm", "bot center y coordinate"),
        VariableSpec(
            "bot_angle", ("realization", "time"), "f", "rad", "bot heading (major axis direction)"
        ),
        VariableSpec(
            "bot_phase",
            ("realization", "time"),
            "i",
            "1",
            "bot driving phase",
            {"flag_values": PHASE_FLAGS, "flag_meanings": PHASE_MEANINGS},
        ),
    )
}

#: The bodies' fine record (optional): the cell's centre and the bot's pose at every
#: ``sample_every`` over the whole run, on their own time axis ``fine_time``, so that
#: analyses of the bodies (the MSD at every lag) use one record (docs/model.md §6). Absent
#: from tracked videos and from files of softcell before 0.3.
#: When a protocol's state events ended phases (optional: only protocols with events).
EVENT_COORDINATE = VariableSpec("event", ("event",), "i", "1", "index of a state event")
EVENT_TIME = VariableSpec(
    "event_time",
    ("realization", "event"),
    "f",
    "s",
    "time at which a state event of the driving protocol ended a phase (NaN: no more events)",
)

FINE_COORDINATE = VariableSpec(
    "fine_time", ("fine_time",), "f", "s", "time of the bodies' fine record"
)
FINE_VARIABLES: dict[str, VariableSpec] = {
    f"{name}_fine": VariableSpec(
        f"{name}_fine",
        ("realization", "fine_time"),
        spec.kind,
        spec.units,
        f"{spec.long_name} (fine record)",
        dict(spec.attrs),
    )
    for name, spec in VARIABLES.items()
    if name.startswith(("cell_", "bot_"))
}

#: Stands for the sweep dims (one per swept parameter, maybe none) in an analysis variable's
#: dims.
SWEEP = "..."

#: What an assembly's analysis adds to the per-cell variables (softcell.analysis.collective):
#: coordinates, then the collective variables, with a sweep's dims in front.
CROWD_COORDINATES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec(
            "crowd_time", ("crowd_time",), "f", "s", "time of the collective statistics' samples"
        ),
        VariableSpec("cluster_size", ("cluster_size",), "i", "1", "cells in a cluster"),
        VariableSpec(
            "pair_distance",
            ("pair_distance",),
            "f",
            "1",
            "distance between cell centres over the cell diameter 2 R, bin center",
        ),
        VariableSpec(
            "area_fraction_bin",
            ("area_fraction_bin",),
            "f",
            "1",
            "local area fraction (cell area over its Voronoi cell's), bin center",
        ),
    )
}
CROWD_VARIABLES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec(
            "polar_order",
            (SWEEP, "realization", "time"),
            "f",
            "1",
            "polar order of the bots' headings, |mean of (cos, sin)| over cells",
        ),
        VariableSpec(
            "largest_cluster",
            (SWEEP, "realization", "crowd_time"),
            "f",
            "1",
            "cells in the largest cluster of cells in contact",
        ),
        VariableSpec(
            "mean_cluster_size",
            (SWEEP, "realization", "crowd_time"),
            "f",
            "1",
            "mean size of the cluster a cell belongs to (sum of s^2 over sum of s)",
        ),
        VariableSpec(
            "cluster_size_fraction",
            (SWEEP, "cluster_size"),
            "f",
            "1",
            "fraction of cells in clusters of this size, pooled over samples and realizations",
        ),
        VariableSpec(
            "pair_correlation",
            (SWEEP, "pair_distance"),
            "f",
            "1",
            "pair correlation g(r) of cell centres, pooled over samples and realizations",
        ),
        VariableSpec(
            "pair_correlation_error",
            (SWEEP, "pair_distance"),
            "f",
            "1",
            "standard error of g(r) across realizations",
        ),
        VariableSpec(
            "local_area_fraction",
            (SWEEP, "realization", "crowd_time", "cell"),
            "f",
            "1",
            "cell area over the area of its Voronoi cell (periodic box)",
        ),
        VariableSpec(
            "shape_index_by_density",
            (SWEEP, "area_fraction_bin"),
            "f",
            "1",
            "mean shape index P / sqrt(A) of cells at this local area fraction",
        ),
        VariableSpec(
            "shape_index_by_density_error",
            (SWEEP, "area_fraction_bin"),
            "f",
            "1",
            "standard error across realizations of the shape index per area-fraction bin",
        ),
        VariableSpec(
            "shape_index_by_density_count",
            (SWEEP, "area_fraction_bin"),
            "i",
            "1",
            "cell samples per area-fraction bin",
        ),
        VariableSpec(
            "neighbour_exchange_rate",
            (SWEEP, "realization"),
            "f",
            "s-1",
            "Voronoi neighbour bonds lost per cell per second between crowd samples",
        ),
    )
}

#: The analysis Dataset's variables, in the order they are written (:func:`analyze` fills
#: them; ``flag_values`` of the two coded variables are the codes above). Over a radius sweep
#: it also holds the scaling-collapse variables along ``collapse_variant``.
ANALYSIS_VARIABLES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec(
            "msd",
            (SWEEP, "body", "lag"),
            "f",
            "cm2",
            "mean-squared displacement, pooled over realizations",
        ),
        VariableSpec(
            "msd_sem",
            (SWEEP, "body", "lag"),
            "f",
            "cm2",
            "standard error of the MSD across realizations",
        ),
        VariableSpec("msd_pairs", (SWEEP, "body", "lag"), "f", "1", "number of displacement pairs"),
        VariableSpec(
            "msd_realization",
            (SWEEP, "body", "realization", "lag"),
            "f",
            "cm2",
            "mean-squared displacement of each realization",
        ),
        VariableSpec(
            "msd_theory",
            (SWEEP, "body", "lag"),
            "f",
            "cm2",
            "run-and-tumble theory 2 v0_hat^2 (tau <tau_g> - <tau_g>^2 (1 - exp(-tau/<tau_g>)))",
        ),
        VariableSpec(
            "speed",
            (SWEEP, "body", "realization", "time"),
            "f",
            "cm s-1",
            "speed, forward difference within a sampling segment",
        ),
        VariableSpec(
            "stopgo_label",
            (SWEEP, "body", "realization", "time"),
            "i",
            "1",
            "stop/go label",
            {"flag_values": STOPGO_FLAGS, "flag_meanings": STOPGO_MEANINGS},
        ),
        VariableSpec(
            "go_duration",
            (SWEEP, "body", "event"),
            "f",
            "s",
            "duration of a complete go phase, (n - 1) dt",
        ),
        VariableSpec(
            "stop_duration",
            (SWEEP, "body", "event"),
            "f",
            "s",
            "duration of a complete stop phase, (n - 1) dt",
        ),
        VariableSpec(
            "go_pdf",
            (SWEEP, "body", "scaled_duration"),
            "f",
            "1",
            "probability density of go durations over their mean",
        ),
        VariableSpec(
            "stop_pdf",
            (SWEEP, "body", "scaled_duration"),
            "f",
            "1",
            "probability density of stop durations over their mean",
        ),
        VariableSpec(
            "mean_go_duration_shifted",
            (SWEEP, "body", "threshold_shift"),
            "f",
            "s",
            "mean go duration with the threshold shifted",
        ),
        VariableSpec(
            "mean_stop_duration_shifted",
            (SWEEP, "body", "threshold_shift"),
            "f",
            "s",
            "mean stop duration with the threshold shifted",
        ),
        VariableSpec(
            "mean_go_duration_interval",
            (SWEEP, "body", "detection_interval"),
            "f",
            "s",
            "mean go duration with the speed measured over a longer interval",
        ),
        VariableSpec(
            "mean_stop_duration_interval",
            (SWEEP, "body", "detection_interval"),
            "f",
            "s",
            "mean stop duration with the speed measured over a longer interval",
        ),
        VariableSpec(
            "mean_go_duration_systematic",
            (SWEEP, "body"),
            "f",
            "s",
            "systematic uncertainty of the mean go duration from the detector",
            {
                "definition": "the largest change of the mean when the threshold moves by "
                "-/+ threshold_shift or the speed is measured over the interval nearest "
                "1/30 s (the experiments' frame rate)"
            },
        ),
        VariableSpec(
            "mean_stop_duration_systematic",
            (SWEEP, "body"),
            "f",
            "s",
            "systematic uncertainty of the mean stop duration from the detector",
            {
                "definition": "the largest change of the mean when the threshold moves by "
                "-/+ threshold_shift or the speed is measured over the interval nearest "
                "1/30 s (the experiments' frame rate)"
            },
        ),
        VariableSpec(
            "go_duration_second_moment",
            (SWEEP, "body"),
            "f",
            "s2",
            "mean squared go duration <tau_g^2>",
        ),
        VariableSpec(
            "msd_slope_affine",
            (SWEEP, "body"),
            "f",
            "cm2 s-1",
            "D hat of the fit MSD = D hat tau + b at long lags (unbiased by the MSD's offset)",
        ),
        VariableSpec(
            "msd_slope_renewal",
            (SWEEP, "body"),
            "f",
            "cm2 s-1",
            "renewal theory's D hat = v0_hat^2 <tau_g^2> / <tau_g>",
        ),
        VariableSpec(
            "mean_speed", (SWEEP, "body"), "f", "cm s-1", "mean speed (the stop/go record)"
        ),
        VariableSpec(
            "v0_hat",
            (SWEEP, "body"),
            "f",
            "cm s-1",
            "root mean square speed sqrt(mean^2 + variance), stops included (theory's v0 hat)",
        ),
        VariableSpec("mean_go_duration", (SWEEP, "body"), "f", "s", "mean go duration <tau_g>"),
        VariableSpec("mean_stop_duration", (SWEEP, "body"), "f", "s", "mean stop duration <tau_s>"),
        VariableSpec(
            "go_fraction", (SWEEP, "body"), "f", "1", "fraction of labelled samples that are go"
        ),
        VariableSpec(
            "go_ks_statistic",
            (SWEEP, "body"),
            "f",
            "1",
            "Kolmogorov-Smirnov distance of t/<t> (go) to exp(-t')",
        ),
        VariableSpec(
            "go_ks_pvalue",
            (SWEEP, "body"),
            "f",
            "1",
            "p-value of go_ks_statistic (fully specified law)",
        ),
        VariableSpec(
            "stop_ks_statistic",
            (SWEEP, "body"),
            "f",
            "1",
            "Kolmogorov-Smirnov distance of t/<t> (stop) to exp(-t')",
        ),
        VariableSpec(
            "stop_ks_pvalue",
            (SWEEP, "body"),
            "f",
            "1",
            "p-value of stop_ks_statistic (fully specified law)",
        ),
        VariableSpec(
            "ballistic_velocity",
            (SWEEP, "body"),
            "f",
            "cm s-1",
            "v of the fit MSD = v^2 tau^2 at short lags",
        ),
        VariableSpec(
            "msd_slope",
            (SWEEP, "body"),
            "f",
            "cm2 s-1",
            "D hat of the fit MSD = D hat tau at long lags (the paper's D hat)",
        ),
        VariableSpec(
            "crossover_time",
            (SWEEP, "body"),
            "f",
            "s",
            "lag where the ballistic and diffusive fits meet",
        ),
        VariableSpec(
            "confined_diffusion_coefficient",
            (SWEEP, "body"),
            "f",
            "cm2 s-1",
            "D of the confined-square MSD fit (MSD -> 4 D tau)",
        ),
        VariableSpec(
            "ballistic_window_end", (SWEEP, "body"), "f", "s", "longest lag of the ballistic fit"
        ),
        VariableSpec(
            "diffusive_window_start", (SWEEP, "body"), "f", "s", "shortest lag of the diffusive fit"
        ),
        VariableSpec("go_events", (SWEEP, "body"), "i", "1", "number of complete go phases"),
        VariableSpec("stop_events", (SWEEP, "body"), "i", "1", "number of complete stop phases"),
        VariableSpec(
            "diffusion_coefficient",
            (SWEEP, "body"),
            "f",
            "cm2 s-1",
            "msd_slope / 4 (MSD -> 4 D tau convention)",
        ),
        VariableSpec(
            "msd_slope_theory",
            (SWEEP, "body"),
            "f",
            "cm2 s-1",
            "theory's D hat = 2 v0_hat^2 <tau_g>",
        ),
        VariableSpec(
            "msd_theory_renewal",
            (SWEEP, "body", "lag"),
            "f",
            "cm2",
            "renewal theory's MSD: measured go durations, each go phase in a new direction",
        ),
        VariableSpec(
            "velocity_autocorrelation",
            (SWEEP, "body", "correlation_lag"),
            "f",
            "cm2 s-2",
            "velocity autocorrelation <v(t).v(t+tau)>, pooled over realizations",
        ),
        VariableSpec(
            "velocity_autocorrelation_realization",
            (SWEEP, "body", "realization", "correlation_lag"),
            "f",
            "cm2 s-2",
            "velocity autocorrelation of each realization",
        ),
        VariableSpec(
            "velocity_autocorrelation_renewal",
            (SWEEP, "body", "correlation_lag"),
            "f",
            "cm2 s-2",
            "renewal theory's velocity autocorrelation on the same grid",
        ),
        VariableSpec(
            "green_kubo_slope",
            (SWEEP, "body"),
            "f",
            "cm2 s-1",
            "D hat from the velocity autocorrelation: dt (C(0) + 2 sum C(k dt))",
        ),
        VariableSpec(
            "go_turn_cosine",
            (SWEEP, "body"),
            "f",
            "1",
            "mean cosine of the angle between consecutive go displacements",
        ),
        VariableSpec(
            "go_turn_pairs",
            (SWEEP, "body", "realization"),
            "i",
            "1",
            "number of consecutive go-phase pairs in the finest segment",
        ),
        VariableSpec(
            "go_displacement_mean", (SWEEP, "body"), "f", "cm", "mean length of a go displacement"
        ),
        VariableSpec(
            "go_displacement_mean_square",
            (SWEEP, "body"),
            "f",
            "cm2",
            "mean squared length of a go displacement",
        ),
        VariableSpec(
            "ipr",
            (SWEEP, "realization", "time"),
            "f",
            "1",
            "shape index P / sqrt(A) of the membrane",
        ),
        VariableSpec("ipr_mean", (SWEEP,), "f", "1", "mean shape index"),
        VariableSpec("gc_distance", (SWEEP,), "f", "cm", "mean distance between bot and cell GCs"),
        VariableSpec("gc_distance_ratio", (SWEEP,), "f", "1", "gc_distance / R"),
        VariableSpec(
            "regime",
            (SWEEP,),
            "i",
            "1",
            "dynamical regime from gc_distance_ratio",
            {
                "flag_values": np.array(list(REGIMES.values()), dtype=np.int8),
                "flag_meanings": " ".join(REGIMES),
            },
        ),
    )
}

#: Quantities with a value per realization (``NAME_realization``) and a standard error
#: across realizations (``NAME_error``): per body, then per point.
BODY_QUANTITIES = (
    "mean_go_duration",
    "mean_stop_duration",
    "go_duration_second_moment",
    "mean_speed",
    "v0_hat",
    "go_fraction",
    "ballistic_velocity",
    "msd_slope",
    "msd_slope_affine",
    "diffusion_coefficient",
    "crossover_time",
    "confined_diffusion_coefficient",
    "msd_slope_theory",
    "msd_slope_renewal",
    "green_kubo_slope",
    "go_turn_cosine",
)
POINT_QUANTITIES = ("ipr_mean", "gc_distance", "gc_distance_ratio")
#: Per-realization counts behind the pooled quantities.
REALIZATION_COUNTS = {
    "go_events": "number of complete go phases",
    "stop_events": "number of complete stop phases",
    "speed_samples": "number of speed samples",
    "labelled_samples": "number of samples with a stop/go label",
}


def _with_errors(variables: dict[str, VariableSpec]) -> dict[str, VariableSpec]:
    """``variables`` and, for each quantity, its per-realization values and its error."""
    out = dict(variables)
    for name in (*BODY_QUANTITIES, *POINT_QUANTITIES):
        base = variables[name]
        out[f"{name}_realization"] = VariableSpec(
            f"{name}_realization",
            (*base.dims, "realization"),
            base.kind,
            base.units,
            f"{base.long_name}, per realization",
        )
        out[f"{name}_error"] = VariableSpec(
            f"{name}_error",
            base.dims,
            base.kind,
            base.units,
            f"standard error of {name} across realizations",
        )
    for name, long_name in REALIZATION_COUNTS.items():
        out[f"{name}_realization"] = VariableSpec(
            f"{name}_realization",
            (SWEEP, "body", "realization"),
            "i",
            "1",
            f"{long_name}, per realization",
        )
    return out


ANALYSIS_VARIABLES = _with_errors(ANALYSIS_VARIABLES)

#: Global attributes every file carries, and those a simulation adds.
REQUIRED_ATTRS = ("Conventions", "title", "source", "softcell_version", "softcell_origin")
SIMULATION_ATTRS = (
    "softcell_parameters",
    "softcell_parameter_units",
    "softcell_seed",
    "softcell_components",
)
ORIGINS = ("simulation", "tracking")


def problems(ds: xr.Dataset) -> list[str]:
    """Every way ``ds`` departs from the schema (empty list: it conforms)."""
    found: list[str] = []
    for spec in (*COORDINATES.values(), *VARIABLES.values()):
        found.extend(_variable_problems(ds, spec))
    found.extend(_fine_problems(ds))
    if "event" in ds.dims or EVENT_TIME.name in ds.variables:
        for spec in (EVENT_COORDINATE, EVENT_TIME):
            found.extend(_variable_problems(ds, spec))
    if "cell" in ds.dims:
        for spec in (CELL_COORDINATE, *DOMAIN_VARIABLES.values()):
            found.extend(_variable_problems(ds, spec))
    if "time" in ds.coords and ds.sizes.get("time", 0) > 1:
        if not bool(np.all(np.diff(ds["time"].values) > 0)):
            found.append("time: values must increase strictly")
    found.extend(
        f"{name}: values outside the flag values {PHASE_FLAGS.tolist()}"
        for name in ("bot_phase", "bot_phase_fine")
        if name in ds.variables and not np.isin(np.unique(ds[name].values), PHASE_FLAGS).all()
    )
    return found + _attribute_problems(ds)


def _attribute_problems(ds: xr.Dataset) -> list[str]:
    """How the global attributes depart from the schema."""
    found = [f"global attribute {n!r} is missing" for n in REQUIRED_ATTRS if n not in ds.attrs]
    if ds.attrs.get("Conventions", CONVENTIONS) != CONVENTIONS:
        found.append(f"global attribute Conventions must be {CONVENTIONS!r}")
    origin = ds.attrs.get("softcell_origin")
    if origin is not None and origin not in ORIGINS:
        found.append(f"global attribute softcell_origin must be one of {ORIGINS}, not {origin!r}")
    if origin == "simulation":
        for name in SIMULATION_ATTRS:
            if name not in ds.attrs:
                found.append(f"global attribute {name!r} is missing (required for simulations)")
    return found


def _fine_problems(ds: xr.Dataset) -> list[str]:
    """How the bodies' fine record departs from the schema: optional, but all or nothing."""
    if not any(n in ds.variables for n in (FINE_COORDINATE.name, *FINE_VARIABLES)):
        return []
    found = []
    for spec in (FINE_COORDINATE, *FINE_VARIABLES.values()):
        found.extend(_variable_problems(ds, spec))
    if "fine_time" in ds.coords and ds.sizes.get("fine_time", 0) > 1:
        if not bool(np.all(np.diff(ds["fine_time"].values) > 0)):
            found.append("fine_time: values must increase strictly")
    return found


def _variable_problems(ds: xr.Dataset, spec: VariableSpec) -> list[str]:
    if spec.name not in ds.variables:
        return [f"{spec.name}: missing"]
    var = ds[spec.name]
    found = []
    # Sweeps add leading dims (one per swept parameter); the schema's dims must come last
    # (with ``cell`` after the time dim in an assembly's file).
    per_cell = spec.name in VARIABLES or spec.name in FINE_VARIABLES
    expected = with_cell(spec.dims) if per_cell and "cell" in ds.dims else spec.dims
    if var.dims[len(var.dims) - len(expected) :] != expected:
        found.append(f"{spec.name}: dims {var.dims}, expected (..., {', '.join(expected)})")
    if var.dtype.kind not in (spec.kind, "u" if spec.kind == "i" else spec.kind):
        found.append(
            f"{spec.name}: dtype {var.dtype}, expected "
            + ("floating point" if spec.kind == "f" else "integer")
        )
    for attr in ("units", "long_name"):
        if attr not in var.attrs:
            found.append(f"{spec.name}: attribute {attr!r} missing")
    if var.attrs.get("units", spec.units) != spec.units:
        found.append(f"{spec.name}: units {var.attrs['units']!r}, expected {spec.units!r}")
    for attr, value in spec.attrs.items():
        if not np.array_equal(np.asarray(var.attrs.get(attr)), np.asarray(value)):
            found.append(f"{spec.name}: attribute {attr!r} must be {value!r}")
    return found


def validate(ds: xr.Dataset) -> xr.Dataset:
    """Return ``ds`` unchanged if it follows the schema (which includes each variable's
    CF ``units``: cm, s, rad, or 1).

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation or tracked Dataset.

    Raises
    ------
    SchemaError
        Naming every missing or malformed variable and attribute.
    """
    found = problems(ds)
    if found:
        raise SchemaError(found)
    return ds


def global_attrs(origin: str, title: str, source: str, **extra: Any) -> dict[str, Any]:
    """The global attributes every softcell file starts with (no timestamps: same inputs,
    same bytes)."""
    return {
        "Conventions": CONVENTIONS,
        "title": title,
        "source": source,
        "softcell_version": __version__,
        "softcell_origin": origin,
        **extra,
    }


def simulation_dataset(
    time: np.ndarray,
    realization: np.ndarray,
    *,
    membrane_x: np.ndarray,
    membrane_y: np.ndarray,
    bot_x: np.ndarray,
    bot_y: np.ndarray,
    bot_angle: np.ndarray,
    bot_phase: np.ndarray,
    parameters: Any,
    seed: int,
    components: Mapping[str, Any],
    cell_x: np.ndarray | None = None,
    cell_y: np.ndarray | None = None,
    extra_attrs: Mapping[str, Any] | None = None,
    scalar_coords: Sequence[str] = ("radius",),
    fine: Mapping[str, np.ndarray] | None = None,
    domain: Mapping[str, Any] | None = None,
    events: np.ndarray | None = None,
) -> xr.Dataset:
    """Build a simulation Dataset that follows the schema.

    Parameters
    ----------
    time : float64[T]
        Sample times (s).
    realization : int[R]
        Realization indices.
    membrane_x, membrane_y : float64[R, T, M]
        Membrane points (cm).
    bot_x, bot_y, bot_angle : float64[R, T]
        Bot center (cm) and heading (rad).
    bot_phase : int8[R, T]
        Driving phase code (0 tumble, 1 run, -1 unknown).
    parameters : Parameters
        The run's parameters (stored with units in the attributes).
    seed : int
        Root seed of the run.
    components : mapping
        Component names by kind, e.g. ``{"energy_terms": [...], "integrator": "..."}``.
    cell_x, cell_y : float64[R, T], optional
        Geometric center (cm); by default the algebraic mean of the membrane points.
    scalar_coords : sequence of str
        Parameters also stored as scalar coordinates with their units and long names (the
        swept ones: a sweep's files then combine with plain xarray along them).
    fine : mapping, optional
        The bodies' fine record: ``fine_time`` (float64[F], s) and every variable of
        :data:`FINE_VARIABLES` ([R, F]: ``cell_x_fine`` ... in cm, ``bot_angle_fine`` in rad,
        ``bot_phase_fine`` int8).
    domain : mapping, optional
        For an assembly of cells: ``box`` (cm, NaN for the open plane), ``boundary`` (str)
        and ``start_x``, ``start_y`` (float64[C], cm); every variable then has a ``cell`` dim
        after its time dim ([R, T, C, node] for the membrane, [R, T, C] for the bodies).
    events : float64[R, E], optional
        The times (s) at which the protocol's state events ended phases, NaN-padded
        (``event_time``; only for a protocol with events).
    """
    if cell_x is None:
        cell_x = membrane_x.mean(axis=-1)
    if cell_y is None:
        cell_y = membrane_y.mean(axis=-1)
    arrays = {
        "membrane_x": membrane_x,
        "membrane_y": membrane_y,
        "cell_x": cell_x,
        "cell_y": cell_y,
        "bot_x": bot_x,
        "bot_y": bot_y,
        "bot_angle": bot_angle,
        "bot_phase": np.asarray(bot_phase, dtype=np.int8),
    }
    dims = with_cell if domain is not None else (lambda d: d)
    data_vars = {
        name: (dims(VARIABLES[name].dims), np.asarray(arr), VARIABLES[name].cf_attrs())
        for name, arr in arrays.items()
    }
    n_nodes = np.shape(membrane_x)[-1]
    coords = {
        "realization": (
            "realization",
            np.asarray(realization, dtype=np.int64),
            COORDINATES["realization"].cf_attrs(),
        ),
        "time": ("time", np.asarray(time, dtype=np.float64), COORDINATES["time"].cf_attrs()),
        "node": ("node", np.arange(n_nodes, dtype=np.int64), COORDINATES["node"].cf_attrs()),
    }
    if fine is not None:
        coords["fine_time"] = (
            "fine_time",
            np.asarray(fine["fine_time"], dtype=np.float64),
            FINE_COORDINATE.cf_attrs(),
        )
        for name, spec in FINE_VARIABLES.items():
            values = np.asarray(fine[name])
            if spec.name == "bot_phase_fine":
                values = values.astype(np.int8)
            data_vars[name] = (dims(spec.dims), values, spec.cf_attrs())
    if events is not None:
        events = np.asarray(events, dtype=np.float64)
        coords["event"] = (
            "event",
            np.arange(events.shape[-1], dtype=np.int64),
            EVENT_COORDINATE.cf_attrs(),
        )
        data_vars[EVENT_TIME.name] = (EVENT_TIME.dims, events, EVENT_TIME.cf_attrs())
    if domain is not None:
        cells = len(domain["start_x"])
        coords["cell"] = ("cell", np.arange(cells, dtype=np.int64), CELL_COORDINATE.cf_attrs())
        for name, value, extra in (  # per realization: a sweep's files concatenate along it
            ("domain_box", [domain["box"]], {"boundary": domain["boundary"]}),
            ("cell_start_x", [domain["start_x"]], {}),
            ("cell_start_y", [domain["start_y"]], {}),
        ):
            spec = DOMAIN_VARIABLES[name]
            data_vars[name] = (
                spec.dims,
                np.asarray(value, np.float64),
                {**spec.cf_attrs(), **extra},
            )
    for name in dict.fromkeys(scalar_coords):
        spec = parameters.specs[name]
        coords[name] = ((), parameters[name], {"units": spec.unit, "long_name": spec.long_name})
    attrs = global_attrs(
        "simulation",
        "soft robotic cell simulation",
        f"softcell {__version__} simulation",
        softcell_seed=int(seed),
        softcell_components=json.dumps(dict(components), sort_keys=True),
        **parameters.to_attrs(),
        **dict(extra_attrs or {}),
    )
    return validate(xr.Dataset(data_vars, coords, attrs))
