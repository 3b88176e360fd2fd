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
from rocket_fft import c2c

from softcell.config import JIT_COMPOSED
from softcell.core.engine import Model, SimulationError, Stepper, compose_partials
from softcell.core.params import ParameterSpec
from softcell.core.plugin.contracts import Integrator, Schedule
from softcell.core.plugin.hookspecs import hookimpl
from softcell.errors import ParameterError
from softcell.kernels.jacobian import (
    SPARSE_POINTS,
    active_points,
    assemble_jacobian,
    compose_hessians,
    make_fd_drive_jacobian,
)
from softcell.kernels.rosenbrock import (
    Tableau,
    dense_output,
    dense_value,
    error_norm,
    factor_iteration_matrix,
    stages,
)
from softcell.kernels.spectral import AXES, assemble, derivative_spectrum

# RODAS4 in Hairer & Wanner's transformed variables: gamma, a_ij, c_ij, dense output h_ij.
GAMMA = 0.25
A = np.array([
    [0.0, 0.0, 0.0, 0.0],
    [1.544, 0.0, 0.0, 0.0],
    [0.9466785280815826, 0.2557011698983284, 0.0, 0.0],
    [3.314825187068521, 2.896124015972201, 0.9986419139977817, 0.0],
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950],
])
C = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [-5.6688, 0.0, 0.0, 0.0, 0.0],
    [-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0],
    [-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0.0, 0.0],
    [7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160, 0.0],
    [8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136,
     -6.058818238834054],
])
DENSE = np.array([
    [10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823,
     1.025137723295662],
    [-0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386,
     -6.594389125716872],
])

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

Grid = namedtuple("Grid", [
    "spec", "curve", "w", "parts", "q", "fhat", "dpose", "saved", "plus", "minus", "hww",
    "hwp", "hpp", "twiddle", "index", "active", "n_active", "buf_a", "buf_b", "scratch"])

Workspace = namedtuple("Workspace", [
    "modes", "smooth", "fine", "drv", "steps", "dplus", "dminus", "pose_tmp", "djac",
    "drv_plus", "drv_minus", "a_hat", "b_hat", "g_hat", "cal_a", "cal_b", "factors", "orders",
    "jac", "mat", "pivots", "k", "f0", "y", "ynew", "force", "drag"])


def grid(n: int, m: int) -> Grid:
    """Scratch arrays of one collocation grid of n points (m = 2 Lc + 1 modes)."""
    c = np.complex128
    return Grid(spec=np.zeros(n, c), curve=np.zeros((3, n), c), w=np.zeros((6, n)),
                parts=np.zeros((6, n)), q=np.zeros((3, n), c), fhat=np.zeros(m, c),
                dpose=np.zeros(3), saved=np.zeros(n), plus=np.zeros((6, n)),
                minus=np.zeros((6, n)), hww=np.zeros((n, 6, 6)), hwp=np.zeros((n, 6, 3)),
                hpp=np.zeros((3, 3)), twiddle=np.exp(-2j * np.pi * np.arange(n) / n),
                index=np.zeros(n, np.int64), active=np.zeros(n, np.int64),
                n_active=np.zeros(1, np.int64), buf_a=np.zeros(n, c), buf_b=np.zeros(n, c),
                scratch=np.zeros(n, c))


def workspace(model: Model, smooth_nodes: int) -> Workspace:
    """Every scratch array of the compiled loop, allocated once per stepper."""
    n, lc = model.nodes, model.cutoff
    m = 2 * lc + 1
    nu = 2 * m + 3
    scale = model.params.membrane_length / (2 * math.pi)
    c = np.complex128
    return Workspace(
        modes=np.zeros(m, c), smooth=grid(smooth_nodes, m), fine=grid(n, m), drv=np.zeros(3),
        steps=np.array([1e-7 * scale] * 8 + [1e-7]), dplus=np.zeros(3), dminus=np.zeros(3),
        pose_tmp=np.zeros(3), djac=np.zeros((3, 3)), drv_plus=np.zeros(3),
        drv_minus=np.zeros(3), a_hat=np.zeros(4 * lc + 1, c), b_hat=np.zeros(4 * lc + 1, c),
        g_hat=np.zeros(m, c), cal_a=np.zeros((m, m), c), cal_b=np.zeros((m, m), c),
        factors=np.zeros((3, m), c), orders=np.zeros((3, m), c), jac=np.zeros((nu, nu)),
        mat=np.zeros((nu, nu)), pivots=np.zeros(nu, np.int64), k=np.zeros((6, nu)),
        f0=np.zeros(nu), y=np.zeros(nu), ynew=np.zeros(nu), force=np.zeros(nu),
        drag=np.zeros(3))


@njit(**JIT_COMPOSED)
def _accumulate(g, mobility, out, drag):
    """Add one grid's force modes to the modes' rates in ``out`` and its (2 pi / N)-weighted
    pose derivatives to ``drag``."""
    m = g.fhat.size
    weight = 2.0 * math.pi / g.w.shape[1]
    for j in range(m):
        out[j] += mobility * g.fhat[j].real
        out[m + j] += mobility * g.fhat[j].imag
    for c in range(3):
        drag[c] += weight * g.dpose[c]


def _make_grid_functions(partials, hessian, scan):
    """Force modes and Jacobian contributions of one group of terms on one grid.

    With ``scan`` False, second derivatives are taken to vanish where all partials do (true
    of the contact, which vanishes beyond its cut-off) and only those points are visited;
    otherwise (the fallback's differences, or a small grid) every point is scanned.
    """

    @njit(**JIT_COMPOSED)
    def forces(modes, pose, order, context, coefficients, g):
        """g.fhat (N) and g.dpose of the group at these modes; curve derivatives above
        ``order`` are left at zero."""
        n = g.w.shape[1]
        lc = (modes.size - 1) // 2
        for o in range(order + 1):
            derivative_spectrum(modes, o, g.spec)
            c2c(g.spec, g.curve[o], AXES, False, 1.0, 1)
            for i in range(n):
                g.w[2 * o, i] = g.curve[o, i].real
                g.w[2 * o + 1, i] = g.curve[o, i].imag
        g.parts[:, :] = 0.0
        g.dpose[:] = 0.0
        p = g.parts
        partials(g.w[0], g.w[1], g.w[2], g.w[3], g.w[4], g.w[5], pose, context, coefficients,
                 p[0], p[1], p[2], p[3], p[4], p[5], g.dpose)
        count = 0
        n_active = 0
        higher = False
        for i in range(n):
            zero = True
            if p[0, i] != 0.0 or p[1, i] != 0.0:
                g.index[count] = i
                count += 1
                zero = False
            if p[2, i] != 0.0 or p[3, i] != 0.0 or p[4, i] != 0.0 or p[5, i] != 0.0:
                higher = True
                zero = False
            if not zero:
                g.active[n_active] = i
                n_active += 1
        g.n_active[0] = n_active
        if higher or count > SPARSE_POINTS:
            for i in range(n):
                for o in range(3):
                    g.q[o, i] = complex(p[2 * o, i], p[2 * o + 1, i])
            assemble(g.q[0], g.q[1], g.q[2], count > 0, g.spec, g.fhat)
        else:
            # Only a few points carry a force (the contact): direct sums, no FFT.
            inv = 1.0 / n
            for j in range(modes.size):
                k = j - lc
                acc = 0.0 + 0.0j
                for t in range(count):
                    i = g.index[t]
                    acc += complex(p[0, i], p[1, i]) * g.twiddle[(k * i) % n]
                g.fhat[j] = -acc * inv

    @njit(**JIT_COMPOSED)
    def jacobian(pose, context, coefficients, mobility, bot_mobility, g, ws):
        """Add the group's part of the Jacobian into ws.jac; g.w must hold the curve and
        g.active the points where the last :func:`forces` at this state found partials."""
        hessian(g.w, pose, context, coefficients, ws.steps, g.saved, g.plus, g.minus,
                ws.dplus, ws.dminus, ws.pose_tmp, g.hww, g.hwp, g.hpp)
        if scan:
            n_active = active_points(g.hww, g.hwp, g.active)
        else:
            n_active = g.n_active[0]
        assemble_jacobian(g.hww, g.hwp, g.hpp, (ws.modes.size - 1) // 2, mobility,
                          bot_mobility, g.twiddle, g.index, g.active, n_active, g.buf_a,
                          g.buf_b, g.scratch,
                          ws.a_hat, ws.b_hat, ws.g_hat, ws.cal_a, ws.cal_b, ws.factors,
                          ws.orders, ws.jac)

    return forces, jacobian


def _make_rhs(smooth_group, fine_group, drive):
    """The compiled right-hand side and its Jacobian. Each group is (partials, hessian,
    present, order, scan) for the smooth terms (coarse grid) and the others (N points)."""
    forces_s, jacobian_s = _make_grid_functions(smooth_group[0], smooth_group[1], True)
    forces_f, jacobian_f = _make_grid_functions(fine_group[0], fine_group[1], fine_group[4])
    has_s, order_s = smooth_group[2], smooth_group[3]
    has_f, order_f = fine_group[2], fine_group[3]
    fd_drive = make_fd_drive_jacobian(drive)

    @njit(**JIT_COMPOSED)
    def rhs(u, phase, datum, out, coefficients, context, drive_coefficients, mobility,
            bot_mobility, membrane, ws):
        """du/dt at u (phase fixed); leaves the curves at u in the grids' ``w``.
        ``coefficients``: (smooth group's, other group's)."""
        m = ws.modes.size
        pose = u[2 * m:]
        drag = ws.drag
        drag[:] = 0.0
        if membrane:
            for j in range(m):
                ws.modes[j] = complex(u[j], u[m + j])
            for j in range(m):
                out[j] = 0.0
                out[m + j] = 0.0
            if has_s:
                forces_s(ws.modes, pose, order_s, context, coefficients[0], ws.smooth)
                _accumulate(ws.smooth, mobility, out, drag)
            if has_f:
                forces_f(ws.modes, pose, order_f, context, coefficients[1], ws.fine)
                _accumulate(ws.fine, mobility, out, drag)
        else:
            out[:2 * m] = 0.0
        drive(phase, datum, pose, context, drive_coefficients, ws.drv)
        for c in range(3):
            out[2 * m + c] = bot_mobility[c] * (ws.drv[c] - drag[c])

    @njit(**JIT_COMPOSED)
    def jacobian(u, phase, datum, coefficients, context, drive_coefficients, mobility,
                 bot_mobility, membrane, ws):
        """The Jacobian at u into ``ws.jac``; the grids' ``w`` must hold the curves at u."""
        m = ws.modes.size
        pose = u[2 * m:]
        ws.jac[:, :] = 0.0
        if membrane:
            if has_s:
                jacobian_s(pose, context, coefficients[0], mobility, bot_mobility, ws.smooth,
                           ws)
            if has_f:
                jacobian_f(pose, context, coefficients[1], mobility, bot_mobility, ws.fine, ws)
        fd_drive(phase, datum, pose, context, drive_coefficients, ws.steps, ws.pose_tmp,
                 ws.drv_plus, ws.drv_minus, ws.djac)
        for c in range(3):
            for d in range(3):
                ws.jac[2 * m + c, 2 * m + d] += bot_mobility[c] * ws.djac[c, d]

    return rhs, jacobian


def _make_loop(rhs, jacobian):  # noqa: C901 (its complexity is the compiled advance_to)
    """The compiled time loop around :func:`_make_rhs`'s right-hand side and Jacobian: steps
    of the generic Rosenbrock method with RODAS4's tableau, step-size control, landing on
    the protocol's switches, and samples from the continuous extension."""

    @njit(**JIT_COMPOSED)
    def stage_rhs(y, out, args):
        """The right-hand side in the form of :func:`softcell.kernels.rosenbrock.stages`."""
        phase, datum, coefficients, context, drive_coefficients, mobility, bot_mobility, \
            membrane, ws = args
        rhs(y, phase, datum, out, coefficients, context, drive_coefficients, mobility,
            bot_mobility, membrane, ws)

    @njit(**JIT_COMPOSED)
    def advance_to(u, clock, phase_index, counters, dense, t_end, sample, starts, phases, data,
                   coefficients, context, drive_coefficients, mobility, bot_mobility,
                   membrane, atol, rtol, max_step, a, cc, hd, ws):
        t = clock[T]
        p = phase_index[0]
        k = ws.k
        y = ws.y
        ynew = ws.ynew
        force = ws.force
        mat = ws.mat
        eps = 1e-12 * (1.0 + abs(t_end))
        while t < t_end - eps:
            t_switch = starts[p + 1] if p + 1 < starts.size else np.inf
            phase, datum = phases[p], data[p]
            rhs(u, phase, datum, ws.f0, coefficients, context, drive_coefficients, mobility,
                bot_mobility, membrane, ws)
            jacobian(u, phase, datum, coefficients, context, drive_coefficients, mobility,
                     bot_mobility, membrane, ws)
            counters[RHS_CALLS] += 1
            counters[JACOBIANS] += 1
            while True:
                h = min(clock[H_NEXT], max_step)
                land = False
                if t_switch - t <= 1.05 * h:
                    h = t_switch - t
                    land = True
                if h <= 1e-14 * (1.0 + abs(t)):
                    return STEP_UNDERFLOW
                if not factor_iteration_matrix(ws.jac, h, GAMMA, mat, ws.pivots):
                    return SINGULAR
                stages(stage_rhs, (phase, datum, coefficients, context, drive_coefficients,
                                   mobility, bot_mobility, membrane, ws),
                       u, ws.f0, h, a, cc, mat, ws.pivots, k, y, force)
                counters[RHS_CALLS] += cc.shape[0] - 1
                err = error_norm(u, y, k, atol, rtol, ynew)
                if not math.isfinite(err):
                    err = 1e10
                fac = max(1.0 / GROW_LIMIT, min(1.0 / SHRINK_LIMIT, err ** 0.25 / SAFETY))
                if err <= 1.0:
                    if counters[STEPS] > 0:
                        gus = (clock[H_ACCEPTED] / h) * (err * err / clock[ERR_ACCEPTED]) ** 0.25
                        gus = max(1.0 / GROW_LIMIT, min(1.0 / SHRINK_LIMIT, gus / SAFETY))
                        fac = max(fac, gus)
                    h_new = h / fac
                    if clock[REJECTED_LAST] > 0.0:
                        h_new = min(h_new, h)
                    clock[H_ACCEPTED] = h
                    clock[ERR_ACCEPTED] = max(1e-2, err)
                    clock[REJECTED_LAST] = 0.0
                    dense_output(u, ynew, k, hd, dense)
                    u[:] = ynew
                    clock[T_LAST] = t
                    clock[H_LAST] = h
                    if land:
                        t = t_switch
                        p += 1
                    else:
                        t = t + h
                    clock[T] = t
                    clock[H_NEXT] = h_new
                    counters[STEPS] += 1
                    break
                clock[H_NEXT] = h / fac
                clock[REJECTED_LAST] = 1.0
                counters[REJECTED] += 1
        phase_index[0] = p
        if abs(t - t_end) <= eps or clock[H_LAST] == 0.0:
            sample[:] = u
        else:
            dense_value(dense, (t_end - clock[T_LAST]) / clock[H_LAST], sample)
        return OK

    @njit(**JIT_COMPOSED)
    def integrate(u, clock, phase_index, counters, dense, targets, samples, starts, phases,
                  data, coefficients, context, drive_coefficients, mobility, bot_mobility,
                  membrane, atol, rtol, max_step, a, cc, hd, ws):
        """For each time of ``targets`` (increasing, s): step until the clock reaches it, then
        write the state there into the matching row of ``samples`` from the last step's
        continuous extension. Returns a status code."""
        for r in range(targets.size):
            status = advance_to(u, clock, phase_index, counters, dense, targets[r],
                                samples[r], starts, phases, data, coefficients, context,
                                drive_coefficients, mobility, bot_mobility, membrane, atol,
                                rtol, max_step, a, cc, hd, ws)
            if status != OK:
                return status
        return OK

    return integrate


_LOOPS: dict[tuple, tuple] = {}


def groups(model: Model) -> tuple[list, list]:
    """The model's terms split into those evaluated on the coarse grid (``smooth``) and the
    others, each as a list of (index, term)."""
    smooth = [(i, t) for i, t in enumerate(model.terms) if t.smooth]
    other = [(i, t) for i, t in enumerate(model.terms) if not t.smooth]
    return smooth, other


def compiled_loop(model: Model) -> tuple:
    """(rhs, jacobian, integrate) compiled for the model's terms and drive (cached)."""
    parts = []
    key: list[object] = [id(model.drive)]
    for group in groups(model):
        terms = [t for _, t in group]
        kernels = [t.partials_kernel() for t in terms]
        hessians = [t.hessian_kernel() for t in terms]
        order = max([t.derivative_order for t in terms], default=0)
        key.append((tuple(id(k) for k in kernels), tuple(id(h) for h in hessians), order))
        parts.append((kernels, terms, order))
    key_t = tuple(key)
    if key_t not in _LOOPS:
        built = [(compose_partials(kernels), compose_hessians(terms), bool(terms), order,
                  any(t.hessian_kernel() is None for t in terms))
                 for kernels, terms, order in parts]
        rhs, jacobian = _make_rhs(built[0], built[1], model.drive)
        _LOOPS[key_t] = (rhs, jacobian, _make_loop(rhs, jacobian))
    return _LOOPS[key_t]


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
    return u[:m] + 1j * u[m:2 * m], u[2 * m:2 * m + 3].copy()


class Rodas4Stepper(Stepper):
    def __init__(self, model: Model, atol: float, rtol: float, max_step: float,
                 first_step: float, smooth_nodes: int) -> None:
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
        return {"modes": np.asarray(modes, dtype=np.complex128).copy(),
                "pose": np.asarray(pose, dtype=np.float64).copy(), "time": np.zeros(1),
                "u": u, "clock": clock, "phase_index": np.zeros(1, dtype=np.int64),
                "counters": np.zeros(4, dtype=np.int64), "dense": np.zeros((4, u.size))}

    def advance(self, state, schedule: Schedule, t_end: float) -> None:
        self.sample(state, schedule, np.array([t_end], dtype=np.float64))

    def sample(self, state, schedule: Schedule, times: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        m = self.model
        times = np.ascontiguousarray(times, dtype=np.float64)
        samples = np.empty((times.size, state["u"].size))
        status = self.integrate(
            state["u"], state["clock"], state["phase_index"], state["counters"],
            state["dense"], times, samples, schedule.start, schedule.phase,
            schedule.data, self.coefficients, m.context, m.drive_coefficients,
            m.membrane_mobility, m.bot_mobility, m.has_membrane, self.atol, self.rtol,
            self.max_step, RODAS4.a, RODAS4.c, RODAS4.dense, self.ws)
        if status != OK:
            t = state["clock"][T]
            reason = "the step size underflowed" if status == STEP_UNDERFLOW else \
                "the iteration matrix is singular"
            raise SimulationError(f"rodas4 failed at t = {t:.9g} s: {reason}")
        size = 2 * m.cutoff + 1
        modes = samples[:, :size] + 1j * samples[:, size:2 * size]
        pose = samples[:, 2 * size:]
        state["modes"][:], state["pose"][:] = modes[-1], pose[-1]
        state["time"][0] = times[-1]
        return modes, pose

    def statistics(self, state) -> dict[str, int]:
        """Steps accepted and rejected, right-hand-side and Jacobian evaluations so far."""
        c = state["counters"]
        return {"steps": int(c[STEPS]), "rejected": int(c[REJECTED]),
                "rhs_calls": int(c[RHS_CALLS]), "jacobians": int(c[JACOBIANS])}


class Rodas4(Integrator):
    """Adaptive linearly implicit RODAS4 (order 4(3), L-stable) on the whole coupled system."""

    name = "rodas4"
    description = ("adaptive Rosenbrock RODAS4, order 4(3), full Jacobian, steps on the "
                   "protocol's switches, dense output")
    parameters = (
        ParameterSpec("atol", 1e-6, "cm", "absolute error tolerance of rodas4 per step "
                      "(cm for positions and modes, rad for the heading)", minimum=0.0),
        ParameterSpec("rtol", 1e-6, "1", "relative error tolerance of rodas4 per step",
                      minimum=0.0),
        ParameterSpec("max_step", 0.05, "s", "largest step of rodas4", minimum=0.0),
        ParameterSpec("first_step", 1e-4, "s", "first trial step of rodas4", minimum=0.0),
        ParameterSpec("smooth_nodes", 128, "1", "collocation points of rodas4's coarse grid for "
                      "smooth energy terms (bending, tension)", kind=int, minimum=8,
                      minimum_inclusive=True, power_of_two=True),
    )

    @classmethod
    def check(cls, params):
        lc, smooth = int(params.cutoff), int(params.smooth_nodes)
        if smooth < 4 * lc and smooth < int(params.nodes):
            raise ParameterError("smooth_nodes", smooth, f"must be >= 4 cutoff = {4 * lc} (or "
                                 f">= nodes) so that the smooth terms' forces are not aliased",
                                 "1")

    def build(self, model: Model) -> Rodas4Stepper:
        p = self.params
        return Rodas4Stepper(model, float(p.atol), float(p.rtol), float(p.max_step),
                             float(p.first_step), int(p.smooth_nodes))


@hookimpl
def softcell_integrators() -> list[type[Integrator]]:
    return [Rodas4]
