"""``softcell calibrate``: planted values come back from data simulated with them.

The data are made here with ``softcell.simulate`` (another seed than the calibration's) and
measured here, with numpy or ``softcell.analyze``, not with the calibration's own code.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import softcell
from softcell.cli import main
from softcell.model.parameters import MODEL_PARAMETERS
from softcell.paper.calibrate import calibrate_bending, calibrate_friction

F0 = MODEL_PARAMETERS["drive_force"].default
GAMMA_T = MODEL_PARAMETERS["bot_friction"].default


def _pushed_speed(folder) -> float:
    ds = softcell.open_dataset(folder)
    t = ds["time"].values
    v = np.hypot(
        np.diff(ds["cell_x"].values, axis=-1), np.diff(ds["cell_y"].values, axis=-1)
    ) / np.diff(t)
    return float(v[..., t[:-1] >= 5.0].mean())


def test_membrane_friction_comes_back_from_a_planted_push(tmp_path):
    planted, radius = 6.84e-4, 6.0
    config = softcell.RunConfig(
        parameters={"radius": radius, "duration": 15.0, "membrane_friction": planted}
    ).updated(components={"driving_protocol": "constant_push"})
    softcell.simulate(config, tmp_path / "push", realizations=1, seed=11, progress=False)
    speed = _pushed_speed(tmp_path / "push")
    # The ring slides whole: F0 = (gamma_T + gamma_mem l0) v, friction per unstretched length.
    assert speed == pytest.approx(F0 / (GAMMA_T + planted * 2 * math.pi * radius), rel=1e-3)
    found = calibrate_friction(speed, radius, push_speed_error=0.01)
    assert found.value == pytest.approx(planted, rel=0.05)
    assert found.unit == "N s cm-2"
    # A 0.01 cm/s error on 1.49 cm/s is 0.7 % of the speed, ~0.8 % of gamma_mem.
    assert 0.004 * planted < found.uncertainty < 0.02 * planted
    assert abs(found.residual[0]) < 1e-3


@pytest.mark.slow
def test_bending_stiffness_comes_back_from_planted_shape_indices(tmp_path):
    planted, radii = 0.18, [4.0, 6.0]
    config = softcell.RunConfig(
        parameters={"radius": radii, "duration": 60.0, "bending_stiffness": planted}
    )
    softcell.simulate(config, tmp_path / "cell", realizations=4, seed=5, workers=2, progress=False)
    analysis = softcell.analyze(softcell.open_dataset(tmp_path / "cell"), {"discard": 15.0})
    ipr = [float(v) for v in analysis["ipr_mean"].values]
    error = [
        float(np.std(analysis["ipr"].isel(radius=i).mean("time"), ddof=1) / 2) for i in range(2)
    ]
    found = calibrate_bending(ipr, radii, ipr_error=error, realizations=4, duration=60.0, workers=2)
    assert found.value == pytest.approx(planted, rel=0.05)
    assert 0 < found.uncertainty < 0.05 * planted
    assert found.radius == radii and len(found.residual) == 2


def test_the_command_prints_the_value_unit_and_residuals(tmp_path, capsys):
    out = tmp_path / "k.json"
    assert (
        main(
            [
                "calibrate",
                "--ipr",
                "3.5475",
                "--radius",
                "4",
                "--realizations",
                "1",
                "--duration",
                "12",
                "--settle",
                "4",
                "--quiet",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "bending_stiffness = " in text and "N cm2" in text and "residual" in text
    stored = json.loads(out.read_text())["calibrations"][0]
    assert stored["parameter"] == "bending_stiffness" and 0.05 < stored["value"] < 5
    assert abs(stored["residual"][0]) < 1e-5
    # A rerun may replace its own output; not a file it did not make.
    other = tmp_path / "notes.json"
    other.write_text("{}")
    assert main(["calibrate", "--push-speed", "2", "--radius", "8", "-o", str(other)]) == 2
    assert other.read_text() == "{}"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--push-speed", "15", "--radius", "8"], "not below the free bot's"),
        (["--push-speed", "-1", "--radius", "8"], "push speed = -1 cm s-1"),
        (["--ipr", "3.4", "--radius", "8"], "at least a circle's"),
        (["--ipr", "3.55,3.56", "--radius", "8"], "one IPR per radius"),
        (["--ipr", "3.55", "--radius", "8", "--ipr-error", "-1"], "IPR errors"),
        (["--radius", "8"], "nothing to calibrate"),
        (["--push-speed", "2", "--radius", "8,9"], "one --radius"),
        (["--push-speed", "2", "--radius", "x"], "comma-separated list"),
        (["--push-speed", "2", "--radius", "8", "--settle", "20"], "averaging window"),
        (["--push-speed", "2", "--radius", "8", "--realizations", "0"], "realizations = 0"),
    ],
)
def test_bad_requests_name_the_value(argv, message, capsys):
    assert main(["calibrate", *argv]) == 2
    assert message in capsys.readouterr().err
