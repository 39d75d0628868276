"""Helpers both forms share for procedural code: sorting units as equations, the
declared stores of names, and the listing's own text of an expression."""

from __future__ import annotations

from collections.abc import Callable

from .. import ir
from .. import syntax as ast
from ..diagnostics import Span
from ..language import split_lines
from .code import CodeLowering, assigned_names
from .names import Names


def written_text(source: str | None) -> Callable[[Span], str | None]:
    """span -> the listing's text there (one line only), e.g. "T >= TSTOP"."""
    lines = split_lines(source or "")

    def text(span: Span) -> str | None:
        if span is None or span.end_line != span.line or not 1 <= span.line <= len(lines) \
                or span.end_column is None:
            return None
        found = " ".join(lines[span.line - 1][span.column - 1:span.end_column - 1].split())
        return found or None
    return text


def declared_stores(statements) -> dict[str, str]:
    """Names declared INTEGER or LOGICAL anywhere (what an assignment keeps)."""
    out: dict[str, str] = {}
    for st in statements:
        for node in ast.walk(st):
            if isinstance(node, ast.Declare) and node.type in ("INTEGER", "LOGICAL"):
                out.update(dict.fromkeys(node.names, node.type))
    return out


def first_assignment(st: ast.Node, name: str) -> Span:
    for node in ast.walk(st):
        if isinstance(node, ast.Assign) and name in node.targets:
            return node.target_spans[node.targets.index(name)]
    return st.span


def unit_equations(code: CodeLowering, names: Names, st: ast.If | ast.Procedural,
                   units: list[ir.Unit], section: str) -> list[ir.Equation]:
    """An IF or PROCEDURAL block of sorted code as one unit, and an equation for
    each of its outputs (its value: the unit's)."""
    unit = code.unit(st, len(units), section)
    if unit is None:
        return []
    units.append(unit)
    if isinstance(st, ast.If):
        partial = _partial_outputs(st)
        if partial and any(b.cond is not None and _moves(b.cond) for b in st.branches):
            code.low.warn(
                f"{', '.join(partial)} is not assigned on every path of this IF: where it "
                "is not, it keeps its value from before the block (INITIAL's, a DISCRETE's, "
                "else 0)", st.span, "assign it on every path (an ELSE) to say what it is")
    out = []
    for name in unit.outputs:
        if names.define(name, first_assignment(st, name), section):
            out.append(ir.Equation(name, ir.UnitValue(unit.index, name, st.span), st.span))
    return out


def _moves(cond: ast.Node) -> bool:
    return any(isinstance(n, ast.Name) for n in ast.walk(cond))


def _partial_outputs(st: ast.If) -> list[str]:
    everywhere: set[str] | None = None
    for b in st.branches:
        here = set(assigned_names(b.body))
        everywhere = here if everywhere is None else everywhere & here
    has_else = st.branches[-1].cond is None
    everywhere = everywhere if has_else and everywhere is not None else set()
    return [n for n in assigned_names((st,)) if n not in everywhere]
