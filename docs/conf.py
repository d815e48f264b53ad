"""Sphinx configuration of the amb_fast documentation.

Build (warnings are errors, as in CI):

    sphinx-build -W -b html docs docs/_build/html
    sphinx-build -W -b doctest docs docs/_build/doctest

The package must be installed (``pip install ".[docs]"``): the API reference, the gallery, the paper
page and the speed page all run it. ``_ext/amb_docs.py`` generates the paper's figures and claims
table and the benchmark tables into ``_generated/`` during the build.
"""

from __future__ import annotations

import doctest
import sys
from pathlib import Path

import amb_fast

sys.path.insert(0, str(Path(__file__).parent / "_ext"))

project = "amb_fast"
author = "the amb_fast developers"
copyright = "2026, the amb_fast developers"
release = amb_fast.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.doctest",
    "sphinx.ext.mathjax",
    "matplotlib.sphinxext.plot_directive",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "amb_docs",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_generated", "_ext", "auto_examples/*.ipynb", "auto_examples/*.py"]
templates_path: list[str] = []

# MyST: the Markdown pages (model.md and errors.md are the same files the README links to).
myst_enable_extensions: list[str] = []  # plain CommonMark + tables: a "$" in model.md stays a "$"
myst_heading_anchors = 3

# Autodoc and numpydoc: the docstrings are numpy style. Class members are listed explicitly on the
# API pages (numpydoc's automatic member tables would repeat the dataclass fields), and numpydoc's
# docstring validation is off: the docstrings are checked by review, the examples by doctest.
autodoc_default_options = {"member-order": "bysource"}
# Signatures without type hints (names and defaults only, as numpy's and scipy's pages have): the
# numpydoc sections carry the types with their units, and Sphinx would print numpy's ArrayLike as its
# private pieces.
autodoc_typehints = "none"
autodoc_preserve_defaults = True
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

# Doctests: every `doctest` / `testcode` block on the pages runs with `sphinx-build -b doctest`.
doctest_global_setup = """
import numpy as np
import amb_fast as af
"""
doctest_default_flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE | doctest.DONT_ACCEPT_TRUE_FOR_1

# Figures on the pages (the tour): the plot directive runs the code and shows the figure and the source.
plot_include_source = True
plot_html_show_source_link = False
plot_html_show_formats = False
plot_formats = [("png", 100)]

# Gallery: examples/plot_*.py, each run during the build (its figure is scraped from matplotlib).
sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"__init__\.py",
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "remove_config_comments": True,
    "download_all_examples": False,
    "doc_module": ("amb_fast",),
    "backreferences_dir": "_generated/backreferences",
    "reference_url": {"amb_fast": None},
    "min_reported_time": 0,
    "show_memory": False,
    "image_srcset": [],
}

html_theme = "pydata_sphinx_theme"
html_title = f"amb_fast {release}"
html_theme_options = {
    "navigation_with_keys": False,
    # The top bar: the pages' short H1 titles, the first five in the bar and the rest under "More", so
    # the bar stays on one line down to the theme's collapsed layout (long page titles wrapped it).
    "header_links_before_dropdown": 5,
    "navbar_persistent": ["search-button"],  # the search as an icon (Ctrl+K), not a wide field
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc", "sourcelink"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
# The guide pages have no sub-pages, so the left sidebar would show an empty "Section Navigation": it is
# left out on them (kept for the API reference and the gallery, which have sub-pages).
_FLAT_PAGES = sorted(p.stem for p in Path(__file__).parent.glob("*.md"))
html_sidebars: dict[str, list[str]] = {name: [] for name in _FLAT_PAGES}
html_show_sourcelink = True
html_static_path: list[str] = []
