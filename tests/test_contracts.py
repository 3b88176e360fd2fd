"""A component's kernels are compiled against its contract's signature when the model is
built: a mismatch is one line naming where the component came from, the component, the kernel
and the signature, before any time step."""

import types

import pytest
from numba import njit

import softcell
from softcell.cli import main
from softcell.core.engine import build_model
from softcell.core.params import Parameters
from softcell.core.plugin.contracts import DrivingProtocol, EnergyTerm, Schedule
from softcell.errors import ContractError
from softcell.plugins.run_and_tumble import RunAndTumble
from softcell.testing import registered


@njit
def partials_missing_dpose(x, y, xp, yp, xpp, ypp, pose, context, coefficients,
                           p0x, p0y, p1x, p1y, p2x, p2y):  # one argument short
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
    softcell_driving_protocols=softcell.hookimpl(lambda: [BadDrive]))


@pytest.mark.parametrize("terms, protocol, message", [
    (["bending", "short_term"], "run_and_tumble",
     r"^registered object 'test_plugin': energy term 'short_term': "
     r"partials_kernel\(\) does not compile for the "
     r"contract's signature void\(float64\[::1\], .*\): Signature mismatch: 16 argument types "
     r"given, but function takes 15 arguments$"),
    (["plain_term"], "run_and_tumble",
     r"^registered object 'test_plugin': energy term 'plain_term': "
     r"partials_kernel\(\) returned <function .*>, "
     r"not a numba.njit function$"),
    (["bending"], "bad_drive",
     r"^registered object 'test_plugin': driving protocol 'bad_drive': "
     r"drive_kernel\(\) does not compile for the "
     r"contract's signature void\(int8, float64, .*\): .*setitem"),
])
def test_a_kernel_that_breaks_its_contract_stops_the_build(terms, protocol, message):
    with registered(PLUGIN):
        with pytest.raises(ContractError, match=message) as info:
            build_model(Parameters({"radius": 4.0}), terms, protocol)
    assert "\n" not in str(info.value)


def test_the_command_line_reports_it_in_one_line_with_exit_2(tmp_path, capsys):
    with registered(PLUGIN):
        status = main(["simulate", "--radius", "4", "--duration", "0.01", "--quiet",
                       "--energy-terms", "bending,tension,short_term", "-o", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2
    assert len(err) == 1
    assert err[0].startswith("softcell: error: registered object 'test_plugin': energy term "
                             "'short_term': partials_kernel()")
    assert not list(tmp_path.glob("*.nc"))


def test_every_builtin_meets_its_contract():
    """The built-ins compile for the declared signatures (the contract describes the engine)."""
    model = build_model(Parameters({"radius": 4.0}), ["bending", "tension", "contact"],
                        "pivot_run_and_tumble")
    for term in model.terms:
        assert len(term.partials_kernel().signatures) >= 1
    assert isinstance(model.protocol, DrivingProtocol) and Schedule is not None
