"""A synthetic top-view movie of a simulated realization, for the tracker and for people.

Geometry: a pixel (row i, column j) has its center at world coordinates
x = x0 + (j + 0.5) / s, y = y0 + (H - i - 0.5) / s (cm), with s the scale in px per cm, H the
frame height in px and (x0, y0) the world position of the frame's lower-left corner. Angles
are counter-clockwise in the world frame (the image's y axis points down).

The membrane is drawn as a red band of finite width (anti-aliased, at 1/16 px precision), the
bot as a dark ellipse with a light mark at its head, on a light arena, with optional noise,
blur and uneven illumination.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
import xarray as xr

from softcell.errors import SoftcellError
from softcell.io.files import StorageError, atomic_write, storage_problem
from softcell.model.limits import check_seed
from softcell.schema import refuse_several_bots, validate
from softcell.video.track import codec, count_frames
from softcell.video.tracker import Frame

SHIFT = 4  # fixed-point bits of OpenCV drawing coordinates: 1/16 px
SUB = 1 << SHIFT
BACKGROUND = np.array([200.0, 200.0, 200.0])  # BGR
BAND = (40, 40, 210)
BOT = (35, 35, 35)
MARK = (225, 225, 225)
#: Frames between two looks at the free disk space while rendering.
DISK_CHECK_EVERY = 10
#: Largest frame side (px) rendered: beyond it a frame no longer fits a codec's limits (and
#: one 16384 x 16384 BGR frame is 768 MiB in float64 while drawn).
MAX_FRAME_SIDE = 16384
#: Smallest frame side (px): the codecs need a few macroblocks.
MIN_FRAME_SIDE = 16
#: Most frames one render writes: 9.3 h of video at 30 frames/s, days of drawing.
MAX_FRAMES = 1_000_000


def _fine_curve(mx: np.ndarray, my: np.ndarray, points: int) -> tuple[np.ndarray, np.ndarray]:
    """Trigonometric interpolation of a closed curve sampled at equal xi: exact for a
    membrane stored with more nodes than 2 cutoff + 1."""
    n = mx.size
    if points <= n:
        return mx, my
    spec = np.fft.fft(mx + 1j * my) / n
    padded = np.zeros(points, dtype=complex)
    half = n // 2
    padded[:half] = spec[:half]
    padded[-(n - half) :] = spec[half:]
    z = np.fft.ifft(padded) * points
    return z.real, z.imag


@dataclass
class RenderInfo:
    """What :func:`render` wrote: frame times (s), pixel geometry, and whether the states
    between samples were interpolated (linearly) or came from a coarser record."""

    path: Path
    times: np.ndarray
    frame: Frame
    interpolated: bool
    coarser_than_video: bool
    notes: list[str] = field(default_factory=list)


def render(
    ds: xr.Dataset,
    path: str | os.PathLike[str],
    *,
    realization: int = 0,
    point: dict[str, int] | None = None,
    px_per_cm: float = 10.0,
    fps: float = 30.0,
    size: tuple[int, int] | None = None,
    start: float | None = None,
    end: float | None = None,
    band_width: float = 0.3,
    head_mark: bool = True,
    noise: float = 0.0,
    blur: float = 0.0,
    illumination: float = 0.0,
    seed: int = 0,
    progress: bool = False,
) -> RenderInfo:
    """Render one realization as a top-view movie.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation Dataset (``membrane_x/y``, ``bot_x/y``, ``bot_angle``; cm, rad).
    path : path-like
        ``.mkv`` / ``.avi`` (lossless FFV1: for tracking) or ``.mp4`` (MPEG-4, lossy).
    realization, point
        Which realization, and for a sweep which point (e.g. ``{"radius": 1}``).
    px_per_cm, fps
        Scale (px/cm) and frame rate (1/s).
    size : (width, height) px, optional
        Default: the region the membrane visits, with a 2 cm margin.
    start, end : float, optional
        Time span (s); by default the whole record. Frames fall at start + k / fps; states
        between samples are interpolated linearly (and a record sampled more coarsely than
        the video is reported in ``notes``).
    band_width : float
        Width of the drawn membrane (cm).
    head_mark : bool
        Draw the light mark at the bot's head (without it the tracker falls back on
        continuity and the direction of motion).
    noise, blur, illumination
        Gaussian noise (grey levels), Gaussian blur (px), and the relative amplitude of an
        uneven illumination (a gradient and a vignette).
    seed : int
        Seed of the noise (0 .. 2**64 - 1).
    progress : bool
        Show a progress bar over the frames.

    Returns
    -------
    RenderInfo
    """
    check_seed(seed)
    _check_render_arguments(
        px_per_cm=px_per_cm,
        fps=fps,
        band_width=band_width,
        noise=noise,
        blur=blur,
        illumination=illumination,
    )
    path = Path(path)
    fourcc = cv2.VideoWriter_fourcc(*codec(path))
    film = Film(
        ds,
        realization=realization,
        point=point,
        px_per_cm=px_per_cm,
        fps=fps,
        size=size,
        start=start,
        end=end,
    )
    times, frame = film.times, film.frame
    from softcell.settings import progress_bar_class

    tqdm = progress_bar_class()

    frame_bytes = DISK_CHECK_EVERY * 3 * frame.width * frame.height  # uncompressed, at most
    images = film.images(
        band_width=band_width,
        head_mark=head_mark,
        noise=noise,
        blur=blur,
        illumination=illumination,
        seed=seed,
    )
    with atomic_write(path) as tmp:
        writer = cv2.VideoWriter(str(tmp), fourcc, fps, (frame.width, frame.height))
        if not writer.isOpened():
            raise SoftcellError(f"cannot open {path} for writing with codec {codec(path)}")
        try:
            for index, image in enumerate(
                tqdm(images, total=times.size, disable=not progress, desc="render", unit="frame")
            ):
                writer.write(image)
                if index and index % DISK_CHECK_EVERY == 0:
                    # OpenCV's writer reports no failed write: watch the disk instead.
                    problem = storage_problem(tmp, need=frame_bytes)
                    if problem:
                        raise StorageError(
                            f"cannot write {path}: {problem} (after {index} of {times.size} frames)"
                        )
        finally:
            writer.release()
        written = count_frames(tmp)
        if written != times.size:
            problem = storage_problem(tmp) or "the file is incomplete"
            raise StorageError(
                f"cannot write {path}: {problem} ({written} of {times.size} frames read back)"
            )
    return RenderInfo(path, times, frame, film.interpolated, film.coarse, film.notes)


class Film:
    """One realization's frames, drawn as :func:`render` films them (without writing them):
    the frame times, the pixel geometry, and the images on demand.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation Dataset (``membrane_x/y``, ``bot_x/y``, ``bot_angle``; cm, rad).
    realization, point, px_per_cm, fps, size, start, end
        As for :func:`render`.

    Attributes
    ----------
    times : numpy.ndarray
        float64[frame]: each frame's time (s).
    frame : Frame
        The pixel geometry.
    interpolated, coarse : bool
        Whether frames fall between samples; whether the record is coarser than the film
        somewhere.
    notes : list of str
        What a user should know of the interpolation.
    """

    def __init__(
        self,
        ds: xr.Dataset,
        *,
        realization: int = 0,
        point: dict[str, int] | None = None,
        px_per_cm: float = 10.0,
        fps: float = 30.0,
        size: tuple[int, int] | None = None,
        start: float | None = None,
        end: float | None = None,
    ) -> None:
        sel = _realization(ds, realization, point)
        time = np.asarray(sel["time"].values, dtype=np.float64)
        valid = np.isfinite(np.asarray(sel["bot_x"].values))
        self._time = time[valid]
        self.times, self.notes, self.coarse, on_grid = _frame_times(self._time, start, end, fps)
        self.interpolated = not on_grid
        t0, t1 = self.times[0], float(self._time[-1] if end is None else end)
        self._state = {
            "mx": np.asarray(sel["membrane_x"].transpose("time", "node").values)[valid],
            "my": np.asarray(sel["membrane_y"].transpose("time", "node").values)[valid],
            "bx": np.asarray(sel["bot_x"].values)[valid],
            "by": np.asarray(sel["bot_y"].values)[valid],
            "angle": np.unwrap(np.asarray(sel["bot_angle"].values)[valid]),
        }
        params = json.loads(ds.attrs.get("softcell_parameters", "{}"))
        self._axes = (
            float(params.get("bot_semi_major", 3.0)),
            float(params.get("bot_semi_minor", 2.0)),
        )
        span = (self._time >= t0) & (self._time <= t1)
        self.frame = _frame_for(self._state["mx"], self._state["my"], span, px_per_cm, size)

    def images(
        self,
        *,
        band_width: float = 0.3,
        head_mark: bool = True,
        noise: float = 0.0,
        blur: float = 0.0,
        illumination: float = 0.0,
        seed: int = 0,
    ) -> Iterator[np.ndarray]:
        """Each frame as uint8[height, width, 3] BGR, one at a time; the arguments as for
        :func:`render` (the same seed draws the same noise, frame by frame)."""
        check_seed(seed)
        rng = np.random.default_rng(seed)
        background = _background(self.frame, illumination)
        a, b = self._axes
        time = self._time
        for t in self.times:
            k = int(np.clip(np.searchsorted(time, t, side="right") - 1, 0, time.size - 2))
            w = (t - time[k]) / (time[k + 1] - time[k])
            state = {name: (1 - w) * arr[k] + w * arr[k + 1] for name, arr in self._state.items()}
            image = _draw(self.frame, background, state, a, b, band_width, head_mark)
            if blur > 0:
                image = cv2.GaussianBlur(image, (0, 0), blur)
            if noise > 0:
                image += rng.normal(0.0, noise, image.shape)
            np.rint(image, out=image)
            yield np.clip(image, 0, 255, out=image).astype(np.uint8)


def _check_render_arguments(**values: float) -> None:
    """One line naming the first bad scale, rate, width or image effect."""
    units = {
        "px_per_cm": "px/cm",
        "fps": "1/s",
        "band_width": "cm",
        "noise": "grey levels",
        "blur": "px",
        "illumination": "1",
    }
    for name in ("px_per_cm", "fps", "band_width"):
        value = values[name]
        if not (np.isfinite(value) and value > 0):
            raise SoftcellError(
                f"{name} = {value} is not allowed: must be finite and > 0 {units[name]}"
            )
    for name in ("noise", "blur", "illumination"):
        value = values[name]
        if not (np.isfinite(value) and value >= 0):
            raise SoftcellError(
                f"{name} = {value} is not allowed: must be finite and >= 0 {units[name]}"
            )


def _swept(ds: xr.Dataset) -> tuple[str, ...]:
    """The sweep dims of ``ds``: those of ``cell_x`` before its realization dim."""
    dims = ds["cell_x"].dims
    return tuple(dims[: dims.index("realization")])


def check_point(ds: xr.Dataset, point: dict[str, int], option: str = "point") -> None:
    """Raise a one-line :class:`SoftcellError` unless ``point`` names sweep dimensions of
    ``ds`` (those of ``bot_x`` before realization and time) with an index in range each; the
    message names ``option``, the dimensions there are and each index's value."""
    swept = _swept(ds)
    for dim, index in point.items():
        if dim not in swept:
            there = (
                f"its sweep dimensions are {', '.join(swept)}"
                if swept
                else "the input is one parameter point, so there is no point to choose"
            )
            raise SoftcellError(f"{option} {dim}={index} is not allowed: {there}")
        if not 0 <= index < ds.sizes[dim]:
            values = ", ".join(f"{v:g}" for v in np.asarray(ds[dim].values, dtype=float))
            unit = ds[dim].attrs.get("units", "")
            raise SoftcellError(
                f"{option} {dim}={index} is not allowed: an index from 0 to "
                f"{ds.sizes[dim] - 1}, not a value ({dim} = {values} {unit}".rstrip()
                + ")"
            )


def _realization(ds: xr.Dataset, realization: int, point: dict[str, int] | None) -> xr.Dataset:
    """The one realization (of one sweep point) to render; a one-line error for an index out
    of range, a sweep without a chosen point, or a free bot."""
    validate(ds)
    refuse_several_bots(ds, "render")
    check_point(ds, point or {})
    if not 0 <= realization < ds.sizes["realization"]:
        raise SoftcellError(
            f"realization index {realization} is not allowed: 0 .. {ds.sizes['realization'] - 1}"
        )
    for dim in _swept(ds):
        if dim not in (point or {}):
            raise SoftcellError(
                f"this is a sweep over {dim} ({ds.sizes[dim]} points): choose "
                f"one with point {dim}=INDEX (0 .. {ds.sizes[dim] - 1}; "
                f"--point on the command line)"
            )
    sel = ds.isel(point or {}).isel(realization=realization)
    if not np.isfinite(np.asarray(sel["membrane_x"].values)).any():
        raise SoftcellError("this realization has no membrane (a free bot): nothing to render")
    return sel


def _frame_times(
    time_valid: np.ndarray, start: float | None, end: float | None, fps: float
) -> tuple[np.ndarray, list[str], bool, bool]:
    """The frame times (s) in [start, end], notes on interpolation, whether the record is
    coarser than the video somewhere, and whether every frame falls on a sample."""
    t0 = float(time_valid[0] if start is None else start)
    t1 = float(time_valid[-1] if end is None else end)
    if not time_valid[0] <= t0 < t1 <= time_valid[-1]:
        raise SoftcellError(
            f"render span [{t0}, {t1}] s is not inside the record "
            f"[{time_valid[0]}, {time_valid[-1]}] s"
        )
    count = frame_count(t0, t1, fps)
    if count > MAX_FRAMES:
        raise SoftcellError(
            f"fps = {fps:g} 1/s over [{t0:g}, {t1:g}] s makes {count:.3g} frames, more than "
            f"{MAX_FRAMES:,}; lower --fps or shorten the span (--start, --end)"
        )
    times = t0 + np.arange(count) / fps
    notes = []
    step = np.diff(time_valid[(time_valid >= t0) & (time_valid <= t1)])
    coarse = bool(step.size and step.max() > 1.0 / fps * (1 + 1e-9))
    if coarse:
        notes.append(
            f"the record is sampled every {step.max():g} s somewhere in the span, "
            f"more coarsely than the video (1/{fps:g} s): frames there are linear "
            "interpolations"
        )
    on_grid = np.isin(np.round(times, 9), np.round(time_valid, 9)).all()
    if not on_grid:
        notes.append("frame times fall between samples: states are interpolated linearly")
    return times, notes, coarse, on_grid


def frame_count(start: float, end: float, fps: float) -> int:
    """Frames at ``start`` + k / ``fps`` up to ``end`` (s), both ends included."""
    return int(np.floor((end - start) * fps + 1e-9)) + 1


def _frame_for(
    mx: np.ndarray, my: np.ndarray, span: np.ndarray, px_per_cm: float, size: tuple[int, int] | None
) -> Frame:
    """The pixel geometry: the region the membrane visits during ``span`` with a 2 cm margin,
    or ``size`` (px) centred on the first shape."""
    if size is None:
        lo = np.array([np.nanmin(mx[span]), np.nanmin(my[span])]) - 2.0
        hi = np.array([np.nanmax(mx[span]), np.nanmax(my[span])]) + 2.0
        width, height = (2 * np.ceil((hi - lo) * px_per_cm / 2)).astype(int)
        frame = Frame(px_per_cm, int(width), int(height), float(lo[0]), float(lo[1]))
    else:
        width, height = int(size[0]), int(size[1])
        cx, cy = float(np.mean(mx[0])), float(np.mean(my[0]))
        frame = Frame(
            px_per_cm, width, height, cx - width / (2 * px_per_cm), cy - height / (2 * px_per_cm)
        )
    _check_frame_size(frame)
    return frame


def _check_frame_size(frame: Frame) -> None:
    for side, value in (("width", frame.width), ("height", frame.height)):
        if not MIN_FRAME_SIDE <= value <= MAX_FRAME_SIDE:
            raise SoftcellError(
                f"frame {side} = {value} px is not allowed: must be between "
                f"{MIN_FRAME_SIDE} and {MAX_FRAME_SIDE} px (scale "
                f"{frame.px_per_cm:g} px/cm; lower --px-per-cm or set --size)"
            )


def _background(frame: Frame, illumination: float) -> np.ndarray:
    v, u = np.mgrid[0 : frame.height, 0 : frame.width].astype(np.float64)
    gx, gy = u / max(frame.width - 1, 1) - 0.5, v / max(frame.height - 1, 1) - 0.5
    shade = 1.0 + illumination * (0.6 * gx + 0.3 * gy - 0.8 * (gx**2 + gy**2))
    return shade[..., None] * BACKGROUND


def _draw(
    frame: Frame,
    background: np.ndarray,
    state: dict,
    a: float,
    b: float,
    band_width: float,
    head_mark: bool = True,
) -> np.ndarray:
    """One frame as float64 BGR; shapes are drawn on uint8 masks and blended."""
    mx, my = _fine_curve(state["mx"], state["my"], 720)
    u, v = frame.to_pixels(mx, my)
    pts = np.rint(np.stack([u, v], axis=1) * SUB).astype(np.int32)
    shape = (frame.height, frame.width)
    band = np.zeros(shape, np.uint8)
    cv2.polylines(
        band, [pts], True, 255, max(1, int(round(band_width * frame.px_per_cm))), cv2.LINE_AA, SHIFT
    )
    bot = np.zeros(shape, np.uint8)
    cu, cv_ = frame.to_pixels(state["bx"], state["by"])
    axes = (int(round(a * frame.px_per_cm * SUB)), int(round(b * frame.px_per_cm * SUB)))
    center = (int(round(float(cu) * SUB)), int(round(float(cv_) * SUB)))
    degrees = -np.degrees(float(state["angle"]))  # image rows point down
    cv2.ellipse(bot, center, axes, degrees, 0, 360, 255, -1, cv2.LINE_AA, SHIFT)
    mark = np.zeros(shape, np.uint8)
    hx = state["bx"] + 0.6 * a * np.cos(state["angle"])
    hy = state["by"] + 0.6 * a * np.sin(state["angle"])
    mu, mv = frame.to_pixels(hx, hy)
    if head_mark:
        cv2.circle(
            mark,
            (int(round(float(mu) * SUB)), int(round(float(mv) * SUB))),
            int(round(0.3 * b * frame.px_per_cm * SUB)),
            255,
            -1,
            cv2.LINE_AA,
            SHIFT,
        )
    image = background.copy()
    for layer, colour in ((bot, BOT), (mark, MARK), (band, BAND)):  # the wall hides the bot
        # Where a layer is 0 the blend leaves the image as it is, bit for bit: blend only
        # within the box of its drawn pixels.
        x, y, w, h = cv2.boundingRect(layer)
        if not w:
            continue
        box = (slice(y, y + h), slice(x, x + w))
        alpha = layer[box].astype(np.float64)[..., None] / 255.0
        image[box] = image[box] * (1 - alpha) + alpha * np.asarray(colour, dtype=np.float64)
    return image


def parse_point(text: str, option: str = "point") -> dict[str, int]:
    """A sweep point written ``NAME=INDEX[,...]`` (``"radius=1"``), as ``{name: index}``.

    Raises
    ------
    SoftcellError
        Naming ``option`` and the text, for anything else.
    """
    try:
        return {k: int(v) for k, v in (item.split("=") for item in text.split(","))}
    except ValueError:
        raise SoftcellError(
            f"{option} = {text!r} is not allowed: must be NAME=INDEX[,...] (e.g. radius=1)"
        ) from None


def parse_size(text: str, option: str = "size") -> tuple[int, int]:
    """A frame size written ``WIDTHxHEIGHT`` (px), as ``(width, height)``.

    Raises
    ------
    SoftcellError
        Naming ``option`` and the text, for anything else.
    """
    try:
        size = tuple(int(v) for v in text.lower().split("x"))
    except ValueError:
        size = ()
    if len(size) != 2:
        raise SoftcellError(f"{option} = {text!r} is not allowed: must be WIDTHxHEIGHT px")
    return size[0], size[1]
