"""The analysis of assemblies: every cell as the single-cell analysis sees it, and the
crowd's statistics against arrangements whose answer is known (rings placed by hand, random
points against a brute-force histogram, a lattice's Voronoi cells)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import softcell
from softcell.cli import main
from softcell.errors import ConfigError
from softcell.model.configuration import RunConfig
from softcell.runner.ensemble import simulate

R = 5.0
BOX = 30.0


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("crowd_analysis")
    crowd = simulate(
        RunConfig(parameters={"radius": R, "duration": 3.0}, assembly={"cells": 4, "box": BOX}),
        root / "crowd",
        realizations=2,
        progress=False,
    )
    one = simulate(
        RunConfig(parameters={"radius": R, "duration": 3.0}), root / "one", progress=False
    )
    return root, crowd[0].parent, one[0]


def _crowd(runs, cells=None):
    ds = softcell.open_dataset(runs[1]).load()
    if cells is not None:  # the cell dim repeated to ``cells`` (their positions set after)
        ds = ds.isel(cell=np.arange(cells) % ds.sizes["cell"])
        ds = ds.assign_coords(cell=np.arange(cells))
    return ds


def _place(ds, centres, radius=R, boundary=None):
    """Every sample of every realization: rings of ``radius`` (cm) at ``centres`` (cells, 2)."""
    ds = ds.copy(deep=True)
    nodes = ds.sizes["node"]
    phi = 2 * np.pi * np.arange(nodes) / nodes
    centres = np.asarray(centres, dtype=float)
    ds["cell_x"][:] = centres[:, 0]
    ds["cell_y"][:] = centres[:, 1]
    ds["membrane_x"][:] = centres[:, 0, None] + radius * np.cos(phi)
    ds["membrane_y"][:] = centres[:, 1, None] + radius * np.sin(phi)
    if boundary is not None:
        ds["domain_box"].attrs["boundary"] = boundary
    return ds


OPTIONS = {"discard": 0.0, "crowd_every": 0.5}


def test_every_cell_is_what_the_single_cell_analysis_makes_of_it(runs):
    ds = _crowd(runs)
    out = softcell.analyze(ds, OPTIONS)
    for c in range(ds.sizes["cell"]):
        alone = softcell.analyze(ds.isel(cell=c), {"discard": 0.0})
        np.testing.assert_allclose(
            out["msd_realization"].sel(cell=c).values, alone["msd_realization"].values, rtol=1e-12
        )
        np.testing.assert_array_equal(
            out["stopgo_label"].sel(cell=c).values, alone["stopgo_label"].values
        )
        np.testing.assert_allclose(out["ipr"].sel(cell=c).values, alone["ipr"].values)
    # Pooled over cells and realizations of equal length: the plain mean of every MSD.
    np.testing.assert_allclose(
        out["msd"].values, out["msd_realization"].mean(("realization", "cell")).values, rtol=1e-10
    )
    # The error is across realizations (cells that push each other are not independent).
    means = out["msd_realization"].mean("cell")
    sem = means.std("realization", ddof=1) / math.sqrt(ds.sizes["realization"])
    np.testing.assert_allclose(out["msd_sem"].values, sem.transpose(*out["msd_sem"].dims).values)
    for name, var in out.variables.items():
        if var.dtype.kind != "U":  # the body labels are names, without units
            assert var.attrs.get("units") and var.attrs.get("long_name"), name


def test_polar_order_is_one_for_aligned_bots_and_zero_for_evenly_spread_ones(runs):
    ds = _crowd(runs)
    ds["bot_angle"][:] = 0.7
    aligned = softcell.analyze(ds, OPTIONS)["polar_order"]
    np.testing.assert_allclose(aligned.values, 1.0, rtol=1e-12)
    cells = ds.sizes["cell"]
    ds["bot_angle"][:] = 2 * np.pi * np.arange(cells) / cells + ds["time"].values[:, None]
    spread = softcell.analyze(ds, OPTIONS)["polar_order"]
    np.testing.assert_allclose(spread.values, 0.0, atol=1e-12)


# Two pairs with a 0.3 cm gap: one face to face, one only through the periodic boundary.
PAIRS = [(-5.15, -7.5), (5.15, -7.5), (-9.85, 7.5), (9.85, 7.5)]


@pytest.mark.parametrize(
    ("boundary", "largest", "mean_size", "fractions"),
    [("periodic", 2, 2.0, [0, 1, 0, 0]), ("walls", 2, 1.5, [0.5, 0.5, 0, 0])],
)
def test_clusters_of_rings_placed_by_hand(runs, boundary, largest, mean_size, fractions):
    ds = _place(_crowd(runs), PAIRS, boundary=boundary)
    out = softcell.analyze(ds, {**OPTIONS, "contact_distance": 0.6})
    np.testing.assert_array_equal(out["largest_cluster"].values, largest)
    np.testing.assert_allclose(out["mean_cluster_size"].values, mean_size)
    np.testing.assert_allclose(out["cluster_size_fraction"].values, fractions)
    # Below the gap, no contact at all.
    apart = softcell.analyze(ds, {**OPTIONS, "contact_distance": 0.25})
    np.testing.assert_array_equal(apart["largest_cluster"].values, 1)


def _brute_force_g(centres, box, edges):
    """g(r) of points in a periodic square box by the minimum image, every pair counted."""
    n = centres.shape[0]
    d = centres[:, None, :] - centres[None, :, :]
    d -= box * np.round(d / box)
    r = np.hypot(d[..., 0], d[..., 1])[~np.eye(n, dtype=bool)]
    counts = np.histogram(r, edges)[0]
    shells = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    return counts / (n * (n - 1) / box**2 * shells)


def test_pair_correlation_matches_a_brute_force_histogram_of_the_minimum_image(runs):
    cells = 40
    ds = _crowd(runs, cells)
    rng = np.random.default_rng(3)
    centres = rng.uniform(-BOX / 2, BOX / 2, (cells, 2))
    ds = _place(ds, centres, radius=0.5)  # overlap is fine: g(r) only sees the centres
    out = softcell.analyze(ds, {**OPTIONS, "pair_bins": 10, "pair_distance_max": 1.4})
    edges = np.linspace(0.0, 1.4 * 2 * R, 11)
    np.testing.assert_allclose(
        out["pair_distance"].values, 0.5 * (edges[1:] + edges[:-1]) / (2 * R), rtol=1e-12
    )
    np.testing.assert_allclose(
        out["pair_correlation"].values, _brute_force_g(centres, BOX, edges), rtol=1e-6
    )  # freud counts in single precision
    np.testing.assert_allclose(out["pair_correlation_error"].values, 0.0, atol=1e-12)


def test_a_square_lattice_has_voronoi_cells_of_a_quarter_box_and_no_exchanges(runs):
    q = BOX / 4
    ds = _place(_crowd(runs), [(-q, -q), (q, -q), (-q, q), (q, q)])
    out = softcell.analyze(ds, OPTIONS)
    np.testing.assert_allclose(
        out["local_area_fraction"].values, np.pi * R**2 / (BOX**2 / 4), rtol=1e-9
    )
    np.testing.assert_array_equal(out["neighbour_exchange_rate"].values, 0.0)
    assert int(out["shape_index_by_density_count"].sum()) == out["local_area_fraction"].size
    # The open plane and walls have no Voronoi cells here: NaN, not a number made up.
    walls = softcell.analyze(
        _place(ds, [(-q, -q), (q, -q), (-q, q), (q, q)], boundary="walls"), OPTIONS
    )
    assert np.isnan(walls["local_area_fraction"].values).all()


def test_collective_options_on_one_cell_are_one_line_naming_them(runs, tmp_path, capsys):
    _, crowd, one = runs
    with pytest.raises(ConfigError, match="crowd_every apply to assemblies"):
        softcell.analyze(softcell.open_dataset(one), {"crowd_every": 1.0})
    argv = ["analyze", str(one), "-o", str(tmp_path / "a.nc"), "--contact-distance", "0.5"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "contact_distance apply to assemblies" in err
    argv = ["analyze", str(crowd), "-o", str(tmp_path / "b.nc"), "--pair-distance-max", "2"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "pair_distance_max = 2 cell diameters reaches half the periodic box" in err
    assert not (tmp_path / "b.nc").exists()


def test_one_cell_of_an_assembly_has_no_pairs_to_correlate(runs):
    ds = _crowd(runs).isel(cell=[0])
    out = softcell.analyze(ds, OPTIONS)
    np.testing.assert_allclose(out["polar_order"].values, 1.0, rtol=1e-15)
    assert np.isnan(out["pair_correlation"].values).all()
    with pytest.raises(ConfigError, match="pair_bins describe pairs of cells"):
        softcell.analyze(ds, {**OPTIONS, "pair_bins": 5})


def test_the_command_line_analyses_an_assembly_into_a_file_with_a_cell_dim(runs, capsys):
    root, crowd, _ = runs
    out = root / "crowd_analysis.nc"
    assert main(["analyze", str(crowd), "-o", str(out), "--discard", "0", "--quiet"]) == 0
    assert "2 realization(s) of 4 cells" in capsys.readouterr().out
    analysis = softcell.read_dataset(out)
    assert analysis["speed"].dims == ("body", "realization", "cell", "time")
    assert analysis.attrs["softcell_boundary"] == "periodic"
    assert 0.0 <= float(analysis["polar_order"].min()) <= float(analysis["polar_order"].max()) <= 1


def test_a_sweep_of_assemblies_is_analysed_point_by_point(tmp_path):
    config = RunConfig(
        parameters={"radius": [4.0, 5.0], "duration": 1.0}, assembly={"cells": 2, "box": 30.0}
    )
    simulate(config, tmp_path / "sweep", progress=False)
    ds = softcell.open_dataset(tmp_path / "sweep")
    options = {"discard": 0.0, "crowd_every": 0.25, "pair_distance_max": 1.4}
    out = softcell.analyze(ds, options)
    assert out["pair_correlation"].dims == ("radius", "pair_distance")
    assert out["polar_order"].dims == ("radius", "realization", "time")
    for i in range(2):  # each point as if analysed alone
        alone = softcell.analyze(ds.isel(radius=i), options)
        np.testing.assert_allclose(
            out["largest_cluster"].isel(radius=i).values, alone["largest_cluster"].values
        )
        np.testing.assert_allclose(
            out["pair_correlation"].isel(radius=i).values,
            alone["pair_correlation"].values,
            equal_nan=True,
        )
