"""A simulation as other tools read it: GSD (``softcell export SIM.nc -o traj.gsd``).

GSD is HOOMD-blue's trajectory format, read by OVITO, freud, MDAnalysis and AMEP. Each
stored sample becomes one frame; its particles are the membrane's stored nodes (type
``membrane``, cell by cell, node by node) and then the bots (type ``bot``, one per cell),
in cm. Every frame logs its time in s (``log/softcell/time``); frame 0 logs the simulation
file's attributes as JSON in UTF-8 bytes (``log/softcell/attributes``, uint8: parameters,
seed, components, version; :func:`gsd_attributes` reads them), so an exported run can be
redone. The particles' shapes (``type_shapes``) are the
membrane nodes as discs of the nodes' mean spacing and the bot as an ellipse of its
semi-axes; a bot's orientation is the quaternion of its heading about z.

A periodic assembly's box is its box, its positions wrapped into it about the origin with
their image counts (freud does both), so that a reader can unwrap them. A single cell, an
assembly between walls or in the open plane has no periodic box: its GSD box is a square
about the origin that holds every frame (or the walls' box), and every image count is 0.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from softcell.engine.interrupt import deferred
from softcell.errors import SoftcellError
from softcell.io.files import atomic_write, default_mode
from softcell.io.files import gsd_attributes as gsd_attributes  # read here, kept with the files

#: The GSD particle types, in order of their type ids.
TYPES = ("membrane", "bot")
#: Room (cm) between the outermost position and the side of a box that only holds frames.
MARGIN = 1.0


@dataclass(frozen=True)
class Exported:
    """What :func:`to_gsd` wrote.

    Parameters
    ----------
    path : Path
        The GSD file.
    frames : int
        Frames written.
    particles : int
        Particles per frame.
    span : tuple of float
        First and last frame's time (s).
    """

    path: Path
    frames: int
    particles: int
    span: tuple[float, float]


def _realization(ds: xr.Dataset, realization: int | None) -> xr.Dataset:
    """The one realization to export, checked."""
    count = ds.sizes.get("realization", 1)
    if realization is None:
        if count > 1:
            raise SoftcellError(
                f"the file holds {count} realizations; choose one with --realization "
                f"(0 to {count - 1})"
            )
        realization = 0
    if not 0 <= realization < count:
        raise SoftcellError(
            f"--realization {realization} is not allowed: the file holds realizations 0 to "
            f"{count - 1}"
        )
    return ds.isel(realization=realization) if "realization" in ds.dims else ds


def _check_simulation(ds: xr.Dataset) -> None:
    """Refuse what is no single simulated run: a sweep, an analysis, a tracking file."""
    origin = ds.attrs.get("softcell_origin")
    if origin != "simulation":
        raise SoftcellError(
            f"export takes a simulation file (softcell simulate); this one is a softcell "
            f"{origin or 'unknown'} file"
        )
    allowed = ("realization", "time", "cell", "node", "fine_time", "bot")
    extra = [d for d in ds.dims if d not in allowed]
    if extra:
        raise SoftcellError(
            f"export takes one parameter point; this input sweeps {', '.join(extra)} "
            "(export one of its files)"
        )


def _positions(ds: xr.Dataset, every: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times (s), positions (frames, particles, 2) in cm and bot headings (frames, cells) in
    rad, every ``every``-th sample; a free bot's membrane (all NaN) is left out."""
    sl = slice(None, None, every)
    time = ds["time"].values[sl]
    cells = ds.sizes.get("cell", 1)
    nodes = ds.sizes["node"]

    def values(name: str) -> np.ndarray:
        return ds[name].values[sl].reshape(time.size, -1)

    mx, my = values("membrane_x"), values("membrane_y")
    bots = np.stack([values("bot_x"), values("bot_y")], axis=-1)
    if np.isnan(mx).all():  # the free bot
        xy = bots
    else:
        membrane = np.stack([mx, my], axis=-1).reshape(time.size, cells * nodes, 2)
        xy = np.concatenate([membrane, bots], axis=1)
    return time, xy, values("bot_angle")


def _box(ds: xr.Dataset, xy: np.ndarray):
    """The freud box of the export and whether it is periodic."""
    import freud

    side = float(ds["domain_box"].values) if "domain_box" in ds else math.nan
    periodic = "domain_box" in ds and ds["domain_box"].attrs.get("boundary") == "periodic"
    if not math.isfinite(side):
        side = 2 * float(np.nanmax(np.abs(xy))) + 2 * MARGIN
    return freud.box.Box.square(side), periodic


def _shapes(ds: xr.Dataset) -> list[dict]:
    """GSD ``type_shapes``: discs of the nodes' mean spacing, the bot's ellipse (cm)."""
    params = json.loads(ds.attrs["softcell_parameters"])
    spacing = 2 * math.pi * float(params["radius"]) / ds.sizes["node"]
    a, b = float(params["bot_semi_major"]), float(params["bot_semi_minor"])
    return [
        {"type": "Sphere", "diameter": spacing},
        {"type": "Ellipsoid", "a": a, "b": b, "c": b / 4},
    ]


def check_gsd_path(path: str | os.PathLike[str]) -> Path:
    """``path`` as a Path, refused in one line unless it ends in ``.gsd``."""
    path = Path(path)
    if path.suffix.lower() != ".gsd":
        raise SoftcellError(f"-o {path}: a GSD file ends in .gsd")
    return path


def to_gsd(
    ds: xr.Dataset,
    path: str | os.PathLike[str],
    *,
    realization: int | None = None,
    every: int = 1,
) -> Exported:
    """Write one realization of the simulation ``ds`` as a GSD trajectory at ``path``.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation file as ``softcell simulate`` writes it (one cell or an assembly).
    path : path-like
        The ``.gsd`` file, written atomically (a crash leaves none).
    realization : int, optional
        Which realization; required when ``ds`` holds more than one.
    every : int
        Write every ``every``-th stored sample (>= 1).

    Returns
    -------
    Exported

    Raises
    ------
    SoftcellError
        For an input that is no simulation of one parameter point, a realization it does not
        hold, ``every`` < 1, or an output not ending in ``.gsd``.
    """
    import gsd.hoomd

    path = check_gsd_path(path)
    if every < 1:
        raise SoftcellError(f"--every {every} is not allowed: must be >= 1")
    _check_simulation(ds)
    one = _realization(ds, realization)
    time, xy, heading = _positions(one, every)
    box, periodic = _box(one, xy)
    n, bots = xy.shape[1], heading.shape[1]
    typeid = np.zeros(n, dtype=np.uint32)
    typeid[n - bots :] = 1
    # UTF-8 bytes: gsd 5.0 writes a str log but fails reading any later frame after one
    attributes = np.frombuffer(
        json.dumps({k: _plain(v) for k, v in ds.attrs.items()}).encode(), dtype=np.uint8
    )
    with atomic_write(path) as tmp:
        with gsd.hoomd.open(tmp, "w") as trajectory:
            for i, t in enumerate(time):
                points = np.zeros((n, 3))
                points[:, :2] = xy[i]
                frame = gsd.hoomd.Frame()
                frame.configuration.step = i * every
                frame.configuration.dimensions = 2
                frame.configuration.box = [box.Lx, box.Ly, 0, 0, 0, 0]
                frame.particles.N = n
                frame.particles.position = box.wrap(points).astype(np.float32)
                frame.particles.image = (box.get_images(points) if periodic else 0 * points).astype(
                    np.int32
                )
                orientation = np.tile(np.array([1.0, 0, 0, 0], dtype=np.float32), (n, 1))
                orientation[n - bots :, 0] = np.cos(heading[i] / 2)
                orientation[n - bots :, 3] = np.sin(heading[i] / 2)
                frame.particles.orientation = orientation
                frame.log["softcell/time"] = np.array([t], dtype=np.float64)
                if i == 0:
                    frame.particles.types = list(TYPES)
                    frame.particles.typeid = typeid
                    frame.particles.type_shapes = _shapes(ds)
                    frame.log["softcell/attributes"] = attributes
                trajectory.append(frame)
        default_mode(tmp)  # gsd creates its files 0640; every output is 0666 less the umask
    return Exported(path, int(time.size), n, (float(time[0]), float(time[-1])))


def _plain(value):
    """An attribute as JSON takes it (numpy scalars as Python numbers)."""
    return value.item() if isinstance(value, np.generic) else value


# -- movement's poses dataset -----------------------------------------------------------------

#: The keypoints of a poses dataset: the bot's centre, the point its heading marks at its
#: semi-major axis (so that a pose carries the heading), and the cell's centre (membrane GC).
KEYPOINTS = ("bot", "bot_front", "cell")


def to_movement(
    ds: xr.Dataset, path: str | os.PathLike[str], *, realization: int | None = None
) -> Exported:
    """Write one realization of a tracked or simulated ``ds`` as a poses dataset of the
    ``movement`` package (netCDF), which ``movement`` and its napari widget load.

    The layout is movement's: ``position`` (time, space, keypoints, individuals) in cm and
    ``confidence`` (time, keypoints, individuals), with the attributes ``ds_type = "poses"``,
    ``source_software``, ``fps`` and ``time_unit = "seconds"``. The keypoints are
    bot, bot_front and cell (``KEYPOINTS``); the individuals are the cells (one, or an
    assembly's), or the bots of a ring of several (each with the ring's centre as its cell
    keypoint). Time keeps its values (s). A tracked frame whose bot or membrane was lost
    has NaN positions and confidence 0 for those keypoints; everything else has
    confidence 1.

    Parameters
    ----------
    ds : xarray.Dataset
        A tracking file (``softcell track``) or a simulation file of one parameter point.
    path : path-like
        The ``.nc`` file, written atomically.
    realization : int, optional
        Which realization; required when ``ds`` holds more than one.

    Returns
    -------
    Exported
        ``particles`` is keypoints x individuals.

    Raises
    ------
    SoftcellError
        For an input that is neither, a realization it does not hold, samples that are not
        evenly spaced in time (movement's ``fps``), or an output not ending in ``.nc``.
    """
    path = Path(path)
    if path.suffix.lower() != ".nc":
        raise SoftcellError(f"-o {path}: a movement poses file is netCDF and ends in .nc")
    origin = ds.attrs.get("softcell_origin")
    if origin not in ("tracking", "simulation"):
        raise SoftcellError(
            f"--to movement takes a tracking or simulation file; this one is a softcell "
            f"{origin or 'unknown'} file"
        )
    one = _realization(ds, realization)
    time = one["time"].values
    step = np.diff(time)
    if time.size < 2 or not np.allclose(step, step[0], rtol=1e-6):
        raise SoftcellError(
            "--to movement needs samples evenly spaced in time (movement has one fps); this "
            "file's sampling changes (export from a run with sample_every_late = sample_every)"
        )
    position, confidence, names = _poses(one, ds)
    poses = xr.Dataset(
        {
            "position": (("time", "space", "keypoints", "individuals"), position, {"units": "cm"}),
            "confidence": (("time", "keypoints", "individuals"), confidence, {"units": "1"}),
        },
        coords={
            "time": ("time", time, {"units": "s"}),
            "space": ["x", "y"],
            "keypoints": list(KEYPOINTS),
            "individuals": names,
        },
        attrs={
            "ds_type": "poses",
            "source_software": f"softcell {ds.attrs.get('softcell_version', '')} {origin}",
            "fps": float(1.0 / step[0]),
            "time_unit": "seconds",
            "softcell_origin": "export",
            "softcell_attributes": json.dumps({k: _plain(v) for k, v in ds.attrs.items()}),
        },
    )
    with atomic_write(path) as tmp, deferred():
        poses.to_netcdf(tmp)
    span = (float(time[0]), float(time[-1]))
    return Exported(path, int(time.size), len(KEYPOINTS) * len(names), span)


def _poses(one: xr.Dataset, ds: xr.Dataset) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(time, 2, keypoints, cells) positions in cm, (time, keypoints, cells) confidences and
    the individuals' names."""
    from softcell.model.parameters import MODEL_PARAMETERS

    params = json.loads(ds.attrs.get("softcell_parameters", "{}"))
    semi_major = float(params.get("bot_semi_major", MODEL_PARAMETERS["bot_semi_major"].default))

    def cells(name: str) -> np.ndarray:  # (time, cells)
        return one[name].values.reshape(one.sizes["time"], -1)

    angle = cells("bot_angle")
    bx, by = cells("bot_x"), cells("bot_y")
    # several bots in one ring: the individuals are the bots, each with the ring's centre
    cx, cy = (np.broadcast_to(cells(n), bx.shape) for n in ("cell_x", "cell_y"))
    points = [
        (bx, by),
        (bx + semi_major * np.cos(angle), by + semi_major * np.sin(angle)),
        (cx, cy),
    ]
    position = np.stack([np.stack(p, axis=1) for p in points], axis=2)
    confidence = np.isfinite(position).all(axis=1).astype(np.float64)
    count = position.shape[-1]
    if "bot" in one.dims:
        names = [f"bot_{j}" for j in range(count)]
    else:
        names = ["cell"] if count == 1 else [f"cell_{c}" for c in range(count)]
    return position, confidence, names
