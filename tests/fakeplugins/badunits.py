"""A plugin with one component whose units are no units, beside a well-formed one."""

import numpy as np

from softcell import hookimpl
from softcell.components.contracts import StopGoDetector
from softcell.model.parameters import ParameterSpec


class Bananas(StopGoDetector):
    name = "bananas"
    description = "a detector declaring a unit that is no unit"
    parameters = (
        ParameterSpec("banana_level", 1.0, "bananas", "a level in bananas"),
        ParameterSpec("blank_level", 1.0, "", "a level with an empty unit"),
    )

    def label(self, speed, interval):
        return (np.asarray(speed) > 1.0).astype(np.int8)


class Plain(StopGoDetector):
    name = "plain"
    description = "a well-formed detector of the same plugin"
    parameters = (ParameterSpec("plain_level", 1.0, "cm s-1", "a level", minimum=0.0),)

    def label(self, speed, interval):
        return (np.asarray(speed) > self.params["plain_level"]).astype(np.int8)


@hookimpl
def softcell_stopgo_detectors():
    return [Bananas, Plain]
