"""The paper's stop/go detector: a sample is *go* when its speed reaches a threshold
(docs/model.md §6).

The paper uses 0.3 cm/s for the experiments and 0.03 cm/s for the simulations; the default is
the simulations' value.
"""

from __future__ import annotations

import numpy as np

from softcell.components.contracts import StopGoDetector
from softcell.components.hookspecs import hookimpl
from softcell.model.parameters import ParameterSpec
from softcell.schema import STOPGO_UNKNOWN

#: The paper's speed thresholds (cm/s): 0.03 for its simulations, 0.3 for its experiments.
SIMULATION_THRESHOLD, EXPERIMENT_THRESHOLD = 0.03, 0.3
#: The threshold detector's parameter (the analysis option ``threshold`` overrides it).
THRESHOLD = ParameterSpec(
    "threshold",
    SIMULATION_THRESHOLD,
    "cm s-1",
    "speed below which a sample is stop (0.3 for experiments)",
    minimum=0.0,
)


class Threshold(StopGoDetector):
    """Stop where the speed is below ``threshold`` (cm/s), go where it is at or above it."""

    name = "threshold"
    description = "stop below a speed threshold, go at or above it (the paper's detector)"
    parameters = (THRESHOLD,)

    def label(self, speed: np.ndarray, interval: float) -> np.ndarray:
        speed = np.asarray(speed, dtype=np.float64)
        labels = (speed >= float(self.params["threshold"])).astype(np.int8)
        labels[np.isnan(speed)] = STOPGO_UNKNOWN
        return labels


@hookimpl
def softcell_stopgo_detectors() -> list[type[StopGoDetector]]:
    return [Threshold]
