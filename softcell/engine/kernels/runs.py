"""Run-length encoding of stop/go labels into uncensored phases (docs/model.md §6)."""

from __future__ import annotations

import numpy as np
from numba import njit

from softcell.settings import JIT


@njit(**JIT)
def run_lengths(
    labels: np.ndarray, segment: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The complete phases of a label series.

    Parameters
    ----------
    labels : int8[T]
        1 go, 0 stop, -1 unknown, per sample.
    segment : int64[T]
        Sampling-segment index of each sample; detection never spans two segments.

    Returns
    -------
    start, length, value : int64[K], int64[K], int8[K]
        First sample, number of samples n and label of each phase that is neither the first
        nor the last of its segment and touches no unknown sample (those are censored: their
        true extent is not seen). A phase of n samples lasts (n - 1) sampling intervals.
    """
    n = labels.size
    start = np.empty(n, dtype=np.int64)
    length = np.empty(n, dtype=np.int64)
    value = np.empty(n, dtype=np.int8)
    k = 0
    i = 0
    while i < n:
        j = i
        while j + 1 < n and labels[j + 1] == labels[i] and segment[j + 1] == segment[i]:
            j += 1
        first = i == 0 or segment[i - 1] != segment[i] or labels[i - 1] < 0
        last = j == n - 1 or segment[j + 1] != segment[j] or labels[j + 1] < 0
        if labels[i] >= 0 and not first and not last:
            start[k] = i
            length[k] = j - i + 1
            value[k] = labels[i]
            k += 1
        i = j + 1
    return start[:k].copy(), length[:k].copy(), value[:k].copy()
