"""Sphinx configuration of the softcell documentation (``python -m sphinx -W -b html docs
docs/_build/html``; the ``docs`` extra installs what it needs)."""

from __future__ import annotations

import re

from softcell import __version__

project = "softcell"
author = "The softcell developers"
copyright = "2026, the softcell developers"
version = release = __version__

extensions = [
    "myst_nb",  # MyST Markdown pages and executed notebooks
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",  # numpydoc-style docstrings
    "sphinx.ext.mathjax",
]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "**/.ipynb_checkpoints"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

# Executed examples: every notebook runs at each build, so none can rot.
nb_execution_mode = "force"
nb_execution_timeout = 600
nb_execution_raise_on_error = True

# Every cross-reference to softcell's own objects must resolve (nitpicky); a type that
# names another library's class, or a numpydoc phrase ("optional", "path-like"), is not
# checked (the build is offline: no intersphinx).
nitpicky = True
nitpick_ignore_regex = [("py:class", r"(?!softcell\.).*")]

autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = False
napoleon_numpy_docstring = True

html_theme = "pydata_sphinx_theme"
html_title = f"softcell {version}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "show_nav_level": 2,  # the section's pages open in the left sidebar
    "header_links_before_dropdown": 4,
    # One sidebar, the left: the section's pages, then this page's contents. Without a
    # right sidebar the text column takes ~980 px of a 1280 px window (code, tables).
    "secondary_sidebar_items": [],
}
html_sidebars = {"**": ["sidebar-nav-bs", "page-toc"]}
# A wider content column: code blocks, tables and figures up to the full width.
html_static_path = ["_static"]
html_css_files = ["softcell.css"]

# Units, read from the numpydoc sections: every documented input and output that is a
# physical quantity (a float, a complex or an array) names its unit in its type or
# description (cm, s, rad, N, ...; "1" or "dimensionless" for pure numbers). Integers are
# counts and indices, and the other types (names, paths, Datasets that carry their units in
# attributes) have no unit. A missing unit fails the build (with -W).
SECTIONS = ("Parameters", "Other Parameters", "Returns", "Yields", "Attributes")
QUANTITY = re.compile(r"^\W*(float|complex|ndarray|array|scalar|numpy|np\.)")
UNIT_WORD = r"(cm|cm2|cm-1|cm-2|cm/s|cm s-1|s|s-1|rad|rad/s|N|N cm|N cm2|px|Hz|B|MiB|bytes|1)"
UNIT = re.compile(
    rf"\([^()]*\b{UNIT_WORD}(?![\w'])[^()]*\)|\bin {UNIT_WORD}\b"
    r"|\bdimensionless\b|\bunits?\b|\bper cent\b|%|\bfraction\b|\bratio\b|\bmultiples? of\b"
    r"|\bprobabilit"
)


def _units_missing(doc: str) -> list[str]:
    """The entries of ``doc``'s numpydoc sections that are quantities without a unit."""
    from numpydoc.docscrape import NumpyDocString

    parsed = NumpyDocString(doc)
    return [
        f"{section} {entry.name or entry.type!r}"
        for section in SECTIONS
        for entry in parsed[section]
        if QUANTITY.search(entry.type) and not UNIT.search(" ".join([entry.type, *entry.desc]))
    ]


def _undescribed(obj, doc: str) -> list[str]:
    """The parameters of ``obj``'s signature that its numpydoc Parameters sections do not
    describe (``self``, ``cls``, ``*args`` and ``**kwargs`` aside)."""
    import inspect

    from numpydoc.docscrape import NumpyDocString

    try:
        signature = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    docs = [doc]
    if inspect.isclass(obj):
        # The constructor is described where it is defined: on that class or its __init__
        # (a dataclass describes its fields as Attributes).
        owner = next((c for c in obj.__mro__ if "__init__" in vars(c)), obj)
        docs += [inspect.getdoc(owner) or "", inspect.getdoc(owner.__init__) or ""]
    entries = []
    for text in docs:
        parsed = NumpyDocString(text)
        entries += [*parsed["Parameters"], *parsed["Other Parameters"], *parsed["Attributes"]]
    described = {n.strip().lstrip("*") for e in entries for n in e.name.split(",")}
    skip = (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    return [
        name
        for name, p in signature.parameters.items()
        if name not in ("self", "cls") and p.kind not in skip and name not in described
    ]


def _check_docstring(app, what, name, obj, options, lines):
    """Warn (an error with -W) for a public callable whose docstring states no unit for a
    quantity or leaves a parameter undescribed."""
    if what not in ("function", "method", "class") or name.split(".")[-1].startswith("_"):
        return
    import inspect

    from sphinx.util import logging

    doc = inspect.getdoc(obj) or ""
    for missing, says, subtype in (
        (_units_missing(doc), "states no unit for", "units"),
        (_undescribed(obj, doc), "does not describe the parameter(s)", "parameters"),
    ):
        if missing:
            logging.getLogger(__name__).warning(
                "the docstring of %s %s %s",
                name,
                says,
                ", ".join(missing),
                type="softcell",
                subtype=subtype,
            )


def setup(app):
    app.connect("autodoc-process-docstring", _check_docstring)
