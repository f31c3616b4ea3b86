"""The ``status-table`` directive: the table of the status vocabulary, built from its one source.

``.. status-table::`` renders :data:`toolkit_common.status.STATUS_TABLE` as a list table (word,
usable, who reports it, meaning, what the controller does), so the documentation cannot drift
from the code.
"""

from __future__ import annotations

from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

from toolkit_common.status import STATUS_TABLE

__all__ = ["StatusTable", "setup", "status_table_rst"]


def status_table_rst() -> list[str]:
    """The reStructuredText lines of the table, one row per word of :data:`STATUS_TABLE`."""
    lines = [
        ".. list-table::",
        "   :header-rows: 1",
        "   :widths: 16 8 10 33 33",
        "",
        "   * - status",
        "     - usable",
        "     - reported by",
        "     - meaning",
        "     - what the controllers do",
    ]
    for row in STATUS_TABLE:
        lines += [
            f'   * - ``"{row.status.value}"``',
            f"     - {'yes' if row.usable else 'no'}",
            f"     - {row.source}",
            f"     - {row.meaning}",
            f"     - {row.action}",
        ]
    return lines


class StatusTable(SphinxDirective):
    """``.. status-table::`` (no arguments, no content)."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        holder = nodes.container()
        source = StringList(status_table_rst(), source="toolkit_common.status.STATUS_TABLE")
        self.state.nested_parse(source, self.content_offset, holder)
        return list(holder.children)


def setup(app: Any) -> dict[str, Any]:
    """Register the directive."""
    app.add_directive("status-table", StatusTable)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
