"""Does softness let a cell through a gap? (``softcell study constriction``)

One cell runs and tumbles in a closed channel cut in two by a partition with a gap of width
w in its middle. The membrane's perimeter is fixed, so to pass a gap narrower than its
diameter 2R the cell must elongate. The study measures, for each radius R and gap w / 2R,
how often the cell passes (passages of its centre from one chamber to the other, per 100 s)
and how elongated it is in the gap.

Everything scales with R (:func:`channel`): two square chambers of side
:data:`CHAMBER` R, walls :data:`WALL` R thick, the partition's centre line at
x_p = CHAMBER R / 2 + WALL R / 2 from the cell's start at the origin (the middle of the left
chamber). A gap of w / 2R = CHAMBER / 2 is no partition at all: the open channel, the
reference. What changes with R at a fixed w / 2R is then the cell's softness (its bending
stiffness is the same, its ring larger) and the size of the bot inside it (6 x 4 cm by
default): a gap below the bot's width 2b lets nothing through.

A passage is counted when the cell's centre, last seen on one side beyond x_p - BAND R, is
next seen beyond x_p + BAND R on the other (:func:`passages`): wiggling in the gap is not
a passage, and the centre is at least :data:`BAND` R through.

Every (R, w) point's realizations draw from the root seed as ``softcell simulate`` draws them
(realization r of gap index p: ``SeedSequence(seed, spawn_key=(p, r))``), for every R alike:
the radii share their random drive (common random numbers).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from softcell.errors import SoftcellError
from softcell.model.obstacle_layout import Wall, obstacle_text
from softcell.studies.protocol import GridStudy

#: Side of each square chamber, in cell radii R.
CHAMBER = 3.0
#: Thickness of the channel's walls and of the partition, in R.
WALL = 0.2
#: How far beyond the partition's centre line the cell's centre must go to count as through,
#: in R.
BAND = 0.5
#: The open channel's gap ratio w / 2R: the gap spans the channel, no partition.
OPEN = CHAMBER / 2
#: Sampling interval of the study's runs (s): enough to see a passage (the cell moves < 0.3 cm
#: in it) at a tenth of the default storage.
SAMPLE_EVERY = 0.1
#: The Poisson 95 % upper limit on a rate from zero counts is -ln(0.05) / T = 3.0 / T.
ZERO_COUNT_LIMIT = -math.log(0.05)


@dataclass(frozen=True)
class ConstrictionDesign:
    """The study's grid.

    Parameters
    ----------
    name : str
        What the grid is called (in the study's summary).
    radii : tuple of float
        Cell radii R (cm).
    gaps : tuple of float
        Gap widths w / 2R (dimensionless), in (0, 1.5]; 1.5 (``OPEN``, the channel's
        width) is no partition.
    realizations : int
        Realizations per (R, gap).
    duration : float
        Duration of each realization (s).
    """

    name: str
    radii: tuple[float, ...]
    gaps: tuple[float, ...]
    realizations: int
    duration: float

    def check(self) -> None:
        """Refuse, in one line naming the value, a grid that cannot be run: an empty grid,
        a gap ratio not in (0, OPEN] (a gap wider than the channel does not fit), a radius
        or duration that is not > 0, fewer than one realization."""
        if not self.radii or not self.gaps:
            raise SoftcellError(f"constriction design {self.name!r}: no radii or no gaps")
        for r in self.radii:
            if not (math.isfinite(r) and r > 0):
                raise SoftcellError(f"constriction radius {r!r} cm: must be > 0")
        for g in self.gaps:
            if not (math.isfinite(g) and 0 < g <= OPEN):
                raise SoftcellError(
                    f"constriction gap w / 2R = {g!r}: must be in (0, {OPEN:g}]; the channel "
                    f"is {CHAMBER:g} R wide, and {OPEN:g} is the open channel"
                )
        if self.realizations < 1:
            raise SoftcellError(f"constriction realizations = {self.realizations}: must be >= 1")
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise SoftcellError(f"constriction duration = {self.duration!r} s: must be > 0")


#: The study as docs/assemblies.md shows it (20 min on 2 cores).
FULL = ConstrictionDesign(
    name="full",
    radii=(4.0, 5.0, 6.0, 7.0),
    gaps=(0.7, 0.8, 0.9, 1.0, 1.1, OPEN),
    realizations=6,
    duration=600.0,
)
#: A look in about a minute on 2 cores: two radii, three gaps, two short realizations.
QUICK = ConstrictionDesign(
    name="quick", radii=(5.0, 7.0), gaps=(0.8, 1.2, OPEN), realizations=2, duration=200.0
)


@dataclass(frozen=True)
class Gate:
    """Where a channel's partition stands: its centre line x (cm) and the band (cm) the
    cell's centre must cross beyond it on either side to count as through."""

    x: float
    band: float


def channel(radius: float, gap: float) -> tuple[str, Gate]:
    """The obstacles of the channel for a cell of radius ``radius`` (cm) with a gap of
    ``gap`` x 2R, as the parameter ``obstacles`` (cm), and its :class:`Gate`.

    The gap is the distance between the partition walls' round ends, surface to surface.
    """
    t = WALL * radius
    half = CHAMBER * radius / 2
    x_gate = half + t / 2
    left, right, y = -half - t / 2, x_gate + t / 2 + CHAMBER * radius + t / 2, half + t / 2
    walls = [(left, -y, right, -y), (left, y, right, y), (left, -y, left, y), (right, -y, right, y)]
    if gap < OPEN:
        tip = gap * radius + t / 2
        walls += [(x_gate, -y, x_gate, -tip), (x_gate, y, x_gate, tip)]
    # Six significant digits: the walls' entries read as they always have.
    placed = [Wall(*(float(f"{v:.6g}") for v in (*w, t))) for w in walls]
    return obstacle_text(placed), Gate(x=x_gate, band=BAND * radius)


def passages(x: np.ndarray, gate: Gate) -> int:
    """Passages of a track ``x`` (cm, along time) through ``gate``: the times the track,
    last beyond ``gate.x - gate.band`` on one side, is next beyond ``gate.x + gate.band`` on
    the other (NaN samples are skipped)."""
    return int(passage_samples(x, gate).size)


def passage_samples(x: np.ndarray, gate: Gate) -> np.ndarray:
    """The sample indices at which the track ``x`` (cm) completes a passage through
    ``gate`` (see :func:`passages`)."""
    x = np.asarray(x, dtype=np.float64)
    side = np.where(x < gate.x - gate.band, -1, np.where(x > gate.x + gate.band, 1, 0))
    beyond = np.flatnonzero((side != 0) & np.isfinite(x))
    return beyond[1:][np.diff(side[beyond]) != 0]


def _config(design: ConstrictionDesign, radius: float, parameters: dict[str, Any]):
    """The request for every gap of ``design`` at ``radius``: one parameter point per gap."""
    from softcell.model.configuration import RunConfig, with_obstacle_term

    return with_obstacle_term(
        RunConfig(
            parameters={
                **parameters,
                "radius": radius,
                "duration": design.duration,
                "sample_every": SAMPLE_EVERY,
                "sample_every_late": SAMPLE_EVERY,
                "obstacles": [channel(radius, g)[0] for g in design.gaps],
            }
        )
    )


def _folder(out: Path, radius: float) -> Path:
    return out / f"R{radius:g}"


# -- what the runs measured ---------------------------------------------------------------------


def _in_gap(radius: float) -> float:
    """Half-width (cm) of the window about the partition's centre line in which the cell's
    centre counts as in the gap (a quarter radius)."""
    return 0.25 * radius


def measure_point(paths: Sequence[Path], radius: float, gap: float) -> dict[str, Any]:
    """One (R, w) point from its realizations' files: passages per realization, simulated
    seconds, the rate per 100 s (mean over realizations, its standard error across them, and
    the Poisson 95 % upper limit when none passed), and the membrane's shape index
    P / sqrt(A) (2 sqrt(pi) for a circle) with the centre in the gap and elsewhere."""
    import xarray as xr

    from softcell.analysis.series import shape_index

    _, gate = channel(radius, gap)
    counts, seconds, in_gap, elsewhere = [], [], [], []
    for path in paths:
        with xr.open_dataset(path) as ds:
            x = ds["cell_x"].values.reshape(-1)
            time = ds["time"].values
            ipr = shape_index(
                ds["membrane_x"].values[0], ds["membrane_y"].values[0], band_limited=True
            )
        counts.append(passages(x, gate))
        seconds.append(float(time[-1] - time[0]))
        near = np.abs(x - gate.x) < _in_gap(radius)
        in_gap.append(ipr[near])
        elsewhere.append(ipr[~near])
    rates = 100.0 * np.array(counts) / np.array(seconds)
    n = len(rates)
    sem = float(np.std(rates, ddof=1) / math.sqrt(n)) if n > 1 else math.nan
    gap_samples = np.concatenate(in_gap)
    return {
        "radius": radius,
        "gap": gap,
        "gap_cm": 2 * gap * radius,
        "passages": counts,
        "seconds": seconds,
        "rate": float(rates.mean()),
        "rate_sem": sem,
        "rate_upper_95": (
            100.0 * ZERO_COUNT_LIMIT / float(np.sum(seconds)) if sum(counts) == 0 else None
        ),
        "shape_index_in_gap": float(gap_samples.mean()) if gap_samples.size else None,
        "samples_in_gap": int(gap_samples.size),
        "shape_index_elsewhere": float(np.concatenate(elsewhere).mean()),
    }


def measure(out: Path, design: ConstrictionDesign) -> list[dict[str, Any]]:
    """Every point of ``design`` in ``out``, radius by radius, gap by gap, each with its
    :func:`transmission` when the grid has the open channel."""
    points = []
    for radius in design.radii:
        folder = _folder(out, radius)
        mine = []
        for p, gap in enumerate(design.gaps):
            paths = [
                folder / f"point{p:03d}_realization{r:04d}.nc" for r in range(design.realizations)
            ]
            mine.append(measure_point(paths, radius, gap))
        reference = next((q for q in mine if q["gap"] >= OPEN), None)
        points += [{**q, **transmission(q, reference)} for q in mine]
    return points


def transmission(point: dict[str, Any], reference: dict[str, Any] | None) -> dict[str, Any]:
    """The rate of ``point`` over the open channel's (``reference``) at the same radius:
    ``transmission`` with its standard error (the two relative errors added in quadrature)
    or, when no cell passed, ``transmission_upper_95`` (the rate's 95 % limit over the open
    rate); the reference itself is 1 without an error. All None without a reference or when
    nothing passed the open channel either."""
    none = {"transmission": None, "transmission_sem": None, "transmission_upper_95": None}
    if reference is None or reference["rate"] <= 0:
        return none
    if point is reference:
        return {**none, "transmission": 1.0}  # by definition
    ratio = point["rate"] / reference["rate"]
    if point["rate_upper_95"] is not None:
        return {**none, "transmission_upper_95": point["rate_upper_95"] / reference["rate"]}
    relative = [
        (q["rate_sem"] / q["rate"]) if q["rate_sem"] is not None and q["rate"] > 0 else math.nan
        for q in (point, reference)
    ]
    return {**none, "transmission": ratio, "transmission_sem": ratio * math.hypot(*relative)}


def _rate_text(point: dict[str, Any]) -> str:
    if point["rate_upper_95"] is not None:
        return f"0 (< {point['rate_upper_95']:.2g} at 95 %)"
    return f"{point['rate']:.3g} ± {point['rate_sem']:.2g}"


def _transmission_text(point: dict[str, Any]) -> str:
    if point["transmission_upper_95"] is not None:
        return f"< {point['transmission_upper_95']:.2g}"
    if point["transmission"] is None:
        return "-"
    if point["transmission_sem"] is None:
        return "1 (by definition)"
    return f"{point['transmission']:.2f} ± {point['transmission_sem']:.2f}"


def _markdown(result: dict[str, Any], caption: str) -> str:
    design = result["design"]
    lines = [
        "# A cell at a constriction",
        "",
        f"softcell {result['version']}, root seed {result['seed']}, design "
        f"{design['name']!r}: {design['realizations']} realizations of "
        f"{design['duration']:g} s per point. Channel: two square chambers of side "
        f"{CHAMBER:g} R, walls {WALL:g} R thick; a passage is the cell's centre going from "
        f"{BAND:g} R before the partition to {BAND:g} R beyond it. Rates are means over "
        "realizations with their standard error across them; a point where no cell passed "
        "gives the Poisson 95 % upper limit. 'Over the open channel' divides by the rate of "
        "the same radius with no partition (errors in quadrature), so that it compares how a "
        "gap hinders cells of different mobility. The shape index P / sqrt(A) is 3.5449 "
        "for a circle; 'in the gap' averages the samples with the centre within R / 4 of "
        "the partition.",
        "",
        "| R (cm) | w / 2R | w (cm) | passages | rate (per 100 s) | over the open channel "
        "| shape index in gap (samples) | shape index elsewhere |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for p in result["points"]:
        gap = "open" if p["gap"] >= OPEN else f"{p['gap']:g}"
        inside = "-" if p["shape_index_in_gap"] is None else f"{p['shape_index_in_gap']:.4f}"
        lines.append(
            f"| {p['radius']:g} | {gap} | {p['gap_cm']:.3g} | {sum(p['passages'])} | "
            f"{_rate_text(p)} | {_transmission_text(p)} | {inside} ({p['samples_in_gap']}) | "
            f"{p['shape_index_elsewhere']:.4f} |"
        )
    lines += [
        "",
        "![passage rate and shape in the gap](constriction.png)",
        "",
        "*(a) Passages per 100 s against the gap, per radius (errors: standard error across "
        "realizations; open triangles: the 95 % upper limit where no cell passed). (b) The "
        "same over the open channel's rate at that radius. (c) The membrane's shape index with "
        f"its centre in the gap (a circle: 2 sqrt(pi) = 3.5449). {caption}*",
        "",
    ]
    return "\n".join(lines)


class Constriction(GridStudy):
    """The constriction study (``softcell study constriction``) in the study protocol.

    Its folder: ``R<radius>/`` holds each radius's simulations (one file per gap and
    realization); ``constriction.json``, ``constriction.md`` and ``constriction.png`` the
    result. The default design is ``FULL`` (the grid docs/assemblies.md shows); ``radius``,
    ``duration``, ``obstacles`` and the sampling are the study's own parameters. A grid
    that cannot run is refused by :meth:`ConstrictionDesign.check`.
    """

    name = "constriction"
    designs = {"quick": QUICK, "full": FULL}
    own = ("radius", "duration", "obstacles", "sample_every", "sample_every_late")
    flags = ("gaps",)

    def points(self, out, design, parameters):
        return {
            _folder(out, r): (
                f"R = {r:g} cm, {len(design.gaps)} gaps",
                _config(design, r, parameters),
            )
            for r in design.radii
        }

    def measure(self, out, design):
        return measure(out, design)

    def context(self, design, parameters):
        from softcell.model.parameters import MODEL_PARAMETERS

        semi_minor = parameters.get("bot_semi_minor", MODEL_PARAMETERS["bot_semi_minor"].default)
        return {
            "geometry": {"chamber_R": CHAMBER, "wall_R": WALL, "band_R": BAND, "open_gap": OPEN},
            "bot_width_cm": 2 * float(semi_minor),
        }

    def figure(self, path, result, design):
        from softcell.studies.figures import constriction_figure

        return constriction_figure(
            path, result["points"], design.radii, OPEN, result["bot_width_cm"]
        )

    def page(self, result, caption):
        return _markdown(result, caption)


STUDY = Constriction()
#: The summary of a constriction study's folder (see :meth:`GridStudy.summarize`).
summarize = STUDY.summarize
#: Run the constriction study into a folder and write its summary (:meth:`GridStudy.run
#: <softcell.studies.protocol.GridStudy.run>`).
constriction = STUDY.run
