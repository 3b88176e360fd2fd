"""Locomotion strategies beyond the paper's protocol (docs/strategies.md): ``graspion``, the
robot's own firmware; ``bump_and_turn``, runs that end when the bot touches its membrane;
``active_brownian``, a heading that diffuses; ``chiral``, runs that curve.

Each draws its whole schedule up front from the realization's Generator, like
``run_and_tumble``, so a run is the same to the byte whatever the number of workers; a state
event (``bump_and_turn``'s contact) only moves the later phases earlier.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.builtins.run_and_tumble import alternate, alternating_schedule, run_and_tumble_drive
from softcell.components.contracts import DrivingProtocol, Schedule, Sense
from softcell.components.hookspecs import hookimpl
from softcell.errors import ParameterError
from softcell.model.parameters import MODEL_PARAMETERS as P
from softcell.model.parameters import ParameterSpec
from softcell.schema import PHASE_RUN as RUN
from softcell.schema import PHASE_TUMBLE as TUMBLE
from softcell.settings import JIT

#: The published digital twin of the robot (docs/model.md §5): the centre of rotation of a
#: one-motor tumble lies this far (cm) from the bot's centre, turning counterclockwise and
#: clockwise, and the tumble turns at most this fast (rad/s).
GRASPION_PIVOT_CCW = 1.61
GRASPION_PIVOT_CW = 1.45
GRASPION_TURN_RATE = 3.46
#: The sense vector's entries the contact event reads.
FORCE_X, FORCE_Y = int(Sense.FORCE_X), int(Sense.FORCE_Y)


def _spec(name: str, default: float, unit: str, long_name: str) -> ParameterSpec:
    return ParameterSpec(name, default, unit, long_name, minimum=0.0, minimum_inclusive=True)


TURN_RATE = ParameterSpec(
    "turn_rate",
    GRASPION_TURN_RATE,
    "rad s-1",
    "angular speed of a free graspion tumble (its sense is the tumble's)",
    minimum=0.0,
)
PIVOT_CCW = _spec(
    "pivot_ccw", GRASPION_PIVOT_CCW, "cm", "pivot offset of a counterclockwise graspion tumble"
)
PIVOT_CW = _spec("pivot_cw", GRASPION_PIVOT_CW, "cm", "pivot offset of a clockwise graspion tumble")
ROTATIONAL_DIFFUSION = _spec(
    "rotational_diffusion", 1.0, "rad2 s-1", "rotational diffusion coefficient D_r of the heading"
)
NOISE_INTERVAL = ParameterSpec(
    "noise_interval",
    0.05,
    "s",
    "interval of the piecewise-constant active_brownian torque (from 1 ms: one value is "
    "stored per interval)",
    minimum=1e-3,
    minimum_inclusive=True,
)
CONTACT_THRESHOLD = ParameterSpec(
    "contact_threshold",
    0.02,
    "N",
    "force of the membrane on the bot that ends a bump_and_turn run",
    minimum=0.0,
)
CHIRAL_TORQUE = ParameterSpec(
    "chiral_torque", 28.5, "N cm", "constant torque on the bot during a chiral run"
)


def millisecond_schedule(rng: np.random.Generator, duration: float, lo: float, hi: float):
    """Run, tumble, run, ... each lasting an integer number of milliseconds drawn uniformly
    from [lo, hi] (s, rounded to ms), the turn signs +-1 with probability 1/2: the firmware's
    timer.

    Returns
    -------
    Schedule
        Start times (s), phase codes and turn signs.
    """
    first, last = round(1000 * lo), round(1000 * hi)
    count = int(math.ceil(duration / max(first, 1) * 1000)) + 1
    lengths = rng.integers(first, last + 1, count) / 1000.0
    return alternate(lengths, rng.choice(np.array([-1.0, 1.0]), count), duration)


@njit(**JIT)
def graspion_drive(phase, data, pose, context, coefficients, out):
    """Run: force F0 along the heading. Tumble: one motor turns the bot at omega about the
    stopped wheel's side, offset d_ccw or d_cw by direction (coefficients: F0 (N), omega
    (rad/s), gamma_T (N s/cm), gamma_R (N cm s), d_ccw, d_cw (cm)).

    Parameters
    ----------
    phase : int
        The phase code (0 tumble, 1 run).
    data : float
        The turn sign (+1 counterclockwise, -1 clockwise) of a tumble.
    pose : ndarray
        float64[3]: the bot's x, y (cm) and heading (rad).
    context : ndarray
        float64[3]: l0 (cm), the bot's semi-axes (cm).
    coefficients : ndarray
        float64[6]: as above.
    out : ndarray
        float64[3]: receives the force x, y (N) and the torque (N cm).
    """
    c, s = math.cos(pose[2]), math.sin(pose[2])
    if phase == RUN:
        out[0] = coefficients[0] * c
        out[1] = coefficients[0] * s
        out[2] = 0.0
        return
    omega = data * coefficients[1]
    offset = coefficients[4] if data > 0.0 else coefficients[5]
    # The pivot sits on the inner side of the turn: the free centre moves at omega z x
    # (r - pivot) = |omega| d along the heading.
    speed = data * offset * omega
    out[0] = coefficients[2] * speed * c
    out[1] = coefficients[2] * speed * s
    out[2] = coefficients[3] * omega


@njit(**JIT)
def chiral_drive(phase, data, pose, context, coefficients, out):
    """Run: force F0 along the heading and the constant torque T_c. Tumble: torque data * T0
    about the centre (coefficients: F0 (N), T0 (N cm), T_c (N cm)).

    Parameters
    ----------
    phase : int
        The phase code (0 tumble, 1 run).
    data : float
        The turn sign (+1 or -1) of a tumble.
    pose : ndarray
        float64[3]: the bot's x, y (cm) and heading (rad).
    context : ndarray
        float64[3]: l0 (cm), the bot's semi-axes (cm).
    coefficients : ndarray
        float64[3]: as above.
    out : ndarray
        float64[3]: receives the force x, y (N) and the torque (N cm).
    """
    if phase == RUN:
        out[0] = coefficients[0] * math.cos(pose[2])
        out[1] = coefficients[0] * math.sin(pose[2])
        out[2] = coefficients[2]
    else:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = data * coefficients[1]


@njit(**JIT)
def active_brownian_drive(phase, data, pose, context, coefficients, out):
    """Force F0 along the heading and the phase's random torque ``data`` (N cm)
    (coefficients: F0 (N)).

    Parameters
    ----------
    phase : int
        The phase code (always 1, run).
    data : float
        The torque (N cm) of this noise interval.
    pose : ndarray
        float64[3]: the bot's x, y (cm) and heading (rad).
    context : ndarray
        float64[3]: l0 (cm), the bot's semi-axes (cm).
    coefficients : ndarray
        float64[1]: F0 (N).
    out : ndarray
        float64[3]: receives the force x, y (N) and the torque (N cm).
    """
    out[0] = coefficients[0] * math.cos(pose[2])
    out[1] = coefficients[0] * math.sin(pose[2])
    out[2] = data


@njit(**JIT)
def bump_event(phase, data, sense, coefficients):
    """A run ends when the force of the energies on the bot (its membrane's contact, walls)
    reaches the threshold (coefficients[2], N); a tumble never ends early.

    Parameters
    ----------
    phase : int
        The phase code (0 tumble, 1 run).
    data : float
        The phase's schedule datum (unused).
    sense : ndarray
        float64[9]: what the bot senses (:class:`softcell.plugin.Sense`).
    coefficients : ndarray
        float64[3]: F0 (N), T0 (N cm), the threshold (N).

    Returns
    -------
    float
        |F| - threshold (N) in a run; -1 in a tumble.
    """
    if phase != RUN:
        return -1.0
    return math.hypot(sense[FORCE_X], sense[FORCE_Y]) - coefficients[2]


def bump_schedule(rng: np.random.Generator, duration: float, shortest: float, longest: float):
    """Run, tumble, run, ...: each run as long as the whole duration (its contact event
    ends it), each tumble U[shortest, longest] (s) with a turn sign +-1; as many phases as
    fit if every run ended at once (2 ceil(duration / shortest) + 2), so the count depends
    on the parameters only."""
    pairs = int(math.ceil(duration / shortest)) + 1
    tumbles = rng.uniform(shortest, longest, pairs)
    signs = rng.choice(np.array([-1.0, 1.0]), pairs)
    lengths = np.empty(2 * pairs)
    lengths[0::2] = duration + longest  # a run only its event ends
    lengths[1::2] = tumbles
    start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    phase = np.tile(np.array([RUN, TUMBLE], dtype=np.int8), pairs)
    data = np.zeros(2 * pairs)
    data[1::2] = signs
    return Schedule(start, phase, data)


class _UniformHeading:
    def initial_heading(self, rng):
        return float(rng.uniform(0.0, 2.0 * np.pi))


class Graspion(_UniformHeading, DrivingProtocol):
    """The robot's firmware: integer-millisecond runs and tumbles from U[tau_l, tau_h]; a
    tumble runs one motor, so the bot pivots about a wheel (offsets by turning direction)."""

    name = "graspion"
    description = (
        "the robot's firmware: integer-ms runs and tumbles, one-motor tumbles "
        "pivoting 1.61 / 1.45 cm off centre"
    )
    parameters = (
        P["drive_force"],
        TURN_RATE,
        P["bot_friction"],
        P["bot_rotational_friction"],
        PIVOT_CCW,
        PIVOT_CW,
        P["phase_min"],
        P["phase_max"],
    )

    def schedule(self, rng, duration):
        p = self.params
        return millisecond_schedule(rng, duration, float(p.phase_min), float(p.phase_max))

    def coefficients(self):
        """F0 (N), omega (rad/s), gamma_T, gamma_R, d_ccw (cm), d_cw (cm)."""
        return super().coefficients()[:6]

    def drive_kernel(self):
        return graspion_drive


class BumpAndTurn(_UniformHeading, DrivingProtocol):
    """Runs at F0 until the bot touches its membrane (the force on it reaches the
    threshold), then tumbles at +-T0 for a U[tau_l, tau_h] duration; a run that begins in
    contact ends at once, so the bot turns again."""

    name = "bump_and_turn"
    description = (
        "runs until the membrane pushes back with contact_threshold, then tumbles U[tau_l, tau_h]"
    )
    parameters = (
        P["drive_force"],
        P["drive_torque"],
        CONTACT_THRESHOLD,
        P["phase_min"],
        P["phase_max"],
    )

    @classmethod
    def check(cls, params):
        threshold, force = float(params.contact_threshold), float(params.drive_force)
        if threshold >= force:
            raise ParameterError(
                "contact_threshold",
                threshold,
                f"must be < drive_force = {force:g} N: a run stalled against its membrane "
                "is pushed back with the bot's own force, so the event could never be reached",
                "N",
            )

    def schedule(self, rng, duration):
        p = self.params
        return bump_schedule(rng, duration, float(p.phase_min), float(p.phase_max))

    def coefficients(self):
        """F0 (N), T0 (N cm), the contact threshold (N)."""
        return super().coefficients()[:3]

    def drive_kernel(self):
        return run_and_tumble_drive

    def event_kernel(self):
        return bump_event


class Chiral(_UniformHeading, DrivingProtocol):
    """run_and_tumble whose runs also carry a constant torque T_c: they curve on circles of
    radius v / omega_c (v = F0 / gamma_T, omega_c = T_c / gamma_R) when free."""

    name = "chiral"
    description = "runs with a constant torque T_c (circles when free), tumbles at +-T0"
    parameters = (
        P["drive_force"],
        P["drive_torque"],
        CHIRAL_TORQUE,
        P["phase_min"],
        P["phase_max"],
    )

    def schedule(self, rng, duration):
        p = self.params
        return alternating_schedule(rng, duration, float(p.phase_min), float(p.phase_max))

    def coefficients(self):
        """F0 (N), T0 (N cm), T_c (N cm)."""
        return super().coefficients()[:3]

    def drive_kernel(self):
        return chiral_drive


class ActiveBrownian(_UniformHeading, DrivingProtocol):
    """No tumbles: a permanent run whose heading diffuses with coefficient D_r. The torque is
    piecewise constant over intervals dt = noise_interval, gamma_R sqrt(2 D_r / dt) times a
    standard normal draw, so the free bot's heading is Brownian exactly at the interval
    ends (variance 2 D_r t)."""

    name = "active_brownian"
    description = "a permanent run; the heading diffuses (D_r) under a piecewise-constant torque"
    parameters = (
        P["drive_force"],
        P["bot_rotational_friction"],
        ROTATIONAL_DIFFUSION,
        NOISE_INTERVAL,
    )

    def schedule(self, rng, duration):
        p = self.params
        dt = float(p.noise_interval)
        count = int(math.ceil(duration / dt)) + 1
        scale = float(p.bot_rotational_friction) * math.sqrt(2.0 * p.rotational_diffusion / dt)
        torque = scale * rng.standard_normal(count)
        start = dt * np.arange(count)
        keep = start < duration
        return Schedule(start[keep], np.full(int(keep.sum()), RUN, dtype=np.int8), torque[keep])

    def coefficients(self):
        """F0 (N)."""
        return np.array([float(self.params.drive_force)])

    def drive_kernel(self):
        return active_brownian_drive


@hookimpl
def softcell_driving_protocols() -> list[type[DrivingProtocol]]:
    return [Graspion, BumpAndTurn, Chiral, ActiveBrownian]
