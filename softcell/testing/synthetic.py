"""Synthetic trajectories with known statistics, as softcell Datasets.

:func:`stop_and_go_dataset` plants the two-state process of the paper's theory (SI Sec. S4):
go phases at speed v in a uniformly random direction, stop phases at rest, both with
exponential durations. Its MSD is exactly SI:EQ:msd with v0_hat^2 = p v^2, p = <tau_g> /
(<tau_g> + <tau_s>), and its complete phases have the planted mean durations.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from softcell.model.parameters import Parameters
from softcell.schema import simulation_dataset


def stop_and_go_path(
    rng: np.random.Generator,
    times: np.ndarray,
    speed: float,
    mean_go: float,
    mean_stop: float,
    turn: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Positions x, y (cm) at ``times`` (s) of one stationary stop-and-go path from the
    origin: the first phase is go with probability p, every duration is exponential (so the
    path is stationary from t = 0). Each go phase heads in a new uniformly random direction,
    or, with ``turn`` (rad), turns by +-``turn`` (either sign with probability 1/2) from the
    previous go phase's direction (mean cosine between consecutive go phases: cos(turn))."""
    horizon = float(times[-1] - times[0])
    p = mean_go / (mean_go + mean_stop)
    go = rng.random() < p
    t, x, y = [float(times[0])], [0.0], [0.0]
    angle = rng.uniform(0, 2 * np.pi)
    while t[-1] < times[0] + horizon:
        duration = rng.exponential(mean_go if go else mean_stop)
        if go:
            angle = (
                rng.uniform(0, 2 * np.pi) if turn is None else angle + turn * rng.choice((-1, 1))
            )
        step = speed * duration if go else 0.0
        t.append(t[-1] + duration)
        x.append(x[-1] + step * np.cos(angle))
        y.append(y[-1] + step * np.sin(angle))
        go = not go
    return np.interp(times, t, x), np.interp(times, t, y)


def stop_and_go_dataset(
    rng: np.random.Generator,
    times: np.ndarray,
    *,
    realizations: int,
    speed: float,
    mean_go: float,
    mean_stop: float,
    radius: float = 12.0,
    bot_offset: float = 6.0,
    nodes: int = 16,
    offset: Sequence[float] = (0.0, 0.0),
    turn: float | None = None,
    fine: bool = False,
) -> xr.Dataset:
    """A simulation-schema Dataset whose cell follows ``stop_and_go_path``: a stationary
    stop-and-go path with exponential durations, each go phase in a new direction.

    Parameters
    ----------
    rng : Generator
        The random stream (a numpy Generator) of every path.
    times : ndarray
        float64[T]: sample times (s), increasing (two sampling rates are allowed).
    realizations : int
        Paths drawn.
    speed : float
        Speed (cm/s) in the go phases.
    mean_go, mean_stop : float
        Mean durations (s) of the exponential go and stop phases.
    radius : float
        Radius (cm) of the membrane, a circle of ``nodes`` points around the cell.
    bot_offset : float
        Distance (cm) of the bot from the cell, in a direction that turns at 1 rad/s.
    nodes : int
        Membrane points.
    offset : (float, float)
        Added to every position (cm).
    turn : float, optional
        Angle (rad): each go phase turns by +-``turn`` from the previous one instead of
        heading anywhere (mean cosine between consecutive go phases: cos(turn)).
    fine : bool
        Also store the bodies' fine record, as a simulation does: the paths every finest
        interval of ``times`` over the whole span (``times`` must lie on that grid).

    Returns
    -------
    xarray.Dataset
        The simulation schema; with ``fine``, the bodies' fine record too.
    """
    times = np.asarray(times, dtype=np.float64)
    grid = times
    if fine:
        step = float(np.min(np.diff(times)))
        grid = times[0] + step * np.arange(int(round((times[-1] - times[0]) / step)) + 1)
        at = np.rint((times - times[0]) / step).astype(np.int64)
        if not np.allclose(grid[at], times, rtol=0, atol=1e-6 * step):
            raise ValueError("fine=True needs sample times on the grid of the finest interval")
    paths = [
        stop_and_go_path(rng, grid, speed, mean_go, mean_stop, turn) for _ in range(realizations)
    ]
    fx = np.array([p[0] for p in paths]) + offset[0]
    fy = np.array([p[1] for p in paths]) + offset[1]
    cx, cy = (fx[:, at], fy[:, at]) if fine else (fx, fy)
    angle = np.linspace(0, 2 * np.pi, nodes, endpoint=False)
    mx = cx[..., None] + radius * np.cos(angle)
    my = cy[..., None] + radius * np.sin(angle)
    turn = times[None, :] + np.zeros((realizations, 1))
    bx = cx + bot_offset * np.cos(turn)
    by = cy + bot_offset * np.sin(turn)
    record = None
    if fine:
        heading = grid[None, :] + np.zeros((realizations, 1))
        record = {
            "fine_time": grid,
            "cell_x_fine": fx,
            "cell_y_fine": fy,
            "bot_x_fine": fx + bot_offset * np.cos(heading),
            "bot_y_fine": fy + bot_offset * np.sin(heading),
            "bot_angle_fine": heading,
            "bot_phase_fine": np.ones(fx.shape, dtype=np.int8),
        }
    return simulation_dataset(
        times,
        np.arange(realizations),
        membrane_x=mx,
        membrane_y=my,
        cell_x=cx,
        cell_y=cy,
        bot_x=bx,
        bot_y=by,
        bot_angle=turn,
        bot_phase=np.ones(cx.shape, dtype=np.int8),
        parameters=Parameters({"radius": radius}),
        seed=0,
        components={"synthetic": "stop_and_go_dataset"},
        fine=record,
    )


def two_rate_times(fine: float, coarse: float, switch: float, end: float) -> np.ndarray:
    """Sample times (s): every ``fine`` up to ``switch``, then every ``coarse`` to ``end``
    (the paper's 0.01 s then 0.1 s)."""
    early = fine * np.arange(int(round(switch / fine)) + 1)
    late = switch + coarse * np.arange(1, int(round((end - switch) / coarse)) + 1)
    return np.concatenate([early, late])
