"""Many parameter points, each a run of its own folder, from one root seed on one cluster.

A study's grid and a fit's design are sets of points that a sweep cannot express (not a
product of lists): each point is a :class:`~softcell.model.configuration.RunConfig` and a
folder. :func:`run_points` plans every point before any runs (a bad value stops all of them
at once), then simulates them one after another on one local cluster or scheduler, each
resumable as ``softcell simulate``'s runs are.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from contextlib import nullcontext
from pathlib import Path
from typing import Any

from softcell.errors import SoftcellError
from softcell.model.limits import check_worker_count, cores


def worker_count(workers: int | None, scheduler: str | None) -> int | None:
    """The local worker processes: as given (checked by :func:`check_worker_count`), or every
    core when neither they nor a scheduler are given.

    Raises
    ------
    SoftcellError
        For fewer than one worker, or more than the machine can run.
    """
    if workers is not None:
        return check_worker_count(workers)
    return cores() if scheduler is None else None


def run_points(
    points: dict[Path, tuple[str, Any]],
    *,
    realizations: int,
    seed: int | Sequence[int],
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = None,
    planned: Callable[[], None] | None = None,
) -> None:
    """Simulate each point: its folder gets its RunConfig with ``realizations`` from root
    ``seed`` (every point draws the same streams: common random numbers).

    Parameters
    ----------
    points : dict
        Folder -> (a label for the log, the RunConfig it runs).
    realizations : int
        Realizations per point.
    seed : int or sequence of int
        The root seed of every point, or one per point (in order).
    workers : int, optional
        Local worker processes (default: every core, unless ``scheduler`` is given).
    scheduler : str, optional
        Address of a dask.distributed scheduler to run on instead.
    overwrite : bool
        Recompute what a folder holds from another seed, version or request.
    progress : bool
        A progress bar per point, in simulated seconds.
    log : callable, optional
        Receives a line per point and what ``softcell simulate`` reports.
    planned : callable, optional
        Called once every point is planned and before any runs (a study marks its folder).

    Raises
    ------
    SoftcellError
        For a point that cannot run (named by its folder's checks), before any runs.
    """
    from softcell.components.registry import default_registry
    from softcell.runner.cluster import cluster_client
    from softcell.runner.ensemble import plan, simulate

    registry = default_registry()
    seeds = [seed] * len(points) if isinstance(seed, int) else list(seed)
    if len(seeds) != len(points):
        raise SoftcellError(f"{len(seeds)} seeds for {len(points)} points: one each")
    for (folder, (_, config)), root in zip(points.items(), seeds, strict=True):
        plan(config, folder, realizations=realizations, seed=root, registry=registry)
    if planned is not None:
        planned()
    say = log or (lambda _: None)
    workers = worker_count(workers, scheduler)
    many = scheduler is not None or (workers or 1) > 1
    with cluster_client(workers or 1, scheduler) if many else nullcontext() as client:
        for i, (folder, (label, config)) in enumerate(points.items()):
            say(f"point {i + 1}/{len(points)}: {label}")
            simulate(
                config,
                folder,
                realizations=realizations,
                seed=seeds[i],
                client=client,
                progress=progress,
                overwrite=overwrite,
                log=log,
            )
