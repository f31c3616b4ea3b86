"""The mutation operators: where a module's source can be changed, and the changed source.

Each mutant changes one node of the module's syntax tree and nothing else: the text of that node
(located by its line and column span) is replaced by the unparsed mutated node, so comments, layout
and every other line stay as they were. The operators:

=============  ========================================================================
``compare``    a comparison negated: ``<`` -> ``>=``, ``<=`` -> ``>``, ``==`` -> ``!=``,
               ``is`` -> ``is not``, ``in`` -> ``not in`` and back
``arith``      ``+`` <-> ``-``, ``*`` <-> ``/``, ``**`` -> ``*``, ``//`` -> ``/``, in
               expressions and augmented assignments
``boolop``     ``and`` <-> ``or``
``not``        ``not x`` -> ``x``; ``-x`` -> ``x``
``constant``   a number: ``0`` <-> ``1``, another integer ``n`` -> ``n + 1``, a float
               ``x`` -> ``2 x`` (``0.0`` -> ``1.0``); ``True`` <-> ``False``
``return``     ``return value`` -> ``return None``
``statement``  a statement removed (replaced by ``pass``): a call made for its effect, a
               ``raise``, an augmented assignment, an assignment to an attribute or an item,
               ``break`` and ``continue``
=============  ========================================================================

Left alone: docstrings and other strings, f-strings, annotations, ``__all__``, the body of
``if TYPE_CHECKING:`` and assignments to plain names (removing them only raises ``NameError``).
"""

from __future__ import annotations

import ast
from dataclasses import asdict, dataclass
from typing import Any

__all__ = ["OPERATORS", "Mutant", "apply_mutant", "find_mutants"]

#: The operator families, in the order a report lists them.
OPERATORS = ("compare", "arith", "boolop", "not", "constant", "return", "statement")

_COMPARE: dict[type, type] = {
    ast.Lt: ast.GtE, ast.GtE: ast.Lt, ast.Gt: ast.LtE, ast.LtE: ast.Gt, ast.Eq: ast.NotEq,
    ast.NotEq: ast.Eq, ast.Is: ast.IsNot, ast.IsNot: ast.Is, ast.In: ast.NotIn, ast.NotIn: ast.In,
}
_ARITH: dict[type, type] = {
    ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult, ast.Pow: ast.Mult,
    ast.FloorDiv: ast.Div,
}


@dataclass(frozen=True)
class Mutant:
    """One change to one module.

    Attributes
    ----------
    module : str
        Dotted module name, e.g. ``"lmi.kothare"``.
    path : str
        The module's file, relative to the project root (``/`` separated).
    line, col, end_line, end_col : int
        Span of the replaced text (lines from 1; columns in UTF-8 bytes, as :mod:`ast` gives them).
    operator : str
        One of :data:`OPERATORS`.
    original, replacement : str
        The replaced text (first line of it, for the report) and the text put in its place.
    scope : str
        ``"function"`` (the line runs when its function is called), ``"compiled"`` (inside a numba
        ``@njit``/``@jit`` function: never seen by a line tracer) or ``"module"`` (runs on import:
        module constants, default values, class bodies).
    ordinal : int
        0, or 1, 2, ... for the further mutants of the same operator at the same place (a chained
        comparison).
    """

    module: str
    path: str
    line: int
    col: int
    end_line: int
    end_col: int
    operator: str
    original: str
    replacement: str
    scope: str
    ordinal: int = 0

    @property
    def id(self) -> str:
        """Stable name: ``module:line:col:operator``, with ``#ordinal`` when that is not 0."""
        base = f"{self.module}:{self.line}:{self.col}:{self.operator}"
        return f"{base}#{self.ordinal}" if self.ordinal else base


def _is_compiled(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    for dec in node.decorator_list:
        target = dec.func if isinstance(dec, ast.Call) else dec
        name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
        if name in {"njit", "jit", "vectorize", "guvectorize"}:
            return True
    return False


def _mutated_constant(value: Any) -> Any:
    if isinstance(value, bool):
        return not value
    if isinstance(value, int):
        return {0: 1, 1: 0}.get(value, value + 1)
    if isinstance(value, float):
        return 1.0 if value == 0.0 else 2.0 * value
    return None


class _Finder(ast.NodeVisitor):
    def __init__(self) -> None:
        self.found: list[tuple[ast.AST, ast.AST | None, str, str]] = []  # node, new node, operator, scope
        self.scope = "module"

    # --- scopes and what is left alone ----------------------------------------------------------
    def _function(self, node: ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda) -> None:
        for default in [*node.args.defaults, *node.args.kw_defaults]:
            if default is not None:
                self.visit(default)  # evaluated on import
        if not isinstance(node, ast.Lambda):
            for dec in node.decorator_list:
                self.visit(dec)
        outer = self.scope
        compiled = not isinstance(node, ast.Lambda) and _is_compiled(node)
        self.scope = "compiled" if (compiled or outer == "compiled") else "function"
        body = node.body if isinstance(node.body, list) else [node.body]
        for i, stmt in enumerate(body):
            if i == 0 and _is_docstring(stmt):
                continue
            self.visit(stmt)
        self.scope = outer

    visit_FunctionDef = visit_AsyncFunctionDef = visit_Lambda = _function

    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        for i, stmt in enumerate(node.body):
            if not (i == 0 and _is_docstring(stmt)):
                self.visit(stmt)

    def visit_Module(self, node: ast.Module) -> None:
        for i, stmt in enumerate(node.body):
            if not (i == 0 and _is_docstring(stmt)):
                self.visit(stmt)

    def visit_If(self, node: ast.If) -> None:
        test = node.test
        if (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
            isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
        ):
            return
        self.generic_visit(node)

    def visit_JoinedStr(self, node: ast.JoinedStr) -> None:
        return

    def visit_AnnAssign(self, node: ast.AnnAssign) -> None:
        if node.value is not None:
            self.visit(node.value)

    def visit_Assign(self, node: ast.Assign) -> None:
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            return
        if all(isinstance(t, ast.Attribute | ast.Subscript) for t in node.targets):
            self._add(node, None, "statement")
        self.generic_visit(node)

    def visit_arg(self, node: ast.arg) -> None:
        return  # annotations

    # --- the operators ---------------------------------------------------------------------------
    def _add(self, node: ast.AST, new: ast.AST | None, operator: str) -> None:
        self.found.append((node, new, operator, self.scope))

    def visit_Compare(self, node: ast.Compare) -> None:
        for i, op in enumerate(node.ops):
            flipped = _COMPARE.get(type(op))
            if flipped is not None:
                ops = list(node.ops)
                ops[i] = flipped()
                self._add(node, ast.Compare(left=node.left, ops=ops, comparators=node.comparators), "compare")
        self.generic_visit(node)

    def visit_BinOp(self, node: ast.BinOp) -> None:
        swapped = _ARITH.get(type(node.op))
        if swapped is not None and not _is_string_format(node):
            self._add(node, ast.BinOp(left=node.left, op=swapped(), right=node.right), "arith")
        self.generic_visit(node)

    def visit_AugAssign(self, node: ast.AugAssign) -> None:
        swapped = _ARITH.get(type(node.op))
        if swapped is not None:
            self._add(node, ast.AugAssign(target=node.target, op=swapped(), value=node.value), "arith")
        self._add(node, None, "statement")
        self.generic_visit(node)

    def visit_BoolOp(self, node: ast.BoolOp) -> None:
        other = ast.Or() if isinstance(node.op, ast.And) else ast.And()
        self._add(node, ast.BoolOp(op=other, values=node.values), "boolop")
        self.generic_visit(node)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> None:
        if isinstance(node.op, ast.Not | ast.USub):
            self._add(node, node.operand, "not")
        if isinstance(node.op, ast.USub) and isinstance(node.operand, ast.Constant):
            return  # -1 is a constant to the reader: mutate the sign, not the number as well
        self.generic_visit(node)

    def visit_Constant(self, node: ast.Constant) -> None:
        value = _mutated_constant(node.value)
        if value is not None:
            self._add(node, ast.Constant(value=value), "constant")

    def visit_Return(self, node: ast.Return) -> None:
        if node.value is not None and not (isinstance(node.value, ast.Constant) and node.value.value is None):
            self._add(node, ast.Return(value=ast.Constant(value=None)), "return")
        self.generic_visit(node)

    def visit_Expr(self, node: ast.Expr) -> None:
        if isinstance(node.value, ast.Call):
            self._add(node, None, "statement")
        self.generic_visit(node)

    def visit_Raise(self, node: ast.Raise) -> None:
        self._add(node, None, "statement")
        self.generic_visit(node)

    def visit_Break(self, node: ast.Break) -> None:
        self._add(node, None, "statement")

    visit_Continue = visit_Break


def _is_docstring(stmt: ast.stmt) -> bool:
    return isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant) and isinstance(
        stmt.value.value, str
    )


def _is_string_format(node: ast.BinOp) -> bool:
    return isinstance(node.left, ast.Constant) and isinstance(node.left.value, str)


def _segment(lines: list[bytes], line: int, col: int, end_line: int, end_col: int) -> str:
    if line == end_line:
        return lines[line - 1][col:end_col].decode()
    parts = [lines[line - 1][col:], *lines[line : end_line - 1], lines[end_line - 1][:end_col]]
    return b"".join(parts).decode()


def find_mutants(source: str, module: str, path: str) -> list[Mutant]:
    """Every mutant of one module's source, in source order.

    Parameters
    ----------
    source : str
        The module's text.
    module, path : str
        Its dotted name and its file relative to the project root (copied into each mutant).

    Returns
    -------
    list of Mutant
        Each one parses and differs from the original tree.

    Examples
    --------
    >>> [m.replacement for m in find_mutants("def f(x):\\n    return x < 1\\n", "m", "m.py")]
    ['return None', '(x >= 1)', '0']
    """
    tree = ast.parse(source)
    finder = _Finder()
    finder.visit(tree)
    lines = source.encode().splitlines(keepends=True)
    original_dump = ast.dump(tree)
    mutants: list[Mutant] = []
    seen: dict[str, int] = {}
    for node, new, operator, scope in finder.found:
        span = (node.lineno, node.col_offset, node.end_lineno, node.end_col_offset)
        text = _segment(lines, *span)
        if new is None:
            replacement = "pass"
        elif isinstance(new, ast.expr) and not isinstance(new, ast.Constant | ast.Name):
            replacement = f"({ast.unparse(new)})"
        else:
            replacement = ast.unparse(new)
        first = text.splitlines()[0] if text else text
        mutant = Mutant(module, path, *span, operator, first, replacement, scope)
        mutant = Mutant(**{**asdict(mutant), "ordinal": seen.get(mutant.id, 0)})
        try:
            mutated = apply_mutant(source, mutant)
            changed = ast.dump(ast.parse(mutated)) != original_dump
        except SyntaxError:
            continue
        if changed:
            base = mutant.id.split("#")[0]
            seen[base] = seen.get(base, 0) + 1
            mutants.append(mutant)
    return mutants


def apply_mutant(source: str, mutant: Mutant) -> str:
    """The module's source with the mutant's span replaced by its replacement text."""
    lines = source.encode().splitlines(keepends=True)
    head = b"".join(lines[: mutant.line - 1]) + lines[mutant.line - 1][: mutant.col]
    tail = lines[mutant.end_line - 1][mutant.end_col :] + b"".join(lines[mutant.end_line :])
    return (head + mutant.replacement.encode() + tail).decode()
