"""The paper's findings beside ours: each a measured value and a verdict computed from the
numbers, with the rule the verdict follows (:func:`findings`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import xarray as xr

from softcell.core.schema import REGIME_NAMES


@dataclass(frozen=True)
class Finding:
    """One row of the findings table."""

    topic: str
    paper: str
    measured: str
    verdict: str  # "agrees", "differs", "partly" or "not measured"
    rule: str  # how the verdict follows from the numbers


def cell_values(analysis: xr.Dataset, name: str) -> np.ndarray:
    """The cell's (``body = "cell"``) values of the analysis variable ``name``, as floats in
    the variable's own unit."""
    return np.asarray(analysis[name].sel(body="cell").values, dtype=float)


def _trend(radii: np.ndarray, values: np.ndarray) -> tuple[float, float]:
    from scipy.stats import spearmanr

    ok = np.isfinite(values)
    if ok.sum() < 3 or np.ptp(values[ok]) == 0:
        return np.nan, np.nan  # no trend to rank
    result = spearmanr(radii[ok], values[ok])
    return float(result.statistic), float(result.pvalue)


def _trend_finding(
    topic: str, paper: str, radii: np.ndarray, values: np.ndarray, unit: str, sign: int
) -> Finding:
    rho, p = _trend(radii, values)
    word = "increasing" if sign > 0 else "decreasing"
    measured = (
        f"{values[0]:.3g} {unit} at R = {radii[0]:g} cm, {values[-1]:.3g} {unit} at "
        f"{radii[-1]:g} cm; Spearman rho = {rho:+.2f} (p = {p:.2g})"
    )
    if not np.isfinite(rho):
        verdict = "not measured"
    else:
        verdict = "agrees" if sign * rho > 0 and p < 0.05 else "differs"
    return Finding(
        topic,
        paper,
        measured,
        verdict,
        f"{word}: Spearman rank correlation with R of sign {sign:+d} and p < 0.05",
    )


class _Sweep(NamedTuple):
    """What every finding reads: the analysis of a radius sweep, the free bot's (or None),
    the radii (cm), the regime code and the bot-cell GC distance / R per radius."""

    analysis: xr.Dataset
    free_bot: xr.Dataset | None
    radii: np.ndarray
    regime: np.ndarray
    ratio: np.ndarray


def _regime_verdict(radii: np.ndarray, regime: np.ndarray) -> str:
    small = [regime[i] for i, r in enumerate(radii) if r in (4.0, 5.0)]
    large = [regime[i] for i, r in enumerate(radii) if r >= 12.0]
    monotone = bool(np.all(np.diff(regime) >= 0))
    if not small or not large:
        return "not measured"
    if all(g == 0 for g in small) and all(g == 2 for g in large) and monotone:
        return "agrees"
    if small[0] == 0 and all(g == 2 for g in large):
        return "partly"
    return "differs"


def _regime_findings(sweep: _Sweep) -> list[Finding]:
    """The regime per radius."""
    radii, regime, ratio = sweep.radii, sweep.regime, sweep.ratio
    rows: list[Finding] = []
    names = ", ".join(
        f"{r:g}: {REGIME_NAMES[g]} ({q:.2f})" for r, g, q in zip(radii, regime, ratio, strict=True)
    )
    verdict = _regime_verdict(radii, regime)
    rows.append(
        Finding(
            "regime per R",
            "coupled at R = 4 and 5 cm, a continuous crossover, decoupled at large R (12 cm shown)",
            f"R (cm): regime (bot-cell GC distance / R): {names}",
            verdict,
            "agrees: 4 and 5 cm coupled, >= 12 cm decoupled, regimes in order of R; "
            "partly: 4 cm coupled and >= 12 cm decoupled",
        )
    )
    return rows


def _trend_findings(sweep: _Sweep) -> list[Finding]:
    """<tau_s>, <tau_g>, the ballistic velocity and D hat against R."""
    analysis, radii, regime = sweep.analysis, sweep.radii, sweep.regime
    rows: list[Finding] = []
    rows.append(
        _trend_finding(
            "<tau_s> against R",
            "increases monotonically with R",
            radii,
            cell_values(analysis, "mean_stop_duration"),
            "s",
            +1,
        )
    )
    tau_g = cell_values(analysis, "mean_go_duration")
    if np.isfinite(tau_g).any():
        peak = int(np.nanargmax(tau_g))
        dec = regime == 2
        spread = (np.nanstd(tau_g[dec]) / np.nanmean(tau_g[dec])) if dec.sum() >= 2 else np.nan
        grows = tau_g[peak] > tau_g[0]
        verdict = (
            "agrees"
            if grows and regime[peak] == 1 and spread < 0.1
            else ("partly" if grows else "differs")
        )
        rows.append(
            Finding(
                "<tau_g> against R",
                "grows beyond the coupled state, longest in the intermediate "
                "regime, saturates in the decoupled regime",
                f"{tau_g[0]:.3g} s at R = {radii[0]:g} cm; largest {tau_g[peak]:.3g} s at R = "
                f"{radii[peak]:g} cm ({REGIME_NAMES[regime[peak]]}); spread over the decoupled "
                f"radii {spread:.1%} of their mean",
                verdict,
                "agrees: the largest <tau_g> exceeds that of the smallest R, lies in the "
                "intermediate regime, and the decoupled radii spread < 10 %; partly: only the "
                "first",
            )
        )
    rows.append(
        _trend_finding(
            "ballistic velocity against R",
            "decreases with R (Fig. 4a)",
            radii,
            cell_values(analysis, "ballistic_velocity"),
            "cm/s",
            -1,
        )
    )
    rows.append(
        _trend_finding(
            "D hat (fitted MSD slope) against R",
            "decreases with R (Fig. 4b)",
            radii,
            cell_values(analysis, "msd_slope"),
            "cm2/s",
            -1,
        )
    )
    return rows


def _collapse_findings(sweep: _Sweep) -> list[Finding]:
    """The scaling collapse of the decoupled radii."""
    analysis = sweep.analysis
    rows: list[Finding] = []
    if "collapse_metric" in analysis:
        metric = np.asarray(analysis["collapse_metric"].values, dtype=float)
        variants = [str(v) for v in analysis["collapse_variant"].values]
        paper = int(
            np.flatnonzero(
                (analysis["collapse_msd_exponent"].values > 0)
                & (analysis["collapse_lag_exponent"].values < 0)
            )[0]
        )
        if np.isfinite(metric).any():
            order = np.argsort(np.where(np.isfinite(metric), metric, np.inf))
            listed = "; ".join(f"{variants[k]}: {metric[k]:.3f}" for k in order)
            verdict = "agrees" if order[0] == paper else "differs"
        else:
            listed, verdict = "fewer than two decoupled radii", "not measured"
        radii_used = np.atleast_1d(analysis["collapse_metric"].attrs.get("radii", []))
        rows.append(
            Finding(
                "scaling collapse",
                "ballistic and crossover MSDs of the decoupled radii collapse "
                "with MSD R^(1/3) against lag R^(-1)",
                f"spread in decades over R = {', '.join(f'{r:g}' for r in radii_used)} cm, best "
                f"first: {listed}",
                verdict,
                "agrees: the paper's variant has the smallest spread of the four",
            )
        )
    return rows


def _theory_findings(sweep: _Sweep) -> list[Finding]:
    """The theory's v0 hat and D hat against the fits."""
    analysis, radii = sweep.analysis, sweep.radii
    rows: list[Finding] = []
    fit, theory = cell_values(analysis, "ballistic_velocity"), cell_values(analysis, "v0_hat")
    dev = np.abs(fit / theory - 1)
    rows.append(
        Finding(
            "theory: v0 hat against the ballistic fit",
            "consistent (Fig. 4a)",
            f"|fit / v0_hat - 1| <= {np.nanmax(dev):.1%} over all R "
            f"(median {np.nanmedian(dev):.1%})",
            "agrees" if np.nanmax(dev) < 0.1 else "differs",
            "agrees: within 10 % at every R",
        )
    )
    fit, theory = cell_values(analysis, "msd_slope"), cell_values(analysis, "msd_slope_theory")
    q = fit / theory
    big = radii >= 10
    rows.append(
        Finding(
            "theory: D hat against the fitted MSD slope",
            "fair overall agreement; at large R the "
            "theory falls below the fits (it underestimates velocity correlations)",
            "fit / theory: " + ", ".join(f"{r:g}: {v:.2f}" for r, v in zip(radii, q, strict=True)),
            "agrees" if big.any() and np.all(q[big] > 1) else "differs",
            "agrees: fit / theory > 1 at every R >= 10 cm",
        )
    )
    return rows


def _duration_findings(sweep: _Sweep) -> list[Finding]:
    """The stop and go durations' distributions."""
    analysis = sweep.analysis
    rows: list[Finding] = []
    ks_go, ks_stop = (
        cell_values(analysis, "go_ks_statistic"),
        cell_values(analysis, "stop_ks_statistic"),
    )
    rows.append(
        Finding(
            "stop and go durations",
            "exponential in experiments; in simulations the go phases "
            "deviate at short times (the membrane's finite relaxation)",
            f"Kolmogorov-Smirnov distance of t/<t> to exp(-t'), median over R: go "
            f"{np.nanmedian(ks_go):.2f}, stop {np.nanmedian(ks_stop):.2f} (Fig. S2)",
            "not measured",
            "a reading of Fig. S2; no verdict is computed",
        )
    )
    return rows


def _bot_msd_findings(sweep: _Sweep) -> list[Finding]:
    """The bot's MSD inside the membrane against the free bot's."""
    analysis, free_bot = sweep.analysis, sweep.free_bot
    rows: list[Finding] = []
    if free_bot is not None:
        lag = analysis["lag"].values
        free = free_bot["msd"].sel(body="bot")
        free = np.asarray(free.isel({d: 0 for d in free.dims if d != "lag"}).values)
        bot = np.asarray(analysis["msd"].sel(body="bot").values)
        k_short = int(np.argmin(np.abs(lag - 0.1)))
        k_long = int(np.argmin(np.abs(lag - 10.0)))
        short = bot[:, k_short] / free[k_short]
        long = bot[:, k_long] / free[k_long]
        rows.append(
            Finding(
                "bot MSD inside the membrane (S1)",
                "almost unaffected by the membrane",
                f"bot in membrane / free bot at lag {lag[k_short]:.2g} s: "
                f"{np.nanmin(short):.2f} to "
                f"{np.nanmax(short):.2f}; at {lag[k_long]:.3g} s: {np.nanmin(long):.2f} to "
                f"{np.nanmax(long):.2f} (over R)",
                "agrees" if np.nanmin(short) > 0.5 else "differs",
                "agrees: the short-lag ratio stays above 0.5 at every R",
            )
        )
    return rows


def _merge_findings(sweep: _Sweep) -> list[Finding]:
    """The bot's and the cell's MSD at R = 12 cm."""
    analysis, radii = sweep.analysis, sweep.radii
    rows: list[Finding] = []
    i12 = np.flatnonzero(radii == 12.0)
    if i12.size:
        msd = analysis["msd"].isel(radius=int(i12[0]))
        pairs = analysis["msd_pairs"].isel(radius=int(i12[0])).sel(body="cell").values
        k = int(np.flatnonzero(pairs > 0)[-1])
        ratio12 = float(msd.sel(body="bot")[k] / msd.sel(body="cell")[k])
        short12 = float(msd.sel(body="bot")[0] / msd.sel(body="cell")[0])
        rows.append(
            Finding(
                "bot and cell MSD at R = 12 cm (S3)",
                "distinct at short lags, merge at long lags",
                f"bot / cell MSD: {short12:.3g} at {float(analysis['lag'][0]):.2g} s, "
                f"{ratio12:.2f} at {float(analysis['lag'][k]):.3g} s",
                "agrees" if short12 > 2 and abs(ratio12 - 1) < 0.5 else "differs",
                "agrees: ratio > 2 at the shortest lag and within 50 % of 1 at the longest",
            )
        )
    return rows


#: The findings in the order the report lists them.
FINDINGS = (
    _regime_findings,
    _trend_findings,
    _collapse_findings,
    _theory_findings,
    _duration_findings,
    _bot_msd_findings,
    _merge_findings,
)


def findings(analysis: xr.Dataset, free_bot: xr.Dataset | None = None) -> list[Finding]:
    """The paper's findings beside the measured values of a radius sweep's analysis."""
    radii = np.asarray(analysis["radius"].values, dtype=float)
    regime = np.asarray(analysis["regime"].values, dtype=int)
    ratio = np.asarray(analysis["gc_distance_ratio"].values, dtype=float)
    sweep = _Sweep(analysis, free_bot, radii, regime, ratio)
    return [row for finding in FINDINGS for row in finding(sweep)]
