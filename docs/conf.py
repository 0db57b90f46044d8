"""Sphinx configuration of flexarm's documentation.

Build it with ``sphinx-build -W --keep-going -b html docs docs/_build/html``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

import flexarm_api  # noqa: E402

import flexarm  # noqa: E402

os.environ.setdefault("MPLBACKEND", "Agg")

project = "flexarm"
author = "flexarm developers"
copyright = "flexarm developers"
release = flexarm.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
    "myst_parser",
    "flexarm_api",
]
# the user guide is Markdown (MyST): the README's long sections moved there as written
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_heading_anchors = 3

exclude_patterns = ["_build", "gallery/README.rst", "Thumbs.db", ".DS_Store"]
templates_path = ["_templates"]
root_doc = "index"
smartquotes_action = "qe"  # no dashes: "--help" stays two hyphens

# --- API reference --------------------------------------------------------------------
autosummary_generate = True
autosummary_ignore_module_all = False
autosummary_context = {"flexarm_api": flexarm_api.api_map().context()}
autodoc_typehints = "none"  # the numpydoc sections give the types, with units
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = True  # overrides without a docstring show the base's
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
# every cross-reference must resolve (flexarm_api resolves re-exports and names in scope)
nitpicky = True
nitpick_ignore_regex = [
    # outside flexarm: no intersphinx inventories are fetched (the build is offline)
    ("py:.*", r"(numpy|np|scipy|matplotlib|numba|control|gymnasium|pandas|sklearn)(\..*)?"),
    ("py:.*", r"(typing|collections|pathlib|threading|argparse|os|concurrent)(\..*)?"),
    ("py:.*", r"(csv|tomllib|json|threadpoolctl|signal|dataclasses)(\..*)?"),
    ("py:.*", r"(int|float|str|bool|bytes|dict|list|tuple|set|frozenset|None|object)"),
    ("py:.*", r"(ValueError|TypeError|RuntimeError|KeyboardInterrupt|Exception|Warning)"),
    ("py:.*", r"(UserWarning|ArithmeticError|OSError|NotImplementedError)"),
]

# --- Gallery ---------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "abort_on_example_error": False,
    "only_warn_on_example_error": False,
    "write_computation_times": False,
}

# --- HTML ------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"flexarm {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
}
html_static_path: list[str] = []
html_show_sourcelink = False
