"""``softcell study sensitivity`` on a small design: every variant runs from one seed, the
summary says which findings each flips, and a rerun keeps what finished."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

import softcell
from softcell.cli import main
from softcell.errors import SoftcellError
from softcell.studies.sensitivity import (
    BASE,
    STUDY,
    VARIANTS,
    candidates,
    crossing,
    flips,
    sensitivity,
)

SMALL = replace(
    BASE, radii=(4.0, 12.0), realizations=2, duration=20.0, free_bot_realizations=2, discard=5.0
)


def test_crossing_interpolates_between_radii():
    radii = np.array([4.0, 5.0, 6.0, 7.0])
    assert crossing(radii, np.array([0.2, 0.3, 0.4, 0.6]), 0.35) == pytest.approx(5.5)
    assert crossing(radii, np.array([0.2, 0.3, 0.4, 0.6]), 0.5) == pytest.approx(6.5)
    assert crossing(radii, np.array([0.6, 0.7, 0.8, 0.9]), 0.35) == 4.0
    assert math.isnan(crossing(radii, np.array([0.1, 0.2, 0.2, 0.3]), 0.35))


def _result(verdicts, **facts):
    base = {
        "free_bot_run_speed": 15.0,
        "length_deviation": 2e-4,
        "regime_at_4": "coupled",
        "regime_at_12": "decoupled",
    }
    return {"verdicts": verdicts, "facts": {**base, **facts}}


def test_flips_and_candidates_follow_their_rules():
    variants = STUDY.named(["k_0.18", "pivot", "coulomb"])
    results = {
        "default": _result({"a": "agrees", "b": "differs", "c": "differs"}),
        "k_0.18": _result({"a": "agrees", "b": "agrees", "c": "differs"}),  # strictly more
        "pivot": _result({"a": "differs", "b": "agrees", "c": "agrees"}),  # loses a
        "coulomb": _result(
            {"a": "agrees", "b": "agrees", "c": "agrees"}, regime_at_12="intermediate"
        ),  # breaks a stated fact
    }
    assert flips(results, variants) == {
        "a": {"pivot": "differs"},
        "b": {"k_0.18": "agrees", "pivot": "agrees", "coulomb": "agrees"},
        "c": {"pivot": "agrees", "coulomb": "agrees"},
    }
    assert candidates(results, variants) == ["k_0.18"]


def test_the_variants_move_one_unknown_each():
    names = [v.name for v in VARIANTS]
    assert names[0] == "default" and len(set(names)) == len(names)
    unknowns = [v.unknown for v in VARIANTS[1:]]
    assert sorted(set(unknowns)) == [
        "bot",
        "cutoff",
        "force",
        "friction",
        "gamma_mem",
        "k",
        "lambda",
        "rotation",
        "rotation and friction",
        "torque",
        "torque and k",
    ]
    owns = {
        "bot": {"bot_semi_major", "bot_semi_minor"},
        "k": {"bending_stiffness"},
        "cutoff": {"cutoff"},
        "lambda": {"contact_length"},
        "rotation": {"driving_protocol"},
        "friction": {"friction_law", "membrane_static_friction", "static_friction_width"},
        "gamma_mem": {"membrane_friction"},
        "torque": {"drive_torque", "bot_rotational_friction"},
        "torque and k": {"drive_torque", "bot_rotational_friction", "bending_stiffness"},
        "force": {"drive_force", "bot_friction"},
        "rotation and friction": {
            "driving_protocol",
            "friction_law",
            "membrane_static_friction",
            "static_friction_width",
        },
    }
    for v in VARIANTS[1:]:  # what a variant sets belongs to its unknown alone
        assert set(v.parameters) | set(v.components) <= owns[v.unknown]
    with pytest.raises(SoftcellError, match="unknown variant"):
        STUDY.named(["k_0.5"])


@pytest.mark.slow
def test_small_study_runs_resumes_and_summarizes(tmp_path):
    out = tmp_path / "study"
    variants = STUDY.named(["k_0.18"])
    lines: list[str] = []
    report = sensitivity(
        out, variants=variants, base=SMALL, workers=2, progress=False, log=lines.append
    )
    summary = json.loads((out / "sensitivity.json").read_text())
    assert summary["seed"] == 0 and list(summary["variants"]) == ["default", "k_0.18"]
    default = summary["variants"]["default"]
    # The free bot's runs go at F0 / gamma_T = 15 cm/s exactly (docs/model.md §2).
    assert default["facts"]["free_bot_run_speed"] == pytest.approx(15.0, rel=1e-6)
    # Common random numbers: every variant's realization r drew the same schedule.
    phases = [
        softcell.open_dataset(out / v / "simulations")["bot_phase"].isel(time=slice(0, 50))
        for v in ("default", "k_0.18")
    ]
    assert np.array_equal(phases[0].values, phases[1].values)
    # A softer membrane deforms more: the IPR excess grows at every radius.
    circle = 2 * math.sqrt(math.pi)
    soft = np.array(summary["variants"]["k_0.18"]["ipr"]["value"]) - circle
    stiff = np.array(default["ipr"]["value"]) - circle
    assert np.all(soft > 1.5 * stiff) and np.all(stiff > 0)
    # The per-realization spread is the standard error of the realizations' own means.
    sims = softcell.open_dataset(out / "default" / "simulations")
    keep = sims["time"].values >= 5.0
    gap = np.hypot(sims["bot_x"] - sims["cell_x"], sims["bot_y"] - sims["cell_y"]).values
    each = gap[..., keep].mean(axis=-1) / np.array([4.0, 12.0])[:, None]
    assert default["gc_distance_ratio"]["sem"] == pytest.approx(
        list(each.std(axis=1, ddof=1) / np.sqrt(2)), rel=1e-9
    )
    text = report.read_text()
    for heading in (
        "The findings per variant",
        "Which variants flip a verdict",
        "The paper's stated facts per variant",
        "Regime boundaries",
    ):
        assert heading in text
    assert (out / "figures" / "sensitivity.png").stat().st_size > 10_000
    assert (out / "figures" / "verdicts.png").stat().st_size > 5_000
    # A rerun keeps the finished variants and redoes only the summary.
    lines.clear()
    before = (out / "k_0.18" / "analysis.nc").stat().st_mtime_ns
    sensitivity(out, variants=variants, base=SMALL, workers=2, progress=False, log=lines.append)
    assert sum("finished, kept" in line for line in lines) == 2
    assert (out / "k_0.18" / "analysis.nc").stat().st_mtime_ns == before


def test_the_command_refuses_an_unknown_variant(tmp_path, capsys):
    assert main(["study", "sensitivity", "-o", str(tmp_path / "s"), "--only", "k_9"]) == 2
    assert "unknown variant(s) k_9" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()
