"""Command-line start-up: ``softcell --version`` and ``--help`` must answer in under 0.3 s (they
import no numba, xarray or plugin registry); ``softcell plugins`` builds the registry (numba,
the built-in kernels from their disk cache), for comparison. Medians of 5 runs, each a new
process. And ``softcell params`` of a sweep of 200,000 radii (from a TOML file), which must
answer within 60 s: it checks every point as ``simulate`` would (it did not end within 120 s
while its check of repeated values was quadratic). One run.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUNS = 5


def _median_seconds(*args: str) -> float:
    times = []
    for _ in range(RUNS):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "softcell", *args], capture_output=True, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _params_of_a_large_sweep(points: int = 200_000) -> float:
    with tempfile.TemporaryDirectory() as folder:
        config = Path(folder) / "sweep.toml"
        radii = ", ".join(f"{4 + i * 1e-5:.5f}" for i in range(points))
        config.write_text(f"[parameters]\nradius = [{radii}]\n", encoding="utf-8")
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "softcell", "params", str(config)],
            capture_output=True,
            check=True,
        )
        return time.perf_counter() - start


def rows() -> list[dict[str, object]]:
    _median_seconds("plugins")  # warm the kernels' disk cache and the file system
    return [
        {
            "benchmark": "softcell --version",
            "value": _median_seconds("--version"),
            "unit": "s",
            "target": 0.3,
            "note": f"median of {RUNS} new processes",
        },
        {
            "benchmark": "softcell --help",
            "value": _median_seconds("--help"),
            "unit": "s",
            "target": 0.3,
            "note": f"median of {RUNS} new processes",
        },
        {
            "benchmark": "softcell plugins",
            "value": _median_seconds("plugins"),
            "unit": "s",
            "target": None,
            "note": "builds the registry: numba and the built-in kernels",
        },
        {
            "benchmark": "softcell params, 200,000 points",
            "value": _params_of_a_large_sweep(),
            "unit": "s",
            "target": 60.0,
            "note": "one run; every point checked as simulate checks it",
        },
    ]
