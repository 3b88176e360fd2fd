"""Analysis (docs/model.md §6): MSD, stop/go, fits, theory, shape index, collapse."""

import numpy as np
import pytest
import tidynamics
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy.special import ellipe

import softcell
from softcell.analysis import analyze, fits, stopgo
from softcell.analysis.msd import msd, msd_sums
from softcell.analysis.series import polygon_area_perimeter_centroid, shape_index
from softcell.analysis.sweep import COLLAPSE_VARIANTS, _collapse
from softcell.builtins.threshold import Threshold
from softcell.errors import SoftcellError
from softcell.testing.synthetic import stop_and_go_dataset, two_rate_times

#: These planted datasets have no fine record: their MSD comes from the two-rate samples
#: (short lags from the first segment), the estimator these tests were written for.
SAMPLED = "sampled"


def naive_msd(r):
    """The definition, pair by pair, skipping pairs with a missing sample."""
    size = len(r)
    out = np.full(size, np.nan)
    for m in range(size):
        d = r[m:] - r[: size - m]
        ok = np.all(np.isfinite(d), axis=1)
        if ok.any():
            out[m] = np.mean(np.sum(d[ok] ** 2, axis=1))
    return out


@settings(max_examples=60, deadline=None)
@given(
    hnp.arrays(
        np.float64,
        st.tuples(st.integers(1, 120), st.integers(1, 3)),
        elements=st.floats(-50, 50, allow_nan=False),
    ),
    st.sampled_from([0.0, 1e4, -3e4]),
    st.lists(st.integers(0, 119), max_size=10),
)
def test_fft_msd_equals_the_double_loop(r, offset, holes):
    r = r + offset
    r[[h for h in holes if h < len(r)]] = np.nan
    expected = naive_msd(r)
    got = msd(r)
    assert np.array_equal(np.isnan(got), np.isnan(expected))
    ok = np.isfinite(expected)
    # Rounding scale: the spread of the positions about their mean, not the offset.
    finite = r[np.all(np.isfinite(r), axis=1)]
    scale = np.sum((finite - finite.mean(axis=0)) ** 2, axis=1).max() if finite.size else 0.0
    np.testing.assert_allclose(got[ok], expected[ok], rtol=1e-9, atol=1e-11 * (scale + 1))


def test_fft_msd_agrees_with_tidynamics():
    rng = np.random.default_rng(3)
    r = np.cumsum(rng.normal(size=(20000, 2)), axis=0) + 1e4
    ours = msd(r)
    theirs = tidynamics.msd(r - r.mean(axis=0))
    np.testing.assert_allclose(ours[1:], theirs[1:], rtol=1e-9)
    sums, pairs = msd_sums(r)
    assert pairs[0] == 20000 and pairs[-1] == 1


def test_threshold_detector_recovers_planted_durations_exactly():
    dt = 0.01
    detector = Threshold(softcell.Parameters({"threshold": 0.03}, Threshold.parameters))

    @settings(max_examples=80, deadline=None)
    @given(st.lists(st.integers(1, 40), min_size=1, max_size=12), st.booleans())
    def check(lengths, first_go):
        values = []
        go = first_go
        for n in lengths:
            values += [1.0 if go else 0.0] * n
            go = not go
        speed = np.array(values + [np.nan])  # the last sample has no forward difference
        time = dt * np.arange(speed.size)
        d = stopgo.durations(stopgo.label(detector, speed, time), time)
        inner = lengths[1:-1]  # the first and last phases are censored
        kinds = [(first_go if k % 2 == 0 else not first_go) for k in range(len(lengths))][1:-1]
        expected_go = [(n - 1) * dt for n, g in zip(inner, kinds, strict=True) if g]
        expected_stop = [(n - 1) * dt for n, g in zip(inner, kinds, strict=True) if not g]
        np.testing.assert_allclose(d.go, expected_go, atol=1e-12)
        np.testing.assert_allclose(d.stop, expected_stop, atol=1e-12)

    check()


def test_detection_runs_separately_on_each_sampling_segment():
    detector = Threshold(softcell.Parameters({}, Threshold.parameters))
    time = two_rate_times(0.01, 0.1, 0.5, 1.5)  # 51 fine samples, then 10 coarse
    speed = np.zeros(time.size)
    speed[10:20] = 1.0  # a complete go inside the fine segment: 10 samples, 0.09 s
    speed[45:55] = 1.0  # a go across the change of rate: censored on both sides
    speed[-1] = np.nan
    d = stopgo.durations(stopgo.label(detector, speed, time), time)
    assert d.go == pytest.approx([0.09])
    assert d.stop == pytest.approx([(45 - 20 - 1) * 0.01])


def test_scaled_pdfs_integrate_to_one():
    rng = np.random.default_rng(0)
    values = rng.exponential(2.0, 500)
    edges = stopgo.pdf_edges((values / values.mean()).max())
    pdf = stopgo.scaled_pdf(values, edges)
    assert np.diff(edges) == pytest.approx(np.full(edges.size - 1, 0.25))
    assert np.sum(pdf * 0.25) == pytest.approx(1.0, abs=1e-12)
    stat, p = stopgo.exponential_fit_statistic(values)
    assert stat < 0.1 and p > 0.01


def test_run_and_tumble_theory_limits():
    v0, tg = 1.7, 0.8
    short = np.array([1e-6, 1e-5])
    assert fits.run_and_tumble_msd(short, v0, tg) == pytest.approx(v0**2 * short**2, rel=1e-4)
    long = np.array([1e4, 1e5])
    slope = np.diff(fits.run_and_tumble_msd(long, v0, tg)) / np.diff(long)
    assert slope == pytest.approx(2 * v0**2 * tg, rel=1e-9)


def test_stop_and_go_msd_matches_the_si_formula_within_its_standard_error():
    rng = np.random.default_rng(11)
    v, tg, ts = 2.0, 1.0, 2.0
    times = two_rate_times(0.01, 0.1, 100.0, 300.0)
    ds = stop_and_go_dataset(rng, times, realizations=40, speed=v, mean_go=tg, mean_stop=ts)
    out = analyze(ds, {"max_lag_fraction": 0.2, "msd_record": SAMPLED}).sel(body="cell")
    theory = fits.run_and_tumble_msd(out.lag.values, np.sqrt(tg / (tg + ts)) * v, tg)
    z = (out.msd.values - theory) / out.msd_sem.values
    assert np.all(np.abs(z) < 3.5), np.round(z, 1)


def test_stop_and_go_fits_and_theory_recover_the_planted_process():
    """200 realizations sampled like the paper (0.01 s to 100 s, then 0.1 s, to 2000 s).

    Stop/go statistics come from the finest segment only: at 0.1 s a detector misses the
    short phases of this process (mean 1 s), which would bias <tau_g> upwards. The diffusive
    fit (lags >= 10 <tau_g>, exponent fixed to 1) carries a known bias: applied to the exact
    curve, whose long-time form is D hat (tau - <tau_g>), it returns 0.974 D hat here.
    """
    rng = np.random.default_rng(5)
    v, tg, ts = 2.0, 1.0, 2.0
    times = two_rate_times(0.01, 0.1, 100.0, 2000.0)
    ds = stop_and_go_dataset(
        rng, times, realizations=200, speed=v, mean_go=tg, mean_stop=ts, nodes=4, offset=(1e4, -1e4)
    )
    out = analyze(
        ds, {"max_lag_fraction": 0.25, "stopgo_segments": "finest", "msd_record": SAMPLED}
    ).sel(body="cell")
    v0_planted = np.sqrt(tg / (tg + ts)) * v
    slope_planted = 2 * v0_planted**2 * tg
    assert float(out.mean_go_duration) == pytest.approx(tg, rel=0.05)
    assert float(out.mean_stop_duration) == pytest.approx(ts, rel=0.05)
    assert float(out.ballistic_velocity) == pytest.approx(v0_planted, rel=0.05)
    assert float(out.v0_hat) == pytest.approx(v0_planted, rel=0.05)
    assert float(out.msd_slope) == pytest.approx(slope_planted, rel=0.05)
    assert float(out.msd_slope_theory) == pytest.approx(slope_planted, rel=0.05)
    assert float(out.diffusion_coefficient) == pytest.approx(float(out.msd_slope) / 4)
    assert float(out.crossover_time) == pytest.approx(2 * tg, rel=0.1)


def test_turns_between_go_phases_are_measured_and_carry_the_msd_slope():
    """Go phases turning by +-60 degrees (mean cosine c = 1/2 between consecutive ones, c^k
    between phases k apart) double D hat: the displacements sum to
    (<l^2> + 2 <l>^2 c / (1 - c)) / (<tau_g> + <tau_s>) = 2 v^2 <tau_g>^2 / ((1 - c) cycle)
    for exponential go phases. The renewal theory (no turn memory) misses the factor; the
    velocity autocorrelation's Green-Kubo sum recovers it. Uniform turns give c = 0 and an
    autocorrelation that the renewal theory accounts for."""
    v, tg, ts = 2.0, 1.0, 2.0
    times = two_rate_times(0.01, 0.1, 100.0, 1000.0)
    planted = 2 * v**2 * tg**2 / ((1 - 0.5) * (tg + ts))
    options = {"max_lag_fraction": 0.25, "correlation_max_lag": 40.0, "msd_record": SAMPLED}

    def cell(seed: int, turn: float | None):
        ds = stop_and_go_dataset(
            np.random.default_rng(seed),
            times,
            realizations=60,
            speed=v,
            mean_go=tg,
            mean_stop=ts,
            nodes=4,
            turn=turn,
        )
        return analyze(ds, options).sel(body="cell")

    kept = cell(8, np.pi / 3)
    assert float(kept.go_turn_cosine) == pytest.approx(0.5, abs=0.03)
    assert float(kept.green_kubo_slope) == pytest.approx(planted, rel=0.1)
    renewal = fits.renewal_msd_slope(float(kept.v0_hat), tg, 2 * tg**2)
    assert renewal == pytest.approx(planted / 2, rel=0.1)
    fresh = cell(9, None)
    assert abs(float(fresh.go_turn_cosine)) < 0.03
    c = fresh.velocity_autocorrelation.values
    theory = fresh.velocity_autocorrelation_renewal.values
    np.testing.assert_allclose(c, theory, atol=0.05 * c[0])
    assert float(fresh.green_kubo_slope) == pytest.approx(
        2 * float(fresh.v0_hat) ** 2 * tg, rel=0.1
    )


def test_confined_square_formula_limits():
    side, d = 10.0, 1.3
    assert fits.confined_square_msd(np.array([1e6]), d, side)[0] == pytest.approx(side**2 / 3)
    tiny = np.array([1e-9, 2e-9])
    odd = 2 * np.arange(51) + 1
    truncated = 4 * d * 8 / np.pi**2 * np.sum(1.0 / odd**2)  # the slope of 51 terms at 0
    slope = np.diff(fits.confined_square_msd(tiny, d, side)) / np.diff(tiny)
    assert slope[0] == pytest.approx(truncated, rel=1e-5)
    slope = np.diff(fits.confined_square_msd(tiny, d, side, terms=200_000)) / np.diff(tiny)
    assert slope[0] == pytest.approx(4 * d, rel=1e-5)  # the full series: 4 D


def test_confined_square_fit_recovers_d_from_a_reflected_walk():
    rng = np.random.default_rng(2)
    side, d, dt = 10.0, 2.0, 0.01
    steps = rng.normal(scale=np.sqrt(2 * d * dt), size=(20, 100_000, 2))
    walks = np.cumsum(steps, axis=1) + rng.uniform(0, side, size=(20, 1, 2))
    folded = np.abs(np.mod(walks, 2 * side))  # reflection at 0 and side, by unfolding
    folded = np.where(folded > side, 2 * side - folded, folded)
    lags = np.unique(np.rint(np.geomspace(1, 20_000, 60)).astype(int))
    curve = np.mean([msd(w)[lags] for w in folded], axis=0)
    fitted, used = fits.confined_square_fit(lags * dt, curve, side)
    assert used == lags.size
    assert fitted == pytest.approx(d, rel=0.05)


def test_shape_index_of_known_shapes():
    for n in (16, 64, 1024):
        a = 2 * np.pi * np.arange(n) / n
        expected = 2 * n * np.sin(np.pi / n) / np.sqrt(0.5 * n * np.sin(2 * np.pi / n))
        assert shape_index(3 * np.cos(a) + 7, 3 * np.sin(a) - 2) == pytest.approx(expected)
    assert expected == pytest.approx(2 * np.sqrt(np.pi), rel=1e-5)
    square = shape_index(np.array([0.0, 2, 2, 0]), np.array([0.0, 0, 2, 2]))
    assert square == pytest.approx(4.0)
    triangle = shape_index(np.array([0.0, 1, 0.5]), np.array([0.0, 0, np.sqrt(3) / 2]))
    assert triangle == pytest.approx(6 / 3**0.25)
    a, b, n = 5.0, 3.0, 20000
    t = 2 * np.pi * np.arange(n) / n
    ellipse = shape_index(a * np.cos(t), b * np.sin(t))
    assert ellipse == pytest.approx(
        4 * a * ellipe(1 - b**2 / a**2) / np.sqrt(np.pi * a * b), rel=1e-7
    )
    # A band-limited curve from few nodes: the smooth curve's IPR, not its polygon's.
    for n in (16, 64):
        t = 2 * np.pi * np.arange(n) / n
        smooth = shape_index(8.3 * np.cos(t) + 3, 7.6 * np.sin(t) - 1, band_limited=True)
        exact = 4 * 8.3 * ellipe(1 - 7.6**2 / 8.3**2) / np.sqrt(np.pi * 8.3 * 7.6)
        assert smooth == pytest.approx(exact, abs=1e-12)
        assert shape_index(8.3 * np.cos(t), 7.6 * np.sin(t)) - exact > 1e-3  # the polygon's
    _, _, cx, cy = polygon_area_perimeter_centroid(
        np.array([0.0, 4, 4, 0, 0]) + 1e4, np.array([0.0, 0, 2, 2, 1])
    )
    assert (cx, cy) == (pytest.approx(1e4 + 2), pytest.approx(1.0))


def test_collapse_metric_finds_the_planted_scaling():
    lag = np.geomspace(0.01, 10, 80)
    radii = np.array([8.0, 10.0, 12.0])
    # MSD = R^(-1/3) F(lag R): collapses exactly as MSD R^(1/3) against lag R.
    curves = np.array([r ** (-1 / 3) * ((lag * r) ** 2 / (1 + lag * r)) for r in radii])
    metric = _collapse(lag, curves, radii, np.full(3, 10.0))
    best = int(np.nanargmin(metric))
    assert COLLAPSE_VARIANTS[best] == (1 / 3, 1.0)
    assert metric[best] < 1e-3 < np.nanmin(np.delete(metric, best))


def test_missing_variable_is_named():
    rng = np.random.default_rng(0)
    ds = stop_and_go_dataset(
        rng, 0.01 * np.arange(100), realizations=1, speed=1.0, mean_go=0.1, mean_stop=0.1
    )
    with pytest.raises(SoftcellError, match="bot_y, membrane_x"):
        analyze(ds.drop_vars(["bot_y", "membrane_x"]))


def test_bad_option_is_named():
    rng = np.random.default_rng(0)
    ds = stop_and_go_dataset(
        rng, 0.01 * np.arange(100), realizations=1, speed=1.0, mean_go=0.1, mean_stop=0.1
    )
    with pytest.raises(softcell.ParameterError, match="discard = -1"):
        analyze(ds, {"discard": -1})
    with pytest.raises(softcell.ConfigError, match="did you mean 'discard'"):
        analyze(ds, {"discrad": 1})


def test_accessor_matches_the_pipeline():
    rng = np.random.default_rng(4)
    ds = stop_and_go_dataset(
        rng, 0.01 * np.arange(3000), realizations=3, speed=1.0, mean_go=0.5, mean_stop=0.5
    )
    direct = analyze(ds, {"discard": 1.0})
    np.testing.assert_array_equal(
        ds.softcell.msd("cell", discard=1.0).values, direct.msd.sel(body="cell").values
    )
    speed = ds.softcell.speed("bot")
    assert speed.attrs["units"] == "cm s-1" and speed.shape == ds.bot_x.shape
    cx, cy = ds.softcell.geometric_center("centroid")
    np.testing.assert_allclose(cx.values, ds.cell_x.values, atol=1e-9)
