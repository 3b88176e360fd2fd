"""Beyond the paper's model: what static friction and the arena change (``softcell beyond``).

The quick design (every radius, 5 realizations of 240 s, one root seed for all variants, so
that differences are not noise) is run with

- ``viscous``: the paper's model (the reference);
- ``coulomb`` at three static thresholds f_s around the estimate of docs/model.md §3
  (3e-5, 1e-4 and 3e-4 N/cm, each regularised over f_s / 10);
- ``arena``: the paper's model inside the experiments' 1 m x 1 m plate, whose free bot runs
  inside the same walls;

each into its own folder by :func:`softcell.workflows.reproduce.reproduce` (resumable, with its
own report), and :func:`summarize` sets them side by side against the paper's claims:
``beyond.md``, ``beyond.json`` and figures.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from softcell.core.runconfig import DEFAULT_COMPONENTS
from softcell.workflows.reproduce import QUICK, Design, reproduce


@dataclass(frozen=True)
class Variant:
    """One model variant of the study: components and parameters over the quick design's."""

    name: str
    label: str
    components: dict[str, Any] = field(default_factory=dict)
    parameters: dict[str, Any] = field(default_factory=dict)

    def design(self, base: Design = QUICK) -> Design:
        return replace(base, name=f"{base.name}-{self.name}",
                       components={**DEFAULT_COMPONENTS, **self.components},
                       parameters={**base.parameters, **self.parameters})


def _coulomb(threshold: float) -> Variant:
    return Variant(f"coulomb_{threshold:g}", f"coulomb, f_s = {threshold:g} N/cm",
                   {"friction_law": "coulomb"},
                   {"membrane_static_friction": threshold,
                    "static_friction_width": threshold / 10})


VARIANTS: tuple[Variant, ...] = (
    Variant("viscous", "viscous (the paper's)"),
    _coulomb(3e-5), _coulomb(1e-4), _coulomb(3e-4),
    Variant("arena", "viscous, in the 100 cm arena",
            {"energy_terms": [*DEFAULT_COMPONENTS["energy_terms"], "arena"]},
            {"arena_side": 100.0}),
)


def beyond(out: str | os.PathLike[str], *, seed: int = 0, workers: int | None = None,
           variants: tuple[Variant, ...] = VARIANTS, base: Design = QUICK,
           overwrite: bool = False, progress: bool = True,
           log: Callable[[str], None] | None = print) -> Path:
    """Run every variant of ``base`` into ``out/<variant>`` and write the comparison.

    Parameters
    ----------
    out : path-like
        Results directory; each variant's reproduction is a subfolder (finished parts found
        there are kept, as :func:`~softcell.workflows.reproduce.reproduce` does).
    seed : int
        One root seed for every variant (common random numbers).
    workers : int, optional
        Local worker processes (default: every core).

    Returns
    -------
    Path
        ``out / "beyond.md"``.
    """
    out = Path(out)
    say = log or (lambda _: None)
    for i, variant in enumerate(variants):
        say(f"variant {i + 1}/{len(variants)}: {variant.label}")
        reproduce(out / variant.name, variant.design(base), seed=seed, workers=workers,
                  overwrite=overwrite, progress=progress, log=log)
    return summarize(out, variants)


# -- the comparison ---------------------------------------------------------------------------

def _cell(ds, name: str) -> np.ndarray:
    return np.asarray(ds[name].sel(body="cell").values, dtype=float)


def _shape_by_phase(analysis) -> tuple[np.ndarray, np.ndarray]:
    """Mean IPR excess over a circle's 2 sqrt(pi), per radius, during the cell's stop and
    during its go samples."""
    from softcell.core.schema import GO, STOP

    ipr = np.asarray(analysis["ipr"].values, dtype=float) - 2 * np.sqrt(np.pi)
    labels = np.asarray(analysis["stopgo_label"].sel(body="cell").values)
    stop = np.array([np.nanmean(np.where(labels[i] == STOP, ipr[i], np.nan))
                     for i in range(ipr.shape[0])])
    go = np.array([np.nanmean(np.where(labels[i] == GO, ipr[i], np.nan))
                   for i in range(ipr.shape[0])])
    return stop, go


def measure(folder: Path) -> dict[str, Any]:
    """The quantities the paper's static-friction and arena claims are about, from one
    variant's reproduction folder."""
    from softcell.core.freebot import renewal_diffusion
    from softcell.core.params import Parameters
    from softcell.core.plugin.registry import get_registry
    from softcell.io.netcdf import read_dataset

    analysis = read_dataset(folder / "analysis.nc")
    free = read_dataset(folder / "free_bot_analysis.nc")
    stop_excess, go_excess = _shape_by_phase(analysis)
    findings = json.loads((folder / "findings.json").read_text())["findings"]
    free_msd = free["msd"].sel(body="bot")
    free_msd = free_msd.isel({d: 0 for d in free_msd.dims if d != "lag"})
    stored = read_dataset(next((folder / "free_bot").glob("*.nc"))).attrs["softcell_parameters"]
    params = Parameters(json.loads(stored), get_registry().parameter_specs().values())
    confined = free["confined_diffusion_coefficient"].sel(body="bot")
    return {
        "radius": [float(r) for r in analysis["radius"].values],
        "mean_stop_duration": _cell(analysis, "mean_stop_duration").tolist(),
        "mean_go_duration": _cell(analysis, "mean_go_duration").tolist(),
        "ipr_mean": np.asarray(analysis["ipr_mean"].values, dtype=float).tolist(),
        "ipr_excess_stop": stop_excess.tolist(),
        "ipr_excess_go": go_excess.tolist(),
        "regime": [int(g) for g in analysis["regime"].values],
        "verdicts": {f["name"]: f["verdict"] for f in findings},
        "free_lag": [float(t) for t in free["lag"].values],
        "free_msd": [float(v) for v in np.asarray(free_msd.values)],
        "free_confined_d": float(np.ravel(confined.values)[0]),
        "free_renewal_d": float(renewal_diffusion(params)),
    }


def summarize(out: str | os.PathLike[str], variants: tuple[Variant, ...] = VARIANTS) -> Path:
    """``beyond.md``, ``beyond.json`` and ``figures/`` in ``out`` from the variants' folders."""
    from softcell.io.files import atomic_write

    out = Path(out)
    results = {v.name: measure(out / v.name) for v in variants}
    with atomic_write(out / "beyond.json") as tmp:
        tmp.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    figures = _figures(out / "figures", variants, results)
    text = _markdown(variants, results, figures)
    with atomic_write(out / "beyond.md") as tmp:
        tmp.write_text(text, encoding="utf-8")
    return out / "beyond.md"


def _figures(folder: Path, variants, results) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8), constrained_layout=True)
    for v in variants:
        r = results[v.name]
        axes[0].plot(r["radius"], r["mean_stop_duration"], "o-", label=v.label)
        axes[1].plot(r["radius"], r["mean_go_duration"], "o-", label=v.label)
        axes[2].plot(r["radius"], np.array(r["ipr_excess_stop"]), "o-", label=v.label)
    axes[0].set(xlabel="R (cm)", ylabel="<tau_s> (s)", title="mean stop duration (cell)")
    axes[1].set(xlabel="R (cm)", ylabel="<tau_g> (s)", title="mean go duration (cell)")
    axes[2].set(xlabel="R (cm)", ylabel="IPR - 2 sqrt(pi)", yscale="log",
                title="shape excess during stops")
    axes[0].legend(fontsize=7)
    fig.savefig(folder / "friction.png", dpi=120)
    plt.close(fig)

    from softcell.core.analysis.fits import confined_square_msd

    fig, ax = plt.subplots(figsize=(5.5, 4), constrained_layout=True)
    for name in ("viscous", "arena"):
        if name not in results:
            continue
        r = results[name]
        lag = np.asarray(r["free_lag"])
        ax.loglog(lag, r["free_msd"], label=f"free bot, {name}")
    if "arena" in results:
        r = results["arena"]
        lag = np.asarray(r["free_lag"])
        ax.loglog(lag, confined_square_msd(lag, r["free_confined_d"], 100.0), "k--",
                  label=f"confined fit, D = {r['free_confined_d']:.1f} cm2/s")
        ax.loglog(lag, confined_square_msd(lag, r["free_renewal_d"], 100.0), "k:",
                  label=f"confined formula at the renewal D = {r['free_renewal_d']:.2f}")
    ax.set(xlabel="lag (s)", ylabel="MSD (cm2)", title="free bot: open floor and 1 m arena")
    ax.legend(fontsize=7)
    fig.savefig(folder / "arena.png", dpi=120)
    plt.close(fig)
    return ["friction.png", "arena.png"]


def _row(cells) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def _fmt(values, digits=3) -> str:
    return ", ".join(f"{v:.{digits}g}" for v in values)


def _markdown(variants, results, figures) -> str:
    from softcell._version import __version__

    base = results[variants[0].name]
    radii = base["radius"]
    lines = [
        "# Beyond the paper: static friction and the arena",
        "",
        f"Made by `softcell beyond` (softcell {__version__}): the quick design (every radius, "
        "5 realizations of 240 s, root seed 0 for every variant) with each variant below. "
        "Each variant's own report is in its folder.",
        "",
        "## The paper's findings, per variant",
        "",
        _row(["finding", *[v.label for v in variants]]),
        _row(["---"] * (len(variants) + 1)),
    ]
    for name in base["verdicts"]:
        lines.append(_row([name, *[results[v.name]["verdicts"].get(name, "-")
                                   for v in variants]]))
    lines += ["", "## What static friction is claimed to do", "",
              f"Radii: {_fmt(radii)} cm.", "",
              _row(["variant", "<tau_s> (s)", "<tau_g> (s)", "IPR excess, stops",
                    "IPR excess, goes"]),
              _row(["---"] * 5)]
    for v in variants:
        r = results[v.name]
        lines.append(_row([v.label, _fmt(r["mean_stop_duration"]), _fmt(r["mean_go_duration"]),
                           _fmt(r["ipr_excess_stop"], 2), _fmt(r["ipr_excess_go"], 2)]))
    lines += ["", *[f"![{f}](figures/{f})" for f in figures], ""]
    if "arena" in results:
        r = results["arena"]
        free = results[variants[0].name]
        lines += ["## The free bot in the arena", "",
                  f"Renewal D of the free bot: {r['free_renewal_d']:.2f} cm2/s. Confined-square "
                  f"fit (L = 100 cm) to the free bot's MSD: {r['free_confined_d']:.2f} cm2/s "
                  f"inside the arena, {free['free_confined_d']:.2f} cm2/s on the open floor.",
                  ""]
    return "\n".join(lines) + "\n"
