"""The house's rooms, checked by parsing every module.

Each module of ``softcell`` lives in a room (a folder named by a concept; see
``docs/architecture.md``). The rooms stand on levels, and a module imports only from rooms on
lower levels or from its own room; rooms on one level do not import each other. Imports inside
functions count (they are arrows too, only hidden); imports that only a type checker runs
(under ``if TYPE_CHECKING:``) do not. No module imports itself back through others.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "softcell"

#: The levels of the house, lowest first: each room imports only from lower levels and from
#: itself. The last three hold the faces the public sees: the plugin authors' API, the test
#: helpers and the command line, and the package itself.
LEVELS: tuple[tuple[str, ...], ...] = (
    ("_version", "errors", "settings"),
    ("kernels",),  # softcell.engine.kernels: compiled functions on arrays
    ("model",),
    ("schema",),
    ("components",),
    ("engine",),
    ("builtins", "integrators"),
    ("analysis",),
    ("io",),
    ("video",),
    ("runner",),
    ("paper",),
    ("studies",),
    ("fit",),  # a search of the unknowns runs the studies' variants
    ("plugin",),
    ("testing", "cli"),
    ("__main__", "__init__"),
)
LEVEL = {room: level for level, rooms in enumerate(LEVELS) for room in rooms}
#: Rooms of the lowest level import each other (errors and settings know the version).
SHARED_LEVELS = {0}

#: Modules that import others by a name string, and the tuple of names (or the dict whose
#: values are the names) they import: the checker reads them and counts each as an import.
IMPORTS_BY_NAME = {
    "softcell.components.registry": "BUILTIN_PLUGINS",
    "softcell.engine": "_WHERE",  # the engine's public names, imported on first use
    "softcell.settings": "DEFAULT_STORE",  # the default compiled-model store, on first use
    "softcell.studies": "WHERE",  # each study's module, imported when the study is asked for
}

#: Arrows allowed against the levels, each for one reason: the registry registers the
#: built-in components (a level above it) through the same hooks as third-party ones, and
#: the settings name the default store of compiled models (on disk, in io), made on first use.
UPWARD = {
    "softcell.components.registry": {"builtins", "integrators"},
    "softcell.settings": {"io"},
}


def room_of(module: str) -> str:
    """The room of ``softcell.a.b`` (``a``; ``kernels`` for ``softcell.engine.kernels``), or
    ``__init__`` for ``softcell`` itself."""
    pieces = module.split(".")
    if pieces[1:3] == ["engine", "kernels"]:
        return "kernels"
    return pieces[1] if len(pieces) > 1 else "__init__"


def module_name(path: Path) -> str:
    relative = path.relative_to(PACKAGE.parent).with_suffix("")
    pieces = list(relative.parts)
    if pieces[-1] == "__init__":
        pieces.pop()
    return ".".join(pieces)


MODULES = sorted(PACKAGE.rglob("*.py"))
NAMES = {module_name(path) for path in MODULES}


def _type_only(tree: ast.Module) -> set[int]:
    """The ids of the import nodes inside ``if TYPE_CHECKING:`` blocks."""
    found: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            found |= {id(n) for b in node.body for n in ast.walk(b)}
    return found


def _from_target(node: ast.ImportFrom, package: str) -> str:
    if not node.level:
        return node.module or ""
    base = package.split(".")
    base = base[: len(base) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def imported_modules(path: Path, name: str | None = None) -> list[tuple[int, str]]:
    """Every ``softcell`` module imported anywhere in the file (but under ``TYPE_CHECKING``),
    with its line; ``from package import name`` counts as an import of the submodule
    ``package.name`` when there is one. ``name`` is the module's dotted name (by default from
    its place in the package)."""
    name = module_name(path) if name is None else name
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = [*_named_imports(path, name)]
    tree = ast.parse(path.read_text(), filename=str(path))
    skip = _type_only(tree)
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = _from_target(node, package)
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                relative_package = node.level and not node.module
                found.append((node.lineno, sub if sub in NAMES or relative_package else target))
    return sorted({(line, m) for line, m in found if m.split(".")[0] == "softcell"})


def _named_imports(path: Path, name: str) -> list[tuple[int, str]]:
    """The modules ``name`` imports by a name string (see :data:`IMPORTS_BY_NAME`)."""
    target = IMPORTS_BY_NAME.get(name)
    if target is None:
        return []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        targets = getattr(node, "targets", None) or [getattr(node, "target", None)]
        if any(isinstance(t, ast.Name) and t.id == target for t in targets):
            names = ast.literal_eval(node.value)
            names = names.values() if isinstance(names, dict) else names
            names = [names] if isinstance(names, str) else names
            return [(node.lineno, n) for n in names]
    raise AssertionError(f"{name} has no literal tuple {target}")


def allowed(source: str, target: str) -> bool:
    """Whether a module of room ``source`` may import one of room ``target``."""
    if source == target:
        return True
    if LEVEL[source] == LEVEL[target]:
        return LEVEL[source] in SHARED_LEVELS
    return LEVEL[target] < LEVEL[source]


def test_every_import_by_name_is_a_literal_the_checker_reads():
    """``importlib.import_module`` only where the checker reads what it imports (or where the
    name comes from the user: entry points, the lazy public names of the package)."""
    readers = {
        "softcell.components.registry",  # BUILTIN_PLUGINS, and entry points
        "softcell",  # _LAZY: the public functions, imported on first use
        "softcell.engine.compiled",  # the package of a bound kernel, to hash its files
        "softcell.engine",  # _WHERE: the engine's public names, imported on first use
        "softcell.settings",  # DEFAULT_STORE, on first use
        "softcell.studies",  # WHERE: each study's module, when the study is asked for
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
            PACKAGE / "components/registry.py", "softcell.components.registry"
        )
    } >= {"softcell.integrators.rodas4", "softcell.builtins.bending"}


def test_every_room_has_a_level():
    rooms = {room_of(module_name(path)) for path in MODULES}
    assert rooms <= set(LEVEL), rooms - set(LEVEL)


@pytest.mark.parametrize("path", MODULES, ids=lambda path: module_name(path))
def test_imports_point_down(path):
    name = module_name(path)
    source = room_of(name)
    wrong = [
        f"{path.relative_to(PACKAGE.parent)}:{line} imports {module}"
        for line, module in imported_modules(path)
        if not allowed(source, room_of(module)) and room_of(module) not in UPWARD.get(name, ())
    ]
    assert not wrong, "\n".join(wrong)


def _cycles(arrows: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in arrows.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(arrows):
        if v not in index:
            visit(v)
    return groups


def arrows_of(modules: list[Path]) -> dict[str, set[str]]:
    return {
        module_name(path): {m for _, m in imported_modules(path) if m != module_name(path)}
        for path in modules
    }


def test_no_import_circles():
    """No module imports itself back through others (the arrows of :data:`UPWARD` excepted:
    they name what is registered or made on first use, not what is used)."""
    arrows = arrows_of(MODULES)
    for name, rooms in UPWARD.items():
        arrows[name] = {m for m in arrows[name] if room_of(m) not in rooms}
    assert not _cycles(arrows), _cycles(arrows)


def test_the_cycle_finder_finds_a_circle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_the_checker_sees_inner_relative_and_type_only_imports(tmp_path):
    """The parser finds an import hidden in a function, resolves a relative one and skips a
    type-only one (the probe is written to a temporary folder: the checkout may be
    read-only)."""
    fake = tmp_path / "_layer_probe.py"
    source = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from softcell.paper import report\n"
        "def f():\n    from ..runner import ensemble\n    import softcell.io.files\n"
    )
    fake.write_text(source)
    found = [module for _, module in imported_modules(fake, "softcell.model._layer_probe")]
    assert found == ["softcell.runner.ensemble", "softcell.io.files"]
    assert [room_of(module) for module in found] == ["runner", "io"]
    assert not allowed("model", "runner") and allowed("runner", "model")
    assert not allowed("builtins", "integrators") and allowed("settings", "errors")
