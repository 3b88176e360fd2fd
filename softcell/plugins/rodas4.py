"""RODAS4: an adaptive, L-stable, stiffly accurate Rosenbrock method of order 4(3) (Hairer &
Wanner, Solving ODEs II, section IV.7; coefficients of their code RODAS), for the whole coupled
system: the membrane modes, the contact and the bot (~70 unknowns).

Each step factors W = I / (h gamma) - J once, with J the Jacobian of the full right-hand side
(:mod:`softcell.kernels.jacobian`), and solves six linear systems; the sixth stage is the
embedded error estimate. Steps adapt to the error (Gustafsson's predictive controller), land
exactly on the protocol's switching times (within a step the right-hand side is autonomous),
and samples come from the method's continuous extension, so the sampling grid never
constrains the step. Everything runs inside one compiled loop; nothing is allocated per step.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from softcell.config import JIT
from softcell.core.components.contracts import Integrator, Schedule
from softcell.core.components.hookspecs import hookimpl
from softcell.core.engine import (
    Model,
    SimulationError,
    Stepper,
    compose_hessians,
    compose_partials,
    fd_drive_jacobian,
    nonlinear_friction,
)
from softcell.core.engine.compiled import compile_module
from softcell.core.engine.compose import compose_bot, template
from softcell.core.params import ParameterSpec
from softcell.errors import ParameterError
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

#: Status codes of the compiled loop.
OK, STEP_UNDERFLOW, SINGULAR = 0, 1, 2

#: Slots of the ``clock`` state array.
T, H_NEXT, H_ACCEPTED, ERR_ACCEPTED, T_LAST, H_LAST, REJECTED_LAST = range(7)
#: Slots of the ``counters`` state array.
STEPS, REJECTED, RHS_CALLS, JACOBIANS = range(4)

Grid = namedtuple(
    "Grid",
    [
        "spec",
        "curve",
        "w",
        "parts",
        "q",
        "fhat",
        "dpose",
        "saved",
        "plus",
        "minus",
        "hww",
        "hwp",
        "hpp",
        "twiddle",
        "index",
        "active",
        "n_active",
        "buf_a",
        "buf_b",
        "scratch",
        "cursor",
    ],
)

Workspace = namedtuple(
    "Workspace",
    [
        "modes",
        "smooth",
        "fine",
        "drv",
        "steps",
        "dplus",
        "dminus",
        "pose_tmp",
        "djac",
        "drv_plus",
        "drv_minus",
        "a_hat",
        "b_hat",
        "g_hat",
        "cal_a",
        "cal_b",
        "factors",
        "orders",
        "jac",
        "mat",
        "pivots",
        "k",
        "f0",
        "y",
        "ynew",
        "force",
        "drag",
        "law",
        "bot_hpp",
    ],
)


def grid(n: int, m: int) -> Grid:
    """Scratch arrays of one collocation grid of n points (m = 2 Lc + 1 modes)."""
    c = np.complex128
    return Grid(
        spec=np.zeros(n, c),
        curve=np.zeros((3, n), c),
        w=np.zeros((6, n)),
        parts=np.zeros((6, n)),
        q=np.zeros((3, n), c),
        fhat=np.zeros(m, c),
        dpose=np.zeros(3),
        saved=np.zeros(n),
        plus=np.zeros((6, n)),
        minus=np.zeros((6, n)),
        hww=np.zeros((n, 6, 6)),
        hwp=np.zeros((n, 6, 3)),
        hpp=np.zeros((3, 3)),
        twiddle=np.exp(-2j * np.pi * np.arange(n) / n),
        index=np.zeros(n, np.int64),
        active=np.zeros(n, np.int64),
        n_active=np.zeros(1, np.int64),
        buf_a=np.zeros(n, c),
        buf_b=np.zeros(n, c),
        scratch=np.zeros(n, c),
        cursor=np.zeros(n, np.int64),
    )


def workspace(model: Model, smooth_nodes: int) -> Workspace:
    """Every scratch array of the compiled loop, allocated once per stepper."""
    n, lc = model.nodes, model.cutoff
    m = 2 * lc + 1
    nu = 2 * m + 3
    scale = model.params.membrane_length / (2 * math.pi)
    c = np.complex128
    return Workspace(
        modes=np.zeros(m, c),
        smooth=grid(smooth_nodes, m),
        fine=grid(n, m),
        drv=np.zeros(3),
        steps=np.array([1e-7 * scale] * 8 + [1e-7]),
        dplus=np.zeros(3),
        dminus=np.zeros(3),
        pose_tmp=np.zeros(3),
        djac=np.zeros((3, 3)),
        drv_plus=np.zeros(3),
        drv_minus=np.zeros(3),
        a_hat=np.zeros(4 * lc + 1, c),
        b_hat=np.zeros(4 * lc + 1, c),
        g_hat=np.zeros(m, c),
        cal_a=np.zeros((m, m), c),
        cal_b=np.zeros((m, m), c),
        factors=np.zeros((3, m), c),
        orders=np.zeros((3, m), c),
        jac=np.zeros((nu, nu)),
        mat=np.zeros((nu, nu)),
        pivots=np.zeros(nu, np.int64),
        k=np.zeros((6, nu)),
        f0=np.zeros(nu),
        y=np.zeros(nu),
        ynew=np.zeros(nu),
        force=np.zeros(nu),
        drag=np.zeros(3),
        law=nonlinear_friction.model_workspace(model, nu),
        bot_hpp=np.zeros((3, 3)),
    )


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


def groups(model: Model) -> tuple[list, list]:
    """The model's terms split into those evaluated on the coarse grid (``smooth``) and the
    others, each as a list of (index, term)."""
    smooth = [(i, t) for i, t in enumerate(model.terms) if t.smooth]
    other = [(i, t) for i, t in enumerate(model.terms) if not t.smooth]
    return smooth, other


def _names(terms) -> str:
    return " + ".join(t.name for t in terms) or "none"


def compiled_loop(model: Model) -> tuple:
    """(rhs, jacobian, integrate) compiled for the model's terms and drive: generated modules
    from ``templates/rodas4_grid.py`` (once per group of terms) and
    ``templates/rodas4_loop.py``, cached on disk (:mod:`softcell.core.engine.compiled`), with
    the model's friction law when it is nonlinear
    (:mod:`softcell.core.engine.nonlinear_friction`)."""
    grid_source = template(__package__ + ".templates", "rodas4_grid.py")
    bindings: dict[str, object] = {}
    for suffix, group in zip("sf", groups(model), strict=True):
        terms = [t for _, t in group]
        grid_module = compile_module(
            "rodas4-grid",
            grid_source,
            {
                "partials": compose_partials([t.partials_kernel() for t in terms]),
                "hessian": compose_hessians(terms),
                # the coarse grid is always scanned; the others are unless every term has an
                # analytic Hessian
                "SCAN": suffix == "s" or any(t.hessian_kernel() is None for t in terms),
            },
            _names(terms),
        )
        bindings[f"forces_{suffix}"] = grid_module.forces
        bindings[f"jacobian_{suffix}"] = grid_module.grid_jacobian
        bindings[f"HAS_{suffix.upper()}"] = bool(terms)
        bindings[f"ORDER_{suffix.upper()}"] = max([t.derivative_order for t in terms], default=0)
        bindings[f"HAS_BOT_{suffix.upper()}"] = any(t.acts_on_bot for t in terms)
        bindings[f"bot_forces_{suffix}"], bindings[f"bot_hessians_{suffix}"] = (
            compose_bot(terms) if any(t.acts_on_bot for t in terms) else (0, 0)
        )
    bindings["drive"] = model.drive
    bindings["drive_jacobian"] = fd_drive_jacobian(model.drive)
    bindings["LAW"] = model.nonlinear_friction
    law = nonlinear_friction.compiled_friction(model.friction) if model.nonlinear_friction else None
    # unused (and pruned by numba) with the linear law
    bindings["friction_velocity"] = law.velocity if law else 0
    bindings["friction_jacobian"] = law.jacobian if law else 0
    loop = compile_module(
        "rodas4-loop",
        template(__package__ + ".templates", "rodas4_loop.py"),
        bindings,
        f"{_names(model.terms)}; {model.protocol.name}"
        + (f"; {model.friction.name}" if law else ""),
    )
    return loop.rhs, loop.jacobian, loop.integrate


def group_coefficients(model: Model) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """The terms' coefficient arrays, split like :func:`groups`."""
    out = []
    for group in groups(model):
        out.append(tuple(model.coefficients[i] for i, _ in group) or (np.zeros(1),))
    return out[0], out[1]


def pack(modes: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """The unknowns as one float64 vector: Re g, Im g (cm), then x, y (cm), heading (rad)."""
    return np.concatenate([modes.real, modes.imag, pose]).astype(np.float64)


def unpack(u: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`pack`: modes (complex128[m]) and pose (float64[3])."""
    return u[:m] + 1j * u[m : 2 * m], u[2 * m : 2 * m + 3].copy()


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
        self.atol, self.rtol, self.max_step, self.first_step = atol, rtol, max_step, first_step

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
        }

    def advance(self, state, schedule: Schedule, t_end: float) -> None:
        self.sample(state, schedule, np.array([t_end], dtype=np.float64))

    def sample(self, state, schedule: Schedule, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m = self.model
        times = np.ascontiguousarray(times, dtype=np.float64)
        samples = np.empty((times.size, state["u"].size))
        status = self.integrate(
            state["u"],
            state["clock"],
            state["phase_index"],
            state["counters"],
            state["dense"],
            times,
            samples,
            schedule.start,
            schedule.phase,
            schedule.data,
            self.coefficients,
            m.context,
            m.drive_coefficients,
            nonlinear_friction.mobility(m),
            m.bot_mobility,
            m.has_membrane,
            self.atol,
            self.rtol,
            self.max_step,
            RODAS4.a,
            RODAS4.c,
            RODAS4.dense,
            self.ws,
        )
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
    description = (
        "adaptive Rosenbrock RODAS4, order 4(3), full Jacobian, steps on the "
        "protocol's switches, dense output"
    )
    parameters = (
        ParameterSpec(
            "atol",
            1e-6,
            "cm",
            "absolute error tolerance of rodas4 per step "
            "(cm for positions and modes, rad for the heading)",
            minimum=0.0,
        ),
        ParameterSpec(
            "rtol", 1e-6, "1", "relative error tolerance of rodas4 per step", minimum=0.0
        ),
        ParameterSpec("max_step", 0.05, "s", "largest step of rodas4", minimum=0.0),
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


@hookimpl
def softcell_integrators() -> list[type[Integrator]]:
    return [Rodas4]
