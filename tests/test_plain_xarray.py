"""Files read well without softcell: plain xarray and netCDF4 see text as text, a sweep's
swept parameters as coordinates with units, and every parameter as an attribute."""

from __future__ import annotations

import netCDF4
import numpy as np
import pytest
import xarray as xr

import softcell


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("plain") / "sweep"
    config = softcell.RunConfig(
        parameters={"radius": [4.0, 6.0], "duration": 2.0, "bending_stiffness": [0.3, 0.57]}
    )
    softcell.simulate(config, out, realizations=2, seed=3, progress=False)
    return out


def test_a_file_carries_its_swept_parameters_and_every_parameter(sweep):
    ds = xr.open_dataset(sorted(sweep.glob("*.nc"))[0])
    assert float(ds["radius"]) == 4.0 and ds["radius"].attrs["units"] == "cm"
    assert float(ds["bending_stiffness"]) == 0.3
    assert ds["bending_stiffness"].attrs["units"] == "N cm2"
    assert ds.attrs["parameter_radius"] == 4.0 and ds.attrs["parameter_cutoff"] == 16
    assert ds.attrs["parameter_pivot_side"] == "inner"
    assert ds.attrs["parameter_duration"] == 2.0


def test_plain_xarray_rebuilds_the_sweep_as_softcell_does(sweep):
    files = sorted(sweep.glob("*.nc"))
    stored = {f: xr.open_dataset(f) for f in files}
    key = {
        f: (float(d["radius"]), float(d["bending_stiffness"]), int(d["realization"][0]))
        for f, d in stored.items()
    }
    grid = [
        [[f for f in files if key[f] == (r, k, i)][0] for i in (0, 1)]
        for r in (4.0, 6.0)
        for k in (0.3, 0.57)
    ]
    # Nested: one list per (radius, k) point, realizations inside; the radius and k of each
    # point are its files' scalar coordinates.
    points = [xr.open_mfdataset(row, combine="nested", concat_dim="realization") for row in grid]
    plain = xr.combine_nested(
        [points[0:2], points[2:4]],
        concat_dim=["radius", "bending_stiffness"],
        combine_attrs="drop_conflicts",
    )
    ours = softcell.open_dataset(sweep)
    assert plain["radius"].values.tolist() == [4.0, 6.0]
    assert plain["bending_stiffness"].values.tolist() == [0.3, 0.57]
    assert plain["radius"].attrs["units"] == "cm"
    for name in ("membrane_x", "cell_y", "bot_phase"):
        a = plain[name].transpose(*ours[name].dims)
        np.testing.assert_array_equal(a.values, ours[name].values)
    for d in stored.values():
        d.close()


def _radius_analysis(sweep):
    one_k = softcell.open_dataset(sweep).sel(bending_stiffness=0.57)  # a radius sweep
    return softcell.analyze(one_k, {"discard": 0.5})


def test_text_reads_as_text_without_softcell(sweep, tmp_path):
    path = softcell.write_dataset(_radius_analysis(sweep), tmp_path / "analysis.nc")
    with netCDF4.Dataset(path) as nc:
        assert nc["body_label"][:].tolist() == ["cell", "bot"]  # chars decoded by _Encoding
    plain = xr.open_dataset(path)
    assert plain["body_label"].values.tolist() == ["cell", "bot"]
    assert plain["body_label"].attrs["long_name"]
    assert all(isinstance(v, str) and "lag" in v for v in plain["collapse_variant_label"].values)
    assert plain["regime"].attrs["flag_meanings"] == "unknown coupled intermediate decoupled"
    assert plain.set_index(body="body_label")["msd"].sel(body="cell").dims == ("radius", "lag")
    back = softcell.read_dataset(path)  # and softcell reads the text coordinate back
    assert back["body"].values.tolist() == ["cell", "bot"]
    plain.close()
