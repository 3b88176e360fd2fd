"""The command line: plugins listing, parameter errors as one line with exit status 2."""

import shutil
import subprocess
import sys

import pytest

import softcell
from softcell.cli import main

PY = [sys.executable, "-m", "softcell"]


def test_plugins_lists_every_kind(capsys):
    from softcell.components.registry import KINDS

    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    kinds = (
        "energy_term",
        "driving_protocol",
        "friction_law",
        "integrator",
        "stopgo_detector",
        "pair_term",
        "bot_interaction",
    )
    assert sorted(KINDS.values()) == sorted(kinds)
    for kind in kinds:
        assert f"{kind} (" in out
    assert "threshold = 0.03 cm s-1" in out


def test_bad_parameter_is_one_line_and_status_2():
    run = subprocess.run([*PY, "params", "--radius", "2.5"], capture_output=True, text=True)
    assert run.returncode == 2
    assert run.stderr.strip() == (
        "softcell: error: parameter radius = 2.5 cm is not allowed: must be > bot_semi_major = 3 cm"
    )
    assert "Traceback" not in run.stderr


def test_config_file_and_flags(tmp_path, capsys):
    config = tmp_path / "run.toml"
    config.write_text("[parameters]\nradius = [4, 8]\ntension = 0.03\nthreshold = 0.3\n")
    assert main(["params", str(config), "--tension", "0.05"]) == 0
    out = capsys.readouterr().out
    assert "4, 8" in out and "0.05" in out and "# 2 parameter points" in out
    assert "0.3" in out.split("threshold")[1].splitlines()[0]
    config.write_text("[parameter]\nradius = 4\n")
    assert main(["params", str(config)]) == 2
    assert "unknown table [parameter] (did you mean 'parameters'?)" in capsys.readouterr().err
    config.write_text("radius = \n")
    assert main(["params", str(config)]) == 2
    assert "not valid TOML" in capsys.readouterr().err


def test_import_compiles_nothing_and_skips_heavy_modules():
    code = (
        "import sys, softcell; heavy = [m for m in ('numba', 'xarray', 'netCDF4', "
        "'matplotlib', 'cv2', 'dask') if m in sys.modules]; print(heavy)"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "[]"


def test_analyze_a_simulated_sweep(tmp_path, capsys):
    run = tmp_path / "run"
    assert (
        main(
            [
                "simulate",
                "--radius",
                "4,12",
                "--duration",
                "0.3",
                "--dt",
                "1e-5",
                "--cutoff",
                "4",
                "--nodes",
                "64",
                "--stored-nodes",
                "16",
                "--quiet",
                "-o",
                str(run),
            ]
        )
        == 0
    )
    out = tmp_path / "analysis.nc"
    for _ in range(2):  # the second time, its own earlier output is replaced
        assert main(["analyze", str(run), "-o", str(out), "--discard", "0.05", "--quiet"]) == 0
    assert "1 realization(s) at 2 radius" in capsys.readouterr().out
    # An analysis file inside a sweep directory is left out of the sweep; writing one there
    # is refused (it is inside an input), so it is placed there by hand.
    shutil.copy(out, run / "analysis.nc")
    assert (
        main(
            ["analyze", str(run), "-o", str(tmp_path / "again.nc"), "--discard", "0.05", "--quiet"]
        )
        == 0
    )
    assert "1 realization(s) at 2 radius" in capsys.readouterr().out
    result = softcell.open_dataset(out)
    assert list(result.radius.values) == [4.0, 12.0]
    assert result.msd.sel(body="bot").notnull().all()
    assert result.attrs["softcell_input_origin"] == "simulation"
    assert main(["analyze", str(run), "-o", str(out), "--discard", "-2"]) == 2
    assert "discard = -2.0 s is not allowed" in capsys.readouterr().err


def test_version_and_help_import_no_numba_xarray_or_registry():
    code = (
        "import sys\nfrom softcell.cli import main\n"
        "for argv in (['--version'], ['--help']):\n"
        "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
        "heavy = [m for m in ('numba', 'xarray', 'softcell.components.registry', 'scipy')"
        " if m in sys.modules]\nprint('HEAVY', heavy)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert f"softcell {softcell.__version__}" in run.stdout
    assert "HEAVY []" in run.stdout, run.stdout


def test_no_prefix_abbreviations(capsys):
    with pytest.raises(SystemExit) as stop:  # argparse's own exit, status 2
        main(["params", "--radiu", "4"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "unrecognized arguments: --radiu (did you mean '--radius'?)" in err


def test_component_flags_only_for_the_components_in_use(tmp_path, capsys):
    assert main(["params", "--atol", "1e-7"]) == 0  # rodas4, the default integrator
    assert "1e-07" in capsys.readouterr().out
    config = tmp_path / "explicit.toml"
    config.write_text('[components]\nintegrator = "explicit_euler"\n')
    assert main(["params", str(config), "--atol", "1e-7"]) == 2
    assert (
        capsys.readouterr()
        .err.strip()
        .startswith(
            "softcell: error: --atol is a parameter of integrator 'rodas4', which this run "
            "does not use (components:"
        )
    )
    assert (
        main(
            [
                "simulate",
                "--integrator",
                "explicit_euler",
                "--atol",
                "1e-7",
                "-o",
                str(tmp_path / "out"),
            ]
        )
        == 2
    )
    assert "--atol is a parameter of integrator 'rodas4'" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
    for argv, shown in (
        (["simulate", "--help"], True),
        (["simulate", "--integrator", "explicit_euler", "--help"], False),
    ):
        try:
            main(argv)
        except SystemExit as stop:
            assert stop.code == 0
        assert ("--atol" in capsys.readouterr().out) is shown


def test_every_example_of_the_top_level_help_is_a_valid_command_line():
    import shlex

    from softcell.cli import WORKFLOWS, parse_arguments

    examples = [
        line.strip().split("  (")[0]
        for line in WORKFLOWS.splitlines()
        if line.strip().startswith("softcell ")
    ]
    assert len(examples) == 14
    for example in examples:
        args = parse_arguments(shlex.split(example.replace("X0,Y0", "1.5,-2"))[1:])
        assert args.command == shlex.split(example)[1], example
