"""Locomotion strategies: what each costs (rodas4, R = 5 cm, the default model, one core).

Wall seconds per simulated second of one 60 s realization for each built-in protocol,
interleaved over 3 rounds (medians), and each over the paper's ``run_and_tumble`` in the same
round: the cost of ``bump_and_turn``'s contact event (an extra right-hand side per step, the
root finding at each event) and of ``active_brownian``'s noise intervals (every 0.05 s a
switch the steps land on).
"""

from __future__ import annotations

import statistics
import time

PROTOCOLS = ("run_and_tumble", "graspion", "bump_and_turn", "active_brownian", "chiral")
DURATION = 60.0


def _built(protocol: str):
    from softcell.components.registry import default_registry
    from softcell.engine import build_integrator, build_model
    from softcell.model.parameters import Parameters

    registry = default_registry()
    params = Parameters({"radius": 5.0, "duration": DURATION}, registry.parameter_specs().values())
    model = build_model(params, ["bending", "tension", "contact"], protocol, registry=registry)
    return model, build_integrator("rodas4", params, registry).build(model)


def _wall(model, stepper) -> float:
    from softcell.engine.cell import realization_rng, run_realization

    start = time.perf_counter()
    run_realization(model, stepper, realization_rng(0, 0, 0))
    return time.perf_counter() - start


def rows() -> list[dict[str, object]]:
    built = {p: _built(p) for p in PROTOCOLS}
    for model, stepper in built.values():
        _wall(model, stepper)  # compile outside the timings
    walls: dict[str, list[float]] = {p: [] for p in PROTOCOLS}
    ratios: dict[str, list[float]] = {p: [] for p in PROTOCOLS}
    for _ in range(3):
        for p in PROTOCOLS:
            walls[p].append(_wall(*built[p]))
        for p in PROTOCOLS:
            ratios[p].append(walls[p][-1] / walls["run_and_tumble"][-1])
    return [
        {
            "benchmark": f"{p}, R = 5 cm",
            "value": statistics.median(walls[p]) / DURATION,
            "unit": "wall s / simulated s",
            "target": None,
            "note": f"{statistics.median(ratios[p]):.2f}x run_and_tumble (median of 3, "
            "interleaved)",
        }
        for p in PROTOCOLS
    ]
