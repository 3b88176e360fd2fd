"""Long explicit-Euler runs (minutes each): the pushed cell and the two regimes (SPEC 3, 6)."""

import numpy as np
import pytest

from softcell.core.engine import build_integrator, build_model, membrane_length
from softcell.core.ensemble import realization_rng, run_realization
from softcell.core.params import Parameters

pytestmark = pytest.mark.slow


def run(radius, protocol, duration, seed=0):
    params = Parameters({"radius": radius, "duration": duration})
    model = build_model(params, ["bending", "tension", "contact"], protocol)
    stepper = build_integrator("explicit_euler", params).build(model)
    record = run_realization(model, stepper, realization_rng(seed, 0, 0))
    cell = record.modes[:, model.cutoff]
    bot = record.pose[:, 0] + 1j * record.pose[:, 1]
    speed = np.abs(np.diff(cell)) / np.diff(record.times)
    lengths = np.array([membrane_length(g) for g in record.modes])
    return params, cell, bot, speed, lengths


def test_constant_push_moves_the_cell_at_the_calibration_speed():
    params, cell, bot, speed, lengths = run(4.0, "constant_push", 0.6)
    expected = params.drive_force / (params.bot_friction
                                     + params.membrane_friction * params.membrane_length)
    assert speed[-20:].mean() == pytest.approx(expected, rel=0.02)
    assert np.abs(lengths / lengths[0] - 1).max() < 1e-3  # within 0.1 % while pushing


@pytest.mark.parametrize("radius", [
    4.0,
    pytest.param(12.0, marks=pytest.mark.xfail(strict=True, reason=(
        "open (issue 3): at R = 12 cm one 4 s run gave mean cell speed 0.30 cm/s (target "
        "<= 0.2; the prototype saw ~0.07) with GC distance 0.72 R (target >= 0.5 R)"))),
])
def test_regimes_coupled_at_4_decoupled_at_12(radius):
    params, cell, bot, speed, lengths = run(radius, "run_and_tumble", 4.0)
    distance = np.abs(cell - bot).mean()
    if radius == 4.0:
        assert speed.mean() >= 1.0 and distance <= 0.35 * radius
    else:
        assert speed.mean() <= 0.2 and distance >= 0.5 * radius
    assert np.abs(lengths / lengths[0] - 1).max() < 1e-3
