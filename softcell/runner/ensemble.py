"""Ensembles: parameter points x realizations, one file each, reproducible and resumable.

Every random stream comes from one root seed: realization r of parameter point p draws from
``SeedSequence(seed, spawn_key=(p, r))``, so results do not depend on the number of workers or
their order. :func:`plan` checks a request and turns it into tasks
(:mod:`softcell.runner.tasks`); :func:`simulate` compares them with what the output folder
holds (:mod:`softcell.runner.resume`) and runs the rest, here or on a dask.distributed
cluster (:mod:`softcell.runner.cluster`).
"""

from __future__ import annotations

import math
import os
import sys
import warnings
from collections.abc import Callable
from contextlib import suppress
from pathlib import Path
from typing import Any

from softcell.components.registry import (
    Registry,
    check_in_use,
    check_point,
    default_registry,
)
from softcell.errors import ConfigError, SoftcellError
from softcell.model.configuration import RunConfig, assembly_of, bots_of, with_assembly_defaults
from softcell.model.limits import (
    check_realizations,
    check_run,
    check_seed,
    check_worker_count,
    cores,
    human_bytes,
)
from softcell.model.obstacle_layout import check_clear_of_start
from softcell.model.parameters import expand_sweep
from softcell.runner.cluster import check_scheduler, cluster_client, run_on_cluster
from softcell.runner.resume import expected_bytes, resume_plan
from softcell.runner.tasks import (
    STOP_FILE,
    Task,
    compiles_on_first_call,
    component_code,
    run_task,
    stored_components,
)
from softcell.settings import CHECKPOINT_EVERY


def plan(
    config: RunConfig,
    out: Path,
    *,
    realizations: int,
    seed: int,
    membrane: bool = True,
    registry: Registry,
) -> list[Task]:
    """The tasks of an ensemble, one per (parameter point, realization), in order.

    Everything is checked here, before anything is computed: the component names, every
    parameter point (including what fits in memory, :func:`softcell.model.limits.check_run`),
    the integrator's own conditions, the seed and the number of realizations.

    Parameters
    ----------
    config : RunConfig
        Parameter values (units of ``softcell params``; a list sweeps) and component names.
    out : Path
        The output folder; task ``(p, r)`` writes ``pointPPP_realizationRRRR.nc`` there.
    realizations : int
        Realizations per parameter point.
    seed : int
        The root seed.
    membrane : bool
        False for a free bot.
    registry : Registry
        Where the components are looked up.

    Returns
    -------
    list of Task
        Point-major order.
    """
    check_realizations(realizations)
    check_seed(seed)
    config = with_assembly_defaults(config)
    assembly = assembly_of(config)
    config.check_components(registry)
    components = dict(config.components)
    if assembly is not None:
        components["pair_terms"] = list(assembly.pair_terms)
        for name in assembly.pair_terms:
            registry.get("pair_term", name)
    several = bots_of(config)
    if several is not None:
        components["bot_interactions"] = list(several.interactions)
        for name in several.interactions:
            registry.get("bot_interaction", name)
    check_in_use(config.parameters, registry, components)
    # Only the parameters of the components in use: installing a plugin changes no request.
    points = expand_sweep(config.parameters, list(registry.parameter_specs(components).values()))
    for _, params in points:
        check_run(params)
        check_point(params, registry, components)
    if several is not None:
        _check_bots(several, assembly, components, points, realizations, seed, membrane, registry)
    if assembly is not None:
        _check_assembly(assembly, config, points, realizations, seed, membrane, registry)
    else:
        for _, params in points:
            check_clear_of_start(params)
    _check_total(points, realizations, out)
    swept = tuple(
        dict.fromkeys(
            ["radius", *(k for k, v in config.parameters.items() if isinstance(v, list | tuple))]
        )
    )
    settings = assembly.as_dict() if assembly is not None else None
    bots = several.as_dict() if several is not None else None
    stored = stored_components(dict(config.components), membrane, registry, settings, bots)
    code = component_code(stored, registry)
    return [
        Task(
            point=p,
            realization=r,
            params=params,
            components=components,
            stored_components=stored,
            seed=seed,
            membrane=membrane,
            path=str(out / f"point{p:03d}_realization{r:04d}.nc"),
            swept=swept,
            assembly=settings,
            code=code,
            bots=bots,
        )
        for p, (_, params) in enumerate(points)
        for r in range(realizations)
    ]


def _check_bots(bots, assembly, components, points, realizations, seed, membrane, registry):
    """Refuse several bots in one ring that cannot run, in one line, before anything is
    computed: with an assembly or a free bot, an integrator that does not step them, a
    nonlinear friction law, a protocol with state events, or bots that do not fit."""
    import numpy as np

    from softcell.engine.bots import bot_rngs, placement_rng
    from softcell.engine.state import equilibrium_radius
    from softcell.model.bots import place_bots

    if assembly is not None:
        raise SoftcellError(
            "several bots per cell in an assembly of cells are not built yet: drop --bots or "
            "[assembly]"
        )
    if not membrane:
        raise SoftcellError("several bots need a ring: drop --free-bot or --bots")
    integrator = components["integrator"]
    if not getattr(registry.get("integrator", integrator), "steps_bots", False):
        raise SoftcellError(
            f"integrator {integrator!r} does not step several bots in one ring: use rodas4"
        )
    law = registry.get("friction_law", components.get("friction_law", "viscous"))
    if not law.linear:
        raise SoftcellError(
            f"friction law {law.name!r} is not linear: several bots in one ring need the "
            "viscous law (the parts' membrane velocities are summed)"
        )
    protocol = registry.get("driving_protocol", components["driving_protocol"])
    for p, (_, params) in enumerate(points):
        drive = protocol(params)
        if drive.event_kernel() is not None:
            raise SoftcellError(
                f"driving protocol {protocol.name!r} ends phases on state events, which the "
                "loop of several bots does not locate yet: choose another protocol"
            )
        a, b = float(params.bot_semi_major), float(params.bot_semi_minor)
        radius = equilibrium_radius(params)
        for r in range(realizations if bots.placement == "random" else 1):
            rngs = bot_rngs(seed, p, r, bots.count)
            headings = np.array([drive.initial_heading(g) for g in rngs])
            place_bots(bots, radius, a, b, headings, placement_rng(seed, p, r))


def _check_assembly(assembly, config, points, realizations, seed, membrane, registry) -> None:
    """Refuse an assembly that cannot run, before anything is computed: a free bot, an
    integrator that does not step groups of cells, a nonlinear friction law, obstacles in a
    periodic box, cells that do not fit in memory, and cells that cannot be placed (every
    realization's placement is drawn here)."""
    from softcell.engine.groups import starting_centres
    from softcell.model.limits import check_assembly_memory

    if not membrane:
        raise SoftcellError("an assembly of cells needs membranes: drop --free-bot or [assembly]")
    integrator = config.components["integrator"]
    if assembly.cells > 1 and not getattr(
        registry.get("integrator", integrator), "steps_groups", False
    ):
        raise SoftcellError(
            f"integrator {integrator!r} does not step groups of cells in contact: an assembly "
            "of more than one cell needs rodas4"
        )
    _check_no_events(config, points, registry)
    for _, params in points:
        law = registry.get("friction_law", config.components["friction_law"])(params)
        if not law.linear:
            raise SoftcellError(
                f"friction law {law.name!r} is not linear: an assembly of cells needs the "
                "viscous law (the pair forces move the membranes by their mobility)"
            )
        if assembly.boundary == "periodic" and str(params.get("obstacles", "") or ""):
            raise SoftcellError(
                "obstacles in a periodic box are not supported: use boundary walls or the "
                "open plane"
            )
        check_assembly_memory(params, assembly.cells)
    for p, (_, params) in enumerate(points):
        reach = max(registry.get("pair_term", n)(params).reach() for n in assembly.pair_terms)
        for r in range(realizations if assembly.placement == "random" else 1):
            starting_centres(params, assembly, seed, p, r, reach)


def _check_no_events(config, points, registry) -> None:
    """Refuse an assembly whose driving protocol has state events (the group loop does not
    locate them)."""
    name = config.components["driving_protocol"]
    for _, params in points[:1]:
        if registry.get("driving_protocol", name)(params).event_kernel() is not None:
            raise SoftcellError(
                f"driving protocol {name!r} ends phases on state events, which an assembly "
                "of cells does not support yet: run it one cell at a time"
            )


def _check_total(points: list, realizations: int, out: Path) -> None:
    """Refuse, before a task is made, an ensemble whose files cannot fit on the disk of
    ``out`` (the simulation files already there, which a rerun reuses, count as room)."""
    from softcell.io.files import check_writable
    from softcell.model.limits import file_bytes

    need = realizations * sum(file_bytes(params) for _, params in points)
    have = sum(p.stat().st_size for p in Path(out).glob("*.nc")) if Path(out).is_dir() else 0
    check_writable(out, max(need - have, 0))


def _check_execution(
    workers: int, scheduler: str | None, client: Any, checkpoint_every: float
) -> None:
    """Raise a one-line :class:`SoftcellError` for a bad choice of where and how to run."""
    check_worker_count(workers)
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


def _to_stderr(line: str) -> None:
    """Print ``line`` where the progress bar is drawn (for callers that gave no ``log``)."""
    from softcell.settings import progress_bar_class

    progress_bar_class().write(line, file=sys.stderr)


def _warn(message: str) -> None:
    warnings.warn(message, stacklevel=3)


def _progress_bar(todo: list[Task], progress: bool):
    from softcell.settings import progress_bar_class

    tqdm = progress_bar_class()
    # smoothing=0: the ETA from the average rate since the start, not the last few updates
    return tqdm(
        total=sum(t.duration for t in todo),
        unit="sim s",
        disable=not progress or not todo,
        unit_scale=False,
        smoothing=0,
        bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.2f}/{total:.2f} sim s "
        "[{elapsed}<{remaining}]",
        desc=f"{len(todo)} realizations",
    )


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
    registry: Registry | None = None,
) -> list[Path]:
    """Run an ensemble: every parameter point of ``config`` x ``realizations``.

    Parameters take the units of ``softcell params`` (cm, s, rad, N); each file stores
    positions in cm, angles in rad and times in s, with CF ``units`` attributes.

    Finished files already in ``out`` are kept when they match the request exactly (see
    ``resume_plan``); a mismatch stops the run before anything is computed.

    Parameters
    ----------
    config : RunConfig
        The request: parameters (a list of values sweeps that parameter; every combination
        is one parameter point), components and run settings.
    out : path-like
        Output folder, one NetCDF file per (point, realization); created if missing.
    realizations : int
        Independent realizations per parameter point, each with its own random stream.
    seed : int
        Root seed, 0 to 2**64 - 1: realization r of point p draws from
        ``SeedSequence(seed, spawn_key=(p, r))``.
    workers : int
        1: run in this process; more: a local dask.distributed cluster of that many
        single-threaded worker processes.
    scheduler : str, optional
        Address of a running dask.distributed scheduler (``tcp://host:8786``): one task per
        realization on its workers, which must be able to write to ``out``. Excludes
        ``workers``.
    client : distributed.Client, optional
        A dask.distributed client to submit the tasks to (instead of ``workers`` or
        ``scheduler``).
    membrane : bool
        False simulates the free bot: no membrane, no contact (the cell's variables are NaN).
    progress : bool
        Show a progress bar in simulated seconds (s).
    checkpoint_every : float
        Wall seconds (s) between the checkpoints of a running realization (default 60 s),
        from which an interrupted run resumes.
    overwrite : bool
        Recompute files and checkpoints in ``out`` that do not match the request, and remove
        simulation files that are no part of it (``log`` is told which).
    log : callable, optional
        Receives one line naming what ``overwrite`` removes, and one per file made for this
        request but damaged on disk (its checksum fails), which is recomputed.
    registry : Registry, optional
        Where the components are looked up; by default the built-ins and the installed
        plugins. Workers of a cluster always use their own installed plugins.

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
    from softcell.io.files import check_output, folder_lock

    registry = registry if registry is not None else default_registry()
    if not isinstance(config, RunConfig):
        raise ConfigError(
            f"simulate: config is a {type(config).__name__}, not a RunConfig; write "
            "softcell.RunConfig(parameters={...}, components={...})"
        )
    _check_execution(workers, scheduler, client, checkpoint_every)
    out = check_output(out, "simulation", directory=True)  # absolute: cluster workers too
    tasks = plan(
        config, out, realizations=realizations, seed=seed, membrane=membrane, registry=registry
    )
    if scheduler is not None:
        check_scheduler(scheduler)
    made = [p for p in (out, *out.parents) if not p.exists()]  # removed again if refused
    out.mkdir(parents=True, exist_ok=True)
    try:
        with folder_lock(out, "softcell simulate"):  # one writer at a time
            _run(tasks, out, overwrite, log, workers, scheduler, client, progress,
                 checkpoint_every, registry)  # fmt: skip
    except BaseException:
        with suppress(OSError):  # only while empty: a run refused or failed at once leaves
            for folder in made:  # no folder behind, an interrupted one its checkpoints
                folder.rmdir()
        raise
    return [Path(t.path) for t in tasks]


def _say_removals(resume, out: Path, log: Callable[[str], None] | None) -> None:
    """Say which files a run removes: each damaged one (always, even without a log), and
    those --overwrite replaces."""
    for path, why in resume.damaged:
        (log or _warn)(f"{path} was made for this request but {why}: recomputing it")
    overwritten = [p for p in resume.remove if p not in {d for d, _ in resume.damaged}]
    if overwritten and log:
        names = [p.name for p in overwritten]
        log(
            f"--overwrite: removing {len(names)} file(s) of {out} that do not match this "
            f"request ({', '.join(names[:3])}{', ...' if len(names) > 3 else ''})"
        )


def _say_preparation(
    task: Task, registry: Registry, where: str, say: Callable[[str], None]
) -> None:
    """Say, before the progress bar moves, what the first realization waits for: the
    compilation of a model not yet cached on this machine (nothing when it is cached), or,
    for remote workers whose caches this process cannot see, that they load or compile it.
    ``where``: ``"process"`` (this one), ``"local"`` (a cluster on this machine) or
    ``"remote"`` (a scheduler's or client's workers, whose caches this process cannot see).
    """
    if where == "remote":
        say(
            "each worker loads the compiled model from its machine's cache before its first "
            f"realization, or compiles it the first time on a machine ({COMPILING})"
        )
        return
    who = "this process" if where == "process" else "each worker"
    if compiles_on_first_call(task, registry):  # loading a cached model takes a second
        say(
            f"compiling the model for these components in {who}, once per machine "
            f"({COMPILING}); the bar moves after it"
        )


def _where_workers(client: Any, scheduler: str | None) -> str:
    """``"local"`` for workers on this machine (``--workers N``, or a client of a
    ``LocalCluster``), ``"remote"`` otherwise."""
    if scheduler is not None:
        return "remote"
    if client is None:
        return "local"
    return (
        "local" if type(getattr(client, "cluster", None)).__name__ == "LocalCluster" else "remote"
    )


#: What compiling a model costs, as measured in docs/performance.md.
COMPILING = "about 1 min for the paper's model, 30 s more for many cells, 1.5 min for several bots"


#: From this many realizations, a run says what it is about to compute and store.
LARGE_RUN = 100


def _say_plan(
    todo: list[Task], total: int, reused: int, out: Path, log: Callable[[str], None] | None
) -> None:
    """Tell ``log`` what a large run is about to compute and store, and what it reuses."""
    if log and len(todo) >= LARGE_RUN:
        points = len({t.point for t in todo})
        log(
            f"{len(todo)} realizations to compute ({points} parameter points), about "
            f"{human_bytes(expected_bytes(todo))} of files in {out}; Ctrl-C stops, a rerun "
            "resumes"
        )
    if log and reused:
        log(
            f"{reused} of {total} file(s) in {out} already hold this request: "
            f"reused as they are; computing {len(todo)}"
        )


def _run(
    tasks: list[Task],
    out: Path,
    overwrite: bool,
    log: Callable[[str], None] | None,
    workers: int,
    scheduler: str | None,
    client: Any,
    progress: bool,
    checkpoint_every: float,
    registry: Registry,
) -> None:
    """Compare ``out`` with the request and run what is missing (``out`` is locked)."""
    from softcell.io.files import check_writable, remove

    resume = resume_plan(tasks, out, overwrite=overwrite)
    check_writable(out, expected_bytes(resume.todo))
    _say_removals(resume, out, log)
    remove([*resume.remove, out / STOP_FILE])  # a stop request left by a crash is stale
    todo = resume.todo
    _say_plan(todo, len(tasks), resume.reused, out, log)
    in_process = client is None and scheduler is None and workers == 1
    where = "process" if in_process else _where_workers(client, scheduler)
    if todo and (log or progress):
        _say_preparation(todo[0], registry, where, log or _to_stderr)
    with _progress_bar(todo, progress) as bar:
        if client is not None:
            run_on_cluster(todo, client, bar.update, checkpoint_every)
        elif in_process:
            # One process: an assembly's realization steps its groups on every core it may
            # use. A cluster's workers fill the cores already: one thread each there.
            for task in todo:
                run_task(task, bar.update, checkpoint_every, registry=registry, threads=cores())
        elif todo:
            with cluster_client(workers, scheduler) as own:
                run_on_cluster(todo, own, bar.update, checkpoint_every)
    return [Path(t.path) for t in tasks]
