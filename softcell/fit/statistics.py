"""What a fit compares: summary statistics of the cell, one value per realization.

A statistic is an analysis quantity with a value per realization (``NAME_realization`` in
the Dataset :func:`softcell.analyze` returns; the cell's, for the per-body ones): the mean
speed, D hat, <tau_g>, <tau_s>, the shape index, ... Data (tracked films, simulations) and
the fit's own simulations are reduced the same way, by the same analysis, so that a film of
six realizations is compared with simulations of six realizations of the same design.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from softcell.errors import ConfigError
from softcell.model.parameters import suggest
from softcell.schema.analysis import ANALYSIS_VARIABLES, BODY_QUANTITIES, POINT_QUANTITIES

#: The statistics a fit compares unless told otherwise: speed, diffusion, the stop and go
#: durations, the shape index.
DEFAULT_STATISTICS = (
    "mean_speed",
    "diffusion_coefficient",
    "mean_go_duration",
    "mean_stop_duration",
    "ipr_mean",
)
#: Every statistic a fit can compare.
STATISTICS = (*BODY_QUANTITIES, *POINT_QUANTITIES)


@dataclass(frozen=True)
class Observed:
    """Summary statistics per point and realization.

    Attributes
    ----------
    statistics : tuple of str
        The statistics' names (analysis variables).
    units : tuple of str
        Their units (UDUNITS-2).
    each : numpy.ndarray
        float64[point, realization, statistic]: each realization's value (NaN where the
        analysis left it undefined, e.g. a go phase that never ended).
    """

    statistics: tuple[str, ...]
    units: tuple[str, ...]
    each: np.ndarray

    @property
    def mean(self) -> np.ndarray:
        """float64[point, statistic]: the mean over the realizations where defined."""
        return np.nanmean(self.each, axis=1)

    @property
    def error(self) -> np.ndarray:
        """float64[point, statistic]: the standard error of :attr:`mean` across realizations
        (NaN with fewer than two)."""
        n = np.sum(np.isfinite(self.each), axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            sd = np.nanstd(self.each, axis=1, ddof=1)
            return np.where(n > 1, sd / np.sqrt(np.maximum(n, 1)), np.nan)


def check_statistics(names: Sequence[str]) -> tuple[str, ...]:
    """``names`` as a tuple, each a statistic a fit can compare.

    Raises
    ------
    ConfigError
        Naming an unknown statistic (with a suggestion), or none given.
    """
    names = tuple(names)
    if not names:
        raise ConfigError("a fit compares at least one statistic; none given")
    for name in names:
        if name not in STATISTICS:
            raise ConfigError(
                f"statistic {name!r} is not one a fit can compare{suggest(name, STATISTICS)}; "
                f"they are {', '.join(STATISTICS)}"
            )
    return names


def observed(analysis, statistics: Sequence[str] = DEFAULT_STATISTICS) -> Observed:
    """The statistics of an analysis Dataset (:func:`softcell.analyze`), per point and
    realization.

    Raises
    ------
    ConfigError
        For a statistic that is unknown, or that the data lacks (absent, or undefined in
        every realization of a point: a tracked film has no membrane, so no ``ipr_mean``).
    """
    statistics = check_statistics(statistics)
    columns, units = [], []
    for name in statistics:
        var = analysis.get(f"{name}_realization")
        if var is None:
            raise ConfigError(f"the data lacks the statistic {name!r} (no {name}_realization)")
        if "body" in var.dims:
            var = var.sel(body="cell")
        values = np.asarray(var.transpose(..., "realization").values, dtype=np.float64)
        values = values.reshape(-1, values.shape[-1])
        if not np.all(np.any(np.isfinite(values), axis=1)):
            raise ConfigError(
                f"the data lacks the statistic {name!r}: it is undefined in every realization"
                " of a point"
            )
        columns.append(values)
        units.append(ANALYSIS_VARIABLES[name].units)
    return Observed(statistics, tuple(units), np.stack(columns, axis=-1))
