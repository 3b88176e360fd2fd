"""Driving protocols of docs/model.md §5: run_and_tumble and pivot_run_and_tumble.

Runs and tumbles alternate, starting with a run; each lasts an independent U[phase_min,
phase_max] draw; a tumble turns counterclockwise or clockwise with probability 1/2. The bot
starts at the membrane center with a uniform heading. The schedule is drawn whole, up front,
from the realization's Generator.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.components.contracts import DrivingProtocol, Schedule
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import MODEL_PARAMETERS as P
from softcell.schema import PHASE_RUN as RUN
from softcell.schema import PHASE_TUMBLE as TUMBLE
from softcell.settings import JIT


def alternating_schedule(
    rng: np.random.Generator, duration: float, shortest: float, longest: float
) -> Schedule:
    """Run, tumble, run, ... with U[shortest, longest] durations covering [0, duration];
    the datum of a tumble is its turn sign (+1 counterclockwise, -1 clockwise).

    Parameters
    ----------
    rng : Generator
        The realization's random stream: the durations, then the turn signs.
    duration : float
        Length (s) the schedule covers.
    shortest, longest : float
        Bounds (s) of the uniform phase durations.

    Returns
    -------
    Schedule
        Start times (s), phase codes and turn signs.
    """
    count = int(math.ceil(duration / shortest)) + 1
    lengths = rng.uniform(shortest, longest, count)
    return alternate(lengths, rng.choice(np.array([-1.0, 1.0]), count), duration)


def alternate(lengths: np.ndarray, signs: np.ndarray, duration: float) -> Schedule:
    """Run, tumble, run, ... of the given ``lengths`` (s), a tumble's datum its turn sign
    from ``signs``, keeping the phases that start before ``duration`` (s).

    Returns
    -------
    Schedule
        Start times (s), phase codes and turn signs.
    """
    start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    keep = start < duration
    phase = np.where(np.arange(lengths.size) % 2 == 0, RUN, TUMBLE).astype(np.int8)
    data = np.where(phase == TUMBLE, signs, 0.0)
    return Schedule(start[keep], phase[keep], data[keep])


@njit(**JIT)
def run_and_tumble_drive(phase, data, pose, context, coefficients, out):
    """Run: force F0 = coefficients[0] (N) along the heading. Tumble: torque
    data * T0 = coefficients[1] (N cm) about the center, data the turn sign.

    Parameters
    ----------
    phase : int
        The phase code (0 tumble, 1 run).
    data : float
        The phase's schedule datum: the turn sign (+1 or -1) of a tumble.
    pose : ndarray
        float64[3]: the bot's x, y (cm) and heading (rad).
    context : ndarray
        float64[3]: l0 (cm), the bot's semi-axes (cm).
    coefficients : ndarray
        float64: as above, each in its unit.
    out : ndarray
        float64[3]: receives the force x, y (N) and the torque (N cm).
    """
    if phase == RUN:
        out[0] = coefficients[0] * math.cos(pose[2])
        out[1] = coefficients[0] * math.sin(pose[2])
        out[2] = 0.0
    else:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = data * coefficients[1]


@njit(**JIT)
def pivot_drive(phase, data, pose, context, coefficients, out):
    """As :func:`run_and_tumble_drive`, but a tumble turns the bot about a pivot offset d
    along its minor axis (coefficients: F0 (N), T0 (N cm), gamma_T, gamma_R, d (cm), and
    1.0 for the inner side of the turn or 0.0 for a fixed side).

    Parameters
    ----------
    phase : int
        The phase code (0 tumble, 1 run).
    data : float
        The phase's schedule datum: the turn sign (+1 or -1) of a tumble.
    pose : ndarray
        float64[3]: the bot's x, y (cm) and heading (rad).
    context : ndarray
        float64[3]: l0 (cm), the bot's semi-axes (cm).
    coefficients : ndarray
        float64: as above, each in its unit.
    out : ndarray
        float64[3]: receives the force x, y (N) and the torque (N cm).
    """
    if phase == RUN:
        run_and_tumble_drive(phase, data, pose, context, coefficients, out)
        return
    omega = data * coefficients[1] / coefficients[3]
    side = data if coefficients[5] > 0.5 else 1.0
    # The center then moves as omega z x (r - pivot): the free bot turns about the pivot.
    speed = side * coefficients[4] * omega
    out[0] = coefficients[2] * speed * math.cos(pose[2])
    out[1] = coefficients[2] * speed * math.sin(pose[2])
    out[2] = data * coefficients[1]


class RunAndTumble(DrivingProtocol):
    """Runs at force F0 along the heading; tumbles at torque +-T0 about the bot's center."""

    name = "run_and_tumble"
    description = "runs (force F0) and tumbles (torque +-T0 about the center), U[tau_l, tau_h]"
    parameters = (P["drive_force"], P["drive_torque"], P["phase_min"], P["phase_max"])

    def schedule(self, rng, duration):
        return alternating_schedule(
            rng, duration, float(self.params["phase_min"]), float(self.params["phase_max"])
        )

    def initial_heading(self, rng):
        return float(rng.uniform(0.0, 2.0 * np.pi))

    def drive_kernel(self):
        return run_and_tumble_drive


class PivotRunAndTumble(RunAndTumble):
    """As run_and_tumble, but a tumble turns the bot about a pivot offset along its minor axis."""

    name = "pivot_run_and_tumble"
    description = (
        "runs and tumbles about a pivot offset d along the minor axis "
        "(inner side of the turn, or fixed), as in the experiments"
    )
    parameters = (
        *RunAndTumble.parameters,
        P["bot_friction"],
        P["bot_rotational_friction"],
        P["pivot_offset"],
        P["pivot_side"],
    )

    def coefficients(self):
        """F0 (N), T0 (N cm), gamma_T, gamma_R, pivot offset d (cm), 1.0 inner / 0.0 fixed."""
        p = self.params
        return np.array(
            [
                p.drive_force,
                p.drive_torque,
                p.bot_friction,
                p.bot_rotational_friction,
                p.pivot_offset,
                1.0 if p.pivot_side == "inner" else 0.0,
            ],
            dtype=np.float64,
        )

    def drive_kernel(self):
        return pivot_drive


@hookimpl
def softcell_driving_protocols() -> list[type[DrivingProtocol]]:
    return [RunAndTumble, PivotRunAndTumble]
