"""Analysis of simulated and tracked Datasets (docs/model.md §6): MSD, fits, stop/go, theory,
shape index, regimes and scaling collapse. Entry point: :func:`analyze`; in an xarray
session, the ``ds.softcell`` accessor.

Importing this package registers the accessor only; the pipeline (numba, pyfftw, scipy) is
imported when :func:`analyze` is first used.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from softcell.analysis import accessor as _accessor  # noqa: F401  (registers ds.softcell)

if TYPE_CHECKING:
    from softcell.analysis.sweep import analyze

__all__ = ["analyze"]


def __getattr__(name: str) -> Any:
    if name == "analyze":
        from softcell.analysis.sweep import analyze

        return analyze
    raise AttributeError(f"module 'softcell.analysis' has no attribute {name!r}")
