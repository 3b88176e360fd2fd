"""The engine: compose the chosen components into one compiled model and run a realization.

The energy terms' kernels are composed, by generated source, into one compiled function that
sums their partial derivatives; integrators compile that, the spectral force assembly and the
drive kernel into one stepper. Pluggy is only consulted here, at set-up.

State of one realization (SPEC sections 3-4): the membrane's Fourier modes g_k, |k| <= Lc
(complex128[2 Lc + 1], cm; ``modes[j]`` is g_{j - Lc}) and the bot's pose (x, y in cm, heading
in rad).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from softcell.core.components import DrivingProtocol, EnergyTerm, Integrator, Schedule
from softcell.core.config import BLOWUP_CHECK_POINTS, BLOWUP_LENGTH_FRACTION
from softcell.core.errors import SoftcellError
from softcell.core.params import Parameters
from softcell.core.registry import get_registry

PARTIALS_ARGS = ("x, y, xp, yp, xpp, ypp, pose, context, coefficients, "
                 "p0x, p0y, p1x, p1y, p2x, p2y, dpose")


class SimulationError(SoftcellError):
    """A run that blew up: a non-finite value or a membrane length far from l0."""


def compose_partials(kernels: Sequence[Callable[..., None]]) -> Callable[..., None]:
    """One compiled function that calls every term's partials kernel in turn.

    Its signature is that of a term kernel, except that ``coefficients`` is a tuple holding
    one coefficient array per term.
    """
    calls = [f"    k{i}({PARTIALS_ARGS.replace('coefficients', f'coefficients[{i}]')})"
             for i in range(len(kernels))] or ["    pass"]
    source = f"def total_partials({PARTIALS_ARGS}):\n" + "\n".join(calls) + "\n"
    namespace: dict[str, object] = {f"k{i}": k for i, k in enumerate(kernels)}
    exec(compile(source, "<softcell composed partials>", "exec"), namespace)
    return njit(nogil=True)(namespace["total_partials"])


def equilibrium_radius(params: Parameters) -> float:
    """Radius (cm) of the force-free circle: the root near l0 / 2 pi of
    4 pi alpha l0 R^3 - 2 alpha l0^2 R^2 - k = 0 (SPEC section 3; the paper's cubic has a typo).
    """
    l0, alpha, k = params.membrane_length, float(params.tension), float(params.bending_stiffness)
    roots = np.roots([4 * math.pi * alpha * l0, -2 * alpha * l0**2, 0.0, -k])
    real = roots[np.abs(roots.imag) < 1e-9 * abs(roots).max()].real
    return float(real[np.argmin(np.abs(real - l0 / (2 * math.pi)))])


@dataclass
class Model:
    """The compiled model of one parameter point: what an integrator composes into a stepper.

    Attributes
    ----------
    params : Parameters
    terms : list of EnergyTerm
        Empty for a free bot (no membrane).
    protocol : DrivingProtocol
    partials : compiled function
        Sum of the terms' partials kernels (see :func:`compose_partials`).
    coefficients : tuple of float64 arrays
        One per term.
    drive : compiled function
        The protocol's drive kernel; ``drive_coefficients`` its coefficients.
    context : float64[3]
        l0 (cm), bot semi-major and semi-minor axes (cm).
    membrane_mobility : float
        2 pi / (gamma_mem l0) (cm^2 N^-1 s^-1 per unit xi): dg_k/dt = membrane_mobility f_hat_k.
    bot_mobility : float64[3]
        1/gamma_T, 1/gamma_T (cm N^-1 s^-1) and 1/gamma_R (N^-1 cm^-1 s^-1).
    """

    params: Parameters
    terms: list[EnergyTerm]
    protocol: DrivingProtocol
    partials: Callable[..., None]
    coefficients: tuple[np.ndarray, ...]
    drive: Callable[..., None]
    drive_coefficients: np.ndarray
    context: np.ndarray
    membrane_mobility: float
    bot_mobility: np.ndarray
    nodes: int
    cutoff: int
    names: dict[str, object] = field(default_factory=dict)

    @property
    def has_membrane(self) -> bool:
        return bool(self.terms)

    @property
    def couples_bot(self) -> bool:
        return any(t.couples_bot for t in self.terms)


_PARTIALS_CACHE: dict[tuple[int, ...], Callable[..., None]] = {}


def build_model(params: Parameters, energy_terms: Sequence[str], protocol: str,
                membrane: bool = True) -> Model:
    """Instantiate the named components for ``params`` and compile their composition.

    Parameters
    ----------
    params : Parameters
        A validated parameter point (including the components' own parameters).
    energy_terms : sequence of str
        Names of registered energy terms.
    protocol : str
        Name of a registered driving protocol.
    membrane : bool
        False for a free bot: no membrane, no energy terms.
    """
    registry = get_registry()
    terms = [registry.get("energy_term", n)(params) for n in energy_terms] if membrane else []
    drive = registry.get("driving_protocol", protocol)(params)
    kernels = [t.partials_kernel() for t in terms]
    key = tuple(id(k) for k in kernels)
    if key not in _PARTIALS_CACHE:
        _PARTIALS_CACHE[key] = compose_partials(kernels)
    coefficients = tuple(np.ascontiguousarray(t.coefficients()) for t in terms)
    if not coefficients:
        coefficients = (np.zeros(1),)
    l0 = params.membrane_length
    return Model(
        params=params, terms=terms, protocol=drive, partials=_PARTIALS_CACHE[key],
        coefficients=coefficients, drive=drive.drive_kernel(),
        drive_coefficients=np.ascontiguousarray(drive.coefficients()),
        context=np.array([l0, float(params.bot_semi_major), float(params.bot_semi_minor)]),
        membrane_mobility=2 * math.pi / (float(params.membrane_friction) * l0),
        bot_mobility=np.array([1 / float(params.bot_friction), 1 / float(params.bot_friction),
                               1 / float(params.bot_rotational_friction)]),
        nodes=int(params.nodes), cutoff=int(params.cutoff),
        names={"energy_terms": list(energy_terms) if membrane else [],
               "driving_protocol": protocol},
    )


def circle_modes(radius: float, cutoff: int, center: complex = 0j) -> np.ndarray:
    """Fourier modes (complex128[2 cutoff + 1], cm) of a circle z = center + radius e^{i xi}."""
    modes = np.zeros(2 * cutoff + 1, dtype=np.complex128)
    modes[cutoff] = center
    modes[cutoff + 1] = radius
    return modes


def sample_times(params: Parameters) -> np.ndarray:
    """The sampling grid (s): every ``sample_every`` before ``sample_switch``, then every
    ``sample_every_late``, up to and including ``duration`` where it falls on the grid."""
    duration, early = float(params.duration), float(params.sample_every)
    late, switch = float(params.sample_every_late), float(params.sample_switch)
    first_end = min(switch, duration)
    n_early = int(math.floor(first_end / early * (1 + 1e-12))) + 1
    times = np.arange(n_early) * early
    if switch < duration:
        times = times[times < switch]
        n_late = int(math.floor((duration - switch) / late * (1 + 1e-12))) + 1
        times = np.concatenate([times, switch + np.arange(n_late) * late])
    return times


def phase_at(schedule: Schedule, times: np.ndarray) -> np.ndarray:
    """Phase code (int8) active at each time (s): the last phase started at or before it."""
    index = np.searchsorted(schedule.start, times, side="right") - 1
    return schedule.phase[np.clip(index, 0, None)]


def membrane_length(modes: np.ndarray, points: int = 256) -> float:
    """Length (cm) of the curve with these Fourier modes, by the trapezoidal rule (spectrally
    accurate for a trigonometric polynomial)."""
    zp = (1j * modes) @ _derivative_basis((modes.size - 1) // 2, points)
    return float(2 * np.pi * np.abs(zp).mean())


@functools.lru_cache(maxsize=8)
def _derivative_basis(lc: int, points: int) -> np.ndarray:
    """k e^{i k xi_n} for k = -lc..lc (rows) at ``points`` equally spaced xi_n (columns)."""
    k = np.arange(-lc, lc + 1)
    xi = 2 * np.pi * np.arange(points) / points
    return k[:, None] * np.exp(1j * np.outer(k, xi))


class Stepper:
    """What :meth:`Integrator.build` returns: advances one realization's state in time.

    The state is a dict of numpy arrays, so a checkpoint is a plain ``.npz``: ``modes``
    (complex128[2 Lc + 1], cm), ``pose`` (float64[3]: cm, cm, rad), ``time`` (float64[1], s)
    and whatever else the integrator keeps.
    """

    def start(self, modes: np.ndarray, pose: np.ndarray, schedule: Schedule
              ) -> dict[str, np.ndarray]:
        """The initial state for these modes, pose and phase schedule."""
        raise NotImplementedError

    def advance(self, state: dict[str, np.ndarray], schedule: Schedule, t_end: float) -> None:
        """Advance ``state`` in place to time ``t_end`` (s)."""
        raise NotImplementedError

    def sample(self, state: dict[str, np.ndarray], schedule: Schedule, times: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """Advance ``state`` through the increasing ``times`` (s) and return the modes
        (complex128[K, 2 Lc + 1], cm) and poses (float64[K, 3]) there.

        The default calls :meth:`advance` once per time; an integrator whose calls cost more
        than its steps (one compiled call per sample) overrides it. Either way the result must
        not depend on how the times are split between calls.
        """
        modes = np.empty((len(times), state["modes"].size), dtype=np.complex128)
        pose = np.empty((len(times), 3))
        for i, t in enumerate(times):
            self.advance(state, schedule, float(t))
            modes[i], pose[i] = state["modes"], state["pose"]
        return modes, pose


@dataclass
class Record:
    """What a realization produced, before it becomes a Dataset."""

    times: np.ndarray
    modes: np.ndarray  # complex128[T, 2 Lc + 1]
    pose: np.ndarray  # float64[T, 3]
    phase: np.ndarray  # int8[T]
    state: dict[str, np.ndarray] | None = None  # the integrator's state after the last sample


def check_state(state: dict[str, np.ndarray], model: Model, realization: object,
                times: np.ndarray | None = None, modes: np.ndarray | None = None,
                pose: np.ndarray | None = None) -> None:
    """Raise :class:`SimulationError` on a non-finite value or a membrane length off by more
    than BLOWUP_LENGTH_FRACTION of l0, naming the time, the realization and the quantity.

    ``times``, ``modes`` and ``pose`` (float64[K], complex128[K, 2 Lc + 1], float64[K, 3]), if
    given, are the samples recorded since the last check, which are checked instead of the
    state.
    """
    if times is None:
        times, modes, pose = state["time"], state["modes"][None], state["pose"][None]
    for name, values in (("modes", modes), ("pose", pose)):
        bad = ~np.all(np.isfinite(values), axis=-1)
        if bad.any():
            t = float(times[np.argmax(bad)])
            raise SimulationError(f"realization {realization}: non-finite {name} at t = {t:g} s "
                                  "(the run blew up; reduce dt or tighten the tolerances)")
    if model.has_membrane:
        l0 = model.params.membrane_length
        lengths = 2 * np.pi * np.abs((1j * modes) @ _derivative_basis(
            model.cutoff, BLOWUP_CHECK_POINTS)).mean(axis=-1)
        bad = np.abs(lengths / l0 - 1) > BLOWUP_LENGTH_FRACTION
        if bad.any():
            i = int(np.argmax(bad))
            raise SimulationError(
                f"realization {realization}: membrane length {lengths[i]:.6g} cm at "
                f"t = {times[i]:g} s is off l0 = {l0:.6g} cm by more than "
                f"{BLOWUP_LENGTH_FRACTION:.0%}")


def initial_state(model: Model, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray,
                                                                     Schedule]:
    """Draw the heading and the schedule (in that order) and set up the membrane at rest:
    the equilibrium circle centred on the bot (SPEC section 5)."""
    heading = model.protocol.initial_heading(rng)
    schedule = model.protocol.schedule(rng, float(model.params.duration))
    radius = equilibrium_radius(model.params) if model.has_membrane else 0.0
    return circle_modes(radius, model.cutoff), np.array([0.0, 0.0, heading]), schedule


def build_integrator(name: str, params: Parameters) -> Integrator:
    """Instantiate the named integrator (its ``check`` runs on ``params``)."""
    return get_registry().get("integrator", name)(params)


def _curve(modes: np.ndarray, n: int) -> np.ndarray:
    """z, z', z'' (complex128[3, n], cm) at n collocation points, with numpy FFTs."""
    lc = (modes.size - 1) // 2
    k = np.arange(-lc, lc + 1)
    spectrum = np.zeros((3, n), dtype=np.complex128)
    for order in range(3):
        spectrum[order, k % n] = (1j * k) ** order * modes
    return np.fft.ifft(spectrum, axis=1) * n


def force_modes(model: Model, modes: np.ndarray, pose: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Force modes and bot reaction for one state, with numpy FFTs (set-up, checks, tests).

    Returns
    -------
    fhat : complex128[2 Lc + 1]
        f_hat_k (N) for |k| <= Lc, with f_hat_k = N^-1 sum_n f_n e^{-i k xi_n}.
    dpose : float64[3]
        sum_n de_n/d(x_bot, y_bot, theta_bot); the reaction on the bot is -(2 pi / N) dpose.
    """
    n, lc = model.nodes, model.cutoff
    k = np.arange(-lc, lc + 1)
    z, zp, zpp = _curve(modes, n)
    parts = np.zeros((6, n))
    dpose = np.zeros(3)
    model.partials(z.real.copy(), z.imag.copy(), zp.real.copy(), zp.imag.copy(),
                   zpp.real.copy(), zpp.imag.copy(), np.asarray(pose, dtype=np.float64),
                   model.context, model.coefficients, *parts, dpose)
    q = np.fft.fft(parts[0::2] + 1j * parts[1::2], axis=1)[:, k % n] / n
    return -q[0] + 1j * k * q[1] + (k * k) * q[2], dpose


def total_energy(model: Model, modes: np.ndarray, pose: np.ndarray) -> float:
    """E = (2 pi / N) sum_n e_n over all terms (N cm), from the terms' ``density``."""
    n = model.nodes
    z, zp, zpp = _curve(modes, n)
    e = sum(t.density(z.real, z.imag, zp.real, zp.imag, zpp.real, zpp.imag, pose)
            for t in model.terms)
    return float(2 * np.pi / n * np.sum(e))


def explicit_decay_rate(model: Model) -> float:
    """Largest decay rate lambda_max (1/s) of the linearized explicit membrane update at the
    equilibrium circle (SPEC section 2): the explicit Euler step is stable for dt lambda < 2.
    """
    return float(np.max(-np.linalg.eigvals(membrane_jacobian(model)).real))


def membrane_jacobian(model: Model) -> np.ndarray:
    """Jacobian (1/s) of d(Re g, Im g)/dt at the equilibrium circle, bot at its center.

    Built by central differences (2 (2 Lc + 1) force evaluations); rows and columns are
    ordered Re g_{-Lc..Lc}, then Im g_{-Lc..Lc}.
    """
    lc = model.cutoff
    radius = equilibrium_radius(model.params)
    base = circle_modes(radius, lc)
    pose = np.array([0.0, 0.0, 0.0])  # the bot at the center feels and exerts nothing
    size = 2 * lc + 1
    jac = np.zeros((2 * size, 2 * size))
    h = 1e-6 * radius
    for j in range(2 * size):
        delta = np.zeros(size, dtype=np.complex128)
        delta[j % size] = h if j < size else 1j * h
        plus = force_modes(model, base + delta, pose)[0]
        minus = force_modes(model, base - delta, pose)[0]
        column = model.membrane_mobility * (plus - minus) / (2 * h)
        jac[:size, j], jac[size:, j] = column.real, column.imag
    return jac
