"""The bodies' fine record: what the engine writes, how a resumed run treats files without it,
and the MSD it gives, against a direct sum over pairs and a random walk's exact MSD."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from softcell.analysis.sweep import analyze
from softcell.errors import AnalysisWarning
from softcell.model.parameters import Parameters
from softcell.schema import FINE_VARIABLES, problems, simulation_dataset
from softcell.testing.synthetic import two_rate_times

DT, SWITCH, END = 0.01, 100.0, 300.0
D_EARLY, D_LATE = 1.0, 3.0  # cm^2/s: the walk diffuses faster after the sampling switch


def _walk(realizations: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Fine times (s) and positions [realization, time, 2] (cm) of a 2-d random walk with
    diffusion coefficient D_EARLY before SWITCH and D_LATE after it."""
    t = DT * np.arange(int(round(END / DT)) + 1)
    d = np.where(t[:-1] < SWITCH - 1e-9, D_EARLY, D_LATE)
    rng = np.random.default_rng(seed)
    steps = rng.normal(size=(realizations, t.size - 1, 2)) * np.sqrt(2 * d * DT)[None, :, None]
    r = np.concatenate([np.zeros((realizations, 1, 2)), np.cumsum(steps, axis=1)], axis=1)
    return t, r


def _dataset(t: np.ndarray, r: np.ndarray, fine: bool) -> xr.Dataset:
    """A simulation Dataset sampled at two rates (every DT to SWITCH, then every 10 DT), the
    cell and the bot on the walk, a small circle of membrane around it; with the bodies' fine
    record if ``fine``."""
    times = two_rate_times(DT, 10 * DT, SWITCH, END)
    at = np.rint(times / DT).astype(int)
    x, y = r[:, at, 0], r[:, at, 1]
    angle = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    n_real = r.shape[0]
    record = None
    if fine:
        record = {"fine_time": t}
        for body in ("cell", "bot"):
            record[f"{body}_x_fine"], record[f"{body}_y_fine"] = r[..., 0], r[..., 1]
        record["bot_angle_fine"] = np.zeros(r.shape[:2])
        record["bot_phase_fine"] = np.ones(r.shape[:2], dtype=np.int8)
    return simulation_dataset(
        times,
        np.arange(n_real),
        membrane_x=x[..., None] + np.cos(angle),
        membrane_y=y[..., None] + np.sin(angle),
        bot_x=x,
        bot_y=y,
        bot_angle=np.zeros_like(x),
        bot_phase=np.ones(x.shape, dtype=np.int8),
        cell_x=x,
        cell_y=y,
        parameters=Parameters({"radius": 5.0, "duration": END}),
        seed=0,
        components={},
        fine=record,
    )


def _expected_msd(lag: np.ndarray) -> np.ndarray:
    """The walk's exact MSD (cm^2) pooled over every pair of fine samples: 4 times the
    diffusion coefficient integrated over each pair's interval, averaged over the pairs."""
    n = int(round(END / DT))
    d = np.where(DT * np.arange(n) < SWITCH - 1e-9, D_EARLY, D_LATE)
    cumulative = np.concatenate([[0.0], np.cumsum(d * DT)])
    out = []
    for m in np.rint(lag / DT).astype(int):
        out.append(4 * np.mean(cumulative[m:] - cumulative[:-m]))
    return np.array(out)


@pytest.fixture(scope="module")
def walk():
    return _walk(16, seed=4)


def test_the_msd_from_the_fine_record_has_no_step_where_the_sampling_changes(walk):
    t, r = walk
    out = analyze(_dataset(t, r, fine=True), {"discard": 0.0})
    msd = out["msd"].sel(body="cell")
    lag = out["lag"].values
    assert "fine record" in out["lag"].attrs["msd_record"]
    # Against the exact MSD of the walk, at every lag to 10 s, within 4 standard errors.
    short = (lag > 0) & (lag <= 10.0)
    expected = _expected_msd(lag[short])
    sem = out["msd_sem"].sel(body="cell").values[short]
    assert np.all(np.abs(msd.values[short] - expected) < 4 * sem)
    # Either side of the old seam (short_lag_max = 1 s) the curve is smooth: neighbouring
    # lags share their pairs, so the ratio is the lags' within 1 %.
    below, above = lag[lag < 1.0].max(), lag[lag >= 1.0].min()
    ratio = float(msd.sel(lag=above) / msd.sel(lag=below))
    assert ratio == pytest.approx(above / below, rel=0.01)


def test_the_sampled_record_steps_at_the_seam_and_says_so(walk):
    """The estimator the fine record replaces, on the same walk: lags below 1 s see only the
    first 100 s (D = 1), longer lags the whole record (mean D = 7/3)."""
    t, r = walk
    with pytest.warns(AnalysisWarning, match="makes a step where the two meet"):
        out = analyze(_dataset(t, r, fine=False), {"discard": 0.0})
    msd, lag = out["msd"].sel(body="cell"), out["lag"].values
    below, above = lag[lag < 1.0].max(), lag[lag >= 1.0].min()
    ratio = float(msd.sel(lag=above) / msd.sel(lag=below)) / (above / below)
    assert ratio == pytest.approx((D_EARLY + 2 * D_LATE) / 3 / D_EARLY, rel=0.05)
    forced = analyze(_dataset(t, r, fine=True), {"discard": 0.0, "msd_record": "sampled"})
    np.testing.assert_array_equal(forced["msd"].values, out["msd"].values)


def test_the_fine_msd_is_the_direct_sum_over_pairs(walk):
    t, r = walk
    out = analyze(_dataset(t, r, fine=True), {"discard": 5.0})
    keep = t >= 5.0
    lag = out["lag"].values
    for k in (0, lag.size // 3, 2 * lag.size // 3):
        m = int(round(lag[k] / DT))
        rr = r[:, keep]
        direct = np.sum((rr[:, m:] - rr[:, :-m]) ** 2) / (rr.shape[0] * (rr.shape[1] - m))
        assert float(out["msd"].sel(body="bot").isel(lag=k)) == pytest.approx(direct, rel=1e-9)


def test_the_fine_record_is_all_or_nothing_in_the_schema(walk):
    t, r = walk
    ds = _dataset(t, r[:2], fine=True)
    assert problems(ds) == []
    assert set(FINE_VARIABLES) <= set(ds.data_vars)
    assert ds["bot_x_fine"].attrs["units"] == "cm" and ds["fine_time"].attrs["units"] == "s"
    broken = ds.drop_vars("bot_angle_fine")
    assert problems(broken) == ["bot_angle_fine: missing"]


# A coarse membrane (cutoff 4) is stable at dt = 1e-5 s, which keeps these runs fast.
SHORT_RUN = {
    "radius": 4.0,
    "duration": 0.05,
    "sample_every": 0.005,
    "sample_every_late": 0.01,
    "sample_switch": 0.02,
    "cutoff": 4,
    "nodes": 64,
    "stored_nodes": 16,
    "dt": 1e-5,
}


def _simulate(out, **kwargs):
    from softcell import RunConfig
    from softcell.runner.ensemble import simulate

    config = RunConfig(parameters=SHORT_RUN).updated(components={"integrator": "explicit_euler"})
    return simulate(config, out, realizations=1, seed=2, progress=False, **kwargs)


def test_the_engine_records_the_bodies_at_every_sample_every_over_the_whole_run(tmp_path):
    import softcell

    (path,) = _simulate(tmp_path / "sim")
    ds = softcell.open_dataset(path).load()
    np.testing.assert_allclose(ds["fine_time"].values, 0.005 * np.arange(11), atol=1e-15)
    np.testing.assert_allclose(ds["time"].values, [0, 0.005, 0.01, 0.015, 0.02, 0.03, 0.04, 0.05])
    shared = np.searchsorted(ds["fine_time"].values, ds["time"].values - 1e-12)
    for name in ("cell_x", "cell_y", "bot_x", "bot_y", "bot_angle", "bot_phase"):
        np.testing.assert_array_equal(
            ds[f"{name}_fine"].values[:, shared], ds[name].values, err_msg=name
        )
    # Between the membrane's late samples the bot moves: the fine record is no copy.
    between = ds["bot_x_fine"].values[0, 5::2]
    assert np.all(np.diff(between) != 0)


def test_a_file_without_the_fine_record_is_recomputed_not_reused(tmp_path):
    import softcell
    from softcell.errors import SoftcellError
    from softcell.io.netcdf import write_dataset

    (path,) = _simulate(tmp_path / "sim")
    original = path.read_bytes()
    ds = softcell.open_dataset(path).load()
    old = ds.drop_vars(["fine_time", *FINE_VARIABLES])
    path.unlink()
    write_dataset(old, path)
    with pytest.raises(SoftcellError, match="did not record the bodies' fine record"):
        _simulate(tmp_path / "sim")
    _simulate(tmp_path / "sim", overwrite=True)
    assert path.read_bytes() == original


def test_a_sweep_over_durations_combines_both_time_axes_with_padding(tmp_path):
    """Points of different durations have time axes of different lengths; combined, each
    variable keeps its own axis (xarray's combine would otherwise concatenate along one of
    them and broadcast every variable over the other)."""
    import softcell
    from softcell import RunConfig
    from softcell.runner.ensemble import simulate

    params = {**SHORT_RUN, "duration": [0.03, 0.05]}
    config = RunConfig(parameters=params).updated(components={"integrator": "explicit_euler"})
    paths = simulate(config, tmp_path / "sim", realizations=1, seed=2, progress=False)
    ds = softcell.open_dataset(tmp_path / "sim").load()
    assert ds["cell_x_fine"].dims == ("duration", "realization", "fine_time")
    assert ds["membrane_x"].dims == ("duration", "realization", "time", "node")
    assert ds.sizes["fine_time"] == 11 and ds.sizes["time"] == 8
    short = softcell.open_dataset(paths[0]).load()
    n = short.sizes["fine_time"]
    np.testing.assert_array_equal(
        ds["bot_x_fine"].isel(duration=0).values[:, :n], short["bot_x_fine"].values
    )
    assert np.isnan(ds["bot_x_fine"].isel(duration=0).values[:, n:]).all()
    assert (ds["bot_phase_fine"].isel(duration=0).values[:, n:] == -1).all()
