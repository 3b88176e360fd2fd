"""The module map of docs/architecture.md, made from the modules' own docstrings.

``python docs/module_map.py`` rewrites the map between its two markers in
docs/architecture.md; ``tests/test_docs.py`` fails when the page and the docstrings disagree
(a module added, moved or described anew).
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "architecture.md"
BEGIN, END = "<!-- module map: made by docs/module_map.py -->", "<!-- end of the module map -->"


def first_sentence(path: Path) -> str:
    """The first sentence of the module's docstring, on one line."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    text = " ".join(doc.split("\n\n")[0].split())
    match = re.match(r"(.+?[.?!])(\s|$)", text)
    return (match.group(1) if match else text) or "(no docstring)"


def markdown(text: str) -> str:
    """A docstring's reStructuredText as Markdown for a table cell: roles and double
    backquotes as code, and the cell's separator escaped."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"`\1`", text)
    text = re.sub(r"``([^`]+)``", r"`\1`", text)
    return text.replace("|", "\\|")


def module_map() -> str:
    """A Markdown table: every module of softcell (templates included) and what it holds."""
    rows = ["| module | what it holds |", "| --- | --- |"]
    for path in sorted((ROOT / "softcell").rglob("*.py")):
        relative = path.relative_to(ROOT).as_posix()
        if path.name == "__main__.py" or path.name == "_version.py":
            continue
        rows.append(f"| `{relative}` | {markdown(first_sentence(path))} |")
    return "\n".join(rows)


def page_with_map(page: str) -> str:
    """``page`` with the text between the markers replaced by :func:`module_map`."""
    head, rest = page.split(BEGIN)
    _, tail = rest.split(END)
    return f"{head}{BEGIN}\n{module_map()}\n{END}{tail}"


if __name__ == "__main__":
    PAGE.write_text(page_with_map(PAGE.read_text(encoding="utf-8")), encoding="utf-8")
    sys.exit(0)
