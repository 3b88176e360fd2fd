"""Exceptions that softcell raises for bad input, so the CLI can print them as one line."""

from __future__ import annotations


class SoftcellError(Exception):
    """Base class of every error softcell reports to a user as one line (CLI exit status 2).

    Parameters
    ----------
    message : str
        The line printed: what was wrong, with the value and what is allowed. The subclasses
        below without parameters of their own take this one argument too.
    """


class ParameterError(SoftcellError, ValueError):
    """A parameter value outside its allowed range.

    The message names the parameter, its value with unit, the allowed range and the unit:
    ``parameter radius = -1 cm is not allowed: must be > 0``.

    Parameters
    ----------
    name : str
        The parameter's name, as ``softcell params`` lists it (kept as ``.name``).
    value : object
        The value given, in the parameter's unit (kept as ``.value``).
    allowed : str
        What is allowed, as a phrase ("must be > 0", "must be one of ...").
    unit : str
        The parameter's unit (UDUNITS, e.g. "cm"); "" or "1" for a pure number, which is then
        shown without one.
    """

    def __init__(self, name: str, value: object, allowed: str, unit: str = "") -> None:
        self.name, self.value, self.allowed, self.unit = name, value, allowed, unit
        shown = f"{value} {unit}".strip() if unit not in ("", "1") else f"{value}"
        super().__init__(f"parameter {name} = {shown} is not allowed: {allowed}")


class ConfigError(SoftcellError, ValueError):
    """A configuration file or command line that cannot be read (unknown key, bad syntax)."""


class SchemaError(SoftcellError, ValueError):
    """A Dataset that does not follow the softcell schema; the message names every problem.

    Parameters
    ----------
    problems : list of str
        One phrase per problem found (a missing variable, a variable without ``units``, ...),
        kept as ``.problems`` and joined by "; " into the message.
    """

    def __init__(self, problems: list[str]) -> None:
        self.problems = list(problems)
        super().__init__("dataset does not follow the softcell schema: " + "; ".join(problems))


class SimulationError(SoftcellError):
    """A run that blew up: a non-finite value or a membrane length far from l0."""


class ContractError(SoftcellError):
    """A component whose kernels do not match its contract (wrong signature, a kernel that
    does not compile); the message names the distribution, the component, the kernel and what
    was expected."""


class RegistryError(SoftcellError):
    """Conflicting or malformed plugin components (e.g. two components with one name)."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a run, once what was done is saved; the message says where the run
    stopped and how to resume it (CLI exit status 130, no traceback)."""


class PluginWarning(UserWarning):
    """A plugin was skipped because it failed to import or to register."""


class CacheWarning(UserWarning):
    """The compiled-model cache could not be used as is: a corrupt entry rebuilt, or a
    composition compiled in memory only because a bound function cannot be identified."""


class AnalysisWarning(UserWarning):
    """An analysis ran on data that limit it in a way its result shows: e.g. an MSD from a
    record sampled at two intervals, without the bodies' fine record."""
