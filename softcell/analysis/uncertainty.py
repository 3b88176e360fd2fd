"""Errors across realizations: every quantity of an analysis, its value per realization and
its standard error from a bootstrap over realizations (docs/analysis.md, "Errors").

The realizations of one sweep point are independent (each has its own random stream), so
the sampling distribution of any pooled measurement, a ratio of sums (a mean duration) or a
fit to the pooled MSD whose window moves with <tau_g> (D hat), is found by drawing the
realizations again with replacement and measuring again. One estimator,
:func:`estimates`, computes every quantity from per-realization sums under a matrix of
weights ``W`` [row, realization]: a row of ones gives the value itself, the identity gives
the value of each realization, and bootstrap rows (how often each realization was drawn)
give the resamples. So the value, its spread per realization and its error are the same
computation, never three.

Two choices, each stated in the error's attributes:

- the standard error is the standard deviation over the resamples times sqrt(n / (n - 1))
  (n realizations): for a mean, the bootstrap's own standard deviation is
  sqrt((n - 1) / n) s / sqrt(n), and the factor makes it the usual s / sqrt(n);
- realizations that are not independent (the cells of one assembly) are drawn together, as
  one block (``blocks``); the error is then across the blocks.

With one realization (or one block) no error across realizations exists: the errors are NaN.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import xarray as xr

from softcell.analysis import fits
from softcell.schema import BODY_QUANTITIES as BODY_QUANTITIES  # the quantities estimated here
from softcell.schema import POINT_QUANTITIES as POINT_QUANTITIES

#: Resamples of the realizations per sweep point (the analysis option ``resamples``).
RESAMPLES = 1000
#: The first entry of the spawn key of every bootstrap stream (a realization's stream is
#: (point, realization); this one cannot collide with a point index).
STREAM = 2**31 - 1

#: Quantities per (point, body) that :func:`estimates` returns, and per point (of the cell
#: and bot together).


@dataclass
class BodySums:
    """Per-realization sums of one body at one sweep point ([realization] arrays, or
    [realization, lag] and [realization, correlation lag] curves), from which
    :func:`estimates` pools any set of realizations.

    ``go_sum`` and ``stop_sum`` (s) are the summed complete phase durations, ``go_count``
    and ``stop_count`` their numbers, ``go_square`` (s^2) the summed squared go durations;
    ``speed_sum`` (cm/s) and ``speed_square`` (cm^2/s^2) the summed speeds and squared
    speeds over ``speed_count`` samples; ``go_samples`` over ``known_samples`` the labelled
    samples that are go; ``msd`` (cm^2) each realization's MSD at ``lag`` (s);
    ``correlation`` (cm^2/s^2) each realization's velocity autocorrelation on a grid of
    ``interval`` (s), or None; ``turn_cosine`` the summed cosines between consecutive go
    displacements over ``turn_pairs`` pairs.
    """

    go_sum: np.ndarray
    go_count: np.ndarray
    go_square: np.ndarray
    stop_sum: np.ndarray
    stop_count: np.ndarray
    speed_sum: np.ndarray
    speed_square: np.ndarray
    speed_count: np.ndarray
    go_samples: np.ndarray
    known_samples: np.ndarray
    msd: np.ndarray
    lag: np.ndarray
    correlation: np.ndarray | None = None
    interval: float = np.nan
    turn_cosine: np.ndarray | None = None
    turn_pairs: np.ndarray | None = None


def weights(
    n: int,
    resamples: int,
    rng: np.random.Generator,
    blocks: np.ndarray | None = None,
) -> np.ndarray:
    """float64[resamples, n]: how often each of n realizations is drawn in each bootstrap
    resample; with ``blocks`` (int[n], the block of each realization) whole blocks are drawn,
    as many as there are blocks."""
    if blocks is None:
        blocks = np.arange(n)
    labels, block = np.unique(np.asarray(blocks), return_inverse=True)
    picks = rng.integers(0, labels.size, (resamples, labels.size))
    counts = np.zeros((resamples, labels.size))
    np.add.at(counts, (np.repeat(np.arange(resamples), labels.size), picks.ravel()), 1.0)
    return counts[:, block]


def independent_count(n: int, blocks: np.ndarray | None = None) -> int:
    """The number of independent units among n realizations (blocks, if given)."""
    return n if blocks is None else int(np.unique(np.asarray(blocks)).size)


def rng_for(seed: int, point: int) -> np.random.Generator:
    """The bootstrap stream of sweep point ``point``: SeedSequence(seed, spawn_key=(STREAM,
    point)); both bodies of a point share it, so joint quantities resample together."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(STREAM, point)))


def _ratio(w: np.ndarray, top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        t, b = w @ np.nan_to_num(top), w @ np.nan_to_num(bottom)
        return np.where(b > 0, t / np.where(b > 0, b, 1.0), np.nan)


def pooled_curve(w: np.ndarray, each: np.ndarray) -> np.ndarray:
    """Weighted mean over realizations of curves [realization, k] with NaNs left out."""
    finite = np.isfinite(each)
    return _ratio(w, np.where(finite, each, 0.0), finite.astype(np.float64))


def power_fits(
    lag: np.ndarray, msd: np.ndarray, exponent: float, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray:
    """Row by row, the coefficient c of MSD = c tau^exponent fitted in log space over
    lo <= tau <= hi (``fits.power_fit`` for many curves [row, lag] at once)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        use = (lag >= lo[:, None]) & (lag <= hi[:, None]) & np.isfinite(msd) & (msd > 0) & (lag > 0)
        residual = np.where(use, np.log(np.where(use, msd, 1.0)) - exponent * np.log(lag), 0.0)
        n = use.sum(axis=1)
        return np.where(n > 0, np.exp(residual.sum(axis=1) / np.maximum(n, 1)), np.nan)


def affine_fits(lag: np.ndarray, msd: np.ndarray, lo: np.ndarray) -> np.ndarray:
    """Row by row, D hat of MSD = D hat tau + b over tau >= lo in relative error
    (``fits.affine_slope`` for many curves at once)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        use = (lag >= lo[:, None]) & np.isfinite(msd) & (msd > 0)
        inv = np.where(use, 1.0 / np.where(use, msd, 1.0), 0.0)
        a11 = (inv**2 * lag**2).sum(axis=1)
        a12 = (inv**2 * lag).sum(axis=1)
        a22 = (inv**2).sum(axis=1)
        r1, r2 = (inv * lag).sum(axis=1), inv.sum(axis=1)
        det = a11 * a22 - a12**2
        slope = (r1 * a22 - r2 * a12) / det
        return np.where((use.sum(axis=1) >= 2) & (det > 0), slope, np.nan)


def confined_fits(
    lag: np.ndarray, msd: np.ndarray, lo: np.ndarray, side: float, iterations: int = 30
) -> np.ndarray:
    """Row by row, D (cm^2/s) of the confined-square formula fitted in log space over
    tau >= lo (``fits.confined_square_fit`` for many curves at once): Gauss-Newton in
    log D from each curve's first lag (MSD ~ 4 D tau), steps capped at one decade."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        use = (lag >= lo[:, None]) & (lag > 0) & np.isfinite(msd) & (msd > 0)
        rows = np.flatnonzero(use.any(axis=1))
        out = np.full(msd.shape[0], np.nan)
        if rows.size == 0:
            return out
        cols = np.flatnonzero(use[rows].any(axis=0))
        lag, msd, use = lag[cols], msd[np.ix_(rows, cols)], use[np.ix_(rows, cols)]
        y = np.log(np.where(use, msd, 1.0))
        first = np.argmax(use, axis=1)
        log_d = np.log(msd[np.arange(rows.size), first] / (4 * lag[first]))
        odd = 2.0 * np.arange(fits.CONFINED_TERMS) + 1.0
        rate = np.pi**2 * np.multiply.outer(lag, odd**2) / side**2  # [lag, term]
        scale = 32 * side**2 / np.pi**4
        active = np.arange(rows.size)
        for _ in range(iterations):
            d = np.exp(log_d[active])[:, None, None]
            decay = np.exp(-rate[None] * d) / odd**4  # [row, lag, term]
            model = side**2 / 3 - scale * decay.sum(axis=-1)
            slope = scale * (decay * rate[None]).sum(axis=-1) * d[..., 0]  # d model / d log D
            ok = use[active] & (model > 0)
            r = np.where(ok, np.log(np.where(ok, model, 1.0)) - y[active], 0.0)
            j = np.where(ok, slope / np.where(ok, model, 1.0), 0.0)
            step = -(r * j).sum(axis=1) / np.maximum((j * j).sum(axis=1), 1e-300)
            log_d[active] += np.clip(step, -np.log(10), np.log(10))
            active = active[np.abs(step) > 1e-10]
            if active.size == 0:
                break
        out[rows] = np.exp(log_d)
        return out


def estimates(sums: BodySums, w: np.ndarray, options: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Every quantity of :data:`BODY_QUANTITIES` for each row of weights ``w`` [row,
    realization] (see the module's docstring): the pooled durations, speeds, MSD and
    autocorrelation of the weighted realizations, and the fits to that MSD with windows from
    that row's <tau_g> (options ``ballistic_window``, ``diffusive_window``,
    ``confined_side``). Returns float64[row] arrays, NaN where not measurable."""
    out: dict[str, np.ndarray] = {}
    tau_g = _ratio(w, sums.go_sum, sums.go_count)
    out["mean_go_duration"] = tau_g
    out["mean_stop_duration"] = _ratio(w, sums.stop_sum, sums.stop_count)
    out["go_duration_second_moment"] = _ratio(w, sums.go_square, sums.go_count)
    out["mean_speed"] = _ratio(w, sums.speed_sum, sums.speed_count)
    v0 = np.sqrt(_ratio(w, sums.speed_square, sums.speed_count))
    out["v0_hat"] = v0
    out["go_fraction"] = _ratio(w, sums.go_samples, sums.known_samples)
    curves = pooled_curve(w, sums.msd)
    lag = np.asarray(sums.lag, dtype=np.float64)
    hi = options["ballistic_window"] * tau_g
    lo = options["diffusive_window"] * tau_g
    never = np.full(tau_g.shape, np.nan)
    known = np.isfinite(tau_g)
    lo_fit, hi_fit = np.where(known, lo, np.inf), np.where(known, hi, -np.inf)
    velocity = np.sqrt(power_fits(lag, curves, 2.0, np.zeros_like(hi), hi_fit))
    slope = power_fits(lag, curves, 1.0, lo_fit, np.full_like(lo, np.inf))
    out["ballistic_velocity"] = velocity
    out["msd_slope"] = slope
    out["msd_slope_affine"] = affine_fits(lag, curves, lo_fit)
    out["diffusion_coefficient"] = slope / 4
    with np.errstate(invalid="ignore", divide="ignore"):
        out["crossover_time"] = np.where(velocity > 0, slope / velocity**2, np.nan)
        out["msd_slope_theory"] = 2 * v0**2 * tau_g
        out["msd_slope_renewal"] = np.where(
            tau_g > 0, v0**2 * out["go_duration_second_moment"] / tau_g, np.nan
        )
    out["confined_diffusion_coefficient"] = confined_fits(
        lag, curves, lo_fit, float(options["confined_side"])
    )
    if sums.correlation is not None:
        c = pooled_curve(w, sums.correlation)
        out["green_kubo_slope"] = sums.interval * (c[:, 0] + 2 * np.nansum(c[:, 1:], axis=1))
        out["green_kubo_slope"][~np.isfinite(c[:, 0])] = np.nan
    else:
        out["green_kubo_slope"] = never.copy()
    if sums.turn_pairs is not None and sums.turn_cosine is not None:
        out["go_turn_cosine"] = _ratio(w, sums.turn_cosine, sums.turn_pairs)
    else:
        out["go_turn_cosine"] = never.copy()
    return out


def spread(samples: np.ndarray) -> np.ndarray:
    """The standard deviation over the leading axis of ``samples`` [row, ...] (ddof 1, NaN
    ignored), NaN where fewer than 2 rows are finite."""
    finite = np.isfinite(samples).sum(axis=0)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # entries with < 2 finite rows
        err = np.nanstd(samples, axis=0, ddof=1)
    return np.where(finite >= 2, err, np.nan)


def standard_error(samples: np.ndarray, n: int) -> np.ndarray:
    """The bootstrap standard error of resamples [resample, ...] of n independent units:
    the standard deviation over the finite resamples times sqrt(n / (n - 1)); NaN for
    n < 2 or fewer than 2 finite resamples."""
    samples = np.asarray(samples, dtype=np.float64)
    finite = np.isfinite(samples).sum(axis=0)
    if n < 2:
        return np.full(samples.shape[1:], np.nan)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # entries with < 2 finite resamples
        err = np.nanstd(samples, axis=0, ddof=1) * np.sqrt(n / (n - 1))
    return np.where(finite >= 2, err, np.nan)


def describe(n: int, resamples: int, blocks: bool = False) -> str:
    """What an ``_error`` variable is, for its attributes."""
    if n < 2:
        return (
            f"not measurable: {n} independent realization"
            f"{'' if n == 1 else 's'} (an error across realizations needs two or more)"
        )
    unit = (
        "realizations (the cells of one realization drawn together)" if blocks else ("realizations")
    )
    return (
        f"standard error across {n} {unit}: bootstrap of {resamples} resamples, their "
        f"standard deviation times sqrt(n / (n - 1))"
    )


def mean_of(w: np.ndarray, values: np.ndarray) -> np.ndarray:
    """float64[row]: the mean over realizations of ``values`` [realization] (NaN left out)
    under each row of weights ``w`` [row, realization]."""
    finite = np.isfinite(values)
    return _ratio(w, np.where(finite, values, 0.0), finite.astype(np.float64))


def sums_from_analysis(point: xr.Dataset) -> BodySums:
    """The per-realization sums of one point and body of an analysis Dataset (its
    ``NAME_realization`` variables), as :func:`estimates` takes them."""

    def get(name: str) -> np.ndarray:
        return np.asarray(point[name].values, dtype=np.float64)

    def total(mean: str, count: str) -> np.ndarray:
        return np.where(get(count) > 0, np.nan_to_num(get(mean)) * get(count), 0.0)

    speeds = get("speed_samples_realization")
    correlation = interval = None
    if "velocity_autocorrelation_realization" in point:
        correlation = get("velocity_autocorrelation_realization")
        interval = float(point["correlation_lag"].attrs["velocity_interval"])
    return BodySums(
        go_sum=total("mean_go_duration_realization", "go_events_realization"),
        go_count=get("go_events_realization"),
        go_square=total("go_duration_second_moment_realization", "go_events_realization"),
        stop_sum=total("mean_stop_duration_realization", "stop_events_realization"),
        stop_count=get("stop_events_realization"),
        speed_sum=np.where(speeds > 0, np.nan_to_num(get("mean_speed_realization")) * speeds, 0),
        speed_square=np.where(
            speeds > 0, np.nan_to_num(get("v0_hat_realization")) ** 2 * speeds, 0
        ),
        speed_count=speeds,
        go_samples=total("go_fraction_realization", "labelled_samples_realization"),
        known_samples=get("labelled_samples_realization"),
        msd=get("msd_realization"),
        lag=np.asarray(point["lag"].values, dtype=np.float64),
        correlation=correlation,
        interval=np.nan if interval is None else interval,
        turn_cosine=total("go_turn_cosine_realization", "go_turn_pairs"),
        turn_pairs=get("go_turn_pairs"),
    )
