"""The cost and the calibration of a fit (2 cores).

Cost: the issue's target, one unknown (k) from six films of 120 s at R = 5 cm within 20
min on 2 cores, and what a second unknown (gamma_mem) adds. The films are made once, outside
the timings, from a simulation of a known k (0.2 N cm2) and gamma_mem (the default,
3.42e-4 N s cm-2): filmed with the paper's camera (10 px/cm, 30 frames/s, noise 2, blur 1)
and tracked, in memory (the same Dataset as ``softcell render`` then ``softcell track``, a
test holds). Each fit runs with ``softcell fit``'s defaults for films but a design of 8
points per unknown and 4 check draws.

Calibration on the model itself: 40 data sets of simulation data at truths drawn from the
prior (4 realizations of 40 s at R = 5 cm, k log-uniform on 0.05 .. 0.8 N cm2), fitted
by 4 designs of 16 points (10 data sets each, each design from its own seed); the 90 %
intervals should hold their truth a binomial number of times (99 % band: 30 to 40 of 40).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

TRUTH = {"bending_stiffness": 0.2, "membrane_friction": 3.42e-4}
FILMS, FILM, WARMUP = 6, 120.0, 15.0


def _films(folder: Path) -> list[Path]:
    from softcell.io.netcdf import open_dataset, write_dataset
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate
    from softcell.video.film import Camera, filmed

    config = RunConfig(parameters={"radius": 5.0, "duration": WARMUP + FILM + 1, **TRUTH})
    simulate(config, folder / "cell", realizations=FILMS, seed=21, progress=False)
    ds = open_dataset(folder / "cell")
    paths = []
    for r in range(FILMS):
        tracked = filmed(ds, camera=Camera(), start=WARMUP, end=WARMUP + FILM, seed=300 + r,
                         realization=r, radius=5.0)  # fmt: skip
        paths.append(write_dataset(tracked, folder / f"tracked{r}.nc"))
    return paths


def _fit(films: list[Path], priors: list[str], out: Path) -> tuple[float, str]:
    import xarray as xr

    from softcell.fit.fitting import fit

    start = time.perf_counter()
    fit(films, priors, out, simulations=8 * len(priors), check_draws=4, workers=2,
        progress=False, log=None)  # fmt: skip
    wall = time.perf_counter() - start
    result = xr.open_dataset(out)
    held = []
    for name, truth in TRUTH.items():
        if name in result:
            low, mid, high = result[f"{name}_interval"].values
            held.append(f"{name} {mid:.3g} ({low:.3g}..{high:.3g}, truth {truth:g})")
    return wall, "; ".join(held)


def _coverage(folder: Path) -> tuple[int, int, float]:
    from softcell.fit.design import run_design, space_filling, statistics_of
    from softcell.fit.fitting import _flat
    from softcell.fit.inference import fit_emulator, sample_posterior
    from softcell.fit.priors import Prior
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    prior = Prior("bending_stiffness", 0.05, 0.8, "N cm2", "log")
    base = RunConfig(parameters={"radius": 5.0, "duration": 40.0})
    statistics = ("mean_speed", "diffusion_coefficient", "mean_go_duration",
                  "mean_stop_duration", "ipr_mean")  # fmt: skip
    options = {"discard": 5.0}
    rng = np.random.default_rng(7)
    held = trials = 0
    start = time.perf_counter()
    for design in range(4):
        seed = 1000 + design
        values = space_filling([prior], 16, seed)
        folders = run_design(folder / f"design{design}", base, [prior], values,
                             realizations=4, seed=seed, workers=2, progress=False)  # fmt: skip
        each = statistics_of(folders, statistics, options)
        emulator = fit_emulator([prior], values, _flat(each), seed=seed)
        for trial in range(10):
            truth = float(prior.value(rng.uniform()))
            data = folder / f"data{design}_{trial}"
            config = base.updated(parameters={"bending_stiffness": truth})
            simulate(config, data, realizations=4, seed=50_000 + 10 * design + trial,
                     workers=2, progress=False)  # fmt: skip
            seen = statistics_of([data], statistics, options)
            draws = sample_posterior(emulator, _flat(seen)[0], seed=seed + trial)
            low, high = np.quantile(draws[:, 0], [0.05, 0.95])
            held += int(low <= truth <= high)
            trials += 1
    return held, trials, time.perf_counter() - start


def rows() -> list[dict[str, object]]:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        films = _films(folder)
        one, one_note = _fit(films, ["bending_stiffness=0.05:0.8"], folder / "one.nc")
        two, two_note = _fit(
            films, ["bending_stiffness=0.05:0.8", "membrane_friction=1.5e-4:8e-4"],
            folder / "two.nc",
        )  # fmt: skip
        held, trials, coverage_wall = _coverage(folder)
    return [
        {
            "benchmark": "fit k, six 120 s films, R = 5 cm",
            "value": one / 60,
            "unit": "wall min",
            "target": 20,
            "note": f"2 workers; 8 design points + 4 check draws x 6 films; {one_note}",
        },
        {
            "benchmark": "fit k and gamma_mem, same films",
            "value": two / 60,
            "unit": "wall min",
            "target": None,
            "note": f"16 design points + 4 check draws; the second unknown adds "
            f"{(two - one) / 60:.1f} min; {two_note}",
        },
        {
            "benchmark": "coverage of 90 % intervals (k, simulations)",
            "value": held,
            "unit": f"of {trials}",
            "target": 30,
            "higher_is_better": True,
            "note": f"binomial 99 % band 30..40; 4 designs x 10 data sets, "
            f"{coverage_wall / 60:.1f} wall min",
        },
    ]
