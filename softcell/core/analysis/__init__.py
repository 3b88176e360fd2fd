"""Analysis of simulated and tracked Datasets (SPEC section 6): MSD, fits, stop/go, theory,
shape index, regimes and scaling collapse. Entry point: :func:`analyze`; in an xarray
session, the ``ds.softcell`` accessor."""

from softcell.core.analysis import accessor as _accessor  # noqa: F401  (registers ds.softcell)
from softcell.core.analysis.pipeline import analyze

__all__ = ["analyze"]
