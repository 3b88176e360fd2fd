"""Calibration as the paper did it (``softcell calibrate``).

- **gamma_mem from a constant push** (:func:`calibrate_friction`): the bot pushes the cell
  along a fixed heading (the ``constant_push`` protocol); the time average of the speed of
  the cell's geometric center, after the push has settled, is matched to the measured one by
  a root search on log gamma_mem. Heavier friction, slower cell: the root is unique.
- **k from the shape index** (:func:`calibrate_bending`): the time-averaged IPR of the
  run-and-tumble cell at one or more radii is matched to the measured values, by a root
  search on log k at one radius and a least-squares search at several. A stiffer membrane
  deforms less: the IPR falls with k.

Every evaluation simulates the same realizations (one seed: common random numbers), so the
simulated value is a smooth function of the parameter and the search converges on it. The
uncertainty propagates the measurement's error (when given) and the simulation's spread
across realizations through the local slope of the simulated value.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from softcell.errors import SoftcellError
from softcell.model.configuration import RunConfig
from softcell.model.limits import check_realizations, check_worker_count

#: Relative step in the parameter for the slope behind the uncertainty.
SLOPE_STEP = 0.03
#: Tolerance of the searches on the log of the parameter (a relative tolerance): the root
#: searches' and the least-squares search's (its every evaluation costs as much as a root's).
ROOT_TOLERANCE = 1e-4
FIT_TOLERANCE = 1e-3


@dataclass
class Calibration:
    """What a calibration found.

    ``value`` and ``uncertainty`` are in ``unit``; per radius (cm): the measured and the
    simulated values at ``value`` (``quantity`` in ``quantity_unit``), their residual, and
    the error each residual is weighed with (the measurement's and the simulation's, in
    quadrature).
    """

    parameter: str
    unit: str
    value: float
    uncertainty: float
    quantity: str
    quantity_unit: str
    radius: list[float]
    measured: list[float]
    simulated: list[float]
    error: list[float]
    evaluations: int
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def residual(self) -> list[float]:
        return [s - m for s, m in zip(self.simulated, self.measured, strict=True)]

    def summary(self) -> str:
        """Lines for the terminal: the value with unit and uncertainty, the residual per R."""
        lines = [
            f"{self.parameter} = {self.value:.4g} ± {self.uncertainty:.2g} {self.unit} "
            f"({self.evaluations} simulated evaluations)",
            f"  {'R (cm)':>7}  {'measured':>10}  {'simulated':>10}  {'residual':>10}  "
            f"{'error':>9}   ({self.quantity}, {self.quantity_unit})",
        ]
        for r, m, s, e in zip(self.radius, self.measured, self.simulated, self.error, strict=True):
            lines.append(f"  {r:7g}  {m:10.6g}  {s:10.6g}  {s - m:+10.3g}  {e:9.2g}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "residual": self.residual}


class _Simulator:
    """Runs the realizations of one evaluation into a scratch folder (one cluster for all)."""

    def __init__(self, workers: int, progress: bool) -> None:
        import contextlib

        self.stack = contextlib.ExitStack()
        self.scratch = Path(
            self.stack.enter_context(tempfile.TemporaryDirectory(prefix="softcell-calibrate-"))
        )
        self.workers, self.progress, self.client, self.count = workers, progress, None, 0

    def __enter__(self) -> _Simulator:
        if self.workers > 1:
            from softcell.runner.cluster import cluster_client

            self.client = self.stack.enter_context(cluster_client(self.workers))
        return self

    def __exit__(self, *exc: object) -> None:
        self.stack.close()

    def __call__(self, config: RunConfig, realizations: int, seed: int):
        """The realizations of ``config`` (one point), as one Dataset with ``realization``."""
        from softcell.io.netcdf import open_dataset
        from softcell.runner.ensemble import simulate

        self.count += 1
        folder = self.scratch / f"evaluation{self.count:03d}"
        simulate(
            config, folder, realizations=realizations, seed=seed, client=self.client, progress=False
        )
        return open_dataset(folder).load()


def _positive(name: str, values: Sequence[float], unit: str) -> list[float]:
    out = [float(v) for v in values]
    for v in out:
        if not (math.isfinite(v) and v > 0):
            raise SoftcellError(f"{name} = {v:g} {unit} is not allowed: must be finite and > 0")
    return out


def _common(realizations: int, duration: float, settle: float, workers: int) -> None:
    check_realizations(realizations)
    if not (math.isfinite(duration) and math.isfinite(settle) and 0 <= settle < duration):
        raise SoftcellError(
            f"the averaging window [{settle:g}, {duration:g}] s is empty: "
            "need 0 <= settle < duration"
        )
    check_worker_count(workers)


def push_speed(ds, settle: float) -> np.ndarray:
    """Time average (from ``settle`` s on) of the cell GC's speed (cm/s), per realization."""
    from softcell.analysis.series import speed

    time = np.asarray(ds["time"].values, dtype=float)
    v = speed(np.asarray(ds["cell_x"].values), np.asarray(ds["cell_y"].values), time)
    return np.nanmean(v[..., time >= settle], axis=-1)


def mean_shape_index(ds, settle: float) -> np.ndarray:
    """Time average (from ``settle`` s on) of the membrane's IPR (the smooth curve through
    the stored nodes), per realization."""
    from softcell.analysis.series import shape_index

    time = np.asarray(ds["time"].values, dtype=float)
    keep = time >= settle
    ipr = shape_index(
        np.asarray(ds["membrane_x"].values)[..., keep, :],
        np.asarray(ds["membrane_y"].values)[..., keep, :],
        band_limited=True,
    )
    return ipr.mean(axis=-1)


def _sem(values: np.ndarray) -> float:
    return float(np.std(values, ddof=1) / math.sqrt(values.size)) if values.size > 1 else 0.0


def _default(config: RunConfig, name: str) -> float:
    from softcell.model.parameters import MODEL_PARAMETERS

    value = config.parameters.get(name, MODEL_PARAMETERS[name].default)
    if isinstance(value, list):
        raise SoftcellError(f"{name} is swept in the configuration; calibration needs one value")
    return float(value)


def calibrate_friction(
    push_speed_value: float,
    radius: float,
    *,
    config: RunConfig | None = None,
    push_speed_error: float = 0.0,
    realizations: int = 2,
    duration: float = 15.0,
    settle: float = 5.0,
    seed: int = 0,
    workers: int = 1,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
) -> Calibration:
    """gamma_mem (N s cm-2) that gives a constantly pushed cell of radius ``radius`` (cm)
    the mean GC speed ``push_speed_value`` (cm/s), time-averaged over [``settle``,
    ``duration``] s.

    A speed at or above the free bot's F0 / gamma_T, or below what 100 times the default
    friction gives, is refused.

    Parameters
    ----------
    push_speed_value : float
        The measured mean GC speed (cm/s) of a constantly pushed cell.
    radius : float
        The cell's radius (cm).
    config : RunConfig, optional
        Every other parameter (its ``driving_protocol`` is replaced by ``constant_push``).
    push_speed_error : float
        The measurement's standard error (cm/s).
    realizations : int
        Simulations per friction value tried.
    duration, settle : float
        Length (s) of each simulation, and the time (s) before the speed is averaged.
    seed : int
        Root seed of the simulations.
    workers : int
        Processes that run the simulations.
    progress : bool
        Show a progress bar.
    log : callable, optional
        Receives one line per friction value tried.

    Returns
    -------
    Calibration
        gamma_mem (N s cm-2) with its uncertainty, and the residual per radius.
    """
    from scipy.optimize import brentq

    config = config or RunConfig()
    (v_meas,) = _positive("push speed", [push_speed_value], "cm s-1")
    (radius,) = _positive("radius", [radius], "cm")
    if push_speed_error < 0 or not math.isfinite(push_speed_error):
        raise SoftcellError(
            f"push speed error = {push_speed_error:g} cm s-1 is not allowed: "
            "must be finite and >= 0"
        )
    _common(realizations, duration, settle, workers)
    f0, gamma_t = _default(config, "drive_force"), _default(config, "bot_friction")
    if v_meas >= f0 / gamma_t:
        raise SoftcellError(
            f"push speed {v_meas:g} cm/s is not below the free bot's F0 / "
            f"gamma_T = {f0 / gamma_t:.4g} cm/s: no membrane friction gives it"
        )
    # The whole ring sliding with the bot: F0 = (gamma_T + gamma_mem 2 pi R) v.
    guess = (f0 / v_meas - gamma_t) / (2 * math.pi * radius)
    base = config.updated(
        parameters={"radius": radius, "duration": duration},
        components={"driving_protocol": "constant_push"},
    )
    say = log or (lambda _: None)
    cache: dict[float, np.ndarray] = {}

    with _Simulator(workers, progress) as run:

        def speeds(log_gamma: float) -> np.ndarray:
            if log_gamma not in cache:
                gamma = math.exp(log_gamma)
                cache[log_gamma] = push_speed(
                    run(base.updated(parameters={"membrane_friction": gamma}), realizations, seed),
                    settle,
                )
                say(
                    f"gamma_mem = {gamma:.5g} N s cm-2: mean push speed "
                    f"{cache[log_gamma].mean():.5g} cm/s"
                )
            return cache[log_gamma]

        def gap(log_gamma: float) -> float:
            return float(speeds(log_gamma).mean()) - v_meas

        lo, hi = math.log(guess) - 0.7, math.log(guess) + 0.7
        for _ in range(6):  # widen the bracket until the speed is on both sides
            if gap(lo) < 0:
                lo -= 1.5
            elif gap(hi) > 0:
                hi += 1.5
            else:
                break
        else:
            raise SoftcellError(
                f"no gamma_mem in [{math.exp(lo):.3g}, {math.exp(hi):.3g}] "
                f"N s cm-2 gives a push speed of {v_meas:g} cm/s at R = "
                f"{radius:g} cm"
            )
        log_gamma = brentq(gap, lo, hi, xtol=ROOT_TOLERANCE)
        gamma = math.exp(log_gamma)
        step = math.log1p(SLOPE_STEP)
        slope = (gap(log_gamma + step) - gap(log_gamma - step)) / (2 * step)  # cm/s per ln
        at = speeds(log_gamma)
        error = math.hypot(push_speed_error, _sem(at))
        # The search's own tolerance is the floor (the push itself is deterministic).
        uncertainty = gamma * math.hypot(error / abs(slope), ROOT_TOLERANCE)
        return Calibration(
            "membrane_friction",
            "N s cm-2",
            gamma,
            uncertainty,
            "time-averaged GC speed of the pushed cell",
            "cm s-1",
            [radius],
            [v_meas],
            [float(at.mean())],
            [error],
            run.count,
            {
                "realizations": realizations,
                "duration": duration,
                "settle": settle,
                "seed": seed,
                "push_speed_error": push_speed_error,
            },
        )


def _checked_ipr(
    ipr: Sequence[float], radius: Sequence[float], ipr_error: Sequence[float] | None
) -> tuple[list[float], list[float], list[float]]:
    """The IPR values (1), radii (cm) and the IPRs' errors (1) of a calibration, checked."""
    ipr = _positive("IPR", ipr, "1")
    radius = _positive("radius", radius, "cm")
    if len(ipr) != len(radius):
        raise SoftcellError(
            f"{len(ipr)} IPR value(s) for {len(radius)} radius value(s): give one IPR per radius"
        )
    circle = 2 * math.sqrt(math.pi)
    low = [v for v in ipr if v <= circle]
    if low:
        raise SoftcellError(
            f"IPR = {low[0]:g} is not allowed: a closed curve's IPR is at "
            f"least a circle's 2 sqrt(pi) = {circle:.5f}"
        )
    errors = [0.0] * len(ipr) if ipr_error is None else [float(e) for e in ipr_error]
    if len(errors) != len(ipr) or any(not (math.isfinite(e) and e >= 0) for e in errors):
        raise SoftcellError(
            f"IPR errors {errors} are not allowed: one finite value >= 0 per radius"
        )
    return ipr, radius, errors


def _best_log_k(
    residual: Callable[[float], np.ndarray],
    weights: Callable[[float], np.ndarray],
    k0: float,
    ipr: list[float],
    radius: list[float],
) -> float:
    """ln k (k in N cm2) within [k0 / 30, 30 k0]: the root of the residual at one radius, the
    weighted least squares at several."""
    from scipy.optimize import brentq, minimize_scalar

    lo, hi = math.log(k0 / 30), math.log(k0 * 30)
    if len(radius) == 1:
        r_lo, r_hi = residual(lo)[0], residual(hi)[0]
        if r_lo < 0 or r_hi > 0:
            raise SoftcellError(
                f"IPR = {ipr[0]:g} at R = {radius[0]:g} cm is out of reach for k in "
                f"[{k0 / 30:.3g}, {k0 * 30:.3g}] N cm2 (simulated {r_hi + ipr[0]:.6f} to "
                f"{r_lo + ipr[0]:.6f})"
            )
        return brentq(lambda x: residual(x)[0], lo, hi, xtol=ROOT_TOLERANCE)

    def cost(x: float) -> float:
        return float(np.sum((residual(x) / weights(x)) ** 2))

    log_k = float(
        minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": FIT_TOLERANCE}).x
    )
    if min(log_k - lo, hi - log_k) < 0.01:
        raise SoftcellError(
            f"the best k lies at the edge of [{k0 / 30:.3g}, "
            f"{k0 * 30:.3g}] N cm2: the IPR values are out of reach"
        )
    return log_k


def calibrate_bending(
    ipr: Sequence[float],
    radius: Sequence[float],
    *,
    config: RunConfig | None = None,
    ipr_error: Sequence[float] | None = None,
    realizations: int = 4,
    duration: float = 120.0,
    settle: float = 15.0,
    seed: int = 0,
    workers: int = 1,
    progress: bool = False,
    log: Callable[[str], None] | None = None,
) -> Calibration:
    """k (N cm2) that gives the run-and-tumble cell the measured time-averaged IPR ``ipr``
    (1) at the radii ``radius`` (cm): a root at one radius, the least-squares fit (residuals
    weighed by their errors) at several.

    ``config`` holds every other parameter and the components; ``ipr_error`` is the
    measurements' standard errors (default 0). Each evaluation simulates ``realizations`` of
    ``duration`` s per radius and averages from ``settle`` s on. The search spans k from 1/30
    to 30 times the configuration's; a measured IPR below a circle's 2 sqrt(pi) is refused.
    """
    config = config or RunConfig()
    ipr, radius, errors = _checked_ipr(ipr, radius, ipr_error)
    _common(realizations, duration, settle, workers)
    k0 = _default(config, "bending_stiffness")
    measured = np.asarray(ipr)
    say = log or (lambda _: None)
    cache: dict[float, list[np.ndarray]] = {}

    with _Simulator(workers, progress) as run:

        def values(log_k: float) -> list[np.ndarray]:
            if log_k not in cache:
                k = math.exp(log_k)
                cache[log_k] = [
                    mean_shape_index(
                        run(
                            config.updated(
                                parameters={
                                    "radius": r,
                                    "duration": duration,
                                    "bending_stiffness": k,
                                }
                            ),
                            realizations,
                            seed,
                        ),
                        settle,
                    )
                    for r in radius
                ]
                say(
                    f"k = {k:.5g} N cm2: mean IPR "
                    + ", ".join(f"{v.mean():.6f}" for v in cache[log_k])
                )
            return cache[log_k]

        def residual(log_k: float) -> np.ndarray:
            return np.array([v.mean() for v in values(log_k)]) - measured

        def weights(log_k: float) -> np.ndarray:
            sims = np.array([_sem(v) for v in values(log_k)])
            err = np.hypot(np.asarray(errors), sims)
            return np.where(err > 0, err, 1.0)

        log_k = _best_log_k(residual, weights, k0, ipr, radius)
        step = math.log1p(SLOPE_STEP)
        slope = (residual(log_k + step) - residual(log_k - step)) / (2 * step)  # per ln k
        at = values(log_k)
        err = np.hypot(np.asarray(errors), [_sem(v) for v in at])
        information = float(np.sum((slope[err > 0] / err[err > 0]) ** 2))
        sigma_log = math.hypot(
            1.0 / math.sqrt(information) if information > 0 else 0.0,
            ROOT_TOLERANCE if len(radius) == 1 else FIT_TOLERANCE,
        )
        k = math.exp(log_k)
        return Calibration(
            "bending_stiffness",
            "N cm2",
            k,
            k * sigma_log,
            "time-averaged IPR",
            "1",
            radius,
            [float(v) for v in measured],
            [float(v.mean()) for v in at],
            [float(e) for e in err],
            run.count,
            {
                "realizations": realizations,
                "duration": duration,
                "settle": settle,
                "seed": seed,
                "ipr_error": errors,
            },
        )


def write_calibration(
    results: Sequence[Calibration], path: str | os.PathLike[str], config: RunConfig
) -> Path:
    """The calibrations as JSON at ``path``, with the configuration and the version."""
    from softcell._version import __version__
    from softcell.io.files import atomic_write

    path = Path(path)
    with atomic_write(path) as tmp:
        tmp.write_text(
            json.dumps(
                {
                    "softcell_version": __version__,
                    "parameters": config.parameters,
                    "components": config.components,
                    "calibrations": [c.to_dict() for c in results],
                },
                indent=1,
            )
            + "\n",
            encoding="utf-8",
        )
    return path
