"""Mean-squared displacement by the FFT algorithm, with missing samples (docs/model.md §6).

For positions r_i (NaN where unknown) with validity w_i in {0, 1}, the sum over pairs
S(m) = sum_i w_i w_(i+m) |r_(i+m) - r_i|^2 and the pair count C(m) = sum_i w_i w_(i+m) are
correlations, computed with FFTs (pyfftw) in O(T log T):

    S(m) = corr(w, q)(m) + corr(q, w)(m) - 2 sum_d corr(w x_d, w x_d)(m),   q = w |r|^2

(corr(a, b)(m) = sum_i a_i b_(i+m)). Without missing samples the first two terms are the
exact cumulative sums of the classic algorithm. Positions are taken relative to their mean
first: an offset of 1e4 cm would otherwise cost 8 digits.
"""

from __future__ import annotations

import numpy as np
import pyfftw
import pyfftw.interfaces.numpy_fft as fftw
from scipy.fft import next_fast_len

pyfftw.interfaces.cache.enable()
_FFT = {"planner_effort": "FFTW_ESTIMATE"}


def correlate(a: np.ndarray, b: np.ndarray | None, n: int) -> np.ndarray:
    """sum_i a_i b_(i+m) for m = 0..T-1 along the last axis (b = a if None), by FFTs of
    length n >= 2 T (no wrap-around)."""
    size = a.shape[-1]
    fa = fftw.rfft(a, n=n, axis=-1, **_FFT)
    fb = fa if b is None else fftw.rfft(b, n=n, axis=-1, **_FFT)
    return fftw.irfft(np.conj(fa) * fb, n=n, axis=-1, **_FFT)[..., :size]


def msd_sums(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sum of squared displacements and number of pairs at every lag.

    Parameters
    ----------
    positions : float64[T, D]
        One trajectory sampled at a uniform interval (cm); a row with any NaN is missing.

    Returns
    -------
    sums : float64[T]
        S(m) = sum over valid pairs (i, i + m) of |r_(i+m) - r_i|^2 (cm^2), m = 0..T-1.
    pairs : float64[T]
        Number of valid pairs C(m); the MSD is S / C where C > 0.
    """
    r = np.asarray(positions, dtype=np.float64)
    if r.ndim != 2:
        raise ValueError(f"positions must be [T, D], got shape {r.shape}")
    size = r.shape[0]
    valid = np.all(np.isfinite(r), axis=1)
    if size == 0 or not valid.any():
        return np.zeros(size), np.zeros(size)
    r = np.where(valid[:, None], r - r[valid].mean(axis=0), 0.0)
    q = np.sum(r * r, axis=1)
    n = next_fast_len(2 * size, real=True)
    cross = correlate(r.T, None, n).sum(axis=0)
    if valid.all():
        # corr(1, q)(m) + corr(q, 1)(m) = sum_(i >= m) q_i + sum_(i < T - m) q_i, exactly.
        tail = np.cumsum(q[::-1])[::-1]
        head = np.cumsum(q)[::-1]
        squares = tail + head
        pairs = np.arange(size, 0, -1, dtype=np.float64)
    else:
        w = valid.astype(np.float64)
        squares = correlate(w, q, n) + correlate(q, w, n)
        pairs = np.rint(correlate(w, None, n))
    sums = squares - 2.0 * cross
    sums[pairs <= 0] = 0.0
    return np.maximum(sums, 0.0), np.maximum(pairs, 0.0)


def msd(positions: np.ndarray) -> np.ndarray:
    """MSD (cm^2) of one uniformly sampled trajectory float64[T, D] at lags 0..T-1 samples;
    NaN where no valid pair exists."""
    sums, pairs = msd_sums(positions)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(pairs > 0, sums / np.where(pairs > 0, pairs, 1.0), np.nan)


def log_lags(first: int, last: int, per_decade: int) -> np.ndarray:
    """Distinct integer lags from ``first`` to ``last`` (inclusive), log-spaced with about
    ``per_decade`` per decade; empty if last < first."""
    if last < first or last < 1:
        return np.zeros(0, dtype=np.int64)
    first = max(first, 1)
    count = max(2, int(np.ceil(np.log10(last / first) * per_decade)) + 1)
    return np.unique(np.rint(np.geomspace(first, last, count)).astype(np.int64))
