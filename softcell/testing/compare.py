"""Integrators side by side: one realization from the same state and schedule, and the coarse
statistics an integrator must reproduce (how a fast integrator is validated against the
explicit reference).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from softcell.components.registry import default_registry
from softcell.engine import (
    Model,
    Record,
    build_integrator,
    build_model,
    fd_hessian,
    force_modes,
)
from softcell.engine.cell import run_realization
from softcell.model.parameters import Parameters
from softcell.schema import PHASE_RUN as RUN
from softcell.schema import PHASE_TUMBLE as TUMBLE

#: The model of the comparisons: the paper's membrane and protocol.
TERMS = ("bending", "tension", "contact")
PROTOCOL = "run_and_tumble"

#: A sample counts as "in contact" when the contact pushes the bot with more than this
#: fraction of the drive force F0.
CONTACT_FRACTION_OF_F0 = 0.01

#: Go threshold of the coarse statistics: the simulations' 0.03 cm/s (docs/model.md §6).
GO_THRESHOLD = 0.03


@dataclass
class Run:
    """One realization run by one integrator, with its wall time (s)."""

    record: Record
    wall: float
    statistics: dict[str, int]


def parameters(radius: float, duration: float, **extra: object) -> Parameters:
    """The default model at this radius (cm) and duration (s), plus integrator settings."""
    return default_registry().parameters({"radius": radius, "duration": duration, **extra})


def run(params: Parameters, integrator: str, seed: int = 0) -> Run:
    """Run realization 0 of point 0 with root ``seed`` (the ensemble's stream) and time it."""
    from softcell.engine.cell import realization_rng

    model = build_model(params, TERMS, PROTOCOL, registry=default_registry())
    stepper = build_integrator(integrator, params, default_registry()).build(model)
    rng = realization_rng(seed, 0, 0)
    # Compile outside the timing: a throwaway run over two sample intervals.
    warm = parameters(
        float(params.radius),
        2 * float(params.sample_every),
        **{k: v for k, v in params.given.items() if k not in ("radius", "duration")},
    )
    warm_model = build_model(warm, TERMS, PROTOCOL, registry=default_registry())
    run_realization(
        warm_model,
        build_integrator(integrator, warm, default_registry()).build(warm_model),
        realization_rng(seed, 0, 0),
    )
    begin = time.perf_counter()
    record = run_realization(model, stepper, rng)
    wall = time.perf_counter() - begin
    statistics = getattr(stepper, "statistics", None)
    stats = (
        statistics(record.state)
        if statistics
        else {"steps": int(record.state["step"][0]), "rejected": 0}
    )
    return Run(record, wall, stats)


def contact_force(model: Model, record: Record) -> np.ndarray:
    """|contact force on the bot| (N) at each sample, from the contact term alone."""
    contact_only = build_model(model.params, ("contact",), PROTOCOL, registry=default_registry())
    weight = 2 * math.pi / model.nodes
    out = np.empty(record.times.size)
    for i in range(record.times.size):
        _, dpose = force_modes(contact_only, record.modes[i], record.pose[i])
        out[i] = weight * math.hypot(dpose[0], dpose[1])
    return out


def coarse_statistics(
    params: Parameters, record: Record, schedule_phase: np.ndarray
) -> dict[str, float]:
    """Mean cell speed in runs and in tumbles (cm/s), fraction of samples in go, mean bot-cell
    distance (cm) and fraction of samples in contact, over the whole record."""
    cell = record.modes[:, int(params.cutoff)]
    dt = np.diff(record.times)
    speed = np.abs(np.diff(cell)) / dt
    phase = schedule_phase[:-1]
    model = build_model(params, TERMS, PROTOCOL, registry=default_registry())
    force = contact_force(model, record)
    return {
        "cell_speed_run": float(speed[phase == RUN].mean()),
        "cell_speed_tumble": float(speed[phase == TUMBLE].mean()),
        "go_fraction": float(np.mean(speed > GO_THRESHOLD)),
        "bot_cell_distance": float(
            np.mean(np.abs(record.pose[:, 0] + 1j * record.pose[:, 1] - cell))
        ),
        "contact_fraction": float(
            np.mean(force > CONTACT_FRACTION_OF_F0 * float(params.drive_force))
        ),
    }


def path_difference(a: Record, b: Record, cutoff: int) -> dict[str, float]:
    """Largest distance (cm) between the two bot paths and the two cell (GC) paths, and the
    largest heading difference (rad), over the common samples."""
    if not np.array_equal(a.times, b.times):
        raise ValueError("the records are not sampled at the same times")
    bot = np.hypot(a.pose[:, 0] - b.pose[:, 0], a.pose[:, 1] - b.pose[:, 1])
    cell = np.abs(a.modes[:, cutoff] - b.modes[:, cutoff])
    return {
        "bot": float(bot.max()),
        "cell": float(cell.max()),
        "heading": float(np.abs(a.pose[:, 2] - b.pose[:, 2]).max()),
    }


def rodas4_rhs(model: Model, stepper, u: np.ndarray, phase: int = RUN) -> np.ndarray:
    """du/dt of rodas4's compiled right-hand side at the packed state ``u`` (cm, rad) in
    ``phase``, with the model's friction law; ``stepper`` is the model's rodas4 stepper."""
    out = np.zeros_like(u)
    stepper.rhs(u, phase, 0.0, out, stepper.problem._replace(membrane=True), stepper.ws)
    return out


def rodas4_jacobians(
    model: Model, stepper, u: np.ndarray, phase: int = RUN, step: float = 1e-7
) -> tuple[np.ndarray, np.ndarray]:
    """(rodas4's Jacobian at ``u``, central differences of :func:`rodas4_rhs` with ``step``
    in every unknown): the two should agree to the differences' truncation error."""
    rodas4_rhs(model, stepper, u, phase)  # the Jacobian reads what the rhs left at u
    stepper.jacobian(u, phase, 0.0, stepper.problem._replace(membrane=True), stepper.ws)
    jac = stepper.ws.jac.copy()
    diff = np.zeros_like(jac)
    for j in range(u.size):
        du = np.zeros_like(u)
        du[j] = step
        diff[:, j] = (
            rodas4_rhs(model, stepper, u + du, phase) - rodas4_rhs(model, stepper, u - du, phase)
        ) / (2 * step)
    return jac, diff


__all__ = [
    "Run",
    "parameters",
    "run",
    "coarse_statistics",
    "path_difference",
    "rodas4_rhs",
    "rodas4_jacobians",
]


def term_hessians(term, w: np.ndarray, pose: np.ndarray, context: np.ndarray, steps):
    """An energy term's second derivatives at the curve ``w`` (float64[6, N]: x, y and their
    first and second derivatives in xi, cm) and the bot's ``pose``, twice: from its
    ``hessian_kernel`` and by central differences of its partials with ``steps``
    (float64[9]: the step of each of the six curve quantities and the three pose
    coordinates). Returns (analytic, differences), each [hww (N, 6, 6), hwp (N, 6, 3),
    hpp (3, 3)]."""
    n = w.shape[1]
    coefficients = np.ascontiguousarray(term.coefficients())
    blank = lambda: [np.zeros((n, 6, 6)), np.zeros((n, 6, 3)), np.zeros((3, 3))]  # noqa: E731
    analytic, differences = blank(), blank()
    term.hessian_kernel()(*w, pose, context, coefficients, *analytic)
    work = [np.zeros(n), np.zeros((6, n)), np.zeros((6, n)), *(np.zeros(3) for _ in range(3))]
    fd_hessian(term.partials_kernel())(
        w.copy(),
        pose,
        context,
        coefficients,
        np.asarray(steps, dtype=np.float64),
        *work,
        *differences,
    )
    return analytic, differences
