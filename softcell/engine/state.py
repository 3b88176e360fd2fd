"""The state of one realization: its initial condition, its sampling grid, its checks.

The membrane is held as its Fourier modes g_k, |k| <= Lc (complex128[2 Lc + 1], cm;
``modes[j]`` is g_{j - Lc}) and the bot as its pose (x, y in cm, heading in rad); see
``docs/model.md``, "State and units".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from softcell.components.contracts import Schedule
from softcell.errors import SimulationError
from softcell.model.parameters import Parameters
from softcell.settings import BLOWUP_CHECK_POINTS, BLOWUP_LENGTH_FRACTION

if TYPE_CHECKING:
    from softcell.components.contracts import Model


def equilibrium_radius(params: Parameters) -> float:
    """Radius (cm) of the force-free circle: the root near l0 / 2 pi of
    4 pi alpha l0 R^3 - 2 alpha l0^2 R^2 - k = 0 (docs/model.md §3; the paper's cubic has a typo).
    """
    l0, alpha, k = params.membrane_length, float(params.tension), float(params.bending_stiffness)
    roots = np.roots([4 * math.pi * alpha * l0, -2 * alpha * l0**2, 0.0, -k])
    real = roots[np.abs(roots.imag) < 1e-9 * abs(roots).max()].real
    return float(real[np.argmin(np.abs(real - l0 / (2 * math.pi)))])


def circle_modes(radius: float, cutoff: int, center: complex = 0j) -> np.ndarray:
    """Fourier modes (complex128[2 cutoff + 1], cm) of a circle z = center + radius e^{i xi}."""
    modes = np.zeros(2 * cutoff + 1, dtype=np.complex128)
    modes[cutoff] = center
    modes[cutoff + 1] = radius
    return modes


def sample_times(params: Parameters) -> np.ndarray:
    """The sampling grid (s): every ``sample_every`` before ``sample_switch``, then every
    ``sample_every_late``, up to and including ``duration`` where it falls on the grid."""
    duration, early = float(params.duration), float(params.sample_every)
    late, switch = float(params.sample_every_late), float(params.sample_switch)
    first_end = min(switch, duration)
    n_early = int(math.floor(first_end / early * (1 + 1e-12))) + 1
    times = np.arange(n_early) * early
    if switch < duration:
        times = times[times < switch]
        n_late = int(math.floor((duration - switch) / late * (1 + 1e-12))) + 1
        times = np.concatenate([times, switch + np.arange(n_late) * late])
    return times


def fine_times(params: Parameters) -> np.ndarray:
    """The grid (s) of the bodies' fine record: every ``sample_every`` from 0 up to and
    including ``duration`` where it falls on the grid, over the whole run (the membrane, the
    bulk of a sample, is thinned to :func:`sample_times`; the cell's centre and the bot's pose
    are a few numbers a sample)."""
    duration, early = float(params.duration), float(params.sample_every)
    return np.arange(int(math.floor(duration / early * (1 + 1e-12))) + 1) * early


def sampling_plan(params: Parameters) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The times (s) the stepper is sampled at: the union of :func:`sample_times` (the
    membrane's) and :func:`fine_times` (the bodies'), increasing, times closer than 1e-9 of
    their size counted once (at the membrane's value); and the index into it of each
    membrane and each fine time."""
    membrane, fine = sample_times(params), fine_times(params)
    both = np.concatenate([membrane, fine])
    order = np.argsort(both, kind="stable")
    ordered = both[order]
    new = np.ones(ordered.size, dtype=bool)
    new[1:] = np.diff(ordered) > 1e-9 * np.maximum(1.0, np.abs(ordered[1:]))
    slot = np.cumsum(new) - 1  # the grid index of each entry of ``ordered``
    index = np.empty(both.size, dtype=np.int64)
    index[order] = slot
    grid = ordered[new]
    grid[index[: membrane.size]] = membrane  # a shared time is the membrane's, to the bit
    return grid, index[: membrane.size], index[membrane.size :]


def phase_at(schedule: Schedule, times: np.ndarray, starts: np.ndarray | None = None) -> np.ndarray:
    """Phase code (int8) active at each time (s): the last phase started at or before it,
    by the schedule's start times or by ``starts`` (s), the start times as state events
    shifted them (non-decreasing: a phase an event ended at its start lasts 0 s)."""
    begin = schedule.start if starts is None else starts
    index = np.searchsorted(begin, times, side="right") - 1
    return schedule.phase[np.clip(index, 0, None)]


def membrane_length(modes: np.ndarray, points: int = 256) -> float:
    """Length (cm) of the curve with these Fourier modes, by the trapezoidal rule (spectrally
    accurate for a trigonometric polynomial)."""
    return float(2 * np.pi * _speeds(modes, points).mean())


def _speeds(modes: np.ndarray, points: int) -> np.ndarray:
    """|dgamma/dxi| (cm) at ``points`` equally spaced xi of each row of modes
    (complex128[..., 2 Lc + 1], k = -Lc..Lc), by an inverse FFT.

    An FFT rather than a product with a basis of exponentials: a matrix product goes to
    OpenBLAS, whose threads spin after each call and, with several softcell processes on the
    cores (an ensemble's workers, two commands at once), took ~40 % of each one's time.
    """
    lc = (modes.shape[-1] - 1) // 2
    k = np.arange(-lc, lc + 1)
    rows = np.reshape(1j * k * modes, (-1, k.size))
    spectrum = np.zeros((rows.shape[0], points), dtype=np.complex128)
    np.add.at(spectrum, (slice(None), k % points), rows)  # modes beyond points/2 alias
    speeds = np.abs(np.fft.ifft(spectrum, axis=-1) * points)
    return speeds.reshape(*modes.shape[:-1], points)


@dataclass
class Record:
    """What a realization produced, before it becomes a Dataset: the membrane's samples at
    ``times`` and, if recorded, the bodies' fine record at ``fine_times``."""

    times: np.ndarray
    modes: np.ndarray  # complex128[T, 2 Lc + 1]
    pose: np.ndarray  # float64[T, 3]
    phase: np.ndarray  # int8[T]
    state: dict[str, np.ndarray] | None = None  # the integrator's state after the last sample
    fine_times: np.ndarray | None = None  # float64[F], s
    fine_center: np.ndarray | None = None  # complex128[F]: g_0, cm
    fine_pose: np.ndarray | None = None  # float64[F, 3]
    fine_phase: np.ndarray | None = None  # int8[F]
    event_times: np.ndarray | None = None  # float64[E], s: phases ended by state events


def check_state(
    state: dict[str, np.ndarray],
    model: Model,
    realization: object,
    times: np.ndarray | None = None,
    modes: np.ndarray | None = None,
    pose: np.ndarray | None = None,
) -> None:
    """Raise :class:`SimulationError` on a non-finite value or a membrane length off by more
    than BLOWUP_LENGTH_FRACTION of l0, naming the time, the realization and the quantity.

    ``times``, ``modes`` and ``pose`` (float64[K], complex128[K, 2 Lc + 1], float64[K, 3]), if
    given, are the samples recorded since the last check, which are checked instead of the
    state.
    """
    if times is None:
        times, modes, pose = state["time"], state["modes"][None], state["pose"][None]
    for name, values in (("modes", modes), ("pose", pose)):
        bad = ~np.all(np.isfinite(values), axis=-1)
        if bad.any():
            t = float(times[np.argmax(bad)])
            raise SimulationError(f"realization {realization}: non-finite {name} at t = {t:g} s")
    if model.has_membrane:
        l0 = model.params.membrane_length
        lengths = 2 * np.pi * _speeds(modes, BLOWUP_CHECK_POINTS).mean(axis=-1)
        bad = np.abs(lengths / l0 - 1) > BLOWUP_LENGTH_FRACTION
        if bad.any():
            i = int(np.argmax(bad))
            raise SimulationError(
                f"realization {realization}: membrane length {lengths[i]:.6g} cm at "
                f"t = {times[i]:g} s is off l0 = {l0:.6g} cm by more than "
                f"{BLOWUP_LENGTH_FRACTION:.0%}"
            )


def initial_state(
    model: Model, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, Schedule]:
    """Draw the heading and the schedule (in that order) and set up the membrane at rest:
    the equilibrium circle centred on the bot (docs/model.md §5)."""
    heading = model.protocol.initial_heading(rng)
    schedule = model.protocol.schedule(rng, float(model.params.duration))
    radius = equilibrium_radius(model.params) if model.has_membrane else 0.0
    return circle_modes(radius, model.cutoff), np.array([0.0, 0.0, heading]), schedule


def event_state(model: Model, schedule: Schedule) -> dict[str, np.ndarray]:
    """The state a protocol's events need: the phases' start times, which events shift
    (s), room for an event per phase (s) and the count logged; empty without events."""
    if model.event is None:
        return {}
    return {
        "starts": np.array(schedule.start, dtype=np.float64),
        "event_times": np.full(len(schedule.start), np.nan),
        "event_count": np.zeros(1, dtype=np.int64),
    }
