"""Velocity correlations: what the run-and-tumble theories assume away (docs/model.md §6).

Both theories of the paper's Sec. S4 (the exponential one and its renewal generalization)
assume that every go phase starts in a new, uniformly random direction, so the velocity
autocorrelation vanishes beyond the longest go phase. Two measurements test that:

- :func:`velocity_autocorrelation`: C(tau) = <v(t) . v(t + tau)> of the velocity
  v = (r(t + dt) - r(t)) / dt on one uniform grid of interval dt. Its sum is the MSD slope
  exactly (Green-Kubo on a grid): MSD(n dt) = dt^2 sum_(i, j < n) C((i - j) dt), so
  D hat = dt (C(0) + 2 sum_(k >= 1) C(k dt)).
- :func:`turn_statistics`: the displacement of every complete go phase and the cosine of the
  angle between consecutive go phases (0 on average in both theories).

:func:`renewal_msd` and :func:`renewal_autocorrelation` are the renewal theory's MSD curve and
its velocity autocorrelation on the same grid, for any measured go durations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.fft import next_fast_len

from softcell.analysis.msd import correlate
from softcell.engine.kernels.runs import run_lengths

GO = 1


def velocity_autocorrelation(
    positions: np.ndarray, interval: float, max_lag: int
) -> tuple[np.ndarray, np.ndarray]:
    """C(k dt) = mean over valid pairs of v_i . v_(i+k), k = 0..max_lag.

    Parameters
    ----------
    positions : float64[T, D]
        One trajectory on a uniform grid of ``interval`` dt (s), in cm; a row with a NaN is
        missing (so are the velocities next to it).
    interval : float
        dt (s).
    max_lag : int
        Largest lag k (samples).

    Returns
    -------
    sums, pairs : float64[max_lag + 1]
        Sum of v_i . v_(i+k) (cm^2 s^-2) over valid pairs, and their number; C = sums / pairs.
    """
    r = np.asarray(positions, dtype=np.float64)
    v = np.diff(r, axis=0) / interval
    valid = np.all(np.isfinite(v), axis=1)
    size = v.shape[0]
    sums, pairs = np.zeros(max_lag + 1), np.zeros(max_lag + 1)
    if size == 0 or not valid.any():
        return sums, pairs
    v = np.where(valid[:, None], v, 0.0)
    n = next_fast_len(2 * size, real=True)
    keep = min(max_lag + 1, size)
    sums[:keep] = correlate(v.T, None, n).sum(axis=0)[:keep]
    pairs[:keep] = np.rint(correlate(valid.astype(np.float64), None, n))[:keep]
    return sums, pairs


def green_kubo_slope(correlation: np.ndarray, interval: float) -> float:
    """D hat (cm^2/s) = dt (C(0) + 2 sum_(k >= 1) C(k dt)) of a velocity autocorrelation on a
    grid of interval dt (s), truncated at its last lag."""
    c = np.asarray(correlation, dtype=np.float64)
    return float(interval * (c[0] + 2.0 * c[1:].sum()))


@dataclass(frozen=True)
class TurnStatistics:
    """Go phases of one trajectory: their number, the sums of their displacement lengths
    (cm) and squared lengths (cm^2), and the number of consecutive pairs (go, stop, go) with
    the sum of the cosines of the angle between the two go displacements."""

    phases: int
    length_sum: float
    square_sum: float
    pairs: int
    cosine_sum: float


def turn_statistics(
    positions: np.ndarray, labels: np.ndarray, segment: np.ndarray, only: int
) -> TurnStatistics:
    """Go-phase displacements of one trajectory in sampling segment ``only``.

    ``positions`` float64[T, 2] (cm), ``labels`` int8[T] (1 go, 0 stop, -1 unknown; a label
    describes the motion to the next sample), ``segment`` int64[T] (the segment of each
    sample). A go phase of samples s..s + n - 1 moves the body from r_s to r_(s + n); phases
    touching an unknown sample or a segment's end are left out, as for the durations.
    """
    start, length, value = run_lengths(np.ascontiguousarray(labels, dtype=np.int8), segment)
    inside = segment[start] == only
    start, length, value = start[inside], length[inside], value[inside]
    end = start + length
    d = positions[np.minimum(end, positions.shape[0] - 1)] - positions[start]
    size = np.hypot(d[:, 0], d[:, 1])
    go = (value == GO) & np.isfinite(size)
    idx = np.flatnonzero(go)
    # consecutive go phases: the phase between them is the whole gap
    a, b = idx[:-1], idx[1:]
    adjacent = (b == a + 2) & (start[np.minimum(a + 1, start.size - 1)] == end[a])
    adjacent &= start[b] == end[np.minimum(a + 1, end.size - 1)]
    a, b = a[adjacent], b[adjacent]
    moved = (size[a] > 0) & (size[b] > 0)
    a, b = a[moved], b[moved]
    cosine = np.einsum("ij,ij->i", d[a], d[b]) / (size[a] * size[b])
    return TurnStatistics(
        int(go.sum()),
        float(size[go].sum()),
        float((size[go] ** 2).sum()),
        int(a.size),
        float(cosine.sum()),
    )


def renewal_msd(lag: np.ndarray, v0_hat: float, go_durations: np.ndarray) -> np.ndarray:
    """The renewal theory's MSD (cm^2) at ``lag`` (s): go phases of the measured durations
    (s), stops in between, each go phase in a new uniformly random direction at one speed.

    Its velocity autocorrelation is C(u) = (v0_hat^2 / <tau_g>) <(tau_g - u)_+> (v0_hat^2 is
    the go speed squared times the go fraction), and MSD(tau) = 2 int_0^tau (tau - u) C(u) du
    = (2 v0_hat^2 / <tau_g>) <f(tau_g, tau)> with f(d, tau) = tau^2 d / 2 - tau^3 / 6 for
    d >= tau and tau d^2 / 2 - d^3 / 6 for d < tau. Exponential durations give the paper's
    formula; its slope at long lags is v0_hat^2 <tau_g^2> / <tau_g>.
    """
    d = np.asarray(go_durations, dtype=np.float64)
    d = d[np.isfinite(d)]
    tau = np.asarray(lag, dtype=np.float64)
    if d.size == 0 or not d.mean() > 0:
        return np.full(tau.shape, np.nan)
    t, g = tau[..., None], d
    f = np.where(g >= t, t**2 * g / 2 - t**3 / 6, t * g**2 / 2 - g**3 / 6)
    return 2 * v0_hat**2 / d.mean() * f.mean(axis=-1)


def renewal_autocorrelation(
    interval: float, max_lag: int, v0_hat: float, go_durations: np.ndarray
) -> np.ndarray:
    """The renewal theory's C(k dt) (cm^2 s^-2), k = 0..max_lag, for velocities differenced
    over dt (s), as :func:`velocity_autocorrelation` measures them: the second difference
    of :func:`renewal_msd` on the grid, C(0) = MSD(dt) / dt^2 and C(k dt) = (MSD((k + 1) dt)
    + MSD((k - 1) dt) - 2 MSD(k dt)) / (2 dt^2)."""
    m = renewal_msd(interval * np.arange(max_lag + 2), v0_hat, go_durations)
    out = np.empty(max_lag + 1)
    out[0] = m[1] / interval**2
    out[1:] = (m[2:] + m[:-2] - 2 * m[1:-1]) / (2 * interval**2)
    # C vanishes beyond the longest go phase, so C(k dt) does from (k - 1) dt on: exactly 0
    # there, not the round-off of a second difference.
    d = np.asarray(go_durations, dtype=np.float64)
    longest = np.nanmax(d) if np.isfinite(d).any() else np.inf
    out[(np.arange(max_lag + 1) - 1) * interval >= longest] = 0.0
    return out
