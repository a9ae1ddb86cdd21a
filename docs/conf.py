"""Sphinx configuration: Markdown pages (MyST) and an API reference from numpydoc docstrings.

Build from the repository root with ``sphinx-build -W docs docs/_build/html``.
"""
import os
import sys

# The checkout's package, not whatever copy happens to be installed, is the one documented.
sys.path.insert(0, os.path.abspath(".."))

project = "skfem_flex"
author = "skfem_flex developers"
copyright = "skfem_flex developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "numpydoc",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build"]

# Headings down to ### get anchors, so that [text](page.md#heading) links resolve.
myst_heading_anchors = 3

nitpicky = False
autodoc_member_order = "bysource"
autodoc_typehints = "none"          # the numpydoc Parameters sections carry types and units
numpydoc_show_class_members = False  # members are documented by autodoc's :members: instead
numpydoc_class_members_toctree = False

html_theme = "alabaster"
html_title = "skfem_flex"
