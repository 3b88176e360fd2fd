"""The space-filling design of a fit: points of the prior box, each simulated like the data.

The design is a scrambled Sobol sequence (:class:`scipy.stats.qmc.Sobol`) in the prior's
quantiles, mapped to parameter values by each :class:`~softcell.fit.priors.Prior` (uniform
or log-uniform), its scrambling drawn from the fit's seed. Every point runs the data's
design (its radius, duration, sampling and number of realizations) into its own folder from
one root seed, so that realization r of every point draws the same random numbers (common
random numbers: the points differ by their parameters, not by noise). Each folder is
resumable as ``softcell simulate``'s are: an interrupted design resumes where it stopped.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from softcell.errors import ConfigError
from softcell.fit.priors import Prior
from softcell.model.configuration import RunConfig

#: The spawn key of the design's scrambling under the fit's root seed (the simulations
#: draw from the root seed's other keys).
DESIGN_KEY = 7_000


def space_filling(priors: Sequence[Prior], count: int, seed: int) -> np.ndarray:
    """``count`` points of the priors' box, float64[count, len(priors)] in each prior's unit.

    Parameters
    ----------
    priors : sequence of Prior
        The unknowns.
    count : int
        Points; a power of two (a Sobol sequence keeps its balance only at powers of two).
    seed : int
        The fit's root seed (the scrambling draws from ``SeedSequence(seed,
        spawn_key=(DESIGN_KEY,))``).

    Raises
    ------
    ConfigError
        For no prior, or a ``count`` that is not a power of two >= 2.
    """
    from scipy.stats import qmc

    if not priors:
        raise ConfigError("a fit needs at least one unknown: give --prior NAME=LOW:HIGH")
    if isinstance(count, bool) or not isinstance(count, int) or count < 2 or count & (count - 1):
        below = 1 << max(1, int(count).bit_length() - 1) if isinstance(count, int) else 2
        raise ConfigError(
            f"design of {count!r} points is not allowed: must be a power of two >= 2 "
            f"(e.g. {below} or {2 * below})"
        )
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(DESIGN_KEY,)))
    unit = qmc.Sobol(len(priors), scramble=True, seed=rng).random_base2(count.bit_length() - 1)
    return np.column_stack([p.value(unit[:, i]) for i, p in enumerate(priors)])


def design_points(
    out: Path, base: RunConfig, priors: Sequence[Prior], values: np.ndarray
) -> dict[Path, tuple[str, RunConfig]]:
    """Each design point's folder (``out/pointNNNN``), a label and the RunConfig it runs:
    ``base`` with the unknowns set to the point's ``values`` (each in its prior's unit)."""
    points = {}
    for i, row in enumerate(np.asarray(values, dtype=np.float64)):
        given = {p.name: float(v) for p, v in zip(priors, row, strict=True)}
        label = ", ".join(f"{p.name} = {v:.4g} {p.unit}" for p, v in zip(priors, row, strict=True))
        points[out / f"point{i:04d}"] = (label, base.updated(parameters=given))
    return points


def run_design(
    out: Path,
    base: RunConfig,
    priors: Sequence[Prior],
    values: np.ndarray,
    *,
    realizations: int,
    seed: int,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = None,
) -> list[Path]:
    """Simulate every design point (:func:`design_points`) with ``realizations`` from root
    ``seed``; every point is planned before any runs (``overwrite``: recompute a folder made
    from another request). Returns the points' folders, in order.

    Raises
    ------
    SoftcellError
        For a point that cannot run (a value of an unknown that the model refuses with the
        other parameters), before any simulation.
    """
    from softcell.runner.points import run_points

    points = design_points(Path(out), base, priors, values)
    run_points(
        points,
        realizations=realizations,
        seed=seed,
        workers=workers,
        scheduler=scheduler,
        overwrite=overwrite,
        progress=progress,
        log=log,
    )
    return list(points)


def statistics_of(folders: Sequence[Path], statistics: Sequence[str], options: dict[str, Any]):
    """The statistics of each design point's simulations (analysed with ``options``, e.g.
    ``{"discard": 15}``): float64[design point, point of the data (radius), realization,
    statistic]."""
    from softcell.analysis import analyze
    from softcell.fit.statistics import observed
    from softcell.io.netcdf import open_dataset

    each = []
    for folder in folders:
        analysis = analyze(open_dataset(folder), options)
        each.append(observed(analysis, statistics).each)
    return np.stack(each)
