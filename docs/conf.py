"""Sphinx configuration of the virtspec-mi manual (``make docs``; built warning-free by the tests)."""

from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
# autosummary's pages are written anew on every build: a module renamed or removed leaves no stale page behind
shutil.rmtree(Path(__file__).with_name("_generated"), ignore_errors=True)
os.environ.setdefault("MPLBACKEND", "Agg")

import virtspec_mi  # noqa: E402

virtspec_mi.mitsuba()  # the variant is set before autodoc imports the kernel modules

project = "virtspec-mi"
author = "the virtspec-mi developers"
release = version = virtspec_mi.__version__
copyright = "2026, the virtspec-mi developers; NPSG leaf data © 2010 NPSG (BSD-3)"

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "notebooks/README.md", "notebooks/.ipynb_checkpoints", "**/.ipynb_checkpoints"]

# The notebooks are shown with the outputs stored in them (`make notebooks` refreshes them).
nb_execution_mode = "off"
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

autosummary_generate = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = False  # Mitsuba base classes carry their own (C++-style) docstrings
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

html_theme = "furo"
html_title = f"virtspec-mi {release}"


# Docstrings write absolute values as |x| (plain text that reads well in help()); in
# reStructuredText a pair of bars is a substitution, so the bars are escaped here,
# outside inline literals and grid tables.
_LITERAL = re.compile(r"(``.*?``)")


def _escape_bars(app, what, name, obj, options, lines: list[str]) -> None:
    for i, line in enumerate(lines):
        stripped = line.strip()
        if "|" not in line or stripped.startswith("+") or (stripped.startswith("|") and stripped.endswith("|")):
            continue  # a table's row or border
        parts = _LITERAL.split(line)
        lines[i] = "".join(part if part.startswith("``") else part.replace("|", r"\|") for part in parts)


def setup(app) -> None:
    app.connect("autodoc-process-docstring", _escape_bars)
