"""The fast integrator: its Jacobian, its plugin contract, its reproducibility, and
its accuracy against the stored explicit reference (tests/regression)."""

from pathlib import Path

import numpy as np
import pytest

from softcell.builtins.bending import bending_partials
from softcell.components.contracts import EnergyTerm
from softcell.components.registry import default_registry
from softcell.engine import (
    build_integrator,
    build_model,
    circle_modes,
    equilibrium_radius,
    force_modes,
    initial_state,
)
from softcell.engine.cell import realization_rng
from softcell.integrators.rodas4 import pack
from softcell.model.parameters import MODEL_PARAMETERS, Parameters
from softcell.testing import registered
from softcell.testing.compare import rodas4_jacobians, rodas4_rhs, term_hessians

TERMS = ["bending", "tension", "contact"]
REFERENCE = Path(__file__).parent / "regression" / "integrator_reference.npz"


def _state(radius, contact, seed=1):
    """A deformed membrane with the bot's tip 0.005 cm inside it (contact) or at rest."""
    params = Parameters(
        {"radius": radius, "duration": 1.0}, default_registry().parameter_specs().values()
    )
    rng = np.random.default_rng(seed)
    lc = int(params.cutoff)
    modes = circle_modes(equilibrium_radius(params), lc)
    modes += (
        (rng.normal(size=modes.size) + 1j * rng.normal(size=modes.size))
        * 0.02
        / (1 + np.abs(np.arange(-lc, lc + 1))) ** 2
    )
    pose = np.array([radius - 3.0 - 0.005, 0.1, 0.2] if contact else [0.3, 0.1, 0.0])
    return params, modes, pose


def _stepper(params, terms=TERMS):
    model = build_model(params, terms, "run_and_tumble", registry=default_registry())
    return model, build_integrator("rodas4", params, default_registry()).build(model)


def _rhs(model, stepper, u, phase=1):
    return rodas4_rhs(model, stepper, u, phase)


@pytest.mark.parametrize("name", TERMS)
def test_analytic_second_derivatives_match_the_fallback(name):
    params, modes, pose = _state(4.0, contact=True)
    model = build_model(params, TERMS, "run_and_tumble", registry=default_registry())
    term = model.terms[TERMS.index(name)]
    n = model.nodes
    from softcell.engine.reference import _curve

    z, zp, zpp = _curve(modes, n)
    w = np.ascontiguousarray(np.stack([z.real, z.imag, zp.real, zp.imag, zpp.real, zpp.imag]))
    steps = [1e-7 * 4.0] * 8 + [1e-7]
    analytic, fallback = term_hessians(term, w, pose, model.context, steps)
    assert np.abs(analytic[0]).max() > 0
    for a, f in zip(analytic, fallback, strict=True):
        assert np.abs(a - f).max() <= 1e-6 * np.abs(f).max() + 1e-300
    if name == "contact":
        assert np.count_nonzero(analytic[1]) > 0 and np.abs(analytic[2]).max() > 0


@pytest.mark.parametrize("radius, contact", [(4.0, True), (8.0, True), (12.0, False)])
def test_jacobian_matches_differences_of_the_right_hand_side(radius, contact):
    params, modes, pose = _state(radius, contact)
    model, stepper = _stepper(params)
    jac, diff = rodas4_jacobians(model, stepper, pack(modes, pose))
    assert np.abs(jac - diff).max() <= 1e-8 * np.abs(diff).max()
    # The bot rows and columns: pose-pose, pose-modes, modes-pose.
    assert np.abs(jac[-3:] - diff[-3:]).max() <= 1e-6 * np.abs(diff[-3:]).max()
    assert np.abs(jac[:, -3:] - diff[:, -3:]).max() <= 1e-6 * np.abs(diff[:, -3:]).max()


def test_right_hand_side_matches_the_engine_forces():
    """The coarse grid of the smooth terms changes their forces by aliasing only."""
    params, modes, pose = _state(4.0, contact=True)
    model, stepper = _stepper(params)
    assert stepper.ws.smooth.w.shape[1] == 128 < model.nodes
    out = _rhs(model, stepper, pack(modes, pose))
    fhat, dpose = force_modes(model, modes, pose)  # numpy FFTs, all terms at N = 1024
    m = modes.size
    scale = np.abs(model.membrane_mobility * fhat).max()
    assert np.abs(out[:m] - model.membrane_mobility * fhat.real).max() <= 1e-11 * scale
    assert np.abs(out[m : 2 * m] - model.membrane_mobility * fhat.imag).max() <= 1e-11 * scale
    drive = float(params.drive_force) * np.array([np.cos(pose[2]), np.sin(pose[2]), 0.0])
    expected = model.bot_mobility * (drive - 2 * np.pi / model.nodes * dpose)
    np.testing.assert_allclose(out[2 * m :], expected, rtol=1e-10, atol=1e-12)


def test_a_state_s_right_hand_side_does_not_depend_on_the_states_before_it():
    """The partials' buffers are reset only where the last call left partials: a contact
    state, then another contact, then one without, each equals a fresh stepper's bytes."""
    params, modes, pose = _state(4.0, contact=True)
    model, stepper = _stepper(params)
    other = pose + np.array([0.0, 0.3, 0.4])  # the bot's tip elsewhere along the membrane
    far = np.array([0.3, 0.1, 0.0])
    for p in (pose, other, far, pose):
        u = pack(modes, p)
        again = _rhs(model, stepper, u)
        fresh = _rhs(model, _stepper(params)[1], u)
        assert np.array_equal(again, fresh)
    assert np.count_nonzero(stepper.ws.fine.parts) > 0  # the last state has contact


class DifferentialBending(EnergyTerm):
    """Bending without second derivatives and not marked smooth: the fallback path."""

    name = "differential_bending"
    description = "bending through the central-difference fallback (test)"
    parameters = (MODEL_PARAMETERS["bending_stiffness"],)

    def partials_kernel(self):
        return bending_partials

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        raise NotImplementedError


class Plugin:
    @staticmethod
    def softcell_energy_terms():
        return [DifferentialBending]


def test_a_term_without_second_derivatives_uses_the_documented_fallback():
    from softcell.components.hookspecs import hookimpl

    Plugin.softcell_energy_terms = hookimpl(Plugin.softcell_energy_terms)
    with registered(Plugin):
        params, modes, pose = _state(4.0, contact=True)
        model, stepper = _stepper(params, ["differential_bending", "tension", "contact"])
        assert DifferentialBending.hessian_kernel(None) is None
        jac, diff = rodas4_jacobians(model, stepper, pack(modes, pose))
        assert np.abs(jac - diff).max() <= 1e-6 * np.abs(diff).max()


def test_same_bytes_whatever_the_split_of_the_samples():
    params = Parameters(
        {"radius": 4.0, "duration": 0.3}, default_registry().parameter_specs().values()
    )
    model, stepper = _stepper(params)
    modes, pose, schedule = initial_state(model, realization_rng(0, 0, 0))
    times = np.arange(1, 31) * 0.01
    state = stepper.start(modes, pose, schedule)
    whole = stepper.sample(state, schedule, times)
    state = stepper.start(modes, pose, schedule)
    pieces = [stepper.sample(state, schedule, times[i : i + 7]) for i in range(0, 30, 7)]
    for k in range(2):
        assert np.concatenate([p[k] for p in pieces]).tobytes() == whole[k].tobytes()
    assert stepper.statistics(state)["steps"] > 0


def test_bad_smooth_grid_is_refused():
    from softcell.errors import ParameterError

    params = Parameters(
        {"radius": 4.0, "smooth_nodes": 32}, default_registry().parameter_specs().values()
    )
    with pytest.raises(ParameterError, match="smooth_nodes = 32 .* must be >= 4 cutoff = 64"):
        build_integrator("rodas4", params, default_registry())


@pytest.fixture(scope="module")
def reference():
    return np.load(REFERENCE)


@pytest.mark.parametrize("radius", [4.0, 8.0, 12.0])
def test_against_the_explicit_reference(reference, radius):
    """5 s from identical states and schedules: paths within 1e-4 cm at the default
    tolerance, not worse as the tolerance tightens, and the coarse statistics within 1 %."""
    from softcell.engine import Record
    from softcell.testing.compare import coarse_statistics, parameters, path_difference, run

    key = f"r{radius:g}"
    explicit = Record(
        reference[f"{key}_times"], reference[f"{key}_modes"], reference[f"{key}_pose"], None
    )
    errors = {}
    for tol in (1e-5, None, 1e-7):
        extra = {} if tol is None else {"atol": tol, "rtol": tol}
        params = parameters(radius, float(reference["duration"]), **extra)
        result = run(params, "rodas4", seed=int(reference["seed"]))
        errors[tol] = path_difference(result.record, explicit, int(params.cutoff))
        if tol is None:
            mine = coarse_statistics(params, result.record, result.record.phase)
            theirs = coarse_statistics(params, explicit, result.record.phase)
    assert errors[None]["bot"] <= 1e-4 and errors[None]["cell"] <= 1e-4
    for part in ("bot", "cell"):
        assert errors[1e-7][part] <= errors[None][part] <= errors[1e-5][part]
    for name, value in theirs.items():
        assert mine[name] == pytest.approx(value, rel=0.01), name


@pytest.mark.slow
def test_a_fast_bot_never_steps_over_the_membrane():
    """The bot driven ten times harder than the paper's (150 cm/s free) from the centre of
    the smallest ring, into the membrane within ~10 ms and along it: rodas4 at its default
    step control follows the explicit scheme at dt = 1e-6 s to 1e-4 cm, and the membrane's
    deepest point inside the bot is the same in both (a step over the contact would leave
    the membrane behind the bot, a path difference of centimetres)."""
    from softcell.engine.kernels.ellipse import signed_distance
    from softcell.testing.compare import parameters, path_difference, run

    params = parameters(4.0, 0.3, drive_force=10 * float(MODEL_PARAMETERS["drive_force"].default))
    explicit = run(params, "explicit_euler").record
    fast = run(params, "rodas4").record
    paths = path_difference(fast, explicit, int(params.cutoff))
    assert paths["bot"] <= 1e-4 and paths["cell"] <= 1e-4, paths

    def deepest(record):
        lc = int(params.cutoff)
        xi = 2 * np.pi * np.arange(256) / 256
        basis = np.exp(1j * np.outer(xi, np.arange(-lc, lc + 1)))
        a, b = float(params.bot_semi_major), float(params.bot_semi_minor)
        return min(
            signed_distance(z.real, z.imag, *pose, a, b)[0]
            for modes, pose in zip(record.modes, record.pose, strict=True)
            for z in basis @ modes
        )

    inside = deepest(explicit)
    assert inside < -0.01  # the contact was hard: the membrane 0.01 cm and more inside
    assert deepest(fast) == pytest.approx(inside, abs=1e-4)
