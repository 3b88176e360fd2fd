"""Run softcell's benchmarks and print one table: value, target, and peak memory.

    python benchmarks/run.py            # every suite
    python benchmarks/run.py engine     # only benchmarks/bench_engine.py

Each suite (``benchmarks/bench_<name>.py``, a ``rows()`` function) runs in a fresh Python
process, so its peak resident memory (``ru_maxrss``) is its own, compilation included.
Timings are wall-clock on this machine; they never go into the tests.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
CHILD = """
import json, resource, sys
sys.path.insert(0, {here!r})
import bench_{name} as suite
rows = suite.rows()
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({{"rows": rows, "peak_mib": peak}}))
"""


def suites() -> list[str]:
    return sorted(p.stem.removeprefix("bench_") for p in HERE.glob("bench_*.py"))


def run_suite(name: str) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", CHILD.format(here=str(HERE), name=name)],
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        raise SystemExit(f"benchmark suite {name!r} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv: list[str]) -> int:
    names = argv or suites()
    unknown = sorted(set(names) - set(suites()))
    if unknown:
        raise SystemExit(f"unknown benchmark suite(s) {unknown}; available: {suites()}")
    header = f"{'benchmark':<40} {'value':>10} {'unit':<9} {'target':>8} {'ok':<3} note"
    print(header)
    print("-" * len(header))
    for name in names:
        result = run_suite(name)
        for row in result["rows"]:
            target = row["target"]
            if target is None:
                ok = ""
            else:
                met = (
                    row["value"] >= target
                    if row.get("higher_is_better")
                    else row["value"] <= target
                )
                ok = "yes" if met else "NO"
            print(
                f"{row['benchmark']:<40} {row['value']:>10.3g} {row['unit']:<9} "
                f"{'' if target is None else format(target, 'g'):>8} {ok:<3} {row['note']}"
            )
        print(f"{'peak memory, suite ' + name:<40} {result['peak_mib']:>10.0f} {'MiB':<9}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
