"""What a study is: a name, its designs (a quick look and the full one), the flags that change
a design, and a run that writes the study's page (``softcell study NAME``).

Every study is a :class:`Study`. Two kinds share the rest of their work:

- a :class:`GridStudy` (constriction, crowding, strategies) says what is its own: the points of
  a design, what one point measured, the context and conclusions its record carries, its
  figure and its page. Running and summarising are the same for every grid study: every point
  is planned before any runs, all of them from one root seed on one local cluster
  (:func:`~softcell.studies.variants.run_points`), and the summary is written atomically as
  ``<name>.json``, ``<name>.png`` and ``<name>.md``;
- a :class:`VariantStudy` (sensitivity, beyond) runs model variants of the paper's design side
  by side, each a reproduction in its own folder from one root seed
  (:func:`~softcell.studies.variants.run_variants`), and compares them.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any, ClassVar

from softcell.errors import SoftcellError


class Study:
    """The protocol of every study (``softcell study NAME``).

    A study sets ``name`` (its command and the name of its files), ``designs`` (its designs
    by name, ``"quick"`` and ``"full"``; a design is a frozen dataclass with a ``name`` and a
    ``check()`` that refuses one that cannot run), ``default`` (the design :meth:`run` runs
    when given none), ``own`` (the model parameters the study sets itself, refused among the
    caller's) and ``flags`` (the fields of its design that the command line offers, as
    ``--FIELD``).
    """

    name: ClassVar[str]
    designs: ClassVar[dict[str, Any]]
    default: ClassVar[str] = "full"
    own: ClassVar[tuple[str, ...]] = ()
    flags: ClassVar[tuple[str, ...]] = ()

    def offered(self) -> tuple[str, ...]:
        """The fields of the design that the command line offers (``--FIELD``)."""
        return self.flags

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
        """Run the study into ``out`` and write its page.

        Parameters
        ----------
        out : path-like
            Results directory: one folder per point or variant (resumable as ``softcell
            simulate``'s are), and the study's ``<name>.md`` with its record and figures.
        design : design, optional
            What to run (default: the design the study names in ``default``).
        seed : int
            Root seed (every point or variant draws the same streams).
        workers : int, optional
            Local worker processes (default: every core).
        parameters : dict, optional
            Model parameters over the defaults (units of ``softcell params``); those named in
            ``own`` are the study's.
        overwrite : bool
            Recompute what ``out`` holds from another seed, version or request, and write
            into a non-empty folder the study did not make.
        progress : bool
            Show a progress bar per run, in simulated seconds.
        log : callable, optional
            Receives a line per point or variant and what ``softcell simulate`` reports.

        Returns
        -------
        Path
            ``out / "<name>.md"``.

        Raises
        ------
        SoftcellError
            For a design that cannot run (its ``check``), a bad parameter (every point is
            planned before anything runs), or a folder another study or seed made.
        """
        raise NotImplementedError


class GridStudy(Study):
    """A study over a grid of points, each a :class:`~softcell.model.configuration.RunConfig`
    simulated with the design's realizations.

    Its designs have ``radii``, ``realizations`` and ``duration`` besides their own fields
    (``gaps``, ``fractions``, ...): ``flags`` lists the fields of its own.
    """

    own: ClassVar[tuple[str, ...]] = ("radius", "duration")
    #: The fields every grid design has, offered by the command line beside ``flags``.
    common: ClassVar[tuple[str, ...]] = ("quick", "radii", "realizations", "duration")

    def offered(self) -> tuple[str, ...]:
        """The design fields the command line offers: the common ones and ``flags``."""
        return (*self.common, *self.flags)

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

    # -- what every grid study does ----------------------------------------------------------

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

    def redraw(self, record: Path, path: Path) -> str:
        """Draw the figure of a study's record (its ``<name>.json``) again at ``path`` from
        the values the record holds, without its runs; returns the figure's caption ("" when
        the page writes its own)."""
        import json

        result = json.loads(Path(record).read_text(encoding="utf-8"))
        if result.get("study") != self.name:
            raise SoftcellError(
                f"{record} is the record of study {result.get('study')!r}, not {self.name!r}"
            )
        kind = type(self.designs[self.default])
        design = kind(
            **{k: tuple(v) if isinstance(v, list) else v for k, v in result["design"].items()}
        )
        return self.figure(Path(path), result, design)

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
        from softcell.io.files import atomic_write, json_text

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
            tmp.write_text(json_text(result, indent=1) + "\n", encoding="utf-8")
        caption = self.figure(out / f"{self.name}.png", result, design)
        page = out / f"{self.name}.md"
        with atomic_write(page) as tmp:
            tmp.write_text(self.page(result, caption), encoding="utf-8")
        return page


class VariantStudy(Study):
    """A study of model variants of the paper's design, each reproduced in its own folder
    from one root seed and compared with the first, the reference.

    Its design is a ``VariantDesign`` (``softcell.studies.variants``); it has one, the
    quick design of the paper over every variant the study knows (``variants``), and the
    command line's ``--only NAMES`` keeps some of them (:meth:`named`). A study sets
    ``variants``, ``base`` (the paper's design every variant runs) and ``comparison``, the
    function that runs its variants and writes its page.
    """

    default: ClassVar[str] = "full"
    flags: ClassVar[tuple[str, ...]] = ("only",)
    variants: ClassVar[tuple[Any, ...]]
    base: ClassVar[Any]
    #: Runs the variants and writes the page: ``comparison(out, *, seed, workers, variants,
    #: base, overwrite, progress, log) -> Path`` (a ``staticmethod``).
    comparison: ClassVar[Callable[..., Path]]

    @property
    def designs(self) -> dict[str, Any]:  # type: ignore[override]
        """The one design: every variant over ``base``."""
        from softcell.studies.variants import VariantDesign

        design = VariantDesign("every variant", self.variants, self.base)
        return {"full": design}

    def design(self, quick: bool, **changes: Any) -> Any:
        """The study's design, with ``only`` (names of variants) keeping some of them.

        Raises
        ------
        SoftcellError
            For ``quick`` (the study runs the paper's quick design already) or a change of
            another field than ``only``.
        """
        from softcell.errors import SoftcellError

        if quick:
            raise SoftcellError(
                f"--quick does not belong to 'study {self.name}': it runs the paper's quick "
                "design already"
            )
        design = self.designs["full"]
        only = changes.pop("only", None)
        if changes:
            raise SoftcellError(f"'study {self.name}' has no design field {next(iter(changes))}")
        if only is None:
            return design
        return replace(design, name="some variants", variants=self.named(only))

    def named(self, names: Any) -> tuple[Any, ...]:
        """The study's variants called ``names`` (the reference always first).

        Parameters
        ----------
        names : sequence of str
            Names of the study's variants (``--only``).

        Returns
        -------
        tuple of Variant

        Raises
        ------
        SoftcellError
            For an unknown name, or names that leave nothing to compare.
        """
        from softcell.studies.variants import variants_named

        return variants_named(self.variants, list(names), self.name)

    def compare(
        self,
        out: Path,
        design: Any,
        *,
        seed: int,
        workers: int | None,
        overwrite: bool,
        progress: bool,
        log: Callable[[str], None] | None,
    ) -> Path:
        """Run the variants of ``design`` into ``out`` and write the comparison (the options
        as :meth:`run` takes them), by the study's ``comparison``; the path of its page."""
        return self.comparison(
            out, seed=seed, workers=workers, variants=design.variants, base=design.base,
            overwrite=overwrite, progress=progress, log=log,
        )  # fmt: skip

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
        design = self.designs[self.default] if design is None else design
        design.check()
        if parameters:
            from softcell.studies.variants import own_parameters

            base = design.base
            varied = {k for v in design.variants for k in v.parameters}
            given = own_parameters(parameters, self.name, (*self.own, *sorted(varied)))
            design = replace(design, base=replace(base, parameters={**base.parameters, **given}))
        return self.compare(
            Path(out), design, seed=seed, workers=workers, overwrite=overwrite,
            progress=progress, log=log,
        )  # fmt: skip

    run.__doc__ = Study.run.__doc__
