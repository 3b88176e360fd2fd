"""A simulated realization filmed and tracked in memory: what a camera and the tracker make of
it, without a video file between them.

:func:`filmed` draws the frames :func:`~softcell.video.render.render` would write, and gives
each to the :class:`~softcell.video.tracker.Tracker` as :func:`~softcell.video.track.track`
would read it back: the tracked Dataset is the same (a lossless film decodes to the frames
drawn), and neither the encoding nor the disk is paid. A fit to tracked films simulates its
design this way, so that its statistics carry the camera's and the tracker's errors as the
data's do.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from softcell.errors import SoftcellError


@dataclass(frozen=True)
class Camera:
    """How a film is made: the scale, the frame rate and the image's defects.

    Attributes
    ----------
    px_per_cm : float
        Scale (px/cm).
    fps : float
        Frame rate (1/s).
    noise : float
        Gaussian noise (grey levels).
    blur : float
        Gaussian blur (px).
    """

    px_per_cm: float = 10.0
    fps: float = 30.0
    noise: float = 2.0
    blur: float = 1.0

    def __post_init__(self) -> None:
        for name, unit, low in (("px_per_cm", "px/cm", None), ("fps", "1/s", None),
                                ("noise", "grey levels", 0.0), ("blur", "px", 0.0)):  # fmt: skip
            value = getattr(self, name)
            if not (np.isfinite(value) and (value > 0 if low is None else value >= low)):
                bound = "> 0" if low is None else ">= 0"
                raise SoftcellError(
                    f"camera {name} = {value!r} is not allowed: must be {bound} {unit}"
                )


def filmed(
    ds: xr.Dataset,
    *,
    camera: Camera,
    start: float,
    end: float,
    seed: int,
    realization: int = 0,
    point: dict[str, int] | None = None,
    radius: float | None = None,
    nodes: int = 64,
    piece: float | None = None,
) -> xr.Dataset:
    """Film one realization from ``start`` to ``end`` (s) and track the film, in memory.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation Dataset.
    camera : Camera
        Scale, frame rate, noise and blur.
    start, end : float
        The filmed span (s of the simulation); the tracked clock starts at 0 at ``start``.
    seed : int
        Seed of the camera's noise (0 .. 2**64 - 1).
    realization, point
        Which realization, and for a sweep which point (e.g. ``{"radius": 1}``).
    radius : float, optional
        The membrane's radius R (cm) the tracker expects (default: learned from the film).
    nodes : int
        Membrane points of the tracked contour.
    piece : float, optional
        Film in pieces of about this many seconds, each framed on the region the cell
        visits during it and tracked from its first frame, their noise drawn from
        ``SeedSequence(seed, spawn_key=(k,))`` for piece k: a camera that follows the cell.
        A long film's frame covers all the cell visits, and its pixels are the cost; in
        pieces of 30 s a 120 s film at R = 5 cm took 38 s instead of 62 s. Default: one piece, the
        film :func:`~softcell.video.render.render` writes.

    Returns
    -------
    xarray.Dataset
        The tracked realization (origin ``tracking``), as :func:`softcell.video.track.track`
        returns it for the film :func:`softcell.video.render.render` would write (in one
        piece); its ``softcell_video`` attribute says how it was made.

    Raises
    ------
    SoftcellError
        For a span outside the record, a bad camera, or a film in which no frame was tracked.
    """
    from softcell.video.render import frame_count
    from softcell.video.tracker import FLAGS, TrackResult, tracked_dataset

    count = frame_count(start, end, camera.fps)
    size = count if piece is None else max(2, int(round(piece * camera.fps)))
    pieces = np.array_split(np.arange(count), max(1, count // size))
    result = TrackResult()
    for k, frames in enumerate(pieces):
        noise_seed = seed if len(pieces) == 1 else _piece_seed(seed, k)
        first, last = start + frames[0] / camera.fps, start + frames[-1] / camera.fps
        part = _tracked_piece(
            ds, camera, first, last, noise_seed, realization, point, radius, nodes
        )
        result.times.extend(t + frames[0] / camera.fps for t in part.times)
        for name in ("cell", "bot", "membrane", "flags", "marked", "reasons"):
            getattr(result, name).extend(getattr(part, name))
    if all(f == FLAGS["both_lost"] for f in result.flags):
        raise SoftcellError(
            f"no frame of the film of realization {realization} ({start:g} .. {end:g} s) was "
            "tracked"
        )
    return tracked_dataset(
        result,
        nodes=nodes,
        radius=radius,
        attrs={
            "softcell_video": film_label(camera, start, end, seed, piece),
            "softcell_fps": float(camera.fps),
            "softcell_px_per_cm": float(camera.px_per_cm),
        },
    )


def _piece_seed(seed: int, k: int) -> int:
    """The noise seed of piece ``k`` of a film of noise seed ``seed``."""
    state = np.random.SeedSequence(seed, spawn_key=(k,)).generate_state(1, dtype=np.uint64)
    return int(state[0])


def _tracked_piece(ds, camera, start, end, seed, realization, point, radius, nodes):
    """The TrackResult of one piece of film, its clock starting at 0 at ``start``."""
    from softcell.video.render import Film
    from softcell.video.track import track_frames
    from softcell.video.tracker import Tracker

    film = Film(
        ds,
        realization=realization,
        point=point,
        px_per_cm=camera.px_per_cm,
        fps=camera.fps,
        start=start,
        end=end,
    )
    tracker = Tracker(film.frame, nodes, radius=radius)
    images = film.images(noise=camera.noise, blur=camera.blur, seed=seed)
    return track_frames(images, tracker, camera.fps, film.times.size, False, None)


def film_label(
    camera: Camera, start: float, end: float, seed: int, piece: float | None = None
) -> str:
    """How a film was made, as its tracked Dataset's ``softcell_video`` attribute says: the
    camera, the span (s), the noise's seed and the pieces' length (s; None: one piece)."""
    made = {**asdict(camera), "start": float(start), "end": float(end), "seed": int(seed)}
    if piece is not None:
        made["piece"] = float(piece)
    return f"filmed in memory: {json.dumps(made)}"
