"""Top-view videos: a synthetic renderer of simulated cells, and the paper's tracker (SI S1).

Geometry shared by both: a pixel (row i, column j) has its center at world coordinates
x = x0 + (j + 0.5) / s, y = y0 + (H - i - 0.5) / s (cm), with s the scale in px per cm, H the
frame height in px and (x0, y0) the world position of the frame's lower-left corner. Angles
are counter-clockwise in the world frame (the image's y axis points down).

Rendering draws the membrane as a red band of finite width (anti-aliased, at 1/16 px
precision), the bot as a dark ellipse with a light mark at its head, on a light arena, with
optional noise, blur and uneven illumination. Tracking reads frames one at a time: the
largest red contour is the membrane, the midline between its outer and inner edges its
shape, and the area centroid of that midline the cell GC (the paper's "centroid of the
membrane contour": averaging over ~1000 edge points makes it sub-pixel); the dark region
inside it is the bot, whose filled mask gives its center and axis, the head mark (or,
without one, continuity) its direction.
"""

from __future__ import annotations

import json
import os
import queue
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.core.analysis.series import polygon_area_perimeter_centroid
from softcell.errors import SoftcellError
from softcell.io.files import StorageError, atomic_write, storage_problem

SHIFT = 4  # fixed-point bits of OpenCV drawing coordinates: 1/16 px
SUB = 1 << SHIFT
BACKGROUND = np.array([200.0, 200.0, 200.0])  # BGR
BAND = (40, 40, 210)
BOT = (35, 35, 35)
MARK = (225, 225, 225)
#: Points of the band's edges and midline before the membrane is resampled to its nodes.
MIDLINE_POINTS = 1024
#: Frames between two looks at the free disk space while rendering.
DISK_CHECK_EVERY = 10
#: Largest frame side (px) rendered: beyond it a frame no longer fits a codec's limits (and
#: one 16384 x 16384 BGR frame is 768 MiB in float64 while drawn).
MAX_FRAME_SIDE = 16384
#: Smallest frame side (px): the codecs need a few macroblocks.
MIN_FRAME_SIDE = 16
#: Most membrane points a tracked contour is resampled to.
MAX_TRACKED_NODES = 4096
#: tracking_flag values and meanings.
FLAGS = {"ok": 0, "membrane_lost": 1, "bot_lost": 2, "both_lost": 3}


@dataclass(frozen=True)
class Frame:
    """Pixel geometry: scale (px/cm), frame size (px) and lower-left world corner (cm)."""

    px_per_cm: float
    width: int
    height: int
    x0: float = 0.0
    y0: float = 0.0

    def to_pixels(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Column and row (px, pixel centers at integers) of world points (cm)."""
        return ((np.asarray(x) - self.x0) * self.px_per_cm - 0.5,
                self.height - (np.asarray(y) - self.y0) * self.px_per_cm - 0.5)

    def to_world(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World points (cm) of column and row coordinates (px)."""
        return (self.x0 + (np.asarray(u) + 0.5) / self.px_per_cm,
                self.y0 + (self.height - np.asarray(v) - 0.5) / self.px_per_cm)


def _codec(path: Path) -> str:
    """Lossless FFV1 for .mkv / .avi (what a round trip needs), MPEG-4 for .mp4."""
    suffix = path.suffix.lower()
    if suffix in (".mkv", ".avi"):
        return "FFV1"
    if suffix == ".mp4":
        return "mp4v"
    raise SoftcellError(f"video file {path} must end in .mkv or .avi (lossless) or .mp4")


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
    padded[-(n - half):] = spec[half:]
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


def render(ds: xr.Dataset, path: str | os.PathLike[str], *, realization: int = 0,
           point: dict[str, int] | None = None, px_per_cm: float = 10.0, fps: float = 30.0,
           size: tuple[int, int] | None = None, start: float | None = None,
           end: float | None = None, band_width: float = 0.3, head_mark: bool = True,
           noise: float = 0.0,
           blur: float = 0.0, illumination: float = 0.0, seed: int = 0,
           progress: bool = False) -> RenderInfo:
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
        Seed of the noise.

    Returns
    -------
    RenderInfo
    """
    from softcell.core.schema import validate

    for name, value, unit in (("px_per_cm", px_per_cm, "px/cm"), ("fps", fps, "1/s"),
                              ("band_width", band_width, "cm")):
        if not (np.isfinite(value) and value > 0):
            raise SoftcellError(f"{name} = {value} is not allowed: must be finite and > 0 "
                                f"{unit}")
    for name, value, unit in (("noise", noise, "grey levels"), ("blur", blur, "px"),
                              ("illumination", illumination, "1")):
        if not (np.isfinite(value) and value >= 0):
            raise SoftcellError(f"{name} = {value} is not allowed: must be finite and >= 0 "
                                f"{unit}")
    path = Path(path)
    fourcc = cv2.VideoWriter_fourcc(*_codec(path))
    validate(ds)
    for dim, index in {**(point or {}), "realization": realization}.items():
        if dim not in ds.sizes or not 0 <= index < ds.sizes[dim]:
            allowed = f"0 .. {ds.sizes[dim] - 1}" if dim in ds.sizes else "not a dimension"
            raise SoftcellError(f"{dim} index {index} is not allowed: {allowed}")
    for dim in ds["bot_x"].dims[:-2]:
        if dim not in (point or {}):
            raise SoftcellError(f"this is a sweep over {dim} ({ds.sizes[dim]} points): choose "
                                f"one with point {dim}=INDEX (0 .. {ds.sizes[dim] - 1}; "
                                f"--point on the command line)")
    sel = ds.isel(point or {}).isel(realization=realization)
    if not np.isfinite(np.asarray(sel["membrane_x"].values)).any():
        raise SoftcellError("this realization has no membrane (a free bot): nothing to render")
    time = np.asarray(sel["time"].values, dtype=np.float64)
    valid = np.isfinite(np.asarray(sel["bot_x"].values))
    time_valid = time[valid]
    t0 = float(time_valid[0] if start is None else start)
    t1 = float(time_valid[-1] if end is None else end)
    if not time_valid[0] <= t0 < t1 <= time_valid[-1]:
        raise SoftcellError(f"render span [{t0}, {t1}] s is not inside the record "
                            f"[{time_valid[0]}, {time_valid[-1]}] s")
    times = t0 + np.arange(int(np.floor((t1 - t0) * fps + 1e-9)) + 1) / fps
    mx = np.asarray(sel["membrane_x"].transpose("time", "node").values)[valid]
    my = np.asarray(sel["membrane_y"].transpose("time", "node").values)[valid]
    bx, by = np.asarray(sel["bot_x"].values)[valid], np.asarray(sel["bot_y"].values)[valid]
    angle = np.unwrap(np.asarray(sel["bot_angle"].values)[valid])
    params = json.loads(ds.attrs.get("softcell_parameters", "{}"))
    a, b = float(params.get("bot_semi_major", 3.0)), float(params.get("bot_semi_minor", 2.0))
    notes = []
    step = np.diff(time_valid[(time_valid >= t0) & (time_valid <= t1)])
    coarse = bool(step.size and step.max() > 1.0 / fps * (1 + 1e-9))
    if coarse:
        notes.append(f"the record is sampled every {step.max():g} s somewhere in the span, "
                     f"more coarsely than the video (1/{fps:g} s): frames there are linear "
                     "interpolations")
    on_grid = np.isin(np.round(times, 9), np.round(time_valid, 9)).all()
    if not on_grid:
        notes.append("frame times fall between samples: states are interpolated linearly")
    if size is None:
        span = (time_valid >= t0) & (time_valid <= t1)
        lo = np.array([np.nanmin(mx[span]), np.nanmin(my[span])]) - 2.0
        hi = np.array([np.nanmax(mx[span]), np.nanmax(my[span])]) + 2.0
        width, height = (2 * np.ceil((hi - lo) * px_per_cm / 2)).astype(int)
        frame = Frame(px_per_cm, int(width), int(height), float(lo[0]), float(lo[1]))
    else:
        width, height = int(size[0]), int(size[1])
        cx, cy = float(np.mean(mx[0])), float(np.mean(my[0]))
        frame = Frame(px_per_cm, width, height, cx - width / (2 * px_per_cm),
                      cy - height / (2 * px_per_cm))
    _check_frame_size(frame)
    rng = np.random.default_rng(seed)
    background = _background(frame, illumination)
    from tqdm.auto import tqdm

    frame_bytes = DISK_CHECK_EVERY * 3 * frame.width * frame.height  # uncompressed, at most
    with atomic_write(path) as tmp:
        writer = cv2.VideoWriter(str(tmp), fourcc, fps, (frame.width, frame.height))
        if not writer.isOpened():
            raise SoftcellError(f"cannot open {path} for writing with codec {_codec(path)}")
        try:
            for index, t in enumerate(tqdm(times, disable=not progress, desc="render",
                                           unit="frame")):
                k = int(np.clip(np.searchsorted(time_valid, t, side="right") - 1, 0,
                                time_valid.size - 2))
                w = (t - time_valid[k]) / (time_valid[k + 1] - time_valid[k])
                state = {name: (1 - w) * arr[k] + w * arr[k + 1]
                         for name, arr in (("mx", mx), ("my", my), ("bx", bx), ("by", by),
                                           ("angle", angle))}
                image = _draw(frame, background, state, a, b, band_width, head_mark)
                if blur > 0:
                    image = cv2.GaussianBlur(image, (0, 0), blur)
                if noise > 0:
                    image = image + rng.normal(0.0, noise, image.shape)
                writer.write(np.clip(np.rint(image), 0, 255).astype(np.uint8))
                if index and index % DISK_CHECK_EVERY == 0:
                    # OpenCV's writer reports no failed write: watch the disk instead.
                    problem = storage_problem(tmp, need=frame_bytes)
                    if problem:
                        raise StorageError(f"cannot write {path}: {problem} (after {index} "
                                           f"of {times.size} frames)")
        finally:
            writer.release()
        written = count_frames(tmp)
        if written != times.size:
            problem = storage_problem(tmp) or "the file is incomplete"
            raise StorageError(f"cannot write {path}: {problem} ({written} of {times.size} "
                               "frames read back)")
    return RenderInfo(path, times, frame, not on_grid, coarse, notes)


def _check_frame_size(frame: Frame) -> None:
    for side, value in (("width", frame.width), ("height", frame.height)):
        if not MIN_FRAME_SIDE <= value <= MAX_FRAME_SIDE:
            raise SoftcellError(f"frame {side} = {value} px is not allowed: must be between "
                                f"{MIN_FRAME_SIDE} and {MAX_FRAME_SIDE} px (scale "
                                f"{frame.px_per_cm:g} px/cm; lower --px-per-cm or set --size)")


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


def _background(frame: Frame, illumination: float) -> np.ndarray:
    v, u = np.mgrid[0:frame.height, 0:frame.width].astype(np.float64)
    gx, gy = u / max(frame.width - 1, 1) - 0.5, v / max(frame.height - 1, 1) - 0.5
    shade = 1.0 + illumination * (0.6 * gx + 0.3 * gy - 0.8 * (gx**2 + gy**2))
    return shade[..., None] * BACKGROUND


def _draw(frame: Frame, background: np.ndarray, state: dict, a: float, b: float,
          band_width: float, head_mark: bool = True) -> np.ndarray:
    """One frame as float64 BGR; shapes are drawn on uint8 masks and blended."""
    mx, my = _fine_curve(state["mx"], state["my"], 720)
    u, v = frame.to_pixels(mx, my)
    pts = np.rint(np.stack([u, v], axis=1) * SUB).astype(np.int32)
    shape = (frame.height, frame.width)
    band = np.zeros(shape, np.uint8)
    cv2.polylines(band, [pts], True, 255, max(1, int(round(band_width * frame.px_per_cm))),
                  cv2.LINE_AA, SHIFT)
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
        cv2.circle(mark, (int(round(float(mu) * SUB)), int(round(float(mv) * SUB))),
                   int(round(0.3 * b * frame.px_per_cm * SUB)), 255, -1, cv2.LINE_AA, SHIFT)
    image = background.copy()
    for layer, colour in ((bot, BOT), (mark, MARK), (band, BAND)):  # the wall hides the bot
        alpha = layer.astype(np.float64)[..., None] / 255.0
        image = image * (1 - alpha) + alpha * np.asarray(colour, dtype=np.float64)
    return image


# ---------------------------------------------------------------------------------------
# Tracking


@dataclass
class TrackResult:
    """Per-frame results (world units) before they become a Dataset."""

    times: list[float] = field(default_factory=list)
    cell: list[tuple[float, float]] = field(default_factory=list)
    bot: list[tuple[float, float, float]] = field(default_factory=list)
    membrane: list[np.ndarray] = field(default_factory=list)
    flags: list[int] = field(default_factory=list)
    marked: list[bool] = field(default_factory=list)


def _arclength_resample(points: np.ndarray, count: int) -> np.ndarray:
    """``count`` points equally spaced by arclength along a closed polyline [K, 2]."""
    closed = np.vstack([points, points[:1]])
    seg = np.hypot(*np.diff(closed, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    target = np.arange(count) * s[-1] / count
    return np.stack([np.interp(target, s, closed[:, 0]), np.interp(target, s, closed[:, 1])],
                    axis=1)


def _start_at_angle_zero(points: np.ndarray, center: np.ndarray) -> np.ndarray:
    """Roll a closed curve (world frame, counter-clockwise) to start nearest angle 0."""
    angles = np.arctan2(points[:, 1] - center[1], points[:, 0] - center[0])
    return np.roll(points, -int(np.argmin(np.abs(angles))), axis=0)


class Tracker:
    """The paper's tracker, one frame at a time (state: the previous heading).

    Parameters
    ----------
    frame : Frame
        Pixel geometry (scale and world origin).
    nodes : int
        Membrane points resampled by arclength.
    """

    def __init__(self, frame: Frame, nodes: int = 64) -> None:
        self.frame = frame
        self.nodes = nodes
        self.heading: float | None = None
        self.band_level: float | None = None
        self.dark_level: float | None = None
        self.window: tuple[int, int, int, int] | None = None  # x0, y0, x1, y1 (px)
        self.mark_seen = False  # whether the last frame's head mark fixed the direction

    def track(self, image: np.ndarray) -> tuple[int, tuple[float, float], np.ndarray,
                                                tuple[float, float, float]]:
        """Track one BGR uint8 frame: (flag, cell GC (cm), membrane nodes [nodes, 2] (cm),
        bot (x cm, y cm, heading rad)); NaN where detection failed.

        After a success only a window around the last membrane is searched; the whole frame
        is searched again when the membrane is not found well inside that window."""
        height, width = image.shape[:2]
        if self.window is not None:
            x0, y0, x1, y1 = self.window
            result, box = self._detect(image[y0:y1, x0:x1], x0, y0)
            inside = box is not None and (box[0] > x0 or x0 == 0) and (
                box[1] > y0 or y0 == 0) and (box[2] < x1 or x1 == width) and (
                box[3] < y1 or y1 == height)
            if inside:
                self._move_window(box, width, height)
                return result
        result, box = self._detect(image, 0, 0)
        self.window = None
        if box is not None:
            self._move_window(box, width, height)
        return result

    def _move_window(self, box: tuple[int, int, int, int], width: int, height: int) -> None:
        x0, y0, x1, y1 = box
        margin = max(40, (x1 - x0) // 4, (y1 - y0) // 4)
        self.window = (max(x0 - margin, 0), max(y0 - margin, 0), min(x1 + margin, width),
                       min(y1 + margin, height))

    def _detect(self, image: np.ndarray, ox: int, oy: int):
        """Detect in a sub-image whose top-left pixel is (ox, oy) of the frame; returns the
        result and the membrane's bounding box (x0, y0, x1, y1) in frame pixels, or None."""
        nan2 = (np.nan, np.nan)
        lost = (FLAGS["both_lost"], nan2, np.full((self.nodes, 2), np.nan), (np.nan,) * 3)
        b, g, r = cv2.split(image)
        redness = cv2.subtract(r, cv2.max(g, b))  # saturates at 0
        if self.band_level is None:
            level, _ = cv2.threshold(redness, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
            self.band_level = max(float(level), 20.0)
        band = (redness > self.band_level).astype(np.uint8)
        contours, hierarchy = cv2.findContours(band, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
        if not contours:
            return lost, None
        areas = [cv2.contourArea(c) if hierarchy[0][k][3] < 0 else -1.0
                 for k, c in enumerate(contours)]
        outer_k = int(np.argmax(areas))
        holes = [k for k in range(len(contours)) if hierarchy[0][k][3] == outer_k]
        if areas[outer_k] <= 0 or not holes:
            return lost, None
        inner_k = max(holes, key=lambda k: cv2.contourArea(contours[k]))
        offset = np.array([ox, oy])
        outer = contours[outer_k][:, 0, :] + offset
        inner = contours[inner_k][:, 0, :] + offset
        bx, by, bw, bh = cv2.boundingRect(contours[outer_k])
        box = (bx + ox, by + oy, bx + ox + bw, by + oy + bh)
        # Membrane: the midline between the band's outer and inner edges, by arclength; the
        # cell GC is its area centroid (the contour's centroid, as the paper's tracker).
        edges = []
        for edge in (outer, inner):
            world = np.stack(self.frame.to_world(edge[:, 0], edge[:, 1]), axis=1)
            area = 0.5 * np.sum(world[:, 0] * np.roll(world[:, 1], -1)
                                - np.roll(world[:, 0], -1) * world[:, 1])
            if area < 0:
                world = world[::-1]
            edges.append(_start_at_angle_zero(_arclength_resample(world, MIDLINE_POINTS),
                                              world.mean(axis=0)))
        fine = 0.5 * (edges[0] + edges[1])
        _, _, gx, gy = polygon_area_perimeter_centroid(fine[:, 0], fine[:, 1])
        gc = np.array([gx, gy])
        midline = _start_at_angle_zero(_arclength_resample(fine, self.nodes), gc)
        # Bot: the dark region inside the membrane's inner edge.
        inside = np.zeros(band.shape, np.uint8)
        cv2.drawContours(inside, contours, inner_k, 1, -1)
        bot = self._bot(image, inside, ox, oy)
        flag = FLAGS["ok"] if np.isfinite(bot[0]) else FLAGS["bot_lost"]
        return (flag, (float(gc[0]), float(gc[1])), midline, bot), box

    @staticmethod
    def _mark_offset(mark: np.ndarray, m: dict, cu: float, cv_: float, heading: float
                     ) -> float | None:
        """Offset of a head mark from the bot's center along its axis (px, signed), or None
        unless the light region inside the bot looks like the mark: small,
        on the axis, between the center and an end (gaps where the bot touches the membrane
        are not marks)."""
        mm = cv2.moments(mark, binaryImage=True)
        if mm["m00"] < 3 or mm["m00"] > 0.15 * m["m00"]:
            return None
        du, dv = mm["m10"] / mm["m00"] - cu, mm["m01"] / mm["m00"] - cv_
        along = np.cos(heading) * du - np.sin(heading) * dv  # world frame: (du, -dv)
        across = -np.sin(heading) * du - np.cos(heading) * dv
        spread = np.linalg.eigvalsh(np.array([[m["mu20"], m["mu11"]], [m["mu11"], m["mu02"]]])
                                    / m["m00"])
        semi_minor, semi_major = 2 * np.sqrt(np.maximum(spread, 0.0))
        if not (0.3 * semi_major <= abs(along) <= 0.9 * semi_major
                and abs(across) <= 0.35 * semi_minor):
            return None
        return float(along)

    def _bot(self, image: np.ndarray, inside: np.ndarray, ox: int, oy: int
             ) -> tuple[float, float, float]:
        x, y, w, h = cv2.boundingRect(inside)
        roi = cv2.cvtColor(image[y:y + h, x:x + w], cv2.COLOR_BGR2GRAY)
        mask_in = inside[y:y + h, x:x + w]
        if self.dark_level is None:
            values = roi[mask_in > 0]
            level, _ = cv2.threshold(values.reshape(-1, 1), 0, 255,
                                     cv2.THRESH_BINARY + cv2.THRESH_OTSU)
            self.dark_level = float(level)
        dark = ((roi < self.dark_level) & (mask_in > 0)).astype(np.uint8)
        contours, _ = cv2.findContours(dark, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        if not contours:
            return (np.nan, np.nan, np.nan)
        blob = max(contours, key=cv2.contourArea)
        if cv2.contourArea(blob) < 20:
            return (np.nan, np.nan, np.nan)
        filled = np.zeros(dark.shape, np.uint8)
        cv2.drawContours(filled, [blob], 0, 1, -1)
        m = cv2.moments(filled, binaryImage=True)
        cu, cv_ = m["m10"] / m["m00"], m["m01"] / m["m00"]
        axis = 0.5 * np.arctan2(2 * m["mu11"], m["mu20"] - m["mu02"])  # image frame
        heading = -axis  # world frame, defined modulo pi
        along = self._mark_offset(filled & (1 - dark), m, cu, cv_, heading)
        self.mark_seen = along is not None
        if along is not None:
            if along < 0:
                heading += np.pi
        elif self.heading is not None and np.cos(heading - self.heading) < 0:
            heading += np.pi
        if self.heading is not None:  # keep the heading continuous (unwrapped)
            heading = self.heading + (heading - self.heading + np.pi) % (2 * np.pi) - np.pi
        self.heading = heading
        wx, wy = self.frame.to_world(cu + x + ox, cv_ + y + oy)
        return (float(wx), float(wy), float(heading))


def _orient_by_motion(bot: np.ndarray, marked: np.ndarray) -> None:
    """Fix the head-tail ambiguity of the frames before the first head mark (all frames
    if none is seen), whose headings only continuity links: the bot runs forward, so if its
    displacements point against that heading on the whole, turn it by pi (in place)."""
    first = int(np.argmax(marked)) if marked.any() else len(bot)
    if first < 2:
        return
    part = bot[:first]
    step = np.diff(part[:, :2], axis=0)
    along = step[:, 0] * np.cos(part[:-1, 2]) + step[:, 1] * np.sin(part[:-1, 2])
    if np.nansum(along) < 0:
        bot[:first, 2] += np.pi


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

    Returns
    -------
    xarray.Dataset
        The schema's variables (NaN where detection failed) plus ``tracking_flag``; failures
        are counted in the ``softcell_tracking_summary`` attribute.

    Raises
    ------
    SoftcellError
        For a missing, empty or unreadable file, or no calibration.
    """
    from tqdm.auto import tqdm

    from softcell.core.schema import COORDINATES, VARIABLES, global_attrs, validate

    video = Path(video)
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
        tracker = Tracker(frame, nodes)
        result = TrackResult()
        total = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) or None
        with tqdm(total=total, disable=not progress, desc="track", unit="frame") as bar:
            index = 0
            for image in _read_ahead(capture):
                flag, gc, membrane, bot = tracker.track(image)
                result.times.append(index / rate)
                result.cell.append(gc)
                result.membrane.append(membrane)
                result.bot.append(bot)
                result.flags.append(flag)
                result.marked.append(tracker.mark_seen and np.isfinite(bot[2]))
                index += 1
                bar.update(1)
                if on_frame:
                    on_frame(index)
    finally:
        capture.release()
    if not result.times:
        raise SoftcellError(f"video file {video} has no readable frame (corrupt or empty)")
    if all(f == FLAGS["both_lost"] for f in result.flags):
        raise SoftcellError(f"no frame of {video} was tracked: no red ring found in any of its "
                            f"{len(result.flags)} frames")
    cell = np.array(result.cell)
    bot = np.array(result.bot)
    _orient_by_motion(bot, np.array(result.marked))
    membrane = np.array(result.membrane)
    flags = np.array(result.flags, dtype=np.int8)
    if radius is None:
        closed = np.concatenate([membrane, membrane[:, :1]], axis=1)
        perimeter = np.hypot(*np.diff(closed, axis=1).transpose(2, 0, 1)).sum(axis=1)
        radius = float(np.nanmean(perimeter) / (2 * np.pi))
    summary = {name: int(np.sum(flags == value)) for name, value in FLAGS.items()}
    data = {"membrane_x": membrane[None, :, :, 0], "membrane_y": membrane[None, :, :, 1],
            "cell_x": cell[None, :, 0], "cell_y": cell[None, :, 1],
            "bot_x": bot[None, :, 0], "bot_y": bot[None, :, 1],
            "bot_angle": bot[None, :, 2],
            "bot_phase": np.full((1, len(flags)), -1, dtype=np.int8)}
    data_vars = {name: (VARIABLES[name].dims, arr, VARIABLES[name].cf_attrs())
                 for name, arr in data.items()}
    data_vars["tracking_flag"] = (("realization", "time"), flags[None], {
        "units": "1", "long_name": "tracking outcome per frame",
        "flag_values": np.array(list(FLAGS.values()), dtype=np.int8),
        "flag_meanings": " ".join(FLAGS)})
    coords = {"realization": ("realization", np.array([0]),
                              COORDINATES["realization"].cf_attrs()),
              "time": ("time", np.array(result.times), COORDINATES["time"].cf_attrs()),
              "node": ("node", np.arange(nodes), COORDINATES["node"].cf_attrs())}
    attrs = global_attrs("tracking", "soft robotic cell tracked from video",
                         f"softcell {__version__} tracker", softcell_video=video.name,
                         softcell_px_per_cm=float(px_per_cm), softcell_fps=rate,
                         softcell_origin_cm=np.array(origin, dtype=np.float64),
                         softcell_tracking_summary=json.dumps(summary),
                         softcell_parameters=json.dumps({"radius": radius}),
                         softcell_parameter_units=json.dumps({"radius": "cm"}))
    return validate(xr.Dataset(data_vars, coords, attrs))
