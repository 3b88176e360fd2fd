"""Data safety: a stale result is never kept, an input never destroyed, and every bad input is
one line on stderr with exit status 2, leaving the disk as it was.

The table below holds every bad input the package has been found to mishandle (each row was a
traceback, a silent acceptance or a destroyed input before it was fixed), with the words the
message must contain: the value, and what is allowed.
"""

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import cv2
import netCDF4
import numpy as np
import pytest
import xarray as xr
from hypothesis import example, given
from hypothesis import strategies as st

import softcell
from softcell.cli import main
from softcell.components.registry import default_registry
from softcell.errors import ConfigError
from softcell.model.configuration import RunConfig
from softcell.runner.ensemble import plan
from softcell.testing import registered

PY = [sys.executable, "-m", "softcell"]
SMALL = [
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
    "--integrator",
    "explicit_euler",
    "--quiet",
]


def tree_hash(folder: Path) -> str:
    """One digest of every file's relative name and bytes under ``folder`` (hidden included)."""
    digest = hashlib.sha256()
    for path in sorted(folder.rglob("*")):
        digest.update(str(path.relative_to(folder)).encode())
        if path.is_file():
            digest.update(path.read_bytes())
    return digest.hexdigest()


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    """A folder as a user has it: a sweep, its analysis, a film, its tracking and analysis,
    and files that are not what they claim to be."""
    w = tmp_path_factory.mktemp("world")
    assert main(["simulate", "--radius", "4,5", *SMALL, "-o", str(w / "sim")]) == 0
    assert (
        main(["analyze", str(w / "sim"), "-o", str(w / "an.nc"), "--discard", "0.05", "--quiet"])
        == 0
    )
    assert (
        main(["render", str(w / "sim"), "--point", "radius=0", "-o", str(w / "v.mkv"), "--quiet"])
        == 0
    )
    assert (
        main(
            [
                "track",
                str(w / "v.mkv"),
                "--px-per-cm",
                "10",
                "--radius",
                "4",
                "-o",
                str(w / "tr.nc"),
                "--quiet",
            ]
        )
        == 0
    )
    (w / "empty.nc").write_bytes(b"")
    whole = (w / "sim" / "point000_realization0000.nc").read_bytes()
    (w / "trunc.nc").write_bytes(whole[: len(whole) // 2])
    ds = softcell.read_dataset(w / "sim" / "point000_realization0000.nc")
    softcell.write_dataset(ds.drop_vars("bot_angle"), w / "novar.nc")
    analysis = softcell.read_dataset(w / "an.nc")
    softcell.write_dataset(analysis.drop_vars(["stop_pdf", "go_pdf"]), w / "nopdf.nc")
    (w / "notes.txt").write_text("a user's own notes\n")
    writer = cv2.VideoWriter(str(w / "grey.mkv"), cv2.VideoWriter_fourcc(*"FFV1"), 30, (64, 64))
    for _ in range(5):
        writer.write(np.full((64, 64, 3), 180, np.uint8))
    writer.release()
    (w / "bad_integrator.toml").write_text('[components]\nintegrator = "rodaz4"\n')
    (w / "bad_detector.toml").write_text('[components]\nstopgo_detector = "treshold"\n')
    (w / "bad_seed.toml").write_text("[run]\nseed = -4\n")
    (w / "zero.toml").write_text("[run]\nrealizations = 0\n")
    return w


#: (command line, words the one-line message must contain). ``W`` is the world folder.
BAD = [
    # Resume only what matches (the sweep in W/sim was made with radius 4,5 and SMALL).
    (
        ["simulate", "--radius", "4,6", *SMALL, "-o", "W/sim"],
        ["radius = 5.0 there, 6.0 in this request", "--overwrite"],
    ),
    (
        ["simulate", "--radius", "4,5", *SMALL, "--seed", "3", "-o", "W/sim"],
        ["seed = 0 there, 3 in this request"],
    ),
    (
        ["simulate", "--radius", "4,5", *SMALL, "--duration", "0.2", "-o", "W/sim"],
        ["duration = 0.3 there, 0.2 in this request"],
    ),
    (
        ["simulate", "--radius", "4,5", *SMALL, "--energy-terms", "bending,tension", "-o", "W/sim"],
        ['energy_terms = ["bending", "tension", "contact"] there'],
    ),
    (
        ["simulate", "--radius", "4", *SMALL, "-o", "W/sim"],
        ["no part of this request", "point001_realization0000.nc"],
    ),
    # An output never destroys an input.
    (
        ["analyze", "W/sim", "-o", "W/sim/point000_realization0000.nc"],
        ["inside the input directory"],
    ),
    (["analyze", "W/sim", "-o", "W/sim/new.nc"], ["inside the input directory"]),
    (["analyze", "W/an.nc", "-o", "W/an.nc"], ["is the input"]),
    (["track", "W/v.mkv", "--px-per-cm", "10", "-o", "W/v.mkv"], ["is the input"]),
    (["render", "W/sim", "--point", "radius=0", "-o", "W/v.mkv"], ["exists", "--overwrite"]),
    (["analyze", "W/sim", "-o", "W/notes.txt"], ["not a softcell analysis file", "--overwrite"]),
    (
        ["track", "W/v.mkv", "--px-per-cm", "10", "-o", "W/an.nc"],
        ["is a softcell analysis file", "--overwrite"],
    ),
    (["figures", "W/an.nc", "-o", "W/an.nc"], ["is the input"]),
    (["figures", "W/an.nc", "--simulations", "W/sim", "-o", "W/sim"], ["is the input"]),
    (
        ["figures", "W/an.nc", "--simulations", "W/sim", "-o", "W/sim/figs"],
        ["inside the input directory"],
    ),
    (["figures", "W/an.nc", "-o", "W"], ["holds the input"]),
    (["simulate", "--radius", "4", *SMALL, "-o", "W/an.nc"], ["existing file, not a directory"]),
    (["analyze", "W/sim", "-o", "W"], ["is a directory"]),
    (["track", "W/v.mkv", "--px-per-cm", "10", "-o", "W"], ["is a directory"]),
    (["reproduce", "-o", "W/an.nc"], ["existing file, not a directory"]),
    (["reproduce", "-o", "W"], ["not empty and was not made by `softcell reproduce`"]),
    # Fail before computing.
    (["simulate", "--seed", "-1", "-o", "W/new"], ["seed = -1", "2**64 - 1"]),
    (["simulate", "--seed", str(2**64), "-o", "W/new"], [f"seed = {2**64}", "2**64 - 1"]),
    (["simulate", "W/bad_seed.toml", "-o", "W/new"], ["seed = -4"]),
    (
        ["simulate", "--duration", "1e12", "-o", "W/new"],
        ["duration = 1000000000000.0 s", "must be <=", "memory"],
    ),
    (["params", "--duration", "1e12"], ["duration = 1000000000000.0 s", "memory"]),
    (["simulate", "--nodes", str(2**30), "-o", "W/new"], [f"nodes = {2**30}", "memory"]),
    (["params", "--nodes", str(2**30)], [f"nodes = {2**30}", "memory"]),
    (
        ["simulate", "--radius", "1e300", "-o", "W/new"],
        ["radius = 1e+300 cm", "must be <= 4.5e+09 cm", "float64"],
    ),
    (["params", "--radius", "1e300"], ["radius = 1e+300 cm", "float64"]),
    (["simulate", "--radius", "inf", "-o", "W/new"], ["radius = inf cm", "must be finite"]),
    (["simulate", "--realizations", "0", "-o", "W/new"], ["realizations = 0", ">= 1"]),
    (["simulate", "W/zero.toml", "-o", "W/new"], ["realizations = 0", ">= 1"]),
    (["simulate", "--integrator", "rodaz4", "-o", "W/new"], ["'rodaz4'", "did you mean 'rodas4'"]),
    (["simulate", "W/bad_integrator.toml", "-o", "W/new"], ["'rodaz4'"]),
    (["params", "W/bad_detector.toml"], ["'treshold'", "did you mean 'threshold'"]),
    (
        ["simulate", "--energy-terms", "bending,bending", "-o", "W/new"],
        ["'bending' is named twice"],
    ),
    (["simulate", "--scheduler", "bogus://x", "-o", "W/new"], ["'bogus://x'", "tcp"]),
    (
        ["simulate", "--scheduler", "tcp://127.0.0.1:1", "-o", "W/new"],
        ["cannot reach the dask scheduler", "refused"],
    ),
    (["simulate", "--checkpoint-every", "0", "-o", "W/new"], ["checkpoint-every = 0.0 s"]),
    (["simulate", "--seed", "x", "-o", "W/new"], ["invalid int value: 'x'"]),
    # Unreadable or unsuitable inputs.
    (["analyze", "W/empty.nc", "-o", "W/out.nc"], ["empty (0 bytes)"]),
    (["analyze", "W/trunc.nc", "-o", "W/out.nc"], ["cannot read", "truncated or corrupt"]),
    (["figures", "W/empty.nc", "-o", "W/figs"], ["empty (0 bytes)"]),
    (["figures", "W/trunc.nc", "-o", "W/figs"], ["truncated or corrupt"]),
    (["render", "W/empty.nc", "-o", "W/out.mkv"], ["empty (0 bytes)"]),
    (["render", "W/trunc.nc", "-o", "W/out.mkv"], ["truncated or corrupt"]),
    (
        ["render", "W/novar.nc", "-o", "W/out.mkv"],
        ["novar.nc: it does not follow the simulation schema", "bot_angle: missing"],
    ),
    (["render", "W/sim", "-o", "W/out.mkv"], ["sweep over radius", "radius=INDEX"]),
    (
        ["render", "W/sim", "--point", "radius=0", "--px-per-cm", "inf", "-o", "W/out.mkv"],
        ["px_per_cm = inf", "must be finite"],
    ),
    (
        ["render", "W/sim", "--point", "radius=0", "--px-per-cm", "1e5", "-o", "W/out.mkv"],
        ["frame width = ", "16384 px"],
    ),
    (
        ["render", "W/sim", "--point", "radius=0", "--size", "0x0", "-o", "W/out.mkv"],
        ["frame width = 0 px", "between 16 and 16384 px"],
    ),
    (["render", "W/sim", "--point", "radius=0", "-o", "W/out.txt"], [".mkv or .avi"]),
    (["track", "W/v.mkv", "--arena-size", "0", "-o", "W/out.nc"], ["arena_size = 0.0", "> 0 cm"]),
    (
        ["track", "W/v.mkv", "--px-per-cm", "10", "--fps", "0", "-o", "W/out.nc"],
        ["fps = 0.0", "> 0 1/s"],
    ),
    (
        ["track", "W/v.mkv", "--px-per-cm", "10", "--radius", "-1", "-o", "W/out.nc"],
        ["radius = -1.0", "> 0 cm"],
    ),
    (
        ["track", "W/v.mkv", "--px-per-cm", "10", "--origin", "inf,0", "-o", "W/out.nc"],
        ["--origin = 'inf,0'", "finite"],
    ),
    (
        ["track", "W/grey.mkv", "--px-per-cm", "10", "--quiet", "-o", "W/out.nc"],
        ["no frame of", "was tracked", "5 frames"],
    ),
    (["track", "W/missing.mkv", "--px-per-cm", "10", "-o", "W/out.nc"], ["no such video file"]),
    (
        ["figures", "W/an.nc", "--tracked", "W/tr.nc", "-o", "W/figs"],
        ["tracked input is a tracking file, not an analysis"],
    ),
    (["figures", "W/tr.nc", "-o", "W/figs"], ["analysis input is a tracking file"]),
    (
        ["figures", "W/an.nc", "--tracked", "W/nopdf.nc", "-o", "W/figs"],
        ["tracked input lacks stop_pdf, go_pdf"],
    ),
    (
        ["render", "W/sim", "--point", "radius=7", "-o", "W/out.mkv"],
        ["point radius=7 is not allowed: an index from 0 to 1, not a value (radius = 4, 5 cm)"],
    ),
]


def _argv(row: list[str], world: Path) -> list[str]:
    return [
        str(world / a[2:]) if a.startswith("W/") else str(world) if a == "W" else a for a in row
    ]


@pytest.mark.parametrize(("row", "words"), BAD, ids=[" ".join(r[:4]) for r, _ in BAD])
def test_every_bad_input_is_one_line_exit_2_and_changes_nothing(world, row, words, capsys):
    before = tree_hash(world)
    try:
        status = main(_argv(row, world))
    except SystemExit as exc:  # argparse's own errors
        status = exc.code
    assert status == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("softcell"), lines[0]
    for word in words:
        assert word in lines[0], lines[0]
    assert tree_hash(world) == before, "a refused command changed the disk"


@pytest.mark.parametrize(
    "row",
    [
        ["simulate", "--seed", "-1", "-o", "W/new"],
        ["track", "W/grey.mkv", "--px-per-cm", "10", "--quiet", "-o", "W/out.nc"],
        ["analyze", "W/trunc.nc", "-o", "W/out.nc"],
        ["simulate", "--radius", "4,6", *SMALL, "-o", "W/sim"],
    ],
)
def test_the_installed_command_prints_no_traceback(world, row):
    before = tree_hash(world)
    run = subprocess.run([*PY, *_argv(row, world)], capture_output=True, text=True)
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr and len(run.stderr.strip().splitlines()) == 1
    assert tree_hash(world) == before


# -- resuming only what matches -------------------------------------------------------------


@pytest.fixture()
def sweep(world, tmp_path):
    """A copy of the world's sweep to damage."""
    out = tmp_path / "sim"
    shutil.copytree(world / "sim", out)
    return out


def _simulate(out, *extra, radius="4,5"):
    return main(["simulate", "--radius", radius, *SMALL, *extra, "-o", str(out)])


def test_a_rerun_of_the_same_request_reuses_every_file(sweep, capsys):
    before = tree_hash(sweep)
    assert _simulate(sweep) == 0
    assert tree_hash(sweep) == before


def test_a_truncated_or_empty_file_is_not_reused(sweep, capsys):
    path = sweep / "point001_realization0000.nc"
    whole = path.read_bytes()
    path.write_bytes(whole[:1000])
    assert _simulate(sweep) == 2
    err = capsys.readouterr().err
    assert "point001_realization0000.nc cannot be reused" in err and "truncated" in err
    assert _simulate(sweep, "--overwrite") == 0
    assert path.read_bytes() == whole  # recomputed to the same bytes


def test_a_file_of_another_spawn_key_is_not_reused(sweep, capsys):
    shutil.copy(sweep / "point000_realization0000.nc", sweep / "point001_realization0000.nc")
    assert _simulate(sweep) == 2
    err = capsys.readouterr().err
    assert "point001_realization0000.nc was made with parameter radius = 4.0 there, 5.0" in err
    # Same point, other realization: everything equal but the spawn key.
    assert (
        main(
            [
                "simulate",
                "--radius",
                "4",
                *SMALL,
                "--realizations",
                "2",
                "--overwrite",
                "-o",
                str(sweep),
            ]
        )
        == 0
    )
    shutil.copy(sweep / "point000_realization0000.nc", sweep / "point000_realization0001.nc")
    assert main(["simulate", "--radius", "4", *SMALL, "--realizations", "2", "-o", str(sweep)]) == 2
    assert "spawn key = 0,0 there, 0,1 in this request" in capsys.readouterr().err


def test_a_file_of_another_version_is_not_reused(sweep, capsys, monkeypatch):
    import softcell.runner.tasks as tasks

    monkeypatch.setattr(tasks, "__version__", "99.0")
    assert _simulate(sweep) == 2
    assert f"softcell version = {softcell.__version__} there, 99.0 in this request" in (
        capsys.readouterr().err
    )


def test_installing_a_plugin_changes_no_request(sweep, capsys):
    # A file stores the parameters of the components it used, and only those: a plugin
    # installed since, with parameters of its own, leaves the same command reusing every file.
    import fakeplugins.good

    before = tree_hash(sweep)
    stored = json.loads(
        xr.open_dataset(sweep / "point000_realization0000.nc").attrs["softcell_parameters"]
    )
    assert "fake_level" not in stored and "threshold" in stored  # the detector in use
    assert "arena_side" not in stored and "atol" not in stored  # the arena's, rodas4's
    with registered(fakeplugins.good):
        assert _simulate(sweep) == 0
    assert tree_hash(sweep) == before


def test_a_plugin_whose_code_changed_is_a_changed_request(tmp_path, capsys, monkeypatch):
    # The same plugin, the same version, one line of its code changed: the files made with
    # the old code are not reused silently; --overwrite recomputes them.
    import importlib

    from softcell.components.registry import registered

    package = tmp_path / "plugin" / "changing_plugin"
    package.mkdir(parents=True)
    code = (Path(__file__).parent / "fakeplugins" / "good.py").read_text(encoding="utf-8")
    (package / "__init__.py").write_text(code, encoding="utf-8")
    monkeypatch.syspath_prepend(str(package.parent))
    plugin = importlib.import_module("changing_plugin")
    config = tmp_path / "run.toml"
    config.write_text('[components]\nstopgo_detector = "fake_hysteresis"\n', encoding="utf-8")
    out = tmp_path / "sim"

    def run(*extra):
        with registered(plugin):
            return main(["simulate", str(config), "--radius", "4", *SMALL, *extra, "-o", str(out)])

    assert run() == 0
    stored = json.loads(
        xr.open_dataset(out / "point000_realization0000.nc").attrs["softcell_component_code"]
    )
    assert "code of stopgo_detector fake_hysteresis" in stored
    before = tree_hash(out)
    assert run() == 0 and tree_hash(out) == before  # the same code: every file reused
    (package / "__init__.py").write_text(code + "# a changed line\n", encoding="utf-8")
    capsys.readouterr()
    assert run() == 2
    err = capsys.readouterr().err
    assert "code of stopgo_detector fake_hysteresis = " in err and "--overwrite" in err, err
    assert tree_hash(out) == before
    assert run("--overwrite") == 0
    again = json.loads(
        xr.open_dataset(out / "point000_realization0000.nc").attrs["softcell_component_code"]
    )
    assert (
        again["code of stopgo_detector fake_hysteresis"]
        != (stored["code of stopgo_detector fake_hysteresis"])
    )


def test_a_file_that_stored_every_installed_components_parameters_is_reused(sweep, capsys):
    # softcell 0.2.0 stored the parameters of every registered component, used or not.
    for path in sweep.glob("*.nc"):
        with netCDF4.Dataset(path, "a") as nc:
            values = json.loads(nc.getncattr("softcell_parameters"))
            nc.setncattr(
                "softcell_parameters",
                json.dumps({**values, "fake_level": 1.0, "atol": 1e-9}),
            )
            nc.delncattr("softcell_sha256")  # 0.2.0 stored no checksum either
    before = tree_hash(sweep)
    assert _simulate(sweep) == 0
    assert tree_hash(sweep) == before


def test_a_value_for_a_component_not_in_use_is_refused(tmp_path, capsys):
    import fakeplugins.good

    with registered(fakeplugins.good):
        with pytest.raises(
            ConfigError, match="'fake_level' belongs to stop/go detector 'fake_hysteresis'"
        ):
            plan(
                RunConfig(parameters={"fake_level": 2.0}),
                tmp_path,
                realizations=1,
                seed=0,
                registry=default_registry(),
            )


def test_overwrite_recomputes_and_removes_what_is_no_part_of_the_request(sweep, tmp_path, capsys):
    assert _simulate(sweep, "--overwrite", radius="4") == 0
    assert "--overwrite: removing 1 file(s)" in capsys.readouterr().err  # never silently
    assert sorted(p.name for p in sweep.iterdir()) == ["point000_realization0000.nc"]
    assert _simulate(tmp_path / "fresh", radius="4") == 0
    name = "point000_realization0000.nc"
    assert (sweep / name).read_bytes() == (tmp_path / "fresh" / name).read_bytes()


def test_a_checkpoint_of_another_request_or_a_corrupt_one_stops_the_run(tmp_path, capsys):
    from softcell.runner.tasks import checkpoint_path, save_checkpoint

    out = tmp_path / "sim"
    out.mkdir()
    checkpoint = checkpoint_path(out / "point000_realization0000.nc")
    request = json.dumps({"parameter radius": 9.0})
    save_checkpoint(
        checkpoint,
        request,
        1,
        np.zeros((1, 9), complex),
        np.zeros((1, 3)),
        {"modes": np.zeros(9, complex)},
        np.zeros(1, complex),
    )
    assert _simulate(out, radius="4") == 2
    assert "ckpt.npz was made with parameter radius = 9.0 there, 4.0" in capsys.readouterr().err
    checkpoint.write_bytes(b"PK\x03\x04 not a zip")
    assert _simulate(out, radius="4") == 2
    assert "truncated or corrupt" in capsys.readouterr().err
    assert _simulate(out, "--overwrite", radius="4") == 0
    assert not checkpoint.exists() and (out / "point000_realization0000.nc").is_file()


def test_reproduce_into_a_folder_of_another_design_or_seed_stops_before_computing(tmp_path):
    from softcell.errors import SoftcellError
    from softcell.paper.reproduce import MANIFEST, Design, _manifest, reproduce

    design = Design("tiny", radii=(4.0, 12.0), realizations=2, duration=30.0)
    (tmp_path / MANIFEST).write_text(json.dumps(_manifest(design, 0)))
    before = tree_hash(tmp_path)
    with pytest.raises(SoftcellError, match="seed = 0 there, 1 in this request"):
        reproduce(tmp_path, design, seed=1, workers=1, progress=False, log=None)
    other = Design("tiny", radii=(4.0, 12.0), realizations=3, duration=30.0)
    with pytest.raises(SoftcellError, match="design.realizations = 2 there, 3 in this request"):
        reproduce(tmp_path, other, seed=0, workers=1, progress=False, log=None)
    assert tree_hash(tmp_path) == before


# -- the disk: read-only and full -----------------------------------------------------------


@pytest.fixture()
def small_disk(tmp_path):
    """A 3 MiB tmpfs (root and mount(8) needed; skipped otherwise)."""
    mount = tmp_path / "disk"
    mount.mkdir()
    run = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", str(mount)],
        capture_output=True,
        text=True,
    )
    if run.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {run.stderr.strip() or run.returncode}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def _fill(disk: Path, leave: int) -> None:
    free = os.statvfs(disk).f_bavail * os.statvfs(disk).f_frsize
    (disk / "filler").write_bytes(b"\0" * max(free - leave, 0))


def test_read_only_folder_is_refused_before_computing(world, small_disk, capsys):
    subprocess.run(["mount", "-o", "remount,ro", str(small_disk)], check=True)
    for row in (
        ["simulate", "--radius", "4", *SMALL, "-o", str(small_disk / "sim")],
        ["analyze", str(world / "sim"), "-o", str(small_disk / "a.nc")],
        ["figures", str(world / "an.nc"), "-o", str(small_disk / "figs")],
        ["render", str(world / "sim"), "--point", "radius=0", "-o", str(small_disk / "v.mkv")],
    ):
        assert main(row) == 2
        assert "read-only file system" in capsys.readouterr().err
    assert list(small_disk.iterdir()) == []


def test_a_full_disk_is_named_and_leaves_nothing(world, small_disk, capsys, monkeypatch):
    # Refused up front: the run needs more than the disk has.
    assert (
        main(
            [
                "simulate",
                "--radius",
                "4,5,6,7",
                "--realizations",
                "8",
                *SMALL,
                "--duration",
                "3",
                "-o",
                str(small_disk / "sim"),
            ]
        )
        == 2
    )
    assert "no space left on device (the run needs about" in capsys.readouterr().err
    _fill(small_disk, 100_000)
    # NetCDF: the library loses the errno; the file system tells.
    big = xr.Dataset({"x": ("n", np.random.default_rng(0).normal(size=200_000))})
    with pytest.raises(softcell.SoftcellError, match="no space left on device"):
        softcell.write_dataset(big, small_disk / "big.nc")
    # Figures: the whole set or nothing.
    assert main(["figures", str(world / "an.nc"), "-o", str(small_disk / "figs")]) == 2
    assert "no space left on device" in capsys.readouterr().err
    # Video: the writer never says; the frames read back do.
    import softcell.video.render as video

    monkeypatch.setattr(video, "DISK_CHECK_EVERY", 10**9)
    assert (
        main(
            [
                "render",
                str(world / "sim"),
                "--point",
                "radius=0",
                "--px-per-cm",
                "40",
                "--noise",
                "3",
                "-o",
                str(small_disk / "v.mkv"),
                "--quiet",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "cannot write" in err and "no space left on device" in err and "frames" in err
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler"]


# -- interruption -----------------------------------------------------------------------------


def _interrupt(
    command: list[str], out: Path, wait_for: str, signum: int = signal.SIGINT
) -> subprocess.CompletedProcess:
    """Run ``command``, send ``signum`` (SIGINT: as Ctrl-C does) to its process group once
    ``wait_for`` files exist in ``out``, and return the finished process."""
    import time

    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    deadline = time.monotonic() + 300
    while not list(out.glob(wait_for)) and process.poll() is None:
        assert time.monotonic() < deadline, "the run never got going"
        time.sleep(0.05)
    time.sleep(0.3)
    assert process.poll() is None, "the run ended before it could be interrupted"
    os.killpg(process.pid, signum)
    stdout, stderr = process.communicate(timeout=120)
    return subprocess.CompletedProcess(command, process.returncode, stdout, stderr)


LONG = [
    "--radius",
    "4",
    "--duration",
    "12",
    "--dt",
    "1e-5",
    "--cutoff",
    "4",
    "--nodes",
    "64",
    "--stored-nodes",
    "16",
    "--integrator",
    "explicit_euler",
    "--quiet",
]


@pytest.mark.parametrize(
    ("signum", "status", "tail"),
    [
        (signal.SIGINT, 130, ""),
        # what batch schedulers send: handled as Ctrl-C, said, 128 + 15
        pytest.param(signal.SIGTERM, 143, " (SIGTERM)", marks=pytest.mark.slow),
    ],
)
def test_ctrl_c_says_where_it_stopped_and_the_rerun_resumes_to_the_same_bytes(
    tmp_path, signum, status, tail
):
    out = tmp_path / "run"
    command = [*PY, "simulate", *LONG, "--checkpoint-every", "0.2", "-o", str(out)]
    run = _interrupt(command, out, ".*.ckpt.npz", signum)
    assert run.returncode == status, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in run.stderr, run.stderr
    assert lines[0].startswith("softcell: interrupted at t = ")
    assert lines[0].endswith(
        f"s of point 0 realization 0; rerun the same command to resume{tail}"
    ), lines[0]
    assert not list(out.glob("*.nc"))
    subprocess.run(command, check=True)
    subprocess.run([*PY, "simulate", *LONG, "-o", str(tmp_path / "whole")], check=True)
    name = "point000_realization0000.nc"
    assert (out / name).read_bytes() == (tmp_path / "whole" / name).read_bytes()


@pytest.mark.slow
def test_ctrl_c_on_two_workers_is_one_line_and_resumes(tmp_path):
    out = tmp_path / "run"
    flags = [*LONG[:1], "4,5", *LONG[2:]]
    command = [
        *PY,
        "simulate",
        *flags,
        "--workers",
        "2",
        "--checkpoint-every",
        "0.2",
        "-o",
        str(out),
    ]
    run = _interrupt(command, out, ".*.ckpt.npz")
    assert run.returncode == 130, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in run.stderr, run.stderr
    assert "interrupted at t = " in lines[0] and "rerun the same command" in lines[0]
    finished = len(list(out.glob("*.nc")))  # counted from what is on disk
    assert f"({finished} of 2 realizations finished)" in lines[0], lines[0]
    # The rerun, with a plugin warning: printed once by the command, not once per worker.
    env = {**os.environ, "SOFTCELL_DISABLE_PLUGINS": "nosuch"}
    rerun = subprocess.run(command, check=True, capture_output=True, text=True, env=env)
    assert rerun.stderr.count("softcell: warning: ") == 1, rerun.stderr
    assert "match no plugin" in rerun.stderr
    subprocess.run([*PY, "simulate", *flags, "-o", str(tmp_path / "whole")], check=True)
    for path in sorted(out.glob("*.nc")):
        assert path.read_bytes() == (tmp_path / "whole" / path.name).read_bytes()


# -- plugins ----------------------------------------------------------------------------------


def test_disabled_plugins_by_distribution_name_and_unknown_names_are_warned(tmp_path, monkeypatch):
    from test_registry import fake_entry_points

    from softcell.components.registry import PluginWarning, Registry

    eps = fake_entry_points(tmp_path, monkeypatch, broken="broken", good="good")
    # The warning names the distribution "softcell-fake": that name blocks its plugins
    # (spelt as pip compares names), so the broken one is never imported.
    with pytest.warns(PluginWarning, match="'nosuch', which match no plugin"):
        registry = Registry(entry_points=eps, disabled=["Softcell_Fake", "nosuch"])
    assert registry.skipped == [] and "fake_hysteresis" not in registry.names("stopgo_detector")
    registry = Registry(entry_points=eps, disabled=["broken"])  # the entry-point name
    assert registry.skipped == [] and "fake_hysteresis" in registry.names("stopgo_detector")


def test_plugins_lists_skipped_plugins_on_stdout_and_warns_once(tmp_path, monkeypatch, capsys):
    from test_registry import fake_entry_points

    from softcell.components import registry as reg

    eps = fake_entry_points(tmp_path, monkeypatch, broken="broken")
    monkeypatch.setattr(reg, "_override", [])
    monkeypatch.setattr(reg, "_default_registry", lambda: reg.Registry(entry_points=eps))
    assert main(["plugins"]) == 0
    captured = capsys.readouterr()
    assert "skipped (1)" in captured.out
    assert "broken: ImportError: this fake plugin needs a module that is not installed" in (
        captured.out
    )
    assert "distribution softcell-fake 1.2" in captured.out
    warned = [line for line in captured.err.splitlines() if "was skipped" in line]
    assert len(warned) == 1 and warned[0].startswith("softcell: warning: ")


# -- the property: a second request reuses exactly what it asked for, or stops -------------

FIRST = {
    "radius": [4.0, 5.0],
    "duration": 0.3,
    "dt": 1e-5,
    "cutoff": 4,
    "nodes": 64,
    "stored_nodes": 16,
}
FIRST_COMPONENTS = {"integrator": "explicit_euler"}

requests = st.fixed_dictionaries(
    {
        "radius": st.sampled_from([[4.0, 5.0], [4.0], [5.0, 4.0], [4.0, 6.0], [4.0, 5.0, 6.0]]),
        "duration": st.sampled_from([0.3, 0.2, 0.5]),
        "tension": st.sampled_from([None, 0.02, 0.03]),
        "seed": st.sampled_from([0, 1, 2**64 - 1]),
        "realizations": st.integers(1, 3),
        "integrator": st.sampled_from(["explicit_euler", "rodas4"]),
        "energy_terms": st.sampled_from(
            [["bending", "tension", "contact"], ["bending", "tension"]]
        ),
        "membrane": st.booleans(),
    }
)


@given(second=requests)
@example(
    second={
        "radius": [4.0, 5.0],
        "duration": 0.3,
        "tension": None,
        "seed": 0,
        "realizations": 2,
        "integrator": "explicit_euler",
        "energy_terms": ["bending", "tension", "contact"],
        "membrane": True,
    }
)
@example(
    second={
        "radius": [4.0, 5.0],
        "duration": 0.3,
        "tension": 0.02,
        "seed": 0,
        "realizations": 1,
        "integrator": "explicit_euler",
        "energy_terms": ["bending", "tension", "contact"],
        "membrane": True,
    }
)
@example(
    second={
        "radius": [4.0, 5.0, 6.0],
        "duration": 0.3,
        "tension": None,
        "seed": 0,
        "realizations": 1,
        "integrator": "explicit_euler",
        "energy_terms": ["bending", "tension", "contact"],
        "membrane": True,
    }
)
def test_a_second_request_reuses_only_identical_files_or_stops(world, second):
    from softcell.components.registry import default_registry
    from softcell.errors import SoftcellError
    from softcell.model.configuration import RunConfig
    from softcell.runner.ensemble import plan
    from softcell.runner.resume import resume_plan, stored_request

    out = world / "sim"  # made with FIRST, seed 0, 1 realization, the membrane
    values = {**FIRST, "radius": second["radius"], "duration": second["duration"]}
    if second["tension"] is not None:
        values["tension"] = second["tension"]
    config = RunConfig(parameters=values).updated(
        components={"integrator": second["integrator"], "energy_terms": second["energy_terms"]}
    )
    tasks = plan(
        config,
        out,
        realizations=second["realizations"],
        seed=second["seed"],
        membrane=second["membrane"],
        registry=default_registry(),
    )
    try:
        resume = resume_plan(tasks, out)
    except SoftcellError as exc:
        message = str(exc)
        assert " there, " in message or "no part of this request" in message
        return
    todo = {t.path for t in resume.todo}
    for task in tasks:
        if task.path not in todo:  # reused: made with exactly this request
            assert stored_request(Path(task.path))[0] == task.request()
    assert resume.reused == len(tasks) - len(todo)
    # Independently: the first run made realization 0 of radius 4 (point 0) and 5 (point 1);
    # a task may reuse its file only if every other setting is the first run's too.
    same_settings = (
        second["duration"] == 0.3
        and second["tension"] in (None, 0.02)
        and second["seed"] == 0
        and second["integrator"] == "explicit_euler"
        and second["membrane"]
        and second["energy_terms"] == ["bending", "tension", "contact"]
    )
    made = {0: 4.0, 1: 5.0}
    expected = sum(
        1
        for t in tasks
        if same_settings and t.realization == 0 and made.get(t.point) == second["radius"][t.point]
    )
    assert resume.reused == expected


def test_simulate_says_which_files_it_reused(tmp_path, capsys):
    # Before: a rerun said "3 files in OUT" whether it computed them or found them there.
    out = tmp_path / "run"
    assert main(["simulate", "--radius", "4", *SMALL, "--realizations", "2", "-o", str(out)]) == 0
    assert "reused" not in capsys.readouterr().err
    assert main(["simulate", "--radius", "4", *SMALL, "--realizations", "3", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert (
        f"2 of 3 file(s) in {out} already hold this request: reused as they are; computing 1" in err
    )
