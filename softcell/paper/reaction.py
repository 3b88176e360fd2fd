"""The membrane's reaction on the bot, measured on stored simulations (a mechanism study).

The paper explains the long go phases of its intermediate regime by the membrane steering the
bot ("membrane deformations constrict the bot's orientation"). Whether the model can do that
is a matter of magnitudes: the contact force and torque on the bot against the drive's F0 and
T0, and the heading's drift in a run, torque / gamma_R, against the tumble's T0 / gamma_R.
:func:`bot_reaction` evaluates every energy term's reaction on the bot at stored samples of
one realization (the membrane rebuilt exactly from its stored nodes), and
:func:`contact_summary` sums it up per radius over a sweep's files.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import xarray as xr

from softcell.components.registry import Registry, default_registry
from softcell.errors import SoftcellError

#: Samples of a record between two evaluations of the reaction.
STRIDE = 10


def _modes(x: np.ndarray, y: np.ndarray, cutoff: int) -> np.ndarray:
    """Fourier modes (complex128[T, 2 cutoff + 1], cm) of curves stored at N equally spaced
    xi (x, y float64[T, N], cm): exact when N > 2 cutoff (the stored shape is band-limited)."""
    z = np.asarray(x) + 1j * np.asarray(y)
    n = z.shape[-1]
    if n <= 2 * cutoff:
        raise SoftcellError(
            f"the membrane is stored at {n} nodes, too few for its cutoff {cutoff} "
            f"(needs > {2 * cutoff}): its modes cannot be recovered"
        )
    k = np.arange(-cutoff, cutoff + 1)
    return np.fft.fft(z, axis=-1)[..., k % n] / n


def _model(ds: xr.Dataset, registry: Registry):
    from softcell.engine.model import build_model

    try:
        components = json.loads(ds.attrs["softcell_components"])
        values = json.loads(ds.attrs["softcell_parameters"])
    except KeyError as exc:
        raise SoftcellError(
            f"not a softcell simulation (no {exc.args[0]} attribute): the reaction needs the "
            "model that made the file"
        ) from None
    if not components.get("membrane", True):
        raise SoftcellError("a free-bot simulation has no membrane to act on the bot")
    params = registry.parameters(values, components)
    return build_model(
        params,
        components["energy_terms"],
        components["driving_protocol"],
        friction_law=components.get("friction_law", "viscous"),
        registry=registry,
    )


def bot_reaction(
    ds: xr.Dataset, stride: int = STRIDE, registry: Registry | None = None
) -> xr.Dataset:
    """The energy terms' reaction on the bot at every ``stride``-th sample of one realization.

    Parameters
    ----------
    ds : xarray.Dataset
        One simulation file's Dataset (dims realization = 1, time, node), positions in cm.
    stride : int
        Samples between two evaluations (>= 1).
    registry : Registry, optional
        Where the file's components are looked up (default: built-ins and installed plugins).

    Returns
    -------
    xarray.Dataset
        Along ``time`` (s): ``contact_force_x``, ``contact_force_y`` (N) and
        ``contact_torque`` (N cm, about the bot's centre, counter-clockwise positive), the
        reaction -(2 pi / N) sum_n de_n / d(x, y, theta) of every energy term in the file.
    """
    from softcell.engine.reference import force_modes

    if int(stride) < 1:
        raise SoftcellError(f"stride = {stride} is not allowed: must be >= 1")
    model = _model(ds, registry if registry is not None else default_registry())
    pick = slice(None, None, int(stride))
    mx = np.asarray(ds["membrane_x"].isel(realization=0).values)[pick]
    my = np.asarray(ds["membrane_y"].isel(realization=0).values)[pick]
    modes = _modes(mx, my, model.cutoff)
    pose = np.stack(
        [
            np.asarray(ds[v].isel(realization=0).values)[pick]
            for v in ("bot_x", "bot_y", "bot_angle")
        ],
        axis=-1,
    )
    weight = -2 * math.pi / model.nodes
    out = np.empty((modes.shape[0], 3))
    for i in range(modes.shape[0]):
        out[i] = weight * force_modes(model, modes[i], pose[i])[1]
    time = np.asarray(ds["time"].values)[pick]
    attrs = {"long_name": "time", "units": "s"}
    return xr.Dataset(
        {
            "contact_force_x": (
                "time",
                out[:, 0],
                {"units": "N", "long_name": "membrane force on the bot, x"},
            ),
            "contact_force_y": (
                "time",
                out[:, 1],
                {"units": "N", "long_name": "membrane force on the bot, y"},
            ),
            "contact_torque": (
                "time",
                out[:, 2],
                {"units": "N cm", "long_name": "membrane torque on the bot about its centre"},
            ),
        },
        coords={"time": ("time", time, attrs)},
    )


def contact_summary(
    folder: str | os.PathLike[str],
    realizations: int = 3,
    stride: int = STRIDE,
    discard: float = 15.0,
    registry: Registry | None = None,
) -> xr.Dataset:
    """The membrane's reaction on the bot per radius of a sweep's simulation folder.

    Reads the first ``realizations`` files of every point (``pointPPP_realizationRRRR.nc``),
    evaluates :func:`bot_reaction` every ``stride`` samples after ``discard`` s, and returns
    along ``radius`` (cm): ``contact_torque_rms`` and ``contact_torque_max`` (N cm, the largest
    |torque|), ``contact_force_rms`` (N), ``contact_fraction`` (1, samples with a non-zero
    force), and the drive's ``drive_torque`` (N cm), ``drive_force`` (N) and
    ``bot_rotational_friction`` (N cm s) for scale.
    """
    from softcell.io.netcdf import read_dataset

    folder = Path(folder)
    files = sorted(folder.glob("point*_realization*.nc"))
    if not files:
        raise SoftcellError(f"{folder} holds no simulation files (pointPPP_realizationRRRR.nc)")
    points: dict[str, list[Path]] = {}
    for f in files:
        points.setdefault(f.name.split("_")[0], []).append(f)
    rows = []
    for name in sorted(points):
        torque, force, radius, params = [], [], np.nan, {}
        for f in points[name][: max(int(realizations), 1)]:
            ds = read_dataset(f)
            ds = ds.isel(time=np.asarray(ds["time"].values) >= float(ds["time"][0]) + discard)
            r = bot_reaction(ds, stride, registry)
            torque.append(r["contact_torque"].values)
            force.append(np.hypot(r["contact_force_x"].values, r["contact_force_y"].values))
            params = json.loads(ds.attrs["softcell_parameters"])
            radius = float(params["radius"])
        t, f_ = np.concatenate(torque), np.concatenate(force)
        rows.append(
            (
                radius,
                float(np.sqrt(np.mean(t**2))),
                float(np.abs(t).max()),
                float(np.sqrt(np.mean(f_**2))),
                float(np.mean(f_ > 0)),
                float(params["drive_torque"]),
                float(params["drive_force"]),
                float(params["bot_rotational_friction"]),
            )
        )
    a = np.array(rows)
    spec = (
        ("contact_torque_rms", "N cm", "RMS membrane torque on the bot"),
        ("contact_torque_max", "N cm", "largest |membrane torque| on the bot"),
        ("contact_force_rms", "N", "RMS |membrane force| on the bot"),
        ("contact_fraction", "1", "fraction of samples with the membrane touching the bot"),
        ("drive_torque", "N cm", "drive torque T0 in a tumble"),
        ("drive_force", "N", "drive force F0 in a run"),
        ("bot_rotational_friction", "N cm s", "rotational friction gamma_R of the bot"),
    )
    return xr.Dataset(
        {
            n: ("radius", a[:, k + 1], {"units": u, "long_name": ln})
            for k, (n, u, ln) in enumerate(spec)
        },
        coords={"radius": ("radius", a[:, 0], {"units": "cm", "long_name": "membrane radius R"})},
        attrs={"realizations": int(realizations), "stride": int(stride), "discard": float(discard)},
    )
