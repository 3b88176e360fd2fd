"""The locomotion strategies (docs/strategies.md): graspion, chiral, active_brownian, each
against closed-form kinematics of the free bot and its renewal or diffusion law."""

import numpy as np
import pytest

from softcell.components.registry import default_registry
from softcell.engine import build_integrator, build_model
from softcell.engine.free_bot import diffusion_from_cycles, firmware_diffusion
from softcell.engine.state import initial_state
from softcell.errors import ParameterError
from softcell.model.parameters import Parameters

REGISTRY = default_registry()


def free_bot(protocol, integrator="rodas4", **values):
    specs = [
        *REGISTRY.get("driving_protocol", protocol).parameters,
        *REGISTRY.get("integrator", integrator).parameters,
    ]
    params = Parameters(values, specs)
    model = build_model(params, [], protocol, membrane=False, registry=REGISTRY)
    return params, model, build_integrator(integrator, params, REGISTRY).build(model)


def poses_at_switches(model, stepper, seed):
    """The bot's pose at t = 0 and at every phase start after it, and the schedule."""
    modes, pose, schedule = initial_state(model, np.random.default_rng(seed))
    state = stepper.start(modes, pose, schedule)
    _, poses = stepper.sample(state, schedule, schedule.start[1:])
    return np.vstack([pose, poses]), schedule


def test_graspion_phases_last_integer_milliseconds_within_the_firmware_bounds():
    params, model, _ = free_bot("graspion", duration=500.0)
    schedule = model.protocol.schedule(np.random.default_rng(0), 500.0)
    ms = np.diff(schedule.start) * 1000
    assert np.allclose(ms, np.rint(ms), atol=1e-6)
    assert ms.min() >= 400 - 1e-6 and ms.max() <= 1200 + 1e-6
    # Every integer from 400 to 1200 is possible: 801 values, so a 600-phase sample spans.
    assert ms.max() - ms.min() > 700


def test_graspion_tumbles_pivot_about_the_wheel_of_its_direction():
    params, model, stepper = free_bot("graspion", duration=60.0)
    poses, schedule = poses_at_switches(model, stepper, 1)
    v = params.drive_force / params.bot_friction
    z = poses[:, 0] + 1j * poses[:, 1]
    tau = np.diff(schedule.start)
    for k in range(len(tau)):
        start_heading, turn = poses[k, 2], poses[k + 1, 2] - poses[k, 2]
        move = (z[k + 1] - z[k]) * np.exp(-1j * start_heading)  # in the heading's frame
        if schedule.phase[k] == 1:
            assert move == pytest.approx(v * tau[k], abs=1e-6)
            assert turn == pytest.approx(0.0, abs=1e-9)
            continue
        s = schedule.data[k]
        d = params.pivot_ccw if s > 0 else params.pivot_cw
        phi = s * params.turn_rate * tau[k]
        assert turn == pytest.approx(phi, abs=1e-6)
        # The pivot is on the inner side: s d along the left normal.
        assert move == pytest.approx(s * d * 1j * (1 - np.exp(1j * phi)), abs=1e-6)


def test_firmware_renewal_formula_against_exact_cycles():
    params = Parameters({}, REGISTRY.get("driving_protocol", "graspion").parameters)
    v = params.drive_force / params.bot_friction
    durations = np.arange(400, 1201) / 1000
    formula = firmware_diffusion(v, params.turn_rate, durations, params.pivot_ccw, params.pivot_cw)
    rng = np.random.default_rng(5)
    n = 10**6
    run, tumble = rng.choice(durations, n), rng.choice(durations, n)
    sign = rng.choice(np.array([-1.0, 1.0]), n)
    phi = sign * params.turn_rate * tumble
    body = v * run + sign * np.where(sign > 0, params.pivot_ccw, params.pivot_cw) * 1j * (
        1 - np.exp(1j * phi)
    )
    heading = np.concatenate([[0.0], np.cumsum(phi)[:-1]])
    # Turns anticorrelate strongly (<cos phi> = -0.66): the sum needs ~40 lags.
    sampled = diffusion_from_cycles(np.exp(1j * heading) * body, run + tumble, lags=40)
    assert sampled == pytest.approx(formula, rel=0.02)
    assert formula == pytest.approx(9.515, abs=1e-3)


def test_chiral_runs_curve_on_circles_of_radius_v_over_omega():
    params, model, stepper = free_bot("chiral", duration=30.0)
    poses, schedule = poses_at_switches(model, stepper, 2)
    v = params.drive_force / params.bot_friction
    omega_c = params.chiral_torque / params.bot_rotational_friction
    z = poses[:, 0] + 1j * poses[:, 1]
    runs = np.flatnonzero(schedule.phase[:-1] == 1)
    assert runs.size > 5
    for k in runs:
        tau = schedule.start[k + 1] - schedule.start[k]
        assert poses[k + 1, 2] - poses[k, 2] == pytest.approx(omega_c * tau, abs=1e-6)
        chord = (v / omega_c) * (np.exp(1j * omega_c * tau) - 1) / 1j
        assert (z[k + 1] - z[k]) * np.exp(-1j * poses[k, 2]) == pytest.approx(chord, abs=1e-5)


def test_active_brownian_heading_msd_is_2_dr_tau():
    dr, dt = 0.7, 0.05
    params, model, stepper = free_bot(
        "active_brownian", duration=4000.0, rotational_diffusion=dr, noise_interval=dt
    )
    modes, pose, schedule = initial_state(model, np.random.default_rng(4))
    state = stepper.start(modes, pose, schedule)
    times = np.arange(1, 40001) * 0.1
    _, poses = stepper.sample(state, schedule, times)
    heading = np.concatenate([[pose[2]], poses[:, 2]])
    for lag_s in (0.5, 2.0, 10.0):
        lag = round(lag_s / 0.1)
        jumps = heading[lag:] - heading[:-lag]
        # Non-overlapping windows are independent Gaussians: the mean square's error is
        # sqrt(2 / n) of its value.
        independent = jumps[::lag]
        msd = np.mean(independent**2)
        assert msd == pytest.approx(2 * dr * lag_s, rel=4 * np.sqrt(2 / independent.size))


def test_active_brownian_refuses_a_negative_dr():
    with pytest.raises(ParameterError, match="rotational_diffusion"):
        free_bot("active_brownian", rotational_diffusion=-0.1)
