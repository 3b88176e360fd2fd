"""A well-formed third-party plugin: one stop/go detector."""

import numpy as np

from softcell import hookimpl
from softcell.components.contracts import StopGoDetector
from softcell.model.parameters import ParameterSpec


class Hysteresis(StopGoDetector):
    name = "fake_hysteresis"
    description = "a fake detector for the registry tests"
    parameters = (ParameterSpec("fake_level", 1.0, "cm s-1", "a fake level", minimum=0.0),)

    def label(self, speed, interval):
        return (np.asarray(speed) > self.params["fake_level"]).astype(np.int8)


@hookimpl
def softcell_stopgo_detectors():
    return [Hysteresis]
