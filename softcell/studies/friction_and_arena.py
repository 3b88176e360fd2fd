"""Beyond the paper's model: what static friction and the arena change (``softcell study beyond``).

The quick design (every radius, 5 realizations of 240 s, one root seed for all variants, so
that differences are not noise) is run with

- ``viscous``: the paper's model (the reference);
- ``coulomb`` at three static thresholds f_s around the estimate of docs/model.md §3
  (3e-5, 1e-4 and 3e-4 N/cm, each regularised over f_s / 10);
- ``arena``: the paper's model inside the experiments' 1 m x 1 m plate, whose free bot runs
  inside the same walls;

each into its own folder by :func:`softcell.paper.reproduce.reproduce` (resumable, with its
own report). The quick design's free bot (240 s) hardly sees a 1 m arena's walls, so the free
bot also runs long (:data:`FREE_LONG`: 10 realizations of 1800 s) on the open floor and in the
arena (``free_bot_long/``). :func:`summarize` sets everything side by side against the paper's
claims: ``beyond.md``, ``beyond.json`` and figures.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from softcell.io.pages import Block, markdown
from softcell.model.configuration import DEFAULT_COMPONENTS
from softcell.paper.findings import cell_values
from softcell.paper.reproduce import QUICK, Design
from softcell.studies.figures import friction_figures
from softcell.studies.protocol import VariantStudy
from softcell.studies.variants import Variant, run_variants


def _coulomb(threshold: float) -> Variant:
    return Variant(
        f"coulomb_{threshold:g}",
        f"coulomb, f_s = {threshold:g} N/cm",
        {"friction_law": "coulomb"},
        {"membrane_static_friction": threshold, "static_friction_width": threshold / 10},
    )


VARIANTS: tuple[Variant, ...] = (
    Variant("viscous", "viscous (the paper's)"),
    _coulomb(3e-5),
    _coulomb(1e-4),
    _coulomb(3e-4),
    Variant(
        "arena",
        "viscous, in the 100 cm arena",
        {"energy_terms": [*DEFAULT_COMPONENTS["energy_terms"], "arena"]},
        {"arena_side": 100.0},
    ),
)


#: The long free-bot runs: realizations and duration (s).
FREE_LONG = (10, 1800.0)
#: Their two settings: the open floor and the paper's 1 m arena.
FREE_SETTINGS = {"open": ([], {}), "arena": (["arena"], {"arena_side": 100.0})}


def _free_long(
    out: Path, seed: int, workers: int | None, overwrite: bool, progress: bool, log
) -> None:
    from softcell.analysis import analyze
    from softcell.io.netcdf import open_dataset, write_dataset
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    realizations, duration = FREE_LONG
    for name, (terms, values) in FREE_SETTINGS.items():
        folder = out / "free_bot_long" / name
        config = RunConfig(
            parameters={"radius": QUICK.radii[0], "duration": duration, **values}
        ).updated(components={**DEFAULT_COMPONENTS, "energy_terms": terms})
        simulate(
            config,
            folder,
            realizations=realizations,
            seed=seed,
            workers=workers or len(os.sched_getaffinity(0)),
            membrane=False,
            progress=progress,
            overwrite=overwrite,
            log=log,
        )
        analysis = analyze(open_dataset(folder), {"discard": QUICK.discard})
        write_dataset(analysis, folder.parent / f"{name}_analysis.nc")


def beyond(
    out: str | os.PathLike[str],
    *,
    seed: int = 0,
    workers: int | None = None,
    variants: tuple[Variant, ...] = VARIANTS,
    base: Design = QUICK,
    overwrite: bool = False,
    progress: bool = True,
    long_free_bot: bool = True,
    log: Callable[[str], None] | None = print,
) -> Path:
    """Run every variant of ``base`` into ``out/<variant>`` and write the comparison.

    Parameters
    ----------
    out : path-like
        Results directory; each variant's reproduction is a subfolder (finished parts found
        there are kept, as :func:`~softcell.paper.reproduce.reproduce` does).
    seed : int
        One root seed for every variant (common random numbers).
    workers : int, optional
        Local worker processes (default: every core).
    long_free_bot : bool
        Also run the long free-bot ensembles (:data:`FREE_LONG`) on the open floor and in
        the arena.

    Returns
    -------
    Path
        ``out / "beyond.md"``.
    """
    out = Path(out)
    say = log or (lambda _: None)
    run_variants(
        out,
        variants,
        base,
        command="beyond",
        seed=seed,
        workers=workers,
        overwrite=overwrite,
        progress=progress,
        log=log,
    )
    if long_free_bot:
        say(
            f"the free bot, {FREE_LONG[0]} realizations of {FREE_LONG[1]:g} s, on the open "
            "floor and in the arena"
        )
        _free_long(out, seed, workers, overwrite, progress, log)
    return summarize(out, variants)


# -- the comparison ---------------------------------------------------------------------------


def _shape_by_phase(analysis) -> tuple[np.ndarray, np.ndarray]:
    """Mean IPR excess over a circle's 2 sqrt(pi), per radius, during the cell's stop and
    during its go samples."""
    from softcell.schema import GO, STOP

    ipr = np.asarray(analysis["ipr"].values, dtype=float) - 2 * np.sqrt(np.pi)
    labels = np.asarray(analysis["stopgo_label"].sel(body="cell").values)
    stop = np.array(
        [np.nanmean(np.where(labels[i] == STOP, ipr[i], np.nan)) for i in range(ipr.shape[0])]
    )
    go = np.array(
        [np.nanmean(np.where(labels[i] == GO, ipr[i], np.nan)) for i in range(ipr.shape[0])]
    )
    return stop, go


def measure(folder: Path) -> dict[str, Any]:
    """The quantities the paper's static-friction and arena claims are about, from one
    variant's reproduction folder."""
    from softcell.components.registry import default_registry
    from softcell.engine.free_bot import renewal_diffusion
    from softcell.io.netcdf import read_dataset

    analysis = read_dataset(folder / "analysis.nc")
    free = read_dataset(folder / "free_bot_analysis.nc")
    stop_excess, go_excess = _shape_by_phase(analysis)
    findings = json.loads((folder / "findings.json").read_text())["findings"]
    free_msd = free["msd"].sel(body="bot")
    free_msd = free_msd.isel({d: 0 for d in free_msd.dims if d != "lag"})
    stored = read_dataset(next((folder / "free_bot").glob("*.nc"))).attrs["softcell_parameters"]
    params = default_registry().parameters(json.loads(stored))
    confined = free["confined_diffusion_coefficient"].sel(body="bot")
    return {
        "radius": [float(r) for r in analysis["radius"].values],
        "mean_stop_duration": cell_values(analysis, "mean_stop_duration").tolist(),
        "mean_go_duration": cell_values(analysis, "mean_go_duration").tolist(),
        "ipr_mean": np.asarray(analysis["ipr_mean"].values, dtype=float).tolist(),
        "ipr_excess_stop": stop_excess.tolist(),
        "ipr_excess_go": go_excess.tolist(),
        "regime": [int(g) for g in analysis["regime"].values],
        "verdicts": {f["topic"]: f["verdict"] for f in findings},
        "free_lag": [float(t) for t in free["lag"].values],
        "free_msd": [float(v) for v in np.asarray(free_msd.values)],
        "free_confined_d": float(np.ravel(confined.values)[0]),
        "free_renewal_d": float(renewal_diffusion(params)),
    }


def _free_measure(path: Path) -> dict[str, Any]:
    from softcell.io.netcdf import read_dataset

    free = read_dataset(path)
    msd = free["msd"].sel(body="bot")
    msd = msd.isel({d: 0 for d in msd.dims if d != "lag"})
    confined = free["confined_diffusion_coefficient"].sel(body="bot")
    return {
        "lag": [float(t) for t in free["lag"].values],
        "msd": [float(v) for v in np.asarray(msd.values)],
        "confined_d": float(np.ravel(confined.values)[0]),
    }


def summarize(out: str | os.PathLike[str], variants: tuple[Variant, ...] = VARIANTS) -> Path:
    """``beyond.md``, ``beyond.json`` and ``figures/`` in ``out`` from the variants' folders."""
    from softcell.io.files import atomic_write, json_text

    out = Path(out)
    results: dict[str, Any] = {v.name: measure(out / v.name) for v in variants}
    long = {
        name: _free_measure(out / "free_bot_long" / f"{name}_analysis.nc")
        for name in FREE_SETTINGS
        if (out / "free_bot_long" / f"{name}_analysis.nc").exists()
    }
    if long:
        results["free_bot_long"] = long
    with atomic_write(out / "beyond.json") as tmp:
        tmp.write_text(json_text(results, indent=1) + "\n", encoding="utf-8")
    figures = friction_figures(out / "figures", variants, results, FREE_LONG[1])
    text = _markdown(variants, results, figures)
    with atomic_write(out / "beyond.md") as tmp:
        tmp.write_text(text, encoding="utf-8")
    return out / "beyond.md"


def claims(reference: dict[str, Any], variant: dict[str, Any]) -> dict[str, float]:
    """A variant against the reference, on the paper's three static-friction claims: the
    median over R of the ratio of the IPR excess during stops, the mean ratio of <tau_s> over
    R >= 10 cm, the median ratio of <tau_g>."""
    radius = np.asarray(reference["radius"])
    ratio = {
        k: np.asarray(variant[k]) / np.asarray(reference[k])
        for k in ("ipr_excess_stop", "mean_stop_duration", "mean_go_duration")
    }
    return {
        "stop_shape": float(np.nanmedian(ratio["ipr_excess_stop"])),
        "stop_large": float(np.nanmean(ratio["mean_stop_duration"][radius >= 10])),
        "go": float(np.nanmedian(ratio["mean_go_duration"])),
    }


def _fmt(values, digits=3) -> str:
    return ", ".join(f"{v:.{digits}g}" for v in values)


def _verdict_blocks(variants, results) -> list[Block]:
    base = results[variants[0].name]
    rows = [
        [name, *[results[v.name]["verdicts"].get(name, "-") for v in variants]]
        for name in base["verdicts"]
    ]
    return [
        Block("h2", "The paper's findings, per variant"),
        Block("table", (["finding", *[v.label for v in variants]], rows)),
    ]


def _friction_blocks(variants, results, figures) -> list[Block]:
    base = results[variants[0].name]
    values = [
        [
            v.label,
            _fmt(results[v.name]["mean_stop_duration"]),
            _fmt(results[v.name]["mean_go_duration"]),
            _fmt(results[v.name]["ipr_excess_stop"], 2),
            _fmt(results[v.name]["ipr_excess_go"], 2),
        ]
        for v in variants
    ]
    ratios = []
    for v in variants[1:]:
        c = claims(base, results[v.name])
        ratios.append(
            [v.label, f"{c['stop_shape']:.3g}", f"{c['stop_large']:.3g}", f"{c['go']:.3g}"]
        )
    header = ["variant", "<tau_s> (s)", "<tau_g> (s)", "IPR excess, stops", "IPR excess, goes"]
    return [
        Block("h2", "What static friction is claimed to do"),
        Block("p", f"Radii: {_fmt(base['radius'])} cm."),
        Block("table", (header, values)),
        Block("p", "Against the paper's model (ratios to `viscous`, same seed):"),
        Block(
            "table",
            (
                [
                    "variant",
                    "IPR excess during stops (median over R)",
                    "<tau_s> at R >= 10 cm (mean)",
                    "<tau_g> (median over R)",
                ],
                ratios,
            ),
        ),
        Block(
            "p",
            "The paper's claims, read from these columns: static friction keeps the shape "
            "during stops (first column > 1), lengthens <tau_s> at large R (second > 1) and "
            "shortens the go phases (third < 1).",
        ),
        Block("images", [(f, f"figures/{f}") for f in figures]),
    ]


def _arena_blocks(results, renewal: float) -> list[Block]:
    long = results.get("free_bot_long", {})
    if not long:
        return []
    rows = [
        [
            name,
            f"{r['confined_d']:.2f}",
            f"{r['confined_d'] / renewal:.2f}",
            f"{r['msd'][-1]:.0f}",
        ]
        for name, r in long.items()
    ]
    header = ["floor", "confined-fit D (cm2/s)", "fit / renewal", "MSD at the longest lag (cm2)"]
    return [
        Block("h2", "The free bot in the arena"),
        Block(
            "p",
            f"{FREE_LONG[0]} realizations of {FREE_LONG[1]:g} s of the free bot (rotation "
            f"about its centre), whose renewal D is {renewal:.2f} cm2/s; the "
            "confined-square formula (L = 100 cm) fitted to its MSD:",
        ),
        Block("table", (header, rows)),
        Block("p", f"L^2 / 3 = {100.0**2 / 3:.0f} cm2 is where the MSD saturates in the arena."),
    ]


def _markdown(variants, results, figures) -> str:
    from softcell._version import __version__

    blocks = [
        Block("h1", "Beyond the paper: static friction and the arena"),
        Block(
            "p",
            f"Made by `softcell beyond` (softcell {__version__}): the quick design (every "
            "radius, 5 realizations of 240 s, root seed 0 for every variant) with each variant "
            "below. Each variant's own report is in its folder.",
        ),
        *_verdict_blocks(variants, results),
        *_friction_blocks(variants, results, figures),
        *_arena_blocks(results, results[variants[0].name]["free_renewal_d"]),
    ]
    return markdown(blocks) + "\n"


class Beyond(VariantStudy):
    """``softcell study beyond``: static friction and the arena beside the paper's model
    (:func:`beyond`, with the long free-bot runs)."""

    name = "beyond"
    variants = VARIANTS
    base = QUICK

    comparison = staticmethod(beyond)


#: The study, as ``softcell study beyond`` runs it.
STUDY = Beyond()
