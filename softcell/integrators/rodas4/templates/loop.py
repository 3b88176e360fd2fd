"""rodas4's right-hand side, its Jacobian and the compiled time loop, compiled per component
set by :func:`softcell.integrators.rodas4.compiled_loop`: steps of the generic Rosenbrock method
with RODAS4's tableau, step-size control, landing on the protocol's switches, and samples from
the continuous extension.

Bound: ``forces_s``, ``jacobian_s`` (the smooth terms on the coarse grid), ``forces_f``,
``jacobian_f`` (the other terms on the N points), ``HAS_S``, ``ORDER_S``, ``HAS_F``,
``ORDER_F`` (whether each group has terms, and the highest curve derivative it needs),
``drive``, ``drive_jacobian``, ``event``, ``HAS_EVENT`` (the protocol's event kernel,
and whether it has one), ``LAW`` (whether the friction law is nonlinear; then
``friction_velocity`` and ``friction_jacobian`` are its compiled functions, from
``engine/templates/friction_law.py``), ``HAS_BOT_S``, ``HAS_BOT_F`` (whether a group has
energies of the bot alone; then ``bot_forces_s``/``_f`` and ``bot_hessians_s``/``_f`` are
their sums, from :func:`softcell.engine.compose.compose_bot`) and ``LEAN_JIT_FLAGS``.
"""

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from softcell.engine.kernels.rosenbrock import (
    dense_output,
    dense_value,
    error_norm,
    factor_iteration_matrix,
    stages,
)
from softcell.integrators.rodas4.method import (
    GAMMA,
    H_ACCEPTED,
    H_LAST,
    H_NEXT,
    JACOBIANS,
    OK,
    RHS_CALLS,
    SINGULAR,
    STEP_UNDERFLOW,
    STEPS,
    T_LAST,
    T,
    accumulate,
    judge,
    trial_step,
)

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        forces_s,
        jacobian_s,
        HAS_S,
        ORDER_S,
        HAS_BOT_S,
        bot_forces_s,
        bot_hessians_s,
        forces_f,
        jacobian_f,
        HAS_F,
        ORDER_F,
        HAS_BOT_F,
        bot_forces_f,
        bot_hessians_f,
        drive,
        drive_jacobian,
        event,
        HAS_EVENT,
        LAW,
        friction_velocity,
        friction_jacobian,
        LEAN_JIT_FLAGS,
    ) = (None,) * 22


#: The names this template expects the loader to bind (besides the numba flags); a missing
#: or an extra binding is an error naming the template.
BOUND = (
    "forces_s",
    "jacobian_s",
    "HAS_S",
    "ORDER_S",
    "HAS_BOT_S",
    "bot_forces_s",
    "bot_hessians_s",
    "forces_f",
    "jacobian_f",
    "HAS_F",
    "ORDER_F",
    "HAS_BOT_F",
    "bot_forces_f",
    "bot_hessians_f",
    "drive",
    "drive_jacobian",
    "event",
    "HAS_EVENT",
    "LAW",
    "friction_velocity",
    "friction_jacobian",
)


@njit(**LEAN_JIT_FLAGS)
def rhs(u, phase, datum, out, problem, ws):
    """du/dt at u (phase fixed); leaves the curves at u in the grids' ``w``. ``problem`` is
    a :class:`~softcell.integrators.rodas4.method.Problem` (``coefficients``: the smooth group's
    and the other group's)."""
    coefficients, context, drive_coefficients, mobility, bot_mobility, membrane = problem
    m = ws.modes.size
    pose = u[2 * m :]
    drag = ws.drag
    drag[:] = 0.0
    if membrane:
        for j in range(m):
            ws.modes[j] = complex(u[j], u[m + j])
        for j in range(m):
            out[j] = 0.0
            out[m + j] = 0.0
        if HAS_S:
            forces_s(ws.modes, pose, ORDER_S, context, coefficients[0], ws.smooth)
            accumulate(ws.smooth, mobility, out, drag)
        if HAS_F:
            forces_f(ws.modes, pose, ORDER_F, context, coefficients[1], ws.fine)
            accumulate(ws.fine, mobility, out, drag)
        if LAW:  # out holds the force modes (mobility 1): move by the law's velocity
            lw = ws.law
            for j in range(m):
                lw.fhat[j] = complex(out[j], out[m + j])
            friction_velocity(ws.modes, lw.fhat, lw.vhat, lw)
            for j in range(m):
                out[j] = lw.vhat[j].real
                out[m + j] = lw.vhat[j].imag
    else:
        out[: 2 * m] = 0.0
    if HAS_BOT_S:
        bot_forces_s(pose, context, coefficients[0], drag)
    if HAS_BOT_F:
        bot_forces_f(pose, context, coefficients[1], drag)
    drive(phase, datum, pose, context, drive_coefficients, ws.drv)
    for c in range(3):
        out[2 * m + c] = bot_mobility[c] * (ws.drv[c] - drag[c])


@njit(**LEAN_JIT_FLAGS)
def jacobian(u, phase, datum, problem, ws):
    """The Jacobian at u into ``ws.jac``; the grids' ``w`` (and, with a nonlinear friction
    law, ``ws.law``) must hold what :func:`rhs` left there at u."""
    coefficients, context, drive_coefficients, mobility, bot_mobility, membrane = problem
    m = ws.modes.size
    pose = u[2 * m :]
    ws.jac[:, :] = 0.0
    if membrane:
        if HAS_S:
            jacobian_s(pose, context, coefficients[0], mobility, bot_mobility, ws.smooth, ws)
        if HAS_F:
            jacobian_f(pose, context, coefficients[1], mobility, bot_mobility, ws.fine, ws)
        if LAW:
            friction_jacobian(ws.jac, ws.law)
    drive_jacobian(
        phase,
        datum,
        pose,
        context,
        drive_coefficients,
        ws.steps,
        ws.pose_tmp,
        ws.drv_plus,
        ws.drv_minus,
        ws.djac,
    )
    for c in range(3):
        for d in range(3):
            ws.jac[2 * m + c, 2 * m + d] += bot_mobility[c] * ws.djac[c, d]
    if HAS_BOT_S or HAS_BOT_F:
        hpp = ws.bot_hpp
        hpp[:, :] = 0.0
        if HAS_BOT_S:
            bot_hessians_s(
                pose, context, coefficients[0], ws.steps, ws.pose_tmp, ws.dplus, ws.dminus, hpp
            )
        if HAS_BOT_F:
            bot_hessians_f(
                pose, context, coefficients[1], ws.steps, ws.pose_tmp, ws.dplus, ws.dminus, hpp
            )
        for c in range(3):
            for d in range(3):
                ws.jac[2 * m + c, 2 * m + d] -= bot_mobility[c] * hpp[c, d]


@njit(**LEAN_JIT_FLAGS)
def stage_rhs(y, out, args):
    """The right-hand side in the form of :func:`softcell.engine.kernels.rosenbrock.stages`."""
    phase, datum, problem, ws = args
    rhs(y, phase, datum, out, problem, ws)


@njit(**LEAN_JIT_FLAGS)
def membrane_distance(u, m, x, y):
    """The distance (cm) from (x, y) to the membrane's curve of modes u[:m] + i u[m:2m]
    (g_k, k = -Lc..Lc), sampled at 8 m points: each point by Horner's rule in e^{i xi}."""
    lc = (m - 1) // 2
    points = 8 * m
    best = np.inf
    for n in range(points):
        xi = 2.0 * math.pi * n / points
        w = complex(math.cos(xi), math.sin(xi))
        acc = complex(u[m - 1], u[2 * m - 1])
        for j in range(m - 2, -1, -1):
            acc = acc * w + complex(u[j], u[m + j])
        z = acc * complex(math.cos(lc * xi), -math.sin(lc * xi))
        best = min(best, math.hypot(z.real - x, z.imag - y))
    return best


@njit(**LEAN_JIT_FLAGS)
def event_at(u, t, t_phase, phase, datum, problem, ws, scratch):
    """The event kernel's value at the state u at time t (s), in a phase begun at t_phase
    (s): evaluates the right-hand side into ``scratch`` for the force on the bot."""
    rhs(u, phase, datum, scratch, problem, ws)
    m = ws.modes.size
    sense = ws.sense
    for c in range(3):
        sense[c] = u[2 * m + c]
        sense[3 + c] = -ws.drag[c]
    sense[6] = membrane_distance(u, m, u[2 * m], u[2 * m + 1]) if problem[5] else np.inf
    sense[7] = t
    sense[8] = t - t_phase
    return event(phase, datum, sense, problem[2])


@njit(**LEAN_JIT_FLAGS)
def locate(dense, t0, h, phase, datum, t_phase, problem, ws):
    """The fraction of the last step [t0, t0 + h] (s) at which the event first reaches 0,
    by the Illinois method on the continuous extension, to 1e-9 s; the state there is left
    in ``ws.y``."""
    lo, hi = 0.0, 1.0
    dense_value(dense, 0.0, ws.y)
    g_lo = event_at(ws.y, t0, t_phase, phase, datum, problem, ws, ws.ynew)
    dense_value(dense, 1.0, ws.y)
    g_hi = event_at(ws.y, t0 + h, t_phase, phase, datum, problem, ws, ws.ynew)
    side = 0
    for _ in range(200):
        if (hi - lo) * h <= 1e-9:
            break
        if g_hi - g_lo > 0.0 and math.isfinite(g_hi - g_lo):
            mid = hi - g_hi * (hi - lo) / (g_hi - g_lo)
            mid = min(max(mid, lo + 0.01 * (hi - lo)), hi - 0.01 * (hi - lo))
        else:
            mid = 0.5 * (lo + hi)
        dense_value(dense, mid, ws.y)
        g = event_at(ws.y, t0 + mid * h, t_phase, phase, datum, problem, ws, ws.ynew)
        if g >= 0.0:
            hi, g_hi = mid, g
            if side == 1:
                g_lo *= 0.5
            side = 1
        else:
            lo, g_lo = mid, g
            if side == -1:
                g_hi *= 0.5
            side = -1
    dense_value(dense, hi, ws.y)
    return hi


@njit(**LEAN_JIT_FLAGS)
def end_phase(starts, p, t, log):
    """Phase p ends at t (s): the later phases start that much earlier; t is logged."""
    if p + 1 < starts.size:
        shift = t - starts[p + 1]
        for q in range(p + 1, starts.size):
            starts[q] += shift
    n = log.count[0]
    if n < log.times.size:
        log.times[n] = t
        log.count[0] = n + 1


@njit(**LEAN_JIT_FLAGS)
def advance_to(state, t_end, sample, schedule, problem, control, tableau, ws, log):  # noqa: C901
    """Step until the clock reaches ``t_end`` (s), then write the state there into
    ``sample``; returns a status code. ``state``, ``schedule``, ``problem``, ``control``,
    ``tableau`` and ``log`` are the records of :mod:`softcell.integrators.rodas4.method`; with an
    event kernel, ``schedule.starts`` is shifted in place as events end phases."""
    u, clock, phase_index, counters, dense = state
    starts, phases, data = schedule
    atol, rtol, max_step = control
    a, cc, hd = tableau
    t = clock[T]
    p = phase_index[0]
    k = ws.k
    y = ws.y
    ynew = ws.ynew
    force = ws.force
    mat = ws.mat
    eps = 1e-12 * (1.0 + abs(t_end))
    while t < t_end - eps:
        if HAS_EVENT:
            while p + 1 < starts.size and starts[p + 1] <= t:
                p += 1
            # A phase whose event holds as it begins ends at once.
            while (
                p + 1 < starts.size
                and t <= starts[p]
                and event_at(u, t, starts[p], phases[p], data[p], problem, ws, ws.f0) >= 0.0
            ):
                end_phase(starts, p, t, log)
                p += 1
        t_switch = starts[p + 1] if p + 1 < starts.size else np.inf
        phase, datum = phases[p], data[p]
        rhs(u, phase, datum, ws.f0, problem, ws)
        jacobian(u, phase, datum, problem, ws)
        counters[RHS_CALLS] += 1
        counters[JACOBIANS] += 1
        h_rejected = err_rejected = 0.0
        while True:
            h, land = trial_step(clock, max_step, t, t_switch)
            if h <= 1e-14 * (1.0 + abs(t)):
                return STEP_UNDERFLOW
            if not factor_iteration_matrix(ws.jac, h, GAMMA, mat, ws.pivots):
                return SINGULAR
            stages(
                stage_rhs,
                (phase, datum, problem, ws),
                u,
                ws.f0,
                h,
                a,
                cc,
                mat,
                ws.pivots,
                k,
                y,
                force,
            )
            counters[RHS_CALLS] += cc.shape[0] - 1
            err = error_norm(u, y, k, atol, rtol, ynew)
            accepted, h_new, err = judge(err, h, clock, h_rejected, err_rejected, counters)
            if accepted:
                dense_output(u, ynew, k, hd, dense)
                for i in range(u.size):
                    u[i] = ynew[i]
                clock[T_LAST] = t
                clock[H_LAST] = h
                t_new = t_switch if land else t + h
                if (
                    HAS_EVENT
                    and p + 1 < starts.size
                    and event_at(u, t_new, starts[p], phase, datum, problem, ws, ynew) >= 0.0
                ):
                    # The event crossed zero during this step: go on from where it did.
                    frac = locate(dense, t, h, phase, datum, starts[p], problem, ws)
                    t_new = t + frac * h
                    for i in range(u.size):
                        u[i] = ws.y[i]
                    end_phase(starts, p, t_new, log)
                    p += 1
                    clock[H_ACCEPTED] = 0.0
                elif land:
                    p += 1
                    clock[H_ACCEPTED] = 0.0
                t = t_new
                clock[T] = t
                clock[H_NEXT] = h_new
                counters[STEPS] += 1
                break
            h_rejected, err_rejected = h, err
    phase_index[0] = p
    if abs(t - t_end) <= eps or clock[H_LAST] == 0.0:
        for i in range(u.size):
            sample[i] = u[i]
    else:
        dense_value(dense, (t_end - clock[T_LAST]) / clock[H_LAST], sample)
    return OK


@njit(**LEAN_JIT_FLAGS)
def integrate(state, targets, samples, schedule, problem, control, tableau, ws, log):
    """For each time of ``targets`` (increasing, s): step until the clock reaches it, then
    write the state there into the matching row of ``samples`` from the last step's
    continuous extension. Returns a status code."""
    for r in range(targets.size):
        status = advance_to(
            state, targets[r], samples[r], schedule, problem, control, tableau, ws, log
        )
        if status != OK:
            return status
    return OK
