"""A plugin whose detector takes the name of the built-in one."""

from softcell import hookimpl
from softcell.components.contracts import StopGoDetector


class Threshold(StopGoDetector):
    name = "threshold"
    description = "clashes with the built-in threshold detector"

    def label(self, speed, interval):
        raise NotImplementedError


@hookimpl
def softcell_stopgo_detectors():
    return [Threshold]
