"""Helpers both forms share for procedural code: sorting units as equations, the
declared stores of names, and the listing's own text of an expression."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from .. import ir
from ..diagnostics import Span
from ..language import split_lines
from ..parse import syntax as ast
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


def stored(st: ast.Assign, stores: dict[str, str]) -> ast.Assign:
    """An assignment of sorted code to an INTEGER (truncated toward 0) or LOGICAL (1 or
    0) name, as the value it keeps."""
    kind = stores.get(st.targets[0]) if len(st.targets) == 1 else None
    if kind == "INTEGER":
        return replace(st, expr=ast.Call("AINT", (st.expr,), st.expr.span))
    if kind == "LOGICAL" and not ast.is_logical(st.expr):
        return replace(st, expr=ast.BinOp(">", st.expr, ast.Num(0.0, st.span, "0"), st.span))
    return st


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
        # (its faults are said; what it assigns is still defined, so that what reads
        # it is not reported too: a PRINT of a CALL's output, a name the block reads
        # after assigning it)
        body = st.body if isinstance(st, ast.Procedural) else (st,)
        listed = st.outputs if isinstance(st, ast.Procedural) else ()
        for name in dict.fromkeys([*listed, *assigned_names(body)]):
            names.define(name, first_assignment(st, name), section)
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


@dataclass(frozen=True)
class ImplGroup:
    """`Y = IMPL(IC, P, FOFY)` and the statements after it up to `FOFY = ...`."""

    head: ast.Assign
    body: tuple[ast.Assign, ...]


def impl_groups(statements: list, rep) -> list:
    """DYNAMIC's statements with each IMPL loop gathered into an ImplGroup."""
    out: list = []
    i = 0
    while i < len(statements):
        st = statements[i]
        call = st.expr if isinstance(st, ast.Assign) else None
        if not (isinstance(call, ast.Call) and call.func == "IMPL"):
            out.append(st)
            i += 1
            continue
        if len(call.args) != 3 or len(st.targets) != 1 or \
                not isinstance(call.args[2], ast.Name):
            rep.error("IMPL is Y = IMPL(IC, P, FOFY): one name assigned, the first guess, "
                      "the tolerance and the name the loop computes", st.span,
                      "write Y = IMPL(IC, P, FOFY), then the statements that compute FOFY "
                      "from Y, ending with FOFY = ...")
            i += 1
            continue
        fofy = call.args[2].name
        j = i + 1
        while j < len(statements) and not (isinstance(statements[j], ast.Assign)
                                           and fofy in statements[j].targets):
            j += 1
        if j == len(statements):
            rep.error(f"IMPL for {st.targets[0]}: no statement {fofy} = ... follows", st.span,
                      f"end the loop with {fofy} = (an expression of {st.targets[0]})")
            i += 1
            continue
        body = statements[i + 1:j + 1]
        bad = next((b for b in body if not isinstance(b, ast.Assign)), None)
        if bad is not None:
            rep.error(f"the IMPL loop for {st.targets[0]} holds assignments only", bad.span)
        else:
            out.append(ImplGroup(st, tuple(body)))
        i = j + 1
    return out


def impl_equations(code: CodeLowering, names: Names, group: ImplGroup,
                   units: list[ir.Unit]) -> list[ir.Equation]:
    """An IMPL loop as one sorting unit: its statements lowered, run inside the
    fixed-point iteration (ir.Solve) from the last accepted Y (library's IMPL_LAST)."""
    from ..library import IMPL_LAST
    from .names import PURE

    head, low = group.head, code.low
    y = head.targets[0]
    ic, tol, result = head.expr.args
    if not (names.define(y, head.target_spans[0], "DYNAMIC")
            and names.check_calls(ic, PURE, "IMPL") and names.check_calls(tol, PURE, "IMPL")):
        return []
    unit = code.unit(ast.Procedural((), (), group.body, head.span), len(units), "DYNAMIC")
    if unit is None:
        return []
    last = low.memory(ast.Call(IMPL_LAST, (ic, ast.Name(y, head.span)), head.span), y)
    solve = ir.Solve(y, ir.MemoryValue(last, head.span), low.expr(tol, y), result.name,
                     unit.body, head.span)
    unit = replace(unit, kind="IMPL", outputs=(y, *unit.outputs), body=(solve,),
                   inputs=tuple(n for n in unit.inputs if n != y))
    units.append(unit)
    out = [ir.Equation(y, ir.UnitValue(unit.index, y, head.span), head.span)]
    for name in unit.outputs[1:]:
        if names.define(name, _assigned_at(group.body, name), "DYNAMIC"):
            out.append(ir.Equation(name, ir.UnitValue(unit.index, name, head.span), head.span))
    return out


def _assigned_at(body, name: str):
    return next(st.target_spans[st.targets.index(name)] for st in body if name in st.targets)


def nosort_regions(statements: list, rep) -> list:
    """Sorted code with each NOSORT ... SORT region (to the section's end when no SORT
    follows) as one written-order unit, a PROCEDURAL with inferred lists."""
    out: list = []
    region: list | None = None
    start = None
    for st in statements:
        if isinstance(st, ast.Nosort):
            if st.sorted and region is not None:
                out.append(_region(region, start))
                region = None
            elif not st.sorted and region is None:
                region, start = [], st.span
            continue
        if region is None:
            out.append(st)
        elif isinstance(st, ast.Termt):
            out.append(st)  # a TERMT ends the run wherever it stands
        else:
            region.append(st)
    if region is not None:
        out.append(_region(region, start))
    return [st for st in out if st is not None]


def _region(body: list, span) -> ast.Procedural | None:
    return ast.Procedural((), (), tuple(body), span) if body else None
