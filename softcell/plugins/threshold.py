"""The paper's stop/go detector: a sample is *go* when its speed reaches a threshold
(docs/model.md §6).

The paper uses 0.3 cm/s for the experiments and 0.03 cm/s for the simulations; the default is
the simulations' value.
"""

from __future__ import annotations

import numpy as np

from softcell.core.analysis.stopgo import THRESHOLD
from softcell.core.components.contracts import StopGoDetector
from softcell.core.components.hookspecs import hookimpl
from softcell.core.schema import STOPGO_UNKNOWN


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
