"""What a grid study is: a design (quick and full), its points, running them, and a summary
(measurements, a JSON record, a figure and a page).

A study subclasses :class:`GridStudy` and says what is its own: the points of a design, what
one point measured, the context and conclusions its record carries, its figure and its page.
Running and summarising are the same for every study: every point is planned before any runs,
all of them from one root seed on one local cluster (:func:`~softcell.studies.variants.run_points`),
and the summary is written atomically as ``<name>.json``, ``<name>.png`` and ``<name>.md``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any, ClassVar


class GridStudy:
    """The protocol of a grid study (``softcell study NAME``).

    A study class sets ``name`` (its command, ``softcell study NAME``, and the name of its
    files), ``designs`` (its designs by name: ``"quick"``, a look, and ``"full"``; a design is
    a frozen dataclass with ``name``, ``radii``, ``realizations``, ``duration`` and a
    ``check()`` that refuses a grid that cannot run), ``default`` (the design :meth:`run`
    runs when given none), ``own`` (the model parameters the study sets itself, refused
    among the caller's) and ``flags`` (the design's fields that only this study has, such as
    ``gaps`` or ``fractions``, which the command line offers beside ``radii``,
    ``realizations`` and ``duration``).
    """

    name: ClassVar[str]
    designs: ClassVar[dict[str, Any]]
    default: ClassVar[str] = "full"
    own: ClassVar[tuple[str, ...]] = ("radius", "duration")
    flags: ClassVar[tuple[str, ...]] = ()

    # -- what a study says --------------------------------------------------------------------

    def points(
        self, out: Path, design: Any, parameters: dict[str, Any]
    ) -> dict[Path, tuple[str, Any]]:
        """Each point of ``design``: its folder under ``out``, a label for the log and the
        :class:`~softcell.model.configuration.RunConfig` it runs (with the model
        ``parameters`` over the defaults)."""
        raise NotImplementedError

    def measure(self, out: Path, design: Any) -> list[dict[str, Any]]:
        """What every point of ``design`` in ``out`` measured, as JSON-ready records."""
        raise NotImplementedError

    def context(self, design: Any, parameters: dict[str, Any]) -> dict[str, Any]:
        """Settings of the study the record carries before its points (none by default)."""
        return {}

    def conclusions(self, points: list[dict[str, Any]], design: Any) -> dict[str, Any]:
        """What the record concludes after its points (none by default)."""
        return {}

    def figure(self, path: Path, result: dict[str, Any], design: Any) -> str:
        """Draw the study's figure of ``design`` into ``path`` from its ``result``; its
        caption ("" when the page writes its own)."""
        raise NotImplementedError

    def page(self, result: dict[str, Any], caption: str) -> str:
        """The study's page (Markdown) from its ``result`` and its figure's ``caption``."""
        raise NotImplementedError

    # -- what every study does ----------------------------------------------------------------

    def design(self, quick: bool, **changes: Any) -> Any:
        """The quick or the full design, with some of its fields changed.

        Parameters
        ----------
        quick : bool
            The quick design (a look) rather than the full one.
        **changes
            Fields of the design and their new values (named ``"<name>, changed"``).

        Returns
        -------
        design
            The study's design, changed.
        """
        design = self.designs["quick" if quick else "full"]
        return replace(design, name=f"{design.name}, changed", **changes) if changes else design

    def run(
        self,
        out: str | os.PathLike[str],
        *,
        design: Any = None,
        seed: int = 0,
        workers: int | None = None,
        parameters: dict[str, Any] | None = None,
        overwrite: bool = False,
        progress: bool = True,
        log: Callable[[str], None] | None = print,
    ) -> Path:
        """Run the study into ``out`` and write its summary.

        Parameters
        ----------
        out : path-like
            Results directory: one folder per point (resumable as ``softcell simulate``'s
            are), and ``<name>.json``, ``<name>.md`` and ``<name>.png``.
        design : design, optional
            The grid (default: the design the study names in ``default``).
        seed : int
            Root seed (every point draws the same streams).
        workers : int, optional
            Local worker processes (default: every core).
        parameters : dict, optional
            Model parameters over the defaults (units of ``softcell params``); those named in
            ``own`` are the study's.
        overwrite : bool
            Recompute what ``out`` holds from another seed, version or request, and write
            into a non-empty folder the study did not make.
        progress : bool
            Show a progress bar per point, in simulated seconds.
        log : callable, optional
            Receives a line per point and what ``softcell simulate`` reports.

        Returns
        -------
        Path
            ``out / "<name>.md"``.

        Raises
        ------
        SoftcellError
            For a grid that cannot run (the design's ``check``), a bad parameter (every
            point is planned before anything runs), or a folder another study or seed made.
        """
        from softcell.io.files import check_output
        from softcell.studies.variants import own_parameters, run_points

        design = self.designs[self.default] if design is None else design
        design.check()
        parameters = own_parameters(parameters, self.name, self.own)
        out = check_output(Path(out), "report", directory=True)
        run_points(
            out,
            self.points(out, design, parameters),
            command=f"study {self.name}",
            realizations=design.realizations,
            seed=seed,
            workers=workers,
            overwrite=overwrite,
            progress=progress,
            log=log,
        )
        return self.summarize(out, design, seed, parameters)

    def summarize(
        self, out: Path, design: Any, seed: int, parameters: dict[str, Any] | None = None
    ) -> Path:
        """Write the study's record, figure and page from the runs in ``out``.

        Parameters
        ----------
        out : Path
            The study's folder, holding its points' runs.
        design : design
            The design that was run.
        seed : int
            The root seed it was run from.
        parameters : dict, optional
            The model parameters over the defaults it was run with.

        Returns
        -------
        Path
            ``out / "<name>.md"``, beside ``<name>.json`` and ``<name>.png``.
        """
        from softcell._version import __version__
        from softcell.io.files import atomic_write

        parameters = dict(parameters or {})
        points = self.measure(out, design)
        result = {
            "study": self.name,
            "design": asdict(design),
            "seed": seed,
            "version": __version__,
            "parameters": parameters,
            **self.context(design, parameters),
            "points": points,
            **self.conclusions(points, design),
        }
        with atomic_write(out / f"{self.name}.json") as tmp:
            tmp.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
        caption = self.figure(out / f"{self.name}.png", result, design)
        page = out / f"{self.name}.md"
        with atomic_write(page) as tmp:
            tmp.write_text(self.page(result, caption), encoding="utf-8")
        return page
