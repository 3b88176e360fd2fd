"""Several bots in one ring: the ring's collective state and motion against the number of
bots (``softcell study bots``).

K bots run and tumble in one ring of radius R, elongated (semi-axes 1.8 x 0.9 cm) or round
(radius 1.27 cm, the same area), with or without the built-in ``alignment`` (J = 500 N cm;
the bots always repel with ``bot_repulsion``). They start on the lattice of
:func:`~softcell.model.bots.place_bots` with :data:`GAP` cm between them; a (R, K) whose
bots the lattice cannot hold is left out and said so. One bot is today's single-bot run.
Each realization is analysed alone (the first :data:`DISCARD` s dropped); a point reports the
mean over realizations and the standard error across them of the bots' boundary fraction, the
membrane's asphericity, the bots' polar order, and the cell's speed v, persistence time tau_p
and D hat from the persistent random walk fit to the cell's MSD (:func:`persistent_walk`).
The analysis' own fits of the MSD place their windows at multiples of the cell's mean go
time, which with many bots is the record's length (the cell hardly stops): they are left
aside here.

Then each published trend is judged by a rule that can fail (:func:`trends`): a difference
"agrees" when it has the published sign and exceeds twice its standard error (the two
points' errors combined), "disagrees" when it exceeds that with the other sign, and is
"undecided" otherwise.

Realization r of every point draws from ``SeedSequence(seed, spawn_key=(0, r, ...))``: the
points share their drives bot by bot (bot 0 is the single-bot run's stream).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from softcell.errors import SoftcellError
from softcell.studies.protocol import GridStudy

#: Starting gap between bots, and between a bot and the ring (cm).
GAP = 0.3
#: Seconds dropped at the start of each realization before the analysis (s).
DISCARD = 10.0
#: The bots' shapes: semi-axes a, b (cm), of one area.
SHAPES = {"elongated": (1.8, 0.9), "round": (1.2728, 1.2728)}
#: The aligning torque of the runs with alignment (N cm); 0 is none.
ALIGNMENT = 500.0
#: What a point measures, from each realization's analysis: name -> (where, unit, label).
QUANTITIES = {
    "boundary_fraction": ("bots_boundary_fraction", "1", "bots within 2 a of the membrane"),
    "asphericity": ("membrane_asphericity", "1", "membrane asphericity"),
    "polar_order": ("bots_polar_order", "1", "polar order of the bots"),
    "velocity": ("walk", "cm s-1", "cell's speed v of the persistent walk fit"),
    "persistence": ("walk", "s", "cell's persistence time tau_p of the fit"),
    "d_hat": ("walk", "cm2 s-1", "cell's D hat = 2 v^2 tau_p of the fit"),
}


@dataclass(frozen=True)
class BotsDesign:
    """The study's grid.

    Parameters
    ----------
    name : str
        What the grid is called.
    radii : tuple of float
        Ring radii R (cm).
    counts : tuple of int
        Numbers of bots K (1 is the single-bot run).
    shapes : tuple of str
        Names of :data:`SHAPES`.
    alignments : tuple of float
        Aligning torques J (N cm); 0 runs without alignment.
    realizations : int
        Realizations per point, >= 2 for an error.
    duration : float
        Duration of each realization (s).
    """

    name: str
    radii: tuple[float, ...]
    counts: tuple[int, ...]
    shapes: tuple[str, ...]
    alignments: tuple[float, ...]
    realizations: int
    duration: float

    def check(self) -> None:
        """Refuse, in one line naming the value, a grid that cannot be run."""
        if not (self.radii and self.counts and self.shapes and self.alignments):
            raise SoftcellError(f"bots design {self.name!r}: an empty list")
        _check_values(self)
        if self.realizations < 2:
            raise SoftcellError(f"bots realizations = {self.realizations}: must be >= 2")
        if not (math.isfinite(self.duration) and self.duration > DISCARD + 20):
            raise SoftcellError(
                f"bots duration = {self.duration!r} s: must exceed the discard of "
                f"{DISCARD:g} s by at least 20 s"
            )


def _check_values(design: BotsDesign) -> None:
    """Refuse a radius, count, shape or aligning torque out of range, naming it."""
    for r in design.radii:
        if not (math.isfinite(r) and r > 0):
            raise SoftcellError(f"bots radius {r!r} cm: must be > 0")
    for k in design.counts:
        if not (isinstance(k, int) and 1 <= k <= 200):
            raise SoftcellError(f"bots count {k!r}: must be an integer from 1 to 200")
    for s in design.shapes:
        if s not in SHAPES:
            raise SoftcellError(f"bots shape {s!r}: must be one of {', '.join(SHAPES)}")
    for j in design.alignments:
        if not (math.isfinite(j) and j >= 0):
            raise SoftcellError(f"bots alignment {j!r} N cm: must be >= 0")


#: The full grid (not yet run: its cost is estimated in docs/results/bots).
FULL = BotsDesign(
    name="full",
    radii=(8.0, 12.0, 20.0),
    counts=(1, 2, 4, 8, 16, 32),
    shapes=("elongated", "round"),
    alignments=(0.0, ALIGNMENT),
    realizations=3,
    duration=120.0,
)
#: Every radius and up to 32 elongated bots, two realizations of 60 s (docs/bots.md).
MEDIUM = BotsDesign(
    name="medium",
    radii=(8.0, 12.0, 20.0),
    counts=(1, 4, 16, 32),
    shapes=("elongated",),
    alignments=(0.0, ALIGNMENT),
    realizations=2,
    duration=60.0,
)
#: A look: one ring of 12 cm, 1, 4 and 16 bots.
QUICK = BotsDesign(
    name="quick",
    radii=(12.0,),
    counts=(1, 4, 16),
    shapes=("elongated", "round"),
    alignments=(0.0, ALIGNMENT),
    realizations=2,
    duration=60.0,
)


def _label(radius: float, shape: str, count: int, alignment: float) -> str:
    aligned = "" if count == 1 else ("_aligned" if alignment > 0 else "_free")
    return f"R{radius:g}_{shape}_K{count}{aligned}"


def fits(radius: float, shape: str, count: int) -> bool:
    """Whether the lattice holds ``count`` bots of ``shape`` in a ring of ``radius`` (cm),
    taken as its starting radius."""
    from softcell.model.bots import lattice_sites

    a, b = SHAPES[shape]
    return count == 1 or len(lattice_sites(radius, a, b, GAP)) >= count


def _grid(design: BotsDesign):
    """Every (radius, shape, count, alignment) of ``design``: one bot once per (R, shape)."""
    for radius in design.radii:
        for shape in design.shapes:
            for count in design.counts:
                for alignment in (0.0,) if count == 1 else design.alignments:
                    yield radius, shape, count, alignment


def _config(parameters: dict[str, Any], design: BotsDesign, point: tuple) -> Any:
    from softcell.model.configuration import RunConfig

    radius, shape, count, alignment = point
    a, b = SHAPES[shape]
    values = {**parameters, "radius": radius, "duration": design.duration}
    values.update(bot_semi_major=a, bot_semi_minor=b)
    if count == 1:
        return RunConfig(parameters=values)
    interactions = ["bot_repulsion"] + (["alignment"] if alignment > 0 else [])
    if alignment > 0:
        values["alignment_strength"] = alignment
    bots = {"count": count, "placement": "lattice", "gap": GAP, "interactions": interactions}
    return RunConfig(parameters=values, bots=bots)


# -- what the runs measured -----------------------------------------------------------------


def measure_point(folder: Path, realizations: int, a: float) -> dict[str, Any]:
    """One point from its realizations, each analysed alone (the first :data:`DISCARD` s
    dropped): the mean, standard error across realizations (``_sem``) and every value
    (``_each``) of each of :data:`QUANTITIES`."""
    from softcell.analysis import analyze
    from softcell.analysis.bots import ring_statistics
    from softcell.errors import AnalysisWarning
    from softcell.io.netcdf import open_dataset

    values: dict[str, list[float]] = {key: [] for key in QUANTITIES}
    for r in range(realizations):
        ds = open_dataset(folder / f"point000_realization{r:04d}.nc")
        with warnings.catch_warnings():  # one realization: the errors are across them, here
            warnings.simplefilter("ignore", AnalysisWarning)
            analysis = analyze(ds, {"discard": DISCARD})
        collective = [where for where, _, _ in QUANTITIES.values() if where.startswith(
            ("bots_", "membrane_"))]  # fmt: skip
        if "bot" in ds.dims:
            ring = {where: float(analysis[where]) for where in collective}
        else:  # one bot: the ring's statistics of its one bot
            keep = np.flatnonzero(ds["time"].values >= DISCARD)
            one = ds.isel(realization=0, time=keep)
            one = one.assign({n: one[n].expand_dims(bot=1, axis=-1) for n in _BOT_VARIABLES})
            stats = ring_statistics(one, a)
            ring = {where: float(stats[where]) for where in collective}
        msd = analysis["msd_realization"].sel(body="cell")
        msd = msd.isel(bot=0) if "bot" in msd.dims else msd  # every bot's cell is one
        walk = persistent_walk(analysis["lag"].values, np.ravel(msd.values))
        for key, (where, _, _) in QUANTITIES.items():
            values[key].append(ring[where] if where in ring else walk[key])
    point: dict[str, Any] = {}
    for key, each in values.items():
        v = np.array(each)
        v = v[np.isfinite(v)]
        point[key] = float(v.mean()) if v.size else math.nan
        point[f"{key}_sem"] = float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan
        point[f"{key}_each"] = each
    return point


_BOT_VARIABLES = ("bot_x", "bot_y", "bot_angle")


def persistent_walk(lag: np.ndarray, msd: np.ndarray) -> dict[str, float]:
    """The persistent random walk fit to an MSD (cm^2) at ``lag`` (s):
    MSD = 2 v^2 tau_p (tau - tau_p (1 - exp(-tau / tau_p))) (2D), least squares in log MSD
    over every lag with a finite, positive value. Returns ``velocity`` v (cm/s),
    ``persistence`` tau_p (s) and ``d_hat`` = 2 v^2 tau_p (cm^2/s, the long-lag slope);
    NaN when fewer than 4 lags hold a value or the fit fails."""
    from scipy.optimize import least_squares

    ok = (lag > 0) & np.isfinite(msd) & (msd > 0)
    nan = {"velocity": math.nan, "persistence": math.nan, "d_hat": math.nan}
    if ok.sum() < 4:
        return nan
    t, m = lag[ok], msd[ok]

    def residual(p):
        v, tau = math.exp(p[0]), math.exp(p[1])
        model = 2 * v * v * tau * (t - tau * -np.expm1(-t / tau))
        return np.log(np.maximum(model, 1e-300)) - np.log(m)

    start = [math.log(math.sqrt(m[0]) / t[0]), math.log(max(t[len(t) // 4], t[0]))]
    fit = least_squares(residual, start)
    if not fit.success:
        return nan
    v, tau = math.exp(fit.x[0]), math.exp(fit.x[1])
    return {"velocity": v, "persistence": tau, "d_hat": 2 * v * v * tau}


def uniform_boundary_fraction(radius: float, a: float, b: float) -> float:
    """The boundary fraction of bots spread evenly over the disc their centres can reach
    (radius R - b, cm): the share of it within 2 a of the ring, 1 - ((R - 2 a) / (R - b))^2."""
    inner = max(radius - 2 * a, 0.0)
    return 1.0 - (inner / (radius - b)) ** 2


def measure(out: Path, design: BotsDesign) -> list[dict[str, Any]]:
    """Every point of ``design`` in ``out``; one the lattice cannot hold is marked
    ``does_not_fit``, one whose realizations are not all there ``missing``."""
    points = []
    for radius, shape, count, alignment in _grid(design):
        a, b = SHAPES[shape]
        point = {
            "radius": radius,
            "shape": shape,
            "count": count,
            "alignment": alignment,
            "per_area": count / (math.pi * radius**2),
            "uniform_boundary_fraction": uniform_boundary_fraction(radius, a, b),
        }
        folder = out / _label(radius, shape, count, alignment)
        files = [folder / f"point000_realization{r:04d}.nc" for r in range(design.realizations)]
        if not fits(radius, shape, count):
            points.append({**point, "does_not_fit": True})
        elif all(f.is_file() for f in files):
            points.append({**point, **measure_point(folder, design.realizations, a)})
        else:
            points.append({**point, "missing": True})
    return points


def _compare(first: dict, second: dict, key: str) -> tuple[float, float]:
    """second - first and its standard error (the two errors combined)."""
    diff = second[key] - first[key]
    return diff, math.hypot(first[f"{key}_sem"], second[f"{key}_sem"])


def _verdict(diff: float, error: float, sign: int) -> str:
    if not (math.isfinite(diff) and math.isfinite(error)):
        return "undecided"
    if sign * diff > 2 * error:
        return "agrees"
    if -sign * diff > 2 * error:
        return "disagrees"
    return "undecided"


def trends(points: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each published trend, judged at every pair of points it compares (see the module's
    docstring): the comparisons and how many agree, disagree or are undecided."""
    ran = [p for p in points if not p.get("missing") and not p.get("does_not_fit")]
    return [
        _rule("bots gather at the membrane: boundary fraction above an even spread's",
              "Paoluzzi et al. 2016; Deblais et al. 2018", _gathering(ran)),
        _rule("the ring is rounder with more bots: asphericity falls with K",
              "Paoluzzi et al. 2016", _rounding(ran)),
        _rule("elongated bots move the ring farther: D hat above round bots'",
              "Paoluzzi et al. 2016",
              _against(ran, "d_hat", lambda p: p["shape"] == "elongated" and p["count"] >= 2,
                       {"shape": "round"})),
        _rule("aligned bots drive the ring faster: v above the free bots'",
              "Uplap et al. 2023; Quillen et al. 2020",
              _against(ran, "velocity", lambda p: p["alignment"] > 0, {"alignment": 0.0})),
        _rule("more bots drive the ring faster: v above one bot's", "Deblais et al. 2018",
              _against(ran, "velocity", lambda p: p["count"] >= 2,
                       {"count": 1, "alignment": 0.0})),
    ]  # fmt: skip


def _gathering(ran: list[dict]) -> list:
    """Each point of two or more bots against an even spread of them."""
    return [
        (p, p["boundary_fraction"] - p["uniform_boundary_fraction"], p["boundary_fraction_sem"], 1)
        for p in ran
        if p["count"] >= 2
    ]


def _rounding(ran: list[dict]) -> list:
    """Each point against every point of more bots, the rest alike: asphericity falls."""
    checks = []
    for p in ran:
        for q in ran:
            if _same(q, p, "radius", "shape", "alignment") and q["count"] > p["count"] >= 2:
                diff, error = _compare(p, q, "asphericity")
                checks.append((q, diff, error, -1))
    return checks


def _against(ran: list[dict], key: str, chosen, other: dict) -> list:
    """Each chosen point against the point that differs from it by ``other``: ``key``
    higher (the chosen minus the other, sign +1)."""
    checks = []
    for p in ran:
        if not chosen(p):
            continue
        wanted = {k: p[k] for k in ("radius", "shape", "count", "alignment")} | other
        q = next((q for q in ran if all(q[k] == v for k, v in wanted.items())), None)
        if q is not None:
            diff, error = _compare(q, p, key)
            checks.append((p, diff, error, 1))
    return checks


def _same(p: dict, q: dict, *keys: str) -> bool:
    return all(p[k] == q[k] for k in keys)


def _rule(claim: str, source: str, checks: list) -> dict[str, Any]:
    compared = []
    for p, diff, error, sign in checks:
        compared.append(
            {
                "point": _label(p["radius"], p["shape"], p["count"], p["alignment"]),
                "difference": diff,
                "error": error,
                "verdict": _verdict(diff, error, sign),
            }
        )
    counts = {v: sum(c["verdict"] == v for c in compared) for v in
              ("agrees", "disagrees", "undecided")}  # fmt: skip
    return {"claim": claim, "source": source, "comparisons": compared, **counts}


def _pm(p: dict, key: str, spec: str) -> str:
    return f"{p[key]:{spec}} ± {p[key + '_sem']:.2g}"


def _markdown(result: dict[str, Any]) -> str:
    design = result["design"]
    lines = [
        "# Several bots in one ring",
        "",
        f"softcell {result['version']}, root seed {result['seed']}, design "
        f"{design['name']!r}: {design['realizations']} realizations of "
        f"{design['duration']:g} s per point, the first {DISCARD:g} s dropped; bots start on "
        f"a lattice {GAP:g} cm apart. Elongated bots are 1.8 x 0.9 cm (semi-axes), round ones "
        f"1.27 cm in radius (the same area); aligned bots feel the built-in alignment, J = "
        f"{ALIGNMENT:g} N cm. Values: means over realizations ± the standard error across "
        "them. 'even' is the boundary fraction of bots spread evenly over the disc their "
        "centres can reach.",
        "",
        "| R (cm) | bots | K | boundary fraction (even) | asphericity | polar order | "
        "v (cm/s) | tau_p (s) | D hat (cm2/s) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for p in result["points"]:
        kind = p["shape"] + ("" if p["count"] == 1 else
                             (", aligned" if p["alignment"] > 0 else ", free"))  # fmt: skip
        head = f"| {p['radius']:g} | {kind} | {p['count']} |"
        if p.get("does_not_fit") or p.get("missing"):
            why = "do not fit the lattice" if p.get("does_not_fit") else "not run"
            lines.append(f"{head} {why} | | | | | | |")
            continue
        lines.append(
            f"{head} {_pm(p, 'boundary_fraction', '.2f')} "
            f"({p['uniform_boundary_fraction']:.2f}) | {_pm(p, 'asphericity', '.3g')} | "
            f"{_pm(p, 'polar_order', '.2f')} | {_pm(p, 'velocity', '.3g')} | "
            f"{_pm(p, 'persistence', '.3g')} | {_pm(p, 'd_hat', '.3g')} |"
        )
    lines += [
        "",
        "![The ring against the number of bots](bots.png)",
        "",
        "*Against the bots per area of the ring (K / pi R^2): (a) the bots' boundary fraction "
        "(dashed: an even spread), (b) the membrane's asphericity, (c) the bots' polar order, "
        "(d) the cell's speed v, (e) its persistence time tau_p and (f) its D hat = 2 v^2 tau_p, "
        "from the persistent random walk fit MSD = 2 v^2 tau_p (tau - tau_p (1 - "
        "exp(-tau / tau_p))) to the cell's MSD (lags to half the analysed record). The polar "
        "order of one bot is 1 by construction. Errors: standard errors across realizations.*",
        "",
        "## The published trends, judged",
        "",
        "A comparison agrees when its difference has the published sign and exceeds twice its "
        "standard error, disagrees when it exceeds that with the other sign, and is undecided "
        "otherwise.",
        "",
        "| claim | source | agrees | disagrees | undecided |",
        "| --- | --- | --- | --- | --- |",
    ]
    for rule in result["trends"]:
        lines.append(
            f"| {rule['claim']} | {rule['source']} | {rule['agrees']} | {rule['disagrees']} | "
            f"{rule['undecided']} |"
        )
    lines.append("")
    return "\n".join(lines)


class BotsStudy(GridStudy):
    """The study of several bots in one ring (``softcell study bots``) in the study protocol.

    Its folder: ``R<R>_<shape>_K<K>_<aligned|free>/`` holds each point's realizations
    (``R<R>_<shape>_K1/`` the single bot's); ``bots.json``, ``bots.md`` and ``bots.png`` the
    result. The default design is ``FULL``; ``QUICK`` for a look.
    """

    name = "bots"
    designs = {"quick": QUICK, "full": FULL}
    flags = ("counts",)

    def points(self, out, design, parameters):
        return {
            out / _label(*point): (
                f"R = {point[0]:g} cm, {point[2]} {point[1]} bot(s)"
                + ("" if point[2] == 1 else (", aligned" if point[3] > 0 else ", free")),
                _config(parameters, design, point),
            )
            for point in _grid(design)
            if fits(point[0], point[1], point[2])
        }

    def measure(self, out, design):
        return measure(out, design)

    def context(self, design, parameters):
        return {"gap_cm": GAP, "discard_s": DISCARD, "shapes_cm": SHAPES}

    def conclusions(self, points, design):
        return {"trends": trends(points)}

    def figure(self, path, result, design):
        from softcell.studies.figures import bots_figure

        bots_figure(path, result["points"])
        return ""

    def page(self, result, caption):
        return _markdown(result)


STUDY = BotsStudy()
#: The summary of a bots study's folder (see :meth:`GridStudy.summarize`).
summarize = STUDY.summarize
#: Run the bots study into a folder and write its summary.
bots = STUDY.run
