"""rodas4 against the stiff solvers a user would pick, on the same realization.

For R = 4, 8 and 12 cm, realization 0 of root seed 0 over 5 s (the realization of
``tests/regression/integrator_reference.npz``), scipy's ``solve_ivp`` with LSODA, Radau and
BDF integrates softcell's own compiled right-hand side and analytic Jacobian (the functions
rodas4 steps), phase by phase (each phase is autonomous; every solver restarts at the
protocol's switches, as rodas4 lands on them), sampled at the reference's times. Each peer runs
down a ladder of tolerances (rtol = atol) and is timed at the loosest one whose path error
against the stored explicit reference is <= ``TARGET_ERROR`` cm; rodas4 likewise (and at its
defaults). Runs are interleaved (one of each method per round), ``ROUNDS`` rounds, medians.

Each peer is given the better of two largest steps, rodas4's default (0.2 s) and 0.05 s, the
tolerance found for each: without a largest step, LSODA, Radau and BDF can step over a
contact altogether (the bot passes through the membrane; the path error then rules that
tolerance out).

Calls from scipy reach the compiled functions through a jitclass that holds the problem and
the workspace, so a call crosses from Python into compiled code with three arguments (the
overhead, measured on a state without contact, is in the table).

SUNDIALS' CVODE (BDF, through scikit-sundae: ``pip install -e '.[bench]'``) runs the same way,
phase by phase with the same largest steps, with the analytic Jacobian and each of its direct
linear solvers ('dense', LAPACK's 'lapackdense'), and with GMRES on difference-quotient
Jacobian-vector products (no preconditioner). A banded solver gains nothing here: in contact the
Jacobian is full (the contact couples every membrane mode to every other and to the bot), so
its bandwidths are those of a dense matrix.
"""

from __future__ import annotations

import time
from pathlib import Path

import numba
import numpy as np
from numba import njit
from numba.experimental import jitclass

RADII = (4.0, 8.0, 12.0)
TARGET_ERROR = 1e-4  # cm
LADDER = (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7)
MAX_STEPS = (0.2, 0.05)  # s, the peers' largest steps: rodas4's default, and a tighter one
ROUNDS = 5
PEERS = ("LSODA", "Radau", "BDF")
CVODE_SOLVERS = ("dense", "lapackdense", "gmres")  # CVODE's linear solvers, as "CVODE-<name>"
REFERENCE = (
    Path(__file__).resolve().parents[1] / "tests" / "regression" / "integrator_reference.npz"
)


class Case:
    """One radius: the model, rodas4's stepper, the schedule, the start state and the
    compiled right-hand side and Jacobian as Python callables."""

    def __init__(self, radius: float, reference) -> None:
        from softcell.components.registry import default_registry
        from softcell.engine import Record, build_integrator, build_model, initial_state
        from softcell.engine.cell import realization_rng
        from softcell.testing.compare import PROTOCOL, TERMS, parameters

        self.radius = radius
        key = f"r{radius:g}"
        self.times = reference[f"{key}_times"]
        self.duration = float(reference["duration"])
        self.explicit = Record(
            self.times, reference[f"{key}_modes"], reference[f"{key}_pose"], None
        )
        self.params = parameters(radius, self.duration)
        self.model = build_model(self.params, TERMS, PROTOCOL, registry=default_registry())
        self.stepper = build_integrator("rodas4", self.params, default_registry()).build(self.model)
        modes, pose, self.schedule = initial_state(
            self.model, realization_rng(int(reference["seed"]), 0, 0)
        )
        from softcell.integrators.rodas4 import pack

        self.u0 = pack(modes, pose)
        self.m = 2 * self.model.cutoff + 1
        self.holder, self.fun, self.jac = _callables(self.stepper)

    def phases(self):
        """(t_start, t_end, phase code, datum) of each phase within the run."""
        s = self.schedule
        for i, start in enumerate(s.start):
            if start >= self.duration:
                break
            end = s.start[i + 1] if i + 1 < s.start.size else np.inf
            yield float(start), float(min(end, self.duration)), int(s.phase[i]), float(s.data[i])

    def error(self, samples: np.ndarray) -> float:
        """Largest bot or cell path difference (cm) from the explicit reference."""
        from softcell.engine import Record
        from softcell.testing.compare import path_difference

        modes = samples[:, : self.m] + 1j * samples[:, self.m : 2 * self.m]
        record = Record(self.times, modes, samples[:, 2 * self.m :], None)
        paths = path_difference(record, self.explicit, int(self.model.cutoff))
        return max(paths["bot"], paths["cell"])


def _callables(stepper):
    """A jitclass holding rodas4's problem and workspace, and f(t, y), J(t, y) for scipy."""
    spec = [
        ("problem", numba.typeof(stepper.problem)),
        ("ws", numba.typeof(stepper.ws)),
        ("phase", numba.int64),
        ("datum", numba.float64),
    ]
    holder_class = jitclass(spec)(_Holder)
    holder = holder_class(stepper.problem, stepper.ws, 1, 0.0)
    rhs, jacobian = stepper.rhs, stepper.jacobian

    @njit
    def f(h, u):
        out = np.empty_like(u)
        rhs(u, h.phase, h.datum, out, h.problem, h.ws)
        return out

    @njit
    def jac(h, u):
        rhs(u, h.phase, h.datum, h.ws.f0, h.problem, h.ws)  # the grids' curves at u
        jacobian(u, h.phase, h.datum, h.problem, h.ws)
        return h.ws.jac.copy()

    return holder, (lambda t, y: f(holder, y)), (lambda t, y: jac(holder, y))


class _Holder:
    def __init__(self, problem, ws, phase, datum):
        self.problem = problem
        self.ws = ws
        self.phase = phase
        self.datum = datum


def run_peer(case: Case, method: str, tol: float, max_step: float) -> tuple[float, float, int]:
    """(wall s, path error cm, right-hand-side calls) of one peer at rtol = atol = tol with
    the largest step ``max_step`` (s)."""
    from scipy.integrate import solve_ivp

    if method.startswith("CVODE-"):
        return run_cvode(case, method.removeprefix("CVODE-"), tol, max_step)

    samples = np.empty((case.times.size, case.u0.size))
    samples[0] = case.u0
    y = case.u0.copy()
    calls = 0
    begin = time.perf_counter()
    for start, end, phase, datum in case.phases():
        case.holder.phase, case.holder.datum = phase, datum
        inside = (case.times > start) & (case.times < end)
        at_end = case.times == end
        sol = solve_ivp(
            case.fun,
            (start, end),
            y,
            method=method,
            t_eval=np.concatenate([case.times[inside], [end]]),
            rtol=tol,
            atol=tol,
            max_step=max_step,
            jac=case.jac,
        )
        if sol.status != 0 or not np.all(np.isfinite(sol.y)):
            return np.nan, np.inf, calls  # failed, or blew up (the bot through the membrane)
        samples[inside] = sol.y[:, :-1].T
        y = sol.y[:, -1].copy()
        samples[at_end] = y
        calls += sol.nfev
    wall = time.perf_counter() - begin
    return wall, case.error(samples), calls


def run_cvode(case: Case, linsolver: str, tol: float, max_step: float) -> tuple[float, float, int]:
    """(wall s, path error cm, right-hand-side calls) of CVODE (BDF) with the linear solver
    ``linsolver`` at rtol = atol = tol and the largest step ``max_step`` (s), phase by phase."""
    from sksundae.cvode import CVODE

    # y is a read-only view of CVODE's vector; passed as is, the compiled functions are
    # compiled again for read-only arrays and memory grows by ~50 MB a run: a copy
    def rhsfn(t, y, yp):
        yp[:] = case.fun(t, np.array(y))

    def jacfn(t, y, yp, jj):
        jj[:, :] = case.jac(t, np.array(y))

    options = {"rtol": tol, "atol": tol, "max_step": max_step, "max_num_steps": 100_000}
    if linsolver == "gmres":
        options.update(linsolver="gmres", krylov_dim=case.u0.size)
    else:
        options.update(linsolver=linsolver, jacfn=jacfn)
    samples = np.empty((case.times.size, case.u0.size))
    samples[0] = case.u0
    y = case.u0.copy()
    calls = 0
    begin = time.perf_counter()
    # one solver, started afresh at each phase (a phase is autonomous)
    solver = CVODE(rhsfn, **options)
    for start, end, phase, datum in case.phases():
        case.holder.phase, case.holder.datum = phase, datum
        solver.init_step(start, y)
        rows = np.flatnonzero((case.times > start) & (case.times <= end))
        for row in rows:
            sol = solver.step(case.times[row], tstop=end)
            if not sol.success or not np.all(np.isfinite(sol.y)):
                return np.nan, np.inf, calls
            samples[row] = sol.y
        if rows.size == 0 or case.times[rows[-1]] != end:  # the phase ends between samples
            sol = solver.step(end, tstop=end)
            if not sol.success or not np.all(np.isfinite(sol.y)):
                return np.nan, np.inf, calls
        y = np.array(sol.y, dtype=np.float64).reshape(-1)
        calls += sol.nfev
    wall = time.perf_counter() - begin
    return wall, case.error(samples), calls


def run_rodas4(case: Case, tol: float | None) -> tuple[float, float, int]:
    """(wall s, path error cm, right-hand-side calls) of rodas4 at rtol = atol = tol (its
    defaults when None)."""
    from softcell.components.registry import default_registry
    from softcell.engine import build_integrator

    extra = {} if tol is None else {"atol": tol, "rtol": tol}
    params = case.params.replace(**extra)
    stepper = build_integrator("rodas4", params, default_registry()).build(case.model)
    modes = case.u0[: case.m] + 1j * case.u0[case.m : 2 * case.m]
    state = stepper.start(modes, case.u0[2 * case.m :], case.schedule)
    begin = time.perf_counter()
    modes_s, pose_s = stepper.sample(state, case.schedule, case.times[1:])
    wall = time.perf_counter() - begin
    samples = np.empty((case.times.size, case.u0.size))
    samples[0] = case.u0
    samples[1:, : case.m] = modes_s.real
    samples[1:, case.m : 2 * case.m] = modes_s.imag
    samples[1:, 2 * case.m :] = pose_s
    return wall, case.error(samples), stepper.statistics(state)["rhs_calls"]


def loosest(run, case: Case, method: str, max_step: float = 0.0) -> float | None:
    """The loosest tolerance of LADDER whose path error is <= TARGET_ERROR (None if none)."""
    for tol in LADDER:
        _, error, _ = run(case, method, tol, max_step) if method != "rodas4" else run(case, tol)
        if error <= TARGET_ERROR:
            return tol
    return None


def call_overhead(case: Case) -> float:
    """Median wall time (us) of one right-hand-side call from Python at the start state (no
    contact), minus the same call from compiled code."""
    stepper = case.stepper
    rhs, problem, ws = stepper.rhs, stepper.problem, stepper.ws
    u = case.u0.copy()

    @njit
    def inside(u, out, problem, ws, reps):
        for _ in range(reps):
            rhs(u, 1, 0.0, out, problem, ws)

    out = np.empty_like(u)
    inside(u, out, problem, ws, 1)
    case.fun(0.0, u)
    reps, compiled, python = 2000, [], []
    for _ in range(5):
        begin = time.perf_counter()
        inside(u, out, problem, ws, reps)
        compiled.append((time.perf_counter() - begin) / reps)
        begin = time.perf_counter()
        for _ in range(reps):
            case.fun(0.0, u)
        python.append((time.perf_counter() - begin) / reps)
    return (np.median(python) - np.median(compiled)) * 1e6


def _peers() -> tuple[str, ...]:
    """scipy's methods, and CVODE's linear solvers when scikit-sundae is installed."""
    try:
        import sksundae  # noqa: F401
    except ImportError:
        return PEERS
    return PEERS + tuple(f"CVODE-{name}" for name in CVODE_SOLVERS)


def rows() -> list[dict[str, object]]:
    reference = np.load(REFERENCE)
    out: list[dict[str, object]] = []
    for radius in RADII:
        case = Case(radius, reference)
        run_rodas4(case, None)  # compile
        case.fun(0.0, case.u0)
        case.jac(0.0, case.u0)
        # name -> (method, tolerance or None, largest step): rodas4 at its loosest
        # tolerance, every peer at each of MAX_STEPS with its loosest tolerance there
        configs = {"rodas4 default": ("rodas4", None, 0.0)}
        configs["rodas4"] = ("rodas4", loosest(run_rodas4, case, "rodas4"), 0.0)
        for method in _peers():
            for max_step in MAX_STEPS:
                configs[f"{method}@{max_step:g}"] = (
                    method,
                    loosest(run_peer, case, method, max_step),
                    max_step,
                )
        timings = {
            name: []
            for name, (_, tol, _) in configs.items()
            if tol is not None or name == "rodas4 default"
        }
        results = {}
        for _ in range(ROUNDS):
            for name in timings:
                method, tol, max_step = configs[name]
                if method == "rodas4":
                    result = run_rodas4(case, tol)
                else:
                    result = run_peer(case, method, tol, max_step)
                timings[name].append(result[0])
                results[name] = result
        base = np.median(timings["rodas4 default"])
        shown = ["rodas4 default", "rodas4"]
        for method in _peers():  # each peer at its faster largest step
            tried = [f"{method}@{m:g}" for m in MAX_STEPS if f"{method}@{m:g}" in timings]
            shown.append(min(tried, key=lambda n: np.median(timings[n])) if tried else method)
        best_peer = min((np.median(timings[n]) for n in shown[2:] if n in timings), default=np.nan)
        for name in shown:
            if name not in timings:
                out.append(
                    {
                        "benchmark": f"{name}, R={radius:g}",
                        "value": np.nan,
                        "unit": "x",
                        "target": None,
                        "note": f"no tolerance of {LADDER[0]:g}..{LADDER[-1]:g} reaches "
                        f"{TARGET_ERROR:g} cm at a largest step of "
                        f"{' or '.join(f'{m:g}' for m in MAX_STEPS)} s",
                    }
                )
                continue
            walls = timings[name]
            method, tol, max_step = configs[name]
            wall, error, calls = results[name]
            setting = "defaults" if tol is None else f"tol {tol:g}"
            if method != "rodas4":
                setting += f", max_step {max_step:g} s"
            out.append(
                {
                    "benchmark": f"{method if method != 'rodas4' else name} / rodas4, R={radius:g}",
                    "value": float(np.median(walls) / base),
                    "unit": "x time",
                    "target": None,
                    "note": f"{case.duration / np.median(walls):.1f} sim s/s, {setting}, "
                    f"error {error:.1e} cm, {calls} RHS",
                }
            )
        out.append(
            {
                "benchmark": f"best peer / rodas4, R={radius:g}",
                "value": float(best_peer / base),
                "unit": "x time",
                "target": 1.3,
                "higher_is_better": True,
                "note": "rodas4 at its defaults against the fastest peer at <= 1e-4 cm",
            }
        )
        out.append(
            {
                "benchmark": f"call overhead from Python, R={radius:g}",
                "value": call_overhead(case),
                "unit": "us",
                "target": None,
                "note": "a peer's f(t, y) call, beyond the compiled work",
            }
        )
    if len(_peers()) == len(PEERS):
        out.append(
            {
                "benchmark": "CVODE (scikit-sundae)",
                "value": np.nan,
                "unit": "",
                "target": None,
                "note": "not installed (pip install -e '.[bench]'): not timed",
            }
        )
    return out
