"""The example plugin distribution (examples/plugin): installed with pip, found through its
entry point, and each of its four components checked against what it claims."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from softcell.components.registry import default_registry
from softcell.engine import build_model, circle_modes, force_modes
from softcell.errors import ConfigError
from softcell.model.parameters import Parameters
from softcell.testing import registered

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plugin"
COARSE = ["--cutoff", "4", "--nodes", "64", "--stored-nodes", "16"]


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """softcell-example installed with pip into a fresh directory (not into this venv)."""
    target = tmp_path_factory.mktemp("site")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--quiet",
            "--no-deps",
            "--target",
            str(target),
            str(EXAMPLE),
        ],
        check=True,
    )
    return target


def softcell_cli(site, *args, cwd):
    """``python -m softcell ARGS`` with the example installed; its standard output (a failure
    raises)."""
    done = run_cli(site, *args, cwd=cwd)
    done.check_returncode()
    return done.stdout


@pytest.fixture(scope="module")
def example(site):
    """The install directory on sys.path: a registry built inside ``registered()`` then
    finds the plugin through its entry point, as an installed one is found."""
    sys.path.insert(0, str(site))
    try:
        with registered() as registry:
            origin = registry.entries("energy_term")
            assert any(
                e.component.name == "pressure" and "softcell-example" in e.origin for e in origin
            )
        yield registered
    finally:
        sys.path.remove(str(site))


def test_installed_distribution_registers_one_component_of_each_kind(site, tmp_path):
    listing = softcell_cli(site, "plugins", cwd=tmp_path)
    for name in ("pressure", "run_and_reverse", "anisotropic", "explicit_auto", "hysteresis"):
        block = listing.split(f"    {name}:")[1].split("\n    ")[0:2]
        assert block[1].strip() == (
            "origin: distribution softcell-example 1.0.0 "
            "(entry point example = softcell_example.plugin)"
        )


def test_installed_components_run_end_to_end_from_the_command_line(site, tmp_path):
    softcell_cli(
        site,
        "simulate",
        "--energy-terms",
        "bending,tension,contact,pressure",
        "--pressure",
        "2e-4",
        "--protocol",
        "run_and_reverse",
        "--integrator",
        "explicit_auto",
        "--radius",
        "5",
        "--duration",
        "0.3",
        *COARSE,
        "--quiet",
        "-o",
        "run",
        cwd=tmp_path,
    )
    softcell_cli(
        site,
        "analyze",
        "run",
        "-o",
        "analysis.nc",
        "--discard",
        "0.05",
        "--detector",
        "hysteresis",
        "--quiet",
        cwd=tmp_path,
    )
    run = xr.open_dataset(next((tmp_path / "run").glob("*.nc")))
    components = json.loads(run.attrs["softcell_components"])
    assert components["energy_terms"] == ["bending", "tension", "contact", "pressure"]
    assert (components["driving_protocol"], components["integrator"]) == (
        "run_and_reverse",
        "explicit_auto",
    )
    assert json.loads(run.attrs["softcell_parameters"])["pressure"] == 2e-4
    analysis = xr.open_dataset(tmp_path / "analysis.nc")
    assert analysis.attrs["softcell_detector"] == "hysteresis"


def test_pressure_pushes_a_circle_out_with_force_p_r(example):
    # f = P (y', -x') per unit xi; on the circle z = R e^{i xi} that is P R e^{i xi}, the
    # mode k = 1 alone; and E = -P * pi R^2.
    radius, pressure = 6.0, 3e-4
    with example():
        params = Parameters(
            {"radius": radius, "pressure": pressure}, default_registry().parameter_specs().values()
        )
        model = build_model(params, ["pressure"], "run_and_reverse", registry=default_registry())
    modes = circle_modes(radius, model.cutoff, 0.4 - 0.2j)
    fhat, dpose = force_modes(model, modes, np.zeros(3))
    expected = np.zeros_like(fhat)
    expected[model.cutoff + 1] = pressure * radius
    np.testing.assert_allclose(fhat, expected, atol=1e-14 * pressure * radius)
    xi = 2 * np.pi * np.arange(model.nodes) / model.nodes
    z = 0.4 - 0.2j + radius * np.exp(1j * xi)
    zp = 1j * radius * np.exp(1j * xi)
    term = model.terms[0]
    energy = (
        2
        * np.pi
        / model.nodes
        * term.density(z.real, z.imag, zp.real, zp.imag, 0, 0, np.zeros(3)).sum()
    )
    assert energy == pytest.approx(-pressure * np.pi * radius**2, rel=1e-12)


def test_run_and_reverse_runs_both_ways_at_f0_over_gamma(example, tmp_path):
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    with example():
        config = RunConfig(parameters={"radius": 5.0, "duration": 8.0}).updated(
            components={"driving_protocol": "run_and_reverse", "integrator": "explicit_auto"}
        )
        path = simulate(config, tmp_path, membrane=False, progress=False)[0]
    ds = xr.open_dataset(path)
    t = ds.time.values
    x, y, angle = (ds[n].values[0] for n in ("bot_x", "bot_y", "bot_angle"))
    phase = ds.bot_phase.values[0]
    run = (phase[:-1] == 1) & (phase[1:] == 1)
    along = ((np.diff(x) * np.cos(angle[:-1]) + np.diff(y) * np.sin(angle[:-1])) / np.diff(t))[run]
    v = 0.04275 / 0.00285  # F0 / gamma_T = 15 cm/s
    assert np.all(np.isclose(np.abs(along), v, rtol=1e-6))
    assert (along > 0).any() and (along < 0).any()


def test_explicit_auto_stays_stable_and_matches_the_reference(example, tmp_path):
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    runs = {}
    with example():
        for integrator in ("explicit_auto", "explicit_euler"):
            config = RunConfig(
                parameters={
                    "radius": 4.0,
                    "duration": 0.3,
                    "cutoff": 4,
                    "nodes": 64,
                    "stored_nodes": 16,
                }
            ).updated(components={"integrator": integrator})
            runs[integrator] = xr.open_dataset(
                simulate(config, tmp_path / integrator, seed=3, progress=False)[0]
            )
        params = Parameters(
            {"radius": 4.0, "cutoff": 4, "nodes": 64, "stored_nodes": 16},
            default_registry().parameter_specs().values(),
        )
        model = build_model(
            params, ["bending", "tension", "contact"], "run_and_tumble", registry=default_registry()
        )
        auto = default_registry().get("integrator", "explicit_auto")(params)
        from softcell.engine import explicit_decay_rate

        dt = auto.step(model)
    assert dt > 1e-6 and dt * explicit_decay_rate(model) <= 2 * 0.5
    assert round(0.01 / dt) * dt == pytest.approx(0.01, rel=1e-12)
    for name in ("bot_x", "bot_y", "cell_x", "cell_y"):
        np.testing.assert_allclose(
            runs["explicit_auto"][name], runs["explicit_euler"][name], atol=2e-3
        )


def test_hysteresis_holds_its_label_between_the_thresholds(example):
    with example():
        cls = default_registry().get("stopgo_detector", "hysteresis")
        detector = cls(Parameters({"go_above": 0.05, "stop_below": 0.02}, cls.parameters))
        with pytest.raises(Exception, match="stop_below"):
            cls(Parameters({"go_above": 0.01, "stop_below": 0.02}, cls.parameters))
    speed = np.array([[0.0, 0.03, 0.06, 0.04, 0.03, 0.01, 0.03, np.nan, 0.04, 0.07]])
    expected = np.array([[0, 0, 1, 1, 1, 0, 0, -1, 0, 1]])
    np.testing.assert_array_equal(detector.label(speed, 0.01), expected)


def run_cli(site, *args, cwd):
    """``python -m softcell ARGS`` with the example installed; the completed process."""
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), *filter(None, [os.environ.get("PYTHONPATH")])]),
    }
    return subprocess.run(
        [sys.executable, "-m", "softcell", *map(str, args)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
    )


@pytest.fixture(scope="module")
def hysteresis_run(site, tmp_path_factory):
    """A simulation made with the hysteresis detector and go_above = 0.07 (from TOML)."""
    folder = tmp_path_factory.mktemp("hysteresis")
    (folder / "sim.toml").write_text(
        "[parameters]\ngo_above = 0.07\nradius = 5\nduration = 0.3\ncutoff = 4\n"
        'nodes = 64\nstored_nodes = 16\ndt = 1e-5\n[components]\nstopgo_detector = "hysteresis"\n'
        'integrator = "explicit_euler"\n'
        "[analysis]\ndiscard = 0.05\nstop_below = 0.01\n"
    )
    softcell_cli(site, "simulate", "sim.toml", "-o", "run", "--quiet", cwd=folder)
    return folder


def detector_attrs(path):
    with xr.open_dataset(path) as ds:
        return (
            ds.attrs["softcell_detector"],
            json.loads(ds.attrs["softcell_detector_parameters"]),
            json.loads(ds.attrs["softcell_parameters"]),
            json.loads(ds.attrs["softcell_components"])["stopgo_detector"],
        )


def test_the_detector_and_its_parameters_come_from_the_input_toml_and_flags(site, hysteresis_run):
    cwd = hysteresis_run
    # The input's detector, its stored go_above, the TOML's stop_below.
    softcell_cli(site, "analyze", "run", "-o", "a.nc", "--config", "sim.toml", "--quiet", cwd=cwd)
    name, ran, params, component = detector_attrs(cwd / "a.nc")
    assert (name, component) == ("hysteresis", "hysteresis")
    assert ran == {"go_above": 0.07, "stop_below": 0.01}
    assert (params["go_above"], params["stop_below"]) == (0.07, 0.01)  # what ran, not the input's
    # A flag over the TOML over the input.
    softcell_cli(
        site, "analyze", "run", "-o", "b.nc", "--config", "sim.toml", "--go-above", "0.2",
        "--stop-below", "0.05", "--quiet", cwd=cwd,
    )  # fmt: skip
    assert detector_attrs(cwd / "b.nc")[1] == {"go_above": 0.2, "stop_below": 0.05}
    # Another detector: the input's hysteresis values do not follow it.
    softcell_cli(
        site, "analyze", "run", "-o", "c.nc", "--detector", "threshold", "--discard", "0.05",
        "--quiet", cwd=cwd,
    )  # fmt: skip
    name, ran, params, component = detector_attrs(cwd / "c.nc")
    assert (name, ran, component) == ("threshold", {"threshold": 0.03}, "threshold")


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (
            ["--stop-below", "0.5"],
            "stop/go detector 'hysteresis' refuses its parameters: parameter stop_below = 0.5",
        ),
        (
            ["--detector", "threshold", "--go-above", "0.5"],
            "'go_above' belongs to stop/go detector 'hysteresis', which this analysis does not use",
        ),
        (["--go-above", "-1"], "go_above = -1"),
        (["--hmm-go-speed", "0.3"], "unrecognized arguments: --hmm-go-speed"),
    ],
)
def test_a_refused_detector_setting_is_one_line_and_exit_2(site, hysteresis_run, flags, message):
    done = run_cli(site, "analyze", "run", "-o", "bad.nc", *flags, "--quiet", cwd=hysteresis_run)
    assert done.returncode == 2
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (hysteresis_run / "bad.nc").exists()


def test_analyze_takes_detector_parameters_as_options(example, hysteresis_run):
    from softcell.analysis import analyze
    from softcell.io.netcdf import open_inputs

    ds = open_inputs([hysteresis_run / "run"])
    with example():
        out = analyze(ds, {"discard": 0.05, "go_above": 0.3, "stop_below": 0.1})
        with pytest.raises(ConfigError, match="unknown analysis option 'go_abov'"):
            analyze(ds, {"go_abov": 0.3})
    assert json.loads(out.attrs["softcell_detector_parameters"]) == {
        "go_above": 0.3,
        "stop_below": 0.1,
    }


@pytest.mark.parametrize(
    ("kind", "name"),
    [
        ("energy_term", "pressure"),
        ("driving_protocol", "run_and_reverse"),
        ("friction_law", "anisotropic"),
        ("stopgo_detector", "hysteresis"),
    ],
)
def test_every_example_component_keeps_its_contract(example, kind, name):
    from softcell.testing import check_component

    with example():
        cls = default_registry().get(kind, name)
    check_component(cls)
    if kind == "stopgo_detector":  # its own thresholds, below the planted stop and go
        check_component(cls, {"go_above": 1.0, "stop_below": 0.5})


def test_anisotropic_friction_with_equal_frictions_is_the_viscous_law(example, tmp_path):
    # Along = across: the law is v = f / gamma_mem at every point, which the engine applies
    # through its general path (points, tangents, force density at M points) instead of the
    # viscous law's direct one. The two runs agree to rounding.
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import simulate

    coarse = {"radius": 4.0, "duration": 0.2, "cutoff": 4, "nodes": 64, "stored_nodes": 16}
    runs = {}
    with example():
        for law, extra in (("viscous", {}), ("anisotropic", {"friction_along": 3.42e-4})):
            config = RunConfig(parameters={**coarse, "dt": 1e-5, **extra}).updated(
                components={"friction_law": law, "integrator": "explicit_euler"}
            )
            runs[law] = xr.open_dataset(simulate(config, tmp_path / law, progress=False)[0])
    for name in ("bot_x", "bot_y", "membrane_x", "membrane_y"):
        np.testing.assert_allclose(runs["anisotropic"][name], runs["viscous"][name], atol=1e-9)
