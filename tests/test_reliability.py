"""Faults a careful and slightly hostile user met, each a test first: one line and exit 2
from the command line, the package's own error naming the argument from the library, and
nothing touched that softcell did not make."""

import os
from pathlib import Path

import numpy as np
import pytest

import softcell
from softcell.cli import main
from softcell.core.params import Parameters
from softcell.errors import ConfigError, ParameterError, SoftcellError


def one_line_exit_2(argv, capsys):
    status = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2, err
    assert len(err) == 1 and err[0].startswith("softcell: error: "), err
    return err[0]


@pytest.fixture()
def configs(tmp_path):
    latin = tmp_path / "latin.toml"
    latin.write_bytes("[parameters]\n# r\xe9glage\nradius = 4\n".encode("latin-1"))
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    locked = tmp_path / "locked.toml"
    locked.write_text("[parameters]\nradius = 4\n")
    locked.chmod(0)
    yield {"latin": latin, "folder": folder, "locked": locked}
    locked.chmod(0o644)


@pytest.mark.parametrize("command", ["simulate", "params"])
@pytest.mark.parametrize(
    ("which", "words"),
    [
        ("latin", "not a text file in UTF-8 (byte 16); TOML files are UTF-8"),
        ("folder", "is a directory, not a configuration file"),
        ("locked", "permission denied (the file is not readable)"),
    ],
)
def test_a_configuration_file_that_cannot_be_read_is_one_line(
    configs, tmp_path, capsys, monkeypatch, command, which, words
):
    if which == "locked" and os.access(configs["locked"], os.R_OK):  # root reads mode 000
        real = Path.read_text

        def refuse(self, *args, **kwargs):
            if self == configs["locked"]:
                raise PermissionError(13, "Permission denied", str(self))
            return real(self, *args, **kwargs)

        monkeypatch.setattr(Path, "read_text", refuse)
    argv = [command, str(configs[which])] + (
        ["-o", str(tmp_path / "out")] if command == "simulate" else []
    )
    line = one_line_exit_2(argv, capsys)
    assert words in line and str(configs[which]) in line
    assert not (tmp_path / "out").exists()


def test_render_refuses_a_negative_seed_before_reading_anything(tmp_path, capsys):
    line = one_line_exit_2(
        ["render", str(tmp_path / "nothing.nc"), "-o", str(tmp_path / "v.mp4"), "--seed", "-1"],
        capsys,
    )
    assert "seed = -1 is not allowed: must be an integer between 0 and 2**64 - 1" in line


def test_render_seed_is_checked_by_the_library(tmp_path):
    from softcell.io.render import render

    with pytest.raises(SoftcellError, match="seed = -1 is not allowed"):
        render(None, tmp_path / "v.mp4", seed=-1)


def test_numpy_scalars_are_parameter_values():
    p = Parameters({"radius": np.float32(8), "cutoff": np.int64(8), "duration": np.float64(2)})
    assert (p.radius, p.cutoff, p.duration) == (8.0, 8, 2.0)
    assert isinstance(p.cutoff, int) and isinstance(p.radius, float)
    with pytest.raises(ParameterError, match="radius"):
        Parameters({"radius": np.True_})


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (
            lambda tmp: softcell.simulate({"radius": 4}, tmp),
            "simulate: config is a dict, not a RunConfig",
        ),
        (lambda tmp: softcell.analyze(None), "analyze: ds is a NoneType, not an xarray.Dataset"),
        (lambda tmp: softcell.write_dataset(None, tmp / "x.nc"), "write_dataset: ds is a NoneType"),
    ],
)
def test_the_library_names_a_wrong_argument(tmp_path, call, words):
    with pytest.raises(ConfigError, match=words):
        call(tmp_path)
    assert not (tmp_path / "x.nc").exists()


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (
            ["params", "--radius", "8,8"],
            "parameter 'radius' is swept over ['8', '8'] with 8.0 twice",
        ),
        (["params", "--radius", "8,8.0"], "with 8.0 twice"),
        (
            ["params", "--integrator", "explicit_euler", "--dt", "1"],
            "parameter dt = 1.0 s is not allowed: must divide sample_every = 0.01 s",
        ),
        (["calibrate", "--push-speed", "0.1", "--radius", "4", "--workers", "0"], "--workers = 0"),
        (["study", "sensitivity", "-o", "S", "--only", ","], "names no variant to compare"),
    ],
)
def test_requests_refused_before_computing(tmp_path, capsys, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    line = one_line_exit_2(argv, capsys)
    assert words in line, line
    assert list(tmp_path.iterdir()) == []


def test_an_output_reached_through_a_link_into_the_input_is_refused(tmp_path, capsys):
    source = tmp_path / "run"
    source.mkdir()
    (source / "point000_realization0000.nc").write_bytes(b"")
    (tmp_path / "link").symlink_to(source)
    line = one_line_exit_2(["analyze", str(source), "-o", str(tmp_path / "link" / "an.nc")], capsys)
    assert "is inside the input directory" in line
    assert sorted(p.name for p in source.iterdir()) == ["point000_realization0000.nc"]


COARSE = ["--cutoff", "4", "--nodes", "64", "--stored-nodes", "16", "--integrator",
          "explicit_euler", "--dt", "1e-5", "--quiet"]  # fmt: skip


@pytest.fixture(scope="module")
def two_sweeps(tmp_path_factory):
    root = tmp_path_factory.mktemp("sweeps")
    for name, extra in (("a", ["--seed", "3", "--duration", "0.3"]),
                        ("b", ["--seed", "5", "--duration", "0.2"]),
                        ("c", ["--seed", "3", "--duration", "0.2"])):  # fmt: skip
        assert main(["simulate", "--radius", "4,5", *COARSE, *extra, "-o", str(root / name)]) == 0
    return root


@pytest.mark.parametrize(
    ("pair", "words"),
    [
        (("a", "b"), "are not one sweep: softcell_seed = 3 there, 5 here"),
        (("a", "c"), "parameter duration differs between them"),
    ],
)
def test_unrelated_sweeps_are_not_merged(two_sweeps, tmp_path, capsys, pair, words):
    inputs = [str(two_sweeps / p) for p in pair]
    line = one_line_exit_2(["analyze", *inputs, "-o", str(tmp_path / "an.nc")], capsys)
    assert words in line, line
    assert not (tmp_path / "an.nc").exists()


def test_one_sweep_still_combines(two_sweeps, tmp_path, capsys):
    from softcell.io.netcdf import open_inputs

    ds = open_inputs([two_sweeps / "a"])
    assert ds.sizes["radius"] == 2


@pytest.mark.parametrize(
    ("flags", "blamed"),
    [(["--stored-nodes", "1e8"], "stored_nodes"), (["--duration", "1e9"], "duration")],
)
def test_a_realization_too_large_for_memory_blames_the_parameter_out_of_the_ordinary(
    capsys, flags, blamed
):
    line = one_line_exit_2(["params", *flags], capsys)
    assert line.startswith(f"softcell: error: parameter {blamed} = "), line
    assert "of memory, more than 50% of this machine's" in line


def test_an_ensemble_that_cannot_fit_on_the_disk_is_refused_before_planning(tmp_path, capsys):
    # Refused from the sizes alone: making 1e8 tasks first took minutes and the memory.
    line = one_line_exit_2(
        ["simulate", "--realizations", "100000000", "-o", str(tmp_path / "big")], capsys
    )
    assert "no space left on device (the run needs about" in line and " PiB, " in line
    assert not (tmp_path / "big").exists()
