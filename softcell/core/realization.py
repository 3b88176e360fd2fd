"""One realization: the schedule, the stepper and the samples, as a Dataset.

This is the engine's outer loop. It touches no file: where a long realization keeps its
checkpoint is the caller's business, handed in as a :class:`Checkpoint` (the ensembles of
:mod:`softcell.workflows.ensemble` keep one file per realization).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from softcell.config import CHECKPOINT_EVERY
from softcell.core.components.contracts import Schedule, Stepper
from softcell.core.engine.model import Model
from softcell.core.engine.probe import diagnose
from softcell.core.engine.state import Record, check_state, initial_state, phase_at, sample_times
from softcell.core.interrupt import received
from softcell.errors import Interrupted, SimulationError

#: Samples handed to the stepper per call (progress, checks and checkpoints happen between
#: calls): 1 s of simulated time at the paper's early sampling.
SAMPLES_PER_CALL = 100


def realization_rng(seed: int, point: int, realization: int) -> np.random.Generator:
    """The Generator of one realization: SeedSequence(seed, spawn_key=(point, realization))."""
    return np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(point, realization)))
    )


@dataclass
class Saved:
    """What a checkpoint holds: the samples recorded so far and the stepper's state."""

    next_sample: int  # index of the first sample not yet recorded
    modes_record: np.ndarray  # (next_sample, modes) complex, cm
    pose_record: np.ndarray  # (next_sample, 3): x (cm), y (cm), angle (rad)
    state: dict[str, np.ndarray]  # the stepper's state after sample next_sample - 1


class Checkpoint(Protocol):
    """Where a realization saves its progress and resumes from."""

    def load(self) -> Saved | None:
        """The saved progress, or None to start from the beginning."""

    def save(self, saved: Saved) -> None:
        """Keep ``saved`` (replacing what was kept before), all or nothing."""


def run_realization(
    model: Model,
    stepper: Stepper,
    rng: np.random.Generator,
    *,
    label: object = 0,
    checkpoint: Checkpoint | None = None,
    checkpoint_every: float = CHECKPOINT_EVERY,
    progress: Callable[[float], None] | None = None,
    stop: Callable[[], bool] | None = None,
) -> Record:
    """Integrate one realization over the sampling grid of ``model.params``.

    Parameters
    ----------
    checkpoint : Checkpoint, optional
        Saved every ``checkpoint_every`` wall seconds (and when interrupted), and resumed from
        when it holds progress.
    progress : callable, optional
        Called with the simulated seconds advanced since its last call.
    stop : callable, optional
        Asked between chunks of samples; True stops the run as Ctrl-C does.

    Raises
    ------
    Interrupted
        On Ctrl-C (a ``KeyboardInterrupt``) or ``stop``, after saving the checkpoint of the
        last finished chunk; its message says where the run stopped.
    """
    times = sample_times(model.params)
    modes, pose, schedule = initial_state(model, rng)
    state = stepper.start(modes, pose, schedule)
    rec_modes = np.empty((times.size, modes.size), dtype=np.complex128)
    rec_pose = np.empty((times.size, 3))
    first, state = _resume(checkpoint, state, rec_modes, rec_pose)
    if first and progress:
        progress(float(times[first - 1]))
    last_save = time.monotonic()
    if first == 0:
        check_state(state, model, label)
        rec_modes[0], rec_pose[0] = state["modes"], state["pose"]
        first = 1

    def keep(next_sample: int, kept_state: dict[str, np.ndarray]) -> None:
        checkpoint.save(
            Saved(next_sample, rec_modes[:next_sample], rec_pose[:next_sample], kept_state)
        )

    done, done_state = first, _copy_state(state)  # the last consistent point
    record = Record(times, rec_modes, rec_pose, schedule.phase)
    try:
        for i in range(first, times.size, SAMPLES_PER_CALL):
            j = min(i + SAMPLES_PER_CALL, times.size)
            _sample_checked(model, stepper, state, schedule, record, slice(i, j), label)
            done, done_state = j, _copy_state(state)
            if progress:
                progress(float(times[j - 1] - times[i - 1]))
            if checkpoint is not None and time.monotonic() - last_save > checkpoint_every:
                keep(j, state)
                last_save = time.monotonic()
            if received() or (stop is not None and stop()):  # a swallowed Ctrl-C too
                raise KeyboardInterrupt
    except KeyboardInterrupt:
        # The stepper may have been stopped half way through a chunk: save what is whole.
        if checkpoint is not None:
            keep(done, done_state)
        raise Interrupted(
            f"interrupted at t = {times[done - 1]:.2f} s of {label}"
            + ("; rerun the same command to resume" if checkpoint else "")
        ) from None
    return Record(times, rec_modes, rec_pose, phase_at(schedule, times), state)


def _resume(
    checkpoint: Checkpoint | None,
    state: dict[str, np.ndarray],
    rec_modes: np.ndarray,
    rec_pose: np.ndarray,
) -> tuple[int, dict[str, np.ndarray]]:
    """The first sample still to compute and the state to compute it from: the checkpoint's
    (its samples copied into the records), or 0 and ``state``."""
    saved = checkpoint.load() if checkpoint is not None else None
    if saved is None:
        return 0, state
    first = saved.next_sample
    rec_modes[:first], rec_pose[:first] = saved.modes_record, saved.pose_record
    return first, {k: v.copy() for k, v in saved.state.items()}


def _sample_checked(
    model: Model,
    stepper: Stepper,
    state: dict[str, np.ndarray],
    schedule: Schedule,
    record: Record,
    chunk: slice,
    label: object,
) -> None:
    """Sample ``chunk`` of ``record.times`` into the record and check it; a failure is
    re-raised with :func:`~softcell.core.engine.probe.diagnose`'s finding appended."""
    filled = chunk.start  # samples recorded so far (finite or not)
    try:
        record.modes[chunk], record.pose[chunk] = stepper.sample(
            state, schedule, record.times[chunk]
        )
        filled = chunk.stop
        check_state(
            state, model, label, record.times[chunk], record.modes[chunk], record.pose[chunk]
        )
    except SimulationError as exc:
        modes, pose, t = stepper.current(state)  # a failed step may run ahead of the samples
        why = diagnose(
            model,
            np.append(record.times[:filled], t),
            np.vstack([record.modes[:filled], modes[None]]),
            np.vstack([record.pose[:filled], pose[None]]),
            schedule,
        )
        raise SimulationError(f"{exc}; {why}") from None


def _copy_state(state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {k: np.array(v, copy=True) for k, v in state.items()}


def record_dataset(
    record: Record,
    model: Model,
    *,
    realization: int,
    seed: int,
    components: dict[str, object],
    extra_attrs: dict[str, object] | None = None,
    scalar_coords: tuple[str, ...] = ("radius",),
):
    """The simulation Dataset (schema of :mod:`softcell.core.schema`) of one realization;
    the parameters ``scalar_coords`` are also its scalar coordinates."""
    # Imported here: the loop above needs no xarray (about 70 MiB), only the Dataset does.
    from softcell.core.schema import simulation_dataset
    from softcell.kernels.spectral import resample

    nodes = int(model.params.stored_nodes)
    if model.has_membrane:
        mx, my = resample(record.modes, nodes)
        cell = record.modes[:, model.cutoff]  # g_0: the mean of the membrane points
    else:
        mx = my = np.full((record.times.size, nodes), np.nan)
        cell = np.full(record.times.size, np.nan + 0j)
    return simulation_dataset(
        record.times,
        np.array([realization]),
        membrane_x=mx[None],
        membrane_y=my[None],
        cell_x=cell.real[None],
        cell_y=cell.imag[None],
        bot_x=record.pose[None, :, 0],
        bot_y=record.pose[None, :, 1],
        bot_angle=record.pose[None, :, 2],
        bot_phase=record.phase[None],
        parameters=model.params,
        seed=seed,
        components=components,
        extra_attrs=extra_attrs,
        scalar_coords=scalar_coords,
    )
