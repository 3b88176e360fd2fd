"""Everything a plugin author implements against, from one module.

A plugin is a module with functions named after the hooks (``softcell_energy_terms``,
``softcell_driving_protocols``, ``softcell_friction_laws``, ``softcell_integrators``,
``softcell_stopgo_detectors``, ``softcell_pair_terms``, ``softcell_bot_interactions``),
each marked with :data:`hookimpl`
and returning a list of component classes, registered under the entry-point group
``softcell``. ``docs/plugins.md`` is the tutorial; the names below are the public interface,
and everything else in softcell is private and may move.

Contracts (subclass one per component)
    :class:`EnergyTerm`, :class:`DrivingProtocol`, :class:`FrictionLaw`, :class:`Integrator`,
    :class:`StopGoDetector`, :class:`PairTerm` (how two cells' membranes meet),
    :class:`BotInteraction` (how two bots in one ring meet), their base
    :class:`Component`; what an integrator returns:
    :class:`Stepper`; what a protocol draws: :class:`Schedule`; what its event kernel senses:
    :class:`Sense`; what an integrator composes: :class:`Model`.
Parameters
    :class:`ParameterSpec` declares one (default, unit, range); :data:`MODEL_PARAMETERS`
    holds the model's own, to reuse by listing them; :class:`Parameters` is what a component
    receives as ``self.params``; :class:`ParameterError` is the error for a bad value, and
    :class:`ContractError` what a component that breaks its contract raises.
Codes
    :data:`PHASE_RUN`, :data:`PHASE_TUMBLE`, :data:`PHASE_UNKNOWN` (``bot_phase``);
    :data:`GO`, :data:`STOP`, :data:`STOPGO_UNKNOWN` (stop/go labels).
Registration
    :data:`hookimpl` marks a hook; :func:`registered` registers plugin modules for the
    duration of a ``with`` block (for tests).

Building blocks (built-in protocols and kernels to reuse, the explicit stepper, the compiled
module loader) are in :mod:`softcell.plugin.blocks`; the checks of a component against its
contract, for a plugin's tests, in ``softcell.testing``.
"""

from __future__ import annotations

import warnings
from typing import Any

from softcell.components.contracts import (
    BotInteraction,
    Component,
    DrivingProtocol,
    EnergyTerm,
    FrictionLaw,
    Integrator,
    PairTerm,
    Schedule,
    Sense,
    Stepper,
    StopGoDetector,
)
from softcell.components.hookspecs import hookimpl
from softcell.components.registry import registered
from softcell.engine.model import Model
from softcell.errors import ContractError, ParameterError
from softcell.model.parameters import MODEL_PARAMETERS, Parameters, ParameterSpec
from softcell.plugin import blocks
from softcell.schema import GO, PHASE_RUN, PHASE_TUMBLE, PHASE_UNKNOWN, STOP, STOPGO_UNKNOWN

__all__ = [
    "GO",
    "MODEL_PARAMETERS",
    "PHASE_RUN",
    "PHASE_TUMBLE",
    "PHASE_UNKNOWN",
    "STOP",
    "STOPGO_UNKNOWN",
    "BotInteraction",
    "Component",
    "ContractError",
    "DrivingProtocol",
    "EnergyTerm",
    "FrictionLaw",
    "Integrator",
    "Model",
    "PairTerm",
    "ParameterError",
    "ParameterSpec",
    "Parameters",
    "Schedule",
    "Sense",
    "Stepper",
    "StopGoDetector",
    "hookimpl",
    "registered",
]

#: Names that were here in softcell 0.2 and moved to :mod:`softcell.plugin.blocks` in 0.3;
#: importing them from here still works, with a DeprecationWarning, until 0.4.
MOVED = tuple(blocks.__all__)


def __getattr__(name: str) -> Any:
    if name in MOVED:
        warnings.warn(
            f"softcell.plugin.{name} moved to softcell.plugin.blocks in softcell 0.3; "
            "import it from there (the old place works until 0.4)",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(blocks, name)
    raise AttributeError(f"module 'softcell.plugin' has no attribute {name!r}")
