"""A file written by softcell passes the CF checker with no errors and no warnings."""

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softcell import write_dataset
from softcell.core.params import Parameters
from softcell.io.schema import simulation_dataset

HERE = Path(__file__).parent / "cf"


def test_cfchecks_reports_no_errors(tmp_path):
    beside = Path(sys.executable).with_name("cfchecks")
    cfchecks = str(beside) if beside.exists() else shutil.which("cfchecks")
    if cfchecks is None:
        pytest.fail("cfchecks is not installed: pip install the 'test' extra")
    import compliance_checker

    names = Path(compliance_checker.__file__).parent / "data" / "cf-standard-name-table.xml"
    rng = np.random.default_rng(0)
    ds = simulation_dataset(
        np.r_[np.arange(5) * 0.01, 0.1 + np.arange(3) * 0.1], np.arange(2),
        membrane_x=rng.normal(size=(2, 8, 64)), membrane_y=rng.normal(size=(2, 8, 64)),
        bot_x=rng.normal(size=(2, 8)), bot_y=rng.normal(size=(2, 8)),
        bot_angle=rng.normal(size=(2, 8)), bot_phase=rng.integers(0, 2, size=(2, 8)),
        parameters=Parameters({"radius": 5}), seed=11,
        components={"integrator": "explicit_euler"})
    path = write_dataset(ds, tmp_path / "sim.nc")
    run = subprocess.run([cfchecks, "-s", str(names), "-a", str(HERE / "area-type-table.xml"),
                          "-r", str(HERE / "standardized-region-list.xml"), str(path)],
                         capture_output=True, text=True, cwd=tmp_path)
    assert "ERRORS detected: 0" in run.stdout, run.stdout + run.stderr
    assert "WARNINGS given: 0" in run.stdout, run.stdout
