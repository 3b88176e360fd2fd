"""Every component's kernels evaluated once at one state, to name the one that is not finite.

When a model is built, :func:`probe_components` runs each kernel of each component in use
(an energy term's partials, Hessian and bot kernels, the drive, the friction law and its
derivative) once on an initial state, before anything steps; a non-finite output is a
:class:`ContractError` naming the component's origin (distribution or built-in module), the
component, the kernel and the quantity. When a run fails later, :func:`diagnose` says which
component's output is the first to be non-finite at the last finite state or just ahead of it
on its course, or that none is.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

import numpy as np

from softcell.components.contracts import Component, Schedule, kind_name
from softcell.errors import ContractError

if TYPE_CHECKING:
    from softcell.components.contracts import Model

#: What each kernel writes, in the order of its output arguments.
PARTIALS_OUT = ("p0x", "p0y", "p1x", "p1y", "p2x", "p2y", "dpose")
FRICTION_OUT = ("vx", "vy")
DERIVATIVE_OUT = ("dxx", "dxy", "dyx", "dyy")


def _curve(modes: np.ndarray, n: int) -> list[np.ndarray]:
    """x, y, x', y', x'', y'' (cm) at n equally spaced xi of the curve with these modes."""
    from softcell.engine.reference import _curve as curve

    return [np.ascontiguousarray(p) for z in curve(modes, n) for p in (z.real, z.imag)]


def _sense(model: Model, modes: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """What the bot senses (:class:`~softcell.components.contracts.Sense`) at this state, at
    t = 0 s and the start of a phase: its pose, the force and torque of the energy terms on
    it, and its distance to the membrane's curve at its nodes (inf for a free bot)."""
    from softcell.components.contracts import SENSE_SIZE
    from softcell.engine.reference import force_modes

    sense = np.zeros(SENSE_SIZE)
    sense[:3] = pose
    load = np.zeros(3)
    sense[6] = np.inf
    if model.has_membrane:
        _, dpose = force_modes(model, modes, pose)
        load += 2 * np.pi / model.nodes * dpose
        x, y = _curve(modes, model.nodes)[:2]
        sense[6] = float(np.min(np.hypot(x - pose[0], y - pose[1])))
    for term in model.bot_terms:
        dpose = np.zeros(3)
        term.bot_kernel()(pose, model.context, np.ascontiguousarray(term.coefficients()), dpose)
        load += dpose
    sense[3:6] = -load
    return sense


def _evaluations(
    model: Model, modes: np.ndarray, pose: np.ndarray, phase: int, datum: float
) -> Iterator[tuple[Component, str, tuple[str, ...], Callable[[], list[np.ndarray]]]]:
    """(component, kernel method, output names, a call returning the outputs) for every kernel
    of every component in use."""
    pose = np.ascontiguousarray(pose, dtype=np.float64)
    ctx = model.context
    for term in model.terms:
        coef = np.ascontiguousarray(term.coefficients())
        if model.has_membrane:
            w = _curve(modes, model.nodes)

            def partials(term=term, coef=coef, w=w):
                out = [np.zeros(model.nodes) for _ in range(6)] + [np.zeros(3)]
                term.partials_kernel()(*w, pose, ctx, coef, *out)
                return out

            yield term, "partials_kernel", PARTIALS_OUT, partials
            if term.hessian_kernel() is not None:

                def hessian(term=term, coef=coef, w=w):
                    n = model.nodes
                    out = [np.zeros((n, 6, 6)), np.zeros((n, 6, 3)), np.zeros((3, 3))]
                    term.hessian_kernel()(*w, pose, ctx, coef, *out)
                    return out

                yield term, "hessian_kernel", ("hww", "hwp", "hpp"), hessian
        if term.bot_kernel() is not None:

            def bot(term=term, coef=coef):
                out = np.zeros(3)
                term.bot_kernel()(pose, ctx, coef, out)
                return [out]

            yield term, "bot_kernel", ("dpose",), bot
        if term.bot_hessian_kernel() is not None:

            def bot_hessian(term=term, coef=coef):
                out = np.zeros((3, 3))
                term.bot_hessian_kernel()(pose, ctx, coef, out)
                return [out]

            yield term, "bot_hessian_kernel", ("hpp",), bot_hessian

    def drive():
        out = np.zeros(3)
        model.protocol.drive_kernel()(
            np.int8(phase), float(datum), pose, ctx, model.drive_coefficients, out
        )
        return [out]

    yield model.protocol, "drive_kernel", ("force and torque",), drive
    if model.event is not None:

        def event():
            sense = _sense(model, modes, pose)
            value = model.event(np.int8(phase), float(datum), sense, model.drive_coefficients)
            return [np.array([value])]

        yield model.protocol, "event_kernel", ("event value",), event
    if model.nonlinear_friction:
        yield from _friction_evaluations(model, modes, pose)


def _friction_evaluations(model: Model, modes: np.ndarray, pose: np.ndarray):
    from softcell.engine.reference import law_inputs

    law = model.friction
    inputs = law_inputs(model, modes, pose)
    m = inputs[0].size
    coef = model.friction_coefficients

    def velocity():
        out = [np.zeros(m), np.zeros(m)]
        law.velocity_kernel()(*inputs, coef, *out)
        return out

    yield law, "velocity_kernel", FRICTION_OUT, velocity
    if law.derivative_kernel() is not None:

        def derivative():
            out = [np.zeros(m) for _ in range(4)]
            law.derivative_kernel()(*inputs, coef, *out)
            return out

        yield law, "derivative_kernel", DERIVATIVE_OUT, derivative


def first_non_finite(
    model: Model, modes: np.ndarray, pose: np.ndarray, phase: int, datum: float
) -> str | None:
    """``"<origin>: energy term 'posts': partials_kernel() wrote non-finite p0x at point 3
    of 1024"`` for the first kernel output that is not finite at this state (modes in
    cm, pose in cm, cm, rad; the protocol's phase code and datum), or None."""
    for component, method, names, call in _evaluations(model, modes, pose, phase, datum):
        try:
            outputs = call()
        except Exception as exc:  # a kernel that raises is named as one that returns NaN
            return f"{_who(model, component)}: {method}() raised {type(exc).__name__}: {exc}"
        for name, values in zip(names, outputs, strict=True):
            bad = ~np.isfinite(values)
            if bad.any():
                where = np.unravel_index(int(np.argmax(bad)), values.shape)
                at = f" at index {tuple(int(i) for i in where)}" if values.ndim > 1 else ""
                if values.ndim == 1 and name not in ("dpose", "force and torque"):
                    at = f" at point {int(where[0])} of {values.size}"
                return f"{_who(model, component)}: {method}() wrote non-finite {name}{at}"
    return None


def _who(model: Model, component: Component) -> str:
    kind = kind_name(component.kind)
    origin = model.origins.get(f"{component.kind} {component.name}", "unknown origin")
    return f"{origin}: {kind} {component.name!r}"


def probe_components(model: Model) -> None:
    """Evaluate every kernel of every component in use once at an initial state: the state
    :func:`~softcell.engine.state.initial_state` draws with the seed 0 (the membrane's
    circle about the origin, the bot at the origin), in the schedule's first phase.

    Raises
    ------
    ContractError
        One line naming the origin, the component, the kernel and the quantity of the first
        non-finite output, before any time step.
    """
    from softcell.engine.state import initial_state

    modes, pose, schedule = initial_state(model, np.random.default_rng(0))
    found = first_non_finite(model, modes, pose, int(schedule.phase[0]), float(schedule.data[0]))
    if found is not None:
        raise ContractError(f"{found} at the initial state (t = 0 s), before any time step")


def _phase(schedule: Schedule, t: float) -> tuple[int, float]:
    index = max(int(np.searchsorted(schedule.start, t, side="right")) - 1, 0)
    return int(schedule.phase[index]), float(schedule.data[index])


#: How far ahead of the last finite state :func:`diagnose` looks, as fractions of a horizon
#: (the time to the failure, or since the state before).
AHEAD = tuple(2.0**-e for e in range(12, -1, -1))


def _velocity(
    model: Model, modes: np.ndarray, pose: np.ndarray, phase: int, datum: float
) -> tuple[np.ndarray, np.ndarray] | None:
    """d modes/dt (cm/s) and d pose/dt (cm/s, cm/s, rad/s) with the viscous law (the course a
    state is on, for :func:`diagnose`), or None where not finite."""
    from softcell.engine.reference import force_modes

    pose = np.ascontiguousarray(pose, dtype=np.float64)
    load = np.zeros(3)
    model.protocol.drive_kernel()(
        np.int8(phase), float(datum), pose, model.context, model.drive_coefficients, load
    )
    dmodes = np.zeros_like(modes)
    if model.has_membrane:
        fhat, dpose = force_modes(model, modes, pose)
        dmodes = model.membrane_mobility * fhat
        load -= 2 * np.pi / model.nodes * dpose
    for term in model.bot_terms:
        dpose = np.zeros(3)
        term.bot_kernel()(pose, model.context, np.ascontiguousarray(term.coefficients()), dpose)
        load -= dpose
    dpose = model.bot_mobility * load
    if not (np.all(np.isfinite(dmodes)) and np.all(np.isfinite(dpose))):
        return None
    return dmodes, dpose


def diagnose(
    model: Model, times: np.ndarray, modes: np.ndarray, pose: np.ndarray, schedule: Schedule
) -> str:
    """Why a run failed, as far as the components tell: the first non-finite kernel output at
    the last finite state, or just ahead of it on its course (an implicit step fails on trial
    states it never accepts; an explicit one jumps past the state where a kernel fails).

    Parameters
    ----------
    times : float64[K]
        Times (s) of the states, in the order reached (the last row: where the integrator
        got to; rows after the last finite one: where the run was found to have failed).
    modes, pose : complex128[K, 2 Lc + 1] (cm), float64[K, 3] (cm, cm, rad)
        The states.
    schedule : Schedule
        The realization's phases.

    Returns
    -------
    str
        One phrase, naming the component or saying that every kernel is finite.
    """
    finite = np.all(np.isfinite(modes), axis=1) & np.all(np.isfinite(pose), axis=1)
    rows = np.flatnonzero(finite)
    if not rows.size:
        return "no finite state to examine"
    k = int(rows[-1])
    t_k = float(times[k])
    found = first_non_finite(model, modes[k], pose[k], *_phase(schedule, t_k))
    if found is not None:
        return f"at the last finite state (t = {t_k:g} s) the first non-finite output is {found}"
    horizon = float(np.max(times)) - t_k
    if horizon <= 0:
        earlier = times[rows][times[rows] < t_k]
        horizon = t_k - float(earlier.max()) if earlier.size else 0.0
    course = _velocity(model, modes[k], pose[k], *_phase(schedule, t_k))
    if course is not None and horizon > 0:
        for fraction in AHEAD:
            dt = fraction * horizon
            found = first_non_finite(
                model,
                modes[k] + dt * course[0],
                pose[k] + dt * course[1],
                *_phase(schedule, t_k + dt),
            )
            if found is not None:
                return (
                    f"every kernel is finite at the last finite state (t = {t_k:g} s); just "
                    f"ahead of it on its course (t = {t_k + dt:.6g} s) the first non-finite "
                    f"output is {found}"
                )
    return (
        f"every component's kernels are finite at the last finite state (t = {t_k:g} s) and "
        "just ahead of it: the integration itself diverged (reduce dt or tighten the "
        "tolerances)"
    )
