"""Ensembles: parameter points x realizations, one file each, reproducible and resumable.

Every random stream comes from one root seed: realization r of parameter point p draws from
``SeedSequence(seed, spawn_key=(p, r))``, so results do not depend on the number of workers or
their order. Each (point, realization) is written atomically to its own file; a finished file
is reused when the same request runs again (and only then: a file made with any other
setting stops the run, ``resume_plan``), and a long realization checkpoints its state
(``.<name>.ckpt.npz``) so that a killed or interrupted run resumes to the same bytes.

Beyond one process the realizations run on a dask.distributed cluster, one task each: a local
cluster of ``workers`` processes, or the cluster whose scheduler listens at ``scheduler``
(whose workers must see the output directory, e.g. on a shared file system).
"""

from __future__ import annotations

import json
import math
import os
import warnings
import zipfile
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from softcell._version import __version__
from softcell.config import CHECKPOINT_EVERY
from softcell.core.engine import Model, Stepper, build_integrator, build_model, sample_times
from softcell.core.limits import check_run, check_seed, file_bytes
from softcell.core.params import Parameters, ParameterSpec, expand_sweep
from softcell.core.realization import Saved, realization_rng, record_dataset, run_realization
from softcell.core.runconfig import RunConfig
from softcell.errors import Interrupted, SoftcellError
from softcell.io.files import atomic_write


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
    swept: tuple[str, ...] = ("radius",)  # stored as scalar coordinates too

    @property
    def name(self) -> str:
        return f"point {self.point} realization {self.realization}"

    @property
    def stored_components(self) -> dict[str, Any]:
        """The component names as its file stores them (a free bot keeps only the energy terms
        that act on the bot alone, such as the arena)."""
        components = {**self.components, "membrane": self.membrane}
        if not self.membrane:
            components["energy_terms"] = bot_terms(self.components.get("energy_terms", []))
        return components

    def request(self, extra_specs: Iterable[ParameterSpec] = ()) -> dict[str, Any]:
        """Every setting a file or checkpoint of this task must have been made with, in the
        order they are compared: each parameter, the components, seed, spawn key, version."""
        params = json.loads(Parameters(self.values, extra_specs).to_attrs()["softcell_parameters"])
        return _request(
            params,
            self.stored_components,
            self.seed,
            f"{self.point},{self.realization}",
            __version__,
        )


def bot_terms(names: Iterable[str]) -> list[str]:
    """Of the energy terms ``names``, those that act on the bot alone (what a free bot keeps)."""
    from softcell.core.plugin.registry import get_registry

    registry = get_registry()
    return [n for n in names if registry.get("energy_term", n).acts_on_bot]


def _request(
    parameters: dict[str, Any], components: dict[str, Any], seed: Any, spawn_key: Any, version: Any
) -> dict[str, Any]:
    return {
        **{f"parameter {k}": v for k, v in parameters.items()},
        **{f"component {k}": v for k, v in sorted(components.items())},
        "seed": seed,
        "spawn key": spawn_key,
        "softcell version": version,
    }


class FileCheckpoint:
    """The checkpoint of one realization in a file (``.<name>.ckpt.npz`` beside its result),
    valid only for the request it was made for (``fingerprint``, the task's request as JSON)."""

    def __init__(self, path: Path, fingerprint: str):
        self.path, self.fingerprint = path, fingerprint

    def load(self) -> Saved | None:
        if not self.path.exists():
            return None
        data = read_checkpoint(self.path)
        if data["request"] != self.fingerprint:
            raise SoftcellError(
                f"checkpoint {self.path} was made for another request; "
                "remove it or rerun with --overwrite"
            )
        return Saved(
            int(data["next_sample"]),
            data["modes_record"],
            data["pose_record"],
            {k.removeprefix("state_"): v for k, v in data.items() if k.startswith("state_")},
        )

    def save(self, saved: Saved) -> None:
        _save_checkpoint(
            self.path,
            self.fingerprint,
            saved.next_sample,
            saved.modes_record,
            saved.pose_record,
            saved.state,
        )


def _save_checkpoint(
    path: Path,
    request: str,
    next_sample: int,
    rec_modes: np.ndarray,
    rec_pose: np.ndarray,
    state: dict[str, np.ndarray],
) -> None:
    with atomic_write(path) as tmp:
        np.savez(
            tmp,
            request=np.array(request),
            next_sample=np.array(next_sample),
            modes_record=rec_modes[:next_sample],
            pose_record=rec_pose[:next_sample],
            **{f"state_{k}": v for k, v in state.items()},
        )


def read_checkpoint(path: Path) -> dict[str, Any]:
    """The arrays of a checkpoint, ``request`` as a str; a one-line error if unreadable."""
    try:
        with np.load(path, allow_pickle=False) as saved:
            data = {k: saved[k] for k in saved.files}
        data["request"] = str(data.get("request", ""))
        int(data["next_sample"])
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise SoftcellError(
            f"checkpoint {path} is unreadable (truncated or corrupt: "
            f"{type(exc).__name__}); rerun with --overwrite to start that "
            "realization again"
        ) from None
    return data


_BUILT: dict[str, tuple[Model, Stepper]] = {}


def _model_and_stepper(task: Task, extra_specs) -> tuple[Model, Stepper]:
    key = json.dumps([task.values, task.components, task.membrane], sort_keys=True)
    if key not in _BUILT:
        params = Parameters(task.values, extra_specs)
        model = build_model(
            params,
            task.components["energy_terms"],
            task.components["driving_protocol"],
            membrane=task.membrane,
            friction_law=task.components.get("friction_law", "viscous"),
        )
        integrator = build_integrator(task.components["integrator"], params)
        _BUILT[key] = (model, integrator.build(model))
    return _BUILT[key]


#: A file in the output directory asking the realizations running on a cluster to save a
#: checkpoint and stop (what Ctrl-C does to this process; see :func:`run_on_cluster`).
STOP_FILE = ".softcell-stop"
#: Wall seconds a cluster's realizations get to checkpoint and stop after Ctrl-C.
STOP_GRACE = 30.0


def run_task(
    task: Task,
    progress: Callable[[float], None] | None = None,
    checkpoint_every: float = CHECKPOINT_EVERY,
    stoppable: bool = False,
) -> str | None:
    """Run one (point, realization) and write its file atomically; returns the path.

    With ``stoppable`` (on a cluster), :data:`STOP_FILE` appearing beside the file makes the
    realization save its checkpoint and return None.
    """
    from softcell.core.plugin.registry import PluginWarning, get_registry
    from softcell.io.netcdf import write_dataset

    with warnings.catch_warnings():  # the command that planned the run has warned already
        warnings.simplefilter("ignore", PluginWarning)
        specs = get_registry().parameter_specs().values()
    model, stepper = _model_and_stepper(task, specs)
    path = Path(task.path)
    checkpoint = checkpoint_path(path)
    stop_file = path.parent / STOP_FILE
    try:
        record = run_realization(
            model,
            stepper,
            realization_rng(task.seed, task.point, task.realization),
            label=task.name,
            checkpoint=FileCheckpoint(checkpoint, _canonical(task.request(specs))),
            checkpoint_every=checkpoint_every,
            progress=progress,
            stop=stop_file.exists if stoppable else None,
        )
    except Interrupted:
        if not stoppable:
            raise
        return None  # asked to stop: the checkpoint is saved
    ds = record_dataset(
        record,
        model,
        realization=task.realization,
        seed=task.seed,
        components=task.stored_components,
        extra_attrs={
            "softcell_point": task.point,
            "softcell_spawn_key": f"{task.point},{task.realization}",
        },
        scalar_coords=task.swept,
    )
    write_dataset(ds, path)
    checkpoint.unlink(missing_ok=True)
    return str(path)


def plan(
    config: RunConfig, out: Path, *, realizations: int, seed: int, membrane: bool = True
) -> list[Task]:
    """The tasks of an ensemble, one per (parameter point, realization), in order.

    Everything is checked here, before anything is computed: the component names, every
    parameter point (including what fits in memory, :func:`softcell.core.limits.check_run`),
    the integrator's own conditions, the seed and the number of realizations.
    """
    from softcell.core.plugin.registry import get_registry

    if isinstance(realizations, bool) or not isinstance(realizations, int) or realizations < 1:
        raise SoftcellError(
            f"realizations = {realizations!r} is not allowed: must be an integer >= 1"
        )
    check_seed(seed)
    config.check_components()
    registry = get_registry()
    points = expand_sweep(config.parameters, list(registry.parameter_specs().values()))
    integrator = registry.get("integrator", config.components["integrator"])
    for _, params in points:
        check_run(params)
        integrator.check(params)
    swept = tuple(
        dict.fromkeys(
            ["radius", *(k for k, v in config.parameters.items() if isinstance(v, list | tuple))]
        )
    )
    tasks = []
    for p, (_, params) in enumerate(points):
        for r in range(realizations):
            tasks.append(
                Task(
                    p,
                    r,
                    dict(params.given),
                    dict(config.components),
                    seed,
                    membrane,
                    str(out / f"point{p:03d}_realization{r:04d}.nc"),
                    swept,
                )
            )
    return tasks


def checkpoint_path(path: Path) -> Path:
    """The checkpoint of the realization whose file is ``path``."""
    return path.with_name(f".{path.stem}.ckpt.npz")


def _canonical(request: dict[str, Any]) -> str:
    return json.dumps(request, sort_keys=True)


def _shown(value: Any) -> str:
    return value if isinstance(value, str) else json.dumps(value, sort_keys=True)


def first_mismatch(made: dict[str, Any], wanted: dict[str, Any]) -> str | None:
    """``"radius = 4.0 there, 8.0 in this request"`` for the first setting (in the order of
    ``wanted``) whose value differs, or None when every setting is equal."""
    for key in [*wanted, *(k for k in made if k not in wanted)]:
        there, here = made.get(key, "(none)"), wanted.get(key, "(none)")
        if json.dumps(there, sort_keys=True) != json.dumps(here, sort_keys=True):
            return f"{key} = {_shown(there)} there, {_shown(here)} in this request"
    return None


def stored_request(path: Path) -> tuple[dict[str, Any], np.ndarray]:
    """The settings a simulation file was made with, in the form of :meth:`Task.request`,
    and its sample times (s).

    Raises
    ------
    SoftcellError
        If the file does not open or does not follow the schema.
    """
    from softcell.core.schema import problems
    from softcell.io.netcdf import open_dataset

    try:
        ds = open_dataset(path)  # lazily: the membrane is not read
    except SoftcellError:
        raise SoftcellError("it is not a readable NetCDF file (truncated or corrupt)") from None
    with ds:
        found = problems(ds)
        if found:
            raise SoftcellError(f"it does not follow the simulation schema ({found[0]})")
        a = ds.attrs
        return _request(
            json.loads(a["softcell_parameters"]),
            json.loads(a["softcell_components"]),
            int(a["softcell_seed"]),
            str(a.get("softcell_spawn_key")),
            a.get("softcell_version"),
        ), np.asarray(ds["time"].values)


def _reuse_problem(path: Path, wanted: dict[str, Any], times: np.ndarray) -> str | None:
    """Why the finished file ``path`` cannot stand for the request ``wanted``, or None."""
    try:
        made, stored = stored_request(path)
    except SoftcellError as exc:
        return f"cannot be reused: {exc}"
    why = first_mismatch(made, wanted)
    if why:
        return f"was made with {why}"
    if not np.array_equal(stored, times):
        return f"is incomplete ({stored.size} samples, {times.size} expected)"
    return None


@dataclass
class Resume:
    """What an existing output directory holds for a request: tasks still to run, files to
    remove first (``overwrite``), and how many finished files are reused."""

    todo: list[Task]
    remove: list[Path]
    reused: int


def _overwrite_hint(path: Path, why: str) -> SoftcellError:
    return SoftcellError(
        f"{path} {why}; rerun with --overwrite to recompute it (and every "
        "other file that does not match), or write to another directory"
    )


def resume_plan(tasks: list[Task], out: Path, *, overwrite: bool = False) -> Resume:
    """Compare what ``out`` holds with the request ``tasks``, before anything runs.

    A finished file is reused only when it is complete and was made with exactly the
    request's settings (every parameter, the components, seed, spawn key, package version);
    a checkpoint only when it was made for the same request. Anything else stops the run
    with one line naming the first mismatching setting and both values, unless
    ``overwrite``: then it is removed and recomputed. Simulation files in ``out`` that are
    no part of the request (a larger sweep, more realizations) stop the run too, as they
    would be read as part of the sweep; ``overwrite`` removes them.
    """
    from softcell.io.files import kind_of

    specs = _specs()
    resume = Resume([], [], 0)
    if not out.exists():
        return Resume(list(tasks), [], 0)
    for task in tasks:
        path, checkpoint = Path(task.path), checkpoint_path(Path(task.path))
        wanted = task.request(specs)
        if path.exists():
            why = _reuse_problem(path, wanted, sample_times(Parameters(task.values, specs)))
            if why is None:
                resume.reused += 1
                continue
            if not overwrite:
                raise _overwrite_hint(path, why)
            resume.remove.append(path)
        if checkpoint.exists():
            try:
                made = json.loads(read_checkpoint(checkpoint)["request"] or "{}")
                why = first_mismatch(made, wanted)
                why = why and f"was made with {why}"
            except (SoftcellError, ValueError):
                why = "cannot be reused: it is truncated or corrupt"
            if why is not None:
                if not overwrite:
                    raise _overwrite_hint(checkpoint, why)
                resume.remove.append(checkpoint)
        resume.todo.append(task)
    planned = {Path(t.path).name for t in tasks}
    stray = sorted(
        p
        for p in out.glob("*.nc")
        if p.name not in planned and not p.name.startswith(".") and kind_of(p) == "simulation"
    )
    if stray and not overwrite:
        raise SoftcellError(
            f"{out} holds {len(stray)} simulation file(s) that are no part of "
            f"this request (e.g. {stray[0].name}), which would be read as part "
            "of the sweep; rerun with --overwrite to remove them, or write to "
            "another directory"
        )
    resume.remove.extend(stray)
    return resume


def expected_bytes(tasks: list[Task]) -> int:
    """Disk space (bytes) the files of ``tasks`` will take, about."""
    specs = _specs()
    return sum(file_bytes(Parameters(t.values, specs)) for t in tasks)


def simulate(
    config: RunConfig,
    out: str | os.PathLike[str],
    *,
    realizations: int = 1,
    seed: int = 0,
    workers: int = 1,
    scheduler: str | None = None,
    client: Any = None,
    membrane: bool = True,
    progress: bool = True,
    checkpoint_every: float = CHECKPOINT_EVERY,
    overwrite: bool = False,
    log: Callable[[str], None] | None = None,
) -> list[Path]:
    """Run an ensemble: every parameter point of ``config`` x ``realizations``.

    Parameters take the units of ``softcell params`` (cm, s, rad, N); each file stores
    positions in cm, angles in rad and times in s, with CF ``units`` attributes.

    Finished files already in ``out`` are kept when they match the request exactly (see
    ``resume_plan``); a mismatch stops the run before anything is computed.

    Parameters
    ----------
    workers : int
        1: run in this process; more: a local dask.distributed cluster of that many
        single-threaded worker processes.
    scheduler : str, optional
        Address of a running dask.distributed scheduler (``tcp://host:8786``): one task per
        realization on its workers, which must be able to write to ``out``. Excludes
        ``workers``.
    overwrite : bool
        Recompute files and checkpoints in ``out`` that do not match the request, and remove
        simulation files that are no part of it (``log`` is told which).
    log : callable, optional
        Receives one line naming what ``overwrite`` removes.

    Returns
    -------
    list of Path
        One NetCDF file per (point, realization), in task order. The bytes do not depend on
        ``workers`` or ``scheduler``.

    Raises
    ------
    SoftcellError
        For any bad request, before anything is computed or any directory created.
    softcell.errors.Interrupted
        On Ctrl-C, once the running realizations' checkpoints are saved.
    """
    from softcell.config import progress_bar_class

    tqdm = progress_bar_class()

    from softcell.io.files import check_output, check_writable, remove

    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise SoftcellError(f"workers = {workers!r} is not allowed: must be an integer >= 1")
    if sum([scheduler is not None, workers != 1, client is not None]) > 1:
        raise SoftcellError(
            f"workers = {workers}, scheduler = {scheduler!r} and a client "
            "exclude each other: give one"
        )
    if not (isinstance(checkpoint_every, int | float) and 0 <= checkpoint_every < math.inf):
        raise SoftcellError(
            f"checkpoint_every = {checkpoint_every} s is not allowed: must be "
            "finite and >= 0 s (0: after every chunk of samples)"
        )
    out = check_output(out, "simulation", directory=True)  # absolute: cluster workers too
    tasks = plan(config, out, realizations=realizations, seed=seed, membrane=membrane)
    resume = resume_plan(tasks, out, overwrite=overwrite)
    check_writable(out, expected_bytes(resume.todo))
    if scheduler is not None:
        check_scheduler(scheduler)
    if resume.remove and log:
        names = [p.name for p in resume.remove]
        log(
            f"--overwrite: removing {len(names)} file(s) of {out} that do not match this "
            f"request ({', '.join(names[:3])}{', ...' if len(names) > 3 else ''})"
        )
    remove([*resume.remove, out / STOP_FILE])  # a stop request left by a crash is stale
    out.mkdir(parents=True, exist_ok=True)
    todo = resume.todo
    total = sum(_duration(t) for t in todo)
    # smoothing=0: the ETA from the average rate since the start, not the last few updates
    with tqdm(
        total=total,
        unit="sim s",
        disable=not progress or not todo,
        unit_scale=False,
        smoothing=0,
        bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.2f}/{total:.2f} sim s "
        "[{elapsed}<{remaining}]",
        desc=f"{len(todo)} realizations",
    ) as bar:
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
    return float(Parameters(task.values, _specs()).duration)


@contextmanager
def cluster_client(workers: int, scheduler: str | None = None) -> Iterator[Any]:
    """A dask.distributed Client, as a context manager: of the scheduler at ``scheduler``, or
    of a new local cluster of ``workers`` single-threaded processes, closed on exit."""
    import logging

    from distributed import Client, LocalCluster

    if scheduler is not None:
        check_scheduler(scheduler)
        try:
            client = Client(scheduler, timeout="30s")
        except OSError as exc:
            raise SoftcellError(
                f"cannot reach the dask scheduler at {scheduler!r}: {exc}"
            ) from None
        with client:
            yield client
        return
    logging.getLogger("distributed").setLevel(logging.ERROR)
    # Workers log at ERROR only (a task cancelled by Ctrl-C is no warning to the user), and
    # ignore SIGINT, which a terminal sends the whole process group: this process handles
    # Ctrl-C, cancels the tasks and closes the cluster in order.
    with _sigint_ignored_by_children():
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
    with cluster, Client(cluster) as client:
        yield client


@contextmanager
def _sigint_ignored_by_children() -> Iterator[None]:
    """Within the block, SIGINT is ignored, so processes started here inherit that (an
    ignored signal stays ignored across fork and exec); restored on exit."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def run_on_cluster(
    tasks: list[Task],
    client,
    progress: Callable[[float], None] | None = None,
    checkpoint_every: float = CHECKPOINT_EVERY,
) -> list[str]:
    """Run ``tasks`` on a dask.distributed ``client``, one task per realization; each writes
    its own file atomically. ``progress`` is called with a task's simulated seconds when it
    ends. The longest tasks start first. The first failure cancels what has not started and
    is raised (finished files stay).
    """
    from distributed import as_completed

    # Longest first (priority = simulated seconds): a long realization submitted last would
    # run alone on one worker at the end while the others idle.
    futures = {
        client.submit(
            run_task,
            task,
            None,
            checkpoint_every,
            True,
            pure=False,
            priority=int(math.ceil(_duration(task))),
        ): task
        for task in tasks
    }
    paths = []
    try:
        for future in as_completed(futures):
            paths.append(future.result())
            if progress:
                progress(_duration(futures[future]))
    except KeyboardInterrupt:
        raise Interrupted(_stop(client, futures)) from None
    except BaseException:
        client.cancel(list(futures))
        raise
    return paths


def _stop(client, futures: dict[Any, Task]) -> str:
    """After Ctrl-C: ask the running realizations to checkpoint and stop (through
    :data:`STOP_FILE`), wait for them (:data:`STOP_GRACE`, or a second Ctrl-C), cancel the rest,
    and say where the run stood."""
    from distributed import wait

    stop_files = {Path(t.path).parent / STOP_FILE for t in futures.values()}
    try:
        for stop_file in stop_files:
            stop_file.touch()
        wait(list(futures), timeout=STOP_GRACE)
    except (KeyboardInterrupt, TimeoutError, OSError):
        pass
    finally:
        client.cancel(list(futures))
        for stop_file in stop_files:
            stop_file.unlink(missing_ok=True)
    done = [t for f, t in futures.items() if f.status == "finished" and f.result() is not None]
    unfinished = [t for t in futures.values() if t not in done]
    return _where(unfinished, len(done), len(futures))


def _where(unfinished: list[Task], finished: int, total: int) -> str:
    """Where an interrupted cluster run stood, from the checkpoints of its unfinished tasks."""
    saved = []
    for task in unfinished:
        checkpoint = checkpoint_path(Path(task.path))
        try:
            data = read_checkpoint(checkpoint) if checkpoint.exists() else None
        except SoftcellError:
            data = None
        if data is not None:
            last = int(data["next_sample"]) - 1
            saved.append(
                f"t = {float(sample_times(Parameters(task.values, _specs()))[last]):.2f}"
                f" s of {task.name}"
            )
    where = ", ".join(saved) if saved else "t = 0 s of every unfinished realization"
    return (
        f"interrupted at {where} ({finished} of {total} realizations finished); rerun the "
        "same command to resume"
    )


def _specs() -> list[ParameterSpec]:
    from softcell.core.plugin.registry import get_registry

    return list(get_registry().parameter_specs().values())


#: Address schemes of dask.distributed's communication back ends.
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "inproc", "ucx")


def check_scheduler(address: str) -> None:
    """Raise a one-line :class:`SoftcellError` unless ``address`` names a scheduler that
    accepts a connection, at once (dask itself waits 30 s before it gives up)."""
    import socket
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
        parts = None
    if (
        parts is None
        or parts.scheme not in SCHEDULER_SCHEMES
        or (parts.scheme != "inproc" and (not host or port is None))
    ):
        raise SoftcellError(
            f"scheduler address {address!r} is not allowed: must be "
            "SCHEME://HOST:PORT with SCHEME one of "
            f"{', '.join(SCHEDULER_SCHEMES)} (e.g. tcp://10.0.0.5:8786)"
        )
    if parts.scheme == "inproc":
        return
    try:
        socket.create_connection((host, port), timeout=5).close()
    except OSError as exc:
        raise SoftcellError(
            f"cannot reach the dask scheduler at {address!r}: {exc.strerror or exc}"
        ) from None
