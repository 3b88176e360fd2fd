"""Fixed obstacles as one parameter: the text of ``obstacles`` (cm), read and written.

``obstacles`` is a list separated by ``;`` of ``post X Y RADIUS`` (a circular post) and
``wall X0 Y0 X1 Y1 WIDTH`` (a straight wall of thickness WIDTH about the segment from
(X0, Y0) to (X1, Y1), with round ends), every number in cm. A configuration file writes
them as ``[[obstacles]]`` tables, the command line as ``--obstacle X,Y,RADIUS`` and
``--wall X0,Y0,X1,Y1,WIDTH``. The energy term that makes them act is
``obstacles`` (:mod:`softcell.builtins.obstacles`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from softcell.errors import ParameterError

#: Fields of each kind of obstacle, in the order of its text (all in cm).
FIELDS = {"post": ("x", "y", "radius"), "wall": ("x0", "y0", "x1", "y1", "width")}
MEANING = "a list of 'post X Y RADIUS' and 'wall X0 Y0 X1 Y1 WIDTH' (cm) separated by ';'"
ENTRY = (
    "must be 'post X Y RADIUS' or 'wall X0 Y0 X1 Y1 WIDTH' (numbers in cm; entries "
    "separated by ';')"
)


def parse_obstacles(text: str) -> list[tuple[str, tuple[float, ...]]]:
    """The obstacles of the parameter ``obstacles``: a list of (kind, numbers in cm).

    Raises
    ------
    ParameterError
        Naming the entry that is not ``post X Y RADIUS`` or ``wall X0 Y0 X1 Y1 WIDTH`` with
        finite numbers, a post radius or wall width that is not > 0, or a wall of zero length.
    """
    entries = (e.strip() for e in text.split(";"))
    return [_entry(e) for e in entries if e]


def _entry(entry: str) -> tuple[str, tuple[float, ...]]:
    """One obstacle from its text, checked (see :func:`parse_obstacles`)."""
    kind, *words = entry.split()
    bad = ParameterError("obstacles", repr(entry), ENTRY, "cm")
    if kind not in FIELDS or len(words) != len(FIELDS[kind]):
        raise bad
    try:
        numbers = tuple(float(w) for w in words)
    except ValueError:
        raise bad from None
    if not all(math.isfinite(v) for v in numbers):
        raise bad
    problem = None
    if kind == "post" and numbers[2] <= 0:
        problem = "must have a post radius > 0 cm"
    elif kind == "wall" and numbers[4] <= 0:
        problem = "must have a wall width > 0 cm"
    elif kind == "wall" and numbers[:2] == numbers[2:4]:
        problem = "must have a wall of two distinct ends"
    if problem:
        raise ParameterError("obstacles", repr(entry), problem, "cm")
    return kind, numbers


def obstacle_text(tables: Iterable[Mapping[str, Any]], source: object = "obstacles") -> str:
    """The parameter ``obstacles`` from ``[[obstacles]]`` tables: ``{x, y, radius}`` for a
    post, ``{x0, y0, x1, y1, width}`` for a wall (cm).

    Raises
    ------
    ParameterError
        For a table with other keys or a value that is not a number.
    """
    entries = []
    for table in tables:
        keys = set(table)
        kind = next((k for k, f in FIELDS.items() if keys == set(f)), None)
        if kind is None:
            raise ParameterError(
                "obstacles",
                repr(dict(table)),
                "must be a table of x, y, radius (a post) or x0, y0, x1, y1, width (a wall), in cm",
                "cm",
            )
        values = [table[f] for f in FIELDS[kind]]
        if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
            raise ParameterError("obstacles", repr(dict(table)), "must hold numbers (cm)", "cm")
        entries.append(" ".join([kind, *(_number(float(v)) for v in values)]))
    text = "; ".join(entries)
    parse_obstacles(text)
    return text


def _number(value: float) -> str:
    """``value`` written short, and exactly: 12, 0.1, 0.30000000000000004."""
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def surface_distances(x: np.ndarray, y: np.ndarray, text: str) -> np.ndarray:
    """Signed distance (cm) from each point (x, y) (cm, any shape) to the surface of each
    obstacle of the parameter ``text``, negative inside: float64[obstacles, *x.shape]."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    out = []
    for kind, v in parse_obstacles(text):
        if kind == "post":
            out.append(np.hypot(x - v[0], y - v[1]) - v[2])
            continue
        ex, ey = v[2] - v[0], v[3] - v[1]
        t = np.clip(((x - v[0]) * ex + (y - v[1]) * ey) / (ex * ex + ey * ey), 0.0, 1.0)
        out.append(np.hypot(x - v[0] - t * ex, y - v[1] - t * ey) - 0.5 * v[4])
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
    for (kind, numbers), rho in zip(parse_obstacles(text), distances, strict=True):
        if rho <= reach:
            raise ParameterError(
                "obstacles",
                f"'{kind} {' '.join(f'{v:g}' for v in numbers)}'",
                f"must keep clear of the cell at the start: its surface is {rho:g} cm "
                f"from the origin, the ring reaches {reach:g} cm (radius plus "
                f"{CONTACT_CUTOFF_LENGTHS:g} contact lengths)",
                "cm",
            )
