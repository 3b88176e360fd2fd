"""What the paper's unknowns decide: the quick design over one unknown at a time
(``softcell study sensitivity``).

The paper leaves open the bot's semi-axes, the reading of k, the cutoff Lambda_c, the reading
of lambda, whether a tumble turns the bot about its centre or about a pivot, and whether the
membrane has static friction (docs/model.md §8). :data:`VARIANTS` moves one of them at a time
away from the defaults; each variant runs the quick design (every radius, 5 realizations of
240 s, the free bot; no video) into its own folder by
:func:`softcell.paper.reproduce.reproduce`, from the same root seed, so the variants share
their random numbers (common random numbers: their differences are the model's, not noise).
:func:`summarize` sets them side by side: which findings each variant flips, the measured
values behind them with the spread across realizations, the paper's stated facts per variant
(``sensitivity.md``, ``sensitivity.json``, ``figures/``).

A rerun into the same directory skips the variants that finished and resumes the others
realization by realization, as ``softcell reproduce`` does.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from softcell.errors import SoftcellError
from softcell.io.pages import Block, markdown
from softcell.paper.reproduce import QUICK, Design
from softcell.studies.figures import values_figure, verdicts_figure
from softcell.studies.protocol import VariantStudy
from softcell.studies.variants import Variant, run_variants

#: The quick design without its video: the study needs the simulations' findings only.
BASE = replace(QUICK, video=None)


def _bot(a: float, b: float) -> Variant:
    return Variant(
        f"bot_{a:g}x{b:g}",
        f"bot {a:g} x {b:g} cm",
        parameters={"bot_semi_major": a, "bot_semi_minor": b},
        unknown="bot",
    )


VARIANTS: tuple[Variant, ...] = (
    Variant("default", "defaults"),
    _bot(2.5, 1.5),
    _bot(3.5, 2.5),
    *(
        Variant(f"k_{k:g}", f"k = {k:g} N cm2", parameters={"bending_stiffness": k}, unknown="k")
        for k in (0.057, 0.18)
    ),
    *(
        Variant(f"cutoff_{c}", f"Lambda_c = {c}", parameters={"cutoff": c}, unknown="cutoff")
        for c in (12, 19)
    ),
    Variant(
        "lambda_1e-4", "lambda = 1e-4 cm", parameters={"contact_length": 1e-4}, unknown="lambda"
    ),
    Variant(
        "pivot",
        "tumbles about a pivot 1 cm off-centre",
        components={"driving_protocol": "pivot_run_and_tumble"},
        unknown="rotation",
    ),
    Variant(
        "coulomb",
        "coulomb friction, f_s = 1e-4 N/cm",
        components={"friction_law": "coulomb"},
        parameters={"membrane_static_friction": 1e-4, "static_friction_width": 1e-5},
        unknown="friction",
    ),
    # The bot's MSD inside the ring reaches half the free bot's only below ~4.7e-5 (a bot
    # pushing the ring moves at F0 / (gamma_T + gamma_mem 2 pi R)).
    Variant(
        "gamma_mem_4.7e-5",
        "gamma_mem = 4.7e-5 N s/cm2",
        parameters={"membrane_friction": 4.7e-5},
        unknown="gamma_mem",
    ),
    # The drive torque is ~1e3 times any contact torque, so the membrane cannot steer the
    # bot; both / 1000 keep the tumbles' angular speed T0 / gamma_R and let it.
    Variant(
        "torque_1e-3",
        "T0 and gamma_R / 1000",
        parameters={"drive_torque": 0.1511, "bot_rotational_friction": 0.0285},
        unknown="torque",
    ),
    # ... and jointly with a membrane 10 times softer, which deforms more and so could
    # steer the bot more.
    Variant(
        "torque_1e-3_k_0.057",
        "T0 and gamma_R / 1000, k = 0.057 N cm2",
        parameters={
            "drive_torque": 0.1511,
            "bot_rotational_friction": 0.0285,
            "bending_stiffness": 0.057,
        },
        unknown="torque and k",
    ),
    # F0 and gamma_T halved together keep the free bot's 15 cm/s (a stated fact) and double
    # the membrane's friction relative to the bot's.
    Variant(
        "force_x0.5",
        "F0 and gamma_T / 2",
        parameters={"drive_force": 0.021375, "bot_friction": 0.001425},
        unknown="force",
    ),
    # The experiments' conditions: a tumble turns the bot about a pivot, on a floor with
    # static friction.
    Variant(
        "pivot_coulomb",
        "pivot tumbles and coulomb friction",
        components={"driving_protocol": "pivot_run_and_tumble", "friction_law": "coulomb"},
        parameters={"membrane_static_friction": 1e-4, "static_friction_width": 1e-5},
        unknown="rotation and friction",
    ),
)
#: What the defaults are, per unknown (for the tables' legends).
DEFAULTS = {
    "bot": "3 x 2 cm",
    "k": "0.57 N cm2",
    "cutoff": "16",
    "lambda": "0.01 cm",
    "rotation": "about the centre",
    "friction": "viscous",
    "gamma_mem": "3.42e-4 N s/cm2",
    "torque": "T0 = 151 N cm, gamma_R = 28.5 N cm s",
    "rotation and friction": "about the centre, viscous",
    "torque and k": "T0 = 151 N cm, gamma_R = 28.5 N cm s, k = 0.57 N cm2",
    "force": "F0 = 0.04275 N, gamma_T = 2.85e-3 N s/cm",
}
#: The bot's MSD inside the membrane is compared with the free bot's at this lag (s).
SHORT_LAG = 0.1


def sensitivity(
    out: str | os.PathLike[str],
    *,
    seed: int = 0,
    workers: int | None = None,
    variants: tuple[Variant, ...] = VARIANTS,
    base: Design = BASE,
    overwrite: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = print,
) -> Path:
    """Run every variant of ``base`` into ``out/<variant>`` and write the comparison.

    Parameters
    ----------
    out : path-like
        Results directory; each variant's reproduction is a subfolder. A variant that
        finished there (same design, seed and version) is kept; an unfinished one resumes.
    seed : int
        One root seed for every variant (common random numbers).
    workers : int, optional
        Local worker processes (default: every core).
    variants : tuple of Variant
        The first is the reference the others are compared with (default :data:`VARIANTS`).
    base : Design
        The design every variant runs (default :data:`BASE`, the quick design without video).
    overwrite : bool
        Recompute every variant.

    Returns
    -------
    Path
        ``out / "sensitivity.md"``.
    """
    run_variants(
        out,
        variants,
        base,
        command="study sensitivity",
        seed=seed,
        workers=workers,
        overwrite=overwrite,
        progress=progress,
        log=log,
    )
    return summarize(out, variants, seed=seed, base=base)


# -- what each variant measured ----------------------------------------------------------------


def _mean_sem(per_realization: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error over the last axis (NaN-aware; NaN with fewer than 2)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        n = np.sum(np.isfinite(per_realization), axis=-1)
        mean = np.nanmean(per_realization, axis=-1)
        sem = np.where(
            n >= 2, np.nanstd(per_realization, axis=-1, ddof=1) / np.sqrt(np.maximum(n, 1)), np.nan
        )
    return mean, sem


def crossing(radii: np.ndarray, ratio: np.ndarray, level: float) -> float:
    """The radius (cm) where ``ratio`` first reaches ``level``, interpolated linearly between
    the radii around it; the first radius if it starts there, NaN if it never does."""
    above = np.flatnonzero(ratio >= level)
    if above.size == 0:
        return math.nan
    j = int(above[0])
    if j == 0:
        return float(radii[0])
    r0, r1, q0, q1 = radii[j - 1], radii[j], ratio[j - 1], ratio[j]
    return float(r0 + (level - q0) * (r1 - r0) / (q1 - q0))


def membrane_measures(
    sims, params: dict[str, Any], keep: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """From a sweep's stored membranes: the mean IPR per (radius, realization) over the
    samples ``keep`` (the smooth curve through the nodes, which sample a band-limited shape),
    and the largest |L / L_eq - 1| per radius over every realization and sample, L the
    membrane's length (spectrally) and L_eq that of the force-free circle."""
    from softcell.analysis.series import smooth_area_perimeter
    from softcell.components.registry import default_registry
    from softcell.engine.state import equilibrium_radius

    registry = default_registry()
    ipr, deviation = [], []
    for i, radius in enumerate(np.asarray(sims["radius"].values, dtype=float)):
        point = sims.isel(radius=i)  # [realization, time, node]
        area, length = smooth_area_perimeter(point["membrane_x"].values, point["membrane_y"].values)
        ipr.append((length / np.sqrt(np.abs(area)))[:, keep].mean(axis=-1))
        r_eq = equilibrium_radius(registry.parameters({**params, "radius": float(radius)}))
        deviation.append(float(np.nanmax(np.abs(length / (2 * np.pi * r_eq) - 1))))
    return np.asarray(ipr), np.asarray(deviation)


def run_speed(free_bot) -> float:
    """The free bot's median speed (cm/s) between consecutive samples of the finest sampling
    that both fall in a run (``bot_phase`` 1)."""
    time = np.asarray(free_bot["time"].values, dtype=float)
    step = np.diff(time)
    fine = np.isclose(step, step.min())
    x, y = (
        np.asarray(free_bot[f"bot_{c}"].values, dtype=float).reshape(-1, time.size) for c in "xy"
    )
    run = np.asarray(free_bot["bot_phase"].values).reshape(-1, time.size) == 1
    both = run[:, 1:] & run[:, :-1] & fine
    v = np.hypot(np.diff(x, axis=1), np.diff(y, axis=1)) / step
    return float(np.median(v[both]))


def measure(folder: str | os.PathLike[str]) -> dict[str, Any]:
    """The measured values behind the findings, from one variant's reproduction folder.

    Returns a JSON-ready dict: per radius (cm) the pooled value and its standard error
    across realizations of <tau_g> (s), the bot-cell GC distance over R (1), the mean IPR
    (1; of the smooth curve through the stored nodes) and the bot's MSD over the free bot's
    at :data:`SHORT_LAG` (1); the radii where the GC distance ratio crosses the regime
    thresholds (cm); the paper's stated facts (the free bot's median speed in its runs,
    cm/s; the largest relative deviation of the membrane's length from its equilibrium
    value; the regimes at 4 and 12 cm); and every finding's verdict and measured text.
    """
    from softcell.analysis.options import analysis_options
    from softcell.io.netcdf import open_dataset, read_dataset
    from softcell.schema import REGIME_NAMES

    folder = Path(folder)
    analysis = read_dataset(folder / "analysis.nc")
    free = read_dataset(folder / "free_bot_analysis.nc")
    sims = open_dataset(folder / "simulations")
    radii = np.asarray(analysis["radius"].values, dtype=float)
    opts = analysis_options(json.loads(analysis.attrs["softcell_analysis_options"]))
    tau_g = np.asarray(analysis["mean_go_duration_realization"].sel(body="cell").values)
    keep = np.asarray(sims["time"].values) >= float(sims["time"].values[0]) + opts["discard"]
    gap = np.hypot(
        np.asarray(sims["bot_x"].values) - np.asarray(sims["cell_x"].values),
        np.asarray(sims["bot_y"].values) - np.asarray(sims["cell_y"].values),
    )
    gc_ratio = np.nanmean(gap[..., keep], axis=-1) / radii[:, None]
    lag = np.asarray(analysis["lag"].values, dtype=float)
    k = int(np.argmin(np.abs(lag - SHORT_LAG)))
    free_msd = free["msd"].sel(body="bot")
    free_short = float(np.ravel(free_msd.isel(lag=k).values)[0])
    bot_each = np.asarray(analysis["msd_realization"].sel(body="bot").isel(lag=k).values)
    bot_pooled = np.asarray(analysis["msd"].sel(body="bot").isel(lag=k).values)

    params = json.loads(sims.attrs["softcell_parameters"])
    ipr, deviation = membrane_measures(sims, params, keep)
    regime = np.asarray(analysis["regime"].values, dtype=int)
    findings = json.loads((folder / "findings.json").read_text())["findings"]

    def series(pooled: np.ndarray, each: np.ndarray) -> dict[str, list[float]]:
        return {"value": [float(v) for v in pooled], "sem": [float(v) for v in _mean_sem(each)[1]]}

    def at(r: float) -> str:
        i = np.flatnonzero(radii == r)
        return REGIME_NAMES[int(regime[i[0]])] if i.size else "not run"

    coupled, decoupled = opts["coupled_below"], opts["decoupled_above"]
    bounds = {}
    for name, level in (("coupled_until", coupled), ("decoupled_from", decoupled)):
        each = np.array([crossing(radii, gc_ratio[:, r], level) for r in range(gc_ratio.shape[1])])
        bounds[name] = {
            "value": crossing(
                radii, np.asarray(analysis["gc_distance_ratio"].values, dtype=float), level
            ),
            "sem": float(_mean_sem(each)[1]),
            "level": level,
        }
    return {
        "radius": radii.tolist(),
        "mean_go_duration": series(
            np.asarray(analysis["mean_go_duration"].sel(body="cell").values), tau_g
        ),
        "gc_distance_ratio": series(np.asarray(analysis["gc_distance_ratio"].values), gc_ratio),
        "ipr": series(ipr.mean(axis=-1), ipr),
        "bot_msd_ratio": series(bot_pooled / free_short, bot_each / free_short),
        "short_lag": float(lag[k]),
        "regime": [REGIME_NAMES[int(g)] for g in regime],
        "regime_bounds": bounds,
        "facts": {
            "free_bot_run_speed": run_speed(open_dataset(folder / "free_bot")),
            "length_deviation": float(deviation.max()),
            "regime_at_4": at(4.0),
            "regime_at_12": at(12.0),
        },
        "verdicts": {f["topic"]: f["verdict"] for f in findings},
        "measured": {f["topic"]: f["measured"] for f in findings},
    }


# -- the comparison ---------------------------------------------------------------------------

#: The paper's stated facts a proposed default must keep: (key, label, test).
FACTS = (
    (
        "free_bot_run_speed",
        "free bot's speed 15 cm/s (median over its runs, within 2 %)",
        lambda v: abs(v / 15.0 - 1) < 0.02,
    ),
    ("length_deviation", "membrane length within 0.1 % of its equilibrium", lambda v: v < 1e-3),
    ("regime_at_4", "coupled at R = 4 cm", lambda v: v == "coupled"),
    ("regime_at_12", "decoupled at R = 12 cm", lambda v: v == "decoupled"),
)


def facts_kept(result: dict[str, Any]) -> dict[str, bool]:
    """Each stated fact of the paper (:data:`FACTS`): whether the variant keeps it."""
    return {key: bool(test(result["facts"][key])) for key, _, test in FACTS}


def flips(
    results: dict[str, dict[str, Any]], variants: Sequence[Variant]
) -> dict[str, dict[str, str]]:
    """Per finding, the variants whose verdict differs from the reference's (the first
    variant), with their verdict."""
    reference = results[variants[0].name]["verdicts"]
    return {
        topic: {
            v.name: results[v.name]["verdicts"].get(topic, "-")
            for v in variants[1:]
            if results[v.name]["verdicts"].get(topic, "-") != verdict
        }
        for topic, verdict in reference.items()
    }


def candidates(results: dict[str, dict[str, Any]], variants: Sequence[Variant]) -> list[str]:
    """The variants that agree with strictly more findings than the reference, every
    finding the reference agrees with included, and keep every stated fact."""
    reference = results[variants[0].name]["verdicts"]
    agreed = {t for t, v in reference.items() if v == "agrees"}
    out = []
    for v in variants[1:]:
        mine = {t for t, x in results[v.name]["verdicts"].items() if x == "agrees"}
        if agreed < mine and all(facts_kept(results[v.name]).values()):
            out.append(v.name)
    return out


def summarize(
    out: str | os.PathLike[str],
    variants: tuple[Variant, ...] = VARIANTS,
    *,
    seed: int = 0,
    base: Design = BASE,
) -> Path:
    """``sensitivity.md``, ``sensitivity.json`` and ``figures/`` in ``out`` from the
    variants' folders."""
    from softcell.io.files import atomic_write, json_text

    out = Path(out)
    missing = [v.name for v in variants if not (out / v.name / "findings.json").is_file()]
    if missing:
        raise SoftcellError(
            f"{out} has no finished variant {', '.join(missing)}: run "
            f"`softcell study sensitivity -o {out}` to make them"
        )
    results = {v.name: measure(out / v.name) for v in variants}
    with atomic_write(out / "sensitivity.json") as tmp:
        tmp.write_text(
            json_text({"seed": seed, "variants": results}, indent=1) + "\n", encoding="utf-8"
        )
    figures = [
        values_figure(out / "figures", variants, results, DEFAULTS),
        verdicts_figure(out / "figures", variants, results),
    ]
    with atomic_write(out / "sensitivity.md") as tmp:
        tmp.write_text(_markdown(variants, results, figures, seed, base), encoding="utf-8")
    return out / "sensitivity.md"


def _pm(value: float, sem: float, spec: str) -> str:
    if not np.isfinite(value):
        return "-"
    return f"{value:{spec}}" + (f" ± {sem:{spec}}" if np.isfinite(sem) else "")


def _findings_section(variants, results) -> list[Block]:
    ref = results[variants[0].name]
    rows = []
    for t in ref["verdicts"]:
        mine = ref["verdicts"][t]
        cells = [results[v.name]["verdicts"].get(t, "-") for v in variants]
        rows.append([t, mine, *[f"**{c}**" if c != mine else c for c in cells[1:]]])
    agree = [sum(x == "agrees" for x in results[v.name]["verdicts"].values()) for v in variants]
    rows.append(["findings that agree", *agree])
    flipped = [
        [t, ref["verdicts"][t], "; ".join(f"{n}: {v}" for n, v in who.items()) or "none"]
        for t, who in flips(results, variants).items()
    ]
    return [
        Block("h2", "The findings per variant"),
        Block("table", (["finding", *[v.name for v in variants]], rows)),
        Block("p", "Bold: a verdict that differs from the defaults'."),
        Block("h2", "Which variants flip a verdict"),
        Block("table", (["finding", "defaults", "flipped by"], flipped)),
    ]


def _facts_section(variants, results) -> list[Block]:
    rows = []
    for v in variants:
        f, kept = results[v.name]["facts"], facts_kept(results[v.name])
        cells = [
            f"{f['free_bot_run_speed']:.2f} cm/s",
            f"{f['length_deviation']:.2%}",
            f["regime_at_4"],
            f["regime_at_12"],
        ]
        marked = [
            c if kept[key] else f"**{c}** (broken)"
            for c, (key, _, _) in zip(cells, FACTS, strict=True)
        ]
        rows.append([v.name, *marked])
    proposed = candidates(results, variants)
    return [
        Block("h2", "The paper's stated facts per variant"),
        Block("table", (["variant", *[label for _, label, _ in FACTS]], rows)),
        Block(
            "p",
            "A variant is a candidate default when it agrees with strictly more findings "
            "than the defaults, every finding the defaults agree with included, and keeps "
            "every fact above: " + (", ".join(proposed) if proposed else "none") + ".",
        ),
    ]


def _values_section(variants, results, base: Design) -> list[Block]:
    ref = results[variants[0].name]
    radii = ref["radius"]
    blocks = [
        Block("h2", "The measured values"),
        Block(
            "p",
            f"Pooled value ± standard error across the {base.realizations} realizations "
            "(common random numbers: "
            "a difference between variants is smaller than the error bars suggest).",
        ),
    ]
    tables = (
        ("mean_go_duration", "<tau_g> of the cell (s)", ".3f", 0.0),
        (
            "gc_distance_ratio",
            "bot-cell GC distance / R (coupled <= 0.35, decoupled >= 0.5)",
            ".2f",
            0.0,
        ),
        ("ipr", "mean IPR minus a circle's 2 sqrt(pi) = 3.5449", ".1e", 2 * math.sqrt(math.pi)),
        (
            "bot_msd_ratio",
            f"bot MSD in the membrane / free bot's, at lag {ref['short_lag']:g} s",
            ".2f",
            0.0,
        ),
    )
    for key, title, digits, offset in tables:
        rows = []
        for v in variants:
            r = results[v.name][key]
            values = [_pm(x - offset, s, digits) for x, s in zip(r["value"], r["sem"], strict=True)]
            rows.append([v.name, *values])
        blocks += [
            Block("h3", title),
            Block("table", (["variant", *[f"R = {r:g}" for r in radii]], rows)),
        ]
    return blocks


def _bounds_section(variants, results) -> list[Block]:
    rows = []
    for v in variants:
        b = results[v.name]["regime_bounds"]
        rows.append(
            [
                v.name,
                _pm(b["coupled_until"]["value"], b["coupled_until"]["sem"], ".2f"),
                _pm(b["decoupled_from"]["value"], b["decoupled_from"]["sem"], ".2f"),
                ", ".join(g[:3] for g in results[v.name]["regime"]),
            ]
        )
    return [
        Block("h3", "Regime boundaries (cm)"),
        Block(
            "p",
            "Where the GC distance ratio reaches 0.35 (end of the coupled regime) and 0.5 "
            "(start of the decoupled one), interpolated between radii; the first radius when "
            "it starts above, - when it never reaches it.",
        ),
        Block("table", (["variant", "coupled until", "decoupled from", "regime per R"], rows)),
    ]


def _markdown(variants, results, figures, seed: int, base: Design) -> str:
    from softcell._version import __version__

    blocks = [
        Block("h1", "What the paper's unknowns decide"),
        Block(
            "p",
            f"Made by `softcell study sensitivity` (softcell {__version__}): {base.describe()}; "
            f"one unknown moved at a time, root seed {seed} for every variant. Each variant's "
            "own report is in its folder; the values are in `sensitivity.json`.",
        ),
        Block("p", "Defaults: " + "; ".join(f"{k} {v}" for k, v in DEFAULTS.items()) + "."),
        *_findings_section(variants, results),
        *_facts_section(variants, results),
        *_values_section(variants, results, base),
        *_bounds_section(variants, results),
        Block("images", [(f, f"figures/{f}") for f in figures]),
    ]
    return markdown(blocks) + "\n"


class Sensitivity(VariantStudy):
    """``softcell study sensitivity``: the paper's unknowns one at a time (:func:`sensitivity`)."""

    name = "sensitivity"
    variants = VARIANTS
    base = BASE

    comparison = staticmethod(sensitivity)


#: The study, as ``softcell study sensitivity`` runs it.
STUDY = Sensitivity()
