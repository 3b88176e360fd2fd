"""The engine: the compiled model of a parameter point, the state of a realization, one
cell's loop and many cells' groups, and the model evaluated with numpy for checks.

The names below are imported on first use, so that a module of the engine (the kernels, the
signal handling) is imported without compiling anything.
"""

from __future__ import annotations

import importlib
from typing import Any

#: Where each public name of the engine lives.
_WHERE = {
    "Stepper": "softcell.components.contracts",
    "HESSIAN_ARGS": "softcell.engine.compose",
    "PARTIALS_ARGS": "softcell.engine.compose",
    "compose_hessians": "softcell.engine.compose",
    "compose_partials": "softcell.engine.compose",
    "fd_drive_jacobian": "softcell.engine.compose",
    "fd_hessian": "softcell.engine.compose",
    "Model": "softcell.engine.model",
    "build_integrator": "softcell.engine.model",
    "build_model": "softcell.engine.model",
    "explicit_decay_rate": "softcell.engine.reference",
    "force_modes": "softcell.engine.reference",
    "membrane_jacobian": "softcell.engine.reference",
    "total_energy": "softcell.engine.reference",
    "Record": "softcell.engine.state",
    "check_state": "softcell.engine.state",
    "circle_modes": "softcell.engine.state",
    "equilibrium_radius": "softcell.engine.state",
    "fine_times": "softcell.engine.state",
    "initial_state": "softcell.engine.state",
    "membrane_length": "softcell.engine.state",
    "phase_at": "softcell.engine.state",
    "sample_times": "softcell.engine.state",
    "sampling_plan": "softcell.engine.state",
    "SimulationError": "softcell.errors",
}

__all__ = [
    "HESSIAN_ARGS",
    "PARTIALS_ARGS",
    "Model",
    "Record",
    "SimulationError",
    "Stepper",
    "build_integrator",
    "build_model",
    "check_state",
    "circle_modes",
    "compose_hessians",
    "compose_partials",
    "equilibrium_radius",
    "explicit_decay_rate",
    "fd_drive_jacobian",
    "fd_hessian",
    "force_modes",
    "initial_state",
    "membrane_jacobian",
    "membrane_length",
    "phase_at",
    "fine_times",
    "sample_times",
    "sampling_plan",
    "total_energy",
]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(f"module 'softcell.engine' has no attribute {name!r}")
