"""The public plugin API: ``softcell.plugin`` (the contracts) and ``softcell.plugin.blocks``
(what to build on) are all a plugin author imports."""

import ast
import re
import types
from pathlib import Path

import pytest

import softcell.plugin
from softcell.components.contracts import CONTRACTS

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "plugin" / "src"
OWN = "softcell_example"  # the example's own package


def softcell_imports(source: str, where: str) -> list[str]:
    """Every module of softcell that ``source`` imports from, as ``where:line module``."""
    found = []
    for node in ast.walk(ast.parse(source, filename=where)):
        if isinstance(node, ast.Import):
            names = [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and not node.level:
            names = [(node.lineno, node.module or "")]
        else:
            continue
        found += [
            f"{where}:{line} {name}" for line, name in names if name.split(".")[0] == "softcell"
        ]
    return found


def python_blocks(markdown: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", markdown.read_text(), flags=re.S)


SOURCES = [(str(p.relative_to(ROOT)), p.read_text()) for p in sorted(EXAMPLE.rglob("*.py"))]
SOURCES += [
    (f"docs/plugins.md block {i}", block)
    for i, block in enumerate(python_blocks(ROOT / "docs" / "plugins.md"))
]


@pytest.mark.parametrize("where, source", SOURCES, ids=[w for w, _ in SOURCES])
def test_plugin_code_imports_only_softcell_plugin(where, source):
    public = (" softcell.plugin", " softcell.plugin.blocks", " softcell.testing")
    wrong = [line for line in softcell_imports(source, where) if not line.endswith(public)]
    assert not wrong, "\n".join(wrong)


def test_the_checker_sees_a_private_import():
    found = softcell_imports(
        "import softcell.model.parameters\nfrom softcell.plugin import X\n", "f"
    )
    assert found == ["f:1 softcell.model.parameters", "f:2 softcell.plugin"]


def test_the_api_holds_every_contract_and_what_it_promises():
    names = set(softcell.plugin.__all__)
    assert {c.__name__ for c in CONTRACTS.values()} <= names
    assert {
        "hookimpl",
        "Stepper",
        "Schedule",
        "Model",
        "ParameterSpec",
        "ParameterError",
        "PHASE_RUN",
        "PHASE_TUMBLE",
        "registered",
    } <= names
    # The contracts, what an event senses, parameters, codes and registration: no more.
    assert len(names) == 25
    for name in names:
        assert hasattr(softcell.plugin, name), name
        value = getattr(softcell.plugin, name)
        if callable(value):
            assert (value.__doc__ or "").strip(), f"softcell.plugin.{name} has no docstring"


def test_the_docs_example_protocol_runs():
    """The protocol of docs/plugins.md that only changes the schedule: phases of 2-5 ms."""
    import numpy as np

    from softcell.model.parameters import Parameters

    namespace: dict = {}
    block = next(b for b in python_blocks(ROOT / "docs" / "plugins.md") if "Flicker" in b)
    exec(compile(block, "docs/plugins.md", "exec"), namespace)
    flicker = namespace["Flicker"](Parameters())
    schedule = flicker.schedule(np.random.default_rng(1), 1.0)
    lengths = np.diff(schedule.start)
    assert lengths.min() >= 0.002 and lengths.max() <= 0.005
    assert set(schedule.phase[:2]) == {softcell.plugin.PHASE_RUN, softcell.plugin.PHASE_TUMBLE}
    plugin = types.SimpleNamespace(
        softcell_driving_protocols=namespace["softcell_driving_protocols"]
    )
    with softcell.plugin.registered(plugin) as registry:
        assert registry.get("driving_protocol", "flicker") is namespace["Flicker"]


def test_the_building_blocks_moved_and_the_old_names_warn():
    import softcell.plugin.blocks as blocks

    for name in softcell.plugin.MOVED:
        assert name in blocks.__all__ and name not in softcell.plugin.__all__
        with pytest.warns(DeprecationWarning, match=f"softcell.plugin.{name} moved to"):
            assert getattr(softcell.plugin, name) is getattr(blocks, name)
    with pytest.warns(DeprecationWarning):
        from softcell.plugin import RunAndTumble  # noqa: F401
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        softcell.plugin.nothing  # noqa: B018


def test_the_renamed_energy_term_attributes_still_work_with_a_warning():
    with pytest.warns(DeprecationWarning, match="couples_bot was renamed reads_pose"):

        class Old(softcell.plugin.EnergyTerm):
            couples_bot = True
            acts_on_bot = True

    assert Old.reads_pose and Old.has_bot_energy


def test_a_run_configuration_naming_some_kinds_takes_the_defaults_for_the_others():
    from softcell.components.registry import default_registry
    from softcell.model.configuration import DEFAULT_COMPONENTS, RunConfig

    config = RunConfig(components={"integrator": "explicit_euler"})
    assert config.components == {**DEFAULT_COMPONENTS, "integrator": "explicit_euler"}
    config.check_components(default_registry())


def test_the_trap_recipe_of_the_plugin_guide_holds_the_bot(tmp_path, monkeypatch):
    # docs/plugins.md: "A trap on the bot's centre", run as it is written there.
    import sys

    import numpy as np
    import xarray as xr

    from softcell.cli import main
    from softcell.plugin import registered
    from softcell.testing import check_component

    text = (Path(__file__).parents[1] / "docs" / "plugins.md").read_text(encoding="utf-8")
    (block,) = re.findall(r"\*A trap on the bot's centre\*.*?```python\n(.*?)```", text, re.S)
    (tmp_path / "trap_recipe.py").write_text(block, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = __import__("trap_recipe")
    assert isinstance(module, types.ModuleType) and "trap_recipe" in sys.modules
    check_component(module.Trap)
    common = ["simulate", "--radius", "5", "--duration", "20", "--quiet"]
    with registered(module):
        terms = ["--energy-terms", "bending,tension,contact,trap", "--trap-stiffness", "0.01"]
        assert main([*common, *terms, "-o", str(tmp_path / "trapped")]) == 0
    assert main([*common, "-o", str(tmp_path / "free")]) == 0

    def distance(folder):
        with xr.open_dataset(folder / "point000_realization0000.nc") as ds:
            return float(np.hypot(ds.bot_x, ds.bot_y).mean())

    assert distance(tmp_path / "trapped") < 2.0 < 5.0 < distance(tmp_path / "free")


def test_the_deprecation_warnings_speak_of_this_version_and_the_next():
    """A rename is announced "in softcell X, ... until Y": X is at most the version being
    built (``softcell --version``) and Y above it, so a shim past its date fails here."""
    import re
    import warnings

    import softcell
    from softcell.components.contracts import EnergyTerm
    from softcell.plugin import MOVED

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")

        class Old(EnergyTerm):  # noqa: F841 (defined for its warning)
            couples_bot = True

        getattr(softcell.plugin, MOVED[0])
    messages = [str(w.message) for w in caught if w.category is DeprecationWarning]
    assert len(messages) == 2

    def release(text: str) -> tuple[int, int]:
        major, minor = text.split(".")[:2]
        return int(major), int(minor)

    now = release(softcell.__version__)
    for message in messages:
        (since,) = re.findall(r"in softcell (\d+\.\d+)", message)
        (until,) = re.findall(r"until (\d+\.\d+)", message)
        assert release(since) <= now < release(until), (message, softcell.__version__)
