"""The public plugin API: one module, ``softcell.plugin``, is all a plugin author imports."""

import ast
import re
import types
from pathlib import Path

import pytest

import softcell.plugin
from softcell.core.components.contracts import CONTRACTS

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
    wrong = [
        line for line in softcell_imports(source, where) if not line.endswith(" softcell.plugin")
    ]
    assert not wrong, "\n".join(wrong)


def test_the_checker_sees_a_private_import():
    found = softcell_imports("import softcell.core.params\nfrom softcell.plugin import X\n", "f")
    assert found == ["f:1 softcell.core.params", "f:2 softcell.plugin"]


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
        "RunAndTumble",
        "run_and_tumble_drive",
    } <= names
    for name in names:
        assert hasattr(softcell.plugin, name), name
        value = getattr(softcell.plugin, name)
        if callable(value):
            assert (value.__doc__ or "").strip(), f"softcell.plugin.{name} has no docstring"


def test_the_docs_example_protocol_runs():
    """The protocol of docs/plugins.md that only changes the schedule: phases of 2-5 ms."""
    import numpy as np

    from softcell.core.params import Parameters

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
