"""The on-disk cache of composed models (softcell.engine.compiled): a second process
reads what the first compiled, a changed plugin is never served its old code, corrupt entries
are rebuilt with a warning, processes starting at once do not trip over each other."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from softcell.engine import compiled
from softcell.errors import CacheWarning
from softcell.io import model_cache

SOURCE = textwrap.dedent("""
    from numba import njit


    @njit(**JIT_FLAGS)
    def total(a):
        s = 0.0
        for v in a:
            s += kernel(v) + OFFSET
        return s
""")

# A plugin package with one kernel, written into a temporary folder put on sys.path.
PLUGIN = textwrap.dedent("""
    from numba import njit


    @njit
    def kernel(x):
        return {factor} * x
""")

# In a new process: compose the plugin's kernel, call it, print the result and numba's
# cache statistics of the composed function.
CHILD = textwrap.dedent("""
    import json, sys
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    from softcell.engine import compiled
    from cachedplugin import kernel
    source = open(sys.argv[2]).read()
    module = compiled.compile_module("test", source, {"kernel": kernel, "OFFSET": 1.0})
    value = module.total(np.arange(4.0))
    stats = module.total.stats
    print(json.dumps({"value": value, "hits": sum(stats.cache_hits.values()),
                      "misses": sum(stats.cache_misses.values())}))
""")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    root = tmp_path / "cache"
    monkeypatch.setenv(model_cache.CACHE_ENV, str(root))
    return root


def composed(cache: Path) -> list[model_cache.Entry]:
    """The cache's entries of composed models (not the one of softcell's own kernels, made
    when a process first imports them with ``cache`` as its cache)."""
    return [e for e in model_cache.entries(cache) if e.label != model_cache.KERNELS]


def _plugin(folder: Path, factor: float) -> Path:
    package = folder / "cachedplugin"
    package.mkdir(parents=True, exist_ok=True)
    (package / "__init__.py").write_text(PLUGIN.format(factor=factor))
    return folder


def _child(cache: Path, plugin: Path, source: Path) -> subprocess.Popen:
    env = {**os.environ, model_cache.CACHE_ENV: str(cache)}
    return subprocess.Popen(
        [sys.executable, "-c", CHILD, str(plugin), str(source)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _result(process: subprocess.Popen) -> dict:
    out, err = process.communicate(timeout=300)
    assert process.returncode == 0, err
    assert "CacheWarning" not in err, err  # writers at once never see each other as corrupt
    return json.loads(out.strip().splitlines()[-1])


def test_a_second_process_reads_the_compiled_function_and_a_changed_plugin_recompiles(
    cache, tmp_path
):
    source = tmp_path / "source.py"
    source.write_text(SOURCE)
    plugin = _plugin(tmp_path / "site", 2.0)
    first = _result(_child(cache, plugin, source))
    second = _result(_child(cache, plugin, source))
    assert first == {"value": 2.0 * 6 + 4, "hits": 0, "misses": 1}
    assert second == {"value": 2.0 * 6 + 4, "hits": 1, "misses": 0}
    _plugin(tmp_path / "site", 3.0)  # the plugin's code changes: never its old entry
    third = _result(_child(cache, plugin, source))
    assert third == {"value": 3.0 * 6 + 4, "hits": 0, "misses": 1}
    assert len(composed(cache)) == 2


def test_processes_starting_at_once_share_one_entry(cache, tmp_path):
    source = tmp_path / "source.py"
    source.write_text(SOURCE)
    plugin = _plugin(tmp_path / "site", 2.0)
    children = [_child(cache, plugin, source) for _ in range(6)]
    results = [_result(c) for c in children]
    assert {r["value"] for r in results} == {16.0}
    assert len(composed(cache)) == 1
    assert _result(_child(cache, plugin, source))["hits"] == 1


@njit
def _double(x):
    return 2.0 * x


def _compile():
    return compiled.compile_module("test", SOURCE, {"kernel": _double, "OFFSET": 1.0})


def _forget():
    compiled._LOADED.clear()


def test_a_run_knows_whether_its_first_call_compiles(cache):
    _forget()
    mark = compiled.loaded_count()
    assert not compiled.first_call_compiles(mark)  # nothing loaded
    module = _compile()
    assert compiled.first_call_compiles(mark)  # loaded, numba has nothing on disk
    assert module.total(np.arange(3.0)) == 2.0 * 3 + 3
    assert not compiled.first_call_compiles(mark)  # compiled once on this machine
    _forget()  # a new process: loads the entry from disk, nothing to compile
    mark = compiled.loaded_count()
    _compile()
    assert not compiled.first_call_compiles(mark)


@pytest.mark.parametrize("damage", ["index", "data", "source"])
def test_a_corrupt_entry_is_rebuilt_with_a_warning(cache, damage):
    module = _compile()
    assert module.total(np.arange(4.0)) == 16.0
    (folder,) = [e.path for e in composed(cache)]
    if damage == "source":
        path = folder / model_cache.SOURCE
    else:
        (path,) = (folder / "__pycache__").glob("*.nbi" if damage == "index" else "*.nbc")
    path.write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])
    _forget()
    with pytest.warns(CacheWarning, match="corrupt"):
        module = _compile()
    assert module.total(np.arange(4.0)) == 16.0
    _forget()
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        assert _compile().total(np.arange(4.0)) == 16.0  # whole again


def test_a_closure_is_compiled_in_memory_with_a_warning(cache):
    factor = 5.0

    @njit
    def closure(x):
        return factor * x

    with pytest.warns(CacheWarning, match="closure"):
        module = compiled.compile_module("test", SOURCE, {"kernel": closure, "OFFSET": 0.0})
    assert module.total(np.arange(4.0)) == 30.0
    assert composed(cache) == []


def test_bindings_other_than_compiled_functions_and_scalars_are_refused(cache):
    with pytest.raises(TypeError, match="OFFSET"):
        compiled.compile_module("test", SOURCE, {"kernel": _double, "OFFSET": np.ones(3)})


def test_the_key_covers_constants_and_imports(cache, tmp_path):
    base = compiled.entry_key(SOURCE, {"kernel": _double, "OFFSET": 1.0})
    assert compiled.entry_key(SOURCE, {"kernel": _double, "OFFSET": 2.0}) != base
    plugin = _plugin(tmp_path / "site", 2.0)
    sys.path.insert(0, str(plugin))
    try:
        importing = SOURCE + "\nfrom cachedplugin import kernel as helper\n"
        before = compiled.entry_key(importing, {"kernel": _double, "OFFSET": 1.0})
        (plugin / "cachedplugin" / "__init__.py").write_text(PLUGIN.format(factor=7.0))
        assert compiled.entry_key(importing, {"kernel": _double, "OFFSET": 1.0}) != before
    finally:
        sys.path.remove(str(plugin))
        sys.modules.pop("cachedplugin", None)


def test_the_cache_command_shows_and_clears(cache, capsys):
    from softcell.cli import main

    _compile()
    assert main(["cache"]) == 0
    out = capsys.readouterr().out
    assert str(cache) in out and "1 entries" in out and "test-" in out
    assert main(["cache", "clear", "--stale"]) == 0
    assert "removed 0 stale entries" in capsys.readouterr().out
    assert main(["cache", "clear"]) == 0
    assert "removed 1 entries" in capsys.readouterr().out
    assert composed(cache) == []


def test_the_plugin_guide_example_composes_and_runs(cache):
    import re
    from types import SimpleNamespace

    from softcell.builtins.run_and_tumble import run_and_tumble_drive

    text = (Path(__file__).parents[1] / "docs" / "plugins.md").read_text()
    (block,) = [
        b for b in re.findall(r"```python\n(.*?)```", text, flags=re.S) if "compile_module" in b
    ]
    namespace: dict = {}
    exec(compile(block, "docs/plugins.md", "exec"), namespace)
    loop = namespace["build_loop"](SimpleNamespace(drive=run_and_tumble_drive))
    out, expected = np.zeros(3), np.zeros(3)
    args = (0, 1.0, np.array([1.0, 2.0, 0.5]), np.array([10.0, 3.0, 2.0]), np.array([0.04, 150.0]))
    loop(*args, out)
    run_and_tumble_drive(*args, expected)
    assert np.array_equal(out, expected) and np.any(out != 0.0)
    assert [e.label for e in composed(cache)] == ["my-loop"]


MODEL_CHILD = textwrap.dedent("""
    import json
    import numpy as np
    from softcell.engine import build_integrator, build_model, compiled, initial_state
    from softcell.components.registry import default_registry
    from softcell.engine.cell import realization_rng
    from softcell.testing.compare import PROTOCOL, TERMS, parameters

    params = parameters(6.0, 0.2)
    registry = default_registry()
    mark = compiled.loaded_count()
    model = build_model(params, TERMS, PROTOCOL, registry=registry)
    stepper = build_integrator("rodas4", params, registry).build(model)
    compiles = compiled.first_call_compiles(mark)
    modes, pose, schedule = initial_state(model, realization_rng(0, 0, 0))
    state = stepper.start(modes, pose, schedule)
    stepper.sample(state, schedule, np.array([0.2]))
    stats = stepper.integrate.stats
    print(json.dumps({"pose": state["pose"].tolist(), "compiles": compiles,
                      "hits": sum(stats.cache_hits.values()),
                      "misses": sum(stats.cache_misses.values())}))
""")


@pytest.mark.slow
def test_the_built_in_model_is_compiled_once_per_machine(cache):
    """A new process reads rodas4's loop from the cache the first one wrote, and gets the
    same numbers."""
    env = {**os.environ, model_cache.CACHE_ENV: str(cache)}
    runs = []
    for _ in range(2):
        done = subprocess.run(
            [sys.executable, "-c", MODEL_CHILD],
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert done.returncode == 0, done.stderr
        runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    assert (runs[0]["hits"], runs[0]["misses"], runs[0]["compiles"]) == (0, 1, True)
    assert (runs[1]["hits"], runs[1]["misses"], runs[1]["compiles"]) == (1, 0, False)
    assert runs[0]["pose"] == runs[1]["pose"]
    labels = {e.label for e in composed(cache)}
    assert {"rodas4-loop", "rodas4-grid", "partials", "hessians", "fd-drive"} <= labels


def test_an_unwritable_cache_compiles_in_memory_with_a_warning(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv(model_cache.CACHE_ENV, str(blocker / "cache"))
    with pytest.warns(CacheWarning, match="cannot write"):
        module = compiled.compile_module("test", SOURCE, {"kernel": _double, "OFFSET": 1.0})
    assert module.total(np.arange(4.0)) == 16.0


def test_cache_clear_on_a_results_folder_removes_nothing(tmp_path, monkeypatch, capsys):
    # $SOFTCELL_CACHE_DIR pointing at a user's results: nothing there is softcell's cache.
    from softcell.cli import main

    results = tmp_path / "results"
    (results / "simulations").mkdir(parents=True)
    (results / "simulations" / "point000_realization0000.nc").write_bytes(b"data")
    (results / "figures").mkdir()
    (results / "figures" / "fig2.png").write_bytes(b"png")
    (results / "report.md").write_text("# report\n")
    monkeypatch.setenv(model_cache.CACHE_ENV, str(results))
    assert main(["cache"]) == 0
    out = capsys.readouterr().out
    assert "0 entries" in out and "not a cache: 3 item(s) softcell did not make" in out
    assert main(["cache", "clear"]) == 2
    err = capsys.readouterr().err
    assert "is not a softcell cache: it holds 3 item(s) softcell did not make" in err
    assert "nothing removed" in err
    assert sorted(p.name for p in results.iterdir()) == ["figures", "report.md", "simulations"]
    assert (results / "simulations" / "point000_realization0000.nc").read_bytes() == b"data"


def test_cache_clear_says_what_it_could_not_remove(cache, capsys, monkeypatch):
    from softcell.cli import main

    _compile()
    (entry,) = composed(cache)
    real = model_cache.shutil.rmtree

    def refuse(path, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(model_cache.shutil, "rmtree", refuse)
    assert main(["cache", "clear"]) == 2
    err = capsys.readouterr().err
    assert f"could not remove 1 of 1 entries from {cache}" in err
    assert "PermissionError: Permission denied" in err and "0 removed" in err
    monkeypatch.setattr(model_cache.shutil, "rmtree", real)
    assert composed(cache) == [entry]


def test_stale_without_clear_is_refused(cache, capsys):
    from softcell.cli import main

    assert main(["cache", "--stale"]) == 2
    assert "--stale goes with 'clear'" in capsys.readouterr().err


def test_the_kernels_cache_files_live_in_the_cache_and_are_cleared(tmp_path):
    # Before: numba wrote them beside the sources (site-packages/softcell/**/__pycache__),
    # where `softcell cache clear` never looked.
    cache = tmp_path / "cache"
    code = (
        "import numpy as np\n"
        "from softcell.engine.kernels.runs import run_lengths\n"
        "run_lengths(np.array([1, 1, 0, 1], dtype=np.int8), np.zeros(4, dtype=np.int64))\n"
        "print(run_lengths._cache._cache_path)\n"
    )
    env = {**os.environ, "SOFTCELL_CACHE_DIR": str(cache)}
    run = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    entry_folder = model_cache.kernel_entry(cache)
    assert entry_folder.name.startswith("kernels-")
    assert Path(run.stdout.strip()) == entry_folder / "engine" / "kernels"
    assert list((entry_folder / "engine" / "kernels").glob("runs.run_lengths-*.nbi"))
    (entry,) = model_cache.entries(cache)
    assert entry.label == model_cache.KERNELS and not entry.stale
    assert model_cache.clear(cache) == 1 and not entry_folder.exists()


def test_the_kernels_entry_is_named_by_the_code(tmp_path, monkeypatch):
    # numba checks a cache file against its own function's source only: a kernel calling an
    # edited function of another file kept its old compiled code. Edited code (another
    # digest of the compiled parts) must get another entry, and the old one is stale.
    cache = tmp_path / "cache"
    old = model_cache.kernel_entry(cache)
    old.mkdir(parents=True)
    (old / "entry.json").write_text(
        json.dumps({**model_cache._kernel_meta(), "code": "0" * 20}), encoding="utf-8"
    )
    (entry,) = model_cache.entries(cache)
    assert entry.stale
    monkeypatch.setattr(model_cache, "_kernel_code", lambda: "f" * 20)
    assert model_cache.kernel_entry(cache) != old


def _flip_one_byte(path: Path, at: float) -> None:
    data = bytearray(path.read_bytes())
    data[int(len(data) * at)] ^= 0x10
    path.write_bytes(bytes(data))


def test_a_damaged_kernel_cache_file_is_reported_and_compiled_again(tmp_path):
    # Before: one changed byte in the object code of a kernel's .nbc unpickled fine and the
    # process died of an illegal instruction (exit 132); `softcell cache` saw nothing wrong.
    cache = tmp_path / "cache"
    code = (
        "import numpy as np\n"
        "from softcell.engine.kernels.runs import run_lengths\n"
        "print(run_lengths(np.array([1, 1, 0, 1, 1, 1], dtype=np.int8),"
        " np.zeros(6, dtype=np.int64)))\n"
    )
    env = {**os.environ, "SOFTCELL_CACHE_DIR": str(cache)}

    def run():
        return subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300
        )

    first = run()
    assert first.returncode == 0, first.stderr
    (data,) = model_cache.kernel_entry(cache).glob("engine/kernels/runs.run_lengths-*.nbc")
    _flip_one_byte(data, 0.02)
    (entry,) = model_cache.entries(cache)
    assert "run_lengths" in entry.damaged and "sha256" in entry.damaged
    again = run()
    assert again.returncode == 0, again.stderr
    assert again.stdout == first.stdout
    assert "CacheWarning" in again.stderr and "does not match its sha256" in again.stderr
    (entry,) = model_cache.entries(cache)
    assert not entry.damaged  # compiled again and rewritten
    _flip_one_byte(data, 0.5)
    assert model_cache.clear(cache, stale_only=True) == 1
