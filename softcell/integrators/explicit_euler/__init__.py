"""The paper's explicit Euler scheme, SI steps 1-6: the reference every faster integrator is
judged against.

Each step evaluates the cut-off shape and its derivatives at the N points (inverse FFTs),
sums the energy terms' partials, assembles the force modes (forward FFTs), and moves modes and
bot with the forces of the same instant: g_k += dt (2 pi / (gamma_mem l0)) f_hat_k,
r_bot += dt (F_int + F_dr) / gamma_T, theta += dt (T_int + T_dr) / gamma_R, with
F_int = -(2 pi / N) sum_n de_n/dr_bot (SI:EQ:int_bot). Time is counted in whole steps.
"""

from __future__ import annotations

import numpy as np

from softcell.components.contracts import Integrator, Schedule
from softcell.components.hookspecs import hookimpl
from softcell.engine import Model, Stepper, explicit_decay_rate, nonlinear_friction, placeholders
from softcell.engine.compiled import compile_module
from softcell.engine.compose import compose_bot, template
from softcell.engine.state import event_state
from softcell.errors import ParameterError
from softcell.model.parameters import MODEL_PARAMETERS


class ExplicitEulerStepper(Stepper):
    """The explicit scheme at a fixed step ``dt`` (s) for ``model``: a :class:`Stepper` whose
    state counts whole steps, so sample times must be multiples of ``dt``.

    An integrator that only chooses its step returns one from ``build(model)``; the bound
    ``dt < 2 / explicit_decay_rate(model)`` keeps it stable.
    """

    def __init__(self, model: Model, dt: float) -> None:
        law = (
            nonlinear_friction.compiled_friction(model.friction)
            if model.nonlinear_friction
            else None
        )
        self.segment = compile_module(
            "explicit-euler",
            template(__package__ + ".templates", "loop.py"),
            {
                "partials": model.partials,
                "drive": model.drive,
                "LAW": law is not None,
                "friction_velocity": law.velocity if law else placeholders.no_friction_velocity,
                "HAS_BOT": bool(model.bot_terms),
                "bot_forces": compose_bot(model.terms)[0]
                if model.bot_terms
                else placeholders.no_bot_forces,
                "event": model.event if model.event is not None else placeholders.no_event,
                "HAS_EVENT": model.event is not None,
            },
            f"{' + '.join(t.name for t in model.terms) or 'none'}; {model.protocol.name}"
            + (f"; {model.friction.name}" if law else ""),
        ).segment
        self.model, self.dt = model, dt
        self.law = nonlinear_friction.model_workspace(model, 2 * (2 * model.cutoff + 1) + 3)

    def start(self, modes, pose, schedule):
        return {
            "modes": modes.astype(np.complex128).copy(),
            "pose": np.asarray(pose, dtype=np.float64).copy(),
            "time": np.zeros(1),
            "step": np.zeros(1, dtype=np.int64),
            "phase_index": np.zeros(1, dtype=np.int64),
            **event_state(self.model, schedule),
        }

    def advance(self, state, schedule: Schedule, t_end: float) -> None:
        target = round(t_end / self.dt)
        if abs(target * self.dt - t_end) > 1e-9 * max(1.0, t_end):
            raise ParameterError("dt", self.dt, f"must divide the sample time {t_end:g} s", "s")
        m = self.model
        step, p = self.segment(
            state["modes"],
            state["pose"],
            int(state["step"][0]),
            int(state["phase_index"][0]),
            int(target - state["step"][0]),
            self.dt,
            state.get("starts", schedule.start),
            schedule.phase,
            schedule.data,
            m.coefficients,
            m.context,
            m.drive_coefficients,
            nonlinear_friction.mobility(m),
            m.bot_mobility,
            m.nodes,
            m.has_membrane,
            self.law,
            (state.get("event_times", _NO_EVENTS), state.get("event_count", _NO_COUNT)),
        )
        state["step"][0], state["phase_index"][0] = step, p
        state["time"][0] = step * self.dt


class ExplicitBotsStepper:
    """The explicit scheme for ``bots`` (> 1) bots in one ring (``templates/bots.py``): its
    state's ``pose`` is float64[3 K] (bot b's at ``[3 b:3 b + 3]``) and its schedules one per
    bot. Only the viscous friction law and protocols without state events."""

    def __init__(self, model: Model, dt: float, bots: int) -> None:
        from softcell.engine.compose import compose_interactions, compose_partials
        from softcell.integrators.rodas4.several import check_bots_model, split_model

        check_bots_model(model)
        membrane_part, contact_part = split_model(model)
        interactions = model.bot_interactions
        self.segment = compile_module(
            "explicit-euler-bots",
            template(__package__ + ".templates", "bots.py"),
            {
                "partials_m": compose_partials([t.partials_kernel() for t in membrane_part.terms]),
                "partials_c": compose_partials([t.partials_kernel() for t in contact_part.terms]),
                "drive": model.drive,
                "HAS_BOT": bool(model.bot_terms),
                "bot_forces": compose_bot(model.terms)[0]
                if model.bot_terms
                else placeholders.no_bot_forces,
                "HAS_INTERACT": bool(interactions),
                "interact": compose_interactions(interactions)
                if interactions
                else placeholders.no_interaction,
            },
            f"{' + '.join(t.name for t in model.terms)}; {model.protocol.name}; bots "
            + (" + ".join(i.name for i in interactions) or "without interactions"),
        ).segment_bots
        self.model, self.dt, self.bots = model, dt, bots
        self.problem = (
            membrane_part.coefficients,
            contact_part.coefficients,
            model.coefficients,
            tuple(np.ascontiguousarray(i.coefficients()) for i in interactions) or (np.zeros(1),),
            float(model.bot_reach),
            model.context,
            model.drive_coefficients,
            float(model.membrane_mobility),
            model.bot_mobility,
        )

    def start(self, modes, poses, schedules):
        return {
            "modes": np.asarray(modes, dtype=np.complex128).copy(),
            "pose": np.asarray(poses, dtype=np.float64).reshape(-1).copy(),
            "time": np.zeros(1),
            "step": np.zeros(1, dtype=np.int64),
            "phase_index": np.zeros(self.bots, dtype=np.int64),
        }

    def advance(self, state, schedules: list[Schedule], t_end: float) -> None:
        target = round(t_end / self.dt)
        if abs(target * self.dt - t_end) > 1e-9 * max(1.0, t_end):
            raise ParameterError("dt", self.dt, f"must divide the sample time {t_end:g} s", "s")
        offsets = np.cumsum([0] + [len(s.start) for s in schedules]).astype(np.int64)
        table = (
            np.concatenate([s.start for s in schedules]),
            np.concatenate([s.phase for s in schedules]),
            np.concatenate([s.data for s in schedules]),
            offsets,
        )
        step = self.segment(
            state["modes"],
            state["pose"],
            int(state["step"][0]),
            state["phase_index"],
            int(target - state["step"][0]),
            self.dt,
            table,
            self.problem,
            self.model.nodes,
        )
        state["step"][0] = step
        state["time"][0] = step * self.dt

    def sample(self, state, schedules: list[Schedule], times: np.ndarray):
        """Advance through ``times`` (s); the modes (complex128[T, 2 Lc + 1], cm) and poses
        (float64[T, 3 K]) there."""
        modes = np.empty((len(times), state["modes"].size), dtype=np.complex128)
        pose = np.empty((len(times), state["pose"].size))
        for i, t in enumerate(times):
            self.advance(state, schedules, float(t))
            modes[i], pose[i] = state["modes"], state["pose"]
        return modes, pose

    def current(self, state):
        """The modes (cm), poses and time (s) reached."""
        return state["modes"], state["pose"], float(state["time"][0])


_NO_EVENTS = np.zeros(0)
_NO_COUNT = np.zeros(1, dtype=np.int64)


class ExplicitEuler(Integrator):
    """The paper's explicit Euler scheme at a fixed step dt (default 1e-6 s)."""

    name = "explicit_euler"
    #: Steps several bots in one ring (:meth:`build_bots`).
    steps_bots = True
    description = "the paper's explicit Euler scheme (SI steps 1-6), fixed step dt; the reference"
    parameters = (MODEL_PARAMETERS["dt"],)

    @classmethod
    def check(cls, params):
        dt = float(params.dt)
        for name in ("sample_every", "sample_every_late", "sample_switch"):
            ratio = float(params[name]) / dt
            if abs(ratio - round(ratio)) > 1e-6 * max(1.0, ratio):
                raise ParameterError(
                    "dt",
                    dt,
                    f"must divide {name} = {params[name]:g} s "
                    "(explicit_euler samples on whole steps)",
                    "s",
                )

    def build(self, model: Model) -> ExplicitEulerStepper:
        return ExplicitEulerStepper(model, self._stable_dt(model))

    def _stable_dt(self, model: Model) -> float:
        """dt (s), refused unless below the membrane's stability bound."""
        dt = float(self.params.dt)
        if model.has_membrane:
            rate = explicit_decay_rate(model)
            if dt * rate >= 2.0:
                raise ParameterError(
                    "dt",
                    dt,
                    f"must be < 2 / lambda_max = {2 / rate:.4g} s for explicit_euler "
                    f"to be stable (lambda_max = {rate:.4g} 1/s at cutoff = {model.cutoff}, "
                    f"radius = {model.params.radius:g} cm)",
                    "s",
                )
        return dt

    def build_bots(self, model: Model, bots: int) -> ExplicitBotsStepper:
        """The stepper of ``bots`` (> 1) bots in one ring, at this integrator's dt (its
        stability bound is the membrane's, checked as :meth:`build` does; the bots' contact
        adds its own, which a too long dt shows as a blow-up)."""
        return ExplicitBotsStepper(model, self._stable_dt(model), bots)


@hookimpl
def softcell_integrators() -> list[type[Integrator]]:
    return [ExplicitEuler]
