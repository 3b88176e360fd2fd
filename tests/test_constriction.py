"""``softcell study constriction``: the channel's geometry, the passage count, the grid's
checks and a small study end to end."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr

from softcell.cli import main
from softcell.components.registry import default_registry
from softcell.errors import SoftcellError
from softcell.model.obstacle_layout import check_clear_of_start, parse_obstacles, surface_distances
from softcell.studies.constriction import (
    BAND,
    CHAMBER,
    OPEN,
    WALL,
    ConstrictionDesign,
    Gate,
    channel,
    constriction,
    passage_samples,
    passages,
)


@pytest.mark.parametrize("radius,gap", [(5.0, 0.8), (7.0, 0.45), (4.0, 1.2)])
def test_the_gap_is_w_wide_surface_to_surface_and_the_chambers_are_squares(radius, gap):
    text, gate = channel(radius, gap)
    walls = parse_obstacles(text)
    assert len(walls) == 6 and {o.kind for o in walls} == {"wall"}
    w = 2 * gap * radius
    # The middle of the gap is w / 2 from both partition walls, and nearer to nothing else.
    d = surface_distances(np.array([gate.x]), np.array([0.0]), text)[:, 0]
    assert np.allclose(np.sort(d)[:2], w / 2, rtol=1e-6) and np.sort(d)[2] > w / 2
    # From the start (the left chamber's middle) every wall of that chamber is 1.5 R away.
    d0 = surface_distances(np.zeros(1), np.zeros(1), text)[:, 0]
    assert np.isclose(np.sort(d0)[0], CHAMBER * radius / 2, rtol=1e-6)
    assert np.sum(np.isclose(d0, CHAMBER * radius / 2, rtol=1e-6)) == 3  # top, bottom, left
    # The right chamber is the left one shifted by a side and a wall.
    shift = CHAMBER * radius + WALL * radius
    d1 = surface_distances(np.array([shift]), np.zeros(1), text)[:, 0]
    assert np.isclose(np.sort(d1)[0], CHAMBER * radius / 2, rtol=1e-6)
    assert gate == Gate(x=CHAMBER * radius / 2 + WALL * radius / 2, band=BAND * radius)
    check_clear_of_start(default_registry().parameters({"radius": radius, "obstacles": text}))


def test_the_open_channel_has_no_partition():
    text, _ = channel(5.0, OPEN)
    assert len(parse_obstacles(text)) == 4


def test_passages_count_crossings_of_the_band_and_nothing_inside_it():
    gate = Gate(x=10.0, band=2.0)
    t = np.linspace(0, 10, 10001)
    # Three periods of a swing 3 cm either side from the right: over and back thrice, 6.
    assert passages(gate.x + 3.0 * np.cos(2 * np.pi * 0.3 * t), gate) == 6
    # Starting in the band, the first swing out is no passage: 5.
    assert passages(gate.x + 3.0 * np.sin(2 * np.pi * 0.3 * t), gate) == 5
    # Wiggling within the band, however often, passes nothing.
    assert passages(gate.x + 1.9 * np.sin(2 * np.pi * 5 * t), gate) == 0
    # Going deep into the band and coming back is no passage; going through is one.
    assert passages(np.array([0.0, 11.9, 8.5, 0.0]), gate) == 0
    assert passages(np.array([0.0, 11.9, 8.5, 12.1, np.nan, 20.0]), gate) == 1
    assert passage_samples(np.array([0.0, 11.9, 8.5, 12.1, np.nan, 20.0, 7.0]), gate).tolist() == [
        3,
        6,
    ]


@pytest.mark.parametrize(
    "change,words",
    [
        ({"gaps": (0.8, 1.6)}, "gap w / 2R = 1.6: must be in (0, 1.5]"),
        ({"gaps": (0.0,)}, "gap w / 2R = 0.0"),
        ({"radii": (-5.0,)}, "radius -5.0 cm: must be > 0"),
        ({"realizations": 0}, "realizations = 0"),
        ({"duration": math.inf}, "duration = inf s"),
        ({"radii": ()}, "no radii or no gaps"),
    ],
)
def test_a_grid_that_cannot_run_is_refused_before_anything_is_made(tmp_path, change, words):
    design = ConstrictionDesign("bad", (5.0,), (1.0,), 1, 10.0)
    from dataclasses import replace

    with pytest.raises(SoftcellError, match=re_escape(words)):
        constriction(tmp_path / "out", design=replace(design, **change), workers=1)
    assert not (tmp_path / "out").exists()


def re_escape(text: str) -> str:
    import re

    return re.escape(text)


def test_a_bad_model_parameter_is_refused_for_every_radius_before_any_run(tmp_path):
    design = ConstrictionDesign("bad", (5.0, 2.5), (1.0,), 1, 10.0)  # 2.5 < the bot's 3 cm
    with pytest.raises(SoftcellError, match="radius"):
        constriction(tmp_path / "out", design=design, workers=1)
    assert not list((tmp_path / "out").glob("R5/*.nc"))
    with pytest.raises(SoftcellError, match="set by the constriction study"):
        constriction(tmp_path / "o2", design=design, parameters={"obstacles": ""}, workers=1)


@pytest.mark.parametrize(
    "argv,words",
    [
        (["--gaps", "0.8,2"], "gap w / 2R = 2.0"),
        (["--radii", "5,x"], "--radii '5,x' is not a comma-separated list"),
        (["--only", "pivot"], "it belongs to 'study sensitivity' or 'study beyond'"),
    ],
)
def test_the_command_refuses_a_bad_grid_in_one_line(tmp_path, capsys, argv, words):
    code = main(["study", "constriction", "-o", str(tmp_path / "o"), *argv])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1


def test_grid_flags_belong_to_the_constriction_study(tmp_path, capsys):
    code = main(["study", "sensitivity", "-o", str(tmp_path / "o"), "--gaps", "0.8"])
    assert (
        code == 2
        and "--gaps does not belong to 'study sensitivity'; it belongs to 'study constriction'"
        in capsys.readouterr().err
    )


def test_a_small_study_end_to_end(tmp_path, capsys):
    out = tmp_path / "study"
    code = main(
        ["study", "constriction", "-o", str(out), "--radii", "5", "--gaps", "0.9,1.5"]
        + ["--realizations", "2", "--duration", "20", "--workers", "1", "--quiet"]
    )
    assert code == 0, capsys.readouterr().err
    result = json.loads((out / "constriction.json").read_text())
    assert result["design"]["gaps"] == [0.9, 1.5] and result["seed"] == 0
    assert (out / "constriction.png").stat().st_size > 10_000
    assert "| 5 | open | 15 |" in (out / "constriction.md").read_text()
    for p, point in enumerate(result["points"]):
        _, gate = channel(5.0, point["gap"])
        counts = []
        for r in range(2):
            with xr.open_dataset(out / "R5" / f"point{p:03d}_realization{r:04d}.nc") as ds:
                assert ds.attrs["parameter_obstacles"] == channel(5.0, point["gap"])[0]
                x = ds["cell_x"].values.reshape(-1)
                assert np.isclose(float(ds["time"][1] - ds["time"][0]), 0.1)
            counts.append(passages(x, gate))
        assert point["passages"] == counts
        assert point["rate"] == pytest.approx(100 * np.mean(counts) / 20.0)
        if sum(counts) == 0:  # the Poisson 95 % limit, -ln 0.05 / T
            assert point["rate_upper_95"] == pytest.approx(100 * 2.9957 / 40.0, rel=1e-4)
    # The same study again keeps every file and remakes the same summary.
    before = (out / "constriction.json").read_bytes()
    assert (
        main(
            [
                "study",
                "constriction",
                "-o",
                str(out),
                "--radii",
                "5",
                "--gaps",
                "0.9,1.5",
                "--realizations",
                "2",
                "--duration",
                "20",
                "--workers",
                "1",
                "--quiet",
            ]
        )
        == 0
    )
    assert (out / "constriction.json").read_bytes() == before
