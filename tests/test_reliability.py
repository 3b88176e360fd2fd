"""Faults a careful and slightly hostile user met, each a test first: one line and exit 2
from the command line, the package's own error naming the argument from the library, and
nothing touched that softcell did not make."""

import json
import os
import re
import signal
import subprocess
import sys
import time
from contextlib import suppress
from pathlib import Path

import numpy as np
import pytest

import softcell
from softcell.cli import main
from softcell.errors import ConfigError, ParameterError, SoftcellError
from softcell.model.parameters import Parameters


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


def test_a_configuration_file_with_a_byte_order_mark_is_read(tmp_path, capsys):
    # Before: "not valid TOML: Invalid statement (at line 1, column 1)" (Notepad's UTF-8).
    config = tmp_path / "bom.toml"
    config.write_bytes(b"\xef\xbb\xbf[parameters]\nradius = 5.5\n")
    assert main(["params", str(config)]) == 0
    assert re.search(r"^radius\s+5\.5\s+cm", capsys.readouterr().out, re.MULTILINE)


@pytest.mark.parametrize(
    ("given", "words"),
    [
        # before: "parameter radius = '8cm' cm is not allowed: must be > 0 cm"
        (
            ["--radius", "8cm"],
            "radius = '8cm' is not allowed: it is not a number: write "
            "radius as a plain number in cm, without its unit (must be > 0 cm)",
        ),
        ('radius = "five"', "radius = 'five' is not allowed: it is not a number"),
        # before: "parameter obstacles = 5 cm is not allowed: must be any finite value cm"
        ("radius = 5\nobstacles = 5", "obstacles = 5 is not allowed: must be text, in quotes"),
    ],
)
def test_a_value_of_the_wrong_type_says_what_is_meant(tmp_path, capsys, given, words):
    argv = ["simulate", "-o", str(tmp_path / "out")]
    if isinstance(given, str):
        config = tmp_path / "run.toml"
        config.write_text(f"[parameters]\n{given}\n", encoding="utf-8")
        argv.insert(1, str(config))
    else:
        argv += given
    line = one_line_exit_2(argv, capsys)
    assert words in line, line


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
    from softcell.video.render import render

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
        # before: the study marked S as its own (study.json) and refused a rerun with
        # another seed, though nothing was computed
        (["study", "constriction", "-o", "S", "--workers", "0"], "--workers = 0 is not allowed"),
        # before: 1000 local workers started (493 tracebacks, deaf to SIGTERM)
        (["simulate", "--radius", "4", "-o", "S", "--workers", "1000"], "(4 per core)"),
        (["study", "constriction", "-o", "S", "--workers", "1000"], "(4 per core)"),
        (["reproduce", "--quick", "-o", "S", "--workers", "1000"], "(4 per core)"),
        (["calibrate", "--push-speed", "0.1", "--workers", "1000"], "(4 per core)"),
        (["simulate", "--radius", "4", "-o", "S", "--workers", "two"], "not a whole number"),
        # before: ran, with positions at 2.5e11 cm and a ring's roundness 1e-5 (not 1e-14)
        (
            ["simulate", "--radius", "4", "-o", "S", "--cells", "2", "--box", "1e12"],
            "at most 1e+06 cm for boundary periodic",
        ),
        # before: ZeroDivisionError, a math domain error, a 14.6 TiB allocation
        *(
            (
                ["simulate", "--radius", "4", "-o", "S", "--protocol", "active_brownian"]
                + ["--noise-interval", value],
                f"noise_interval = {value} s is not allowed: must be >= 0.001 s",
            )
            for value in ("0.0", "-0.05", "1e-12")
        ),
        # before: accepted (bump_and_turn's bot never ran; graspion turned backwards)
        (
            ["simulate", "--radius", "4", "-o", "S", "--protocol", "bump_and_turn"]
            + ["--contact-threshold", "0"],
            "contact_threshold = 0.0 N is not allowed: must be > 0 N",
        ),
        (
            ["simulate", "--radius", "4", "-o", "S", "--protocol", "graspion", "--turn-rate", "-3"],
            "turn_rate = -3.0 rad s-1 is not allowed: must be > 0 rad s-1",
        ),
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


# -- a file damaged on disk is named and recomputed, never trusted --------------------------


@pytest.fixture()
def one_run(tmp_path):
    out = tmp_path / "run"
    assert main(["simulate", "--radius", "4", "--duration", "0.2", *COARSE, "-o", str(out)]) == 0
    path = out / "point000_realization0000.nc"
    return out, path, path.read_bytes()


def damage_data(path: Path) -> None:
    """Flip 400 bytes of ``path`` past its header, where the file still opens and its request
    still reads: the damage a rerun used to trust."""
    from softcell.runner.resume import stored_request

    clean = path.read_bytes()
    for start in range(len(clean) // 2, len(clean) - 400, 97):
        bad = bytearray(clean)
        bad[start : start + 400] = bytes(b ^ 0xFF for b in bad[start : start + 400])
        path.write_bytes(bytes(bad))
        try:
            stored_request(path)
        except SoftcellError:
            continue
        return
    pytest.fail(f"no 400 bytes of {path} could be flipped with its header intact")


def change_one_value(path: Path) -> None:
    """Rewrite one stored number in place (a silent change no decompression notices)."""
    import netCDF4

    with netCDF4.Dataset(path, "r+") as nc:
        nc["bot_x"][0, 1] = nc["bot_x"][0, 1] + 1.0


@pytest.mark.parametrize("harm", [damage_data, change_one_value])
@pytest.mark.parametrize("flags", [[], ["--overwrite"]])
def test_a_damaged_file_is_named_and_recomputed_by_a_rerun(one_run, capsys, harm, flags):
    from softcell.io.netcdf import data_problem

    out, path, clean = one_run
    assert data_problem(path) is None
    harm(path)
    assert data_problem(path) is not None
    argv = ["simulate", "--radius", "4", "--duration", "0.2", *COARSE, "-o", str(out), *flags]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert f"{path} was made for this request but it" in err and "recomputing it" in err, err
    assert path.read_bytes() == clean


def test_analyze_names_the_damaged_file(one_run, tmp_path, capsys):
    out, path, _ = one_run
    damage_data(path)
    argv = ["analyze", str(out), "--discard", "0.05", "--quiet", "-o", str(tmp_path / "an.nc")]
    line = one_line_exit_2(argv, capsys)
    assert line.startswith(f"softcell: error: {path}: it cannot be read in full"), line
    assert not (tmp_path / "an.nc").exists()


def test_a_file_without_a_checksum_is_still_read_in_full(one_run, tmp_path):
    import netCDF4

    from softcell.io.netcdf import CHECKSUM, data_problem

    _, path, _ = one_run
    with netCDF4.Dataset(path, "r+") as nc:  # as softcell 0.2.0 wrote it
        nc.delncattr(CHECKSUM)
    assert data_problem(path) is None
    damage_data(path)
    assert "cannot be read in full" in data_problem(path)


def test_the_checksum_is_no_attribute_of_the_data(one_run, tmp_path):
    from softcell.io.netcdf import CHECKSUM, read_dataset, write_dataset

    _, path, clean = one_run
    ds = read_dataset(path)
    assert CHECKSUM not in ds.attrs
    write_dataset(ds, tmp_path / "again.nc")
    assert (tmp_path / "again.nc").read_bytes() == clean


def flip_one_time_bit(path: Path) -> None:
    """One bit of one sample time flipped in place (the time axis is stored uncompressed)."""
    import netCDF4

    with netCDF4.Dataset(path, "r+") as nc:
        value = np.array(nc["time"][2], dtype=np.float64)
        nc["time"][2] = (value.view(np.uint64) ^ np.uint64(1 << 40)).view(np.float64)


def move_the_cell(path: Path) -> None:
    """``cell_x`` edited by +1000 cm, the checksum left as it was."""
    import netCDF4

    with netCDF4.Dataset(path, "r+") as nc:
        nc["cell_x"][...] = nc["cell_x"][...] + 1000.0


def rewritten(path: Path, change) -> None:
    """``path`` read, changed by ``change`` and written again by softcell (a fresh checksum)."""
    from softcell.io.netcdf import read_dataset, write_dataset

    ds = change(read_dataset(path))
    path.unlink()
    write_dataset(ds, path)


def newer_version(path: Path) -> None:
    rewritten(path, lambda ds: ds.assign_attrs(softcell_version="999"))


def no_cell(path: Path) -> None:
    rewritten(path, lambda ds: ds.assign(cell_x=ds["cell_x"] * np.nan))


def dropped_variable(path: Path) -> None:
    rewritten(path, lambda ds: ds.drop_vars("bot_angle"))


READERS = {
    "analyze": lambda out, tmp: ["analyze", str(out), "--discard", "0.05", "--quiet",
                                 "-o", str(tmp / "an.nc")],
    "export": lambda out, tmp: ["export", str(out), "-o", str(tmp / "poses.nc")],
    "animate": lambda out, tmp: ["animate", str(out), "--quiet", "-o", str(tmp / "film.gif")],
}  # fmt: skip


@pytest.mark.parametrize("reader", sorted(READERS))
@pytest.mark.parametrize(
    ("harm", "words"),
    [
        (flip_one_time_bit, "its contents do not match their checksum"),
        (move_the_cell, "its contents do not match their checksum"),
        (newer_version, "softcell 999 wrote it, newer than this softcell"),
        (no_cell, "cell_x holds no value (all NaN)"),
        (dropped_variable, "it does not follow the simulation schema (bot_angle: missing)"),
    ],
)
def test_readers_check_what_they_read(one_run, tmp_path, capsys, reader, harm, words):
    out, path, _ = one_run
    harm(path)
    line = one_line_exit_2(READERS[reader](out, tmp_path), capsys)
    assert line.startswith(f"softcell: error: {path}: {words}"), line
    assert "recompute it" in line, line
    assert not any(p.name.startswith(("an.", "poses.", "film.")) for p in tmp_path.iterdir())


def test_no_verify_reads_a_file_as_it_is(one_run, tmp_path):
    import xarray as xr

    out, path, _ = one_run
    move_the_cell(path)
    assert main([*READERS["export"](out, tmp_path), "--no-verify"]) == 0
    with xr.open_dataset(tmp_path / "poses.nc") as poses:
        assert float(poses["position"].max()) > 900.0  # the edited cell, as it is


def test_a_rerun_names_the_checksum_of_a_damaged_time_axis(one_run, capsys):
    out, path, clean = one_run
    flip_one_time_bit(path)
    argv = ["simulate", "--radius", "4", "--duration", "0.2", *COARSE, "-o", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "do not match their checksum" in err and "incomplete" not in err, err
    assert path.read_bytes() == clean


@pytest.mark.parametrize("reader", sorted(READERS))
def test_readers_refuse_a_folder_being_written(one_run, tmp_path, capsys, reader):
    from softcell.io.files import folder_lock

    out, _, _ = one_run
    with folder_lock(out, "softcell simulate"):
        line = one_line_exit_2(READERS[reader](out, tmp_path), capsys)
    assert f"{out} is being written by softcell simulate (pid {os.getpid()}" in line, line
    assert "wait for it to end" in line, line
    assert main(READERS[reader](out, tmp_path)) == 0  # once it ends, the folder reads


# -- one writer per output folder; signals; renders that cannot end ------------------------


PY = [sys.executable, "-m", "softcell"]
#: Two points of a short coarse run: what a test of the command line needs to be cheap.
SMALL_RUN = ["--radius", "4,8", "--duration", "0.5", "--quiet"]


def _start(argv: list[str]) -> subprocess.Popen:
    return subprocess.Popen(
        [*PY, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True,
    )  # fmt: skip


def _wait_for(path: Path, process: subprocess.Popen) -> None:
    deadline = time.monotonic() + 300
    while not path.exists():
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.05)


def test_a_second_writer_of_one_folder_is_refused_while_the_first_runs(tmp_path):
    from softcell.io.files import LOCK_FILE

    out = tmp_path / "run"
    first = _start(["simulate", "--radius", "4", "--duration", "30", *COARSE, "-o", str(out)])
    try:
        _wait_for(out / LOCK_FILE, first)
        second = subprocess.run(
            [*PY, "simulate", "--radius", "5", "--duration", "0.2", *COARSE, "-o", str(out)],
            capture_output=True,
            text=True,
        )
        assert first.poll() is None, "the first run ended before the second was tried"
    finally:
        os.killpg(first.pid, signal.SIGINT)
        first.communicate(timeout=120)
    lines = second.stderr.strip().splitlines()
    assert second.returncode == 2 and len(lines) == 1, second.stderr
    assert lines[0].startswith(
        f"softcell: error: {out} is being written by softcell simulate (pid {first.pid} on "
    ), lines[0]
    assert first.returncode == 130
    assert not list(out.glob("*.nc")) and not (out / LOCK_FILE).exists()


def test_a_lock_is_never_stale(tmp_path):
    from softcell.io.files import LOCK_FILE

    out = tmp_path / "run"
    first = _start(["simulate", "--radius", "4", "--duration", "30", *COARSE, "-o", str(out)])
    _wait_for(out / LOCK_FILE, first)
    os.killpg(first.pid, signal.SIGKILL)  # no cleanup at all: the file stays, the lock not
    first.communicate(timeout=60)
    assert (out / LOCK_FILE).exists()
    argv = ["simulate", "--radius", "4", "--duration", "0.2", *COARSE, "-o", str(out)]
    assert main([*argv, "--overwrite"]) == 0
    assert not (out / LOCK_FILE).exists()


def test_one_process_holds_a_folder_once(tmp_path):
    from softcell.io.files import folder_lock

    with folder_lock(tmp_path, "softcell simulate"):
        with pytest.raises(
            SoftcellError, match=f"is being written by softcell simulate \\(pid {os.getpid()}"
        ):
            with folder_lock(tmp_path, "softcell simulate"):
                pass
    with folder_lock(tmp_path, "softcell simulate"):  # released
        pass
    assert list(tmp_path.iterdir()) == []


def test_a_refused_simulation_leaves_no_folder(tmp_path, capsys):
    out = tmp_path / "a" / "b" / "run"
    line = one_line_exit_2(
        ["simulate", "--radius", "4", *COARSE, "--scheduler", "tcp://127.0.0.1:9", "-o", str(out)],
        capsys,
    )
    assert "cannot reach the dask scheduler" in line
    assert list(tmp_path.iterdir()) == []


def test_sigterm_stops_a_render_without_leaving_its_temporary_file(one_run, tmp_path):
    out, _, _ = one_run
    video = tmp_path / "v.mkv"
    render = _start(
        ["render", str(out), "--fps", "20000", "--px-per-cm", "40", "--quiet", "-o", str(video)]
    )
    deadline = time.monotonic() + 300
    while not list(tmp_path.glob(".v.*.tmp.mkv")):
        assert render.poll() is None, render.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.05)
    time.sleep(0.3)
    assert render.poll() is None, "the render ended before it could be stopped"
    os.killpg(render.pid, signal.SIGTERM)
    _, err = render.communicate(timeout=120)
    lines = err.strip().splitlines()
    assert render.returncode == 143 and len(lines) == 1, err
    assert lines[0].startswith("softcell: interrupted") and lines[0].endswith("(SIGTERM)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_a_render_of_a_million_frames_is_refused_before_drawing(one_run, tmp_path, capsys):
    out, _, _ = one_run
    line = one_line_exit_2(
        ["render", str(out), "--fps", "1e9", "-o", str(tmp_path / "v.mkv")], capsys
    )
    assert "fps = 1e+09 1/s over [0, 0.2] s makes 2e+08 frames, more than 1,000,000" in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


# -- studies write only into folders they made ------------------------------------------------


@pytest.mark.parametrize("command", [["beyond"], ["study", "sensitivity", "--only", "pivot"]])
def test_a_study_refuses_a_folder_it_did_not_make(tmp_path, capsys, command):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "sensitivity.json").write_text('{"mine": 1}')
    assert main([*command, "-o", str(mine)]) == 2
    err = capsys.readouterr().err
    assert "is not empty and was not made by `softcell " in err and "study.json" in err
    assert (mine / "sensitivity.json").read_text() == '{"mine": 1}'
    assert sorted(p.name for p in mine.iterdir()) == ["sensitivity.json"]


def test_a_study_folder_is_kept_for_its_own_study_and_seed(tmp_path):
    from softcell.paper.reproduce import QUICK
    from softcell.studies.variants import run_variants

    def run(command, seed, overwrite=False):
        run_variants(
            tmp_path,
            (),
            QUICK,
            command=command,
            seed=seed,
            workers=1,
            overwrite=overwrite,
            progress=False,
            log=None,
        )

    run("beyond", 3)
    run("beyond", 3)  # a rerun of the same study
    with pytest.raises(SoftcellError, match="made with seed = 3, not 4; rerun with --overwrite"):
        run("beyond", 4)
    with pytest.raises(SoftcellError, match="holds the study `softcell beyond`, not"):
        run("study sensitivity", 3)
    run("beyond", 4, overwrite=True)
    assert json.loads((tmp_path / "study.json").read_text()) == {"study": "beyond", "seed": 4}


def test_the_library_bounds_local_workers(tmp_path):
    from softcell.model.configuration import RunConfig
    from softcell.model.limits import WORKERS_PER_CORE, cores
    from softcell.runner.ensemble import simulate

    too_many = WORKERS_PER_CORE * cores() + 1
    with pytest.raises(SoftcellError, match=f"workers = {too_many} is not allowed: this machine"):
        simulate(RunConfig(parameters={"radius": 4.0}), tmp_path / "out", workers=too_many)
    assert not (tmp_path / "out").exists()


# -- track stops its reader on every error -----------------------------------------------------


@pytest.fixture(scope="module")
def plain_video(tmp_path_factory):
    """200 frames of an empty grey floor: no plate, no ring, no bot."""
    import cv2

    path = tmp_path_factory.mktemp("video") / "floor.mkv"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), 25.0, (320, 240))
    rng = np.random.default_rng(0)
    for _ in range(200):
        writer.write(rng.integers(100, 140, (240, 320, 3), dtype=np.uint8))
    writer.release()
    return path


@pytest.mark.parametrize(
    ("flags", "words"),
    [
        ([], "pass px_per_cm, arena_size (cm) to derive it, or plate_size"),
        (["--plate-size", "30"], "plate"),
    ],
)
def test_track_ends_with_one_line_on_an_error(plain_video, tmp_path, flags, words):
    # Before: the main thread released the capture while the read-ahead thread still read
    # from it, and both waited for ever.
    run = subprocess.run(
        [*PY, "track", str(plain_video), *flags, "-o", str(tmp_path / "t.nc")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], run.stderr
    assert not (tmp_path / "t.nc").exists()


# -- a scheduler address that is not a dask scheduler -----------------------------------------


@pytest.fixture
def listener():
    """A loopback listener that is no dask scheduler: it accepts, then says ``reply`` (or
    nothing) and keeps the connection open."""
    import socket
    import threading

    server = socket.create_server(("127.0.0.1", 0))
    held = []

    def serve(reply: bytes) -> None:
        while True:
            try:
                connection, _ = server.accept()
            except OSError:
                return
            held.append(connection)
            if reply:
                connection.sendall(reply)

    def start(reply: bytes) -> str:
        threading.Thread(target=serve, args=(reply,), daemon=True).start()
        return f"tcp://127.0.0.1:{server.getsockname()[1]}"

    yield start
    server.close()
    for connection in held:
        connection.close()


@pytest.mark.parametrize(
    ("reply", "words"),
    [
        (b"", "accepts connections but is not a dask scheduler (it said nothing in 5 s)"),
        (b"\xff" * 64, "where a dask handshake has at most 65536"),  # garbage: 2**64 - 1
        (b"HTTP/1.1 200 OK\r\n\r\n", "is not a dask scheduler (its first message claims"),
    ],
)
def test_a_listener_that_is_no_scheduler_is_one_line(listener, tmp_path, capsys, reply, words):
    address = listener(reply)
    out = tmp_path / "out"
    argv = ["simulate", "--radius", "8", "--duration", "1", "--scheduler", address]
    assert main([*argv, "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_an_inproc_address_of_no_scheduler_is_one_line(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["simulate", "--radius", "8", "--duration", "1", "--scheduler", "inproc://nothing"]
    assert main([*argv, "-o", str(out), "--quiet"]) == 2
    assert "no dask scheduler listens at 'inproc://nothing' in this process" in (
        capsys.readouterr().err
    )
    assert not out.exists()


# -- inputs that are not what they should be ---------------------------------------------------


def test_an_unreadable_input_folder_is_not_called_empty(tmp_path, capsys, monkeypatch):
    import softcell.io.netcdf

    folder = tmp_path / "sweep"
    folder.mkdir()

    def denied(path):
        raise PermissionError(13, "Permission denied", str(path))

    # chmod 000 would not stop root (CI runs as root): refuse the listing itself
    monkeypatch.setattr(softcell.io.netcdf.os, "scandir", denied)
    assert main(["analyze", str(folder), "-o", str(tmp_path / "a.nc")]) == 2
    assert f"cannot read directory {folder} (Permission denied)" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (
            ["track", "D/v.mkv", "--px-per-cm", "10", "-o", "W/t.nc"],
            "v.mkv is a directory, not a video file",
        ),
        (["render", "D/v.mkv", "-o", "W/out.mkv"], "no .nc files in directory"),
    ],
)
def test_a_directory_where_a_file_is_expected_is_named_so(tmp_path, capsys, argv, words):
    (tmp_path / "v.mkv").mkdir()
    argv = [a.replace("D/", f"{tmp_path}/").replace("W/", f"{tmp_path}/") for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and "no such" not in err, err


def test_read_dataset_of_a_directory_says_so(tmp_path):
    from softcell.io.netcdf import read_dataset

    with pytest.raises(SoftcellError, match="is a directory, not a NetCDF file"):
        read_dataset(tmp_path)


def test_a_second_local_cluster_on_the_machine_says_nothing(tmp_path):
    # dask's scheduler listens on 8787 even with no dashboard; a second softcell cluster on
    # the machine printed a four-line "Port 8787 is already in use" warning.
    import socket

    held = socket.socket()
    with suppress(OSError):  # taken already: the situation this test sets up
        held.bind(("127.0.0.1", 8787))
        held.listen()
    try:
        run = subprocess.run(
            [*PY, "simulate", *SMALL_RUN, "--workers", "2", "-o", str(tmp_path / "out")],
            capture_output=True,
            text=True,
            timeout=300,
        )
    finally:
        held.close()
    assert run.returncode == 0, run.stderr
    said = [  # the workers compile the model the first time on a machine, and say so
        line
        for line in run.stderr.strip().splitlines()
        if not line.startswith("softcell: compiling the model")
    ]
    assert "already in use" not in run.stderr and said == [], run.stderr


@pytest.mark.parametrize("verb", ["export", "animate"])
def test_a_long_legal_output_name_is_written(one_run, tmp_path, verb):
    # Before: a 250-byte name is legal, but its temporary name was not (a traceback from gsd
    # and from av: "File name too long").
    out, _, _ = one_run
    name = "a" * 246 + (".gsd" if verb == "export" else ".gif")
    where = tmp_path / "outputs"
    assert main([verb, str(out), "-o", str(where / name)]) == 0
    assert (where / name).stat().st_size > 0
    assert [p.name for p in where.iterdir()] == [name]


@pytest.mark.parametrize("verb", ["export", "animate", "analyze", "simulate"])
def test_a_name_too_long_for_the_file_system_is_one_line(one_run, tmp_path, capsys, verb):
    # Before: an OSError traceback from files.py (export, animate) once the work was done.
    out, _, _ = one_run
    name = "b" * 296 + (".gif" if verb == "animate" else ".nc")
    argv = (
        ["simulate", "--radius", "4", "--duration", "0.2"]
        if verb == "simulate"
        else [verb, str(out)]
    )
    where = tmp_path / "outputs"
    line = one_line_exit_2([*argv, "-o", str(where / name)], capsys)
    assert f"that name is {len(name)} bytes long, and file systems take at most 255" in line
    assert not where.exists()


def test_a_killed_writers_temporary_files_are_removed_by_the_next_run(one_run, tmp_path):
    # Before: a killed export left .NAME.PID-RAND.tmp.gsd (14.7 MB), and a killed checkpoint
    # write ..pointP_realizationR.ckpt.PID-RAND.tmp.npz, for good. Such a name records the
    # writer's pid and host: the next write into the folder removes those of dead writers
    # on this host, and keeps those of running processes and of other hosts.
    from softcell.io.files import temporary_path

    out, _, _ = one_run
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    pid = int(dead.stdout)
    mine = temporary_path(tmp_path / "movie.gsd").name
    host = mine.split(".")[-3].split("-")[1]
    left = {
        f".movie.{pid}-{host}-0a1b2c.tmp.gsd": False,  # a dead writer of this host
        f".movie.{pid}-9e8d7c.tmp.gsd": False,  # the same, named by softcell 0.2
        f".movie.{os.getppid()}-{host}-0a1b2c.tmp.gsd": True,  # a running process
        f".movie.{pid}-{'0000' if host != '0000' else '1111'}-0a1b2c.tmp.gsd": True,  # elsewhere
        ".notes.txt": True,  # not softcell's
    }
    where = tmp_path / "outputs"
    where.mkdir()
    for name in left:
        (where / name).write_bytes(b"partial")
    assert main(["export", str(out), "-o", str(where / "movie.gsd")]) == 0
    kept = {p.name for p in where.iterdir()} - {"movie.gsd"}
    assert kept == {name for name, stays in left.items() if stays}


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        # before: one point written twice; internal wall strings; three equal panels
        (["study", "constriction", "-o", "S", "--radii", "5,5"], "--radii names 5 twice"),
        (["study", "constriction", "-o", "S", "--gaps", "1.0,1"], "--gaps names 1 twice"),
        (["study", "strategies", "-o", "S", "--strategies", "graspion,graspion"], "twice"),
        (["animate", "{a}", "-o", "S/m.gif", "--realizations", "0,0,0"], "names 0 twice"),
        # before: xarray's "Could not find any dimension coordinates"
        (["analyze", "{a}/point000_realization0000.nc"] * 1 + ["{a}"] + ["-o", "S/a.nc"],
         "is given twice: give each file or folder once"),
        # before: tracebacks, or (radius=-1) the last point animated
        (["animate", "{a}", "-o", "S/m.gif", "--point", "radius=5"],
         "--point radius=5 is not allowed: an index from 0 to 1, not a value (radius = 4, 5 cm)"),
        (["animate", "{a}", "-o", "S/m.gif", "--point", "radius=-1"], "an index from 0 to 1"),
        (["animate", "{a}", "-o", "S/m.gif", "--point", "cutoff=0"],
         "--point cutoff=0 is not allowed: its sweep dimensions are radius"),
        (["animate", "{a}/point000_realization0000.nc", "-o", "S/m.gif", "--point", "radius=0"],
         "the input is one parameter point, so there is no point to choose"),
    ],
)  # fmt: skip
def test_repeated_or_misplaced_choices_are_one_line(
    two_sweeps, tmp_path, capsys, monkeypatch, argv, words
):
    monkeypatch.chdir(tmp_path)
    argv = [a.replace("{a}", str(two_sweeps / "a")) for a in argv]
    line = one_line_exit_2(argv, capsys)
    assert words in line, line
    assert list(tmp_path.iterdir()) == []


def test_json_outputs_hold_no_nan():
    # Before: `study constriction --realizations 1` wrote NaN into constriction.json (no JSON).
    from softcell.io.files import json_text

    text = json_text({"a": float("nan"), "b": [np.float64("inf"), 1.5], "c": "x"})
    assert json.loads(text) == {"a": None, "b": [None, 1.5], "c": "x"}
    assert "NaN" not in text and "Infinity" not in text


@pytest.mark.parametrize(
    ("table", "words"),
    [
        ("[run]\nrealizations = 0", "realizations = 0 is not allowed: must be an integer >= 1"),
        ("[run]\nseed = -1", "seed = -1 is not allowed"),
        ("[analysis]\ndiscardd = 3", "unknown analysis option 'discardd' (did you mean"),
    ],
)
def test_params_refuses_what_simulate_and_analyze_refuse(tmp_path, capsys, table, words):
    # Before: `softcell params` printed the parameters, exit 0.
    config = tmp_path / "run.toml"
    config.write_text(table + "\n", encoding="utf-8")
    line = one_line_exit_2(["params", str(config)], capsys)
    assert words in line, line


def test_an_assembly_beyond_the_process_memory_limit_is_refused_at_once(tmp_path):
    # Before: under a 6 GB address-space limit, a MemoryError traceback after 85 s (the
    # estimate took the machine's memory, and the placement held all M x M pairs).
    import resource

    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (6 * 10**9, resource.RLIM_INFINITY))

    argv = ["simulate", "--cells", "12000", "--radius", "4", "--duration", "1"]
    run = subprocess.run(
        [sys.executable, "-m", "softcell", *argv, "-o", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        preexec_fn=limited,
        timeout=120,
    )
    assert run.returncode == 2, run.stderr
    assert run.stderr.startswith("softcell: error: parameter cells = 12000 is not allowed")
    assert "Traceback" not in run.stderr
    if os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") > 6 * 10**9:
        assert "more than 50% of 5.59 GiB" in run.stderr, run.stderr  # the limit, not the RAM
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_track_refuses_an_animation(one_run, tmp_path, capsys, suffix):
    # Before: track took animate's two-panel GIF for a cell ("26 frames tracked").
    out, _, _ = one_run
    movie = tmp_path / f"movie{suffix}"
    assert main(["animate", str(out), "-o", str(movie), "--quiet"]) == 0
    capsys.readouterr()
    line = one_line_exit_2(["track", str(movie), "-o", str(tmp_path / "t.nc")], capsys)
    assert ("is a GIF" if suffix == ".gif" else "is an animation of a simulation") in line, line
    assert not (tmp_path / "t.nc").exists()
