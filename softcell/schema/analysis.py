"""The analysis Dataset schema, as code: what :func:`softcell.analyze` writes, for one cell and
for an assembly, and which quantities carry values per realization and errors across them."""

from __future__ import annotations

import numpy as np

from softcell.schema.simulation import REGIMES, STOPGO_FLAGS, STOPGO_MEANINGS, VariableSpec

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
