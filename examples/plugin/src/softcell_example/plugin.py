"""The module the entry point names: one hook implementation per component kind.

softcell imports this module when it builds its registry and calls each hook once; the
hooks return component classes, never instances.
"""

from softcell.plugin import hookimpl
from softcell_example.anisotropic import Anisotropic
from softcell_example.explicit_auto import ExplicitAuto
from softcell_example.hysteresis import Hysteresis
from softcell_example.pressure import Pressure
from softcell_example.run_and_reverse import RunAndReverse


@hookimpl
def softcell_energy_terms():
    return [Pressure]


@hookimpl
def softcell_driving_protocols():
    return [RunAndReverse]


@hookimpl
def softcell_friction_laws():
    return [Anisotropic]


@hookimpl
def softcell_integrators():
    return [ExplicitAuto]


@hookimpl
def softcell_stopgo_detectors():
    return [Hysteresis]
