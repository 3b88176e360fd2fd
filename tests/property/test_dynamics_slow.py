"""Long explicit-Euler runs (minutes each): the pushed cell and the two regimes
(docs/model.md §3, §6)."""

import numpy as np
import pytest

import softcell
from softcell.components.registry import default_registry
from softcell.engine import build_integrator, build_model, membrane_length
from softcell.engine.cell import realization_rng, run_realization
from softcell.model.configuration import RunConfig
from softcell.model.parameters import Parameters
from softcell.runner.ensemble import simulate

pytestmark = pytest.mark.slow


def run(radius, protocol, duration, seed=0):
    params = Parameters({"radius": radius, "duration": duration})
    model = build_model(
        params, ["bending", "tension", "contact"], protocol, registry=default_registry()
    )
    stepper = build_integrator("explicit_euler", params, default_registry()).build(model)
    record = run_realization(model, stepper, realization_rng(seed, 0, 0))
    cell = record.modes[:, model.cutoff]
    bot = record.pose[:, 0] + 1j * record.pose[:, 1]
    speed = np.abs(np.diff(cell)) / np.diff(record.times)
    lengths = np.array([membrane_length(g) for g in record.modes])
    return params, cell, bot, speed, lengths


def test_constant_push_moves_the_cell_at_the_calibration_speed():
    params, cell, bot, speed, lengths = run(4.0, "constant_push", 0.6)
    expected = params.drive_force / (
        params.bot_friction + params.membrane_friction * params.membrane_length
    )
    assert speed[-20:].mean() == pytest.approx(expected, rel=0.02)
    assert np.abs(lengths / lengths[0] - 1).max() < 1e-3  # within 0.1 % while pushing


@pytest.fixture(scope="module")
def regimes(tmp_path_factory):
    """Five realizations of 4 s at R = 4 and 12 cm (root seed 0), with their measures.

    One 4 s run is not enough at R = 12 cm: the cell moves only while the bot presses on it,
    and whether the bot reaches the membrane in 4 s depends on the draw (single runs, root
    seeds 0-4, gave mean cell speeds 0.30, 0.18, 0.41, 0.00, 0.07 cm/s).
    """
    out = tmp_path_factory.mktemp("regimes")
    config = RunConfig(parameters={"radius": [4.0, 12.0], "duration": 4.0})
    simulate(config, out, realizations=5, seed=0, workers=2, progress=False)
    ds = softcell.open_dataset(out).load()
    assert list(ds["radius"].values) == [4.0, 12.0]
    dt = np.diff(ds["time"].values)
    cell = ds["cell_x"] + 1j * ds["cell_y"]
    bot = ds["bot_x"] + 1j * ds["bot_y"]
    speed = (np.abs(np.diff(cell.values, axis=-1)) / dt).mean(axis=(1, 2))
    distance = np.abs(cell - bot).mean(("realization", "time")).values
    return (
        ds,
        dict(zip((4.0, 12.0), speed, strict=True)),
        dict(zip((4.0, 12.0), distance, strict=True)),
    )


def test_coupled_at_4(regimes):
    _, speed, distance = regimes
    assert speed[4.0] >= 1.0 and distance[4.0] <= 0.35 * 4.0, (speed, distance)


def test_decoupled_distance_at_12(regimes):
    _, speed, distance = regimes
    assert distance[12.0] >= 0.5 * 12.0, (speed, distance)


@pytest.mark.xfail(
    strict=True,
    reason=(
        "open: over 5 realizations of 4 s (root seed 0) the mean cell speed at R = 12 cm is "
        "0.337 cm/s against the target <= 0.2 (GC distance 0.72 R passes). The cell moves at "
        "F_contact / (gamma_mem l0) ~ 1-1.5 cm/s whenever the bot presses on it, so the 4 s mean "
        "is set by the contact fraction, which varies from 0 to ~40 % between draws; the "
        "prototype's "
        "0.07 cm/s matches our single run at root seed 4 (0.073 cm/s, 0.59 R). Longer runs do not "
        "bring it under 0.2 either: softcell reproduce --quick (5 realizations x 225 s after the "
        "discard, seed 0) measures 0.265 cm/s at R = 12 cm."
    ),
)
def test_decoupled_speed_at_12(regimes):
    _, speed, distance = regimes
    assert speed[12.0] <= 0.2, (speed, distance)


def test_length_within_a_tenth_of_a_percent(regimes):
    ds = regimes[0]
    # Length from the stored nodes' Fourier series (64 nodes > 2 cutoff: exact), evaluated on
    # 1024 points; within 0.1 % of its initial value (docs/model.md §3).
    z = (ds["membrane_x"] + 1j * ds["membrane_y"]).values
    nodes = z.shape[-1]
    k = np.fft.fftfreq(nodes, 1 / nodes)
    dz = np.fft.fft(z, axis=-1) / nodes * 1j * k
    fine = np.zeros(z.shape[:-1] + (1024,), dtype=complex)
    fine[..., : nodes // 2] = dz[..., : nodes // 2]
    fine[..., -(nodes // 2) :] = dz[..., nodes // 2 :]
    length = 2 * np.pi * np.abs(np.fft.ifft(fine, axis=-1) * 1024).mean(-1)
    assert np.abs(length / length[..., :1] - 1).max() < 1e-3
