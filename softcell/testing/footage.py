"""Camera-like footage of a cell, for testing the tracker against what a real camera sees.

Independent of :mod:`softcell.video.render` (which draws flat shapes on a flat image): every
pixel here is a bundle of rays cast from a pinhole camera above a plate, through a lens with
radial distortion, into a 3D scene: a light square plate on a darker floor, the membrane a
paper wall of finite height and thickness standing on it, the bot an elliptic cylinder with
a dark top, a green circuit board and a bright LED at its head. Each effect is a parameter of
:class:`Scene`: tilt, radial distortion, vignetting, soft shadows (a lamp's arm across the
plate and the bot's and wall's own, cast by a lamp at a slant), Bayer sensor noise, motion
blur, MPEG-4 4:2:0 compression (an ``.mp4`` path), off-red paper with a highlight.

Coordinates: the plate's corner at the image's lower left is the origin, x along the edge
towards the lower-right corner, y towards the upper-left one, z up (cm). The camera follows
OpenCV: pixel centers at integers, x right, y down, k1 on normalized coordinates
(u - cx) / f.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
import xarray as xr

#: BGR colours (0..255) of the scene's materials, before light and sensor.
PLATE = np.array([196.0, 198.0, 200.0])
FLOOR = np.array([70.0, 80.0, 90.0])
RED_PAPER = np.array([45.0, 40.0, 205.0])
OFF_RED_PAPER = np.array([40.0, 95.0, 225.0])  # orange-ish
BOT_TOP = np.array([38.0, 36.0, 40.0])
BOT_SIDE = np.array([28.0, 27.0, 30.0])
PCB = np.array([45.0, 95.0, 40.0])
LED = np.array([235.0, 245.0, 250.0])


@dataclass(frozen=True)
class Scene:
    """One camera above a plate, and every effect as a parameter (lengths in cm).

    ``tilt`` (degrees, about the camera's x and y axes), ``k1`` (OpenCV radial distortion),
    ``vignetting`` (relative fall-off at the frame's corner), ``shadow`` (relative darkness of
    the lamp arm's soft shadow across the plate, 0: none), ``cast_shadow`` (darkness of the
    bot's and wall's shadows), ``noise`` (sensor noise, grey levels, through a Bayer mosaic),
    ``blur`` (exposure as a fraction of the frame interval: motion blur), ``off_red`` (orange
    paper with a specular highlight), ``paper`` (another colour, BGR), ``wall`` thickness
    and ``ring_height``, ``bot_height``.
    """

    size: int = 1024
    focal: float = 1500.0  # px: 10 px/cm on the plate from 150 cm
    camera_height: float = 150.0
    camera_xy: tuple[float, float] = (40.0, 40.0)
    plate_size: float = 80.0
    tilt: tuple[float, float] = (0.0, 0.0)
    k1: float = 0.0
    ring_height: float = 3.0
    wall: float = 0.3
    bot_height: float = 2.5
    vignetting: float = 0.0
    shadow: float = 0.0
    cast_shadow: float = 0.0
    noise: float = 0.0
    blur: float = 0.0
    off_red: bool = False
    paper: tuple[float, float, float] | None = None  # BGR, instead of red or orange
    light: tuple[float, float, float] = (0.45, 0.25, 1.0)  # towards the lamp
    oversample: int = 2

    @property
    def rotation(self) -> np.ndarray:
        """World (plate) to camera rotation: looking down, image up along +y, then tilted."""
        ax, ay = np.radians(self.tilt)
        rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
        ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
        return rx @ ry @ np.diag([1.0, -1.0, -1.0])

    @property
    def center(self) -> np.ndarray:
        return np.array([*self.camera_xy, self.camera_height])

    def camera_matrix(self) -> np.ndarray:
        c = (self.size - 1) / 2
        return np.array([[self.focal, 0, c], [0, self.focal, c], [0, 0, 1.0]])

    def project(
        self, x: np.ndarray, y: np.ndarray, z: np.ndarray | float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Pixel (u, v) of plate points (cm) at height z: the forward camera model."""
        world = np.stack(np.broadcast_arrays(x, y, z), axis=-1) - self.center
        cam = world @ self.rotation.T
        xn, yn = cam[..., 0] / cam[..., 2], cam[..., 1] / cam[..., 2]
        d = 1 + self.k1 * (xn**2 + yn**2)
        c = (self.size - 1) / 2
        return self.focal * xn * d + c, self.focal * yn * d + c

    def rays(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For pixel positions: the ray's point on the plate p0 [..., 2] and its horizontal
        drift per cm of height g [..., 2], so that it passes over p0 + z g at height z."""
        c = (self.size - 1) / 2
        xd, yd = (u - c) / self.focal, (v - c) / self.focal
        xn, yn = xd.copy(), yd.copy()
        for _ in range(20):  # undistort by fixed point (|k1| r^2 << 1)
            d = 1 + self.k1 * (xn**2 + yn**2)
            xn, yn = xd / d, yd / d
        direction = np.stack([xn, yn, np.ones_like(xn)], axis=-1) @ self.rotation  # R^T d
        g = direction[..., :2] / direction[..., 2:]
        p0 = self.center[:2] - self.camera_height * g
        return p0, g


@dataclass
class Footage:
    """What :func:`film` wrote: the frames' times (s) and the truth in plate coordinates:
    cell GC (cm), bot center (cm), heading (rad), membrane curve [frames, points, 2] (cm)."""

    path: Path
    times: np.ndarray
    cell: np.ndarray
    bot: np.ndarray
    heading: np.ndarray
    membrane: np.ndarray
    scene: Scene
    notes: dict = field(default_factory=dict)


def _subpixel_grid(u0: int, v0: int, width: int, height: int, n: int):
    offsets = (np.arange(n) + 0.5) / n - 0.5
    uu = u0 + np.arange(width)[None, :, None, None] + offsets[None, None, None, :]
    vv = v0 + np.arange(height)[:, None, None, None] + offsets[None, None, :, None]
    return np.broadcast_to(uu, (height, width, n, n)), np.broadcast_to(vv, (height, width, n, n))


def _plate_colour(scene: Scene, p: np.ndarray) -> np.ndarray:
    """Colour of the floor and plate at plate points p [..., 2], with the lamp arm's shadow."""
    x, y = p[..., 0], p[..., 1]
    inside = (x >= 0) & (x <= scene.plate_size) & (y >= 0) & (y <= scene.plate_size)
    colour = np.where(inside[..., None], PLATE, FLOOR)
    if scene.shadow:
        # A soft band (the lamp arm's shadow), 6 cm wide, 4 cm penumbra, across the plate
        # through its middle at 30 degrees: the cell drives in and out of it.
        mid = scene.plate_size / 2
        across = (x - mid) * np.sin(np.radians(30)) - (y - mid) * np.cos(np.radians(30))
        dark = scene.shadow * np.clip((3.0 + 2.0 - np.abs(across)) / 4.0, 0, 1)
        colour = colour * (1 - dark[..., None])
    return colour


class _Membrane:
    """The wall's signed distance (cm, negative inside) on a fine grid, and its normal."""

    def __init__(self, curve: np.ndarray, resolution: float = 0.02) -> None:
        lo = curve.min(axis=0) - 2.0
        hi = curve.max(axis=0) + 2.0
        self.lo, self.res = lo, resolution
        shape = np.ceil((hi - lo) / resolution).astype(int)
        sub = 16
        pts = np.rint((curve - lo) / resolution * sub).astype(np.int32)
        mask = np.zeros((shape[1], shape[0]), np.uint8)
        cv2.fillPoly(mask, [pts], 1, cv2.LINE_8, 4)
        outside = cv2.distanceTransform(1 - mask, cv2.DIST_L2, 5)
        inside = cv2.distanceTransform(mask, cv2.DIST_L2, 5)
        self.sd = ((outside - inside) * resolution).astype(np.float32)
        gy, gx = np.gradient(cv2.GaussianBlur(self.sd, (0, 0), 2))
        norm = np.hypot(gx, gy) + 1e-9
        self.nx, self.ny = (gx / norm).astype(np.float32), (gy / norm).astype(np.float32)

    def sample(self, field: np.ndarray, p: np.ndarray) -> np.ndarray:
        q = ((p - self.lo) / self.res).astype(np.float32).reshape(-1, 2)
        count = q.shape[0]
        width = 4096  # remap's maps are images: at most 32767 on a side
        q = np.concatenate([q, np.zeros((-count % width, 2), np.float32)])
        grid = q.reshape(-1, width, 2)
        out = cv2.remap(
            field, grid[..., 0], grid[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
        return out.reshape(-1)[:count].reshape(p.shape[:-1])


def _bot_local(p: np.ndarray, bot: np.ndarray, heading: float) -> tuple[np.ndarray, np.ndarray]:
    dx, dy = p[..., 0] - bot[0], p[..., 1] - bot[1]
    c, s = np.cos(heading), np.sin(heading)
    return c * dx + s * dy, -s * dx + c * dy


def _in_cast_shadow(
    scene: Scene,
    p0: np.ndarray,
    light: np.ndarray,
    top: float,
    wall: _Membrane,
    bot: np.ndarray,
    heading: float,
    a: float,
    b: float,
) -> np.ndarray:
    """Where the plate points ``p0`` lie in a cast shadow: the ray from the plate point
    towards the lamp meets the bot or the wall below their tops."""
    blocked = np.zeros(p0.shape[:-1], bool)
    previous = None
    for z in np.linspace(0.0, top, 8):
        q = p0 + z * light[:2]
        if z <= scene.bot_height:
            lx, ly = _bot_local(q, bot, heading)
            blocked |= (lx / a) ** 2 + (ly / b) ** 2 <= 1
        if z <= scene.ring_height:  # the light's ray meets the wall, or crosses it
            sd = wall.sample(wall.sd, q)
            blocked |= np.abs(sd) <= scene.wall / 2
            if previous is not None:
                blocked |= np.sign(sd) != np.sign(previous)
            previous = sd
    return blocked


def _wall_colour(
    scene: Scene, wall: _Membrane, p: np.ndarray, z: float, paper: np.ndarray, light: np.ndarray
) -> np.ndarray:
    """The paper's colour where the rays meet the wall at height ``z`` (cm): lit on top,
    shaded on the side, with a highlight where it faces the lamp (off-red paper)."""
    shade = 1.0 if z >= scene.ring_height - 1e-9 else 0.82
    c = np.broadcast_to(paper * shade, (*p.shape[:-1], 3)).copy()
    if scene.off_red:  # a highlight where the wall faces the lamp
        n = np.stack([wall.sample(wall.nx, p), wall.sample(wall.ny, p)], axis=-1)
        facing = np.abs(n @ (light[:2] / np.hypot(*light[:2])))
        gloss = 0.5 * np.clip((facing - 0.9) / 0.1, 0, 1)[..., None]
        c = c * (1 - gloss) + 250.0 * gloss
    return c


def _bot_colour(
    scene: Scene,
    lx: np.ndarray,
    ly: np.ndarray,
    z: float,
    a: float,
    b: float,
    shape: tuple[int, ...],
) -> np.ndarray:
    """The bot's colour at body coordinates (lx, ly) (cm) met at height ``z`` (cm): its top
    with the board and the LED, or its side."""
    if z >= scene.bot_height - 1e-9:
        c = np.broadcast_to(BOT_TOP, (*shape, 3)).copy()
        pcb = (lx > -0.75 * a) & (lx < 0.1 * a) & (np.abs(ly) < 0.55 * b)
        led = (lx - 0.7 * a) ** 2 + ly**2 <= (0.22 * b) ** 2
        c[pcb] = PCB
        c[led] = LED
        return c
    return np.broadcast_to(BOT_SIDE, (*shape, 3))


def _shade_roi(
    scene: Scene,
    p0: np.ndarray,
    g: np.ndarray,
    wall: _Membrane,
    bot: np.ndarray,
    heading: float,
    a: float,
    b: float,
) -> np.ndarray:
    """Colour of the rays (p0, g) [..., 2]: the highest surface each meets, walking down."""
    top = max(scene.ring_height, scene.bot_height)
    # Heights walked down: the tops exactly (a top face is met there), the rest in steps.
    levels = np.unique(
        np.concatenate([np.linspace(top, 0.0, 16), [scene.ring_height, scene.bot_height]])
    )[::-1]
    colour = _plate_colour(scene, p0)
    # Cast shadows on the plate: the ray from the plate point towards the lamp meets the
    # bot or the wall below their tops.
    light = np.array(scene.light) / scene.light[2]
    if scene.cast_shadow:
        blocked = _in_cast_shadow(scene, p0, light, top, wall, bot, heading, a, b)
        colour = colour * (1 - scene.cast_shadow * blocked[..., None])
    paper = (
        np.array(scene.paper)
        if scene.paper is not None
        else (OFF_RED_PAPER if scene.off_red else RED_PAPER)
    )
    hit = np.zeros(p0.shape[:-1], bool)
    previous = None
    for z in levels:
        p = p0 + z * g
        sd = wall.sample(wall.sd, p)
        lx, ly = _bot_local(p, bot, heading)
        in_bot = (z <= scene.bot_height) & ((lx / a) ** 2 + (ly / b) ** 2 <= 1)
        on_wall = (z <= scene.ring_height) & (np.abs(sd) <= scene.wall / 2)
        if previous is not None and z < scene.ring_height:
            on_wall |= np.sign(sd) != np.sign(previous)  # crossed a thin wall in between
        previous = sd
        new_wall = on_wall & ~hit & ~(in_bot & (z >= scene.ring_height))
        new_bot = in_bot & ~hit & ~new_wall
        if new_wall.any():
            c = _wall_colour(scene, wall, p, z, paper, light)
            colour = np.where(new_wall[..., None], c, colour)
        if new_bot.any():
            c = _bot_colour(scene, lx, ly, z, a, b, p0.shape[:-1])
            colour = np.where(new_bot[..., None], c, colour)
        hit |= new_wall | new_bot
    return colour


def _roi_box(scene: Scene, fine: np.ndarray) -> tuple[int, int, int, int]:
    """The pixels (u0, v0, u1, v1) that can see the cell whose wall is ``fine`` (cm): the
    projection of its bounding box, 1 cm larger, from the plate to the wall's top."""
    lo = fine.min(axis=0) - 1.0
    hi = fine.max(axis=0) + 1.0
    us, vs = [], []
    for z in (0.0, scene.ring_height):
        for x in (lo[0], hi[0]):
            for y in (lo[1], hi[1]):
                u, v = scene.project(x, y, z)
                us.append(u)
                vs.append(v)
    n = scene.size
    u0, v0 = max(int(min(us)) - 4, 0), max(int(min(vs)) - 4, 0)
    u1, v1 = min(int(max(us)) + 5, n), min(int(max(vs)) + 5, n)
    return u0, v0, u1, v1


def film(
    ds: xr.Dataset,
    path: str | Path,
    scene: Scene,
    *,
    offset: tuple[float, float],
    fps: float = 30.0,
    end: float | None = None,
    seed: int = 0,
) -> Footage:
    """Film realization 0 of a simulated cell with ``scene``'s camera; the simulation's
    origin sits at plate point ``offset`` (cm). ``.mkv``: lossless FFV1; ``.mp4``: MPEG-4
    4:2:0. Returns the truth at the frame times, in plate coordinates."""
    path = Path(path)
    sel = ds.isel(realization=0)
    t_end = float(sel.time[-1]) if end is None else end
    times = np.arange(0.0, t_end + 1e-9, 1 / fps)
    parameters = json.loads(ds.attrs.get("softcell_parameters", "{}"))
    a = float(parameters.get("bot_semi_major", 3.0))
    b = float(parameters.get("bot_semi_minor", 2.0))
    rng = np.random.default_rng(seed)
    n = scene.size
    # The static frame: plate and floor, oversampled 4 x 4 (their edges calibrate).
    background = np.zeros((n, n, 3))
    for row in range(0, n, 128):
        uu, vv = _subpixel_grid(0, row, n, 128, 4)
        p0, _ = scene.rays(uu, vv)
        background[row : row + 128] = _plate_colour(scene, p0).mean(axis=(2, 3))
    rays = (
        np.empty((n, n, scene.oversample, scene.oversample, 2)),
        np.empty((n, n, scene.oversample, scene.oversample, 2)),
    )
    for row in range(0, n, 128):
        uu, vv = _subpixel_grid(0, row, n, 128, scene.oversample)
        rays[0][row : row + 128], rays[1][row : row + 128] = scene.rays(uu, vv)
    c = (n - 1) / 2
    yy, xx = np.mgrid[0:n, 0:n]
    r2 = ((xx - c) ** 2 + (yy - c) ** 2) / (2 * c**2)
    vignette = (1 - scene.vignetting * r2)[..., None]
    fourcc = cv2.VideoWriter_fourcc(*("mp4v" if path.suffix == ".mp4" else "FFV1"))
    writer = cv2.VideoWriter(str(path), fourcc, fps, (n, n))
    truth = {"cell": [], "bot": [], "heading": [], "membrane": []}
    sub_times = [0.0] if not scene.blur else list(np.linspace(-0.5, 0.5, 3) * scene.blur / fps)
    off = np.asarray(offset)

    record_t = sel.time.values
    record = {
        name: np.asarray(sel[name].transpose("time", ...).values)
        for name in ("membrane_x", "membrane_y", "bot_x", "bot_y", "cell_x", "cell_y")
    }
    record["bot_angle"] = np.unwrap(sel.bot_angle.values)

    def at(name, t):
        values = record[name]
        if values.ndim == 1:
            return float(np.interp(t, record_t, values))
        return np.array([np.interp(t, record_t, column) for column in values.T])

    def state(t):
        curve = np.stack([at("membrane_x", t), at("membrane_y", t)], axis=1) + off
        return (
            curve,
            np.array([at("bot_x", t), at("bot_y", t)]) + off,
            at("bot_angle", t),
            np.array([at("cell_x", t), at("cell_y", t)]) + off,
        )

    try:
        for t in times:
            image = background.copy()
            frames = []
            for dt in sub_times:
                curve, bot, heading, gc = state(t + dt)
                fine = _fine(curve, 1440)
                wall = _Membrane(fine)
                u0, v0, u1, v1 = _roi_box(scene, fine)
                p0 = rays[0][v0:v1, u0:u1]
                g = rays[1][v0:v1, u0:u1]
                roi = _shade_roi(scene, p0, g, wall, bot, heading, a, b).mean(axis=(2, 3))
                frames.append((u0, v0, u1, v1, roi))
            box = (
                min(f[0] for f in frames),
                min(f[1] for f in frames),
                max(f[2] for f in frames),
                max(f[3] for f in frames),
            )
            acc = np.zeros((box[3] - box[1], box[2] - box[0], 3))
            for u0, v0, u1, v1, roi in frames:
                part = background[box[1] : box[3], box[0] : box[2]].copy()
                part[v0 - box[1] : v1 - box[1], u0 - box[0] : u1 - box[0]] = roi
                acc += part
            image[box[1] : box[3], box[0] : box[2]] = acc / len(frames)
            curve, bot, heading, gc = state(t)
            truth["cell"].append(gc)
            truth["bot"].append(bot)
            truth["heading"].append(heading)
            truth["membrane"].append(curve)
            writer.write(_sensor(image * vignette, scene.noise, rng))
    finally:
        writer.release()
    return Footage(
        path,
        times,
        np.array(truth["cell"]),
        np.array(truth["bot"]),
        np.array(truth["heading"]),
        np.array(truth["membrane"]),
        scene,
    )


def _fine(curve: np.ndarray, points: int) -> np.ndarray:
    """Trigonometric interpolation of a closed curve [K, 2] to ``points`` points."""
    z = curve[:, 0] + 1j * curve[:, 1]
    spec = np.fft.fft(z) / z.size
    padded = np.zeros(points, complex)
    half = z.size // 2
    padded[:half] = spec[:half]
    padded[-(z.size - half) :] = spec[half:]
    w = np.fft.ifft(padded) * points
    return np.stack([w.real, w.imag], axis=1)


def _sensor(image: np.ndarray, noise: float, rng: np.random.Generator) -> np.ndarray:
    """The image through a Bayer (BGGR) sensor: one colour per pixel, noise, demosaicing."""
    if not noise:
        return np.clip(np.rint(image), 0, 255).astype(np.uint8)
    h, w = image.shape[:2]
    mosaic = np.empty((h, w))
    mosaic[0::2, 0::2] = image[0::2, 0::2, 0]  # blue
    mosaic[0::2, 1::2] = image[0::2, 1::2, 1]
    mosaic[1::2, 0::2] = image[1::2, 0::2, 1]
    mosaic[1::2, 1::2] = image[1::2, 1::2, 2]  # red
    mosaic += rng.normal(0.0, noise, mosaic.shape) * np.sqrt(np.maximum(mosaic, 1) / 128)
    raw = np.clip(np.rint(mosaic), 0, 255).astype(np.uint8)
    return cv2.cvtColor(raw, cv2.COLOR_BayerRG2BGR)


def every_effect(wall: float = 0.3) -> Scene:
    """The issue's camera: tilt 3 degrees, k1 = -0.1, vignetting, shadows, noise, blur,
    off-red paper, with a wall of ``wall`` cm."""
    return replace(
        Scene(),
        tilt=(2.0, -2.2),
        k1=-0.1,
        vignetting=0.25,
        shadow=0.25,
        cast_shadow=0.2,
        noise=4.0,
        blur=0.5,
        off_red=True,
        wall=wall,
    )
