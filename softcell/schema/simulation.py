"""The simulation Dataset schema, as code: its variables, codes and attributes.

One simulation, or one tracked video, is one :class:`xarray.Dataset` with dims
``realization``, ``time`` and ``node``. A sweep adds one leading dimension per swept
parameter (e.g. ``radius``). :func:`validate` names every missing or malformed variable or
attribute. :func:`simulation_dataset` builds a conforming Dataset from arrays.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.errors import SchemaError

CONVENTIONS = "CF-1.8"

#: bot_phase flag values and meanings (CF flag_values / flag_meanings).
PHASE_UNKNOWN, PHASE_TUMBLE, PHASE_RUN = -1, 0, 1
PHASE_FLAGS = np.array([PHASE_UNKNOWN, PHASE_TUMBLE, PHASE_RUN], dtype=np.int8)
PHASE_MEANINGS = "unknown tumble run"

#: Stop/go labels of a speed series (the analysis' ``stopgo`` variable, CF flags).
STOPGO_UNKNOWN, STOP, GO = -1, 0, 1
STOPGO_FLAGS = np.array([STOPGO_UNKNOWN, STOP, GO], dtype=np.int8)
STOPGO_MEANINGS = "unknown stop go"

#: Coupling regimes of a parameter point (the analysis' ``regime`` variable, CF flags).
REGIMES = {"unknown": -1, "coupled": 0, "intermediate": 1, "decoupled": 2}
REGIME_NAMES = {code: name for name, code in REGIMES.items()}

#: tracking_flag values of a tracked video, by meaning.
TRACKING_FLAGS = {"ok": 0, "membrane_lost": 1, "bot_lost": 2, "both_lost": 3}


@dataclass(frozen=True)
class VariableSpec:
    """One variable of the schema: its dims, dtype kind ('f' float, 'i' integer), CF attributes."""

    name: str
    dims: tuple[str, ...]
    kind: str
    units: str
    long_name: str
    attrs: Mapping[str, Any] = field(default_factory=dict)

    def cf_attrs(self) -> dict[str, Any]:
        return {"units": self.units, "long_name": self.long_name, **self.attrs}


COORDINATES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec("realization", ("realization",), "i", "1", "realization index"),
        VariableSpec("time", ("time",), "f", "s", "time since the start of the record"),
        VariableSpec("node", ("node",), "i", "1", "membrane node index"),
    )
}

#: The coordinate of an assembly's cells: a file of many cells has the variables of one
#: with ``cell`` after its time dim ((realization, time, cell, node) for the membrane).
CELL_COORDINATE = VariableSpec("cell", ("cell",), "i", "1", "cell index in the assembly")

#: An assembly's domain: the side of its square box (NaN for the open plane), with its
#: boundary (open, walls, periodic) as an attribute; and where each cell started (both per
#: realization, so that the files of a sweep concatenate along it).
DOMAIN_VARIABLES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec(
            "domain_box",
            ("realization",),
            "f",
            "cm",
            "side of the square box (NaN: the open plane)",
        ),
        VariableSpec(
            "cell_start_x", ("realization", "cell"), "f", "cm", "cell starting center x coordinate"
        ),
        VariableSpec(
            "cell_start_y", ("realization", "cell"), "f", "cm", "cell starting center y coordinate"
        ),
    )
}


#: The coordinate of several bots in one ring: a file of K > 1 bots has the bot's variables
#: (``bot_*`` and ``bot_*_fine``) with ``bot`` after their time dim.
BOT_COORDINATE = VariableSpec("bot", ("bot",), "i", "1", "bot index in the ring")

#: Where each bot started (per realization, so that the files of a sweep concatenate).
BOT_START_VARIABLES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec("bot_start_x", ("realization", "bot"), "f", "cm", "bot starting x"),
        VariableSpec("bot_start_y", ("realization", "bot"), "f", "cm", "bot starting y"),
        VariableSpec("bot_start_angle", ("realization", "bot"), "f", "rad", "bot starting heading"),
    )
}


def with_bot(dims: tuple[str, ...]) -> tuple[str, ...]:
    """``dims`` of a bot's variable as a file of several bots stores it: ``bot`` after the
    time dim (after ``cell`` in an assembly)."""
    for i, d in enumerate(dims):
        if d in ("time", "fine_time"):
            j = i + 2 if i + 1 < len(dims) and dims[i + 1] == "cell" else i + 1
            return (*dims[:j], "bot", *dims[j:])
    return dims


def refuse_several_bots(ds: xr.Dataset, what: str) -> None:
    """Raise :class:`~softcell.errors.SoftcellError` in one line when ``ds`` holds several
    bots in one ring, which ``what`` (a command) does not handle yet."""
    if "bot" in ds.dims:
        from softcell.errors import SoftcellError

        raise SoftcellError(
            f"{what} does not handle files of several bots in one ring yet (this one has "
            f"{ds.sizes['bot']} bots); open it with softcell.open_dataset and select one, "
            "ds.isel(bot=0), for a first look"
        )


def with_cell(dims: tuple[str, ...]) -> tuple[str, ...]:
    """``dims`` of a one-cell variable as an assembly stores it: ``cell`` after the time
    dim (``time`` or ``fine_time``); dims without a time dim are unchanged."""
    for i, d in enumerate(dims):
        if d in ("time", "fine_time"):
            return (*dims[: i + 1], "cell", *dims[i + 1 :])
    return dims


VARIABLES: dict[str, VariableSpec] = {
    v.name: v
    for v in (
        VariableSpec(
            "membrane_x", ("realization", "time", "node"), "f", "cm", "membrane point x coordinate"
        ),
        VariableSpec(
            "membrane_y", ("realization", "time", "node"), "f", "cm", "membrane point y coordinate"
        ),
        VariableSpec(
            "cell_x", ("realization", "time"), "f", "cm", "cell geometric center x coordinate"
        ),
        VariableSpec(
            "cell_y", ("realization", "time"), "f", "cm", "cell geometric center y coordinate"
        ),
        VariableSpec("bot_x", ("realization", "time"), "f", "cm", "bot center x coordinate"),
        VariableSpec("bot_y", ("realization", "time"), "f", "cm", "bot center y coordinate"),
        VariableSpec(
            "bot_angle", ("realization", "time"), "f", "rad", "bot heading (major axis direction)"
        ),
        VariableSpec(
            "bot_phase",
            ("realization", "time"),
            "i",
            "1",
            "bot driving phase",
            {"flag_values": PHASE_FLAGS, "flag_meanings": PHASE_MEANINGS},
        ),
    )
}

#: The bodies' fine record (optional): the cell's centre and the bot's pose at every
#: ``sample_every`` over the whole run, on their own time axis ``fine_time``, so that
#: analyses of the bodies (the MSD at every lag) use one record (docs/model.md §6). Absent
#: from tracked videos and from files of softcell before 0.3.
#: When a protocol's state events ended phases (optional: only protocols with events).
EVENT_COORDINATE = VariableSpec("event", ("event",), "i", "1", "index of a state event")
EVENT_TIME = VariableSpec(
    "event_time",
    ("realization", "event"),
    "f",
    "s",
    "time at which a state event of the driving protocol ended a phase (NaN: no more events)",
)

FINE_COORDINATE = VariableSpec(
    "fine_time", ("fine_time",), "f", "s", "time of the bodies' fine record"
)
FINE_VARIABLES: dict[str, VariableSpec] = {
    f"{name}_fine": VariableSpec(
        f"{name}_fine",
        ("realization", "fine_time"),
        spec.kind,
        spec.units,
        f"{spec.long_name} (fine record)",
        dict(spec.attrs),
    )
    for name, spec in VARIABLES.items()
    if name.startswith(("cell_", "bot_"))
}

#: Global attributes every file carries, and those a simulation adds.
REQUIRED_ATTRS = ("Conventions", "title", "source", "softcell_version", "softcell_origin")
SIMULATION_ATTRS = (
    "softcell_parameters",
    "softcell_parameter_units",
    "softcell_seed",
    "softcell_components",
)
ORIGINS = ("simulation", "tracking")


def problems(ds: xr.Dataset) -> list[str]:
    """Every way ``ds`` departs from the schema (empty list: it conforms)."""
    found: list[str] = []
    for spec in (*COORDINATES.values(), *VARIABLES.values()):
        found.extend(_variable_problems(ds, spec))
    found.extend(_fine_problems(ds))
    if "event" in ds.dims or EVENT_TIME.name in ds.variables:
        for spec in (EVENT_COORDINATE, EVENT_TIME):
            found.extend(_variable_problems(ds, spec))
    if "cell" in ds.dims:
        for spec in (CELL_COORDINATE, *DOMAIN_VARIABLES.values()):
            found.extend(_variable_problems(ds, spec))
    if "bot" in ds.dims:
        for spec in (BOT_COORDINATE, *BOT_START_VARIABLES.values()):
            found.extend(_variable_problems(ds, spec))
    if "time" in ds.coords and ds.sizes.get("time", 0) > 1:
        if not bool(np.all(np.diff(ds["time"].values) > 0)):
            found.append("time: values must increase strictly")
    found.extend(
        f"{name}: values outside the flag values {PHASE_FLAGS.tolist()}"
        for name in ("bot_phase", "bot_phase_fine")
        if name in ds.variables and not np.isin(np.unique(ds[name].values), PHASE_FLAGS).all()
    )
    return found + _attribute_problems(ds)


def _attribute_problems(ds: xr.Dataset) -> list[str]:
    """How the global attributes depart from the schema."""
    found = [f"global attribute {n!r} is missing" for n in REQUIRED_ATTRS if n not in ds.attrs]
    if ds.attrs.get("Conventions", CONVENTIONS) != CONVENTIONS:
        found.append(f"global attribute Conventions must be {CONVENTIONS!r}")
    origin = ds.attrs.get("softcell_origin")
    if origin is not None and origin not in ORIGINS:
        found.append(f"global attribute softcell_origin must be one of {ORIGINS}, not {origin!r}")
    if origin == "simulation":
        for name in SIMULATION_ATTRS:
            if name not in ds.attrs:
                found.append(f"global attribute {name!r} is missing (required for simulations)")
    return found


def _fine_problems(ds: xr.Dataset) -> list[str]:
    """How the bodies' fine record departs from the schema: optional, but all or nothing."""
    if not any(n in ds.variables for n in (FINE_COORDINATE.name, *FINE_VARIABLES)):
        return []
    found = []
    for spec in (FINE_COORDINATE, *FINE_VARIABLES.values()):
        found.extend(_variable_problems(ds, spec))
    if "fine_time" in ds.coords and ds.sizes.get("fine_time", 0) > 1:
        if not bool(np.all(np.diff(ds["fine_time"].values) > 0)):
            found.append("fine_time: values must increase strictly")
    return found


def _expected_dims(ds: xr.Dataset, spec: VariableSpec) -> tuple[str, ...]:
    """The dims ``spec``'s variable must end with in ``ds``: ``cell`` after the time dim in
    an assembly's file, ``bot`` after it for the bot's variables of several bots."""
    per_cell = spec.name in VARIABLES or spec.name in FINE_VARIABLES
    expected = with_cell(spec.dims) if per_cell and "cell" in ds.dims else spec.dims
    if per_cell and "bot" in ds.dims and spec.name.startswith("bot_"):
        expected = with_bot(expected)
    return expected


def _variable_problems(ds: xr.Dataset, spec: VariableSpec) -> list[str]:
    if spec.name not in ds.variables:
        return [f"{spec.name}: missing"]
    var = ds[spec.name]
    found = []
    # Sweeps add leading dims (one per swept parameter); the schema's dims must come last
    # (with ``cell`` after the time dim in an assembly's file).
    expected = _expected_dims(ds, spec)
    if var.dims[len(var.dims) - len(expected) :] != expected:
        found.append(f"{spec.name}: dims {var.dims}, expected (..., {', '.join(expected)})")
    if var.dtype.kind not in (spec.kind, "u" if spec.kind == "i" else spec.kind):
        found.append(
            f"{spec.name}: dtype {var.dtype}, expected "
            + ("floating point" if spec.kind == "f" else "integer")
        )
    for attr in ("units", "long_name"):
        if attr not in var.attrs:
            found.append(f"{spec.name}: attribute {attr!r} missing")
    if var.attrs.get("units", spec.units) != spec.units:
        found.append(f"{spec.name}: units {var.attrs['units']!r}, expected {spec.units!r}")
    for attr, value in spec.attrs.items():
        if not np.array_equal(np.asarray(var.attrs.get(attr)), np.asarray(value)):
            found.append(f"{spec.name}: attribute {attr!r} must be {value!r}")
    return found


def validate(ds: xr.Dataset) -> xr.Dataset:
    """Return ``ds`` unchanged if it follows the schema (which includes each variable's
    CF ``units``: cm, s, rad, or 1).

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation or tracked Dataset.

    Raises
    ------
    SchemaError
        Naming every missing or malformed variable and attribute.
    """
    found = problems(ds)
    if found:
        raise SchemaError(found)
    return ds


def global_attrs(origin: str, title: str, source: str, **extra: Any) -> dict[str, Any]:
    """The global attributes every softcell file starts with (no timestamps: same inputs,
    same bytes)."""
    return {
        "Conventions": CONVENTIONS,
        "title": title,
        "source": source,
        "softcell_version": __version__,
        "softcell_origin": origin,
        **extra,
    }


def simulation_dataset(
    time: np.ndarray,
    realization: np.ndarray,
    *,
    membrane_x: np.ndarray,
    membrane_y: np.ndarray,
    bot_x: np.ndarray,
    bot_y: np.ndarray,
    bot_angle: np.ndarray,
    bot_phase: np.ndarray,
    parameters: Any,
    seed: int,
    components: Mapping[str, Any],
    cell_x: np.ndarray | None = None,
    cell_y: np.ndarray | None = None,
    extra_attrs: Mapping[str, Any] | None = None,
    scalar_coords: Sequence[str] = ("radius",),
    fine: Mapping[str, np.ndarray] | None = None,
    domain: Mapping[str, Any] | None = None,
    events: np.ndarray | None = None,
    bots: Mapping[str, Any] | None = None,
) -> xr.Dataset:
    """Build a simulation Dataset that follows the schema.

    Parameters
    ----------
    time : float64[T]
        Sample times (s).
    realization : int[R]
        Realization indices.
    membrane_x, membrane_y : float64[R, T, M]
        Membrane points (cm).
    bot_x, bot_y, bot_angle : float64[R, T]
        Bot center (cm) and heading (rad).
    bot_phase : int8[R, T]
        Driving phase code (0 tumble, 1 run, -1 unknown).
    parameters : Parameters
        The run's parameters (stored with units in the attributes).
    seed : int
        Root seed of the run.
    components : mapping
        Component names by kind, e.g. ``{"energy_terms": [...], "integrator": "..."}``.
    cell_x, cell_y : float64[R, T], optional
        Geometric center (cm); by default the algebraic mean of the membrane points.
    scalar_coords : sequence of str
        Parameters also stored as scalar coordinates with their units and long names (the
        swept ones: a sweep's files then combine with plain xarray along them).
    fine : mapping, optional
        The bodies' fine record: ``fine_time`` (float64[F], s) and every variable of
        :data:`FINE_VARIABLES` ([R, F]: ``cell_x_fine`` ... in cm, ``bot_angle_fine`` in rad,
        ``bot_phase_fine`` int8).
    domain : mapping, optional
        For an assembly of cells: ``box`` (cm, NaN for the open plane), ``boundary`` (str)
        and ``start_x``, ``start_y`` (float64[C], cm); every variable then has a ``cell`` dim
        after its time dim ([R, T, C, node] for the membrane, [R, T, C] for the bodies).
    events : float64[R, E], optional
        The times (s) at which the protocol's state events ended phases, NaN-padded
        (``event_time``; only for a protocol with events).
    bots : mapping, optional
        For several bots in one ring: ``start`` (float64[K, 3]: the starting poses, cm, cm,
        rad) and ``settings`` (stored as the attribute ``bots`` of ``bot_start_x``); the
        bot's variables then have a ``bot`` dim after their time dim ([R, T, K]).
    """
    if cell_x is None:
        cell_x = membrane_x.mean(axis=-1)
    if cell_y is None:
        cell_y = membrane_y.mean(axis=-1)
    arrays = {
        "membrane_x": membrane_x,
        "membrane_y": membrane_y,
        "cell_x": cell_x,
        "cell_y": cell_y,
        "bot_x": bot_x,
        "bot_y": bot_y,
        "bot_angle": bot_angle,
        "bot_phase": np.asarray(bot_phase, dtype=np.int8),
    }

    def dims(d: tuple[str, ...], name: str = "") -> tuple[str, ...]:
        d = with_cell(d) if domain is not None else d
        return with_bot(d) if bots is not None and name.startswith("bot_") else d

    data_vars = {
        name: (dims(VARIABLES[name].dims, name), np.asarray(arr), VARIABLES[name].cf_attrs())
        for name, arr in arrays.items()
    }
    n_nodes = np.shape(membrane_x)[-1]
    coords = {
        "realization": (
            "realization",
            np.asarray(realization, dtype=np.int64),
            COORDINATES["realization"].cf_attrs(),
        ),
        "time": ("time", np.asarray(time, dtype=np.float64), COORDINATES["time"].cf_attrs()),
        "node": ("node", np.arange(n_nodes, dtype=np.int64), COORDINATES["node"].cf_attrs()),
    }
    if fine is not None:
        coords["fine_time"] = (
            "fine_time",
            np.asarray(fine["fine_time"], dtype=np.float64),
            FINE_COORDINATE.cf_attrs(),
        )
        for name, spec in FINE_VARIABLES.items():
            values = np.asarray(fine[name])
            if spec.name == "bot_phase_fine":
                values = values.astype(np.int8)
            data_vars[name] = (dims(spec.dims, name), values, spec.cf_attrs())
    if events is not None:
        events = np.asarray(events, dtype=np.float64)
        coords["event"] = (
            "event",
            np.arange(events.shape[-1], dtype=np.int64),
            EVENT_COORDINATE.cf_attrs(),
        )
        data_vars[EVENT_TIME.name] = (EVENT_TIME.dims, events, EVENT_TIME.cf_attrs())
    if domain is not None:
        cells = len(domain["start_x"])
        coords["cell"] = ("cell", np.arange(cells, dtype=np.int64), CELL_COORDINATE.cf_attrs())
        for name, value, extra in (  # per realization: a sweep's files concatenate along it
            ("domain_box", [domain["box"]], {"boundary": domain["boundary"]}),
            ("cell_start_x", [domain["start_x"]], {}),
            ("cell_start_y", [domain["start_y"]], {}),
        ):
            spec = DOMAIN_VARIABLES[name]
            data_vars[name] = (
                spec.dims,
                np.asarray(value, np.float64),
                {**spec.cf_attrs(), **extra},
            )
    if bots is not None:
        start = np.asarray(bots["start"], dtype=np.float64)
        coords["bot"] = ("bot", np.arange(len(start), dtype=np.int64), BOT_COORDINATE.cf_attrs())
        for column, name in enumerate(BOT_START_VARIABLES):
            spec = BOT_START_VARIABLES[name]
            extra = {"bots": json.dumps(bots["settings"], sort_keys=True)} if column == 0 else {}
            data_vars[name] = (spec.dims, start[None, :, column], {**spec.cf_attrs(), **extra})
    for name in dict.fromkeys(scalar_coords):
        spec = parameters.specs[name]
        coords[name] = ((), parameters[name], {"units": spec.unit, "long_name": spec.long_name})
    attrs = global_attrs(
        "simulation",
        "soft robotic cell simulation",
        f"softcell {__version__} simulation",
        softcell_seed=int(seed),
        softcell_components=json.dumps(dict(components), sort_keys=True),
        **parameters.to_attrs(),
        **dict(extra_attrs or {}),
    )
    return validate(xr.Dataset(data_vars, coords, attrs))
