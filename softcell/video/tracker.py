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
``softcell.video.track``'s business.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import cv2
import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.analysis.series import polygon_area_perimeter_centroid
from softcell.schema import (
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

    def to_pixels(
        self, x: np.ndarray, y: np.ndarray, z: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Column and row (px, pixel centers at integers) of world points (cm) (``z`` must
        be 0: see :meth:`to_world`)."""
        _flat(z)
        return (
            (np.asarray(x) - self.x0) * self.px_per_cm - 0.5,
            self.height - (np.asarray(y) - self.y0) * self.px_per_cm - 0.5,
        )

    def to_world(
        self, u: np.ndarray, v: np.ndarray, z: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """World points (cm) of column and row coordinates (px); a linear frame has no
        parallax to correct, so ``z`` (cm) must be 0."""
        _flat(z)
        return (
            self.x0 + (np.asarray(u) + 0.5) / self.px_per_cm,
            self.y0 + (self.height - np.asarray(v) - 0.5) / self.px_per_cm,
        )


def _flat(z: float) -> None:
    if z:
        raise ValueError(
            f"an object height of {z:g} cm needs a camera model (a plate "
            "calibration), not a linear frame"
        )


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
    reasons: list[str] = field(default_factory=list)


def _arclength_resample(points: np.ndarray, count: int) -> np.ndarray:
    """``count`` points equally spaced by arclength along a closed polyline [K, 2]."""
    closed = np.vstack([points, points[:1]])
    seg = np.hypot(*np.diff(closed, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    target = np.arange(count) * s[-1] / count
    return np.stack(
        [np.interp(target, s, closed[:, 0]), np.interp(target, s, closed[:, 1])], axis=1
    )


def _start_at_angle_zero(points: np.ndarray, center: np.ndarray) -> np.ndarray:
    """Roll a closed curve (world frame, counter-clockwise) to start nearest angle 0."""
    angles = np.arctan2(points[:, 1] - center[1], points[:, 0] - center[0])
    return np.roll(points, -int(np.argmin(np.abs(angles))), axis=0)


#: Defaults of the adaptive detection (each can be set): a pixel is paper when its redness
#: (R - max(G, B)) / R exceeds RING_FRACTION of the frame's paper redness, and bot when its
#: grey level is below DARK_FRACTION of the plate's inside the ring (shadows of 15-35 % are
#: not: they keep 65-85 % of it).
RING_FRACTION = 0.45
#: Paper colours the tracker knows (orange paper is "red": its red channel leads).
RING_COLORS = ("red", "green", "blue", "yellow")
DARK_FRACTION = 0.5
#: Plausibility of a membrane: perimeter within this fraction of the expected 2 pi R, and
#: for a gapped wall, the share of directions around the GC where the wall is seen.
PERIMETER_TOLERANCE = 0.1
MIN_COVERAGE = 0.35
#: Fourier modes of the shape prior that bridges the gaps of a wall seen edge-on.
PRIOR_MODES = 6
ANGLE_BINS = 180


class Tracker:
    """The tracker, one frame at a time (state: the previous heading, GC and perimeter).

    Parameters
    ----------
    frame : Frame or PlateCamera
        Pixel to world geometry: ``to_world(u, v, z)`` and ``to_pixels(x, y, z)`` (px, cm).
    nodes : int
        Membrane points resampled by arclength.
    ring_z, bot_z : float
        Heights (cm) at which the membrane's midline and the bot's outline are mapped (half
        the ring's and the bot's height: what the camera sees of each spans their height).
    radius : float, optional
        Expected membrane radius (cm); default learned from the closed rings seen.
    ring_color : str
        The paper's colour, one of :data:`RING_COLORS`: its colourfulness is the share of
        its own channel(s) above the others, (R - max(G, B)) / R for red (or orange) paper.
    ring_threshold : float, optional
        Colourfulness above which a pixel is paper; default per frame,
        :data:`RING_FRACTION` of the paper's.
    dark_fraction : float
        A pixel is bot when darker than this fraction of the plate inside the ring.
    """

    def __init__(
        self,
        frame,
        nodes: int = 64,
        *,
        ring_z: float = 0.0,
        bot_z: float = 0.0,
        radius: float | None = None,
        ring_color: str = "red",
        ring_threshold: float | None = None,
        dark_fraction: float = DARK_FRACTION,
    ) -> None:
        if ring_color not in RING_COLORS:
            raise ValueError(
                f"ring colour {ring_color!r} is not known: one of {', '.join(RING_COLORS)}"
            )
        self.ring_color = ring_color
        self.frame = frame
        self.nodes = nodes
        self.ring_z, self.bot_z = float(ring_z), float(bot_z)
        self.radius = radius
        self.ring_threshold = ring_threshold
        self.dark_fraction = dark_fraction
        self.heading: float | None = None
        self.perimeters: list[float] = []  # of closed rings seen, when no radius is given
        self.window: tuple[int, int, int, int] | None = None  # x0, y0, x1, y1 (px)
        self.mark_seen = False  # whether the last frame's head mark fixed the direction
        self.reason = ""  # why the last frame failed, "" when it did not
        self.gc: np.ndarray | None = None
        self.bot_outline: np.ndarray | None = None  # the last bot's outline [K, 2] (px)
        mask = getattr(frame, "plate_mask", None)
        self.search_mask = mask() if mask is not None else None

    def track(
        self, image: np.ndarray
    ) -> tuple[int, tuple[float, float], np.ndarray, tuple[float, float, float]]:
        """Track one BGR uint8 frame: (flag, cell GC (cm), membrane nodes [nodes, 2] (cm),
        bot (x cm, y cm, heading rad)); NaN where detection failed, and :attr:`reason` says
        why.

        After a success only a window around the last membrane is searched; the whole frame
        is searched again when the membrane is not found well inside that window."""
        height, width = image.shape[:2]
        if self.window is not None:
            x0, y0, x1, y1 = self.window
            result, box = self._detect(image[y0:y1, x0:x1], x0, y0)
            inside = (
                box is not None
                and (box[0] > x0 or x0 == 0)
                and (box[1] > y0 or y0 == 0)
                and (box[2] < x1 or x1 == width)
                and (box[3] < y1 or y1 == height)
            )
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
        self.window = (
            max(x0 - margin, 0),
            max(y0 - margin, 0),
            min(x1 + margin, width),
            min(y1 + margin, height),
        )

    @property
    def expected_perimeter(self) -> float | None:
        if self.radius is not None:
            return 2 * np.pi * self.radius
        return float(np.median(self.perimeters[-50:])) if self.perimeters else None

    def _paper(self, image: np.ndarray, region: np.ndarray | None = None) -> np.ndarray:
        """Paper mask of a BGR image (within ``region``, a mask, if given): redness above
        this frame's threshold."""
        b, g, r = (c.astype(np.float32) for c in cv2.split(cv2.medianBlur(image, 3)))
        main, rest = {
            "red": (r, np.maximum(g, b)),
            "green": (g, np.maximum(r, b)),
            "blue": (b, np.maximum(r, g)),
            "yellow": (np.minimum(r, g), b),
        }[self.ring_color]
        bright = main >= 0.25 * float(np.percentile(main, 90))  # dark pixels have no colour
        redness = np.where(bright, (main - rest) / np.maximum(main, 1.0), 0.0)
        if region is not None:
            redness = np.where(region > 0, redness, 0.0)
        level = self.ring_threshold
        if level is None:
            paper = redness[redness > 0.3]
            level = RING_FRACTION * float(np.median(paper)) if paper.size >= 30 else 0.3
            level = max(level, 0.15)
        return (redness > level).astype(np.uint8)

    def _closed_ring(self, band: np.ndarray, offset: np.ndarray):
        """(outer, inner) edge contours (px) of the largest closed band, or a reason."""
        contours, hierarchy = cv2.findContours(band, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
        if not contours:
            return None, "no paper seen"
        areas = [
            cv2.contourArea(c) if hierarchy[0][k][3] < 0 else -1.0 for k, c in enumerate(contours)
        ]
        outer_k = int(np.argmax(areas))
        holes = [k for k in range(len(contours)) if hierarchy[0][k][3] == outer_k]
        if areas[outer_k] <= 0 or not holes:
            return None, "the wall is not closed"
        inner_k = max(holes, key=lambda k: cv2.contourArea(contours[k]))
        if cv2.contourArea(contours[inner_k]) < 0.5 * areas[outer_k]:
            return None, "the wall is not closed"
        return (contours[outer_k][:, 0, :] + offset, contours[inner_k][:, 0, :] + offset), ""

    def _midline_of_band(self, outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
        edges = []
        for edge in (outer, inner):
            world = np.stack(self.frame.to_world(edge[:, 0], edge[:, 1], self.ring_z), axis=1)
            area = 0.5 * np.sum(
                world[:, 0] * np.roll(world[:, 1], -1) - np.roll(world[:, 0], -1) * world[:, 1]
            )
            if area < 0:
                world = world[::-1]
            edges.append(
                _start_at_angle_zero(_arclength_resample(world, MIDLINE_POINTS), world.mean(axis=0))
            )
        return 0.5 * (edges[0] + edges[1])

    def _fitted_ring(self, band: np.ndarray, offset: np.ndarray):
        """The wall as a closed curve fitted to the paper seen: its gaps, where the wall is
        seen edge-on, bridged by the shape prior (a smooth closed curve of
        :data:`PRIOR_MODES` Fourier modes about the GC, its deformations penalized and, when
        the radius is known, its mean radius held near it): the fine curve
        [MIDLINE_POINTS, 2] (cm), or None and a reason."""
        expected = self.expected_perimeter
        radius = None if expected is None else expected / (2 * np.pi)
        seen = self._wall_seen(band, offset, radius)
        if isinstance(seen, str):
            return None, seen
        return self._prior_fit(*seen, radius)

    def _wall_seen(self, band: np.ndarray, offset: np.ndarray, radius: float | None):
        """The paper's pixels that belong to the ring, as plate points (x, y) in cm, or the
        reason there are none."""
        count, labels, stats, centroids = cv2.connectedComponentsWithStats(band, connectivity=8)
        if count <= 1:
            return "no paper seen"
        areas = stats[1:, cv2.CC_STAT_AREA]
        # The ring's pieces: no specks, and (the paper's colour fringes at far edges are
        # not the ring) near the largest piece, or near the last GC.
        keep = np.nonzero(areas >= max(3, 0.05 * areas.max()))[0] + 1
        cx, cy = self.frame.to_world(
            centroids[keep, 0] + offset[0], centroids[keep, 1] + offset[1], self.ring_z
        )
        if self.gc is not None and radius is not None:
            close = np.hypot(cx - self.gc[0], cy - self.gc[1]) < 1.5 * radius
        else:
            big = int(np.argmax(areas[keep - 1]))
            reach = (
                2.5 * radius
                if radius is not None
                else 0.5 * np.hypot(*band.shape) / max(self.frame.px_per_cm, 1e-9)
            )
            close = np.hypot(cx - cx[big], cy - cy[big]) < reach
        vv, uu = np.nonzero(np.isin(labels, keep[close]))
        if uu.size < 50:
            return "too little of the wall seen"
        return self.frame.to_world(uu + offset[0], vv + offset[1], self.ring_z)

    def _prior_fit(self, x: np.ndarray, y: np.ndarray, radius: float | None):
        """The shape prior fitted to the wall seen at (x, y) (cm): the fine curve and ``""``,
        or None and a reason."""
        center = self.gc
        if center is None:  # the circle through the paper seen (algebraic least squares)
            a = np.column_stack([2 * x, 2 * y, np.ones_like(x)])
            center = np.linalg.lstsq(a, x**2 + y**2, rcond=None)[0][:2]
        modes = np.arange(1, PRIOR_MODES + 1)
        # Penalty on each unknown (a0, cos modes, sin modes): none on the shift (mode 1),
        # growing with the mode's bending for the rest.
        stiffness = np.concatenate([[0.0], (modes**2 - 1.0) ** 2])  # 0 for the shift
        stiffness = np.concatenate([stiffness, stiffness[1:]]) * 1e-3
        for step in range(4):
            angle = np.arctan2(y - center[1], x - center[0])
            r = np.hypot(x - center[0], y - center[1])
            if radius is not None and (step > 0 or self.gc is not None):
                near = np.abs(r - radius) < 0.35 * radius  # paper far away is not the ring
                angle, r = angle[near], r[near]
            bins = ((angle + np.pi) / (2 * np.pi) * ANGLE_BINS).astype(int) % ANGLE_BINS
            counts = np.bincount(bins, minlength=ANGLE_BINS)
            filled = counts > 0
            if filled.mean() < MIN_COVERAGE:
                return None, "too little of the wall seen"
            order = np.argsort(bins, kind="stable")
            groups = np.split(r[order], np.cumsum(counts)[:-1])
            phi = (np.nonzero(filled)[0] + 0.5) / ANGLE_BINS * 2 * np.pi - np.pi
            radii = np.array([np.median(g) for g in groups if g.size])
            basis = np.column_stack(
                [np.ones_like(phi), np.cos(np.outer(phi, modes)), np.sin(np.outer(phi, modes))]
            )
            lhs = basis.T @ basis + np.diag(stiffness * phi.size)
            rhs = basis.T @ radii
            if radius is not None:  # the known length: mean radius near R
                weight = 0.1 * phi.size
                lhs[0, 0] += weight
                rhs[0] += weight * radius
            coef = np.linalg.solve(lhs, rhs)
            theta = np.linspace(-np.pi, np.pi, MIDLINE_POINTS, endpoint=False)
            full = (
                np.column_stack(
                    [
                        np.ones_like(theta),
                        np.cos(np.outer(theta, modes)),
                        np.sin(np.outer(theta, modes)),
                    ]
                )
                @ coef
            )
            curve = center + full[:, None] * np.stack([np.cos(theta), np.sin(theta)], axis=1)
            _, _, gx, gy = polygon_area_perimeter_centroid(curve[:, 0], curve[:, 1])
            center = np.array([gx, gy])
        return _start_at_angle_zero(curve, center), ""

    def _plausible(self, fine: np.ndarray) -> tuple[str, float]:
        """Why a membrane curve (cm) is refused ("" if it is not), and its perimeter (cm)."""
        _, perimeter, _, _ = polygon_area_perimeter_centroid(fine[:, 0], fine[:, 1])
        expected = self.expected_perimeter
        if expected is not None and abs(perimeter / expected - 1) > PERIMETER_TOLERANCE:
            return f"perimeter not within {PERIMETER_TOLERANCE:.0%} of 2 pi R", float(perimeter)
        return "", float(perimeter)

    def _detect(self, image: np.ndarray, ox: int, oy: int):
        """Detect in a sub-image whose top-left pixel is (ox, oy) of the frame; returns the
        result and the membrane's bounding box (x0, y0, x1, y1) in frame pixels, or None."""
        nan2 = (np.nan, np.nan)
        lost = (FLAGS["both_lost"], nan2, np.full((self.nodes, 2), np.nan), (np.nan,) * 3)
        offset = np.array([ox, oy])
        region = None
        if self.search_mask is not None:  # the plate: paper on the floor is not the ring
            region = self.search_mask[oy : oy + image.shape[0], ox : ox + image.shape[1]]
        band = self._paper(image, region)
        edges, self.reason = self._closed_ring(band, offset)
        fine = None
        if edges is not None:
            fine = self._midline_of_band(*edges)
            self.reason, perimeter = self._plausible(fine)
            if not self.reason and self.radius is None:
                self.perimeters.append(perimeter)
        if edges is None or self.reason:
            closed_reason = self.reason if edges is not None else ""
            fine, self.reason = self._fitted_ring(band, offset)
            if fine is not None:
                self.reason, _ = self._plausible(fine)
            elif closed_reason:  # a closed ring was seen: why it was refused says more
                self.reason = closed_reason
        if fine is None or self.reason:
            self.reason = "membrane: " + self.reason
            return lost, None
        _, _, gx, gy = polygon_area_perimeter_centroid(fine[:, 0], fine[:, 1])
        gc = np.array([gx, gy])
        self.gc = gc
        midline = _start_at_angle_zero(_arclength_resample(fine, self.nodes), gc)
        # The inside: the wall's curve where the bot's outline is seen, less the paper.
        pu, pv = self.frame.to_pixels(fine[:, 0], fine[:, 1], self.bot_z)
        outline = np.stack([pu - ox, pv - oy], axis=1)
        bx, by = np.floor(outline.min(axis=0)).astype(int)
        ex, ey = np.ceil(outline.max(axis=0)).astype(int) + 1
        box = (bx + ox, by + oy, ex + ox, ey + oy)
        inside = np.zeros(band.shape, np.uint8)
        cv2.fillPoly(inside, [np.rint(outline * 16).astype(np.int32)], 1, cv2.LINE_8, 4)
        inside &= 1 - band
        if edges is not None:  # the band's hole, where the wall closes
            hole = np.zeros(band.shape, np.uint8)
            cv2.drawContours(hole, [edges[1] - offset], 0, 1, -1)
            inside |= hole & (1 - band)
        bot = self._bot(image, inside, band, ox, oy)
        flag = FLAGS["ok"] if np.isfinite(bot[0]) else FLAGS["bot_lost"]
        return (flag, (float(gc[0]), float(gc[1])), midline, bot), box

    @staticmethod
    def _mark_offset(mark: np.ndarray, m: dict, cu: float, cv_: float, axis: float) -> float | None:
        """Offset of a head mark from the bot's center along its axis (px, signed), or None
        unless the light region inside the bot looks like the mark: small,
        on the axis, between the center and an end (gaps where the bot touches the membrane
        are not marks). ``axis`` is the image-frame angle of the bot's axis."""
        mm = cv2.moments(mark, binaryImage=True)
        if mm["m00"] < 3 or mm["m00"] > 0.15 * m["m00"]:
            return None
        du, dv = mm["m10"] / mm["m00"] - cu, mm["m01"] / mm["m00"] - cv_
        along = np.cos(axis) * du + np.sin(axis) * dv
        across = -np.sin(axis) * du + np.cos(axis) * dv
        spread = np.linalg.eigvalsh(
            np.array([[m["mu20"], m["mu11"]], [m["mu11"], m["mu02"]]]) / m["m00"]
        )
        semi_minor, semi_major = 2 * np.sqrt(np.maximum(spread, 0.0))
        if not (
            0.3 * semi_major <= abs(along) <= 0.9 * semi_major and abs(across) <= 0.35 * semi_minor
        ):
            return None
        return float(along)

    def _bot(
        self, image: np.ndarray, inside: np.ndarray, band: np.ndarray, ox: int, oy: int
    ) -> tuple[float, float, float]:
        x, y, w, h = cv2.boundingRect(inside)
        if w == 0 or h == 0:
            self.reason = "bot: the ring has no inside"
            return (np.nan, np.nan, np.nan)
        roi = cv2.cvtColor(image[y : y + h, x : x + w], cv2.COLOR_BGR2GRAY)
        mask_in = inside[y : y + h, x : x + w]
        plate = float(np.median(roi[mask_in > 0]))  # the bot covers a small part of it
        dark = ((roi < self.dark_fraction * plate) & (mask_in > 0)).astype(np.uint8)
        contours, _ = cv2.findContours(dark, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        if not contours:
            self.reason = "bot: nothing dark inside the ring"
            return (np.nan, np.nan, np.nan)
        blob = max(contours, key=cv2.contourArea)
        if cv2.contourArea(blob) < 20:
            self.reason = "bot: nothing dark inside the ring"
            return (np.nan, np.nan, np.nan)
        # The bot is convex: its hull fills the head mark even where the mark meets its edge.
        filled = np.zeros(dark.shape, np.uint8)
        cv2.drawContours(filled, [cv2.convexHull(blob)], 0, 1, -1)
        filled &= mask_in
        m = cv2.moments(filled, binaryImage=True)
        cu, cv_ = m["m10"] / m["m00"], m["m01"] / m["m00"]
        moment_axis = 0.5 * np.arctan2(2 * m["mu11"], m["mu20"] - m["mu02"])  # image frame
        axis = moment_axis
        # Where the wall hides part of the bot, its outline there is the wall's: the ellipse
        # through the rest of its outline is the bot's.
        near_wall = cv2.dilate(band[y : y + h, x : x + w], np.ones((5, 5), np.uint8))
        hull, _ = cv2.findContours(filled, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        outline = max(hull, key=len)[:, 0, :]
        free = outline[near_wall[outline[:, 1], outline[:, 0]] == 0]
        if len(free) < len(outline) and len(free) >= max(20, 0.5 * len(outline)):
            (cu, cv_), (first, second), degrees = cv2.fitEllipse(free.astype(np.float32))
            axis = np.radians(degrees) + (np.pi / 2 if second > first else 0.0)  # major axis
            axis = (axis + np.pi / 2) % np.pi - np.pi / 2
            if abs(np.cos(axis - moment_axis)) < 0.7:  # a fit gone astray
                axis = moment_axis
        # The head mark: light holes of the dark region (not its edge's notches).
        holes = np.zeros(dark.shape, np.uint8)
        cv2.drawContours(holes, [blob], 0, 1, -1)
        holes &= (roi > 0.75 * plate).astype(np.uint8)
        along = self._mark_offset(holes, m, cu, cv_, axis)
        # The axis in the world: through two image points on it, mapped.
        step = 5.0
        pu = np.array([cu - step * np.cos(axis), cu, cu + step * np.cos(axis)]) + x + ox
        pv = np.array([cv_ - step * np.sin(axis), cv_, cv_ + step * np.sin(axis)]) + y + oy
        wx, wy = self.frame.to_world(pu, pv, self.bot_z)
        heading = float(np.arctan2(wy[2] - wy[0], wx[2] - wx[0]))  # towards +axis
        self.mark_seen = along is not None
        if along is not None:
            if along < 0:
                heading += np.pi
        elif self.heading is not None and np.cos(heading - self.heading) < 0:
            heading += np.pi
        if self.heading is not None:  # keep the heading continuous (unwrapped)
            heading = self.heading + (heading - self.heading + np.pi) % (2 * np.pi) - np.pi
        self.heading = heading
        self.reason = ""
        self.bot_outline = outline + np.array([x + ox, y + oy])
        return (float(wx[1]), float(wy[1]), float(heading))


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


def tracked_dataset(
    result: TrackResult, *, nodes: int, radius: float | None, attrs: dict
) -> xr.Dataset:
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
    data = {
        "membrane_x": membrane[None, :, :, 0],
        "membrane_y": membrane[None, :, :, 1],
        "cell_x": cell[None, :, 0],
        "cell_y": cell[None, :, 1],
        "bot_x": bot[None, :, 0],
        "bot_y": bot[None, :, 1],
        "bot_angle": bot[None, :, 2],
        "bot_phase": np.full((1, len(flags)), -1, dtype=np.int8),
    }
    data_vars = {
        name: (VARIABLES[name].dims, arr, VARIABLES[name].cf_attrs()) for name, arr in data.items()
    }
    data_vars["tracking_flag"] = (
        ("realization", "time"),
        flags[None],
        {
            "units": "1",
            "long_name": "tracking outcome per frame",
            "flag_values": np.array(list(FLAGS.values()), dtype=np.int8),
            "flag_meanings": " ".join(FLAGS),
        },
    )
    coords = {
        "realization": ("realization", np.array([0]), COORDINATES["realization"].cf_attrs()),
        "time": ("time", np.array(result.times), COORDINATES["time"].cf_attrs()),
        "node": ("node", np.arange(nodes), COORDINATES["node"].cf_attrs()),
    }
    attrs = global_attrs(
        "tracking",
        "soft robotic cell tracked from video",
        f"softcell {__version__} tracker",
        **attrs,
        softcell_tracking_summary=json.dumps(summary),
        softcell_parameters=json.dumps({"radius": radius}),
        softcell_parameter_units=json.dumps({"radius": "cm"}),
    )
    return validate(xr.Dataset(data_vars, coords, attrs))
