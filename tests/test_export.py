"""``softcell export``: a simulation as a GSD trajectory, read back by gsd, freud and
MDAnalysis, and softcell's MSD against trackpy's and MDAnalysis' on the same trajectories."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import gsd.hoomd
import MDAnalysis as mda
import numpy as np
import pandas as pd
import pytest
import trackpy
import xarray as xr
from MDAnalysis.analysis.msd import EinsteinMSD

import softcell
from softcell.analysis.msd import msd
from softcell.cli import main
from softcell.errors import SoftcellError
from softcell.io.export import gsd_attributes, to_gsd, to_movement
from softcell.io.netcdf import open_inputs
from softcell.model.configuration import RunConfig


@pytest.fixture(scope="module")
def one_cell(tmp_path_factory):
    """Two realizations of one cell, R = 5 cm, 8 s sampled every 0.05 s."""
    out = tmp_path_factory.mktemp("one")
    config = RunConfig(
        parameters={"radius": 5.0, "duration": 8.0, "sample_every": 0.05, "sample_every_late": 0.05}
    )
    softcell.simulate(config, out, realizations=2, seed=3, progress=False)
    return out


@pytest.fixture(scope="module")
def crowd(tmp_path_factory):
    """Four cells in a small periodic box, 3 s: they cross its edges."""
    out = tmp_path_factory.mktemp("crowd")
    config = RunConfig(
        parameters={"radius": 5.0, "duration": 3.0},
        assembly={"cells": 4, "box": 24.0, "boundary": "periodic"},
    )
    (path,) = softcell.simulate(config, out, realizations=1, seed=1, progress=False)
    return path


def test_every_sample_is_a_frame_of_the_membrane_nodes_then_the_bot(one_cell, tmp_path):
    ds = open_inputs([one_cell])
    done = to_gsd(ds, tmp_path / "r1.gsd", realization=1)
    # the permissions every output has (gsd alone would give 0640)
    written = next(one_cell.glob("*.nc")).stat().st_mode & 0o777
    assert (tmp_path / "r1.gsd").stat().st_mode & 0o777 == written
    one = ds.isel(realization=1)
    with gsd.hoomd.open(tmp_path / "r1.gsd") as trajectory:
        assert len(trajectory) == done.frames == one.sizes["time"]
        for i in (0, 7, len(trajectory) - 1):
            frame = trajectory[i]
            assert frame.configuration.dimensions == 2
            assert list(frame.particles.types) == ["membrane", "bot"]
            assert (frame.particles.typeid[:64] == 0).all() and frame.particles.typeid[64] == 1
            xy = frame.particles.position[:, :2]
            assert np.allclose(xy[:64, 0], one.membrane_x[i], atol=1e-5)
            assert np.allclose(xy[:64, 1], one.membrane_y[i], atol=1e-5)
            assert np.allclose(xy[64], [one.bot_x[i], one.bot_y[i]], atol=1e-5)
            q = frame.particles.orientation[64]  # about z by the heading
            heading = float(one.bot_angle[i])
            assert np.allclose(q, [np.cos(heading / 2), 0, 0, np.sin(heading / 2)], atol=1e-6)
            assert frame.log["softcell/time"][0] == pytest.approx(float(one.time[i]))
            half = frame.configuration.box[0] / 2
            assert np.abs(xy).max() < half  # the box holds every frame
    assert gsd_attributes(tmp_path / "r1.gsd") == json.loads(json.dumps(_plain(one.attrs)))
    shapes = trajectory_shapes(tmp_path / "r1.gsd")
    assert shapes[1] == {"type": "Ellipsoid", "a": 3.0, "b": 2.0, "c": 0.5}
    assert shapes[0]["diameter"] == pytest.approx(2 * np.pi * 5.0 / 64)


def trajectory_shapes(path):
    with gsd.hoomd.open(path) as trajectory:
        return trajectory[0].particles.type_shapes


def _plain(attrs):
    return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in attrs.items()}


def test_a_periodic_crowd_is_wrapped_with_its_images(crowd, tmp_path):
    ds = softcell.read_dataset(crowd)
    to_gsd(ds, tmp_path / "crowd.gsd")
    one = ds.isel(realization=0)
    crossed = False
    with gsd.hoomd.open(tmp_path / "crowd.gsd") as trajectory:
        for i in range(0, len(trajectory), 25):
            frame = trajectory[i]
            side = frame.configuration.box[0]
            assert side == 24.0
            xy = frame.particles.position[:, :2].astype(np.float64)
            assert np.abs(xy).max() <= side / 2
            unwrapped = xy + side * frame.particles.image[:, :2]
            nodes = np.stack([one.membrane_x[i].values, one.membrane_y[i].values], axis=-1)
            assert np.allclose(unwrapped[: 4 * 64], nodes.reshape(-1, 2), atol=1e-4)
            bots = np.stack([one.bot_x[i].values, one.bot_y[i].values], axis=-1)
            assert np.allclose(unwrapped[4 * 64 :], bots, atol=1e-4)
            crossed |= bool(np.any(frame.particles.image != 0))
    assert crossed  # the test saw the wrapping at work


def test_softcells_msd_is_trackpys_and_mdanalysis_on_the_same_trajectories(one_cell, tmp_path):
    ds = open_inputs([one_cell])
    for r in range(2):
        one = ds.isel(realization=r)
        bot = np.stack([one.bot_x.values, one.bot_y.values], axis=1)
        ours = msd(bot)
        # MDAnalysis reads the exported GSD (float32 positions: 1e-5 relative)
        to_gsd(ds, tmp_path / f"r{r}.gsd", realization=r)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "Reader has no dt information"
            universe = mda.Universe(str(tmp_path / f"r{r}.gsd"))
            theirs = EinsteinMSD(universe, select="type bot", msd_type="xy", fft=True).run()
        lags = slice(1, ours.size // 2)
        assert np.allclose(theirs.results.timeseries[lags], ours[lags], rtol=1e-5)
        # trackpy on the same float64 track with a third of the samples missing: softcell's
        # masked FFT sums against trackpy's pairs of the frames present.
        keep = np.random.default_rng(r).random(bot.shape[0]) > 1 / 3
        holes = np.where(keep[:, None], bot, np.nan)
        frames = np.flatnonzero(keep)
        table = pd.DataFrame({"frame": frames, "particle": 0, "x": bot[keep, 0], "y": bot[keep, 1]})
        top = ours.size // 2
        emsd = trackpy.emsd(table, mpp=1.0, fps=1.0, max_lagtime=top)
        masked = msd(holes)
        at = np.rint(emsd.index.values).astype(int)  # lag times k / fps, floats
        assert np.allclose(emsd.values, masked[at], rtol=1e-9)


@pytest.mark.parametrize(
    "argv,words",
    [
        (
            ["--realization", "5"],
            "--realization 5 is not allowed: the file holds realizations 0 to 1",
        ),
        ([], "the file holds 2 realizations; choose one with --realization (0 to 1)"),
        (["--realization", "0", "--every", "0"], "--every 0 is not allowed"),
    ],
)
def test_bad_requests_are_one_line(one_cell, tmp_path, capsys, argv, words):
    code = main(["export", str(one_cell), "-o", str(tmp_path / "t.gsd"), *argv])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "t.gsd").exists()


def test_the_output_must_be_gsd_and_others_files_are_kept(one_cell, tmp_path, capsys):
    assert main(["export", str(one_cell), "-o", str(tmp_path / "t.xyz"), "--to", "gsd"]) == 2
    assert "a GSD file ends in .gsd" in capsys.readouterr().err
    mine = tmp_path / "notes.gsd"
    mine.write_text("mine")
    assert main(["export", str(one_cell), "-o", str(mine), "--realization", "0"]) == 2
    assert "pass --overwrite" in capsys.readouterr().err and mine.read_text() == "mine"
    out = tmp_path / "t.gsd"
    assert main(["export", str(one_cell), "-o", str(out), "--realization", "0"]) == 0
    assert main(["export", str(one_cell), "-o", str(out), "--realization", "1"]) == 0  # a rerun


def test_only_a_simulation_is_exported(one_cell, tmp_path, capsys):
    analysis = tmp_path / "a.nc"
    assert main(["analyze", str(one_cell), "-o", str(analysis), "--discard", "0"]) == 0
    capsys.readouterr()
    assert main(["export", str(analysis), "-o", str(tmp_path / "t.gsd")]) == 2
    assert "no simulation or tracking files" in capsys.readouterr().err
    tracked = open_inputs([one_cell]).assign_attrs(softcell_origin="tracking")
    with pytest.raises(SoftcellError, match="this one is a softcell tracking file"):
        to_gsd(tracked, tmp_path / "t.gsd", realization=0)
    assert not (tmp_path / "t.gsd").exists()


# -- movement -----------------------------------------------------------------------------------

REFERENCE = Path(__file__).with_name("data") / "movement_poses_reference.nc"


def _tracked_from(reference: xr.Dataset) -> xr.Dataset:
    """A tracking file (softcell's tracked schema) holding the reference's planted tracks."""
    from softcell.video.tracker import FLAGS, TrackResult, tracked_dataset

    p = reference["position"].values[:, :, :, 0]  # time, space, keypoint
    bot, front, cell = p[:, :, 0], p[:, :, 1], p[:, :, 2]
    heading = np.arctan2(front[:, 1] - bot[:, 1], front[:, 0] - bot[:, 0])
    result = TrackResult()
    for i, t in enumerate(reference["time"].values):
        lost = not np.isfinite(bot[i]).all()
        result.times.append(float(t))
        result.cell.append(tuple(cell[i]))
        result.bot.append((*bot[i], heading[i]))
        result.membrane.append(np.full((8, 2), np.nan) if lost else cell[i] + np.ones((8, 2)))
        result.flags.append(FLAGS["both_lost"] if lost else FLAGS["ok"])
        result.marked.append(True)
    return tracked_dataset(result, nodes=8, radius=5.0, attrs={})


def test_a_tracked_video_becomes_movements_own_poses_dataset(tmp_path):
    """The poses file of a tracked file is the one movement's load_poses.from_numpy makes of
    the same tracks (the stored reference: tests/data/make_movement_reference.py)."""
    reference = xr.open_dataset(REFERENCE)
    tracked = _tracked_from(reference)
    done = to_movement(tracked, tmp_path / "poses.nc")
    assert done.frames == 31 and done.particles == 3
    ours = xr.open_dataset(tmp_path / "poses.nc")
    for name in ("position", "confidence"):
        assert ours[name].dims == reference[name].dims
        np.testing.assert_allclose(ours[name].values, reference[name].values, atol=1e-9)
    for coord in ("time", "space", "keypoints", "individuals"):
        np.testing.assert_array_equal(ours[coord].values, reference[coord].values)
    for key in ("ds_type", "fps", "time_unit"):
        assert ours.attrs[key] == reference.attrs[key]
    assert json.loads(ours.attrs["softcell_attributes"])["softcell_origin"] == "tracking"


def test_movement_bad_requests_are_one_line(one_cell, tmp_path, capsys):
    # the default sampling switches from 0.01 s to 0.1 s: no single fps
    uneven = tmp_path / "uneven"
    softcell.simulate(
        RunConfig(parameters={"radius": 5.0, "duration": 1.0, "sample_switch": 0.5}),
        uneven,
        progress=False,
    )
    assert main(["export", str(uneven), "-o", str(tmp_path / "p.nc")]) == 2
    assert "evenly spaced in time" in capsys.readouterr().err
    assert main(["export", str(one_cell), "-o", str(tmp_path / "p.txt")]) == 2
    assert "give a .gsd (GSD) or .nc (movement) file" in capsys.readouterr().err
    argv = ["export", str(one_cell), "-o", str(tmp_path / "p.nc"), "--every", "2"]
    assert main([*argv, "--realization", "0"]) == 2
    assert "--every belongs to --to gsd" in capsys.readouterr().err
    assert main(["export", str(one_cell), "-o", str(tmp_path / "p.nc"), "--realization", "1"]) == 0
    poses = xr.open_dataset(tmp_path / "p.nc")
    assert poses.attrs["fps"] == pytest.approx(20.0) and poses.sizes["time"] == 161
    # a rerun replaces its own export; the folder still reads as the simulation it was
    assert main(["export", str(one_cell), "-o", str(tmp_path / "p.nc"), "--realization", "0"]) == 0
