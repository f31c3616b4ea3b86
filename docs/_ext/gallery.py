"""The example gallery: every script of ``docs/examples`` with the figures it draws, made at build time.

At ``builder-inited`` every example that imports :mod:`matplotlib.pyplot` runs once in the build
process (backend Agg, ``plt.show`` a no-op, its printed output captured); each figure it leaves
open is written to ``docs/_generated/examples/<stem>-<n>.png`` (not tracked). An example that
raises, or that imports pyplot and draws nothing, is a build warning (an error with ``-W``).

Two directives use the runs:

``.. example-figure:: NAME.py``
    The figures of one example, where a page explains it.
``.. example-gallery::``
    One section per example, in file order: its docstring, the page that explains it, its
    figures and its code.
"""

from __future__ import annotations

import ast
import contextlib
import io
import re
import runpy
from pathlib import Path
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

__all__ = ["ExampleFigure", "ExampleGallery", "draws_figures", "run_example", "setup"]

DOCS = Path(__file__).resolve().parent.parent
EXAMPLES = DOCS / "examples"
OUT = DOCS / "_generated" / "examples"
DPI = 80
"""Resolution of the gallery's PNGs: 6.4 x 4.4 in at 80 dpi is 512 x 352 pixels, about 40 kB."""

_PYPLOT = re.compile(r"^\s*(import matplotlib\.pyplot|from matplotlib import pyplot)", re.MULTILINE)
_FIGURES: dict[str, list[str]] = {}
logger = logging.getLogger(__name__)


def draws_figures(example: Path) -> bool:
    """Whether an example draws figures: it imports :mod:`matplotlib.pyplot`."""
    return bool(_PYPLOT.search(example.read_text(encoding="utf-8")))


def run_example(example: Path) -> tuple[dict[str, Any], str, list[Any]]:
    """Run an example as ``__main__`` with the Agg backend; return its globals, output and figures.

    ``plt.show`` does nothing during the run; the figures it leaves open are returned (and
    stay open: the caller closes them).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.close("all")
    out = io.StringIO()
    show = plt.show
    plt.show = lambda *args, **kwargs: None
    try:
        with contextlib.redirect_stdout(out):
            namespace = runpy.run_path(str(example), run_name="__main__")
    finally:
        plt.show = show
    figures = [plt.figure(number) for number in plt.get_fignums()]
    return namespace, out.getvalue().strip(), figures


def _write_figures(app: Any) -> None:
    import matplotlib.pyplot as plt

    OUT.mkdir(parents=True, exist_ok=True)
    for old in OUT.glob("*.png"):
        old.unlink()
    _FIGURES.clear()
    for example in sorted(EXAMPLES.glob("*.py")):
        if not draws_figures(example):
            continue
        try:
            _, _, figures = run_example(example)
        except Exception as err:
            logger.warning("example %s raised %s: %s", example.name, type(err).__name__, err)
            plt.close("all")
            continue
        if not figures:
            logger.warning("example %s imports matplotlib.pyplot but draws no figure", example.name)
        names = []
        for n, fig in enumerate(figures, start=1):
            name = f"{example.stem}-{n}.png"
            fig.savefig(OUT / name, dpi=DPI)
            names.append(name)
        plt.close("all")
        _FIGURES[example.name] = names


def _figure_lines(example: str) -> list[str]:
    lines = []
    for name in _FIGURES.get(example, []):
        lines += [f".. image:: /_generated/examples/{name}", f"   :alt: the figure of examples/{example}", ""]
    return lines


def _explained_on(example: str) -> str | None:
    """The page (docname) that includes the example with ``literalinclude``, if one does."""
    name = re.escape(example)
    pattern = re.compile(rf"^\.\. literalinclude:: (?:/|\.\./)?examples/{name}\s*$", re.MULTILINE)
    for page in sorted(DOCS.rglob("*.rst")):
        if "_build" in page.parts or "_generated" in page.parts:
            continue
        if pattern.search(page.read_text(encoding="utf-8")):
            return page.relative_to(DOCS).with_suffix("").as_posix()
    return None


def _summary(example: Path) -> str:
    doc = ast.get_docstring(ast.parse(example.read_text(encoding="utf-8"))) or ""
    return " ".join(doc.split()) or example.stem


class ExampleFigure(SphinxDirective):
    """``.. example-figure:: NAME.py``: the figures drawn by ``docs/examples/NAME.py``."""

    required_arguments = 1
    has_content = False

    def run(self) -> list[nodes.Node]:
        example = self.arguments[0]
        self.env.note_dependency(str(EXAMPLES / example))
        if not _FIGURES.get(example):
            logger.warning("example-figure: %s drew no figure", example, location=self.get_location())
            return []
        holder = nodes.container()
        lines = StringList(_figure_lines(example), source=example)
        self.state.nested_parse(lines, self.content_offset, holder)
        return list(holder.children)


class ExampleGallery(SphinxDirective):
    """``.. example-gallery::``: every example with its summary, page, figures and code."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        lines: list[str] = []
        for example in sorted(EXAMPLES.glob("*.py")):
            self.env.note_dependency(str(example))
            title = example.name
            lines += [title, "-" * len(title), "", _summary(example), ""]
            page = _explained_on(example.name)
            if page is not None:
                lines += [f"Explained, with its output, in :doc:`/{page}`.", ""]
            lines += _figure_lines(example.name)
            lines += [f".. literalinclude:: /examples/{example.name}", "   :language: python", ""]
        holder = nodes.section()
        holder.document = self.state.document
        nested_parse_with_titles(self.state, StringList(lines, source="example-gallery"), holder)
        return list(holder.children)


def setup(app: Any) -> dict[str, Any]:
    """Register the directives and run the examples that draw figures when the build starts."""
    app.connect("builder-inited", _write_figures)
    app.add_directive("example-figure", ExampleFigure)
    app.add_directive("example-gallery", ExampleGallery)
    return {"parallel_read_safe": False, "parallel_write_safe": True}
