"""The engine: the compiled model of a parameter point, the state of a realization, and the
model evaluated with numpy for checks."""

from softcell.components.contracts import Stepper
from softcell.engine.compose import (
    HESSIAN_ARGS,
    PARTIALS_ARGS,
    compose_hessians,
    compose_partials,
    fd_drive_jacobian,
    fd_hessian,
)
from softcell.engine.model import Model, build_integrator, build_model
from softcell.engine.reference import (
    explicit_decay_rate,
    force_modes,
    membrane_jacobian,
    total_energy,
)
from softcell.engine.state import (
    Record,
    check_state,
    circle_modes,
    equilibrium_radius,
    fine_times,
    initial_state,
    membrane_length,
    phase_at,
    sample_times,
    sampling_plan,
)
from softcell.errors import SimulationError

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
