"""Run configuration: parameter values (possibly swept) and the chosen components.

A configuration file has up to three tables::

    [parameters]            # any parameter; a list sweeps it
    radius = [4, 8, 12]
    bending_stiffness = 0.57

    [components]            # chosen by name from the plugin registry
    energy_terms = ["bending", "tension", "contact"]
    driving_protocol = "run_and_tumble"
    friction_law = "viscous"
    integrator = "rodas4"
    stopgo_detector = "threshold"

    [run]
    seed = 1
    realizations = 25

    [analysis]              # softcell analyze --config: analysis options and the
    detector = "threshold"  # detector's parameters (softcell analyze --help lists them)
    threshold = 0.05

Values are in the units of the parameter table (``softcell params`` prints it).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from softcell.core.params import suggest
from softcell.errors import ConfigError

if TYPE_CHECKING:
    from softcell.core.components.registry import Registry

DEFAULT_COMPONENTS: dict[str, Any] = {
    "energy_terms": ["bending", "tension", "contact"],
    "driving_protocol": "run_and_tumble",
    "friction_law": "viscous",
    "integrator": "rodas4",
    "stopgo_detector": "threshold",
}
RUN_KEYS: dict[str, type] = {"seed": int, "realizations": int}
SECTIONS = ("parameters", "components", "run", "analysis")


@dataclass(frozen=True)
class RunConfig:
    """Parameter values (a list value is a sweep), component names by kind (a kind not named
    takes its default, ``DEFAULT_COMPONENTS``), run settings, and analysis options
    (validated by the analysis).

    Attributes
    ----------
    parameters : dict
        Parameter values by name, in the units of ``softcell params`` (cm, s, rad, N); a list
        of values sweeps that parameter.
    components : dict
        Component names by kind: ``energy_terms`` (a list), ``driving_protocol``,
        ``friction_law``, ``integrator``, ``stopgo_detector``.
    run : dict
        Run settings (the ``[run]`` table of a configuration file): ``seed``,
        ``realizations``, ...
    analysis : dict
        Analysis options and the detector's parameters (``softcell analyze --help``).
    """

    parameters: dict[str, Any] = field(default_factory=dict)
    components: dict[str, Any] = field(default_factory=lambda: dict(DEFAULT_COMPONENTS))
    run: dict[str, Any] = field(default_factory=dict)
    analysis: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # A kind not named takes its default: RunConfig(components={"integrator": "x"}).
        object.__setattr__(self, "components", {**DEFAULT_COMPONENTS, **self.components})

    def updated(
        self,
        parameters: Mapping[str, Any] = (),
        components: Mapping[str, Any] = (),
        run: Mapping[str, Any] = (),
    ) -> RunConfig:
        """A copy with some entries replaced (command-line flags over a file).

        Parameters
        ----------
        parameters : mapping
            Parameter values by name, in the units of ``softcell params``.
        components : mapping
            Component names by kind.
        run : mapping
            Run settings.
        """
        return dataclasses.replace(
            self,
            parameters={**self.parameters, **dict(parameters)},
            components={**self.components, **dict(components)},
            run={**self.run, **dict(run)},
        )

    def check_components(self, registry: Registry) -> None:
        """Raise :class:`ConfigError` unless every component named exists in ``registry``
        (with a suggestion for a misspelt one) and no energy term is named twice.

        Parameters
        ----------
        registry : Registry
            Where the components are looked up.
        """
        terms = self.components.get("energy_terms", [])
        if isinstance(terms, str) or not isinstance(terms, list | tuple):
            raise ConfigError(f"energy_terms = {terms!r} is not allowed: must be a list of names")
        for name in terms:
            if list(terms).count(name) > 1:
                raise ConfigError(
                    f"energy term {name!r} is named twice in energy_terms = "
                    f"{list(terms)}: each term counts once"
                )
            registry.get("energy_term", name)
        for kind in ("driving_protocol", "friction_law", "integrator", "stopgo_detector"):
            name = self.components.get(kind)
            if not isinstance(name, str):
                raise ConfigError(f"{kind} = {name!r} is not allowed: must be a name")
            registry.get(kind, name)


def config_from_mapping(data: dict[str, Any], source: object = "configuration") -> RunConfig:
    """A run configuration from the tables of a TOML document (``source`` names it in errors).

    Raises
    ------
    ConfigError
        For an unknown table or key (with a suggestion), or a value of the wrong type.
        Parameter values are validated later, by :class:`Parameters`.
    """
    for section, value in data.items():
        if section not in SECTIONS:
            raise ConfigError(
                f"{source}: unknown table [{section}]{suggest(section, SECTIONS)}; "
                f"tables: {', '.join(SECTIONS)}"
            )
        if not isinstance(value, dict):
            raise ConfigError(f"{source}: {section} must be a table, [{section}]")
    components = dict(data.get("components", {}))
    for kind in components:
        if kind not in DEFAULT_COMPONENTS:
            raise ConfigError(
                f"{source}: unknown component kind {kind!r}{suggest(kind, DEFAULT_COMPONENTS)}"
            )
    run = dict(data.get("run", {}))
    for key, value in run.items():
        if key not in RUN_KEYS:
            raise ConfigError(f"{source}: unknown [run] key {key!r}{suggest(key, RUN_KEYS)}")
        if not isinstance(value, RUN_KEYS[key]) or isinstance(value, bool):
            raise ConfigError(f"{source}: [run] {key} = {value!r} must be an integer")
    return RunConfig(
        parameters=dict(data.get("parameters", {})),
        components={**DEFAULT_COMPONENTS, **components},
        run=run,
        analysis=dict(data.get("analysis", {})),
    )
