"""Video files: the codec for a file name, frames read on a second core, frames counted.

Rendering a movie is ``softcell.video.render``; the tracker, a pure function of images, is
``softcell.video.tracker``; :func:`track` reads a file through it.
"""

from __future__ import annotations

import collections
import itertools
import json
import math
import os
import queue
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np
import xarray as xr

from softcell.errors import SoftcellError
from softcell.io.files import atomic_write, no_input
from softcell.video.animate import ANIMATION_MARK
from softcell.video.calibration import CalibrationError, calibrate_from_plate
from softcell.video.tracker import (
    DARK_FRACTION,
    FLAGS,
    MAX_TRACKED_NODES,
    RING_COLORS,
    Frame,
    Tracker,
    TrackResult,
    tracked_dataset,
)


def codec(path: Path) -> str:
    """Lossless FFV1 for .mkv / .avi (what a round trip needs), MPEG-4 for .mp4."""
    suffix = path.suffix.lower()
    if suffix in (".mkv", ".avi"):
        return "FFV1"
    if suffix == ".mp4":
        return "mp4v"
    raise SoftcellError(f"video file {path} must end in .mkv or .avi (lossless) or .mp4")


def _check_film(path: Path) -> None:
    """Refuse what is no film of a cell: a GIF (256 colours, frame times in hundredths of a
    second) and a movie that ``softcell animate`` made (its panels are drawings of a
    simulation; it says so in its metadata)."""
    if path.suffix.lower() == ".gif":
        raise SoftcellError(
            f"{path} is a GIF: an animation format (256 colours, frame times in hundredths of "
            "a second), not a film to track; track the camera's video, or one that softcell "
            "render made (.mkv, .avi, .mp4)"
        )
    try:
        import av

        with av.open(str(path)) as container:
            comment = str(container.metadata.get("comment", ""))
    except Exception:  # unreadable here: OpenCV's reader says why below
        return
    if comment.startswith(ANIMATION_MARK):
        raise SoftcellError(
            f"{path} is an animation of a simulation ({comment}), not a film to track; "
            "film a realization with softcell render, then track that"
        )


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


def track(
    video: str | os.PathLike[str],
    *,
    px_per_cm: float | None = None,
    arena_size: float | None = None,
    origin: tuple[float, float] = (0.0, 0.0),
    plate_size: float | None = None,
    camera: str | os.PathLike[str] | None = None,
    camera_height: float | None = None,
    ring_height: float = 0.0,
    bot_height: float = 0.0,
    ring_color: str = "red",
    ring_threshold: float | None = None,
    dark_fraction: float = DARK_FRACTION,
    fps: float | None = None,
    nodes: int = 64,
    radius: float | None = None,
    overlay: str | os.PathLike[str] | None = None,
    progress: bool = False,
    on_frame: Callable[[int], None] | None = None,
) -> xr.Dataset:
    """Track a top-view video into the simulation schema (origin ``tracking``).

    Two geometries: a linear frame (``px_per_cm`` or ``arena_size``, and ``origin``: a camera
    exactly above, no lens distortion), or a camera calibrated from the plate seen in the
    first frame (``plate_size``: perspective, radial distortion and parallax, see
    ``softcell.video.calibration``; plate coordinates, origin at the plate corner seen at the
    lower left).

    Parameters
    ----------
    video : path-like
        Any file OpenCV reads. Frames are read one at a time (never all in memory).
    px_per_cm : float, optional
        Scale (px/cm); or give ``arena_size``.
    arena_size : float, optional
        World width (cm) of the frame, instead of ``px_per_cm``.
    origin : (float, float)
        World position (cm) of the frame's lower-left corner (linear frame only).
    plate_size : float, optional
        Side (cm) of the square plate, wholly in view: calibrate the camera from it.
    camera : path-like, optional
        OpenCV calibration file (``camera_matrix``, ``distortion_coefficients``), with
        ``plate_size``: its lens model replaces the one estimated from the plate's edges.
    camera_height : float, optional
        Height (cm) of the camera above the plate, for parallax (default: from the
        calibration file, or estimated from the plate when the camera is tilted enough).
    ring_height, bot_height : float
        Heights (cm) of the membrane's wall and of the bot: their outlines are mapped at half
        these heights (parallax), which needs ``plate_size``.
    ring_color : str
        The paper's colour: red (also orange), green, blue or yellow.
    ring_threshold : float, optional
        Colourfulness ((R - max(G, B)) / R for red) above which a pixel is paper (default:
        per frame).
    dark_fraction : float
        A pixel is bot when darker than this fraction of the plate inside the ring.
    fps : float, optional
        Frame rate (1/s); default: the container's.
    nodes : int
        Membrane points, resampled by arclength.
    radius : float, optional
        The membrane's radius R (cm): the expected perimeter 2 pi R for the plausibility
        check, and stored as a parameter for the analysis; default estimated as the mean
        tracked perimeter over 2 pi.
    overlay : path-like, optional
        Also write the frames with what was tracked drawn on them (.mkv/.avi/.mp4).
    progress : bool
        Show a progress bar.
    on_frame : callable, optional
        Called with the number of frames tracked so far, after each frame.

    Returns
    -------
    xarray.Dataset
        The schema's variables (NaN where detection failed) plus ``tracking_flag``; failures
        are counted in the ``softcell_tracking_summary`` attribute, by kind in
        ``softcell_tracking_failures``.

    Raises
    ------
    SoftcellError
        For a bad argument, a missing, empty or unreadable file, no calibration, or a plate
        not found.
    """
    video = Path(video)
    _check_film(Path(video))
    _check_track_arguments(video, px_per_cm, arena_size, origin, fps, nodes, radius)
    _check_camera_arguments(
        px_per_cm,
        arena_size,
        plate_size,
        camera,
        camera_height,
        ring_height,
        bot_height,
        ring_threshold,
        dark_fraction,
    )
    if ring_color not in RING_COLORS:
        raise SoftcellError(
            f"ring_color = {ring_color!r} is not allowed: one of {', '.join(RING_COLORS)}"
        )
    calibration = read_calibration(camera) if camera is not None else None
    capture = cv2.VideoCapture(str(video))
    frames = None
    try:
        if not capture.isOpened():
            raise SoftcellError(f"cannot read video file {video} (corrupt or unknown format)")
        width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH))
        height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))
        rate = float(fps or capture.get(cv2.CAP_PROP_FPS) or 0.0)
        if not (np.isfinite(rate) and rate > 0):
            raise SoftcellError(f"video file {video} states no frame rate: pass fps")
        frames = _read_ahead(capture)
        first = next(frames, None)
        if first is None:
            raise SoftcellError(f"video file {video} has no readable frame (corrupt or empty)")
        geometry, attrs = _geometry(
            first,
            width,
            height,
            plate_size=plate_size,
            camera_height=camera_height,
            calibration=calibration,
            ring_height=ring_height,
            bot_height=bot_height,
            px_per_cm=px_per_cm,
            arena_size=arena_size,
            origin=origin,
        )
        tracker = Tracker(
            geometry,
            nodes,
            ring_z=ring_height / 2,
            bot_z=bot_height / 2,
            radius=radius,
            ring_color=ring_color,
            ring_threshold=ring_threshold,
            dark_fraction=dark_fraction,
        )
        total = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) or None
        with _overlay_writer(overlay, rate, width, height) as draw:
            result = track_frames(
                itertools.chain([first], frames), tracker, rate, total, progress, on_frame, draw
            )
    finally:
        # The read-ahead thread stops before the capture is released, whatever went wrong:
        # releasing a capture another thread reads from deadlocks.
        if frames is not None:
            frames.close()
        capture.release()
    failures = _failures(result, video)
    return tracked_dataset(
        result,
        nodes=nodes,
        radius=radius,
        attrs={
            "softcell_video": video.name,
            "softcell_fps": rate,
            **attrs,
            "softcell_tracking_failures": json.dumps(dict(failures.most_common())),
        },
    )


def _geometry(
    first: np.ndarray,
    width: int,
    height: int,
    *,
    plate_size: float | None,
    camera_height: float | None,
    calibration: tuple[np.ndarray, np.ndarray] | None,
    ring_height: float,
    bot_height: float,
    px_per_cm: float | None,
    arena_size: float | None,
    origin: tuple[float, float],
) -> tuple[object, dict[str, object]]:
    """The pixels-to-cm geometry of a video (calibrated from the plate in its ``first``
    frame, or a linear frame) and the attributes that record it (lengths in cm)."""
    if plate_size is not None:
        geometry = calibrate_from_plate(
            first, plate_size, camera_height=camera_height, calibration=calibration
        )
        if ring_height or bot_height:
            geometry.to_world(0.0, 0.0, max(ring_height, bot_height) / 2)  # or says why
        return geometry, {
            "softcell_plate_size_cm": float(plate_size),
            "softcell_camera": json.dumps(geometry.summary()),
            "softcell_ring_height_cm": float(ring_height),
            "softcell_bot_height_cm": float(bot_height),
        }
    if px_per_cm is None:
        px_per_cm = width / arena_size  # one of them is given (_check_camera_arguments)
    geometry = Frame(float(px_per_cm), width, height, float(origin[0]), float(origin[1]))
    return geometry, {
        "softcell_px_per_cm": float(px_per_cm),
        "softcell_origin_cm": np.array(origin, dtype=np.float64),
    }


def _failures(result, video: Path) -> collections.Counter:
    """The tracking failures by kind; an error naming them when no frame was tracked."""
    failures = collections.Counter(r for r in result.reasons if r)
    if all(f == FLAGS["both_lost"] for f in result.flags):
        why = "; ".join(f"{n} x {reason}" for reason, n in failures.most_common())
        hint = (
            " (is the scale right? check --plate-size or --px-per-cm, and --radius)"
            if "perimeter" in why
            else ""
        )
        raise SoftcellError(
            f"no frame of {video} was tracked: no plausible ring found in any "
            f"of its {len(result.flags)} frames: {why}{hint}"
        )
    return failures


def _check_camera_arguments(
    px_per_cm,
    arena_size,
    plate_size,
    camera,
    camera_height,
    ring_height,
    bot_height,
    ring_threshold,
    dark_fraction,
) -> None:
    for name, value in (("plate_size", plate_size), ("camera_height", camera_height)):
        if value is not None and not (np.isfinite(value) and value > 0):
            raise SoftcellError(f"{name} = {value} is not allowed: must be finite and > 0 cm")
    for name, value in (("ring_height", ring_height), ("bot_height", bot_height)):
        if not (np.isfinite(value) and value >= 0):
            raise SoftcellError(f"{name} = {value} is not allowed: must be finite and >= 0 cm")
    if plate_size is not None and (px_per_cm is not None or arena_size is not None):
        raise SoftcellError(
            "plate_size calibrates the camera; px_per_cm and arena_size set a "
            "linear frame instead: give one of them"
        )
    if plate_size is None:
        if px_per_cm is None and arena_size is None:
            raise SoftcellError(
                "pass px_per_cm, arena_size (cm) to derive it, or "
                "plate_size (cm) to calibrate from the plate"
            )
        _check_without_plate(camera, camera_height, ring_height, bot_height)
    _check_detection_arguments(ring_threshold, dark_fraction)


def _check_without_plate(camera, camera_height, ring_height, bot_height) -> None:
    """Without a plate, nothing that needs a calibrated camera may be given."""
    for name, value in (
        ("camera", camera),
        ("camera_height", camera_height),
        ("ring_height", ring_height or None),
        ("bot_height", bot_height or None),
    ):
        if value is not None:
            raise SoftcellError(
                f"{name} needs plate_size: parallax and lenses are "
                "corrected only with a camera calibrated from the plate"
            )


def _check_detection_arguments(ring_threshold, dark_fraction) -> None:
    if ring_threshold is not None and not (np.isfinite(ring_threshold) and 0 < ring_threshold < 1):
        raise SoftcellError(
            f"ring_threshold = {ring_threshold} is not allowed: a redness "
            "(R - max(G, B)) / R between 0 and 1"
        )
    if not (np.isfinite(dark_fraction) and 0 < dark_fraction < 1):
        raise SoftcellError(
            f"dark_fraction = {dark_fraction} is not allowed: must be between "
            "0 and 1 (of the plate's grey level)"
        )


def _check_track_arguments(
    video: Path, px_per_cm, arena_size, origin, fps, nodes: int, radius
) -> None:
    if nodes < 3 or nodes > MAX_TRACKED_NODES:
        raise SoftcellError(
            f"nodes = {nodes} is not allowed: must be an integer between 3 and {MAX_TRACKED_NODES}"
        )
    for name, value, unit in (
        ("px_per_cm", px_per_cm, "px/cm"),
        ("arena_size", arena_size, "cm"),
        ("fps", fps, "1/s"),
        ("radius", radius, "cm"),
    ):
        if value is not None and not (np.isfinite(value) and value > 0):
            raise SoftcellError(f"{name} = {value} is not allowed: must be finite and > 0 {unit}")
    if px_per_cm is not None and arena_size is not None:
        raise SoftcellError("px_per_cm and arena_size both set the scale: give one")
    if len(origin) != 2 or not np.isfinite(origin).all():
        raise SoftcellError(
            f"origin = {tuple(origin)} is not allowed: must be two finite coordinates X,Y in cm"
        )
    if not video.is_file():
        raise no_input(video, "video file")
    if video.stat().st_size == 0:
        raise SoftcellError(f"video file {video} is empty")


def track_frames(
    frames: Iterator[np.ndarray],
    tracker: Tracker,
    rate: float,
    total: int | None,
    progress: bool,
    on_frame: Callable[[int], None] | None,
    draw: Callable[[np.ndarray, Tracker, tuple], None] | None = None,
) -> TrackResult:
    """Run the tracker over every frame; frame k is at time k / rate (s)."""
    from softcell.settings import progress_bar_class

    tqdm = progress_bar_class()

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
            result.reasons.append(tracker.reason)
            if draw:
                draw(image, tracker, (index / rate, flag, gc, membrane, bot))
            bar.update(1)
            if on_frame:
                on_frame(index + 1)
    return result


@contextmanager
def _overlay_writer(
    path: str | os.PathLike[str] | None, rate: float, width: int, height: int
) -> Iterator[Callable[[np.ndarray, Tracker, tuple], None] | None]:
    """A function that draws one tracked frame into the overlay movie at ``path`` (written
    atomically), or None without a path."""
    if path is None:
        yield None
        return
    path = Path(path)
    fourcc = cv2.VideoWriter_fourcc(*codec(path))
    with atomic_write(path) as tmp:
        writer = cv2.VideoWriter(str(tmp), fourcc, rate, (width, height))
        if not writer.isOpened():
            raise SoftcellError(f"cannot write the overlay video {path}")
        try:
            yield lambda image, tracker, state: writer.write(draw_overlay(image, tracker, *state))
        finally:
            writer.release()


def draw_overlay(
    image: np.ndarray, tracker: Tracker, time: float, flag: int, gc, membrane, bot
) -> np.ndarray:
    """One frame with what was tracked drawn on it: the membrane's midline (green), its GC
    (a cross), the bot's outline (yellow) and heading (an arrow of 3 cm), or the reason a
    frame was lost (red text)."""
    out = image.copy()
    geometry, scale = tracker.frame, 16  # drawing at 1/16 px
    thick = max(1, image.shape[1] // 640)
    if np.isfinite(gc[0]):
        u, v = geometry.to_pixels(membrane[:, 0], membrane[:, 1], tracker.ring_z)
        pts = np.rint(np.stack([u, v], axis=1) * scale).astype(np.int32)
        cv2.polylines(out, [pts], True, (60, 220, 60), thick, cv2.LINE_AA, 4)
        gu, gv = geometry.to_pixels(np.array([gc[0]]), np.array([gc[1]]), tracker.ring_z)
        cv2.drawMarker(
            out,
            (int(round(gu[0])), int(round(gv[0]))),
            (60, 220, 60),
            cv2.MARKER_CROSS,
            12 * thick,
            thick,
        )
    if np.isfinite(bot[0]) and tracker.bot_outline is not None:
        cv2.polylines(
            out, [tracker.bot_outline.astype(np.int32)], True, (0, 220, 255), thick, cv2.LINE_AA
        )
        ends = geometry.to_pixels(
            np.array([bot[0], bot[0] + 3 * np.cos(bot[2])]),
            np.array([bot[1], bot[1] + 3 * np.sin(bot[2])]),
            tracker.bot_z,
        )
        cv2.arrowedLine(
            out,
            (int(round(ends[0][0])), int(round(ends[1][0]))),
            (int(round(ends[0][1])), int(round(ends[1][1]))),
            (0, 220, 255),
            thick,
            cv2.LINE_AA,
            tipLength=0.3,
        )
    text = f"t = {time:.2f} s"
    if flag != FLAGS["ok"]:
        text += f"  LOST ({tracker.reason})"
    cv2.putText(
        out,
        text,
        (10, 30 * thick),
        cv2.FONT_HERSHEY_SIMPLEX,
        0.8 * thick,
        (0, 0, 230) if flag != FLAGS["ok"] else (40, 40, 40),
        thick,
        cv2.LINE_AA,
    )
    return out


def read_calibration(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Camera matrix [3, 3] (px) and distortion coefficients from an OpenCV YAML/XML file
    with nodes ``camera_matrix`` and ``distortion_coefficients`` (what ``cv2.FileStorage``
    writes after ``cv2.calibrateCamera``)."""
    path = Path(path)
    if not path.is_file():
        raise CalibrationError(f"no such calibration file: {path}")
    storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    try:
        if not storage.isOpened():
            raise CalibrationError(f"cannot read calibration file {path} (not OpenCV YAML/XML)")
        matrix = storage.getNode("camera_matrix").mat()
        dist = storage.getNode("distortion_coefficients").mat()
    finally:
        storage.release()
    if matrix is None or matrix.shape != (3, 3) or not np.isfinite(matrix).all():
        raise CalibrationError(f"calibration file {path} has no 3 x 3 camera_matrix")
    if dist is None or dist.size not in (4, 5, 8, 12, 14):
        raise CalibrationError(
            f"calibration file {path} has no distortion_coefficients (4, 5, 8, 12 or 14 numbers)"
        )
    return matrix.astype(np.float64), dist.astype(np.float64).ravel()


def parse_origin(text: str, option: str = "origin") -> tuple[float, float]:
    """A plate position written ``X,Y`` (cm), as ``(x, y)``.

    Raises
    ------
    SoftcellError
        Naming ``option`` and the text, unless it is two finite numbers.
    """
    try:
        origin = tuple(float(v) for v in text.split(","))
    except ValueError:
        origin = ()
    if len(origin) != 2 or not all(map(math.isfinite, origin)):
        raise SoftcellError(
            f"{option} = {text!r} is not allowed: must be X,Y, two finite coordinates in cm"
        )
    return origin[0], origin[1]
