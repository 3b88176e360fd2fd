"""A component's kernels are compiled against its contract's signature when the model is
built: a mismatch is one line naming where the component came from, the component, the kernel
and the signature, before any time step."""

import types

import numpy as np
import pytest
from numba import njit

import softcell
from softcell.builtins.run_and_tumble import RunAndTumble
from softcell.cli import main
from softcell.components.contracts import EnergyTerm, FrictionLaw
from softcell.engine import build_model
from softcell.errors import ContractError
from softcell.model.parameters import MODEL_PARAMETERS, Parameters
from softcell.testing import registered


@njit
def partials_missing_dpose(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y
):  # one argument short
    for n in range(x.size):
        p0x[n] += coefficients[0] * x[n]


@njit
def drive_writing_an_array(phase, data, pose, context, coefficients, out):
    out[0] = pose  # a float64 slot cannot take an array: does not type


class ShortTerm(EnergyTerm):
    name = "short_term"
    description = "a partials kernel one argument short (a test)"

    def partials_kernel(self):
        return partials_missing_dpose

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        return 0.0 * x


class PlainTerm(ShortTerm):
    name = "plain_term"
    description = "a partials kernel that is not compiled (a test)"

    def partials_kernel(self):
        return lambda *args: None


class BadDrive(RunAndTumble):
    name = "bad_drive"
    description = "a drive kernel that does not type (a test)"

    def drive_kernel(self):
        return drive_writing_an_array


PLUGIN = types.SimpleNamespace(
    softcell_energy_terms=softcell.hookimpl(lambda: [ShortTerm, PlainTerm]),
    softcell_driving_protocols=softcell.hookimpl(lambda: [BadDrive]),
)


@pytest.mark.parametrize(
    "terms, protocol, message",
    [
        (
            ["bending", "short_term"],
            "run_and_tumble",
            r"^registered object 'test_plugin': energy term 'short_term': "
            r"partials_kernel\(\) does not compile for the "
            r"contract's signature void\(float64\[::1\], .*\): Signature mismatch: "
            r"16 argument types "
            r"given, but function takes 15 arguments$",
        ),
        (
            ["plain_term"],
            "run_and_tumble",
            r"^registered object 'test_plugin': energy term 'plain_term': "
            r"partials_kernel\(\) returned <function .*>, "
            r"not a numba.njit function$",
        ),
        (
            ["bending"],
            "bad_drive",
            r"^registered object 'test_plugin': driving protocol 'bad_drive': "
            r"drive_kernel\(\) does not compile for the "
            r"contract's signature void\(int8, float64, .*\): .*setitem",
        ),
    ],
)
def test_a_kernel_that_breaks_its_contract_stops_the_build(terms, protocol, message):
    with registered(PLUGIN) as registry:
        with pytest.raises(ContractError, match=message) as info:
            build_model(Parameters({"radius": 4.0}), terms, protocol, registry=registry)
    assert "\n" not in str(info.value)


def test_the_command_line_reports_it_in_one_line_with_exit_2(tmp_path, capsys):
    with registered(PLUGIN):
        status = main(
            [
                "simulate",
                "--radius",
                "4",
                "--duration",
                "0.01",
                "--quiet",
                "--energy-terms",
                "bending,tension,short_term",
                "-o",
                str(tmp_path),
            ]
        )
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2
    assert len(err) == 1
    assert err[0].startswith(
        "softcell: error: registered object 'test_plugin': energy term "
        "'short_term': partials_kernel()"
    )
    assert not list(tmp_path.glob("*.nc"))


ENGINE_TYPES = """
import json
from softcell.engine import build_integrator, build_model
from softcell.model.parameters import Parameters
from softcell.components.registry import default_registry
from softcell.engine.cell import realization_rng, run_realization

counts = {}
for integrator, protocol, extra in (("rodas4", "run_and_tumble", {}),
                                    ("explicit_euler", "pivot_run_and_tumble", {"dt": 1e-6})):
    params = default_registry().parameters({"radius": 4.0, "duration": 0.01, "cutoff": 4,
                                            "nodes": 64, "stored_nodes": 16, **extra})
    model = build_model(params, ["bending", "tension", "contact"], protocol,
                        registry=default_registry())
    run_realization(model, build_integrator(integrator, params, default_registry()).build(model),
                    realization_rng(0, 0, 0))
    for component in (*model.terms, model.protocol):
        for method in type(component).kernels:
            kernel = getattr(component, method)()
            if kernel is not None:
                counts[f"{component.name}.{method}"] = len(kernel.overloads)
print(json.dumps(counts))
"""


@pytest.mark.slow
def test_the_contract_signatures_are_the_types_the_engine_calls_with():
    """In a new process, after both integrators have run, every built-in kernel has exactly
    one compiled signature: the contract's. A declared signature other than the engine's
    types would leave two (the check's and the engine's)."""
    import json
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-c", ENGINE_TYPES], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    counts = json.loads(run.stdout.strip().splitlines()[-1])
    assert len(counts) == 8  # 3 terms x (partials, hessian) and 2 drives
    assert set(counts.values()) == {1}, counts


# -- non-finite kernels are named ------------------------------------------------------------


@njit
def partials_nan(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    for n in range(x.size):
        p0x[n] += 0.0
        p1y[n] += np.nan if n == 5 else 0.0


@njit
def partials_nan_away(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    # Finite while the bot is within 0.1 cm of the origin, NaN once it has run away.
    if pose[0] * pose[0] + pose[1] * pose[1] > 0.01:
        dpose[0] += np.nan


@njit
def velocity_nan(x, y, tx, ty, fx, fy, coefficients, vx, vy):
    for n in range(fx.size):
        vx[n] = fx[n] / coefficients[0]
        vy[n] = np.sqrt(-1.0 - fy[n] * fy[n])  # NaN everywhere


class NanTerm(ShortTerm):
    name = "nan_term"
    description = "a partials kernel that writes NaN (a test)"
    reads_pose = True

    def partials_kernel(self):
        return partials_nan


class NanAwayTerm(NanTerm):
    name = "nan_away"
    description = "a partials kernel that writes NaN once the bot has moved (a test)"

    def partials_kernel(self):
        return partials_nan_away


class NanLaw(FrictionLaw):
    name = "nan_law"
    description = "a friction law whose velocity is NaN (a test)"
    parameters = (MODEL_PARAMETERS["membrane_friction"],)

    def velocity_kernel(self):
        return velocity_nan


NAN_PLUGIN = types.SimpleNamespace(
    softcell_energy_terms=softcell.hookimpl(lambda: [NanTerm, NanAwayTerm]),
    softcell_friction_laws=softcell.hookimpl(lambda: [NanLaw]),
)
SMALL = ["--radius", "4", "--cutoff", "4", "--nodes", "64", "--stored-nodes", "16", "--quiet"]


@pytest.mark.parametrize(
    ("flags", "named"),
    [
        (
            ["--energy-terms", "bending,tension,contact,nan_term"],
            "energy term 'nan_term': partials_kernel() wrote non-finite p1y at point 5 of 64",
        ),
        (
            ["--friction-law", "nan_law"],
            "friction law 'nan_law': velocity_kernel() wrote non-finite vy at point 0 of 32",
        ),
    ],
)
@pytest.mark.parametrize("integrator", ["rodas4", "explicit_euler"])
def test_a_non_finite_kernel_is_named_before_any_step(tmp_path, capsys, flags, named, integrator):
    with registered(NAN_PLUGIN):
        status = main(
            ["simulate", *SMALL, "--duration", "0.05", "--integrator", integrator, *flags,
             "-o", str(tmp_path)]
        )  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1
    assert err[0] == (
        f"softcell: error: registered object 'test_plugin': {named} at the initial state "
        "(t = 0 s), before any time step"
    )
    assert not list(tmp_path.glob("*.nc")) and not list(tmp_path.glob(".*ckpt*"))


@pytest.mark.parametrize(
    "integrator", [pytest.param("rodas4", marks=pytest.mark.slow), "explicit_euler"]
)
def test_a_kernel_that_goes_non_finite_later_is_named_when_the_run_fails(
    tmp_path, capsys, integrator
):
    with registered(NAN_PLUGIN):
        status = main(
            ["simulate", *SMALL, "--duration", "1", "--integrator", integrator, "--dt", "1e-5",
             "--energy-terms", "bending,tension,contact,nan_away", "-o", str(tmp_path)]
        )  # fmt: skip
    # the run compiles the plugin's model first, and says so the first time on a machine
    err = [
        line
        for line in capsys.readouterr().err.strip().splitlines()
        if not line.startswith("softcell: compiling the model")
    ]
    assert status == 2 and len(err) == 1, err
    assert (
        "the first non-finite output is registered object 'test_plugin': energy term "
        "'nan_away': partials_kernel() wrote non-finite dpose"
        in err[0]
        and "reduce dt" not in err[0]
    ), err[0]


def test_a_run_that_diverges_with_finite_kernels_says_so():
    # A state that went non-finite while every built-in kernel is finite before it and along
    # its course: the integration itself is blamed, not a component.
    from softcell.engine.diagnose import diagnose
    from softcell.engine.state import initial_state

    registry = softcell.components.registry.default_registry()
    params = registry.parameters({"radius": 4.0, "cutoff": 4, "nodes": 64, "stored_nodes": 16})
    model = build_model(
        params, ["bending", "tension", "contact"], "run_and_tumble", registry=registry
    )
    modes, pose, schedule = initial_state(model, np.random.default_rng(1))
    why = diagnose(
        model,
        np.array([0.0, 0.01]),
        np.vstack([modes, np.full_like(modes, np.nan)]),
        np.vstack([pose, np.full(3, np.nan)]),
        schedule,
    )
    assert why == (
        "every component's kernels are finite at the last finite state (t = 0 s) and just "
        "ahead of it: the integration itself diverged (reduce dt or tighten the tolerances)"
    )


def test_check_component_reports_a_wrong_kernel_signature_as_a_violation():
    # Before: a bare TypeError from numba ("No matching definition ...").
    from softcell.testing import check_component

    with pytest.raises(AssertionError, match=r"energy term 'short_term' breaks its contract:\n"
                       r"- a kernel cannot be called as the contract calls it"):  # fmt: skip
        check_component(ShortTerm)


def test_check_component_reports_a_unit_that_is_no_unit():
    # Before: check_component passed a component declaring "bananas" (registration skips it).
    from fakeplugins.badunits import Bananas

    from softcell.testing import check_component

    with pytest.raises(AssertionError, match=r"parameter 'banana_level': .*bananas"):
        check_component(Bananas)
