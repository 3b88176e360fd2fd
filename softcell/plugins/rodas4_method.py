"""RODAS4's coefficients, its step-size control, the status codes and state slots of its
compiled loop, and the loop's small kernels: what the integrator (:mod:`softcell.plugins.rodas4`)
and its template (``templates/rodas4_loop.py``) share, so that neither imports the other.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from softcell.config import JIT
from softcell.kernels.rosenbrock import Tableau

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

#: The method as data, for the generic step of :mod:`softcell.kernels.rosenbrock`.
RODAS4 = Tableau(GAMMA, A, C, DENSE)

# Step-size control (Hairer & Wanner's RODAS defaults).
SAFETY, SHRINK_LIMIT, GROW_LIMIT = 0.9, 0.2, 6.0


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


@njit(**JIT)
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
