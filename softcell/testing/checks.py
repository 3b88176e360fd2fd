"""Checks of a component against its contract, for plugin authors' tests.

Each ``check_*`` function builds the component with its defaults (or the values given),
evaluates its kernels on a generic state, compares them with what the contract says they
are, and raises one :class:`AssertionError` listing every violation (nothing when the
component keeps its contract):

- :func:`~softcell.testing.check_energy_term`: the partials against central differences of
  the density, the partials beyond ``derivative_order`` and the pose partials against
  ``reads_pose``, the Hessian kernels against differences of the partials and of the bot
  kernel (a gradient's derivative is symmetric, which the bot kernel's differences must be
  too).
- :func:`~softcell.testing.check_friction_law`: finite velocities that never feed energy in
  (f . v >= 0), the derivative against differences of the velocity, a ``linear`` law being
  v = f / gamma_mem.
- :func:`~softcell.testing.check_driving_protocol`: a schedule covering the duration, a
  finite heading, a finite drive in every phase the schedule uses, and a drive smooth
  enough in the pose for the central differences ``rodas4`` takes of it (two step sizes
  agree).
- :func:`~softcell.testing.check_stopgo_detector`: labels on a planted series (long go and
  stop stretches and missing samples) of the contract's shape, type and codes.
- :func:`~softcell.testing.check_component`: the check of the component's kind.

Example (in a plugin's tests)::

    from softcell.testing import check_component
    from my_plugin.posts import Posts

    def test_posts_keep_the_energy_term_contract():
        check_component(Posts, {"post_count": 3})
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from softcell.components.contracts import (
    SENSE_SIZE,
    BotInteraction,
    DrivingProtocol,
    EnergyTerm,
    FrictionLaw,
    PairTerm,
    Sense,
    StopGoDetector,
    kind_name,
)
from softcell.model.parameters import Parameters
from softcell.schema import GO, STOP, STOPGO_UNKNOWN

#: w = (x, y, x', y'', x'', y''): the curve's arguments, in the order of the partials.
W_NAMES = ("x", "y", "x'", "y'", "x''", "y''")
POSE_NAMES = ("x_bot", "y_bot", "theta_bot")


def _context(params: Parameters) -> tuple[float, np.ndarray]:
    """The radius R (cm) and a kernel's context: l0 (cm), the bot's semi-axes (cm)."""
    radius = float(params["radius"])
    axes = (float(params["bot_semi_major"]), float(params["bot_semi_minor"]))
    return radius, np.array([2 * math.pi * radius, *axes])


def _build(cls: type, values: Mapping[str, Any] | None):
    """The component with ``values``, once its class is well formed (its name, description,
    methods and the units of its parameters, which registration checks too)."""
    _fail(cls, cls.contract_problems())
    params = Parameters(dict(values or {}), cls.parameters)
    return cls(params), params


def _fail(component: type, problems: list[str]) -> None:
    if problems:
        raise AssertionError(
            f"{kind_name(component.kind)} {component.name!r} breaks its contract:\n- "
            + "\n- ".join(problems)
        )


def _contract_calls(check: Callable[..., None]) -> Callable[..., None]:
    """``check`` with a kernel that cannot be called as the contract calls it (numba's
    ``TypeError``: another signature) reported as the violation it is."""

    @functools.wraps(check)
    def checked(cls: type, *args: Any, **kwargs: Any) -> None:
        try:
            return check(cls, *args, **kwargs)
        except TypeError as exc:
            signatures = "; ".join(f"{k}: {v}" for k, v in getattr(cls, "kernels", {}).items())
            _fail(
                cls,
                [
                    "a kernel cannot be called as the contract calls it ("
                    + " ".join(str(exc).split())
                    + f"); the contract's signatures: {signatures}"
                ],
            )

    return checked


def _close(a: np.ndarray, b: np.ndarray, rtol: float, floor: float) -> tuple[bool, float]:
    """Whether a and b agree to rtol of the larger's size (at least ``floor``), and the
    worst relative difference."""
    scale = max(float(np.max(np.abs(a), initial=0.0)), float(np.max(np.abs(b), initial=0.0)))
    scale = max(scale, floor, 1e-300)
    worst = float(np.max(np.abs(a - b), initial=0.0)) / scale
    return worst <= rtol, worst


# -- energy terms ----------------------------------------------------------------------------


def _shape(radius: float, n: int, seed: int) -> list[np.ndarray]:
    """x, y, x', y', x'', y'' (cm) of a wobbly closed curve about the origin, at n points."""
    rng = np.random.default_rng(seed)
    xi = 2 * np.pi * np.arange(n) / n
    z = radius * np.exp(1j * xi)
    zp, zpp = 1j * z, -z
    for k in (-3, -2, 2, 3):
        c = 0.03 * radius * complex(*rng.normal(size=2))
        z, zp, zpp = (
            z + c * np.exp(1j * k * xi),
            zp + 1j * k * c * np.exp(1j * k * xi),
            zpp - k * k * c * np.exp(1j * k * xi),
        )
    return [np.ascontiguousarray(p) for v in (z, zp, zpp) for p in (v.real, v.imag)]


def _partials(term: EnergyTerm, w, pose, context, coef) -> tuple[np.ndarray, np.ndarray]:
    n = w[0].size
    out = [np.zeros(n) for _ in range(6)]
    dpose = np.zeros(3)
    term.partials_kernel()(*w, pose, context, coef, *out, dpose)
    return np.array(out), dpose


@_contract_calls
def check_energy_term(
    cls: type[EnergyTerm],
    values: Mapping[str, Any] | None = None,
    *,
    pose: tuple[float, float, float] = (0.3, -0.2, 0.4),
    nodes: int = 128,
    rtol: float = 1e-5,
    seed: int = 0,
) -> None:
    """Check an energy term against its contract on a wobbly curve of the membrane's radius.

    Parameters
    ----------
    cls : EnergyTerm subclass
        The term.
    values : mapping, optional
        Parameter values (each in its declared unit); the rest take their defaults.
    pose : (float, float, float)
        The bot's x, y (cm) and heading (rad).
    nodes : int
        Points of the curve.
    rtol : float
        Allowed difference from the central differences, relative to the largest value
        compared (dimensionless; the differences are accurate to ~1e-8 for a smooth term).
    seed : int
        Seed of the curve's wobble.

    Raises
    ------
    AssertionError
        Listing every violation.
    """
    term, params = _build(cls, values)
    radius, context = _context(params)
    coef = np.ascontiguousarray(term.coefficients())
    w = _shape(radius, nodes, seed)
    p = np.ascontiguousarray(pose, dtype=np.float64)
    problems: list[str] = []
    parts, dpose = _partials(term, w, p, context, coef)
    if not (np.all(np.isfinite(parts)) and np.all(np.isfinite(dpose))):
        _fail(cls, ["partials_kernel() wrote a non-finite value"])
    density = lambda w_, p_: np.asarray(term.density(*w_, p_), dtype=np.float64)  # noqa: E731
    e0 = density(w, p)
    if e0.shape != (nodes,) or not np.all(np.isfinite(e0)):
        _fail(cls, [f"density() returned shape {e0.shape} or non-finite values, not float64[N]"])
    problems += _partials_against_density(cls, density, w, p, parts, dpose, radius, rtol)
    hessian = term.hessian_kernel()
    if hessian is not None:
        problems += _hessian_against_partials(term, hessian, w, p, context, coef, radius, rtol)
    problems += _bot_kernels(term, p, context, coef, radius, rtol)
    _fail(cls, problems)


def _step(scale: float) -> float:
    return 1e-6 * scale


def _partials_against_density(cls, density, w, pose, parts, dpose, radius, rtol) -> list[str]:
    problems = []
    order = cls.derivative_order
    for a in range(6):
        h = _step(radius)
        plus, minus = [v.copy() for v in w], [v.copy() for v in w]
        plus[a] += h
        minus[a] -= h
        fd = (density(plus, pose) - density(minus, pose)) / (2 * h)
        if a // 2 > order:
            if np.any(parts[a] != 0.0) or not _close(fd, 0 * fd, rtol, np.abs(parts).max())[0]:
                problems.append(
                    f"derivative_order = {order}, but the density or the partials depend on "
                    f"{W_NAMES[a]}"
                )
            continue
        ok, worst = _close(parts[a], fd, rtol, 1e-300)
        if not ok:
            problems.append(
                f"partials_kernel(): de/d{W_NAMES[a]} differs from central differences of "
                f"density() by {worst:.2e} (relative; allowed {rtol:g})"
            )
    for c in range(3):
        h = _step(radius) if c < 2 else 1e-6
        plus, minus = pose.copy(), pose.copy()
        plus[c] += h
        minus[c] -= h
        fd = float(np.sum(density(w, plus) - density(w, minus)) / (2 * h))
        if not cls.reads_pose:
            if dpose[c] != 0.0 or abs(fd) > rtol * max(np.abs(parts).max(), 1e-300) * radius:
                problems.append(
                    f"reads_pose is False, but the density or dpose depend on {POSE_NAMES[c]}"
                )
            continue
        ok, worst = _close(np.array([dpose[c]]), np.array([fd]), rtol, np.abs(dpose).max())
        if not ok:
            problems.append(
                f"partials_kernel(): sum_n de_n/d{POSE_NAMES[c]} differs from central "
                f"differences of density() by {worst:.2e} (relative; allowed {rtol:g})"
            )
    return problems


def _hessian_against_partials(term, hessian, w, pose, context, coef, radius, rtol) -> list[str]:
    n = w[0].size
    hww, hwp, hpp = np.zeros((n, 6, 6)), np.zeros((n, 6, 3)), np.zeros((3, 3))
    hessian(*w, pose, context, coef, hww, hwp, hpp)
    fd_ww, fd_wp, fd_pp = np.zeros_like(hww), np.zeros_like(hwp), np.zeros_like(hpp)
    for b in range(6):
        h = _step(radius)
        plus, minus = [v.copy() for v in w], [v.copy() for v in w]
        plus[b] += h
        minus[b] -= h
        fd_ww[:, :, b] = (
            _partials(term, plus, pose, context, coef)[0]
            - _partials(term, minus, pose, context, coef)[0]
        ).T / (2 * h)
    for c in range(3):
        h = _step(radius) if c < 2 else 1e-6
        plus, minus = pose.copy(), pose.copy()
        plus[c] += h
        minus[c] -= h
        (pp, dp), (pm, dm) = (_partials(term, w, q, context, coef) for q in (plus, minus))
        fd_wp[:, :, c] = (pp - pm).T / (2 * h)
        fd_pp[:, c] = (dp - dm) / (2 * h)
    problems = []
    for name, kernel_value, fd in (("hww", hww, fd_ww), ("hwp", hwp, fd_wp), ("hpp", hpp, fd_pp)):
        ok, worst = _close(kernel_value, fd, rtol, 1e-300)
        if not ok:
            problems.append(
                f"hessian_kernel(): {name} differs from central differences of "
                f"partials_kernel() by {worst:.2e} (relative; allowed {rtol:g})"
            )
    return problems


def _bot_kernels(term, pose, context, coef, radius, rtol) -> list[str]:
    kernel = term.bot_kernel()
    if term.has_bot_energy and kernel is None:
        return ["has_bot_energy is True, but bot_kernel() returns None"]
    if kernel is None:
        return []

    def gradient(q):
        out = np.zeros(3)
        kernel(q, context, coef, out)
        return out

    fd = np.zeros((3, 3))
    for d in range(3):
        h = _step(radius) if d < 2 else 1e-6
        plus, minus = pose.copy(), pose.copy()
        plus[d] += h
        minus[d] -= h
        fd[:, d] = (gradient(plus) - gradient(minus)) / (2 * h)
    problems = []
    if not np.all(np.isfinite(gradient(pose))):
        problems.append("bot_kernel() wrote a non-finite value")
    # Mixed units (N/cm, N, N cm): compare in the units of a length scale of the radius.
    scaled = fd * np.array([1, 1, 1 / radius])[:, None] * np.array([1, 1, 1 / radius])
    ok, worst = _close(scaled, scaled.T, max(rtol, 1e-4), 1e-300)
    if not ok:
        problems.append(
            f"bot_kernel() is not a gradient: its differences are asymmetric by {worst:.2e}"
        )
    second = term.bot_hessian_kernel()
    if second is not None:
        hpp = np.zeros((3, 3))
        second(pose, context, coef, hpp)
        ok, worst = _close(hpp, fd, rtol, 1e-300)
        if not ok:
            problems.append(
                "bot_hessian_kernel() differs from central differences of bot_kernel() by "
                f"{worst:.2e} (relative; allowed {rtol:g})"
            )
    return problems


# -- friction laws ---------------------------------------------------------------------------


@_contract_calls
def check_friction_law(
    cls: type[FrictionLaw],
    values: Mapping[str, Any] | None = None,
    *,
    points: int = 128,
    rtol: float = 1e-4,
    seed: int = 0,
) -> None:
    """Check a friction law on a circle about the origin under force densities spread over
    six decades (1e-7 to 1e-1 N/cm) in every direction.

    Parameters
    ----------
    cls : FrictionLaw subclass
        The law.
    values : mapping, optional
        Parameter values (each in its declared unit); the rest take their defaults.
    points : int
        Points of the circle.
    rtol : float
        Allowed difference of the derivative from central differences, relative to its size
        (dimensionless).
    seed : int
        Seed of the force densities' directions.

    Raises
    ------
    AssertionError
        Listing every violation: a non-finite velocity, a negative dissipation f . v, a
        derivative that differs from central differences of the velocity by more than
        ``rtol`` (relative), a ``linear`` law that is not v = f / membrane_friction.
    """
    law, params = _build(cls, values)
    rng = np.random.default_rng(seed)
    radius = float(params["radius"])
    xi = 2 * np.pi * np.arange(points) / points
    x, y = radius * np.cos(xi), radius * np.sin(xi)
    tx, ty = -np.sin(xi), np.cos(xi)
    size = 10.0 ** rng.uniform(-7, -1, points)
    angle = rng.uniform(0, 2 * np.pi, points)
    fx, fy = size * np.cos(angle), size * np.sin(angle)
    geometry = [np.ascontiguousarray(a) for a in (x, y, tx, ty)]
    coef = np.ascontiguousarray(law.coefficients())

    def velocity(gx, gy):
        v = [np.zeros(points), np.zeros(points)]
        law.velocity_kernel()(
            *geometry, np.ascontiguousarray(gx), np.ascontiguousarray(gy), coef, *v
        )
        return np.array(v)

    problems: list[str] = []
    v = velocity(fx, fy)
    if not np.all(np.isfinite(v)):
        _fail(cls, ["velocity_kernel() wrote a non-finite value"])
    power = fx * v[0] + fy * v[1]
    scale = size * np.hypot(v[0], v[1])
    if np.any(power < -1e-12 * scale):
        n = int(np.argmin(power / np.maximum(scale, 1e-300)))
        problems.append(
            f"velocity_kernel() feeds energy in: f . v = {power[n]:.3g} N cm^-1 cm s^-1 < 0 at "
            f"f = ({fx[n]:.3g}, {fy[n]:.3g}) N/cm"
        )
    if cls.linear:
        gamma = float(params["membrane_friction"])
        ok, worst = _close(v, np.array([fx, fy]) / gamma, 1e-12, 1e-300)
        if not ok:
            problems.append(
                f"linear is True, but v differs from f / membrane_friction by {worst:.2e}"
            )
    derivative = law.derivative_kernel()
    if derivative is not None:
        d = [np.zeros(points) for _ in range(4)]
        derivative(*geometry, np.ascontiguousarray(fx), np.ascontiguousarray(fy), coef, *d)
        for b, name in enumerate("xy"):
            h = 1e-6 * (np.abs(fx if b == 0 else fy) + 1e-8)
            step = [h * (b == 0), h * (b == 1)]
            fd = (velocity(fx + step[0], fy + step[1]) - velocity(fx - step[0], fy - step[1])) / (
                2 * h
            )
            for a, out in enumerate("xy"):
                ok, worst = _close(d[2 * a + b], fd[a], rtol, 1e-300)
                if not ok:
                    problems.append(
                        f"derivative_kernel(): dv{out}/df{name} differs from central differences "
                        f"of velocity_kernel() by {worst:.2e} (relative; allowed {rtol:g})"
                    )
    _fail(cls, problems)


# -- driving protocols -----------------------------------------------------------------------


@_contract_calls
def check_driving_protocol(
    cls: type[DrivingProtocol],
    values: Mapping[str, Any] | None = None,
    *,
    duration: float = 60.0,
    rtol: float = 1e-4,
    seed: int = 0,
) -> None:
    """Check a driving protocol: its schedule over ``duration`` (s), its initial heading, and
    its drive kernel in each phase the schedule uses, at the origin (where the bot starts)
    and at four poses around it.

    ``rodas4`` differentiates a drive that depends on the pose by central differences
    (steps 1e-7 l0 / 2 pi in x, y and 1e-7 rad in the heading); the check requires that the
    differences with that step and with 4 times it agree to ``rtol`` (relative to the
    drive's size over a centimetre), which a drive discontinuous in the pose fails.

    Parameters
    ----------
    cls : DrivingProtocol subclass
        The protocol.
    values : mapping, optional
        Parameter values (each in its declared unit); the rest take their defaults.
    duration : float
        Length (s) of the schedule drawn.
    rtol : float
        Allowed difference between the two central differences (dimensionless, relative).
    seed : int
        Seed of the schedule and the heading.

    Raises
    ------
    AssertionError
        Listing every violation.
    """
    protocol, params = _build(cls, values)
    rng = np.random.default_rng(seed)
    problems: list[str] = []
    try:
        schedule = protocol.schedule(rng, duration)
    except Exception as exc:  # the Schedule checks its own invariants
        _fail(cls, [f"schedule() failed: {type(exc).__name__}: {exc}"])
    if schedule.phase.dtype != np.int8:
        problems.append(f"schedule().phase is {schedule.phase.dtype}, not int8")
    heading = protocol.initial_heading(rng)
    if not math.isfinite(heading):
        problems.append(f"initial_heading() returned {heading!r}")
    radius, context = _context(params)
    coef = np.ascontiguousarray(protocol.coefficients())
    kernel = protocol.drive_kernel()

    def drive(phase, datum, pose):
        out = np.zeros(3)
        kernel(np.int8(phase), float(datum), np.ascontiguousarray(pose), context, coef, out)
        return out

    seen = dict(zip(schedule.phase.tolist(), schedule.data.tolist(), strict=True))
    for phase, datum in sorted(seen.items()):
        # The bot's initial pose (the origin), then poses around it.
        poses = np.vstack([[0.0, 0.0, 0.0], rng.uniform([-1, -1, -np.pi], [1, 1, np.pi], (4, 3))])
        for pose in poses:
            value = drive(phase, datum, pose)
            if not np.all(np.isfinite(value)):
                problems.append(f"drive_kernel() wrote a non-finite value in phase {phase}")
                break
            problems += _drive_smoothness(drive, phase, datum, pose, context[0], value, rtol)
    problems += _event_values(protocol, seen, context[0], coef)
    _fail(cls, problems)


def _event_values(protocol, seen: dict, l0: float, coef: np.ndarray) -> list[str]:
    """The event kernel (if any) in each phase, at the bot's start in a ring of
    circumference ``l0`` (cm) at rest: its value must be finite."""
    event = protocol.event_kernel()
    if event is None:
        return []
    sense = np.zeros(SENSE_SIZE)
    sense[Sense.DISTANCE] = l0 / (2 * math.pi)
    problems = []
    for phase, datum in sorted(seen.items()):
        value = event(np.int8(phase), float(datum), sense, coef)
        if not math.isfinite(value):
            problems.append(f"event_kernel() returned {value!r} in phase {phase} at the start")
    return problems


def _drive_smoothness(drive: Callable, phase, datum, pose, l0, value, rtol) -> list[str]:
    steps = np.array([1e-7 * l0 / (2 * np.pi)] * 2 + [1e-7])
    jac = []
    for factor in (1.0, 4.0):
        j = np.zeros((3, 3))
        for d in range(3):
            plus, minus = pose.copy(), pose.copy()
            plus[d] += factor * steps[d]
            minus[d] -= factor * steps[d]
            j[:, d] = (drive(phase, datum, plus) - drive(phase, datum, minus)) / (
                2 * factor * steps[d]
            )
        jac.append(j)
    floor = max(float(np.abs(value).max()), 1e-300)
    ok, worst = _close(jac[0], jac[1], rtol, floor)
    if ok:
        return []
    return [
        f"drive_kernel() in phase {phase} is not smooth in the pose at "
        f"{np.round(pose, 3).tolist()}: central differences with two steps differ by "
        f"{worst:.2e} (relative; allowed {rtol:g}), so rodas4's Jacobian of it would be wrong"
    ]


# -- stop/go detectors -----------------------------------------------------------------------


@_contract_calls
def check_stopgo_detector(
    cls: type[StopGoDetector],
    values: Mapping[str, Any] | None = None,
    *,
    go_speed: float = 5.0,
    stop_speed: float = 0.0,
    interval: float = 0.01,
    margin: int = 20,
) -> None:
    """Check a detector on a planted series: 2 s stretches at ``go_speed`` and at
    ``stop_speed`` (cm/s) alternating, sampled every ``interval`` (s), with missing (NaN)
    samples, as one series and as a (3, T) batch.

    The labels must be int8 of the input's shape, -1 exactly where the speed is NaN, and go
    (1) / stop (0) on every sample of a stretch farther than ``margin`` samples from its
    ends (a detector may smooth or hold its label near a switch).

    Parameters
    ----------
    cls : StopGoDetector subclass
        The detector.
    values : mapping, optional
        Parameter values (each in its declared unit); the rest take their defaults.
    go_speed, stop_speed : float
        Speeds (cm/s) of the go and the stop stretches.
    interval : float
        Sampling interval (s).
    margin : int
        Samples next to a switch where any label is accepted.

    Raises
    ------
    AssertionError
        Listing every violation.
    """
    detector, _ = _build(cls, values)
    stretch = int(round(2.0 / interval))
    truth = np.tile(np.repeat(np.array([GO, STOP], dtype=np.int8), stretch), 4)
    speed = np.where(truth == GO, go_speed, stop_speed).astype(np.float64)
    missing = np.zeros(speed.size, dtype=bool)
    missing[stretch // 2 :: 3 * stretch // 2] = True
    speed[missing] = np.nan
    index = np.arange(speed.size) % stretch
    inner = (index >= margin) & (index < stretch - margin) & ~missing
    problems: list[str] = []
    for series in (speed, np.tile(speed, (3, 1))):
        labels = np.asarray(detector.label(series, interval))
        if labels.shape != series.shape or labels.dtype != np.int8:
            problems.append(
                f"label() returned {labels.dtype}{list(labels.shape)} for float64"
                f"{list(series.shape)}: must be int8 of the same shape"
            )
            continue
        flat = labels.reshape(-1, speed.size)
        for row in flat:
            if np.any((row == STOPGO_UNKNOWN) != missing):
                problems.append("label() is not -1 exactly where the speed is NaN")
            wrong = inner & (row != truth)
            if wrong.any():
                n = int(np.argmax(wrong))
                problems.append(
                    f"label() gives {int(row[n])} at sample {n} of a stretch at "
                    f"{speed[n]:g} cm/s, {margin} samples or more from its ends: "
                    f"expected {int(truth[n])}"
                )
    _fail(cls, list(dict.fromkeys(problems)))


@_contract_calls
def check_pair_term(
    cls: type[PairTerm],
    values: Mapping[str, Any] | None = None,
    *,
    points: int = 401,
    rtol: float = 1e-5,
) -> None:
    """Check a pair term's law on signed distances from -reach / 2 to 3 reach / 2.

    Parameters
    ----------
    cls : PairTerm subclass
        The term.
    values : mapping, optional
        Parameter values (each in its declared unit); the rest take their defaults.
    points : int
        Distances checked.
    rtol : float
        Allowed difference of each derivative from central differences of the value below
        it, relative to the larger's size (dimensionless).

    Raises
    ------
    AssertionError
        Listing every violation: a reach that is not finite and > 0 (cm), a non-finite value,
        a value beyond the reach that is not zero, a derivative that differs from central
        differences.
    """
    term, _ = _build(cls, values)
    reach = float(term.reach())
    problems: list[str] = []
    if not (math.isfinite(reach) and reach > 0):
        _fail(cls, [f"reach() = {reach} cm: must be finite and > 0"])
    law, coef = term.law_kernel(), np.ascontiguousarray(term.coefficients())
    rho = np.linspace(-0.5 * reach, 1.5 * reach, points)
    step = 1e-6 * reach

    def values_at(r: np.ndarray) -> np.ndarray:
        out, row = np.zeros((r.size, 3)), np.zeros(3)
        for i, value in enumerate(r):
            law(float(value), coef, row)
            out[i] = row
        return out

    at, plus, minus = values_at(rho), values_at(rho + step), values_at(rho - step)
    if not np.isfinite(at).all():
        problems.append(
            f"law gives a non-finite value at rho = {rho[~np.isfinite(at).all(1)][0]:g} cm"
        )
    beyond = rho > reach * (1 + 1e-9)
    if np.any(at[beyond] != 0.0):
        problems.append(f"law is not zero beyond reach() = {reach:g} cm")
    inside = np.abs(rho - reach) > 10 * step
    for k, name in ((1, "de/drho"), (2, "d2e/drho2")):
        numeric = (plus[inside, k - 1] - minus[inside, k - 1]) / (2 * step)
        ok, worst = _close(at[inside, k], numeric, rtol, 1e-300)
        if not ok:
            problems.append(f"{name} differs from central differences by {worst:.2g} (relative)")
    _fail(cls, problems)


@_contract_calls
def check_bot_interaction(
    cls: type[BotInteraction],
    values: Mapping[str, Any] | None = None,
    *,
    pairs: int = 200,
    conserves: bool = True,
    rtol: float = 1e-5,
    seed: int = 0,
) -> None:
    """Check a bot interaction on ``pairs`` random placements of two bots, their centres up
    to 1.2 times its reach apart, overlapping by no more than 5 % of b (drawn from
    ``seed``).

    Parameters
    ----------
    cls : BotInteraction subclass
        The interaction.
    values : mapping, optional
        Parameter values (each in its declared unit); the rest take their defaults.
    pairs : int
        Placements checked.
    conserves : bool
        Whether the forces must be equal and opposite and the torques balance about the
        origin (Newton's third law; False for an interaction meant to break it).
    rtol : float
        Allowed departure of the momentum sums, relative to the largest generalized force
        of the placement (dimensionless); a ``jacobian_kernel`` (if it has one) may depart
        from central differences of the kernel by 1000 rtol of the largest entry over the
        placements.
    seed : int
        The seed of the placements' random stream.

    Raises
    ------
    AssertionError
        Listing every violation: a reach that is not finite and > 0 (cm), a non-finite
        output, an output beyond the reach, forces that do not balance, a Jacobian that
        differs from central differences.
    """
    interaction, params = _build(cls, values)
    reach = float(interaction.reach())
    if not (math.isfinite(reach) and reach > 0):
        _fail(cls, [f"reach() = {reach} cm: must be finite and > 0"])
    kernel, coef = interaction.pair_kernel(), np.ascontiguousarray(interaction.coefficients())
    jacobian = interaction.jacobian_kernel()
    a, b = float(params.bot_semi_major), float(params.bot_semi_minor)
    context = np.array([float(params.membrane_length), a, b])
    rng = np.random.default_rng(seed)
    problems: list[str] = []

    def forces(pa: np.ndarray, pb: np.ndarray) -> np.ndarray:
        out = np.zeros(6)
        kernel(pa, pb, context, coef, out)
        return out

    worst, largest = (0.0, ""), 0.0  # the Jacobian's largest error and entry, over placements
    for pa, pb, distance in _bot_placements(rng, pairs, reach, a, b):
        out = forces(pa, pb)
        where = f"at centres {distance:.3g} cm apart"
        if not np.isfinite(out).all():
            problems.append(f"pair_kernel gives a non-finite value {where}")
            continue
        if distance > reach * (1 + 1e-9) and np.any(out != 0.0):
            problems.append(f"pair_kernel adds forces beyond reach() = {reach:g} cm")
        scale = float(np.abs(out).max())
        if conserves and scale > 0.0:
            problems += _third_law(out, pa, pb, scale, rtol, where)
        if jacobian is not None:
            error, size = _interaction_jacobian_error(jacobian, forces, pa, pb, context, coef)
            largest = max(largest, size)
            if error > worst[0]:
                worst = (error, where)
    if largest > 0.0 and worst[0] > 1e3 * rtol * largest:
        problems.append(
            f"jacobian_kernel differs from central differences of pair_kernel {worst[1]} by "
            f"{worst[0] / largest:.2g} of the largest entry over the placements"
        )
    _fail(cls, list(dict.fromkeys(problems)))


def _bot_placements(rng, pairs: int, reach: float, a: float, b: float):
    """``pairs`` random placements of two bots (poses and the distance of their centres, up
    to 1.2 reach), overlapping by no more than 5 % of b: deeper, where no run goes, a soft
    repulsion's forces are not smooth (the distance inside an ellipse kinks on its medial
    axis)."""
    from softcell.engine.kernels.ellipse import ellipse_gap

    made = 0
    while made < pairs:
        pa = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-math.pi, math.pi)])
        angle, distance = rng.uniform(0, 2 * math.pi), rng.uniform(0.3 * b, 1.2 * reach)
        pb = np.array(
            [pa[0] + distance * math.cos(angle), pa[1] + distance * math.sin(angle),
             rng.uniform(-math.pi, math.pi)]
        )  # fmt: skip
        if ellipse_gap(pa, pb, a, b) < -0.05 * b:
            continue
        made += 1
        yield pa, pb, distance


def _third_law(out, pa, pb, scale: float, rtol: float, where: str) -> list[str]:
    """A problem when the forces are not equal and opposite or the torques do not balance
    about the origin."""
    net = np.abs(out[:2] + out[3:5]).max()
    spin = pa[0] * out[1] - pa[1] * out[0] + out[2] + pb[0] * out[4] - pb[1] * out[3] + out[5]
    if net > rtol * scale or abs(spin) > rtol * scale * (1 + abs(pb[:2]).max()):
        return [
            f"forces are not equal and opposite, or torques do not balance, {where} "
            f"(net force {net:.2g} N, net torque {spin:.2g} N cm; conserves=False "
            "for an interaction meant to break Newton's third law)"
        ]
    return []


def _interaction_jacobian_error(jacobian, forces, pa, pb, context, coef) -> tuple[float, float]:
    """The largest difference between ``jacobian``'s 6 x 6 block and central differences of
    ``forces`` at the placement, and the differences' largest entry."""
    a = float(context[1])
    steps = np.array([1e-7 * context[0] / (2 * math.pi)] * 8 + [1e-7])
    jac, scratch = np.zeros((6, 6)), np.zeros(24)
    jacobian(pa, pb, context, coef, steps, scratch, jac)
    numeric = np.zeros((6, 6))
    for j in range(6):
        h = 1e-6 * (1.0 if j % 3 == 2 else max(a, 1.0))
        plus, minus = np.concatenate([pa, pb]), np.concatenate([pa, pb])
        plus[j] += h
        minus[j] -= h
        numeric[:, j] = (forces(plus[:3], plus[3:]) - forces(minus[:3], minus[3:])) / (2 * h)
    return float(np.abs(jac - numeric).max()), float(np.abs(numeric).max())


CHECKS: dict[type, Callable[..., None]] = {
    EnergyTerm: check_energy_term,
    FrictionLaw: check_friction_law,
    DrivingProtocol: check_driving_protocol,
    StopGoDetector: check_stopgo_detector,
    PairTerm: check_pair_term,
    BotInteraction: check_bot_interaction,
}


def check_component(cls: type, values: Mapping[str, Any] | None = None, **options: Any) -> None:
    """The check of ``cls``'s kind with parameter ``values`` (each in its declared unit) and
    that check's keyword ``options``: :func:`~softcell.testing.check_energy_term`,
    :func:`~softcell.testing.check_friction_law`,
    :func:`~softcell.testing.check_driving_protocol`,
    :func:`~softcell.testing.check_stopgo_detector`,
    :func:`~softcell.testing.check_pair_term` or
    :func:`~softcell.testing.check_bot_interaction`.

    Parameters
    ----------
    cls : type
        The component class.
    values : mapping, optional
        Parameter values (each in its declared unit); the rest take their defaults.
    **options
        Keywords of that check.

    Raises
    ------
    AssertionError
        Listing every violation.
    TypeError
        For a class of no checked kind (integrators are checked by running them).
    """
    for contract, check in CHECKS.items():
        if isinstance(cls, type) and issubclass(cls, contract):
            return check(cls, values, **options)
    raise TypeError(
        f"{cls!r} is not an energy term, friction law, driving protocol, detector, pair term "
        "or bot interaction"
    )
