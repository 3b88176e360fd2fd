"""What an output folder already holds for a request: files to reuse, to recompute, to remove.

A finished file is reused only when it is complete and was made with exactly the request's
settings (every parameter of the components in use, the components, seed, spawn key, package
version); a checkpoint
only when it was made for the same request. Anything else stops the run with one line naming
the first setting that differs and both values, unless the user asks to overwrite.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from softcell.engine import fine_times, sample_times
from softcell.errors import SoftcellError
from softcell.model.limits import file_bytes
from softcell.model.parameters import Parameters
from softcell.runner.tasks import (
    CODE_ATTR,
    CODE_KEY,
    Task,
    checkpoint_path,
    read_checkpoint,
    request_of,
)


def _shown(value: Any) -> str:
    return value if isinstance(value, str) else json.dumps(value, sort_keys=True)


def first_mismatch(made: dict[str, Any], wanted: dict[str, Any]) -> str | None:
    """``"radius = 4.0 there, 8.0 in this request"`` for the first setting (in the order of
    ``wanted``) whose value differs, or None when every setting is equal.

    A parameter stored in ``made`` that ``wanted`` lacks is no difference: the request holds
    every parameter of the components it uses, and softcell 0.2.0 also stored those of every
    installed component (used or not), which must not make its files unusable. Nor does the
    components' code (``"code of KIND NAME"``) in a file made before it was recorded.
    """
    if not any(k.startswith(CODE_KEY) for k in made):
        wanted = {k: v for k, v in wanted.items() if not k.startswith(CODE_KEY)}
    extra = (k for k in made if k not in wanted and not k.startswith("parameter "))
    for key in [*wanted, *extra]:
        there, here = made.get(key, "(none)"), wanted.get(key, "(none)")
        if json.dumps(there, sort_keys=True) != json.dumps(here, sort_keys=True):
            return f"{key} = {_shown(there)} there, {_shown(here)} in this request"
    return None


def stored_request(path: Path) -> tuple[dict[str, Any], np.ndarray, np.ndarray | None]:
    """The settings a simulation file was made with, in the form of :meth:`Task.request`,
    its sample times (s) and the times of its bodies' fine record (s; None without one).

    Raises
    ------
    SoftcellError
        If the file does not open or does not follow the schema.
    """
    from softcell.io.netcdf import open_dataset
    from softcell.schema import problems

    try:
        ds = open_dataset(path, verify=False)  # lazily; _damage verifies the checksum
    except SoftcellError:
        raise SoftcellError("it is not a readable NetCDF file (truncated or corrupt)") from None
    with ds:
        found = problems(ds)
        if found:
            raise SoftcellError(f"it does not follow the simulation schema ({found[0]})")
        a = ds.attrs
        return (
            request_of(
                json.loads(a["softcell_parameters"]),
                json.loads(a["softcell_components"]),
                int(a["softcell_seed"]),
                str(a.get("softcell_spawn_key")),
                a.get("softcell_version"),
                json.loads(a.get(CODE_ATTR, "{}")),
            ),
            np.asarray(ds["time"].values),
            (np.asarray(ds["fine_time"].values) if "fine_time" in ds.coords else None),
        )


def _reuse_problem(path: Path, wanted: dict[str, Any], params: Parameters) -> str | None:
    """Why the finished file ``path`` cannot stand for the request ``wanted`` (whose
    parameters are ``params``), or None."""
    try:
        made, stored, fine = stored_request(path)
    except SoftcellError as exc:
        return f"cannot be reused: {exc}"
    why = first_mismatch(made, wanted)
    if why:
        return f"was made with {why}"
    times = sample_times(params)
    if not np.array_equal(stored, times):
        return f"is incomplete ({stored.size} samples, {times.size} expected)"
    if fine is None:
        return "was made by a softcell that did not record the bodies' fine record"
    if not np.array_equal(fine, fine_times(params)):
        return f"is incomplete ({fine.size} fine samples, {fine_times(params).size} expected)"
    return None


def _damage(path: Path) -> str | None:
    """Why a file made for this very request cannot be trusted (see
    :func:`softcell.io.netcdf.data_problem`), or None."""
    from softcell.io.netcdf import data_problem

    return data_problem(path)


def _checkpoint_problem(checkpoint: Path, wanted: dict[str, Any]) -> str | None:
    """Why the checkpoint cannot resume the request ``wanted``, or None."""
    try:
        data = read_checkpoint(checkpoint)
        made = json.loads(data["request"] or "{}")
        why = first_mismatch(made, wanted)
        if not why and "center_record" not in data:
            return "was made by a softcell that did not record the bodies' fine record"
        return why and f"was made with {why}"
    except (SoftcellError, ValueError):
        return "cannot be reused: it is truncated or corrupt"


@dataclass
class Resume:
    """What an existing output directory holds for a request.

    Attributes
    ----------
    todo : list
        The tasks (``softcell.runner.tasks.Task``) still to run.
    remove : list of Path
        Files to remove first (``overwrite``).
    reused : int
        Finished files reused as they are.
    damaged : list of (Path, str)
        Files made for this request but damaged on disk, with why (removed and recomputed,
        overwrite or not).
    """

    todo: list[Task]
    remove: list[Path]
    reused: int
    damaged: list[tuple[Path, str]] = field(default_factory=list)


def _overwrite_hint(path: Path, why: str) -> SoftcellError:
    return SoftcellError(
        f"{path} {why}; rerun with --overwrite to recompute it (and every "
        "other file that does not match), or write to another directory"
    )


def _stray_files(tasks: list[Task], out: Path) -> list[Path]:
    """Simulation files in ``out`` that are no part of the request ``tasks``."""
    from softcell.io.files import kind_of

    planned = {Path(t.path).name for t in tasks}
    return sorted(
        p
        for p in out.glob("*.nc")
        if p.name not in planned and not p.name.startswith(".") and kind_of(p) == "simulation"
    )


def resume_plan(tasks: list[Task], out: Path, *, overwrite: bool = False) -> Resume:
    """Compare what ``out`` holds with the request ``tasks``, before anything runs.

    Parameters
    ----------
    tasks : list of Task
        The request, from ``softcell.runner.ensemble.plan``.
    out : Path
        The output folder.
    overwrite : bool
        Remove and recompute what does not match instead of stopping.

    Returns
    -------
    Resume
        The tasks still to run, the files to remove first, the number of files reused. A
        file made for this very request whose contents fail their checksum is never reused:
        it is listed in ``damaged`` and recomputed.

    Raises
    ------
    SoftcellError
        Without ``overwrite``: for a file or checkpoint made with other settings, and for
        simulation files in ``out`` that are no part of the request (they would be read as
        part of the sweep), naming the first.
    """
    if not out.exists():
        return Resume(list(tasks), [], 0)
    resume = Resume([], [], 0)
    for task in tasks:
        path, checkpoint = Path(task.path), checkpoint_path(Path(task.path))
        wanted = task.request()
        if path.exists():
            why = _reuse_problem(path, wanted, task.params)
            # A file of this request whose samples look wrong may be damaged: say which.
            damage = _damage(path) if why is None or why.startswith("is incomplete") else None
            if why is None and damage is None:
                resume.reused += 1
                continue
            if damage is not None:  # softcell made it for this request: redo it, say so
                resume.damaged.append((path, damage))
            elif not overwrite:
                raise _overwrite_hint(path, why)
            resume.remove.append(path)
        if checkpoint.exists():
            why = _checkpoint_problem(checkpoint, wanted)
            if why is not None:
                if not overwrite:
                    raise _overwrite_hint(checkpoint, why)
                resume.remove.append(checkpoint)
        resume.todo.append(task)
    stray = _stray_files(tasks, out)
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
    return sum(file_bytes(t.params) * (t.assembly["cells"] if t.assembly else 1) for t in tasks)
