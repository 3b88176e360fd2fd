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
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}

# A public function whose docstring names no unit fails the build (with -W): physical inputs
# and outputs carry their units (cm, s, rad, N, ...), dimensionless ones say "1" or
# "dimensionless", and those with no quantity at all say "no units".
UNIT = re.compile(
    r"\((?:[^()]*\b(?:cm|s|rad|N|px|cm2|cm/s|frames/s|1|Hz|MiB|B)\b[^()]*)\)"
    r"|\bunits?\b|\bdimensionless\b|\bcm\b|\bseconds?\b"
)


def _check_units(app, what, name, obj, options, lines):
    if what not in ("function", "method") or name.split(".")[-1].startswith("_"):
        return
    if not UNIT.search("\n".join(lines)):
        from sphinx.util import logging

        logging.getLogger(__name__).warning(
            "the docstring of %s states no units (name them, or say 'no units')",
            name,
            type="softcell",
            subtype="units",
        )


def setup(app):
    app.connect("autodoc-process-docstring", _check_units)
