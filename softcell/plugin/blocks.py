"""Building blocks for plugin authors: built-in components to subclass and kernels to reuse.

Not contracts: what a component may build on. ``softcell.plugin`` holds the contracts.

Protocols
    :class:`RunAndTumble` and :class:`PivotRunAndTumble` (subclass to change only the
    schedule), their drive kernels :func:`run_and_tumble_drive` and :func:`pivot_drive`, and
    :func:`alternating_schedule`.
Integrators
    :class:`ExplicitEulerStepper` (the explicit scheme, for an integrator that only chooses
    its step) and :func:`explicit_decay_rate` (its stability bound, 1/s).
Compiling once per machine
    :func:`compile_module` runs generated source with compiled functions bound into it and
    caches its compiled functions on disk, keyed by the bound code (what the built-in
    integrators compose their loops with); :class:`CacheWarning` is what it warns with.
"""

from __future__ import annotations

from softcell.builtins.run_and_tumble import (
    PivotRunAndTumble,
    RunAndTumble,
    alternating_schedule,
    pivot_drive,
    run_and_tumble_drive,
)
from softcell.engine.compiled import compile_module
from softcell.engine.reference import explicit_decay_rate
from softcell.errors import CacheWarning
from softcell.integrators.explicit_euler import ExplicitEulerStepper

__all__ = [
    "CacheWarning",
    "ExplicitEulerStepper",
    "PivotRunAndTumble",
    "RunAndTumble",
    "alternating_schedule",
    "compile_module",
    "explicit_decay_rate",
    "pivot_drive",
    "run_and_tumble_drive",
]
