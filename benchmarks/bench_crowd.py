"""Assemblies of cells: what many cells cost (rodas4, R = 5 cm, the default model).

- the overhead of the assembly loop: one cell as an assembly against the single-cell run,
  the same realization, interleaved, medians of 3 (target: within 10 %);
- 16 cells at an area fraction of 0.35 in a periodic box, 100 simulated seconds on one core
  (target: 5 minutes), and the analysis of that run (each cell and the crowd, samples 1 s
  apart);
- wall time per simulated second for 4, 16 and 64 cells at that area fraction (10 simulated
  seconds each; target: 64 cells at most 4.8 times 16 cells, i.e. 1.2 times linear);
- what a cell costs in a crowd against a lone cell (the single-cell run of the same model,
  60 s): the crowd's wall per simulated second over the number of cells, over the lone
  cell's (target: at most 2, at 16 and at 64 cells);
- one 64-cell realization (5 s) on two threads against one, interleaved, median of 3 (target:
  at least 1.7), beside the ceiling the machine gives: two lone cells' compiled loops on two
  threads against one after the other;
- memory per cell: the record of 100 simulated seconds (the membrane every 0.01 s as 33 modes,
  the bodies' fine record) and the peak of the suite.
"""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

RADIUS = 5.0
FRACTION = 0.35


def _built(duration: float):
    from softcell.components.registry import default_registry
    from softcell.engine import build_integrator, build_model
    from softcell.model.parameters import Parameters

    registry = default_registry()
    params = Parameters(
        {"radius": RADIUS, "duration": duration}, registry.parameter_specs().values()
    )
    model = build_model(
        params,
        ["bending", "tension", "contact"],
        "run_and_tumble",
        registry=registry,
        pair_terms=["repulsion"],
    )
    return model, build_integrator("rodas4", params, registry).build(model)


def _crowd(cells: int, duration: float, seed: int = 0, threads: int = 1) -> tuple[float, object]:
    """Wall seconds of one realization of ``cells`` cells at FRACTION in a periodic box, and
    its record."""
    wall, record, _ = _crowd_run(cells, duration, seed, threads)
    return wall, record


def _crowd_run(cells: int, duration: float, seed: int = 0, threads: int = 1):
    from softcell.engine.groups import cell_rngs, crowd_dataset, placement_rng, run_assembly
    from softcell.model.assembly import Assembly, Domain, place_cells

    model, stepper = _built(duration)
    box = math.sqrt(cells * math.pi * RADIUS**2 / FRACTION)
    domain = Domain("periodic", box)
    centres = place_cells(cells, RADIUS, domain, placement_rng(seed, 0, 0))
    start = time.perf_counter()
    record = run_assembly(
        model, stepper, domain, centres, cell_rngs(seed, 0, 0, cells), threads=threads
    )
    wall = time.perf_counter() - start

    def dataset():
        assembly = Assembly(cells=cells, boundary="periodic", box=box)
        return crowd_dataset(
            record, model, assembly, centres, realization=0, seed=seed, components={}
        )

    return wall, record, dataset


def _analysis(dataset) -> float:
    """Wall seconds of the analysis of an assembly's realization (options as the docs')."""
    import softcell

    ds = dataset()
    start = time.perf_counter()
    softcell.analyze(ds, {"discard": 15.0, "crowd_every": 1.0})
    return time.perf_counter() - start


def _overhead(duration: float = 60.0, rounds: int = 3) -> float:
    """Median wall time of the one-cell assembly over the single-cell run's."""
    from softcell.engine.cell import realization_rng, run_realization
    from softcell.engine.groups import cell_rngs, run_assembly
    from softcell.model.assembly import Domain

    model, stepper = _built(duration)
    _, single = _built(duration)
    run_assembly(model, stepper, Domain(), np.zeros((1, 2)), cell_rngs(0, 0, 0, 1))  # compile
    ratios = []
    for _ in range(rounds):
        start = time.perf_counter()
        run_realization(model, single, realization_rng(0, 0, 0))
        alone = time.perf_counter() - start
        start = time.perf_counter()
        run_assembly(model, stepper, Domain(), np.zeros((1, 2)), cell_rngs(0, 0, 0, 1))
        ratios.append((time.perf_counter() - start) / alone)
    return statistics.median(ratios)


def _lone(duration: float = 60.0) -> float:
    """Wall seconds per simulated second of the single-cell run of the same model."""
    from softcell.engine.cell import realization_rng, run_realization

    model, stepper = _built(duration)
    start = time.perf_counter()
    run_realization(model, stepper, realization_rng(0, 0, 0))
    return (time.perf_counter() - start) / duration


def _threads(cells: int = 64, duration: float = 5.0, rounds: int = 3) -> tuple[float, float]:
    """Median speed-up of one realization of ``cells`` cells on two threads over one, and
    the ceiling: two lone cells' compiled loops (60 s each) on two threads over one after
    the other (BLAS on one thread, as in an assembly)."""
    from concurrent.futures import ThreadPoolExecutor

    from threadpoolctl import threadpool_limits

    from softcell.engine.groups import cell_rngs, start_cells

    ratios = []
    for _ in range(rounds):
        one, _ = _crowd(cells, duration, threads=1)
        two, _ = _crowd(cells, duration, threads=2)
        ratios.append(one / two)
    model, stepper = _built(60.0)
    twin = stepper.twin()
    times = np.arange(1, 6001) * 0.01

    def lone(st, seed: int) -> None:
        states, schedules = start_cells(model, st, np.zeros((1, 2)), cell_rngs(seed, 0, 0, 1))
        st.sample(states[0], schedules[0], times)

    ceiling = []
    with threadpool_limits(1, user_api="blas"), ThreadPoolExecutor(1) as pool:
        lone(stepper, 0)
        lone(twin, 0)
        for _ in range(rounds):
            start = time.perf_counter()
            lone(stepper, 1)
            lone(stepper, 2)
            apart = time.perf_counter() - start
            start = time.perf_counter()
            other = pool.submit(lone, twin, 2)
            lone(stepper, 1)
            other.result()
            ceiling.append(apart / (time.perf_counter() - start))
    return statistics.median(ratios), statistics.median(ceiling)


def rows() -> list[dict[str, object]]:
    out = [
        {
            "benchmark": "one-cell assembly / single cell",
            "value": _overhead(),
            "unit": "x",
            "target": 1.1,
            "note": "R = 5 cm, 60 s, same realization, median of 3",
        }
    ]
    _crowd(4, 0.1)  # compile the group loop outside the timings
    wall, record, dataset = _crowd_run(16, 100.0)
    analysis = _analysis(dataset)
    out.append(
        {
            "benchmark": "16 cells, 100 s, phi = 0.35",
            "value": wall,
            "unit": "s",
            "target": 300.0,
            "note": f"periodic box, one core; {record.statistics['grouped_intervals']} group "
            "intervals",
        }
    )
    out.append(
        {
            "benchmark": "its analysis (each cell, the crowd)",
            "value": analysis,
            "unit": "s",
            "target": None,
            "note": f"{analysis / wall:.1%} of the simulation; samples 1 s apart",
        }
    )
    per_cell = (record.modes.nbytes + record.fine_pose.nbytes + record.fine_center.nbytes) / 16
    out.append(
        {
            "benchmark": "record per cell, 100 s",
            "value": per_cell / 2**20,
            "unit": "MiB",
            "target": None,
            "note": "33 modes every 0.01 s and the fine record, in memory",
        }
    )
    per_second = {}
    for cells in (4, 16, 64):
        wall, _ = _crowd(cells, 10.0)
        per_second[cells] = wall / 10.0
        out.append(
            {
                "benchmark": f"{cells} cells, wall per simulated s",
                "value": per_second[cells],
                "unit": "s/s",
                "target": None,
                "note": "phi = 0.35, periodic, 10 s",
            }
        )
    out.append(
        {
            "benchmark": "64 cells / 16 cells, wall per s",
            "value": per_second[64] / per_second[16],
            "unit": "x",
            "target": 4.8,
            "note": "linear would be 4",
        }
    )
    lone = _lone()
    for cells in (4, 16, 64):
        out.append(
            {
                "benchmark": f"a cell of {cells} / a lone cell",
                "value": per_second[cells] / cells / lone,
                "unit": "x",
                "target": None if cells == 4 else 2.0,
                "note": f"one core; a lone cell {lone * 1e3:.1f} ms per simulated s (60 s)",
            }
        )
    speedup, ceiling = _threads()
    out.append(
        {
            "benchmark": "64 cells, 2 threads / 1 thread",
            "value": speedup,
            "unit": "x",
            "target": 1.7,
            "higher_is_better": True,
            "note": f"5 s, median of 3 interleaved; the machine's ceiling (two lone cells' "
            f"compiled loops on two threads) {ceiling:.2f}x",
        }
    )
    return out
