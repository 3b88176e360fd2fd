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

    [[obstacles]]           # a fixed post (cm); the energy term "obstacles" joins the terms
    x = 12
    y = 0
    radius = 2

    [[obstacles]]           # a straight wall from (x0, y0) to (x1, y1) (cm)
    x0 = -20
    y0 = -8
    x1 = 20
    y1 = -8

    [assembly]              # many cells: how many, in what box (cm), placed how
    cells = 16
    box = 60
    boundary = "periodic"   # or "walls"; no box: the open plane
    placement = "lattice"   # or "random", at least gap (cm) apart

Values are in the units of the parameter table (``softcell params`` prints it).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from softcell.errors import ConfigError, ParameterError
from softcell.model.obstacle_layout import from_table, obstacle_text
from softcell.model.parameters import suggest


class Lookup(Protocol):
    """What :meth:`RunConfig.check_components` asks of a registry
    (:class:`softcell.components.registry.Registry` is one): the component of a kind and a
    name, or a :class:`ConfigError` naming what is available."""

    def get(self, kind: str, name: str) -> object: ...


DEFAULT_COMPONENTS: dict[str, Any] = {
    "energy_terms": ["bending", "tension", "contact"],
    "driving_protocol": "run_and_tumble",
    "friction_law": "viscous",
    "integrator": "rodas4",
    "stopgo_detector": "threshold",
}
RUN_KEYS: dict[str, type] = {"seed": int, "realizations": int}
SECTIONS = ("parameters", "components", "run", "analysis", "obstacles", "assembly", "bots")


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
    assembly : dict
        Many cells (the ``[assembly]`` table: ``cells``, ``box`` in cm, ``boundary``,
        ``placement``, ``gap`` in cm; see :class:`~softcell.model.assembly.Assembly`); empty
        for one cell.
    bots : dict
        Several bots in one ring (the ``[bots]`` table: ``count``, ``placement``, ``gap`` in
        cm, ``interactions``; see :class:`~softcell.model.bots.Bots`); empty, or a count of
        1, for one bot.
    """

    parameters: dict[str, Any] = field(default_factory=dict)
    components: dict[str, Any] = field(default_factory=lambda: dict(DEFAULT_COMPONENTS))
    run: dict[str, Any] = field(default_factory=dict)
    analysis: dict[str, Any] = field(default_factory=dict)
    assembly: dict[str, Any] = field(default_factory=dict)
    bots: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # A kind not named takes its default: RunConfig(components={"integrator": "x"}).
        object.__setattr__(self, "components", {**DEFAULT_COMPONENTS, **self.components})

    def updated(
        self,
        parameters: Mapping[str, Any] = (),
        components: Mapping[str, Any] = (),
        run: Mapping[str, Any] = (),
        assembly: Mapping[str, Any] = (),
        bots: Mapping[str, Any] = (),
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
        assembly : mapping
            Settings of an assembly of cells (``cells``, ``box``, ...).
        bots : mapping
            Settings of several bots in one ring (``count``, ``placement``, ...).
        """
        return dataclasses.replace(
            self,
            parameters={**self.parameters, **dict(parameters)},
            components={**self.components, **dict(components)},
            run={**self.run, **dict(run)},
            assembly={**self.assembly, **dict(assembly)},
            bots={**self.bots, **dict(bots)},
        )

    def check_components(self, registry: Lookup) -> None:
        """Raise :class:`ConfigError` unless every component named exists in ``registry``
        (with a suggestion for a misspelt one) and no energy term is named twice.

        Parameters
        ----------
        registry : Lookup
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
        if section != "obstacles" and not isinstance(value, dict):
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
    parameters = dict(data.get("parameters", {}))
    if "obstacles" in data:
        parameters["obstacles"] = _obstacle_tables(data, source)
    return with_obstacle_term(
        RunConfig(
            parameters=parameters,
            components={**DEFAULT_COMPONENTS, **components},
            run=run,
            analysis=dict(data.get("analysis", {})),
            assembly=dict(data.get("assembly", {})),
            bots=dict(data.get("bots", {})),
        )
    )


def _obstacle_tables(data: dict[str, Any], source: object) -> str:
    """The parameter ``obstacles`` from a document's ``[[obstacles]]`` tables."""
    tables = data["obstacles"]
    if not (isinstance(tables, list) and all(isinstance(v, dict) for v in tables)):
        raise ConfigError(
            f"{source}: obstacles must be tables, [[obstacles]] (x, y, radius for a post; "
            "x0, y0, x1, y1, width for a wall; cm)"
        )
    if "obstacles" in data.get("parameters", {}):
        raise ConfigError(
            f"{source}: obstacles are given twice, as [[obstacles]] tables and as the "
            "parameter obstacles: keep one"
        )
    try:
        return obstacle_text(from_table(t) for t in tables)
    except ParameterError as exc:
        raise ConfigError(f"{source}: {exc}") from None


def with_obstacle_term(config: RunConfig) -> RunConfig:
    """``config`` with the energy term ``obstacles`` among its terms when it places
    obstacles (the parameter ``obstacles`` is set and not empty) and the term is not named."""
    terms = config.components.get("energy_terms")
    if not config.parameters.get("obstacles") or not isinstance(terms, list | tuple):
        return config
    return config.updated(components={"energy_terms": terms_with_obstacles(terms)})


def terms_with_obstacles(terms: list[str] | tuple[str, ...]) -> list[str]:
    """The energy terms ``terms`` with ``obstacles`` added last unless already named."""
    return list(terms) if "obstacles" in terms else [*terms, "obstacles"]


def assembly_of(config: RunConfig):
    """The :class:`~softcell.model.assembly.Assembly` ``config`` asks for, None for one cell
    (no ``[assembly]`` settings)."""
    from softcell.model.assembly import Assembly

    return Assembly.from_mapping(dict(config.assembly)) if config.assembly else None


def bots_of(config: RunConfig):
    """The :class:`~softcell.model.bots.Bots` ``config`` asks for, None for one bot (no
    ``[bots]`` settings, or a count of 1: the single-bot run, to the bit)."""
    from softcell.model.bots import Bots

    if not config.bots:
        return None
    bots = Bots.from_mapping(dict(config.bots))
    return bots if bots.count > 1 else None


#: The membrane record of an assembly of more than one cell, unless the request sets
#: ``sample_switch``: thinned to ``sample_every_late`` (0.1 s by default) from the start. The
#: bodies' fine record (every ``sample_every``) is kept whole: the stop/go phases, speeds and
#: MSDs read it; the membrane's uses (the shape index, the crowd's clusters, pair correlation
#: and Voronoi cells, every ``crowd_every`` >= 0.1 s) need no more. A 9-cell realization of
#: 120 s drops from 94 MB to 11 MB of membrane samples (before compression).
ASSEMBLY_SAMPLING = {"sample_switch": 0.0}


def with_assembly_defaults(config: RunConfig) -> RunConfig:
    """``config`` with what an assembly changes: for more than one cell, the thinned membrane
    record (:data:`ASSEMBLY_SAMPLING`, where the request does not set ``sample_switch``); for
    boundary ``walls``, the arena's walls as the box (the energy term ``arena`` joins the
    terms and its side ``arena_side`` is the box's).

    Raises
    ------
    ConfigError
        When ``arena_side`` is set to another side than the box's.
    """
    assembly = assembly_of(config)
    if assembly is None:
        return config
    if assembly.cells > 1:
        config = config.updated(
            parameters={k: v for k, v in ASSEMBLY_SAMPLING.items() if k not in config.parameters}
        )
    if assembly.boundary != "walls":
        return config
    side = config.parameters.get("arena_side")
    if side is not None and float(side) != assembly.box:
        raise ConfigError(
            f"arena_side = {side} cm and the assembly's box = {assembly.box:g} cm differ: "
            "a walled box is the arena; set one of them"
        )
    terms = list(config.components.get("energy_terms", []))
    if "arena" not in terms:
        terms.append("arena")
    return config.updated(
        parameters={"arena_side": assembly.box}, components={"energy_terms": terms}
    )
