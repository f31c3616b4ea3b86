"""Sphinx configuration of the rmpc-satellite documentation.

Build (warnings are errors)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

The build needs no network: intersphinx is deliberately not enabled. Neither do the pages: the
math is typeset in the browser by MathJax 3 served from ``_static/mathjax/`` (the package
``sphinx-mathjax-offline``, in the ``docs`` extra, ships it and copies it into every build).
"""

from __future__ import annotations

import sys
from importlib import metadata
from pathlib import Path

# Document the checkout this file belongs to, also when an older copy is installed.
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
# The project's own directives (``status-table``: the status vocabulary's table; the example
# gallery, ``example-figure`` and ``example-gallery``).
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

# -- Project -------------------------------------------------------------------------
project = "rmpc-satellite"
author = "rmpc-satellite contributors"
copyright = "rmpc-satellite contributors"
try:
    release = metadata.version("rmpc-satellite")
except metadata.PackageNotFoundError:  # running from a checkout that is not installed
    release = "0.1.0"
version = ".".join(release.split(".")[:2])

# -- General -------------------------------------------------------------------------
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax from _static/mathjax/, not from a CDN (sets mathjax_path)
    "sphinx.ext.doctest",
    "numpydoc",
    "status_table",
    "gallery",
]
exclude_patterns = ["_build", "_generated", "examples", "figures", "Thumbs.db", ".DS_Store"]
root_doc = "index"
language = "en"
default_role = "literal"  # a single-backtick `x` is code, as in the docstrings' double ones

# -- autodoc -------------------------------------------------------------------------
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_preserve_defaults = True
# Keep the name of numpy's array-like alias in the signatures (``x: ArrayLike``), not its
# expansion into a union of numpy's private protocols.
autodoc_type_aliases = {"ArrayLike": "numpy.typing.ArrayLike"}

# -- numpydoc ------------------------------------------------------------------------
# numpydoc's own member tables duplicate autodoc's :members: and warn about missing stubs.
numpydoc_show_class_members = False
numpydoc_show_inherited_class_members = False
numpydoc_class_members_toctree = False

# -- doctest (``sphinx-build -b doctest docs OUT`` runs the ``>>>`` examples) --------
doctest_global_setup = "import numpy as np"

# -- HTML ----------------------------------------------------------------------------
html_theme = "alabaster"
html_title = f"{project} {release}"
html_theme_options = {
    "description": "Robust MPC for satellite attitude control",
    "fixed_sidebar": True,
    "page_width": "1100px",
    "sidebar_width": "240px",
}
html_sidebars = {"**": ["about.html", "navigation.html", "relations.html", "searchbox.html"]}


# -- Figures drawn from code at build time ----------------------------------------------
# Each module of docs/figures has ``write(path)``; its PNG goes to docs/_generated/ (not
# tracked), which the pages include with ``.. figure:: _generated/<name>.png``.
FIGURES = ("architecture",)


def _write_figures(app: object) -> None:
    import importlib.util

    out = Path(__file__).resolve().parent / "_generated"
    for name in FIGURES:
        source = out.parent / "figures" / f"{name}.py"
        spec = importlib.util.spec_from_file_location(f"docs_figure_{name}", source)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        module.write(out / f"{name}.png")


def _alias_names(
    app: object, what: str, name: str, obj: object, options: object, signature: str | None,
    return_annotation: str | None,
) -> tuple[str | None, str | None]:
    """Show an alias of ``autodoc_type_aliases`` by its name also inside a union or a subscript.

    Sphinx prints ``x: ArrayLike | None`` as ``TypeAliasForwardRef('numpy.typing.ArrayLike') | None``.
    """
    import re

    def plain(text: str | None) -> str | None:
        return None if text is None else re.sub(r"TypeAliasForwardRef\('([\w.]+)'\)", r"\1", text)

    return plain(signature), plain(return_annotation)


def setup(app: object) -> None:
    app.connect("builder-inited", _write_figures)  # type: ignore[attr-defined]
    app.connect("autodoc-process-signature", _alias_names)  # type: ignore[attr-defined]
