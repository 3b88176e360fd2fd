"""One realization: the schedule, the stepper and the samples, as a Dataset.

This is the engine's outer loop. It touches no file: where a long realization keeps its
checkpoint is the caller's business, handed in as a :class:`Checkpoint` (the ensembles of
:mod:`softcell.runner.ensemble` keep one file per realization).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from softcell.components.contracts import Schedule, Stepper
from softcell.engine.diagnose import diagnose
from softcell.engine.interrupt import received, shielded
from softcell.engine.model import Model
from softcell.engine.state import (
    Record,
    check_state,
    fine_times,
    initial_state,
    phase_at,
    sample_times,
    sampling_plan,
)
from softcell.errors import Interrupted, SimulationError
from softcell.settings import CHECKPOINT_EVERY

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
    """What a checkpoint holds: the samples recorded so far and the stepper's state.

    Sample indices count the sampling grid of :func:`~softcell.engine.state.sampling_plan`
    (the membrane's times and the bodies' fine times together).
    """

    next_sample: int  # index of the first grid sample not yet recorded
    modes_record: np.ndarray  # (membrane samples so far, modes) complex, cm
    pose_record: np.ndarray  # (next_sample, 3): x (cm), y (cm), angle (rad)
    state: dict[str, np.ndarray]  # the stepper's state after sample next_sample - 1
    center_record: np.ndarray | None = None  # (next_sample,) complex: g_0 (cm)


class Checkpoint(Protocol):
    """Where a realization saves its progress and resumes from."""

    def load(self) -> Saved | None:
        """The saved progress, or None to start from the beginning."""

    def save(self, saved: Saved) -> None:
        """Keep ``saved`` (replacing what was kept before), all or nothing."""


@dataclass
class SampleGrid:
    """The samples of one realization on its sampling grid (see :class:`Saved`); an
    assembly's (:mod:`softcell.engine.groups`) have a cell axis after the first."""

    times: np.ndarray  # float64[G], s
    membrane: np.ndarray  # int64[T]: grid index of each membrane sample
    fine: np.ndarray  # int64[F]: grid index of each fine sample
    modes: np.ndarray  # complex128[T, 2 Lc + 1]
    pose: np.ndarray  # float64[G, 3]
    center: np.ndarray  # complex128[G]

    def membrane_before(self, sample: int) -> int:
        """Membrane samples among the first ``sample`` grid samples."""
        return int(np.searchsorted(self.membrane, sample))

    def saved(self, sample: int, state: dict[str, np.ndarray]) -> Saved:
        return Saved(
            sample,
            self.modes[: self.membrane_before(sample)],
            self.pose[:sample],
            state,
            self.center[:sample],
        )

    def restore(self, saved: Saved) -> None:
        first = saved.next_sample
        self.modes[: self.membrane_before(first)] = saved.modes_record
        self.pose[:first], self.center[:first] = saved.pose_record, saved.center_record

    def keep(self, chunk: slice, modes: np.ndarray, pose: np.ndarray, cutoff: int) -> None:
        """Record the stepper's samples of grid ``chunk``: every pose and centre, the modes
        of the membrane samples alone."""
        self.pose[chunk], self.center[chunk] = pose, modes[:, cutoff]
        lo, hi = self.membrane_before(chunk.start), self.membrane_before(chunk.stop)
        self.modes[lo:hi] = modes[self.membrane[lo:hi] - chunk.start]


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
    start: tuple[dict[str, np.ndarray], Schedule | list[Schedule]] | None = None,
) -> Record:
    """Integrate one realization over the sampling grid of ``model.params``: the membrane at
    :func:`~softcell.engine.state.sample_times`, the cell's centre and the bot's pose
    also at :func:`~softcell.engine.state.fine_times` (the record's ``fine_*`` fields).

    Parameters
    ----------
    checkpoint : Checkpoint, optional
        Saved every ``checkpoint_every`` wall seconds (and when interrupted), and resumed from
        when it holds progress.
    progress : callable, optional
        Called with the simulated seconds advanced since its last call.
    stop : callable, optional
        Asked between chunks of samples; True stops the run as Ctrl-C does.
    start : (state, schedules), optional
        The stepper's starting state and the bots' schedules, for several bots in one ring
        (:mod:`softcell.engine.bots`): the pose record then has 3 columns per bot and the
        phase record one per bot. None: one bot, started by
        :func:`~softcell.engine.state.initial_state` from ``rng``.

    Raises
    ------
    Interrupted
        On Ctrl-C (a ``KeyboardInterrupt``) or ``stop``, after saving the checkpoint of the
        last finished chunk; its message says where the run stopped.
    """
    times, membrane, fine = sampling_plan(model.params)
    state, schedule = _started(model, stepper, rng, start)
    grid = SampleGrid(
        times,
        membrane,
        fine,
        np.empty((membrane.size, state["modes"].size), dtype=np.complex128),
        np.empty((times.size, state["pose"].size)),
        np.empty(times.size, dtype=np.complex128),
    )
    first, state = _restored(checkpoint, grid, state)
    if first and progress:
        progress(float(times[first - 1]))
    last_save = time.monotonic()
    if first == 0:
        check_state(state, model, label)
        grid.keep(slice(0, 1), state["modes"][None], state["pose"][None], model.cutoff)
        first = 1

    def keep(next_sample: int, kept_state: dict[str, np.ndarray]) -> None:
        checkpoint.save(grid.saved(next_sample, kept_state))

    done, done_state = first, _copy_state(state)  # the last consistent point
    try:
        for i in range(first, times.size, SAMPLES_PER_CALL):
            j = min(i + SAMPLES_PER_CALL, times.size)
            _sample_checked(model, stepper, state, schedule, grid, slice(i, j), label)
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
            with shielded():
                keep(done, done_state)
        raise Interrupted(
            f"interrupted at t = {times[done - 1]:.2f} s of {label}"
            + ("; rerun the same command to resume" if checkpoint else "")
        ) from None
    membrane_times, fine_times_ = sample_times(model.params), fine_times(model.params)
    starts = state.get("starts")  # as the protocol's events shifted them
    return Record(
        membrane_times,
        grid.modes,
        grid.pose[membrane],
        _phases(schedule, membrane_times, starts),
        state,
        fine_times=fine_times_,
        fine_center=grid.center[fine],
        fine_pose=grid.pose[fine],
        fine_phase=_phases(schedule, fine_times_, starts),
        event_times=None
        if starts is None
        else state["event_times"][: int(state["event_count"][0])].copy(),
    )


def _started(model: Model, stepper: Stepper, rng: np.random.Generator | None, start):
    """``start`` (several bots), or the stepper's starting state and the schedule of one bot,
    drawn from ``rng``."""
    if start is not None:
        return start
    modes, pose, schedule = initial_state(model, rng)
    return stepper.start(modes, pose, schedule), schedule


def _phases(
    schedule: Schedule | list[Schedule], times: np.ndarray, starts: np.ndarray | None
) -> np.ndarray:
    """The phase codes at ``times``: int8[T] for one bot, int8[T, K] for several."""
    if isinstance(schedule, list):
        return np.stack([phase_at(s, times) for s in schedule], axis=-1)
    return phase_at(schedule, times, starts)


def _restored(
    checkpoint: Checkpoint | None, grid: SampleGrid, state: dict[str, np.ndarray]
) -> tuple[int, dict[str, np.ndarray]]:
    """The first grid sample still to compute and the state to compute it from: the
    checkpoint's (its samples copied into ``grid``), or 0 and ``state``."""
    saved = checkpoint.load() if checkpoint is not None else None
    if saved is None:
        return 0, state
    grid.restore(saved)
    return saved.next_sample, {k: v.copy() for k, v in saved.state.items()}


def _sample_checked(
    model: Model,
    stepper: Stepper,
    state: dict[str, np.ndarray],
    schedule: Schedule,
    grid: SampleGrid,
    chunk: slice,
    label: object,
) -> None:
    """Sample ``chunk`` of ``grid.times`` into the grid's records and check it; a failure is
    re-raised with :func:`~softcell.engine.diagnose.diagnose`'s finding appended."""
    filled = chunk.start  # samples recorded so far (finite or not)
    try:
        modes, pose = stepper.sample(state, schedule, grid.times[chunk])
        grid.keep(chunk, modes, pose, model.cutoff)
        filled = chunk.stop
        check_state(state, model, label, grid.times[chunk], modes, pose)
    except SimulationError as exc:
        modes, pose, t = stepper.current(state)  # a failed step may run ahead of the samples
        n = grid.membrane_before(filled)
        first_bot = schedule[0] if isinstance(schedule, list) else schedule
        why = diagnose(  # of the first bot, with several
            model,
            np.append(grid.times[grid.membrane[:n]], t),
            np.vstack([grid.modes[:n], modes[None]]),
            np.vstack([grid.pose[grid.membrane[:n]], pose[None]])[:, :3],
            first_bot,
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
    """The simulation Dataset (schema of :mod:`softcell.schema`) of one realization;
    the parameters ``scalar_coords`` are also its scalar coordinates."""
    # Imported here: the loop above needs no xarray (about 70 MiB), only the Dataset does.
    from softcell.engine.kernels.spectral import resample
    from softcell.schema import simulation_dataset

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
        fine=_fine_record(record, model),
        events=None if record.event_times is None else record.event_times[None],
    )


def _fine_record(record: Record, model: Model) -> dict[str, np.ndarray] | None:
    """The bodies' fine record as :func:`~softcell.schema.simulation_dataset` takes it."""
    if record.fine_times is None:
        return None
    center = record.fine_center
    if not model.has_membrane:
        center = np.full(center.shape, complex(np.nan, np.nan))
    return {
        "fine_time": record.fine_times,
        "cell_x_fine": center.real[None],
        "cell_y_fine": center.imag[None],
        "bot_x_fine": record.fine_pose[None, :, 0],
        "bot_y_fine": record.fine_pose[None, :, 1],
        "bot_angle_fine": record.fine_pose[None, :, 2],
        "bot_phase_fine": record.fine_phase[None],
    }
