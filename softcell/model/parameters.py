"""The parameter model: every model constant with its default, unit and allowed range.

The catalogue :data:`MODEL_PARAMETERS` is the table of docs/model.md §2 as code. A
:class:`Parameters` object is one validated point in that space: built from defaults,
a TOML file and command-line flags, checked by the rules of docs/model.md §2, and stored in
every output file's attributes (:meth:`Parameters.to_attrs`) so that any run can be redone.
Components may declare further parameters (a third-party energy term with its own
coefficient); they are validated and stored the same way.

Units follow docs/model.md §1: cm, s, rad, N. Unit strings are UDUNITS-2 syntax, as CF asks.
"""

from __future__ import annotations

import difflib
import functools
import itertools
import json
import math
import numbers
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from softcell.errors import ConfigError, ParameterError
from softcell.model.limits import max_radius

Value = float | int | str


@dataclass(frozen=True)
class ParameterSpec:
    """Declaration of one parameter.

    Attributes
    ----------
    name : str
        Identifier used in code, TOML files, file attributes and as ``--name-with-dashes``.
    default : float, int, str or None
        Default value in ``unit``; ``None`` means the default is derived from other
        parameters (see ``_derived_default``).
    unit : str
        UDUNITS-2 unit string (``"1"`` for dimensionless).
    long_name : str
        Human-readable description, used as the CF ``long_name``.
    kind : type
        ``float``, ``int`` or ``str``.
    minimum, maximum : float, optional
        Bounds, in ``unit``.
    minimum_inclusive, maximum_inclusive : bool
        Whether each bound is itself allowed (default: minimum excluded, maximum included).
    choices : tuple of str, optional
        Allowed values of a ``str`` parameter.
    power_of_two : bool
        An ``int`` parameter that must be a power of two.
    """

    name: str
    default: Value | None
    unit: str
    long_name: str
    kind: type = float
    minimum: float | None = None
    maximum: float | None = None
    minimum_inclusive: bool = False
    maximum_inclusive: bool = True
    choices: tuple[str, ...] | None = None
    power_of_two: bool = False

    def allowed(self) -> str:
        """The allowed range as a phrase, with the unit: ``"> 0 cm"``."""
        if self.choices is not None:
            return "must be one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind is str:
            return f"must be text, in quotes ({self.long_name})"
        parts = []
        unit = "" if self.unit == "1" else f" {self.unit}"
        if self.minimum is not None:
            parts.append(f"{'>=' if self.minimum_inclusive else '>'} {self.minimum:g}{unit}")
        if self.maximum is not None:
            parts.append(f"{'<=' if self.maximum_inclusive else '<'} {self.maximum:g}{unit}")
        text = " and ".join(parts) if parts else f"any finite value{unit}"
        if self.kind is int:
            text = ("a power of two " if self.power_of_two else "an integer ") + text
        return "must be " + text

    def coerce(self, value: Any) -> Value:
        """Convert ``value`` (from TOML, a flag or an attribute) to ``kind``, or raise."""
        bad = ParameterError(
            self.name, repr(value), self.allowed(), "" if self.kind is str else self.unit
        )
        if isinstance(value, bool):  # numpy's bool is no numbers.Real: refused below
            raise bad
        if self.kind is str:
            if not isinstance(value, str):
                raise bad
            return value
        if isinstance(value, str):
            try:
                value = float(value)
            except ValueError:
                raise self._not_a_number(value) from None
        if not isinstance(value, numbers.Real):  # numpy's scalars too (np.float32(8))
            raise self._not_a_number(value)
        if self.kind is int:
            if not float(value).is_integer():
                raise bad
            return int(value)
        return float(value)

    def _not_a_number(self, value: Any) -> ParameterError:
        """The error for a value that is no number at all ("8cm", "five", a list)."""
        unit = "" if self.unit in ("", "1") else f" in {self.unit}"
        return ParameterError(
            self.name,
            repr(value),
            f"it is not a number: write {self.name} as a plain number{unit}, without its "
            f"unit ({self.allowed()})",
        )

    def check(self, value: Value) -> None:
        """Raise :class:`ParameterError` unless ``value`` (already coerced) is allowed."""
        if self.choices is not None:
            if value not in self.choices:
                raise ParameterError(self.name, repr(value), self.allowed(), self.unit)
            return
        if self.kind is str:
            return  # a name (e.g. of a plugin): whoever looks it up names a bad one
        assert isinstance(value, int | float)
        if not math.isfinite(value):
            rest = self.allowed().removeprefix("must be ")
            raise ParameterError(
                self.name,
                value,
                "must be finite" if rest.startswith("any finite") else f"must be finite and {rest}",
                self.unit,
            )
        if not self._in_range(value):
            raise ParameterError(self.name, value, self.allowed(), self.unit)

    def _in_range(self, value: float) -> bool:
        """Whether a finite ``value`` is within the bounds (and a power of two if asked)."""
        if self.minimum is not None and not (
            value >= self.minimum if self.minimum_inclusive else value > self.minimum
        ):
            return False
        if self.maximum is not None and not (
            value <= self.maximum if self.maximum_inclusive else value < self.maximum
        ):
            return False
        return not self.power_of_two or (value > 0 and (int(value) & (int(value) - 1)) == 0)


@functools.cache
def unit_problem(unit: object) -> str | None:
    """Why ``unit`` is not a unit a parameter may declare, or None.

    A unit is a non-empty UDUNITS-2 string (``"N cm-2"``; ``"1"`` for dimensionless), parsed
    by cf-units, which ships UDUNITS-2 in its wheels.
    """
    if not isinstance(unit, str) or not unit.strip():
        return f"unit {unit!r} is not a UDUNITS-2 unit string (use '1' for dimensionless)"
    import cf_units

    try:
        parsed = cf_units.Unit(unit)
    except ValueError:
        return f"unit {unit!r} does not parse as UDUNITS-2"
    if parsed.is_unknown() or parsed.is_no_unit():
        return f"unit {unit!r} is not a physical unit (use '1' for dimensionless)"
    return None


def _positive(name: str, default: float, unit: str, long_name: str) -> ParameterSpec:
    return ParameterSpec(name, default, unit, long_name, minimum=0.0)


#: docs/model.md §2, in the order of its table.
MODEL_PARAMETERS: dict[str, ParameterSpec] = {
    spec.name: spec
    for spec in (
        _positive("radius", 4.0, "cm", "unstretched membrane radius R (l0 = 2 pi R)"),
        ParameterSpec(
            "nodes",
            1024,
            "1",
            "membrane collocation points N",
            kind=int,
            minimum=8,
            minimum_inclusive=True,
            power_of_two=True,
        ),
        ParameterSpec(
            "cutoff",
            16,
            "1",
            "Fourier cutoff Lambda_c of the membrane shape",
            kind=int,
            minimum=2,
            minimum_inclusive=True,
        ),
        _positive("bending_stiffness", 0.57, "N cm2", "bending stiffness k"),
        _positive("tension", 0.02, "N cm-2", "surface tension coefficient alpha"),
        _positive(
            "membrane_friction", 3.42e-4, "N s cm-2", "membrane friction per unit length gamma_mem"
        ),
        _positive("contact_amplitude", 2.85e-4, "N", "bot-membrane interaction amplitude A"),
        _positive("contact_length", 0.01, "cm", "bot-membrane interaction length lambda"),
        _positive("bot_semi_major", 3.0, "cm", "bot semi-major axis a"),
        _positive("bot_semi_minor", 2.0, "cm", "bot semi-minor axis b"),
        _positive("drive_force", 0.04275, "N", "bot drive force F0"),
        _positive("drive_torque", 151.1, "N cm", "bot drive torque T0"),
        _positive("bot_friction", 0.00285, "N s cm-1", "bot translational friction gamma_T"),
        _positive("bot_rotational_friction", 28.5, "N cm s", "bot rotational friction gamma_R"),
        _positive("phase_min", 0.4, "s", "shortest run or tumble tau_l"),
        _positive("phase_max", 1.2, "s", "longest run or tumble tau_h"),
        _positive("dt", 1e-6, "s", "time step of the explicit_euler integrator"),
        ParameterSpec(
            "pivot_offset",
            1.0,
            "cm",
            "offset of the tumble pivot along the minor axis d_pivot",
            minimum=0.0,
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "pivot_side",
            "inner",
            "1",
            "side of the tumble pivot: inner side of each turn, or fixed",
            kind=str,
            choices=("inner", "fixed"),
        ),
        _positive(
            "duration",
            None,
            "s",
            "simulated duration (default 900 s for R < 10 cm, 1800 s otherwise)",
        ),
        _positive("sample_every", 0.01, "s", "sampling interval before sample_switch"),
        _positive("sample_every_late", 0.1, "s", "sampling interval from sample_switch on"),
        ParameterSpec(
            "sample_switch",
            100.0,
            "s",
            "time at which sampling changes to sample_every_late",
            minimum=0.0,
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "stored_nodes",
            64,
            "1",
            "membrane points written to files",
            kind=int,
            minimum=1,
            minimum_inclusive=True,
        ),
    )
}


def _derived_default(name: str, values: Mapping[str, Value]) -> Value:
    if name == "duration":
        # docs/model.md §2 (an assumption): the paper's experiment durations.
        return 900.0 if float(values["radius"]) < 10.0 else 1800.0
    raise AssertionError(f"no derived default for {name}")  # pragma: no cover


def _cross_check(v: Mapping[str, Value]) -> None:
    """The rules of docs/model.md §2 that involve more than one parameter."""
    if v["radius"] <= v["bot_semi_major"]:
        raise ParameterError(
            "radius", v["radius"], f"must be > bot_semi_major = {v['bot_semi_major']:g} cm", "cm"
        )
    if v["radius"] > max_radius(v["contact_length"]):
        raise ParameterError(
            "radius",
            v["radius"],
            f"must be <= {max_radius(v['contact_length']):.3g} cm: beyond it, "
            "float64 positions (relative rounding 2.2e-16) no longer resolve "
            f"the contact length lambda = {v['contact_length']:g} cm",
            "cm",
        )
    if v["bot_semi_minor"] > v["bot_semi_major"]:
        raise ParameterError(
            "bot_semi_minor",
            v["bot_semi_minor"],
            f"must be <= bot_semi_major = {v['bot_semi_major']:g} cm",
            "cm",
        )
    if v["cutoff"] >= v["nodes"] // 2:
        raise ParameterError(
            "cutoff",
            v["cutoff"],
            f"must be < nodes/2 = {v['nodes'] // 2} (nodes = {v['nodes']})",
            "1",
        )
    if v["stored_nodes"] <= 2 * v["cutoff"]:
        raise ParameterError(
            "stored_nodes",
            v["stored_nodes"],
            f"must be > 2 * cutoff = {2 * v['cutoff']} so the shape is resampled exactly",
            "1",
        )
    if v["phase_min"] > v["phase_max"]:
        raise ParameterError(
            "phase_min", v["phase_min"], f"must be <= phase_max = {v['phase_max']:g} s", "s"
        )
    if v["sample_every_late"] < v["sample_every"]:
        raise ParameterError(
            "sample_every_late",
            v["sample_every_late"],
            f"must be >= sample_every = {v['sample_every']:g} s",
            "s",
        )


def suggest(name: str, known: Iterable[str]) -> str:
    """``" (did you mean 'x'?)"`` for a misspelt name, or ``""``."""
    close = difflib.get_close_matches(name, list(known), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


class Parameters(Mapping[str, Value]):
    """One validated parameter point: a read-only mapping ``name -> value`` in declared units.

    Parameters
    ----------
    values : mapping, optional
        Values that differ from the defaults, by parameter name, in the declared units.
    extra_specs : iterable of ParameterSpec, optional
        Parameters declared by components beyond ``MODEL_PARAMETERS``. A plain value object:
        it never looks anything up, so a component's parameter (``{"pressure": 2e-4}``)
        needs its declaration here; ``Registry.parameters(values)`` passes every
        registered component's.

    Raises
    ------
    ConfigError
        For a parameter name neither ``MODEL_PARAMETERS`` nor ``extra_specs`` declares.
    ParameterError
        For a value outside its allowed range (the message names parameter, value, range, unit).

    Examples
    --------
    >>> p = Parameters({"radius": 12})
    >>> p.radius, p.duration, p.specs["radius"].unit
    (12.0, 1800.0, 'cm')
    """

    __slots__ = ("specs", "_given", "_values")

    def __init__(
        self, values: Mapping[str, Any] | None = None, extra_specs: Iterable[ParameterSpec] = ()
    ) -> None:
        specs = dict(_with_model_parameters(tuple(extra_specs)))
        given = {k: v for k, v in (values or {}).items() if v is not None}
        unknown = [k for k in given if k not in specs]
        if unknown:
            raise ConfigError(f"unknown parameter {unknown[0]!r}{suggest(unknown[0], specs)}")
        resolved: dict[str, Value] = {}
        for name, spec in specs.items():
            if name in given:
                resolved[name] = spec.coerce(given[name])
                spec.check(resolved[name])
            elif spec.default is not None:
                resolved[name] = spec.default
        for name, spec in specs.items():
            if name not in resolved:
                resolved[name] = spec.coerce(_derived_default(name, resolved))
                spec.check(resolved[name])
        _cross_check(resolved)
        self.specs: dict[str, ParameterSpec] = specs
        self._given = {k: resolved[k] for k in given}
        self._values = resolved

    def __getitem__(self, name: str) -> Value:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __getattr__(self, name: str) -> Value:
        try:
            return object.__getattribute__(self, "_values")[name]
        except KeyError:
            raise AttributeError(f"no parameter named {name!r}") from None

    def __repr__(self) -> str:
        return f"Parameters({self._given!r})"

    @property
    def given(self) -> dict[str, Value]:
        """The values that were set explicitly rather than taken from defaults."""
        return dict(self._given)

    def replace(self, **changes: Any) -> Parameters:
        """A new validated point with some values changed (derived defaults recomputed;
        values in each parameter's unit, ``specs[name].unit``)."""
        return Parameters({**self._given, **changes}, self._extra_specs())

    def _extra_specs(self) -> list[ParameterSpec]:
        return [s for n, s in self.specs.items() if n not in MODEL_PARAMETERS]

    @property
    def membrane_length(self) -> float:
        """Unstretched membrane length l0 = 2 pi R (cm)."""
        return 2.0 * math.pi * float(self._values["radius"])

    def to_attrs(self) -> dict[str, Any]:
        """File attributes: ``softcell_parameters`` (JSON ``{name: value}``, what softcell
        reads back), ``softcell_parameter_units`` (JSON ``{name: unit}``), and each parameter
        on its own as ``parameter_<name>`` (a number or text, so that ``ncdump -h`` and a
        plain ``xr.open_dataset`` show it; booleans as 0/1)."""
        each = parameter_attrs(self._values)
        return {
            "softcell_parameters": json.dumps(self._values),
            "softcell_parameter_units": json.dumps({k: s.unit for k, s in self.specs.items()}),
            **each,
        }

    @classmethod
    def from_attrs(
        cls, attrs: Mapping[str, Any], extra_specs: Iterable[ParameterSpec] = ()
    ) -> Parameters:
        """Rebuild the parameters stored by :meth:`to_attrs` in a file's attributes.

        Parameters
        ----------
        attrs : mapping
            A file's global attributes (``softcell_parameters``: values in the units of
            ``softcell_parameter_units``).
        extra_specs : iterable of ParameterSpec
            The specs of parameters the components added (a plugin's).
        """
        try:
            values = json.loads(attrs["softcell_parameters"])
        except KeyError:
            raise ConfigError("no softcell_parameters attribute: not a softcell file") from None
        return cls(values, extra_specs)


@functools.lru_cache(maxsize=64)
def _with_model_parameters(extra: tuple[ParameterSpec, ...]) -> dict[str, ParameterSpec]:
    """:func:`merge_specs` of the model's parameters and ``extra``, made once per set of
    declarations (a sweep builds one :class:`Parameters` per point); callers copy it."""
    return merge_specs(MODEL_PARAMETERS.values(), extra)


def merge_specs(*groups: Iterable[ParameterSpec]) -> dict[str, ParameterSpec]:
    """Union of parameter declarations; one name declared two different ways is an error."""
    merged: dict[str, ParameterSpec] = {}
    for spec in itertools.chain(*groups):
        if spec.name in merged and merged[spec.name] != spec:
            raise ConfigError(
                f"parameter {spec.name!r} is declared twice, differently: "
                f"{merged[spec.name]} and {spec}"
            )
        merged[spec.name] = spec
    return merged


#: Prefix of the attributes that repeat each parameter on its own.
PARAMETER_ATTR_PREFIX = "parameter_"


def parameter_attrs(values: Mapping[str, Any]) -> dict[str, Any]:
    """Each parameter as its own file attribute ``parameter_<name>``: a number, a text, or
    the list of a swept parameter's values (booleans as 0/1; unset values left out)."""
    out: dict[str, Any] = {}
    for name, value in values.items():
        if value is None:
            continue
        if isinstance(value, list | tuple):
            value = [int(v) if isinstance(v, bool) else v for v in value]
            if not all(isinstance(v, int | float) for v in value):
                value = json.dumps(value)
        elif isinstance(value, bool):
            value = int(value)
        out[f"{PARAMETER_ATTR_PREFIX}{name}"] = value
    return out


def expand_sweep(
    values: Mapping[str, Any], extra_specs: Sequence[ParameterSpec] = ()
) -> list[tuple[dict[str, Value], Parameters]]:
    """Expand list-valued parameters into the grid of parameter points they span.

    Parameters
    ----------
    values : mapping
        Parameter values; a list or tuple value is a swept parameter.

    Returns
    -------
    list of (swept, Parameters)
        One entry per grid point, in row-major order of the swept names as given; ``swept``
        maps each swept name to its value at that point.
    """
    swept = {k: list(v) for k, v in values.items() if isinstance(v, list | tuple)}
    for name, options in swept.items():
        if not options:
            raise ConfigError(f"parameter {name!r} is swept over an empty list")
        spec = merge_specs(MODEL_PARAMETERS.values(), extra_specs).get(name)
        seen: set[Any] = set()
        twice = None
        for value in options:
            value = spec.coerce(value) if spec is not None else value
            key = json.dumps(value, sort_keys=True) if isinstance(value, list | dict) else value
            if key in seen:
                twice = value
                break
            seen.add(key)
        if twice is not None:
            raise ConfigError(
                f"parameter {name!r} is swept over {options} with {twice} twice: each value "
                "is one parameter point (for more samples of a point, add realizations)"
            )
    fixed = {k: v for k, v in values.items() if k not in swept}
    points = []
    for combo in itertools.product(*swept.values()):
        point = dict(zip(swept, combo, strict=True))
        params = Parameters({**fixed, **point}, extra_specs)
        points.append(({k: params[k] for k in point}, params))
    return points
