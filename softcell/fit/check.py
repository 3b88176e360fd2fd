"""The posterior predictive check of a fit: the statistics re-simulated at posterior draws,
beside the data's, with a verdict per statistic.

``draws`` posterior samples, evenly spaced through the sample, are each simulated with the
data's request and as many realizations as the data has, each from its own root seed
(derived from the fit's, so that the check's spread holds the noise of the data's mean as
well as the parameters' uncertainty). For each statistic and point of the data, z is the
data's mean less the mean of the draws' means, over the predictive standard deviation of a
mean: the larger of the draws' means' spread and the realizations' spread within a draw
(pooled over the draws) over the square root of the data's realizations (with few draws
the first alone is too noisy to judge by). The rule is ``consistent`` when |z| <= 2,
``inconsistent`` otherwise.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from softcell.fit.priors import Prior
from softcell.model.configuration import RunConfig

#: The spawn key of the check's root seeds under the fit's root seed.
CHECK_KEY = 7_003
#: |z| above which a statistic is inconsistent with the fit.
LIMIT = 2.0
VERDICTS = ("consistent", "inconsistent")


def check_seed(seed: int, draw: int) -> int:
    """The root seed of the check's ``draw``-th simulation, derived from the fit's ``seed``."""
    state = np.random.SeedSequence(seed, spawn_key=(CHECK_KEY, draw)).generate_state(1)
    return int(state[0] >> 1)  # a non-negative int64


def predictive_check(
    out: Path,
    base: RunConfig,
    priors: Sequence[Prior],
    samples: np.ndarray,
    data: np.ndarray,
    statistics: Sequence[str],
    *,
    draws: int,
    seed: int,
    measure: Any,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = None,
) -> dict[str, np.ndarray]:
    """Re-simulate ``draws`` posterior samples and judge each statistic.

    Parameters
    ----------
    out : Path
        Folder of the check's simulations (one per draw, resumable).
    base : RunConfig
        The data's request.
    priors : sequence of Prior
        The unknowns.
    samples : numpy.ndarray
        float64[sample, unknown]: the posterior, each in its prior's unit.
    data : numpy.ndarray
        float64[point, realization, statistic]: the data's statistics.
    statistics : sequence of str
        Their names.
    draws : int
        Posterior samples to simulate (>= 2).
    seed : int
        The fit's root seed.
    measure : Direct or Filmed
        How the fit measures its simulations (:mod:`softcell.fit.measure`).
    workers, scheduler, overwrite, progress, log
        As :func:`softcell.runner.points.run_points` takes them.

    Returns
    -------
    dict
        ``values`` float64[draw, unknown], ``each`` float64[draw, point, realization,
        statistic], ``z`` float64[point, statistic] and ``verdict`` int8[point, statistic]
        (an index of :data:`VERDICTS`).
    """
    from softcell.fit.design import design_points
    from softcell.runner.points import run_points

    picks = np.linspace(0, samples.shape[0] - 1, draws).round().astype(int)
    values = samples[picks]
    points = design_points(Path(out), base, priors, values)
    points = {folder: (f"check: {label}", config) for folder, (label, config) in points.items()}
    seeds = [check_seed(seed, i) for i in range(draws)]
    run = {"workers": workers, "scheduler": scheduler, "progress": progress, "log": log}
    run_points(points, realizations=data.shape[1], seed=seeds, overwrite=overwrite, **run)
    each = measure.statistics(list(points), statistics, seed=seeds, **run)
    z, verdict = judge(data, each)
    return {"values": values, "each": each, "z": z, "verdict": verdict}


def judge(data: np.ndarray, each: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """z and the verdict (an index of :data:`VERDICTS`) per point and statistic, from the
    data's statistics float64[point, realization, statistic] and the draws'
    float64[draw, point, realization, statistic] (see the module's docstring)."""
    means = np.nanmean(each, axis=2)  # [draw, point, statistic]
    within = np.nanmean(np.nanvar(each, axis=2, ddof=1), axis=0) / data.shape[1]
    spread = np.sqrt(np.maximum(np.var(means, axis=0, ddof=1), within))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (np.nanmean(data, axis=1) - means.mean(axis=0)) / spread
    return z, np.where(np.abs(z) <= LIMIT, 0, 1).astype(np.int8)


def corner_figure(path: Path, priors: Sequence[Prior], samples: np.ndarray, truths=None) -> Path:
    """The posterior's corner plot (each unknown's histogram and each pair's density), with
    the 5 %, 50 % and 95 % quantiles marked; log axes for log-uniform priors. Written to
    ``path`` (PNG)."""
    import corner
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from softcell.io.files import atomic_write

    labels = [f"{p.name}\n({p.unit})" for p in priors]
    data = np.column_stack(
        [
            np.log10(samples[:, i]) if p.scale == "log" else samples[:, i]
            for i, p in enumerate(priors)
        ]
    )
    labels = [
        f"log10 {lab}" if p.scale == "log" else lab for p, lab in zip(priors, labels, strict=True)
    ]
    titles = [f"log10 {p.name}" if p.scale == "log" else p.name for p in priors]
    if truths is not None:
        truths = [
            np.log10(t) if p.scale == "log" else t for p, t in zip(priors, truths, strict=True)
        ]
    figure = corner.corner(
        data, labels=labels, quantiles=[0.05, 0.5, 0.95], show_titles=True, truths=truths,
        title_fmt=".3g", titles=titles, title_kwargs={"fontsize": 9},
        title_quantiles=[0.05, 0.5, 0.95],
    )  # fmt: skip
    from softcell._version import __version__

    with atomic_write(path) as tmp:
        software = f"softcell {__version__} (fit: corner plot)"
        figure.savefig(tmp, format="png", dpi=120, metadata={"Software": software})
    plt.close(figure)
    return path
