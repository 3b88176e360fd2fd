"""``softcell study crowding``: the grid's checks, the box of an area fraction, and a small
study end to end (slow)."""

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
from softcell.studies.crowding import (
    DISCARD,
    CrowdingDesign,
    box_side,
    crowding,
)

SMALL = CrowdingDesign("small", (5.0,), (0.5,), 4, 2, DISCARD + 31)


@pytest.mark.parametrize("cells,radius,fraction", [(16, 5.0, 0.35), (9, 10.0, 0.7), (4, 4.0, 0.1)])
def test_the_box_covers_the_area_fraction(cells, radius, fraction):
    side = box_side(cells, radius, fraction)
    assert cells * math.pi * radius**2 / side**2 == pytest.approx(fraction, rel=1e-12)


@pytest.mark.parametrize(
    "change,words",
    [
        ({"fractions": (0.3, 0.8)}, "crowding area fraction 0.8: must be in (0, 0.7854)"),
        ({"fractions": (0.0,)}, "crowding area fraction 0.0"),
        ({"cells": 8}, "crowding cells = 8: must be a square number >= 4"),
        ({"cells": 1}, "crowding cells = 1"),
        ({"realizations": 1}, "crowding realizations = 1: must be >= 2 for an error"),
        ({"duration": 40.0}, "crowding duration = 40.0 s: must exceed the discard"),
        ({"radii": (0.0,)}, "crowding radius 0.0 cm: must be > 0"),
        ({"fractions": ()}, "no radii or no area fractions"),
    ],
)
def test_a_grid_that_cannot_run_is_refused_before_anything_is_made(tmp_path, change, words):
    with pytest.raises(SoftcellError, match=re.escape(words)):
        crowding(tmp_path / "out", design=replace(SMALL, **change), workers=1)
    assert not (tmp_path / "out").exists()


def test_a_lattice_that_does_not_fit_its_box_is_refused_before_any_run(tmp_path):
    # R = 5 cm at an area fraction of 0.75: 16 rings 0.12 cm apart, under the study's gap.
    dense = replace(SMALL, cells=16, fractions=(0.1, 0.75))
    with pytest.raises(SoftcellError, match="cannot|gap"):
        crowding(tmp_path / "out", design=dense, workers=1)
    assert not list(tmp_path.glob("out/*/*.nc"))


@pytest.mark.parametrize(
    "argv,words",
    [
        (["--fractions", "0.3,0.9"], "crowding area fraction 0.9"),
        (["--gaps", "0.9"], "--gaps does not belong to 'study crowding'"),
        (["--cells", "10"], "crowding cells = 10"),
    ],
)
def test_the_command_refuses_a_bad_grid_in_one_line(tmp_path, capsys, argv, words):
    code = main(["study", "crowding", "-o", str(tmp_path / "o"), *argv])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_a_small_study_end_to_end(tmp_path):
    out = tmp_path / "study"
    crowding(out, design=SMALL, workers=1, progress=False, log=None)
    result = json.loads((out / "crowding.json").read_text())
    alone, crowd = result["points"]
    assert alone["fraction"] is None and crowd["fraction"] == 0.5
    # each point's values are the means over realizations analysed one by one
    for point, folder in ((alone, "R5_alone"), (crowd, "R5_phi0.5")):
        each = []
        for r in range(2):
            ds = softcell.open_dataset(out / folder / f"point000_realization{r:04d}.nc")
            if point is crowd:
                side = float(ds["domain_box"].values.reshape(-1)[0])
                assert side == pytest.approx(box_side(4, 5.0, 0.5))
            analysis = softcell.analyze(ds, {"discard": DISCARD})
            each.append(float(analysis["msd_slope"].sel(body="cell")))
        assert point["msd_slope_each"] == pytest.approx(each, rel=1e-12)
        assert point["msd_slope"] == pytest.approx(np.mean(each))
        assert point["msd_slope_sem"] == pytest.approx(np.std(each, ddof=1) / math.sqrt(2))
    assert (out / "crowding.png").stat().st_size > 10_000
    assert "| 5 | alone | - |" in (out / "crowding.md").read_text()


def test_a_summary_of_points_not_run_says_so(tmp_path):
    from softcell.studies.crowding import summarize

    summarize(tmp_path, SMALL, seed=0)
    result = json.loads((tmp_path / "crowding.json").read_text())
    assert [p.get("missing") for p in result["points"]] == [True, True]
    assert (
        "| 5 | 0.5 | 25.1 | not run | not run | not run |" in (tmp_path / "crowding.md").read_text()
    )
