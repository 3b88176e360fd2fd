"""Rendering and tracking: the round trip against the simulated truth, and bad inputs."""

import cv2
import numpy as np
import pytest

import softcell
from softcell.cli import main
from softcell.errors import SoftcellError
from softcell.model.configuration import RunConfig
from softcell.runner.ensemble import simulate
from softcell.video.render import render
from softcell.video.track import FLAGS, track

# A coarse membrane (cutoff 4, stable at dt = 1e-5 s) keeps the simulation cheap; the
# renderer and tracker do not care how the record was made.
COARSE = {"cutoff": 4, "nodes": 64, "stored_nodes": 16, "dt": 1e-5}


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    out = tmp_path_factory.mktemp("sim")
    config = RunConfig(parameters={"radius": 8.0, "duration": 4.0, **COARSE})
    path = simulate(config, out, realizations=1, seed=1, progress=False)[0]
    return softcell.read_dataset(path)


def errors(tracked, truth):
    """RMS errors of cell GC (cm), bot center (cm) and heading (degrees)."""
    t = tracked.isel(realization=0)
    cell = np.hypot(t.cell_x.values - truth.cell_x.values, t.cell_y.values - truth.cell_y.values)
    bot = np.hypot(t.bot_x.values - truth.bot_x.values, t.bot_y.values - truth.bot_y.values)
    turn = (t.bot_angle.values - truth.bot_angle.values + np.pi) % (2 * np.pi) - np.pi
    return (
        np.sqrt(np.mean(cell**2)),
        np.sqrt(np.mean(bot**2)),
        np.degrees(np.sqrt(np.mean(turn**2))),
    )


@pytest.mark.parametrize("noise, blur, illumination", [(0.0, 0.0, 0.0), (3.0, 1.0, 0.2)])
def test_round_trip_positions_at_10_px_per_cm(simulated, tmp_path, noise, blur, illumination):
    info = render(
        simulated,
        tmp_path / "cell.mkv",
        px_per_cm=10,
        fps=30,
        noise=noise,
        blur=blur,
        illumination=illumination,
        seed=3,
    )
    assert info.interpolated  # 1/30 s frames fall between 0.01 s samples, and it says so
    tracked = track(tmp_path / "cell.mkv", px_per_cm=10, origin=(info.frame.x0, info.frame.y0))
    softcell.validate(tracked)
    assert tracked.sizes["time"] == info.times.size
    assert (tracked.tracking_flag == FLAGS["ok"]).all()
    # The truth resampled at the frame times, as the renderer did (linear interpolation).
    truth = simulated.isel(realization=0).interp(time=info.times)
    cell, bot, heading = errors(tracked, truth)
    assert cell <= 0.01 and bot <= 0.05 and heading <= 3.0, (cell, bot, heading)
    result = softcell.analyze(tracked, {"discard": 0.0})  # the analysis runs unchanged
    assert result.attrs["softcell_input_origin"] == "tracking"
    assert float(result.softcell_threshold) == 0.3


def test_without_a_head_mark_continuity_and_motion_fix_the_direction(simulated, tmp_path):
    info = render(simulated, tmp_path / "cell.mkv", px_per_cm=10, fps=30, head_mark=False)
    tracked = track(tmp_path / "cell.mkv", px_per_cm=10, origin=(info.frame.x0, info.frame.y0))
    truth = simulated.isel(realization=0).interp(time=info.times)
    cell, bot, heading = errors(tracked, truth)
    assert heading <= 3.0 and bot <= 0.05, (cell, bot, heading)


def test_a_failed_frame_is_nan_flagged_and_counted(simulated, tmp_path):
    info = render(simulated, tmp_path / "cell.mkv", px_per_cm=10, fps=30, end=0.5)
    reader = cv2.VideoCapture(str(tmp_path / "cell.mkv"))
    writer = cv2.VideoWriter(
        str(tmp_path / "gap.mkv"),
        cv2.VideoWriter_fourcc(*"FFV1"),
        30,
        (info.frame.width, info.frame.height),
    )
    index = 0
    while True:
        ok, image = reader.read()
        if not ok:
            break
        writer.write(np.full_like(image, 200) if index == 4 else image)
        index += 1
    writer.release()
    tracked = track(tmp_path / "gap.mkv", px_per_cm=10)
    flags = tracked.tracking_flag.values[0]
    assert flags[4] == FLAGS["both_lost"] and (np.delete(flags, 4) == FLAGS["ok"]).all()
    assert np.isnan(tracked.cell_x.values[0, 4]) and np.isnan(tracked.bot_x.values[0, 4])
    assert '"both_lost": 1' in tracked.attrs["softcell_tracking_summary"]


def test_bad_videos_give_one_clear_error(tmp_path, capsys):
    with pytest.raises(SoftcellError, match="no such video file"):
        track(tmp_path / "missing.mkv", px_per_cm=10)
    (tmp_path / "empty.mkv").write_bytes(b"")
    with pytest.raises(SoftcellError, match="is empty"):
        track(tmp_path / "empty.mkv", px_per_cm=10)
    (tmp_path / "corrupt.mkv").write_bytes(np.random.default_rng(0).bytes(5000))
    with pytest.raises(SoftcellError, match="corrupt"):
        track(tmp_path / "corrupt.mkv", px_per_cm=10)
    assert (
        main(
            [
                "track",
                str(tmp_path / "corrupt.mkv"),
                "--px-per-cm",
                "10",
                "-o",
                str(tmp_path / "t.nc"),
            ]
        )
        == 2
    )
    assert "corrupt" in capsys.readouterr().err


def test_bad_render_requests_are_named(simulated, tmp_path):
    with pytest.raises(SoftcellError, match="realization index 3 is not allowed: 0 .. 0"):
        render(simulated, tmp_path / "v.mkv", realization=3)
    with pytest.raises(SoftcellError, match="px_per_cm = 0 is not allowed"):
        render(simulated, tmp_path / "v.mkv", px_per_cm=0)
    with pytest.raises(SoftcellError, match="must end in .mkv"):
        render(simulated, tmp_path / "v.gif")
    assert not list(tmp_path.iterdir())


def test_cli_render_then_track(simulated, tmp_path, capsys):
    sim = tmp_path / "sim.nc"
    softcell.write_dataset(simulated, sim)
    assert main(["render", str(sim), "-o", str(tmp_path / "v.mkv"), "--end", "0.3", "--quiet"]) == 0
    out = capsys.readouterr().out
    corner = out.split("--origin=")[1].split(")")[0]
    assert (
        main(
            [
                "track",
                str(tmp_path / "v.mkv"),
                "--px-per-cm",
                "10",
                f"--origin={corner}",
                "--quiet",
                "-o",
                str(tmp_path / "t.nc"),
            ]
        )
        == 0
    )
    tracked = softcell.open_dataset(tmp_path / "t.nc")
    assert tracked.sizes["time"] == 10
    assert abs(float(tracked.cell_x[0, 0]) - float(simulated.cell_x[0, 0])) < 0.01
