"""Several bots in one ring: how many, placed how, interacting how.

Pure geometry, no dynamics. :class:`Bots` holds the ``[bots]`` settings (``--bots K``);
:func:`place_bots` puts K ellipses inside the ring's starting circle, clear of it and of each
other by a gap, on a ring of starting points, on a lattice or at random. Every length is in cm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from softcell.engine.kernels.ellipse import ellipse_gap
from softcell.errors import ConfigError, ParameterError

PLACEMENTS = ("random", "ring", "lattice")

#: Keys of the ``[bots]`` table: their type and unit.
BOTS_KEYS: dict[str, tuple[type, str]] = {
    "count": (int, "1"),
    "placement": (str, "1"),
    "gap": (float, "cm"),
    "interactions": (list, "1"),
}

#: Random placement: positions tried per bot before the placement is refused.
PLACEMENT_TRIES = 20000


@dataclass(frozen=True)
class Bots:
    """K bots in one ring.

    Attributes
    ----------
    count : int
        Number of bots K (each with its own drive, schedule and random stream). 1 is the
        single-bot run, to the bit.
    placement : str
        ``random`` (uniform positions without overlap, headings as each bot's protocol draws
        them), ``ring`` (K starting points evenly spaced on a circle, headings drawn) or
        ``lattice`` (rows of bots along x, nearest the centre first; a heading 0 or pi, the
        sign of the cosine of the drawn heading).
    gap : float
        Smallest starting gap between bots, and between a bot and the ring (cm).
    interactions : tuple of str
        The bot interactions by name (the built-in ``bot_repulsion`` by default).
    """

    count: int = 1
    placement: str = "random"
    gap: float = 0.5
    interactions: tuple[str, ...] = ("bot_repulsion",)

    def __post_init__(self) -> None:
        if not 1 <= self.count <= 10000:
            raise ParameterError("bots", self.count, "must be from 1 to 10000", "1")
        if self.placement not in PLACEMENTS:
            raise ParameterError(
                "placement", repr(self.placement), f"must be one of {', '.join(PLACEMENTS)}", "1"
            )
        if not (math.isfinite(self.gap) and self.gap >= 0):
            raise ParameterError("gap", self.gap, "must be >= 0 cm and finite", "cm")
        names = self.interactions
        if isinstance(names, str) or not all(isinstance(n, str) for n in names):
            raise ParameterError(
                "interactions", repr(names), "must be a list of bot interaction names", "1"
            )
        if len(set(names)) < len(names):
            raise ParameterError(
                "interactions", repr(list(names)), "must name each interaction once", "1"
            )
        object.__setattr__(self, "interactions", tuple(names))

    def as_dict(self) -> dict[str, object]:
        """The settings as a file stores them (JSON-ready)."""
        return {
            "count": self.count,
            "placement": self.placement,
            "gap": self.gap,
            "interactions": list(self.interactions),
        }

    @classmethod
    def from_mapping(cls, data: dict[str, object], source: object = "[bots]") -> Bots:
        """The settings of a ``[bots]`` table or of the flags.

        Parameters
        ----------
        data : dict
            Keys of ``BOTS_KEYS`` (``gap`` in cm, ``interactions`` a list of names).
        source : object
            What the values came from, for errors (``"[bots]"``, a file name).

        Returns
        -------
        Bots

        Raises
        ------
        ConfigError
            For an unknown key (with a suggestion) or a value of the wrong type.
        ParameterError
            For a value out of range.
        """
        from softcell.model.parameters import suggest

        values = {}
        for key, value in data.items():
            if key not in BOTS_KEYS:
                raise ConfigError(
                    f"{source}: unknown key {key!r}{suggest(key, BOTS_KEYS)}; "
                    f"keys: {', '.join(BOTS_KEYS)}"
                )
            kind, unit = BOTS_KEYS[key]
            ok = isinstance(value, kind | tuple if kind is list else kind) and not isinstance(
                value, bool
            )
            if kind is float and isinstance(value, int) and not isinstance(value, bool):
                value, ok = float(value), True
            if not ok:
                what = {int: "an integer", float: "a number", str: "a name", list: "a list"}[kind]
                unit_text = "" if unit == "1" else f" ({unit})"
                raise ConfigError(f"{source}: {key} = {value!r} must be {what}{unit_text}")
            values[key] = tuple(value) if kind is list else value
        return cls(**values)


def _inside(x: float, y: float, heading: float, a: float, b: float, limit: float) -> bool:
    """Whether the ellipse (centre x, y; heading in rad) lies within ``limit`` of the origin:
    its farthest point, found over 256 boundary points and a margin of the chord's sagitta."""
    phi = np.linspace(0.0, 2 * np.pi, 256, endpoint=False)
    c, s = math.cos(heading), math.sin(heading)
    px = x + c * a * np.cos(phi) - s * b * np.sin(phi)
    py = y + s * a * np.cos(phi) + c * b * np.sin(phi)
    sagitta = a * (1 - math.cos(np.pi / 256))
    return float(np.hypot(px, py).max()) + sagitta <= limit


def _clear(pose: np.ndarray, placed: list[np.ndarray], a: float, b: float, gap: float) -> bool:
    """Whether the bot at ``pose`` keeps ``gap`` from every placed bot."""
    for other in placed:
        if math.hypot(pose[0] - other[0], pose[1] - other[1]) >= 2 * a + gap:
            continue
        if ellipse_gap(pose, other, a, b) < gap:
            return False
    return True


def lattice_sites(radius: float, a: float, b: float, gap: float) -> np.ndarray:
    """Every site of the lattice placement inside a ring of starting radius ``radius`` (cm):
    float64[S, 3] (x, y in cm, heading 0), nearest the centre first. The lattice is the
    densest packing of circles of radius a + gap / 2 squeezed by b / a along y (rows of pitch
    2 a + gap, every other one shifted by half a pitch), its row spacing widened until
    neighbours in adjacent rows keep ``gap`` between them."""
    limit = radius - gap
    px = 2 * a + gap
    py = math.sqrt(3) * (a + 0.5 * gap) * b / a
    origin = np.zeros(3)
    while ellipse_gap(origin, np.array([0.5 * px, py, 0.0]), a, b) < gap * (1 - 1e-9) or (
        ellipse_gap(origin, np.array([0.0, 2 * py, 0.0]), a, b) < gap * (1 - 1e-9)
    ):
        py *= 1.01
    rows = int(limit // py) + 2
    cols = int(limit // px) + 2
    best: list[tuple[float, float, float]] = []
    # the lattice shifted by a 4 x 2 grid of offsets within its cell: the one holding most
    for ox, oy in ((i * px / 4, j * py / 2) for j in range(2) for i in range(4)):
        sites = []
        for j in range(-rows, rows + 1):
            shift = 0.5 * px if j % 2 else 0.0
            for i in range(-cols, cols + 1):
                x, y = i * px + shift + ox, j * py + oy
                if _inside(x, y, 0.0, a, b, limit):
                    sites.append((x, y, 0.0))
        if len(sites) > len(best):
            best = sites
    best.sort(key=lambda s: (round(math.hypot(s[0], s[1]), 9), s[1], s[0]))
    return np.array(best, dtype=np.float64).reshape(-1, 3)


def place_bots(
    bots: Bots,
    radius: float,
    a: float,
    b: float,
    headings: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """The bots' starting poses (float64[K, 3]: x, y in cm, heading in rad) inside the ring's
    starting circle of radius ``radius`` (cm, centred on the origin), each ``bots.gap`` clear
    of the circle and of the others (the bots' gap of
    ``softcell.engine.kernels.ellipse.ellipse_gap``).

    Parameters
    ----------
    bots : Bots
        How many, placed how, with what gap (cm).
    radius : float
        The ring's starting radius (cm).
    a, b : float
        The bots' semi-axes (cm).
    headings : float64[K]
        The headings each bot's protocol drew (rad).
    rng : Generator
        The placement's stream (positions of a random placement).

    Raises
    ------
    ParameterError
        When the bots do not fit, in one line naming how many would.
    """
    k, gap = bots.count, bots.gap
    if k == 1:
        return np.array([[0.0, 0.0, float(headings[0])]])
    if bots.placement == "lattice":
        sites = lattice_sites(radius, a, b, gap)
        if len(sites) < k:
            raise _too_many(bots, radius, a, b, f"the lattice holds {len(sites)}")
        poses = sites[:k].copy()
        poses[:, 2] = np.where(np.cos(headings) >= 0, 0.0, math.pi)
        return poses
    if bots.placement == "ring":
        centre = radius - gap - a
        chord = 2 * centre * math.sin(math.pi / k) if centre > 0 else 0.0
        if chord < 2 * a + gap:
            fits = _ring_fits(radius, a, gap)
            raise _too_many(bots, radius, a, b, f"a ring of starting points holds {fits}")
        angles = 2 * math.pi * np.arange(k) / k
        return np.column_stack([centre * np.cos(angles), centre * np.sin(angles), headings])
    return _random_poses(bots, radius, a, b, headings, rng)


def _ring_fits(radius: float, a: float, gap: float) -> int:
    centre = radius - gap - a
    if centre <= 0:
        return 1
    half = (2 * a + gap) / (2 * centre)
    return 1 if half >= 1 else int(math.pi // math.asin(half))


def _random_poses(bots, radius, a, b, headings, rng) -> np.ndarray:
    placed: list[np.ndarray] = []
    reach = radius - bots.gap - b  # no centre of a bot inside the ring lies farther out
    for i in range(bots.count):
        for _ in range(PLACEMENT_TRIES):
            r = reach * math.sqrt(rng.uniform())
            angle = rng.uniform(0.0, 2 * math.pi)
            pose = np.array([r * math.cos(angle), r * math.sin(angle), float(headings[i])])
            if _inside(*pose, a, b, radius - bots.gap) and _clear(pose, placed, a, b, bots.gap):
                placed.append(pose)
                break
        else:
            fits = len(lattice_sites(radius, a, b, bots.gap))
            raise _too_many(
                bots,
                radius,
                a,
                b,
                f"bot {i + 1} found no place in {PLACEMENT_TRIES} random tries; placement = "
                f"'lattice' holds {fits}",
            )
    return np.array(placed)


def _too_many(bots: Bots, radius: float, a: float, b: float, why: str) -> ParameterError:
    area = bots.count * math.pi * a * b / (math.pi * radius * radius)
    return ParameterError(
        "bots",
        bots.count,
        f"do not fit in a ring of starting radius {radius:.3g} cm with placement "
        f"{bots.placement!r} and gap {bots.gap:g} cm ({why}; the bots would cover "
        f"{area:.0%} of its area)",
        "1",
    )
