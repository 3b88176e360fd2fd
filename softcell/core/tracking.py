"""The paper's tracker (SI S1) as a pure function of images: frame in, geometry out.

Geometry: a pixel (row i, column j) has its center at world coordinates
x = x0 + (j + 0.5) / s, y = y0 + (H - i - 0.5) / s (cm), with s the scale in px per cm, H the
frame height in px and (x0, y0) the world position of the frame's lower-left corner. Angles
are counter-clockwise in the world frame (the image's y axis points down).

The largest red contour of a frame is the membrane, the midline between its outer and inner
edges its shape, and the area centroid of that midline the cell GC (the paper's "centroid of
the membrane contour": averaging over ~1000 edge points makes it sub-pixel); the dark region
inside it is the bot, whose filled mask gives its center and axis, the head mark (or, without
one, continuity and the direction of motion) its direction. Reading the frames from a file is
``softcell.io.video``'s business.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import cv2
import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.core.analysis.series import polygon_area_perimeter_centroid
from softcell.core.schema import (
    COORDINATES,
    TRACKING_FLAGS,
    VARIABLES,
    global_attrs,
    validate,
)

#: Points of the band's edges and midline before the membrane is resampled to its nodes.
MIDLINE_POINTS = 1024
#: Most membrane points a tracked contour is resampled to.
MAX_TRACKED_NODES = 4096
FLAGS = TRACKING_FLAGS


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

@dataclass
class TrackResult:
    """Per-frame results (world units) before they become a Dataset: times (s), cell GC
    (cm), bot (x cm, y cm, heading rad), membrane nodes [nodes, 2] (cm), flag, and whether
    the head mark fixed the heading."""

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


def tracked_dataset(result: TrackResult, *, nodes: int, radius: float | None,
                    attrs: dict) -> xr.Dataset:
    """The simulation schema's Dataset (origin ``tracking``) of per-frame results.

    ``radius`` (cm) is stored as a parameter for the analysis; None estimates it as the mean
    tracked perimeter over 2 pi. ``attrs`` are added to the global attributes (the video's
    name, scale, frame rate and origin). Frames before the first head mark are oriented by
    the direction of motion.
    """
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
                         f"softcell {__version__} tracker", **attrs,
                         softcell_tracking_summary=json.dumps(summary),
                         softcell_parameters=json.dumps({"radius": radius}),
                         softcell_parameter_units=json.dumps({"radius": "cm"}))
    return validate(xr.Dataset(data_vars, coords, attrs))
