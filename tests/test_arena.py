"""The arena: a square plate whose walls repel the membrane and the bot."""

import numpy as np
import pytest

from softcell.builtins.arena import arena_bot
from softcell.cli import main
from softcell.components.registry import default_registry
from softcell.engine import build_integrator, build_model, initial_state
from softcell.engine.cell import realization_rng
from softcell.engine.compose import compose_bot
from softcell.engine.reference import _curve
from softcell.errors import ParameterError
from softcell.integrators.rodas4 import pack
from softcell.io.netcdf import read_dataset
from softcell.model.parameters import Parameters
from softcell.settings import CONTACT_CUTOFF_LENGTHS
from softcell.testing.compare import rodas4_jacobians, term_hessians

TERMS = ["bending", "tension", "contact", "arena"]


def _params(**values):
    return Parameters(
        {"radius": 4.0, "duration": 1.0, **values}, default_registry().parameter_specs().values()
    )


def _run(terms, duration, membrane=True, integrator="rodas4", seed=0, **values):
    params = _params(duration=duration, **values)
    model = build_model(
        params, terms, "run_and_tumble", membrane=membrane, registry=default_registry()
    )
    stepper = build_integrator(integrator, params, default_registry()).build(model)
    modes, pose, schedule = initial_state(model, realization_rng(seed, 0, 0))
    state = stepper.start(modes, pose, schedule)
    times = np.arange(1, int(duration / 0.05) + 1) * 0.05
    return model, stepper.sample(state, schedule, times)


def _half_widths(a, b, theta):
    """The bot ellipse's half-widths along x and y (cm)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.sqrt(a * a * c * c + b * b * s * s), np.sqrt(a * a * s * s + b * b * c * c)


def test_second_derivatives_match_differences():
    params = _params(arena_side=10.0)
    model = build_model(params, TERMS, "run_and_tumble", registry=default_registry())
    term = model.terms[3]
    n = model.nodes
    # a curve crossing the walls' reach: a circle of radius 4.99 centred at (0.01, -0.005)
    xi = 2 * np.pi * np.arange(n) / n
    w = np.zeros((6, n))
    w[0], w[1] = 0.01 + 4.99 * np.cos(xi), -0.005 + 4.99 * np.sin(xi)
    coefficients = np.ascontiguousarray(term.coefficients())
    pose = np.array([0.0, 0.0, 0.3])
    analytic, fallback = term_hessians(term, w, pose, model.context, [1e-7] * 9)
    assert np.count_nonzero(analytic[0]) > 8
    assert np.abs(analytic[0] - fallback[0]).max() <= 1e-6 * np.abs(fallback[0]).max()
    # the bot's walls: at a corner, turned, within reach of two walls
    a, b = params.bot_semi_major, params.bot_semi_minor
    theta = 0.7
    hx, hy = _half_widths(a, b, theta)
    pose = np.array([5.0 - hx - 0.02, -(5.0 - hy - 0.03), theta])
    exact = np.zeros((3, 3))
    term.bot_hessian_kernel()(pose, model.context, coefficients, exact)
    _, differences = compose_bot([type(term)(params)])
    approx = np.zeros((3, 3))
    differences(
        pose,
        model.context,
        (coefficients,),
        np.array([1e-8] * 9),
        np.zeros(3),
        np.zeros(3),
        np.zeros(3),
        approx,
    )  # the analytic kernel: bound as such
    assert np.array_equal(exact, approx)
    numeric = np.zeros((3, 3))
    for d in range(3):
        plus, minus = pose.copy(), pose.copy()
        plus[d] += 1e-8
        minus[d] -= 1e-8
        gp, gm = np.zeros(3), np.zeros(3)
        arena_bot(plus, model.context, coefficients, gp)
        arena_bot(minus, model.context, coefficients, gm)
        numeric[:, d] = (gp - gm) / 2e-8
    assert np.count_nonzero(exact) >= 5
    assert np.abs(exact - numeric).max() <= 1e-5 * np.abs(numeric).max()
    assert np.allclose(exact, exact.T, rtol=1e-12, atol=0)


def test_rodas4_jacobian_with_the_arena_matches_differences():
    params = _params(arena_side=10.0)
    model = build_model(params, TERMS, "run_and_tumble", registry=default_registry())
    stepper = build_integrator("rodas4", params, default_registry()).build(model)
    lc = model.cutoff
    modes = np.zeros(2 * lc + 1, dtype=np.complex128)
    modes[lc], modes[lc + 1] = 0.02 - 0.01j, 4.99  # reaching two walls
    u = pack(modes, np.array([1.99 - 0.005 + 0.02, -0.01, 0.0]))  # and the bot's tip in contact

    jac, diff = rodas4_jacobians(model, stepper, u)
    assert np.abs(jac - diff).max() <= 1e-6 * np.abs(diff).max()


@pytest.mark.slow
def test_the_arena_keeps_the_membrane_and_the_bot_inside_over_a_long_run():
    side = 10.0  # the membrane (R = 4 cm) is pushed against the walls again and again
    model, (modes, pose) = _run(TERMS, 60.0, arena_side=side)
    half = side / 2
    points = np.stack([_curve(m, 256)[0] for m in modes])
    lam = float(model.params.contact_length)
    reach = CONTACT_CUTOFF_LENGTHS * lam
    # the walls are soft like the contact (length lambda): the bot presses the membrane into
    # them by ~lambda (measured: 1.04 lambda), never by much more
    assert np.abs(points.real).max() < half + 3 * lam
    assert np.abs(points.imag).max() < half + 3 * lam
    gc = points.mean(axis=1)
    assert np.abs(gc.real).max() < half - 4.0 + reach
    # the walls were felt: some point came within their reach
    assert max(np.abs(points.real).max(), np.abs(points.imag).max()) > half - reach


@pytest.mark.parametrize(
    "integrator", [pytest.param("rodas4", marks=pytest.mark.slow), "explicit_euler"]
)
def test_a_free_bot_stays_inside_the_walls(integrator):
    side = 8.0
    duration = 20.0 if integrator == "rodas4" else 0.5
    model, (_, pose) = _run(
        ["bending", "arena"],
        duration,
        membrane=False,
        integrator=integrator,
        arena_side=side,
        dt=1e-5,
        radius=3.2,
    )
    assert [t.name for t in model.terms] == ["arena"]  # a free bot keeps only the walls
    a, b = model.params.bot_semi_major, model.params.bot_semi_minor
    hx, hy = _half_widths(a, b, pose[:, 2])
    lam = model.params.contact_length
    # the ellipse never goes past a wall by more than the repulsion's length
    assert (np.abs(pose[:, 0]) + hx).max() < side / 2 + lam
    assert (np.abs(pose[:, 1]) + hy).max() < side / 2 + lam
    if integrator == "rodas4":
        # it did reach them: the bot runs 15 cm/s, the walls are ~2 cm away
        assert (
            max((np.abs(pose[:, 0]) + hx).max(), (np.abs(pose[:, 1]) + hy).max())
            > side / 2 - 5 * lam
        )


def test_walls_never_reached_change_nothing_to_the_byte():
    _, (free, pose_free) = _run([], 3.0, membrane=False)
    _, (walled, pose_walled) = _run(["arena"], 3.0, membrane=False, arena_side=100.0)
    assert np.array_equal(pose_free, pose_walled) and np.array_equal(free, walled)


def test_an_arena_too_small_is_refused_with_the_bound():
    with pytest.raises(ParameterError, match=r"arena_side = 8.0 cm .* must be > 8.5 cm"):
        build_model(_params(arena_side=8.0), TERMS, "run_and_tumble", registry=default_registry())


def test_the_command_line_simulates_a_free_bot_in_the_arena(tmp_path):
    out = tmp_path / "free"
    assert (
        main(
            [
                "simulate",
                "--free-bot",
                "--energy-terms",
                "arena",
                "--arena-side",
                "10",
                "--radius",
                "4",
                "--duration",
                "2",
                "--realizations",
                "1",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    ds = read_dataset(next(out.glob("*.nc")))
    assert '"energy_terms": ["arena"]' in ds.attrs["softcell_components"]
    assert float(np.abs(ds["bot_x"]).max()) < 5.0
