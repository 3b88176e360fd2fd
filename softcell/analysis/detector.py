"""Which stop/go detector an analysis runs, and with which parameter values.

An analysis is asked for by options (``softcell analyze`` flags, an ``[analysis]`` TOML table,
or a mapping): the analysis options of :data:`~softcell.analysis.options.ANALYSIS_OPTIONS`
and the parameters of the registered detectors (``--hmm-stop-speed 0.04``). The detector is
the one named by the ``detector`` option, else the one the input was simulated with (its
``[components] stopgo_detector``), else ``threshold``. Each of its parameters takes, in this
order: the value asked for; the value the input file stores for it, when the input was made
with that detector; for a tracked video and the ``threshold`` detector, the experiments'
0.3 cm/s; the parameter's default. The detector's own ``check()`` then judges the set.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from softcell.analysis import stopgo
from softcell.analysis.options import ANALYSIS_OPTIONS
from softcell.components.contracts import StopGoDetector
from softcell.components.registry import Registry
from softcell.errors import ConfigError, ParameterError, SoftcellError
from softcell.model.parameters import Parameters, suggest

KIND = "stopgo_detector"


@dataclass(frozen=True)
class DetectorChoice:
    """The detector an analysis runs.

    Attributes
    ----------
    name : str
        The detector's registered name.
    component : type of StopGoDetector
        Its class.
    values : dict
        Every parameter of the detector as it runs, each in its declared unit.
    """

    name: str
    component: type[StopGoDetector]
    values: dict[str, Any]

    def build(self, **changes: Any) -> StopGoDetector:
        """The detector with ``values`` (updated by ``changes``), validated by its ranges and
        its ``check()`` (:class:`~softcell.errors.ParameterError` for a refused set)."""
        try:
            return self.component(Parameters({**self.values, **changes}, self.component.parameters))
        except ParameterError as exc:
            raise ConfigError(
                f"stop/go detector {self.name!r} refuses its parameters: {exc}"
            ) from None

    def units(self) -> dict[str, str]:
        """The unit of each of :attr:`values`."""
        return {s.name: s.unit for s in self.component.parameters}


def detector_parameters(registry: Registry) -> dict[str, str]:
    """Every parameter a registered detector declares, beyond the analysis options, by name,
    with the first detector declaring it (``"stop/go detector 'hmm'"``)."""
    owners: dict[str, str] = {}
    for entry in registry.entries(KIND):
        for spec in entry.component.parameters:
            if spec.name not in ANALYSIS_OPTIONS:
                owners.setdefault(spec.name, f"stop/go detector {entry.component.name!r}")
    return owners


def split_options(
    values: Mapping[str, Any] | None, registry: Registry
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Split requested options into analysis options and detector parameters.

    Raises
    ------
    ConfigError
        For a name that is neither (with a suggestion).
    """
    owners = detector_parameters(registry)
    analysis, detector = {}, {}
    for name, value in (values or {}).items():
        if value is None:
            continue
        if name in ANALYSIS_OPTIONS:
            analysis[name] = value
        elif name in owners:
            detector[name] = value
        else:
            known = [*ANALYSIS_OPTIONS, *owners]
            raise ConfigError(f"unknown analysis option {name!r}{suggest(name, known)}")
    return analysis, detector


def _input_detector(attrs: Mapping[str, Any]) -> str | None:
    components = json.loads(attrs.get("softcell_components", "{}") or "{}")
    name = components.get(KIND) if isinstance(components, dict) else None
    return name if isinstance(name, str) else None


def choose_detector(
    attrs: Mapping[str, Any],
    options: Mapping[str, Any],
    given: Mapping[str, Any],
    registry: Registry,
) -> DetectorChoice:
    """The detector and its parameter values for an input with global attributes ``attrs``.

    Parameters
    ----------
    attrs : mapping
        The input's global attributes (``softcell_components``, ``softcell_parameters``,
        ``softcell_swept_parameters``, ``softcell_origin``).
    options : mapping
        Validated analysis options; ``detector`` may be None (the input's, else threshold)
        and ``threshold`` (cm/s) None (not asked for).
    given : mapping
        Detector parameters asked for, by name, in their declared units.
    registry : Registry
        Where the detector is looked up.

    Raises
    ------
    ConfigError
        For a parameter of another detector, or an input detector that is not installed.
    SoftcellError
        For a threshold asked of a detector without one.
    ParameterError
        For a value the detector refuses (its ranges or its ``check()``).
    """
    stored_name = _input_detector(attrs)
    name = options.get("detector") or stored_name or "threshold"
    if options.get("detector") is None and stored_name is not None:
        if stored_name not in registry.names(KIND):
            raise ConfigError(
                f"the input was made with stop/go detector {stored_name!r}, which is not "
                "installed; choose one with --detector"
            )
    cls = registry.get(KIND, name)
    declared = {s.name for s in cls.parameters}
    owners = detector_parameters(registry)
    for param in given:
        if param not in declared:
            raise ConfigError(
                f"parameter {param!r} belongs to {owners.get(param, 'another detector')}, "
                f"which this analysis does not use (detector {name!r})"
            )
    asked = dict(given)
    if options.get("threshold") is not None:
        if "threshold" not in declared:
            raise SoftcellError(f"stop/go detector {name!r} has no parameter 'threshold'")
        asked["threshold"] = options["threshold"]
    values = _stored_values(attrs, cls, name == stored_name)
    if "threshold" in declared and attrs.get("softcell_origin") == "tracking":
        values["threshold"] = stopgo.EXPERIMENT_THRESHOLD
    values.update(asked)
    choice = DetectorChoice(name, cls, {})
    detector = choice.build(**values)  # ranges and check(): refused here, before computing
    return DetectorChoice(name, cls, {s.name: detector.params[s.name] for s in cls.parameters})


def _stored_values(
    attrs: Mapping[str, Any], cls: type[StopGoDetector], same_detector: bool
) -> dict[str, Any]:
    """The detector's parameter values the input file stores, when it was made with it (a
    parameter swept in the input is not taken: one analysis runs one detector)."""
    if not same_detector:
        return {}
    stored = json.loads(attrs.get("softcell_parameters", "{}") or "{}")
    swept = set(str(attrs.get("softcell_swept_parameters", "")).split())
    return {
        s.name: stored[s.name] for s in cls.parameters if s.name in stored and s.name not in swept
    }
