"""The README's main job and the study: ``softcell reproduce --quick`` on this machine, the
ensemble's efficiency on local workers, and the paper's full design as measured.

- ``reproduce --quick`` from scratch in a temporary directory with every core, the way the
  README's first command does: the wall time of each step and of the whole (target: under
  10 minutes on 2 cores).
- The ensemble at full speed: the same ensemble (R = 6, 9, 12 cm x 4 realizations x 240 s) run
  in this process and on ``CORES`` local dask workers, side by side, sampling, files and dask
  included, the compiled model warm in the cache; efficiency = rate on N workers / (N x the
  single-process rate), target 0.9.
- Where the rest goes: the machine's own ceiling, the same realizations run as ``CORES``
  plain processes at once (one BLAS/OpenMP thread each, as dask's workers have) against one
  alone, no dask, no cluster; what the ensemble loses beyond that ceiling is dask's (cluster
  start, worker imports and cache loads, the tail).
- The full design as run by ``softcell reproduce --full`` (``docs/results/full/timing.json``,
  written by the documented command there), beside its projection.

Takes ~10 minutes: ``python benchmarks/run.py reproduce``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ENSEMBLE = {"radius": [6.0, 9.0, 12.0], "duration": 240.0}
ENSEMBLE_REALIZATIONS = 4
CORES = os.cpu_count() or 1
FULL_TARGET = 0.75  # h: the paper's full design to the end in 45 min on 2 cores
MEASURED = Path(__file__).resolve().parents[1] / "docs" / "results" / "full" / "timing.json"


def ensemble_rate(out: Path, workers: int, client=None) -> float:
    """Simulated seconds per wall second of the whole ensemble on ``workers`` processes (or on
    the workers of ``client``)."""
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    config = RunConfig(parameters=dict(ENSEMBLE))
    start = time.perf_counter()
    simulate(
        config,
        out,
        realizations=ENSEMBLE_REALIZATIONS,
        workers=workers,
        client=client,
        progress=False,
    )
    wall = time.perf_counter() - start
    return len(ENSEMBLE["radius"]) * ENSEMBLE_REALIZATIONS * ENSEMBLE["duration"] / wall


def warm_cluster_rate(tmp: Path) -> float:
    """The ensemble's rate on ``CORES`` workers that have already imported softcell and loaded
    the compiled model: what a long ensemble tends to, its start-up spread thin."""
    from softcell.model.configuration import RunConfig
    from softcell.runner.cluster import cluster_client
    from softcell.runner.ensemble import simulate

    with cluster_client(CORES) as client:
        simulate(
            RunConfig(parameters={"radius": 6.0, "duration": 0.1}),
            tmp / "warm-all",
            realizations=CORES,
            client=client,
            progress=False,
        )
        return ensemble_rate(tmp / "warm-cluster", 1, client)


# One process's share of the ceiling measurement: warm, then time a few realizations.
PLAIN = """
import sys, time
from pathlib import Path
from softcell.model.configuration import RunConfig
from softcell.runner.ensemble import simulate
out = Path(sys.argv[1])
simulate(RunConfig(parameters={"radius": 9.0, "duration": 0.1}), out / "warm", progress=False)
start = time.perf_counter()
simulate(RunConfig(parameters={"radius": 9.0, "duration": 240.0}), out / "run",
         realizations=2, progress=False)
print(time.perf_counter() - start)
"""


def plain_processes(tmp: Path, count: int) -> float:
    """Wall time (s) of the slowest of ``count`` processes started at once, each running the
    same two realizations with one BLAS/OpenMP thread."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    runs = [
        subprocess.Popen(
            [sys.executable, "-c", PLAIN, str(tmp / f"plain{count}-{k}")],
            stdout=subprocess.PIPE,
            text=True,
            env=env,
        )
        for k in range(count)
    ]
    return max(float(r.communicate()[0].split()[-1]) for r in runs)


def ceiling_rows(tmp: Path) -> list[dict[str, object]]:
    alone = [plain_processes(tmp / f"a{k}", 1) for k in range(3)]
    together = [plain_processes(tmp / f"t{k}", CORES) for k in range(3)]
    ceiling = sorted(alone)[1] / sorted(together)[1]
    return [
        {
            "benchmark": f"machine ceiling, {CORES} plain processes",
            "value": ceiling,
            "unit": "1",
            "target": None,
            "note": f"median of 3: one alone {sorted(alone)[1]:.2f} s, {CORES} at once "
            f"{sorted(together)[1]:.2f} s (R = 9 cm, 2 x 240 s, no dask)",
        }
    ]


def ensemble_rows(tmp: Path) -> list[dict[str, object]]:
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    simulate(
        RunConfig(parameters={"radius": 6.0, "duration": 0.1}), tmp / "warm", progress=False
    )  # the compiled model into the cache
    single = ensemble_rate(tmp / "single", 1)
    several = ensemble_rate(tmp / "several", CORES)
    warm = warm_cluster_rate(tmp)
    simulated = len(ENSEMBLE["radius"]) * ENSEMBLE_REALIZATIONS * ENSEMBLE["duration"]
    ideal = simulated / (CORES * single)
    start_up = simulated / several - simulated / warm
    return [
        {
            "benchmark": "ensemble, 1 process",
            "value": single,
            "unit": "sim s/s",
            "target": None,
            "note": "R = 6, 9, 12 x 4 x 240 s, files included",
        },
        {
            "benchmark": f"ensemble, {CORES} dask workers",
            "value": several,
            "unit": "sim s/s",
            "target": None,
            "note": f"the same ensemble, side by side: {simulated / several:.1f} s "
            f"against {ideal:.1f} s for 1/{CORES} of the single run",
        },
        {
            "benchmark": f"ensemble efficiency, {CORES} workers",
            "value": several / (CORES * single),
            "unit": "1",
            "target": 0.9,
            "higher_is_better": True,
            "note": "rate / (workers x 1-process rate), cluster start included",
        },
        {
            "benchmark": f"ensemble efficiency, {CORES} warm workers",
            "value": warm / (CORES * single),
            "unit": "1",
            "target": None,
            "note": f"workers already started and loaded: start-up costs {start_up:.1f} s; the rest"
            " is the tail and the workers' own overhead",
        },
    ]


def measured_rows() -> list[dict[str, object]]:
    if not MEASURED.exists():
        return [
            {
                "benchmark": "reproduce --full, measured",
                "value": float("nan"),
                "unit": "h",
                "target": FULL_TARGET,
                "note": f"not run yet: see {MEASURED.parent}/README.md",
            }
        ]
    timing = json.loads(MEASURED.read_text())
    return [
        {
            "benchmark": "reproduce --full, measured",
            "value": timing["total"] / 3600,
            "unit": "h",
            "target": FULL_TARGET,
            "note": f"softcell {timing['version']}, {timing['cores']} cores, {timing['date']}",
        }
    ]


def rows() -> list[dict[str, object]]:
    from softcell.paper.reproduce import QUICK, reproduce

    with tempfile.TemporaryDirectory() as tmp:
        out = ensemble_rows(Path(tmp)) + ceiling_rows(Path(tmp))
        start = time.perf_counter()
        outcome = reproduce(Path(tmp) / "quick", QUICK, progress=False, log=None)
        total = time.perf_counter() - start
    simulated = len(QUICK.radii) * QUICK.realizations * QUICK.duration
    steps = [
        {
            "benchmark": f"reproduce --quick: {name}",
            "value": seconds,
            "unit": "s",
            "target": None,
            "note": "",
        }
        for name, seconds in outcome.steps.items()
    ]
    steps[0]["note"] = (
        f"{simulated:g} simulated s: {simulated / outcome.steps['simulations']:.0f}"
        " sim s per wall s"
    )
    return [
        *out,
        *steps,
        {
            "benchmark": "reproduce --quick, total",
            "value": total,
            "unit": "s",
            "target": 600,
            "note": "README main job, every core",
        },
        *measured_rows(),
    ]
