"""Several bots in one ring: the bots' contact law, the several-bot loop against independent
computations, and the run as a user makes it (one line for what cannot run, resumes, K = 1
is the single-bot run)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.path import Path as Polygon
from numba import njit as njit_kernel

from softcell.builtins.bot_repulsion import bot_repulsion_kernel
from softcell.cli import main
from softcell.components.registry import default_registry
from softcell.engine import build_model
from softcell.engine.bots import bot_rngs, placement_rng, start_bots
from softcell.engine.cell import run_realization
from softcell.engine.kernels.ellipse import ellipse_gap, signed_distance_local
from softcell.engine.kernels.spectral import resample
from softcell.io.netcdf import open_dataset
from softcell.model.bots import Bots, lattice_sites, place_bots
from softcell.model.configuration import RunConfig
from softcell.runner.ensemble import simulate

A, B = 3.0, 2.0
CONTEXT = np.array([50.0, A, B])
#: F_c (N), lambda_b (cm), cut-off (cm), reach (cm): the built-in's defaults
COEFFICIENTS = np.array([0.4275, 0.05, 1.25, 2 * A + 1.25])


def _energy(pa: np.ndarray, pb: np.ndarray) -> float:
    force, length = COEFFICIENTS[0], COEFFICIENTS[1]
    return force * length * math.exp(-ellipse_gap(pa, pb, A, B) / length)


def _near_pair(heading_a: float, direction: float, heading_b: float, gap: float):
    """Two bots whose gap is ``gap`` (cm): b slid along ``direction`` until it is."""
    pa = np.array([0.3, -0.2, heading_a])
    unit = np.array([math.cos(direction), math.sin(direction)])
    lo, hi = 0.0, 4 * A
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        pb = np.array([*(pa[:2] + mid * unit), heading_b])
        if ellipse_gap(pa, pb, A, B) < gap:
            lo = mid
        else:
            hi = mid
    return pa, np.array([*(pa[:2] + hi * unit), heading_b])


angles = st.floats(-math.pi, math.pi)


@settings(max_examples=60, deadline=None)
@given(angles, angles, angles, st.floats(-0.04, 0.4))
def test_the_bots_forces_are_equal_opposite_and_balance_torques(ha, direction, hb, gap):
    pa, pb = _near_pair(ha, direction, hb, gap)
    out = np.zeros(6)
    bot_repulsion_kernel(pa, pb, CONTEXT, COEFFICIENTS, out)
    scale = np.abs(out).max()
    assert scale > 0
    assert np.abs(out[:2] + out[3:5]).max() <= 1e-12 * scale
    # angular momentum about the origin: r_a x F_a + tau_a + r_b x F_b + tau_b = 0
    total = pa[0] * out[1] - pa[1] * out[0] + out[2] + pb[0] * out[4] - pb[1] * out[3] + out[5]
    assert abs(total) <= 1e-11 * scale * (1 + np.abs(pb[:2]).max())


@settings(max_examples=30, deadline=None)
@given(angles, angles, angles, st.floats(-0.04, 0.4))
def test_the_bots_forces_are_minus_the_gradient_of_their_energy(ha, direction, hb, gap):
    """Central differences of F_c lambda_b exp(-gap / lambda_b), the gap from its own
    definition (an independent computation of the derivatives the kernel takes by the
    envelope theorem)."""
    pa, pb = _near_pair(ha, direction, hb, gap)
    out = np.zeros(6)
    bot_repulsion_kernel(pa, pb, CONTEXT, COEFFICIENTS, out)
    both = np.concatenate([pa, pb])
    gradient = np.zeros(6)
    h = 1e-6
    for j in range(6):
        plus, minus = both.copy(), both.copy()
        plus[j] += h
        minus[j] -= h
        gradient[j] = (_energy(plus[:3], plus[3:]) - _energy(minus[:3], minus[3:])) / (2 * h)
    np.testing.assert_allclose(out, -gradient, rtol=0, atol=2e-6 * np.abs(out).max())


def test_the_gap_of_two_bots_side_by_side_is_their_distance_less_two_semi_minor_axes():
    """Parallel bots side by side: the gap is analytic."""
    for d in (4.5, 4.01, 3.9):
        gap = ellipse_gap(np.array([0.0, 0.0, 0.0]), np.array([0.0, d, 0.0]), A, B)
        assert gap == pytest.approx(d - 2 * B, abs=1e-12)
        gap = ellipse_gap(np.array([0.0, 0.0, 0.0]), np.array([d + 2.0, 0.0, math.pi]), A, B)
        assert gap == pytest.approx(d + 2.0 - 2 * A, abs=1e-12)


# -- the several-bot loop ---------------------------------------------------------------------


def _model(params: dict, interactions=("bot_repulsion",)):
    registry = default_registry()
    components = {
        "energy_terms": ["bending", "tension", "contact"],
        "driving_protocol": "run_and_tumble",
        "integrator": "rodas4",
        "friction_law": "viscous",
        "bot_interactions": list(interactions),
    }
    p = registry.parameters(params, components)
    model = build_model(
        p,
        components["energy_terms"],
        "run_and_tumble",
        registry=registry,
        bot_interactions=list(interactions),
    )
    return model, registry.get("integrator", "rodas4")(p)


@pytest.fixture(scope="module")
def three_bots():
    model, integrator = _model({"radius": 8.0, "duration": 2.0})
    return model, integrator.build_bots(model, 3)


def test_the_several_bot_jacobian_matches_central_differences(three_bots):
    """The loop's Jacobian (membrane, contacts, drives, bot-bot pair) against central
    differences of its own right-hand side, at a state where bots 0 and 1 touch each other
    and bot 2 presses on the membrane."""
    model, stepper = three_bots
    m = 2 * model.cutoff + 1
    from softcell.engine.state import circle_modes, equilibrium_radius

    radius = equilibrium_radius(model.params)
    pa, pb = _near_pair(0.4, 1.1, -0.7, 0.02)
    poses = np.array([pa, pb, [0.0, -(radius - A - 0.02), math.pi / 2]])
    modes = circle_modes(radius, model.cutoff)
    modes[model.cutoff + 3] = 0.01  # not a circle
    u = np.concatenate([modes.real, modes.imag, poses.reshape(-1)])
    phases, data = np.array([1, 0, 1], dtype=np.int8), np.array([0.0, 1.0, 0.0])
    jac = stepper.jacobian(u, phases, data)
    fd = np.zeros_like(jac)
    scale = model.params.membrane_length / (2 * math.pi)
    for j in range(u.size):
        h = 1e-6 * (scale if j < 2 * m or j % 3 != (2 * m + 2) % 3 else 1.0)
        plus, minus = u.copy(), u.copy()
        plus[j] += h
        minus[j] -= h
        fd[:, j] = (stepper.rhs(plus, phases, data) - stepper.rhs(minus, phases, data)) / (2 * h)
    # the pair's and the contact's blocks are nonzero
    assert np.abs(jac[2 * m : 2 * m + 3, 2 * m + 3 : 2 * m + 6]).max() > 0
    assert np.abs(jac[: 2 * m, 2 * m + 6 :]).max() > 0
    error = np.abs(jac - fd).max()
    assert error <= 1e-4 * np.abs(fd).max(), error


def test_the_several_bot_rhs_is_the_single_bot_rhs_for_one_bot_and_the_sum_of_contacts():
    """K = 2 with the second bot far from everything except the membrane it does not touch:
    the membrane's velocity and bot 0's are those of the single-bot loop at bot 0 alone (the
    split into parts and their sum, checked against the single-bot right-hand side)."""
    from softcell.integrators.rodas4 import compiled_loop, group_coefficients, workspace
    from softcell.integrators.rodas4.method import Problem

    model, integrator = _model({"radius": 12.0, "duration": 1.0})
    stepper = integrator.build_bots(model, 2)
    from softcell.engine.state import circle_modes, equilibrium_radius

    radius = equilibrium_radius(model.params)
    m = 2 * model.cutoff + 1
    modes = circle_modes(radius, model.cutoff)
    modes[model.cutoff - 2] = 0.01
    bot0 = np.array([0.0, -(radius - A - 0.02), 1.5])  # pressing on the membrane
    bot1 = np.array([0.0, 2.5, 1.0])  # alone in the middle
    u = np.concatenate([modes.real, modes.imag, bot0, bot1])
    phases, data = np.array([1, 1], dtype=np.int8), np.zeros(2)
    several = stepper.rhs(u, phases, data)
    rhs, _, _ = compiled_loop(model)
    single = np.zeros(2 * m + 3)
    ws = workspace(model, min(int(model.params.smooth_nodes), model.nodes))
    problem = Problem(
        group_coefficients(model), model.context, model.drive_coefficients,
        model.membrane_mobility, model.bot_mobility, True,
    )  # fmt: skip
    rhs(np.concatenate([modes.real, modes.imag, bot0]), 1, 0.0, single, problem, ws)
    scale = np.abs(single).max()
    np.testing.assert_allclose(several[: 2 * m + 3], single, rtol=0, atol=1e-12 * scale)
    # bot 1 moves by its drive alone: F0 / gamma_T along its heading
    speed = float(model.params.drive_force) / float(model.params.bot_friction)
    np.testing.assert_allclose(
        several[2 * m + 3 : 2 * m + 5], speed * np.array([math.cos(1.0), math.sin(1.0)])
    )


def _polygon_inside(x, y, px, py):
    return Polygon(np.column_stack([x, y])).contains_points(np.column_stack([px, py]))


@pytest.mark.parametrize(
    "count, placement, seed", [(2, "random", 1), (3, "ring", 2), (5, "lattice", 3)]
)
def test_no_bot_enters_another_and_every_bot_stays_in_its_ring(count, placement, seed):
    """Bots in a ring of 10 cm for 3 s: the bots' gap never below -0.05 cm (the soft law
    lets them touch; at zero gap it pushes with ten drive forces), no membrane point deeper
    than 0.05 cm inside a bot (the contact's own softness), every bot centre inside the
    ring."""
    model, integrator = _model({"radius": 10.0, "duration": 3.0})
    stepper = integrator.build_bots(model, count)
    bots = Bots(count=count, placement=placement)
    modes, poses, schedules = start_bots(
        model, bots, bot_rngs(seed, 0, 0, count), placement_rng(seed, 0, 0)
    )
    record = run_realization(
        model, stepper, None, start=(stepper.start(modes, poses, schedules), schedules)
    )
    pose = record.pose.reshape(len(record.times), count, 3)
    gaps = [
        ellipse_gap(pose[t, i], pose[t, j], A, B)
        for t in range(len(record.times))
        for i in range(count)
        for j in range(i + 1, count)
    ]
    assert min(gaps) > -0.05
    mx, my = resample(record.modes, 512)
    deepest = np.inf
    for t in range(0, len(record.times), 10):
        for i in range(count):
            x, y, heading = pose[t, i]
            c, s = math.cos(heading), math.sin(heading)
            px = c * (mx[t] - x) + s * (my[t] - y)
            py = -s * (mx[t] - x) + c * (my[t] - y)
            deepest = min(
                deepest,
                min(signed_distance_local(u, v, A, B)[0] for u, v in zip(px, py, strict=True)),
            )
        assert _polygon_inside(mx[t], my[t], pose[t, :, 0], pose[t, :, 1]).all()
    assert deepest > -0.05


# -- placement --------------------------------------------------------------------------------


@pytest.mark.parametrize("placement", ["random", "ring", "lattice"])
def test_placed_bots_keep_the_gap_and_lie_inside_the_ring(placement):
    rng = np.random.default_rng(3)
    bots = Bots(count=4, placement=placement, gap=0.5)
    poses = place_bots(bots, 10.0, A, B, rng.uniform(-3, 3, 4), rng)
    for i in range(4):
        phi = np.linspace(0, 2 * np.pi, 400)
        c, s = math.cos(poses[i, 2]), math.sin(poses[i, 2])
        x = poses[i, 0] + c * A * np.cos(phi) - s * B * np.sin(phi)
        y = poses[i, 1] + s * A * np.cos(phi) + c * B * np.sin(phi)
        assert np.hypot(x, y).max() <= 10.0 - 0.5 + 1e-9
        for j in range(i + 1, 4):
            assert ellipse_gap(poses[i], poses[j], A, B) >= 0.5 - 1e-9


def test_the_lattice_packs_the_sites_of_an_analytic_count():
    """Bots of 1 x 0.5 cm in a ring of 40 cm: the sites fill the disc their centres can
    reach, of radius 40 - gap - a, at the lattice's density, to 3 % (measured 1.4 %)."""
    gap = 0.1
    sites = lattice_sites(40.0, 1.0, 0.5, gap)
    px = 2 + gap
    py = np.diff(np.unique(np.round(sites[:, 1], 9)))[0]
    area = math.pi * (40.0 - gap - 1.0) ** 2
    assert len(sites) == pytest.approx(area / (px * py), rel=0.03)


# -- the run as a user makes it ---------------------------------------------------------------


def test_one_bot_is_the_single_bot_run_to_the_bit(tmp_path):
    base = {"radius": 5.0, "duration": 0.4}
    plain = simulate(RunConfig(parameters=base), tmp_path / "plain", seed=3, progress=False)
    one = simulate(
        RunConfig(parameters=base, bots={"count": 1, "placement": "lattice"}),
        tmp_path / "one",
        seed=3,
        progress=False,
    )
    assert one[0].read_bytes() == plain[0].read_bytes()


def test_bot_zero_draws_the_single_bot_stream():
    """Bot 0's heading and schedule are those of the run of one bot of the same seed."""
    model, _ = _model({"radius": 8.0, "duration": 5.0})
    from softcell.engine.cell import realization_rng
    from softcell.engine.state import initial_state

    _, pose, schedule = initial_state(model, realization_rng(7, 2, 1))
    _, poses, schedules = start_bots(
        model, Bots(count=3), bot_rngs(7, 2, 1, 3), placement_rng(7, 2, 1)
    )
    assert poses[0, 2] == pose[2]
    np.testing.assert_array_equal(schedules[0].start, schedule.start)


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--bots", "30"], "parameter bots = 30 is not allowed: do not fit in a ring"),
        (["--bots", "3", "--cells", "2"], "several bots per cell in an assembly"),
        (["--bots", "3", "--free-bot"], "several bots need a ring"),
        (["--bots", "3", "--friction-law", "coulomb"], "is not linear"),
        (["--bots", "2", "--bot-placement", "ring", "--radius", "4"], "a ring of starting"),
        (["--bots", "0"], "parameter bots = 0 is not allowed"),
        (["--bots", "2", "--bot-interactions", "nope"], "no bot_interaction named 'nope'"),
    ],
)
def test_bots_that_cannot_run_are_one_line_before_anything_runs(tmp_path, capsys, flags, message):
    out = tmp_path / "bad"
    argv = ["simulate", "--radius", "8", "--duration", "0.3", "--quiet", "-o", str(out)]
    assert main([*argv, *flags]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
    assert not out.exists()


def test_a_file_of_several_bots_follows_the_schema_and_the_commands_take_it(tmp_path, capsys):
    out = tmp_path / "k2"
    argv = ["simulate", "--radius", "8", "--duration", "0.3", "--quiet", "-o", str(out)]
    assert main([*argv, "--bots", "2", "--seed", "5"]) == 0
    path = next(out.glob("*.nc"))
    ds = open_dataset(path)
    assert ds["bot_x"].dims == ("realization", "time", "bot")
    assert ds["bot_phase_fine"].dims == ("realization", "fine_time", "bot")
    assert ds.sizes["bot"] == 2
    np.testing.assert_array_equal(ds["bot_start_x"].values[0], ds["bot_x"].values[0, 0])
    assert main(["animate", str(path), "-o", str(tmp_path / "a.gif"), "--quiet"]) == 0
    assert main(["export", str(path), "-o", str(tmp_path / "a.gsd")]) == 0
    import gsd.hoomd

    with gsd.hoomd.open(str(tmp_path / "a.gsd")) as trajectory:
        frame = trajectory[0]
        assert int((frame.particles.typeid == 1).sum()) == 2  # two bots
    capsys.readouterr()
    assert main(["render", str(path), "-o", str(tmp_path / "r.mp4")]) == 2
    assert "render does not handle files of several bots" in capsys.readouterr().err


def test_an_interrupted_ring_of_bots_resumes_to_the_same_bytes(tmp_path, monkeypatch):
    import softcell.runner.tasks as tasks

    config = RunConfig(parameters={"radius": 8.0, "duration": 3.0}, bots={"count": 3})
    whole = simulate(config, tmp_path / "whole", seed=4, progress=False)[0]
    original = tasks.run_realization
    calls = {"n": 0}

    def interrupted(*args, **kwargs):
        def progress(dt):
            calls["n"] += 1
            if calls["n"] == 2:
                raise KeyboardInterrupt  # as if killed after the second chunk

        kwargs["progress"] = progress
        kwargs["checkpoint_every"] = 0.0
        return original(*args, **kwargs)

    monkeypatch.setattr(tasks, "run_realization", interrupted)
    out = tmp_path / "resumed"
    with pytest.raises(KeyboardInterrupt):
        simulate(config, out, seed=4, progress=False)
    assert not list(out.glob("*.nc"))
    assert list(out.glob(".*.ckpt.npz"))
    monkeypatch.setattr(tasks, "run_realization", original)
    resumed = simulate(config, out, seed=4, progress=False)[0]
    assert resumed.read_bytes() == whole.read_bytes()


def _order(folder, power: int) -> float:
    """|<e^(i p theta)>| over the bots (p = 1 polar, 2 nematic), averaged over the last two
    thirds of each file and over the files."""
    values = []
    for path in sorted(folder.glob("*.nc")):
        heading = open_dataset(path)["bot_angle"].values[0]
        order = np.abs(np.exp(1j * power * heading).mean(axis=-1))
        values.append(order[len(order) // 3 :].mean())
    return float(np.mean(values))


#: Four bots on a ring of starting points in a ring of 10 cm, 30 s, two realizations.
FOUR = ["simulate", "--radius", "10", "--duration", "30", "--quiet", "--bots", "4"]
FOUR += ["--bot-placement", "ring", "--seed", "3", "--realizations", "2"]


@pytest.mark.slow
def test_the_built_in_alignment_aligns_the_bots(tmp_path):
    """Polar order 0.83 with alignment (J = 500 N cm) against 0.44 without (measured; at
    J = 50 N cm, less than the tumble's 151 N cm, it was 0.45)."""
    from softcell.builtins.alignment import Alignment
    from softcell.testing import check_component

    check_component(Alignment)
    both = ["--bot-interactions", "bot_repulsion,alignment"]
    assert main([*FOUR, *both, "-o", str(tmp_path / "aligned")]) == 0
    assert main([*FOUR, "-o", str(tmp_path / "free")]) == 0
    assert _order(tmp_path / "aligned", 1) > 0.7 > 0.55 > _order(tmp_path / "free", 1)


@pytest.mark.slow
def test_the_nematic_recipe_of_the_plugin_guide_aligns_the_bots_axes(tmp_path, monkeypatch):
    # docs/plugins.md: "Nematic alignment of the bots' axes", run as it is written there.
    import re
    import sys
    from pathlib import Path

    from softcell.plugin import registered
    from softcell.testing import check_component

    text = (Path(__file__).parents[1] / "docs" / "plugins.md").read_text(encoding="utf-8")
    pattern = r"\*Nematic alignment of the bots' axes\*.*?```python\n(.*?)```"
    (block,) = re.findall(pattern, text, re.S)
    (tmp_path / "nematic_recipe.py").write_text(block, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = __import__("nematic_recipe")
    assert "nematic_recipe" in sys.modules
    check_component(module.NematicAlignment)
    with registered(module):
        both = ["--bot-interactions", "bot_repulsion,nematic_alignment"]
        assert main([*FOUR, *both, "-o", str(tmp_path / "aligned")]) == 0
    assert main([*FOUR, "-o", str(tmp_path / "free")]) == 0
    aligned, free = _order(tmp_path / "aligned", 2), _order(tmp_path / "free", 2)
    assert aligned > 0.7 > 0.6 > free  # measured: 0.81 and 0.46


def test_check_bot_interaction_finds_a_broken_third_law_and_a_wrong_jacobian():
    from softcell.plugin import BotInteraction
    from softcell.testing import check_bot_interaction

    @njit_kernel
    def push_a_only(pose_a, pose_b, context, coefficients, out):
        dx, dy = pose_b[0] - pose_a[0], pose_b[1] - pose_a[1]
        if dx * dx + dy * dy < 25.0:
            out[0] -= 0.01 * dx

    @njit_kernel
    def no_jacobian(pose_a, pose_b, context, coefficients, steps, scratch, jac):
        jac[0, 0] += 1.0

    class OneSided(BotInteraction):
        name = "one_sided"
        description = "pushes bot a only"

        def pair_kernel(self):
            return push_a_only

        def jacobian_kernel(self):
            return no_jacobian

        def reach(self):
            return 5.0

    with pytest.raises(AssertionError) as failed:
        check_bot_interaction(OneSided)
    message = str(failed.value)
    assert "forces are not equal and opposite" in message
    assert "jacobian_kernel differs from central differences" in message


@pytest.mark.slow
def test_rodas4_follows_the_explicit_scheme_with_several_bots():
    """Three bots 0.1 cm apart on a lattice in a ring of 8 cm, two of them colliding, 0.3 s
    from one state and one set of schedules: rodas4's several-bot loop at a tight tolerance
    (1e-8) and the explicit scheme's (dt = 1e-6 s, the paper's; an independent loop: one
    curve, every bot's partials added at the points, the interactions' forces, a forward
    step) within 5e-5 cm. Measured: 2.9e-5 cm, and 1.4e-5 at dt = 5e-7 s (the explicit
    scheme's first-order error); rodas4 at its default tolerance (3e-6) is 1.5e-4 cm from
    its own 1e-8 path here, above the 1e-4 cm the single bot holds over 5 s
    (tests/test_rodas4.py): a collision of bots costs accuracy at the default step control."""
    params = {"radius": 8.0, "duration": 0.3}
    model, _ = _model({**params, "atol": 1e-8, "rtol": 1e-8})
    registry = default_registry()
    rodas4 = registry.get("integrator", "rodas4")(model.params)
    explicit = registry.get("integrator", "explicit_euler")(model.params)
    bots = Bots(count=3, placement="lattice", gap=0.1)
    modes, poses, schedules = start_bots(model, bots, bot_rngs(2, 0, 0, 3), placement_rng(2, 0, 0))
    assert min(ellipse_gap(poses[0], poses[i], A, B) for i in (1, 2)) < 0.2
    times = np.arange(1, 31) * 0.01
    paths = []
    for stepper in (rodas4.build_bots(model, 3), explicit.build_bots(model, 3)):
        state = stepper.start(modes, poses, schedules)
        paths.append(stepper.sample(state, schedules, times))
    (modes_r, pose_r), (modes_e, pose_e) = paths
    assert np.abs(pose_r - pose_e).max() <= 5e-5
    assert np.abs(modes_r - modes_e).max() <= 5e-5
    assert np.abs(pose_r[-1] - poses.reshape(-1)).max() > 0.1  # the bots moved


# -- the analysis of several bots -------------------------------------------------------------


def _ring(points: np.ndarray, bots: np.ndarray, headings: np.ndarray) -> xr.Dataset:
    """One realization's samples as ring_statistics reads them: points (T, N) complex,
    bots (T, K) complex, headings (T, K) rad; the cell's centre the points' mean."""
    centre = points.mean(axis=1)
    return xr.Dataset(
        {
            "membrane_x": (("time", "node"), points.real),
            "membrane_y": (("time", "node"), points.imag),
            "cell_x": ("time", centre.real),
            "cell_y": ("time", centre.imag),
            "bot_x": (("time", "bot"), bots.real),
            "bot_y": (("time", "bot"), bots.imag),
            "bot_angle": (("time", "bot"), headings),
        }
    )


def test_the_ring_statistics_of_shapes_and_placements_known_exactly():
    from softcell.analysis.bots import SHAPE_MODES, ring_statistics

    xi = np.linspace(0, 2 * np.pi, 512, endpoint=False)
    # a three-lobed ring r = 10 (1 + 0.04 cos 3 phi): r_3 / r_0 = 0.02, the others 0
    lobed = (10 * (1 + 0.04 * np.cos(3 * xi)) * np.exp(1j * xi))[None]
    # four bots on the circle of radius 8, heading counter-clockwise around the centre
    angles = np.array([0.1, 1.7, 3.3, 4.9])
    bots = (8 * np.exp(1j * angles))[None]
    stats = ring_statistics(_ring(lobed, bots, (angles + np.pi / 2)[None]), a=1.5)
    expected = np.where(SHAPE_MODES == 3, 0.02, 0.0)
    np.testing.assert_allclose(stats["membrane_shape_amplitude"], expected, atol=2e-5)
    assert stats["bots_circulation"] == pytest.approx(1.0)
    assert stats["bots_circulation_abs"] == pytest.approx(1.0)
    assert stats["bots_polar_order"] == pytest.approx(0.0, abs=0.25)  # four spread headings
    # within 2 a = 3 cm of the lobed ring (radius 9.6 .. 10.4 cm): all four bots at 8 cm
    assert stats["bots_boundary_fraction"] == 1.0
    # an ellipse of semi-axes 12 and 8 sampled evenly in its parameter: gyration eigenvalues
    # 144 / 2 and 64 / 2, asphericity ((144 - 64) / (144 + 64))^2
    ellipse = (12 * np.cos(xi) + 8j * np.sin(xi))[None]
    aligned = np.zeros((1, 2))
    inner = np.array([[0.0, 4.0j]])  # 8 and 4 cm from the ellipse: none within 3 cm
    stats = ring_statistics(_ring(ellipse, inner, aligned), a=1.5)
    assert stats["membrane_asphericity"] == pytest.approx((80 / 208) ** 2, rel=1e-9)
    assert stats["bots_polar_order"] == 1.0
    assert stats["bots_boundary_fraction"] == 0.0


def test_the_analysis_of_several_bots_has_each_bot_and_the_cell_as_one_bot_sees_it(tmp_path):
    """Each bot's values split back into (realization, bot); the cell's quantities, which
    every bot shares, are those of the analysis of the ring seen through bot 0 alone."""
    import softcell

    config = RunConfig(parameters={"radius": 10.0, "duration": 30.0}, bots={"count": 3})
    files = simulate(config, tmp_path / "k3", seed=2, realizations=2, progress=False)
    ds = xr.concat([open_dataset(f) for f in files], dim="realization")
    options = {"discard": 10.0}
    several = softcell.analyze(ds, options)
    one = softcell.analyze(ds.isel(bot=0).drop_vars(["bot_start_x", "bot_start_y",
                                                     "bot_start_angle"]), options)  # fmt: skip
    assert several["mean_speed_realization"].dims == ("body", "realization", "bot")
    for name in ("msd_slope", "ballistic_velocity", "mean_speed", "mean_go_duration"):
        np.testing.assert_allclose(
            several[name].sel(body="cell").values, one[name].sel(body="cell").values,
            rtol=1e-12, equal_nan=True,
        )  # fmt: skip
    per_bot = several["mean_speed_realization"].sel(body="bot").values
    np.testing.assert_allclose(
        per_bot[:, 0], one["mean_speed_realization"].sel(body="bot").values, rtol=1e-12
    )
    for name in ("bots_boundary_fraction", "bots_polar_order", "membrane_asphericity"):
        values = several[f"{name}_realization"].values
        assert several[name].values == pytest.approx(values.mean())
        assert several[f"{name}_error"].values == pytest.approx(values.std(ddof=1) / np.sqrt(2))
        assert "across the 2 realizations" in several[f"{name}_error"].attrs["error"]


# -- the study ---------------------------------------------------------------------------------


def _point(count, shape="elongated", alignment=0.0, **values):
    base = {"radius": 12.0, "shape": shape, "count": count, "alignment": alignment,
            "per_area": count / (math.pi * 144), "uniform_boundary_fraction": 0.5}  # fmt: skip
    for key in ("boundary_fraction", "asphericity", "polar_order", "velocity", "persistence",
                "d_hat"):  # fmt: skip
        value, error = values.get(key, (1.0, 0.1))
        base[key], base[f"{key}_sem"] = value, error
    return base


def test_the_study_judges_each_trend_and_can_find_it_wrong():
    """Synthetic points: each rule agrees, disagrees or is undecided by the 2-sigma rule."""
    from softcell.studies.bots import trends

    points = [
        _point(1, velocity=(1.0, 0.05)),
        _point(
            4,
            boundary_fraction=(0.9, 0.05),
            asphericity=(0.02, 0.001),
            velocity=(2.0, 0.05),
            d_hat=(5.0, 0.1),
        ),  # fmt: skip
        _point(
            16,
            boundary_fraction=(0.55, 0.05),
            asphericity=(0.05, 0.001),
            velocity=(1.05, 0.05),
            d_hat=(1.0, 0.1),
        ),  # fmt: skip
        _point(16, shape="round", d_hat=(2.0, 0.1)),
        _point(16, alignment=500.0, velocity=(0.5, 0.05)),
        {**_point(32), "does_not_fit": True},
    ]
    rules = {r["claim"].split(":")[0]: r for r in trends(points)}
    gather = rules["bots gather at the membrane"]
    # 0.9 +- 0.05 and two of 1.0 +- 0.1 against 0.5 agree; 0.55 +- 0.05 is undecided
    assert (gather["agrees"], gather["undecided"]) == (3, 1)
    rounder = rules["the ring is rounder with more bots"]
    assert rounder["disagrees"] == 1  # 0.05 at K = 16 above 0.02 at K = 4
    elongated = rules["elongated bots move the ring farther"]
    assert elongated["disagrees"] == 1  # 1.0 against the round bots' 2.0
    aligned = rules["aligned bots drive the ring faster"]
    assert aligned["disagrees"] == 1
    more = rules["more bots drive the ring faster"]
    assert (more["agrees"], more["undecided"], more["disagrees"]) == (1, 1, 1)


def test_a_bots_design_that_cannot_run_is_one_line(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["study", "bots", "--quick", "--counts", "2.5", "-o", str(out)]) == 2
    assert "--counts 2.5 is not allowed" in capsys.readouterr().err
    assert main(["study", "bots", "--quick", "--realizations", "1", "-o", str(out)]) == 2
    assert "realizations = 1: must be >= 2" in capsys.readouterr().err
    assert not out.exists()


def test_the_persistent_walk_fit_recovers_a_known_walk():
    from softcell.studies.bots import persistent_walk

    lag = np.geomspace(0.01, 25.0, 60)
    v, tau = 1.3, 2.0
    msd = 2 * v * v * tau * (lag - tau * (1 - np.exp(-lag / tau)))
    fit = persistent_walk(lag, msd)
    assert fit["velocity"] == pytest.approx(v, rel=1e-9)
    assert fit["persistence"] == pytest.approx(tau, rel=1e-9)
    assert fit["d_hat"] == pytest.approx(2 * v * v * tau, rel=1e-9)
    assert math.isnan(persistent_walk(lag[:3], msd[:3])["velocity"])  # too few lags


def test_the_bots_repel_exactly_within_the_cut_off():
    """Over random placements: forces where the gap is within the cut-off (1.25 cm), none
    beyond it (the kernel's quick separation test never drops a pair that touches)."""
    rng = np.random.default_rng(5)
    cutoff = COEFFICIENTS[2]
    seen = {True: 0, False: 0}
    for _ in range(400):
        pa = np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)])
        angle, d = rng.uniform(0, 2 * np.pi), rng.uniform(2 * B, 2 * A + cutoff + 0.5)
        pb = np.array([d * math.cos(angle), d * math.sin(angle), rng.uniform(-np.pi, np.pi)])
        gap = ellipse_gap(pa, pb, A, B)
        if abs(gap - cutoff) < 1e-6:
            continue
        out = np.zeros(6)
        bot_repulsion_kernel(pa, pb, CONTEXT, COEFFICIENTS, out)
        within = gap <= cutoff
        assert bool(np.any(out != 0)) == within, (gap, out)
        seen[within] += 1
    assert min(seen.values()) > 50
