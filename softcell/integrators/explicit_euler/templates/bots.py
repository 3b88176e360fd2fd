"""The explicit scheme's time loop for several bots in one ring, compiled per component set
by :class:`softcell.integrators.explicit_euler.ExplicitBotsStepper`: each step evaluates the
curve once, the terms that do not read the pose once (``partials_m``, their pose argument
bot 0's and their pose partials unread), those that do once per bot (``partials_c``, adding
into the same points' partials and each bot's own pose partials), the energies of each bot
alone, the bots' interactions and their drives, then moves everything by the forces of the
same instant, as the single-bot scheme does.

Bound: ``partials_m``, ``partials_c``, ``drive``, ``HAS_BOT``, ``bot_forces``,
``HAS_INTERACT``, ``interact`` and ``JIT_FLAGS``. Only the viscous friction law and no state
events.
"""

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from softcell.engine.kernels.spectral import assemble, evaluate

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        partials_m,
        partials_c,
        drive,
        HAS_BOT,
        bot_forces,
        HAS_INTERACT,
        interact,
        JIT_FLAGS,
    ) = (None,) * 8


#: The names this template expects the loader to bind (besides the flags).
BOUND = (
    "partials_m",
    "partials_c",
    "drive",
    "HAS_BOT",
    "bot_forces",
    "HAS_INTERACT",
    "interact",
)


@njit(**JIT_FLAGS)
def segment_bots(modes, pose, step, p, n_steps, dt, schedule, problem, n_nodes):  # noqa: C901
    """``n_steps`` steps of ``dt`` (s) from whole step ``step``; ``pose`` float64[3 K] and
    ``p`` (int64[K], each bot's phase index) are advanced in place. ``schedule`` = (starts,
    phases, data, offsets), bot b's from ``offsets[b]``; ``problem`` = (coefficients of the
    membrane part, of the contact part, of every term, of the interactions, the
    interactions' reach (cm), context, drive coefficients, membrane mobility, bot
    mobilities). Returns the new step count."""
    starts, phases, data, offsets = schedule
    (coef_m, coef_c, coef_all, coef_i, reach, context, drive_coef, mobility, bot_mob) = problem
    k = p.size
    n = n_nodes
    spec = np.empty(n, dtype=np.complex128)
    z = np.empty(n, dtype=np.complex128)
    zp = np.empty(n, dtype=np.complex128)
    zpp = np.empty(n, dtype=np.complex128)
    q0 = np.empty(n, dtype=np.complex128)
    q1 = np.empty(n, dtype=np.complex128)
    q2 = np.empty(n, dtype=np.complex128)
    w = np.empty((6, n))
    parts = np.empty((6, n))
    fhat = np.zeros(modes.size, dtype=np.complex128)
    dpose = np.zeros((k, 3))
    unread = np.zeros(3)
    force = np.zeros((k, 3))
    out = np.zeros(3)
    pair_out = np.zeros(6)
    pb = np.zeros((k, 3))
    weight = 2.0 * math.pi / n
    for _ in range(n_steps):
        t = step * dt
        for b in range(k):
            while offsets[b] + p[b] + 1 < offsets[b + 1] and starts[offsets[b] + p[b] + 1] <= t:
                p[b] += 1
            for c in range(3):
                pb[b, c] = pose[3 * b + c]
        evaluate(modes, spec, z, zp, zpp)
        for i in range(n):
            w[0, i], w[1, i] = z[i].real, z[i].imag
            w[2, i], w[3, i] = zp[i].real, zp[i].imag
            w[4, i], w[5, i] = zpp[i].real, zpp[i].imag
        parts[:, :] = 0.0
        dpose[:, :] = 0.0
        partials_m(
            w[0], w[1], w[2], w[3], w[4], w[5], pb[0], context, coef_m,
            parts[0], parts[1], parts[2], parts[3], parts[4], parts[5], unread,
        )  # fmt: skip
        for b in range(k):
            partials_c(
                w[0], w[1], w[2], w[3], w[4], w[5], pb[b], context, coef_c,
                parts[0], parts[1], parts[2], parts[3], parts[4], parts[5], dpose[b],
            )  # fmt: skip
        has_q0 = False
        for i in range(n):
            q0[i] = parts[0, i] + 1j * parts[1, i]
            q1[i] = parts[2, i] + 1j * parts[3, i]
            q2[i] = parts[4, i] + 1j * parts[5, i]
            if parts[0, i] != 0.0 or parts[1, i] != 0.0:
                has_q0 = True
        assemble(q0, q1, q2, has_q0, True, True, spec, fhat)
        for b in range(k):
            drive(phases[offsets[b] + p[b]], data[offsets[b] + p[b]], pb[b], context,
                  drive_coef, out)  # fmt: skip
            for c in range(3):
                force[b, c] = out[c] - weight * dpose[b, c]
            if HAS_BOT:
                out[:] = 0.0
                bot_forces(pb[b], context, coef_all, out)
                for c in range(3):
                    force[b, c] -= out[c]
        if HAS_INTERACT:
            for a in range(k):
                for b in range(a + 1, k):
                    dx, dy = pb[b, 0] - pb[a, 0], pb[b, 1] - pb[a, 1]
                    if dx * dx + dy * dy > reach * reach:
                        continue
                    pair_out[:] = 0.0
                    interact(pb[a], pb[b], context, coef_i, pair_out)
                    for c in range(3):
                        force[a, c] += pair_out[c]
                        force[b, c] += pair_out[3 + c]
        for b in range(k):
            for c in range(3):
                pose[3 * b + c] += dt * bot_mob[c] * force[b, c]
        for j in range(modes.size):
            modes[j] += dt * mobility * fhat[j]
        step += 1
    return step
