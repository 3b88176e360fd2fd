"""Meta-tests that keep the plugin documentation honest."""

import inspect
import re
from pathlib import Path

import pytest

from softcell.components import hookspecs
from softcell.components.contracts import CONTRACTS
from softcell.components.registry import KINDS

DOCS = Path(__file__).parents[1] / "docs"
DOC = (DOCS / "plugins.md").read_text()


def test_every_hook_appears_with_its_signature():
    hooks = [n for n in dir(hookspecs) if n.startswith("softcell_")]
    assert sorted(hooks) == sorted(KINDS)
    for name in hooks:
        hook = inspect.signature(getattr(hookspecs, name))  # annotations as written
        signature = f"{name}({', '.join(hook.parameters)}) -> {hook.return_annotation}"
        assert signature in DOC, f"docs/plugins.md lacks `{signature}`"


def test_every_contract_method_is_documented():
    for contract in CONTRACTS.values():
        assert f"class {contract.__name__}" in DOC
        for method in sorted(contract.__abstractmethods__):
            assert f"{method}(" in DOC, f"docs/plugins.md lacks {contract.__name__}.{method}"


def test_python_examples_in_the_docs_run(tmp_path, monkeypatch):
    import re

    monkeypatch.chdir(tmp_path)  # examples may write files
    for name in ("getting-started.md", "model.md", "analysis.md"):
        text = (Path(__file__).parents[1] / "docs" / name).read_text()
        blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
        assert blocks, f"docs/{name} has no python example"
        for block in blocks:
            exec(compile(block, f"docs/{name}", "exec"), {})


def test_the_model_page_lists_every_model_parameter():
    from softcell.model.parameters import MODEL_PARAMETERS

    text = (Path(__file__).parents[1] / "docs" / "model.md").read_text()
    table = text.split("## 2. Parameters")[1].split("## 3.")[0]
    missing = [name for name in MODEL_PARAMETERS if f"`{name}`" not in table]
    assert not missing, f"docs/model.md section 2 lacks {missing}"


def test_docstrings_cite_sections_that_exist():
    import re

    root = Path(__file__).parents[1]
    text = (root / "docs" / "model.md").read_text()
    sections = set(re.findall(r"^## (\d+)\. ", text, flags=re.M))
    cited = set()
    for path in [
        *(root / "softcell").rglob("*.py"),
        *(root / "docs").glob("*.md"),
        root / "README.md",
    ]:
        for first, last in re.findall(r"model\.md §(\d+)(?:-(\d+))?", path.read_text()):
            cited |= {str(n) for n in range(int(first), int(last or first) + 1)}
    assert cited and cited <= sections, cited - sections


def documented_commands() -> list[tuple[str, str]]:
    """Every ``softcell`` command line of the Markdown pages (continuations joined, comments
    and pipes dropped), with the page it is on."""
    import re
    import shlex

    root = Path(__file__).parents[1]
    pages = [
        root / "README.md",
        *sorted((root / "docs").glob("*.md")),
        root / "examples" / "plugin" / "README.md",
    ]
    found = []
    for page in pages:
        for block in re.findall(r"```(?:console|bash)\n(.*?)```", page.read_text(), flags=re.S):
            text = block.replace("\\\n", " ")
            for line in text.splitlines():
                line = line.strip().removeprefix("$ ")
                if line.startswith("softcell "):
                    words = shlex.split(line.split("|")[0], comments=True)
                    found.append((page.name, shlex.join(words[1:])))
    return found


COMMANDS = documented_commands()


def test_the_documented_commands_are_found():
    assert len(COMMANDS) >= 15


@pytest.mark.parametrize("page, line", COMMANDS, ids=[f"{p}: {c[:40]}" for p, c in COMMANDS])
def test_documented_commands_parse(page, line):
    """Each documented command line is one the command line accepts (the example plugin's
    components registered, as its pages assume it is installed)."""
    import shlex
    import sys

    from softcell.cli import parse_arguments
    from softcell.testing import registered

    sys.path.insert(0, str(Path(__file__).parents[1] / "examples" / "plugin" / "src"))
    try:
        from softcell_example import plugin
    finally:
        sys.path.pop(0)
    with registered(plugin, name="example"):
        args = parse_arguments(shlex.split(line))
    assert callable(args.func)
    for source in getattr(args, "inputs", None) or []:  # the data-safety rule of analyze
        assert Path(source) not in Path(args.output).parents, (
            f"{page}: `softcell {line}` writes inside its input {source}"
        )


def test_the_units_check_reads_the_numpydoc_sections():
    """The docs build's check (docs/conf.py): a quantity without a unit is named, one with
    its unit, a count and a name are not."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "docs_conf", Path(__file__).resolve().parents[1] / "docs" / "conf.py"
    )
    conf = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(conf)
    doc = """Do it.

    Parameters
    ----------
    radius : float
        The membrane's radius.
    speed : float
        Threshold (cm/s).
    nodes : int
        Points.
    name : str
        A component.

    Returns
    -------
    ndarray
        The MSD.
    """
    import inspect

    assert conf._units_missing(inspect.cleandoc(doc)) == [
        "Parameters 'radius'",
        "Returns 'ndarray'",
    ]


def test_the_module_map_is_made_from_the_docstrings():
    """docs/architecture.md lists every module with its docstring's first sentence (rerun
    ``python docs/module_map.py`` after adding, moving or describing a module)."""
    import importlib.util

    root = Path(__file__).parents[1]
    spec = importlib.util.spec_from_file_location("module_map", root / "docs" / "module_map.py")
    module_map = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module_map)
    page = module_map.PAGE.read_text(encoding="utf-8")
    assert page == module_map.page_with_map(page)
    assert "`softcell/integrators/rodas4/templates/loop.py`" in page


def test_getting_started_shows_the_steps_reproduce_prints():
    from softcell.paper.reproduce import QUICK, step_count

    text = (DOCS / "getting-started.md").read_text()
    steps = re.findall(r"^\[(\d+)/(\d+)\] (.*)$", text, flags=re.M)
    total = step_count(QUICK)
    assert [(int(k), int(n)) for k, n, _ in steps] == [(k, total) for k in range(1, total + 1)]
    assert steps[0][2] == f"simulating {QUICK.describe()}"
