"""softcell animate: H.264 MP4 and GIF movies of simulations, decoded back and counted."""

import av
import numpy as np
import pytest

from softcell.cli import main
from softcell.errors import SoftcellError
from softcell.io.netcdf import open_dataset
from softcell.model.configuration import RunConfig
from softcell.runner.ensemble import simulate
from softcell.video.animate import animate


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("animate")
    one = simulate(
        RunConfig(parameters={"radius": 4.0, "duration": 1.0}),
        root / "one",
        realizations=2,
        progress=False,
    )
    crowd = simulate(
        RunConfig(parameters={"radius": 5.0, "duration": 0.5}, assembly={"cells": 4, "box": 30.0}),
        root / "crowd",
        progress=False,
    )
    return root, one[0].parent, crowd[0].parent


def _decoded(path):
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        frames = [f.to_ndarray(format="rgb24") for f in container.decode(stream)]
        return stream.codec_context.name, frames


def test_an_mp4_is_h264_with_one_frame_per_step_and_both_realizations(runs):
    root, one, _ = runs
    movie = animate(open_dataset(one), root / "one.mp4", fps=20, progress=False)
    codec, frames = _decoded(movie.path)
    assert codec == "h264"
    assert movie.frames == len(frames) == 21  # 0 .. 1 s every 0.05 s
    height, width, _ = frames[0].shape
    assert (width, height) == movie.size and width % 2 == 0 and height % 2 == 0
    assert width == 2 * 480  # two panels side by side
    # the membrane's red is drawn in both panels
    red = (frames[-1][..., 0] > 150) & (frames[-1][..., 1] < 100) & (frames[-1][..., 2] < 100)
    assert red[:, : width // 2].sum() > 50 and red[:, width // 2 :].sum() > 50


def test_a_gif_of_an_assembly_has_every_cell_in_one_panel(runs):
    root, _, crowd = runs
    movie = animate(open_dataset(crowd), root / "crowd.gif", fps=10, speed=0.5, progress=False)
    codec, frames = _decoded(movie.path)
    assert codec == "gif" and len(frames) == movie.frames == 11
    assert movie.size[0] == 480  # one panel


def _red(frame):
    return (frame[..., 0] > 150) & (frame[..., 1] < 100) & (frame[..., 2] < 100)


def test_a_gif_keeps_flat_colours_flat(runs):
    """The panel's light grey background is one colour in every frame (FFmpeg's fixed
    palette dithered it into speckles), and the membrane stays red."""
    root, one, _ = runs
    movie = animate(open_dataset(one), root / "one.gif", fps=10, progress=False)
    _, frames = _decoded(movie.path)
    for frame in frames:
        corner = frame[40:70, 400:470].reshape(-1, 3)  # the first panel's top right, empty
        assert len(np.unique(corner, axis=0)) == 1
        assert np.abs(corner[0].astype(int) - 250).max() <= 3  # #fafafa
        assert _red(frame).sum() > 50


def test_a_ring_across_a_periodic_edge_shows_on_the_other_side(runs):
    """Every cell put astride the box's right edge (x = 15 cm of a 30 cm box): its image
    shows at the left edge."""
    root, _, crowd = runs
    ds = open_dataset(crowd).load()
    moved = ds.copy(deep=True)
    for body in ("cell", "bot"):
        moved[f"{body}_x"].values[:] = 15.0
        moved[f"{body}_y"].values[:] = 0.0
    for axis, centre in (("x", 15.0), ("y", 0.0)):
        ring = (ds[f"membrane_{axis}"] - ds[f"cell_{axis}"]).isel(cell=0).values
        moved[f"membrane_{axis}"].values[:] = ring[:, :, None, :] + centre
    movie = animate(moved, root / "edge.mp4", fps=10, end=0.2, progress=False)
    _, frames = _decoded(movie.path)
    panel = frames[-1][28:]  # below the header
    # the window spans -16 .. 16 cm over 480 px: the image's arc at -15 .. -10 cm
    left = _red(panel[:, 15:90]).sum()
    right = _red(panel[:, 390:465]).sum()
    assert right > 50 and left > 0.5 * right


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"out": "x.avi"}, "unknown movie format"),
        ({"fps": 0.0}, "fps = 0.0"),
        ({"speed": -1.0}, "speed = -1.0"),
        ({"realizations": [5]}, "realization 5 is not allowed"),
        ({"realizations": [0, 1, 0, 1, 0]}, "choose 1 to 4"),
        ({"start": 0.8, "end": 0.2}, "start = 0.8 s, end = 0.2 s"),
        ({"height": 10}, "height = 10 px"),
    ],
)
def test_a_bad_request_is_one_line(runs, kwargs, message):
    root, one, _ = runs
    out = root / kwargs.pop("out", "bad.mp4")
    with pytest.raises(SoftcellError, match=message):
        animate(open_dataset(one), out, progress=False, **kwargs)
    assert not out.exists()


def test_the_command_line_writes_a_movie_and_names_it(runs, capsys):
    root, one, _ = runs
    out = root / "cli.mp4"
    assert main(["animate", str(one), "-o", str(out), "--realizations", "1", "--quiet"]) == 0
    assert f"{out}: 31 frames at 30/s" in capsys.readouterr().out
    assert main(["animate", str(one), "-o", str(out), "--quiet"]) == 2  # exists
    assert "--overwrite" in capsys.readouterr().err
    assert np.isfinite(_decoded(out)[1][0]).all()


def test_a_sweep_of_assemblies_opens_as_one_dataset_and_animates_one_point(tmp_path):
    """The box and the starts are per realization, so a sweep's files concatenate along it
    (no variable without a realization dim for xarray to guess about)."""
    config = RunConfig(
        parameters={"radius": [5.0, 5.5], "duration": 0.3}, assembly={"cells": 2, "box": 30.0}
    )
    simulate(config, tmp_path / "sweep", realizations=2, progress=False)
    ds = open_dataset(tmp_path / "sweep")
    assert ds["domain_box"].dims == ("radius", "realization")
    assert ds["cell_start_x"].dims == ("radius", "realization", "cell")
    movie = animate(ds.isel(radius=1), tmp_path / "one.mp4", progress=False)
    assert movie.size[0] == 480 and _decoded(movie.path)[0] == "h264"
