"""A study: model variants of one design, run side by side from one root seed.

Each :class:`Variant` is the base design with some components and parameters changed; each
runs into its own folder by :func:`softcell.paper.reproduce.reproduce` (resumable, with
its own report), from the same root seed, so that the variants share their random numbers
and their differences are the model's, not noise. ``softcell study sensitivity`` and
``softcell study beyond`` are such studies (:class:`~softcell.studies.protocol.VariantStudy`);
this module holds what they share, and what they share with the grid studies.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from softcell.errors import SoftcellError
from softcell.model.configuration import DEFAULT_COMPONENTS
from softcell.paper.reproduce import QUICK, Design, reproduce


@dataclass(frozen=True)
class Variant:
    """One model variant of a study: components and parameters over the quick design's.

    ``name`` is its folder, ``label`` its legend; ``unknown`` names what it varies (the
    sensitivity study groups its variants by it; empty for the reference). Parameter values
    are in the units of ``softcell params``.
    """

    name: str
    label: str
    components: dict[str, Any] = field(default_factory=dict)
    parameters: dict[str, Any] = field(default_factory=dict)
    unknown: str = ""

    def design(self, base: Design = QUICK) -> Design:
        """``base`` with this variant's components (over the defaults) and parameters."""
        return replace(
            base,
            name=f"{base.name}-{self.name}",
            components={**DEFAULT_COMPONENTS, **self.components},
            parameters={**base.parameters, **self.parameters},
        )


@dataclass(frozen=True)
class VariantDesign:
    """What a variant study runs.

    Parameters
    ----------
    name : str
        What the design is called (its study's logs).
    variants : tuple of Variant
        The variants; the first is the reference the others are compared with.
    base : Design
        The paper's design every variant runs (radii, realizations, duration, ...).
    """

    name: str
    variants: tuple[Variant, ...]
    base: Design

    def check(self) -> None:
        """Refuse a design with nothing to compare with its reference, or a variant named
        twice."""
        names = [v.name for v in self.variants]
        if len(names) < 2:
            raise SoftcellError(
                f"variants {', '.join(names) or '(none)'}: a variant study compares at least "
                "one variant with its reference"
            )
        if len(set(names)) < len(names):
            raise SoftcellError(f"variants {', '.join(names)}: each variant runs once")


def variants_named(
    known: tuple[Variant, ...], names: Sequence[str], study: str
) -> tuple[Variant, ...]:
    """The variants of ``known`` called ``names``, after ``known``'s first (the reference,
    always run), for the study ``study`` (named in errors).

    Raises
    ------
    SoftcellError
        For an unknown name, or names that leave nothing to compare with the reference.
    """
    by_name = {v.name: v for v in known}
    reference = known[0].name
    if not [n for n in names if n != reference]:
        raise SoftcellError(
            f"--only {','.join(names)!r} names no variant to compare with the {reference}; the "
            f"{study} study's variants are {', '.join(n for n in by_name if n != reference)}"
        )
    bad = [n for n in names if n not in by_name]
    if bad:
        raise SoftcellError(
            f"unknown variant(s) {', '.join(bad)}; the {study} study's variants are "
            f"{', '.join(by_name)}"
        )
    return (known[0], *(by_name[n] for n in dict.fromkeys(names) if n != reference))


#: What a study's folder was made for: the study and its seed (checked on a rerun, as a
#: reproduction's ``reproduce.json`` is; each variant's folder has its own).
STUDY_MANIFEST = "study.json"


def check_study_directory(out: Path, command: str, seed: int, overwrite: bool) -> None:
    """Stop, in one line, unless ``out`` is new or empty, or holds the study ``command``
    (e.g. ``"beyond"``) made from ``seed``: a study writes only into folders it made
    (``overwrite`` lifts this, as it does for ``softcell reproduce``)."""
    if overwrite or not out.is_dir() or not any(out.iterdir()):
        return
    manifest = out / STUDY_MANIFEST
    if not manifest.is_file():
        raise SoftcellError(
            f"{out} is not empty and was not made by `softcell {command}` (no "
            f"{STUDY_MANIFEST}); choose a new directory, or pass --overwrite to write into it"
        )
    try:
        made = json.loads(manifest.read_text(encoding="utf-8"))
        made_by, made_seed = made["study"], made["seed"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise SoftcellError(
            f"{manifest} is unreadable ({exc}); pass --overwrite to write into {out}"
        ) from None
    if made_by != command:
        raise SoftcellError(
            f"{out} holds the study `softcell {made_by}`, not `softcell {command}`; "
            "write to another directory"
        )
    if made_seed != seed:
        raise SoftcellError(
            f"{out} holds this study made with seed = {made_seed}, not {seed}; rerun with "
            "--overwrite to recompute it, or write to another directory"
        )


def own_parameters(
    parameters: dict[str, Any] | None, study: str, keys: tuple[str, ...]
) -> dict[str, Any]:
    """A copy of the model ``parameters`` a grid study was given, refused in one line if it
    sets one of ``keys``, which the study ``study`` sets itself."""
    parameters = dict(parameters or {})
    for key in keys:
        if key in parameters:
            raise SoftcellError(f"parameter {key!r} is set by the {study} study itself")
    return parameters


def mark_study(out: Path, command: str, seed: int, overwrite: bool) -> None:
    """Check that ``out`` may hold the study ``command`` from ``seed``
    (:func:`check_study_directory`), create it, and mark it as that study's."""
    from softcell.io.files import atomic_write

    check_study_directory(out, command, seed, overwrite)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / STUDY_MANIFEST) as tmp:
        tmp.write_text(json.dumps({"study": command, "seed": seed}) + "\n", encoding="utf-8")


def run_variants(
    out: Path,
    variants: tuple[Variant, ...],
    base: Design,
    *,
    command: str,
    seed: int,
    workers: int | None,
    overwrite: bool,
    progress: bool,
    log: Callable[[str], None] | None,
    scheduler: str | None = None,
) -> None:
    """Reproduce each variant of ``base`` into ``out/<variant>`` from one root seed; a
    variant that finished there (same design, seed and version) is kept as it is.

    ``out`` must be new, empty or a folder the study ``command`` made from ``seed``
    (:func:`check_study_directory`); it is marked as such before any variant runs.
    """
    from softcell.io.files import check_output
    from softcell.paper.reproduce import finished

    out = check_output(Path(out), "report", directory=True)
    mark_study(out, command, seed, overwrite)
    say = log or (lambda _: None)
    for i, variant in enumerate(variants):
        design, folder = variant.design(base), out / variant.name
        if not overwrite and finished(folder, design, seed):
            say(f"variant {i + 1}/{len(variants)}: {variant.label} (finished, kept)")
            continue
        say(f"variant {i + 1}/{len(variants)}: {variant.label}")
        reproduce(
            folder,
            design,
            seed=seed,
            workers=workers,
            scheduler=scheduler,
            overwrite=overwrite,
            progress=progress,
            log=log,
        )


def run_points(
    out: Path,
    points: dict[Path, tuple[str, Any]],
    *,
    command: str,
    realizations: int,
    seed: int,
    workers: int | None,
    overwrite: bool,
    progress: bool,
    log: Callable[[str], None] | None,
) -> None:
    """Run a grid study's points: each folder of ``points`` (under ``out``) gets its
    (label, RunConfig) simulated with ``realizations`` from root ``seed``, resumable as
    ``softcell simulate`` is. Every point is planned (every bad value, before any run)
    before ``out`` is marked as the study ``command``'s; one local cluster serves them all
    (:func:`softcell.runner.points.run_points`)."""
    from softcell.runner.points import run_points as run

    run(
        points,
        realizations=realizations,
        seed=seed,
        workers=workers,
        overwrite=overwrite,
        progress=progress,
        log=log,
        planned=lambda: mark_study(out, command, seed, overwrite),
    )


def realization_means(
    folder: Path, realizations: int, keys: tuple[str, ...], discard: float
) -> dict[str, Any]:
    """One point of a grid study from its realization files: each analysed alone (the
    first ``discard`` s dropped; an assembly's pooled over its cells), then, for each
    analysis variable of ``keys`` (its cell value), the mean over the realizations where it
    is defined (finite), ``<key>_sem`` the standard error across them (NaN with fewer than
    two), ``<key>_n`` how many they are and ``<key>_each`` every value (NaN where the analysis
    left it undefined, e.g. a go phase that never ended), in the variable's unit."""
    from softcell.analysis import analyze
    from softcell.io.netcdf import open_dataset

    values: dict[str, list[float]] = {key: [] for key in keys}
    for r in range(realizations):
        ds = open_dataset(folder / f"point000_realization{r:04d}.nc")
        analysis = analyze(ds, {"discard": discard})
        for key in keys:
            value = analysis[key]
            values[key].append(float(value.sel(body="cell") if "body" in value.dims else value))
    point: dict[str, Any] = {}
    for key, each in values.items():
        v = np.array(each)
        v = v[np.isfinite(v)]
        point[key] = float(v.mean()) if v.size else math.nan
        point[f"{key}_sem"] = float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan
        point[f"{key}_n"] = int(v.size)
        point[f"{key}_each"] = each
    return point
