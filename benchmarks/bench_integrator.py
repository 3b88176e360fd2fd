"""The fast integrator against the explicit reference.

For R = 4, 8 and 12 cm, realization 0 of root seed 0 (the realization of
``tests/regression/integrator_reference.npz``):

- ``explicit_euler`` at dt = 1e-6 s is timed over the first ``EXPLICIT_SPAN`` s. Those are
  the cheap seconds for it (the bot starts at the centre, and a step in contact costs ~2x a
  free step), so the ratio below is conservative;
- ``rodas4`` at its default tolerance is timed over the whole 5 s (the median of
  ``FAST_REPEATS`` runs: one run takes ~0.07 s, so a single one is at the mercy of a busy
  machine), and its bot and cell paths
  are compared with the stored explicit reference (largest difference, cm), as are the coarse
  statistics (largest relative difference);
- the wall time of the paper's study (10 radii x 25 realizations, 900 s for R <= 9 cm and
  1800 s above, on 2 cores) is projected from these rates, each radius at the rate of the
  nearest measured one.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

RADII = (4.0, 8.0, 12.0)
EXPLICIT_SPAN = 1.0
REFERENCE = (
    Path(__file__).resolve().parents[1] / "tests" / "regression" / "integrator_reference.npz"
)
STUDY_RADII = tuple(float(r) for r in range(4, 14))
REALIZATIONS, CORES = 25, 2
FAST_REPEATS = 7


def explicit_rate(radius: float) -> float:
    """Simulated seconds per wall second of explicit_euler over [0, EXPLICIT_SPAN] s."""
    from softcell.components.registry import default_registry
    from softcell.engine import build_integrator, build_model, initial_state
    from softcell.engine.cell import realization_rng
    from softcell.testing.compare import PROTOCOL, TERMS, parameters

    params = parameters(radius, EXPLICIT_SPAN)
    model = build_model(params, TERMS, PROTOCOL, registry=default_registry())
    stepper = build_integrator("explicit_euler", params, default_registry()).build(model)
    modes, pose, schedule = initial_state(model, realization_rng(0, 0, 0))
    state = stepper.start(modes, pose, schedule)
    stepper.advance(state, schedule, 1e-4)  # compile
    begin = time.perf_counter()
    stepper.advance(state, schedule, EXPLICIT_SPAN)
    return (EXPLICIT_SPAN - 1e-4) / (time.perf_counter() - begin)


def fast_run(radius: float, reference) -> dict[str, float]:
    from softcell.engine import Record
    from softcell.testing.compare import coarse_statistics, parameters, path_difference, run

    key = f"r{radius:g}"
    duration = float(reference["duration"])
    params = parameters(radius, duration)
    runs = [run(params, "rodas4", seed=int(reference["seed"])) for _ in range(FAST_REPEATS)]
    result = runs[-1]
    wall = float(np.median([r.wall for r in runs]))
    explicit = Record(
        reference[f"{key}_times"], reference[f"{key}_modes"], reference[f"{key}_pose"], None
    )
    paths = path_difference(result.record, explicit, int(params.cutoff))
    mine = coarse_statistics(params, result.record, result.record.phase)
    theirs = coarse_statistics(params, explicit, result.record.phase)
    stats = max(abs(mine[k] / theirs[k] - 1) for k in theirs if theirs[k])
    return {
        "rate": duration / wall,
        "bot": paths["bot"],
        "cell": paths["cell"],
        "stats": stats,
        **result.statistics,
    }


def study_hours(rates: dict[float, float]) -> float:
    """Wall hours of the paper's study on CORES cores at these rates (sim s per wall s)."""
    total = 0.0
    for radius in STUDY_RADII:
        nearest = min(rates, key=lambda r: abs(r - radius))
        duration = 900.0 if radius <= 9 else 1800.0
        total += REALIZATIONS * duration / rates[nearest]
    return total / CORES / 3600


def rows() -> list[dict[str, object]]:
    reference = np.load(REFERENCE)
    out: list[dict[str, object]] = []
    explicit, fast = {}, {}
    for radius in RADII:
        explicit[radius] = explicit_rate(radius)
        result = fast_run(radius, reference)
        fast[radius] = result["rate"]
        out.append(
            {
                "benchmark": f"explicit_euler, R={radius:g}",
                "value": explicit[radius],
                "unit": "sim s/s",
                "target": None,
                "note": f"dt = 1e-6 s over the first {EXPLICIT_SPAN:g} s",
            }
        )
        out.append(
            {
                "benchmark": f"rodas4, R={radius:g}",
                "value": result["rate"],
                "unit": "sim s/s",
                "target": None,
                "note": f"{result['steps']} steps, {result['rejected']} rejected, "
                f"{result['rhs_calls']} RHS, over 5 s",
            }
        )
        out.append(
            {
                "benchmark": f"ratio rodas4/explicit, R={radius:g}",
                "value": result["rate"] / explicit[radius],
                "unit": "x",
                "target": 2500.0,
                "higher_is_better": True,
                "note": "the goal is 3000",
            }
        )
        out.append(
            {
                "benchmark": f"rodas4 path error, R={radius:g}",
                "value": max(result["bot"], result["cell"]),
                "unit": "cm",
                "target": 1e-4,
                "note": f"bot {result['bot']:.1e}, cell {result['cell']:.1e}; coarse "
                f"statistics within {result['stats']:.1e} (target 1e-2)",
            }
        )
    out.append(
        {
            "benchmark": "paper study, rodas4, 2 cores",
            "value": study_hours(fast),
            "unit": "h",
            "target": 1.0,
            "note": "projected: 10 radii x 25 x 900/1800 s at the measured rates",
        }
    )
    out.append(
        {
            "benchmark": "paper study, explicit, 2 cores",
            "value": study_hours(explicit),
            "unit": "h",
            "target": None,
            "note": "projected from the rates above",
        }
    )
    return out
