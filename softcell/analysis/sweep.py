"""Dataset in, Dataset out: everything the paper computes from trajectories (docs/model.md §6).

:func:`analyze` takes a simulation or tracked Dataset (dims ``[sweep dims...,] realization,
time[, node]``) and returns the analysis Dataset: for each body (``cell``, ``bot``) and each
sweep point, the MSD against ``lag`` with its standard error, per-sample speed and stop/go
labels, stop and go durations along ``event``, their means, PDFs of t/<t> and fit to
exp(-t'), the shift of the means under a moved threshold, ballistic / diffusive /
confined-square fits, the run-and-tumble theory, the shape index IPR, the bot-cell distance and
the regime; over a ``radius`` sweep, the scaling-collapse variants with a metric each.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.analysis import correlation, fits, stopgo, uncertainty
from softcell.analysis.detector import DetectorChoice, choose_detector, split_options
from softcell.analysis.msd import log_lags, msd_sums
from softcell.analysis.options import analysis_options, options_attrs
from softcell.analysis.series import (
    decimation,
    segment_index,
    segments,
    shape_index,
    speed,
)
from softcell.components.registry import Registry, default_registry
from softcell.errors import AnalysisWarning, ConfigError, SoftcellError
from softcell.model.parameters import parameter_attrs
from softcell.schema import ANALYSIS_VARIABLES, REGIMES, SWEEP

BODIES = ("cell", "bot")
REQUIRED = ("cell_x", "cell_y", "bot_x", "bot_y", "membrane_x", "membrane_y")
#: The bodies' fine record the MSD uses where a file has it.
FINE_BODY_VARIABLES = ("cell_x_fine", "cell_y_fine", "bot_x_fine", "bot_y_fine")
#: Scaling-collapse variants (docs/model.md §6): MSD * R^a against lag * R^b.
COLLAPSE_VARIANTS = ((1 / 3, 1.0), (1 / 3, -1.0), (-1 / 3, 1.0), (-1 / 3, -1.0))
COLLAPSE_GRID = 50


def require(ds: xr.Dataset, names: tuple[str, ...] = REQUIRED) -> None:
    """Raise one SoftcellError naming every variable of ``names`` that ``ds`` lacks."""
    missing = [n for n in ("time", "realization", *names) if n not in ds.variables]
    if missing:
        raise SoftcellError(
            "the analysis needs variable(s) missing from the dataset: " + ", ".join(missing)
        )


def sweep_dims(ds: xr.Dataset) -> list[str]:
    """The dims of ``cell_x`` before (realization, time): one per swept parameter."""
    return [d for d in ds["cell_x"].dims if d not in ("realization", "time")]


def _points(ds: xr.Dataset, lead: list[str]) -> list[dict[str, int]]:
    sizes = [ds.sizes[d] for d in lead]
    return [dict(zip(lead, idx, strict=True)) for idx in np.ndindex(*sizes)] if lead else [{}]


def _radius(ds: xr.Dataset, point: Mapping[str, int]) -> float:
    if "radius" in point:
        return float(ds["radius"].values[point["radius"]])
    params = json.loads(ds.attrs.get("softcell_parameters", "{}"))
    value = params.get("radius")
    return float(value) if isinstance(value, (int, float)) else np.nan


class LagPlan:
    """Which samples give which lags: short lags (< short_lag_max) from the finest segment,
    longer lags from the whole record decimated to the coarsest interval (docs/model.md §6)."""

    def __init__(self, time: np.ndarray, options: Mapping[str, Any]) -> None:
        segs = segments(time)
        if not segs or time.size < 2:
            raise SoftcellError(
                f"the record after the discard of {options['discard']:g} s has "
                f"{time.size} sample(s); the analysis needs at least 2"
            )
        self.fine = max(segs, key=lambda s: (-s.interval, s.last - s.first))
        self.coarse_interval = max(s.interval for s in segs)
        per_decade = int(options["lags_per_decade"])
        fraction = float(options["max_lag_fraction"])
        uniform = len(segs) == 1
        if uniform:
            self.fine_lags = log_lags(1, int(fraction * (time.size - 1)), per_decade)
            self.grid = np.zeros(0, dtype=np.int64)
            self.coarse_lags = np.zeros(0, dtype=np.int64)
        else:
            short = float(options["short_lag_max"])
            last_short = int(np.ceil(short / self.fine.interval - 1e-9)) - 1
            last_short = min(last_short, self.fine.last - self.fine.first)
            self.fine_lags = log_lags(1, last_short, per_decade)
            self.grid = decimation(time, self.coarse_interval, float(time[0]))
            first_long = int(np.ceil(short / self.coarse_interval - 1e-9))
            self.coarse_lags = log_lags(
                first_long, int(fraction * (self.grid.size - 1)), per_decade
            )
        self.lag = np.concatenate(
            [self.fine_lags * self.fine.interval, self.coarse_lags * self.coarse_interval]
        )

    def sums(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Squared-displacement sums and pair counts at ``self.lag`` for one trajectory."""
        r = np.stack([x, y], axis=-1)
        s, c = msd_sums(r[self.fine.samples])
        parts_s, parts_c = [s[self.fine_lags]], [c[self.fine_lags]]
        if self.coarse_lags.size:
            rg = np.where((self.grid >= 0)[:, None], r[np.maximum(self.grid, 0)], np.nan)
            s, c = msd_sums(rg)
            parts_s.append(s[self.coarse_lags])
            parts_c.append(c[self.coarse_lags])
        return np.concatenate(parts_s), np.concatenate(parts_c)


def _ensemble_msd(
    plan: LagPlan, x: np.ndarray, y: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pooled MSD over realizations [Rz, T] (sum of squares over sum of pairs), its standard
    error across realizations, the pairs, and the per-realization MSDs."""
    sums, pairs = zip(*(plan.sums(xr_, yr_) for xr_, yr_ in zip(x, y, strict=True)), strict=True)
    sums, pairs = np.array(sums), np.array(pairs)
    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # lags with < 2 realizations
        each = np.where(pairs > 0, sums / np.where(pairs > 0, pairs, 1), np.nan)
        total = pairs.sum(axis=0)
        pooled = np.where(total > 0, sums.sum(axis=0) / np.where(total > 0, total, 1), np.nan)
        n = np.isfinite(each).sum(axis=0)
        sem = np.where(n >= 2, np.nanstd(each, axis=0, ddof=1) / np.sqrt(np.maximum(n, 1)), np.nan)
    return pooled, sem, total, each


def _collapse(lag: np.ndarray, msd: np.ndarray, radii: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Collapse metric per variant: mean over a common grid of the standard deviation across
    curves of log10(MSD R^a) at equal log10(lag R^b), over lags up to ``ends`` (the start of
    each curve's diffusive window: the ballistic and crossover range). NaN with < 2 curves."""
    out = np.full(len(COLLAPSE_VARIANTS), np.nan)
    if len(radii) < 2:
        return out
    for k, (a, b) in enumerate(COLLAPSE_VARIANTS):
        out[k] = collapse_spread(lag, msd, radii, ends, a, b)
    return out


def collapse_spread(
    lag: np.ndarray, msd: np.ndarray, radii: np.ndarray, ends: np.ndarray, a: float, b: float
) -> float:
    """The collapse metric of MSD R^a against lag R^b (decades; see :func:`_collapse`) of the
    curves ``msd`` [radius, lag] (cm^2) over lags (s) up to ``ends`` [radius]; NaN when a
    curve has fewer than 2 lags or the curves share no range of scaled lags."""
    curves = []
    for m, r, end in zip(msd, radii, ends, strict=True):
        use = (lag <= end) & np.isfinite(m) & (m > 0)
        if use.sum() < 2:
            return np.nan
        curves.append((np.log10(lag[use] * r**b), np.log10(m[use] * r**a)))
    lo = max(c[0][0] for c in curves)
    hi = min(c[0][-1] for c in curves)
    if len(curves) < 2 or not hi > lo:
        return np.nan
    grid = np.linspace(lo, hi, COLLAPSE_GRID)
    ys = np.array([np.interp(grid, cx, cy) for cx, cy in curves])
    return float(ys.std(axis=0, ddof=1).mean())


#: Per-(point, body) scalars of :func:`_body_statistics` that are not quantities with an
#: error across realizations (float, NaN when undefined).
SCALARS = (
    "go_ks_statistic",
    "go_ks_pvalue",
    "stop_ks_statistic",
    "stop_ks_pvalue",
    "ballistic_window_end",
    "diffusive_window_start",
)
#: Detection intervals of the stop/go systematic, in samples of a uniform stop/go record:
#: the record's own, the one nearest 1/30 s (the experiments' frame rate), and 0.1 s.
FRAME_INTERVAL, COARSE_INTERVAL = 1 / 30, 0.1


def _fine_record(
    ds: xr.Dataset, opts: Mapping[str, Any], plan: LagPlan, start: float
) -> np.ndarray | None:
    """Which samples of the bodies' fine record (from ``start``, s) the MSD uses, or None to
    use the sampled record: option ``msd_record`` 'sampled', or a file without a fine record
    (with a warning where its sampled record has two sampling intervals, whose MSD steps
    where they meet)."""
    if opts["msd_record"] == "sampled":
        return None
    if all(n in ds.variables for n in ("fine_time", *FINE_BODY_VARIABLES)):
        fine = np.asarray(ds["fine_time"].values, dtype=np.float64)
        return fine >= start
    if plan.coarse_lags.size:
        warnings.warn(
            "this dataset has no fine record of the bodies (a simulation of softcell "
            "before 0.3, or data made elsewhere): their MSD takes lags below short_lag_max = "
            f"{opts['short_lag_max']:g} s from the finest sampling segment alone and the "
            "rest from the whole record, which makes a step where the two meet; simulate "
            "again for an MSD from one record",
            AnalysisWarning,
            stacklevel=4,
        )
    return None


class _Setup:
    """What every point of one analysis shares: options, detectors, the kept times, lags."""

    def __init__(
        self, ds: xr.Dataset, options: Mapping[str, Any] | None, registry: Registry
    ) -> None:
        asked, given = split_options(options, registry)
        opts = analysis_options(asked)
        require(ds)
        self.origin = ds.attrs.get("softcell_origin", "simulation")
        self.choice = choose_detector(ds.attrs, opts, given, registry)
        self.detector = self.choice.build()
        self.threshold = self.choice.values.get("threshold")
        # What ran: the detector chosen, and its threshold (None if it has none).
        self.opts = opts = {**opts, "detector": self.choice.name, "threshold": self.threshold}
        self.shifts = np.array([-opts["threshold_shift"], 0.0, opts["threshold_shift"]])
        self.shifted = [
            self.choice.build(threshold=self.threshold + s)
            if self.threshold is not None and self.threshold + s >= 0
            else None
            for s in self.shifts
        ]
        time_all = np.asarray(ds["time"].values, dtype=np.float64)
        self.keep = time_all >= time_all[0] + opts["discard"]
        self.time = time_all[self.keep]
        self.plan = LagPlan(self.time, opts)
        self.fine_keep = _fine_record(ds, opts, self.plan, time_all[0] + opts["discard"])
        self.msd_plan = self.plan
        if self.fine_keep is not None:
            fine = np.asarray(ds["fine_time"].values, dtype=np.float64)[self.fine_keep]
            self.msd_plan = LagPlan(fine, opts)
        self.lag = self.msd_plan.lag
        self.only = (
            segments(self.time).index(self.plan.fine)
            if opts["stopgo_segments"] == "finest"
            else None
        )
        self._stopgo_record(ds, opts, time_all[0] + opts["discard"])
        self.seed = int(ds.attrs.get("softcell_seed", 0))
        self.blocks: np.ndarray | None = None
        self.lead = sweep_dims(ds)
        self.points = _points(ds, self.lead)
        self.segment = segment_index(self.time)
        self.fine_index = segments(self.time).index(self.plan.fine)
        if self.plan.coarse_lags.size:  # the whole record on the coarse grid
            self.correlation_grid = self.plan.grid
            self.correlation_interval = self.plan.coarse_interval
        else:
            self.correlation_grid = np.arange(self.plan.fine.first, self.plan.fine.last + 1)
            self.correlation_interval = self.plan.fine.interval
        self.correlation_lags = min(
            int(round(opts["correlation_max_lag"] / self.correlation_interval)),
            max(self.correlation_grid.size - 2, 0),
        )

    def _stopgo_record(self, ds: xr.Dataset, opts: Mapping[str, Any], start: float) -> None:
        """Where the stop/go phases come from: the bodies' fine record (from ``start``, s)
        where the file has one and option ``stopgo_record`` is 'fine', else the sampled
        record; the index of each kept sample time in it (-1: not in it), and the detection
        intervals (in samples) of the systematic."""
        has_fine = all(n in ds.variables for n in ("fine_time", *FINE_BODY_VARIABLES))
        self.stopgo_keep: np.ndarray | None = None
        self.stopgo_time, self.stopgo_only, self.stopgo_index = self.time, self.only, None
        if opts["stopgo_record"] == "fine" and has_fine:
            fine = np.asarray(ds["fine_time"].values, dtype=np.float64)
            self.stopgo_keep = fine >= start
            self.stopgo_time, self.stopgo_only = fine[self.stopgo_keep], None
            self.stopgo_index = decimation_index(self.stopgo_time, self.time)
        elif opts["stopgo_record"] == "fine" and len(segments(self.time)) > 1:
            warnings.warn(
                "this dataset has no fine record of the bodies: its stop/go phases come from "
                "the sampled record, segment by segment, and their durations depend on the "
                "sampling design (a coarse interval misses short phases); simulate again for "
                "durations from one record",
                AnalysisWarning,
                stacklevel=5,
            )
        segs = segments(self.stopgo_time)
        self.stopgo_fine_segment = segs.index(
            max(segs, key=lambda g: (-g.interval, g.last - g.first))
        )
        interval = segs[self.stopgo_fine_segment].interval
        factors = [1]
        if len(segs) == 1:
            factors += [max(1, round(t / interval)) for t in (FRAME_INTERVAL, COARSE_INTERVAL)]
        self.factors = sorted(set(factors))
        self.frame_factor = max(1, round(FRAME_INTERVAL / interval)) if len(segs) == 1 else 1
        self.detection_interval = interval * np.asarray(self.factors, dtype=np.float64)


def decimation_index(record: np.ndarray, times: np.ndarray) -> np.ndarray:
    """int64[T]: the index of each of ``times`` (s) in the increasing ``record`` (s), -1
    where it has no sample within 1e-6 of the record's interval."""
    at = np.clip(np.searchsorted(record, times), 1, max(record.size - 1, 1))
    left = np.where(np.abs(record[at - 1] - times) <= np.abs(record[at] - times), at - 1, at)
    step = float(np.min(np.diff(record))) if record.size > 1 else 1.0
    return np.where(np.abs(record[left] - times) <= 1e-6 * step, left, -1)


class _Results:
    """The per-point arrays of an analysis, filled point by point (leading axis: point)."""

    def __init__(self, setup: _Setup, n_real: int) -> None:
        shape = (len(setup.points), len(BODIES))
        n_lag, n_t = setup.lag.size, setup.time.size
        self.shape = shape
        self.n_real = n_real
        self.scalars = {name: np.full(shape, np.nan) for name in SCALARS}
        quantities = (*uncertainty.BODY_QUANTITIES, *uncertainty.POINT_QUANTITIES)
        self.values = {
            name: np.full(shape if name in uncertainty.BODY_QUANTITIES else shape[0], np.nan)
            for name in quantities
        }
        self.each = {name: np.full((*v.shape, n_real), np.nan) for name, v in self.values.items()}
        self.errors = {name: np.full(v.shape, np.nan) for name, v in self.values.items()}
        self.counts = {
            name: np.zeros((*shape, n_real), dtype=np.int64)
            for name in ("go_events", "stop_events", "speed_samples", "labelled_samples")
        }
        n_factor = len(setup.factors)
        self.interval_go = np.full((*shape, n_factor), np.nan)
        self.interval_stop = np.full((*shape, n_factor), np.nan)
        self.sums: dict[int, uncertainty.BodySums] = {}
        self.go_events = np.zeros(shape, dtype=np.int64)
        self.stop_events = np.zeros(shape, dtype=np.int64)
        self.msd = np.full((*shape, n_lag), np.nan)
        self.msd_sem = np.full((*shape, n_lag), np.nan)
        self.msd_pairs = np.zeros((*shape, n_lag))
        self.msd_each = np.full((*shape, n_real, n_lag), np.nan)
        self.speeds = np.full((*shape, n_real, n_t), np.nan)
        self.labels = np.full((*shape, n_real, n_t), -1, dtype=np.int8)
        self.shifted_go = np.full((*shape, setup.shifts.size), np.nan)
        self.shifted_stop = np.full((*shape, setup.shifts.size), np.nan)
        self.ipr = np.full((len(setup.points), n_real, n_t), np.nan)
        self.durations: dict[tuple[int, int, int], np.ndarray] = {}
        n_corr = setup.correlation_lags + 1
        self.vacf_sums = np.zeros((*shape, n_real, n_corr))
        self.vacf_pairs = np.zeros((*shape, n_real, n_corr))
        self.turns = np.zeros((*shape, n_real, 5))  # phases, |l| sum, |l|^2 sum, pairs, cos sum


def _correlations(
    setup: _Setup, res: _Results, i: int, b: int, x: np.ndarray, y: np.ndarray, lab: np.ndarray
) -> None:
    """Velocity autocorrelation (on the correlation grid) and go-phase turns (in the finest
    segment) of each realization of one body at point i, into ``res``."""
    grid = setup.correlation_grid
    for r in range(x.shape[0]):
        pos = np.stack([x[r], y[r]], axis=-1)
        on_grid = np.where((grid >= 0)[:, None], pos[np.maximum(grid, 0)], np.nan)
        res.vacf_sums[i, b, r], res.vacf_pairs[i, b, r] = correlation.velocity_autocorrelation(
            on_grid, setup.correlation_interval, setup.correlation_lags
        )
        t = correlation.turn_statistics(pos, lab[r], setup.segment, setup.fine_index)
        res.turns[i, b, r] = t.phases, t.length_sum, t.square_sum, t.pairs, t.cosine_sum


def _body_statistics(
    setup: _Setup,
    res: _Results,
    i: int,
    b: int,
    x: np.ndarray,
    y: np.ndarray,
    fine: tuple[np.ndarray, np.ndarray] | None,
    record: tuple[np.ndarray, np.ndarray],
) -> None:
    """Speeds, stop/go, MSD and the per-realization sums of one body (positions x, y
    [realization, time], cm; ``fine`` its fine record [realization, fine_time], if the MSD
    uses it; ``record`` the positions its stop/go phases come from) at point i, into row
    (i, b) of ``res``."""
    time = setup.stopgo_time
    s = speed(*record, time)
    lab = stopgo.label(setup.detector, s, time)
    if setup.stopgo_index is None:
        res.speeds[i, b], res.labels[i, b] = s, lab
    else:
        at, found = np.maximum(setup.stopgo_index, 0), setup.stopgo_index >= 0
        res.speeds[i, b] = np.where(found, s[:, at], np.nan)
        res.labels[i, b] = np.where(found, lab[:, at], -1)
    _correlations(setup, res, i, b, x, y, res.labels[i, b])
    only = setup.stopgo_only
    each = [stopgo.durations(lab[r], time, only) for r in range(lab.shape[0])]
    go = np.concatenate([d.go for d in each])
    stop = np.concatenate([d.stop for d in each])
    res.durations[(i, b, stopgo.GO)], res.durations[(i, b, stopgo.STOP)] = go, stop
    res.go_events[i, b], res.stop_events[i, b] = go.size, stop.size
    res.counts["go_events"][i, b] = [d.go.size for d in each]
    res.counts["stop_events"][i, b] = [d.stop.size for d in each]
    for name, values in (("go", go), ("stop", stop)):
        stat, p = stopgo.exponential_fit_statistic(values)
        res.scalars[f"{name}_ks_statistic"][i, b], res.scalars[f"{name}_ks_pvalue"][i, b] = stat, p
    _systematics(setup, res, i, b, stopgo.Durations(go, stop), s, record)
    seg = segments(time)[setup.stopgo_fine_segment]
    part = s[:, seg.first : seg.last]
    finite = np.isfinite(part)
    known = lab >= 0
    res.counts["speed_samples"][i, b] = finite.sum(axis=1)
    res.counts["labelled_samples"][i, b] = known.sum(axis=1)

    pooled, sem, pairs, msd_each = _ensemble_msd(setup.msd_plan, *(fine or (x, y)))
    res.msd[i, b], res.msd_sem[i, b], res.msd_pairs[i, b], res.msd_each[i, b] = (
        pooled,
        sem,
        pairs,
        msd_each,
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        vacf = np.where(
            res.vacf_pairs[i, b] > 0, res.vacf_sums[i, b] / res.vacf_pairs[i, b], np.nan
        )
    t = res.turns[i, b]
    res.sums[b] = uncertainty.BodySums(
        go_sum=np.array([d.go.sum() for d in each]),
        go_count=res.counts["go_events"][i, b].astype(np.float64),
        go_square=np.array([(d.go**2).sum() for d in each]),
        stop_sum=np.array([d.stop.sum() for d in each]),
        stop_count=res.counts["stop_events"][i, b].astype(np.float64),
        speed_sum=np.where(finite, part, 0.0).sum(axis=1),
        speed_square=np.where(finite, part**2, 0.0).sum(axis=1),
        speed_count=finite.sum(axis=1).astype(np.float64),
        go_samples=(lab == stopgo.GO).sum(axis=1).astype(np.float64),
        known_samples=known.sum(axis=1).astype(np.float64),
        msd=msd_each,
        lag=setup.lag,
        correlation=vacf,
        interval=setup.correlation_interval,
        turn_cosine=t[:, 4],
        turn_pairs=t[:, 3],
    )


def _systematics(
    setup: _Setup,
    res: _Results,
    i: int,
    b: int,
    found: stopgo.Durations,
    s: np.ndarray,
    record: tuple[np.ndarray, np.ndarray],
) -> None:
    """The mean durations of one body at point i with the threshold shifted and with the
    speed measured over longer intervals (``found``: the durations as detected; ``s`` the
    speeds of the stop/go record, ``record`` its positions)."""
    time, only = setup.stopgo_time, setup.stopgo_only
    for k, det in enumerate(setup.shifted):
        if det is not None:
            dk = (
                found
                if setup.shifts[k] == 0
                else stopgo.durations(stopgo.label(det, s, time), time, only)
            )
            res.shifted_go[i, b, k] = dk.mean(stopgo.GO)
            res.shifted_stop[i, b, k] = dk.mean(stopgo.STOP)
    for k, f in enumerate(setup.factors):
        dk = found
        if f > 1:
            tf = time[::f]
            sf = speed(record[0][:, ::f], record[1][:, ::f], tf)
            dk = stopgo.durations(stopgo.label(setup.detector, sf, tf), tf, None)
        res.interval_go[i, b, k] = dk.mean(stopgo.GO)
        res.interval_stop[i, b, k] = dk.mean(stopgo.STOP)


def _quantities(setup: _Setup, res: _Results, i: int, radius: float) -> None:
    """Every quantity of point i with an error across realizations: its value, its value
    per realization and its bootstrap standard error (module ``uncertainty``)."""
    n = res.n_real
    units = uncertainty.independent_count(n, setup.blocks)
    rows = np.ones((1, n))
    boot = uncertainty.weights(
        n, setup.opts["resamples"], uncertainty.rng_for(setup.seed, i), setup.blocks
    )
    for b in range(len(BODIES)):
        sums = res.sums[b]
        value = uncertainty.estimates(sums, rows, setup.opts)
        per = uncertainty.estimates(sums, np.eye(n), setup.opts)
        samples = uncertainty.estimates(sums, boot, setup.opts) if units >= 2 else None
        for name in uncertainty.BODY_QUANTITIES:
            res.values[name][i, b] = value[name][0]
            res.each[name][i, b] = per[name]
            if samples is not None:
                res.errors[name][i, b] = uncertainty.standard_error(samples[name], units)
        tau_g = value["mean_go_duration"][0]
        res.scalars["ballistic_window_end"][i, b] = setup.opts["ballistic_window"] * tau_g
        res.scalars["diffusive_window_start"][i, b] = setup.opts["diffusive_window"] * tau_g
    for name in ("ipr_mean", "gc_distance"):
        each = res.each[name][i]
        res.values[name][i] = uncertainty.mean_of(rows, each)[0]
        if units >= 2:
            res.errors[name][i] = uncertainty.standard_error(uncertainty.mean_of(boot, each), units)
    with np.errstate(invalid="ignore", divide="ignore"):
        res.each["gc_distance_ratio"][i] = res.each["gc_distance"][i] / radius
        res.values["gc_distance_ratio"][i] = res.values["gc_distance"][i] / radius
        res.errors["gc_distance_ratio"][i] = res.errors["gc_distance"][i] / radius


def _point_statistics(setup: _Setup, res: _Results, i: int, sel: xr.Dataset, radius: float) -> None:
    """Everything of point i (the Dataset ``sel``): both bodies, the shape index, the
    bot-cell distance, and every quantity's error across realizations."""
    keep = setup.keep
    pos = {}
    for b, body in enumerate(BODIES):
        x = np.asarray(sel[f"{body}_x"].transpose("realization", "time").values)[:, keep]
        y = np.asarray(sel[f"{body}_y"].transpose("realization", "time").values)[:, keep]
        pos[body] = (x, y)
        fine = None
        if setup.fine_keep is not None:
            fine = _fine_positions(sel, body, setup.fine_keep)
        record = (x, y)
        if setup.stopgo_keep is not None:
            same = setup.fine_keep is not None and np.array_equal(
                setup.fine_keep, setup.stopgo_keep
            )
            record = (
                fine if same and fine is not None else _fine_positions(sel, body, setup.stopgo_keep)
            )
        _body_statistics(setup, res, i, b, x, y, fine, record)
    mx = sel["membrane_x"].transpose("realization", "time", "node")
    my = sel["membrane_y"].transpose("realization", "time", "node")
    for r in range(res.ipr.shape[1]):
        res.ipr[i, r] = shape_index(
            np.asarray(mx[r].values)[keep],
            np.asarray(my[r].values)[keep],
            band_limited=setup.origin == "simulation",
        )
    (cx, cy), (bx, by) = pos["cell"], pos["bot"]
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a realization with no sample: NaN
        res.each["gc_distance"][i] = np.nanmean(np.hypot(bx - cx, by - cy), axis=1)
        res.each["ipr_mean"][i] = np.nanmean(res.ipr[i], axis=1)
    _quantities(setup, res, i, radius)


def _fine_positions(sel: xr.Dataset, body: str, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fine record of ``body`` (cm) [realization, kept fine sample]."""
    return tuple(
        np.asarray(sel[f"{body}_{c}_fine"].transpose("realization", "fine_time").values)[:, keep]
        for c in "xy"
    )


def _pooled_statistics(setup: _Setup, res: _Results) -> tuple[dict[str, Any], np.ndarray]:
    """What needs every point: durations along ``event``, PDFs of t/<t> on common bins, the
    theories, and the regime of each point. Returns every variable of the analysis by name,
    and the edges of the PDF bins."""
    shape = res.shape
    n_event = max([v.size for v in res.durations.values()] + [0])
    durations = {kind: np.full((*shape, n_event), np.nan) for kind in (stopgo.GO, stopgo.STOP)}
    largest = 0.0
    for (i, b, kind), values in res.durations.items():
        durations[kind][i, b, : values.size] = values
        if values.size and values.mean() > 0:
            largest = max(largest, float((values / values.mean()).max()))
    edges = stopgo.pdf_edges(largest)
    pdfs = {kind: np.full((*shape, edges.size - 1), np.nan) for kind in durations}
    for (i, b, kind), values in res.durations.items():
        pdfs[kind][i, b] = stopgo.scaled_pdf(values, edges)

    v0_hat, tau_g = res.values["v0_hat"], res.values["mean_go_duration"]
    msd_theory = np.full(res.msd.shape, np.nan)
    for i, b in np.ndindex(*shape):
        if tau_g[i, b] > 0:
            msd_theory[i, b] = fits.run_and_tumble_msd(setup.lag, v0_hat[i, b], tau_g[i, b])
    opts = setup.opts
    ratio = res.values["gc_distance_ratio"]
    corr = _pooled_correlations(setup, res, durations[stopgo.GO])
    regime = np.full(len(setup.points), REGIMES["unknown"], dtype=np.int8)
    regime[ratio <= opts["coupled_below"]] = REGIMES["coupled"]
    regime[(ratio > opts["coupled_below"]) & (ratio < opts["decoupled_above"])] = REGIMES[
        "intermediate"
    ]
    regime[ratio >= opts["decoupled_above"]] = REGIMES["decoupled"]
    quantities = {}
    for name, value in res.values.items():
        quantities[name] = value
        quantities[f"{name}_realization"] = res.each[name]
        quantities[f"{name}_error"] = res.errors[name]
    with np.errstate(invalid="ignore"):
        systematic = {
            kind: np.fmax(
                np.nanmax(np.abs(shifted - mean[..., None]), axis=-1, initial=0.0)
                if np.isfinite(shifted).any()
                else np.full(mean.shape, np.nan),
                np.abs(interval[..., setup.factors.index(setup.frame_factor)] - mean),
            )
            for kind, shifted, interval, mean in (
                ("go", res.shifted_go, res.interval_go, res.values["mean_go_duration"]),
                ("stop", res.shifted_stop, res.interval_stop, res.values["mean_stop_duration"]),
            )
        }
    return {
        "msd": res.msd,
        "msd_sem": res.msd_sem,
        "msd_pairs": res.msd_pairs,
        "msd_realization": res.msd_each,
        "msd_theory": msd_theory,
        "speed": res.speeds,
        "stopgo_label": res.labels,
        "go_duration": durations[stopgo.GO],
        "stop_duration": durations[stopgo.STOP],
        "go_pdf": pdfs[stopgo.GO],
        "stop_pdf": pdfs[stopgo.STOP],
        "mean_go_duration_shifted": res.shifted_go,
        "mean_stop_duration_shifted": res.shifted_stop,
        "mean_go_duration_interval": res.interval_go,
        "mean_stop_duration_interval": res.interval_stop,
        "mean_go_duration_systematic": systematic["go"],
        "mean_stop_duration_systematic": systematic["stop"],
        **res.scalars,
        **quantities,
        "go_events": res.go_events,
        "stop_events": res.stop_events,
        **{f"{name}_realization": count for name, count in res.counts.items()},
        **corr,
        "ipr": res.ipr,
        "regime": regime,
    }, edges


def _pooled_correlations(setup: _Setup, res: _Results, go: np.ndarray) -> dict[str, np.ndarray]:
    """The velocity autocorrelations (pooled, per realization, the renewal theory's), the
    renewal theory's MSD curve and the go phases' turn statistics, by variable name; ``go``
    [point, body, event] the pooled go durations (s)."""
    dt, k = setup.correlation_interval, setup.correlation_lags
    v0_hat = res.values["v0_hat"]
    with np.errstate(invalid="ignore", divide="ignore"):
        total = res.vacf_pairs.sum(axis=2)
        pooled = np.where(total > 0, res.vacf_sums.sum(axis=2) / total, np.nan)
        each = np.where(res.vacf_pairs > 0, res.vacf_sums / res.vacf_pairs, np.nan)
        t = res.turns
        sums = t.sum(axis=2)
        cosine_each = np.where(t[..., 3] > 0, t[..., 4] / t[..., 3], np.nan)
        length, square = sums[..., 1] / sums[..., 0], sums[..., 2] / sums[..., 0]
    theory_msd = np.full(res.msd.shape, np.nan)
    theory_vacf = np.full(pooled.shape, np.nan)
    for i, b in np.ndindex(*res.shape):
        if np.isfinite(v0_hat[i, b]):
            theory_msd[i, b] = correlation.renewal_msd(setup.lag, v0_hat[i, b], go[i, b])
            theory_vacf[i, b] = correlation.renewal_autocorrelation(dt, k, v0_hat[i, b], go[i, b])
    return {
        "msd_theory_renewal": theory_msd,
        "velocity_autocorrelation": pooled,
        "velocity_autocorrelation_realization": each,
        "velocity_autocorrelation_renewal": theory_vacf,
        "go_turn_cosine_realization": cosine_each,
        "go_turn_pairs": t[..., 3].astype(np.int64),
        "go_displacement_mean": length,
        "go_displacement_mean_square": square,
    }


def _lag_attrs(setup: _Setup) -> dict[str, Any]:
    """The lag coordinate's attributes, with the record the MSD came from."""
    if setup.fine_keep is not None:
        record = (
            f"every lag from the bodies' fine record (every {setup.msd_plan.fine.interval:g} s "
            "over the whole run)"
        )
    elif setup.plan.coarse_lags.size:
        record = (
            f"lags below {setup.opts['short_lag_max']:g} s from the finest sampling segment, "
            "longer ones from the whole record"
        )
    else:
        record = "every lag from the whole record"
    return {"units": "s", "long_name": "time lag", "msd_record": record}


def _analysis_dataset(
    ds: xr.Dataset, setup: _Setup, values: dict[str, Any], edges: np.ndarray
) -> xr.Dataset:
    """The analysis Dataset of ``softcell.schema.ANALYSIS_VARIABLES``, back on the
    sweep's dims."""
    lead = setup.lead
    lead_shape = tuple(ds.sizes[d] for d in lead)
    out = xr.Dataset(
        coords={
            "body": (
                "body",
                np.array(BODIES),
                {"long_name": "moving body: cell (membrane GC) or bot"},
            ),
            "lag": ("lag", setup.lag, _lag_attrs(setup)),
            "realization": (
                "realization",
                np.asarray(ds["realization"].values),
                {"units": "1", "long_name": "realization index"},
            ),
            "time": (
                "time",
                setup.time,
                {"units": "s", "long_name": "time since the start of the record"},
            ),
            "event": (
                "event",
                np.arange(values["go_duration"].shape[-1]),
                {"units": "1", "long_name": "phase index"},
            ),
            "scaled_duration": (
                "scaled_duration",
                0.5 * (edges[1:] + edges[:-1]),
                {
                    "units": "1",
                    "long_name": "phase duration over its mean, bin center",
                    "bin_width": stopgo.PDF_BIN,
                },
            ),
            "threshold_shift": (
                "threshold_shift",
                setup.shifts,
                {"units": "cm s-1", "long_name": "shift of the stop/go threshold"},
            ),
            "detection_interval": (
                "detection_interval",
                setup.detection_interval,
                {
                    "units": "s",
                    "long_name": "interval over which the speed is measured for stop/go",
                },
            ),
            "correlation_lag": (
                "correlation_lag",
                setup.correlation_interval * np.arange(setup.correlation_lags + 1),
                {
                    "units": "s",
                    "long_name": "lag of the velocity autocorrelation",
                    "velocity_interval": setup.correlation_interval,
                },
            ),
        }
    )
    for d in lead:
        out.coords[d] = (d, ds[d].values, dict(ds[d].attrs))
    for name, coord in ds.coords.items():  # e.g. duration along radius
        if name not in lead and coord.dims and set(coord.dims) <= set(lead):
            out.coords[name] = (coord.dims, coord.values, dict(coord.attrs))
    variables = {}
    for name, spec in ANALYSIS_VARIABLES.items():
        dims = tuple(lead) + tuple(d for d in spec.dims if d != SWEEP)
        data = np.asarray(values[name])
        variables[name] = (dims, data.reshape(lead_shape + data.shape[1:]), spec.cf_attrs())
    return out.assign(variables)


def _collapse_variables(
    out: xr.Dataset, setup: _Setup, values: dict[str, Any], radius: np.ndarray
) -> None:
    """The scaling-collapse variants of a radius sweep, over its decoupled radii."""
    decoupled = values["regime"] == REGIMES["decoupled"]
    metric = _collapse(
        setup.lag,
        values["msd"][decoupled, 0],
        radius[decoupled],
        values["diffusive_window_start"][decoupled, 0],
    )
    names = [f"msd R^{a:+.3g}, lag R^{b:+.3g}" for a, b in COLLAPSE_VARIANTS]
    out.coords["collapse_variant"] = (
        "collapse_variant",
        np.array(names),
        {"long_name": "scaling-collapse variant"},
    )
    out["collapse_msd_exponent"] = (
        "collapse_variant",
        [a for a, _ in COLLAPSE_VARIANTS],
        {"units": "1", "long_name": "exponent a of R^a on the MSD"},
    )
    out["collapse_lag_exponent"] = (
        "collapse_variant",
        [b for _, b in COLLAPSE_VARIANTS],
        {"units": "1", "long_name": "exponent b of R^b on the lag"},
    )
    out["collapse_metric"] = (
        "collapse_variant",
        metric,
        {
            "units": "1",
            "long_name": "mean spread (decades) of the rescaled cell MSDs of "
            "the decoupled radii over the ballistic and crossover lags",
            "radii": radius[decoupled],
        },
    )


def _independent(setup: _Setup, blocks: np.ndarray | None, n_real: int) -> int:
    """Set the blocks of the realizations on ``setup`` and return the number of independent
    units among them, with a warning when there are fewer than two."""
    setup.blocks = None if blocks is None else np.asarray(blocks)
    if setup.blocks is not None and setup.blocks.shape != (n_real,):
        raise ConfigError(
            f"analyze: blocks has shape {setup.blocks.shape}, not one block per realization "
            f"({n_real},)"
        )
    units = uncertainty.independent_count(n_real, setup.blocks)
    if units < 2:
        warnings.warn(
            f"{units} independent realization: no error across realizations exists, so every "
            "_error variable is NaN (analyse two or more realizations for errors)",
            AnalysisWarning,
            stacklevel=3,
        )
    return units


def analyze(
    ds: xr.Dataset,
    options: Mapping[str, Any] | None = None,
    *,
    progress: bool = False,
    registry: Registry | None = None,
    blocks: np.ndarray | None = None,
) -> xr.Dataset:
    """Analyse a simulation or tracked Dataset (docs/model.md §6).

    Parameters
    ----------
    ds : xarray.Dataset
        The softcell schema (positions in cm, time in s); a sweep adds leading dims.
    options : mapping, optional
        Analysis options (``softcell.analysis.options.ANALYSIS_OPTIONS``; docs/analysis.md):
        discard (s), fit windows (multiples of the mean go time), detector and threshold
        (cm/s), ...; for an assembly (a ``cell`` dim) also the collective ones
        (``softcell.analysis.collective.CROWD_OPTIONS``: crowd_every in s, contact_distance in
        cm, ...), which a single cell's file refuses.
    progress : bool
        Show a progress bar over sweep points.
    registry : Registry, optional
        Where the stop/go detector is looked up; by default the built-ins and the installed
        plugins (``softcell.components.registry.default_registry()``).
    blocks : sequence of int, optional
        The block of each realization when realizations are not independent of each other
        (the cells of one assembly, analysed as realizations): the bootstrap behind every
        ``_error`` draws whole blocks. Default: every realization its own block.

    Returns
    -------
    xarray.Dataset
        The analysis (``softcell.schema.ANALYSIS_VARIABLES``; an assembly's with a
        ``cell`` dim on the per-cell variables and ``softcell.schema.CROWD_VARIABLES``),
        with CF attributes on every variable and the options, the input's parameters, seed and
        components in the global attributes. Every quantity with an error has its value per
        realization (``NAME_realization``) and its standard error across realizations
        (``NAME_error``, a bootstrap over realizations; NaN, with an
        :class:`~softcell.errors.AnalysisWarning`, for one realization).

    Raises
    ------
    SoftcellError
        Naming every variable the analysis needs that ``ds`` lacks, or a record too short.
    """
    from softcell.settings import progress_bar_class

    tqdm = progress_bar_class()

    if not isinstance(ds, xr.Dataset):
        raise ConfigError(
            f"analyze: ds is a {type(ds).__name__}, not an xarray.Dataset (open one with "
            "softcell.open_dataset)"
        )
    from softcell.analysis import collective as crowd

    if "bot" in ds.dims:
        from softcell.analysis.bots import analyze_bots

        return analyze_bots(ds, options, progress=progress, registry=registry, analyze=analyze)
    collective, options = crowd.split_crowd_options(options)
    if "cell" in ds.dims:
        return crowd.analyze_assembly(
            ds, options, collective, progress=progress, registry=registry, analyze=analyze
        )
    crowd.refuse_for_one_cell(collective)
    setup = _Setup(ds, options, registry if registry is not None else default_registry())
    n_real = ds.sizes["realization"]
    units = _independent(setup, blocks, n_real)
    res = _Results(setup, n_real)
    radius = np.array([_radius(ds, p) for p in setup.points])
    for i, point in enumerate(
        tqdm(setup.points, disable=not progress, desc="analysis", unit="point")
    ):
        _point_statistics(setup, res, i, ds.isel(point) if point else ds, radius[i])
    values, edges = _pooled_statistics(setup, res)
    out = _analysis_dataset(ds, setup, values, edges)
    described = uncertainty.describe(units, setup.opts["resamples"], setup.blocks is not None)
    for name in out.data_vars:
        if str(name).endswith("_error"):
            out[name].attrs["uncertainty"] = described
    if "radius" in setup.lead and len(setup.lead) == 1:
        _collapse_variables(out, setup, values, radius)
    opts = setup.opts
    out.attrs = {
        "Conventions": "CF-1.8",
        "title": "soft robotic cell analysis",
        "source": f"softcell {__version__} analysis",
        "softcell_version": __version__,
        "softcell_origin": "analysis",
        "softcell_input_origin": setup.origin,
        "softcell_detector": opts["detector"],
        "softcell_threshold": np.nan if setup.threshold is None else float(setup.threshold),
        **options_attrs(opts),
        **{
            k: v for k, v in ds.attrs.items() if k in ("softcell_seed", "softcell_swept_parameters")
        },
        **_what_ran(ds.attrs, setup.choice),
    }
    return out


def _what_ran(attrs: Mapping[str, Any], choice: DetectorChoice) -> dict[str, Any]:
    """The input's parameters and components, with the detector and its parameters as they
    ran here (not as the input recorded them), and the detector's parameters on their own."""
    out: dict[str, Any] = {
        "softcell_detector_parameters": json.dumps(choice.values, sort_keys=True),
        "softcell_detector_parameter_units": json.dumps(choice.units(), sort_keys=True),
    }
    if "softcell_parameters" not in attrs:  # a tracked video: no model parameters
        return out
    params = {**json.loads(attrs["softcell_parameters"]), **choice.values}
    units = {**json.loads(attrs.get("softcell_parameter_units", "{}")), **choice.units()}
    out["softcell_parameters"] = json.dumps(params)
    out["softcell_parameter_units"] = json.dumps(units)
    if "softcell_components" in attrs:
        components = json.loads(attrs["softcell_components"])
        out["softcell_components"] = json.dumps({**components, "stopgo_detector": choice.name})
    return {**out, **parameter_attrs(params)}
