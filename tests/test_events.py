"""State events (docs/strategies.md): phases a protocol ends when what the bot senses
crosses zero, located by both integrators against closed-form crossings, stored in the
output, and the same to the byte after a resume and across worker counts."""

import math
import os

import numpy as np
import pytest
from numba import njit

import softcell
from softcell.builtins.protocols import BumpAndTurn
from softcell.builtins.run_and_tumble import RunAndTumble
from softcell.components.contracts import Schedule
from softcell.components.hookspecs import hookimpl
from softcell.components.registry import Registry, default_registry
from softcell.engine import build_integrator, build_model
from softcell.engine.cell import Interrupted, realization_rng, run_realization
from softcell.engine.kernels.ellipse import signed_distance
from softcell.errors import ContractError, ParameterError
from softcell.model.parameters import Parameters

TARGET_X, TURN, HEADING, REACH = 7.0, 1.0, 0.3, 0.5


@njit
def crossing_event(phase, data, sense, coefficients):
    """A run of datum 1 ends where x reaches TARGET_X (cm); a tumble where the heading has
    turned by TURN (rad); a run of datum 2 where the membrane is REACH (cm) nearer."""
    if phase == 1 and data == 1.0:
        return sense[0] - TARGET_X
    if phase == 1 and data == 2.0:
        return (5.0 - REACH) - sense[6]
    if phase == 0:
        return sense[2] - (HEADING + TURN)
    return -1.0


class Crossing(RunAndTumble):
    """A run (ended at x = 7 cm), a tumble (ended after turning 1 rad), a run to the end."""

    name = "crossing"
    description = "a run to x = 7 cm, a tumble of 1 rad, then a run"

    def schedule(self, rng, duration):
        return Schedule(
            np.array([0.0, 10.0, 12.0]), np.array([1, 0, 1], np.int8), np.array([1.0, 1.0, 0.0])
        )

    def initial_heading(self, rng):
        return HEADING

    def event_kernel(self):
        return crossing_event


class Approach(Crossing):
    """One run from the centre of a ring of radius 5 cm, ended 0.5 cm nearer to it."""

    name = "approach"
    description = "a run ended 0.5 cm nearer to the membrane"

    def schedule(self, rng, duration):
        return Schedule(np.array([0.0, 50.0]), np.array([1, 0], np.int8), np.array([2.0, 1.0]))

    def initial_heading(self, rng):
        return 0.0


class NotCompiled(Crossing):
    name = "not_compiled"
    description = "an event kernel that is a plain Python function"

    def event_kernel(self):
        return crossing_event.py_func


class Protocols:
    """A plugin object offering ``protocols`` through the driving-protocol hook."""

    def __init__(self, *protocols):
        self.protocols = list(protocols)

    @hookimpl
    def softcell_driving_protocols(self):
        return self.protocols


def registry_with(*protocols):
    return Registry(entry_points=[], extra_plugins=[("tests", Protocols(*protocols))])


def run(protocol, integrator, membrane, registry, **values):
    specs = [*protocol.parameters, *registry.get("integrator", integrator).parameters]
    params = Parameters({"duration": 3.0, **values}, specs)
    terms = ["bending", "tension", "contact"] if membrane else []
    model = build_model(params, terms, protocol.name, membrane=membrane, registry=registry)
    stepper = build_integrator(integrator, params, registry).build(model)
    return params, run_realization(model, stepper, realization_rng(0, 0, 0))


@pytest.mark.parametrize("integrator, tolerance", [("rodas4", 1e-6), ("explicit_euler", 1e-5)])
def test_events_land_on_closed_form_crossings(integrator, tolerance):
    registry = registry_with(Crossing)
    params, record = run(Crossing, integrator, False, registry, dt=1e-5)
    v = params.drive_force / params.bot_friction
    omega = params.drive_torque / params.bot_rotational_friction
    first = TARGET_X / (v * math.cos(HEADING))
    expected = [first, first + TURN / omega]
    # rodas4 finds the crossing on its continuous extension; explicit_euler at its step.
    assert record.event_times == pytest.approx(expected, abs=tolerance)
    # The run after the tumble starts at the event, 11.3 s before its scheduled start.
    late = record.times > expected[1] + 0.01
    assert np.all(record.phase[late] == 1)
    x_after = record.pose[-1, 0] - v * (record.times[-1] - expected[1]) * math.cos(HEADING + TURN)
    # explicit_euler ends the tumble up to a step late: omega dt = 5e-5 rad over a 35 cm run.
    assert x_after == pytest.approx(TARGET_X, abs=1e-4 if integrator == "rodas4" else 2e-3)


@pytest.mark.parametrize("integrator, tolerance", [("rodas4", 1e-6), ("explicit_euler", 2e-6)])
def test_the_membrane_distance_sensed_is_the_rings(integrator, tolerance):
    registry = registry_with(Approach)
    params, record = run(Approach, integrator, True, registry, duration=0.1, radius=5.0, dt=1e-6)
    # The ring stays at rest, a circle about the origin (its radius slightly above R: the
    # polygon of the nodes has the rest length): the centre is REACH nearer to it after
    # (ring - 5 cm + REACH) / v.
    lc = params.cutoff
    ring = abs(record.modes[0][lc + 1])
    assert np.abs(record.modes[0][np.arange(2 * lc + 1) != lc + 1]).max() < 1e-12
    v = params.drive_force / params.bot_friction
    assert record.event_times == pytest.approx([(ring - 5.0 + REACH) / v], abs=tolerance)


def contact_force(params, modes, pose, nodes):
    """The membrane's force on the bot (N) from the contact energy, summed over ``nodes``
    points of the curve (numpy, independent of the compiled term)."""
    lc = (modes.size - 1) // 2
    xi = 2 * np.pi * np.arange(nodes) / nodes
    z = np.exp(1j * np.outer(xi, np.arange(-lc, lc + 1))) @ modes
    a, b, lam, amp = (
        params.bot_semi_major,
        params.bot_semi_minor,
        params.contact_length,
        params.contact_amplitude,
    )
    force = 0.0j
    for point in z:
        rho, gx, gy = signed_distance(point.real, point.imag, pose[0], pose[1], pose[2], a, b)
        if rho < 30 * lam:
            # e = (l0 / 2 pi) A exp(-rho / lambda): the bot feels -de/dr_bot = -(l0/2pi)(A/lambda)
            # exp(-rho/lambda) grad rho, integrated with the weight 2 pi / nodes.
            force -= (
                (params.membrane_length / nodes)
                * (amp / lam)
                * math.exp(-rho / lam)
                * (gx + 1j * gy)
            )
    return abs(force)


def test_bump_and_turn_runs_never_outlast_their_contact():
    registry = default_registry()
    params, record = run(
        BumpAndTurn, "rodas4", True, registry, duration=20.0, radius=5.0, nodes=128
    )
    assert record.event_times.size > 10
    runs = np.flatnonzero(record.phase == 1)
    forces = np.array([contact_force(params, record.modes[i], record.pose[i], 128) for i in runs])
    # No sampled state of a run pushes harder than the threshold: every run ended at contact
    # (within one sample: the event is located between samples, not at them).
    assert forces.max() < params.contact_threshold * (1 + 1e-6)
    # ... and the runs did reach the membrane: the largest sampled force is near it.
    assert forces.max() > 0.5 * params.contact_threshold
    # Every event ended a run at the threshold: the samples just after it are tumbles.
    after = np.searchsorted(record.times, record.event_times)
    after = after[after < record.times.size]
    assert np.all(record.phase[after] == 0)


class Memory:
    def __init__(self):
        self.saved = None

    def load(self):
        return self.saved

    def save(self, saved):
        self.saved = saved


def test_an_event_run_resumes_to_the_same_values():
    registry = default_registry()
    specs = [*BumpAndTurn.parameters, *registry.get("integrator", "rodas4").parameters]
    params = Parameters({"duration": 8.0, "radius": 5.0}, specs)
    model = build_model(
        params, ["bending", "tension", "contact"], "bump_and_turn", registry=registry
    )

    def fresh():
        return build_integrator("rodas4", params, registry).build(model)

    whole = run_realization(model, fresh(), realization_rng(0, 0, 0))
    memory, calls = Memory(), []
    with pytest.raises(Interrupted):
        run_realization(
            model,
            fresh(),
            realization_rng(0, 0, 0),
            checkpoint=memory,
            checkpoint_every=0.0,
            stop=lambda: calls.append(1) or len(calls) > 3,
        )
    assert memory.saved is not None and 0 < memory.saved.state["event_count"][0]
    resumed = run_realization(model, fresh(), realization_rng(0, 0, 0), checkpoint=memory)
    np.testing.assert_array_equal(resumed.event_times, whole.event_times)
    np.testing.assert_array_equal(resumed.pose, whole.pose)
    np.testing.assert_array_equal(resumed.phase, whole.phase)


@pytest.mark.slow
def test_event_times_are_stored_and_the_same_across_workers(tmp_path):
    config = softcell.RunConfig(parameters={"radius": 5.0, "duration": 6.0}).updated(
        components={"driving_protocol": "bump_and_turn"}
    )
    softcell.simulate(config, tmp_path / "one", realizations=2, seed=4, progress=False)
    softcell.simulate(config, tmp_path / "two", realizations=2, seed=4, workers=2, progress=False)
    names = sorted(p.name for p in (tmp_path / "one").glob("*.nc"))
    assert len(names) == 2
    for name in names:
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()
    ds = softcell.open_dataset(tmp_path / "one")
    assert ds["event_time"].attrs["units"] == "s"
    counts = np.isfinite(ds["event_time"].values).sum(axis=-1)
    assert counts.min() > 2
    # Realizations with fewer events are NaN-padded to the longest.
    assert ds.sizes["event"] == counts.max()


def test_a_threshold_the_bot_cannot_reach_is_refused():
    registry = default_registry()
    with pytest.raises(ParameterError, match="contact_threshold.*drive_force"):
        run(BumpAndTurn, "rodas4", True, registry, contact_threshold=0.05)


def test_an_event_kernel_that_is_not_compiled_is_refused():
    registry = registry_with(NotCompiled)
    with pytest.raises(ContractError, match="event_kernel.*not a numba.njit"):
        run(NotCompiled, "rodas4", False, registry)


def test_the_cli_refuses_a_bad_threshold_in_one_line(tmp_path, capsys):
    from softcell.cli import main

    code = main(
        [
            "simulate",
            "-o",
            str(tmp_path / "x"),
            "--protocol",
            "bump_and_turn",
            "--contact-threshold",
            "0.1",
            "--duration",
            "1",
        ]
    )
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "contact_threshold" in err[0]
    assert not os.path.exists(tmp_path / "x")


@njit
def nan_event(phase, data, sense, coefficients):
    return math.nan


class NaNEvent(Crossing):
    name = "nan_event"
    description = "an event kernel that returns NaN"

    def event_kernel(self):
        return nan_event


def test_an_event_kernel_that_returns_nan_is_named_before_any_step():
    # Before: the run ended with exit 0 and no events (NaN >= 0 is never true).
    registry = registry_with(NaNEvent)
    with pytest.raises(ContractError, match=r"event_kernel\(\) wrote non-finite event value"):
        run(NaNEvent, "rodas4", True, registry)


def test_check_driving_protocol_checks_the_event_kernel():
    from softcell.testing import check_component

    check_component(Crossing)
    with pytest.raises(AssertionError, match=r"event_kernel\(\) returned nan"):
        check_component(NaNEvent)
