"""Fixed obstacles: circular posts and straight walls that repel the membrane as the bot does.

A membrane point at distance rho from an obstacle's surface has the energy density
(l0 / 2 pi) A exp(-rho / lambda), with the contact's amplitude A and length lambda
(SI:EQ:Eint with the obstacle in the bot's place). For a post of centre c and radius r,
rho = |x - c| - r; for a wall of width w about the segment from p0 to p1, rho is the
distance to the nearest point of the segment less w / 2 (a rectangle with round ends).
Inside an obstacle rho < 0 and the push grows as exp(|rho| / lambda): posts and walls at
least MIN_THICKNESS_LENGTHS lambda thick (radius, half-width) hold a membrane that the drive
presses on them (a wall without thickness would stop a point with at most A / lambda per
unit length, which the bot overcomes). Beyond CONTACT_CUTOFF_LENGTHS lambda nothing is felt.
Obstacles act on the membrane only: the bot, inside its ring, meets them through it.

The obstacles are :class:`~softcell.model.obstacle_layout.Post` and
:class:`~softcell.model.obstacle_layout.Wall` objects, stored as one parameter,
``obstacles`` (cm), a list separated by ``;`` of ``post X Y RADIUS`` and
``wall X0 Y0 X1 Y1 WIDTH``; a configuration file writes them as ``[[obstacles]]`` tables and
the command line as ``--obstacle X,Y,RADIUS`` and ``--wall X0,Y0,X1,Y1,WIDTH``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softcell.components.contracts import EnergyTerm
from softcell.components.hookspecs import hookimpl
from softcell.errors import ParameterError
from softcell.model.obstacle_layout import (
    MEANING,
    Post,
    Wall,
    parse_obstacles,
    surface_distances,
)
from softcell.model.parameters import MODEL_PARAMETERS, ParameterSpec
from softcell.settings import CONTACT_CUTOFF_LENGTHS, JIT

#: Smallest post radius and wall half-width, in contact lengths lambda: the push on a
#: membrane point at the obstacle's centre line is e^10 times its push at the surface.
MIN_THICKNESS_LENGTHS = 10.0


def _coefficients(text: str, amplitude: float, length: float) -> np.ndarray:
    """[A, lambda, posts, walls, (x, y, r) per post, (x0, y0, x1, y1, w / 2) per wall]."""
    items = parse_obstacles(text)
    posts = [o for o in items if isinstance(o, Post)]
    walls = [o for o in items if isinstance(o, Wall)]
    flat = [amplitude, length, len(posts), len(walls)]
    for post in posts:
        flat.extend((post.x, post.y, post.radius))
    for wall in walls:
        flat.extend((wall.x0, wall.y0, wall.x1, wall.y1, wall.half_thickness))
    return np.array(flat, dtype=np.float64)


@njit(**JIT)
def _nearest(x, y, coefficients, i):
    """Obstacle i seen from (x, y): (dx, dy, d, rho, curved), with (dx, dy) from the nearest
    point of the obstacle's centre (a post's centre, a wall's segment) to (x, y), d its
    length, rho the signed distance to the surface (cm), and curved False inside a wall's
    span (flat there)."""
    posts = int(coefficients[2])
    if i < posts:
        base = 4 + 3 * i
        dx, dy = x - coefficients[base], y - coefficients[base + 1]
        d = math.sqrt(dx * dx + dy * dy)
        return dx, dy, d, d - coefficients[base + 2], True
    base = 4 + 3 * posts + 5 * (i - posts)
    ax, ay = coefficients[base], coefficients[base + 1]
    ex, ey = coefficients[base + 2] - ax, coefficients[base + 3] - ay
    t = ((x - ax) * ex + (y - ay) * ey) / (ex * ex + ey * ey)
    curved = t <= 0.0 or t >= 1.0
    t = min(max(t, 0.0), 1.0)
    dx, dy = x - (ax + t * ex), y - (ay + t * ey)
    d = math.sqrt(dx * dx + dy * dy)
    return dx, dy, d, d - coefficients[base + 4], curved


@njit(**JIT)
def _box(x, y):
    """The points' bounding box: (x min, x max, y min, y max), cm."""
    x0, x1, y0, y1 = x[0], x[0], y[0], y[0]
    for n in range(1, x.size):
        x0, x1 = min(x0, x[n]), max(x1, x[n])
        y0, y1 = min(y0, y[n]), max(y1, y[n])
    return x0, x1, y0, y1


@njit(**JIT)
def _within_reach(coefficients, i, x0, x1, y0, y1, cutoff):
    """Whether obstacle i's bounding box, widened by the cut-off, meets the box
    [x0, x1] x [y0, y1]: an obstacle out of reach of every point is skipped whole."""
    posts = int(coefficients[2])
    if i < posts:
        base = 4 + 3 * i
        r = coefficients[base + 2] + cutoff
        ax = bx = coefficients[base]
        ay = by = coefficients[base + 1]
    else:
        base = 4 + 3 * posts + 5 * (i - posts)
        r = coefficients[base + 4] + cutoff
        ax, ay = coefficients[base], coefficients[base + 1]
        bx, by = coefficients[base + 2], coefficients[base + 3]
    return (
        min(ax, bx) - r <= x1
        and max(ax, bx) + r >= x0
        and min(ay, by) - r <= y1
        and max(ay, by) + r >= y0
    )


@njit(**JIT)
def obstacles_partials(
    x, y, xp, yp, xpp, ypp, pose, context, coefficients, p0x, p0y, p1x, p1y, p2x, p2y, dpose
):
    amplitude, length = coefficients[0], coefficients[1]
    count = int(coefficients[2]) + int(coefficients[3])
    cutoff = CONTACT_CUTOFF_LENGTHS * length
    scale = context[0] / (2.0 * math.pi) * amplitude / length
    x0, x1, y0, y1 = _box(x, y)
    for i in range(count):
        if not _within_reach(coefficients, i, x0, x1, y0, y1, cutoff):
            continue
        for n in range(x.size):
            dx, dy, d, rho, _ = _nearest(x[n], y[n], coefficients, i)
            if rho > cutoff or d == 0.0:
                continue
            push = scale * math.exp(-rho / length) / d
            p0x[n] -= push * dx
            p0y[n] -= push * dy


@njit(**JIT)
def obstacles_hessian(x, y, xp, yp, xpp, ypp, pose, context, coefficients, hww, hwp, hpp):
    amplitude, length = coefficients[0], coefficients[1]
    count = int(coefficients[2]) + int(coefficients[3])
    cutoff = CONTACT_CUTOFF_LENGTHS * length
    scale = context[0] / (2.0 * math.pi) * amplitude / length
    x0, x1, y0, y1 = _box(x, y)
    for i in range(count):
        if not _within_reach(coefficients, i, x0, x1, y0, y1, cutoff):
            continue
        for n in range(x.size):
            dx, dy, d, rho, curved = _nearest(x[n], y[n], coefficients, i)
            if rho > cutoff or d == 0.0:
                continue
            push = scale * math.exp(-rho / length)
            ux, uy = dx / d, dy / d
            # (push / lambda) u u^T, less push (I - u u^T) / d where the surface curves
            along = push / length
            across = push / d if curved else 0.0
            hww[n, 0, 0] += along * ux * ux - across * (1.0 - ux * ux)
            hww[n, 0, 1] += along * ux * uy + across * ux * uy
            hww[n, 1, 0] += along * ux * uy + across * ux * uy
            hww[n, 1, 1] += along * uy * uy - across * (1.0 - uy * uy)


class Obstacles(EnergyTerm):
    """Fixed posts and walls, repelling the membrane."""

    name = "obstacles"
    description = "fixed circular posts and straight walls repelling the membrane"
    parameters = (
        ParameterSpec("obstacles", "", "cm", "posts and walls: " + MEANING, kind=str),
        MODEL_PARAMETERS["contact_amplitude"],
        MODEL_PARAMETERS["contact_length"],
    )
    derivative_order = 0

    @classmethod
    def check(cls, params) -> None:
        """Refuse a malformed list, or a post or wall too thin to hold a pushed membrane
        (where the cells start is checked by the run that places them:
        :func:`softcell.model.obstacle_layout.check_clear_of_start` for one cell, the placement
        for an assembly)."""
        thinnest = MIN_THICKNESS_LENGTHS * float(params.contact_length)
        for obstacle in parse_obstacles(str(params.obstacles)):
            if obstacle.half_thickness < thinnest:
                what = "post radius" if isinstance(obstacle, Post) else "wall half-width"
                raise ParameterError(
                    "obstacles",
                    repr(obstacle.text),
                    f"must have a {what} >= {thinnest:g} cm ({MIN_THICKNESS_LENGTHS:g} "
                    "contact lengths): a thinner obstacle lets a pushed membrane through",
                    "cm",
                )

    def coefficients(self) -> np.ndarray:
        p = self.params
        return _coefficients(str(p.obstacles), float(p.contact_amplitude), float(p.contact_length))

    def partials_kernel(self):
        return obstacles_partials

    def hessian_kernel(self):
        return obstacles_hessian

    def density(self, x, y, xp, yp, xpp, ypp, pose):
        p = self.params
        length = float(p.contact_length)
        cutoff = CONTACT_CUTOFF_LENGTHS * length
        rho = surface_distances(x, y, str(p.obstacles))
        e = np.where(rho > cutoff, 0.0, np.exp(-rho / length)).sum(axis=0)
        return p.membrane_length / (2 * np.pi) * p.contact_amplitude * e


@hookimpl
def softcell_energy_terms() -> list[type[EnergyTerm]]:
    return [Obstacles]
