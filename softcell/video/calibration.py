"""A camera above the plate, calibrated from the plate itself: image pixels to plate cm.

A real camera above the 1 m plate sees it in perspective (the camera is never exactly level),
through a lens that bends straight lines (radial distortion), and sees every object standing
on the plate from a point above it (parallax: the top of a 3 cm wall at 12 cm from the point
below the camera appears 0.24 cm further out from 150 cm). :class:`PlateCamera` undoes the
three:

- **distortion**: one radial coefficient ``k`` about the image center, in OpenCV's form
  (undistorted point p, distorted c + (p - c)(1 + k |p - c|^2 / s^2), ``s`` the larger image
  side in px), estimated so that the plate's four edges are straightest;
- **perspective**: the homography between the undistorted image and the plate (cm), from the
  plate's four corners (the intersections of its fitted edges);
- **parallax**: the camera's position above the plate, from the homography and either the
  camera's height (``camera_height``) or its focal length (a checkerboard calibration, or
  estimated from the homography when the camera is tilted enough); a point seen at pixel (u, v)
  that stands at height z lies on the line from the camera to the plate point below (u, v).

Plate coordinates: the origin is the plate corner seen at the image's lower left, x runs along
the edge towards the lower-right corner, y towards the upper-left corner, z up; all in cm.
A camera matrix and distortion from ``cv2.calibrateCamera`` (read from its file by
:func:`softcell.video.track.read_calibration`) replace the estimated distortion and focal length.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.optimize import brentq, minimize_scalar

from softcell.errors import SoftcellError

#: Points sampled along each plate edge, and the part of the edge they cover (its corners
#: are rounded by blur and shadows).
EDGE_SAMPLES = 160
EDGE_SPAN = (0.08, 0.92)
#: Largest |k| considered: beyond it a lens is a fish-eye and wants a checkerboard.
MAX_K = 0.6


class CalibrationError(SoftcellError):
    """The plate could not be found, or the camera not calibrated from it."""


@dataclass(frozen=True)
class PlateCamera:
    """Image pixels (OpenCV: pixel centers at integers, v down) to plate points (cm).

    Attributes
    ----------
    homography : ndarray [3, 3]
        Plate (cm, z = 0) to undistorted pixels.
    center : (float, float)
        Principal point (px); the image center unless a calibration says otherwise.
    scale : float
        Length (px) that normalizes the distortion radius (the larger image side).
    k : float
        Radial distortion coefficient (dimensionless, about ``center``, per ``scale``).
    position : ndarray [3] or None
        The camera's optical center in plate coordinates (cm), None when unknown (then only
        z = 0 can be mapped).
    width, height : int
        Frame size (px).
    plate_size : float
        The plate's side (cm).
    camera_matrix, distortion : ndarray or None
        OpenCV's camera matrix and distortion coefficients, when a calibration file gave them
        (they replace ``k``).
    """

    homography: np.ndarray
    center: tuple[float, float]
    scale: float
    k: float
    position: np.ndarray | None
    width: int
    height: int
    plate_size: float
    camera_matrix: np.ndarray | None = None
    distortion: np.ndarray | None = None

    @property
    def px_per_cm(self) -> float:
        """Mean scale (px per cm) at the plate's center, for sizes in pixels."""
        middle = self.plate_size / 2
        return float(
            np.sqrt(abs(np.linalg.det(_homography_jacobian(self.homography, middle, middle))))
        )

    def undistort(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Undistorted pixel positions of observed ones."""
        u, v = np.asarray(u, np.float64), np.asarray(v, np.float64)
        if self.camera_matrix is not None:
            pts = np.stack([u.ravel(), v.ravel()], axis=1).reshape(-1, 1, 2)
            out = cv2.undistortPoints(
                pts, self.camera_matrix, self.distortion, P=self.camera_matrix
            ).reshape(-1, 2)
            return out[:, 0].reshape(u.shape), out[:, 1].reshape(v.shape)
        return _undistort(u, v, self.center, self.scale, self.k)

    def distort(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Observed pixel positions of undistorted ones."""
        u, v = np.asarray(u, np.float64), np.asarray(v, np.float64)
        if self.camera_matrix is not None:
            k = self.camera_matrix
            x = (u - k[0, 2]) / k[0, 0]
            y = (v - k[1, 2]) / k[1, 1]
            pts = np.stack([x.ravel(), y.ravel(), np.ones(x.size)], axis=1)
            out, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), k, self.distortion)
            out = out.reshape(-1, 2)
            return out[:, 0].reshape(u.shape), out[:, 1].reshape(v.shape)
        du, dv = u - self.center[0], v - self.center[1]
        d = 1 + self.k * (du**2 + dv**2) / self.scale**2
        return self.center[0] + du * d, self.center[1] + dv * d

    def to_world(
        self, u: np.ndarray, v: np.ndarray, z: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Plate points (cm) seen at pixels (u, v) of objects at height ``z`` (cm)."""
        uu, vv = self.undistort(u, v)
        inverse = np.linalg.inv(self.homography)
        x, y = _apply(inverse, uu, vv)
        if z:
            c = self._position_for(z)
            factor = 1 - z / c[2]
            x, y = c[0] + (x - c[0]) * factor, c[1] + (y - c[1]) * factor
        return x, y

    def to_pixels(
        self, x: np.ndarray, y: np.ndarray, z: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (u, v) where plate points (cm) at height ``z`` (cm) are seen."""
        x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
        if z:
            c = self._position_for(z)
            factor = c[2] / (c[2] - z)
            x, y = c[0] + (x - c[0]) * factor, c[1] + (y - c[1]) * factor
        return self.distort(*_apply(self.homography, x, y))

    def plate_mask(self, inset: float = 0.5) -> np.ndarray:
        """A uint8 mask [height, width] of the plate in the image, ``inset`` cm inside its
        edges: where a cell on the plate can be (the floor around it is not searched)."""
        side = np.linspace(inset, self.plate_size - inset, 40)
        low, high = np.full(40, inset), np.full(40, self.plate_size - inset)
        x = np.concatenate([side, high, side[::-1], low])
        y = np.concatenate([low, side, high, side[::-1]])
        u, v = self.to_pixels(x, y)
        mask = np.zeros((self.height, self.width), np.uint8)
        cv2.fillPoly(
            mask, [np.rint(np.stack([u, v], axis=1) * 16).astype(np.int32)], 1, cv2.LINE_8, 4
        )
        return mask

    def _position_for(self, z: float) -> np.ndarray:
        if self.position is None:
            raise CalibrationError(
                f"an object height of {z:g} cm needs the camera's position above the plate, "
                "which the plate alone did not give (the camera looks almost straight "
                "down): pass the camera height (--camera-height, cm) or a calibration file"
            )
        if not z < self.position[2]:
            raise CalibrationError(
                f"an object height of {z:g} cm is not below the camera "
                f"({self.position[2]:.1f} cm above the plate)"
            )
        return self.position

    def summary(self) -> dict[str, object]:
        """What the calibration found, for a file's attributes."""
        out: dict[str, object] = {
            "px_per_cm": round(self.px_per_cm, 6),
            "k": round(float(self.k), 6),
            "principal_point_px": [float(c) for c in self.center],
        }
        if self.position is not None:
            out["camera_position_cm"] = [round(float(c), 4) for c in self.position]
        return out


def _apply(h: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    w = h[2, 0] * x + h[2, 1] * y + h[2, 2]
    return (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / w, (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / w


def _homography_jacobian(h: np.ndarray, x: float, y: float) -> np.ndarray:
    eps = 1e-3
    u1, v1 = _apply(h, np.array([x - eps, x + eps, x, x]), np.array([y, y, y - eps, y + eps]))
    return np.array([[u1[1] - u1[0], u1[3] - u1[2]], [v1[1] - v1[0], v1[3] - v1[2]]]) / (2 * eps)


def _undistort(u, v, center, scale, k, iterations: int = 25):
    du, dv = u - center[0], v - center[1]
    xu, yu = du.copy(), dv.copy()
    for _ in range(iterations):  # fixed point: converges for |k| r^2 < 1/3
        d = 1 + k * (xu**2 + yu**2) / scale**2
        xu, yu = du / d, dv / d
    return center[0] + xu, center[1] + yu


# --- finding the plate ------------------------------------------------------------------------


def plate_corners(gray: np.ndarray) -> np.ndarray:
    """The plate's four corners (px) in a grey image: lower-left, lower-right, upper-right,
    upper-left as seen (image v down), from the largest bright region."""
    blurred = cv2.GaussianBlur(gray, (0, 0), 2)
    level, mask = cv2.threshold(blurred, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    light, dark = blurred[mask > 0], blurred[mask == 0]
    if not light.size or not dark.size or np.median(light) - np.median(dark) < 20:
        raise CalibrationError("no plate found: the frame shows no light square on a darker floor")
    mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, np.ones((15, 15), np.uint8))
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        raise CalibrationError("no plate found: the frame has no bright region")
    plate = max(contours, key=cv2.contourArea)
    area = cv2.contourArea(plate)
    if area < 0.1 * gray.size:
        raise CalibrationError(
            f"no plate found: the largest bright region covers "
            f"{area / gray.size:.0%} of the frame (at least 10 % expected)"
        )
    hull = cv2.convexHull(plate)
    quad = None
    for eps in np.linspace(0.005, 0.08, 30):
        approx = cv2.approxPolyDP(hull, eps * cv2.arcLength(hull, True), True)
        if len(approx) == 4:
            quad = approx[:, 0, :].astype(np.float64)
            break
    if quad is None:
        raise CalibrationError(
            "the plate is not a quadrilateral in the frame: is it wholly "
            "in view, with its four corners visible?"
        )
    h, w = gray.shape
    if (quad.min(axis=0) < 3).any() or quad[:, 0].max() > w - 4 or quad[:, 1].max() > h - 4:
        raise CalibrationError(
            "the plate touches the frame's border: its four corners must be in view"
        )
    # Order as seen: lower-left (largest v - u), then counter-clockwise on screen.
    start = int(np.argmax(quad[:, 1] - quad[:, 0]))
    quad = np.roll(quad, -start, axis=0)
    a, b = quad[1] - quad[0], quad[2] - quad[0]
    if a[0] * b[1] - a[1] * b[0] > 0:  # clockwise in v-down: flip
        quad = np.vstack([quad[:1], quad[1:][::-1]])
    return quad


def edge_points(gray: np.ndarray, corners: np.ndarray) -> list[np.ndarray]:
    """Sub-pixel points of the plate's four edges (px): along each side between the corners,
    where the profile across the edge crosses halfway between its local plate and floor
    levels (so vignetting and shadows do not move it)."""
    image = cv2.GaussianBlur(gray.astype(np.float32), (0, 0), 1.0)
    edges = []
    offsets = np.linspace(-10, 10, 81)
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        along = b - a
        normal = np.array([-along[1], along[0]]) / np.hypot(*along)
        s = np.linspace(*EDGE_SPAN, EDGE_SAMPLES)
        base = a + s[:, None] * along
        pts = base[:, None, :] + offsets[None, :, None] * normal
        grid = pts.astype(np.float32)
        profile = cv2.remap(
            image, grid[..., 0], grid[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
        found = []
        for row, line in zip(base, profile, strict=True):
            lo, hi = np.percentile(line[:15], 50), np.percentile(line[-15:], 50)
            level = 0.5 * (lo + hi)
            rel = line - level
            cross = np.nonzero(np.sign(rel[:-1]) != np.sign(rel[1:]))[0]
            if abs(hi - lo) < 10 or cross.size != 1:
                continue
            i = cross[0]
            t = offsets[i] + (offsets[i + 1] - offsets[i]) * rel[i] / (rel[i] - rel[i + 1])
            found.append(row + t * normal)
        if len(found) < EDGE_SAMPLES // 3:
            raise CalibrationError(
                f"the plate's edge {k + 1} of 4 is not visible along most of its length"
            )
        edges.append(np.array(found))
    return edges


def _line_residuals(points: np.ndarray) -> np.ndarray:
    """Signed distances (px) of points from their total-least-squares line."""
    line = _fit_line(points)
    return points @ line[:2] + line[2]


def _fit_line(points: np.ndarray) -> np.ndarray:
    """Homogeneous line (a, b, c), a u + b v + c = 0, through points by total least squares."""
    mean = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - mean, full_matrices=False)
    n = vt[1]
    return np.array([n[0], n[1], -n @ mean])


def estimate_distortion(
    edges: list[np.ndarray], center: tuple[float, float], scale: float
) -> float:
    """The radial coefficient k that makes the edges straightest (least squares)."""

    def cost(k: float) -> float:
        total = 0.0
        for pts in edges:
            u, v = _undistort(pts[:, 0], pts[:, 1], center, scale, k)
            total += float(np.sum(_line_residuals(np.stack([u, v], axis=1)) ** 2))
        return total

    result = minimize_scalar(
        cost, bounds=(-MAX_K, MAX_K), method="bounded", options={"xatol": 1e-6}
    )
    if abs(result.x) > 0.98 * MAX_K:
        raise CalibrationError(
            f"the lens distortion is beyond |k| = {MAX_K} (k = "
            f"{result.x:.3f}): calibrate the camera with a checkerboard "
            "and pass its file"
        )
    return float(result.x)


def calibrate_from_plate(
    image: np.ndarray,
    plate_size: float,
    *,
    camera_height: float | None = None,
    calibration: tuple[np.ndarray, np.ndarray] | None = None,
) -> PlateCamera:
    """A :class:`PlateCamera` from one frame that shows the whole plate.

    Parameters
    ----------
    image : ndarray
        A BGR (or grey) uint8 frame.
    plate_size : float
        The plate's side (cm); the plate is square.
    camera_height : float, optional
        Height (cm) of the camera's optical center above the plate, for parallax.
    calibration : (camera matrix [3, 3], distortion coefficients), optional
        From ``cv2.calibrateCamera``; replaces the estimated distortion and focal length.

    Raises
    ------
    CalibrationError
        When the plate is not wholly in view, or the calibration fails.
    """
    if not (np.isfinite(plate_size) and plate_size > 0):
        raise CalibrationError(
            f"plate_size = {plate_size} is not allowed: must be finite and > 0 cm"
        )
    if camera_height is not None and not (np.isfinite(camera_height) and camera_height > 0):
        raise CalibrationError(
            f"camera_height = {camera_height} is not allowed: must be finite and > 0 cm"
        )
    gray = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    h, w = gray.shape
    corners = plate_corners(gray)
    edges = edge_points(gray, corners)
    scale = float(max(w, h))
    if calibration is not None:
        matrix, dist = (np.asarray(c, np.float64) for c in calibration)
        center = (float(matrix[0, 2]), float(matrix[1, 2]))
        k = 0.0
        probe = PlateCamera(np.eye(3), center, scale, 0.0, None, w, h, 1.0, matrix, dist)
        lines = [_fit_line(np.stack(probe.undistort(p[:, 0], p[:, 1]), axis=1)) for p in edges]
    else:
        center = ((w - 1) / 2, (h - 1) / 2)
        k = estimate_distortion(edges, center, scale)
        lines = [
            _fit_line(np.stack(_undistort(p[:, 0], p[:, 1], center, scale, k), axis=1))
            for p in edges
        ]
        matrix = dist = None
    # Corner k is where edge k-1 meets edge k.
    image_corners = []
    for j in range(4):
        p = np.cross(lines[j - 1], lines[j])
        image_corners.append(p[:2] / p[2])
    s = float(plate_size)
    plate = np.array([[0, 0], [s, 0], [s, s], [0, s]], np.float64)
    homography = _homography(plate, np.array(image_corners))
    focal = None if matrix is None else float(np.sqrt(matrix[0, 0] * matrix[1, 1]))
    position = _camera_position(homography, center, focal, camera_height, scale)
    return PlateCamera(homography, center, scale, k, position, w, h, s, matrix, dist)


def _homography(plate: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """The exact homography of four point pairs, in double precision."""
    a = []
    for (x, y), (u, v) in zip(plate, corners, strict=True):
        a.append([x, y, 1, 0, 0, 0, -u * x, -u * y, -u])
        a.append([0, 0, 0, x, y, 1, -v * x, -v * y, -v])
    _, _, vt = np.linalg.svd(np.array(a))
    out = vt[-1].reshape(3, 3)
    return out / out[2, 2]


def _pose(h: np.ndarray, center: tuple[float, float], focal: float) -> np.ndarray:
    """Camera center (cm, plate frame) of a plate homography, given the focal length (px)."""
    k_inv = np.array(
        [[1 / focal, 0, -center[0] / focal], [0, 1 / focal, -center[1] / focal], [0, 0, 1]]
    )
    m = k_inv @ h
    lam = 2 / (np.linalg.norm(m[:, 0]) + np.linalg.norm(m[:, 1]))
    r1, r2, t = lam * m[:, 0], lam * m[:, 1], lam * m[:, 2]
    u, _, vt = np.linalg.svd(np.stack([r1, r2, np.cross(r1, r2)], axis=1))
    r = u @ vt
    c = -r.T @ t
    return c if c[2] > 0 else -c


def _camera_position(
    h: np.ndarray,
    center: tuple[float, float],
    focal: float | None,
    camera_height: float | None,
    scale: float,
) -> np.ndarray | None:
    if focal is not None:
        return _pose(h, center, focal)
    if camera_height is not None:
        # The focal length that puts the camera at the given height.
        def gap(f: float) -> float:
            return float(_pose(h, center, f)[2] - camera_height)

        try:
            focal = brentq(gap, 0.1 * scale, 20 * scale, xtol=1e-6)
        except ValueError:
            raise CalibrationError(
                f"no camera at {camera_height:g} cm above the plate fits the plate's image"
            ) from None
        return _pose(h, center, focal)
    # The focal length from the homography alone (a square-pixel camera): its rotation's
    # first two columns are orthogonal and of equal length. Ill-posed when looking straight
    # down: then no position.
    c = np.array([[1, 0, -center[0]], [0, 1, -center[1]], [0, 0, 1.0]])
    m = c @ h
    m = m / np.linalg.norm(m)
    h1, h2 = m[:, 0], m[:, 1]
    a = np.array([h1[0] * h2[0] + h1[1] * h2[1], h1[0] ** 2 + h1[1] ** 2 - h2[0] ** 2 - h2[1] ** 2])
    b = np.array([h1[2] * h2[2], h1[2] ** 2 - h2[2] ** 2])
    each = -a / np.where(b == 0, np.nan, b)  # f^2 from either condition
    w = -float(a @ b) / float(b @ b) if b @ b > 0 else np.nan  # both, least squares
    if not (
        np.isfinite(each).all() and (each > 0).all() and w > 0 and each.max() < 2.25 * each.min()
    ):
        return None  # the two disagree by more than 1.5x in f: looking (almost) straight down
    return _pose(h, center, np.sqrt(w))
