"""Assemblies of cells: the membrane-membrane contact (its forces against an independent
energy, its Jacobian against differences), the outer loop (one cell is the single-cell run,
two passive cells relax symmetrically, a periodic box is its replica), and the command line."""

import importlib
import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from matplotlib.path import Path as Polygon
from numba import njit

from softcell.cli import main
from softcell.components.registry import default_registry, registered
from softcell.engine import build_integrator, build_model, circle_modes, equilibrium_radius
from softcell.engine.cell import realization_rng, run_realization
from softcell.engine.groups import cell_rngs, run_assembly
from softcell.engine.kernels.spectral import resample
from softcell.integrators.rodas4 import compiled_group, group_work, pack
from softcell.io.netcdf import open_dataset
from softcell.model.assembly import Domain
from softcell.model.parameters import Parameters, ParameterSpec
from softcell.plugin import PairTerm, hookimpl
from softcell.schema import with_cell
from softcell.settings import CONTACT_CUTOFF_LENGTHS

TERMS = ["bending", "tension", "contact"]


def _built(pair_terms=("repulsion",), **values):
    registry = default_registry()
    params = Parameters(
        {"radius": 5.0, "duration": 1.0, **values}, registry.parameter_specs().values()
    )
    model = build_model(params, TERMS, "run_and_tumble", registry=registry, pair_terms=pair_terms)
    stepper = build_integrator("rodas4", params, registry).build(model)
    return model, stepper


@pytest.fixture(scope="module")
def built():
    return _built()


def _group_module(model):
    return importlib.import_module(compiled_group(model).py_func.__module__)


def _two_rings(model, gap, wobble=0.02):
    """Two resting rings side by side along x, ``gap`` (cm) apart, the first wobbled."""
    radius = equilibrium_radius(model.params)
    states = []
    for c, x in enumerate((0.0, 2 * radius + gap)):
        modes = circle_modes(radius, model.cutoff, complex(x, 0.0))
        if c == 0:
            modes[model.cutoff + 3] = wobble
        states.append(pack(modes, np.array([x + 0.3, 0.1, 0.2 + c])))
    return np.concatenate(states), radius


def _rates(model, stepper, u, shifts=None):
    """(the group's du/dt, the cells' own du/dt alone) at u."""
    work, pair = group_work(model, 2)
    if shifts is not None:
        pair.shifts[:] = shifts
    module = _group_module(model)
    phases, data = np.array([1, 1], np.int8), np.array([1.0, -1.0])
    out = np.zeros(u.size)
    count = module.group_rhs(u, phases, data, out, stepper.problem, stepper.ws, pair)
    nu = u.size // 2
    alone = np.zeros(u.size)
    for c in range(2):
        part = slice(c * nu, (c + 1) * nu)
        stepper.rhs(u[part], phases[c], data[c], alone[part], stepper.problem, stepper.ws)
    return out, alone, count, (module, work, pair, phases, data)


def _differences(module, stepper, pair, u, phases, data, h):
    """The group rate's Jacobian by central differences of step ``h`` in every unknown."""
    numeric = np.zeros((u.size, u.size))
    for i in range(u.size):
        plus, minus = u.copy(), u.copy()
        plus[i] += h
        minus[i] -= h
        fp, fm = np.zeros(u.size), np.zeros(u.size)
        module.group_rhs(plus, phases, data, fp, stepper.problem, stepper.ws, pair)
        module.group_rhs(minus, phases, data, fm, stepper.problem, stepper.ws, pair)
        numeric[:, i] = (fp - fm) / (2 * h)
    return numeric


def test_the_pair_force_is_minus_the_gradient_of_an_independent_contact_energy(built):
    """Two rings 2 lambda apart: the total force on the second (from its centre mode's rate)
    against -dU/dx of the energy summed with numpy over both rings' points, each point's
    distance taken to the other ring's circle."""
    model, stepper = built
    lam = float(model.params.contact_length)
    u, radius = _two_rings(model, 2 * lam, wobble=0.0)
    out, alone, count, _ = _rates(model, stepper, u)
    assert count > 40
    m = 2 * model.cutoff + 1
    nu = 2 * m + 3
    pair = out - alone
    # dg_0/dt = mobility f_hat_0 and the total force is 2 pi f_hat_0 (N)
    force = 2 * math.pi * pair[nu + model.cutoff] / model.membrane_mobility
    assert abs(pair[nu + m + model.cutoff]) < 1e-9 * abs(pair[nu + model.cutoff])  # along x

    n, l0 = model.nodes, model.params.membrane_length
    amplitude = float(model.params.contact_amplitude)

    def energy(separation):
        xi = 2 * np.pi * np.arange(n) / n
        ring = radius * np.exp(1j * xi)
        total = 0.0
        for points, centre in ((ring, separation), (ring + separation, 0.0)):
            rho = np.abs(points - centre) - radius
            e = np.where(rho <= CONTACT_CUTOFF_LENGTHS * lam, np.exp(-rho / lam), 0.0)
            total += (2 * np.pi / n) * (l0 / (2 * np.pi)) * amplitude * e.sum()
        return total

    s, h = 2 * radius + 2 * lam, 1e-6
    expected = -(energy(s + h) - energy(s - h)) / (2 * h)
    assert expected > 0  # repulsive
    # the polygon's sagitta (R (1 - cos(pi / N)) = 2.4e-5 cm = 2.4e-3 lambda) bounds the gap
    assert force == pytest.approx(expected, rel=5e-3)
    # momentum: the first ring gets the opposite force
    assert pair[model.cutoff] == pytest.approx(-pair[nu + model.cutoff], rel=1e-12)


def test_the_group_jacobian_is_the_derivative_of_the_group_rate(built):
    model, stepper = built
    u, _ = _two_rings(model, 0.03)
    _, _, count, (module, work, pair, phases, data) = _rates(model, stepper, u)
    assert count > 40
    module.group_jacobian(
        u, phases, data, stepper.problem, stepper.ws, pair, work.jac, work.scratch
    )
    jac = work.jac.copy()
    numeric = _differences(module, stepper, pair, u, phases, data, 1e-7)
    nu = u.size // 2
    cross = jac[:nu, nu:]
    assert np.abs(cross).max() > 1.0  # the rings are coupled
    np.testing.assert_allclose(cross, numeric[:nu, nu:], atol=1e-6 * np.abs(cross).max())
    np.testing.assert_allclose(jac, numeric, atol=1e-9 * np.abs(jac).max())


def test_an_assembly_of_one_cell_is_the_single_cell_run(built):
    model, stepper = built
    record = run_assembly(model, stepper, Domain(), np.zeros((1, 2)), cell_rngs(5, 0, 3, 1))
    _, single = _built()
    reference = run_realization(model, single, realization_rng(5, 0, 3))
    assert np.array_equal(record.modes[:, 0], reference.modes)
    assert np.array_equal(record.fine_pose[:, 0], reference.fine_pose)


def test_two_passive_cells_pressed_together_relax_symmetrically():
    """No drive: two rings started 0.5 lambda apart push each other away, mirror images of
    each other, and the friction-weighted centroid of the membranes stays put."""
    model, stepper = _built(drive_force=1e-30, drive_torque=1e-30, duration=0.5)
    radius = equilibrium_radius(model.params)
    lam = float(model.params.contact_length)
    centres = np.array([[-radius - 0.25 * lam, 0.0], [radius + 0.25 * lam, 0.0]])
    rngs = cell_rngs(0, 0, 0, 2)
    record = run_assembly(model, stepper, Domain(), centres, rngs)
    x = record.fine_center.real
    y = record.fine_center.imag
    assert x[-1, 1] - x[-1, 0] > x[0, 1] - x[0, 0] + 2 * lam  # pushed apart
    np.testing.assert_allclose(x[:, 0] + x[:, 1], 0.0, atol=1e-9)  # the centroid
    np.testing.assert_allclose(y, 0.0, atol=1e-9)
    np.testing.assert_allclose(x[:, 0], -x[:, 1], atol=1e-9)


def _crossing(periodic: bool):
    """Two driven cells touching across x = +-15 cm of a periodic box of side 30 cm, or the
    same two cells side by side in the open plane."""
    model, stepper = _built(duration=1.0)
    radius = equilibrium_radius(model.params)
    a = np.array([10.0, 0.0])
    b = a + np.array([2 * radius + 0.02, 0.0]) - ([30.0, 0.0] if periodic else 0.0)
    domain = Domain("periodic", 30.0) if periodic else Domain()
    record = run_assembly(model, stepper, domain, np.array([a, b]), cell_rngs(2, 0, 0, 2))
    return model, stepper, record


def test_a_periodic_box_is_its_replica_in_the_open_plane():
    """The rates at one state agree to rounding; the paths to the integrator's tolerance
    (the error control sees a cell at x = -10 cm and its replica at x = 20 cm in different
    roundings, so a step accepted in one may be rejected in the other)."""
    model, stepper, periodic = _crossing(True)
    _, _, replica = _crossing(False)
    assert periodic.statistics["grouped_intervals"] > 0
    u, radius = _two_rings(model, 0.03)
    nu = u.size // 2
    m = 2 * model.cutoff + 1
    wrapped = u.copy()
    wrapped[nu + model.cutoff] -= 30.0  # Re g_0 of the second ring
    wrapped[nu + 2 * m] -= 30.0  # its bot's x
    shifts = np.zeros((2, 2, 2))
    shifts[0, 1, 0], shifts[1, 0, 0] = 30.0, -30.0
    direct, _, count, _ = _rates(model, stepper, u)
    images, _, count_images, _ = _rates(model, stepper, wrapped, shifts)
    assert count == count_images > 40
    np.testing.assert_allclose(images, direct, rtol=1e-10, atol=1e-10 * np.abs(direct).max())
    np.testing.assert_allclose(periodic.fine_center[:, 0], replica.fine_center[:, 0], atol=1e-3)
    np.testing.assert_allclose(
        periodic.fine_center[:, 1] + 30.0, replica.fine_center[:, 1], atol=1e-3
    )


def _segment_distances(points, ring):
    """Each point's distance (cm) to the closed polygon ``ring`` (its edges, not vertices)."""
    a, b = ring, np.roll(ring, -1, axis=0)
    ab = b - a
    ap = points[:, None, :] - a[None]
    t = np.clip((ap * ab[None]).sum(-1) / (ab * ab).sum(-1)[None], 0.0, 1.0)
    d = ap - t[..., None] * ab[None]
    return np.hypot(d[..., 0], d[..., 1]).min(axis=1)


def _deepest(record, domain, model):
    """The deepest any membrane point goes into another ring (cm), over every sample, the
    rings as polygons of the model's N points."""
    worst = 0.0
    for t in range(record.modes.shape[0]):
        x, y = resample(record.modes[t], model.nodes)
        centre = record.modes[t, :, model.cutoff]
        for c in range(len(centre)):
            for d in range(len(centre)):
                if c == d:
                    continue
                direct = np.array([(centre[d] - centre[c]).real, (centre[d] - centre[c]).imag])
                shift = domain.displacement(np.zeros(2), direct) - direct
                ring = np.stack([x[d] + shift[0], y[d] + shift[1]], axis=1)
                points = np.stack([x[c], y[c]], axis=1)
                inside = Polygon(ring).contains_points(points)
                if inside.any():
                    worst = max(worst, float(_segment_distances(points[inside], ring).max()))
    return worst


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_no_membrane_goes_into_another_by_more_than_a_few_lambda(seed):
    """Four driven cells crowded into a small periodic box (area fraction 0.5), from a random
    placement: no membrane point ever gets more than 2 lambda inside another ring (measured
    over twelve seeds: at most 0.51 lambda; a membrane passing through another would go
    centimetres deep)."""
    from softcell.model.assembly import place_cells

    model, stepper = _built(duration=2.0)
    radius = equilibrium_radius(model.params)
    domain = Domain("periodic", math.sqrt(4 * math.pi * radius**2 / 0.5))
    rng = np.random.default_rng(seed)
    centres = place_cells(4, radius, domain, rng, placement="random", gap=0.05)
    record = run_assembly(model, stepper, domain, centres, cell_rngs(seed, 0, 0, 4))
    # A placement whose cells never touch in 2 s (seed 22011) tests nothing: draw another.
    assume(record.statistics["grouped_intervals"] > 0)
    lam = float(model.params.contact_length)
    assert _deepest(record, domain, model) < 2 * lam


def test_two_threads_give_the_same_bytes_as_one(built):
    """Eight cells crowded in a periodic box (area fraction 0.5, random placement), stepped
    on one thread and on two: the same record to the bit, groups and cells alone included
    (each thread steps with its own twin of the stepper)."""
    from softcell.model.assembly import place_cells

    model, stepper = _built(duration=0.6)
    radius = equilibrium_radius(model.params)
    domain = Domain("periodic", math.sqrt(8 * math.pi * radius**2 / 0.5))
    centres = place_cells(8, radius, domain, np.random.default_rng(3), placement="random", gap=0.05)
    one, two = (
        run_assembly(model, stepper, domain, centres, cell_rngs(3, 0, 0, 8), threads=n)
        for n in (1, 2)
    )
    assert one.statistics["grouped_intervals"] > 0  # groups were stepped, not only cells alone
    assert one.statistics == two.statistics
    for name in ("modes", "pose", "fine_center", "fine_pose"):
        assert np.array_equal(getattr(one, name), getattr(two, name)), name
    assert all(
        np.array_equal(a[k], b[k]) for a, b in zip(one.states, two.states, strict=True) for k in a
    )


@pytest.mark.parametrize("threads", [0, -1, 1.5, True, "2"])
def test_a_bad_thread_count_is_named(built, threads):
    from softcell.errors import ParameterError

    model, stepper = built
    domain = Domain("periodic", 40.0)
    centres = np.array([[-10.0, 0.0], [10.0, 0.0]])
    with pytest.raises(ParameterError, match=f"threads = {re.escape(str(threads))}"):
        run_assembly(model, stepper, domain, centres, cell_rngs(0, 0, 0, 2), threads=threads)


@pytest.mark.slow  # compiles a model of its own (walls and a post): ~1 min
@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_no_membrane_goes_into_a_wall_or_a_post_by_more_than_a_few_lambda(seed):
    """Five cells placed at random in a walled box of side 36 cm around a post of radius 3 cm:
    no membrane point goes more than 2 lambda into another ring, or 3 lambda into the post
    or the walls (the single cell's bound in a corral)."""
    from softcell.model.assembly import place_cells
    from softcell.model.obstacle_layout import surface_distances

    post = "post 0 0 3"
    registry = default_registry()
    params = Parameters(
        {"radius": 5.0, "duration": 2.0, "obstacles": post, "arena_side": 36.0},
        registry.parameter_specs().values(),
    )
    terms = [*TERMS, "obstacles", "arena"]
    model = build_model(
        params, terms, "run_and_tumble", registry=registry, pair_terms=["repulsion"]
    )
    stepper = build_integrator("rodas4", params, registry).build(model)
    domain = Domain("walls", 36.0)
    radius = equilibrium_radius(params)
    rng = np.random.default_rng(seed)
    centres = place_cells(5, radius, domain, rng, placement="random", gap=0.2, obstacles=post)
    record = run_assembly(model, stepper, domain, centres, cell_rngs(seed, 0, 0, 5))
    lam = float(params.contact_length)
    assert _deepest(record, domain, model) < 2 * lam
    x, y = resample(record.modes.reshape(-1, record.modes.shape[-1]), model.nodes)
    assert -surface_distances(x, y, post).min() < 3 * lam
    assert np.abs(np.stack([x, y])).max() < 18.0 + 3 * lam


def test_cell_dims_follow_the_time_dim():
    assert with_cell(("realization", "time", "node")) == ("realization", "time", "cell", "node")
    assert with_cell(("realization", "fine_time")) == ("realization", "fine_time", "cell")
    assert with_cell(("node",)) == ("node",)


def test_the_command_line_runs_an_assembly_into_one_file_with_a_cell_dim(tmp_path, capsys):
    out = tmp_path / "crowd"
    argv = ["simulate", "--radius", "5", "--duration", "0.3", "--quiet", "-o", str(out)]
    assert main([*argv, "--cells", "4", "--box", "30"]) == 0
    ds = open_dataset(out)
    assert ds["membrane_x"].dims == ("realization", "time", "cell", "node")
    assert ds["bot_x_fine"].dims == ("realization", "fine_time", "cell")
    assert ds.sizes["cell"] == 4
    assert ds["domain_box"].values.tolist() == [30.0]
    assert ds["domain_box"].attrs["boundary"] == "periodic"
    assert ds["domain_box"].attrs["units"] == "cm"
    assert (
        '"assembly": {"boundary": "periodic", "box": 30.0, "cells": 4'
        in ds.attrs["softcell_components"]
    )
    # the starts are the lattice's: four rings in the box's quarters
    np.testing.assert_allclose(np.abs(ds["cell_start_x"].values), 7.5)
    capsys.readouterr()
    assert main([*argv, "--cells", "4", "--box", "30"]) == 0  # kept: nothing to do


def test_an_assembly_thins_its_membrane_record_unless_told_otherwise(tmp_path):
    from softcell.model.configuration import RunConfig, with_assembly_defaults

    argv = ["simulate", "--radius", "5", "--duration", "0.3", "--quiet", "--cells", "2"]
    assert main([*argv, "--box", "30", "-o", str(tmp_path / "thin")]) == 0
    ds = open_dataset(tmp_path / "thin")
    np.testing.assert_allclose(ds["time"].values, [0.0, 0.1, 0.2, 0.3], atol=1e-12)
    assert ds.sizes["fine_time"] == 31  # the bodies' fine record stays whole
    assert ds.attrs["parameter_sample_switch"] == 0.0
    assert ds.attrs["membrane_record"].startswith("membranes every 0.1 s at 64 points")
    told = ["--box", "30", "--sample-switch", "0.2", "-o", str(tmp_path / "told")]
    assert main([*argv, *told]) == 0
    ds = open_dataset(tmp_path / "told")
    assert ds.sizes["time"] == 20 + 2  # every 0.01 s to 0.19 s, then 0.2 and 0.3
    assert "every 0.01 s until 0.2 s, then every 0.1 s" in ds.attrs["membrane_record"]
    # one cell is the single-cell run: nothing changes
    one = RunConfig(parameters={"radius": 5.0}, assembly={"cells": 1})
    assert with_assembly_defaults(one).parameters == {"radius": 5.0}


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--cells", "0"], "cells = 0 is not allowed"),
        (["--cells", "9", "--box", "30"], "cannot place 9 rings"),
        (["--cells", "2", "--boundary", "walls"], "box = None cm is not allowed"),
        (["--cells", "2", "--free-bot"], "needs membranes"),
        (["--cells", "2", "--integrator", "explicit_euler"], "needs rodas4"),
        (["--cells", "2", "--box", "40", "--obstacle", "0,0,3"], "obstacles in a periodic box"),
        (["--cells", "2", "--box", "40", "--boundary", "walls", "--obstacle", "0,-10,6"],
         "within 1 cm of an obstacle"),
        (["--cells", "2", "--friction-law", "coulomb"], "needs the viscous law"),
        (["--cells", "1", "--box", "18"], "must be > 20.5"),
    ],
)  # fmt: skip
def test_an_assembly_that_cannot_run_is_one_line_before_anything_runs(
    tmp_path, capsys, flags, message
):
    out = tmp_path / "bad"
    argv = ["simulate", "--radius", "5", "--duration", "0.3", "--quiet", "-o", str(out)]
    assert main([*argv, *flags]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not out.exists()


def test_an_interrupted_assembly_resumes_to_the_same_bytes(tmp_path, monkeypatch):
    import softcell.engine.groups as crowd
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    config = RunConfig(
        parameters={"radius": 5.0, "duration": 0.6}, assembly={"cells": 3, "box": 34.0}
    )
    whole = simulate(config, tmp_path / "whole", seed=4, progress=False)[0]
    original = crowd.run_assembly
    calls = {"n": 0}

    def interrupted(*args, **kwargs):
        def progress(dt):
            calls["n"] += 1
            if calls["n"] == 3:
                raise KeyboardInterrupt  # as if killed after the third chunk

        kwargs["progress"] = progress
        kwargs["checkpoint_every"] = 0.0
        return original(*args, **kwargs)

    monkeypatch.setattr(crowd, "run_assembly", interrupted)
    out = tmp_path / "resumed"
    with pytest.raises(KeyboardInterrupt):
        simulate(config, out, seed=4, progress=False)
    assert not list(out.glob("*.nc"))
    assert list(out.glob(".*.ckpt.npz"))
    monkeypatch.setattr(crowd, "run_assembly", original)
    resumed = simulate(config, out, seed=4, progress=False)[0]
    assert resumed.read_bytes() == whole.read_bytes()
    assert not list(out.glob(".*.ckpt.npz"))


# -- a pair term from a plugin: adhesion ------------------------------------------------------


@njit
def adhesion_law(rho, coefficients, out):
    """e = -s exp(-(rho / w)^2) within 5 w: coefficients [s (N cm), w (cm), 5 w (cm)]."""
    strength, width, reach = coefficients[0], coefficients[1], coefficients[2]
    if rho > reach:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = 0.0
        return
    x = rho / width
    e = -strength * math.exp(-x * x)
    out[0] = e
    out[1] = -2.0 * x / width * e
    out[2] = (4.0 * x * x - 2.0) / (width * width) * e


class Adhesion(PairTerm):
    name = "adhesion"
    description = "a Gaussian well between membranes"
    parameters = (
        ParameterSpec("adhesion_strength", 1e-3, "N cm", "depth of the adhesion well", minimum=0.0),
        ParameterSpec("adhesion_width", 0.2, "cm", "width of the adhesion well", minimum=0.0),
    )

    def coefficients(self):
        w = float(self.params.adhesion_width)
        return np.array([float(self.params.adhesion_strength), w, 5 * w])

    def law_kernel(self):
        return adhesion_law

    def reach(self):
        return 5 * float(self.params.adhesion_width)


class AdhesionPlugin:
    @staticmethod
    @hookimpl
    def softcell_pair_terms():
        return [Adhesion]


def test_a_plugin_pair_term_enters_the_forces_and_the_jacobian():
    with registered(AdhesionPlugin):
        model, stepper = _built(pair_terms=("repulsion", "adhesion"))
        assert model.pair_reach == pytest.approx(1.0)
        u, _ = _two_rings(model, 0.3)  # beyond the repulsion, inside the well
        out, alone, count, (module, work, pair, phases, data) = _rates(model, stepper, u)
        assert count > 40
        nu = u.size // 2
        # the second ring is pulled towards the first (its centre mode's rate along -x)
        assert (out - alone)[nu + model.cutoff] < 0 < (out - alone)[model.cutoff]
        module.group_jacobian(
            u, phases, data, stepper.problem, stepper.ws, pair, work.jac, work.scratch
        )
        # the well is 0.2 cm wide; smaller steps only add rounding (1e-7: 7e-6)
        numeric = _differences(module, stepper, pair, u, phases, data, 1e-5)
        cross = work.jac[:nu, nu:]
        assert np.abs(cross).max() > 1e-3
        np.testing.assert_allclose(cross, numeric[:nu, nu:], atol=1e-6 * np.abs(cross).max())


def test_adhering_passive_cells_draw_together_symmetrically():
    with registered(AdhesionPlugin):
        model, stepper = _built(
            pair_terms=("repulsion", "adhesion"),
            drive_force=1e-30,
            drive_torque=1e-30,
            duration=0.5,
        )
        radius = equilibrium_radius(model.params)
        centres = np.array([[-radius - 0.15, 0.0], [radius + 0.15, 0.0]])
        record = run_assembly(model, stepper, Domain(), centres, cell_rngs(0, 0, 0, 2))
    x = record.fine_center.real
    assert x[-1, 1] - x[-1, 0] < x[0, 1] - x[0, 0] - 0.02  # drawn together
    np.testing.assert_allclose(x[:, 0] + x[:, 1], 0.0, atol=1e-9)
    np.testing.assert_allclose(x[:, 0], -x[:, 1], atol=1e-9)


def test_an_unknown_pair_term_is_one_line(tmp_path, capsys):
    argv = ["simulate", "--radius", "5", "--duration", "0.3", "--quiet", "-o", str(tmp_path / "x")]
    assert main([*argv, "--cells", "2", "--pair-terms", "repulsion,glue"]) == 2
    err = capsys.readouterr().err
    assert "glue" in err and err.count("\n") == 1


def test_a_plugin_pair_terms_flags_are_its_own(tmp_path, capsys):
    # Before: "--adhesion-strength is a parameter of pair term 'adhesion', which this run
    # does not use" although --pair-terms named it (the TOML route worked); params had no
    # --cells or --pair-terms.
    with registered(AdhesionPlugin):
        argv = ["--cells", "2", "--pair-terms", "repulsion,adhesion", "--adhesion-strength", "2e-3"]
        assert main(["params", "--radius", "4", *argv]) == 0
        assert re.search(r"^adhesion_strength\s+0\.002\s+N cm", capsys.readouterr().out, re.M)
        assert main(["params", "--radius", "4", "--cells", "2", "--adhesion-strength", "2e-3"]) == 2
        assert "which this run does not use" in capsys.readouterr().err
