"""Fixed obstacles (posts and walls): their derivatives, their hold on a pushed membrane, and
how a run places them (configuration files, flags, refusals, files)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softcell.cli import main
from softcell.components.registry import default_registry
from softcell.engine import build_integrator, build_model, initial_state
from softcell.engine.cell import realization_rng
from softcell.errors import ConfigError, ParameterError
from softcell.integrators.rodas4 import pack
from softcell.io.netcdf import read_dataset
from softcell.model.configuration import config_from_mapping
from softcell.model.obstacle_layout import (
    check_clear_of_start,
    from_table,
    obstacle_text,
    surface_distances,
)
from softcell.model.parameters import Parameters
from softcell.settings import CONTACT_CUTOFF_LENGTHS
from softcell.testing.compare import rodas4_jacobians, term_hessians

TERMS = ["bending", "tension", "contact", "obstacles"]
# a post right of the ring, a wall below it, a wall ending above it
PLACED = "post 5.3 0.2 1; wall -6 -4.5 6 -4.5 0.4; wall -1 4.51 -6 4.51 0.4"


def _params(**values):
    return Parameters(
        {"radius": 4.0, "duration": 1.0, **values}, default_registry().parameter_specs().values()
    )


def _term(text=PLACED):
    params = _params(obstacles=text)
    model = build_model(params, TERMS, "run_and_tumble", registry=default_registry())
    return model, model.terms[3]


def _curve_near(n):
    """A wobbly circle of radius ~4.29 cm: within reach of the post, inside the lower wall's
    span, and past the upper wall's end (x > -1 there), on different points."""
    xi = 2 * np.pi * np.arange(n) / n
    r = 4.29 + 0.004 * np.cos(3 * xi)
    w = np.zeros((6, n))
    w[0], w[1] = r * np.cos(xi), r * np.sin(xi)
    return w


def _distances(x, y, text):
    """Each point's signed distance to the nearest obstacle surface (cm)."""
    return surface_distances(x, y, text).min(axis=0)


def test_partials_are_the_derivatives_of_the_density():
    model, term = _term()
    n = 512
    w = _curve_near(n)
    pose = np.zeros(3)
    coefficients = np.ascontiguousarray(term.coefficients())
    parts = [np.zeros(n) for _ in range(6)]
    term.partials_kernel()(*w, pose, model.context, coefficients, *parts, np.zeros(3))
    near = _distances(w[0], w[1], PLACED) < CONTACT_CUTOFF_LENGTHS * 0.01
    assert near.sum() > 20  # the curve is within reach of all three obstacles
    for axis in range(2):
        h = 1e-7
        plus, minus = w.copy(), w.copy()
        plus[axis] += h
        minus[axis] -= h
        numeric = (term.density(*plus, pose) - term.density(*minus, pose)) / (2 * h)
        scale = np.abs(numeric).max()
        assert scale > 0
        assert np.abs(parts[axis] - numeric).max() <= 1e-5 * scale
    assert not any(np.any(p) for p in parts[2:])  # the obstacles read positions only


def test_second_derivatives_match_differences_of_the_partials():
    model, term = _term()
    n = model.nodes
    w = _curve_near(n)
    pose = np.zeros(3)
    analytic, numeric = term_hessians(term, w, pose, model.context, [1e-8] * 9)
    assert np.count_nonzero(analytic[0]) > 40
    # the off-diagonal terms of the post and the wall's end are there
    assert np.count_nonzero(analytic[0][:, 0, 1]) > 10
    assert np.abs(analytic[0] - numeric[0]).max() <= 1e-5 * np.abs(numeric[0]).max()
    assert not np.any(analytic[1]) and not np.any(analytic[2])


def test_rodas4_jacobian_with_obstacles_matches_differences():
    params = _params(obstacles=PLACED)
    model = build_model(params, TERMS, "run_and_tumble", registry=default_registry())
    stepper = build_integrator("rodas4", params, default_registry()).build(model)
    lc = model.cutoff
    modes = np.zeros(2 * lc + 1, dtype=np.complex128)
    modes[lc], modes[lc + 1] = 0.01 - 0.005j, 4.29  # within reach of all three
    u = pack(modes, np.array([1.2, 0.0, 0.0]))  # and the bot's tip in contact
    jac, diff = rodas4_jacobians(model, stepper, u)
    assert np.abs(jac - diff).max() <= 1e-6 * np.abs(diff).max()


def _pushed(text, seed, duration):
    """A ring of R = 4 cm pushed along a random heading for ``duration`` s: its membrane
    (1024 points) at every 0.1 s, and the bot's poses."""
    from softcell.engine.reference import _curve

    params = _params(obstacles=text, duration=duration)
    model = build_model(params, TERMS, "constant_push", registry=default_registry())
    stepper = build_integrator("rodas4", params, default_registry()).build(model)
    modes, pose, schedule = initial_state(model, realization_rng(seed, 0, 0))
    state = stepper.start(modes, pose, schedule)
    times = np.arange(1, int(round(duration / 0.1)) + 1) * 0.1
    modes_s, pose_s = stepper.sample(state, schedule, times)
    z = np.array([_curve(m, 1024)[0] for m in modes_s])
    return np.stack([z.real, z.imag], axis=1), pose_s


@settings(max_examples=6, deadline=None, derandomize=True)
@given(
    gap=st.floats(0.3, 1.5),
    shift=st.floats(-0.25, 0.25),
    post=st.floats(0.3, 2.0),
    angle=st.floats(0.0, 2 * np.pi),
    seed=st.integers(0, 2**16),
)
def test_a_pushed_membrane_never_enters_an_obstacle(gap, shift, post, angle, seed):
    # a corral: walls on three sides, a post on the fourth; the push is along a random heading
    half = 4.0 + gap + 0.2  # the walls' centre lines
    c, s = np.cos(angle), np.sin(angle)
    corners = [(-half, -half), (half, -half), (half, half), (-half, half)]
    turned = [(c * x - s * y + shift, s * x + c * y) for x, y in corners]
    walls = [(*turned[i], *turned[i + 1]) for i in range(3)]
    tables = [dict(zip(("x0", "y0", "x1", "y1", "width"), (*w, 0.4), strict=True)) for w in walls]
    mid = (0.5 * (turned[3][0] + turned[0][0]), 0.5 * (turned[3][1] + turned[0][1]))
    out = np.hypot(*mid)
    tables.append({"x": mid[0] * (1 + post / out), "y": mid[1] * (1 + post / out), "radius": post})
    text = obstacle_text(from_table(t) for t in tables)
    curves, poses = _pushed(text, seed, 3.0)
    deepest = _distances(curves[:, 0], curves[:, 1], text).min()
    assert deepest >= -3 * 0.01, f"the membrane entered an obstacle by {-deepest:.3g} cm"
    assert np.all(np.abs(poses[:, :2]) < half + 1.0)  # the bot stays in the corral


def test_a_configuration_file_places_obstacles_and_adds_their_term():
    config = config_from_mapping(
        {
            "obstacles": [
                {"x": 12, "y": 0, "radius": 2},
                {"x0": -20, "y0": -8, "x1": 20, "y1": -8, "width": 0.5},
            ]
        }
    )
    assert config.parameters["obstacles"] == "post 12 0 2; wall -20 -8 20 -8 0.5"
    assert config.components["energy_terms"] == ["bending", "tension", "contact", "obstacles"]
    with pytest.raises(ConfigError, match=r"must be a table of x, y, radius"):
        config_from_mapping({"obstacles": [{"x": 1, "radius": 2}]})
    with pytest.raises(ConfigError, match=r"given twice"):
        config_from_mapping(
            {"obstacles": [{"x": 12, "y": 0, "radius": 2}], "parameters": {"obstacles": ""}}
        )
    with pytest.raises(ConfigError, match=r"\[\[obstacles\]\]"):
        config_from_mapping({"obstacles": {"x": 1}})


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("post 8 0 0", r"post radius > 0"),
        ("wall 5 5 5 5 1", r"two distinct ends"),
        ("wall 5 5 9 5 0", r"wall width > 0"),
        ("post 8 0 0.05", r"post radius >= 0.1 cm \(10 contact lengths\)"),
        ("wall 5 5 9 5 0.1", r"wall half-width >= 0.1 cm"),
        ("pole 8 0 1", r"must be 'post X Y RADIUS' or 'wall X0 Y0 X1 Y1 WIDTH'"),
        ("post 8 0", r"must be 'post X Y RADIUS'"),
        ("post 8 nan 1", r"must be 'post X Y RADIUS'"),
    ],
)
def test_a_bad_obstacle_is_refused_naming_it(text, message):
    with pytest.raises(ParameterError, match=message):
        _term(text)


def test_an_obstacle_on_a_single_cell_start_is_refused_naming_it():
    check_clear_of_start(_params(obstacles="post 8 0 1"))  # 7 cm away: clear
    with pytest.raises(
        ParameterError, match=r"keep clear of the cell at the start: its surface is 3.5 cm"
    ):
        check_clear_of_start(_params(obstacles="post 4.5 0 1"))


def test_the_command_line_places_obstacles_refuses_bad_ones_and_stores_them(tmp_path, capsys):
    assert main(["params", "--radius", "4", "--obstacle", "4.5,0,1"]) == 2
    assert "must keep clear of the cell" in capsys.readouterr().err
    out = tmp_path / "run"
    argv = ["simulate", "--radius", "4", "--duration", "0.5", "--quiet", "-o", str(out)]
    assert main([*argv, "--obstacle", "4.5,0,1"]) == 2
    assert "must keep clear of the cell" in capsys.readouterr().err
    assert not out.exists()  # refused before anything ran
    assert main([*argv, "--obstacle", "8,0"]) == 2
    assert "--obstacle 8,0 is not allowed: must be X,Y,RADIUS" in capsys.readouterr().err
    assert main([*argv, "--obstacle", "8,0,1", "--wall=-9,-6,9,-6,0.5"]) == 0
    ds = read_dataset(next(out.glob("*.nc")))
    assert ds.attrs["parameter_obstacles"] == "post 8 0 1; wall -9 -6 9 -6 0.5"
    assert "obstacles" in ds.attrs["softcell_components"]
