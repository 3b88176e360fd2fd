"""Several bots in one ring: what K bots cost (rodas4, R = 12 cm, the default model with bots
of half the paper's size, a = 1.5 cm, b = 1 cm: sixteen of the paper's bots cover 67 % of a
ring of 12 cm and do not fit with a gap).

- wall time per simulated second for K = 1 (the single-bot run), 2, 4, 8 and 16 bots on a
  lattice, 10 simulated seconds, median of 2 seeds; target: 16 bots at most 5 times one bot;
- what limits it: the steps per simulated second (each bot's switches are landed on, so 16
  run-and-tumble bots switch 16 times as often as one) and the cost of a step;
- memory: the stepper's arrays and the record of 10 s, per bot.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

RADIUS, A, B = 12.0, 1.5, 1.0
DURATION = 10.0
COUNTS = (1, 2, 4, 8, 16)


def _built(count: int):
    from softcell.components.registry import default_registry
    from softcell.engine import build_integrator, build_model

    registry = default_registry()
    interactions = ["bot_repulsion"] if count > 1 else []
    components = {
        "energy_terms": ["bending", "tension", "contact"],
        "driving_protocol": "run_and_tumble",
        "integrator": "rodas4",
        "bot_interactions": interactions,
    }
    params = registry.parameters(
        {"radius": RADIUS, "duration": DURATION, "bot_semi_major": A, "bot_semi_minor": B},
        components,
    )
    model = build_model(
        params,
        components["energy_terms"],
        "run_and_tumble",
        registry=registry,
        bot_interactions=interactions,
    )
    integrator = build_integrator("rodas4", params, registry)
    stepper = integrator.build_bots(model, count) if count > 1 else integrator.build(model)
    return model, stepper


def _run(count: int, seed: int):
    """Wall seconds, steps and the record of one realization of ``count`` bots."""
    from softcell.engine.bots import bot_rngs, placement_rng, start_bots
    from softcell.engine.cell import realization_rng, run_realization
    from softcell.model.bots import Bots

    model, stepper = _built(count)
    if count == 1:
        start = time.perf_counter()
        record = run_realization(model, stepper, realization_rng(seed, 0, 0))
    else:
        modes, poses, schedules = start_bots(
            model,
            Bots(count=count, placement="lattice"),
            bot_rngs(seed, 0, 0, count),
            placement_rng(seed, 0, 0),
        )
        begun = (stepper.start(modes, poses, schedules), schedules)
        start = time.perf_counter()
        record = run_realization(model, stepper, None, start=begun)
    wall = time.perf_counter() - start
    return wall, stepper.statistics(record.state)["steps"], record, stepper


def _array_bytes(obj) -> int:
    """Bytes of the numpy arrays held by ``obj`` (nested named tuples)."""
    if isinstance(obj, np.ndarray):
        return obj.nbytes
    if isinstance(obj, tuple):
        return sum(_array_bytes(x) for x in obj)
    return 0


def rows() -> list[dict[str, object]]:
    for count in (1, 2):
        _run(count, 99)  # compile both loops outside the timings
    cost, steps, memory = {}, {}, {}
    for count in COUNTS:
        runs = [_run(count, seed) for seed in (1, 2)]
        cost[count] = statistics.median(r[0] for r in runs) / DURATION
        steps[count] = statistics.median(r[1] for r in runs) / DURATION
        record, stepper = runs[0][2], runs[0][3]
        held = _array_bytes(getattr(stepper, "work", ())) + _array_bytes(
            getattr(stepper, "step", ())
        )
        memory[count] = (held, record.pose.nbytes + record.fine_pose.nbytes)
    out = []
    for count in COUNTS:
        out.append(
            {
                "benchmark": f"{count} bot(s), R = 12 cm, per sim s",
                "value": cost[count],
                "unit": "s",
                "target": None,
                "note": f"{steps[count]:.0f} steps per sim s, "
                f"{cost[count] / steps[count] * 1e3:.2f} ms a step; {cost[count] / cost[1]:.1f}"
                " x one bot; median of 2 seeds, 10 s",
            }
        )
    out.append(
        {
            "benchmark": "16 bots / one bot, cost per sim s",
            "value": cost[16] / cost[1],
            "unit": "x",
            "target": 5.0,
            "note": f"steps {steps[16] / steps[1]:.1f} x, cost of a step "
            f"{cost[16] / steps[16] / (cost[1] / steps[1]):.1f} x",
        }
    )
    for count in COUNTS[1:]:
        held, record = memory[count]
        out.append(
            {
                "benchmark": f"memory per bot, {count} bots",
                "value": (held + record) / count / 2**10,
                "unit": "KiB",
                "target": None,
                "note": f"stepper {held / 2**10:.0f} KiB (its Jacobian grows as (2m + 3K)^2), "
                f"record of 10 s {record / 2**10:.0f} KiB",
            }
        )
    return out
