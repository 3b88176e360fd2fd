"""The README's main job (issue 7): ``softcell reproduce --quick`` on this machine.

Runs the quick design from scratch in a temporary directory with every core, the way the
README's first command does, and reports the wall time of each step and of the whole.
Target: under 10 minutes on 2 cores. Takes ~4.5 minutes: run it with
``python benchmarks/run.py reproduce``.
"""

from __future__ import annotations

import tempfile
import time


def rows() -> list[dict[str, object]]:
    from softcell.workflows.reproduce import QUICK, reproduce

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        outcome = reproduce(tmp, QUICK, progress=False, log=None)
        total = time.perf_counter() - start
    simulated = len(QUICK.radii) * QUICK.realizations * QUICK.duration
    steps = [{"benchmark": f"reproduce --quick: {name}", "value": seconds, "unit": "s",
              "target": None, "note": ""} for name, seconds in outcome.steps.items()]
    steps[0]["note"] = (f"{simulated:g} simulated s: {simulated / outcome.steps['simulations']:.0f}"
                        " sim s per wall s")
    return [*steps, {"benchmark": "reproduce --quick, total", "value": total, "unit": "s",
                     "target": 600, "note": "README main job, every core"}]
