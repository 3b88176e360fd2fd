"""``softcell study strategies``: the grid's checks, the softness ratio, and a small study end
to end (slow)."""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace

import numpy as np
import pytest

import softcell
from softcell.cli import main
from softcell.errors import SoftcellError
from softcell.studies.locomotion import (
    DISCARD,
    StrategiesDesign,
    softness_ratios,
    strategies,
)

SMALL = StrategiesDesign("small", ("run_and_tumble", "bump_and_turn"), (4.0, 5.0), 2, DISCARD + 35)


@pytest.mark.parametrize(
    "change,words",
    [
        ({"strategies": ()}, "must be non-empty and each named once"),
        ({"strategies": ("chiral", "chiral")}, "must be non-empty and each named once"),
        ({"radii": (4.0,)}, "strategies radii [4.0]: give at least two"),
        ({"radii": (4.0, -1.0)}, "strategies radius -1.0 cm: must be > 0"),
        ({"realizations": 1}, "strategies realizations = 1: must be >= 2 for an error"),
        ({"duration": 40.0}, "strategies duration 40.0 s: must be > 45 s"),
    ],
)
def test_a_grid_that_cannot_run_is_refused_before_anything_is_made(tmp_path, change, words):
    with pytest.raises(SoftcellError, match=re.escape(words)):
        strategies(tmp_path / "out", design=replace(SMALL, **change), workers=1)
    assert not (tmp_path / "out").exists()


def test_an_unknown_strategy_is_refused_before_any_run(tmp_path):
    with pytest.raises(SoftcellError, match="bump_and_run"):
        strategies(
            tmp_path / "out", design=replace(SMALL, strategies=("graspion", "bump_and_run")),
            workers=1,
        )  # fmt: skip
    assert not list(tmp_path.glob("out/*/*.nc"))


@pytest.mark.parametrize(
    "argv,words",
    [
        (["--strategies", "chiral", "--radii", "5"], "give at least two"),
        (["--gaps", "0.9"], "--gaps does not belong to 'study strategies'"),
        (["--realizations", "1"], "strategies realizations = 1"),
    ],
)
def test_the_command_refuses_a_bad_grid_in_one_line(tmp_path, capsys, argv, words):
    code = main(["study", "strategies", "-o", str(tmp_path / "o"), *argv])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1


def test_the_softness_ratio_propagates_both_errors():
    points = [
        {"strategy": "a", "radius": 4.0, "msd_slope": 2.0, "msd_slope_sem": 0.2},
        {"strategy": "a", "radius": 5.0, "msd_slope": 1.0, "msd_slope_sem": 0.05},
        {"strategy": "b", "radius": 4.0, "missing": True},
    ]
    design = replace(SMALL, strategies=("a", "b"))
    ratios = softness_ratios(points, design)
    assert list(ratios) == ["a"]
    assert ratios["a"]["ratio"] == 0.5
    assert ratios["a"]["sem"] == pytest.approx(0.5 * math.hypot(0.1, 0.05), rel=1e-12)


@pytest.mark.slow
def test_a_small_study_end_to_end(tmp_path):
    out = tmp_path / "study"
    strategies(out, design=SMALL, workers=1, progress=False, log=None)
    result = json.loads((out / "strategies.json").read_text())
    assert [(p["strategy"], p["radius"]) for p in result["points"]] == [
        ("run_and_tumble", 4.0), ("run_and_tumble", 5.0), ("bump_and_turn", 4.0),
        ("bump_and_turn", 5.0),
    ]  # fmt: skip
    for point in result["points"]:
        folder = out / f"{point['strategy']}_R{point['radius']:g}"
        each = []
        for r in range(2):
            ds = softcell.open_dataset(folder / f"point000_realization{r:04d}.nc")
            assert ds.attrs["softcell_components"].count(point["strategy"]) == 1
            assert ("event_time" in ds) == (point["strategy"] == "bump_and_turn")
            analysis = softcell.analyze(ds, {"discard": DISCARD})
            each.append(float(analysis["mean_stop_duration"].sel(body="cell")))
        assert point["mean_stop_duration_each"] == pytest.approx(each, rel=1e-12)
        assert point["mean_stop_duration"] == pytest.approx(np.mean(each))
    assert set(result["softness"]) == {"run_and_tumble", "bump_and_turn"}
    assert (out / "strategies.png").stat().st_size > 10_000
    assert "| bump_and_turn | 5 |" in (out / "strategies.md").read_text()
