"""rodas4 on one ring with several bots: the membrane's own terms once, the terms that read
the bot's pose (the contact) once per bot, the energies of each bot alone, and the bots'
interactions, stepped together by RODAS4 with the same control as one bot, landing on every
bot's switches. Compiled per component set by
:func:`softcell.integrators.rodas4.several.compiled_bots`.

Unknowns: Re g_k, Im g_k (k = -Lc..Lc, cm), then each bot's x, y (cm) and heading (rad).

Bound: ``rhs_m``, ``jacobian_m`` (the single-bot loop's, from ``loop.py``, of the terms that
do not read the pose; its pose slot holds bot 0's and its pose rows are not read),
``rhs_c``, ``jacobian_c`` (the same of the terms that read it, with the drive; evaluated once
per bot), ``HAS_BOT``, ``bot_forces``, ``bot_hessians`` (the energies of a bot alone, summed
over every term, :func:`softcell.engine.compose.compose_bot`), ``HAS_INTERACT``, ``interact``
and ``interact_jacobian`` (the bot interactions' kernels and Jacobians summed,
:func:`softcell.engine.compose.compose_interaction_jacobians`: each one's own, or central
differences of its kernel with steps ``ws.steps[6:9]``, 1e-7 l0 / 2 pi in x and y and 1e-7
rad). Only the viscous friction law (the membrane's velocities of the parts are summed)
and no state events.
"""

from typing import TYPE_CHECKING

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
    judge,
    trial_step,
)

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        rhs_m,
        jacobian_m,
        rhs_c,
        jacobian_c,
        HAS_BOT,
        bot_forces,
        bot_hessians,
        HAS_INTERACT,
        interact,
        interact_jacobian,
        JIT_FLAGS,
    ) = (None,) * 11


#: The names this template expects the loader to bind (besides the numba flags).
BOUND = (
    "rhs_m",
    "jacobian_m",
    "rhs_c",
    "jacobian_c",
    "HAS_BOT",
    "bot_forces",
    "bot_hessians",
    "HAS_INTERACT",
    "interact",
    "interact_jacobian",
)


@njit(**JIT_FLAGS)
def _set_pose(uc, u, m2, b):
    for c in range(3):
        uc[m2 + c] = u[m2 + 3 * b + c]


@njit(**JIT_FLAGS)
def _near(u, m2, a, b, reach):
    dx = u[m2 + 3 * b] - u[m2 + 3 * a]
    dy = u[m2 + 3 * b + 1] - u[m2 + 3 * a + 1]
    return dx * dx + dy * dy <= reach * reach


@njit(**JIT_FLAGS)
def _pair(u, m2, a, b, bp, bw):
    """The interactions' generalized forces on bots a and b into ``bw.pair_out[0:6]``."""
    for c in range(3):
        bw.pose_a[c] = u[m2 + 3 * a + c]
        bw.pose_b[c] = u[m2 + 3 * b + c]
    bw.pair_out[:] = 0.0
    interact(bw.pose_a, bw.pose_b, bp.context, bp.interactions, bw.pair_out)


@njit(**JIT_FLAGS)
def bots_rhs(u, phases, data, out, bp, bw):
    """du/dt at u (each bot's phase and datum fixed)."""
    k = phases.size
    uc, scratch = bw.uc, bw.scratch
    m2 = uc.size - 3
    mob = bp.bot_mobility
    for i in range(m2):
        uc[i] = u[i]
    _set_pose(uc, u, m2, 0)
    rhs_m(uc, phases[0], data[0], scratch, bp.problem_m, bw.ws_m)
    for i in range(m2):
        out[i] = scratch[i]
    for b in range(k):
        _set_pose(uc, u, m2, b)
        rhs_c(uc, phases[b], data[b], scratch, bp.problem_c, bw.ws_c)
        for i in range(m2):
            out[i] += scratch[i]
        for c in range(3):
            out[m2 + 3 * b + c] = scratch[m2 + c]
    if HAS_BOT:
        for b in range(k):
            _set_pose(uc, u, m2, b)
            bw.drag[:] = 0.0
            bot_forces(uc[m2:], bp.context, bp.coefficients, bw.drag)
            for c in range(3):
                out[m2 + 3 * b + c] -= mob[c] * bw.drag[c]
    if HAS_INTERACT:
        for a in range(k):
            for b in range(a + 1, k):
                if not _near(u, m2, a, b, bp.reach):
                    continue
                _pair(u, m2, a, b, bp, bw)
                for c in range(3):
                    out[m2 + 3 * a + c] += mob[c] * bw.pair_out[c]
                    out[m2 + 3 * b + c] += mob[c] * bw.pair_out[3 + c]


@njit(**JIT_FLAGS)
def _interaction_jacobian(u, m2, a, b, bp, bw, jac):
    """Add the pair (a, b)'s interaction Jacobian, scaled by the bots' mobilities."""
    mob = bp.bot_mobility
    for c in range(3):
        bw.pose_a[c] = u[m2 + 3 * a + c]
        bw.pose_b[c] = u[m2 + 3 * b + c]
    bw.pair_jac[:, :] = 0.0
    interact_jacobian(
        bw.pose_a, bw.pose_b, bp.context, bp.interactions, bw.ws_c.steps, bw.pair_scratch,
        bw.pair_jac,
    )  # fmt: skip
    for j in range(6):
        col = m2 + 3 * (a if j < 3 else b) + j % 3
        for c in range(3):
            jac[m2 + 3 * a + c, col] += mob[c] * bw.pair_jac[c, j]
            jac[m2 + 3 * b + c, col] += mob[c] * bw.pair_jac[3 + c, j]


@njit(**JIT_FLAGS)
def bots_jacobian(u, phases, data, bp, bw, jac):  # noqa: C901
    """The Jacobian at u into ``jac``: the membrane's terms' block, each bot's contact and
    drive blocks (each single-bot part evaluated again first, for the grids it reads), the
    bots' own energies and their interactions."""
    k = phases.size
    uc, scratch = bw.uc, bw.scratch
    m2 = uc.size - 3
    mob = bp.bot_mobility
    jac[:, :] = 0.0
    for i in range(m2):
        uc[i] = u[i]
    _set_pose(uc, u, m2, 0)
    rhs_m(uc, phases[0], data[0], scratch, bp.problem_m, bw.ws_m)
    jacobian_m(uc, phases[0], data[0], bp.problem_m, bw.ws_m)
    jm = bw.ws_m.jac
    for i in range(m2):
        for j in range(m2):
            jac[i, j] = jm[i, j]
    jc = bw.ws_c.jac
    for b in range(k):
        _set_pose(uc, u, m2, b)
        rhs_c(uc, phases[b], data[b], scratch, bp.problem_c, bw.ws_c)
        jacobian_c(uc, phases[b], data[b], bp.problem_c, bw.ws_c)
        p = m2 + 3 * b
        for i in range(m2):
            for j in range(m2):
                jac[i, j] += jc[i, j]
            for c in range(3):
                jac[i, p + c] = jc[i, m2 + c]
                jac[p + c, i] = jc[m2 + c, i]
        for c in range(3):
            for d in range(3):
                jac[p + c, p + d] = jc[m2 + c, m2 + d]
    if HAS_BOT:
        ws = bw.ws_c
        for b in range(k):
            _set_pose(uc, u, m2, b)
            bw.hpp[:, :] = 0.0
            bot_hessians(
                uc[m2:], bp.context, bp.coefficients, ws.steps, ws.pose_tmp, ws.dplus,
                ws.dminus, bw.hpp,
            )  # fmt: skip
            p = m2 + 3 * b
            for c in range(3):
                for d in range(3):
                    jac[p + c, p + d] -= mob[c] * bw.hpp[c, d]
    if HAS_INTERACT:
        for a in range(k):
            for b in range(a + 1, k):
                if _near(u, m2, a, b, bp.reach):
                    _interaction_jacobian(u, m2, a, b, bp, bw, jac)


@njit(**JIT_FLAGS)
def stage_rhs(y, out, args):
    """The right-hand side in the form of :func:`softcell.engine.kernels.rosenbrock.stages`."""
    phases, data, bp, bw = args
    bots_rhs(y, phases, data, out, bp, bw)


@njit(**JIT_FLAGS)
def _next_switch(starts, offsets, p):
    """The earliest start of a next phase among the bots (s), inf if none."""
    t_switch = 1e300
    for c in range(p.size):
        if offsets[c] + p[c] + 1 < offsets[c + 1]:
            t_switch = min(t_switch, starts[offsets[c] + p[c] + 1])
    return t_switch


@njit(**JIT_FLAGS)
def _phases(phases_all, data_all, offsets, p, phases, data):
    for c in range(p.size):
        phases[c] = phases_all[offsets[c] + p[c]]
        data[c] = data_all[offsets[c] + p[c]]


@njit(**JIT_FLAGS)
def advance_bots(state, t_end, sample, schedule, bp, control, tableau, bw, gw):  # noqa: C901
    """Step until the clock reaches ``t_end`` (s), then write the state there into
    ``sample``; returns a status code. ``schedule`` = (starts, phases, data, offsets): the
    bots' schedules one after the other, bot c's from ``offsets[c]``; ``state``'s
    ``phase_index`` holds one index per bot."""
    u, clock, p, counters, dense = state
    starts, phases_all, data_all, offsets = schedule
    atol, rtol, max_step = control
    a, cc, hd = tableau
    phases, data = gw.phases, gw.data
    t = clock[T]
    eps = 1e-12 * (1.0 + abs(t_end))
    while t < t_end - eps:
        t_switch = _next_switch(starts, offsets, p)
        _phases(phases_all, data_all, offsets, p, phases, data)
        bots_rhs(u, phases, data, gw.f0, bp, bw)
        bots_jacobian(u, phases, data, bp, bw, gw.jac)
        counters[RHS_CALLS] += 1
        counters[JACOBIANS] += 1
        h_rejected = err_rejected = 0.0
        while True:
            h, land = trial_step(clock, max_step, t, t_switch)
            if h <= 1e-14 * (1.0 + abs(t)):
                return STEP_UNDERFLOW
            if not factor_iteration_matrix(gw.jac, h, GAMMA, gw.mat, gw.pivots):
                return SINGULAR
            stages(
                stage_rhs, (phases, data, bp, bw), u, gw.f0, h, a, cc, gw.mat, gw.pivots,
                gw.k, gw.y, gw.force,
            )  # fmt: skip
            counters[RHS_CALLS] += cc.shape[0] - 1
            err = error_norm(u, gw.y, gw.k, atol, rtol, gw.ynew)
            accepted, h_new, err = judge(err, h, clock, h_rejected, err_rejected, counters)
            if accepted:
                dense_output(u, gw.ynew, gw.k, hd, dense)
                for i in range(u.size):
                    u[i] = gw.ynew[i]
                clock[T_LAST] = t
                clock[H_LAST] = h
                if land:
                    t = t_switch
                    clock[H_ACCEPTED] = 0.0
                    for c in range(p.size):
                        nxt = offsets[c] + p[c] + 1
                        if nxt < offsets[c + 1] and starts[nxt] <= t_switch:
                            p[c] += 1
                else:
                    t = t + h
                clock[T] = t
                clock[H_NEXT] = h_new
                counters[STEPS] += 1
                break
            h_rejected, err_rejected = h, err
    if abs(t - t_end) <= eps or clock[H_LAST] == 0.0:
        for i in range(u.size):
            sample[i] = u[i]
    else:
        dense_value(dense, (t_end - clock[T_LAST]) / clock[H_LAST], sample)
    return OK


@njit(**JIT_FLAGS)
def integrate_bots(state, targets, samples, schedule, bp, control, tableau, bw, gw):
    """For each time of ``targets`` (increasing, s): :func:`advance_bots` to it, writing the
    state there into the matching row of ``samples``. Returns a status code."""
    for r in range(targets.size):
        status = advance_bots(state, targets[r], samples[r], schedule, bp, control, tableau, bw, gw)
        if status != OK:
            return status
    return OK
