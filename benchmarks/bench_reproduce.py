"""The README's main job and the study: ``softcell reproduce --quick`` on this machine, the
ensemble's efficiency on local workers, and the paper's full design as measured.

- ``reproduce --quick`` from scratch in a temporary directory with every core, the way the
  README's first command does: the wall time of each step and of the whole (target: under
  10 minutes on 2 cores).
- The ensemble at full speed: the same ensemble (R = 6, 9, 12 cm x 4 realizations x 240 s) run
  in this process and on ``CORES`` local dask workers, side by side, sampling, files and dask
  included, the compiled model warm in the cache; efficiency = rate on N workers / (N x the
  single-process rate), target 0.9.
- The full design as run by ``softcell reproduce --full`` (``docs/results/full/timing.json``,
  written by the documented command there), beside its projection.

Takes ~10 minutes: ``python benchmarks/run.py reproduce``.
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path

ENSEMBLE = {"radius": [6.0, 9.0, 12.0], "duration": 240.0}
ENSEMBLE_REALIZATIONS = 4
CORES = os.cpu_count() or 1
MEASURED = Path(__file__).resolve().parents[1] / "docs" / "results" / "full" / "timing.json"


def ensemble_rate(out: Path, workers: int) -> float:
    """Simulated seconds per wall second of the whole ensemble on ``workers`` processes."""
    from softcell.core.runconfig import RunConfig
    from softcell.workflows.ensemble import simulate

    config = RunConfig(parameters=dict(ENSEMBLE))
    start = time.perf_counter()
    simulate(config, out, realizations=ENSEMBLE_REALIZATIONS, workers=workers,
             progress=False)
    wall = time.perf_counter() - start
    return len(ENSEMBLE["radius"]) * ENSEMBLE_REALIZATIONS * ENSEMBLE["duration"] / wall


def ensemble_rows(tmp: Path) -> list[dict[str, object]]:
    from softcell.core.runconfig import RunConfig
    from softcell.workflows.ensemble import simulate

    simulate(RunConfig(parameters={"radius": 6.0, "duration": 0.1}), tmp / "warm",
             progress=False)  # the compiled model into the cache
    single = ensemble_rate(tmp / "single", 1)
    several = ensemble_rate(tmp / "several", CORES)
    efficiency = several / (CORES * single)
    simulated = len(ENSEMBLE["radius"]) * ENSEMBLE_REALIZATIONS * ENSEMBLE["duration"]
    lost = simulated / several - simulated / (CORES * single)
    return [
        {"benchmark": "ensemble, 1 process", "value": single, "unit": "sim s/s",
         "target": None, "note": "R = 6, 9, 12 x 4 x 240 s, files included"},
        {"benchmark": f"ensemble, {CORES} dask workers", "value": several, "unit": "sim s/s",
         "target": None, "note": f"the same ensemble, side by side: {lost:.1f} s more than "
                                 f"1/{CORES} of the single run (cluster, worker start-up, tail)"},
        {"benchmark": f"ensemble efficiency, {CORES} workers", "value": efficiency, "unit": "1",
         "target": 0.9, "higher_is_better": True, "note": "rate / (workers x 1-process rate)"},
    ]


def measured_rows() -> list[dict[str, object]]:
    if not MEASURED.exists():
        return [{"benchmark": "reproduce --full, measured", "value": float("nan"), "unit": "h",
                 "target": 1.0, "note": f"not run yet: see {MEASURED.parent}/README.md"}]
    timing = json.loads(MEASURED.read_text())
    return [{"benchmark": "reproduce --full, measured", "value": timing["total"] / 3600,
             "unit": "h", "target": 1.0,
             "note": f"softcell {timing['version']}, {timing['cores']} cores, "
                     f"{timing['date']}"}]


def rows() -> list[dict[str, object]]:
    from softcell.workflows.reproduce import QUICK, reproduce

    with tempfile.TemporaryDirectory() as tmp:
        out = ensemble_rows(Path(tmp))
        start = time.perf_counter()
        outcome = reproduce(Path(tmp) / "quick", QUICK, progress=False, log=None)
        total = time.perf_counter() - start
    simulated = len(QUICK.radii) * QUICK.realizations * QUICK.duration
    steps = [{"benchmark": f"reproduce --quick: {name}", "value": seconds, "unit": "s",
              "target": None, "note": ""} for name, seconds in outcome.steps.items()]
    steps[0]["note"] = (f"{simulated:g} simulated s: {simulated / outcome.steps['simulations']:.0f}"
                        " sim s per wall s")
    return [*out, *steps,
            {"benchmark": "reproduce --quick, total", "value": total, "unit": "s",
             "target": 600, "note": "README main job, every core"},
            *measured_rows()]
