"""A tiny document model for what softcell writes for people (the report, the studies' pages),
rendered as Markdown and as HTML from the same blocks.
"""

from __future__ import annotations

import html
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: The kinds of block and what each holds.
KINDS = {
    "h1": "a title (str)",
    "h2": "a section heading (str)",
    "h3": "a subsection heading (str)",
    "p": "a paragraph (str, Markdown inline markup allowed)",
    "list": "the items of a bulleted list (list of str)",
    "code": "a code block (str)",
    "table": "(header, rows): a table, each row a list of cells",
    "figure": "(png, pdf, caption): a figure with its PDF",
    "images": "a list of (alt text, path): images one below the other",
}


@dataclass(frozen=True)
class Block:
    """One block of a document: ``kind`` (one of :data:`KINDS`) and its ``content``."""

    kind: str
    content: Any

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"block kind {self.kind!r} is not one of {', '.join(KINDS)}")


def _markdown_table(header: Sequence[Any], rows: Sequence[Sequence[Any]]) -> list[str]:
    cells = [[str(c).replace("|", "\\|") for c in row] for row in [header, *rows]]
    lines = [
        "| " + " | ".join(cells[0]) + " |",
        "| " + " | ".join("---" for _ in header) + " |",
    ]
    return lines + ["| " + " | ".join(row) + " |" for row in cells[1:]] + [""]


def markdown(blocks: Sequence[Block]) -> str:
    """The blocks as Markdown: each followed by a blank line."""
    lines: list[str] = []
    headings = {"h1": "#", "h2": "##", "h3": "###"}
    for b in blocks:
        if b.kind in headings:
            lines += [f"{headings[b.kind]} {b.content}", ""]
        elif b.kind == "p":
            lines += [b.content, ""]
        elif b.kind == "list":
            lines += [f"- {item}" for item in b.content] + [""]
        elif b.kind == "code":
            lines += ["```", b.content, "```", ""]
        elif b.kind == "table":
            lines += _markdown_table(*b.content)
        elif b.kind == "figure":
            png, pdf, caption = b.content
            lines += [f"![{Path(png).stem}]({png})", "", f"*{caption}* ([PDF]({pdf}))", ""]
        elif b.kind == "images":
            lines += [f"![{alt}]({path})" for alt, path in b.content] + [""]
    return "\n".join(lines)


_CSS = (
    "body{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em;"
    "line-height:1.4}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid "
    "#bbb;padding:.25em .5em;vertical-align:top;text-align:left}th{background:#eee}"
    "img{max-width:100%;max-height:92vh}figure{margin:1.5em 0}pre{background:#f4f4f4;padding:.5em;"
    "overflow-x:auto}.agrees{color:#1b5e20}.differs{color:#b71c1c}.partly{color:#e65100}"
)


def _inline(text: str) -> str:
    """``text`` escaped for HTML, with Markdown's inline code (`x`) as <code>x</code>."""
    return re.sub(r"`([^`]+)`", r"<code>\1</code>", html.escape(text))


def _html_table(header: Sequence[Any], rows: Sequence[Sequence[Any]]) -> str:
    e = _inline
    head = "".join(f"<th>{e(str(c))}</th>" for c in header)
    body = "".join(
        "<tr>"
        + "".join(
            f'<td class="{e(str(c))}">{e(str(c))}</td>'
            if str(c) in ("agrees", "differs", "partly")
            else f"<td>{e(str(c))}</td>"
            for c in row
        )
        + "</tr>"
        for row in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def html_page(blocks: Sequence[Block], title: str) -> str:
    """The blocks as one standalone HTML page titled ``title``."""
    e = _inline
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>",
    ]
    for b in blocks:
        if b.kind in ("h1", "h2", "h3"):
            parts.append(f"<{b.kind}>{e(b.content)}</{b.kind}>")
        elif b.kind == "p":
            parts.append(f"<p>{e(b.content)}</p>")
        elif b.kind == "list":
            parts.append("<ul>" + "".join(f"<li>{e(i)}</li>" for i in b.content) + "</ul>")
        elif b.kind == "code":
            parts.append(f"<pre><code>{e(b.content)}</code></pre>")
        elif b.kind == "table":
            parts.append(_html_table(*b.content))
        elif b.kind == "figure":
            png, pdf, caption = b.content
            a = html.escape
            parts.append(
                f'<figure><img src="{a(png)}" alt="{a(caption)}"><figcaption>'
                f'{e(caption)} (<a href="{a(pdf)}">PDF</a>)</figcaption></figure>'
            )
        elif b.kind == "images":
            a = html.escape
            parts += [f'<img src="{a(path)}" alt="{a(alt)}">' for alt, path in b.content]
    parts.append("</body></html>")
    return "\n".join(parts)
