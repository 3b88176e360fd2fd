"""A file written by softcell passes the CF checker with no errors and no warnings."""

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import softcell
from softcell import write_dataset
from softcell.analysis import analyze
from softcell.io.netcdf import combine_sweep
from softcell.model.parameters import Parameters
from softcell.schema import simulation_dataset
from softcell.testing.synthetic import stop_and_go_dataset

HERE = Path(__file__).parent / "cf"


def cfchecks(path):
    """Run the CF checker offline on ``path``; return its report."""
    beside = Path(sys.executable).with_name("cfchecks")
    program = str(beside) if beside.exists() else shutil.which("cfchecks")
    if program is None:
        pytest.fail("cfchecks is not installed: pip install the 'test' extra")
    import compliance_checker

    names = Path(compliance_checker.__file__).parent / "data" / "cf-standard-name-table.xml"
    run = subprocess.run(
        [
            program,
            "-s",
            str(names),
            "-a",
            str(HERE / "area-type-table.xml"),
            "-r",
            str(HERE / "standardized-region-list.xml"),
            str(path),
        ],
        capture_output=True,
        text=True,
        cwd=path.parent,
    )
    return run.stdout + run.stderr


def test_cfchecks_reports_no_errors(tmp_path):
    rng = np.random.default_rng(0)
    ds = simulation_dataset(
        np.r_[np.arange(5) * 0.01, 0.1 + np.arange(3) * 0.1],
        np.arange(2),
        membrane_x=rng.normal(size=(2, 8, 64)),
        membrane_y=rng.normal(size=(2, 8, 64)),
        bot_x=rng.normal(size=(2, 8)),
        bot_y=rng.normal(size=(2, 8)),
        bot_angle=rng.normal(size=(2, 8)),
        bot_phase=rng.integers(0, 2, size=(2, 8)),
        parameters=Parameters({"radius": 5}),
        seed=11,
        components={"integrator": "explicit_euler"},
    )
    report = cfchecks(write_dataset(ds, tmp_path / "sim.nc"))
    assert "ERRORS detected: 0" in report and "WARNINGS given: 0" in report, report


def _analysis_of_a_sweep():
    rng = np.random.default_rng(1)
    parts = []
    for radius in (8.0, 10.0):
        ds = stop_and_go_dataset(
            rng,
            0.01 * np.arange(2000),
            realizations=2,
            speed=1.0,
            mean_go=0.3,
            mean_stop=0.3,
            radius=radius,
        )
        parts.extend(ds.isel(realization=[r]).assign_coords(realization=[r]) for r in (0, 1))
    sweep = combine_sweep(parts)
    assert sweep.sizes["radius"] == 2
    return analyze(sweep, {"discard": 1.0})


def test_analysis_file_passes_cfchecks_and_reads_back(tmp_path):
    written = write_dataset(_analysis_of_a_sweep(), tmp_path / "analysis.nc")
    report = cfchecks(written)
    assert "ERRORS detected: 0" in report and "WARNINGS given: 0" in report, report
    back = softcell.open_dataset(written)
    assert list(back.body.values) == ["cell", "bot"]
    assert back.msd.sel(body="cell").dims == ("radius", "lag")
    for name, var in back.variables.items():
        if var.dtype.kind != "S" and name not in ("body", "collapse_variant"):
            assert "units" in var.attrs and "long_name" in var.attrs, name
    assert '"discard": 1.0' in back.attrs["softcell_analysis_options"]


@pytest.mark.xfail(
    strict=True,
    reason="cfchecker 4.1.0, the newest, rejects every netCDF-4 "
    "string variable (measured: 2 errors on an analysis file, code 2.2, 'vlen "
    "types not supported'), so text stays in CF character arrays",
)
def test_netcdf4_string_labels_would_pass_cfchecks(tmp_path, monkeypatch):
    import netCDF4

    import softcell.io.netcdf as netcdf

    monkeypatch.setattr(netcdf, "TEXT_ENCODING", str)
    written = write_dataset(_analysis_of_a_sweep(), tmp_path / "strings.nc")
    with netCDF4.Dataset(written) as nc:
        assert nc["body_label"].dtype is str  # netCDF-4 strings were written
    report = cfchecks(written)
    assert "ERRORS detected: 0" in report, report
