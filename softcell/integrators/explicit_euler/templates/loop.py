"""The explicit scheme's time loop, compiled per component set by
:class:`softcell.integrators.explicit_euler.ExplicitEulerStepper`.

Bound: ``partials`` (the composed energy terms), ``drive`` (the protocol's kernel), ``LAW``
(whether the friction law is nonlinear; then ``friction_velocity`` is its compiled velocity,
from ``engine/templates/friction_law.py``, and ``mobility`` is 1), ``HAS_BOT`` (whether
some term has an energy of the bot alone; then ``bot_forces`` is their sum), ``event`` and
``HAS_EVENT`` (the protocol's event kernel, and whether it has one) and ``JIT_FLAGS`` (its
functions allocate their scratch arrays, so they keep numba's reference counting).
"""

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from softcell.engine.kernels.spectral import assemble, evaluate

if TYPE_CHECKING:  # bound by the loader before the module runs: BOUND, and the numba flags
    (
        partials,
        drive,
        LAW,
        friction_velocity,
        HAS_BOT,
        bot_forces,
        event,
        HAS_EVENT,
        JIT_FLAGS,
    ) = (None,) * 9


#: The names this template expects the loader to bind (besides the flags); a missing
#: or an extra binding is an error naming the template.
BOUND = (
    "partials",
    "drive",
    "LAW",
    "friction_velocity",
    "HAS_BOT",
    "bot_forces",
    "event",
    "HAS_EVENT",
)


@njit(**JIT_FLAGS)
def end_events(t, p, starts, phases, data, pose, drag, x, y, membrane, coefficients, log):
    """End phase p, and any following phase, while the event holds at time t (s): the later
    phases start that much earlier, each end is logged. ``drag`` (N, N cm) is minus the
    energies' force and torque on the bot: (weighted membrane partials, the bot's own
    energies). Returns the phase index."""
    membrane_part, own = drag
    sense = np.empty(9)
    for c in range(3):
        sense[c] = pose[c]
        sense[3 + c] = -(membrane_part[c] + own[c])
    best = np.inf
    if membrane:
        for i in range(x.size):
            best = min(best, math.hypot(x[i] - pose[0], y[i] - pose[1]))
    sense[6] = best
    sense[7] = t
    times, count = log
    while p + 1 < starts.size:
        sense[8] = t - starts[p]
        if event(phases[p], data[p], sense, coefficients) < 0.0:
            break
        shift = t - starts[p + 1]
        for q in range(p + 1, starts.size):
            starts[q] += shift
        if count[0] < times.size:
            times[count[0]] = t
            count[0] += 1
        p += 1
    return p


@njit(**JIT_FLAGS)
def segment(
    modes,
    pose,
    step,
    phase_index,
    n_steps,
    dt,
    starts,
    phases,
    data,
    coefficients,
    context,
    drive_coefficients,
    mobility,
    bot_mobility,
    n_nodes,
    membrane,
    law,
    log,
):
    n = n_nodes
    spec = np.empty(n, dtype=np.complex128)
    z = np.empty(n, dtype=np.complex128)
    zp = np.empty(n, dtype=np.complex128)
    zpp = np.empty(n, dtype=np.complex128)
    q0 = np.empty(n, dtype=np.complex128)
    q1 = np.empty(n, dtype=np.complex128)
    q2 = np.empty(n, dtype=np.complex128)
    x = np.empty(n)
    y = np.empty(n)
    xp = np.empty(n)
    yp = np.empty(n)
    xpp = np.empty(n)
    ypp = np.empty(n)
    parts = np.empty((6, n))
    fhat = np.zeros(modes.size, dtype=np.complex128)
    dpose = np.zeros(3)
    drive_out = np.zeros(3)
    bot_drag = np.zeros(3)
    weight = 2.0 * math.pi / n
    p = phase_index
    for _ in range(n_steps):
        t = step * dt
        while p + 1 < starts.size and starts[p + 1] <= t:
            p += 1
        dpose[:] = 0.0
        if membrane:
            evaluate(modes, spec, z, zp, zpp)
            for i in range(n):
                x[i] = z[i].real
                y[i] = z[i].imag
                xp[i] = zp[i].real
                yp[i] = zp[i].imag
                xpp[i] = zpp[i].real
                ypp[i] = zpp[i].imag
            parts[:, :] = 0.0
            partials(
                x,
                y,
                xp,
                yp,
                xpp,
                ypp,
                pose,
                context,
                coefficients,
                parts[0],
                parts[1],
                parts[2],
                parts[3],
                parts[4],
                parts[5],
                dpose,
            )
            has_q0 = False
            for i in range(n):
                q0[i] = parts[0, i] + 1j * parts[1, i]
                q1[i] = parts[2, i] + 1j * parts[3, i]
                q2[i] = parts[4, i] + 1j * parts[5, i]
                if parts[0, i] != 0.0 or parts[1, i] != 0.0:
                    has_q0 = True
            assemble(q0, q1, q2, has_q0, True, True, spec, fhat)
            if LAW:
                friction_velocity(modes, fhat, law.vhat, law)
                for j in range(modes.size):
                    fhat[j] = law.vhat[j]
        if HAS_BOT:
            bot_drag[:] = 0.0
            bot_forces(pose, context, coefficients, bot_drag)
        if HAS_EVENT:  # bot_drag stays 0 without energies of the bot alone
            p = end_events(
                t,
                p,
                starts,
                phases,
                data,
                pose,
                (weight * dpose, bot_drag),
                x,
                y,
                membrane,
                drive_coefficients,
                log,
            )
        drive(phases[p], data[p], pose, context, drive_coefficients, drive_out)
        for j in range(3):  # bot_drag is 0 without energies of the bot alone: x - 0.0 == x
            pose[j] += dt * bot_mobility[j] * (drive_out[j] - weight * dpose[j] - bot_drag[j])
        if membrane:
            for j in range(modes.size):
                modes[j] += dt * mobility * fhat[j]
        step += 1
    return step, p
