"""Crowding and softness: the cells' long-time D hat and <tau_g> against area fraction
(``softcell study crowding``).

M cells of radius R run and tumble in a periodic square box whose side sets the area
fraction phi = M pi R^2 / L^2. They start on a square lattice (``--placement lattice``) with
at least :data:`GAP` cm between rings. Each (R, phi) point is one folder of realizations;
each realization (one assembly) is analysed on its own, pooled over its cells (the first
``discard`` seconds dropped), and the study reports the mean over realizations with the
standard error across them: cells of one assembly push each other, so the realizations, not
the cells, are the independent samples. A cell alone (phi -> 0) is the reference: the same
radius in the open plane, one cell per realization.

Realization r of point p draws from ``SeedSequence(seed, spawn_key=(0, r))`` in every
point's folder (each point is its own ``softcell simulate`` call with one parameter point):
the points share their random drives, point by point and cell by cell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from softcell.errors import SoftcellError
from softcell.studies.protocol import GridStudy

#: Smallest starting gap between rings (cm): the densest lattice of the full grid
#: (phi = 0.7 at R = 5 cm) leaves 0.59 cm.
GAP = 0.3
#: Seconds dropped at the start of each realization before the analysis (s).
DISCARD = 15.0


@dataclass(frozen=True)
class CrowdingDesign:
    """The study's grid.

    Parameters
    ----------
    name : str
        What the grid is called (in the study's summary).
    radii : tuple of float
        Cell radii R (cm).
    fractions : tuple of float
        Area fractions phi = M pi R^2 / L^2 (dimensionless), in (0, pi / 4).
    cells : int
        Cells per assembly, M: a square number (the lattice fills a square).
    realizations : int
        Realizations (assemblies) per (R, phi), >= 2 for an error.
    duration : float
        Duration of each realization (s), longer than the discard.
    """

    name: str
    radii: tuple[float, ...]
    fractions: tuple[float, ...]
    cells: int
    realizations: int
    duration: float

    def check(self) -> None:
        """Refuse, in one line naming the value, a grid that cannot be run: no radii or
        fractions, a radius or duration not > 0 (or a duration within the discard), an area
        fraction outside (0, pi / 4) (a square lattice holds no more), a cell count that is
        not a square > 1, fewer than 2 realizations."""
        if not self.radii or not self.fractions:
            raise SoftcellError(f"crowding design {self.name!r}: no radii or no area fractions")
        for r in self.radii:
            if not (math.isfinite(r) and r > 0):
                raise SoftcellError(f"crowding radius {r!r} cm: must be > 0")
        for phi in self.fractions:
            if not (math.isfinite(phi) and 0 < phi < math.pi / 4):
                raise SoftcellError(
                    f"crowding area fraction {phi!r}: must be in (0, {math.pi / 4:.4f}); a "
                    "square lattice of rings holds no more"
                )
        side = math.isqrt(self.cells) if self.cells > 0 else 0
        if self.cells < 4 or side * side != self.cells:
            raise SoftcellError(
                f"crowding cells = {self.cells}: must be a square number >= 4 (4, 9, 16, ...)"
            )
        if self.realizations < 2:
            raise SoftcellError(
                f"crowding realizations = {self.realizations}: must be >= 2 for an error"
            )
        if not (math.isfinite(self.duration) and self.duration > DISCARD + 30):
            raise SoftcellError(
                f"crowding duration = {self.duration!r} s: must exceed the discard of "
                f"{DISCARD:g} s by at least 30 s"
            )


#: The full grid: ~12 h on 2 cores, estimated from the quick grid's cost per cell-second
#: (not yet run).
FULL = CrowdingDesign(
    name="full",
    radii=(5.0, 10.0),
    fractions=(0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7),
    cells=16,
    realizations=4,
    duration=300.0,
)
#: A look: 9 cells, three area fractions, 3 realizations of 120 s (54 min on 2 cores).
QUICK = CrowdingDesign(
    name="quick",
    radii=(5.0, 10.0),
    fractions=(0.1, 0.4, 0.7),
    cells=9,
    realizations=3,
    duration=120.0,
)


def box_side(cells: int, radius: float, fraction: float) -> float:
    """Side L (cm) of the square box in which ``cells`` rings of ``radius`` (cm) cover the
    area fraction ``fraction``: L = sqrt(M pi R^2 / phi)."""
    return math.sqrt(cells * math.pi * radius**2 / fraction)


def _folder(out: Path, radius: float, fraction: float | None) -> Path:
    return out / (f"R{radius:g}_alone" if fraction is None else f"R{radius:g}_phi{fraction:g}")


def _configs(design: CrowdingDesign, parameters: dict[str, Any]) -> dict[tuple, Any]:
    """Each point's request, keyed (radius, fraction); fraction None is the lone cell."""
    from softcell.model.configuration import RunConfig

    configs: dict[tuple, Any] = {}
    for radius in design.radii:
        base = {**parameters, "radius": radius, "duration": design.duration}
        configs[radius, None] = RunConfig(parameters=base)
        for phi in design.fractions:
            assembly = {
                "cells": design.cells,
                "box": round(box_side(design.cells, radius, phi), 6),
                "boundary": "periodic",
                "placement": "lattice",
                "gap": GAP,
            }
            configs[radius, phi] = RunConfig(parameters=base, assembly=assembly)
    return configs


# -- what the runs measured ---------------------------------------------------------------------


def measure_point(folder: Path, realizations: int) -> dict[str, Any]:
    """One point from its realizations: each analysed alone (pooled over its cells, the
    first :data:`DISCARD` s dropped), then the mean and standard error across realizations
    of the cells' D hat (cm^2/s), <tau_g> (s) and shape index P / sqrt(A)."""
    from softcell.studies.variants import realization_means

    return realization_means(
        folder, realizations, ("msd_slope", "mean_go_duration", "ipr_mean"), DISCARD
    )


def measure(out: Path, design: CrowdingDesign) -> list[dict[str, Any]]:
    """Every point of ``design`` in ``out``: the lone cell first, then each area fraction,
    radius by radius; a point whose realizations are not all there is marked ``missing``."""
    points = []
    for radius in design.radii:
        for phi in (None, *design.fractions):
            folder = _folder(out, radius, phi)
            files = [folder / f"point000_realization{r:04d}.nc" for r in range(design.realizations)]
            box = None if phi is None else box_side(design.cells, radius, phi)
            point = {"radius": radius, "fraction": phi, "box_cm": box}
            if all(f.is_file() for f in files):
                points.append({**point, **measure_point(folder, design.realizations)})
            else:  # a study stopped before this point finished (summarize called alone)
                points.append({**point, "missing": True})
    return points


def _pm(point: dict[str, Any], key: str, spec: str) -> str:
    return f"{point[key]:{spec}} ± {point[key + '_sem']:.2g}"


def _markdown(result: dict[str, Any]) -> str:
    design = result["design"]
    lines = [
        "# Crowding and softness",
        "",
        f"softcell {result['version']}, root seed {result['seed']}, design "
        f"{design['name']!r}: {design['cells']} cells in a periodic box, "
        f"{design['realizations']} realizations of {design['duration']:g} s per point, the "
        f"first {DISCARD:g} s dropped. Each realization is analysed alone (pooled over its "
        "cells); values are means over realizations with the standard error across them. "
        "'alone' is one cell in the open plane.",
        "",
        "| R (cm) | area fraction | box (cm) | D hat (cm2/s) | <tau_g> (s) | shape index |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for p in result["points"]:
        phi = "alone" if p["fraction"] is None else f"{p['fraction']:g}"
        box = "-" if p["box_cm"] is None else f"{p['box_cm']:.1f}"
        if p.get("missing"):
            lines.append(f"| {p['radius']:g} | {phi} | {box} | not run | not run | not run |")
            continue
        lines.append(
            f"| {p['radius']:g} | {phi} | {box} | {_pm(p, 'msd_slope', '.3g')} | "
            f"{_pm(p, 'mean_go_duration', '.3g')} | {_pm(p, 'ipr_mean', '.4f')} |"
        )
    lines += [
        "",
        "![D hat and <tau_g> against area fraction](crowding.png)",
        "",
        "*D hat (the long-lag slope of the cells' MSD), the mean go duration <tau_g> and the "
        "mean shape index against the area fraction, per radius; the lone cell at 0. Errors: "
        "standard errors across realizations.*",
        "",
    ]
    return "\n".join(lines)


class Crowding(GridStudy):
    """The crowding study (``softcell study crowding``) in the study protocol.

    Its folder: ``R<R>_phi<phi>/`` holds each point's realizations and ``R<R>_alone/`` the
    lone cell's; ``crowding.json``, ``crowding.md`` and ``crowding.png`` the result. The
    default design is ``FULL`` (about 12 h on 2 cores; ``QUICK`` for a look); ``radius``
    and ``duration`` are the study's own parameters. A grid that cannot run is refused by
    :meth:`CrowdingDesign.check`, a lattice that does not fit its box when planned.
    """

    name = "crowding"
    designs = {"quick": QUICK, "full": FULL}
    flags = ("fractions", "cells")

    def points(self, out, design, parameters):
        return {
            _folder(out, radius, phi): (
                f"R = {radius:g} cm, " + ("alone" if phi is None else f"area fraction {phi:g}"),
                config,
            )
            for (radius, phi), config in _configs(design, parameters).items()
        }

    def measure(self, out, design):
        return measure(out, design)

    def context(self, design, parameters):
        return {"gap_cm": GAP, "discard_s": DISCARD}

    def figure(self, path, result, design):
        from softcell.studies.figures import crowding_figure

        crowding_figure(path, result["points"], design.radii)
        return ""

    def page(self, result, caption):
        return _markdown(result)


STUDY = Crowding()
#: The summary of a crowding study's folder (see :meth:`GridStudy.summarize`).
summarize = STUDY.summarize
#: Run the crowding study into a folder and write its summary (:meth:`GridStudy.run
#: <softcell.studies.protocol.GridStudy.run>`).
crowding = STUDY.run
