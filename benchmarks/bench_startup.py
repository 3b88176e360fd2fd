"""Start-up of a simulation in a new process, with the compiled-model cache cold and warm.

``softcell simulate --radius 8 --duration 1`` is timed as a user runs it (a new process, wall
time to exit): once with an empty cache (``SOFTCELL_CACHE_DIR`` in a temporary folder; numba
compiles the composed model and writes it), then ``RUNS`` times with the cache warm (median).
The same with a third-party energy term added: ``examples/plugin``'s ``pressure``, made
visible as an installed distribution (a ``.dist-info`` folder beside its sources on
``PYTHONPATH``), so its kernels are composed and cached like the built-ins'.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUNS = 3
ROOT = Path(__file__).resolve().parents[1]
COMMAND = ["simulate", "--radius", "8", "--duration", "1", "--quiet"]


def _example_site(folder: Path) -> Path:
    """A folder that importlib.metadata sees as holding softcell-example 1.0.0."""
    site = folder / "site"
    shutil.copytree(
        ROOT / "examples" / "plugin" / "src" / "softcell_example", site / "softcell_example"
    )
    info = site / "softcell_example-1.0.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: softcell-example\nVersion: 1.0.0\n"
    )
    (info / "entry_points.txt").write_text("[softcell]\nexample = softcell_example.plugin\n")
    return site


def _seconds(env: dict[str, str], out: Path, *extra: str) -> float:
    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "softcell", *COMMAND, *extra, "-o", str(out)],
        env=env,
        capture_output=True,
        check=True,
    )
    return time.perf_counter() - start


def rows() -> list[dict[str, object]]:
    out: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        site = _example_site(folder)
        cases = (
            ("built-in terms", {}, ()),
            (
                "with a third-party term",
                {"PYTHONPATH": str(site)},
                ("--energy-terms", "bending,tension,contact,pressure"),
            ),
        )
        for name, extra_env, flags in cases:
            env = {
                **os.environ,
                **extra_env,
                "SOFTCELL_CACHE_DIR": str(folder / f"cache-{len(out)}"),
            }
            cold = _seconds(env, folder / "run", *flags)
            warm = statistics.median(_seconds(env, folder / "run", *flags) for _ in range(RUNS))
            out.append(
                {
                    "benchmark": f"simulate R=8 1 s, cold cache, {name}",
                    "value": cold,
                    "unit": "s",
                    "target": None,
                    "note": "new process, empty cache: numba compiles the model",
                }
            )
            out.append(
                {
                    "benchmark": f"simulate R=8 1 s, warm cache, {name}",
                    "value": warm,
                    "unit": "s",
                    "target": 3.0,
                    "note": f"new process, median of {RUNS}; {cold / warm:.0f}x faster",
                }
            )
    return out
