"""Ensembles: parameter points x realizations, one file each, reproducible and resumable.

Every random stream comes from one root seed: realization r of parameter point p draws from
``SeedSequence(seed, spawn_key=(p, r))``, so results do not depend on the number of workers or
their order. Each (point, realization) is written atomically to its own file; finished files
are skipped when the same command runs again, and a long realization checkpoints its state
(``.<name>.ckpt.npz``) so that a killed run resumes to the same bytes.

Beyond one process the realizations run on a dask.distributed cluster, one task each: a local
cluster of ``workers`` processes, or the cluster whose scheduler listens at ``scheduler``
(whose workers must see the output directory, e.g. on a shared file system).
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from softcell._version import __version__
from softcell.core.config import CHECKPOINT_EVERY
from softcell.core.engine import (
    Model,
    Record,
    Stepper,
    build_integrator,
    build_model,
    check_state,
    initial_state,
    phase_at,
    sample_times,
)
from softcell.core.errors import SoftcellError
from softcell.core.params import Parameters, expand_sweep
from softcell.core.runconfig import RunConfig


@dataclass(frozen=True)
class Task:
    """One (parameter point, realization) of an ensemble."""

    point: int
    realization: int
    values: dict[str, Any]  # the point's parameter values
    components: dict[str, Any]
    seed: int
    membrane: bool
    path: str

    @property
    def name(self) -> str:
        return f"point {self.point} realization {self.realization}"


def realization_rng(seed: int, point: int, realization: int) -> np.random.Generator:
    """The Generator of one realization: SeedSequence(seed, spawn_key=(point, realization))."""
    return np.random.Generator(np.random.PCG64(
        np.random.SeedSequence(seed, spawn_key=(point, realization))))


#: Samples handed to the stepper per call (progress, checks and checkpoints happen between
#: calls): 1 s of simulated time at the paper's early sampling.
SAMPLES_PER_CALL = 100


def run_realization(model: Model, stepper: Stepper, rng: np.random.Generator, *,
                    label: object = 0, checkpoint: Path | None = None,
                    fingerprint: str = "", checkpoint_every: float = CHECKPOINT_EVERY,
                    progress: Callable[[float], None] | None = None) -> Record:
    """Integrate one realization over the sampling grid of ``model.params``.

    Parameters
    ----------
    checkpoint : Path, optional
        Where to save the state every ``checkpoint_every`` wall seconds, and to resume from if
        a checkpoint with the same ``fingerprint`` exists.
    progress : callable, optional
        Called with the simulated seconds advanced since its last call.
    """
    times = sample_times(model.params)
    modes, pose, schedule = initial_state(model, rng)
    state = stepper.start(modes, pose, schedule)
    rec_modes = np.empty((times.size, modes.size), dtype=np.complex128)
    rec_pose = np.empty((times.size, 3))
    first = 0
    if checkpoint is not None and checkpoint.exists():
        saved = np.load(checkpoint, allow_pickle=False)
        if str(saved["fingerprint"]) == fingerprint:
            first = int(saved["next_sample"])
            rec_modes[:first], rec_pose[:first] = saved["modes_record"], saved["pose_record"]
            state = {k.removeprefix("state_"): saved[k].copy() for k in saved.files
                     if k.startswith("state_")}
            if progress:
                progress(float(times[first - 1]))
    last_save = time.monotonic()
    if first == 0:
        check_state(state, model, label)
        rec_modes[0], rec_pose[0] = state["modes"], state["pose"]
        first = 1
    for i in range(first, times.size, SAMPLES_PER_CALL):
        j = min(i + SAMPLES_PER_CALL, times.size)
        rec_modes[i:j], rec_pose[i:j] = stepper.sample(state, schedule, times[i:j])
        check_state(state, model, label, times[i:j], rec_modes[i:j], rec_pose[i:j])
        if progress:
            progress(float(times[j - 1] - times[i - 1]))
        if checkpoint is not None and time.monotonic() - last_save > checkpoint_every:
            _save_checkpoint(checkpoint, fingerprint, j, rec_modes, rec_pose, state)
            last_save = time.monotonic()
    return Record(times, rec_modes, rec_pose, phase_at(schedule, times), state)


def _save_checkpoint(path: Path, fingerprint: str, next_sample: int, rec_modes: np.ndarray,
                     rec_pose: np.ndarray, state: dict[str, np.ndarray]) -> None:
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp.npz")
    np.savez(tmp, fingerprint=np.array(fingerprint), next_sample=np.array(next_sample),
             modes_record=rec_modes[:next_sample], pose_record=rec_pose[:next_sample],
             **{f"state_{k}": v for k, v in state.items()})
    os.replace(tmp, path)


def record_dataset(record: Record, model: Model, *, realization: int, seed: int,
                   components: dict[str, Any], extra_attrs: dict[str, Any] | None = None):
    """The simulation Dataset (schema of ``softcell.io.schema``) of one realization."""
    from softcell.core.kernels.spectral import resample
    from softcell.io.schema import simulation_dataset

    nodes = int(model.params.stored_nodes)
    if model.has_membrane:
        mx, my = resample(record.modes, nodes)
        cell = record.modes[:, model.cutoff]  # g_0: the mean of the membrane points
    else:
        mx = my = np.full((record.times.size, nodes), np.nan)
        cell = np.full(record.times.size, np.nan + 0j)
    return simulation_dataset(
        record.times, np.array([realization]), membrane_x=mx[None], membrane_y=my[None],
        cell_x=cell.real[None], cell_y=cell.imag[None], bot_x=record.pose[None, :, 0],
        bot_y=record.pose[None, :, 1], bot_angle=record.pose[None, :, 2],
        bot_phase=record.phase[None], parameters=model.params, seed=seed,
        components=components, extra_attrs=extra_attrs)


_BUILT: dict[str, tuple[Model, Stepper]] = {}


def _model_and_stepper(task: Task, extra_specs) -> tuple[Model, Stepper]:
    key = json.dumps([task.values, task.components, task.membrane], sort_keys=True)
    if key not in _BUILT:
        params = Parameters(task.values, extra_specs)
        model = build_model(params, task.components["energy_terms"],
                            task.components["driving_protocol"], membrane=task.membrane)
        integrator = build_integrator(task.components["integrator"], params)
        _BUILT[key] = (model, integrator.build(model))
    return _BUILT[key]


def run_task(task: Task, progress: Callable[[float], None] | None = None,
             checkpoint_every: float = CHECKPOINT_EVERY) -> str:
    """Run one (point, realization) and write its file atomically; returns the path."""
    from softcell.core.registry import get_registry
    from softcell.io.netcdf import write_dataset

    model, stepper = _model_and_stepper(task, get_registry().parameter_specs().values())
    path = Path(task.path)
    fingerprint = hashlib.sha256(json.dumps(
        [task.values, task.components, task.seed, task.point, task.realization, task.membrane,
         __version__], sort_keys=True).encode()).hexdigest()
    checkpoint = path.with_name(f".{path.stem}.ckpt.npz")
    record = run_realization(model, stepper, realization_rng(task.seed, task.point,
                                                             task.realization),
                             label=task.name, checkpoint=checkpoint, fingerprint=fingerprint,
                             checkpoint_every=checkpoint_every, progress=progress)
    components = {**task.components, "membrane": task.membrane}
    if not task.membrane:
        components["energy_terms"] = []
    ds = record_dataset(record, model, realization=task.realization, seed=task.seed,
                        components=components,
                        extra_attrs={"softcell_point": task.point,
                                     "softcell_spawn_key": f"{task.point},{task.realization}"})
    write_dataset(ds, path)
    checkpoint.unlink(missing_ok=True)
    return str(path)


def plan(config: RunConfig, out: Path, *, realizations: int, seed: int,
         membrane: bool = True) -> list[Task]:
    """The tasks of an ensemble, one per (parameter point, realization), in order."""
    from softcell.core.registry import get_registry

    registry = get_registry()
    points = expand_sweep(config.parameters, list(registry.parameter_specs().values()))
    integrator = registry.get("integrator", config.components["integrator"])
    for _, params in points:
        integrator.check(params)
    tasks = []
    for p, (_, params) in enumerate(points):
        for r in range(realizations):
            tasks.append(Task(p, r, dict(params.given), dict(config.components), seed, membrane,
                              str(out / f"point{p:03d}_realization{r:04d}.nc")))
    return tasks


def simulate(config: RunConfig, out: str | os.PathLike[str], *, realizations: int = 1,
             seed: int = 0, workers: int = 1, scheduler: str | None = None,
             client: Any = None, membrane: bool = True, progress: bool = True,
             checkpoint_every: float = CHECKPOINT_EVERY) -> list[Path]:
    """Run an ensemble: every parameter point of ``config`` x ``realizations``.

    Files already present in ``out`` are kept (finished realizations are skipped).

    Parameters
    ----------
    workers : int
        1: run in this process; more: a local dask.distributed cluster of that many
        single-threaded worker processes.
    scheduler : str, optional
        Address of a running dask.distributed scheduler (``tcp://host:8786``): one task per
        realization on its workers, which must be able to write to ``out``. Excludes
        ``workers``.

    Returns
    -------
    list of Path
        One NetCDF file per (point, realization), in task order. The bytes do not depend on
        ``workers`` or ``scheduler``.
    """
    from tqdm.auto import tqdm

    if workers < 1:
        raise SoftcellError(f"workers = {workers} is not allowed: must be >= 1")
    if sum([scheduler is not None, workers != 1, client is not None]) > 1:
        raise SoftcellError(f"workers = {workers}, scheduler = {scheduler!r} and a client "
                            "exclude each other: give one")
    out = Path(out).resolve()  # workers of a cluster have their own working directories
    out.mkdir(parents=True, exist_ok=True)
    tasks = plan(config, out, realizations=realizations, seed=seed, membrane=membrane)
    todo = [t for t in tasks if not Path(t.path).exists()]
    total = sum(_duration(t) for t in todo)
    with tqdm(total=total, unit="sim s", disable=not progress or not todo, unit_scale=False,
              bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.2f}/{total:.2f} sim s "
                         "[{elapsed}<{remaining}]",
              desc=f"{len(todo)} realizations") as bar:
        if client is not None:
            run_on_cluster(todo, client, bar.update, checkpoint_every)
        elif scheduler is None and workers == 1:
            for task in todo:
                run_task(task, bar.update, checkpoint_every)
        elif todo:
            with cluster_client(workers, scheduler) as own:
                run_on_cluster(todo, own, bar.update, checkpoint_every)
    return [Path(t.path) for t in tasks]


def _duration(task: Task) -> float:
    from softcell.core.registry import get_registry

    return float(Parameters(task.values, get_registry().parameter_specs().values()).duration)


@contextmanager
def cluster_client(workers: int, scheduler: str | None = None) -> Iterator[Any]:
    """A dask.distributed Client, as a context manager: of the scheduler at ``scheduler``, or
    of a new local cluster of ``workers`` single-threaded processes, closed on exit."""
    import logging

    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="30s")
        except OSError as exc:
            raise SoftcellError(f"cannot reach the dask scheduler at {scheduler!r}: {exc}"
                                ) from None
        with client:
            yield client
        return
    logging.getLogger("distributed").setLevel(logging.ERROR)
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        yield client


def run_on_cluster(tasks: list[Task], client, progress: Callable[[float], None] | None = None,
                   checkpoint_every: float = CHECKPOINT_EVERY) -> list[str]:
    """Run ``tasks`` on a dask.distributed ``client``, one task per realization; each writes
    its own file atomically. ``progress`` is called with a task's simulated seconds when it
    ends. The first failure cancels what has not started and is raised (finished files stay).
    """
    from distributed import as_completed

    futures = {client.submit(run_task, task, None, checkpoint_every, pure=False): task
               for task in tasks}
    paths = []
    try:
        for future in as_completed(futures):
            paths.append(future.result())
            if progress:
                progress(_duration(futures[future]))
    except BaseException:
        client.cancel(list(futures))
        raise
    return paths
