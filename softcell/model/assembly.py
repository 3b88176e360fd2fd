"""Where many cells live: the domain, their starting places, and who is near whom.

Pure geometry, no dynamics: the pieces an assembly of cells is built on.

- :class:`Domain`: the open plane, a walled square box [-L/2, L/2]^2, or a periodic one (the
  minimum image).
- :func:`place_cells`: the cells' starting centres on a square lattice or at random with a
  minimum gap between rings, clear of the walls and of the obstacles, from one random stream.
- :func:`contact_groups`: the connected groups of cells whose bounding circles come within a
  reach of each other (a k-d tree over the centres, so O(M log M)); cells in different groups
  do not interact until the groups are formed again.

Every length is in cm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from softcell.errors import ParameterError, SoftcellError
from softcell.model.obstacle_layout import surface_distances

BOUNDARIES = ("open", "walls", "periodic")
PLACEMENTS = ("lattice", "random")


@dataclass(frozen=True)
class Domain:
    """The plane the cells move in.

    Attributes
    ----------
    boundary : str
        ``open`` (the unbounded plane), ``walls`` (a square box whose walls repel the
        membranes) or ``periodic`` (a square box with periodic boundaries).
    box : float or None
        Side L of the square box centred on the origin (cm); None for the open plane.
    """

    boundary: str = "open"
    box: float | None = None

    def __post_init__(self) -> None:
        if self.boundary not in BOUNDARIES:
            raise ParameterError(
                "boundary", repr(self.boundary), f"must be one of {', '.join(BOUNDARIES)}", "1"
            )
        if self.boundary == "open":
            if self.box is not None:
                raise ParameterError(
                    "box", self.box, "must be unset for the open plane (boundary open)", "cm"
                )
            return
        if self.box is None or not (math.isfinite(self.box) and 0 < self.box <= MAX_BOX):
            raise ParameterError(
                "box",
                self.box,
                f"must be > 0 cm and at most {MAX_BOX:g} cm for boundary {self.boundary} "
                "(farther from the origin, positions lose the precision the contact needs)",
                "cm",
            )

    @property
    def periodic(self) -> bool:
        return self.boundary == "periodic"

    def displacement(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """b - a (cm, arrays of shape (..., 2)), by the minimum image in a periodic box."""
        d = np.asarray(b, dtype=np.float64) - np.asarray(a, dtype=np.float64)
        if self.periodic:
            d = d - self.box * np.round(d / self.box)
        return d

    def wrap(self, points: np.ndarray) -> np.ndarray:
        """Points (cm, (..., 2)) brought into [-L/2, L/2) in a periodic box; unchanged
        otherwise."""
        p = np.asarray(points, dtype=np.float64)
        if not self.periodic:
            return p
        return (p + self.box / 2) % self.box - self.box / 2


#: The largest box side (cm): a position of up to 5e5 cm keeps 1e-10 cm (1e-8 of the
#: contact's length lambda) in float64; at 2.5e11 cm a ring's roundness fell to 1e-5.
MAX_BOX = 1e6

#: The keys of an ``[assembly]`` table (and the ``--cells``, ``--box``, ``--boundary``,
#: ``--placement``, ``--gap`` flags), with their types and units.
ASSEMBLY_KEYS: dict[str, tuple[type, str]] = {
    "cells": (int, "1"),
    "box": (float, "cm"),
    "boundary": (str, "1"),
    "placement": (str, "1"),
    "gap": (float, "cm"),
    "pair_terms": (list, "1"),
}


@dataclass(frozen=True)
class Assembly:
    """Many cells in one plane: how many, in what domain, placed how.

    Attributes
    ----------
    cells : int
        Number of cells M (each a membrane with its own bot, drive and random stream).
    boundary : str
        ``open``, ``walls`` or ``periodic`` (default: ``periodic`` with a box, ``open``
        without).
    box : float or None
        Side L of the square box (cm); None for the open plane.
    placement : str
        ``lattice`` or ``random`` (see ``place_cells`` in this module).
    gap : float
        Smallest starting gap between rings, and between a ring and a wall or an obstacle
        (cm).
    pair_terms : tuple of str
        The pair terms by which the cells' membranes meet (registered names; the built-in
        ``repulsion``, the contact's law, by default).
    """

    cells: int = 1
    boundary: str = "open"
    box: float | None = None
    placement: str = "lattice"
    gap: float = 1.0
    pair_terms: tuple[str, ...] = ("repulsion",)

    def __post_init__(self) -> None:
        _check_request(self.cells, 1.0, self.gap, self.placement)
        Domain(self.boundary, self.box)
        terms = self.pair_terms
        if isinstance(terms, str) or not all(isinstance(t, str) for t in terms) or not terms:
            raise ParameterError(
                "pair_terms", repr(terms), "must be a non-empty list of pair term names", "1"
            )
        if len(set(terms)) < len(terms):
            raise ParameterError("pair_terms", repr(list(terms)), "must name each term once", "1")
        object.__setattr__(self, "pair_terms", tuple(terms))

    @property
    def domain(self) -> Domain:
        return Domain(self.boundary, self.box)

    def as_dict(self) -> dict[str, object]:
        """The settings as a file stores them (JSON-ready; ``box`` None in the open plane)."""
        return {
            "cells": self.cells,
            "boundary": self.boundary,
            "box": self.box,
            "placement": self.placement,
            "gap": self.gap,
            "pair_terms": list(self.pair_terms),
        }

    @classmethod
    def from_mapping(cls, data: dict[str, object], source: object = "[assembly]") -> Assembly:
        """An assembly from an ``[assembly]`` table or the flags' values.

        Parameters
        ----------
        data : dict
            Keys of ``ASSEMBLY_KEYS`` (``box`` and ``gap`` in cm); ``boundary`` defaults
            to ``periodic`` with a box and ``open`` without.
        source : object
            What the values came from, for errors (``"[assembly]"``, a file name).

        Returns
        -------
        Assembly

        Raises
        ------
        ConfigError
            For an unknown key (with a suggestion) or a value of the wrong type.
        ParameterError
            For a value out of range (naming it, with its unit).
        """
        from softcell.errors import ConfigError
        from softcell.model.parameters import suggest

        values = {}
        for key, value in data.items():
            if key not in ASSEMBLY_KEYS:
                raise ConfigError(
                    f"{source}: unknown key {key!r}{suggest(key, ASSEMBLY_KEYS)}; "
                    f"keys: {', '.join(ASSEMBLY_KEYS)}"
                )
            kind, unit = ASSEMBLY_KEYS[key]
            ok = isinstance(value, kind) and not isinstance(value, bool)
            if kind is float and isinstance(value, int) and not isinstance(value, bool):
                value, ok = float(value), True
            if not ok:
                what = {int: "an integer", float: "a number", str: "a name", list: "a list"}[kind]
                unit_text = "" if unit == "1" else f" ({unit})"
                raise ConfigError(f"{source}: {key} = {value!r} must be {what}{unit_text}")
            values[key] = value
        values.setdefault("boundary", "open" if values.get("box") is None else "periodic")
        return cls(**values)


def place_cells(
    count: int,
    radius: float,
    domain: Domain,
    rng: np.random.Generator,
    *,
    placement: str = "lattice",
    gap: float = 1.0,
    obstacles: str = "",
    tries: int = 10_000,
) -> np.ndarray:
    """Starting centres of ``count`` rings of radius ``radius`` (cm), float64[count, 2].

    Rings keep at least ``gap`` (cm) between them (by the minimum image in a periodic box),
    and at least ``gap`` from a walled box's walls and from every obstacle's surface
    (``obstacles``: the parameter of :mod:`softcell.model.obstacle_layout`). ``lattice`` fills a
    square lattice centred on the origin, row by row (spacing 2 radius + gap in the open
    plane, the box's side over the cells per row in a box); ``random`` draws uniform
    centres in the box (in the open plane: in a square 1.5 times the side of the lattice's,
    since random packings jam near an area fraction of 0.55) and keeps each that fits, up to
    ``tries`` draws in all. ``rng`` is used by ``random`` only.

    Raises
    ------
    SoftcellError
        When the rings cannot be placed, naming the count, radius, gap, box and area fraction.
    """
    _check_request(count, radius, gap, placement)
    per_row = math.ceil(math.sqrt(count))
    spacing = 2 * radius + gap
    side = domain.box if domain.box is not None else per_row * spacing
    if placement == "lattice":
        step = side / per_row if domain.box is not None else spacing
        rows = np.arange(count) // per_row
        cols = np.arange(count) % per_row
        centres = np.stack([cols, rows], axis=1) * step - (per_row - 1) * step / 2
        problem = _misfit(centres, radius, domain, gap, obstacles)
        if problem is None:
            return centres
        raise SoftcellError(_cannot(count, radius, gap, domain, f"on a lattice: {problem}"))
    if domain.box is None:
        side *= 1.5  # random packings jam near an area fraction of 0.55
    return _at_random(count, radius, domain, rng, gap, obstacles, tries, side)


def _check_request(count: int, radius: float, gap: float, placement: str) -> None:
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ParameterError("cells", repr(count), "must be an integer >= 1", "1")
    if not (math.isfinite(radius) and radius > 0):
        raise ParameterError("radius", radius, "must be finite and > 0 cm", "cm")
    if not (math.isfinite(gap) and gap >= 0):
        raise ParameterError("gap", gap, "must be finite and >= 0 cm", "cm")
    if placement not in PLACEMENTS:
        raise ParameterError(
            "placement", repr(placement), f"must be one of {', '.join(PLACEMENTS)}", "1"
        )


def _at_random(count, radius, domain, rng, gap, obstacles, tries, side) -> np.ndarray:
    """Uniform draws in the square of ``side`` centred on the origin, each kept if it fits."""
    centres = np.empty((count, 2))
    placed = 0
    for _ in range(tries):
        trial = (rng.random(2) - 0.5) * side
        # the trial alone against the rings placed (they fit each other already)
        if _misfit(trial[None], radius, domain, gap, obstacles) is None and (
            placed == 0
            or np.hypot(*domain.displacement(centres[:placed], trial[None]).T).min()
            >= 2 * radius + gap - 1e-12
        ):
            centres[placed] = trial
            placed += 1
            if placed == count:
                return centres
    raise SoftcellError(
        _cannot(count, radius, gap, domain, f"at random: {placed} placed in {tries} draws")
    )


def _misfit(
    centres: np.ndarray, radius: float, domain: Domain, gap: float, obstacles: str
) -> str | None:
    """Why rings at ``centres`` do not fit (None when they do)."""
    if domain.boundary == "walls":
        limit = domain.box / 2 - radius - gap
        if np.any(np.abs(centres) > limit):
            return f"a ring would come within {gap:g} cm of the walls"
    if obstacles:
        clear = surface_distances(centres[:, 0], centres[:, 1], obstacles)
        if clear.size and clear.min() < radius + gap:
            return f"a ring would come within {gap:g} cm of an obstacle"
    if len(centres) > 1 and _nearest(centres, domain) < 2 * radius + gap - 1e-12:
        return f"two rings would come within {gap:g} cm of each other"
    return None


def _tree(centres: np.ndarray, domain: Domain):
    """A k-d tree of ``centres`` (cm), periodic in a periodic box: memory and time grow as
    M log M, where all pairs of 12,000 cells took 4 GB."""
    from scipy.spatial import cKDTree

    if domain.periodic:
        return cKDTree(domain.wrap(centres) + domain.box / 2, boxsize=domain.box)
    return cKDTree(centres)


def _nearest(centres: np.ndarray, domain: Domain) -> float:
    """The smallest distance between two of ``centres`` (cm; by the minimum image)."""
    distance, _ = _tree(centres, domain).query(
        domain.wrap(centres) + (domain.box / 2 if domain.periodic else 0.0), k=2
    )
    return float(distance[:, 1].min())


def _cannot(count: int, radius: float, gap: float, domain: Domain, how: str) -> str:
    where = "in the open plane" if domain.box is None else f"in a {domain.boundary} box of side "
    if domain.box is not None:
        fraction = count * math.pi * radius**2 / domain.box**2
        where += f"{domain.box:g} cm (area fraction {fraction:.2f})"
    return (
        f"cannot place {count} rings of radius {radius:g} cm with a gap of {gap:g} cm {where} {how}"
    )


def contact_groups(
    centres: np.ndarray, radii: np.ndarray, reach: float, domain: Domain
) -> np.ndarray:
    """Label of each cell's group, int64[M]: cells i and j are in one group when a chain of
    cells links them, each link two bounding circles (centre, radius; cm) closer than
    ``reach`` (cm) to each other (by the minimum image in a periodic box). Labels are
    numbered from 0 in the order of each group's first cell.

    Raises
    ------
    ParameterError
        In a periodic box whose side is not more than twice the largest interaction
        distance (a ring could then meet two images of another, or its own).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    radii = np.broadcast_to(np.asarray(radii, dtype=np.float64), (len(centres),))
    reach_max = 2 * float(radii.max(initial=0.0)) + reach
    if domain.periodic:
        if domain.box <= 2 * reach_max:
            raise ParameterError(
                "box",
                domain.box,
                f"must be > {2 * reach_max:g} cm in a periodic box: twice the largest "
                "distance at which two rings interact (2 x the largest radius + the reach)",
                "cm",
            )
        tree = cKDTree(domain.wrap(centres) + domain.box / 2, boxsize=domain.box)
    else:
        tree = cKDTree(centres)
    pairs = tree.query_pairs(reach_max, output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        d = np.hypot(*domain.displacement(centres[i], centres[j]).T)
        keep = d < radii[i] + radii[j] + reach
        i, j = i[keep], j[keep]
    else:
        i = j = np.empty(0, dtype=np.int64)
    m = len(centres)
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(m, m))
    _, labels = connected_components(graph, directed=False)
    # number the groups in the order of their first cell
    _, first = np.unique(labels, return_index=True)
    order = np.argsort(np.argsort(first))
    return order[labels].astype(np.int64)
