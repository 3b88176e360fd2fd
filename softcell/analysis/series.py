"""Time series of a record: sampling segments, velocity and speed, geometric centers, IPR.

A record may change its sampling interval (the paper: 0.01 s up to 100 s, then 0.1 s). A
*segment* is a maximal run of equal intervals; nothing is ever differenced across two
segments. Arrays here are numpy, time along the last axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Two sampling intervals are equal when they differ by less than this fraction.
INTERVAL_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Segment:
    """Samples ``first`` .. ``last`` (inclusive) spaced by ``interval`` (s)."""

    first: int
    last: int
    interval: float

    @property
    def samples(self) -> slice:
        return slice(self.first, self.last + 1)


def segments(time: np.ndarray) -> list[Segment]:
    """The sampling segments of a strictly increasing time coordinate (s)."""
    time = np.asarray(time, dtype=np.float64)
    if time.size < 2:
        return [Segment(0, max(time.size - 1, 0), np.nan)] if time.size else []
    steps = np.diff(time)
    if not np.all(steps > 0):
        raise ValueError("time must increase strictly")
    changes = np.flatnonzero(np.abs(np.diff(steps)) > INTERVAL_TOLERANCE * steps[:-1]) + 1
    bounds = [0, *changes.tolist(), steps.size]
    return [
        Segment(a, b, float(np.mean(steps[a:b])))
        for a, b in zip(bounds[:-1], bounds[1:], strict=True)
    ]


def segment_index(time: np.ndarray) -> np.ndarray:
    """int64[T]: the segment of each sample's forward interval (the last sample: the last
    segment). Labels of sample i describe the motion from t_i to t_(i+1)."""
    index = np.zeros(np.size(time), dtype=np.int64)
    for k, seg in enumerate(segments(time)):
        index[seg.first :] = k
    return index


def velocity(position: np.ndarray, time: np.ndarray) -> np.ndarray:
    """First-order forward difference (r_(i+1) - r_i) / (t_(i+1) - t_i) along the last axis;
    NaN at the last sample. position: [..., T] in cm, time: [T] in s; returns cm/s."""
    position = np.asarray(position, dtype=np.float64)
    out = np.full(position.shape, np.nan)
    out[..., :-1] = np.diff(position, axis=-1) / np.diff(np.asarray(time, dtype=np.float64))
    return out


def speed(x: np.ndarray, y: np.ndarray, time: np.ndarray) -> np.ndarray:
    """|v| (cm/s) from positions x, y [..., T] (cm); NaN at the last sample."""
    return np.hypot(velocity(x, time), velocity(y, time))


def decimation(time: np.ndarray, interval: float, start: float) -> np.ndarray:
    """Indices of the samples on the grid start, start + interval, ... (s) up to the last
    time: int64[G], -1 where the record has no sample at that grid time."""
    time = np.asarray(time, dtype=np.float64)
    count = int(np.floor((time[-1] - start) / interval * (1 + INTERVAL_TOLERANCE))) + 1
    if count <= 0:
        return np.zeros(0, dtype=np.int64)
    grid = start + interval * np.arange(count)
    nearest = np.clip(np.searchsorted(time, grid), 1, time.size - 1)
    left = np.where(
        np.abs(time[nearest - 1] - grid) <= np.abs(time[nearest] - grid), nearest - 1, nearest
    )
    hit = np.abs(time[left] - grid) <= INTERVAL_TOLERANCE * interval
    return np.where(hit, left, -1)


def polygon_area_perimeter_centroid(
    x: np.ndarray, y: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Signed area (cm^2), perimeter (cm) and area centroid (cm) of closed polygons whose
    vertices run along the last axis (shoelace formulas)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    x0 = x.mean(axis=-1, keepdims=True)  # shift: the shoelace sum loses digits far away
    y0 = y.mean(axis=-1, keepdims=True)
    u, v = x - x0, y - y0
    un, vn = np.roll(u, -1, axis=-1), np.roll(v, -1, axis=-1)
    cross = u * vn - un * v
    area = 0.5 * cross.sum(axis=-1)
    perimeter = np.hypot(un - u, vn - v).sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = ((u + un) * cross).sum(axis=-1) / (6 * area) + x0[..., 0]
        cy = ((v + vn) * cross).sum(axis=-1) / (6 * area) + y0[..., 0]
    return area, perimeter, cx, cy


def smooth_area_perimeter(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed area (cm^2) and perimeter (cm) of the smooth periodic curve that the points
    (x, y) (cm; along the last axis) sample, its modes below their Nyquist mode: the area
    exactly from the Fourier modes, the perimeter from the spectral tangent on a 4x finer
    grid."""
    z = np.asarray(x, dtype=np.float64) + 1j * np.asarray(y, dtype=np.float64)
    n = z.shape[-1]
    modes = np.fft.fft(z, axis=-1) / n
    k = np.fft.fftfreq(n, 1.0 / n)
    area = np.pi * (k * np.abs(modes) ** 2).sum(axis=-1)
    fine = np.zeros((*z.shape[:-1], 4 * n), dtype=np.complex128)
    half = (n + 1) // 2
    fine[..., :half] = (1j * k * modes)[..., :half]
    fine[..., half - n :] = (1j * k * modes)[..., half:]
    tangent = np.fft.ifft(fine, axis=-1) * (4 * n)
    return area, 2 * np.pi * np.abs(tangent).mean(axis=-1)


def shape_index(x: np.ndarray, y: np.ndarray, band_limited: bool = False) -> np.ndarray:
    """IPR = P / sqrt(A) of closed curves through the points (x, y) (cm; along the last
    axis): 2 sqrt(pi) for a circle, larger for any other shape.

    ``band_limited`` False takes the polygon through the points (a tracked contour). True
    takes the smooth periodic curve they sample, as a simulated membrane's stored nodes do
    (their number exceeds twice the cutoff mode; :func:`smooth_area_perimeter`). A polygon
    of N nodes on a circle overestimates the IPR by ~2 sqrt(pi) pi^2 / (2 N^2) (1.4e-3 at
    N = 64, the size of a simulated membrane's deformation at small R).
    """
    if band_limited:
        area, perimeter = smooth_area_perimeter(x, y)
    else:
        area, perimeter, _, _ = polygon_area_perimeter_centroid(x, y)
    return perimeter / np.sqrt(np.abs(area))
