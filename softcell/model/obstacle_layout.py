"""Fixed obstacles: typed posts and walls (cm), and the parameter ``obstacles`` that stores them.

A :class:`Post` is a circular post, a :class:`Wall` a straight wall of thickness ``width``
about the segment from (x0, y0) to (x1, y1), with round ends; every length is in cm. Each
checks itself when made. The run stores them as one model parameter, ``obstacles``: a list
separated by ``;`` of ``post X Y RADIUS`` and ``wall X0 Y0 X1 Y1 WIDTH``
(:func:`obstacle_text` writes it, :func:`parse_obstacles` reads it back into posts and
walls). A configuration file writes them as ``[[obstacles]]`` tables (:func:`from_table`),
the command line as ``--obstacle X,Y,RADIUS`` and ``--wall X0,Y0,X1,Y1,WIDTH``. The energy
term that makes them act is ``obstacles`` (:mod:`softcell.builtins.obstacles`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from softcell.errors import ParameterError

MEANING = "a list of 'post X Y RADIUS' and 'wall X0 Y0 X1 Y1 WIDTH' (cm) separated by ';'"
ENTRY = (
    "must be 'post X Y RADIUS' or 'wall X0 Y0 X1 Y1 WIDTH' (numbers in cm; entries "
    "separated by ';')"
)


@dataclass(frozen=True)
class Post:
    """A circular post of centre (``x``, ``y``) and radius ``radius`` (cm).

    Raises
    ------
    ParameterError
        For a number that is not finite, or a radius that is not > 0 cm.
    """

    x: float
    y: float
    radius: float
    kind: ClassVar[str] = "post"

    def __post_init__(self) -> None:
        _check(self)
        if self.radius <= 0:
            raise ParameterError(
                "obstacles", repr(self.text), "must have a post radius > 0 cm", "cm"
            )

    @property
    def half_thickness(self) -> float:
        """The post's radius (cm): how far its surface lies from its centre."""
        return self.radius

    @property
    def text(self) -> str:
        """The post as an entry of the parameter ``obstacles``: ``post X Y RADIUS``."""
        return _text(self)

    def distance(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Signed distance (cm) from the points (x, y) (cm) to the surface, negative inside."""
        return np.hypot(x - self.x, y - self.y) - self.radius


@dataclass(frozen=True)
class Wall:
    """A straight wall of thickness ``width`` about the segment from (``x0``, ``y0``) to
    (``x1``, ``y1``), with round ends (cm).

    Raises
    ------
    ParameterError
        For a number that is not finite, a width that is not > 0 cm, or two equal ends.
    """

    x0: float
    y0: float
    x1: float
    y1: float
    width: float
    kind: ClassVar[str] = "wall"

    def __post_init__(self) -> None:
        _check(self)
        problem = None
        if self.width <= 0:
            problem = "must have a wall width > 0 cm"
        elif (self.x0, self.y0) == (self.x1, self.y1):
            problem = "must have a wall of two distinct ends"
        if problem:
            raise ParameterError("obstacles", repr(self.text), problem, "cm")

    @property
    def half_thickness(self) -> float:
        """Half the wall's width (cm): how far its surface lies from its segment."""
        return 0.5 * self.width

    @property
    def text(self) -> str:
        """The wall as an entry of the parameter ``obstacles``: ``wall X0 Y0 X1 Y1 WIDTH``."""
        return _text(self)

    def distance(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Signed distance (cm) from the points (x, y) (cm) to the surface, negative inside."""
        ex, ey = self.x1 - self.x0, self.y1 - self.y0
        t = np.clip(((x - self.x0) * ex + (y - self.y0) * ey) / (ex * ex + ey * ey), 0.0, 1.0)
        return np.hypot(x - self.x0 - t * ex, y - self.y0 - t * ey) - self.half_thickness


#: A fixed obstacle.
Obstacle = Post | Wall
#: The obstacles by kind: the word of their entry and their class.
KINDS: dict[str, type[Post] | type[Wall]] = {"post": Post, "wall": Wall}


def _numbers(obstacle: Obstacle) -> tuple[float, ...]:
    """The obstacle's fields in the order of its entry (cm)."""
    return tuple(getattr(obstacle, f.name) for f in dataclasses.fields(obstacle))


def _check(obstacle: Obstacle) -> None:
    """Refuse a field that is not a finite number."""
    values = _numbers(obstacle)
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values) or not all(
        math.isfinite(v) for v in values
    ):
        raise ParameterError("obstacles", repr(obstacle), "must hold finite numbers (cm)", "cm")


def _text(obstacle: Obstacle) -> str:
    """``KIND N1 N2 ...``, each number written short and exactly."""
    return " ".join([obstacle.kind, *(_number(float(v)) for v in _numbers(obstacle))])


def _number(value: float) -> str:
    """``value`` written short, and exactly: 12, 0.1, 0.30000000000000004."""
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def parse_obstacles(text: str) -> tuple[Obstacle, ...]:
    """The posts and walls of the parameter ``obstacles``.

    Raises
    ------
    ParameterError
        Naming the entry that is not ``post X Y RADIUS`` or ``wall X0 Y0 X1 Y1 WIDTH`` with
        finite numbers, a post radius or wall width that is not > 0, or a wall of zero length.
    """
    entries = (e.strip() for e in text.split(";"))
    return tuple(_entry(e) for e in entries if e)


def _entry(entry: str) -> Obstacle:
    """One obstacle from its entry, checked (see :func:`parse_obstacles`)."""
    kind, *words = entry.split()
    bad = ParameterError("obstacles", repr(entry), ENTRY, "cm")
    cls = KINDS.get(kind)
    if cls is None or len(words) != len(dataclasses.fields(cls)):
        raise bad
    try:
        numbers = [float(w) for w in words]
    except ValueError:
        raise bad from None
    if not all(math.isfinite(v) for v in numbers):
        raise bad
    return cls(*numbers)


def obstacle_text(obstacles: Iterable[Obstacle]) -> str:
    """The parameter ``obstacles`` that stores ``obstacles`` (each number exactly)."""
    return "; ".join(o.text for o in obstacles)


def from_table(table: Mapping[str, Any]) -> Obstacle:
    """The obstacle of an ``[[obstacles]]`` table: ``{x, y, radius}`` for a post,
    ``{x0, y0, x1, y1, width}`` for a wall (cm).

    Raises
    ------
    ParameterError
        For a table with other keys, a value that is not a number, or an obstacle that
        its class refuses.
    """
    keys = set(table)
    cls = next((c for c in KINDS.values() if keys == {f.name for f in dataclasses.fields(c)}), None)
    if cls is None:
        raise ParameterError(
            "obstacles",
            repr(dict(table)),
            "must be a table of x, y, radius (a post) or x0, y0, x1, y1, width (a wall), in cm",
            "cm",
        )
    values = {k: table[k] for k in keys}
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values.values()):
        raise ParameterError("obstacles", repr(dict(table)), "must hold numbers (cm)", "cm")
    return cls(**{k: float(v) for k, v in values.items()})


def surface_distances(
    x: np.ndarray, y: np.ndarray, obstacles: str | Iterable[Obstacle]
) -> np.ndarray:
    """Signed distance (cm) from each point (x, y) (cm, any shape) to the surface of each
    obstacle (typed, or the parameter ``obstacles``), negative inside:
    float64[obstacles, *x.shape]."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    items = parse_obstacles(obstacles) if isinstance(obstacles, str) else tuple(obstacles)
    out = [o.distance(x, y) for o in items]
    return np.array(out).reshape(len(out), *x.shape)


def check_clear_of_start(params) -> None:
    """Refuse obstacles within a single cell's reach at the start: the membrane starts as a
    circle of radius ``radius`` about the origin and feels an obstacle up to
    CONTACT_CUTOFF_LENGTHS contact lengths beyond it.

    Raises
    ------
    ParameterError
        Naming the obstacle, its distance from the origin and the ring's reach (cm).
    """
    from softcell.settings import CONTACT_CUTOFF_LENGTHS

    text = str(params.get("obstacles", "") or "")
    if not text:
        return
    reach = float(params.radius) + CONTACT_CUTOFF_LENGTHS * float(params.contact_length)
    distances = surface_distances(np.zeros(1), np.zeros(1), text)[:, 0]
    for obstacle, rho in zip(parse_obstacles(text), distances, strict=True):
        if rho <= reach:
            raise ParameterError(
                "obstacles",
                repr(obstacle.text),
                f"must keep clear of the cell at the start: its surface is {rho:g} cm "
                f"from the origin, the ring reaches {reach:g} cm (radius plus "
                f"{CONTACT_CUTOFF_LENGTHS:g} contact lengths)",
                "cm",
            )
