"""The flags the verbs share, each declared once, and what reads them back.

A verb's ``add`` function calls these to declare its flags; its ``run`` function reads the
parsed values with :func:`run_config`, :func:`numbers` and :func:`given`. Bad input is a
:class:`~softcell.errors.SoftcellError`, which the program prints as one line (exit status 2).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

from softcell.errors import SoftcellError
from softcell.io.config_file import load_config
from softcell.model.configuration import RunConfig
from softcell.model.parameters import ParameterSpec, suggest


class Parser(argparse.ArgumentParser):
    """argparse, but a bad command line is one line on stderr (exit status 2), like every
    other bad input, with the flag meant when one was mistyped."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)  # --arena-sid is not --arena-side
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        if message.startswith("unrecognized arguments: "):
            flags = option_strings(self)
            given_flag = message.removeprefix("unrecognized arguments: ").split()[0]
            message += suggest(given_flag.split("=")[0], flags)
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class Help(argparse.Action):
    """``-h`` / ``--help`` of a verb: its help, first shaped by the verb's ``help_filter``
    default (a function of the parser and the flags parsed so far), when it sets one."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS, **kwargs):
        kwargs.setdefault("help", "show this help message and exit")
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None) -> NoReturn:
        shape = parser.get_default("help_filter")
        if shape is not None:
            shape(parser, namespace)
        parser.print_help()
        parser.exit()


def option_strings(parser: argparse.ArgumentParser) -> list[str]:
    """Every flag of ``parser`` and of its subcommands' parsers."""
    flags = []
    for action in parser._actions:
        flags += action.option_strings
        choices = getattr(action, "choices", None)
        for sub in choices.values() if isinstance(choices, dict) else ():
            if isinstance(sub, argparse.ArgumentParser):
                flags += option_strings(sub)
    return flags


def flag(name: str) -> str:
    """The flag of the parameter ``name`` (``bending_stiffness`` -> ``--bending-stiffness``)."""
    return "--" + name.replace("_", "-")


# -- the flags most verbs take ----------------------------------------------------------------


def output(p: argparse.ArgumentParser, help: str, required: bool = True) -> None:
    """``-o`` / ``--output``: the file or folder the verb writes."""
    p.add_argument("-o", "--output", type=Path, required=required, help=help)


def overwrite(p: argparse.ArgumentParser, help: str) -> None:
    """``--overwrite``: what the verb may replace or recompute instead of stopping."""
    p.add_argument("--overwrite", action="store_true", help=help)


def quiet(p: argparse.ArgumentParser, help: str = "no progress bar") -> None:
    """``--quiet``: no progress bar (or no line per step)."""
    p.add_argument("--quiet", action="store_true", help=help)


def no_verify(p: argparse.ArgumentParser) -> None:
    """``--no-verify``: read the inputs without checking them against their checksums."""
    p.add_argument(
        "--no-verify",
        dest="verify",
        action="store_false",
        help="skip checking each input against its checksum, version and schema (faster "
        "by about one reading of the files; for trusted scratch files)",
    )


def seed(p: argparse.ArgumentParser, help: str, default: int | None = 0) -> None:
    """``--seed``: the root seed every random stream of the run derives from."""
    p.add_argument("--seed", type=int, default=default, help=help)


def workers(p: argparse.ArgumentParser, help: str, scheduler: bool = False) -> None:
    """``--workers N`` (local processes), with ``--scheduler ADDRESS`` (a dask.distributed
    cluster) as its alternative when ``scheduler``."""
    group = p.add_mutually_exclusive_group() if scheduler else p
    group.add_argument("--workers", type=_worker_count, help=help)
    if scheduler:
        group.add_argument(
            "--scheduler",
            metavar="ADDRESS",
            help="run the realizations on the dask.distributed cluster whose "
            "scheduler listens at ADDRESS (e.g. tcp://10.0.0.5:8786), one task "
            "per realization; its workers must see the output directory",
        )


def config_file(p: argparse.ArgumentParser, help: str = "TOML configuration file") -> None:
    """The optional positional TOML configuration file."""
    p.add_argument("config", nargs="?", type=Path, help=help)


def parameters(
    p: argparse.ArgumentParser,
    specs: Sequence[ParameterSpec],
    title: str = "model parameters",
    description: str = "override the defaults (softcell params lists "
    "them; docs/model.md explains them); a comma-separated list sweeps a "
    "parameter",
) -> None:
    """One flag per parameter of ``specs`` (``--radius VALUE``), in a group of its own;
    read back by :func:`parameter_values`."""
    group = p.add_argument_group(title, description)
    for spec in specs:
        unit = "" if spec.unit == "1" else f" [{spec.unit}]"
        default = "derived" if spec.default is None else spec.default
        group.add_argument(
            flag(spec.name),
            dest=f"param_{spec.name}",
            metavar="VALUE",
            help=f"{spec.long_name}{unit} (default {default})",
        )


def component_parameters(p: argparse.ArgumentParser, specs: Sequence[ParameterSpec]) -> None:
    """Flags for the parameters the components declare beyond the model's (e.g. rodas4's
    --atol and --rtol)."""
    parameters(
        p,
        specs,
        "component parameters",
        "parameters of the components this run uses (integrator, protocol, energy terms, detector)",
    )


def components(p: argparse.ArgumentParser) -> None:
    """The components chosen by name, and the obstacles (which bring their energy term)."""
    p.add_argument("--protocol", help="driving protocol (default run_and_tumble)")
    p.add_argument(
        "--integrator",
        help="integrator (default rodas4; explicit_euler is the paper's scheme, the reference)",
    )
    p.add_argument(
        "--friction-law",
        help="the membrane's friction law (default viscous, the "
        "paper's; coulomb adds a static threshold)",
    )
    p.add_argument("--energy-terms", help="comma-separated energy terms")
    p.add_argument(
        "--obstacle",
        action="append",
        metavar="X,Y,RADIUS",
        help="a fixed circular post (cm; repeatable); the energy term obstacles joins the terms",
    )
    p.add_argument(
        "--wall",
        action="append",
        metavar="X0,Y0,X1,Y1,WIDTH",
        help="a fixed straight wall of thickness WIDTH from (X0, Y0) to (X1, Y1) (cm; "
        "repeatable; write --wall=-10,... when the first number is negative)",
    )


#: The flags of an assembly's settings: the ``[assembly]`` key each sets.
ASSEMBLY_KEYS = ("cells", "box", "boundary", "placement", "gap", "pair_terms")


def assembly(p: argparse.ArgumentParser) -> None:
    """The ``[assembly]`` settings as flags: many cells."""
    group = p.add_argument_group(
        "assembly", "many cells, each with its own bot, repelling each other's membranes"
    )
    group.add_argument(
        "--cells", dest="assembly_cells", type=int, metavar="M", help="number of cells"
    )
    group.add_argument(
        "--box",
        dest="assembly_box",
        type=float,
        metavar="L",
        help="side of the square box centred on the origin (cm); none: the open plane",
    )
    group.add_argument(
        "--boundary",
        dest="assembly_boundary",
        choices=("periodic", "walls", "open"),
        help="the box's boundary (default periodic with --box, open without)",
    )
    group.add_argument(
        "--placement",
        dest="assembly_placement",
        choices=("lattice", "random"),
        help="starting places: a square lattice (default) or at random",
    )
    group.add_argument(
        "--gap",
        dest="assembly_gap",
        type=float,
        metavar="CM",
        help="smallest starting gap between rings, walls and obstacles (cm, default 1)",
    )
    group.add_argument(
        "--pair-terms",
        dest="assembly_pair_terms",
        metavar="A,B",
        help="how the membranes meet: comma-separated pair terms (default repulsion)",
    )


def bots(p: argparse.ArgumentParser) -> None:
    """The ``[bots]`` settings as flags: several bots in one ring."""
    group = p.add_argument_group(
        "bots", "several bots in one ring, each with its own drive, schedule and stream"
    )
    group.add_argument(
        "--bots", dest="bots_count", type=int, metavar="K", help="number of bots (default 1)"
    )
    group.add_argument(
        "--bot-placement",
        dest="bots_placement",
        choices=("random", "ring", "lattice"),
        help="starting places: at random without overlap (default), a ring of starting "
        "points, or a lattice",
    )
    group.add_argument(
        "--bot-gap",
        dest="bots_gap",
        type=float,
        metavar="CM",
        help="smallest starting gap between bots and to the ring (cm, default 0.5)",
    )
    group.add_argument(
        "--bot-interactions",
        dest="bots_interactions",
        metavar="A,B",
        help="how the bots meet: comma-separated bot interactions (default bot_repulsion)",
    )


# -- reading them back ------------------------------------------------------------------------


def parameter_values(args: argparse.Namespace) -> dict[str, Any]:
    """The parameters given as flags, as text (a comma-separated value as a list)."""
    values: dict[str, Any] = {}
    for key, raw in vars(args).items():
        if key.startswith("param_") and raw is not None:
            items = [s.strip() for s in raw.split(",")]
            values[key.removeprefix("param_")] = items if len(items) > 1 else items[0]
    return values


def run_config(args: argparse.Namespace) -> RunConfig:
    """The request of a command line: its TOML file (read once), then its flags' parameters,
    obstacles, assembly settings and components."""
    base = load_config(args.config) if getattr(args, "config", None) else RunConfig()
    values = parameter_values(args)
    placed = _obstacles(args)
    if placed:
        if "obstacles" in values:
            raise SoftcellError("--obstacles and --obstacle / --wall both place obstacles: use one")
        values["obstacles"] = placed
    return base.updated(
        parameters=values,
        assembly=_assembly(args),
        components=_component_choice(args),
        bots=_bots(args),
    )


def _bots(args: argparse.Namespace) -> dict[str, Any]:
    found = {
        key: getattr(args, f"bots_{key}")
        for key in ("count", "placement", "gap", "interactions")
        if getattr(args, f"bots_{key}", None) is not None
    }
    if "interactions" in found:
        found["interactions"] = [n.strip() for n in found["interactions"].split(",")]
    return found


def _assembly(args: argparse.Namespace) -> dict[str, Any]:
    found = {
        key: getattr(args, f"assembly_{key}")
        for key in ASSEMBLY_KEYS
        if getattr(args, f"assembly_{key}", None) is not None
    }
    if "pair_terms" in found:
        found["pair_terms"] = [n.strip() for n in found["pair_terms"].split(",")]
    return found


def _obstacles(args: argparse.Namespace) -> str:
    """The parameter ``obstacles`` from ``--obstacle X,Y,RADIUS`` and
    ``--wall X0,Y0,X1,Y1,WIDTH`` (cm), or "" when neither is given."""
    from softcell.model.obstacle_layout import Post, Wall, obstacle_text

    placed = []
    for name, cls in (("obstacle", Post), ("wall", Wall)):
        for raw in getattr(args, name, None) or ():
            fields = [f.name for f in dataclasses.fields(cls)]
            try:
                words = [float(w) for w in raw.split(",")]
                if len(words) != len(fields):
                    raise ValueError
            except ValueError:
                raise SoftcellError(
                    f"--{name} {raw} is not allowed: must be "
                    f"{','.join(f.upper() for f in fields)} (numbers in cm)"
                ) from None
            placed.append(cls(*words))
    return obstacle_text(placed)


def _component_choice(args: argparse.Namespace) -> dict[str, Any]:
    chosen: dict[str, Any] = {
        k: v
        for k, v in (
            ("driving_protocol", getattr(args, "protocol", None)),
            ("friction_law", getattr(args, "friction_law", None)),
            ("integrator", getattr(args, "integrator", None)),
        )
        if v
    }
    if getattr(args, "energy_terms", None):
        chosen["energy_terms"] = [s.strip() for s in args.energy_terms.split(",")]
    return chosen


def numbers(name: str, raw: str | None) -> list[float] | None:
    """The comma-separated numbers of the flag ``name``, None when it was not given."""
    if raw is None:
        return None
    try:
        return [float(v) for v in raw.split(",") if v.strip()]
    except ValueError:
        raise SoftcellError(f"{name} {raw!r} is not a comma-separated list of numbers") from None


def distinct(name: str, values: list[Any] | None) -> list[Any] | None:
    """``values`` of the flag ``name``, refused in one line when one comes twice (a point
    computed twice, a panel drawn twice)."""
    seen: list[Any] = []
    for value in values or []:
        if value in seen:
            shown = f"{value:g}" if isinstance(value, float) else f"{value}"
            raise SoftcellError(f"{name} names {shown} twice: give each value once")
        seen.append(value)
    return values


def distinct_numbers(name: str, raw: str | None) -> list[float] | None:
    """:func:`numbers`, each once (:func:`distinct`)."""
    return distinct(name, numbers(name, raw))


def names(raw: str | None) -> list[str] | None:
    """The comma-separated names of a flag, None when it was not given."""
    return None if raw is None else [n.strip() for n in raw.split(",") if n.strip()]


def given(**values: Any) -> dict[str, Any]:
    """The keyword arguments whose flags were given (not None)."""
    return {k: v for k, v in values.items() if v is not None}


def check_workers(value: int | None) -> int:
    """``--workers`` as a count (1 when not given), checked as
    :func:`softcell.runner.points.check_worker_count` does."""
    return 1 if value is None else _worker_count(str(value))


def _worker_count(text: str) -> int:
    """The ``--workers`` flag's value, checked as it is parsed (before a study marks its
    folder or a run plans anything)."""
    from softcell.model.limits import check_worker_count

    try:
        value = int(text)
    except ValueError:
        raise SoftcellError(f"--workers {text!r} is not a whole number") from None
    return check_worker_count(value, "--workers")


def note(line: str) -> None:
    """A line of progress on stderr."""
    print(f"softcell: {line}", file=sys.stderr)
