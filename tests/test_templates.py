"""Generated code that reads as code: every template declares the names it is given, and a
missing or extra binding is refused with the template's path."""

from __future__ import annotations

import ast
import builtins
from pathlib import Path

import pytest

from softcell.engine.compiled import compile_module
from softcell.engine.compose import template
from softcell.errors import ContractError

PACKAGE = Path(__file__).resolve().parents[1] / "softcell"
TEMPLATES = sorted(
    p for folder in PACKAGE.rglob("templates") for p in folder.glob("*.py") if p.stem != "__init__"
)


def _loader_block(tree: ast.Module) -> ast.If:
    """The template's ``if TYPE_CHECKING:`` block, which names what the loader binds."""
    found = [
        n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING"
    ]
    assert len(found) == 1, "a template names its bound names in one `if TYPE_CHECKING:` block"
    return found[0]


def _undefined(source: str) -> set[str]:
    """Names the source reads but never defines (imports, defs, assignments, arguments),
    leaving out the ``if TYPE_CHECKING:`` block that names them for readers and the linter."""
    tree = ast.parse(source)
    skip = {id(n) for n in ast.walk(_loader_block(tree))}
    read, defined = set(), set(dir(builtins))
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Name):
            (read if isinstance(node.ctx, ast.Load) else defined).add(node.id)
        elif isinstance(node, ast.FunctionDef | ast.ClassDef):
            defined.add(node.name)
        elif isinstance(node, ast.arg):
            defined.add(node.arg)
        elif isinstance(node, ast.alias):
            defined.add((node.asname or node.name).split(".")[0])
    return read - defined


def _named_for_the_linter(source: str) -> set[str]:
    block = _loader_block(ast.parse(source))
    return {n.id for n in ast.walk(block) if isinstance(n, ast.Name) and n.id != "TYPE_CHECKING"}


def _declared(source: str) -> set[str]:
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", None) == "BOUND":
            return set(ast.literal_eval(node.value))
    raise AssertionError("no BOUND declaration")


@pytest.mark.parametrize("path", TEMPLATES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_a_template_declares_exactly_the_names_it_uses_without_defining(path):
    """BOUND lists the names the loader binds (besides the numba flags: JIT_FLAGS, and
    LEAN_JIT_FLAGS without reference counting, for functions that never allocate); the
    ``if TYPE_CHECKING:`` block names the same for readers and the linter (no ``noqa``)."""
    flags = {"JIT_FLAGS", "LEAN_JIT_FLAGS"}
    source = path.read_text()
    used = _undefined(source)
    assert used - flags == _declared(source) and used & flags
    assert _named_for_the_linter(source) == used
    assert "noqa: F821" not in source


def test_a_missing_or_an_extra_binding_names_the_template():
    source = template("softcell.engine.templates", "fd_drive_jacobian.py")
    with pytest.raises(ContractError, match=r"fd_drive_jacobian\.py .*drive not bound"):
        compile_module("fd-drive", source, {})
    with pytest.raises(ContractError, match=r"jacobian\.py .*SPARE bound but not declared"):
        compile_module("fd-drive", source, {"drive": None, "SPARE": 1.0})


def test_a_traceback_into_a_compiled_template_has_the_templates_line(tmp_path, monkeypatch):
    """The cached copy holds the template line for line, and its last line names the
    template: a traceback's line number is the template's own."""
    import traceback

    from softcell.engine.compose import Template
    from softcell.io import model_cache

    monkeypatch.setenv(model_cache.CACHE_ENV, str(tmp_path / "cache"))
    text = '"""A probe."""\n\nBOUND = ("LIMIT",)\n\n\ndef check(x):\n    if x > LIMIT:\n'
    text += '        raise ValueError("too large")\n'
    source = Template(text, "/somewhere/templates/probe.py")
    module = compile_module("probe", source, {"LIMIT": 1.0})
    with pytest.raises(ValueError) as info:
        module.check(2.0)
    frame = traceback.extract_tb(info.tb)[-1]
    assert frame.lineno == 8 and frame.line == 'raise ValueError("too large")'
    stored = Path(frame.filename).read_text().splitlines()
    assert stored[:8] == text.splitlines()
    assert stored[-1].startswith("# softcell compiled model from /somewhere/templates/probe.py")
