"""Stop and go phases of a speed series (docs/model.md §6).

A detector (a plugin, default ``threshold``) labels each sample go (1), stop (0) or unknown
(-1), separately on each sampling segment. A phase of n consecutive equal labels lasts
(n - 1) dt, the time between its first and last samples; the first and last phase of each
segment, and any phase touching an unknown sample, are censored and dropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from softcell.analysis.series import segment_index, segments
from softcell.builtins.threshold import (  # noqa: F401  (the analysis' names for them)
    EXPERIMENT_THRESHOLD,
    SIMULATION_THRESHOLD,
    THRESHOLD,
)
from softcell.components.contracts import StopGoDetector
from softcell.engine.kernels.runs import run_lengths
from softcell.schema import GO, STOP

#: Width of the bins of the PDFs of t / <t> (the paper's 0.25).
PDF_BIN = 0.25


def label(detector: StopGoDetector, speed: np.ndarray, time: np.ndarray) -> np.ndarray:
    """int8 labels [..., T] of a speed series [..., T] (cm/s), segment by segment."""
    speed = np.asarray(speed, dtype=np.float64)
    out = np.full(speed.shape, -1, dtype=np.int8)
    for seg in segments(time):
        part = slice(seg.first, seg.last)  # the forward intervals of this segment
        out[..., part] = detector.label(speed[..., part], seg.interval)
    return out


@dataclass
class Durations:
    """Complete stop and go phase durations (s) of a set of series."""

    go: np.ndarray
    stop: np.ndarray

    def mean(self, kind: int) -> float:
        values = self.go if kind == GO else self.stop
        return float(values.mean()) if values.size else np.nan


def durations(labels: np.ndarray, time: np.ndarray, only: int | None = None) -> Durations:
    """Durations (s) of the complete phases of label series [..., T] sharing ``time``; with
    ``only``, of the phases in that sampling segment alone."""
    time = np.asarray(time, dtype=np.float64)
    seg = segment_index(time)
    intervals = np.array([s.interval for s in segments(time)])
    series = np.asarray(labels, dtype=np.int8).reshape(-1, time.size)
    go, stop = [], []
    for row in series:
        start, length, value = run_lengths(np.ascontiguousarray(row), seg)
        duration = (length - 1) * intervals[seg[start]]
        if only is not None:
            duration, value = duration[seg[start] == only], value[seg[start] == only]
        go.append(duration[value == GO])
        stop.append(duration[value == STOP])
    return Durations(
        np.concatenate(go) if go else np.zeros(0), np.concatenate(stop) if stop else np.zeros(0)
    )


def scaled_pdf(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Density of t / <t> on the bins ``edges`` (integrates to 1 when the bins cover every
    value); NaN if there are no values."""
    if values.size == 0 or not values.mean() > 0:
        return np.full(edges.size - 1, np.nan)
    density, _ = np.histogram(values / values.mean(), bins=edges, density=True)
    return density


def pdf_edges(largest_scaled: float) -> np.ndarray:
    """Bins of width PDF_BIN from 0 covering ``largest_scaled``."""
    count = max(1, int(np.ceil(largest_scaled / PDF_BIN + 1e-12)))
    if count * PDF_BIN <= largest_scaled:
        count += 1
    return PDF_BIN * np.arange(count + 1)


def exponential_fit_statistic(values: np.ndarray) -> tuple[float, float]:
    """Kolmogorov-Smirnov distance between t / <t> and the unit exponential exp(-t'), and its
    p-value as for a fully specified distribution (rescaling by the sample mean makes the true
    p-value somewhat larger: Lilliefors). NaN for fewer than 2 values."""
    if values.size < 2 or not values.mean() > 0:
        return np.nan, np.nan
    from scipy import stats  # imported here: scipy costs ~1 s to import, and a plugin
    # listing or a simulation never needs it

    result = stats.kstest(values / values.mean(), "expon")
    return float(result.statistic), float(result.pvalue)
