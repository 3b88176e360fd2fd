"""One realization of an ensemble as a task: what it asks for, its checkpoint, and running it.

A :class:`Task` is one (parameter point, realization) with its validated parameters, its
components and its file. Realization r of point p draws from
``SeedSequence(seed, spawn_key=(p, r))``, so a task's file does not depend on where or when it
runs. A long realization checkpoints its state beside its file (``.<name>.ckpt.npz``), valid
only for the request it was made for, so that a killed run resumes to the same bytes.
"""

from __future__ import annotations

import json
import warnings
import zipfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from softcell._version import __version__
from softcell.components.registry import Registry, default_registry
from softcell.engine import Model, Stepper, build_integrator, build_model
from softcell.engine.cell import Saved, realization_rng, record_dataset, run_realization
from softcell.engine.groups import cell_rngs
from softcell.engine.interrupt import deferred
from softcell.errors import Interrupted, PluginWarning, SoftcellError
from softcell.io.files import atomic_write
from softcell.model.parameters import Parameters
from softcell.settings import CHECKPOINT_EVERY

#: The attribute of a simulation file holding :attr:`Task.code` (JSON).
CODE_ATTR = "softcell_component_code"

#: How a request names each component's code: ``"code of KIND NAME"``.
CODE_KEY = "code of "

#: A file in the output directory asking the realizations running on a cluster to save a
#: checkpoint and stop (what Ctrl-C does to this process; see
#: :func:`softcell.runner.cluster.run_on_cluster`).
STOP_FILE = ".softcell-stop"


@dataclass(frozen=True)
class Task:
    """One (parameter point, realization) of an ensemble.

    Attributes
    ----------
    point, realization : int
        The indices of its parameter point and realization (its random stream's spawn key).
    params : Parameters
        The point's validated parameters (units of ``softcell params``).
    components : dict
        The component names by kind, as requested.
    stored_components : dict
        The component names as its file stores them: with ``membrane``, and for a free bot
        only the energy terms that act on the bot alone (such as the arena).
    seed : int
        The root seed.
    membrane : bool
        False for a free bot.
    path : str
        Its file.
    swept : tuple of str
        Parameters stored as scalar coordinates too.
    code : dict
        Each component in use (``"code of KIND NAME"``): where it came from (its
        distribution and version) and a digest of its package's code
        (``component_code`` in this module). A file made with other code is
        another request.
    assembly : dict, optional
        Many cells (:meth:`softcell.model.assembly.Assembly.as_dict`); None for one cell.
    bots : dict, optional
        Several bots in one ring (:meth:`softcell.model.bots.Bots.as_dict`); None for one.
    """

    point: int
    realization: int
    params: Parameters
    components: dict[str, Any]
    stored_components: dict[str, Any]
    seed: int
    membrane: bool
    path: str
    swept: tuple[str, ...] = field(default=("radius",))
    assembly: dict[str, Any] | None = None
    code: dict[str, str] = field(default_factory=dict)
    bots: dict[str, Any] | None = None

    @property
    def name(self) -> str:
        return f"point {self.point} realization {self.realization}"

    @property
    def duration(self) -> float:
        """Its simulated duration (s); for an assembly, summed over its cells."""
        return float(self.params.duration) * (self.assembly["cells"] if self.assembly else 1)

    def request(self) -> dict[str, Any]:
        """Every setting a file or checkpoint of this task must have been made with, in the
        order they are compared: each parameter, the components, seed, spawn key, version."""
        params = json.loads(self.params.to_attrs()["softcell_parameters"])
        return request_of(
            params,
            self.stored_components,
            self.seed,
            f"{self.point},{self.realization}",
            __version__,
            self.code,
        )


def component_code(components: dict[str, Any], registry: Registry) -> dict[str, str]:
    """Each component ``components`` names, as ``{"code of KIND NAME": "ORIGIN, code
    DIGEST"}``: its origin (a distribution and its version, or softcell's built-in
    module) and :func:`softcell.engine.compiled.code_digest` of its package, so that a
    plugin whose code changed (even under the same version) makes another request."""
    from softcell.engine.compiled import code_digest

    return {
        f"{CODE_KEY}{r.component.kind} {r.component.name}": (
            f"{r.origin}, code {code_digest(r.component)}"
        )
        for r in registry.in_use(components)
    }


def stored_components(
    components: dict[str, Any],
    membrane: bool,
    registry: Registry,
    assembly: dict[str, Any] | None = None,
    bots: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The component names as a file stores them (see :attr:`Task.stored_components`), with
    an assembly's settings under ``assembly`` (none for one cell) and those of several bots
    under ``bots`` (none for one bot)."""
    stored = {**components, "membrane": membrane}
    if assembly is not None:
        stored["assembly"] = dict(assembly)
    if bots is not None:
        stored["bots"] = dict(bots)
    if not membrane:
        names: Iterable[str] = components.get("energy_terms", [])
        stored["energy_terms"] = [n for n in names if registry.get("energy_term", n).has_bot_energy]
    return stored


def request_of(
    parameters: dict[str, Any],
    components: dict[str, Any],
    seed: Any,
    spawn_key: Any,
    version: Any,
    code: dict[str, str] | None = None,
) -> dict[str, Any]:
    """A request as compared between runs: ``"parameter NAME"`` for each parameter, then
    ``"component KIND"``, ``"code of KIND NAME"`` (see :func:`component_code`; a file made
    before softcell recorded it has none), ``"seed"``, ``"spawn key"``, ``"softcell
    version"``."""
    return {
        **{f"parameter {k}": v for k, v in parameters.items()},
        **{f"component {k}": v for k, v in sorted(components.items())},
        **dict(sorted((code or {}).items())),
        "seed": seed,
        "spawn key": spawn_key,
        "softcell version": version,
    }


def canonical(request: dict[str, Any]) -> str:
    """A request as one JSON text (what a checkpoint stores)."""
    return json.dumps(request, sort_keys=True)


# -- checkpoints -----------------------------------------------------------------------------


def checkpoint_path(path: Path) -> Path:
    """The checkpoint of the realization whose file is ``path``."""
    return path.with_name(f".{path.stem}.ckpt.npz")


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
        if "center_record" not in data:
            raise SoftcellError(
                f"checkpoint {self.path} was made by a softcell without the bodies' fine "
                "record; remove it or rerun with --overwrite"
            )
        return Saved(
            int(data["next_sample"]),
            data["modes_record"],
            data["pose_record"],
            {k.removeprefix("state_"): v for k, v in data.items() if k.startswith("state_")},
            data["center_record"],
        )

    def save(self, saved: Saved) -> None:
        save_checkpoint(
            self.path,
            self.fingerprint,
            saved.next_sample,
            saved.modes_record,
            saved.pose_record,
            saved.state,
            saved.center_record,
        )


def save_checkpoint(
    path: Path,
    request: str,
    next_sample: int,
    rec_modes: np.ndarray,
    rec_pose: np.ndarray,
    state: dict[str, np.ndarray],
    rec_center: np.ndarray,
) -> None:
    """Write a checkpoint atomically: the request (JSON), the first grid sample still to
    compute, the samples so far (the membrane's modes in cm; the pose in cm and rad and the
    centre g_0 in cm at every grid sample) and the stepper's state arrays."""
    with atomic_write(path) as tmp, deferred():
        np.savez(
            tmp,
            request=np.array(request),
            next_sample=np.array(next_sample),
            modes_record=rec_modes,
            pose_record=rec_pose[:next_sample],
            center_record=rec_center[:next_sample],
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


# -- running ---------------------------------------------------------------------------------

_BUILT: dict[str, tuple[Model, Stepper]] = {}


def _model_and_stepper(task: Task, registry: Registry) -> tuple[Model, Stepper]:
    """The task's compiled model and stepper, built once per process and request."""
    key = json.dumps([task.params.given, task.components, task.membrane, task.bots], sort_keys=True)
    if key not in _BUILT:
        model = build_model(
            task.params,
            task.components["energy_terms"],
            task.components["driving_protocol"],
            membrane=task.membrane,
            friction_law=task.components.get("friction_law", "viscous"),
            registry=registry,
            pair_terms=task.components.get("pair_terms", ()),
            bot_interactions=task.components.get("bot_interactions", ()),
        )
        integrator = build_integrator(task.components["integrator"], task.params, registry)
        if task.bots is not None:
            stepper = integrator.build_bots(model, task.bots["count"])
        else:
            stepper = integrator.build(model)
        _BUILT[key] = (model, stepper)
    return _BUILT[key]


def compiles_on_first_call(task: Task, registry: Registry) -> bool:
    """Build ``task``'s model and stepper in this process (once per request, as
    :func:`run_task` would; an assembly's group loop too) and say whether their first call
    compiles them: True when their code is not in the compiled-model cache yet, which
    happens once per machine (see :func:`softcell.engine.compiled.first_call_compiles`)."""
    from softcell.engine.compiled import first_call_compiles, loaded_count

    mark = loaded_count()
    _, stepper = _model_and_stepper(task, registry)
    if task.assembly is not None and hasattr(stepper, "load_group_loop"):
        stepper.load_group_loop()
    return first_call_compiles(mark)


def run_task(
    task: Task,
    progress: Callable[[float], None] | None = None,
    checkpoint_every: float = CHECKPOINT_EVERY,
    stoppable: bool = False,
    registry: Registry | None = None,
    threads: int = 1,
) -> str | None:
    """Run one (point, realization) and write its file atomically; returns the path.

    Parameters
    ----------
    task : Task
        What to run.
    progress : callable, optional
        Called with the simulated seconds (s) advanced since its last call.
    checkpoint_every : float
        Wall seconds (s) between checkpoints.
    stoppable : bool
        On a cluster: :data:`STOP_FILE` appearing beside the file makes the realization save
        its checkpoint and return None.
    registry : Registry, optional
        Where the components are looked up; on a cluster's worker, the built-ins and the
        installed plugins of that worker.
    threads : int
        Threads an assembly of cells steps its independent groups on (the file is the same
        whatever their number); one cell or one ring uses one.
    """

    if registry is None:
        with warnings.catch_warnings():  # the command that planned the run has warned already
            warnings.simplefilter("ignore", PluginWarning)
            registry = default_registry()
    model, stepper = _model_and_stepper(task, registry)
    if task.assembly is not None:
        return _run_assembly(task, model, stepper, progress, checkpoint_every, stoppable, threads)
    if task.bots is not None:
        return _run_bots(task, model, stepper, progress, checkpoint_every, stoppable)
    return _run_and_write(
        task,
        stoppable,
        lambda checkpoint, stop: run_realization(
            model,
            stepper,
            realization_rng(task.seed, task.point, task.realization),
            label=task.name,
            checkpoint=checkpoint,
            checkpoint_every=checkpoint_every,
            progress=progress,
            stop=stop,
        ),
        lambda record, stored: record_dataset(record, model, **stored),
    )


def _run_and_write(
    task: Task,
    stoppable: bool,
    run: Callable[[FileCheckpoint, Callable[[], bool] | None], Any],
    dataset: Callable[[Any, dict[str, Any]], Any],
) -> str | None:
    """``run(checkpoint, stop)``'s record, made a Dataset by ``dataset(record, stored)``
    (``stored``: the realization, seed, components, attributes and scalar coordinates every
    file carries), written atomically to the task's path; its checkpoint is then removed.
    Returns the path, or None when asked to stop (the checkpoint is saved)."""
    from softcell.io.netcdf import write_dataset

    path = Path(task.path)
    checkpoint = checkpoint_path(path)
    stop_file = path.parent / STOP_FILE
    try:
        record = run(
            FileCheckpoint(checkpoint, canonical(task.request())),
            stop_file.exists if stoppable else None,
        )
    except Interrupted:
        if not stoppable:
            raise
        return None
    stored = {
        "realization": task.realization,
        "seed": task.seed,
        "components": task.stored_components,
        "extra_attrs": {
            "softcell_point": task.point,
            "softcell_spawn_key": f"{task.point},{task.realization}",
            CODE_ATTR: json.dumps(task.code, sort_keys=True),
        },
        "scalar_coords": task.swept,
    }
    ds = dataset(record, stored)
    with deferred():  # the file and no checkpoint, or the checkpoint and no file
        write_dataset(ds, path)
        checkpoint.unlink(missing_ok=True)
    return str(path)


def _run_assembly(
    task: Task,
    model: Model,
    stepper: Stepper,
    progress: Callable[[float], None] | None,
    checkpoint_every: float,
    stoppable: bool,
    threads: int = 1,
) -> str | None:
    """Run one realization of an assembly of cells and write its file, checkpointing as a
    single cell's realization does; ``threads`` step its independent groups."""
    from softcell.engine.groups import crowd_dataset, run_assembly, starting_centres
    from softcell.model.assembly import Assembly

    assembly = Assembly(**task.assembly)
    centres = starting_centres(
        model.params, assembly, task.seed, task.point, task.realization, model.pair_reach
    )
    return _run_and_write(
        task,
        stoppable,
        lambda checkpoint, stop: run_assembly(
            model,
            stepper,
            assembly.domain,
            centres,
            cell_rngs(task.seed, task.point, task.realization, assembly.cells),
            label=task.name,
            checkpoint=checkpoint,
            checkpoint_every=checkpoint_every,
            progress=(lambda dt: progress(dt * assembly.cells)) if progress else None,
            stop=stop,
            threads=threads,
        ),
        lambda record, stored: crowd_dataset(record, model, assembly, centres, **stored),
    )


def _run_bots(
    task: Task,
    model: Model,
    stepper: Stepper,
    progress: Callable[[float], None] | None,
    checkpoint_every: float,
    stoppable: bool,
) -> str | None:
    """Run one realization of several bots in one ring and write its file, checkpointing as
    a single bot's realization does."""
    from softcell.engine.bots import bot_rngs, bots_dataset, placement_rng, start_bots
    from softcell.model.bots import Bots

    bots = Bots.from_mapping(task.bots)
    modes, poses, schedules = start_bots(
        model,
        bots,
        bot_rngs(task.seed, task.point, task.realization, bots.count),
        placement_rng(task.seed, task.point, task.realization),
    )
    return _run_and_write(
        task,
        stoppable,
        lambda checkpoint, stop: run_realization(
            model,
            stepper,
            None,
            label=task.name,
            checkpoint=checkpoint,
            checkpoint_every=checkpoint_every,
            progress=progress,
            stop=stop,
            start=(stepper.start(modes, poses, schedules), schedules),
        ),
        lambda record, stored: bots_dataset(record, model, bots, poses, **stored),
    )
