"""The ``softcell`` command: one parse, then one call of the public API per verb.

The verbs live by family in this package (:mod:`~softcell.cli.run`, :mod:`~softcell.cli.analyze`,
:mod:`~softcell.cli.video`, :mod:`~softcell.cli.paper`, :mod:`~softcell.cli.studies`), the flags
they share in :mod:`~softcell.cli.flags`. Every parameter of the model is a flag (``--radius
4,8,12`` sweeps it); a TOML file may set them too (flags win). Bad input is reported as one
line on stderr with exit status 2.
"""

from __future__ import annotations

import argparse
import atexit
import os
import signal
import sys
import warnings
from collections.abc import Callable, Sequence

from softcell._version import __version__
from softcell.cli import analyze, fit, paper, run, studies, video
from softcell.cli.flags import Help, Parser
from softcell.engine.interrupt import (
    STOP_SIGNALS,
    exit_status,
    received,
    shielded,
    stop_signals,
)
from softcell.errors import CacheWarning, PluginWarning, SoftcellError

#: Each verb: its one-line help and what adds its flags, in the order ``--help`` lists them.
#: A verb's flags are built only when it runs, so ``softcell --version`` and ``--help`` import
#: nothing heavy.
COMMANDS: dict[str, tuple[str, Callable[[argparse.ArgumentParser], None]]] = {
    name: {
        **run.VERBS,
        **analyze.VERBS,
        **video.VERBS,
        **paper.VERBS,
        **studies.VERBS,
        **fit.VERBS,
    }[name]
    for name in (
        "plugins",
        "params",
        "simulate",
        "analyze",
        "render",
        "animate",
        "export",
        "track",
        "figures",
        "reproduce",
        "beyond",
        "study",
        "fit",
        "calibrate",
        "cache",
    )
}

#: The top-level help's epilog: the workflows, an example each, where to read on.
WORKFLOWS = """\
workflows:
  the paper end to end (--full: the paper's whole design; what each costs in
  time and disk: docs/performance.md):
    softcell reproduce --quick -o results
  your own runs: simulate -> analyze -> figures
    softcell simulate --radius 4,8,12 --realizations 5 --duration 120 -o run
    softcell analyze run -o analysis.nc
    softcell figures analysis.nc --simulations run -o figures
  watch them: realizations side by side, or a crowd of cells
    softcell animate run --point radius=0 -o cells.mp4 --end 30
    softcell simulate --cells 16 --box 60 --duration 60 -o crowd
    softcell animate crowd -o crowd.mp4
  a camera's view and back: render -> track -> analyze
    softcell render run --point radius=2 -o cell.mkv --start 15 --end 45
    softcell track cell.mkv --px-per-cm 10 --origin=X0,Y0 -o tracked.nc  (render
      prints the --origin to give)
    softcell analyze tracked.nc -o tracked_analysis.nc
  in other tools: OVITO, freud, MDAnalysis (GSD); movement and napari (poses)
    softcell export run/point000_realization0000.nc -o cell.gsd
    softcell export tracked.nc -o poses.nc
  studies beyond the paper: a cell at a gap; crowds
    softcell study constriction --quick -o gap
    softcell study crowding --quick -o crowding

'softcell COMMAND --help' lists a command's options. The documentation
(docs/getting-started.md in the source, first) explains the model, the analysis
and how to write a plugin.
"""


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``softcell`` command, with the flags of ``command`` (of
    every command when None)."""
    parser = Parser(
        prog="softcell",
        description="Simulate, track and analyse a soft robotic cell.",
        epilog=WORKFLOWS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"softcell {__version__}")
    sub = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=Parser
    )
    for name, (help_line, add) in COMMANDS.items():
        p = sub.add_parser(name, help=help_line, add_help=False)
        p.add_argument("-h", "--help", action=Help)
        if command is None or command == name:
            add(p)
    return parser


def parse_arguments(argv: Sequence[str]) -> argparse.Namespace:
    """Parse a command line, once: only the verb named gets its flags built."""
    command = next((a for a in argv if not a.startswith("-")), None)
    return build_parser(command if command in COMMANDS else "").parse_args(argv)


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"softcell: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``softcell`` command; returns the exit status (2 for bad input, 130 when
    interrupted)."""
    with warnings.catch_warnings():
        warnings.simplefilter("once", PluginWarning)
        warnings.simplefilter("once", CacheWarning)
        original, warnings.showwarning = warnings.showwarning, _plugin_warning(_show_warning)
        try:
            with stop_signals():  # SIGTERM (batch schedulers) as Ctrl-C
                try:
                    args = parse_arguments(sys.argv[1:] if argv is None else list(argv))
                    status = int(args.func(args))
                    if received():  # swallowed on the way (Python only prints it in a finaliser)
                        raise KeyboardInterrupt(
                            "interrupted as the command ended; what it wrote is complete"
                        )
                    return status
                except KeyboardInterrupt as exc:
                    with shielded():  # another signal must not break the last words
                        return _interrupted(exc)
                except Exception as exc:
                    if not received():
                        raise
                    # Broken by the stop itself (numba stopped half way through compiling
                    # a function fails the next one): the stop is what happened.
                    with shielded():
                        return _interrupted(
                            KeyboardInterrupt(
                                f"interrupted (as it stopped: {type(exc).__name__}: {exc}); "
                                "rerun the same command to resume"
                            )
                        )
        except SoftcellError as exc:
            print(f"softcell: error: {_one_line(exc)}", file=sys.stderr)
            return 2
        finally:
            warnings.showwarning = original


def _interrupted(exc: KeyboardInterrupt) -> int:
    """Say where a run stopped by Ctrl-C or SIGTERM stood; the exit status (130, 143)."""
    text = str(exc) or "interrupted; rerun the same command to resume"
    if received() == signal.SIGTERM:
        text = f"{text} (SIGTERM)"
    print(f"softcell: {_one_line(text)}", file=sys.stderr)
    return exit_status()


def entry() -> None:
    """The console script: :func:`main`, then an exit that skips the interpreter's teardown
    of compiled code (~0.6 s after a simulation), once output is flushed and exit handlers
    have run."""
    # Signals before and after main()'s own handling are ignored: a second SIGTERM arriving
    # as the handlers are restored must not kill the process on its way out (exit -15).
    for number in STOP_SIGNALS:
        signal.signal(number, signal.SIG_IGN)
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:  # the reader went away (`softcell cache | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 141
    sys.stderr.flush()
    atexit._run_exitfuncs()
    os._exit(code)


def _plugin_warning(show):
    """Plugin warnings as one line each; other warnings as Python shows them."""
    default = warnings.showwarning

    def dispatch(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, PluginWarning | CacheWarning):
            show(message, category, filename, lineno, file, line)
        else:
            default(message, category, filename, lineno, file, line)

    return dispatch


def _one_line(exc: object) -> str:
    return " ".join(str(exc).split())
