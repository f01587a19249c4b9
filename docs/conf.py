"""Sphinx configuration of the cracklab documentation site.

Build (from the repository root, with the project's environment):

    .venv/bin/python -m sphinx -W -b html docs docs/_build/html

The Markdown pages of docs/ are read by myst-parser. They are in four folders by purpose
(guide/, reference/, developer/, studies/), and each folder joins the site through a glob
toctree of its own, with its caption in the sidebar, at the end of docs/index.md (a new
page in a folder needs no edit to appear there). docs/reference/docstrings.rst is the API
reference written by autodoc (+ napoleon) from the docstrings, in the layers of
docs/tools/api_page.py;
the gallery is written by sphinx-gallery from examples/*.py, which it runs while the
site builds (into docs/gallery/, not committed). tests/docs/test_site.py builds the
site with warnings as errors.
"""
from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "tools"))  # sphinx_cracklab (the API directive)
try:
    import cracklab
except ImportError:  # a checkout without an install
    sys.path.insert(0, str(ROOT))
    import cracklab

project = "cracklab"
author = "the cracklab authors"
copyright = "the cracklab authors"
version = release = cracklab.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",        # numpy-style sections: napoleon, through sphinx_cracklab
    "sphinx_gallery.gen_gallery",
    "sphinx_cracklab",
]

root_doc = "index"
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "tools", "figures"]
templates_path: list[str] = []

# ----------------------------------------------------------------------------- Markdown
# The pages are written for GitHub too: headings get GitHub's anchors, so that
# [text](page.md#a-heading) links work on the site as they do there.
myst_heading_anchors = 4

# ----------------------------------------------------------------------------- API
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_default_options = {"members": True}

# Every cross-reference must resolve (-n): the ones to other projects' objects cannot
# without intersphinx (no network during the build), so those are listed here.
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(np|numpy|xr|xarray|pd|pandas|scipy|dask|distributed|zarr|matplotlib|mpl|plt"
               r"|click|netCDF4|numba|pathlib|collections|typing|os|types|datetime)(\..*)?"),
    (r"py:.*", r"(None|int|float|complex|bool|str|bytes|dict|list|tuple|set|frozenset|object|type"
               r"|slice|callable|Callable|Any|Iterable|Iterator|Sequence|Mapping|Path|ndarray"
               r"|Dataset|DataArray|DataTree|Figure|Axes|ArrayLike|NDArray|Literal|Self|Hashable"
               r"|ValueError|RuntimeError|Exception|KeyError|TypeError|optional|array_like|array"
               r"|Client|LocalCluster|Store|StoreLike|ZarrStore)"),
]

# ----------------------------------------------------------------------------- gallery
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "gallery",
    "filename_pattern": r"/plot_",          # run every plot_*.py while the site builds
    "run_stale_examples": True,             # always run them, not only the changed ones
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "write_computation_times": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "reset_modules": ("matplotlib",),
    "min_reported_time": 0,
    "show_memory": False,
    "plot_gallery": "True",
}

# ----------------------------------------------------------------------------- HTML
html_theme = "alabaster"
html_title = f"cracklab {version}"
html_static_path: list[str] = []
html_theme_options = {
    "description": "Spectral boundary-integral simulation of dynamic fracture",
    "fixed_sidebar": False,
    "page_width": "1180px",
    "sidebar_width": "250px",
    "show_relbars": True,
}
html_sidebars = {"**": ["about.html", "navigation.html", "relations.html", "searchbox.html"]}
html_show_sourcelink = False
