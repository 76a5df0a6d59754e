"""Sphinx configuration of flexsym's documentation.

Build: python -m sphinx -W --keep-going -b html docs docs/_build/html
Markdown pages (MyST), executed examples (sphinx-gallery), the command-line reference from the
argparse parser (sphinx-argparse) and the Python reference from docstrings (autodoc)."""
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("FLEXSYM_CACHE", tempfile.mkdtemp(prefix="flexsym-docs-"))
os.environ.setdefault("MPLBACKEND", "Agg")

project = "flexsym"
author = "the flexsym developers"
copyright = "2026, the flexsym developers"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax",
              "sphinxarg.ext", "sphinx_gallery.gen_gallery"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 4
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "examples/README.rst", "bench/bench.md", "exact/exact_study.md", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.md5", "auto_examples/*.json"]
suppress_warnings = ["myst.header", "myst.domains"]  # measured tables keep their heading depth;
# sphinx-argparse's domain cannot resolve MyST's any-links (harmless)

autodoc_member_order = "bysource"
autodoc_typehints = "description"

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r".*\.py$",      # every example is executed
    "download_all_examples": False,
    "abort_on_example_error": True,
    "remove_config_comments": True,
}

html_theme = "furo"
html_title = "flexsym"
