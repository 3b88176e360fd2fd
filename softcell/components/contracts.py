"""The component contracts: one base class per kind of plugin component.

Like xarray's ``BackendEntrypoint``, each contract has class-level ``name`` and
``description``, an explicit parameter declaration, and explicit methods; there is no
``**kwargs`` catch-all. A component class is registered through a hook of
:mod:`softcell.components.hookspecs` and instantiated with a validated
:class:`~softcell.model.parameters.Parameters`.
"""

from __future__ import annotations

import re
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import IntEnum
from typing import ClassVar

import numpy as np

from softcell.errors import ContractError
from softcell.model.parameters import Parameters, ParameterSpec, unit_problem

_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
#: numba's type of the arrays the engine hands a kernel: C-contiguous float64 vectors.
VECTOR = "float64[::1]"


def kind_name(kind: str) -> str:
    """A component kind as prose: ``"stop/go detector"``, ``"energy term"``."""
    return "stop/go detector" if kind == "stopgo_detector" else kind.replace("_", " ")


class Component(ABC):
    """Base of every component.

    A component class sets four class attributes: ``kind`` (set by the contract class:
    ``energy_term``, ``driving_protocol``, ``friction_law``, ``integrator``,
    ``stopgo_detector``, ``pair_term`` or ``bot_interaction``); ``name`` (unique within its
    kind; lower case, digits and underscores, as ``run_and_tumble``); ``description`` (one
    line, shown by ``softcell plugins``); and ``parameters``, a tuple of ``ParameterSpec``:
    the parameters the component reads, each with default, unit and range. A component may
    use parameters of the model catalogue (:data:`softcell.plugin.MODEL_PARAMETERS`) by
    listing their specs, or declare new ones.

    Parameters
    ----------
    params : Parameters
        The run's parameter set (values in their declared units); checked by :meth:`check`
        and kept as ``self.params``.
    """

    kind: ClassVar[str]
    name: ClassVar[str]
    description: ClassVar[str]
    parameters: ClassVar[tuple[ParameterSpec, ...]] = ()
    #: The compiled kernels of the contract: the method returning each, and the numba
    #: signature the engine calls it with (checked by ``check_kernels`` when a model is
    #: built, before any time step).
    kernels: ClassVar[dict[str, str]] = {}

    def __init__(self, params: Parameters) -> None:
        self.check(params)
        self.params = params

    @classmethod
    def check(cls, params: Parameters) -> None:
        """Raise :class:`~softcell.errors.ParameterError` for a parameter set this component
        cannot run with (beyond the per-parameter ranges). The default accepts everything.

        Parameters
        ----------
        params : Parameters
            The run's parameter set, values in their declared units.
        """
        return None

    def coefficients(self) -> np.ndarray:
        """The component's parameter values, each in its declared unit, as a float64 array
        in the order of ``parameters`` (the layout its compiled kernel receives). String
        parameters are not included."""
        return np.array(
            [float(self.params[s.name]) for s in self.parameters if s.kind is not str],
            dtype=np.float64,
        )

    @classmethod
    def contract_problems(cls) -> list[str]:
        """What is wrong with this class as a component, one phrase each (empty when it is
        well formed): its name, description, abstract methods, and each parameter's unit,
        which must parse as UDUNITS-2."""
        problems = []
        name = getattr(cls, "name", None)
        if not isinstance(name, str) or not _NAME.match(name):
            problems.append(f"name {name!r} is not a lower-case identifier")
        description = getattr(cls, "description", None)
        if not isinstance(description, str) or not description.strip() or "\n" in description:
            problems.append("description must be one non-empty line")
        if not all(isinstance(s, ParameterSpec) for s in cls.parameters):
            problems.append("parameters must be a tuple of ParameterSpec")
        else:
            for spec in cls.parameters:
                why = unit_problem(spec.unit)
                if why:
                    problems.append(f"parameter {spec.name!r}: {why}")
        if getattr(cls, "__abstractmethods__", None):
            missing = ", ".join(sorted(cls.__abstractmethods__))
            problems.append(f"abstract methods not implemented: {missing}")
        return problems


#: Energy-term attributes renamed in softcell 0.3 (old: new); the old names still work, with a
#: DeprecationWarning, until 0.4.
RENAMED = {"couples_bot": "reads_pose", "acts_on_bot": "has_bot_energy"}


class EnergyTerm(Component):
    """A membrane energy density and its pointwise partial derivatives (SI:EQ:Eel, Est, Eint).

    The energy is E = integral_0^{2 pi} e(gamma, gamma', gamma''; bot pose) d xi (N cm),
    evaluated as E = (2 pi / N) sum_n e_n at the collocation points xi_n = 2 pi n / N.
    The engine sums the partial derivatives of all terms and assembles the force density
    f = -P0 + D(P1) - D^2(P2) spectrally (docs/model.md §3).
    """

    kind = "energy_term"
    kernels = {
        "partials_kernel": f"void({', '.join([VECTOR] * 16)})",
        "hessian_kernel": f"void({', '.join([VECTOR] * 9)}, float64[:, :, ::1], "
        "float64[:, :, ::1], float64[:, ::1])",
        "bot_kernel": f"void({', '.join([VECTOR] * 4)})",
        "bot_hessian_kernel": f"void({', '.join([VECTOR] * 3)}, float64[:, ::1])",
    }
    #: True if the density depends on the bot's pose (then the kernel fills ``dpose``).
    reads_pose: ClassVar[bool] = False
    #: True if the density is a smooth function of gamma, gamma', gamma'' with no length
    #: scale of its own (bending, tension): its force modes ``|k| <= Lc`` are then computed to
    #: rounding on a coarser grid, and integrators other than the explicit reference may do
    #: so (``rodas4``'s ``smooth_nodes``). False (the default) keeps the N collocation points,
    #: as a term with its own short length scale (the contact, lambda = 0.01 cm) needs.
    smooth: ClassVar[bool] = False
    #: Highest derivative of gamma the density reads (0, 1 or 2). Integrators may skip
    #: evaluating higher ones for this term (they are then passed as zeros).
    derivative_order: ClassVar[int] = 2
    #: True if the term also has an energy of the bot alone (:meth:`bot_kernel`, which must
    #: then return a kernel): such terms act on a free bot too.
    has_bot_energy: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        for old, new in RENAMED.items():
            if old in cls.__dict__:
                warnings.warn(
                    f"{cls.__qualname__}.{old} was renamed {new} in softcell 0.3; set {new} "
                    "(the old name is read until 0.4)",
                    DeprecationWarning,
                    stacklevel=2,
                )
                if new not in cls.__dict__:
                    setattr(cls, new, cls.__dict__[old])

    @abstractmethod
    def partials_kernel(self) -> Callable[..., None]:
        """Return the compiled (``numba.njit``) kernel of this term.

        Kernel signature::

            kernel(x, y, xp, yp, xpp, ypp, pose, context, coefficients,
                   p0x, p0y, p1x, p1y, p2x, p2y, dpose) -> None

        ``x, y`` (cm), ``xp, yp`` (cm), ``xpp, ypp`` (cm): the curve and its first and second
        derivatives with respect to xi at the N points, float64[N]. ``pose``: float64[3], the
        bot's x, y (cm) and heading (rad). ``context``: float64[3], l0 (cm), the bot's semi-major
        and semi-minor axes (cm). ``coefficients``: float64[:], from :meth:`Component.coefficients`.
        The kernel *adds* de/dx, de/dy (N) into ``p0x, p0y``, de/dx', de/dy' (N) into
        ``p1x, p1y``, de/dx'', de/dy'' (N) into ``p2x, p2y``, and, if ``reads_pose``,
        the sum over n of de_n/d(x_bot, y_bot, theta_bot) (N, N, N cm) into ``dpose[0:3]``.
        It must not allocate on the heap and must leave the other entries alone.
        """

    def hessian_kernel(self) -> Callable[..., None] | None:
        """Return the compiled kernel of the term's second derivatives, or None.

        Linearly implicit integrators (``rodas4``) need the Jacobian of the whole right-hand
        side. Kernel signature::

            kernel(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp) -> None

        Arrays as in :meth:`partials_kernel`. With w = (x, y, x', y', x'', y''), the kernel
        *adds* d^2 e_n / dw_a dw_b into ``hww[n, a, b]`` (float64[N, 6, 6], N/cm),
        d^2 e_n / dw_a d pose_c into ``hwp[n, a, c]`` (float64[N, 6, 3]; N/cm, N/cm, and N
        for the heading) and sum_n d^2 e_n / d pose_c d pose_d into ``hpp[c, d]``
        (float64[3, 3]; N/cm, N, N cm). It must not allocate and must leave other entries
        alone.

        The default, None, selects the documented fallback: central differences of
        :meth:`partials_kernel` (a term's partials at point n depend on w_n and the pose
        only, so 2 x 9 kernel calls give every point's Hessian). It is accurate to ~1e-9
        relative for smooth terms; an analytic kernel is faster, which matters when the
        term is evaluated at many points.
        """
        return None

    def bot_kernel(self) -> Callable[..., None] | None:
        """Return the compiled kernel of the term's energy of the bot alone, or None.

        Some terms act on the bot directly, not through the membrane (the arena's walls).
        Their energy U(pose) (N cm) enters the bot's equations of motion as -dU/dpose, with or
        without a membrane: a free bot (``--free-bot``) keeps exactly the terms that have this
        kernel. Kernel signature::

            kernel(pose, context, coefficients, dpose) -> None

        Arrays as in :meth:`partials_kernel`; the kernel *adds* dU/d(x_bot, y_bot, theta_bot)
        (N, N, N cm) into ``dpose``. It must not allocate. The default, None: the term acts
        on the membrane only.
        """
        return None

    def bot_hessian_kernel(self) -> Callable[..., None] | None:
        """Return the compiled kernel of d^2 U / d pose^2 for :meth:`bot_kernel`, or None.

        Kernel signature::

            kernel(pose, context, coefficients, hpp) -> None

        The kernel *adds* d^2 U / d pose_c d pose_d into ``hpp[c, d]`` (float64[3, 3];
        N/cm, N, N cm). The default, None, selects central differences of :meth:`bot_kernel`
        (steps 1e-7 l0 / 2 pi in x, y and 1e-7 rad in the heading).
        """
        return None

    @abstractmethod
    def density(
        self,
        x: np.ndarray,
        y: np.ndarray,
        xp: np.ndarray,
        yp: np.ndarray,
        xpp: np.ndarray,
        ypp: np.ndarray,
        pose: np.ndarray,
    ) -> np.ndarray:
        """The energy density e_n (N cm per unit xi) at the N points, for checks and diagnostics.

        Parameters
        ----------
        x, y : ndarray
            float64[N]: the membrane points (cm), as in :meth:`partials_kernel`.
        xp, yp, xpp, ypp : ndarray
            float64[N]: their first (cm) and second (cm) derivatives along xi.
        pose : ndarray
            float64[3]: the bot's x, y (cm) and heading (rad).

        Returns
        -------
        ndarray
            float64[N]: e_n (N cm per unit xi).
        """


@dataclass(frozen=True)
class Schedule:
    """A driving protocol's phase schedule for one realization.

    Attributes
    ----------
    start : float64[M]
        Start time of each phase (s); ``start[0] == 0`` and strictly increasing.
    phase : int8[M]
        Phase code of each phase: 0 tumble, 1 run (the ``bot_phase`` flag values).
    data : float64[M]
        One number per phase that the drive kernel receives (e.g. the turn sign +-1).
    """

    start: np.ndarray
    phase: np.ndarray
    data: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.start)
        if n == 0 or len(self.phase) != n or len(self.data) != n:
            raise ValueError("a schedule needs equally long, non-empty start, phase and data")
        if self.start[0] != 0.0 or np.any(np.diff(self.start) <= 0):
            raise ValueError("schedule start times must begin at 0 s and increase strictly")


class Sense(IntEnum):
    """What a protocol's event kernel senses: the indices of its ``sense`` vector
    (float64[9]).

    ``X``, ``Y``, ``HEADING``: the bot's pose (cm, cm, rad). ``FORCE_X``, ``FORCE_Y``,
    ``TORQUE``: the force (N) and the torque (N cm, about the bot's centre) of every energy
    term on the bot (its membrane's contact, walls and posts; the drive and the friction
    excluded). ``DISTANCE``: from the bot's centre to the nearest point of its membrane (cm;
    inf for a free bot), over the curve sampled at 8 (2 Lc + 1) points. ``TIME`` and
    ``PHASE_TIME``: the time and the time since the current phase began (s).
    """

    X = 0
    Y = 1
    HEADING = 2
    FORCE_X = 3
    FORCE_Y = 4
    TORQUE = 5
    DISTANCE = 6
    TIME = 7
    PHASE_TIME = 8


#: The length of the ``sense`` vector.
SENSE_SIZE = len(Sense)


class DrivingProtocol(Component):
    """The bot's internal drive: a phase schedule and a force and torque in each phase
    (docs/model.md §5), and optionally a state event that ends a phase early
    (:meth:`event_kernel`)."""

    kind = "driving_protocol"
    kernels = {
        "drive_kernel": f"void(int8, float64, {', '.join([VECTOR] * 4)})",
        "event_kernel": f"float64(int8, float64, {VECTOR}, {VECTOR})",
    }

    @abstractmethod
    def schedule(self, rng: np.random.Generator, duration: float) -> Schedule:
        """Draw the whole phase schedule covering [0, ``duration``] from ``rng``.

        Parameters
        ----------
        rng : Generator
            The realization's random stream (a numpy Generator).
        duration : float
            Length (s) the schedule must cover.
        """

    @abstractmethod
    def initial_heading(self, rng: np.random.Generator) -> float:
        """Draw the bot's initial heading (rad).

        Parameters
        ----------
        rng : Generator
            The realization's random stream (drawn from before the schedule).
        """

    @abstractmethod
    def drive_kernel(self) -> Callable[..., None]:
        """Return the compiled (``numba.njit``) drive kernel.

        Kernel signature::

            kernel(phase, data, pose, context, coefficients, out) -> None

        ``phase``: int, the phase code; ``data``: float, the phase's schedule datum;
        ``pose``: float64[3], bot x, y (cm) and heading (rad); ``context`` and
        ``coefficients`` as for :meth:`softcell.plugin.EnergyTerm.partials_kernel`. The
        kernel writes the drive force x, y (N) and torque about the bot's center (N cm) into
        ``out[0:3]``.
        """

    def event_kernel(self) -> Callable[..., float] | None:
        """Return the compiled (``numba.njit``) event kernel, or None (the default: every
        phase lasts as scheduled).

        Kernel signature::

            kernel(phase, data, sense, coefficients) -> float

        ``phase``, ``data`` and ``coefficients`` as for :meth:`drive_kernel`; ``sense``:
        float64[9], what the bot senses, laid out by the indices of :class:`Sense`
        (pose in cm and rad, force on the bot in N, torque in N cm, distance to the membrane
        in cm, time and time in the phase in s). The phase ends at the first time the
        returned value is >= 0: at once if it is at the phase's start, else where it
        crosses zero, located by ``rodas4`` on its continuous extension to 1e-9 s and by
        ``explicit_euler`` to its step. The phases after it then start that much earlier
        than scheduled: :meth:`schedule` gives each phase with an event its longest
        duration. The event times are stored in the output (``event_time``).
        """
        return None


class FrictionLaw(Component):
    """How a membrane element moves under the force on it: a pointwise map from the force
    density f (N cm^-1, per unit length of membrane) to the element's velocity v (cm s^-1),
    which may depend on where the element is and which way the membrane runs there (its
    position and unit tangent; docs/model.md §3). The engine evaluates the force density of
    the cut-off modes at M equally spaced points (the smallest power of two >= 8 Lc, at most
    N: 128 with the defaults), applies the law there, and keeps the velocity's modes
    ``|k| <= Lc``, so the shape stays band-limited whatever the law.

    The built-in ``viscous`` law, v = f / gamma_mem, is the paper's; it is ``linear``, and
    integrators then keep their direct path (the law's kernels are not called).
    """

    kind = "friction_law"
    kernels = {
        "velocity_kernel": f"void({', '.join([VECTOR] * 9)})",
        "derivative_kernel": f"void({', '.join([VECTOR] * 11)})",
    }
    #: True only for v = f / membrane_friction exactly (the built-in ``viscous``): integrators
    #: then move the modes by the force modes times 2 pi / (gamma_mem l0) (the paper's law).
    linear: ClassVar[bool] = False

    @abstractmethod
    def velocity_kernel(self) -> Callable[..., None]:
        """Return the compiled (``numba.njit``) kernel of the law.

        Kernel signature::

            kernel(x, y, tx, ty, fx, fy, coefficients, vx, vy) -> None

        ``x, y``: float64[M], the membrane's points (cm), in the lab frame (the membrane
        starts as a circle centred on the origin); ``tx, ty``: float64[M], its unit tangent
        there, along increasing xi (counter-clockwise; the outward normal is (ty, -tx));
        ``fx, fy``: float64[M], the force density on the membrane at those points
        (N cm^-1); ``coefficients``: float64[:], from :meth:`Component.coefficients`. The
        kernel writes the velocity (cm s^-1) into ``vx, vy`` (float64[M]). It must not
        allocate. Point n is at xi_n = 2 pi n / M.
        """

    def derivative_kernel(self) -> Callable[..., None] | None:
        """Return the compiled kernel of the law's derivative, or None.

        Kernel signature::

            kernel(x, y, tx, ty, fx, fy, coefficients, dxx, dxy, dyx, dyy) -> None

        Arrays as in :meth:`velocity_kernel`; the kernel writes d v_a / d f_b
        (cm^2 N^-1 s^-1) at fixed points and tangents into ``dab`` (float64[M]) for a, b in
        x, y. Linearly implicit integrators (``rodas4``) need it for their Jacobian, which
        holds the membrane's geometry fixed: how v changes with the points and tangents is
        not in it, so a law that depends strongly on them costs ``rodas4`` smaller steps
        (the error control still holds). The default, None, selects the documented
        fallback: central differences of :meth:`velocity_kernel` with the step
        ``1e-6 (|f| + 1e-8 N/cm)`` per component.
        """
        return None


class Integrator(Component):
    """Advances the coupled bot-membrane state in time."""

    kind = "integrator"

    @abstractmethod
    def build(self, model: Model) -> Stepper:
        """Compose the model's compiled kernels into a stepper.

        Parameters
        ----------
        model : Model
            The compiled model of one parameter point (:class:`softcell.plugin.Model`).

        Returns
        -------
        Stepper
            Advances a realization's state from one sample time (s) to the next
            (``docs/plugins.md``, "class Integrator").
        """


class Stepper(ABC):
    """What :meth:`Integrator.build` returns: advances one realization's state in time.

    The state is a dict of numpy arrays, so a checkpoint is a plain ``.npz``: ``modes``
    (complex128[2 Lc + 1], cm), ``pose`` (float64[3]: cm, cm, rad), ``time`` (float64[1], s)
    and whatever else the integrator keeps. A stepper implements :meth:`start` and
    :meth:`advance`; :meth:`sample` has a default built on :meth:`advance`.
    """

    @abstractmethod
    def start(
        self, modes: np.ndarray, pose: np.ndarray, schedule: Schedule
    ) -> dict[str, np.ndarray]:
        """The initial state of a realization.

        Parameters
        ----------
        modes : ndarray
            complex128[2 Lc + 1]: the membrane's Fourier modes (cm).
        pose : ndarray
            float64[3]: the bot's x, y (cm) and heading (rad).
        schedule : Schedule
            The realization's phase schedule (times in s).
        """

    @abstractmethod
    def advance(self, state: dict[str, np.ndarray], schedule: Schedule, t_end: float) -> None:
        """Advance ``state`` in place to time ``t_end``.

        Parameters
        ----------
        state : dict of ndarray
            The stepper's state (see the class), changed in place.
        schedule : Schedule
            The realization's phase schedule (times in s).
        t_end : float
            Time (s) to advance to, not before the state's time.
        """

    def current(self, state: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, float]:
        """The modes (cm), pose (cm, cm, rad) and time (s) the integrator has reached, for
        the diagnosis of a failed run. The default: ``state``'s ``modes``, ``pose`` and
        ``time``; an integrator whose steps run ahead of them overrides it.

        Parameters
        ----------
        state : dict of ndarray
            The stepper's state.
        """
        return state["modes"], state["pose"], float(state["time"][0])

    def sample(
        self, state: dict[str, np.ndarray], schedule: Schedule, times: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Advance ``state`` through the increasing ``times`` (s) and return the modes
        (complex128[K, 2 Lc + 1], cm) and poses (float64[K, 3]: cm, cm, rad) there.

        The default calls :meth:`advance` once per time; an integrator whose calls cost more
        than its steps (one compiled call per sample) overrides it. Either way the result must
        not depend on how the times are split between calls. The engine asks for the
        membrane's sample times and the bodies' fine record (every ``sample_every``)
        together; the built-in integrators' steps do not depend on where they are sampled.

        Parameters
        ----------
        state : dict of ndarray
            The stepper's state, advanced in place.
        schedule : Schedule
            The realization's phase schedule (times in s).
        times : ndarray
            float64[K]: increasing sample times (s), none before the state's time.
        """
        modes = np.empty((len(times), state["modes"].size), dtype=np.complex128)
        pose = np.empty((len(times), 3))
        for i, t in enumerate(times):
            self.advance(state, schedule, float(t))
            modes[i], pose[i] = state["modes"], state["pose"]
        return modes, pose


class StopGoDetector(Component):
    """Labels each sample of a speed series as stop or go (docs/model.md §6)."""

    kind = "stopgo_detector"

    @abstractmethod
    def label(self, speed: np.ndarray, interval: float) -> np.ndarray:
        """Label samples.

        Parameters
        ----------
        speed : float64 array
            Speed (cm/s), time along the last axis; NaN where unknown.
        interval : float
            Sampling interval (s) of the series.

        Returns
        -------
        int8 array of the same shape
            1 go, 0 stop, -1 unknown (NaN speed).
        """


#: Contract class of each kind, by the hook that returns it.
class PairTerm(Component):
    """How the membranes of two cells of an assembly meet: an energy density e(rho) per unit
    xi of a membrane point at signed distance rho (cm) from another cell's membrane (positive
    outside it, negative inside; rho is taken to that membrane's polygon of N points, both
    ways: c's points against d and d's points against c). A point and its nearest segment
    contribute (2 pi / N) e(rho) to the energy (N cm), so e is in N cm; the engine adds the
    forces on the point and on the segment's two ends (their sum vanishes) and their
    Jacobian. The built-in ``repulsion`` is the contact's law, (l0 / 2 pi) A exp(-rho /
    lambda); a plugin adds adhesion, say, as one more term (docs/plugins.md).
    """

    kind = "pair_term"
    kernels = {"law_kernel": f"void(float64, {VECTOR}, {VECTOR})"}

    @abstractmethod
    def law_kernel(self) -> Callable[..., None]:
        """Return the compiled (``numba.njit``) kernel of the law.

        Kernel signature::

            kernel(rho, coefficients, out) -> None

        ``rho``: float64, the signed distance (cm); ``coefficients``: float64[:], from
        :meth:`Component.coefficients`. The kernel writes e (N cm), de/drho (N) and
        d^2 e / drho^2 (N cm^-1) into ``out[0:3]``, all zero beyond :meth:`reach`. It must
        not allocate. ``context`` is not passed: a law that depends on l0 reads it from its
        own coefficients.
        """

    @abstractmethod
    def reach(self) -> float:
        """The distance (cm) beyond which the law is zero: cells are coupled, and points
        searched for, within the largest reach of the terms in use."""


class BotInteraction(Component):
    """How two bots in one ring act on each other (``--bots K`` > 1): generalized forces on
    both bots from their two poses. The built-in ``bot_repulsion`` is a soft repulsion of the
    ellipses' gap; a plugin adds alignment (a torque toward the other's heading), say, as one
    more interaction (docs/plugins.md). The engine applies each pair's forces with the bots'
    mobilities, and takes their Jacobian by central differences of the kernel (steps 1e-7 of
    l0 / 2 pi in x and y, 1e-7 rad in the heading).
    """

    kind = "bot_interaction"
    kernels = {
        "pair_kernel": f"void({VECTOR}, {VECTOR}, {VECTOR}, {VECTOR}, {VECTOR})",
        "jacobian_kernel": f"void({VECTOR}, {VECTOR}, {VECTOR}, {VECTOR}, {VECTOR}, {VECTOR}, "
        "float64[:, ::1])",
    }

    @abstractmethod
    def pair_kernel(self) -> Callable[..., None]:
        """Return the compiled (``numba.njit``) kernel of the interaction.

        Kernel signature::

            kernel(pose_a, pose_b, context, coefficients, out) -> None

        ``pose_a``, ``pose_b``: float64[3], the two bots' x, y (cm) and heading (rad);
        ``context``: float64[3], (l0, a, b) in cm; ``coefficients``: float64[:], from
        :meth:`Component.coefficients`. The kernel *adds* the generalized forces on bot a
        (N, N, N cm: force x, y and the torque about its centre) into ``out[0:3]`` and those
        on bot b into ``out[3:6]``. An interaction that conserves momentum has out[0:2] =
        -out[3:5] and, about the origin, x_a F_ya - y_a F_xa + tau_a + (the same for b) = 0;
        the tests check the built-in's. It must not allocate, and must add nothing when the
        bots' centres are farther apart than :meth:`reach`.
        """

    def jacobian_kernel(self) -> Callable[..., None] | None:
        """Return a compiled kernel of the interaction's Jacobian, or None (the default):
        the engine then takes central differences of :meth:`pair_kernel`.

        Kernel signature::

            kernel(pose_a, pose_b, context, coefficients, steps, scratch, jac) -> None

        It *adds* d out_c / d q_j into ``jac`` (float64[6, 6]; q = (x_a, y_a, theta_a, x_b,
        y_b, theta_b), out as :meth:`pair_kernel` writes it); ``steps[6:9]`` are the engine's
        difference steps in x, y (cm) and the heading (rad), ``scratch`` float64[24] is the
        kernel's to use. It must not allocate.
        """
        return None

    @abstractmethod
    def reach(self) -> float:
        """The distance (cm) between the bots' centres beyond which the kernel adds nothing:
        pairs farther apart are not visited."""


CONTRACTS: dict[str, type[Component]] = {
    "softcell_energy_terms": EnergyTerm,
    "softcell_driving_protocols": DrivingProtocol,
    "softcell_friction_laws": FrictionLaw,
    "softcell_integrators": Integrator,
    "softcell_stopgo_detectors": StopGoDetector,
    "softcell_pair_terms": PairTerm,
    "softcell_bot_interactions": BotInteraction,
}


def check_kernels(component: Component, origin: str) -> None:
    """Compile each kernel of ``component`` for the signature its contract declares
    (:attr:`Component.kernels`), so that a mismatch stops the run before any time step.

    A kernel method returning None is skipped (the optional ``hessian_kernel``). Compiling a
    kernel that is already compiled (or cached on disk) for that signature costs nothing.

    Raises
    ------
    ContractError
        One line naming ``origin`` (the distribution or module that registered the
        component), the component, the kernel, the expected signature and numba's reason.
    """
    for method, signature in type(component).kernels.items():
        kernel = getattr(component, method)()
        if kernel is None:
            continue
        where = f"{origin}: {kind_name(component.kind)} {component.name!r}: {method}()"
        if not callable(getattr(kernel, "compile", None)):
            raise ContractError(f"{where} returned {kernel!r}, not a numba.njit function")
        try:
            kernel.compile(signature)
        except Exception as exc:  # numba's TypingError, or TypeError for a wrong arity
            raise ContractError(
                f"{where} does not compile for the contract's signature {signature}: {_reason(exc)}"
            ) from None


def _reason(exc: Exception) -> str:
    """The informative part of numba's many-line message, on one line."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    lines = [
        line
        for line in lines
        if not line.startswith(("Failed in nopython mode", "During:", "<source missing"))
    ]
    text = " ".join(lines[:2]) or type(exc).__name__
    return text if len(text) <= 300 else text[:297] + "..."


@dataclass
class Model:
    """The compiled model of one parameter point: what an integrator composes into a stepper.

    Attributes
    ----------
    params : Parameters
    terms : list of EnergyTerm
        For a free bot (``membrane`` False), only the terms that act on the bot alone
        (:meth:`EnergyTerm.bot_kernel`; the arena's walls).
    protocol : DrivingProtocol
    partials : compiled function
        Sum of the terms' partials kernels (see ``compose_partials``).
    coefficients : tuple of float64 arrays
        One per term.
    drive : compiled function
        The protocol's drive kernel.
    drive_coefficients : ndarray
        float64: the protocol's coefficients, each in its declared unit.
    context : float64[3]
        l0 (cm), bot semi-major and semi-minor axes (cm).
    membrane_mobility : float
        2 pi / (gamma_mem l0) (cm^2 N^-1 s^-1 per unit xi): dg_k/dt = membrane_mobility f_hat_k.
    bot_mobility : float64[3]
        1/gamma_T, 1/gamma_T (cm N^-1 s^-1) and 1/gamma_R (N^-1 cm^-1 s^-1).
    nodes : int
        Collocation points N of the membrane.
    cutoff : int
        Fourier cutoff Lc: modes k = -Lc..Lc.
    membrane : bool
        False for a free bot (no membrane; see ``has_membrane``).
    friction : FrictionLaw
        The membrane's friction law. When it is
        not ``linear``, an integrator evaluates the force density
        f = (2 pi / l0) sum_k f_hat_k e^{i k xi} (N cm^-1) at M points (the smallest power of
        two >= 8 Lc, at most N: 128), applies the law's kernel there and moves the modes by the
        velocity's modes ``|k| <= Lc``.
    friction_coefficients : ndarray
        float64: the friction law's coefficients, each in its declared unit.
    force_scale : float
        2 pi / l0 (cm^-1), the factor above.
    names : dict
        The component names by kind, as files store them.
    origins : dict
        Where each component came from, by ``"<kind> <name>"`` (for errors that name it).
    pair_terms : list of PairTerm
        The pair terms between the membranes of an assembly's cells (none for one cell).
    event : callable or None
        The protocol's compiled event kernel (:meth:`DrivingProtocol.event_kernel`; its value
        in the unit the protocol chooses, >= 0 ends the phase), or None.
    bot_interactions : list of BotInteraction
        How the bots of one ring act on each other (``--bots K`` > 1; none for one bot).
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
    membrane: bool = True
    friction: FrictionLaw | None = None
    friction_coefficients: np.ndarray = field(default_factory=lambda: np.zeros(1))
    force_scale: float = 1.0
    names: dict[str, object] = field(default_factory=dict)
    #: Where each component came from, by ``"<kind> <name>"`` (for errors that name it).
    origins: dict[str, str] = field(default_factory=dict)
    #: The pair terms between the membranes of an assembly's cells (none for one cell).
    pair_terms: list[PairTerm] = field(default_factory=list)
    #: The protocol's compiled event kernel, or None (:meth:`DrivingProtocol.event_kernel`).
    event: Callable[..., float] | None = None
    #: How the bots of one ring act on each other (none for one bot).
    bot_interactions: list[BotInteraction] = field(default_factory=list)

    @property
    def bot_reach(self) -> float:
        """The distance (cm) between bots' centres within which they interact: the largest
        reach of the bot interactions (0 without any)."""
        return max((i.reach() for i in self.bot_interactions), default=0.0)

    @property
    def pair_reach(self) -> float:
        """The distance (cm) within which the pair terms act: the largest reach."""
        return max((t.reach() for t in self.pair_terms), default=0.0)

    @property
    def has_membrane(self) -> bool:
        return self.membrane and bool(self.terms)

    @property
    def bot_terms(self) -> list[EnergyTerm]:
        """The terms with an energy of the bot alone (:meth:`EnergyTerm.bot_kernel`)."""
        return [t for t in self.terms if t.has_bot_energy]

    @property
    def reads_pose(self) -> bool:
        """True if any term's density depends on the bot's pose."""
        return any(t.reads_pose for t in self.terms)

    @property
    def couples_bot(self) -> bool:
        """Deprecated name of :attr:`reads_pose` (until softcell 0.4)."""
        import warnings

        warnings.warn(
            "Model.couples_bot was renamed Model.reads_pose in softcell 0.3",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.reads_pose

    @property
    def nonlinear_friction(self) -> bool:
        """True when the friction law is not the linear v = f / gamma_mem (integrators then
        apply the law's kernel)."""
        return self.has_membrane and self.friction is not None and not self.friction.linear
