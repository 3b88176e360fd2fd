"""RODAS4's coefficients, its step-size control, the status codes and state slots of its
compiled loop, and the loop's small kernels: what the integrator
(:mod:`softcell.integrators.rodas4`) and its template (``templates/loop.py``) share, so that
neither imports the other.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from softcell.engine.kernels.rosenbrock import Tableau
from softcell.settings import LEAN_JIT

# RODAS4 in Hairer & Wanner's transformed variables: gamma, a_ij, c_ij, dense output h_ij.
GAMMA = 0.25
A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0],
        [1.544, 0.0, 0.0, 0.0],
        [0.9466785280815826, 0.2557011698983284, 0.0, 0.0],
        [3.314825187068521, 2.896124015972201, 0.9986419139977817, 0.0],
        [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950],
    ]
)
C = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [-5.6688, 0.0, 0.0, 0.0, 0.0],
        [-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0],
        [-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0.0, 0.0],
        [7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160, 0.0],
        [
            8.083246795921522,
            -7.981132988064893,
            -31.52159432874371,
            16.31930543123136,
            -6.058818238834054,
        ],
    ]
)
DENSE = np.array(
    [
        [
            10.12623508344586,
            -7.487995877610167,
            -34.80091861555747,
            -7.992771707568823,
            1.025137723295662,
        ],
        [
            -0.6762803392801253,
            6.087714651680015,
            16.43084320892478,
            24.76722511418386,
            -6.594389125716872,
        ],
    ]
)

#: The method as data, for the generic step of :mod:`softcell.engine.kernels.rosenbrock`.
RODAS4 = Tableau(GAMMA, A, C, DENSE)

# Step-size control (Hairer & Wanner's RODAS defaults).
SAFETY, SHRINK_LIMIT, GROW_LIMIT = 0.9, 0.2, 6.0
#: The embedded error's order in h: err ~ h^ERROR_ORDER for a smooth solution.
ERROR_ORDER = 4.0


class Problem(NamedTuple):
    """What the right-hand side reads besides the state: the terms' coefficient arrays (the
    smooth group's tuple, the other group's), the context (l0, a, b in cm), the drive's
    coefficients, the membrane's mobility (cm s^-1 per unit force mode, 1 with a nonlinear
    friction law), the bot's mobilities (cm s^-1 N^-1, cm s^-1 N^-1, rad s^-1 (N cm)^-1) and
    whether there is a membrane."""

    coefficients: tuple
    context: np.ndarray
    drive_coefficients: np.ndarray
    mobility: float
    bot_mobility: np.ndarray
    membrane: bool


class LoopState(NamedTuple):
    """The stepper's state arrays: the unknowns ``u`` (cm, rad), the ``clock`` (slots below,
    s), the current phase's index, the ``counters`` (slots below) and the last step's
    continuous extension ``dense``."""

    u: np.ndarray
    clock: np.ndarray
    phase_index: np.ndarray
    counters: np.ndarray
    dense: np.ndarray


class PhaseTable(NamedTuple):
    """The protocol's schedule as arrays: phase start times (s), codes and data."""

    starts: np.ndarray
    phases: np.ndarray
    data: np.ndarray


class EventLog(NamedTuple):
    """Where the protocol's events ended phases: their times (s, the first ``count[0]``
    slots) and the phases' start times as shifted by them (s)."""

    times: np.ndarray
    count: np.ndarray


class Control(NamedTuple):
    """Step control: absolute (cm, rad) and relative tolerances, and the largest step (s)."""

    atol: float
    rtol: float
    max_step: float


class Coefficients(NamedTuple):
    """The method's a_ij, c_ij and dense-output rows (Hairer & Wanner's transformed form)."""

    a: np.ndarray
    c: np.ndarray
    dense: np.ndarray


#: Status codes of the compiled loop.
OK, STEP_UNDERFLOW, SINGULAR = 0, 1, 2

#: Slots of the ``clock`` state array.
T, H_NEXT, H_ACCEPTED, ERR_ACCEPTED, T_LAST, H_LAST, REJECTED_LAST = range(7)
#: Slots of the ``counters`` state array.
STEPS, REJECTED, RHS_CALLS, JACOBIANS = range(4)


@njit(**LEAN_JIT)
def step_factor(err, h, clock, h_rejected, err_rejected):
    """h / h_next after an attempt of a step of size ``h`` (s) whose scaled error is ``err``
    (accepted when err <= 1), clamped to [1 / GROW_LIMIT, 1 / SHRINK_LIMIT].

    Accepted: Hairer & Wanner's rule, err^(1/4) / SAFETY, or Gustafsson's predictive factor
    from the last accepted step (``clock[H_ACCEPTED]``, ``clock[ERR_ACCEPTED]``) when it asks
    for a smaller step; ``clock[H_ACCEPTED]`` is 0 after a change of phase, whose dynamics
    the previous step does not predict. Rejected: the same rule, except after a rejected
    attempt of this step (size ``h_rejected`` > h, error ``err_rejected`` > err; 0 if none).
    Then the error's observed order q = log(err_rejected / err) / log(h_rejected / h), within
    [1, 4], replaces 4: near a contact or a switch the error falls as h^1-h^2 (the order
    reduction of stiff components), and the fourth root shrinks too little, attempt after
    attempt."""
    q = ERROR_ORDER
    if err > 1.0 and h_rejected > h and err_rejected > err:
        q = math.log(err_rejected / err) / math.log(h_rejected / h)
        q = max(1.0, min(ERROR_ORDER, q))
    fac = max(1.0 / GROW_LIMIT, min(1.0 / SHRINK_LIMIT, err ** (1.0 / q) / SAFETY))
    if err <= 1.0 and clock[H_ACCEPTED] > 0.0:
        gus = (clock[H_ACCEPTED] / h) * (err * err / clock[ERR_ACCEPTED]) ** (1.0 / ERROR_ORDER)
        gus = max(1.0 / GROW_LIMIT, min(1.0 / SHRINK_LIMIT, gus / SAFETY))
        fac = max(fac, gus)
    return fac


@njit(**LEAN_JIT)
def trial_step(clock, max_step, t, t_switch):
    """The size (s) of the next attempt from ``t`` (s): the step control's ``clock[H_NEXT]``
    within ``max_step``, stretched or cut to land on the next switch ``t_switch`` (s) when
    that is within 5 % more; and whether it lands there. Both loops use it."""
    h = min(clock[H_NEXT], max_step)
    land = False
    if t_switch - t <= 1.05 * h:
        h = t_switch - t
        land = True
    return h, land


@njit(**LEAN_JIT)
def judge(err, h, clock, h_rejected, err_rejected, counters):
    """Accept or reject an attempt of size ``h`` (s) whose scaled error is ``err`` (a
    non-finite error counts as 1e10), after :func:`step_factor`; both loops use it.

    Returns (accepted, h_next, err): accepted, the next step's size (no larger than this one
    just after a rejection) with the step control's record of this one in ``clock``;
    rejected, ``clock[H_NEXT]`` set for the next attempt and the rejection counted. ``err``
    is the error as judged, for the next call's ``err_rejected``.
    """
    if not math.isfinite(err):
        err = 1e10
    fac = step_factor(err, h, clock, h_rejected, err_rejected)
    if err <= 1.0:
        h_new = h / fac
        if clock[REJECTED_LAST] > 0.0:
            h_new = min(h_new, h)
        clock[H_ACCEPTED] = h
        clock[ERR_ACCEPTED] = max(1e-2, err)
        clock[REJECTED_LAST] = 0.0
        return True, h_new, err
    clock[H_NEXT] = h / fac
    clock[REJECTED_LAST] = 1.0
    counters[REJECTED] += 1
    return False, 0.0, err


@njit(**LEAN_JIT)
def accumulate(g, mobility, out, drag):
    """Add one grid's force modes to the modes' rates in ``out`` and its (2 pi / N)-weighted
    pose derivatives to ``drag``."""
    m = g.fhat.size
    weight = 2.0 * math.pi / g.w.shape[1]
    for j in range(m):
        out[j] += mobility * g.fhat[j].real
        out[m + j] += mobility * g.fhat[j].imag
    for c in range(3):
        drag[c] += weight * g.dpose[c]
