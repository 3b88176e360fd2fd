"""rodas4 on a group of cells in contact: the cells' own right-hand sides and Jacobians (one
block each, from the single-cell loop) plus the membrane-membrane pair forces of
:mod:`softcell.engine.kernels.pairs`, stepped together by RODAS4 with the same control as one cell,
landing on every member's switches. Compiled per component set by
:func:`softcell.integrators.rodas4.compiled_group`.

Bound: ``rhs`` and ``jacobian`` (the single-cell loop's, from ``loop.py``),
``pair_law`` (the pair terms' laws summed, :func:`softcell.engine.compose.compose_pair_laws`)
and ``JIT_FLAGS`` (the pair kernels inlined here allocate their scratch arrays, so numba
counts references). Only the viscous friction law: the pair forces move the modes by the
membrane's mobility.
"""

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from softcell.engine.kernels.pairs import find_contacts, membrane_points, pair_forces, pair_jacobian
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
        rhs,
        jacobian,
        pair_law,
        JIT_FLAGS,
    ) = (None,) * 4


#: The names this template expects the loader to bind (besides the flags).
BOUND = ("rhs", "jacobian", "pair_law")

#: Status: more contacts than the contact table holds.
TOO_MANY_CONTACTS = 3


@njit(**JIT_FLAGS)
def _points(u, pair):
    """Every member's N membrane points at the group state u into ``pair.z``."""
    g = pair.z.shape[0]
    nu = u.size // g
    m = (nu - 3) // 2
    for c in range(g):
        for j in range(m):
            pair.modes[j] = complex(u[c * nu + j], u[c * nu + m + j])
        membrane_points(pair.modes, pair.spec, pair.z[c])


@njit(**JIT_FLAGS)
def group_rhs(u, phases, data, out, problem, ws, pair):
    """du/dt of the group at u (each member's phase and datum fixed); returns the number of
    contacts, or -1 if the contact table is full."""
    g = phases.size
    nu = u.size // g
    for c in range(g):
        rhs(u[c * nu : (c + 1) * nu], phases[c], data[c], out[c * nu : (c + 1) * nu], problem, ws)
    _points(u, pair)
    count = find_contacts(pair.z, pair.shifts, pair.constants[0], pair.contacts)
    if count < 0:
        return -1
    pair_forces(
        pair.z, pair.shifts, pair.contacts, count, pair_law, pair.laws, pair.constants[1],
        pair.twiddle, out, nu,
    )  # fmt: skip
    return count


@njit(**JIT_FLAGS)
def group_jacobian(u, phases, data, problem, ws, pair, jac, scratch):
    """The group's Jacobian at u into ``jac``: each member's block (its rhs is evaluated
    again first, into ``scratch``, for the grids the block reads) and the pair forces'.
    Returns the number of contacts, or -1."""
    g = phases.size
    nu = u.size // g
    jac[:, :] = 0.0
    for c in range(g):
        uc = u[c * nu : (c + 1) * nu]
        rhs(uc, phases[c], data[c], scratch, problem, ws)
        jacobian(uc, phases[c], data[c], problem, ws)
        for i in range(nu):
            for j in range(nu):
                jac[c * nu + i, c * nu + j] = ws.jac[i, j]
    _points(u, pair)
    count = find_contacts(pair.z, pair.shifts, pair.constants[0], pair.contacts)
    if count < 0:
        return -1
    pair_jacobian(
        pair.z, pair.shifts, pair.contacts, count, pair_law, pair.laws, pair.constants[1],
        pair.twiddle, pair.constants[2], jac,
    )  # fmt: skip
    return count


@njit(**JIT_FLAGS)
def stage_rhs(y, out, args):
    """The group's right-hand side in the form of
    :func:`softcell.engine.kernels.rosenbrock.stages`."""
    phases, data, problem, ws, pair = args
    if group_rhs(y, phases, data, out, problem, ws, pair) < 0:
        out[:] = np.nan  # rejected by the error norm; the next Jacobian reports it


@njit(**JIT_FLAGS)
def _next_switch(starts, offsets, p):
    """The earliest start of a next phase among the members (s), np.inf if none."""
    t_switch = np.inf
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
def advance_group(state, t_end, sample, schedule, problem, control, tableau, ws, gw, pair):  # noqa: C901
    """Step the group until the clock reaches ``t_end`` (s), then write the state there into
    ``sample``; returns a status code. ``schedule`` = (starts, phases, data, offsets): the
    members' schedules one after the other, member c's from ``offsets[c]``; ``state``'s
    ``phase_index`` holds one index per member."""
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
        if group_rhs(u, phases, data, gw.f0, problem, ws, pair) < 0:
            return TOO_MANY_CONTACTS
        if group_jacobian(u, phases, data, problem, ws, pair, gw.jac, gw.scratch) < 0:
            return TOO_MANY_CONTACTS
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
                stage_rhs,
                (phases, data, problem, ws, pair),
                u,
                gw.f0,
                h,
                a,
                cc,
                gw.mat,
                gw.pivots,
                gw.k,
                gw.y,
                gw.force,
            )
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
