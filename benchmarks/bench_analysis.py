"""Analysis benchmarks.

- MSD of one 10^6-sample 2-D trajectory by the FFT algorithm (target: under 1 s);
- the full analysis of a 25-realization, 1800 s Dataset sampled like the paper (0.01 s to
  100 s, then 0.1 s: 27001 samples, 64 stored membrane nodes), synthetic stop-and-go data of
  the schema's shape (target: under 30 s); the same with the bodies' fine record (every
  0.01 s over the whole run, as a simulation writes it; target: under 60 s). Building the
  Dataset is not timed;
- what checking a file before it is read costs (its checksum, version and schema; readers
  do it unless told ``--no-verify``): the analysis of that fine Dataset read from its file,
  with and without the check (no target: the cost is reported).
"""

from __future__ import annotations

import time

import numpy as np


def rows() -> list[dict[str, object]]:
    from softcell.analysis import analyze
    from softcell.analysis.msd import msd
    from softcell.testing.synthetic import stop_and_go_dataset, two_rate_times

    rng = np.random.default_rng(0)
    walk = np.cumsum(rng.normal(size=(1_000_000, 2)), axis=0)
    msd(walk[:1000])  # plan the FFTs of small sizes once; the big one is timed cold
    start = time.perf_counter()
    msd(walk)
    msd_seconds = time.perf_counter() - start

    times = two_rate_times(0.01, 0.1, 100.0, 1800.0)
    ds = stop_and_go_dataset(
        rng, times, realizations=25, speed=1.0, mean_go=1.0, mean_stop=3.0, nodes=64
    )
    start = time.perf_counter()
    analyze(ds)
    analysis_seconds = time.perf_counter() - start
    # The same design with the bodies' fine record, as a simulation writes it: the MSD and
    # the stop/go phases come from 180,001 samples per realization.
    ds = stop_and_go_dataset(
        rng, times, realizations=25, speed=1.0, mean_go=1.0, mean_stop=3.0, nodes=64, fine=True
    )
    start = time.perf_counter()
    analyze(ds)
    fine_seconds = time.perf_counter() - start
    checked, unchecked = _verified_reading(ds)
    return [
        {
            "benchmark": "MSD, 1e6 samples",
            "value": msd_seconds,
            "unit": "s",
            "target": 1.0,
            "note": "FFT algorithm (pyfftw), no missing samples",
        },
        {
            "benchmark": "analysis, 25 x 1800 s",
            "value": analysis_seconds,
            "unit": "s",
            "target": 30.0,
            "note": f"{times.size} samples x 64 nodes per realization",
        },
        {
            "benchmark": "analysis, 25 x 1800 s, fine record",
            "value": fine_seconds,
            "unit": "s",
            "target": 60.0,
            "note": "stop/go and MSD from the 0.01 s fine record; errors from 1000 resamples",
        },
        {
            "benchmark": "checking a file before analysing it",
            "value": checked - unchecked,
            "unit": "s",
            "target": None,
            "note": f"analysis from the file: {checked:.1f} s checked, {unchecked:.1f} s "
            "--no-verify",
        },
    ]


def _verified_reading(ds) -> tuple[float, float]:
    """Wall s of reading and analysing ``ds`` from a file, checked and not (the second of two
    rounds: the first pays for warming up)."""
    import tempfile
    from pathlib import Path

    from softcell.analysis import analyze
    from softcell.io.netcdf import open_inputs, write_dataset

    with tempfile.TemporaryDirectory() as tmp:
        path = write_dataset(ds, Path(tmp) / "point000_realization0000.nc")
        for _ in range(2):
            seconds = []
            for verify in (True, False):
                start = time.perf_counter()
                analyze(open_inputs([path], chunks={}, verify=verify))
                seconds.append(time.perf_counter() - start)
    return seconds[0], seconds[1]
