"""The paper end to end: simulate, analyze, render and track, draw the figures, write a report.

:func:`reproduce` runs a :class:`Design` (``QUICK`` or ``FULL``) into one results
directory::

    simulations/            one file per (radius, realization)     softcell simulate
    free_bot/               the bot without a membrane (S1)
    free_bot_pivot1/        the same, tumbling about a pivot 1 cm off-centre (the paper's
    free_bot_pivot1.53/     robot), and 1.53 cm (its published digital twin)
    analysis.nc             the sweep's analysis                    softcell analyze
    free_bot_analysis.nc
    contact.nc              the membrane's force and torque on the bot, per radius
    video/                  one realization rendered, tracked and analysed as an experiment
    figures/                Fig. 2, 3, 4, S1, S2, S3 and T (theory) as PNG and PDF
    report.md, report.html  what ran, every figure, the paper's findings beside ours
    findings.json           the findings table, for scripts
    reproduce.json          the design, seed and version the directory was made for
    timing.json             wall time per step and peak memory of the last invocation

Run again into the same directory with the same design, seed and version (``reproduce.json``
records them), it keeps every finished realization (as ``softcell simulate`` does), so an
interrupted run resumes where it stopped; another design or seed stops before anything is
computed (``overwrite`` recomputes). The
analyses, the tracking, the figures and the report take seconds and are redone (the video
pipeline in a process of its own, beside the analyses and the figures it does not mark). Every
random stream derives from the one ``seed``: realization r of radius index p draws from
``SeedSequence(seed, spawn_key=(p, r))``; the free bot's realization r uses the stream of
(0, r); the video's camera noise uses ``SeedSequence(seed, spawn_key=(VIDEO_STREAM,))``.
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from softcell.errors import SoftcellError
from softcell.model.configuration import DEFAULT_COMPONENTS, RunConfig
from softcell.paper.experiment import VideoDesign, experimental_pipeline
from softcell.paper.report import PIVOTS, write_report
from softcell.runner.points import worker_count
from softcell.runner.side_process import Alongside

if TYPE_CHECKING:
    import xarray as xr

    from softcell.components.registry import Registry
    from softcell.paper.figures import FigureSet

RADII = tuple(float(r) for r in range(4, 14))


@dataclass(frozen=True)
class Design:
    """What :func:`reproduce` runs.

    ``duration`` None means the paper's design (docs/model.md §2: 900 s for R <= 9 cm, 1800 s
    above). ``discard`` (s) is left out of every statistic. ``video`` None leaves out the
    experimental pipeline (filming, tracking; and the tracked markers of the figures).
    """

    name: str
    radii: tuple[float, ...] = RADII
    realizations: int = 25
    duration: float | None = None
    discard: float = 15.0
    free_bot_realizations: int = 25
    video: VideoDesign | None = field(default_factory=VideoDesign)
    components: dict[str, Any] = field(default_factory=lambda: dict(DEFAULT_COMPONENTS))
    parameters: dict[str, Any] = field(default_factory=dict)  # beyond the defaults
    caveat: str = ""  # what the design gives up against the paper's, for the report

    def describe(self) -> str:
        length = (
            "the paper's durations (900 s for R <= 9 cm, 1800 s above)"
            if self.duration is None
            else f"{self.duration:g} s each"
        )
        video = (
            "no video"
            if self.video is None
            else f"video of {self.video.span:g} s at R = {self.video.radius:g} cm"
        )
        return (
            f"{len(self.radii)} radii ({', '.join(f'{r:g}' for r in self.radii)} cm) x "
            f"{self.realizations} realizations, {length}; {self.free_bot_realizations} "
            f"free-bot realizations; first {self.discard:g} s discarded; {video}"
        )


#: The README's main job: every radius, fewer and shorter runs; ~5 minutes on 2 cores.
QUICK = Design(
    "quick",
    realizations=5,
    duration=240.0,
    free_bot_realizations=5,
    caveat="5 realizations of 240 s per radius instead of the paper's 25 of 900/1800 s: the "
    "long-lag quantities (the diffusive MSD slopes, the merging of the bot and cell "
    "MSDs) carry larger errors than the paper's; `softcell reproduce --full` runs the "
    "paper's design. The 15 s discard and every model parameter are the paper's.",
)
#: The paper's design: 25 realizations of 900 / 1800 s per radius.
FULL = Design("full", video=VideoDesign(span=300.0))
DESIGNS = {"quick": QUICK, "full": FULL}


@dataclass
class Outcome:
    """What :func:`reproduce` made: its files and how long each step took (wall s)."""

    out: Path
    design: Design
    seed: int
    steps: dict[str, float] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    #: Wall s of the video pipeline, which runs beside the analysis (inside its step).
    video_alone: float | None = None

    @property
    def report(self) -> Path:
        return self.out / "report.md"


def _config(design: Design, radius: float | list[float] | None = None) -> RunConfig:
    values: dict[str, Any] = {
        **design.parameters,
        "radius": list(design.radii) if radius is None else radius,
    }
    if design.duration is not None:
        values["duration"] = design.duration
    return RunConfig(parameters=values).updated(components=design.components)


def _pivot_config(free: RunConfig, offset: float) -> RunConfig:
    return free.updated(
        parameters={"pivot_offset": offset},
        components={"driving_protocol": "pivot_run_and_tumble"},
    )


#: The request a results directory was made for: design, seed, version (checked on a rerun).
MANIFEST = "reproduce.json"


def _flat(prefix: str, value: Any) -> dict[str, Any]:
    if isinstance(value, dict):
        return {
            k: v
            for key, item in value.items()
            for k, v in _flat(f"{prefix}.{key}" if prefix else key, item).items()
        }
    return {prefix: value}


def _manifest(design: Design, seed: int) -> dict[str, Any]:
    from softcell._version import __version__

    return json.loads(
        json.dumps({"design": asdict(design), "seed": seed, "softcell_version": __version__})
    )


def check_results_directory(out: Path, design: Design, seed: int, overwrite: bool) -> None:
    """Stop, in one line, unless ``out`` is new or empty, or holds a reproduction of the same
    design, seed and version (``overwrite`` lifts both)."""
    from softcell.runner.resume import first_mismatch

    if overwrite or not out.is_dir() or not any(out.iterdir()):
        return
    manifest = out / MANIFEST
    if not manifest.is_file():
        raise SoftcellError(
            f"{out} is not empty and was not made by `softcell reproduce` (no "
            f"{MANIFEST}); choose a new directory, or pass --overwrite to "
            "write into it"
        )
    try:
        made = json.loads(manifest.read_text())
    except (OSError, ValueError) as exc:
        raise SoftcellError(
            f"{manifest} is unreadable ({exc}); pass --overwrite to redo the reproduction"
        ) from None
    why = first_mismatch(_flat("", made), _flat("", _manifest(design, seed)))
    if why:
        raise SoftcellError(
            f"{out} holds a reproduction made with {why}; rerun with "
            "--overwrite to recompute it, or write to another directory"
        )


def finished(folder: Path, design: Design, seed: int) -> bool:
    """Whether ``folder`` holds a finished reproduction of ``design`` and ``seed`` by this
    version (its manifest matches and its timing, written last, is there)."""
    try:
        made = json.loads((folder / MANIFEST).read_text())
    except (OSError, ValueError):
        return False
    return made == _manifest(design, seed) and (folder / TIMING).is_file()


def _check_design(design: Design) -> None:
    if design.realizations < 1 or design.free_bot_realizations < 1:
        raise SoftcellError(
            "a design needs at least one realization per radius and one free-bot realization"
        )
    if design.video is not None and design.video.radius not in design.radii:
        raise SoftcellError(
            f"the video's radius {design.video.radius:g} cm is not among the "
            f"design's radii {list(design.radii)}"
        )


def _bytes_to_write(
    config: RunConfig,
    folder: Path,
    count: int,
    membrane: bool,
    seed: int,
    overwrite: bool,
    registry: Registry,
) -> int:
    """Bytes one ensemble will write into ``folder``, once its request is checked against
    what the folder holds."""
    from softcell.runner.ensemble import plan
    from softcell.runner.resume import expected_bytes, resume_plan

    tasks = plan(
        config, folder, realizations=count, seed=seed, membrane=membrane, registry=registry
    )
    return expected_bytes(resume_plan(tasks, folder, overwrite=overwrite).todo)


def _filmed_task(design: Design, out: Path, seed: int, registry: Registry):
    """The realization the experimental pipeline films: realization 0 at the video's radius."""
    from softcell.runner.ensemble import plan

    assert design.video is not None
    tasks = plan(_config(design), out / "simulations", realizations=1, seed=seed, registry=registry)
    return next(t for t in tasks if t.params.radius == design.video.radius)


def reproduce(
    out: str | os.PathLike[str],
    design: Design = QUICK,
    *,
    seed: int = 0,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
    log: Callable[[str], None] | None = print,
    registry: Registry | None = None,
) -> Outcome:
    """Run ``design`` into ``out``: simulations, analyses, the video pipeline, figures, report.

    The design's durations and discard are in s, its radii in cm; every file it writes
    carries its variables' units.

    Parameters
    ----------
    out : path-like
        Results directory (created; finished parts found there are kept).
    design : Design
        ``QUICK`` or ``FULL``, or your own.
    seed : int
        Root seed of every random stream.
    workers : int, optional
        Local worker processes for the simulations (default: every core).
    scheduler : str, optional
        Address of a dask.distributed scheduler to run the realizations on instead.
    overwrite : bool
        Recompute what ``out`` holds from another design, seed or version (without it such
        a directory stops the run before anything is computed), or write into a non-empty
        directory that ``softcell reproduce`` did not make.
    progress : bool
        Progress bars.
    log : callable, optional
        Receives one line per step.
    registry : Registry, optional
        Where the components are looked up; by default the built-ins and the installed
        plugins.

    Returns
    -------
    Outcome
        Paths and step timings; the report is ``out / "report.md"`` (and ``report.html``).
    """
    from softcell.components.registry import default_registry
    from softcell.io.files import atomic_write, check_output, check_writable
    from softcell.model.limits import check_seed
    from softcell.runner.cluster import check_scheduler, cluster_client
    from softcell.runner.ensemble import simulate

    _check_design(design)
    workers = worker_count(workers, scheduler)
    check_seed(seed)
    registry = registry if registry is not None else default_registry()
    out = check_output(out, "report", directory=True)
    check_results_directory(out, design, seed, overwrite)
    config = _config(design)
    free = _config(design, design.radii[0])
    # Every check before anything is computed: both ensembles' requests against the files.
    need = sum(
        _bytes_to_write(cfg, out / folder, count, membrane, seed, overwrite, registry)
        for cfg, folder, count, membrane in (
            (config, "simulations", design.realizations, True),
            (free, "free_bot", design.free_bot_realizations, False),
            *(
                (_pivot_config(free, offset), folder, design.free_bot_realizations, False)
                for folder, offset in PIVOTS.items()
            ),
        )
    )
    check_writable(out, need)
    if scheduler is not None:
        check_scheduler(scheduler)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_write(out / MANIFEST) as tmp:
        tmp.write_text(json.dumps(_manifest(design, seed), indent=1), encoding="utf-8")
    outcome = Outcome(out, design, seed)
    say = log or (lambda _: None)
    options = {"discard": design.discard}

    total = step_count(design)

    def step(name: str, what: str):
        say(f"[{len(outcome.steps) + 1}/{total}] {what}")
        return _Timer(outcome.steps, name)

    with contextlib.ExitStack() as stack:
        # One cluster for both ensembles: each worker compiles its steppers once.
        client = (
            None if workers == 1 else stack.enter_context(cluster_client(workers or 1, scheduler))
        )
        with step("simulations", f"simulating {design.describe()}"):
            simulate(
                config,
                out / "simulations",
                realizations=design.realizations,
                seed=seed,
                client=client,
                progress=progress,
                overwrite=overwrite,
                log=say,
                registry=registry,
            )
        with step("free_bot", "simulating the free bot (turning about its centre and pivots)"):
            for cfg, folder in (
                (free, "free_bot"),
                *((_pivot_config(free, offset), folder) for folder, offset in PIVOTS.items()),
            ):
                simulate(
                    cfg,
                    out / folder,
                    realizations=design.free_bot_realizations,
                    seed=seed,
                    client=client,
                    membrane=False,
                    progress=progress,
                    overwrite=overwrite,
                    log=say,
                    registry=registry,
                )
    figures, video = _analyses_video_figures(
        out, design, seed, options, progress, registry, outcome, step
    )
    with step("report", "writing the report"):
        write_report(
            out,
            design=design,
            seed=seed,
            steps=outcome.steps,
            notes=outcome.notes,
            figures=figures,
            video=video,
        )
    _write_timing(out, outcome, workers if scheduler is None else None)
    say(f"report: {outcome.report} and {outcome.report.with_suffix('.html')}")
    return outcome


def step_count(design: Design) -> int:
    """How many numbered steps ``[k/n]`` :func:`reproduce` prints for ``design``: the two
    ensembles, the analyses, the figures and the report, and with a video the wait for it
    and the figures that show its markers."""
    return 5 if design.video is None else 7


#: What :func:`reproduce` measured of its own run: wall time per step and peak memory.
TIMING = "timing.json"


def _analyses_video_figures(
    out: Path,
    design: Design,
    seed: int,
    options: dict[str, Any],
    progress: bool,
    registry: Registry,
    outcome: Outcome,
    step: Callable[[str, str], _Timer],
) -> tuple[FigureSet, dict[str, Any] | None]:
    """The analyses, the figures and the video pipeline. The video (one core's work) runs
    in a process of its own from the analyses on; the figures that do not show its markers
    are drawn while it runs, Fig. 3 and 4 after it."""
    from softcell.io.netcdf import read_dataset
    from softcell.paper.figures import WITH_TRACKED, FigureSet

    figures, video = FigureSet(), None
    with contextlib.ExitStack() as stack:
        filming, what = None, "analysing the sweep and the free bot"
        if design.video is not None:
            task = _filmed_task(design, out, seed, registry)
            filming = stack.enter_context(
                Alongside(
                    experimental_pipeline,
                    Path(task.path),
                    out / "video",
                    design.video,
                    discard=design.discard,
                    seed=seed,
                )
            )
            what += (
                f"; beside it, rendering, tracking and analysing {design.video.span:g} s "
                f"at R = {design.video.radius:g} cm"
            )
        with step("analysis", what):
            _analyses(out, design, options, progress, registry)
        if filming is None:
            with step("figures", "drawing the figures"):
                figures.update(_figures(out, None))
            return _skipped(figures, outcome), None
        with step("figures", "drawing the figures without the video's markers"):
            figures.update(_figures(out, None, exclude=WITH_TRACKED))
        with step("video", "waiting for the video pipeline"):
            video = filming.result()
        outcome.video_alone = filming.seconds
        video["source"] = str(Path(task.path).relative_to(out))
    tracked = read_dataset(out / "video" / "tracked_analysis.nc")
    with step("figures_with_video", "drawing Fig. 3 and 4 with the tracked video's markers"):
        figures.update(_figures(out, tracked, only=WITH_TRACKED))
    return _skipped(figures, outcome), video


def _figures(
    out: Path,
    tracked: xr.Dataset | None,
    only: tuple[str, ...] | None = None,
    exclude: tuple[str, ...] = (),
) -> FigureSet:
    from softcell.io.netcdf import open_dataset, read_dataset
    from softcell.paper.figures import FIGURES, make_figures

    names = [n for n in (only or FIGURES) if n not in exclude]
    return make_figures(
        read_dataset(out / "analysis.nc"),
        out / "figures",
        simulations=open_dataset(out / "simulations", chunks={}),
        free_bot=read_dataset(out / "free_bot_analysis.nc"),
        tracked=tracked,
        only=names,
    )


def _skipped(figures: FigureSet, outcome: Outcome) -> FigureSet:
    outcome.notes.extend(f"{name} not drawn: {why}" for name, why in figures.skipped.items())
    return figures


def _analyses(
    out: Path, design: Design, options: dict[str, Any], progress: bool, registry: Registry
) -> None:
    """The sweep's and the free bot's analyses and the membrane's reaction on the bot."""
    from softcell.analysis import analyze
    from softcell.io.netcdf import open_dataset, write_dataset
    from softcell.paper.reaction import contact_summary

    # One dask chunk per file: the analysis holds one radius in memory at a time.
    analysis = analyze(
        open_dataset(out / "simulations", chunks={}),
        options,
        progress=progress,
        registry=registry,
    )
    write_dataset(analysis, out / "analysis.nc")
    for folder in ("free_bot", *PIVOTS):
        free_analysis = analyze(open_dataset(out / folder), options, registry=registry)
        write_dataset(free_analysis, out / f"{folder}_analysis.nc")
    # The membrane's reaction on the bot (the paper's steering mechanism), per radius.
    write_dataset(
        contact_summary(out / "simulations", discard=design.discard, registry=registry),
        out / "contact.nc",
    )


def _write_timing(out: Path, outcome: Outcome, workers: int | None) -> None:
    """``timing.json``: this invocation's wall seconds per step and in all, and the peak
    resident memory of this process and of its largest worker process (MiB)."""
    import datetime
    import resource

    from softcell._version import __version__
    from softcell.io.files import atomic_write

    mib = 1024.0  # ru_maxrss is in KiB on Linux
    timing = {
        "version": __version__,
        "date": datetime.date.today().isoformat(),
        "cores": workers,
        "design": outcome.design.name,
        "steps": {k: round(v, 1) for k, v in outcome.steps.items()},
        "total": round(sum(outcome.steps.values()), 1),
        # The video pipeline, in its own process from the analysis on (within the steps).
        "beside": ({} if outcome.video_alone is None else {"video": round(outcome.video_alone, 1)}),
        "peak_rss_mib": {
            "this_process": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / mib),
            "largest_worker": round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / mib),
        },
    }
    with atomic_write(out / TIMING) as tmp:
        tmp.write_text(json.dumps(timing, indent=1) + "\n", encoding="utf-8")


class _Timer:
    def __init__(self, steps: dict[str, float], name: str) -> None:
        self.steps, self.name = steps, name

    def __enter__(self) -> _Timer:
        self.start = time.perf_counter()
        return self

    def __exit__(self, *exc: object) -> None:
        self.steps[self.name] = time.perf_counter() - self.start
