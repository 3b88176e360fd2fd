"""No function of softcell is more complex than one idea, except the compiled inner loops.

Cyclomatic complexity as radon measures it (every branch, loop, boolean operator and
comprehension condition counts). A function decorated with ``njit`` is a compiled inner loop:
long by design, its stages are kernels of their own.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

radon = pytest.importorskip("radon.complexity")

PACKAGE = Path(__file__).resolve().parents[1] / "softcell"
LIMIT = 15


def _compiled(source: str) -> set[int]:
    """Lines of the ``def`` of every function decorated with ``njit`` (or ``njit(...)``)."""
    lines = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.FunctionDef):
            for decorator in node.decorator_list:
                target = decorator.func if isinstance(decorator, ast.Call) else decorator
                if getattr(target, "id", getattr(target, "attr", None)) == "njit":
                    lines.add(node.lineno)
    return lines


def _too_complex(path: Path) -> list[str]:
    source = path.read_text()
    compiled = _compiled(source)
    functions = [b for b in radon.cc_visit(source) if not hasattr(b, "methods")]  # methods too
    return [
        f"{path.relative_to(PACKAGE.parent)}:{f.lineno} {f.name} {f.complexity}"
        for f in functions
        if f.complexity > LIMIT and f.lineno not in compiled
    ]


def test_no_function_is_more_complex_than_the_limit():
    found = [line for path in sorted(PACKAGE.rglob("*.py")) for line in _too_complex(path)]
    assert not found, "\n".join(found)


def test_the_check_sees_a_complex_function_and_spares_a_compiled_one(tmp_path):
    body = "".join(f"    if x == {i}:\n        return {i}\n" for i in range(LIMIT + 1))
    probe = tmp_path / "probe.py"
    probe.write_text(f"def plain(x):\n{body}\n\n@njit(cache=True)\ndef loop(x):\n{body}")
    global PACKAGE
    package, PACKAGE = PACKAGE, tmp_path
    try:
        found = _too_complex(probe)
    finally:
        PACKAGE = package
    assert [line.split()[1] for line in found] == ["plain"]
