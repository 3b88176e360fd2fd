"""The paper's picture as a target: where in the unknowns' space do its claims hold?

The target is not data but the paper's findings (:func:`softcell.paper.findings.findings`):
each design point of the unknowns runs the paper's design (every radius, the free bot) by
:func:`softcell.paper.reproduce.reproduce`, and its findings table is read as a row of
verdicts. A point's **score** is the share of the findings measured there (agrees, partly,
differs; not those that hold by construction or were not measured) that agree, a partial
agreement counting half. Two findings **pull against each other** when each agrees at some
point of the design but never both at one point.

The design is a scrambled Sobol sequence in the priors (as a fit's, :mod:`softcell.fit.design`),
and every point draws the same random numbers (one root seed), so that the differences
between points are the model's. Each point is a folder of ``softcell reproduce`` (resumable:
a point that finished is kept); the search writes the verdicts, the scores and the design as
NetCDF, and a page of them.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from softcell.engine.interrupt import deferred
from softcell.errors import ConfigError
from softcell.fit.priors import Prior, resolve_priors
from softcell.model.configuration import RunConfig
from softcell.paper.findings import VERDICTS
from softcell.paper.reproduce import QUICK, Design

#: How much each measured verdict counts towards a point's score.
WEIGHTS = {"agrees": 1.0, "partly": 0.5, "differs": 0.0}
#: What each point of a search runs by default: a screen, every radius with 4 realizations
#: of 120 s and no film (0.4 of the quick design's simulated time). Its verdicts carry
#: larger errors than the quick design's; confirm the best point with ``softcell reproduce
#: --quick --config``.
SEARCH_DESIGN = replace(
    QUICK,
    name="search",
    realizations=4,
    duration=120.0,
    free_bot_realizations=4,
    video=None,
    caveat="a screen: 4 realizations of 120 s per radius (the quick design runs 5 of 240 s), "
    "so its verdicts carry larger errors; the best point is confirmed with the quick design.",
)


def verdict_matrix(tables: Sequence[Sequence[dict[str, Any]]]) -> tuple[list[str], np.ndarray]:
    """The findings' topics (in the order of their first appearance) and int8[point, topic]:
    each point's verdict, an index of :data:`~softcell.paper.findings.VERDICTS` ("not
    measured" where a point's table lacks the topic). ``tables`` holds each point's findings
    as ``findings.json`` stores them (dicts with ``topic`` and ``verdict``)."""
    topics: list[str] = []
    for table in tables:
        topics += [row["topic"] for row in table if row["topic"] not in topics]
    missing = VERDICTS.index("not measured")
    matrix = np.full((len(tables), len(topics)), missing, dtype=np.int8)
    for i, table in enumerate(tables):
        for row in table:
            matrix[i, topics.index(row["topic"])] = VERDICTS.index(row["verdict"])
    return topics, matrix


def scores(matrix: np.ndarray) -> np.ndarray:
    """float64[point]: the share of a point's measured findings that agree (partly: half;
    NaN for a point with none measured)."""
    weight = np.full(len(VERDICTS), np.nan)
    for verdict, w in WEIGHTS.items():
        weight[VERDICTS.index(verdict)] = w
    values = weight[matrix]
    measured = np.isfinite(values).sum(axis=1)
    with np.errstate(invalid="ignore"):
        return np.where(measured > 0, np.nansum(values, axis=1) / np.maximum(measured, 1), np.nan)


def tensions(topics: Sequence[str], matrix: np.ndarray) -> list[dict[str, Any]]:
    """The pairs of findings that pull against each other: each agrees at some point, never
    both at one point. Each entry names them and counts the points where each agrees."""
    agrees = matrix == VERDICTS.index("agrees")
    found = []
    for a in range(len(topics)):
        for b in range(a + 1, len(topics)):
            if (
                agrees[:, a].any()
                and agrees[:, b].any()
                and not (agrees[:, a] & agrees[:, b]).any()
            ):
                found.append({
                    "findings": [topics[a], topics[b]],
                    "agrees": [int(agrees[:, a].sum()), int(agrees[:, b].sum())],
                    "points": int(matrix.shape[0]),
                })  # fmt: skip
    return found


def search(
    priors: Sequence[str | Prior],
    out: str | Path,
    *,
    prior_table: dict[str, Any] | None = None,
    points: int = 16,
    config: RunConfig | None = None,
    design: Design = SEARCH_DESIGN,
    seed: int = 0,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = print,
) -> Path:
    """Run the paper's design at every point of a space-filling design of the unknowns and
    score each against the paper's findings.

    Parameters
    ----------
    priors : sequence of str or Prior
        The unknowns and their ranges: ``NAME=LOW:HIGH [UNIT]`` (see
        :func:`~softcell.fit.priors.parse_prior`).
    out : path-like
        The search's file (NetCDF); the points' reproductions go to ``<out>_points/``, a
        page of the verdicts to ``out`` with the suffix ``.md``.
    prior_table : dict, optional
        More unknowns, as a ``[priors]`` table (:func:`~softcell.fit.priors.priors_from_table`).
    points : int
        Design points (a power of two).
    config : RunConfig, optional
        Components and parameters every point shares (e.g. a friction law whose static
        friction is an unknown).
    design : Design
        What each point runs (default: the quick design without its film).
    seed : int
        The root seed: the design's scrambling and every point's simulations (the same
        random numbers at every point).
    workers, scheduler, overwrite, progress, log
        As :func:`softcell.paper.reproduce.reproduce` takes them.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    ConfigError
        For a bad or repeated prior, none, a design size that is not a power of two, or a
        parameter the design sets for every point (the radius, the duration).
    """
    from softcell.fit.design import space_filling
    from softcell.io.files import check_output
    from softcell.studies.variants import Variant, run_variants

    shared = config or RunConfig()
    priors = resolve_priors(priors, prior_table, shared.components)
    out = check_output(Path(out), "fit", overwrite=overwrite)
    values = space_filling(priors, points, seed)
    for p in priors:
        if p.name in ("radius", "duration"):
            raise ConfigError(f"the paper's design sets {p.name} at every point: not an unknown")
    variants = []
    for i, row in enumerate(values):
        given = {p.name: float(v) for p, v in zip(priors, row, strict=True)}
        label = ", ".join(f"{p.name} = {v:.4g} {p.unit}" for p, v in zip(priors, row, strict=True))
        variants.append(
            Variant(
                f"point{i:04d}",
                label,
                components=dict(shared.components),
                parameters={**shared.parameters, **given},
            )  # fmt: skip
        )
    folder = out.parent / f"{out.stem}_points"
    run_variants(folder, tuple(variants), design, command="fit --paper", seed=seed,
                 workers=workers, scheduler=scheduler, overwrite=overwrite, progress=progress,
                 log=log)  # fmt: skip
    tables = [json.loads((folder / v.name / "findings.json").read_text())["findings"]
              for v in variants]  # fmt: skip
    topics, matrix = verdict_matrix(tables)
    result = _dataset(priors, values, topics, matrix, design, seed)
    from softcell.io.files import atomic_write

    with atomic_write(out) as tmp, deferred():
        result.to_netcdf(tmp)
    page = out.with_suffix(".md")
    with atomic_write(page) as tmp:
        tmp.write_text(_page(priors, values, topics, matrix, design), encoding="utf-8")
    if log:
        best = int(np.nanargmax(scores(matrix)))
        log(f"best point {best}: score {scores(matrix)[best]:.2f} ({variants[best].label})")
    return out


def _dataset(priors, values, topics, matrix, design: Design, seed: int):
    """The search as an xarray Dataset with CF attributes."""
    import xarray as xr

    from softcell._version import __version__

    ds = xr.Dataset()
    for i, p in enumerate(priors):
        ds[p.name] = ("design_point", values[:, i], {
            "units": p.unit, "long_name": f"{p.name} at each design point"})  # fmt: skip
    ds["finding"] = ("finding", np.array(topics, dtype=object), {
        "long_name": "a finding of the paper (the findings table's topic)"})  # fmt: skip
    ds["verdict"] = (("design_point", "finding"), matrix, {
        "long_name": "the finding's verdict at the design point",
        "flag_values": np.arange(len(VERDICTS), dtype=np.int8),
        "flag_meanings": " ".join(v.replace(" ", "_") for v in VERDICTS)})  # fmt: skip
    ds["score"] = ("design_point", scores(matrix), {
        "units": "1", "long_name": "share of the measured findings that agree (partly: half)",
    })  # fmt: skip
    ds.attrs.update({
        "Conventions": "CF-1.8",
        "title": "softcell fit --paper: the paper's findings across the unknowns",
        "softcell_version": __version__,
        "softcell_origin": "fit",
        "softcell_seed": seed,
        "softcell_priors": json.dumps([p.__dict__ for p in priors]),
        "softcell_design": design.describe(),
        "softcell_tensions": json.dumps(tensions(topics, matrix)),
    })  # fmt: skip
    return ds


def _page(priors, values, topics, matrix, design: Design) -> str:
    """A Markdown page: each point's unknowns, score and verdicts; the findings in tension."""
    short = {"agrees": "A", "partly": "P", "differs": "D", "holds by construction": "C",
             "not measured": "-"}  # fmt: skip
    score = scores(matrix)
    lines = [
        "# The paper's findings across the unknowns",
        "",
        f"Each point runs {design.describe()}. Verdicts: A agrees, P partly, D differs, "
        "C holds by construction, - not measured. Score: the share of the measured findings "
        "that agree (partly: half).",
        "",
        "| point | "
        + " | ".join(f"{p.name} ({p.unit})" for p in priors)
        + " | score | "
        + " | ".join(f"{k + 1}" for k in range(len(topics)))
        + " |",
        "| --- " * (len(priors) + 2 + len(topics)) + "|",
    ]
    for i in np.argsort(-np.nan_to_num(score, nan=-1.0), kind="stable"):
        cells = [f"{v:.4g}" for v in values[i]] + [f"{score[i]:.2f}"]
        cells += [short[VERDICTS[v]] for v in matrix[i]]
        lines.append(f"| {i} | " + " | ".join(cells) + " |")
    lines += ["", "Findings:", ""]
    lines += [f"{k + 1}. {topic}" for k, topic in enumerate(topics)]
    pulls = tensions(topics, matrix)
    lines += ["", "## Findings that pull against each other", ""]
    if pulls:
        lines += [
            f"- {a} (agrees at {na} points) and {b} (at {nb}): never both, of {t['points']}"
            for t in pulls
            for (a, b), (na, nb) in [(t["findings"], t["agrees"])]
        ]
    else:
        lines.append("- none: every two findings that agree somewhere agree together somewhere")
    return "\n".join(lines) + "\n"
