"""Stop signals at random moments: a run never hangs, always says it stopped, and leaves its
folder as a rerun expects (no lock, no temporary file, every file whole).

Before: a SIGTERM arriving while a realization's file was written raised inside netCDF's
locked section and the cleanup waited on the same lock for good (1 run of 12 hung, and one
died of the second signal with exit -15, in the probe these tests repeat).
"""

from __future__ import annotations

import random
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from softcell.io.netcdf import read_dataset

# Many short realizations, each a 1.5 MB file: a random moment falls in a write often.
RUN = [
    sys.executable,
    "-m",
    "softcell",
    "simulate",
    "--radius",
    "4",
    "--duration",
    "20",
    "--realizations",
    "30",
    "--quiet",
]


@pytest.fixture(scope="module")
def warm(tmp_path_factory):
    """One whole run first, so that the compiled models are in the cache: the signals then
    fall in the simulation and its writes, not in numba's first compilation."""
    out = tmp_path_factory.mktemp("warm")
    subprocess.run(
        [*RUN[:7], "1", "--quiet", "-o", str(out)], check=True, capture_output=True, timeout=900
    )


def _two_signals(out: Path, rng: random.Random) -> tuple[str, subprocess.CompletedProcess | None]:
    """Start a run, send SIGTERM at a random moment and again within 50 ms; what it did."""
    process = subprocess.Popen(
        [*RUN, "-o", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    time.sleep(rng.uniform(1.5, 6.0))
    process.send_signal(signal.SIGTERM)
    time.sleep(rng.uniform(0.0, 0.05))
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
    try:
        _, err = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        return "hung (killed after 60 s)", None
    return "", subprocess.CompletedProcess(process.args, process.returncode, "", err)


def _problem(out: Path, hung: str, run: subprocess.CompletedProcess | None) -> str:
    """What is wrong with a run stopped by two signals (read in the main thread: netCDF's
    library is not safe to open files from two threads at once)."""
    if hung:
        return hung
    assert run is not None
    last = run.stderr.strip().splitlines()[-1:] or [""]
    if run.returncode != 143 or "Traceback" in run.stderr:
        return f"exit {run.returncode}: {last[0]}\n{run.stderr[-2000:]}"
    if not last[0].startswith("softcell: interrupted") or not last[0].endswith("(SIGTERM)"):
        return f"said {last[0]!r}"
    # the lock, a temporary file (a checkpoint stays: the rerun resumes from it)
    left = sorted(p.name for p in out.glob(".*") if not p.name.endswith(".ckpt.npz"))
    left += sorted(p.name for p in out.glob("*tmp*"))
    if left:
        return f"left {left}"
    for path in sorted(out.glob("*.nc")):
        read_dataset(path)  # whole: its checksum and schema hold (raises otherwise)
    return ""


def _pairs(tmp_path: Path, count: int, seed: int) -> list[str]:
    seeds = random.Random(seed)
    rngs = [random.Random(seeds.getrandbits(32)) for _ in range(count)]
    with ThreadPoolExecutor(2) as pool:
        runs = list(pool.map(lambda i: _two_signals(tmp_path / f"run{i}", rngs[i]), range(count)))
    found = [_problem(tmp_path / f"run{i}", *runs[i]) for i in range(count)]
    return [f"pair {i}: {p}" for i, p in enumerate(found) if p]


def test_stop_signals_at_random_moments(warm, tmp_path):
    problems = _pairs(tmp_path, 8, seed=1)
    assert not problems, "\n".join(problems)


@pytest.mark.slow
def test_a_hundred_stop_signal_pairs_at_random_moments(warm, tmp_path):
    problems = _pairs(tmp_path, 100, seed=2)
    assert not problems, "\n".join(problems)


def test_a_third_stop_signal_ends_the_process_at_once(tmp_path):
    process = subprocess.Popen(
        [
            sys.executable,
            "-c",
            # a cleanup that never ends: the third signal must end the process all the same
            "import signal, sys, time\n"
            "from softcell.engine.interrupt import shielded, stop_signals\n"
            "with stop_signals():\n"
            "    try:\n"
            "        print('ready', flush=True)\n"
            "        time.sleep(60)\n"
            "    except KeyboardInterrupt:\n"
            "        print('stopping', flush=True)\n"
            "        with shielded():\n"
            "            time.sleep(60)\n",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
    )
    assert process.stdout is not None and process.stdout.readline() == "ready\n"
    process.send_signal(signal.SIGTERM)
    assert process.stdout.readline() == "stopping\n"
    process.send_signal(signal.SIGTERM)
    time.sleep(0.5)
    assert process.poll() is None  # the second is recorded: the cleanup goes on
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=10)
    assert process.returncode == 143
    assert err.startswith("softcell: stopped at once (3 stop signals)"), err


def test_a_stop_raised_inside_a_finaliser_is_not_printed(monkeypatch):
    """Our handler's KeyboardInterrupt, raised while Python runs a finaliser (a progress
    bar's __del__), is unraisable: Python printed it after the one-line message (2 of 100
    SIGTERM pairs on a busy machine). Within stop_signals it goes nowhere; other unraisable
    errors go to the hook that was there, which is back afterwards."""
    import gc

    from softcell.engine import interrupt

    seen = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: seen.append(u.exc_type))

    class Stopped:
        def __del__(self):
            raise KeyboardInterrupt

    class Broken:
        def __del__(self):
            raise ValueError("still reported")

    with interrupt.stop_signals():
        interrupt._received.append(signal.SIGTERM)  # as the handler records a stop
        Stopped()
        Broken()
        gc.collect()
    assert seen == [ValueError]
    Stopped()  # outside: reported as before
    gc.collect()
    assert seen == [ValueError, KeyboardInterrupt]
