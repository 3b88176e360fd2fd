"""The statistical round trip: 100 s of a decoupled cell, rendered and tracked.

Both the truth (resampled at the frame times) and the tracked record are analysed identically:
decimated to 0.1 s (velocities differenced over 0.1 s) with the experiments' 0.3 cm/s
threshold.
"""

import numpy as np
import pytest

import softcell
from softcell.model.configuration import RunConfig
from softcell.runner.ensemble import simulate
from softcell.video.render import render
from softcell.video.track import track

pytestmark = pytest.mark.slow
COARSE = {"cutoff": 4, "nodes": 64, "stored_nodes": 16, "dt": 1e-5}


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    config = RunConfig(parameters={"radius": 12.0, "duration": 100.0, **COARSE})
    out = tmp_path_factory.mktemp("sim")
    return softcell.read_dataset(simulate(config, out, realizations=1, seed=4, progress=False)[0])


@pytest.mark.parametrize("noise, blur", [(0.0, 0.0), (3.0, 1.0)])
def test_round_trip_statistics(sim, tmp_path, noise, blur):
    info = render(
        sim,
        tmp_path / "cell.mkv",
        px_per_cm=10,
        fps=30,
        noise=noise,
        blur=blur,
        illumination=0.2 if noise else 0.0,
        seed=1,
    )
    tracked = track(
        tmp_path / "cell.mkv", px_per_cm=10, origin=(info.frame.x0, info.frame.y0), radius=12.0
    )
    truth = sim.interp(time=info.times).assign_coords(time=tracked.time.values)
    # The truth as a film sees it: no fine record (the analysis would take its phases and
    # MSD from that instead of the frames).
    truth = truth.drop_dims("fine_time")
    truth.attrs.update(softcell_origin="tracking")
    options = {"discard": 0.0, "threshold": 0.3}
    a = softcell.analyze(truth.isel(time=slice(None, None, 3)), options)
    b = softcell.analyze(tracked.isel(time=slice(None, None, 3)), options)
    long = a.lag >= 0.5
    for body in ("cell", "bot"):
        ratio = (b.msd.sel(body=body) / a.msd.sel(body=body)).where(long, drop=True)
        assert np.all(np.abs(ratio - 1) <= 0.02), (body, ratio.values)
    cell_a, cell_b = a.sel(body="cell"), b.sel(body="cell")
    assert int(cell_a.go_events) >= 10 and int(cell_a.stop_events) >= 10
    for name in ("mean_go_duration", "mean_stop_duration"):
        assert float(cell_b[name]) == pytest.approx(float(cell_a[name]), rel=0.10), name
