"""The analysis of several bots in one ring (files with a ``bot`` dim).

Each bot is analysed as the single-bot analysis analyses its bot, with the bots taken as
realizations of their own (realization index r K + b) and the bots of one realization kept
together as one block of the bootstrap behind every ``_error``: the per-realization values
(``NAME_realization``) are split back into (realization, bot), and the pooled values are
over every bot and realization (the cell's quantities, which every bot shares, are the
cell's). Then the collective quantities of the ring, per realization and their mean and
standard error across realizations (time averages after the discard):

- ``bots_boundary_fraction``: the fraction of bots whose centre is within one bot length
  (2 a) of the membrane's polygon;
- ``bots_polar_order``: |mean over bots of e^(i theta)|;
- ``bots_circulation``: the mean over bots of r_hat x e_hat, r_hat the unit vector from the
  cell's centre to the bot, e_hat its heading (+1: all running counter-clockwise around the
  centre), and ``bots_circulation_abs``, its absolute value (the sign is a coin's);
- ``membrane_shape_amplitude``: |r_n| / r_0 of the membrane's radius about its centre,
  r(phi) = sum r_n e^(i n phi), for n = 2..7 (``shape_mode``);
- ``membrane_asphericity``: (l1 - l2)^2 / (l1 + l2)^2 of the membrane points' gyration
  tensor (0 for a circle).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import xarray as xr

from softcell.schema import BOT_START_VARIABLES

#: The membrane's shape modes reported (n of r_n / r_0).
SHAPE_MODES = np.arange(2, 8)

#: The collective quantities: name -> (units, long name).
COLLECTIVE = {
    "bots_boundary_fraction": (
        "1",
        "fraction of bots with their centre within one bot length (2 a) of the membrane",
    ),
    "bots_polar_order": ("1", "polar order of the bots' headings, |mean of e^(i theta)|"),
    "bots_circulation": (
        "1",
        "mean over bots of r_hat x e_hat, r_hat from the cell's centre to the bot, e_hat its "
        "heading (+1: counter-clockwise)",
    ),
    "bots_circulation_abs": ("1", "absolute value of bots_circulation"),
    "membrane_asphericity": (
        "1",
        "(l1 - l2)^2 / (l1 + l2)^2 of the membrane points' gyration tensor",
    ),
}


def analyze_bots(
    ds: xr.Dataset,
    options: Mapping[str, Any] | None,
    *,
    progress: bool = False,
    registry: Any = None,
    analyze: Callable[..., xr.Dataset],
) -> xr.Dataset:
    """The analysis of several bots in one ring (see the module's docstring); ``analyze`` is
    the single-bot analysis (:func:`softcell.analysis.sweep.analyze`, which hands itself
    over)."""
    from softcell.analysis.collective import members_as_realizations, members_back
    from softcell.analysis.options import analysis_options

    k = ds.sizes["bot"]
    blocks = np.repeat(np.arange(ds.sizes["realization"]), k)
    per_bot = analyze(
        members_as_realizations(ds, "bot", BOT_START_VARIABLES),
        options,
        progress=progress,
        registry=registry,
        blocks=blocks,
    )
    out = members_back(per_bot, ds, "bot")
    discard = float(analysis_options(dict(options or {}))["discard"])
    lead = [d for d in ds["cell_x"].dims if d not in ("realization", "time")]
    a = float(json_parameter(ds, "bot_semi_major"))
    shape = [ds.sizes[d] for d in lead]
    n_real = ds.sizes["realization"]
    values = {name: np.full((*shape, n_real), np.nan) for name in COLLECTIVE}
    modes = np.full((*shape, n_real, SHAPE_MODES.size), np.nan)
    times = np.asarray(ds["time"].values)
    keep = times >= discard
    if keep.sum() < 1:
        from softcell.errors import SoftcellError

        raise SoftcellError(
            f"the record after the discard of {discard:g} s has no sample; the bots' "
            "collective statistics need at least one"
        )
    for point in np.ndindex(*shape):
        here = ds.isel(dict(zip(lead, point, strict=True))) if lead else ds
        for r in range(n_real):
            one = here.isel(realization=r, time=np.flatnonzero(keep))
            stats = ring_statistics(one, a)
            for name in COLLECTIVE:
                values[name][(*point, r)] = stats[name]
            modes[(*point, r)] = stats["membrane_shape_amplitude"]
    collective = _collective_dataset(values, modes, lead, ds, discard)
    out = xr.merge([out, collective], combine_attrs="override")
    out.attrs["softcell_bots"] = int(k)
    return out


def json_parameter(ds: xr.Dataset, name: str) -> float:
    """A parameter of the run, as the file's attributes store it (cm, s, ...)."""
    import json

    return float(json.loads(ds.attrs["softcell_parameters"])[name])


def ring_statistics(one: xr.Dataset, a: float) -> dict[str, Any]:
    """The collective quantities of one realization (``one``: no sweep or realization dim),
    averaged over its samples."""
    mx = np.asarray(one["membrane_x"].values)  # (T, N)
    my = np.asarray(one["membrane_y"].values)
    centre = np.asarray(one["cell_x"].values) + 1j * np.asarray(one["cell_y"].values)
    bots = np.asarray(one["bot_x"].values) + 1j * np.asarray(one["bot_y"].values)  # (T, K)
    heading = np.exp(1j * np.asarray(one["bot_angle"].values))
    points = mx + 1j * my
    near = _distance_to_polygon(bots, points) < 2 * a
    offset = bots - centre[:, None]
    unit = offset / np.where(np.abs(offset) > 0, np.abs(offset), 1.0)
    circulation = np.imag(np.conj(unit) * heading).mean(axis=1)
    return {
        "bots_boundary_fraction": float(near.mean()),
        "bots_polar_order": float(np.abs(heading.mean(axis=1)).mean()),
        "bots_circulation": float(circulation.mean()),
        "bots_circulation_abs": float(np.abs(circulation).mean()),
        "membrane_asphericity": float(_asphericity(points).mean()),
        "membrane_shape_amplitude": _shape_amplitudes(points, centre).mean(axis=0),
    }


def _distance_to_polygon(z: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance (cm) from each z[t, k] to the closed polygon points[t, :]: float64[T, K]."""
    start = points[:, None, :]
    edge = np.roll(points, -1, axis=1)[:, None, :] - start
    rel = z[:, :, None] - start
    length2 = np.maximum(np.abs(edge) ** 2, 1e-300)
    s = np.clip(np.real(rel * np.conj(edge)) / length2, 0.0, 1.0)
    return np.abs(rel - s * edge).min(axis=-1)


def _asphericity(points: np.ndarray) -> np.ndarray:
    """(l1 - l2)^2 / (l1 + l2)^2 of the gyration tensor of each row of points: float64[T]."""
    x = points.real - points.real.mean(axis=1, keepdims=True)
    y = points.imag - points.imag.mean(axis=1, keepdims=True)
    sxx, syy, sxy = (x * x).mean(1), (y * y).mean(1), (x * y).mean(1)
    trace, det = sxx + syy, sxx * syy - sxy * sxy
    gap2 = np.maximum(trace * trace - 4 * det, 0.0)  # (l1 - l2)^2
    return gap2 / np.maximum(trace * trace, 1e-300)


def _shape_amplitudes(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """|r_n| / r_0 (n in SHAPE_MODES) of the radius about ``centre`` as a function of the
    polar angle, by the trapezoidal rule over the polygon's points in angle order:
    float64[T, len(SHAPE_MODES)]."""
    rel = points - centre[:, None]
    phi = np.angle(rel)
    order = np.argsort(phi, axis=1)
    phi = np.take_along_axis(phi, order, axis=1)
    radius = np.take_along_axis(np.abs(rel), order, axis=1)
    # close the curve: the first point again, one turn on
    phi = np.concatenate([phi, phi[:, :1] + 2 * math.pi], axis=1)
    radius = np.concatenate([radius, radius[:, :1]], axis=1)
    step = np.diff(phi, axis=1)
    mid = 0.5 * (radius[:, 1:] + radius[:, :-1])
    r0 = (mid * step).sum(axis=1) / (2 * math.pi)
    out = np.empty((points.shape[0], SHAPE_MODES.size))
    for i, n in enumerate(SHAPE_MODES):
        f = radius * np.exp(-1j * n * phi)
        rn = (0.5 * (f[:, 1:] + f[:, :-1]) * step).sum(axis=1) / (2 * math.pi)
        out[:, i] = np.abs(rn) / r0
    return out


def _collective_dataset(values, modes, lead, ds, discard) -> xr.Dataset:
    """Per realization, mean and standard error across realizations of each quantity."""
    n = ds.sizes["realization"]
    spread = f"standard error across the {n} realizations (std / sqrt(n))"
    averaged = f"time average after the discard ({discard:g} s)"
    coords = {d: ds[d] for d in lead}
    coords["realization"] = ds["realization"]
    coords["shape_mode"] = (
        "shape_mode",
        SHAPE_MODES,
        {"units": "1", "long_name": "n of the membrane's shape mode r_n / r_0"},
    )
    data = {}

    def add(name, array, dims, units, long_name):
        mean = np.nanmean(array, axis=len(lead))
        error = (
            np.nanstd(array, axis=len(lead), ddof=1) / math.sqrt(n)
            if n > 1
            else np.full(mean.shape, np.nan)
        )
        data[f"{name}_realization"] = (
            (*lead, "realization", *dims),
            array,
            {"units": units, "long_name": f"{long_name}, per realization ({averaged})"},
        )
        data[name] = ((*lead, *dims), mean, {"units": units, "long_name": long_name})
        data[f"{name}_error"] = (
            (*lead, *dims),
            error,
            {"units": units, "long_name": f"standard error of {name}", "error": spread},
        )

    for name, (units, long_name) in COLLECTIVE.items():
        add(name, values[name], (), units, long_name)
    add(
        "membrane_shape_amplitude",
        modes,
        ("shape_mode",),
        "1",
        "|r_n| / r_0 of the membrane's radius about its centre",
    )
    return xr.Dataset(data, coords)
