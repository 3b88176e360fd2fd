"""The driving protocol ``constant_push``: a permanent run along the initial heading, with
which the paper calibrates the membrane friction gamma_mem (docs/model.md §5)."""

from __future__ import annotations

import numpy as np

from softcell.builtins.run_and_tumble import run_and_tumble_drive
from softcell.components.contracts import DrivingProtocol, Schedule
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import MODEL_PARAMETERS as P
from softcell.schema import PHASE_RUN as RUN


class ConstantPush(DrivingProtocol):
    """A permanent run along the initial heading (the paper's calibration of gamma_mem)."""

    name = "constant_push"
    description = "a permanent run at force F0 along a fixed heading (calibrates gamma_mem)"
    parameters = (P["drive_force"], P["drive_torque"])

    def schedule(self, rng, duration):
        return Schedule(np.zeros(1), np.array([RUN], dtype=np.int8), np.zeros(1))

    def initial_heading(self, rng):
        return float(rng.uniform(0.0, 2.0 * np.pi))

    def drive_kernel(self):
        return run_and_tumble_drive


@hookimpl
def softcell_driving_protocols() -> list[type[DrivingProtocol]]:
    return [ConstantPush]
