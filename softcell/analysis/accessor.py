"""The ``ds.softcell`` accessor: the analysis, one line at a time, in an xarray session.

Registered when softcell opens or writes a Dataset, when :mod:`softcell.analysis` is
imported, and by ``import softcell`` if xarray is already imported::

    >>> import xarray as xr, softcell
    >>> ds = softcell.open_dataset("results/quick")        # doctest: +SKIP
    >>> ds.softcell.msd("cell").plot(x="lag", xscale="log", yscale="log")   # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

import xarray as xr


@xr.register_dataset_accessor("softcell")
class SoftcellAccessor:
    """Analysis methods on a softcell Dataset (simulated or tracked); results in cm and s.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset the accessor is reached from (``ds.softcell``); xarray passes it.
    """

    def __init__(self, ds: xr.Dataset) -> None:
        self._ds = ds
        self._cache: dict[str, xr.Dataset] = {}

    def validate(self) -> xr.Dataset:
        """The Dataset itself if it follows the schema; else a SchemaError naming every
        problem."""
        from softcell.schema import validate

        return validate(self._ds)

    def analyze(self, **options: Any) -> xr.Dataset:
        """The full analysis Dataset (see :func:`softcell.analyze`); options as
        keyword arguments, e.g. ``discard=15, threshold=0.03``."""
        from softcell.analysis.sweep import analyze

        key = repr(sorted(options.items()))
        if key not in self._cache:
            self._cache[key] = analyze(self._ds, options)
        return self._cache[key]

    def msd(self, body: str = "cell", **options: Any) -> xr.DataArray:
        """Ensemble MSD (cm^2) of a body against ``lag`` (s).

        Parameters
        ----------
        body : str
            'cell' (the membrane's GC) or 'bot'.
        **options
            Analysis options, as for :meth:`analyze`.
        """
        return self._body(self.analyze(**options)["msd"], body)

    def speed(self, body: str = "cell") -> xr.DataArray:
        """Speed (cm/s) of a body per sample: forward difference within a sampling segment;
        NaN at the last sample.

        Parameters
        ----------
        body : str
            'cell' (the membrane's GC) or 'bot'.
        """
        from softcell.analysis.series import speed

        # Time last (an assembly stores its cell dim after time).
        x = self._ds[f"{self._check(body)}_x"].transpose(..., "time")
        y = self._ds[f"{body}_y"].transpose(..., "time")
        values = speed(x.values, y.values, self._ds["time"].values)
        return xr.DataArray(
            values,
            dims=x.dims,
            coords=x.coords,
            name=f"{body}_speed",
            attrs={"units": "cm s-1", "long_name": f"{body} speed"},
        ).transpose(*self._ds[f"{body}_x"].dims)

    def ipr(self) -> xr.DataArray:
        """Shape index P / sqrt(A) of the membrane per sample (2 sqrt(pi) for a circle): of
        the smooth curve through a simulation's nodes, of the polygon of a tracked contour."""
        from softcell.analysis.series import shape_index

        mx = self._ds["membrane_x"]
        smooth = self._ds.attrs.get("softcell_origin", "simulation") == "simulation"
        values = shape_index(mx.values, self._ds["membrane_y"].values, band_limited=smooth)
        dims = mx.dims[:-1]
        return xr.DataArray(
            values,
            dims=dims,
            coords={d: mx[d] for d in dims if d in mx.coords},
            name="ipr",
            attrs={"units": "1", "long_name": "shape index"},
        )

    def geometric_center(self, method: str = "mean") -> tuple[xr.DataArray, xr.DataArray]:
        """The membrane's GC (cm), x and y.

        Parameters
        ----------
        method : str
            ``"mean"`` of the points (simulations) or the area ``"centroid"`` of the contour
            (videos).
        """
        from softcell.analysis.series import polygon_area_perimeter_centroid

        mx, my = self._ds["membrane_x"], self._ds["membrane_y"]
        if method == "mean":
            return mx.mean("node"), my.mean("node")
        if method == "centroid":
            _, _, cx, cy = polygon_area_perimeter_centroid(mx.values, my.values)
            dims = mx.dims[:-1]
            coords = {d: mx[d] for d in dims if d in mx.coords}
            attrs = {"units": "cm", "long_name": "membrane area centroid"}
            return (
                xr.DataArray(cx, dims=dims, coords=coords, attrs=attrs),
                xr.DataArray(cy, dims=dims, coords=coords, attrs=attrs),
            )
        raise ValueError(f"method = {method!r} is not allowed: must be 'mean' or 'centroid'")

    def _check(self, body: str) -> str:
        if body not in ("cell", "bot"):
            raise ValueError(f"body = {body!r} is not allowed: must be 'cell' or 'bot'")
        return body

    def _body(self, da: xr.DataArray, body: str) -> xr.DataArray:
        return da.sel(body=self._check(body))
