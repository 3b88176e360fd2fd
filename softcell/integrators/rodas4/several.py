"""rodas4 on one ring with several bots (``--bots K`` > 1): the compiled loop of
``templates/bots.py`` and its stepper.

The model's terms are split in two: those that do not read the bot's pose (tension, bending,
walls and posts acting on the membrane) are evaluated once, those that do (the contact) once
per bot, each with the single-bot loop of ``templates/loop.py``; the energies of a bot alone
(the arena's walls) and the bots' interactions are added per bot and per pair. The membrane's
velocity is the sum of the parts' (the viscous law is linear), so K = 1 would give the
single-bot right-hand side to rounding; a run of one bot never comes here.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from softcell.components.contracts import Schedule
from softcell.engine import Model, SimulationError, nonlinear_friction, placeholders
from softcell.engine.compiled import compile_module
from softcell.engine.compose import (
    compose_bot,
    compose_interaction_jacobians,
    compose_interactions,
    template,
)
from softcell.engine.kernels.linalg import lu_workspace
from softcell.errors import ParameterError
from softcell.integrators.rodas4.method import (
    ERR_ACCEPTED,
    H_NEXT,
    JACOBIANS,
    OK,
    REJECTED,
    RHS_CALLS,
    RODAS4,
    SINGULAR,
    STEP_UNDERFLOW,
    STEPS,
    Coefficients,
    Control,
    LoopState,
    Problem,
    T,
)
from softcell.integrators.rodas4.single import compiled_loop, group_coefficients, workspace


class BotsProblem(NamedTuple):
    """What the several-bot right-hand side reads: the two parts' problems, every term's
    coefficient arrays (for the bots' own energies), the context (l0, a, b in cm), the bots'
    mobilities, the interactions' coefficient arrays and their reach (cm)."""

    problem_m: Problem
    problem_c: Problem
    coefficients: tuple
    context: np.ndarray
    bot_mobility: np.ndarray
    interactions: tuple
    reach: float


class BotsWork(NamedTuple):
    """Scratch of the several-bot right-hand side: the parts' single-bot workspaces, the
    single-bot unknowns ``uc`` and their derivative ``scratch``, and the pair's arrays."""

    ws_m: object
    ws_c: object
    uc: np.ndarray
    scratch: np.ndarray
    drag: np.ndarray
    hpp: np.ndarray
    pose_a: np.ndarray
    pose_b: np.ndarray
    pair_out: np.ndarray
    pair_jac: np.ndarray
    pair_scratch: np.ndarray


class StepWork(NamedTuple):
    """Scratch of the step: Jacobian, iteration matrix, pivots, stages, each bot's phase."""

    jac: np.ndarray
    mat: np.ndarray
    pivots: np.ndarray
    k: np.ndarray
    f0: np.ndarray
    y: np.ndarray
    ynew: np.ndarray
    force: np.ndarray
    phases: np.ndarray
    data: np.ndarray


def split_model(model: Model) -> tuple[Model, Model]:
    """The model of the terms that do not read the pose, and that of those that do (with
    no energy of the bot alone: the loop adds those per bot)."""
    membrane = [i for i, t in enumerate(model.terms) if not t.reads_pose]
    contact = [i for i, t in enumerate(model.terms) if t.reads_pose]
    if any(model.terms[i].has_bot_energy for i in contact):
        raise ParameterError(
            "energy_terms",
            ", ".join(model.terms[i].name for i in contact if model.terms[i].has_bot_energy),
            "must not both read the bot's pose and have an energy of the bot alone for "
            "several bots in one ring",
            "1",
        )

    def part(indices: list[int]) -> Model:
        terms = [model.terms[i] for i in indices]
        return dataclasses.replace(
            model,
            terms=terms,
            coefficients=tuple(model.coefficients[i] for i in indices) or (np.zeros(1),),
        )

    membrane_part = part(membrane)
    # the membrane part's pose rows are never read: its bot energies stay unused there
    return membrane_part, part(contact)


def check_bots_model(model: Model) -> None:
    """Refuse, in one line, a model the several-bot loop cannot step."""
    if not model.has_membrane:
        raise ParameterError(
            "bots", "> 1", "needs a membrane: several free bots are not modelled", "1"
        )
    if model.nonlinear_friction:
        raise ParameterError(
            "friction_law",
            model.friction.name,
            "must be viscous for several bots in one ring (the parts' membrane velocities "
            "are summed)",
            "1",
        )
    if model.event is not None:
        raise ParameterError(
            "driving_protocol",
            model.protocol.name,
            "must have no state events for several bots in one ring (their loop does not "
            "locate them yet)",
            "1",
        )


def compiled_bots(model: Model):
    """The several-bot loop (``integrate_bots``) of ``templates/bots.py`` for the model's
    components, and the two parts' models."""
    check_bots_model(model)
    membrane_part, contact_part = split_model(model)
    rhs_m, jacobian_m, _ = compiled_loop(membrane_part)
    rhs_c, jacobian_c, _ = compiled_loop(contact_part)
    has_bot = bool(model.bot_terms)
    bot_forces, bot_hessians = (
        compose_bot(model.terms)
        if has_bot
        else (placeholders.no_bot_forces, placeholders.no_bot_hessians)
    )
    interactions = model.bot_interactions
    module = compile_module(
        "rodas4-bots",
        template(__package__ + ".templates", "bots.py"),
        {
            "rhs_m": rhs_m,
            "jacobian_m": jacobian_m,
            "rhs_c": rhs_c,
            "jacobian_c": jacobian_c,
            "HAS_BOT": has_bot,
            "bot_forces": bot_forces,
            "bot_hessians": bot_hessians,
            "HAS_INTERACT": bool(interactions),
            "interact": compose_interactions(interactions)
            if interactions
            else placeholders.no_interaction,
            "interact_jacobian": compose_interaction_jacobians(interactions)
            if interactions
            else placeholders.no_interaction_jacobian,
        },
        " + ".join(t.name for t in model.terms)
        + f"; {model.protocol.name}; bots "
        + (" + ".join(i.name for i in interactions) or "without interactions"),
    )
    return module.integrate_bots, membrane_part, contact_part


def _problem(part: Model) -> Problem:
    return Problem(
        group_coefficients(part),
        part.context,
        part.drive_coefficients,
        nonlinear_friction.mobility(part),
        part.bot_mobility,
        part.has_membrane,
    )


class BotsStepper:
    """Steps one ring with ``bots`` bots: :meth:`start`, then :meth:`sample`. The state's
    ``u`` holds the modes' real and imaginary parts (cm), then each bot's x, y (cm) and
    heading (rad); its ``pose`` is float64[3 K] (bot b's pose at ``[3 b:3 b + 3]``)."""

    def __init__(self, model: Model, bots: int, atol, rtol, max_step, first_step, smooth_nodes):
        self.model, self.bots = model, bots
        self.integrate, membrane_part, contact_part = compiled_bots(model)
        m = 2 * model.cutoff + 1
        nu = 2 * m + 3 * bots
        self.problem = BotsProblem(
            _problem(membrane_part),
            _problem(contact_part),
            tuple(np.ascontiguousarray(c) for c in model.coefficients),
            model.context,
            model.bot_mobility,
            tuple(np.ascontiguousarray(i.coefficients()) for i in model.bot_interactions)
            or (np.zeros(1),),
            float(model.bot_reach),
        )
        self.work = BotsWork(
            ws_m=workspace(membrane_part, smooth_nodes),
            ws_c=workspace(contact_part, smooth_nodes),
            uc=np.zeros(2 * m + 3),
            scratch=np.zeros(2 * m + 3),
            drag=np.zeros(3),
            hpp=np.zeros((3, 3)),
            pose_a=np.zeros(3),
            pose_b=np.zeros(3),
            pair_out=np.zeros(6),
            pair_jac=np.zeros((6, 6)),
            pair_scratch=np.zeros(24),
        )
        self.step = StepWork(
            jac=np.zeros((nu, nu)),
            mat=np.zeros((nu, nu)),
            pivots=lu_workspace(nu, transposed=True),
            k=np.zeros((6, nu)),
            f0=np.zeros(nu),
            y=np.zeros(nu),
            ynew=np.zeros(nu),
            force=np.zeros(nu),
            phases=np.zeros(bots, dtype=np.int8),
            data=np.zeros(bots),
        )
        self.control = Control(atol, rtol, max_step)
        self.first_step = first_step

    def start(self, modes: np.ndarray, poses: np.ndarray, schedules: list[Schedule]) -> dict:
        """The state at t = 0: ``modes`` (complex128[2 Lc + 1], cm), ``poses`` (float64[K,
        3]: cm, cm, rad)."""
        modes = np.asarray(modes, dtype=np.complex128)
        pose = np.asarray(poses, dtype=np.float64).reshape(-1)
        u = np.concatenate([modes.real, modes.imag, pose])
        clock = np.zeros(7)
        clock[H_NEXT] = self.first_step
        clock[ERR_ACCEPTED] = 1.0
        return {
            "modes": modes.copy(),
            "pose": pose.copy(),
            "time": np.zeros(1),
            "u": u,
            "clock": clock,
            "phase_index": np.zeros(self.bots, dtype=np.int64),
            "counters": np.zeros(4, dtype=np.int64),
            "dense": np.zeros((4, u.size)),
        }

    def sample(self, state: dict, schedules: list[Schedule], times: np.ndarray):
        """Step to each of ``times`` (s, increasing); returns the modes (complex128[T,
        2 Lc + 1], cm) and poses (float64[T, 3 K]) there."""
        times = np.ascontiguousarray(times, dtype=np.float64)
        samples = np.empty((times.size, state["u"].size))
        offsets = np.cumsum([0] + [len(s.start) for s in schedules]).astype(np.int64)
        table = (
            np.concatenate([s.start for s in schedules]),
            np.concatenate([s.phase for s in schedules]),
            np.concatenate([s.data for s in schedules]),
            offsets,
        )
        status = self.integrate(
            LoopState(
                state["u"], state["clock"], state["phase_index"], state["counters"], state["dense"]
            ),
            times,
            samples,
            table,
            self.problem,
            self.control,
            Coefficients(RODAS4.a, RODAS4.c, RODAS4.dense),
            self.work,
            self.step,
        )
        if status != OK:
            reason = {
                STEP_UNDERFLOW: "the step size underflowed",
                SINGULAR: "the iteration matrix is singular",
            }.get(status, f"status {status}")
            raise SimulationError(
                f"rodas4 failed on {self.bots} bots at t = {state['clock'][T]:.9g} s: {reason}"
            )
        m = 2 * self.model.cutoff + 1
        modes = samples[:, :m] + 1j * samples[:, m : 2 * m]
        pose = samples[:, 2 * m :]
        state["modes"][:], state["pose"][:] = modes[-1], pose[-1]
        state["time"][0] = times[-1]
        return modes, pose

    def current(self, state: dict) -> tuple[np.ndarray, np.ndarray, float]:
        """The last accepted step's modes (cm), poses (float64[3 K]) and time (s)."""
        m = 2 * self.model.cutoff + 1
        u = state["u"]
        return u[:m] + 1j * u[m : 2 * m], u[2 * m :].copy(), float(state["clock"][T])

    def statistics(self, state: dict) -> dict[str, int]:
        """Steps accepted and rejected, right-hand-side and Jacobian evaluations so far."""
        c = state["counters"]
        return {
            "steps": int(c[STEPS]),
            "rejected": int(c[REJECTED]),
            "rhs_calls": int(c[RHS_CALLS]),
            "jacobians": int(c[JACOBIANS]),
        }

    def rhs(self, state_u: np.ndarray, phases: np.ndarray, data: np.ndarray) -> np.ndarray:
        """du/dt at ``state_u`` with each bot's phase code and datum (for checks)."""
        out = np.zeros_like(state_u)
        _module(self).bots_rhs(state_u, phases, data, out, self.problem, self.work)
        return out

    def jacobian(self, state_u: np.ndarray, phases: np.ndarray, data: np.ndarray) -> np.ndarray:
        """The Jacobian the loop uses at ``state_u`` (for checks)."""
        jac = np.zeros((state_u.size, state_u.size))
        _module(self).bots_jacobian(state_u, phases, data, self.problem, self.work, jac)
        return jac


def _module(stepper: BotsStepper):
    import sys

    return sys.modules[stepper.integrate.py_func.__module__]
