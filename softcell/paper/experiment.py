"""The experimental pipeline: a simulated realization filmed, tracked and analysed as the paper
analyses its experiments, beside the simulation's own analysis of the same span."""

from __future__ import annotations

import json
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from softcell.analysis import analyze
from softcell.errors import AnalysisWarning, SoftcellError
from softcell.io.netcdf import read_dataset, write_dataset
from softcell.video.render import render
from softcell.video.track import track

#: spawn_key of the camera-noise stream of the rendered video (no parameter point uses it).
VIDEO_STREAM = 2**32 - 1


@dataclass(frozen=True)
class VideoDesign:
    """The experimental pipeline: which realization is filmed, how, and for how long."""

    radius: float = 12.0  # cm; realization 0 of this radius
    span: float = 60.0  # s of film, from the end of the discard
    px_per_cm: float = 10.0
    fps: float = 30.0  # the paper's camera
    noise: float = 2.0  # grey levels
    blur: float = 1.0  # px


def experimental_pipeline(
    simulation: Path,
    folder: Path,
    video: VideoDesign,
    *,
    discard: float,
    seed: int,
    progress: bool = False,
    keep_film: bool = False,
) -> dict[str, Any]:
    """Film the simulation file ``simulation`` from ``discard`` s on, track the film, and
    analyse it as the paper analyses experiments (threshold 0.3 cm/s), beside the simulation's
    own analysis of the same span (at the simulations' 0.03 cm/s and at 0.3 cm/s).

    Writes, in ``folder``: ``tracked.nc``, ``tracked_analysis.nc``,
    ``simulated_analysis.nc`` (threshold 0.03) and ``simulated_analysis_0.3.nc``; the film
    ``cell.mkv`` only with ``keep_film``. The camera noise draws from
    ``SeedSequence(seed, spawn_key=(VIDEO_STREAM,))``. Returns the render's frame geometry,
    the tracking summary and notes.
    """

    v = video
    folder.mkdir(exist_ok=True)
    simulated = read_dataset(simulation)
    start, end = discard, discard + v.span
    last = float(simulated["time"].values[-1])
    if end > last:
        raise SoftcellError(
            f"the video span [{start:g}, {end:g}] s exceeds the record (0 .. {last:g} s)"
        )
    noise_seed = int(np.random.SeedSequence(seed, spawn_key=(VIDEO_STREAM,)).generate_state(1)[0])
    movie = folder / "cell.mkv"
    info = render(
        simulated,
        movie,
        px_per_cm=v.px_per_cm,
        fps=v.fps,
        start=start,
        end=end,
        noise=v.noise,
        blur=v.blur,
        seed=noise_seed,
        progress=progress,
    )
    frame = info.frame
    tracked = track(
        movie,
        px_per_cm=v.px_per_cm,
        origin=(frame.x0, frame.y0),
        fps=v.fps,
        radius=v.radius,
        progress=progress,
    )
    size_mb = movie.stat().st_size / 1e6
    if not keep_film:
        movie.unlink()  # lossless and noisy: hundreds of MB, remade byte for byte on demand
    notes = [
        *info.notes,
        f"the film ({size_mb:.0f} MB, lossless FFV1) was "
        + ("kept as video/cell.mkv" if keep_film else "deleted after tracking")
        + f"; `softcell render {simulation} -o cell.mkv --px-per-cm {v.px_per_cm:g} "
        f"--fps {v.fps:g} --start {start:g} --end {end:g} --noise {v.noise:g} --blur "
        f"{v.blur:g} --seed {noise_seed}` remakes it",
    ]
    write_dataset(tracked, folder / "tracked.nc")
    with warnings.catch_warnings():
        # One film is one realization: its errors are NaN, as their attributes say.
        warnings.filterwarnings("ignore", "1 independent realization", AnalysisWarning)
        write_dataset(analyze(tracked, {"discard": 0.0}), folder / "tracked_analysis.nc")
        span = _filmed_span(simulated, start, end)
        write_dataset(analyze(span, {"discard": 0.0}), folder / "simulated_analysis.nc")
        write_dataset(
            analyze(span, {"discard": 0.0, "threshold": 0.3}),
            folder / "simulated_analysis_0.3.nc",
        )
    return {
        "radius": v.radius,
        "span": [start, end],
        "noise_seed": noise_seed,
        "design": asdict(v),
        "frames": int(info.times.size),
        "size_px": [frame.width, frame.height],
        "tracking_summary": json.loads(tracked.attrs["softcell_tracking_summary"]),
        "source": str(simulation),
        "notes": notes,
    }


def _filmed_span(simulated: xr.Dataset, start: float, end: float) -> xr.Dataset:
    """The simulation from ``start`` to ``end`` (s), its clock (and its fine record's)
    restarted at 0, as the film sees it."""
    cut = {"time": slice(start - 1e-9, end + 1e-9)}
    if "fine_time" in simulated.dims:
        cut["fine_time"] = slice(start - 1e-9, end + 1e-9)
    span = simulated.sel(cut)
    t0 = float(span["time"].values[0])
    span = span.assign_coords(time=span["time"] - t0)
    span["time"].attrs.update(simulated["time"].attrs)
    if "fine_time" in span.dims:
        span = span.assign_coords(fine_time=span["fine_time"] - t0)
        span["fine_time"].attrs.update(simulated["fine_time"].attrs)
    return span
