"""Locomotion strategies and softness: the cell's D hat, <tau_g>, <tau_s> and shape index
against R for each driving protocol (``softcell study strategies``).

Each (strategy, R) point is one folder of single-cell realizations; each realization is
analysed on its own (the first :data:`DISCARD` s dropped) and the study reports the mean
over realizations with the standard error across them. The paper's protocol
(``run_and_tumble``) is the reference. How strongly softness tunes a strategy is read from
the ratio of its D hat at the largest and the smallest radius, with its error propagated
from the two points' standard errors.

Realization r of every point draws from ``SeedSequence(seed, spawn_key=(0, r))``: the
points of one strategy share their random drives across radii.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from softcell.errors import SoftcellError
from softcell.studies.protocol import GridStudy

#: Seconds dropped at the start of each realization before the analysis (s).
DISCARD = 15.0
#: The analysis variables the study reports: D hat (cm^2/s), <tau_g>, <tau_s> (s), shape
#: index (1).
MEASURES = ("msd_slope", "mean_go_duration", "mean_stop_duration", "ipr_mean")
#: The built-in strategies, the paper's first.
STRATEGIES = ("run_and_tumble", "graspion", "bump_and_turn", "active_brownian", "chiral")


@dataclass(frozen=True)
class StrategiesDesign:
    """The study's grid.

    Parameters
    ----------
    name : str
        What the grid is called (in the study's summary).
    strategies : tuple of str
        Driving protocols (registered names).
    radii : tuple of float
        Membrane radii R (cm), at least two (the ratio needs them).
    realizations : int
        Realizations per point, >= 2 for an error.
    duration : float
        Duration of each realization (s), longer than the discard.
    """

    name: str
    strategies: tuple[str, ...]
    radii: tuple[float, ...]
    realizations: int
    duration: float

    def check(self) -> None:
        """Refuse, in one line naming the value, a grid that cannot be run: no strategy, a
        strategy named twice, fewer than two radii, a radius or duration not > 0 (or a
        duration within 30 s of the discard), fewer than 2 realizations."""
        if not self.strategies or len(set(self.strategies)) != len(self.strategies):
            raise SoftcellError(
                f"strategies design {self.name!r}: strategies {list(self.strategies)} must be "
                "non-empty and each named once"
            )
        if len(self.radii) < 2:
            raise SoftcellError(f"strategies radii {list(self.radii)}: give at least two")
        for r in self.radii:
            if not (math.isfinite(r) and r > 0):
                raise SoftcellError(f"strategies radius {r!r} cm: must be > 0")
        if self.realizations < 2:
            raise SoftcellError(
                f"strategies realizations = {self.realizations}: must be >= 2 for an error"
            )
        if not (math.isfinite(self.duration) and self.duration > DISCARD + 30):
            raise SoftcellError(
                f"strategies duration {self.duration!r} s: must be > {DISCARD + 30:g} s "
                f"(the first {DISCARD:g} s are dropped)"
            )


#: The stated grid: six radii, 6 realizations of 600 s per point (~1.5 h on 2 cores,
#: estimated from the quick grid; not run).
FULL = StrategiesDesign(
    name="full",
    strategies=STRATEGIES,
    radii=(4.0, 5.0, 6.0, 7.0, 8.0, 10.0),
    realizations=6,
    duration=600.0,
)
#: A look: three radii, 3 realizations of 300 s (8.2 min on 2 cores).
QUICK = StrategiesDesign(
    name="quick",
    strategies=STRATEGIES,
    radii=(4.0, 6.0, 8.0),
    realizations=3,
    duration=300.0,
)


def _folder(out: Path, strategy: str, radius: float) -> Path:
    return out / f"{strategy}_R{radius:g}"


# -- what the runs measured ---------------------------------------------------------------------


def measure(out: Path, design: StrategiesDesign) -> list[dict[str, Any]]:
    """Every point of ``design`` in ``out``, strategy by strategy; a point whose
    realizations are not all there is marked ``missing``."""
    from softcell.studies.variants import realization_means

    points = []
    for strategy in design.strategies:
        for radius in design.radii:
            folder = _folder(out, strategy, radius)
            files = [folder / f"point000_realization{r:04d}.nc" for r in range(design.realizations)]
            point: dict[str, Any] = {"strategy": strategy, "radius": radius}
            if all(f.is_file() for f in files):
                point.update(realization_means(folder, design.realizations, MEASURES, DISCARD))
            else:
                point["missing"] = True
            points.append(point)
    return points


def softness_ratios(
    points: list[dict[str, Any]], design: StrategiesDesign
) -> dict[str, dict[str, float]]:
    """Per strategy, D hat at the largest radius over D hat at the smallest, with its
    standard error propagated from the two points' (first order, independent points)."""
    ratios = {}
    small, large = min(design.radii), max(design.radii)
    for strategy in design.strategies:
        ends = {
            p["radius"]: p
            for p in points
            if p["strategy"] == strategy and p["radius"] in (small, large) and not p.get("missing")
        }
        if len(ends) < 2:
            continue
        a, b = ends[small], ends[large]
        ratio = b["msd_slope"] / a["msd_slope"]
        error = ratio * math.hypot(
            a["msd_slope_sem"] / a["msd_slope"], b["msd_slope_sem"] / b["msd_slope"]
        )
        ratios[strategy] = {"ratio": ratio, "sem": error, "from_cm": small, "to_cm": large}
    return ratios


def _pm(point: dict[str, Any], key: str, spec: str) -> str:
    """The mean ± its error, with how many realizations defined it when not all did."""
    n, every = point[f"{key}_n"], len(point[f"{key}_each"])
    if n == 0:
        return "undefined"
    text = f"{point[key]:{spec}} ± {point[key + '_sem']:.2g}"
    return text if n == every else f"{text} ({n} of {every})"


def _markdown(result: dict[str, Any]) -> str:
    design = result["design"]
    lines = [
        "# Locomotion strategies and softness",
        "",
        f"softcell {result['version']}, root seed {result['seed']}, design "
        f"{design['name']!r}: one cell, {design['realizations']} realizations of "
        f"{design['duration']:g} s per point, the first {DISCARD:g} s dropped. Values are "
        "means over the realizations where the analysis defines them, with the standard "
        "error across them; '(n of N)' marks a value only n realizations defined (a go phase "
        "that outlasts the record leaves <tau_g> and D hat undefined).",
        "",
        "| strategy | R (cm) | D hat (cm2/s) | <tau_g> (s) | <tau_s> (s) | shape index |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for p in result["points"]:
        if p.get("missing"):
            lines.append(f"| {p['strategy']} | {p['radius']:g} | not run | not run | not run "
                         "| not run |")  # fmt: skip
            continue
        lines.append(
            f"| {p['strategy']} | {p['radius']:g} | {_pm(p, 'msd_slope', '.3g')} | "
            f"{_pm(p, 'mean_go_duration', '.3g')} | {_pm(p, 'mean_stop_duration', '.3g')} | "
            f"{_pm(p, 'ipr_mean', '.4f')} |"
        )
    lines += [
        "",
        "D hat at the largest radius over D hat at the smallest (softness as a knob):",
        "",
    ]
    for strategy, r in result["softness"].items():
        error = (
            f"± {r['sem']:.2f}"
            if math.isfinite(r["sem"])
            else "(no error: one realization defined D hat at an end)"
        )
        lines.append(
            f"- {strategy}: {r['ratio']:.2f} {error} (R = {r['from_cm']:g} -> {r['to_cm']:g} cm)"
        )
    lines += [
        "",
        "![D hat, <tau_g>, <tau_s> and shape index against R](strategies.png)",
        "",
        "*Per strategy against the membrane radius R: D hat (the long-lag slope of the "
        "cell's MSD), the mean go and stop durations and the mean shape index. Errors: "
        "standard errors across realizations.*",
        "",
    ]
    return "\n".join(lines)


class Strategies(GridStudy):
    """The strategies study (``softcell study strategies``) in the study protocol.

    Its folder: ``<strategy>_R<R>/`` holds each point's realizations; ``strategies.json``,
    ``strategies.md`` and ``strategies.png`` the result. The default design is ``QUICK``
    (``FULL`` for the stated one); ``radius`` and ``duration`` are the study's own
    parameters. A grid that cannot run is refused by :meth:`StrategiesDesign.check`, an
    unknown strategy when planned.
    """

    name = "strategies"
    designs = {"quick": QUICK, "full": FULL}
    default = "quick"
    flags = ("strategies",)

    def points(self, out, design, parameters):
        from softcell.model.configuration import RunConfig

        return {
            _folder(out, strategy, radius): (
                f"{strategy}, R = {radius:g} cm",
                RunConfig(
                    parameters={**parameters, "radius": radius, "duration": design.duration}
                ).updated(components={"driving_protocol": strategy}),
            )
            for strategy in design.strategies
            for radius in design.radii
        }

    def measure(self, out, design):
        return measure(out, design)

    def context(self, design, parameters):
        return {"discard_s": DISCARD}

    def conclusions(self, points, design):
        return {"softness": softness_ratios(points, design)}

    def figure(self, path, result, design):
        from softcell.studies.figures import strategies_figure

        strategies_figure(path, result["points"], design.strategies)
        return ""

    def page(self, result, caption):
        return _markdown(result)


STUDY = Strategies()
#: The summary of a strategies study's folder (see :meth:`GridStudy.summarize`).
summarize = STUDY.summarize
#: Run the strategies study into a folder and write its summary (:meth:`GridStudy.run
#: <softcell.studies.protocol.GridStudy.run>`).
strategies = STUDY.run
