"""One study protocol: every study is found by name and run through it, from Python and from
the command line (the studies' own physics is tested in their own files)."""

from __future__ import annotations

from pathlib import Path

import pytest

from softcell.cli import main
from softcell.errors import SoftcellError
from softcell.studies import WHERE, studies
from softcell.studies.protocol import GridStudy, Study, VariantStudy
from softcell.studies.variants import VariantDesign


def test_every_study_is_found_by_its_name_and_follows_the_protocol():
    found = studies()
    assert list(found) == [
        "sensitivity",
        "beyond",
        "constriction",
        "crowding",
        "strategies",
        "bots",
    ]
    for name, study in found.items():
        assert isinstance(study, Study) and study.name == name
        assert isinstance(study, VariantStudy) == (name in ("sensitivity", "beyond"))
        assert isinstance(study, GridStudy) == (name not in ("sensitivity", "beyond"))
        study.design(quick=False).check()
    assert set(WHERE) == set(found)


@pytest.fixture
def captured(monkeypatch):
    """Each variant study's comparison replaced by a record of what it was asked to run:
    (study, folder, its design's variants and base, the other options)."""
    from types import SimpleNamespace

    asked = []

    def recorder(name):
        def comparison(out, *, variants, base, **options):
            asked.append((name, out, SimpleNamespace(variants=variants, base=base), options))
            return out / f"{name}.md"

        return staticmethod(comparison)

    for study in studies().values():
        if isinstance(study, VariantStudy):
            monkeypatch.setattr(type(study), "comparison", recorder(study.name))
    return asked


def test_the_command_line_runs_a_variant_study_through_the_protocol(tmp_path, captured):
    assert main(["study", "beyond", "-o", str(tmp_path / "b"), "--only", "arena", "--quiet"]) == 0
    assert main(["beyond", "-o", str(tmp_path / "c"), "--seed", "3", "--quiet"]) == 0
    (name, out, some, options), (_, _, every, again) = captured
    assert name == "beyond" and out == tmp_path / "b"
    assert [v.name for v in some.variants] == ["viscous", "arena"]  # the reference first
    assert [v.name for v in every.variants] == [v.name for v in studies()["beyond"].variants]
    assert options["seed"] == 0 and again["seed"] == 3 and again["progress"] is False


def test_a_variant_study_takes_parameters_that_no_variant_sets(tmp_path, captured):
    study = studies()["sensitivity"]
    study.run(tmp_path, parameters={"sample_every": 0.02})
    (_, _, design, _) = captured[0]
    assert design.base.parameters["sample_every"] == 0.02
    assert "sample_every" not in study.base.parameters  # the study's base is untouched
    with pytest.raises(SoftcellError, match="'bending_stiffness' is set by the sensitivity"):
        study.run(tmp_path, parameters={"bending_stiffness": 0.1})


@pytest.mark.parametrize(
    "argv,words",
    [
        (["sensitivity", "--quick"], "--quick does not belong to 'study sensitivity'"),
        (["beyond", "--radii", "4"], "it belongs to 'study constriction' or 'study crowding'"),
        (["crowding", "--only", "k_0.18"], "it belongs to 'study sensitivity' or 'study beyond'"),
        (["beyond", "--only", "viscous"], "names no variant to compare with the viscous"),
        (["sensitivity", "--only", "arena"], "unknown variant(s) arena"),
    ],
)
def test_a_flag_of_another_study_is_refused_in_one_line(tmp_path, capsys, argv, words):
    code = main(["study", argv[0], "-o", str(tmp_path / "o"), *argv[1:]])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_a_variant_design_compares_something():
    one = studies()["beyond"].variants[:1]
    with pytest.raises(SoftcellError, match="compares at least one variant"):
        VariantDesign("one", one, studies()["beyond"].base).check()


def test_the_help_of_only_names_every_variant_of_both_variant_studies():
    from softcell.cli.studies import DESIGN_FLAGS

    help = DESIGN_FLAGS["only"][1]
    for study in studies().values():
        if isinstance(study, VariantStudy):
            assert all(v.name in help for v in study.variants[1:]), study.name


def _redraw_records():
    import importlib.util

    spec = importlib.util.spec_from_file_location("redraw", DOCS_DIR / "redraw.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.RECORDS


DOCS_DIR = Path(__file__).parents[1] / "docs"


@pytest.mark.parametrize("record", sorted(_redraw_records()))
def test_a_study_figure_redrawn_from_its_record_can_be_read(record, tmp_path, monkeypatch):
    """Each committed study figure, drawn again from its record (docs/redraw.py), has no
    text under 9 px at a docs page's width."""
    import json

    from readable import unreadable

    import softcell.studies.figures as figures

    saved = []
    monkeypatch.setattr(figures, "_save", lambda fig, path, dpi: saved.append((fig, dpi)))
    name = json.loads((DOCS_DIR / record).read_text())["study"]
    studies()[name].redraw(DOCS_DIR / record, tmp_path / "figure.png")
    assert len(saved) == 1
    fig, dpi = saved[0]
    assert not unreadable(record, fig, dpi, where={"docs page": (800, None)})


def test_a_record_of_another_study_is_not_redrawn(tmp_path):
    with pytest.raises(SoftcellError, match="record of study 'strategies', not 'crowding'"):
        studies()["crowding"].redraw(DOCS_DIR / "strategies/strategies.json", tmp_path / "x.png")


def test_the_beyond_figures_redrawn_from_their_record_can_be_read(tmp_path, monkeypatch):
    import json

    from readable import unreadable

    import softcell.studies.figures as figures
    from softcell.studies.friction_and_arena import FREE_LONG, VARIANTS

    saved = []
    monkeypatch.setattr(figures, "_save", lambda fig, path, dpi: saved.append((fig, dpi)))
    results = json.loads((DOCS_DIR / "beyond" / "beyond.json").read_text())
    names = figures.friction_figures(tmp_path, VARIANTS, results, FREE_LONG[1])
    assert names == ["friction.png", "arena.png"] and len(saved) == 2
    for name, (fig, dpi) in zip(names, saved, strict=True):
        assert not unreadable(name, fig, dpi, where={"docs page": (800, None)})
