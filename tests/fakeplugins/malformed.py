"""A plugin whose component breaks the contract (no description, abstract method left)."""

from softcell import hookimpl
from softcell.components.contracts import StopGoDetector


class Incomplete(StopGoDetector):
    name = "incomplete"


@hookimpl
def softcell_stopgo_detectors():
    return [Incomplete]
