"""Sphinx configuration of the documentation site (``make docs``).

pydata-sphinx-theme, numpydoc API reference from the docstrings (autodoc, autosummary),
Markdown pages through myst-parser (``models.md``, ``figures.md``, ``results.md``) and a
sphinx-gallery of executed examples (``examples/``). ``KVI_DOCS_QUICK=1`` builds the
gallery without executing it (a fast check of the rest).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import kalman_vs_infoset  # noqa: E402

project = "kalman-vs-infoset"
author = "The kalman-vs-infoset contributors"
copyright = "2026, " + author
release = version = kalman_vs_infoset.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
root_doc = "index"

autosummary_generate = True
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "amsmath"]
suppress_warnings: list[str] = []

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "plot_gallery": "False" if os.environ.get("KVI_DOCS_QUICK") else "True",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
}

html_theme = "pydata_sphinx_theme"
html_title = "kalman-vs-infoset"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
html_static_path: list[str] = []
