"""Uncertainties of a radius sweep's analysis: a bootstrap over realizations.

The realizations of one radius are independent (their own random streams), so resampling
them with replacement and repeating a measurement on each resample gives its sampling
distribution, whatever the measurement: a ratio of pooled sums (the mean durations), a fit
(the ballistic velocity, D hat, whose fitting windows move with each resample's <tau_g>), or
a fit over several radii (the exponents of the scaling collapse). A standard error is the
standard deviation over the resamples; an interval, their 2.5 and 97.5 percentiles.

Everything here reads an analysis Dataset (:func:`softcell.analyze`'s output, which keeps
the per-realization labels, speeds and MSDs) and returns plain arrays; nothing is written.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr
from scipy import optimize

from softcell.core.analysis import correlation, fits, stopgo
from softcell.core.analysis.options import analysis_options
from softcell.core.analysis.series import segments
from softcell.core.analysis.sweep import COLLAPSE_VARIANTS, LagPlan, collapse_spread

#: Resamples of the realizations per radius.
RESAMPLES = 400
#: Resamples of the free fit of the collapse exponents (each is an optimization).
COLLAPSE_RESAMPLES = 100
#: The first entry of the spawn key of every bootstrap stream (a realization's stream is
#: (point, realization); this one cannot collide with a point index).
STREAM = 2**31 - 1


@dataclass(frozen=True)
class Estimate:
    """A measured value per radius with its standard error (same unit), and the bootstrap
    resamples behind the error ([resample, radius]; NaN where not measurable)."""

    value: np.ndarray
    error: np.ndarray
    samples: np.ndarray

    def interval(self, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """The percentile interval of the resamples per radius."""
        tail = 50 * (1 - level)
        with np.errstate(invalid="ignore"):
            lo, hi = np.nanpercentile(self.samples, [tail, 100 - tail], axis=0)
        return lo, hi


def _options(analysis: xr.Dataset) -> dict[str, Any]:
    import json

    return analysis_options(
        {
            k: v
            for k, v in json.loads(analysis.attrs["softcell_analysis_options"]).items()
            if k not in ("detector", "threshold")
        }
    )


def _rng(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(STREAM, *key)))


def standard_error(samples: np.ndarray) -> np.ndarray:
    """The standard deviation over resamples (axis 0) where at least 2 are finite, else NaN:
    the bootstrap standard error, in the samples' unit."""
    finite = np.isfinite(samples).sum(axis=0)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # radii with < 2 finite resamples
        err = np.nanstd(samples, axis=0, ddof=1)
    return np.where(finite >= 2, err, np.nan)


def sweep_estimates(
    analysis: xr.Dataset, seed: int, body: str = "cell", resamples: int = RESAMPLES
) -> dict[str, Estimate]:
    """The per-radius estimates of ``body`` with bootstrap standard errors.

    Returns
    -------
    dict of Estimate
        ``mean_go_duration``, ``mean_stop_duration`` (s), ``v0_hat``, ``ballistic_velocity``
        (cm/s), ``msd_slope`` (cm^2/s): values as the analysis stored them;
        ``go_duration_second_moment`` <tau_g^2> (s^2) of the pooled go phases; if the analysis
        has the velocity autocorrelation, ``green_kubo_slope`` (cm^2/s), ``correlation_tail``
        (1: the fraction of it from lags where the renewal theory's autocorrelation is 0,
        :func:`correlation_tail`) and ``go_turn_cosine`` (1); errors from
        ``resamples`` resamples of the realizations of each radius (seeded by ``seed``).
        ``msd`` ([radius, resample, lag] cm^2 resampled MSD curves) is under the key
        ``"msd_samples"`` as a bare array for the collapse.
    """
    opts = _options(analysis)
    time = np.asarray(analysis["time"].values, dtype=np.float64)
    plan = LagPlan(time, opts)
    only = segments(time).index(plan.fine) if opts["stopgo_segments"] == "finest" else None
    lag = np.asarray(analysis["lag"].values, dtype=np.float64)
    radii = np.atleast_1d(np.asarray(analysis["radius"].values, dtype=float))
    sel = analysis.sel(body=body)
    names = ("mean_go_duration", "mean_stop_duration", "v0_hat", "ballistic_velocity")
    names += ("msd_slope", "go_duration_second_moment")
    if "velocity_autocorrelation_realization" in sel:
        names += ("green_kubo_slope", "correlation_tail", "go_turn_cosine")
    samples = {n: np.full((resamples, radii.size), np.nan) for n in names}
    curves = np.full((radii.size, resamples, lag.size), np.nan)
    for i in range(radii.size):
        point = _point(sel, i)
        labels = np.asarray(point["stopgo_label"].values)
        speed = np.asarray(point["speed"].values, dtype=np.float64)
        each = np.asarray(point["msd_realization"].values, dtype=np.float64)
        n_real = labels.shape[0]
        sums = np.zeros((n_real, 5))  # go sum, go count, stop sum, stop count, go^2 sum
        for k in range(n_real):
            d = stopgo.durations(labels[k], time, only)
            sums[k] = d.go.sum(), d.go.size, d.stop.sum(), d.stop.size, (d.go**2).sum()
        fine = speed[:, plan.fine.first : plan.fine.last]
        squares = np.nansum(fine**2, axis=1), np.isfinite(fine).sum(axis=1)
        idx = _rng(seed, i).integers(0, n_real, (resamples, n_real))
        with np.errstate(invalid="ignore", divide="ignore"):
            picked = sums[idx].sum(axis=1)
            tau_g = picked[:, 0] / picked[:, 1]
            samples["mean_go_duration"][:, i] = tau_g
            samples["mean_stop_duration"][:, i] = picked[:, 2] / picked[:, 3]
            samples["go_duration_second_moment"][:, i] = picked[:, 4] / picked[:, 1]
            samples["v0_hat"][:, i] = np.sqrt(squares[0][idx].sum(1) / squares[1][idx].sum(1))
        if "green_kubo_slope" in names:
            for n, v in _correlation_samples(point, idx).items():
                samples[n][:, i] = v
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # lags no resample reaches
            curves[i] = np.nanmean(each[idx], axis=1)
        for b in range(resamples):
            if not np.isfinite(tau_g[b]):
                continue
            samples["ballistic_velocity"][b, i] = fits.ballistic_velocity(
                lag, curves[i, b], opts["ballistic_window"] * tau_g[b]
            )[0]
            samples["msd_slope"][b, i] = fits.msd_slope(
                lag, curves[i, b], opts["diffusive_window"] * tau_g[b]
            )[0]
    out: dict[str, Any] = {}
    for n in names:
        if n == "go_duration_second_moment":
            go = np.asarray(sel["go_duration"].values, dtype=float).reshape(radii.size, -1)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # a radius with no go phase
                value = np.nanmean(go**2, axis=-1)
        elif n == "correlation_tail":
            value = np.array([correlation_tail(_point(sel, i)) for i in range(radii.size)])
        else:
            value = np.atleast_1d(np.asarray(sel[n].values, dtype=float))
        out[n] = Estimate(value, standard_error(samples[n]), samples[n])
    out["msd_samples"] = curves
    return out


def _point(sel: xr.Dataset, i: int) -> xr.Dataset:
    return sel.isel(radius=i) if "radius" in sel.dims else sel


def _tail_start(point: xr.Dataset) -> int:
    """The first lag index from which the renewal theory's velocity autocorrelation is 0
    (beyond the longest go phase); the number of lags if it never is."""
    theory = np.asarray(point["velocity_autocorrelation_renewal"].values, dtype=float)
    nonzero = np.flatnonzero(theory != 0)  # NaN counts as non-zero
    return int(nonzero[-1]) + 1 if nonzero.size else 0


def correlation_tail(point: xr.Dataset) -> float:
    """The fraction of the Green-Kubo D hat of one point and body (an analysis selection with
    ``velocity_autocorrelation``) from the lags where the renewal theory's velocity
    autocorrelation vanishes: the velocity correlations across go phases (1)."""
    c = np.asarray(point["velocity_autocorrelation"].values, dtype=float)
    dt = float(point["correlation_lag"].attrs["velocity_interval"])
    k0 = _tail_start(point)
    return float(2 * dt * c[k0:].sum() / correlation.green_kubo_slope(c, dt))


def _correlation_samples(point: xr.Dataset, idx: np.ndarray) -> dict[str, np.ndarray]:
    """Resampled Green-Kubo D hat, correlation tail and turn cosine of one point (resamples
    ``idx`` [resample, realization] of its realizations)."""
    each = np.asarray(point["velocity_autocorrelation_realization"].values, dtype=float)
    dt = float(point["correlation_lag"].attrs["velocity_interval"])
    k0 = _tail_start(point)
    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)  # lags no resample reaches
        c = np.nanmean(each[idx], axis=1)
        slope = dt * (c[:, 0] + 2 * c[:, 1:].sum(axis=1))
        pairs = np.asarray(point["go_turn_pairs"].values, dtype=float)
        cos = np.nan_to_num(np.asarray(point["go_turn_cosine_realization"].values, dtype=float))
        turn = (cos * pairs)[idx].sum(axis=1) / pairs[idx].sum(axis=1)
        return {
            "green_kubo_slope": slope,
            "correlation_tail": 2 * dt * c[:, k0:].sum(axis=1) / slope,
            "go_turn_cosine": turn,
        }


@dataclass(frozen=True)
class CollapseFit:
    """The exponents (a, b) of MSD R^a against lag R^b that collapse the curves best, their
    bootstrap resamples ([resample, 2]) and the spread (decades) at the best and at each of
    the paper's four candidate pairs."""

    exponents: np.ndarray
    samples: np.ndarray
    spread: float
    candidates: dict[tuple[float, float], float]

    def interval(self, level: float = 0.95) -> np.ndarray:
        """[[a_lo, a_hi], [b_lo, b_hi]]: percentile intervals of the resamples."""
        tail = 50 * (1 - level)
        return np.nanpercentile(self.samples, [tail, 100 - tail], axis=0).T


def _best_exponents(lag, msd, radii, ends, start) -> tuple[np.ndarray, float]:
    def cost(ab):
        value = collapse_spread(lag, msd, radii, ends, ab[0], ab[1])
        return value if np.isfinite(value) else 1e3

    best = optimize.minimize(
        cost, start, method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-7}
    )
    return np.asarray(best.x, dtype=float), float(best.fun)


def collapse_fit(
    analysis: xr.Dataset,
    msd_samples: np.ndarray,
    resamples: int = COLLAPSE_RESAMPLES,
) -> CollapseFit | None:
    """Fit (a, b) freely over the decoupled radii (the curves and lag ranges the analysis'
    collapse metric uses), and again on the first ``resamples`` bootstrap resamples of their
    realizations (``msd_samples`` of :func:`sweep_estimates`). None with < 2 such radii."""
    decoupled = np.flatnonzero(np.asarray(analysis["regime"].values) == 2)
    if decoupled.size < 2:
        return None
    lag = np.asarray(analysis["lag"].values, dtype=np.float64)
    radii = np.asarray(analysis["radius"].values, dtype=float)[decoupled]
    cell = analysis.sel(body="cell")
    msd = np.asarray(cell["msd"].values, dtype=np.float64)[decoupled]
    ends = np.asarray(cell["diffusive_window_start"].values, dtype=np.float64)[decoupled]
    candidates = {
        (a, b): collapse_spread(lag, msd, radii, ends, a, b) for a, b in COLLAPSE_VARIANTS
    }
    start = np.array(min(candidates, key=lambda k: np.nan_to_num(candidates[k], nan=np.inf)))
    best, spread = _best_exponents(lag, msd, radii, ends, start)
    # Resample k of every radius: independent resamples (each radius has its own stream);
    # the lag ranges stay those of the measured curves.
    count = min(resamples, msd_samples.shape[1])
    samples = np.full((count, 2), np.nan)
    for k in range(count):
        samples[k] = _best_exponents(lag, msd_samples[decoupled, k], radii, ends, best)[0]
    return CollapseFit(best, samples, spread, candidates)
