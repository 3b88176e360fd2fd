"""Errors across realizations (softcell.analysis.uncertainty): the 68 % interval of an
analysis covers a planted truth at the binomial rate, the error has the size of the spread
of single-realization values, one realization has none, blocks resample together, and the
stop/go phases of one simulated cell do not depend on its sampling design."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import stats

import softcell
from softcell.analysis import fits, uncertainty
from softcell.analysis.bootstrap import sweep_estimates
from softcell.analysis.sweep import analyze
from softcell.errors import AnalysisWarning
from softcell.testing.synthetic import stop_and_go_dataset

SPEED, MEAN_GO, MEAN_STOP = 2.0, 0.2, 0.2  # cm/s, s, s
#: D hat of the planted process: 2 v0_hat^2 <tau_g>, v0_hat^2 = p v^2 (SI:EQ:msd).
TRUE_SLOPE = 2 * SPEED**2 * MEAN_GO / (MEAN_GO + MEAN_STOP) * MEAN_GO
OPTIONS = {"discard": 0.0, "max_lag_fraction": 0.25, "lags_per_decade": 10, "threshold": 0.5}


def _ensemble(seed: int, realizations: int, duration: float = 200.0, dt: float = 0.05):
    rng = np.random.default_rng(seed)
    times = dt * np.arange(int(round(duration / dt)) + 1)
    return stop_and_go_dataset(
        rng,
        times,
        realizations=realizations,
        speed=SPEED,
        mean_go=MEAN_GO,
        mean_stop=MEAN_STOP,
    )


def _coverage(ensembles: int, realizations: int) -> dict[str, float]:
    """Fraction of ensembles whose value +- error covers TRUE_SLOPE: the analysis' errors
    (Green-Kubo and affine D hat) and the old error of the log-space slope fit (the scatter
    of the pooled curve about the fit)."""
    hits = {"green_kubo_slope": 0, "msd_slope_affine": 0, "old msd_slope": 0}
    for k in range(ensembles):
        cell = analyze(_ensemble(1000 + k, realizations), {**OPTIONS, "resamples": 300}).sel(
            body="cell"
        )
        for name in ("green_kubo_slope", "msd_slope_affine"):
            value, error = float(cell[name]), float(cell[f"{name}_error"])
            hits[name] += abs(value - TRUE_SLOPE) <= error
        lag, msd = cell["lag"].values, cell["msd"].values
        slope, old_error, _ = fits.msd_slope(lag, msd, float(cell["diffusive_window_start"]))
        hits["old msd_slope"] += abs(slope - TRUE_SLOPE) <= old_error
    return {name: count / ensembles for name, count in hits.items()}


def _binomial_band(ensembles: int, level: float = 0.6827) -> tuple[float, float]:
    """Where the covered fraction of ``ensembles`` falls with 99.7 % probability if the
    intervals cover at the rate ``level``."""
    lo, hi = stats.binom.ppf([0.0015, 0.9985], ensembles, level)
    return lo / ensembles, hi / ensembles


@pytest.mark.slow
def test_the_68_percent_interval_covers_the_planted_slope_at_the_binomial_rate():
    # 8 realizations: a t statistic of 7 degrees of freedom covers 65 % within +-1 error,
    # inside the band; the old error (scatter of one pooled curve) is several times too
    # small and falls far below it.
    ensembles = 120
    covered = _coverage(ensembles, realizations=8)
    lo, hi = _binomial_band(ensembles)
    assert lo <= covered["green_kubo_slope"] <= hi, covered
    assert lo <= covered["msd_slope_affine"] <= hi, covered
    assert covered["old msd_slope"] < lo, covered


def test_the_interval_covers_the_planted_slope_on_a_few_ensembles():
    # The quick version of the test above: 30 ensembles of 8 realizations.
    ensembles = 30
    covered = _coverage(ensembles, realizations=8)
    lo, hi = _binomial_band(ensembles)
    assert lo <= covered["green_kubo_slope"] <= hi, covered
    assert covered["old msd_slope"] < lo, covered


def test_the_error_of_d_hat_is_the_spread_of_single_realization_values():
    # The check: 4 realizations analysed together against each alone.
    for seed in (1, 2, 3):
        ds = _ensemble(seed, 4, duration=150.0)
        together = analyze(ds, OPTIONS).sel(body="cell")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", AnalysisWarning)  # one realization: no error
            alone = [
                float(analyze(ds.isel(realization=[r]), OPTIONS).sel(body="cell")["msd_slope"])
                for r in range(4)
            ]
        spread = np.std(alone, ddof=1) / 2
        error = float(together["msd_slope_error"])
        assert spread / 1.5 <= error <= 1.5 * spread, (seed, error, spread, alone)
        # The per-realization values the analysis keeps are those single analyses.
        assert together["msd_slope_realization"].values == pytest.approx(alone, rel=1e-9)


def test_the_error_attribute_says_what_it_is():
    cell = analyze(_ensemble(4, 3, duration=60.0), OPTIONS)
    text = cell["msd_slope_error"].attrs["uncertainty"]
    assert "across 3 realizations" in text and "bootstrap of 1000" in text
    assert cell["msd_slope_error"].attrs["units"] == "cm2 s-1"
    for name in uncertainty.BODY_QUANTITIES:
        assert f"{name}_error" in cell and f"{name}_realization" in cell, name
        assert cell[f"{name}_realization"].sizes["realization"] == 3


def test_one_realization_has_no_error_and_says_so():
    with pytest.warns(AnalysisWarning, match="no error across realizations"):
        one = analyze(_ensemble(5, 1, duration=60.0), OPTIONS)
    assert np.isnan(one["msd_slope_error"].values).all()
    assert np.isnan(one["mean_go_duration_error"].values).all()
    assert np.isfinite(one["msd_slope"].sel(body="cell").values)
    assert "not measurable" in one["msd_slope_error"].attrs["uncertainty"]


def test_a_mean_s_error_is_the_usual_standard_error():
    # For a plain mean the bootstrap with the sqrt(n / (n - 1)) factor gives s / sqrt(n).
    rng = np.random.default_rng(3)
    values = rng.normal(size=6)
    w = uncertainty.weights(6, 20000, rng)
    error = uncertainty.standard_error(uncertainty.mean_of(w, values), 6)
    assert error == pytest.approx(np.std(values, ddof=1) / np.sqrt(6), rel=0.02)


def test_blocks_are_drawn_whole():
    rng = np.random.default_rng(0)
    blocks = np.repeat(np.arange(3), 4)  # 3 realizations of 4 cells
    w = uncertainty.weights(12, 500, rng, blocks)
    assert np.all(w.reshape(500, 3, 4) == w.reshape(500, 3, 4)[..., :1])
    assert np.all(w.sum(axis=1) == 12)
    assert uncertainty.independent_count(12, blocks) == 3


def test_the_vectorised_fits_are_the_scalar_fits():
    rng = np.random.default_rng(2)
    lag = np.logspace(-2, 2, 70)
    curves = np.array(
        [
            fits.run_and_tumble_msd(lag, rng.uniform(1, 4), rng.uniform(0.2, 1.0))
            * np.exp(rng.normal(0, 0.05, lag.size))
            for _ in range(12)
        ]
    )
    lo = rng.uniform(2.0, 8.0, 12)
    confined = uncertainty.confined_fits(lag, curves, lo, 100.0)
    slope = uncertainty.power_fits(lag, curves, 1.0, lo, np.full(12, np.inf))
    affine = uncertainty.affine_fits(lag, curves, lo)
    for k in range(12):
        assert confined[k] == pytest.approx(
            fits.confined_square_fit(lag, curves[k], 100.0, lo[k])[0], rel=1e-6
        )
        assert slope[k] == pytest.approx(fits.msd_slope(lag, curves[k], lo[k])[0], rel=1e-12)
        assert affine[k] == pytest.approx(fits.affine_slope(lag, curves[k], lo[k]), rel=1e-9)


def test_the_findings_resample_what_the_analysis_resampled():
    ds = _ensemble(6, 5, duration=80.0).expand_dims(radius=[12.0])
    ds = ds.transpose("radius", "realization", ...)
    analysis = analyze(ds, OPTIONS)
    est = sweep_estimates(analysis)
    for name in ("mean_go_duration", "v0_hat", "msd_slope", "green_kubo_slope"):
        stored = analysis[f"{name}_error"].sel(body="cell").values
        assert est[name].error == pytest.approx(stored, rel=1e-9), name


@pytest.mark.slow
def test_one_cell_gives_one_set_of_durations_whatever_its_sampling_design(tmp_path):
    # The same seed sampled two ways (the sampling switch at 100 s or beyond the end): the
    # stop/go phases come from the fine record, the same in both files, so <tau_g> and
    # <tau_s> are the same numbers; detected on the sampled record, <tau_s> moves by many
    # standard errors (measured: 0.358 against 0.412 s, error 0.0025 s).
    cells = {}
    for switch in (100.0, 1000.0):
        config = softcell.RunConfig(
            parameters={"radius": 5.0, "duration": 160.0, "sample_switch": switch}
        )
        out = tmp_path / f"switch{switch:g}"
        softcell.simulate(config, out, realizations=3, seed=7, progress=False)
        ds = softcell.open_dataset(out)
        cells[switch] = [
            analyze(ds, {"stopgo_record": record}).sel(body="cell")
            for record in ("fine", "sampled")
        ]
    (fine_a, sampled_a), (fine_b, sampled_b) = cells[100.0], cells[1000.0]
    for name in ("mean_go_duration", "mean_stop_duration"):
        error = float(fine_a[f"{name}_error"])
        assert abs(float(fine_a[name]) - float(fine_b[name])) <= error, name
        assert float(fine_a[name]) == float(fine_b[name]), name
    gap = abs(float(sampled_a["mean_stop_duration"]) - float(sampled_b["mean_stop_duration"]))
    assert gap > 5 * float(sampled_a["mean_stop_duration_error"])


def test_durations_from_the_fine_record_recover_the_planted_means():
    # Exponential phases of 0.5 s on a record sampled every 0.01 s to 100 s, then 0.1 s,
    # with the fine record every 0.01 s throughout. From the fine record the means come back
    # within 3 errors plus 0.02 s (phases shorter than a sample are missed and merge their
    # neighbours: a bias of about dt / <t>, 2 %); from the sampled record the 0.1 s segment
    # misses the short phases and merges their neighbours: <tau_g> came out 0.56-0.61 s
    # (several errors long) and <tau_s> 0.48 s.
    from softcell.testing.synthetic import two_rate_times

    times = two_rate_times(0.01, 0.1, 100.0, 300.0)
    ds = stop_and_go_dataset(
        np.random.default_rng(8),
        times,
        realizations=12,
        speed=2.0,
        mean_go=0.5,
        mean_stop=0.5,
        fine=True,
    )
    options = {"discard": 0.0, "threshold": 0.5}
    fine = analyze(ds, options).sel(body="cell")
    sampled = analyze(ds, {**options, "stopgo_record": "sampled"}).sel(body="cell")
    for name in ("mean_go_duration", "mean_stop_duration"):
        value, error = float(fine[name]), float(fine[f"{name}_error"])
        assert abs(value - 0.5) <= 3 * error + 0.02, (name, value, error)
    go, go_error = float(sampled["mean_go_duration"]), float(sampled["mean_go_duration_error"])
    assert go - 0.5 > 3 * go_error, (go, go_error)
