"""Fitting the unknowns: priors over parameters, and the statistics data and simulations are
compared by."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from hypothesis import given
from hypothesis import strategies as st
from scipy import integrate

from softcell.components.registry import default_registry
from softcell.errors import ConfigError, SoftcellError
from softcell.fit.design import design_points, run_design, space_filling, statistics_of
from softcell.fit.inference import fit_emulator, sample_posterior
from softcell.fit.priors import Prior, make_prior, parse_prior, priors_from_table
from softcell.fit.statistics import observed
from softcell.model.configuration import DEFAULT_COMPONENTS
from softcell.model.parameters import MODEL_PARAMETERS


@pytest.fixture(scope="module")
def specs():
    return {**MODEL_PARAMETERS, **default_registry().parameter_specs(DEFAULT_COMPONENTS)}


def test_a_prior_over_decades_is_log_uniform_and_a_narrow_one_uniform(specs):
    wide = parse_prior("bending_stiffness=0.01:1", specs)
    assert wide == Prior("bending_stiffness", 0.01, 1.0, "N cm2", "log")
    narrow = parse_prior("membrane_friction=1e-5:1e-4", specs)  # exactly a decade
    assert narrow.scale == "linear" and narrow.unit == "N s cm-2"
    assert parse_prior("radius=4:40", specs, scale="linear").scale == "linear"


def test_a_prior_in_another_unit_is_converted_to_the_parameters(specs):
    # 1e-6 N m2 = 1e-6 x 1e4 N cm2
    prior = parse_prior("bending_stiffness=1e-6:1e-4 N m2", specs)
    assert prior.low == pytest.approx(0.01, rel=1e-12) and prior.high == pytest.approx(1.0)
    assert prior.unit == "N cm2"


@pytest.mark.parametrize(
    "text,words",
    [
        ("bending_stiffnes=1:2", "did you mean 'bending_stiffness'"),
        ("bending_stiffness=1:0.5", "the range 1:0.5 N cm2 is empty"),
        ("bending_stiffness=1:1", "is empty"),
        ("bending_stiffness=0.1:1 furlongs per", "unit 'furlongs per' does not parse"),
        ("bending_stiffness=0.1:1 m", "unit 'm' is not convertible to 'N cm2'"),
        ("bending_stiffness=-1:1", "must be > 0 N cm2"),
        ("bending_stiffness=0.1", "must be NAME=LOW:HIGH"),
        ("bending_stiffness=a:b", "holds no two numbers"),
        ("nodes=16:32", "a fit varies real parameters"),
    ],
)
def test_a_bad_prior_is_one_line_naming_it(specs, text, words):
    with pytest.raises(ConfigError) as caught:
        parse_prior(text, specs)
    assert words in str(caught.value) and "\n" not in str(caught.value)


def test_a_log_prior_needs_a_positive_low_end():
    specs = default_registry().parameter_specs()  # static friction may be 0: a log prior not
    assert make_prior("membrane_static_friction", 0.0, 1e-3, specs).scale == "linear"
    with pytest.raises(ConfigError, match="needs LOW > 0"):
        make_prior("membrane_static_friction", 0.0, 1e-3, specs, scale="log")


def test_a_priors_table_gives_the_same_priors_as_the_flags(specs):
    table = {
        "bending_stiffness": {"low": 1e-6, "high": 1e-4, "unit": "N m2"},
        "membrane_friction": {"low": 1e-5, "high": 1e-4, "scale": "log"},
    }
    priors = priors_from_table(table, specs)
    assert priors[0] == parse_prior("bending_stiffness=1e-6:1e-4 N m2", specs)
    assert priors[1].scale == "log"
    with pytest.raises(ConfigError, match=r"must be a table \{low, high, unit\?, scale\?\}"):
        priors_from_table({"bending_stiffness": 0.1}, specs)


@given(
    low=st.floats(1e-6, 1e3),
    ratio=st.floats(1.01, 1e6),
    u=st.floats(0.0, 1.0),
    log=st.booleans(),
)
def test_quantile_inverts_value_and_the_value_stays_in_range(low, ratio, u, log):
    prior = Prior("x", low, low * ratio, "1", "log" if log else "linear")
    v = prior.value(u)
    assert low * (1 - 1e-12) <= v <= low * ratio * (1 + 1e-12)
    assert prior.quantile(v) == pytest.approx(u, abs=1e-9)


@pytest.mark.parametrize("scale", ["log", "linear"])
def test_the_prior_density_integrates_to_one_and_vanishes_outside(scale):
    prior = Prior("x", 0.02, 5.0, "1", scale)
    total, _ = integrate.quad(lambda v: math.exp(prior.log_density(v)), 0.02, 5.0, limit=200)
    assert total == pytest.approx(1.0, rel=1e-8)
    assert prior.log_density(0.019) == -np.inf and prior.log_density(5.01) == -np.inf
    # uniform in log(value) for the log prior: density x value is constant
    v = np.array([0.05, 0.5, 4.0])
    d = np.exp(prior.log_density(v))
    assert np.ptp(d * v if scale == "log" else d) == pytest.approx(0.0, abs=1e-12)


@pytest.fixture(scope="module")
def analysis():
    import softcell
    from softcell.testing.synthetic import stop_and_go_dataset

    ds = stop_and_go_dataset(
        np.random.default_rng(1),
        np.arange(0, 120, 0.04),
        realizations=6,
        speed=2.0,
        mean_go=1.0,
        mean_stop=0.5,
    )
    return softcell.analyze(ds)


def test_the_statistics_are_the_analysis_per_realization_values(analysis):
    seen = observed(analysis, ("mean_speed", "mean_go_duration", "ipr_mean"))
    assert seen.each.shape == (1, 6, 3) and seen.units == ("cm s-1", "s", "1")
    each = analysis["mean_speed_realization"].sel(body="cell").values
    assert np.array_equal(seen.each[0, :, 0], each)
    assert seen.mean[0, 0] == pytest.approx(each.mean(), rel=1e-12)
    assert seen.error[0, 0] == pytest.approx(each.std(ddof=1) / math.sqrt(6), rel=1e-12)


def test_a_statistic_the_data_lacks_or_an_unknown_one_is_refused(analysis):
    with pytest.raises(ConfigError, match="did you mean 'mean_speed'"):
        observed(analysis, ("mean_sped",))
    lacking = analysis.drop_vars("mean_go_duration_realization")
    with pytest.raises(ConfigError, match="the data lacks the statistic 'mean_go_duration'"):
        observed(lacking, ("mean_go_duration",))
    undefined = analysis.copy()
    undefined["ipr_mean_realization"] = undefined["ipr_mean_realization"] * np.nan
    with pytest.raises(ConfigError, match="undefined in every realization"):
        observed(undefined, ("ipr_mean",))
    with pytest.raises(ConfigError, match="at least one statistic"):
        observed(analysis, ())


# -- the design ---------------------------------------------------------------------------


def _two_priors(specs):
    return [
        parse_prior("bending_stiffness=0.01:1", specs),
        parse_prior("membrane_friction=1e-5:1e-4", specs),
    ]


def test_the_design_fills_the_box_the_same_way_from_the_same_seed(specs):
    priors = _two_priors(specs)
    values = space_filling(priors, 16, seed=4)
    assert values.shape == (16, 2)
    assert np.array_equal(values, space_filling(priors, 16, seed=4))
    assert not np.array_equal(values, space_filling(priors, 16, seed=5))
    for i, prior in enumerate(priors):
        q = prior.quantile(values[:, i])
        assert np.all((q >= 0) & (q < 1))
        # a scrambled Sobol net: each 1/16 of every prior holds exactly one point
        assert sorted(np.floor(q * 16).astype(int)) == list(range(16))


@pytest.mark.parametrize("count", [0, 1, 12, 2.0, True])
def test_a_design_size_that_is_not_a_power_of_two_is_refused(specs, count):
    with pytest.raises(ConfigError, match="must be a power of two >= 2"):
        space_filling(_two_priors(specs), count, seed=0)
    with pytest.raises(ConfigError, match="at least one unknown"):
        space_filling([], 8, seed=0)


def test_the_design_points_set_the_unknowns_over_the_base(tmp_path, specs):
    from softcell.model.configuration import RunConfig

    base = RunConfig(parameters={"radius": 6.0, "duration": 3.0})
    priors = _two_priors(specs)
    points = design_points(tmp_path, base, priors, np.array([[0.1, 2e-5], [0.5, 8e-5]]))
    assert list(points) == [tmp_path / "point0000", tmp_path / "point0001"]
    label, config = points[tmp_path / "point0001"]
    assert config.parameters == {"radius": 6.0, "duration": 3.0,
                                 "bending_stiffness": 0.5, "membrane_friction": 8e-5}  # fmt: skip
    assert label == "bending_stiffness = 0.5 N cm2, membrane_friction = 8e-05 N s cm-2"


def test_every_design_point_draws_the_same_random_numbers(tmp_path, specs):
    from softcell.io.netcdf import open_dataset
    from softcell.model.configuration import RunConfig

    base = RunConfig(parameters={"radius": 5.0, "duration": 4.0})
    priors = _two_priors(specs)
    values = np.array([[0.05, 2e-5], [0.8, 9e-5]])
    folders = run_design(
        tmp_path, base, priors, values, realizations=2, seed=3, workers=1, progress=False
    )
    runs = [open_dataset(f) for f in folders]
    # common random numbers: realization r of each point has the same drive schedule ...
    assert np.array_equal(runs[0]["bot_phase"].values, runs[1]["bot_phase"].values)
    # ... and the two realizations of a point differ
    assert not np.array_equal(*runs[0]["bot_phase"].values)
    # the points differ by their parameters: the softer membrane deforms more
    assert float(runs[0].attrs["parameter_bending_stiffness"]) == 0.05
    each = statistics_of(folders, ("mean_speed", "ipr_mean"), {"discard": 0.0})
    assert each.shape == (2, 1, 2, 2) and np.all(np.isfinite(each))
    assert np.all(each[0, 0, :, 1] > each[1, 0, :, 1])


# -- the posterior ------------------------------------------------------------------------
# A linear Gaussian model whose posterior is known: two statistics x = a + b theta + noise
# (sd s, independent), theta uniform on [0, 1]. With n realizations of data and a flat prior
# the posterior is normal, of precision n sum(b^2 / s^2), centred where the data's means say.

A, B, S = np.array([5.0, 3.0]), np.array([2.0, -1.0]), np.array([0.3, 0.2])


def _linear(theta: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    noise = rng.standard_normal((*np.shape(theta), n, 2))
    return A + B * np.asarray(theta)[..., None, None] + S * noise


def _emulator(points: int, realizations: int, common: bool = False, noise: int = 0):
    """The emulator of a design of the linear model; ``common``: every point draws the same
    noise (common random numbers, as a fit's design does); ``noise``: the seed of the
    design's noise."""
    from scipy.stats import qmc

    prior = Prior("theta", 0.0, 1.0, "1", "linear")
    design = qmc.Sobol(1, seed=1).random_base2(points.bit_length() - 1)[:, 0]
    rng = np.random.default_rng(noise)
    if common:
        each = A + B * design[:, None, None] + S * rng.standard_normal((realizations, 2))
    else:
        each = _linear(design, realizations, rng)
    return fit_emulator([prior], design[:, None], each, seed=0, common=common)


@pytest.fixture(scope="module")
def linear_emulator():
    """A design as a fit runs it: 32 points of 6 realizations (the emulator's own error is
    part of the posterior)."""
    return _emulator(32, 6)


@pytest.fixture(scope="module")
def precise_emulator():
    """A design so dense that the emulator's error is negligible: the posterior is then the
    analytic one."""
    return _emulator(64, 40)


def _analytic(data: np.ndarray) -> tuple[float, float]:
    """The posterior's mean and standard deviation: a normal truncated to the prior [0, 1]."""
    from scipy.stats import truncnorm

    n = data.shape[0]
    precision = n * np.sum(B**2 / S**2)
    centre, sd = float(np.sum(n * B * (data.mean(0) - A) / S**2) / precision), precision**-0.5
    posterior = truncnorm((0 - centre) / sd, (1 - centre) / sd, loc=centre, scale=sd)
    return float(posterior.mean()), float(posterior.std())


@pytest.mark.parametrize("truth,seed", [(0.3, 11), (0.55, 12), (0.8, 13)])
def test_the_posterior_of_a_linear_gaussian_model_is_the_analytic_one(
    precise_emulator, truth, seed
):
    data = _linear(truth, 6, np.random.default_rng(seed))
    draws = sample_posterior(precise_emulator, data, seed=seed, steps=600, burn=200)[:, 0]
    mean, sd = _analytic(data)
    assert abs(draws.mean() - mean) < 0.25 * sd
    assert draws.std() == pytest.approx(sd, rel=0.12)


def test_the_same_seed_draws_the_same_posterior(linear_emulator):
    data = _linear(0.5, 6, np.random.default_rng(3))
    one = sample_posterior(linear_emulator, data, seed=5, steps=100, burn=20)
    assert np.array_equal(one, sample_posterior(linear_emulator, data, seed=5, steps=100, burn=20))
    assert not np.array_equal(
        one, sample_posterior(linear_emulator, data, seed=6, steps=100, burn=20)
    )


@pytest.mark.slow
@pytest.mark.parametrize("common", [False, True], ids=["independent", "common random numbers"])
def test_the_90_percent_intervals_cover_the_truth_at_the_binomial_rate(common):
    """Over data sets drawn at random truths, the 90 % intervals hold the truth at the
    binomial rate, whether the design's points draw independent noise or share it (then
    the emulator carries the shared error, which no number of points averages away).

    With shared noise the design's one noise draw is a common offset: the coverage is the
    promised one over designs, not for one design (one design, seed 0, held the truth in
    82 of 100; without the shared error in the likelihood, 71), so each trial draws its
    own design's noise."""
    from scipy.stats import binom

    emulator = _emulator(32, 6, common)
    rng = np.random.default_rng(2026)
    trials, hits = 100, 0
    for trial in range(trials):
        truth = rng.uniform(0.15, 0.85)  # inside the prior, away from its edges
        if common:
            emulator = _emulator(32, 6, common, noise=1000 + trial)
        draws = sample_posterior(emulator, _linear(truth, 6, rng), seed=trial, steps=400, burn=100)[
            :, 0
        ]
        low, high = np.quantile(draws, [0.05, 0.95])
        hits += bool(low <= truth <= high)
    band = binom.ppf([0.005, 0.995], trials, 0.9)
    assert band[0] <= hits <= band[1], f"{hits} of {trials} intervals hold the truth"


def test_an_emulator_needs_the_noise_of_every_point():
    prior = Prior("theta", 0.0, 1.0, "1", "linear")
    each = _linear(np.array([0.2, 0.7]), 1, np.random.default_rng(0))
    with pytest.raises(SoftcellError, match="two or more realizations per design point"):
        fit_emulator([prior], np.array([[0.2], [0.7]]), each, seed=0)
    each = _linear(np.array([0.2, 0.7]), 3, np.random.default_rng(0))
    each[1, 1:, 0] = np.nan
    with pytest.raises(SoftcellError, match="fewer than two realizations at design point 1"):
        fit_emulator([prior], np.array([[0.2], [0.7]]), each, seed=0)


# -- softcell fit -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """Simulated data of a known stiffness: 3 realizations of 12 s at R = 5 cm, seed 1."""
    from softcell.cli import main

    out = tmp_path_factory.mktemp("fit") / "data"
    argv = ["simulate", "--radius", "5", "--bending-stiffness", "0.2", "--duration", "12"]
    assert main([*argv, "--realizations", "3", "--seed", "1", "-o", str(out), "--quiet"]) == 0
    return out


@pytest.mark.parametrize(
    "argv,words",
    [
        (["--prior", "bending_stiffnes=0.1:1"], "did you mean 'bending_stiffness'"),
        (["--prior", "bending_stiffness=0.1:1", "--simulations", "12"], "power of two"),
        (["--prior", "bending_stiffness=0.1:1", "--seed", "1"], "simulated from seed 1"),
        (["--prior", "bending_stiffness=0.1:1 N"], "unit 'N' is not convertible"),
        (["--prior", "bending_stiffness=1:0.1"], "is empty"),
        (["--prior", "bending_stiffness=0.1:1", "--statistics", "ipr_man"], "'ipr_mean'"),
    ],
)
def test_a_bad_fit_is_one_line_before_any_simulation(data, tmp_path, capsys, argv, words):
    from softcell.cli import main

    code = main(["fit", str(data), *argv, "-o", str(tmp_path / "fit.nc")])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_a_fit_of_simulated_data_holds_its_true_stiffness(data, tmp_path):
    from softcell.cli import main

    out = tmp_path / "fit.nc"
    argv = ["fit", str(data), "--prior", "bending_stiffness=0.05:1", "--simulations", "16"]
    argv += ["--statistics", "ipr_mean,mean_speed", "--discard", "2", "--check-draws", "4"]
    argv += ["-o", str(out)]
    assert main([*argv, "--quiet", "--workers", "2"]) == 0
    result = xr.open_dataset(out)
    low, _, high = result["bending_stiffness_interval"].values
    assert low <= 0.2 <= high and high / low < 10  # the truth, and narrower than the prior
    assert result["bending_stiffness"].attrs["units"] == "N cm2"
    assert result.sizes["design_point"] == 16 and result.attrs["softcell_seed"] == 2
    assert len(list((tmp_path / "fit_design").glob("point*/*.nc"))) == 16 * 3
    assert len(list((tmp_path / "fit_check").glob("point*/*.nc"))) == 4 * 3
    assert result["check_verdict"].dims == ("point", "statistic")
    assert result["check_z"].shape == (1, 2)
    from softcell.io.files import kind_of

    assert kind_of(out.with_suffix(".png")) == "figure"


def test_the_check_judges_a_statistic_by_its_predictive_spread():
    from softcell.fit.check import judge

    rng = np.random.default_rng(4)
    draws = 1.0 + 0.1 * rng.standard_normal((16, 1, 6, 2))  # 16 draws, 6 realizations each
    data = 1.0 + 0.1 * rng.standard_normal((1, 6, 2))
    data[..., 1] += 0.5  # the second statistic far from what the draws give
    z, verdict = judge(data, draws)
    assert abs(z[0, 0]) < 2 and verdict.tolist() == [[0, 1]]
    # the spread of a mean of 6: 0.1 / sqrt(6), not the draws' means' spread alone
    assert z[0, 1] == pytest.approx(
        (data[0, :, 1].mean() - draws[..., 1].mean(axis=2).mean()) / (0.1 / np.sqrt(6)), rel=0.3
    )


# -- films: the fit's simulations filmed and tracked as the data were ---------------------


@pytest.fixture(scope="module")
def films(data, tmp_path_factory):
    """Two films of realizations 0 and 1 of ``data`` (2 s to 6 s), rendered to files and
    tracked as a user would."""
    from softcell.cli import main

    folder = tmp_path_factory.mktemp("films")
    tracked = []
    for r in (0, 1):
        movie, out = folder / f"cell{r}.mkv", folder / f"tracked{r}.nc"
        argv = ["render", str(data), "-o", str(movie), "--realization", str(r), "--start", "2"]
        argv += ["--end", "6", "--noise", "2", "--blur", "1", "--seed", str(7 + r), "--quiet"]
        assert main(argv) == 0
        assert main(["track", str(movie), "-o", str(out), "--px-per-cm", "10", "--radius", "5",
                     "--quiet"]) == 0  # fmt: skip
        tracked.append(out)
    return folder, tracked


def test_a_film_made_in_memory_is_the_rendered_film_tracked(data, films):
    """filmed() against the independent path: render writes the film, track reads it back."""
    import json

    from softcell.io.netcdf import open_dataset
    from softcell.video.film import Camera, filmed
    from softcell.video.render import Film

    folder, tracked = films
    from_file = open_dataset(tracked[1])
    made = filmed(open_dataset(data), camera=Camera(noise=2, blur=1), start=2, end=6, seed=8,
                  realization=1, radius=5)  # fmt: skip
    frame = Film(open_dataset(data), realization=1, start=2, end=6).frame
    origin = (frame.x0, frame.y0)  # the file was tracked from (0, 0)
    for name, shift in (("cell_x", origin[0]), ("cell_y", origin[1]), ("membrane_x", origin[0])):
        np.testing.assert_allclose(made[name].values, from_file[name].values + shift, atol=1e-9)
    np.testing.assert_allclose(made["bot_angle"].values, from_file["bot_angle"].values, atol=1e-12)
    assert json.loads(made.attrs["softcell_video"].split(": ", 1)[1])["seed"] == 8


def test_several_films_are_the_realizations_of_their_radius(films, tmp_path):
    import shutil

    from softcell.io.netcdf import open_inputs

    _, tracked = films
    copy = shutil.copy(tracked[1], tmp_path / "copy_of_tracked1.nc")  # one file twice: refused
    ds = open_inputs([tracked[1], tracked[0], copy])
    assert ds["realization"].values.tolist() == [0, 1, 2]
    np.testing.assert_array_equal(ds["cell_x"].values[0], ds["cell_x"].values[2])
    assert ds.attrs["softcell_videos"] == '["cell1.mkv", "cell0.mkv", "cell1.mkv"]'


def test_films_at_two_radii_are_two_points_each_numbering_its_own(films, tmp_path):
    import json

    from softcell.fit.measure import film_request
    from softcell.io.netcdf import open_dataset, open_inputs, write_dataset

    _, tracked = films
    other = open_dataset(tracked[0]).load()
    other.attrs["softcell_parameters"] = json.dumps({"radius": 6.0})
    other = other.isel(time=slice(0, 61))  # a shorter film: 2 s
    moved = write_dataset(other, tmp_path / "tracked_r6.nc")
    ds = open_inputs([tracked[0], moved, tracked[1]])
    assert ds["radius"].values.tolist() == [5.0, 6.0]
    assert ds["realization"].values.tolist() == [0, 1]
    base, measure = film_request(ds, None, camera=None, warmup=15, options={})
    assert base.parameters["radius"] == [5.0, 6.0] and measure.radii == (5.0, 6.0)
    np.testing.assert_allclose(measure.spans, [[4.0, 4.0], [2.0, np.nan]])


def test_films_ask_for_their_radius_length_and_frame_rate(films):
    from softcell.fit.measure import film_request
    from softcell.io.netcdf import open_inputs
    from softcell.model.configuration import RunConfig

    _, tracked = films
    ds = open_inputs(tracked)
    config = RunConfig(parameters={"bending_stiffness": 0.3})
    base, measure = film_request(ds, config, camera={"noise": 0.5}, warmup=10, options={})
    assert base.parameters["radius"] == 5.0 and base.parameters["bending_stiffness"] == 0.3
    assert base.parameters["sample_every"] == pytest.approx(1 / 30)
    np.testing.assert_allclose(measure.spans, [[4.0, 4.0]])  # 121 frames at 30 /s
    assert base.parameters["duration"] == pytest.approx(10 + 4 + 2 / 30)
    assert (measure.camera.px_per_cm, measure.camera.fps, measure.camera.noise) == (10, 30, 0.5)
    assert measure.made(0, 1, seed=3)["end"] == 14.0
    assert measure.made(0, 1, seed=3) != measure.made(0, 0, seed=3)


@pytest.mark.parametrize(
    "extra,words",
    [
        (["--camera-noise", "-1"], "camera noise = -1.0 is not allowed"),
        (["--warmup", "-3"], "warmup = -3.0 is not allowed"),
        (["--config", "{radius}"], "the films set the radius"),
        (["--config", "{prior}"], "unknown table [prior] (did you mean 'priors'?)"),
        (["--prior", "bending_stiffness=0.1:0.3"], "given 2 times"),
    ],
)
def test_a_bad_film_fit_is_one_line_before_any_simulation(films, tmp_path, capsys, extra, words):
    from softcell.cli import main

    (tmp_path / "radius.toml").write_text("[parameters]\nradius = 4\n")
    (tmp_path / "prior.toml").write_text("[prior]\nbending_stiffness = {low = 1, high = 2}\n")
    extra = [e.format(radius=tmp_path / "radius.toml", prior=tmp_path / "prior.toml")
             for e in extra]  # fmt: skip
    _, tracked = films
    argv = ["fit", *map(str, tracked), "--prior", "bending_stiffness=0.05:1", *extra]
    code = main([*argv, "-o", str(tmp_path / "fit.nc")])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "fit.nc").exists() and not (tmp_path / "fit_design").exists()


def test_simulation_data_take_no_camera(data, tmp_path, capsys):
    from softcell.cli import main

    argv = ["fit", str(data), "--prior", "bending_stiffness=0.05:1", "--camera-blur", "2"]
    assert main([*argv, "-o", str(tmp_path / "fit.nc")]) == 2
    assert "no camera (that is for films)" in capsys.readouterr().err


@pytest.mark.slow
def test_films_of_a_simulated_cell_hold_its_true_stiffness_and_friction(tmp_path):
    """The experiment's pipeline end to end: a cell of known k and gamma_mem simulated,
    filmed (softcell render) and tracked (softcell track) as a user would, then fitted."""
    from softcell.cli import main

    truth = {"bending_stiffness": 0.2, "membrane_friction": 3.42e-4}
    argv = ["simulate", "--radius", "5", "--duration", "45", "--realizations", "3"]
    argv += ["--bending-stiffness", "0.2", "--membrane-friction", "3.42e-4", "--seed", "11"]
    assert main([*argv, "-o", str(tmp_path / "cell"), "--quiet"]) == 0
    films = []
    for r in range(3):
        movie, out = tmp_path / f"cell{r}.mkv", tmp_path / f"tracked{r}.nc"
        argv = ["render", str(tmp_path / "cell"), "-o", str(movie), "--realization", str(r)]
        argv += ["--start", "15", "--end", "45", "--noise", "2", "--blur", "1"]
        assert main([*argv, "--seed", str(100 + r), "--quiet"]) == 0
        argv = ["track", str(movie), "-o", str(out), "--px-per-cm", "10", "--radius", "5"]
        assert main([*argv, "--quiet"]) == 0
        movie.unlink()
        films.append(str(out))
    out = tmp_path / "fit.nc"
    argv = ["fit", *films, "--prior", "bending_stiffness=0.05:0.8"]
    argv += ["--prior", "membrane_friction=1.5e-4:8e-4", "--simulations", "16"]
    assert main([*argv, "--check-draws", "0", "--workers", "2", "--quiet", "-o", str(out)]) == 0
    result = xr.open_dataset(out)
    for name, value in truth.items():
        low, _, high = result[f"{name}_interval"].values
        assert low <= value <= high, (name, low, high)
    low, _, high = result["bending_stiffness_interval"].values
    assert high / low < 2  # against 16 for the prior
    assert result.attrs["softcell_measured"].startswith("filmed (10 px/cm, 30 frames/s")
    assert len(list(tmp_path.glob("fit_design/point*_films/*.nc"))) == 16 * 3


def test_a_film_fit_run_again_films_nothing_again_and_draws_the_same_posterior(films, tmp_path):
    """Every design simulation and film is a file: a fit rerun (or resumed) reuses them, and
    the same seed draws the same posterior."""
    from softcell.fit.fitting import fit

    _, tracked = films
    lines: list[str] = []
    kwargs = {"simulations": 2, "check_draws": 0, "warmup": 2.0, "workers": 1,
              "statistics": ["ipr_mean", "mean_speed"], "progress": False}  # fmt: skip
    out = fit(tracked, ["bending_stiffness=0.1:0.4"], tmp_path / "fit.nc", log=lines.append,
              **kwargs)  # fmt: skip
    assert any(line.startswith("filming and tracking 4 realizations") for line in lines)
    films_made = sorted(tmp_path.glob("fit_design/point*_films/*.nc"))
    stamps = [f.stat().st_mtime_ns for f in films_made]
    first = xr.open_dataset(out)["bending_stiffness"].values
    lines.clear()
    again = fit(tracked, ["bending_stiffness=0.1:0.4"], tmp_path / "fit.nc", log=lines.append,
                overwrite=True, **kwargs)  # fmt: skip
    assert not any("filming" in line for line in lines)
    assert [f.stat().st_mtime_ns for f in films_made] == stamps and len(stamps) == 4
    np.testing.assert_array_equal(xr.open_dataset(again)["bending_stiffness"].values, first)
    # The films remade on a cluster reached through its scheduler's address (loopback), as
    # a remote one would be: the same films, the same posterior.
    from distributed import LocalCluster

    tracks = {f: xr.open_dataset(f)["cell_x"].values for f in films_made}
    for f in films_made:
        f.unlink()
    kwargs["workers"] = None
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:  # fmt: skip
        address = cluster.scheduler_address
        third = fit(tracked, ["bending_stiffness=0.1:0.4"], tmp_path / "fit.nc",
                    scheduler=address, overwrite=True, log=None, **kwargs)  # fmt: skip
    for f, cell_x in tracks.items():
        np.testing.assert_array_equal(xr.open_dataset(f)["cell_x"].values, cell_x)
    np.testing.assert_array_equal(xr.open_dataset(third)["bending_stiffness"].values, first)


# -- the paper's picture as a target ------------------------------------------------------


def _table(**verdicts: str) -> list[dict[str, str]]:
    return [
        {"topic": topic, "verdict": verdict.replace("_", " ")}
        for topic, verdict in verdicts.items()
    ]


def test_a_points_score_is_the_share_of_its_measured_findings_that_agree():
    from softcell.fit.picture import scores, verdict_matrix

    tables = [
        _table(a="agrees", b="partly", c="differs", d="holds_by_construction"),
        _table(a="differs", b="differs", c="not_measured", e="agrees"),
        _table(d="holds_by_construction"),
    ]
    topics, matrix = verdict_matrix(tables)
    assert topics == ["a", "b", "c", "d", "e"]
    assert matrix.shape == (3, 5) and matrix[0, 4] == 4  # "e" not in the first table
    np.testing.assert_allclose(scores(matrix), [(1 + 0.5 + 0) / 3, 1 / 3, np.nan])


def test_findings_pull_against_each_other_when_they_never_agree_together():
    from softcell.fit.picture import tensions, verdict_matrix

    tables = [
        _table(a="agrees", b="differs", c="agrees"),
        _table(a="differs", b="agrees", c="agrees"),
        _table(a="partly", b="agrees", c="differs"),
    ]
    pulls = tensions(*verdict_matrix(tables))
    assert pulls == [{"findings": ["a", "b"], "agrees": [1, 2], "points": 3}]


@pytest.mark.slow
def test_a_search_scores_every_point_against_the_papers_findings(tmp_path):
    from dataclasses import replace

    from softcell.fit.picture import SEARCH_DESIGN, search

    design = replace(SEARCH_DESIGN, radii=(4.0, 6.0), realizations=2, duration=40.0,
                     free_bot_realizations=2)  # fmt: skip
    prior = Prior("bending_stiffness", 0.05, 0.8, "N cm2", "log")
    out = search([prior], tmp_path / "search.nc", points=2, design=design, workers=1,
                 progress=False, log=None)  # fmt: skip
    result = xr.open_dataset(out)
    assert (
        result.sizes["design_point"] == 2 and result["bending_stiffness"].attrs["units"] == "N cm2"
    )
    for i in range(2):  # each point's verdicts are its reproduction's findings table
        import json

        table = json.loads((tmp_path / f"search_points/point{i:04d}/findings.json").read_text())
        verdicts = {row["topic"]: row["verdict"] for row in table["findings"]}
        flags = result["verdict"].attrs["flag_meanings"].split()
        for topic, flag in zip(result["finding"].values, result["verdict"].values[i], strict=True):
            assert flags[flag].replace("_", " ") == verdicts[topic]
    assert "| point | bending_stiffness (N cm2) | score |" in out.with_suffix(".md").read_text()
