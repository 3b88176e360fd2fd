"""How a fit measures its simulations: as they are, or filmed and tracked as the data were.

Data and simulations must be reduced alike. Simulation data are compared with the
simulations' own records (:class:`Direct`). Tracked films carry what the camera and the
tracker make of a cell (a tracked contour is rougher than the membrane, so its shape index
is larger; frame-to-frame jitter adds to the speed): the fit films every simulated
realization with the same camera and tracks it with the same tracker, in memory
(:func:`softcell.video.film.filmed`), over the span of the film it stands for, after a warm-up
(:class:`Filmed`). Each design film is a file beside its simulation's folder
(``pointNNNN_films/``), so that an interrupted fit resumes.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from softcell.errors import ConfigError, SoftcellError
from softcell.model.configuration import RunConfig
from softcell.video.film import Camera, film_label

#: The spawn key of the design films' camera noise under the fit's root seed.
FILM_KEY = 7_004
#: Seconds simulated before a design film starts, unless told otherwise.
WARMUP = 15.0
#: Seconds of a design film framed at a time: a camera that follows the cell (a 120 s film
#: at R = 5 cm: 38 s of one core, against 62 s framed on its whole path).
PIECE = 30.0
_NAME = re.compile(r"point(\d+)_realization(\d+)\.nc$")


@dataclass(frozen=True)
class Direct:
    """The simulations' statistics from their own records, analysed with ``options``."""

    options: dict[str, Any] = field(default_factory=dict)

    def statistics(
        self, folders: Sequence[Path], statistics: Sequence[str], **_: Any
    ) -> np.ndarray:
        """float64[design point, point, realization, statistic] of each folder's
        simulations."""
        from softcell.fit.design import statistics_of

        return statistics_of(folders, statistics, self.options)

    def describe(self) -> str:
        return "the simulations' records"


@dataclass(frozen=True)
class Filmed:
    """Each simulated realization filmed and tracked as the data's films were made.

    Attributes
    ----------
    camera : Camera
        Scale, frame rate, noise and blur of the design's films.
    spans : numpy.ndarray
        float64[point, realization]: each data film's length (s); realization r of point p
        of every design point is filmed for as long.
    radii : tuple of float
        Each point's membrane radius (cm), which the tracker expects.
    warmup : float
        Seconds simulated before the film starts.
    options : dict
        Analysis options of films and data alike.
    piece : float, optional
        Seconds of film framed at a time (:func:`softcell.video.film.filmed`; None: one
        frame for the whole film).
    """

    camera: Camera
    spans: np.ndarray
    radii: tuple[float, ...]
    warmup: float = WARMUP
    options: dict[str, Any] = field(default_factory=dict)
    piece: float | None = PIECE

    def statistics(
        self,
        folders: Sequence[Path],
        statistics: Sequence[str],
        *,
        seed: int | Sequence[int],
        workers: int | None = None,
        scheduler: str | None = None,
        progress: bool = True,
        log: Callable[[str], None] | None = None,
        **_: Any,
    ) -> np.ndarray:
        """Film every realization of ``folders`` (those already filmed for this design are
        kept), the camera's noise drawn from the fit's root ``seed`` (or one per folder),
        and return float64[design point, point, realization, statistic] of the films."""
        from softcell.analysis import analyze
        from softcell.fit.statistics import observed
        from softcell.io.netcdf import open_inputs

        jobs, films = [], []
        seeds = [seed] * len(folders) if isinstance(seed, int) else list(seed)
        for folder, root in zip(folders, seeds, strict=True):
            mine = []
            for simulation in sorted(Path(folder).glob("point*_realization*.nc")):
                point, realization = (int(g) for g in _NAME.search(simulation.name).groups())
                if not np.isfinite(self.spans[point, realization]):
                    continue  # the data have no such film (fewer at this radius)
                target = Path(f"{folder}_films") / simulation.name
                made = self.made(point, realization, root)
                mine.append(target)
                if not _done(target, film_label(self.camera, **made, piece=self.piece)):
                    job = (simulation, target, self.camera, made, self.radii[point], self.piece)
                    jobs.append(job)
            films.append(mine)
        if jobs:
            if log:
                log(f"filming and tracking {len(jobs)} realizations")
            _run(jobs, workers=workers, scheduler=scheduler, progress=progress)
        each = [
            observed(analyze(open_inputs(mine), self.options), statistics).each for mine in films
        ]
        return np.stack(each)

    def made(self, point: int, realization: int, seed: int) -> dict[str, Any]:
        """How realization ``realization`` of ``point`` is filmed: the span (s of the
        simulation) and the noise's seed (``SeedSequence(seed, spawn_key=(FILM_KEY, point,
        realization))``, the same at every design point)."""
        state = np.random.SeedSequence(seed, spawn_key=(FILM_KEY, point, realization))
        return {
            "start": self.warmup,
            "end": self.warmup + float(self.spans[point, realization]),
            "seed": int(state.generate_state(1, dtype=np.uint64)[0]),
        }

    def describe(self) -> str:
        c = self.camera
        return (
            f"filmed ({c.px_per_cm:g} px/cm, {c.fps:g} frames/s, noise {c.noise:g}, blur "
            f"{c.blur:g} px) after {self.warmup:g} s and tracked"
        )


def _done(target: Path, label: str) -> bool:
    """Whether ``target`` is a film made as ``label`` says (a design's film, resumed)."""
    if not target.exists():
        return False
    import netCDF4

    try:
        with netCDF4.Dataset(target) as nc:
            return getattr(nc, "softcell_video", "") == label
    except OSError:
        return False


def film_one(
    simulation: Path,
    target: Path,
    camera: Camera,
    made: dict[str, Any],
    radius: float,
    piece: float | None,
) -> str:
    """Film and track one simulated realization as ``made`` says (``start``, ``end`` in s,
    the noise's ``seed``) into ``target``."""
    from softcell.io.netcdf import read_dataset, write_dataset
    from softcell.video.film import filmed

    ds = read_dataset(simulation)
    tracked = filmed(ds, camera=camera, radius=radius, piece=piece, **made)
    target.parent.mkdir(parents=True, exist_ok=True)
    write_dataset(tracked, target)
    return str(target)


def _run(jobs: list, *, workers: int | None, scheduler: str | None, progress: bool) -> None:
    """Run :func:`film_one` for every job: here, or on a local cluster / a scheduler."""
    from softcell.runner.cluster import cluster_client
    from softcell.runner.points import worker_count
    from softcell.settings import progress_bar_class

    tqdm = progress_bar_class()
    workers = worker_count(workers, scheduler)
    with tqdm(total=len(jobs), disable=not progress, desc="film", unit="film") as bar:
        if scheduler is None and (workers or 1) == 1:
            for job in jobs:
                film_one(*job)
                bar.update(1)
            return
        from distributed import as_completed

        with cluster_client(workers or 1, scheduler) as client:
            futures = [client.submit(film_one, *job, pure=False) for job in jobs]
            for future in as_completed(futures):
                future.result()
                bar.update(1)


def film_request(
    ds,
    config: RunConfig | None,
    *,
    camera: Camera | Mapping[str, float] | None,
    warmup: float,
    options: dict,
) -> tuple[RunConfig, Filmed]:
    """The design that tracked films ask for, and how its simulations are measured.

    The model and components are ``config``'s (default: softcell's); the films give the
    radius of each point, their lengths and frame rate, and (for a film tracked on a linear
    scale) the camera's scale. Each simulation runs ``warmup`` s and then the longest film,
    recorded at the frame rate. ``camera`` is a :class:`Camera`, or some of its fields
    (``px_per_cm``, ``noise``, ``blur``) over the default: the films' scale and frame rate,
    noise 2 grey levels, blur 1 px.

    Raises
    ------
    ConfigError
        For a film whose scale is unknown (a camera calibrated from the plate) and none
        given, a bad camera, or a bad warm-up.
    """
    if not (np.isfinite(warmup) and warmup >= 0):
        raise ConfigError(f"warmup = {warmup!r} is not allowed: must be >= 0 s")
    fps = float(ds.attrs["softcell_fps"])
    given = dict(asdict(camera) if isinstance(camera, Camera) else camera or {})
    unknown = set(given) - {"px_per_cm", "fps", "noise", "blur"}
    if unknown:
        raise ConfigError(f"camera {sorted(unknown)[0]!r} is not a camera setting")
    if "px_per_cm" not in given:
        if "softcell_px_per_cm" not in ds.attrs:
            raise ConfigError(
                "the films were tracked through a camera calibrated from the plate: give the "
                "scale of the fit's own films (--camera-scale PX_PER_CM)"
            )
        given["px_per_cm"] = float(ds.attrs["softcell_px_per_cm"])
    try:
        camera = Camera(**{**given, "fps": fps})
    except SoftcellError as exc:
        raise ConfigError(str(exc)) from None
    spans = _spans(ds)
    parameters = json.loads(ds.attrs["softcell_parameters"])
    radius = parameters["radius"]
    radii = tuple(float(r) for r in (radius if isinstance(radius, list) else [radius]))
    base = config or RunConfig()
    if "radius" in base.parameters or "duration" in base.parameters:
        raise ConfigError(
            "the films set the radius and the duration of the fit's simulations: leave them "
            "out of the configuration"
        )
    step = 1.0 / fps
    base = base.updated(
        parameters={
            "radius": list(radii) if len(radii) > 1 else radii[0],
            "duration": warmup + float(np.nanmax(spans)) + 2 * step,
            "sample_every": step,
            "sample_every_late": step,
        }
    )
    return base, Filmed(camera, spans, radii, warmup, dict(options))


def _spans(ds) -> np.ndarray:
    """float64[point, realization]: each film's length (s), its last frame's time (NaN for a
    film that a point lacks)."""
    flag = ds["tracking_flag"].transpose(..., "realization", "time")
    shown = np.isfinite(np.asarray(flag.values, dtype=np.float64))
    shown = shown.reshape(-1, *shown.shape[-2:])
    time = np.asarray(ds["time"].values, dtype=np.float64)
    last = np.where(shown, time, -np.inf).max(axis=-1)
    return np.where(np.isfinite(last), last, np.nan)
