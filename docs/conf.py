"""Sphinx configuration: the API reference from the docstrings (numpydoc), the README's tour
and the design notes as pages. Build: ``sphinx-build -W -b html docs docs/_build/html``."""

import os
import sys

sys.path.insert(0, os.path.abspath(".."))

project = "clsamp"
author = "the clsamp authors"
extensions = ["sphinx.ext.autodoc", "sphinx.ext.autosummary", "numpydoc", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
root_doc = "index"
autosummary_generate = True
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
myst_heading_anchors = 3
html_theme = "alabaster"
suppress_warnings = ["myst.xref_missing"]
suppress_warnings += ["ref.citation"]      # a paper listed and not cited in the text is fine

# clsamp's docstrings are read in help() first: they write |x| for an absolute value, which
# reStructuredText would take for a substitution. clsamp never uses substitutions, so every
# '|' outside an inline literal is escaped here before numpydoc and docutils see it, and a
# function's citation of its module's references is left as text.
import re  # noqa: E402

_LITERAL = re.compile(r"(``.*?``)")


_CITED = re.compile(r"\[(\w+)\]_")


def _plain_text_math(app, what, name, obj, options, lines):
    """Escape the bars; a citation of the module's references ([6]_ in a function whose own
    docstring lists no [6]) stays as the plain text [6], which numpydoc could not link."""
    own = {m.group(1) for line in lines for m in re.finditer(r"^\s*\.\. \[(\w+)\]", line)}
    for i, line in enumerate(lines):
        if "|" in line and not line.lstrip().startswith(("+-", "..")):
            parts = _LITERAL.split(line)
            line = "".join(p if p.startswith("``") else p.replace("|", r"\|") for p in parts)
        lines[i] = _CITED.sub(lambda m: m.group(0) if m.group(1) in own else f"[{m.group(1)}]", line)


def setup(app):
    app.connect("autodoc-process-docstring", _plain_text_math, priority=400)
