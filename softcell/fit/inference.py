"""The posterior of the unknowns: an emulator of the statistics across the design, a Gaussian
synthetic likelihood, and emcee's ensemble sampler.

Simulations are the cost of a fit (a second of wall time per 120 s realization), so the
simulations are spent once, on the design, and the posterior is drawn from an emulator:

1. each statistic's mean over realizations at a design point (log-transformed where every
   value is positive) is emulated across the design by a Gaussian process
   (:class:`sklearn.gaussian_process.GaussianProcessRegressor`) in the priors' quantiles,
   each point's own noise (the variance of its mean across its realizations) given as its
   nugget;
2. the data's mean of the statistics then has the synthetic likelihood
   N(mu(theta), C / n + C / m + diag(s^2(theta))) (a Student t of C's degrees of freedom,
   since C is estimated): mu and s^2 the emulator's prediction and
   its variance, C the covariance of one realization's statistics, pooled over the design
   points (an approximation: C is taken not to vary across the prior box), n the data's
   realizations and m the design's. The term C / m is there because the design's points
   share their random numbers (common random numbers): their means carry one common error
   of that size, which no number of design points averages away. Without common random
   numbers (``common=False``) it is left out;
3. :class:`emcee.EnsembleSampler` draws from the posterior, the prior uniform in the
   quantiles (so each prior's scale, linear or log, holds by construction). Its walkers
   start at the best of 1024 quasi-random points of the prior box: started uniformly, a
   walker can be stranded in a spurious local maximum where the emulator extrapolates
   beyond the design (a fit of k = 0.2 N cm2 put 7 % of its samples at the prior's edge,
   0.05, where the likelihood is e^-215 of its peak, behind a valley the stretch move does
   not cross).

The emulator is trained once: data of the same design (new films, or synthetic data for a
coverage check) cost no further simulations.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from softcell.errors import SoftcellError
from softcell.fit.priors import Prior

#: The spawn key of the emulator's optimizer restarts and of the sampler under the fit's
#: root seed.
EMULATOR_KEY, SAMPLER_KEY = 7_001, 7_002


@dataclass(frozen=True)
class Emulator:
    """Gaussian-process emulators of the statistics' means, and the pooled covariance of one
    realization's statistics.

    Attributes
    ----------
    priors : tuple of Prior
        The unknowns; the emulators take their quantiles.
    logged : numpy.ndarray
        bool[statistic]: whether the statistic is emulated as its logarithm.
    processes : tuple
        One fitted :class:`~sklearn.gaussian_process.GaussianProcessRegressor` per
        statistic.
    covariance : numpy.ndarray
        float64[statistic, statistic]: the covariance of one realization's (transformed)
        statistics, pooled over the design points.
    shared : numpy.ndarray
        float64[statistic, statistic]: the covariance of the error that every design
        point's mean shares (``covariance`` over the design's realizations under common
        random numbers; zero without).
    dof : float
        The degrees of freedom of ``covariance``: realizations less one, summed over the
        points; under common random numbers, one point's (the points share their noise,
        so the others add little to what is known of it).
    """

    priors: tuple[Prior, ...]
    logged: np.ndarray
    processes: tuple[Any, ...]
    covariance: np.ndarray
    shared: np.ndarray
    dof: float

    def transform(self, each: np.ndarray) -> np.ndarray:
        """Statistics (last axis) as the emulator sees them: the logarithm where
        :attr:`logged`."""
        each = np.asarray(each, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.logged, np.log(np.where(self.logged, each, 1.0)), each)

    def predict(self, quantiles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The emulated means and their variances at prior quantiles float64[n, unknowns]:
        two float64[n, statistic], in the transformed statistics."""
        q = np.atleast_2d(np.asarray(quantiles, dtype=np.float64))
        mean = np.empty((q.shape[0], len(self.processes)))
        var = np.empty_like(mean)
        for k, process in enumerate(self.processes):
            mean[:, k], sd = process.predict(q, return_std=True)
            var[:, k] = sd**2
        return mean, var


def fit_emulator(
    priors: Sequence[Prior],
    values: np.ndarray,
    each: np.ndarray,
    *,
    seed: int,
    common: bool = True,
) -> Emulator:
    """The emulator of a design's statistics.

    Parameters
    ----------
    priors : sequence of Prior
        The unknowns.
    values : numpy.ndarray
        float64[point, unknown]: the design (each in its prior's unit).
    each : numpy.ndarray
        float64[point, realization, statistic]: every realization's statistics (NaN where
        undefined).
    seed : int
        The fit's root seed (the optimizer's restarts draw from it).
    common : bool
        Whether the design's points share their random numbers (as
        :func:`~softcell.fit.design.run_design` runs them).

    Raises
    ------
    SoftcellError
        For a design with fewer than two realizations per point, or a statistic undefined
        at some design point in every realization.
    """
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel

    each = np.asarray(each, dtype=np.float64)
    if each.ndim != 3 or each.shape[1] < 2:
        raise SoftcellError(
            "an emulator needs two or more realizations per design point, to know their noise"
        )
    finite = np.isfinite(each)
    logged = np.all(np.where(finite, each > 0, True), axis=(0, 1))
    placeholder = Emulator(tuple(priors), logged, (), np.empty((0, 0)), np.empty((0, 0)), 0.0)
    z = placeholder.transform(each)
    counts = np.sum(np.isfinite(z), axis=1)
    if np.any(counts < 2):
        point, k = np.argwhere(counts < 2)[0]
        raise SoftcellError(
            f"statistic {k} is defined in fewer than two realizations at design point {point}: "
            "the emulator cannot know its noise there (run longer realizations, or more)"
        )
    means = np.nanmean(z, axis=1)
    noise = np.nanvar(z, axis=1, ddof=1) / counts
    quantiles = np.column_stack([p.quantile(values[:, i]) for i, p in enumerate(priors)])
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(EMULATOR_KEY,)))
    processes = []
    for k in range(z.shape[2]):
        kernel = ConstantKernel(1.0, (1e-6, 1e4)) * RBF(
            np.full(len(priors), 0.5), length_scale_bounds=(1e-2, 1e2)
        )
        process = GaussianProcessRegressor(
            kernel,
            alpha=noise[:, k] / max(np.var(means[:, k]), 1e-300),
            normalize_y=True,
            n_restarts_optimizer=3,
            random_state=int(rng.integers(2**31)),
        )
        with warnings.catch_warnings():
            # A length scale at its upper bound (100 prior widths) is a statistic that the
            # unknown barely moves, or moves linearly: an answer, not a failure.
            warnings.filterwarnings("ignore", "The optimal value found for dimension .* upper")
            processes.append(process.fit(quantiles, means[:, k]))
    covariance, dof = _pooled_covariance(z)
    shared = covariance / each.shape[1] if common else np.zeros_like(covariance)
    if common:
        dof = float(each.shape[1] - 1)
    return Emulator(tuple(priors), logged, tuple(processes), covariance, shared, dof)


def _pooled_covariance(z: np.ndarray) -> tuple[np.ndarray, float]:
    """The covariance of one realization's statistics, pooled over the points
    (float64[point, realization, statistic]; realizations with a NaN left out), and its
    degrees of freedom."""
    total, dof = 0.0, 0
    for point in z:
        rows = point[np.all(np.isfinite(point), axis=1)]
        if rows.shape[0] > 1:
            total = total + np.cov(rows, rowvar=False, ddof=1) * (rows.shape[0] - 1)
            dof += rows.shape[0] - 1
    if dof == 0:
        raise SoftcellError("no design point has two realizations with every statistic defined")
    return np.atleast_2d(total / dof), float(dof)


def log_likelihood(emulator: Emulator, data: np.ndarray, quantiles: np.ndarray) -> np.ndarray:
    """The synthetic log likelihood of the data's statistics at prior quantiles.

    Parameters
    ----------
    emulator : Emulator
        Trained on the design.
    data : numpy.ndarray
        float64[realization, statistic]: the data's statistics per realization.
    quantiles : numpy.ndarray
        float64[n, unknown]: where to evaluate.

    Returns
    -------
    numpy.ndarray
        float64[n]: the log likelihood (natural log, up to a constant): a multivariate
        Student t of the emulator's ``dof`` degrees of freedom, since its covariance is
        estimated from the design's realizations (normal as they grow many).
    """
    z = emulator.transform(data)
    count = np.sum(np.isfinite(z), axis=0)
    observed = np.nanmean(z, axis=0)
    mean, var = emulator.predict(quantiles)
    scale = np.sqrt(np.outer(1 / count, 1 / count))  # C / n, n per statistic
    cov = emulator.covariance * scale + emulator.shared + var[:, :, None] * np.eye(var.shape[1])
    chol = np.linalg.cholesky(cov)
    w = np.linalg.solve(chol, (observed - mean)[:, :, None])[:, :, 0]
    nu, k = emulator.dof, mean.shape[1]
    log_det = np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1)
    return -0.5 * (nu + k) * np.log1p(np.sum(w * w, axis=1) / nu) - log_det


def sample_posterior(
    emulator: Emulator,
    data: np.ndarray,
    *,
    seed: int,
    walkers: int | None = None,
    steps: int = 1500,
    burn: int = 500,
) -> np.ndarray:
    """Posterior draws of the unknowns, float64[sample, unknown] in each prior's unit.

    Parameters
    ----------
    emulator : Emulator
        Trained on the design.
    data : numpy.ndarray
        float64[realization, statistic]: the data's statistics per realization.
    seed : int
        The fit's root seed (the walkers' start and moves draw from it).
    walkers : int, optional
        emcee's walkers (default: 8 per unknown, at least 16).
    steps, burn : int
        Steps per walker, and the first of them discarded.
    """
    import emcee

    d = len(emulator.priors)
    walkers = walkers or max(16, 8 * d)
    sequence = np.random.SeedSequence(seed, spawn_key=(SAMPLER_KEY,))
    start_rng, move_seed = np.random.default_rng(sequence), int(sequence.generate_state(1)[0])

    def log_probability(q: np.ndarray) -> np.ndarray:
        q = np.atleast_2d(q)
        inside = np.all((q >= 0) & (q <= 1), axis=1)
        out = np.full(q.shape[0], -np.inf)
        if inside.any():
            out[inside] = log_likelihood(emulator, data, q[inside])
        return out

    from scipy.stats import qmc

    screen = qmc.Sobol(d, scramble=True, seed=start_rng).random_base2(10)
    start = screen[np.argsort(log_probability(screen))[::-1][:walkers]]
    sampler = emcee.EnsembleSampler(walkers, d, log_probability, vectorize=True)
    sampler.random_state = np.random.RandomState(move_seed).get_state()
    sampler.run_mcmc(start, steps, progress=False)
    q = sampler.get_chain(discard=burn, flat=True)
    return np.column_stack([p.value(q[:, i]) for i, p in enumerate(emulator.priors)])
