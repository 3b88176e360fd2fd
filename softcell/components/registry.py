"""The plugin registry: built-in components and entry-point plugins through one set of hooks.

The registry registers the built-in plugin modules (:data:`BUILTIN_PLUGINS`), then every
entry point of the group ``softcell``, through pluggy, and collects the component classes their
hooks return. A plugin that fails to import or to register is reported with a
:class:`PluginWarning` naming its distribution and the error, and skipped. Two components of
one kind with one name are an error naming both origins. ``SOFTCELL_DISABLE_PLUGINS=a,b``
blocks plugins by name: an entry-point name, a distribution name (as the skip warning shows
it), or the short name of a built-in; a name that matches nothing is warned about.
"""

from __future__ import annotations

import functools
import importlib
import importlib.metadata
import os
import re
import warnings
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import pluggy

from softcell.components import hookspecs
from softcell.components.contracts import CONTRACTS, Component, kind_name
from softcell.errors import ConfigError, PluginWarning, RegistryError
from softcell.model.parameters import (
    MODEL_PARAMETERS,
    Parameters,
    ParameterSpec,
    merge_specs,
    suggest,
)

ENTRY_POINT_GROUP = "softcell"
DISABLE_ENV = "SOFTCELL_DISABLE_PLUGINS"

#: Built-in plugin modules, registered through the same hooks as third-party plugins.
BUILTIN_PLUGINS: tuple[str, ...] = (
    # The one place core names a module of the plugins layer above it; the layer test reads
    # this tuple and allows exactly these imports.
    "softcell.builtins.bending",
    "softcell.builtins.tension",
    "softcell.builtins.contact",
    "softcell.builtins.arena",
    "softcell.builtins.obstacles",
    "softcell.builtins.run_and_tumble",
    "softcell.builtins.constant_push",
    "softcell.builtins.protocols",
    "softcell.builtins.friction_laws",
    "softcell.integrators.explicit_euler",
    "softcell.integrators.rodas4",
    "softcell.builtins.threshold",
    "softcell.builtins.repulsion",
    "softcell.builtins.bot_repulsion",
    "softcell.builtins.alignment",
)

#: Kind name of each hook, in the order ``softcell plugins`` prints them.
__all__ = ["KINDS", "PluginWarning", "Registered", "Registry", "default_registry", "registered"]

KINDS: dict[str, str] = {hook: contract.kind for hook, contract in CONTRACTS.items()}


@dataclass(frozen=True)
class Registered:
    """A component class and where it came from (built-in module or distribution)."""

    component: type[Component]
    origin: str
    plugin: str


class Registry:
    """All components, by kind and name.

    Parameters
    ----------
    entry_points : iterable of importlib.metadata.EntryPoint, optional
        Entry points to load; by default those installed in the group ``softcell``.
    disabled : iterable of str, optional
        Plugin names to block; by default from the environment variable
        ``SOFTCELL_DISABLE_PLUGINS`` (comma-separated).
    extra_plugins : iterable of (name, object), optional
        Plugin modules or objects to register directly, after the built-ins (tests use this).
    builtins : tuple of str
        Built-in plugin modules to register.

    Raises
    ------
    RegistryError
        When two components of one kind share a name.
    """

    def __init__(
        self,
        entry_points: Iterable[importlib.metadata.EntryPoint] | None = None,
        disabled: Iterable[str] | None = None,
        extra_plugins: Iterable[tuple[str, object]] = (),
        builtins: tuple[str, ...] = BUILTIN_PLUGINS,
    ) -> None:
        if disabled is None:
            disabled = [s.strip() for s in os.environ.get(DISABLE_ENV, "").split(",")]
        self.disabled = frozenset(d for d in disabled if d)
        self._blocked: set[str] = set()  # the entries of ``disabled`` that matched a plugin
        self.skipped: list[tuple[str, str]] = []  # (plugin, reason)
        self.skipped_origins: dict[str, str] = {}
        self.pm = pluggy.PluginManager(ENTRY_POINT_GROUP)
        self.pm.add_hookspecs(hookspecs)
        self._origins: dict[str, str] = {}

        self._register_all(builtins, extra_plugins, entry_points)
        self._warn_unmatched()
        self.pm.check_pending()
        self._components = self._collect()

    def _register_all(
        self,
        builtins: tuple[str, ...],
        extra_plugins: Iterable[tuple[str, object]],
        entry_points: Iterable[importlib.metadata.EntryPoint] | None,
    ) -> None:
        """Register the built-ins, then the objects given, then the entry points, skipping
        the blocked ones."""
        for module_name in builtins:
            short = module_name.rsplit(".", 1)[-1]
            if not self._is_disabled(short, module_name):
                self._register(
                    short, importlib.import_module(module_name), f"built-in ({module_name})"
                )
        for name, plugin in extra_plugins:
            if not self._is_disabled(name):
                self._register(name, plugin, f"registered object {name!r}")
        if entry_points is None:
            entry_points = importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)
        for ep in entry_points:
            dist = getattr(ep, "dist", None)
            if not self._is_disabled(ep.name, dist.name if dist else None):
                self._load_entry_point(ep)

    def _warn_unmatched(self) -> None:
        unmatched = sorted(d for d in self.disabled if _normal(d) not in self._blocked)
        if unmatched:
            warnings.warn(
                f"{DISABLE_ENV} names {', '.join(map(repr, unmatched))}, which "
                "match no plugin (give an entry-point name, a distribution name or "
                "a built-in's name, as `softcell plugins` shows them)",
                PluginWarning,
                stacklevel=3,
            )

    def _is_disabled(self, *names: str | None) -> bool:
        """Whether any of a plugin's names (entry point, distribution, module) is blocked;
        distribution names compare as pip does (case, '-', '_' and '.' alike)."""
        wanted = {_normal(d) for d in self.disabled}
        hit = {_normal(n) for n in names if n} & wanted
        self._blocked |= hit
        return bool(hit)

    # -- loading ---------------------------------------------------------------------------

    def _register(self, name: str, plugin: object, origin: str) -> None:
        self.pm.register(plugin, name=name)
        self._origins[name] = origin

    def _skip(
        self, plugin: str, origin: str, error: BaseException | str, component: str = ""
    ) -> None:
        """Warn that ``plugin`` (or only its ``component``, when given) was skipped."""
        reason = error if isinstance(error, str) else f"{type(error).__name__}: {error}"
        what = f"{component} of softcell plugin" if component else "softcell plugin"
        self.skipped.append((f"{plugin}: {component}" if component else plugin, reason))
        self.skipped_origins[self.skipped[-1][0]] = origin
        warnings.warn(
            f"{what} {plugin!r} from {origin} was skipped: {reason}",
            PluginWarning,
            stacklevel=3,
        )

    def _load_entry_point(self, ep: importlib.metadata.EntryPoint) -> None:
        dist = getattr(ep, "dist", None)
        distname = f"distribution {dist.name} {dist.version}" if dist else "an unknown distribution"
        origin = f"{distname} (entry point {ep.name} = {ep.value})"
        try:
            plugin = ep.load()
            if self.pm.is_registered(plugin):  # also given to registered() (a test)
                return
            self._register(ep.name, plugin, origin)
            self.pm.check_pending()  # a misspelt hook name is an error, not a silent no-op
        except Exception as exc:  # a broken plugin must not take softcell down
            if self.pm.has_plugin(ep.name):
                self.pm.unregister(name=ep.name)
            self._skip(ep.name, origin, exc)

    def _plugin_components(self, plugin: object) -> dict[str, list[type[Component]]]:
        """The components ``plugin`` returns from each hook, called through pluggy's hook
        relay of a manager holding this plugin alone (so that each component keeps its
        origin and a broken plugin is skipped alone)."""
        found: dict[str, list[type[Component]]] = {}
        alone = pluggy.PluginManager(ENTRY_POINT_GROUP)
        alone.add_hookspecs(hookspecs)
        alone.register(plugin)
        for hook_name, contract in CONTRACTS.items():
            hook = getattr(alone.hook, hook_name)
            results = hook()
            if len(results) < len(hook.get_hookimpls()):  # pluggy drops the results None
                raise TypeError(f"{hook_name} returned NoneType, not a list")
            for result in results:
                if not isinstance(result, list | tuple):
                    raise TypeError(f"{hook_name} returned {type(result).__name__}, not a list")
                for cls in result:
                    if not (isinstance(cls, type) and issubclass(cls, contract)):
                        raise TypeError(
                            f"{hook_name} returned {cls!r}, not a subclass of {contract.__name__}"
                        )
                found.setdefault(contract.kind, []).extend(result)
        return found

    def _collect(self) -> dict[str, dict[str, Registered]]:
        components: dict[str, dict[str, Registered]] = {k: {} for k in KINDS.values()}
        for plugin_name, plugin in list(self.pm.list_name_plugin()):
            origin = self._origins.get(plugin_name, plugin_name)
            try:
                found = self._plugin_components(plugin)
            except Exception as exc:
                self.pm.unregister(plugin)
                self._skip(plugin_name, origin, exc)
                continue
            for kind, classes in found.items():
                for cls in classes:
                    problems = cls.contract_problems()
                    if problems:  # this component alone is skipped, loudly
                        self._skip(
                            plugin_name,
                            origin,
                            "; ".join(problems),
                            f"the {kind_name(kind)} {cls.__qualname__}",
                        )
                        continue
                    other = components[kind].get(cls.name)
                    if other is not None:
                        raise RegistryError(
                            f"two {kind} components are named {cls.name!r}: one from "
                            f"{other.origin}, one from {origin}; block one with "
                            f"{DISABLE_ENV}={plugin_name} or {DISABLE_ENV}={other.plugin}"
                        )
                    components[kind][cls.name] = Registered(cls, origin, plugin_name)
        return components

    # -- queries ---------------------------------------------------------------------------

    def names(self, kind: str) -> list[str]:
        """Names of the components of ``kind``, sorted."""
        return sorted(self._kind(kind))

    def entries(self, kind: str) -> list[Registered]:
        """Registered components of ``kind``, sorted by name."""
        table = self._kind(kind)
        return [table[n] for n in sorted(table)]

    def get(self, kind: str, name: str) -> type[Component]:
        """The component class of ``kind`` named ``name``.

        Raises
        ------
        ConfigError
            For an unknown name; the message lists the names that exist.
        """
        table = self._kind(kind)
        if name not in table:
            have = ", ".join(sorted(table)) or "none"
            raise ConfigError(f"no {kind} named {name!r}{suggest(name, table)}; available: {have}")
        return table[name].component

    def origin(self, kind: str, name: str) -> str:
        """Where the component of ``kind`` named ``name`` came from (a distribution and its
        entry point, or a built-in module)."""
        self.get(kind, name)
        return self._kind(kind)[name].origin

    def parameter_specs(
        self, components: Mapping[str, Any] | None = None
    ) -> dict[str, ParameterSpec]:
        """The parameters the components declare, by name.

        Parameters
        ----------
        components : mapping, optional
            Component names by kind, as in a run configuration (``energy_terms`` a list,
            the other kinds one name each): only these components' parameters. None: every
            registered component's.
        """
        return merge_specs(*(r.component.parameters for r in self.in_use(components)))

    def parameters(
        self, values: Mapping[str, Any] | None = None, components: Mapping[str, Any] | None = None
    ) -> Parameters:
        """A validated parameter point with the model's and the components' parameters.

        Parameters
        ----------
        values : mapping, optional
            Values that differ from the defaults, by name, each in its declared unit
            (``softcell params`` prints them).
        components : mapping, optional
            Component names by kind: the point then holds only these components'
            parameters (what a file stores, so that installing a plugin changes no request).
            None: every registered component's.

        Returns
        -------
        Parameters

        Raises
        ------
        ConfigError
            For a value of a parameter that only a component not in ``components`` declares
            (naming that component), or that no component declares.
        """
        check_in_use(values or {}, self, components)
        return Parameters(values, self.parameter_specs(components).values())

    def owner(self, parameter: str) -> str | None:
        """``"energy term 'posts'"``: the first registered component declaring ``parameter``
        beyond the model's own, or None."""
        for entry in self:
            if any(s.name == parameter for s in entry.component.parameters):
                return f"{kind_name(entry.component.kind)} {entry.component.name!r}"
        return None

    def in_use(self, components: Mapping[str, Any] | None) -> list[Registered]:
        """The registered components that ``components`` (names by kind, ``energy_terms``
        and ``pair_terms`` lists) names; None: every one."""
        if components is None:
            return list(self)
        return [r for r in self if chosen(r.component, components)]

    def __iter__(self) -> Iterator[Registered]:
        for kind in KINDS.values():
            yield from self.entries(kind)

    def _kind(self, kind: str) -> dict[str, Registered]:
        try:
            return self._components[kind]
        except KeyError:
            raise ConfigError(
                f"no component kind {kind!r}; kinds: " + ", ".join(KINDS.values())
            ) from None


def chosen(cls: type[Component], components: Mapping[str, Any]) -> bool:
    """Whether ``components`` (names by kind, ``energy_terms`` a list) names ``cls``; the
    pair terms are ``pair_terms``, or those of the ``assembly`` settings a file stores."""
    lists = {
        "energy_term": "energy_terms",
        "pair_term": "pair_terms",
        "bot_interaction": "bot_interactions",
    }
    names = components.get(lists.get(cls.kind, cls.kind))
    if names is None and cls.kind == "pair_term":
        names = (components.get("assembly") or {}).get("pair_terms")
    if names is None and cls.kind == "bot_interaction":
        names = (components.get("bots") or {}).get("interactions")
    return cls.name in names if isinstance(names, list | tuple) else cls.name == names


def check_in_use(
    values: Mapping[str, Any], registry: Registry, components: Mapping[str, Any] | None
) -> None:
    """Raise :class:`ConfigError` for a value given to a parameter that only a component not
    in ``components`` declares (None: every component is in use)."""
    if components is None:
        return
    specs = registry.parameter_specs(components)
    for name, value in values.items():
        if value is not None and name not in specs and name not in MODEL_PARAMETERS:
            owner = registry.owner(name)
            if owner is not None:
                raise ConfigError(
                    f"parameter {name!r} belongs to {owner}, which this run does not use; "
                    "choose that component or drop the value"
                )


def check_point(params: Any, registry: Registry, components: Mapping[str, Any]) -> None:
    """Run the ``check`` of every component in ``components`` (the integrator, the energy
    terms, the driving protocol, the friction law) on one parameter point ``params``, so that
    a value a component refuses stops a run before anything is compiled or computed.

    Raises
    ------
    ParameterError
        The first refusal, naming the parameter, its value and what is allowed.
    """
    names = [("integrator", components["integrator"])]
    names += [("energy_term", n) for n in components.get("energy_terms", [])]
    names += [(k, components[k]) for k in ("driving_protocol", "friction_law") if k in components]
    names += [("pair_term", n) for n in components.get("pair_terms", [])]
    names += [("bot_interaction", n) for n in components.get("bot_interactions", [])]
    for kind, name in names:
        registry.get(kind, name).check(params)


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


_override: list[Registry] = []


@functools.cache
def _default_registry() -> Registry:
    return Registry()


def default_registry() -> Registry:
    """The registry of the built-ins and the installed plugins, built on first use (not at
    import); within :func:`registered`, that block's registry.

    Only the entry points (the command line, the public functions) call it; everything below
    them receives the registry it works with.
    """
    return _override[-1] if _override else _default_registry()


@contextmanager
def registered(*plugins: object, name: str = "test_plugin") -> Iterator[Registry]:
    """Within the block, the process-wide registry also holds ``plugins`` (for tests).

    Each plugin is a module or object with hook implementations; the built-ins and installed
    entry points are registered as usual.

    Parameters
    ----------
    *plugins : module or object
        The hook implementations to add.
    name : str
        The name they are registered under (numbered when several), as errors show it.
    """
    extra = [(name if len(plugins) == 1 else f"{name}_{i}", p) for i, p in enumerate(plugins)]
    _override.append(Registry(extra_plugins=extra))
    try:
        yield _override[-1]
    finally:
        _override.pop()
