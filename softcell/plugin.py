"""Everything a plugin author imports, from one module.

A plugin is a module with functions named after the hooks (``softcell_energy_terms``,
``softcell_driving_protocols``, ``softcell_friction_laws``, ``softcell_integrators``,
``softcell_stopgo_detectors``),
each marked with :data:`hookimpl` and returning a list of component classes, registered under
the entry-point group ``softcell``. ``docs/plugins.md`` is the tutorial; the names below are
the public interface, and everything else in softcell is private and may move.

Contracts (subclass one per component)
    :class:`EnergyTerm`, :class:`DrivingProtocol`, :class:`FrictionLaw`, :class:`Integrator`,
    :class:`StopGoDetector`; what an integrator returns: :class:`Stepper`; what a protocol
    draws: :class:`Schedule`; what an integrator composes: :class:`Model`.
Parameters
    :class:`ParameterSpec` declares one (default, unit, range); :data:`MODEL_PARAMETERS`
    holds the model's own, to reuse by listing them; :class:`Parameters` is what a component
    receives as ``self.params``; :class:`ParameterError` is the error for a bad value.
Codes
    :data:`PHASE_RUN`, :data:`PHASE_TUMBLE`, :data:`PHASE_UNKNOWN` (``bot_phase``);
    :data:`GO`, :data:`STOP`, :data:`STOPGO_UNKNOWN` (stop/go labels).
Building blocks
    :class:`RunAndTumble` and :class:`PivotRunAndTumble` (subclass to change only the
    schedule), their drive kernels :func:`run_and_tumble_drive` and :func:`pivot_drive`,
    :func:`alternating_schedule`; :class:`ExplicitEulerStepper` (the explicit scheme, for an
    integrator that only chooses its step) and :func:`explicit_decay_rate` (its stability
    bound).
Compiling once per machine
    :func:`compile_module` runs generated source with compiled functions bound into it and
    caches its compiled functions on disk, keyed by the bound code (what the built-in
    integrators compose their loops with); :class:`CacheWarning` is what it warns with.
Testing
    :func:`registered` registers plugin modules for the duration of a ``with`` block.
"""

from __future__ import annotations

from softcell.core.components.contracts import (
    Component,
    DrivingProtocol,
    EnergyTerm,
    FrictionLaw,
    Integrator,
    Schedule,
    Stepper,
    StopGoDetector,
)
from softcell.core.components.hookspecs import hookimpl
from softcell.core.components.registry import registered
from softcell.core.engine.compiled import compile_module
from softcell.core.engine.model import Model
from softcell.core.engine.reference import explicit_decay_rate
from softcell.core.params import MODEL_PARAMETERS, Parameters, ParameterSpec
from softcell.core.schema import GO, PHASE_RUN, PHASE_TUMBLE, PHASE_UNKNOWN, STOP, STOPGO_UNKNOWN
from softcell.errors import CacheWarning, ContractError, ParameterError
from softcell.plugins.explicit_euler import ExplicitEulerStepper
from softcell.plugins.run_and_tumble import (
    PivotRunAndTumble,
    RunAndTumble,
    alternating_schedule,
    pivot_drive,
    run_and_tumble_drive,
)

__all__ = [
    "GO",
    "MODEL_PARAMETERS",
    "PHASE_RUN",
    "PHASE_TUMBLE",
    "PHASE_UNKNOWN",
    "STOP",
    "STOPGO_UNKNOWN",
    "CacheWarning",
    "Component",
    "ContractError",
    "DrivingProtocol",
    "EnergyTerm",
    "ExplicitEulerStepper",
    "FrictionLaw",
    "Integrator",
    "Model",
    "ParameterError",
    "ParameterSpec",
    "Parameters",
    "PivotRunAndTumble",
    "RunAndTumble",
    "Schedule",
    "Stepper",
    "StopGoDetector",
    "alternating_schedule",
    "compile_module",
    "explicit_decay_rate",
    "hookimpl",
    "pivot_drive",
    "registered",
    "run_and_tumble_drive",
]
