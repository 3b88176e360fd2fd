"""Video files: the codec for a file name, frames read on a second core, frames counted.

Rendering a movie is ``softcell.io.render``; the tracker, a pure function of images, is
``softcell.core.tracking``; :func:`track` reads a file through it.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import cv2
import numpy as np
import xarray as xr

from softcell.core.tracking import (
    FLAGS,
    MAX_TRACKED_NODES,
    Frame,
    Tracker,
    TrackResult,
    tracked_dataset,
)
from softcell.errors import SoftcellError


def codec(path: Path) -> str:
    """Lossless FFV1 for .mkv / .avi (what a round trip needs), MPEG-4 for .mp4."""
    suffix = path.suffix.lower()
    if suffix in (".mkv", ".avi"):
        return "FFV1"
    if suffix == ".mp4":
        return "mp4v"
    raise SoftcellError(f"video file {path} must end in .mkv or .avi (lossless) or .mp4")

def count_frames(path: str | os.PathLike[str]) -> int:
    """Frames a finished video file holds, read back: the container's count, trusted only if
    its last frame can be seeked to and decoded and nothing follows it (0 for a file that
    does not open)."""
    capture = cv2.VideoCapture(str(path))
    try:
        if not capture.isOpened():
            return 0
        stated = capture.get(cv2.CAP_PROP_FRAME_COUNT)
        if not (np.isfinite(stated) and 0 < stated < 2**31):
            return 0
        stated = int(round(stated))
        capture.set(cv2.CAP_PROP_POS_FRAMES, stated - 1)
        if not capture.read()[0] or int(capture.get(cv2.CAP_PROP_POS_FRAMES)) != stated:
            return 0
        return stated if not capture.grab() else stated + 1
    finally:
        capture.release()

def _read_ahead(capture: cv2.VideoCapture, depth: int = 8) -> Iterator[np.ndarray]:
    """Frames of ``capture`` decoded by a background thread (OpenCV releases the GIL), at
    most ``depth`` ahead of the consumer: decoding overlaps tracking on a second core."""
    frames: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def reader() -> None:
        while not stop.is_set():
            ok, image = capture.read()
            while not stop.is_set():
                try:
                    frames.put(image if ok else None, timeout=0.1)
                    break
                except queue.Full:
                    continue
            if not ok:
                return

    thread = threading.Thread(target=reader, daemon=True)
    thread.start()
    try:
        while (image := frames.get()) is not None:
            yield image
    finally:
        stop.set()
        thread.join()

def track(video: str | os.PathLike[str], *, px_per_cm: float | None = None,
          arena_size: float | None = None, origin: tuple[float, float] = (0.0, 0.0),
          fps: float | None = None, nodes: int = 64, radius: float | None = None,
          progress: bool = False, on_frame: Callable[[int], None] | None = None
          ) -> xr.Dataset:
    """Track a top-view video into the simulation schema (origin ``tracking``).

    Parameters
    ----------
    video : path-like
        Any file OpenCV reads. Frames are read one at a time (never all in memory).
    px_per_cm : float, optional
        Scale; or give ``arena_size`` (cm), the world width of the frame.
    origin : (float, float)
        World position (cm) of the frame's lower-left corner.
    fps : float, optional
        Frame rate (1/s); default: the container's.
    nodes : int
        Membrane points, resampled by arclength.
    radius : float, optional
        The membrane's radius R (cm), stored as a parameter for the analysis; default
        estimated as the mean tracked perimeter over 2 pi.
    progress : bool
        Show a progress bar.
    on_frame : callable, optional
        Called with the number of frames tracked so far, after each frame.

    Returns
    -------
    xarray.Dataset
        The schema's variables (NaN where detection failed) plus ``tracking_flag``; failures
        are counted in the ``softcell_tracking_summary`` attribute.

    Raises
    ------
    SoftcellError
        For a bad argument, a missing, empty or unreadable file, or no calibration.
    """
    video = Path(video)
    _check_track_arguments(video, px_per_cm, arena_size, origin, fps, nodes, radius)
    capture = cv2.VideoCapture(str(video))
    try:
        if not capture.isOpened():
            raise SoftcellError(f"cannot read video file {video} (corrupt or unknown format)")
        width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH))
        height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))
        rate = float(fps or capture.get(cv2.CAP_PROP_FPS) or 0.0)
        if not (np.isfinite(rate) and rate > 0):
            raise SoftcellError(f"video file {video} states no frame rate: pass fps")
        if px_per_cm is None:
            if arena_size is None:
                raise SoftcellError("pass px_per_cm, or arena_size (cm) to derive it")
            px_per_cm = width / arena_size
        if not px_per_cm > 0:
            raise SoftcellError(f"px_per_cm = {px_per_cm} is not allowed: must be > 0")
        frame = Frame(float(px_per_cm), width, height, float(origin[0]), float(origin[1]))
        total = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) or None
        result = _track_frames(_read_ahead(capture), Tracker(frame, nodes), rate, total,
                               progress, on_frame)
    finally:
        capture.release()
    if not result.times:
        raise SoftcellError(f"video file {video} has no readable frame (corrupt or empty)")
    if all(f == FLAGS["both_lost"] for f in result.flags):
        raise SoftcellError(f"no frame of {video} was tracked: no red ring found in any of its "
                            f"{len(result.flags)} frames")
    return tracked_dataset(result, nodes=nodes, radius=radius, attrs={
        "softcell_video": video.name, "softcell_px_per_cm": float(px_per_cm),
        "softcell_fps": rate, "softcell_origin_cm": np.array(origin, dtype=np.float64)})


def _check_track_arguments(video: Path, px_per_cm, arena_size, origin, fps, nodes: int,
                           radius) -> None:
    if nodes < 3 or nodes > MAX_TRACKED_NODES:
        raise SoftcellError(f"nodes = {nodes} is not allowed: must be an integer between 3 "
                            f"and {MAX_TRACKED_NODES}")
    for name, value, unit in (("px_per_cm", px_per_cm, "px/cm"), ("arena_size", arena_size, "cm"),
                              ("fps", fps, "1/s"), ("radius", radius, "cm")):
        if value is not None and not (np.isfinite(value) and value > 0):
            raise SoftcellError(f"{name} = {value} is not allowed: must be finite and > 0 "
                                f"{unit}")
    if px_per_cm is not None and arena_size is not None:
        raise SoftcellError("px_per_cm and arena_size both set the scale: give one")
    if len(origin) != 2 or not np.isfinite(origin).all():
        raise SoftcellError(f"origin = {tuple(origin)} is not allowed: must be two finite "
                            "coordinates X,Y in cm")
    if not video.is_file():
        raise SoftcellError(f"no such video file: {video}")
    if video.stat().st_size == 0:
        raise SoftcellError(f"video file {video} is empty")


def _track_frames(frames: Iterator[np.ndarray], tracker: Tracker, rate: float,
                  total: int | None, progress: bool,
                  on_frame: Callable[[int], None] | None) -> TrackResult:
    """Run the tracker over every frame; frame k is at time k / rate (s)."""
    from tqdm.auto import tqdm

    result = TrackResult()
    with tqdm(total=total, disable=not progress, desc="track", unit="frame") as bar:
        for index, image in enumerate(frames):
            flag, gc, membrane, bot = tracker.track(image)
            result.times.append(index / rate)
            result.cell.append(gc)
            result.membrane.append(membrane)
            result.bot.append(bot)
            result.flags.append(flag)
            result.marked.append(tracker.mark_seen and np.isfinite(bot[2]))
            bar.update(1)
            if on_frame:
                on_frame(index + 1)
    return result
