"""softcell reproduce: a small design end to end, the figures, the report and its verdicts."""

import json
import re
from html.parser import HTMLParser

import numpy as np
import pytest
import xarray as xr
from readable import unreadable

import softcell
from softcell.cli import main
from softcell.errors import SoftcellError
from softcell.paper.findings import VERDICTS, cell_values, findings
from softcell.paper.reproduce import Design, VideoDesign, reproduce

TINY = Design(
    "tiny",
    radii=(4.0, 12.0),
    realizations=2,
    duration=30.0,
    discard=5.0,
    free_bot_realizations=2,
    video=VideoDesign(radius=12.0, span=5.0),
)
FIGURES = ("fig2", "fig3", "fig4", "figS1", "figS2", "figS3", "figT")


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("results")
    outcome = reproduce(out, TINY, seed=4, workers=1, progress=False, log=None)
    return out, outcome


def test_every_figure_is_written_as_png_and_pdf(results):
    out, _ = results
    for name in FIGURES:
        assert (out / "figures" / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (out / "figures" / f"{name}.pdf").read_bytes()[:5] == b"%PDF-"


def test_report_states_what_ran_and_links_every_figure(results):
    out, outcome = results
    md = (out / "report.md").read_text()
    for text in (
        f"softcell {softcell.__version__}",
        "integrator = rodas4",
        "Seed 4",
        "SeedSequence(4, spawn_key=(p, r))",
        "Findings: the paper beside this run",
        "The experimental pipeline",
        "| bending_stiffness | 0.57 | N cm2 |",
    ):
        assert text in md
    for name in FIGURES:
        assert f"(figures/{name}.png)" in md and f"(figures/{name}.pdf)" in md
    # A reader meets the findings first; what ran and the parameters close the report.
    headings = re.findall(r"^## (.*)$", md, flags=re.M)
    assert headings[0] == "Findings: the paper beside this run"
    assert headings[-1] == "What ran"
    assert md.index("| bending_stiffness |") > md.index("## Figures")
    # The film's notes are said with the film.
    pipeline = md[md.index("## The experimental pipeline") : md.index("## Figures")]
    assert "About the film: " in pipeline and "remakes it" in pipeline

    class Sources(HTMLParser):
        def __init__(self):
            super().__init__()
            self.links = []

        def handle_starttag(self, tag, attrs):
            self.links += [v for k, v in attrs if k in ("src", "href")]

    parser = Sources()
    parser.feed((out / "report.html").read_text())
    assert len(parser.links) == 2 * len(FIGURES)
    assert all((out / link).is_file() for link in parser.links)
    assert set(outcome.steps) == {
        "simulations",
        "free_bot",
        "analysis",
        "video",
        "figures",
        "figures_with_video",
        "report",
    }
    timing = json.loads((out / "timing.json").read_text())
    assert timing["beside"]["video"] > 0  # the video ran in its own process
    summary = json.loads((out / "findings.json").read_text())
    assert summary["seed"] == 4 and summary["design"] == "tiny"
    for row in summary["findings"]:
        assert row["topic"] in md and row["verdict"] in VERDICTS
        assert {"values", "uncertainties", "unit", "rule", "verdict", "cause"} <= set(row)
        assert row["cause"] or row["verdict"] == "agrees"  # every miss says why


def test_outputs_carry_cf_attributes_and_their_provenance(results):
    out, _ = results
    analysis = softcell.read_dataset(out / "analysis.nc")
    np.testing.assert_array_equal(analysis["radius"].values, [4.0, 12.0])
    for name, var in analysis.data_vars.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert json.loads(analysis.attrs["softcell_components"])["integrator"] == "rodas4"
    assert analysis.attrs["softcell_seed"] == 4
    tracked = softcell.read_dataset(out / "video" / "tracked.nc")
    assert tracked.attrs["softcell_origin"] == "tracking"


def test_the_tracked_film_follows_the_simulated_cell(results):
    # Independent of the tracker's own tests: frame k of the film is the state at
    # discard + k / fps of realization 0 at the video's radius.
    out, _ = results
    tracked = softcell.read_dataset(out / "video" / "tracked.nc").isel(realization=0)
    sim = softcell.read_dataset(out / "simulations" / "point001_realization0000.nc")
    sim = sim.isel(realization=0)
    # At 10 px/cm: the membrane's centroid within 0.3 px, the bot (a smaller contour, partly
    # hidden by the membrane band when they touch) within 1 px.
    t = TINY.discard + tracked["time"].values
    for name, atol in (("cell_x", 0.03), ("cell_y", 0.03), ("bot_x", 0.1), ("bot_y", 0.1)):
        expected = np.interp(t, sim["time"].values, sim[name].values)
        np.testing.assert_allclose(tracked[name].values, expected, atol=atol)
    assert not (out / "video" / "cell.mkv").exists()


def test_a_rerun_keeps_the_finished_realizations(results):
    out, _ = results
    files = sorted((out / "simulations").glob("*.nc")) + sorted((out / "free_bot").glob("*.nc"))
    assert len(files) == 2 * 2 + 2
    before = {f: (f.stat().st_mtime_ns, f.read_bytes()) for f in files}
    reproduce(out, TINY, seed=4, workers=1, progress=False, log=None)
    assert {f: (f.stat().st_mtime_ns, f.read_bytes()) for f in files} == before


def test_figures_command_draws_what_its_inputs_allow(results, tmp_path, capsys):
    out, _ = results
    assert main(["figures", str(out / "analysis.nc"), "-o", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "note: fig2 not drawn: needs the simulations" in printed
    assert "note: figS1 not drawn: needs the free bot's analysis" in printed
    assert sorted(p.name for p in tmp_path.glob("*.png")) == [
        "fig3.png",
        "fig4.png",
        "figS2.png",
        "figS3.png",
        "figT.png",
    ]
    free = softcell.read_dataset(out / "free_bot_analysis.nc")
    assert main(["figures", str(out / "free_bot_analysis.nc"), "-o", str(tmp_path)]) == 2
    assert "radius sweep" in capsys.readouterr().err
    assert "radius" not in free.dims


def _verdict(rows, topic):
    return next(r.verdict for r in rows if r.topic == topic)


@pytest.mark.slow  # ~50 s: the findings and their bootstraps, ten times over
def test_verdicts_follow_their_stated_rules(results):
    out, _ = results
    analysis = softcell.read_dataset(out / "analysis.nc")
    radii = np.arange(4.0, 14.0)
    ten = xr.concat([analysis.isel(radius=0)] * radii.size, dim="radius").assign_coords(
        radius=radii
    )

    def with_cell(ds, name, values):
        ds = ds.copy()
        data = ds[name].values.copy()
        data[:, 0] = values
        ds[name] = (ds[name].dims, data, ds[name].attrs)
        return ds

    up = with_cell(ten, "mean_stop_duration", 0.3 + 0.05 * radii)
    assert _verdict(findings(up), "<tau_s> against R") == "agrees"
    down = with_cell(ten, "mean_stop_duration", 1.0 - 0.05 * radii)
    assert _verdict(findings(down), "<tau_s> against R") == "differs"
    slower = with_cell(ten, "ballistic_velocity", 3.0 / radii)
    assert _verdict(findings(slower), "ballistic velocity against R") == "agrees"

    regimes = ten.copy()
    regimes["regime"] = ("radius", np.array([0, 0, 1, 1, 2, 2, 2, 2, 2, 2], dtype=np.int8))
    assert _verdict(findings(regimes), "regime per R") == "agrees"
    regimes["regime"] = ("radius", np.array([0, 1, 1, 1, 2, 2, 2, 2, 2, 2], dtype=np.int8))
    assert _verdict(findings(regimes), "regime per R") == "partly"
    regimes["regime"] = ("radius", np.array([1, 1, 1, 1, 2, 2, 2, 2, 1, 2], dtype=np.int8))
    assert _verdict(findings(regimes), "regime per R") == "differs"

    peaked = with_cell(
        regimes, "mean_go_duration", [0.3, 0.5, 0.9, 0.8, 0.6, 0.6, 0.61, 0.6, 0.6, 0.6]
    )
    peaked["regime"] = ("radius", np.array([0, 0, 1, 1, 2, 2, 2, 2, 2, 2], dtype=np.int8))
    assert _verdict(findings(peaked), "<tau_g> against R") == "agrees"
    flat_then_low = with_cell(peaked, "mean_go_duration", np.linspace(0.9, 0.3, 10))
    assert _verdict(findings(flat_then_low), "<tau_g> against R") == "differs"

    # A trend whose one step goes against it far beyond the errors is only partly one.
    dip = with_cell(ten, "mean_stop_duration", [1, 2, 3, 4, 5, 6, 7, 8, 3, 10])
    assert _verdict(findings(dip), "<tau_s> against R") == "partly"

    # The ballistic fit and v0 hat share their samples: no rule could fail.
    v0 = with_cell(ten, "ballistic_velocity", 10.0)
    assert _verdict(findings(v0), "theory: v0 hat against the ballistic fit") == (
        "holds by construction"
    )

    # D hat (the affine fit's): within a factor 2 of the theory everywhere, and above it at
    # R >= 10 cm. Two copies of one realization: no spread, so the errors are 0 and the
    # planted ratios alone decide (two 30 s realizations leave the affine fit's error too
    # large for any rule to judge).
    same = ten.isel(realization=[0, 0])
    topic = "theory: D hat against the fitted MSD slope (affine fit)"
    theory = cell_values(same, "msd_slope_theory")
    fit = "msd_slope_affine"
    assert _verdict(findings(with_cell(same, fit, 1.5 * theory)), topic) == "agrees"
    assert _verdict(findings(with_cell(same, fit, 1.0 * theory)), topic) == "partly"
    assert _verdict(findings(with_cell(same, fit, 4.0 * theory)), topic) == "partly"
    assert _verdict(findings(with_cell(same, fit, 0.1 * theory)), topic) == "differs"


def test_bad_requests_are_refused_with_the_value(tmp_path):
    with pytest.raises(SoftcellError, match="video's radius 8 cm is not among"):
        reproduce(
            tmp_path,
            Design("x", radii=(4.0, 12.0), video=VideoDesign(radius=8.0)),
            progress=False,
            log=None,
        )
    assert main(["reproduce", "--quick", "--workers", "0", "-o", str(tmp_path)]) == 2


@pytest.mark.parametrize(
    ("toml", "message"),
    [
        ("[parameters]\nbending_stiffness = -1.0\n", "bending_stiffness"),
        ('[components]\ndriving_protocol = "pivot_run_and_tumbel"\n', "pivot_run_and_tumbel"),
        ("[parameters]\nradius = 5.0\n", "the design sets radius"),
        ("[run]\nrealizations = 2\n", r"not \[run\]"),
        ("[assembly]\ncells = 4\n", r"not \[assembly\]"),
    ],
)
def test_reproduce_at_other_parameters_refuses_a_bad_file_before_running(
    tmp_path, capsys, toml, message
):
    config = tmp_path / "point.toml"
    config.write_text(toml, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["reproduce", "--quick", "--config", str(config), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert re.search(message, err), err
    assert len(err.strip().splitlines()) == 1
    assert not (out / "simulations").exists()


def test_every_figure_can_be_read_where_it_is_shown(results):
    from softcell.paper import figures as paper

    out, _ = results
    analysis = softcell.open_dataset(out / "analysis.nc")
    tracked = softcell.open_dataset(out / "video" / "tracked_analysis.nc")
    drawn = {
        "fig2": paper.figure2(analysis, softcell.open_dataset(out / "simulations")),
        "fig3": paper.figure3(analysis, tracked),
        "fig4": paper.figure4(analysis, tracked),
        "figS1": paper.figure_s1(analysis, softcell.open_dataset(out / "free_bot_analysis.nc")),
        "figS2": paper.figure_s2(analysis),
        "figS3": paper.figure_s3(analysis),
        "figT": paper.figure_theory(analysis),
    }
    assert set(drawn) == set(FIGURES)
    found = [line for name, fig in drawn.items() for line in unreadable(name, fig, dpi=150)]
    assert not found, "\n".join(found)
