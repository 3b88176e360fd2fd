"""RODAS4: an adaptive, L-stable, stiffly accurate Rosenbrock method of order 4(3) (Hairer &
Wanner, Solving ODEs II, section IV.7; coefficients of their code RODAS), for the whole coupled
system: the membrane modes, the contact and the bot (~70 unknowns).

Each step factors W = I / (h gamma) - J once, with J the Jacobian of the full right-hand side
(:mod:`softcell.engine.kernels.jacobian`), and solves six linear systems; the sixth stage is the
embedded error estimate. Steps adapt to the error (Gustafsson's predictive controller within
a phase; after two rejections of one step, the error's observed order in h sets the next try,
see :func:`softcell.integrators.rodas4.method.step_factor`), land
exactly on the protocol's switching times (within a step the right-hand side is autonomous),
and samples come from the method's continuous extension, so the sampling grid never
constrains the step. Everything runs inside one compiled loop; nothing is allocated per step.
"""

from __future__ import annotations

import copy
from typing import NamedTuple

import numba
import numpy as np

from softcell.components.contracts import Integrator, Schedule
from softcell.components.hookspecs import hookimpl
from softcell.engine import Model, SimulationError, Stepper, nonlinear_friction
from softcell.engine.compiled import compile_module
from softcell.engine.compose import compose_pair_laws, template
from softcell.engine.kernels.linalg import lu_workspace
from softcell.engine.state import event_state
from softcell.errors import ParameterError
from softcell.integrators.rodas4.method import (  # shared with the template templates/loop.py
    ERR_ACCEPTED,
    H_ACCEPTED,
    H_LAST,
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
    EventLog,
    LoopState,
    PhaseTable,
    Problem,
    T,
)
from softcell.integrators.rodas4.single import (  # the single-bot loop, re-exported
    Grid as Grid,
)
from softcell.integrators.rodas4.single import (
    Workspace as Workspace,
)
from softcell.integrators.rodas4.single import (
    _names,
    compiled_loop,
    group_coefficients,
    workspace,
)
from softcell.integrators.rodas4.single import (
    grid as grid,
)
from softcell.integrators.rodas4.single import (
    groups as groups,
)
from softcell.model.parameters import ParameterSpec


def compiled_group(model: Model):
    """The group loop of ``templates/group.py`` (``advance_group``) for the model's
    components: several cells and their membrane-membrane contact, stepped together."""
    if model.nonlinear_friction:
        raise ParameterError(
            "friction_law",
            model.friction.name,
            "must be viscous for an assembly of cells (the pair forces move the membrane "
            "by its linear mobility)",
            "1",
        )
    if not model.pair_terms:
        raise ParameterError(
            "pair_terms", "[]", "must name at least one pair term for an assembly", "1"
        )
    if model.event is not None:
        raise ParameterError(
            "driving_protocol",
            model.protocol.name,
            "must have no state events for an assembly of cells (the group loop does not "
            "locate them yet)",
            "1",
        )
    rhs, jacobian, _ = compiled_loop(model)
    module = compile_module(
        "rodas4-group",
        template(__package__ + ".templates", "group.py"),
        {"rhs": rhs, "jacobian": jacobian, "pair_law": compose_pair_laws(model.pair_terms)},
        f"{_names(model.terms)}; {model.protocol.name}; pairs {_names(model.pair_terms)}",
    )
    return module.advance_group


class GroupWork(NamedTuple):
    """Scratch arrays of the group loop for G cells of nu unknowns each."""

    jac: np.ndarray
    mat: np.ndarray
    pivots: np.ndarray
    k: np.ndarray
    f0: np.ndarray
    y: np.ndarray
    ynew: np.ndarray
    force: np.ndarray
    scratch: np.ndarray
    phases: np.ndarray
    data: np.ndarray


class PairWork(NamedTuple):
    """What the pair forces read: the members' points ``z`` (complex128[G, N], cm), scratch
    ``modes`` and ``spec``, the image ``shifts`` (float64[G, G, 2], cm), the ``contacts``
    table, ``constants`` = [the pair terms' reach (cm), the membrane's mobility, the
    difference step of hess rho (cm)], ``twiddle`` = exp(-2 pi i n / N) and ``laws``, the
    pair terms' coefficient arrays."""

    z: np.ndarray
    modes: np.ndarray
    spec: np.ndarray
    shifts: np.ndarray
    contacts: np.ndarray
    constants: np.ndarray
    twiddle: np.ndarray
    laws: tuple


def group_work(model: Model, cells: int) -> tuple[GroupWork, PairWork]:
    """The group loop's scratch arrays for ``cells`` cells of ``model``."""
    m = 2 * model.cutoff + 1
    nu = 2 * m + 3
    size = cells * nu
    n = model.nodes
    reach = model.pair_reach
    # hess rho varies on the scale of the distance itself; the step is 1e-6 of the reach
    constants = np.array([reach, model.membrane_mobility, 1e-6 * reach])
    work = GroupWork(
        jac=np.zeros((size, size)),
        mat=np.zeros((size, size)),
        pivots=lu_workspace(size, transposed=True),
        k=np.zeros((6, size)),
        f0=np.zeros(size),
        y=np.zeros(size),
        ynew=np.zeros(size),
        force=np.zeros(size),
        scratch=np.zeros(nu),
        phases=np.zeros(cells, dtype=np.int8),
        data=np.zeros(cells),
    )
    pair = PairWork(
        z=np.zeros((cells, n), np.complex128),
        modes=np.zeros(m, np.complex128),
        spec=np.zeros(n, np.complex128),
        shifts=np.zeros((cells, cells, 2)),
        contacts=np.zeros((4 * n * cells, 4), np.int64),
        constants=constants,
        twiddle=np.exp(-2j * np.pi * np.arange(n) / n),
        laws=tuple(np.ascontiguousarray(t.coefficients()) for t in model.pair_terms),
    )
    return work, pair


def pack(modes: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """The unknowns as one float64 vector: Re g, Im g (cm), then x, y (cm), heading (rad)."""
    return np.concatenate([modes.real, modes.imag, pose]).astype(np.float64)


def unpack(u: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`pack`: modes (complex128[m]) and pose (float64[3])."""
    return u[:m] + 1j * u[m : 2 * m], u[2 * m : 2 * m + 3].copy()


_NO_EVENTS = np.zeros(0)
_NO_COUNT = np.zeros(1, dtype=np.int64)
_TABLEAU = Coefficients(RODAS4.a, RODAS4.c, RODAS4.dense)


def _rewind(state: dict, schedule: Schedule) -> None:
    """Bring a cell's state back to its last sample (``state["time"]``) if its steps ran
    ahead of it (rodas4 samples its continuous extension): the state there, its phase then,
    and the next step tried from there."""
    t = float(state["time"][0])
    clock = state["clock"]
    if clock[T] <= t + 1e-12 * (1.0 + abs(t)):
        return
    state["u"][:] = pack(state["modes"], state["pose"])
    clock[T] = t
    clock[H_LAST] = 0.0
    state["phase_index"][0] = int(np.searchsorted(schedule.start, t, side="right")) - 1


_GROUP_FAILURES = {
    STEP_UNDERFLOW: "the step size underflowed",
    SINGULAR: "the iteration matrix is singular",
    3: "more membrane contacts than the contact table holds (membranes overlapping)",
}


class Rodas4Stepper(Stepper):
    def __init__(
        self,
        model: Model,
        atol: float,
        rtol: float,
        max_step: float,
        first_step: float,
        smooth_nodes: int,
    ) -> None:
        self.model = model
        self.rhs, self.jacobian, self.integrate = compiled_loop(model)
        self.ws = workspace(model, min(smooth_nodes, model.nodes))
        self.coefficients = group_coefficients(model)
        self.problem = Problem(
            self.coefficients,
            model.context,
            model.drive_coefficients,
            nonlinear_friction.mobility(model),
            model.bot_mobility,
            model.has_membrane,
        )
        self.atol, self.rtol, self.max_step, self.first_step = atol, rtol, max_step, first_step
        self._smooth_nodes = smooth_nodes
        self._control = Control(atol, rtol, max_step)
        self._cells: dict[int, list] = {}  # each cell's arguments (see _prepared)
        self._group = None  # the group loop, compiled on first use
        self._group_work: dict[int, tuple[GroupWork, PairWork]] = {}

    def load_group_loop(self) -> None:
        """Load the group loop of cells in contact (:func:`compiled_group`) now rather than
        at the first contact; an assembly's run loads it before its progress bar starts."""
        if self._group is None:
            self._group = compiled_group(self.model)

    def twin(self) -> Rodas4Stepper:
        """A stepper of the same model and control with workspaces of its own, to step other
        cells on another thread at the same time (the compiled loops release the GIL). What
        a step computes depends on its cells' states alone, so the twin's steps are the
        same to the bit."""
        self.load_group_loop()
        twin = copy.copy(self)
        twin.ws = workspace(self.model, min(self._smooth_nodes, self.model.nodes))
        twin._group_work = {}
        twin._cells = {}
        return twin

    def start(self, modes, pose, schedule):
        u = pack(np.asarray(modes, dtype=np.complex128), np.asarray(pose, dtype=np.float64))
        clock = np.zeros(7)
        clock[H_NEXT] = self.first_step
        clock[ERR_ACCEPTED] = 1.0
        return {
            "modes": np.asarray(modes, dtype=np.complex128).copy(),
            "pose": np.asarray(pose, dtype=np.float64).copy(),
            "time": np.zeros(1),
            "u": u,
            "clock": clock,
            "phase_index": np.zeros(1, dtype=np.int64),
            "counters": np.zeros(4, dtype=np.int64),
            "dense": np.zeros((4, u.size)),
            **event_state(self.model, schedule),
        }

    def advance(self, state, schedule: Schedule, t_end: float) -> None:
        self.sample(state, schedule, np.array([t_end], dtype=np.float64))

    def current(self, state) -> tuple[np.ndarray, np.ndarray, float]:
        """The last accepted step's modes (cm), pose (cm, cm, rad) and time (s), which run
        ahead of ``modes`` and ``pose`` (the last sample's) when a step fails."""
        size = 2 * self.model.cutoff + 1
        u = state["u"]
        return u[:size] + 1j * u[size : 2 * size], u[2 * size :].copy(), float(state["clock"][T])

    def _prepared(self, state, schedule: Schedule) -> list:
        """[the arrays checked, LoopState, PhaseTable, EventLog, compiled entry or None]: the
        arguments of the compiled loop that belong to ``state`` and ``schedule``, and the
        loop's compiled entry for their types: made on a cell's first call (numba resolves
        the types, ~30 us a call for these tuples of arrays) and kept while the same arrays
        and schedule are passed, so that the many short calls of an assembly's cells skip
        the resolution (a call then costs ~4 us besides the steps)."""
        arrays = (
            state["u"],
            state["clock"],
            state["phase_index"],
            state["counters"],
            state["dense"],
            state.get("starts", schedule.start),
            state.get("event_times", _NO_EVENTS),
            state.get("event_count", _NO_COUNT),
            schedule,
        )
        kept = self._cells.get(id(state["u"]))
        if kept is not None and all(a is b for a, b in zip(kept[0], arrays, strict=True)):
            return kept
        if len(self._cells) > 4096:  # states of earlier realizations
            self._cells.clear()
        kept = [
            arrays,
            LoopState(*arrays[:5]),
            PhaseTable(arrays[5], schedule.phase, schedule.data),
            EventLog(arrays[6], arrays[7]),
            None,  # the compiled entry, once the first call has resolved it
        ]
        self._cells[id(state["u"])] = kept
        return kept

    def sample(self, state, schedule: Schedule, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m = self.model
        times = np.ascontiguousarray(times, dtype=np.float64)
        samples = np.empty((times.size, state["u"].size))
        kept = self._prepared(state, schedule)
        _, loop, table, events, entry = kept
        args = (loop, times, samples, table, self.problem, self._control, _TABLEAU, self.ws, events)
        if entry is None:
            status = self.integrate(*args)
            kept[4] = self.integrate.get_overload(tuple(numba.typeof(a) for a in args))
        else:
            status = entry(*args)
        if status != OK:
            t = state["clock"][T]
            reason = (
                "the step size underflowed"
                if status == STEP_UNDERFLOW
                else "the iteration matrix is singular"
            )
            raise SimulationError(f"rodas4 failed at t = {t:.9g} s: {reason}")
        size = 2 * m.cutoff + 1
        modes = samples[:, :size] + 1j * samples[:, size : 2 * size]
        pose = samples[:, 2 * size :]
        state["modes"][:], state["pose"][:] = modes[-1], pose[-1]
        state["time"][0] = times[-1]
        return modes, pose

    def advance_cells(
        self,
        states: list[dict],
        schedules: list[Schedule],
        shifts: np.ndarray,
        t_end: float,
        rewind: bool = True,
    ) -> None:
        """Advance cells in contact together to ``t_end`` (s): ``states`` (each cell's, from
        :meth:`start`, at one time) and ``schedules`` are the members', ``shifts``
        (float64[G, G, 2], cm) the image shift of member d's points seen from member c. The
        group's steps land on every member's switches; afterwards each member's state holds
        the group's clock and its own slice of the last step's continuous extension.
        ``rewind`` brings every member back to its last sample first (steps of a cell alone,
        or of another group, may have run ahead of it); False continues a group that stepped
        together over the last interval from where its steps stopped."""
        self.load_group_loop()
        g = len(states)
        if g not in self._group_work:
            self._group_work[g] = group_work(self.model, g)
        work, pair = self._group_work[g]
        pair.shifts[:] = shifts
        nu = states[0]["u"].size
        if rewind:
            for s, schedule in zip(states, schedules, strict=True):
                _rewind(s, schedule)
        u = np.concatenate([s["u"] for s in states])
        clock = states[0]["clock"].copy()
        clock[H_NEXT] = min(s["clock"][H_NEXT] for s in states)
        clock[H_ACCEPTED] = 0.0  # no step of this group to predict from yet
        p = np.array([s["phase_index"][0] for s in states], dtype=np.int64)
        counters = np.zeros(4, dtype=np.int64)
        dense = np.concatenate([s["dense"] for s in states], axis=1)
        offsets = np.cumsum([0] + [len(s.start) for s in schedules])
        table = (
            np.concatenate([s.start for s in schedules]),
            np.concatenate([s.phase for s in schedules]),
            np.concatenate([s.data for s in schedules]),
            offsets.astype(np.int64),
        )
        sample = np.empty(u.size)
        status = self._group(
            LoopState(u, clock, p, counters, dense),
            float(t_end),
            sample,
            table,
            self.problem,
            Control(self.atol, self.rtol, self.max_step),
            Coefficients(RODAS4.a, RODAS4.c, RODAS4.dense),
            self.ws,
            work,
            pair,
        )
        if status != OK:
            raise SimulationError(
                f"rodas4 failed on a group of {g} cells at t = {clock[T]:.9g} s: "
                + _GROUP_FAILURES.get(status, f"status {status}")
            )
        size = 2 * self.model.cutoff + 1
        for c, s in enumerate(states):
            part = slice(c * nu, (c + 1) * nu)
            s["u"][:] = u[part]
            s["clock"][:] = clock
            s["phase_index"][0] = p[c]
            s["counters"] += counters
            s["dense"][:] = dense[:, part]
            s["modes"][:] = sample[part][:size] + 1j * sample[part][size : 2 * size]
            s["pose"][:] = sample[part][2 * size :]
            s["time"][0] = t_end

    def statistics(self, state) -> dict[str, int]:
        """Steps accepted and rejected, right-hand-side and Jacobian evaluations so far."""
        c = state["counters"]
        return {
            "steps": int(c[STEPS]),
            "rejected": int(c[REJECTED]),
            "rhs_calls": int(c[RHS_CALLS]),
            "jacobians": int(c[JACOBIANS]),
        }


class Rodas4(Integrator):
    """Adaptive linearly implicit RODAS4 (order 4(3), L-stable) on the whole coupled system."""

    name = "rodas4"
    #: Steps groups of cells in contact together (:meth:`Rodas4Stepper.advance_cells`).
    steps_groups = True
    #: Steps several bots in one ring (:meth:`build_bots`).
    steps_bots = True
    description = (
        "adaptive Rosenbrock RODAS4, order 4(3), full Jacobian, steps on the "
        "protocol's switches, dense output"
    )
    parameters = (
        ParameterSpec(
            "atol",
            3e-6,
            "cm",
            "absolute error tolerance of rodas4 per step "
            "(cm for positions and modes, rad for the heading)",
            minimum=0.0,
        ),
        ParameterSpec(
            "rtol", 3e-6, "1", "relative error tolerance of rodas4 per step", minimum=0.0
        ),
        ParameterSpec("max_step", 0.2, "s", "largest step of rodas4", minimum=0.0),
        ParameterSpec("first_step", 1e-4, "s", "first trial step of rodas4", minimum=0.0),
        ParameterSpec(
            "smooth_nodes",
            128,
            "1",
            "collocation points of rodas4's coarse grid for smooth energy terms (bending, tension)",
            kind=int,
            minimum=8,
            minimum_inclusive=True,
            power_of_two=True,
        ),
    )

    @classmethod
    def check(cls, params):
        lc, smooth = int(params.cutoff), int(params.smooth_nodes)
        if smooth < 4 * lc and smooth < int(params.nodes):
            raise ParameterError(
                "smooth_nodes",
                smooth,
                f"must be >= 4 cutoff = {4 * lc} (or "
                f">= nodes) so that the smooth terms' forces are not aliased",
                "1",
            )

    def build(self, model: Model) -> Rodas4Stepper:
        p = self.params
        return Rodas4Stepper(
            model,
            float(p.atol),
            float(p.rtol),
            float(p.max_step),
            float(p.first_step),
            int(p.smooth_nodes),
        )

    def build_bots(self, model: Model, bots: int):
        """The stepper of ``bots`` (> 1) bots in one ring
        (:class:`~softcell.integrators.rodas4.several.BotsStepper`)."""
        from softcell.integrators.rodas4.several import BotsStepper

        p = self.params
        return BotsStepper(
            model,
            bots,
            float(p.atol),
            float(p.rtol),
            float(p.max_step),
            float(p.first_step),
            min(int(p.smooth_nodes), model.nodes),
        )


@hookimpl
def softcell_integrators() -> list[type[Integrator]]:
    return [Rodas4]
