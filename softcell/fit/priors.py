"""The unknowns of a fit: a model or component parameter with a prior range.

A prior is uniform on [low, high] in the parameter's unit, or log-uniform (uniform in
log(value)) when the range spans more than a decade or when asked. ``--prior NAME=LOW:HIGH``
gives one on the command line, in the parameter's unit (``softcell params``), or
``NAME=LOW:HIGH UNIT`` in another unit of the same dimension (converted by UDUNITS-2);
a configuration file gives them as a ``[priors]`` table (``NAME = {low = .., high = ..,
unit = "..", scale = "log"}``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from softcell.errors import ConfigError
from softcell.model.parameters import ParameterSpec, suggest

SCALES = ("linear", "log")


@dataclass(frozen=True)
class Prior:
    """A uniform or log-uniform prior over one parameter.

    Attributes
    ----------
    name : str
        The parameter (any model or component parameter of the run).
    low, high : float
        The range, in ``unit``; low < high, both allowed values of the parameter.
    unit : str
        The parameter's unit (UDUNITS-2), as ``softcell params`` prints it.
    scale : str
        ``linear`` (uniform in the value) or ``log`` (uniform in its logarithm).
    """

    name: str
    low: float
    high: float
    unit: str
    scale: str

    def value(self, u: np.ndarray) -> np.ndarray:
        """The parameter's values (``unit``) at quantiles ``u`` in [0, 1] of the prior."""
        u = np.asarray(u, dtype=np.float64)
        if self.scale == "log":
            return np.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        return self.low + u * (self.high - self.low)

    def quantile(self, value: np.ndarray) -> np.ndarray:
        """The prior quantile (in [0, 1]) of ``value`` (``unit``): :meth:`value`'s inverse."""
        v = np.asarray(value, dtype=np.float64)
        if self.scale == "log":
            return (np.log(v) - math.log(self.low)) / (math.log(self.high) - math.log(self.low))
        return (v - self.low) / (self.high - self.low)

    def log_density(self, value: np.ndarray) -> np.ndarray:
        """The prior's log density at ``value`` (per ``unit``; -inf outside the range)."""
        v = np.asarray(value, dtype=np.float64)
        inside = (v >= self.low) & (v <= self.high)
        if self.scale == "log":
            density = -np.log(np.where(inside, v, 1.0)) - math.log(math.log(self.high / self.low))
        else:
            density = np.full(v.shape, -math.log(self.high - self.low))
        return np.where(inside, density, -np.inf)


def parse_prior(text: str, specs: Mapping[str, ParameterSpec], scale: str | None = None) -> Prior:
    """A prior from ``NAME=LOW:HIGH`` or ``NAME=LOW:HIGH UNIT``.

    Parameters
    ----------
    text : str
        The flag's value.
    specs : mapping
        The parameters of the run, by name (their units and allowed ranges).
    scale : str, optional
        ``linear`` or ``log``; default: ``log`` when high / low > 10, else ``linear``.

    Raises
    ------
    ConfigError
        Naming the bad part: not ``NAME=LOW:HIGH``, an unknown parameter (with a
        suggestion), a unit that does not parse or is not the parameter's dimension, an
        empty range, or a bound the parameter does not allow.
    """
    name, sep, rest = text.partition("=")
    words = rest.split(maxsplit=1)
    bounds = words[0].split(":") if words else []
    if not sep or len(bounds) != 2:
        raise ConfigError(f"--prior {text!r} is not allowed: must be NAME=LOW:HIGH [UNIT]")
    try:
        low, high = (float(b) for b in bounds)
    except ValueError:
        raise ConfigError(f"--prior {text!r}: {rest!r} holds no two numbers LOW:HIGH") from None
    unit = words[1].strip() if len(words) > 1 else None
    return make_prior(name.strip(), low, high, specs, unit=unit, scale=scale)


def make_prior(
    name: str,
    low: float,
    high: float,
    specs: Mapping[str, ParameterSpec],
    unit: str | None = None,
    scale: str | None = None,
) -> Prior:
    """A prior over ``name`` from ``low`` to ``high`` (in ``unit``, default the
    parameter's), checked against the parameter's declaration (see :func:`parse_prior`)."""
    spec = specs.get(name)
    if spec is None:
        raise ConfigError(f"prior on {name!r}: no such parameter in this run{suggest(name, specs)}")
    if spec.kind is not float:
        raise ConfigError(f"prior on {name!r}: a fit varies real parameters; {name} is not one")
    if unit is not None and unit != spec.unit:
        low, high = _converted(name, (low, high), unit, spec.unit)
    _check_range(spec, low, high)
    if scale is None:
        scale = "log" if low > 0 and high / low > 10 else "linear"
    if scale not in SCALES:
        raise ConfigError(f"prior on {name!r}: scale {scale!r} must be one of {', '.join(SCALES)}")
    if scale == "log" and low <= 0:
        raise ConfigError(
            f"prior on {name!r}: a log-uniform prior needs LOW > 0, not {low:g} {spec.unit}"
        )
    return Prior(name, float(low), float(high), spec.unit, scale)


def _check_range(spec: ParameterSpec, low: float, high: float) -> None:
    """Refuse an empty range, or a bound the parameter does not allow."""
    name = spec.name
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ConfigError(
            f"prior on {name!r}: the range {low:g}:{high:g} {spec.unit} is empty; give LOW < HIGH"
        )
    for bound in (low, high):
        try:
            spec.check(bound)
        except Exception as exc:  # ParameterError, with the allowed range
            raise ConfigError(f"prior on {name!r}: {exc}") from None


def _converted(name: str, values: tuple[float, float], unit: str, to: str) -> tuple[float, float]:
    """``values`` from ``unit`` to ``to`` (UDUNITS-2)."""
    import cf_units

    try:
        given = cf_units.Unit(unit)
    except ValueError:
        raise ConfigError(f"prior on {name!r}: unit {unit!r} does not parse as UDUNITS-2") from None
    if not given.is_convertible(cf_units.Unit(to)):
        raise ConfigError(f"prior on {name!r}: unit {unit!r} is not convertible to {to!r}")
    low, high = (float(given.convert(v, cf_units.Unit(to))) for v in values)
    return low, high


def priors_from_table(table: Mapping[str, Any], specs: Mapping[str, ParameterSpec]) -> list[Prior]:
    """The priors of a ``[priors]`` table: ``NAME = {low, high, unit?, scale?}``.

    Raises
    ------
    ConfigError
        For an entry that is not such a table, or a prior :func:`make_prior` refuses.
    """
    priors = []
    for name, entry in table.items():
        keys = set(entry) if isinstance(entry, Mapping) else set()
        if not {"low", "high"} <= keys or keys - {"low", "high", "unit", "scale"}:
            raise ConfigError(
                f"[priors] {name} = {entry!r}: must be a table {{low, high, unit?, scale?}}"
            )
        priors.append(
            make_prior(
                name,
                float(entry["low"]),
                float(entry["high"]),
                specs,
                unit=entry.get("unit"),
                scale=entry.get("scale"),
            )
        )
    return priors


def resolve_priors(
    priors: Sequence[str | Prior],
    table: Mapping[str, Any] | None,
    components: Mapping[str, Any],
) -> list[Prior]:
    """The unknowns of a run of ``components``: ``--prior`` texts (or Priors) and a
    ``[priors]`` table, each checked against the parameters those components declare.

    Raises
    ------
    ConfigError
        For a prior :func:`parse_prior` or :func:`priors_from_table` refuses, or an unknown
        given twice.
    """
    from softcell.components.registry import default_registry
    from softcell.model.parameters import MODEL_PARAMETERS

    specs = {**MODEL_PARAMETERS, **default_registry().parameter_specs(components)}
    found = [p if isinstance(p, Prior) else parse_prior(p, specs) for p in priors]
    found += priors_from_table(table or {}, specs)
    names = [p.name for p in found]
    for name in names:
        if names.count(name) > 1:
            raise ConfigError(f"the prior of {name} is given {names.count(name)} times: give one")
    return found
