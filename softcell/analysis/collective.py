"""The analysis of an assembly (a ``cell`` dim): every cell as the single-cell analysis sees
it, and what the crowd does together (docs/analysis.md, "Assemblies").

Per cell, :func:`analyze_assembly` runs :func:`~softcell.analysis.sweep.analyze` with
the cells of each realization taken as realizations of their own, then puts the ``cell``
dim back: the MSD, D hat, stop/go and the fits are pooled over cells and realizations;
speeds, labels, the shape index, the per-realization MSD and every ``NAME_realization``
value are per cell. Cells of one assembly push each other, so they are not independent
samples: every ``NAME_error`` comes from a bootstrap that draws whole realizations (all
their cells together), and is NaN for one realization; the MSD's error (``msd_sem``) is
the standard error across realizations of the cells' mean MSD when there are two or more,
and across cells (marked so) when there is one.

What the crowd does, at samples ``crowd_every`` s apart after the discard (freud computes
the neighbours, clusters, the Voronoi tessellation and g(r); a periodic box by the minimum
image, walls and the open plane in a box padded so that no image is ever near):

- ``polar_order`` (realization, time): |mean over cells of (cos, sin) of the bot's
  heading|, in [0, 1] (1 for one bot), at every kept sample;
- cluster sizes: cells whose stored membranes come within ``contact_distance``
  (cm) are in contact, and clusters are the connected sets;
- ``pair_correlation`` of the cell centres, g(r), pooled over samples and realizations, with
  its error across realizations (periodic box: exact; walls: normalised by the box's area,
  without an edge correction; the open plane: not defined);
- ``local_area_fraction``: a cell's own area over its Voronoi cell's (periodic box only),
  and the shape index binned by it;
- ``neighbour_exchange_rate``: Voronoi neighbour bonds lost per cell per second between
  consecutive samples (periodic box only).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import xarray as xr

from softcell.errors import ConfigError
from softcell.model.parameters import ParameterSpec

#: The options of the collective analysis, on top of the analysis options.
CROWD_OPTIONS: dict[str, ParameterSpec] = {
    s.name: s
    for s in (
        ParameterSpec(
            "crowd_every",
            1.0,
            "s",
            "interval between the samples of the collective statistics (clusters, g(r), Voronoi)",
            minimum=0.0,
        ),
        ParameterSpec(
            "contact_distance",
            None,
            "cm",
            "two cells are in contact when stored nodes of their membranes come this close "
            "(default: the contact's reach plus the largest stored node spacing)",
            minimum=0.0,
        ),
        ParameterSpec(
            "pair_distance_max",
            None,
            "1",
            "largest distance of the pair correlation, in cell diameters 2 R (default: 4, "
            "or just under half a smaller periodic box)",
            minimum=0.0,
        ),
        ParameterSpec(
            "pair_bins",
            40,
            "1",
            "bins of the pair correlation",
            kind=int,
            minimum=1,
            minimum_inclusive=True,
        ),
        ParameterSpec(
            "density_bins",
            8,
            "1",
            "bins of the local area fraction for the shape index against it",
            kind=int,
            minimum=1,
            minimum_inclusive=True,
        ),
    )
}

#: What each option needs: two cells or more, or a box.
_NEEDS_PAIRS = ("contact_distance", "pair_distance_max", "pair_bins", "density_bins")


def split_crowd_options(
    options: Mapping[str, Any] | None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """``options`` split into (the collective analysis' options, the rest)."""
    crowd = {k: v for k, v in (options or {}).items() if k in CROWD_OPTIONS and v is not None}
    rest = {k: v for k, v in (options or {}).items() if k not in CROWD_OPTIONS}
    return crowd, rest


def crowd_options(
    given: Mapping[str, Any], cells: int, boundary: str, source: str = "analyze"
) -> dict[str, Any]:
    """The validated collective options for an assembly of ``cells`` cells in a domain with
    ``boundary``; an option that makes no sense for it is an error naming it."""
    from softcell.analysis.options import validated

    if cells < 2:
        asked = [k for k in _NEEDS_PAIRS if k in given]
        if asked:
            raise ConfigError(
                f"{source}: {', '.join(asked)} describe pairs of cells; this assembly holds "
                "one cell"
            )
    if boundary == "open" and "pair_distance_max" in given:
        raise ConfigError(
            f"{source}: pair_distance_max: the pair correlation of cells in the open plane is "
            "not defined (no area to normalise by); simulate in a box"
        )
    if boundary != "periodic" and "density_bins" in given:
        raise ConfigError(
            f"{source}: density_bins: the local area fraction comes from the Voronoi "
            f"tessellation of a periodic box; this assembly's boundary is {boundary}"
        )
    return validated(given, CROWD_OPTIONS, "collective analysis option")


def refuse_for_one_cell(crowd: Mapping[str, Any]) -> None:
    """A single-cell file with collective options: the error naming them."""
    if crowd:
        raise ConfigError(
            f"analyze: {', '.join(sorted(crowd))} apply to assemblies of cells (a file made "
            "with --cells or [assembly]); this file holds one cell"
        )


# ---------------------------------------------------------------------------- per cell


def cells_as_realizations(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with its cells taken as realizations: realization index r * cells + c (the
    domain variables dropped)."""
    from softcell.schema import DOMAIN_VARIABLES

    return members_as_realizations(ds, "cell", DOMAIN_VARIABLES)


def members_as_realizations(ds: xr.Dataset, dim: str, dropped) -> xr.Dataset:
    """``ds`` with the members along ``dim`` (an assembly's cells, a ring's bots) taken as
    realizations, index r * members + c; the variables named in ``dropped`` left out, the
    others repeated for each member where they lack ``dim``."""
    body = ds.drop_vars([n for n in dropped if n in ds.variables])
    members = ds.sizes[dim]
    stacked = body.stack(member=("realization", dim), create_index=False)
    stacked = stacked.drop_vars(["realization", dim], errors="ignore")
    stacked = stacked.rename(member="realization").transpose("realization", ...)
    index = np.arange(ds.sizes["realization"] * members, dtype=np.int64)
    return stacked.assign_coords(realization=("realization", index, ds["realization"].attrs))


def cells_back(analysis: xr.Dataset, ds: xr.Dataset) -> xr.Dataset:
    """The per-cell analysis of :func:`cells_as_realizations`'s Dataset with its
    realization dim split back into (realization, cell)."""
    return members_back(analysis, ds, "cell")


def members_back(analysis: xr.Dataset, ds: xr.Dataset, dim: str) -> xr.Dataset:
    """The analysis of :func:`members_as_realizations`'s Dataset with its realization dim
    split back into (realization, ``dim``)."""
    shape = (ds.sizes["realization"], ds.sizes[dim])
    rest = analysis.drop_vars("realization")
    split = {}
    for name in list(rest.data_vars):
        da = rest[name]
        if "realization" not in da.dims:
            continue
        axis = da.dims.index("realization")
        dims = (*da.dims[:axis], "realization", dim, *da.dims[axis + 1 :])
        values = np.asarray(da.values)
        values = values.reshape(values.shape[:axis] + shape + values.shape[axis + 1 :])
        split[name] = (dims, values, da.attrs)
    out = rest.drop_vars(list(split)).assign_coords(
        {name: (name, ds[name].values, dict(ds[name].attrs)) for name in ("realization", dim)}
    )
    return out.assign(split)[list(analysis.data_vars)]


def _msd_error_across_realizations(out: xr.Dataset) -> None:
    """``msd_sem`` across realizations of the cells' mean MSD (two or more realizations),
    else across cells, marked as treating them as independent."""
    sem = out["msd_sem"]
    n = out.sizes["realization"]
    if n >= 2:
        mean = out["msd_realization"].mean("cell")
        values = mean.std("realization", ddof=1) / math.sqrt(n)
        out["msd_sem"] = (
            sem.dims,
            values.transpose(*sem.dims).values,
            {
                **sem.attrs,
                "long_name": "standard error of the MSD across realizations of the cells' mean MSD",
            },
        )
    else:
        sem.attrs["long_name"] = (
            "standard error of the MSD across cells, taken as independent (one realization: "
            "cells that push each other are not, and it understates the error)"
        )


# ---------------------------------------------------------------------------- the crowd


class _Frame:
    """One sample of one realization as freud sees it: a box and the points in it."""

    def __init__(self, boundary: str, box_side: float, pad: float, nodes: np.ndarray) -> None:
        import freud

        self.shift = np.zeros(2)
        if boundary == "periodic":
            self.box = freud.box.Box.square(box_side)
        elif boundary == "walls":  # padded so that no periodic image ever comes within reach
            self.box = freud.box.Box.square(box_side + 4 * pad)
        else:  # the open plane: around the cells, padded
            lo, hi = nodes.reshape(-1, 2).min(axis=0), nodes.reshape(-1, 2).max(axis=0)
            self.box = freud.box.Box.square(float(max(hi - lo)) + 4 * pad)
            self.shift = -(lo + hi) / 2

    def points(self, xy: np.ndarray) -> np.ndarray:
        """(n, 2) positions (cm) as (n, 3) freud points in the box."""
        p = np.zeros((xy.shape[0], 3))
        p[:, :2] = xy + self.shift
        return self.box.wrap(p)


def contact_pairs(frame: _Frame, nodes: np.ndarray, distance: float) -> np.ndarray:
    """(k, 2) pairs i < j of cells with stored nodes within ``distance`` (cm); ``nodes`` is
    (cells, nodes, 2)."""
    import freud

    cells, n = nodes.shape[:2]
    points = frame.points(nodes.reshape(-1, 2))
    query = freud.locality.AABBQuery(frame.box, points)
    found = query.query(points, {"r_max": distance, "exclude_ii": True}).toNeighborList()
    a = found.query_point_indices // n
    b = found.point_indices // n
    keep = a < b
    return np.unique(np.stack([a[keep], b[keep]], axis=1), axis=0).reshape(-1, 2)


def cluster_labels(frame: _Frame, centres: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Each cell's cluster index (freud's Cluster over the contact ``pairs``)."""
    import freud

    cells = centres.shape[0]
    points = frame.points(centres)
    both = np.concatenate([pairs, pairs[:, ::-1]]) if pairs.size else np.zeros((0, 2), int)
    vectors = frame.box.wrap(points[both[:, 1]] - points[both[:, 0]])
    order = np.lexsort((both[:, 1], both[:, 0]))
    nlist = freud.locality.NeighborList.from_arrays(
        cells,
        cells,
        both[order, 0].astype(np.uint32),
        both[order, 1].astype(np.uint32),
        vectors[order],
    )
    cluster = freud.cluster.Cluster()
    cluster.compute((frame.box, points), neighbors=nlist)
    return np.asarray(cluster.cluster_idx)


def _node_spacing(nodes: np.ndarray) -> float:
    return float(np.max(np.hypot(*np.moveaxis(np.diff(nodes, axis=1, append=nodes[:, :1]), -1, 0))))


def crowd_samples(time: np.ndarray, every: float) -> np.ndarray:
    """Indices into ``time`` (s) of samples at least ``every`` s apart, from the first."""
    chosen, last = [], -math.inf
    for i, t in enumerate(time):
        if t >= last + every * (1 - 1e-9):
            chosen.append(i)
            last = t
    return np.asarray(chosen, dtype=np.int64)


class _Crowd:
    """The collective statistics of one sweep point, filled sample by sample."""

    def __init__(self, opts: dict[str, Any], shape: tuple[int, int, int], geometry: dict) -> None:
        realizations, samples, cells = shape
        self.opts, self.geometry = opts, geometry
        self.largest = np.full((realizations, samples), np.nan)
        self.mean_size = np.full((realizations, samples), np.nan)
        self.size_counts = np.zeros(cells)
        self.local = np.full((realizations, samples, cells), np.nan)
        self.lost = np.zeros(realizations)
        self.bonds_time = np.zeros(realizations)
        self.rdf = [None] * realizations

    def cluster(self, r: int, k: int, frame: _Frame, centres: np.ndarray, nodes: np.ndarray):
        distance = self.opts["contact_distance"]
        if distance is None:
            distance = self.geometry["reach"] + _node_spacing(nodes)
        labels = cluster_labels(frame, centres, contact_pairs(frame, nodes, distance))
        sizes = np.bincount(labels)
        sizes = sizes[sizes > 0]
        self.largest[r, k] = sizes.max()
        self.mean_size[r, k] = float(np.sum(sizes.astype(float) ** 2) / np.sum(sizes))
        np.add.at(self.size_counts, sizes - 1, sizes)

    def pair_correlation(self, r: int, frame: _Frame, centres: np.ndarray) -> None:
        import freud

        if self.rdf[r] is None:
            # finite_size: N (N - 1) pairs, so that g -> 1 for independent cells, however few.
            self.rdf[r] = freud.density.RDF(
                self.opts["pair_bins"], self.geometry["r_max"], normalization_mode="finite_size"
            )
        self.rdf[r].compute((frame.box, frame.points(centres)), reset=False)
        # Walls: freud normalises by its padded box; the cells live in the walled one.
        self.rdf_scale = self.geometry["box"] ** 2 / (frame.box.Lx * frame.box.Ly)

    def voronoi(self, r, k, frame, centres, areas, previous, now):
        """Local area fractions, and the Voronoi bonds lost since ``previous`` = (bonds,
        time in s) or None; returns (this sample's bonds, ``now``)."""
        import freud

        voronoi = freud.locality.Voronoi()
        voronoi.compute((frame.box, frame.points(centres)))
        self.local[r, k] = areas / np.asarray(voronoi.volumes)
        nl = voronoi.nlist
        i, j = np.asarray(nl.query_point_indices), np.asarray(nl.point_indices)
        bonds = set(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist(), strict=True))
        if previous is not None:
            self.lost[r] += len(previous[0] - bonds)
            self.bonds_time[r] += (now - previous[1]) * centres.shape[0]
        return bonds, now


def _geometry(ds: xr.Dataset, opts: dict[str, Any]) -> dict[str, Any]:
    """The domain of one sweep point: boundary, box side (cm), R (cm), the pair
    correlation's reach r_max (cm) and the contact's reach (cm)."""
    from softcell.settings import CONTACT_CUTOFF_LENGTHS

    params = json.loads(ds.attrs.get("softcell_parameters", "{}"))
    boundary = str(ds["domain_box"].attrs.get("boundary", "open"))
    box = float(np.asarray(ds["domain_box"].values).ravel()[0])
    radius = float(np.asarray(ds["radius"].values).ravel()[0])
    reach = CONTACT_CUTOFF_LENGTHS * float(params.get("contact_length", 0.0))
    r_max = opts["pair_distance_max"] * 2 * radius
    return {"boundary": boundary, "box": box, "radius": radius, "r_max": r_max, "reach": reach}


def _pair_reach(ds: xr.Dataset, given: float | None) -> float:
    """The pair correlation's reach in cell diameters: ``given``, or 4, at most just under
    half the smallest periodic box of the sweep (freud's minimum image)."""
    if str(ds["domain_box"].attrs.get("boundary")) != "periodic":
        return 4.0 if given is None else given
    boxes = np.asarray(ds["domain_box"].values, dtype=float)
    radius = np.asarray(ds["radius"].values, dtype=float)
    limit = float(np.min(boxes) / (4 * np.max(radius)))
    if given is None:
        return min(4.0, limit * (1 - 1e-6))
    if given >= limit:
        raise ConfigError(
            f"analyze: pair_distance_max = {given:g} cell diameters reaches half the "
            f"periodic box or beyond (box {np.min(boxes):g} cm, R = {np.max(radius):g} cm): "
            f"use a value below {limit:.3g}"
        )
    return given


def _point_crowd(ds: xr.Dataset, time: np.ndarray, opts: dict[str, Any], ipr: np.ndarray):
    """The collective variables of one sweep point (dims realization, time, cell[, node])
    over the analysis' kept ``time`` (s); ``ipr`` (realization, cell, time) is the shape
    index of the per-cell analysis."""
    from softcell.analysis.series import smooth_area_perimeter

    geometry = _geometry(ds, opts)
    boundary, cells = geometry["boundary"], ds.sizes["cell"]
    at = np.searchsorted(np.asarray(ds["time"].values), time)
    angle = np.asarray(ds["bot_angle"].values)[:, at]
    polar = np.abs(np.mean(np.exp(1j * angle), axis=-1))
    picks = crowd_samples(time, opts["crowd_every"])
    shape = (ds.sizes["realization"], picks.size, cells)
    crowd = _Crowd(opts, shape, geometry)
    pairs, voronoi = cells >= 2 and boundary != "open", cells >= 2 and boundary == "periodic"
    pad = max(geometry["r_max"], opts["contact_distance"] or 0.0, geometry["reach"]) + 1.0
    for r in range(shape[0]):
        one = ds.isel(realization=r, time=at[picks])
        mx, my = np.asarray(one["membrane_x"].values), np.asarray(one["membrane_y"].values)
        cx, cy = np.asarray(one["cell_x"].values), np.asarray(one["cell_y"].values)
        areas = smooth_area_perimeter(mx, my)[0] if voronoi else None
        previous = None
        for k in range(picks.size):
            nodes = np.stack([mx[k], my[k]], axis=-1)
            centres = np.stack([cx[k], cy[k]], axis=-1)
            frame = _Frame(boundary, geometry["box"], pad, nodes)
            crowd.cluster(r, k, frame, centres, nodes)
            if pairs:
                crowd.pair_correlation(r, frame, centres)
            if voronoi:
                now = time[picks[k]]
                previous = crowd.voronoi(r, k, frame, centres, areas[k], previous, now)
    return _crowd_variables(crowd, polar, time[picks], ipr[:, :, picks], pairs, voronoi)


def _centres(edges: np.ndarray) -> np.ndarray:
    return 0.5 * (edges[1:] + edges[:-1])


def _sem(values: np.ndarray) -> np.ndarray:
    """Standard error of the mean across the leading axis (NaN below two finite rows)."""
    from softcell.analysis.uncertainty import spread

    return spread(values) / np.sqrt(np.maximum(np.isfinite(values).sum(axis=0), 1))


def _binned_shape(crowd: _Crowd, ipr: np.ndarray) -> tuple[np.ndarray, ...]:
    """The shape index's mean per bin of local area fraction, pooled, its error across
    realizations, and the count per bin."""
    bins = crowd.opts["density_bins"]
    edges = np.linspace(0.0, 1.0, bins + 1)
    which = np.clip(np.digitize(crowd.local, edges) - 1, 0, bins - 1)
    ok = np.isfinite(crowd.local) & np.isfinite(ipr)
    per = np.full((ipr.shape[0], bins), np.nan)
    count = np.zeros(bins, dtype=np.int64)
    total = np.zeros(bins)
    for r in range(ipr.shape[0]):
        w, v = which[r][ok[r]], ipr[r][ok[r]]
        n = np.bincount(w, minlength=bins)
        s = np.bincount(w, weights=v, minlength=bins)
        count += n
        total += s
        with np.errstate(invalid="ignore", divide="ignore"):
            per[r] = s / n
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    return edges, mean, _sem(per), count


def _crowd_variables(
    crowd: _Crowd,
    polar: np.ndarray,
    times: np.ndarray,
    ipr: np.ndarray,
    pairs: bool,
    voronoi: bool,
) -> dict[str, tuple]:
    """The collective variables (dims, values) of one point; ``ipr`` (realization, cell,
    crowd sample)."""
    cells = crowd.size_counts.size
    bins = crowd.opts["pair_bins"]
    g = np.full((len(crowd.rdf), bins), np.nan)
    if pairs:
        g = np.stack([np.asarray(rdf.rdf, dtype=np.float64) * crowd.rdf_scale for rdf in crowd.rdf])
    n_density = crowd.opts["density_bins"]
    shape = (np.linspace(0, 1, n_density + 1), *(np.full(n_density, np.nan),) * 2)
    shape = (*shape, np.zeros(n_density, dtype=np.int64))
    if voronoi:
        shape = _binned_shape(crowd, np.moveaxis(ipr, 1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        exchange = np.where(voronoi, crowd.lost / crowd.bonds_time, np.nan)
    return {
        "coords": {
            "crowd_time": times,
            "cluster_size": np.arange(1, cells + 1),
            "pair_distance": _centres(np.linspace(0.0, crowd.opts["pair_distance_max"], bins + 1)),
            "area_fraction_bin": _centres(shape[0]),
        },
        "polar_order": (("realization", "time"), polar),
        "largest_cluster": (("realization", "crowd_time"), crowd.largest),
        "mean_cluster_size": (("realization", "crowd_time"), crowd.mean_size),
        "cluster_size_fraction": (
            ("cluster_size",),
            crowd.size_counts / max(crowd.size_counts.sum(), 1),
        ),
        "pair_correlation": (("pair_distance",), np.mean(g, axis=0)),
        "pair_correlation_error": (("pair_distance",), _sem(g)),
        "local_area_fraction": (("realization", "crowd_time", "cell"), crowd.local),
        "shape_index_by_density": (("area_fraction_bin",), shape[1]),
        "shape_index_by_density_error": (("area_fraction_bin",), shape[2]),
        "shape_index_by_density_count": (("area_fraction_bin",), shape[3]),
        "neighbour_exchange_rate": (("realization",), exchange),
    }


def _dataset(values: dict[str, Any], lead_coords: dict[str, Any]) -> xr.Dataset:
    """One point's collective variables as a Dataset with CF attributes (lead dims of
    length one in front, for :func:`xarray.combine_by_coords`)."""
    from softcell.schema import CROWD_COORDINATES, CROWD_VARIABLES

    coords = {
        name: (name, data, CROWD_COORDINATES[name].cf_attrs())
        for name, data in values.pop("coords").items()
    }
    out = xr.Dataset(
        {
            name: (dims, data, CROWD_VARIABLES[name].cf_attrs())
            for name, (dims, data) in values.items()
        },
        coords=coords,
    )
    return out.expand_dims({d: [v] for d, v in lead_coords.items()}) if lead_coords else out


def analyze_assembly(
    ds: xr.Dataset,
    options: Mapping[str, Any] | None,
    crowd: Mapping[str, Any],
    *,
    progress: bool = False,
    registry: Any = None,
    analyze: Callable[..., xr.Dataset],
) -> xr.Dataset:
    """The analysis of an assembly (see the module's docstring): the per-cell analysis with
    a ``cell`` dim and the collective variables (``softcell.schema.CROWD_VARIABLES``).
    ``options`` are the analysis options, ``crowd`` the collective ones (CROWD_OPTIONS);
    ``analyze`` is the single-cell analysis (:func:`softcell.analysis.sweep.analyze`, which
    hands itself over: each cell is analysed as a realization of its own)."""
    boundary = str(ds["domain_box"].attrs.get("boundary", "open"))
    opts = crowd_options(crowd, ds.sizes["cell"], boundary)
    lead = [d for d in ds["cell_x"].dims if d not in ("realization", "time", "cell")]
    opts["pair_distance_max"] = _pair_reach(ds, opts["pair_distance_max"])
    blocks = np.repeat(np.arange(ds.sizes["realization"]), ds.sizes["cell"])
    per_cell = analyze(
        cells_as_realizations(ds), options, progress=progress, registry=registry, blocks=blocks
    )
    out = cells_back(per_cell, ds)
    _msd_error_across_realizations(out)
    time = np.asarray(out["time"].values)
    parts = []
    for point in [
        dict(zip(lead, i, strict=True)) for i in np.ndindex(*[ds.sizes[d] for d in lead])
    ]:
        here = ds.isel(point) if point else ds
        ipr = np.asarray((out.isel(point) if point else out)["ipr"].values)
        values = _point_crowd(here, time, opts, ipr)
        parts.append(_dataset(values, {d: ds[d].values[i] for d, i in point.items()}))
    collective = parts[0]
    if lead:  # the points' grids are the same: nest them back along the sweep's dims
        nested: Any = np.empty([ds.sizes[d] for d in lead], dtype=object)
        for i, part in zip(np.ndindex(*nested.shape), parts, strict=True):
            nested[i] = part
        collective = xr.combine_nested(
            nested.tolist(),
            concat_dim=lead,
            coords="minimal",
            compat="override",
            combine_attrs="drop",
        )
    for d in lead:
        collective[d].attrs.update(ds[d].attrs)
    out = xr.merge([out, collective], combine_attrs="override")
    out.attrs.update(
        {
            "softcell_crowd_options": json.dumps(opts, sort_keys=True),
            "softcell_crowd_option_units": json.dumps(
                {k: CROWD_OPTIONS[k].unit for k in opts}, sort_keys=True
            ),
            "softcell_boundary": boundary,
            "softcell_cells": int(ds.sizes["cell"]),
        }
    )
    return out
