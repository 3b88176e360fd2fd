"""Fits of an MSD curve and the run-and-tumble theory (docs/model.md §6; SI Sec. S3, S4).

Two conventions for diffusion, never mixed up:

- ``msd_slope`` D hat (cm^2/s): the long-time slope, MSD ~ D hat tau (the paper's D hat,
  = 2 v0_hat^2 <tau_g> in theory);
- ``diffusion_coefficient`` D (cm^2/s) = D hat / 4, MSD -> 4 D tau in two dimensions, which is
  also the convention of the confined-square formula (SI:EQ:MSD_confined).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

#: Terms of the confined-square series (the paper's 51: p = 0..50).
CONFINED_TERMS = 51


@dataclass(frozen=True)
class PowerFit:
    """MSD = coefficient tau^exponent with a fixed exponent, fitted in log space.

    ``coefficient`` and its standard error ``error`` (from the scatter of the log residuals),
    ``points`` the number of lags used (0: nothing to fit, coefficient NaN).
    """

    coefficient: float
    error: float
    points: int


def power_fit(lag: np.ndarray, msd: np.ndarray, exponent: float, lo: float, hi: float) -> PowerFit:
    """Least squares of log MSD = log c + exponent log tau over lo <= tau <= hi (s)."""
    lag = np.asarray(lag, dtype=np.float64)
    msd = np.asarray(msd, dtype=np.float64)
    use = (lag >= lo) & (lag <= hi) & np.isfinite(msd) & (msd > 0) & (lag > 0)
    n = int(use.sum())
    if n == 0:
        return PowerFit(np.nan, np.nan, 0)
    residual = np.log(msd[use]) - exponent * np.log(lag[use])
    log_c = residual.mean()
    error = residual.std(ddof=1) / np.sqrt(n) if n > 1 else np.nan
    c = float(np.exp(log_c))
    return PowerFit(c, c * float(error), n)


def ballistic_velocity(lag, msd, hi: float) -> tuple[float, float, int]:
    """v (cm/s) of MSD = v^2 tau^2 for tau <= hi (s), with its standard error and the number of
    lags used."""
    fit = power_fit(lag, msd, 2.0, 0.0, hi)
    v = np.sqrt(fit.coefficient)
    return float(v), float(0.5 * fit.error / v) if fit.points > 1 else np.nan, fit.points


def msd_slope(lag, msd, lo: float) -> tuple[float, float, int]:
    """D hat (cm^2/s) of MSD = D hat tau for tau >= lo (s), with its standard error and the
    number of lags used."""
    fit = power_fit(lag, msd, 1.0, lo, np.inf)
    return fit.coefficient, fit.error, fit.points


def affine_slope(lag, msd, lo: float) -> float:
    """D hat (cm^2/s) of MSD = D hat tau + b over tau >= lo (s), least squares in relative
    error (each lag weighted by 1 / MSD, as a fit in log space weights it): unlike
    :func:`msd_slope`, not biased by the MSD's offset b at long lags (b < 0 after a
    ballistic start: MSD ~ D hat (tau - tau_c))."""
    lag = np.asarray(lag, dtype=np.float64)
    msd = np.asarray(msd, dtype=np.float64)
    use = (lag >= lo) & np.isfinite(msd) & (msd > 0)
    if use.sum() < 2:
        return np.nan
    design = np.stack([lag[use], np.ones(int(use.sum()))], axis=1) / msd[use, None]
    return float(np.linalg.lstsq(design, np.ones(int(use.sum())), rcond=None)[0][0])


def crossover_time(velocity: float, slope: float) -> float:
    """tau* (s) where v^2 tau^2 = D hat tau, i.e. D hat / v^2 (the paper's Delta_c ~ v tau^2
    means v^2)."""
    return slope / velocity**2 if velocity > 0 else np.nan


def confined_square_msd(
    lag: np.ndarray, diffusion: float, side: float, terms: int = CONFINED_TERMS
) -> np.ndarray:
    """MSD (cm^2) of a Brownian particle with diffusion coefficient D (cm^2/s, MSD -> 4 D tau
    at short lags) in a square of side L (cm), averaged over a uniform start
    (SI:EQ:MSD_confined): L^2/3 - (32 L^2 / pi^4) sum_p exp(-pi^2 D tau (2p+1)^2 / L^2)
    / (2p+1)^4, p = 0..terms-1."""
    lag = np.asarray(lag, dtype=np.float64)
    odd = 2.0 * np.arange(terms) + 1.0
    decay = np.exp(-(np.pi**2) * diffusion * np.multiply.outer(lag, odd**2) / side**2)
    return side**2 / 3 - 32 * side**2 / np.pi**4 * (decay / odd**4).sum(axis=-1)


def confined_square_fit(
    lag, msd, side: float, lo: float = 0.0, hi: float = np.inf
) -> tuple[float, int]:
    """D (cm^2/s) of the confined-square formula fitted in log space over lo <= tau <= hi,
    and the number of lags used."""
    lag = np.asarray(lag, dtype=np.float64)
    msd = np.asarray(msd, dtype=np.float64)
    use = (lag >= lo) & (lag <= hi) & (lag > 0) & np.isfinite(msd) & (msd > 0)
    n = int(use.sum())
    if n == 0:
        return np.nan, n
    t, y = lag[use], np.log(msd[use])

    def cost(log_d):
        return np.sum((np.log(confined_square_msd(t, np.exp(log_d), side)) - y) ** 2)

    # A first guess from the shortest lag (MSD ~ 4 D tau), then a bounded search around it.
    guess = np.log(msd[use][0] / (4 * t[0]))
    best = optimize.minimize_scalar(
        cost, bounds=(guess - 12, guess + 12), method="bounded", options={"xatol": 1e-10}
    )
    return float(np.exp(best.x)), n


def run_and_tumble_msd(lag: np.ndarray, v0_hat: float, mean_go: float) -> np.ndarray:
    """SI:EQ:msd: 2 v0_hat^2 (tau <tau_g> - <tau_g>^2 (1 - exp(-tau / <tau_g>))) (cm^2).
    (The main text's Eq. 3 prints exp(+tau/<tau_g>): a typo.)"""
    lag = np.asarray(lag, dtype=np.float64)
    return 2 * v0_hat**2 * (lag * mean_go - mean_go**2 * -np.expm1(-lag / mean_go))


def renewal_msd_slope(v0_hat: float, mean_go: float, go_second_moment: float) -> float:
    """D hat (cm^2/s) of alternating go and stop phases of any duration distributions, the
    go phases at one speed, each in a new uniformly random direction (a renewal process):
    v^2 <tau_g^2> / (<tau_g> + <tau_s>) = v0_hat^2 <tau_g^2> / <tau_g>, since v0_hat^2 = v^2
    <tau_g> / (<tau_g> + <tau_s>). Exponential go phases (<tau_g^2> = 2 <tau_g>^2) give the
    paper's 2 v0_hat^2 <tau_g>. ``mean_go`` in s, ``go_second_moment`` in s^2."""
    return v0_hat**2 * go_second_moment / mean_go


def v0_hat(speed: np.ndarray) -> float:
    """sqrt(mean^2 + variance) of the full speed distribution (stops included), i.e. the root
    mean square speed (cm/s); NaN samples are ignored."""
    speed = np.asarray(speed, dtype=np.float64)
    speed = speed[np.isfinite(speed)]
    return float(np.sqrt(np.mean(speed**2))) if speed.size else np.nan
