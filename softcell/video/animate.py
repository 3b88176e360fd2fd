"""Movies a person watches: a simulation as H.264 MP4 (or GIF for slides), drawn with
matplotlib and encoded by FFmpeg's libraries through PyAV.

One panel per realization (up to four side by side), or, for an assembly of cells, every
cell in one panel with its box. Each panel shows the membrane, the bot (its ellipse and
heading), the bot's trail and the cell centre's trail over the last ``trail`` seconds, the
centre's trail coloured by stop (orange) and go (blue) as the threshold detector labels it
(go at or above the file's ``threshold``, cm/s), a time stamp and a scale bar. Positions in
cm, times in s.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from softcell._version import __version__
from softcell.errors import SoftcellError
from softcell.io.files import atomic_write
from softcell.model.obstacle_layout import Post, parse_obstacles
from softcell.schema import validate

#: What each suffix is written as: (codec, pixel format).
FORMATS = {".mp4": ("libx264", "yuv420p"), ".gif": ("gif", "pal8")}

#: The start of the comment written into an MP4's metadata (GIF keeps none), by which
#: ``softcell track`` knows an animation from a film.
ANIMATION_MARK = "softcell animate"
#: Panels side by side, at most.
MAX_PANELS = 4
GO_COLOUR, STOP_COLOUR = "#1f77b4", "#ff7f0e"


@dataclass(frozen=True)
class Movie:
    """What :func:`animate` wrote.

    Parameters
    ----------
    path : Path
        The movie file.
    frames : int
        Frames written.
    fps : float
        Frames per second (1/s).
    size : tuple of int
        Width and height (px).
    span : tuple of float
        The first and last frame's simulated times (s).
    """

    path: Path
    frames: int
    fps: float
    size: tuple[int, int]
    span: tuple[float, float]


def _positive(name: str, value: float, unit: str) -> None:
    if not (math.isfinite(value) and value > 0):
        raise SoftcellError(f"{name} = {value} {unit} is not allowed: must be finite and > 0")


def _check_request(path: Path, *, fps, speed, trail, height, crf) -> None:
    """One line for a bad suffix or value (see :func:`animate` for the units)."""
    if path.suffix.lower() not in FORMATS:
        raise SoftcellError(
            f"{path}: unknown movie format {path.suffix!r}; write .mp4 (H.264) or .gif"
        )
    for name, value, unit in (("fps", fps, "1/s"), ("speed", speed, ""), ("trail", trail, "s")):
        _positive(name, float(value), unit)
    if isinstance(height, bool) or not isinstance(height, int) or not 64 <= height <= 4096:
        raise SoftcellError(f"height = {height!r} px is not allowed: 64 .. 4096")
    if isinstance(crf, bool) or not isinstance(crf, int) or not 0 <= crf <= 51:
        raise SoftcellError(f"crf = {crf!r} is not allowed: an integer 0 .. 51")


def _panels(ds: xr.Dataset, realizations: list[int] | None) -> list[int]:
    count = ds.sizes["realization"]
    chosen = list(range(min(count, MAX_PANELS))) if realizations is None else realizations
    if not chosen or len(chosen) > MAX_PANELS:
        raise SoftcellError(
            f"realizations = {chosen} is not allowed: choose 1 to {MAX_PANELS} of 0 .. {count - 1}"
        )
    for r in chosen:
        if not 0 <= r < count:
            raise SoftcellError(f"realization {r} is not allowed: 0 .. {count - 1}")
    return chosen


def _bodies(ds: xr.Dataset):
    """Times (s) and the bodies' arrays [R, T(, C)] from the fine record when there is one."""
    if "fine_time" in ds.coords:
        t = ds["fine_time"].values
        get = {
            n: ds[f"{n}_fine"].values for n in ("cell_x", "cell_y", "bot_x", "bot_y", "bot_angle")
        }
    else:
        t = ds["time"].values
        get = {n: ds[n].values for n in ("cell_x", "cell_y", "bot_x", "bot_y", "bot_angle")}
    return t, get


def _go(cx: np.ndarray, cy: np.ndarray, t: np.ndarray, threshold: float) -> np.ndarray:
    """Go (True) where the centre's forward speed is at or above ``threshold`` (cm/s)."""
    from softcell.analysis.series import speed

    return speed(np.moveaxis(cx, 1, -1), np.moveaxis(cy, 1, -1), t) >= threshold


def animate(
    ds: xr.Dataset,
    out: str | os.PathLike[str],
    *,
    realizations: list[int] | None = None,
    fps: float = 30.0,
    speed: float = 1.0,
    start: float = 0.0,
    end: float | None = None,
    trail: float = 5.0,
    height: int = 480,
    crf: int = 20,
    progress: bool = True,
) -> Movie:
    """Write a movie of a simulation Dataset (one parameter point).

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation Dataset (``softcell.open_dataset``), of one cell or an assembly.
    out : path-like
        ``.mp4`` (H.264, plays in browsers and common players) or ``.gif``.
    realizations : list of int, optional
        Panels, side by side (default: the first up to four; one for an assembly).
    fps : float
        Frames per second of the movie (1/s).
    speed : float
        Simulated seconds per second of movie (s/s, 1: real time).
    start, end : float
        The simulated span (s); ``end`` defaults to the record's last time.
    trail : float
        How far back the trails reach (s).
    height : int
        Frame height (px); the width is one square panel per realization.
    crf : int
        H.264's constant rate factor, 0 (lossless) to 51 (smallest): 20 looks like the
        figure; 28 is about a third of the size, for the web.
    progress : bool
        Show a progress bar over the frames.

    Returns
    -------
    Movie

    Raises
    ------
    SoftcellError
        One line for a bad value, a sweep (choose a point with ``ds.isel``), a free bot, or
        an unknown suffix.
    """
    path = Path(out)
    _check_request(path, fps=fps, speed=speed, trail=trail, height=height, crf=crf)
    validate(ds)
    swept = [d for d in ds["bot_x"].dims if d not in ("realization", "time", "cell", "bot")]
    if swept:
        raise SoftcellError(
            f"this is a sweep over {', '.join(swept)}: choose one point, ds.isel({swept[0]}=0) "
            f"(--point {swept[0]}=0 on the command line)"
        )
    if not np.isfinite(ds["membrane_x"].values).any():
        raise SoftcellError("this file has no membrane (a free bot): nothing to animate")
    crowd = "cell" in ds.dims
    panels = _panels(ds, realizations if realizations is not None else ([0] if crowd else None))
    t_last = float(ds["time"].values[-1])
    end = t_last if end is None else float(end)
    if not (0 <= start < end <= t_last + 1e-9):
        raise SoftcellError(
            f"start = {start} s, end = {end} s are not allowed: 0 <= start < end <= {t_last:g} s"
        )
    times = np.arange(start, end + 1e-9, speed / fps)
    scene = _Scene(ds, panels, crowd, trail, height)
    codec, pixels = FORMATS[path.suffix.lower()]
    return _encode(scene, times, path, (codec, pixels, crf), fps, progress)


def _encode(scene, times, path: Path, how: tuple, fps: float, progress: bool):
    from fractions import Fraction

    import av

    from softcell.settings import progress_bar_class

    codec, pixels, crf = how
    width, height = scene.size
    with atomic_write(path) as tmp:
        container = av.open(str(tmp), "w", format="mp4" if codec == "libx264" else "gif")
        container.metadata["comment"] = f"{ANIMATION_MARK} {__version__}"  # track refuses it
        stream = container.add_stream(codec, rate=Fraction(fps).limit_denominator(1000))
        stream.width, stream.height, stream.pix_fmt = width, height, pixels
        if codec == "libx264":
            stream.options = {"crf": str(crf), "preset": "medium"}
        palette = _palette(scene, times) if pixels == "pal8" else None
        bar = progress_bar_class()(times, disable=not progress, desc="animate", unit="frame")
        for t in bar:
            image = scene.draw(float(t))
            frame = (
                av.VideoFrame.from_ndarray(image, format="rgb24")
                if palette is None
                else av.VideoFrame.from_ndarray(_indexed(image, palette), format="pal8")
            )
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
        container.close()
    return Movie(path, len(times), fps, (width, height), (float(times[0]), float(times[-1])))


#: Frames a GIF's palette is chosen from, spread over the movie.
PALETTE_FRAMES = 6


def _palette(scene, times: np.ndarray):
    """One palette of 256 colours for a whole GIF, chosen (median cut) from frames spread
    over the movie, so that flat colours stay flat: FFmpeg's fixed 3-3-2 palette dithers
    every colour it lacks, the light grey background into speckles. Returns the palette as
    PIL's image of it and as PyAV's uint8[256, 4] ARGB."""
    from PIL import Image

    picks = np.unique(np.linspace(0, times.size - 1, PALETTE_FRAMES).round().astype(int))
    sample = np.concatenate([scene.draw(float(times[i])) for i in picks], axis=0)
    palette = Image.fromarray(sample).quantize(256, method=Image.Quantize.MEDIANCUT)
    rgb = np.zeros((256, 3), dtype=np.uint8)
    colours = np.frombuffer(bytes(palette.getpalette()), dtype=np.uint8).reshape(-1, 3)[:256]
    rgb[: len(colours)] = colours
    return palette, np.concatenate([np.full((256, 1), 255, dtype=np.uint8), rgb], axis=1)


def _indexed(image: np.ndarray, palette) -> tuple[np.ndarray, np.ndarray]:
    """``image`` (uint8[H, W, 3]) as PyAV's ``pal8`` pair: each pixel the index of the
    nearest colour of ``palette`` (from :func:`_palette`), undithered, and the ARGB table."""
    from PIL import Image

    image_palette, argb = palette
    indices = Image.fromarray(image).quantize(palette=image_palette, dither=Image.Dither.NONE)
    return np.asarray(indices, dtype=np.uint8), argb


class _Scene:
    """The figure and its artists, updated frame by frame."""

    def __init__(self, ds: xr.Dataset, panels: list[int], crowd: bool, trail: float, height: int):
        import matplotlib

        matplotlib.use("Agg", force=False)
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.ds, self.panels, self.crowd, self.trail = ds, panels, crowd, trail
        # an assembly's box (cm, NaN in the open plane; one value, though a combined sweep
        # repeats it along the realizations) and its boundary
        self.box, self.boundary = np.nan, "open"
        if crowd and "domain_box" in ds:
            self.box = float(np.asarray(ds["domain_box"].values).ravel()[0])
            self.boundary = str(ds["domain_box"].attrs.get("boundary", "open"))
        attrs = ds.attrs
        self.a = float(attrs.get("parameter_bot_semi_major", 3.0))
        self.b = float(attrs.get("parameter_bot_semi_minor", 2.0))
        threshold = float(attrs.get("parameter_threshold", 0.03))
        self.mt = ds["time"].values
        self.mx, self.my = ds["membrane_x"].values, ds["membrane_y"].values
        self.t, bodies = _bodies(ds)
        if not crowd:  # a cell axis of one, so both cases index alike
            several = "bot" in ds.dims  # the bots' arrays [R, T, K] get the cell axis first
            bodies = {
                k: v[..., None, :] if several and k.startswith("bot_") else v[..., None]
                for k, v in bodies.items()
            }
            self.mx, self.my = self.mx[:, :, None], self.my[:, :, None]
        # a bot axis last: [R, T, C, K], one bot per cell but in a ring of several
        bodies = {
            k: v if not k.startswith("bot_") or v.ndim == 4 else v[..., None]
            for k, v in bodies.items()
        }
        self.bots = bodies["bot_x"].shape[-1]
        self.bodies = bodies
        self.go = _go(bodies["cell_x"], bodies["cell_y"], self.t, threshold)  # [R, C, T]
        dpi = 100
        header = 28  # px above the panels: the time stamp and the legend
        width = 2 * round(height * len(panels) / 2)
        self.size = (width, 2 * round((height + header) / 2))
        self.fig = Figure(figsize=(self.size[0] / dpi, self.size[1] / dpi), dpi=dpi)
        self.canvas = FigureCanvasAgg(self.fig)
        top = 1 - header / self.size[1]
        self.axes = [
            self.fig.add_axes((i / len(panels), 0, 1 / len(panels), top))
            for i in range(len(panels))
        ]
        middle = 1 - header / 2 / self.size[1]
        self.cells = self.mx.shape[2]
        self.artists = [self._panel(ax, r) for ax, r in zip(self.axes, panels, strict=True)]
        self.stamp = self.fig.text(0.01, middle, "", va="center", fontsize=11, family="monospace")
        legend = [
            ("cell centre: ", "0.2"),
            ("go", GO_COLOUR),
            (" / ", "0.2"),
            ("stop", STOP_COLOUR),
        ]
        x = 0.99
        for text, colour in reversed(legend):
            label = self.fig.text(
                x, middle, text, color=colour, ha="right", va="center", fontsize=10
            )
            self.canvas.draw()
            x -= label.get_window_extent().width / self.size[0]

    def _window(self, r: int) -> tuple[float, float, float, float]:
        if np.isfinite(self.box):
            half = self.box / 2 + 1
            return -half, half, -half, half
        x, y = self.mx[r], self.my[r]
        x0, x1, y0, y1 = np.nanmin(x), np.nanmax(x), np.nanmin(y), np.nanmax(y)
        side = self._side()  # one scale for every panel
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        return cx - side / 2, cx + side / 2, cy - side / 2, cy + side / 2

    def _side(self) -> float:
        """The side (cm) of every panel's window: the largest extent of a panel's membranes
        over the record, plus 2 cm."""
        sides = [
            max(
                np.nanmax(self.mx[r]) - np.nanmin(self.mx[r]),
                np.nanmax(self.my[r]) - np.nanmin(self.my[r]),
            )
            for r in self.panels
        ]
        return max(sides) + 2

    def _panel(self, ax, r: int) -> dict:
        x0, x1, y0, y1 = self._window(r)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_facecolor("#fafafa")
        self._fixtures(ax)
        bar = 10.0 if x1 - x0 > 25 else 5.0
        ax.plot([x0 + 1, x0 + 1 + bar], [y0 + 1, y0 + 1], color="k", lw=3)
        ax.text(x0 + 1 + bar / 2, y0 + 1.3, f"{bar:g} cm", ha="center", va="bottom", fontsize=9)
        if not self.crowd:
            ax.text(0.5, 0.985, f"realization {r}", transform=ax.transAxes, ha="center", va="top")
        # In a periodic box, a ring across an edge shows on the other side too: up to four
        # images of each cell (itself, across x, across y, across the corner).
        copies = 4 if self.boundary == "periodic" and np.isfinite(self.box) else 1
        cells = [[self._cell_artists(ax) for _ in range(copies)] for _ in range(self.cells)]
        return {"cells": cells}

    def _cell_artists(self, ax) -> dict:
        """The artists of one image of a cell: membrane, bot trails, centre trail, bodies."""
        from matplotlib.collections import LineCollection
        from matplotlib.patches import Ellipse

        (membrane,) = ax.plot([], [], color="#c0392b", lw=1.6)
        trails = [ax.plot([], [], color="0.55", lw=0.7)[0] for _ in range(self.bots)]
        centre = LineCollection([], linewidths=1.8)
        ax.add_collection(centre)
        bodies, heads = [], []
        for _ in range(self.bots):
            bodies.append(Ellipse((0, 0), 2 * self.a, 2 * self.b, color="0.2"))
            ax.add_patch(bodies[-1])
            heads.append(ax.plot([], [], color="w", lw=1.5)[0])
        return {"membrane": membrane, "bot": trails, "centre": centre, "body": bodies,
                "head": heads}  # fmt: skip

    def _images(self, mx: np.ndarray, my: np.ndarray) -> list[np.ndarray]:
        """The offsets (cm) at which a ring drawn at ``mx, my`` (cm) shows in a periodic
        box: itself, and its images across each edge it crosses."""
        half = self.box / 2
        ox = self.box if np.min(mx) < -half else -self.box if np.max(mx) > half else 0.0
        oy = self.box if np.min(my) < -half else -self.box if np.max(my) > half else 0.0
        offsets = [(0.0, 0.0)] + [(ox, 0.0)] * bool(ox) + [(0.0, oy)] * bool(oy)
        offsets += [(ox, oy)] * bool(ox and oy)
        return [np.array(o) for o in offsets]

    def _fixtures(self, ax) -> None:
        """The box's walls (or its periodic edges) and the obstacles."""
        from matplotlib.patches import Circle, Polygon

        if np.isfinite(self.box):
            half = self.box / 2
            walls = self.boundary == "walls"
            ax.plot([-half, half, half, -half, -half], [-half, -half, half, half, -half],
                    color="k", lw=2.5 if walls else 0.8, ls="-" if walls else "--")  # fmt: skip
        text = str(self.ds.attrs.get("parameter_obstacles", "") or "")
        for o in parse_obstacles(text) if text else ():
            if isinstance(o, Post):
                ax.add_patch(Circle((o.x, o.y), o.radius, color="0.35"))
            else:
                dx, dy = o.x1 - o.x0, o.y1 - o.y0
                n = np.array([-dy, dx]) / math.hypot(dx, dy) * o.half_thickness
                corners = [(o.x0 + n[0], o.y0 + n[1]), (o.x1 + n[0], o.y1 + n[1]),
                           (o.x1 - n[0], o.y1 - n[1]), (o.x0 - n[0], o.y0 - n[1])]  # fmt: skip
                ax.add_patch(Polygon(corners, color="0.35"))

    def _draw_bot(self, art: dict, r: int, c: int, j: int, span: tuple, shift) -> None:
        """Bot j of cell c of panel r: its trail over samples span[0]..span[1], its body."""
        k0, k = span
        bx = self.bodies["bot_x"][r, k0 : k + 1, c, j] + shift[0]
        by = self.bodies["bot_y"][r, k0 : k + 1, c, j] + shift[1]
        art["bot"][j].set_data(bx, by)
        angle = self.bodies["bot_angle"][r, k, c, j]
        centre = (
            self.bodies["bot_x"][r, k, c, j] + shift[0],
            self.bodies["bot_y"][r, k, c, j] + shift[1],
        )
        art["body"][j].set_center(centre)
        art["body"][j].set_angle(math.degrees(angle))
        tip = (centre[0] + self.a * math.cos(angle), centre[1] + self.a * math.sin(angle))
        art["head"][j].set_data([centre[0], tip[0]], [centre[1], tip[1]])

    def draw(self, t: float) -> np.ndarray:
        """The frame at simulated time ``t`` (s) as uint8[H, W, 3]."""
        m = int(np.argmin(np.abs(self.mt - t)))
        k = int(np.argmin(np.abs(self.t - t)))
        k0 = int(np.searchsorted(self.t, self.t[k] - self.trail))
        box, periodic = self.box, self.boundary == "periodic"
        for panel, r in zip(self.artists, self.panels, strict=True):
            for c, copies in enumerate(panel["cells"]):
                shift = np.zeros(2)
                cx = self.bodies["cell_x"][r, k0 : k + 1, c]
                cy = self.bodies["cell_y"][r, k0 : k + 1, c]
                if periodic and cx.size:
                    shift = -box * np.round(np.array([cx[-1], cy[-1]]) / box)
                mx = np.append(self.mx[r, m, c], self.mx[r, m, c][0]) + shift[0]
                my = np.append(self.my[r, m, c], self.my[r, m, c][0]) + shift[1]
                images = self._images(mx, my) if periodic else [np.zeros(2)]
                for i, art in enumerate(copies):
                    shown = i < len(images)
                    for artist in (art["membrane"], art["centre"], *art["bot"], *art["body"],
                                   *art["head"]):  # fmt: skip
                        artist.set_visible(shown)
                    if not shown:
                        continue
                    o = images[i]
                    art["membrane"].set_data(mx + o[0], my + o[1])
                    points = np.stack([cx + shift[0] + o[0], cy + shift[1] + o[1]], axis=1)
                    art["centre"].set_segments(np.stack([points[:-1], points[1:]], axis=1))
                    art["centre"].set_color(
                        [GO_COLOUR if g else STOP_COLOUR for g in self.go[r, c, k0:k]]
                    )
                    for j in range(self.bots):
                        self._draw_bot(art, r, c, j, (k0, k), shift + o)
        self.stamp.set_text(f"t = {self.t[k]:.2f} s")
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()
