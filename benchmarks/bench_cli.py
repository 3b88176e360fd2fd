"""Command-line start-up: ``softcell --version`` and ``--help`` must answer in under 0.3 s (they
import no numba, xarray or plugin registry); ``softcell plugins`` builds the registry (numba,
the built-in kernels from their disk cache), for comparison. Medians of 5 runs, each a new
process.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time

RUNS = 5


def _median_seconds(*args: str) -> float:
    times = []
    for _ in range(RUNS):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "softcell", *args], capture_output=True, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


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
    ]
