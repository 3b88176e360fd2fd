"""NetCDF-4 input and output.

Files are written through :func:`softcell.io.files.atomic_write` (a hidden temporary name,
flushed and renamed when complete), so a crash never leaves a partial file under a final
name. Reading never decodes ``time`` into dates or timedeltas: simulated time stays a float
in seconds.
:func:`open_dataset` opens one file, or a directory holding the files of one sweep (one file
per parameter point and realization) as one Dataset with one dimension per swept parameter.

Every file carries the SHA-256 of what it stores (:data:`CHECKSUM`); :func:`data_problem`
recomputes it, so that a file damaged on disk is named and never trusted (a rerun recomputes
it, an analysis stops naming it).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

import softcell.analysis.accessor  # noqa: F401  (registers ds.softcell)
from softcell.engine.interrupt import deferred
from softcell.errors import ConfigError, SoftcellError
from softcell.io.files import atomic_write, folder_in_use, no_input
from softcell.model.parameters import MODEL_PARAMETERS, ParameterSpec

#: Keyword arguments that keep simulated time as plain seconds.
DECODE = {"decode_times": False, "decode_timedelta": False}


def _encoding(ds: xr.Dataset, complevel: int) -> dict[str, dict[str, Any]]:
    encoding: dict[str, dict[str, Any]] = {}
    for name, var in ds.data_vars.items():
        if var.ndim > 0 and var.dtype.kind in "fiu":
            encoding[name] = {"zlib": True, "complevel": complevel, "shuffle": True}
    for name, var in ds.variables.items():
        if var.dtype.kind in "UO":  # text as CF char arrays: plain xarray reads them as text
            encoding[name] = {"dtype": TEXT_ENCODING}
    return encoding


#: How text variables are stored: character arrays ("S1", with ``_Encoding`` utf-8, decoded
#: to text by xarray and netCDF4). NetCDF-4 strings (``str``), which CF 1.8 allows, would fail
#: the CF checker (cfchecker 4.1.0: error 2.2, "vlen types not supported").
TEXT_ENCODING = "S1"


#: Global attribute holding the SHA-256 (hex) of a file's contents: every variable's name,
#: type, shape, attributes and stored bytes, and every other global attribute.
CHECKSUM = "softcell_sha256"


def _value_bytes(value: Any) -> bytes:
    if isinstance(value, str):
        return b"s" + value.encode("utf-8")
    array = np.asarray(value)
    return array.dtype.str.encode() + np.ascontiguousarray(array).tobytes()


def _digest(nc: Any) -> str:
    """The SHA-256 of an open ``netCDF4.Dataset``'s contents as stored (no masking, scaling
    or text decoding), :data:`CHECKSUM` itself left out."""
    digest = hashlib.sha256()
    for name in sorted(nc.variables):
        var = nc.variables[name]
        var.set_auto_maskandscale(False)
        var.set_auto_chartostring(False)
        digest.update(f"{name}|{var.dtype}|{var.shape}".encode())
        for key in sorted(var.ncattrs()):
            digest.update(key.encode() + _value_bytes(var.getncattr(key)))
        digest.update(np.ascontiguousarray(var[...]).tobytes())
    for key in sorted(k for k in nc.ncattrs() if k != CHECKSUM):
        digest.update(key.encode() + _value_bytes(nc.getncattr(key)))
    return digest.hexdigest()


def data_problem(path: str | os.PathLike[str]) -> str | None:
    """Why the NetCDF file ``path`` cannot be trusted, or None when its contents match the
    checksum it was written with.

    A file written before checksums existed (softcell 0.2.0) is read in full instead: a
    compressed chunk that no longer decompresses is found, a silent change is not.

    Returns
    -------
    str or None
        e.g. ``"its contents do not match their checksum (damaged on disk)"``.
    """
    import netCDF4

    try:
        with netCDF4.Dataset(path) as nc:
            stored = nc.getncattr(CHECKSUM) if CHECKSUM in nc.ncattrs() else None
            found = _digest(nc)
    # netCDF4 reports damaged metadata as any of these (e.g. AttributeError: "Can't open
    # HDF5 attribute"); whichever it is, the file cannot be trusted.
    except (
        OSError,
        RuntimeError,
        ValueError,
        KeyError,
        AttributeError,
        IndexError,
        TypeError,
        MemoryError,
    ) as exc:
        return f"it cannot be read in full ({type(exc).__name__}: {exc}; damaged on disk)"
    if stored is not None and stored != found:
        return "its contents do not match their checksum (damaged on disk)"
    return None


def input_files(paths: list[str | os.PathLike[str]]) -> list[Path]:
    """The files that ``paths`` (files, and sweep directories) stand for."""
    files: list[Path] = []
    for path in map(Path, paths):
        if path.is_dir():
            files.extend(_sweep_files(path))
        elif path.is_file():
            files.append(path)
        else:
            raise SoftcellError(f"no such file or directory: {path}")
    seen: dict[Path, Path] = {}
    for path in files:
        same = seen.setdefault(path.resolve(), path)
        if same is not path:
            raise SoftcellError(
                f"{path} is given twice"
                + (f" (as {same})" if str(same) != str(path) else "")
                + ": give each file or folder once"
            )
    return files


def read_failure(paths: list[str | os.PathLike[str]], exc: BaseException) -> BaseException:
    """The error to raise when reading the inputs ``paths`` failed with ``exc`` (netCDF's
    "HDF error" names no file): a one-line :class:`SoftcellError` naming the first damaged
    file, or ``exc`` itself when every file reads in full and matches its checksum."""
    for path in input_files(paths):
        why = data_problem(path)
        if why:
            return SoftcellError(f"{path}: {why}; {RECOMPUTE}")
    return exc


def write_dataset(ds: xr.Dataset, path: str | os.PathLike[str], *, complevel: int = 4) -> Path:
    """Write ``ds`` to ``path`` as compressed NetCDF-4, atomically; each variable's CF
    ``units`` attribute is written as it is.

    Parameters
    ----------
    ds : xarray.Dataset
        Any Dataset; its variables and attributes are written as they are.
    path : path-like
        Final file name; parent directories are created.
    complevel : int
        zlib compression level (0-9) of every numeric data variable.

    Returns
    -------
    Path
        ``path``, which exists only once the whole file is written and flushed.

    Raises
    ------
    softcell.io.files.StorageError
        For a full disk, a read-only file system or a missing permission (one line); nothing
        is left under ``path`` nor beside it.
    """
    if not isinstance(ds, xr.Dataset):
        raise ConfigError(f"write_dataset: ds is a {type(ds).__name__}, not an xarray.Dataset")
    path = Path(path)
    ds = _to_cf(ds).copy()
    ds.attrs = {k: v for k, v in ds.attrs.items() if k != CHECKSUM}
    with atomic_write(path) as tmp, deferred():  # no signal inside netCDF's locked section
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4", encoding=_encoding(ds, complevel))
        import netCDF4

        with netCDF4.Dataset(tmp, "r+") as nc:  # the checksum of what was stored
            nc.setncattr(CHECKSUM, _digest(nc))
    return path


def _open(path: Path, chunks: Mapping[str, int] | None = None, verify: bool = True) -> xr.Dataset:
    """``xr.open_dataset`` of one file, with a one-line error for what is no NetCDF file and,
    with ``verify``, for one whose contents fail their checksum or that a newer softcell
    wrote."""
    if path.stat().st_size == 0:
        raise SoftcellError(f"{path} is empty (0 bytes): not a NetCDF file")
    try:
        ds = xr.open_dataset(path, engine="netcdf4", chunks=chunks, **DECODE)
    except (OSError, RuntimeError, ValueError, KeyError) as exc:
        raise SoftcellError(
            f"cannot read {path}: not a NetCDF file, or truncated or corrupt "
            f"({type(exc).__name__}: {exc})"
        ) from None
    ds.attrs.pop(CHECKSUM, None)  # a storage detail, not part of the data
    why = (data_problem(path) or _version_problem(ds)) if verify else None
    if why:
        ds.close()
        raise SoftcellError(f"{path}: {why}; {RECOMPUTE}")
    return ds


#: What a reader advises for a file it cannot trust.
RECOMPUTE = "recompute it (rerun the command that made it), or leave it out"


def _version_problem(ds: xr.Dataset) -> str | None:
    """Why a file's ``softcell_version`` says this softcell cannot read it, or None."""
    from packaging.version import InvalidVersion, Version

    from softcell._version import __version__

    stored = ds.attrs.get("softcell_version")
    if stored is None:
        return None  # not a softcell file: the schema's checks name what it lacks
    try:
        newer = Version(str(stored)) > Version(__version__)
    except InvalidVersion:
        return f"its softcell_version {stored!r} is not a version"
    if newer:
        return (
            f"softcell {stored} wrote it, newer than this softcell ({__version__}), "
            "whose reading of it is unknown: upgrade softcell"
        )
    return None


#: Attribute marking the label variable that stands in for a text dimension coordinate.
LABELS_OF = "softcell_labels_of"


def _to_cf(ds: xr.Dataset) -> xr.Dataset:
    """Text dimension coordinates (e.g. ``body``) become an integer index plus an auxiliary
    label variable ``<dim>_label``: CF has no text coordinate variables."""
    for name in [c for c in ds.coords if ds[c].dims == (c,) and ds[c].dtype.kind in "UO"]:
        attrs = dict(ds[name].attrs)
        labels = np.asarray(ds[name].values).astype(str)
        ds = ds.assign_coords(
            {
                name: (
                    name,
                    np.arange(labels.size),
                    {"units": "1", "long_name": f"{attrs.get('long_name', name)} (index)"},
                )
            }
        )
        ds = ds.assign_coords({f"{name}_label": (name, labels, {**attrs, LABELS_OF: name})})
    return ds


def _from_cf(ds: xr.Dataset) -> xr.Dataset:
    """Undo :func:`_to_cf`: label variables become the text coordinates again."""
    for name in [v for v in ds.variables if LABELS_OF in ds[v].attrs]:
        dim = ds[name].attrs[LABELS_OF]
        attrs = {k: v for k, v in ds[name].attrs.items() if k != LABELS_OF}
        labels = np.asarray(ds[name].values).astype(str)
        ds = ds.drop_vars(name).assign_coords({dim: (dim, labels, attrs)})
    return ds


def read_dataset(path: str | os.PathLike[str], *, verify: bool = True) -> xr.Dataset:
    """Read one NetCDF file fully into memory and close it; every variable keeps the CF
    ``units`` attribute it was written with.

    Parameters
    ----------
    path : path-like
        A softcell NetCDF file (simulation, tracked video or analysis).
    verify : bool
        Check the contents against the checksum they were written with, and that no newer
        softcell wrote the file, first (it costs about one more reading of the file).

    Raises
    ------
    SoftcellError
        For a missing, unreadable or damaged file (one line naming it).
    """
    path = Path(path)
    if not path.is_file():
        raise no_input(path, "NetCDF file")
    with _open(path, verify=verify) as ds:
        try:
            return _from_cf(ds.load())
        except (OSError, RuntimeError, ValueError) as exc:
            raise SoftcellError(
                f"cannot read {path}: truncated or corrupt ({type(exc).__name__}: {exc})"
            ) from None


def open_dataset(
    path: str | os.PathLike[str],
    *,
    chunks: Mapping[str, int] | None = None,
    verify: bool = True,
) -> xr.Dataset:
    """Open one softcell file, or a directory of files from one sweep, as one Dataset.

    Parameters
    ----------
    path : path-like
        A ``.nc`` file, or a directory whose ``*.nc`` files (hidden temporary files excluded)
        come from one run of ``softcell simulate``.
    chunks : mapping, optional
        Dask chunks (lazy loading); by default the data are read lazily without dask.
    verify : bool
        Check every file first: its contents against their checksum, its softcell version,
        and (for simulations and tracked films) the schema and that it holds positions. A
        directory that a running command is writing is refused either way.

    Returns
    -------
    xarray.Dataset
        For a directory: realizations concatenated along ``realization``, and one leading
        dimension per parameter whose value differs between files (e.g. ``radius``), carrying
        that parameter's units. The ``softcell_parameters`` attribute then lists the swept
        values.
    """
    path = Path(path)
    if path.is_file():
        return _from_cf(_open(path, chunks, verify))
    if not path.is_dir():
        raise SoftcellError(f"no such file or directory: {path}")
    return _combine(_sweep_files(path), chunks, verify)


def _sweep_files(directory: Path) -> list[Path]:
    holder = folder_in_use(directory)
    if holder:
        raise SoftcellError(
            f"{directory} is being written by {holder}: it holds only part of its files; "
            "wait for it to end"
        )
    try:  # Path.glob says nothing of a directory it cannot read
        with os.scandir(directory) as entries:
            names = [e.name for e in entries]
    except OSError as exc:
        raise SoftcellError(f"cannot read directory {directory} ({exc.strerror or exc})") from None
    files = sorted(directory / n for n in names if n.endswith(".nc") and not n.startswith("."))
    if not files:
        raise SoftcellError(f"no .nc files in directory {directory}")
    return files


def _combine(
    files: list[Path], chunks: Mapping[str, int] | None = None, verify: bool = True
) -> xr.Dataset:
    """One Dataset from the files of a sweep; analysis and export files among them are left
    out (they are results, not records)."""
    parts, names = [], []
    for f in files:
        ds = _open(f, chunks, verify)
        if ds.attrs.get("softcell_origin") in ("analysis", "export"):
            ds.close()
            continue
        why = _record_problem(ds) if verify else None
        if why:
            ds.close()
            raise SoftcellError(f"{f}: {why}; {RECOMPUTE}")
        parts.append(ds)
        names.append(str(f))
    if not parts:
        raise SoftcellError(f"no simulation or tracking files among {[str(f) for f in files]}")
    return parts[0] if len(parts) == 1 else combine_sweep(parts, names)


def open_inputs(
    paths: list[str | os.PathLike[str]],
    chunks: Mapping[str, int] | None = None,
    *,
    verify: bool = True,
) -> xr.Dataset:
    """Open files and directories (each a sweep, see :func:`open_dataset`) as one Dataset: a
    single file as is, several files combined along their swept parameters. ``chunks`` and
    ``verify`` as for :func:`open_dataset` (``chunks={}``: one dask chunk per file, so that
    an analysis holds one parameter point in memory at a time)."""
    return _combine(input_files(paths), chunks, verify)


#: The positions a simulation or a tracked film must hold somewhere (a free bot: the bot's).
POSITIONS = ("bot_x", "bot_y", "cell_x", "cell_y")


def _record_problem(ds: xr.Dataset) -> str | None:
    """Why a simulation or tracking file cannot be analysed: the first way it departs from
    the schema, or a position it holds nowhere (all NaN); None when it can."""
    from softcell.schema import problems

    found = problems(ds)
    if found:
        return f"it does not follow the simulation schema ({found[0]})"
    membrane = json.loads(ds.attrs.get("softcell_components", "{}")).get("membrane", True)
    for name in POSITIONS if membrane is not False else POSITIONS[:2]:
        if not bool(ds[name].notnull().any()):
            return f"{name} holds no value (all NaN)"
    return None


def _stored_parameters(parts: list[xr.Dataset], names: list[str]) -> list[dict[str, Any]]:
    """Each Dataset's parameters, as its ``softcell_parameters`` attribute stores them."""
    values = []
    for name, ds in zip(names, parts, strict=True):
        if "softcell_parameters" not in ds.attrs:
            raise SoftcellError(f"{name} has no softcell_parameters attribute")
        values.append(json.loads(ds.attrs["softcell_parameters"]))
    return values


def _followers(swept: list[str], values: list[dict[str, Any]]) -> dict[str, str]:
    """The swept parameters derived from another (duration from radius), each with the one it
    follows: no dimension of their own, they become coordinates along it."""
    follows: dict[str, str] = {}
    derived = [k for k in swept if k in MODEL_PARAMETERS and MODEL_PARAMETERS[k].default is None]
    for key in derived:
        for other in [k for k in swept if k != key and k not in follows]:
            pairs = {(json.dumps(v.get(other)), json.dumps(v.get(key))) for v in values}
            if len(pairs) == len({a for a, _ in pairs}):
                follows[key] = other
                break
    return follows


def _with_sweep_coordinates(
    ds: xr.Dataset,
    vals: dict[str, Any],
    swept: list[str],
    follows: dict[str, str],
    units: dict[str, str],
) -> xr.Dataset:
    """``ds`` with a length-1 dim per swept parameter, and its followers as coordinates."""
    for key in swept:  # a file stores its swept parameters as scalar coordinates too
        ds = ds.expand_dims(key) if key in ds.coords else ds.expand_dims({key: [vals[key]]})
        ds[key].attrs = _coordinate_attrs(key, units.get(key, "1"))
    for key, other in follows.items():
        ds = ds.assign_coords(
            {key: (other, [vals[key]], _coordinate_attrs(key, units.get(key, "1")))}
        )
    return ds


#: What every file of one sweep shares (global attributes).
SHARED = ("softcell_origin", "softcell_seed", "softcell_components", "softcell_version")


def _check_one_request(
    parts: list[xr.Dataset], names: list[str], values: list[dict[str, Any]], swept: list[str]
) -> None:
    """Raise unless the parts are files of one request: the same origin, seed, components and
    version, and, for files softcell simulated, parameters that differ only where their
    request swept them (a swept parameter is a scalar coordinate of each file)."""
    first = parts[0].attrs
    for ds, name in zip(parts[1:], names[1:], strict=True):
        for key in SHARED:
            if key in first and key in ds.attrs and str(first[key]) != str(ds.attrs[key]):
                raise SoftcellError(
                    f"{names[0]} and {name} are not one sweep: {key} = {first[key]} there, "
                    f"{ds.attrs[key]} here; analyse them separately"
                )
    for key in swept:
        for ds, name, vals in zip(parts, names, values, strict=True):
            if "softcell_spawn_key" in ds.attrs and key not in ds.coords:
                raise SoftcellError(
                    f"the inputs are not one sweep: parameter {key} differs between them "
                    f"({name} has {vals.get(key)}), but no request swept it; analyse them "
                    "separately"
                )


#: The time axes of a simulation (the membrane's samples, the bodies' fine record), which
#: differ in length between the points of a sweep over durations.
TIME_AXES = ("time", "fine_time", "event")


def _on_common_axes(parts: list[xr.Dataset]) -> list[xr.Dataset]:
    """The parts reindexed onto the union of each time axis they have (NaN where a part has
    no sample; ``bot_phase`` and ``bot_phase_fine`` -1). With two differing axes,
    ``xarray.combine_by_coords`` would otherwise take one of them for a dimension to
    concatenate along and broadcast every variable over the other."""
    for axis in TIME_AXES:
        if not all(axis in ds.coords for ds in parts):
            continue
        values = [np.asarray(ds[axis].values) for ds in parts]
        if all(np.array_equal(values[0], v) for v in values[1:]):
            continue
        union = np.unique(np.concatenate(values))
        fill = {n: np.int8(-1) for n in ("bot_phase", "bot_phase_fine")}
        parts = [
            ds.reindex({axis: union}, fill_value={n: v for n, v in fill.items() if n in ds})
            for ds in parts
        ]
    return parts


def combine_sweep(parts: list[xr.Dataset], names: list[str] | None = None) -> xr.Dataset:
    """Combine per-(point, realization) Datasets into one, adding swept-parameter dims.

    Parameters
    ----------
    parts : list of xarray.Dataset
        One Dataset per file, each with its ``softcell_parameters`` (values in the units of
        ``softcell_parameter_units``).
    names : list of str, optional
        How errors name each part (its file).

    Returns
    -------
    xarray.Dataset
        One dim per parameter that differs between the parts (a parameter derived from
        another is a coordinate along it), with its unit; missing points filled with NaN
        (``bot_phase``: -1).
    """
    names = names or [f"dataset {i}" for i in range(len(parts))]
    values = _stored_parameters(parts, names)
    parts = _numbered_films(parts, values)
    keys = sorted(set().union(*values))
    swept = [k for k in keys if len({json.dumps(v.get(k)) for v in values}) > 1]
    follows = _followers(swept, values)
    swept = [k for k in swept if k not in follows]
    _check_one_request(parts, names, values, swept)
    units = json.loads(parts[0].attrs.get("softcell_parameter_units", "{}"))
    expanded = _on_common_axes(
        [
            _with_sweep_coordinates(ds, vals, swept, follows, units)
            for ds, vals in zip(parts, values, strict=True)
        ]
    )
    fill = {"bot_phase": np.int8(-1)} if "bot_phase" in parts[0] else {}
    try:
        combined = xr.combine_by_coords(
            expanded,
            join="outer",
            combine_attrs="drop_conflicts",
            fill_value=fill or xr.core.dtypes.NA,
        )
    except ValueError as exc:
        raise SoftcellError(
            f"the files do not form one sweep ({exc}); swept parameters: {swept or 'none'}"
        ) from None
    merged = dict(values[0])
    for key in (*swept, *follows):
        merged[key] = sorted({v[key] for v in values})
    combined.attrs["softcell_parameters"] = json.dumps(merged)
    combined.attrs["softcell_swept_parameters"] = " ".join(swept)
    combined.attrs.update(_videos(parts))
    return combined


def _videos(parts: list[xr.Dataset]) -> dict[str, str]:
    """``softcell_videos``: the tracked films' names in the order given, when every part is
    a film (each part's own ``softcell_video`` conflicts, and is dropped)."""
    if not all("softcell_video" in ds.attrs for ds in parts):
        return {}
    return {"softcell_videos": json.dumps([ds.attrs["softcell_video"] for ds in parts])}


def _numbered_films(parts: list[xr.Dataset], values: list[dict[str, Any]]) -> list[xr.Dataset]:
    """Tracked films numbered as the realizations of their point: each film is realization 0
    of its own file, and the films of one radius are realizations 0, 1, ... in the order
    given (the order ``softcell_videos`` records). Other files are returned as they are."""
    if not all(ds.attrs.get("softcell_origin") == "tracking" for ds in parts):
        return parts
    count: dict[str, int] = {}
    numbered = []
    for ds, vals in zip(parts, values, strict=True):
        key = json.dumps(vals, sort_keys=True)
        index = count.get(key, 0)
        count[key] = index + ds.sizes["realization"]
        realization = np.arange(index, count[key])
        numbered.append(
            ds.assign_coords(realization=("realization", realization, ds["realization"].attrs))
        )
    return numbered


def _coordinate_attrs(name: str, unit: str) -> dict[str, str]:
    spec: ParameterSpec | None = MODEL_PARAMETERS.get(name)
    return {"units": unit, "long_name": spec.long_name if spec else name}
