"""NetCDF I/O: round trips, atomic writes, byte-identical output, sweeps as one Dataset."""

import json

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings

from softcell import open_dataset, read_dataset, validate, write_dataset
from softcell.errors import SchemaError, SoftcellError
from softcell.io.netcdf import combine_sweep
from softcell.model.parameters import Parameters
from softcell.schema import problems, simulation_dataset
from softcell.testing.strategies import simulation_datasets


@settings(max_examples=40)
@given(simulation_datasets())
def test_round_trip_is_identical(tmp_path_factory, ds):
    path = tmp_path_factory.mktemp("rt") / "sim.nc"
    write_dataset(ds, path)
    back = read_dataset(path)
    xr.testing.assert_identical(back, ds)
    validate(back)


def _dataset(radius=4.0, realization=0, n_time=6, seed=3):
    rng = np.random.default_rng(realization)
    shape = (1, n_time)
    return simulation_dataset(
        np.arange(n_time) * 0.01,
        np.array([realization]),
        membrane_x=rng.normal(size=(*shape, 40)),
        membrane_y=rng.normal(size=(*shape, 40)),
        bot_x=rng.normal(size=shape),
        bot_y=rng.normal(size=shape),
        bot_angle=rng.normal(size=shape),
        bot_phase=rng.integers(0, 2, size=shape),
        parameters=Parameters({"radius": radius}),
        seed=seed,
        components={"integrator": "x"},
    )


def test_same_dataset_gives_same_bytes(tmp_path):
    a, b = tmp_path / "a.nc", tmp_path / "b.nc"
    write_dataset(_dataset(), a)
    write_dataset(_dataset(), b)
    assert a.read_bytes() == b.read_bytes()


def test_failed_write_leaves_nothing_under_the_final_name(tmp_path):
    ds = _dataset()
    ds.attrs["bad"] = {"a dict": "cannot be a netCDF attribute"}
    target = tmp_path / "out.nc"
    with pytest.raises(Exception):  # noqa: B017 - whatever netCDF4 raises
        write_dataset(ds, target)
    assert not target.exists()
    assert list(tmp_path.iterdir()) == []


def test_validate_names_every_problem():
    ds = _dataset().drop_vars("bot_x")
    ds["bot_y"].attrs["units"] = "m"
    del ds["cell_x"].attrs["long_name"]
    ds["bot_angle"] = ds["bot_angle"].transpose("time", "realization")
    del ds.attrs["softcell_seed"]
    found = problems(ds)
    for needle in (
        "bot_x: missing",
        "bot_y: units 'm'",
        "cell_x: attribute 'long_name'",
        "bot_angle: dims",
        "softcell_seed",
    ):
        assert any(needle in p for p in found), (needle, found)
    with pytest.raises(SchemaError, match="bot_x: missing"):
        validate(ds)


def test_bot_phase_carries_cf_flags():
    phase = _dataset()["bot_phase"]
    assert phase.attrs["flag_meanings"] == "unknown tumble run"
    assert phase.attrs["flag_values"].tolist() == [-1, 0, 1]
    assert phase.dtype == np.int8


def test_directory_of_a_sweep_opens_as_one_dataset(tmp_path):
    for radius in (4.0, 8.0):
        for realization in (0, 1):
            n_time = 6 if radius == 4.0 else 9
            write_dataset(
                _dataset(radius, realization, n_time), tmp_path / f"r{radius}_{realization}.nc"
            )
    (tmp_path / ".half-written.nc.123.tmp").write_bytes(b"garbage")
    ds = open_dataset(tmp_path)
    assert ds.sizes == {"radius": 2, "realization": 2, "time": 9, "node": 40}
    assert ds["radius"].values.tolist() == [4.0, 8.0]
    assert ds["radius"].attrs["units"] == "cm"
    assert json.loads(ds.attrs["softcell_parameters"])["radius"] == [4.0, 8.0]
    # The shorter record is padded: NaN for positions, "unknown" for the phase.
    assert np.isnan(ds["bot_x"].sel(radius=4.0).values[:, 6:]).all()
    assert (ds["bot_phase"].sel(radius=4.0).values[:, 6:] == -1).all()
    assert ds["bot_phase"].dtype == np.int8
    single = read_dataset(tmp_path / "r8.0_1.nc")
    xr.testing.assert_equal(
        ds["bot_x"].sel(radius=8.0, realization=1), single["bot_x"].isel(realization=0)
    )
    assert not problems(ds)


def test_files_that_are_not_one_sweep_are_refused(tmp_path):
    with pytest.raises(SoftcellError, match="no .nc files"):
        open_dataset(tmp_path)
    with pytest.raises(SoftcellError, match="no such file"):
        open_dataset(tmp_path / "missing.nc")
    a, b = _dataset(realization=0), _dataset(realization=0)
    with pytest.raises(SoftcellError, match="one sweep"):
        combine_sweep([a, b])


def test_a_directory_is_no_file_name(tmp_path):
    with pytest.raises(SoftcellError, match="is a directory"):
        write_dataset(_dataset(), tmp_path)
    assert list(tmp_path.iterdir()) == []
