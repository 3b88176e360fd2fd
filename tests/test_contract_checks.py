"""softcell.testing's contract checks: every built-in component passes them, and each kind
of broken component fails them with a message naming what is broken."""

import numpy as np
import pytest
from numba import njit

from softcell.components.contracts import (
    DrivingProtocol,
    EnergyTerm,
    FrictionLaw,
    Schedule,
    StopGoDetector,
)
from softcell.components.registry import Registry
from softcell.model.parameters import MODEL_PARAMETERS, ParameterSpec
from softcell.testing import (
    check_component,
    check_driving_protocol,
    check_energy_term,
    check_friction_law,
    check_stopgo_detector,
)

BUILTINS = [e.component for e in Registry(entry_points=[]) if e.component.kind != "integrator"]


@pytest.mark.parametrize("cls", BUILTINS, ids=lambda c: c.name)
def test_every_builtin_component_keeps_its_contract(cls):
    check_component(cls)


@pytest.mark.parametrize("pose", [(0.9, 0.0, 0.0), (0.0, 1.9, 0.0), (-0.5, 0.5, 1.2)])
def test_the_contact_keeps_its_contract_where_the_bot_nearly_touches(pose):
    contact = Registry(entry_points=[]).get("energy_term", "contact")
    check_energy_term(contact, pose=pose)


# -- energy terms: a tether e = c (x^2 + y^2) / 2, and broken copies -------------------------


@njit
def tether(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):  # noqa: E501
    for n in range(x.size):
        p0x[n] += coefficients[0] * x[n]
        p0y[n] += coefficients[0] * y[n]


@njit
def tether_twice(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):  # noqa: E501
    for n in range(x.size):
        p0x[n] += 2 * coefficients[0] * x[n]
        p0y[n] += coefficients[0] * y[n]


@njit
def tether_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    for n in range(x.size):
        hww[n, 0, 0] += coefficients[0]
        hww[n, 1, 1] += 2 * coefficients[0]  # wrong: c


class Tether(EnergyTerm):
    name = "tether"
    description = "e = c (x^2 + y^2) / 2"
    parameters = (ParameterSpec("tether", 1e-3, "N cm-2", "stiffness c", minimum=0.0),)
    derivative_order = 0

    def partials_kernel(self):
        return tether

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        return 0.5 * self.params["tether"] * (np.asarray(x) ** 2 + np.asarray(y) ** 2)


class TwiceTether(Tether):
    def partials_kernel(self):
        return tether_twice


class ReadsSlope(Tether):
    def density(self, x, y, xp, yp, xpp, ypp, pose):
        return super().density(x, y, xp, yp, xpp, ypp, pose) + 0 * x + 1e-3 * np.asarray(xp)


class FeelsTheBot(Tether):
    def density(self, x, y, xp, yp, xpp, ypp, pose):
        return super().density(x, y, xp, yp, xpp, ypp, pose) * (1 + pose[0])


class WrongHessian(Tether):
    def hessian_kernel(self):
        return tether_hessian


def test_a_correct_energy_term_passes():
    check_energy_term(Tether)


@pytest.mark.parametrize(
    ("cls", "message"),
    [
        (TwiceTether, "de/dx differs from central differences of density()"),
        (ReadsSlope, "derivative_order = 0, but the density or the partials depend on x'"),
        (FeelsTheBot, "reads_pose is False, but the density or dpose depend on x_bot"),
        (WrongHessian, "hessian_kernel(): hww differs from central differences"),
    ],
)
def test_a_broken_energy_term_fails_naming_the_fault(cls, message):
    with pytest.raises(AssertionError, match="energy term 'tether' breaks its contract") as info:
        check_energy_term(cls)
    assert message in str(info.value)


# -- friction laws ------------------------------------------------------------------------------


@njit
def pushes_back(x, y, tx, ty, fx, fy, coefficients, vx, vy):
    for n in range(fx.size):
        vx[n] = -fx[n] / coefficients[0]
        vy[n] = -fy[n] / coefficients[0]


@njit
def zero_derivative(x, y, tx, ty, fx, fy, coefficients, dxx, dxy, dyx, dyy):
    for n in range(fx.size):
        dxx[n] = dyy[n] = dxy[n] = dyx[n] = 0.0


class AntiFriction(FrictionLaw):
    name = "anti"
    description = "v = -f / gamma: feeds energy in"
    parameters = (MODEL_PARAMETERS["membrane_friction"],)

    def velocity_kernel(self):
        return pushes_back


class WrongDerivative(FrictionLaw):
    name = "wrong_derivative"
    description = "viscous velocity, zero derivative"
    parameters = (MODEL_PARAMETERS["membrane_friction"],)

    def velocity_kernel(self):
        from softcell.builtins.friction_laws import viscous_velocity

        return viscous_velocity

    def derivative_kernel(self):
        return zero_derivative


class FalselyLinear(AntiFriction):
    name = "falsely_linear"
    linear = True


@pytest.mark.parametrize(
    ("cls", "message"),
    [
        (AntiFriction, "velocity_kernel() feeds energy in: f . v ="),
        (WrongDerivative, "derivative_kernel(): dvx/dfx differs from central differences"),
        (FalselyLinear, "linear is True, but v differs from f / membrane_friction"),
    ],
)
def test_a_broken_friction_law_fails_naming_the_fault(cls, message):
    with pytest.raises(AssertionError, match="breaks its contract") as info:
        check_friction_law(cls)
    assert message in str(info.value)


# -- driving protocols -------------------------------------------------------------------------


@njit
def kicked_at_the_axis(phase, data, pose, context, coefficients, out):
    out[0] = 1e-3 if pose[0] > 0.0 else -1e-3  # a jump in the pose: no Jacobian
    out[1] = 0.0
    out[2] = 0.0


@njit
def smooth_pull(phase, data, pose, context, coefficients, out):
    out[0] = -1e-3 * pose[0]
    out[1] = -1e-3 * np.sin(pose[1])
    out[2] = 1e-2 * np.cos(pose[2])


class Pull(DrivingProtocol):
    name = "pull"
    description = "a smooth pull towards the origin"

    def schedule(self, rng, duration):
        return Schedule(np.array([0.0]), np.array([1], dtype=np.int8), np.array([0.0]))

    def initial_heading(self, rng):
        return float(rng.uniform(-np.pi, np.pi))

    def drive_kernel(self):
        return smooth_pull


class Kicked(Pull):
    name = "kicked"

    def drive_kernel(self):
        return kicked_at_the_axis


def test_a_smooth_drive_passes_and_a_jump_in_the_pose_fails():
    check_driving_protocol(Pull)
    with pytest.raises(AssertionError, match="drive_kernel\\(\\) in phase 1 is not smooth"):
        check_driving_protocol(Kicked, seed=3)


# -- detectors ---------------------------------------------------------------------------------


class Inverted(StopGoDetector):
    name = "inverted"
    description = "go below 1 cm/s"

    def label(self, speed, interval):
        labels = (np.asarray(speed) < 1.0).astype(np.int8)
        labels[np.isnan(speed)] = -1
        return labels


class Floats(StopGoDetector):
    name = "floats"
    description = "labels as floats, NaN kept"

    def label(self, speed, interval):
        return (np.asarray(speed) > 1.0).astype(np.float64)


@pytest.mark.parametrize(
    ("cls", "message"),
    [
        (Inverted, "label() gives 0 at sample 20 of a stretch at 5 cm/s"),
        (Floats, "label() returned float64[1600] for float64[1600]: must be int8"),
    ],
)
def test_a_broken_detector_fails_on_the_planted_series(cls, message):
    with pytest.raises(AssertionError) as info:
        check_stopgo_detector(cls)
    assert message in str(info.value)


def test_an_integrator_is_not_checked_here():
    rodas4 = Registry(entry_points=[]).get("integrator", "rodas4")
    with pytest.raises(TypeError, match="is not an energy term"):
        check_component(rodas4)
