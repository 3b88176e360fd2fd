"""The paper's explicit Euler scheme, SI steps 1-6: the reference every faster integrator is
judged against.

Each step evaluates the cut-off shape and its derivatives at the N points (inverse FFTs),
sums the energy terms' partials, assembles the force modes (forward FFTs), and moves modes and
bot with the forces of the same instant: g_k += dt (2 pi / (gamma_mem l0)) f_hat_k,
r_bot += dt (F_int + F_dr) / gamma_T, theta += dt (T_int + T_dr) / gamma_R, with
F_int = -(2 pi / N) sum_n de_n/dr_bot (SI:EQ:int_bot). Time is counted in whole steps.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.config import JIT_COMPOSED
from softcell.core.engine import Model, Stepper, explicit_decay_rate
from softcell.core.params import MODEL_PARAMETERS
from softcell.core.plugin.contracts import Integrator, Schedule
from softcell.core.plugin.hookspecs import hookimpl
from softcell.errors import ParameterError
from softcell.kernels.spectral import assemble, evaluate

_STEPPERS: dict[tuple[int, int], object] = {}


def _make_segment(partials, drive):
    @njit(**JIT_COMPOSED)
    def segment(modes, pose, step, phase_index, n_steps, dt, starts, phases, data,
                coefficients, context, drive_coefficients, mobility, bot_mobility,
                n_nodes, membrane):
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
                partials(x, y, xp, yp, xpp, ypp, pose, context, coefficients,
                         parts[0], parts[1], parts[2], parts[3], parts[4], parts[5], dpose)
                has_q0 = False
                for i in range(n):
                    q0[i] = parts[0, i] + 1j * parts[1, i]
                    q1[i] = parts[2, i] + 1j * parts[3, i]
                    q2[i] = parts[4, i] + 1j * parts[5, i]
                    if parts[0, i] != 0.0 or parts[1, i] != 0.0:
                        has_q0 = True
                assemble(q0, q1, q2, has_q0, spec, fhat)
            drive(phases[p], data[p], pose, context, drive_coefficients, drive_out)
            for j in range(3):
                pose[j] += dt * bot_mobility[j] * (drive_out[j] - weight * dpose[j])
            if membrane:
                for j in range(modes.size):
                    modes[j] += dt * mobility * fhat[j]
            step += 1
        return step, p

    return segment


class ExplicitEulerStepper(Stepper):
    """The explicit scheme at a fixed step ``dt`` (s) for ``model``: a :class:`Stepper` whose
    state counts whole steps, so sample times must be multiples of ``dt``.

    An integrator that only chooses its step returns one from ``build(model)``; the bound
    ``dt < 2 / explicit_decay_rate(model)`` keeps it stable.
    """

    def __init__(self, model: Model, dt: float) -> None:
        key = (id(model.partials), id(model.drive))
        if key not in _STEPPERS:
            _STEPPERS[key] = _make_segment(model.partials, model.drive)
        self.segment = _STEPPERS[key]
        self.model, self.dt = model, dt

    def start(self, modes, pose, schedule):
        return {"modes": modes.astype(np.complex128).copy(),
                "pose": np.asarray(pose, dtype=np.float64).copy(),
                "time": np.zeros(1), "step": np.zeros(1, dtype=np.int64),
                "phase_index": np.zeros(1, dtype=np.int64)}

    def advance(self, state, schedule: Schedule, t_end: float) -> None:
        target = round(t_end / self.dt)
        if abs(target * self.dt - t_end) > 1e-9 * max(1.0, t_end):
            raise ParameterError("dt", self.dt, f"must divide the sample time {t_end:g} s", "s")
        m = self.model
        step, p = self.segment(
            state["modes"], state["pose"], int(state["step"][0]), int(state["phase_index"][0]),
            int(target - state["step"][0]), self.dt, schedule.start, schedule.phase,
            schedule.data, m.coefficients, m.context, m.drive_coefficients,
            m.membrane_mobility, m.bot_mobility, m.nodes, m.has_membrane)
        state["step"][0], state["phase_index"][0] = step, p
        state["time"][0] = step * self.dt


class ExplicitEuler(Integrator):
    """The paper's explicit Euler scheme at a fixed step dt (default 1e-6 s)."""

    name = "explicit_euler"
    description = "the paper's explicit Euler scheme (SI steps 1-6), fixed step dt; the reference"
    parameters = (MODEL_PARAMETERS["dt"],)

    @classmethod
    def check(cls, params):
        dt = float(params.dt)
        for name in ("sample_every", "sample_every_late", "sample_switch"):
            ratio = float(params[name]) / dt
            if abs(ratio - round(ratio)) > 1e-6 * max(1.0, ratio):
                raise ParameterError("dt", dt, f"must divide {name} = {params[name]:g} s "
                                     "(explicit_euler samples on whole steps)", "s")

    def build(self, model: Model) -> ExplicitEulerStepper:
        dt = float(self.params.dt)
        if model.has_membrane:
            rate = explicit_decay_rate(model)
            if dt * rate >= 2.0:
                raise ParameterError(
                    "dt", dt, f"must be < 2 / lambda_max = {2 / rate:.4g} s for explicit_euler "
                    f"to be stable (lambda_max = {rate:.4g} 1/s at cutoff = {model.cutoff}, "
                    f"radius = {model.params.radius:g} cm)", "s")
        return ExplicitEulerStepper(model, dt)


@hookimpl
def softcell_integrators() -> list[type[Integrator]]:
    return [ExplicitEuler]
