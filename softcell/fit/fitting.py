"""A fit, end to end: from data files and priors to a file of posterior samples.

The data are simulation files (a folder of realizations, possibly over several radii, or one
file): their request (parameters and components) is the design every simulation of the fit
repeats, with the unknowns set by the space-filling design; their realizations are
analysed as the design's are, and the statistics of both meet in the emulator's synthetic
likelihood (:mod:`softcell.fit.inference`). The design's simulations are files under
``<fit>_design/``: an interrupted fit resumes where it stopped.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from softcell.engine.interrupt import deferred
from softcell.errors import ConfigError
from softcell.fit.measure import WARMUP
from softcell.fit.priors import Prior, resolve_priors
from softcell.fit.statistics import DEFAULT_STATISTICS, check_statistics, observed
from softcell.model.configuration import RunConfig
from softcell.video.film import Camera

#: The posterior quantiles a fit stores for every unknown: the median and the 90 % interval.
QUANTILES = (0.05, 0.5, 0.95)
#: The fit's root seed for films, unless told otherwise (a film does not know its seed).
FILM_SEED = 1


def data_request(ds) -> tuple[RunConfig, int]:
    """The request (parameters, swept ones as lists, and components) of simulation data, and
    the root seed it was simulated from.

    Raises
    ------
    ConfigError
        For data that are no simulation of one cell, or an assembly (films are read by
        :func:`~softcell.fit.measure.film_request`).
    """
    if ds.attrs.get("softcell_origin") != "simulation":
        raise ConfigError(
            "a fit reads simulation files (softcell simulate); this data is "
            f"{ds.attrs.get('softcell_origin', 'not a softcell file')!r}"
        )
    components = json.loads(ds.attrs["softcell_components"])
    if "cell" in ds.dims or components.get("assembly"):
        raise ConfigError("a fit of an assembly of cells is not supported: fit one cell's data")
    if not components.pop("membrane", True):
        raise ConfigError("a fit needs a cell: the data is a free bot's")
    parameters = json.loads(ds.attrs["softcell_parameters"])
    return RunConfig(parameters=parameters, components=components), int(ds.attrs["softcell_seed"])


def fit(
    data: str | Path | Sequence[str | Path],
    priors: Sequence[str | Prior],
    out: str | Path,
    *,
    prior_table: Mapping[str, Mapping[str, Any]] | None = None,
    config: RunConfig | None = None,
    camera: Camera | Mapping[str, float] | None = None,
    warmup: float = WARMUP,
    statistics: Sequence[str] | None = None,
    simulations: int = 32,
    seed: int | None = None,
    discard: float | None = None,
    check_draws: int = 16,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = print,
) -> Path:
    """Fit the unknowns to simulation data, and write their posterior.

    Parameters
    ----------
    data : path-like or sequence of path-like
        Simulation files (a folder of ``softcell simulate``, or one file), or tracked films
        (``softcell track``: each file a realization, at one radius or several).
    priors : sequence of str or Prior
        The unknowns: ``NAME=LOW:HIGH [UNIT]`` (see :func:`~softcell.fit.priors.parse_prior`).
    out : path-like
        The fit's file (NetCDF); the design's simulations go to ``<out>_design/``.
    prior_table : mapping, optional
        More unknowns, as a configuration file's ``[priors]`` table: ``NAME = {low, high,
        unit?, scale?}`` (see :func:`~softcell.fit.priors.priors_from_table`).
    config : RunConfig, optional
        For films: the model and components of the fit's simulations (default softcell's);
        the films set the radius, the duration and the sampling. Simulation data repeat
        their own request: no ``config``.
    camera : Camera or mapping, optional
        For films: how the fit films its simulations, or some of its settings
        (``px_per_cm``, ``noise``, ``blur``); default: the data's scale and frame rate,
        noise 2 grey levels, blur 1 px.
    warmup : float
        For films: seconds simulated before each design film starts (default 15 s).
    statistics : sequence of str, optional
        What data and simulations are compared by (analysis variables with a value per
        realization; default :data:`~softcell.fit.statistics.DEFAULT_STATISTICS`).
    simulations : int
        Design points (a power of two); each runs as many realizations as the data has.
    seed : int, optional
        The fit's root seed: the design, its simulations, the emulator and the sampler draw
        from it. It must differ from the data's own seed (default: the data's seed + 1).
    discard : float, optional
        Seconds dropped at the start of every realization by the analysis (default: the
        analysis's for simulations, 0 for films).
    check_draws : int
        Posterior draws re-simulated for the predictive check (0: no check); their runs go
        to ``<out>_check/``.
    workers, scheduler
        Local worker processes, or a dask scheduler's address.
    overwrite : bool
        Replace an existing fit file, and recompute design simulations of another request.
    progress : bool
        A progress bar per design point.
    log : callable, optional
        Receives a line per stage.

    Returns
    -------
    Path
        ``out``; the posterior's corner plot is ``out`` with the suffix ``.png``.

    Raises
    ------
    ConfigError
        Before any simulation: for a bad prior, statistic, design size or seed, or data a fit
        cannot read.
    """
    from softcell.analysis import analyze
    from softcell.fit.check import corner_figure, predictive_check
    from softcell.fit.design import run_design, space_filling
    from softcell.fit.inference import fit_emulator, sample_posterior
    from softcell.io.files import check_output
    from softcell.io.netcdf import open_inputs

    say = log or (lambda _: None)
    paths = [Path(data)] if isinstance(data, (str, Path)) else [Path(d) for d in data]
    out = check_output(Path(out), "fit", inputs=paths, overwrite=overwrite)
    figure = check_output(out.with_suffix(".png"), "figure", overwrite=overwrite)
    _check_draws(check_draws)
    ds = open_inputs(paths)
    base, data_seed, measure = _request(ds, config, camera, warmup, discard)
    seed = (FILM_SEED if data_seed is None else data_seed + 1) if seed is None else seed
    if seed == data_seed:
        raise ConfigError(
            f"the data was simulated from seed {data_seed}: the fit's simulations must draw "
            "other random numbers; pass another --seed"
        )
    priors = resolve_priors(priors, prior_table, base.components)
    statistics = check_statistics(DEFAULT_STATISTICS if statistics is None else statistics)
    values = space_filling(priors, simulations, seed)
    seen = observed(analyze(ds, measure.options), statistics)
    realizations = seen.each.shape[1]
    say(f"design: {simulations} points x {realizations} realizations ({seen.each.shape[0]} "
        f"point(s) of the data each), measured from {measure.describe()}")  # fmt: skip
    run = {"workers": workers, "scheduler": scheduler, "progress": progress, "log": log}
    folders = run_design(
        out.parent / f"{out.stem}_design", base, priors, values,
        realizations=realizations, seed=seed, overwrite=overwrite, **run,
    )  # fmt: skip
    say("analysing the design")
    each = measure.statistics(folders, statistics, seed=seed, **run)
    say("emulating the statistics and sampling the posterior")
    emulator = fit_emulator(priors, values, _flat(each), seed=seed)
    draws = sample_posterior(emulator, _flat(seen.each[None])[0], seed=seed)
    result = _dataset(priors, draws, values, each, seen, statistics, base, seed, paths, measure)
    corner_figure(figure, priors, draws)
    for p, (low, _, high) in zip(priors, _intervals(draws), strict=True):
        share = (p.quantile(high) - p.quantile(low)) * 100
        say(f"posterior from {simulations} design points: {p.name} in {low:.4g} .. {high:.4g} "
            f"{p.unit} (90 %; {share:.0f} % of the prior, in its quantiles)")  # fmt: skip
    if check_draws:
        say(f"predictive check: {check_draws} posterior draws re-simulated")
        check = predictive_check(
            out.parent / f"{out.stem}_check", base, priors, draws, seen.each, statistics,
            draws=check_draws, seed=seed, measure=measure, overwrite=overwrite, **run,
        )  # fmt: skip
        result = result.merge(_check_dataset(priors, check))
        _report(say, statistics, check)
    _write(result, out)
    for p, (low, mid, high) in zip(priors, _intervals(draws), strict=True):
        say(f"{p.name} = {mid:.4g} {p.unit} (90 % interval {low:.4g} .. {high:.4g})")
    return out


def _request(ds, config, camera, warmup, discard):
    """The design's request, the data's seed (None for films) and how the design is
    measured, for data ``ds``."""
    from softcell.fit.measure import Direct, film_request

    if ds.attrs.get("softcell_origin") == "tracking":
        options = {"discard": 0.0 if discard is None else float(discard)}
        base, measure = film_request(ds, config, camera=camera, warmup=warmup, options=options)
        return base, None, measure
    for name, given in (("config", config), ("camera", camera)):
        if given is not None:
            raise ConfigError(
                f"a fit of simulation data repeats their request: no {name} (that is for films)"
            )
    base, data_seed = data_request(ds)
    return base, data_seed, Direct({} if discard is None else {"discard": float(discard)})


def _check_draws(value: object) -> None:
    """Refuse a number of check draws that is not 0 or an integer >= 2."""
    if isinstance(value, bool) or not isinstance(value, int) or value == 1 or value < 0:
        raise ConfigError(f"check_draws = {value!r} is not allowed: must be 0 or >= 2")


def _report(say: Callable[[str], None], statistics: Sequence[str], check: dict) -> None:
    """A line per statistic and point of the data: its z and verdict."""
    from softcell.fit.check import VERDICTS

    for k, name in enumerate(statistics):
        for point, z in enumerate(check["z"][:, k]):
            say(f"check {name} (point {point}): z = {z:+.2f}, "
                f"{VERDICTS[check['verdict'][point, k]]}")  # fmt: skip


def _flat(each: np.ndarray) -> np.ndarray:
    """float64[j, point, realization, statistic] -> float64[j, realization, point x
    statistic]: the points of one realization side by side."""
    return np.moveaxis(each, 2, 1).reshape(each.shape[0], each.shape[2], -1)


def _intervals(draws: np.ndarray) -> np.ndarray:
    """float64[unknown, 3]: the 5 %, 50 % and 95 % quantiles of each unknown's draws."""
    return np.quantile(draws, QUANTILES, axis=0).T


def _dataset(priors, draws, values, each, seen, statistics, base, seed, data, measure):
    """The fit as an xarray Dataset with CF attributes."""
    import xarray as xr

    from softcell._version import __version__

    out = xr.Dataset()
    for i, p in enumerate(priors):
        out[p.name] = ("sample", draws[:, i], {
            "units": p.unit, "long_name": f"posterior sample of {p.name}"})  # fmt: skip
        out[f"{p.name}_interval"] = ("quantile", _intervals(draws)[i], {
            "units": p.unit, "long_name": f"posterior quantiles of {p.name}"})  # fmt: skip
        out[f"design_{p.name}"] = ("design_point", values[:, i], {
            "units": p.unit, "long_name": f"{p.name} at each design point"})  # fmt: skip
    out["quantile"] = ("quantile", np.array(QUANTILES), {
        "units": "1", "long_name": "posterior probability below"})  # fmt: skip
    out["design_statistics"] = (("design_point", "point", "realization", "statistic"), each, {
        "units": "1", "long_name": "each design point's statistics per realization "
        "(units: statistic_units)"})  # fmt: skip
    out["data_statistics"] = (("point", "realization", "statistic"), seen.each, {
        "units": "1", "long_name": "the data's statistics per realization "
        "(units: statistic_units)"})  # fmt: skip
    out["statistic"] = ("statistic", np.array(statistics, dtype=object), {
        "long_name": "statistic compared (an analysis variable)"})  # fmt: skip
    out.attrs.update({
        "Conventions": "CF-1.8",
        "title": "softcell fit: posterior samples of the unknowns",
        "softcell_version": __version__,
        "softcell_origin": "fit",
        "softcell_seed": seed,
        "softcell_data": json.dumps([str(d) for d in data]),
        "softcell_measured": measure.describe(),
        "softcell_priors": json.dumps([p.__dict__ for p in priors]),
        "statistic_units": json.dumps(dict(zip(statistics, seen.units, strict=True))),
        "softcell_parameters": json.dumps(base.parameters),
        "softcell_components": json.dumps(base.components),
        "method": "Gaussian-process emulator of the statistics over a scrambled Sobol design, "
        "Gaussian synthetic likelihood, emcee's ensemble sampler",
    })  # fmt: skip
    return out


def _check_dataset(priors, check: dict[str, np.ndarray]):
    """The predictive check as variables of the fit's Dataset."""
    import xarray as xr

    from softcell.fit.check import LIMIT, VERDICTS

    out = xr.Dataset()
    for i, p in enumerate(priors):
        long_name = f"{p.name} of each re-simulated posterior draw"
        out[f"check_{p.name}"] = ("check_draw", check["values"][:, i],
                                  {"units": p.unit, "long_name": long_name})  # fmt: skip
    out["check_statistics"] = (("check_draw", "point", "realization", "statistic"), check["each"], {
        "units": "1", "long_name": "each re-simulated draw's statistics per realization "
        "(units: statistic_units)"})  # fmt: skip
    out["check_z"] = (("point", "statistic"), check["z"], {
        "units": "1", "long_name": "data's mean less the draws' mean, over the draws' "
        "standard deviation"})  # fmt: skip
    out["check_verdict"] = (("point", "statistic"), check["verdict"], {
        "long_name": f"posterior predictive verdict: consistent when |check_z| <= {LIMIT:g}",
        "flag_values": np.arange(len(VERDICTS), dtype=np.int8),
        "flag_meanings": " ".join(VERDICTS)})  # fmt: skip
    return out


def _write(result: Any, out: Path) -> None:
    from softcell.io.files import atomic_write

    with atomic_write(out) as tmp, deferred():
        result.to_netcdf(tmp)
