"""The engine and ensembles: reproducibility, workers, resume, blow-up, plugins, CLI."""

import os
import signal
import subprocess
import sys
import time
import types

import numpy as np
import pytest
from numba import njit

import softcell
from softcell.cli import main
from softcell.components.contracts import EnergyTerm
from softcell.components.registry import default_registry
from softcell.engine import (
    SimulationError,
    build_integrator,
    build_model,
    circle_modes,
    force_modes,
    sample_times,
    total_energy,
)
from softcell.errors import ParameterError
from softcell.model.configuration import RunConfig
from softcell.model.parameters import Parameters, ParameterSpec
from softcell.runner.ensemble import simulate
from softcell.testing import registered

# A coarse membrane (cutoff 4) is stable at dt = 1e-5 s, which keeps these tests fast.
COARSE = {"cutoff": 4, "nodes": 64, "stored_nodes": 16, "dt": 1e-5}
SHORT = {"radius": [4.0, 12.0], "duration": 0.03, **COARSE}


def test_sampling_grid():
    t = sample_times(Parameters({"duration": 100.5, "sample_switch": 100.0}))
    assert t[0] == 0 and t[1] == pytest.approx(0.01)
    assert t[9999] == pytest.approx(99.99) and t[10000] == 100.0 and t[-1] == pytest.approx(100.5)
    assert np.all(np.diff(t) > 0)


def test_same_seed_same_bytes_whatever_the_workers(tmp_path):
    """In this process, on a local dask cluster, and through a scheduler's address (the
    explicit scheme: each worker process compiles its stepper, and this one compiles fast)."""
    config = RunConfig(parameters=SHORT).updated(components={"integrator": "explicit_euler"})
    one = simulate(config, tmp_path / "one", realizations=2, seed=5, progress=False)
    two = simulate(config, tmp_path / "two", realizations=2, seed=5, workers=2, progress=False)
    assert [p.read_bytes() for p in one] == [p.read_bytes() for p in two]
    from distributed import LocalCluster

    # A scheduler reached over loopback, as a remote one would be.
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        three = simulate(
            config,
            tmp_path / "three",
            realizations=2,
            seed=5,
            progress=False,
            scheduler=cluster.scheduler_address,
        )
    assert [p.read_bytes() for p in one] == [p.read_bytes() for p in three]
    other = simulate(config, tmp_path / "other", realizations=2, seed=6, progress=False)
    assert one[0].read_bytes() != other[0].read_bytes()
    ds = softcell.open_dataset(tmp_path / "one")
    assert ds.sizes["radius"] == 2 and ds.sizes["realization"] == 2
    softcell.validate(ds)


def test_a_cluster_starts_the_longest_realizations_first(tmp_path):
    """Every task goes to dask with its simulated seconds as priority, so a long realization
    never runs alone at the end (the full design puts its 1800 s radii last)."""
    from softcell.runner.cluster import run_on_cluster
    from softcell.runner.ensemble import plan

    config = RunConfig(parameters={"radius": [4.0, 12.0], "duration": [2.0, 30.5]})
    tasks = plan(config, tmp_path, realizations=1, seed=0, registry=default_registry())

    class Refusing:
        """A client that records what it is given and then fails the wait."""

        submitted: list = []

        def submit(self, fn, task, *args, priority=0, **kwargs):
            self.submitted.append((task.params.duration, priority))
            return object()

        def cancel(self, futures):
            self.cancelled = len(futures)

    client = Refusing()
    with pytest.raises(ValueError, match="No clients found"):  # dask waits on no client
        run_on_cluster(tasks, client)
    assert sorted(client.submitted) == [(2.0, 2), (2.0, 2), (30.5, 31), (30.5, 31)]
    assert client.cancelled == 4


@pytest.mark.parametrize("compiles", [True, False])
def test_a_run_says_it_compiles_before_its_bar_moves(tmp_path, monkeypatch, compiles):
    """The line comes before the first realization, and only when the model's code is not
    cached yet (whether it is: tests/test_compile_cache.py)."""
    import softcell.runner.ensemble as ensemble

    said = []
    asked = []
    monkeypatch.setattr(
        ensemble, "compiles_on_first_call", lambda task, registry: asked.append(task) or compiles
    )
    original = ensemble.run_task
    monkeypatch.setattr(
        ensemble, "run_task", lambda *a, **k: said.append("run") or original(*a, **k)
    )
    config = RunConfig(parameters={"radius": 4.0, "duration": 0.02, **COARSE})
    simulate(config, tmp_path / "run", progress=False, log=said.append)
    assert len(asked) == 1
    compiling = [line for line in said if line.startswith("compiling the model")]
    assert said.index("run") == (0 if not compiles else 1)
    assert len(compiling) == (1 if compiles else 0)
    assert compiling == [] or "once per machine" in compiling[0]


def test_resume_after_interruption_gives_the_same_bytes(tmp_path, monkeypatch):
    config = RunConfig(parameters={"radius": 4.0, "duration": 0.05, **COARSE})
    whole = simulate(config, tmp_path / "whole", realizations=1, seed=2, progress=False)[0]

    import softcell.engine.cell as realization
    import softcell.runner.tasks as ensemble

    calls = {"n": 0}
    original = ensemble.run_realization

    def interrupted(*args, **kwargs):
        def progress(dt):
            calls["n"] += 1
            if calls["n"] == 3:
                raise KeyboardInterrupt  # as if killed after the third sample

        kwargs["progress"] = progress
        return original(*args, **kwargs)

    monkeypatch.setattr(ensemble, "run_realization", interrupted)
    monkeypatch.setattr(realization, "SAMPLES_PER_CALL", 1)
    with pytest.raises(KeyboardInterrupt):
        simulate(
            config,
            tmp_path / "resumed",
            realizations=1,
            seed=2,
            progress=False,
            checkpoint_every=0.0,
        )
    out = tmp_path / "resumed"
    assert not list(out.glob("*.nc"))  # nothing under a final name
    assert list(out.glob(".*.ckpt.npz"))
    monkeypatch.setattr(ensemble, "run_realization", original)
    resumed = simulate(config, out, realizations=1, seed=2, progress=False)[0]
    assert resumed.read_bytes() == whole.read_bytes()
    assert not list(out.glob(".*.ckpt.npz"))


def test_blow_up_names_time_realization_and_quantity(tmp_path):
    config = RunConfig(
        parameters={"radius": 4.0, "duration": 0.02, "dt": 1e-5, "membrane_friction": 1e-6}
    ).updated(components={"integrator": "explicit_euler"})
    with pytest.raises((SimulationError, ParameterError)) as info:
        simulate(config, tmp_path, realizations=1, progress=False)
    assert "dt" in str(info.value)  # the stability check refuses it up front
    # Past the stability check, a blow-up is caught while running.
    params = Parameters({"radius": 4.0, "duration": 0.02, **COARSE})
    model = build_model(
        params, ["bending", "tension", "contact"], "run_and_tumble", registry=default_registry()
    )
    stepper = build_integrator("explicit_euler", params, default_registry()).build(model)
    model.membrane_mobility *= 1e4
    from softcell.engine.cell import realization_rng, run_realization

    with pytest.raises(
        SimulationError,
        match=r"realization 7: (non-finite modes|membrane length)"
        r".* at t = [0-9.e-]+ s",
    ):
        run_realization(model, stepper, realization_rng(0, 0, 0), label=7)
    assert not list(tmp_path.glob("*.nc"))


@pytest.mark.parametrize("cutoff, points", [(16, 64), (40, 64)])
def test_blow_up_check_speeds_equal_the_direct_fourier_sum(cutoff, points):
    from softcell.engine.state import _speeds

    rng = np.random.default_rng(3)
    modes = rng.normal(size=(4, 2 * cutoff + 1)) + 1j * rng.normal(size=(4, 2 * cutoff + 1))
    k = np.arange(-cutoff, cutoff + 1)
    xi = 2 * np.pi * np.arange(points) / points
    direct = np.abs(np.exp(1j * np.outer(xi, k)) @ (1j * k * modes).T).T  # aliased too
    assert np.allclose(_speeds(modes, points), direct, rtol=1e-12, atol=0)
    circle = np.zeros(2 * cutoff + 1, complex)
    circle[cutoff + 1] = 7.0  # g_1 = R: a circle of radius 7 cm, length 14 pi
    assert 2 * np.pi * _speeds(circle, points).mean() == pytest.approx(14 * np.pi, rel=1e-14)


def test_unstable_dt_is_refused_with_the_bound():
    params = Parameters({"radius": 4.0, "cutoff": 20, "dt": 1e-6})
    model = build_model(
        params, ["bending", "tension", "contact"], "run_and_tumble", registry=default_registry()
    )
    with pytest.raises(ParameterError, match=r"dt = 1e-06 s .* must be < 2 / lambda_max"):
        build_integrator("explicit_euler", params, default_registry()).build(model)


ANCHOR = ParameterSpec(
    "anchor_stiffness", 0.01, "N cm-2", "a test spring to the origin", minimum=0.0
)


@njit
def anchor_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    kappa = coefficients[0]
    for n in range(x.size):
        p0x[n] += kappa * x[n]
        p0y[n] += kappa * y[n]


class Anchor(EnergyTerm):
    name = "anchor"
    description = "e = kappa |gamma|^2 / 2: a spring from every point to the origin (a test)"
    parameters = (ANCHOR,)

    def partials_kernel(self):
        return anchor_partials

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        return 0.5 * self.params["anchor_stiffness"] * (x**2 + y**2)


def test_third_party_energy_term_works_like_a_builtin(tmp_path):
    plugin = types.SimpleNamespace(softcell_energy_terms=softcell.hookimpl(lambda: [Anchor]))
    with registered(plugin):
        params = Parameters({"radius": 5.0}, [ANCHOR])
        model = build_model(
            params, ["bending", "tension", "anchor"], "run_and_tumble", registry=default_registry()
        )
        modes = circle_modes(5.0, model.cutoff)
        modes[model.cutoff] = 0.3 + 0.1j
        fhat, _ = force_modes(model, modes, np.zeros(3))
        h = np.zeros_like(modes)
        h[model.cutoff] = 1e-6
        d_re = (
            total_energy(model, modes + h, np.zeros(3))
            - total_energy(model, modes - h, np.zeros(3))
        ) / 2e-6
        assert d_re == pytest.approx(-2 * np.pi * fhat[model.cutoff].real, rel=1e-6)
        # The spring pulls the center back: f_hat_0 = -kappa g_0.
        assert fhat[model.cutoff] == pytest.approx(-0.01 * (0.3 + 0.1j), rel=1e-9)
        config = RunConfig(
            parameters={"radius": 5.0, "duration": 0.02, **COARSE, "anchor_stiffness": 0.02},
            components={**RunConfig().components, "energy_terms": ["bending", "tension", "anchor"]},
        )
        path = simulate(config, tmp_path, realizations=1, progress=False)[0]
        ds = softcell.read_dataset(path)
        assert '"anchor_stiffness": 0.02' in ds.attrs["softcell_parameters"]
        assert "anchor" in ds.attrs["softcell_components"]


def test_cli_simulate_writes_one_file_per_point_and_realization(tmp_path, capsys):
    assert (
        main(
            [
                "simulate",
                "--radius",
                "4,5",
                "--duration",
                "0.02",
                "--dt",
                "1e-5",
                "--cutoff",
                "4",
                "--nodes",
                "64",
                "--stored-nodes",
                "16",
                "--realizations",
                "2",
                "--quiet",
                "-o",
                str(tmp_path),
            ]
        )
        == 0
    )
    assert len(list(tmp_path.glob("*.nc"))) == 4
    assert main(["simulate", "--radius", "2", "-o", str(tmp_path), "--quiet"]) == 2
    assert "radius = 2.0 cm" in capsys.readouterr().err
    assert (
        main(
            [
                "simulate",
                "--free-bot",
                "--duration",
                "0.02",
                "--dt",
                "1e-5",
                "--quiet",
                "-o",
                str(tmp_path / "free"),
            ]
        )
        == 0
    )
    ds = softcell.open_dataset(tmp_path / "free" / "point000_realization0000.nc")
    assert np.isnan(ds["membrane_x"]).all() and not np.isnan(ds["bot_x"]).any()


def test_kill_9_then_the_same_command_resumes_to_the_same_bytes(tmp_path):
    flags = [
        "--integrator",
        "explicit_euler",
        "--radius",
        "4",
        "--duration",
        "8",
        "--dt",
        "1e-5",
        "--cutoff",
        "4",
        "--nodes",
        "64",
        "--stored-nodes",
        "16",
        "--seed",
        "3",
        "--quiet",
    ]
    command = [sys.executable, "-m", "softcell", "simulate", *flags]
    subprocess.run([*command, "-o", str(tmp_path / "whole")], check=True)
    out = tmp_path / "killed"
    killed = [*command, "--checkpoint-every", "0.1", "-o", str(out)]
    process = subprocess.Popen(killed)
    deadline = time.monotonic() + 300
    while not list(out.glob(".*.ckpt.npz")) and process.poll() is None:
        assert time.monotonic() < deadline, "no checkpoint appeared"
        time.sleep(0.01)
    time.sleep(0.15)  # let it run past its first checkpoint
    assert process.poll() is None, "the run ended before it could be killed"
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    assert not list(out.glob("*.nc")), "a killed run left a file under its final name"
    subprocess.run(killed, check=True)
    name = "point000_realization0000.nc"
    assert (out / name).read_bytes() == (tmp_path / "whole" / name).read_bytes()
    assert not list(out.glob(".*"))


def test_the_membrane_resampled_is_the_same_whatever_the_blas_threads():
    """A file must hold the same bytes whether a worker (one BLAS thread) or the command
    (as many as the cores) wrote it: the membrane's points are evaluated on one thread."""
    from threadpoolctl import threadpool_limits

    from softcell.engine.kernels.spectral import resample

    rng = np.random.default_rng(0)
    modes = rng.normal(size=(3001, 33)) + 1j * rng.normal(size=(3001, 33))
    with threadpool_limits(limits=1, user_api="blas"):
        one = resample(modes, 64)
    with threadpool_limits(limits=2, user_api="blas"):
        two = resample(modes, 64)
    assert one.tobytes() == two.tobytes()
