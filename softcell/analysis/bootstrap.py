"""Uncertainties of a radius sweep's analysis: the bootstrap resamples behind its errors.

:func:`~softcell.analyze` stores every quantity's value per realization and its standard
error across realizations (module ``uncertainty``). What a finding needs beyond that is the
resamples themselves: a ratio of two quantities (the fit over the theory) has the error of
the ratio of their resamples, and the exponents of the scaling collapse are fitted again on
resampled MSD curves. :func:`sweep_estimates` draws the same resamples as the analysis did
(the same stream, from the analysis' seed, per point) from the analysis' per-realization
values, so its errors are the analysis' own.

Everything here reads an analysis Dataset and returns plain arrays; nothing is written.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr
from scipy import optimize

from softcell.analysis import correlation, uncertainty
from softcell.analysis.options import analysis_options
from softcell.analysis.sweep import COLLAPSE_VARIANTS, collapse_spread

#: Resamples of the free fit of the collapse exponents (each is an optimization).
COLLAPSE_RESAMPLES = 100


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
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a radius with no resample
            lo, hi = np.nanpercentile(self.samples, [tail, 100 - tail], axis=0)
        return lo, hi


def _options(analysis: xr.Dataset) -> dict[str, Any]:
    return analysis_options(
        {
            k: v
            for k, v in json.loads(analysis.attrs["softcell_analysis_options"]).items()
            if k not in ("detector", "threshold")
        }
    )


def standard_error(samples: np.ndarray, n: int | None = None) -> np.ndarray:
    """The bootstrap standard error of resamples [resample, ...] (axis 0) of n independent
    realizations (``uncertainty.standard_error``); without n, the plain standard deviation
    over the resamples (the error of a quantity built from resamples that already carry the
    factor sqrt(n / (n - 1)) of their own inputs), NaN below two finite resamples."""
    if n is not None:
        return uncertainty.standard_error(samples, n)
    return uncertainty.spread(samples)


#: The quantities :func:`sweep_estimates` returns (with ``correlation_tail``).
NAMES = (
    "mean_go_duration",
    "mean_stop_duration",
    "v0_hat",
    "ballistic_velocity",
    "msd_slope",
    "msd_slope_affine",
    "msd_slope_theory",
    "msd_slope_renewal",
    "go_duration_second_moment",
    "green_kubo_slope",
    "go_turn_cosine",
)


def sweep_estimates(
    analysis: xr.Dataset, seed: int | None = None, body: str = "cell", resamples: int | None = None
) -> dict[str, Any]:
    """The per-radius estimates of ``body`` with their bootstrap resamples.

    Parameters
    ----------
    analysis : xarray.Dataset
        :func:`~softcell.analyze`'s output over a ``radius`` sweep (or one point).
    seed : int, optional
        Seeds the resamples (default: the analysis' own ``softcell_seed``, as the analysis
        used: the errors are then the analysis' ``NAME_error``).
    body : str
        'cell' or 'bot'.
    resamples : int, optional
        Default: the analysis option ``resamples``.

    Returns
    -------
    dict of Estimate
        Every name of :data:`NAMES` and ``correlation_tail`` (1: the fraction of the
        Green-Kubo D hat from lags where the renewal theory's autocorrelation is 0,
        :func:`correlation_tail`), each with values as the analysis stored them (the tail:
        as measured), standard errors and resamples [resample, radius]. Under
        ``"msd_samples"``, the resampled cell MSD curves [radius, resample, lag] (cm^2)
        as a bare array for the collapse.
    """
    opts = _options(analysis)
    seed = int(analysis.attrs.get("softcell_seed", 0)) if seed is None else int(seed)
    resamples = int(opts["resamples"] if resamples is None else resamples)
    lag = np.asarray(analysis["lag"].values, dtype=np.float64)
    radii = np.atleast_1d(np.asarray(analysis["radius"].values, dtype=float))
    sel = analysis.sel(body=body)
    n_real = sel.sizes["realization"]
    samples = {n: np.full((resamples, radii.size), np.nan) for n in (*NAMES, "correlation_tail")}
    curves = np.full((radii.size, resamples, lag.size), np.nan)
    for i in range(radii.size):
        point = _point(sel, i)
        sums = uncertainty.sums_from_analysis(point)
        w = uncertainty.weights(n_real, resamples, uncertainty.rng_for(seed, i))
        values = uncertainty.estimates(sums, w, opts)
        for n in NAMES:
            samples[n][:, i] = values[n]
        curves[i] = uncertainty.pooled_curve(w, sums.msd)
        if sums.correlation is not None:
            c = uncertainty.pooled_curve(w, sums.correlation)
            k0 = _tail_start(point)
            with np.errstate(invalid="ignore", divide="ignore"):
                samples["correlation_tail"][:, i] = (
                    2 * sums.interval * c[:, k0:].sum(axis=1) / values["green_kubo_slope"]
                )
    out: dict[str, Any] = {}
    for n, resampled in samples.items():
        if n == "correlation_tail":
            value = np.array([correlation_tail(_point(sel, i)) for i in range(radii.size)])
        else:
            value = np.atleast_1d(np.asarray(sel[n].values, dtype=float))
        out[n] = Estimate(value, uncertainty.standard_error(resampled, n_real), resampled)
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
    window_end: float | None = None,
) -> CollapseFit | None:
    """Fit (a, b) freely over the decoupled radii (the curves and lag ranges the analysis'
    collapse metric uses: lags up to 10 <tau_g> of each radius, or up to ``window_end`` s),
    and again on the first ``resamples`` bootstrap resamples of their realizations
    (``msd_samples`` of :func:`sweep_estimates`). None with < 2 such radii."""
    decoupled = np.flatnonzero(np.asarray(analysis["regime"].values) == 2)
    if decoupled.size < 2:
        return None
    lag = np.asarray(analysis["lag"].values, dtype=np.float64)
    radii = np.asarray(analysis["radius"].values, dtype=float)[decoupled]
    cell = analysis.sel(body="cell")
    msd = np.asarray(cell["msd"].values, dtype=np.float64)[decoupled]
    ends = np.asarray(cell["diffusive_window_start"].values, dtype=np.float64)[decoupled]
    if window_end is not None:
        ends = np.full(ends.shape, float(window_end))
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
