"""softcell: simulate, track and analyse a soft robotic cell.

A self-propelled elliptical bot runs and tumbles inside a deformable membrane (Mohapatra,
Wery et al., "Run and tumble dynamics of a soft robotic cell"). Importing softcell is cheap:
nothing is compiled, nothing is set, and xarray is imported only when a function that needs
it is called (when xarray is already imported, the ``ds.softcell`` accessor is registered).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from softcell._version import __version__
from softcell.components.hookspecs import hookimpl
from softcell.errors import ConfigError, ParameterError, SchemaError, SoftcellError
from softcell.model.parameters import Parameters

if TYPE_CHECKING:
    from softcell.analysis import analyze
    from softcell.io.netcdf import open_dataset, read_dataset, write_dataset
    from softcell.model.configuration import RunConfig
    from softcell.paper.figures import make_figures
    from softcell.paper.reproduce import reproduce
    from softcell.runner.ensemble import simulate
    from softcell.schema import validate
    from softcell.video.render import render
    from softcell.video.track import track

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
    "validate": "softcell.schema",
    "analyze": "softcell.analysis",
    "simulate": "softcell.runner.ensemble",
    "RunConfig": "softcell.model.configuration",
    "reproduce": "softcell.paper.reproduce",
    "make_figures": "softcell.paper.figures",
    "render": "softcell.video.render",
    "track": "softcell.video.track",
}

if "xarray" in __import__("sys").modules:  # register ds.softcell now; else when softcell
    import softcell.analysis.accessor  # noqa: F401  first opens or writes a Dataset


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'softcell' has no attribute {name!r}")
