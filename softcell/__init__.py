"""softcell: simulate, track and analyse a soft robotic cell.

A self-propelled elliptical bot runs and tumbles inside a deformable membrane (Mohapatra,
Wery et al., "Run and tumble dynamics of a soft robotic cell"). Importing softcell is cheap:
nothing is compiled and xarray is imported only when a function that needs it is called.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from softcell._version import __version__
from softcell.config import use_module_store
from softcell.core.components.hookspecs import hookimpl
from softcell.core.params import Parameters
from softcell.errors import ConfigError, ParameterError, SchemaError, SoftcellError
from softcell.io.model_cache import DiskStore

# The composed models are kept in the disk cache (core, which writes no file, is handed it).
use_module_store(DiskStore())

if TYPE_CHECKING:
    from softcell.core.analysis import analyze
    from softcell.core.runconfig import RunConfig
    from softcell.core.schema import validate
    from softcell.io.figures import make_figures
    from softcell.io.netcdf import open_dataset, read_dataset, write_dataset
    from softcell.io.render import render
    from softcell.io.video import track
    from softcell.workflows.ensemble import simulate
    from softcell.workflows.reproduce import reproduce

__all__ = [
    "ConfigError",
    "ParameterError",
    "Parameters",
    "RunConfig",
    "SchemaError",
    "SoftcellError",
    "__version__",
    "analyze",
    "hookimpl",
    "make_figures",
    "open_dataset",
    "read_dataset",
    "render",
    "reproduce",
    "simulate",
    "track",
    "validate",
    "write_dataset",
]

_LAZY = {
    "open_dataset": "softcell.io.netcdf",
    "read_dataset": "softcell.io.netcdf",
    "write_dataset": "softcell.io.netcdf",
    "validate": "softcell.core.schema",
    "analyze": "softcell.core.analysis",
    "simulate": "softcell.workflows.ensemble",
    "RunConfig": "softcell.core.runconfig",
    "reproduce": "softcell.workflows.reproduce",
    "make_figures": "softcell.io.figures",
    "render": "softcell.io.render",
    "track": "softcell.io.video",
}

if "xarray" in __import__("sys").modules:  # register ds.softcell now; else when softcell
    import softcell.core.analysis.accessor  # noqa: F401  first opens or writes a Dataset


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'softcell' has no attribute {name!r}")
