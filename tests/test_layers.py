"""The house's layers, checked by parsing every module.

Each module of ``softcell`` belongs to a layer (see ``docs/architecture.md``) and may import only
from the layers below it; the two siblings ``plugins`` and ``io`` never import each other. Imports
inside functions count: they are arrows too, only hidden.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "softcell"

# layer of each top-level part of the package
LAYERS = {
    "config": 0,
    "errors": 0,
    "_version": 0,
    "kernels": 1,
    "core": 2,
    "plugins": 3,
    "io": 3,  # layer 4 in the table, but a sibling of plugins: neither imports the other
    "workflows": 5,
    "plugin": 4,  # the public facade for plugin authors: layers 0-3
    "cli": 6,
    "__main__": 6,
    "__init__": 6,
    "testing": 7,
}

ALLOWED = {
    "config": {"config", "errors", "_version"},
    "errors": {"config", "errors", "_version"},
    "_version": set(),
    "kernels": {"config", "errors", "_version", "kernels"},
    "core": {"config", "errors", "_version", "kernels", "core"},
    "plugins": {"config", "errors", "_version", "kernels", "core", "plugins"},
    "io": {"config", "errors", "_version", "kernels", "core", "io"},
    "plugin": {"config", "errors", "_version", "kernels", "core", "plugins", "plugin"},
    "workflows": {"config", "errors", "_version", "kernels", "core", "plugins", "io", "workflows"},
}


def part_of(module: str) -> str:
    """The top-level part of ``softcell.a.b`` (``a``), or ``__init__`` for ``softcell`` itself."""
    pieces = module.split(".")
    return pieces[1] if len(pieces) > 1 else "__init__"


def module_name(path: Path) -> str:
    relative = path.relative_to(PACKAGE.parent).with_suffix("")
    pieces = list(relative.parts)
    if pieces[-1] == "__init__":
        pieces.pop()
    return ".".join(pieces)


def imported_modules(path: Path, name: str | None = None) -> list[tuple[int, str]]:
    """Every ``softcell`` module imported anywhere in the file, with its line; ``name`` is the
    module's dotted name (by default from its place in the package)."""
    name = module_name(path) if name is None else name
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = [*_named_imports(path, name)]
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if node.module is None or node.level and not node.module:
                # ``from . import x``: each name may be a module
                found += [(node.lineno, f"{target}.{alias.name}") for alias in node.names]
            else:
                found.append((node.lineno, target))
    return [(line, module) for line, module in found if module.split(".")[0] == "softcell"]


MODULES = sorted(PACKAGE.rglob("*.py"))

#: Modules that import others by a name string, and the tuple of names they import: the
#: checker reads those tuples and counts each name as an import.
IMPORTS_BY_NAME = {"softcell.core.components.registry": "BUILTIN_PLUGINS"}

#: Arrows allowed against the layers, each for one reason: the registry registers the
#: built-in plugins (the layer above it) through the same hooks as third-party ones.
UPWARD = {"softcell.core.components.registry": {"plugins"}}


def _named_imports(path: Path, name: str) -> list[tuple[int, str]]:
    """The modules ``name`` imports by a name string (see :data:`IMPORTS_BY_NAME`)."""
    target = IMPORTS_BY_NAME.get(name)
    if target is None:
        return []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        targets = getattr(node, "targets", None) or [getattr(node, "target", None)]
        if any(isinstance(t, ast.Name) and t.id == target for t in targets):
            names = ast.literal_eval(node.value)
            return [(node.lineno, n) for n in names]
    raise AssertionError(f"{name} has no literal tuple {target}")


def test_every_import_by_name_is_a_literal_the_checker_reads():
    """``importlib.import_module`` only where the checker reads what it imports (or where the
    name comes from the user: entry points, the lazy public names of the package)."""
    readers = {
        "softcell.core.components.registry",  # BUILTIN_PLUGINS, and entry points
        "softcell",  # _LAZY: the public functions, imported on first use
        "softcell.core.engine.compiled",  # the package of a bound kernel, to hash its files
    }
    found = sorted(
        module_name(path)
        for path in MODULES
        if "import_module(" in path.read_text() and module_name(path) not in readers
    )
    assert not found, found
    assert {
        n
        for _, n in _named_imports(
            PACKAGE / "core/components/registry.py", "softcell.core.components.registry"
        )
    } >= {"softcell.plugins.rodas4", "softcell.plugins.bending"}


def test_every_part_has_a_layer():
    parts = {part_of(module_name(path)) for path in MODULES}
    assert parts <= set(LAYERS), parts - set(LAYERS)


@pytest.mark.parametrize("path", MODULES, ids=lambda path: module_name(path))
def test_imports_point_down(path):
    source = part_of(module_name(path))
    allowed = ALLOWED.get(source)
    if allowed is None:  # cli, the package's __init__, testing: may import anything
        return
    allowed = allowed | UPWARD.get(module_name(path), set())
    wrong = [
        f"{path.relative_to(PACKAGE.parent)}:{line} imports {module}"
        for line, module in imported_modules(path)
        if part_of(module) not in allowed
    ]
    assert not wrong, "\n".join(wrong)


def test_the_checker_sees_inner_and_relative_imports(tmp_path):
    """The parser finds an import hidden in a function and resolves a relative one (the probe
    is written to a temporary folder: the checkout may be read-only)."""
    fake = tmp_path / "_layer_probe.py"
    source = "def f():\n    from ..workflows import ensemble\n    import softcell.io.files\n"
    fake.write_text(source)
    found = [module for _, module in imported_modules(fake, "softcell.core._layer_probe")]
    assert found == ["softcell.workflows", "softcell.io.files"]
    assert [part_of(module) for module in found] == ["workflows", "io"]
