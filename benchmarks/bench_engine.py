"""Engine benchmarks: microseconds per explicit Euler step at N = 1024.

Each case builds a model, compiles the stepper with a short warm-up advance (not timed), then
times one ``advance`` over ``span`` simulated seconds:

- ``R=12 free``: run and tumble at R = 12 cm during the first 0.25 s, when the bot crosses the
  interior and touches nothing (it needs >= 0.6 s to reach the membrane);
- ``R=4 contact``: a constant push at R = 4 cm after 0.1 s, when the bot presses on the membrane
  all the time;
- ``R=4 run_and_tumble``: the paper's protocol at R = 4 cm, a mix of contact and free flight.
"""

from __future__ import annotations

import time

import numpy as np

# (name, radius, protocol, warm-up end (s), timed span (s), target (us/step) or None)
CASES = [
    ("explicit step, R=12 free", 12.0, "run_and_tumble", 0.01, 0.24, 40.0),
    ("explicit step, R=4 contact", 4.0, "constant_push", 0.1, 0.2, 55.0),
    ("explicit step, R=4 run_and_tumble", 4.0, "run_and_tumble", 0.1, 0.4, None),
]


def explicit_step(
    radius: float, protocol: str, warmup: float, span: float, seed: int = 0
) -> dict[str, float]:
    """Time one explicit Euler ``advance`` of ``span`` s after ``warmup`` s; return us per
    step and simulated seconds per wall second."""
    from softcell.components.registry import default_registry
    from softcell.engine import build_integrator, build_model, initial_state
    from softcell.engine.cell import realization_rng
    from softcell.model.parameters import Parameters

    params = Parameters({"radius": radius, "duration": warmup + span})
    model = build_model(
        params, ["bending", "tension", "contact"], protocol, registry=default_registry()
    )
    stepper = build_integrator("explicit_euler", params, default_registry()).build(model)
    modes, pose, schedule = initial_state(model, realization_rng(seed, 0, 0))
    state = stepper.start(modes, pose, schedule)
    stepper.advance(state, schedule, warmup)
    start = time.perf_counter()
    stepper.advance(state, schedule, warmup + span)
    wall = time.perf_counter() - start
    if not np.all(np.isfinite(state["modes"])):
        raise RuntimeError(f"benchmark run at R = {radius} blew up")
    steps = round(span / float(params.dt))
    return {"us_per_step": wall / steps * 1e6, "sim_s_per_wall_s": span / wall}


def rows() -> list[dict[str, object]]:
    """One table row per case; called in a fresh process so peak memory is the case's own."""
    out = []
    for name, radius, protocol, warmup, span, target in CASES:
        result = explicit_step(radius, protocol, warmup, span)
        out.append(
            {
                "benchmark": name,
                "value": result["us_per_step"],
                "unit": "us/step",
                "target": target,
                "note": f"{result['sim_s_per_wall_s']:.3f} sim s per wall s",
            }
        )
    return out
