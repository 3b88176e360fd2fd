"""A driving protocol: each run goes forward or backward along the heading with probability
1/2 (as some bacteria reverse); tumbles turn about the bot's center as in ``run_and_tumble``.
"""

import math

import numpy as np
from numba import njit

from softcell.plugin import MODEL_PARAMETERS, PHASE_RUN, PHASE_TUMBLE, DrivingProtocol, Schedule

RUN, TUMBLE = PHASE_RUN, PHASE_TUMBLE  # the bot_phase flag values (numba reads globals)


@njit(nogil=True, cache=True)
def run_and_reverse_drive(phase, data, pose, context, coefficients, out):
    # data: +1 forward / -1 backward for a run, the turn sign for a tumble.
    if phase == RUN:
        out[0] = data * coefficients[0] * math.cos(pose[2])
        out[1] = data * coefficients[0] * math.sin(pose[2])
        out[2] = 0.0
    else:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = data * coefficients[1]


class RunAndReverse(DrivingProtocol):
    """Runs (force +-F0 along the heading) and tumbles (torque +-T0), U[tau_l, tau_h] each."""

    name = "run_and_reverse"
    description = "runs forward or backward at random (force +-F0), tumbles (torque +-T0)"
    # Parameters of the model catalogue are reused by listing their specs.
    parameters = tuple(
        MODEL_PARAMETERS[n] for n in ("drive_force", "drive_torque", "phase_min", "phase_max")
    )

    def schedule(self, rng: np.random.Generator, duration: float) -> Schedule:
        lo, hi = float(self.params["phase_min"]), float(self.params["phase_max"])
        count = int(math.ceil(duration / lo)) + 1
        start = np.concatenate([[0.0], np.cumsum(rng.uniform(lo, hi, count))[:-1]])
        keep = start < duration
        phase = np.where(np.arange(count) % 2 == 0, RUN, TUMBLE).astype(np.int8)
        sign = rng.choice(np.array([-1.0, 1.0]), count)  # direction of a run, turn of a tumble
        return Schedule(start[keep], phase[keep], sign[keep])

    def initial_heading(self, rng: np.random.Generator) -> float:
        return float(rng.uniform(0.0, 2.0 * np.pi))

    def drive_kernel(self):
        return run_and_reverse_drive
