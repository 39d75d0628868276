"""Faults in generated code, located and explained.

Every generated statement has its own line in the code object, and the code's
globals hold the table of those statements (`STATEMENTS`), so the statement
that raised is found from the traceback alone: the frame's instruction offset
(tb_lasti) through the code's own line table (co_lines) to the line, and the
line to the IR statement. Explaining it re-runs the same function once, in a
checking copy where each division, power and function call is a helper that
reports its operands: only when a fault has happened, never on the hot path.
"""

from __future__ import annotations

import ast as py
import math
from dataclasses import dataclass

from .. import ir
from ..diagnostics import Span
from ..language import plain_float
from ..library.runtime import HelperFault
from ..parse.syntax import deep_enough
from ..parse.unparse import expr_text
from .pytree import locate

# the key under which generated code's globals hold its statement table (a name
# generated code never reads: it reads only the compiler's names)
STATEMENTS = "__amilpy_statements__"


@dataclass(frozen=True)
class Statement:
    """One statement of the generated code."""

    kind: str  # "equation", "derivative", "surface", "memory"
    target: str  # the variable it assigns, the state, or the surface's description
    span: Span | None
    expr: object = None  # the IR expression it evaluates


@dataclass(frozen=True)
class FaultReport:
    """Where a fault in generated code happened and what the operation was."""

    span: Span | None  # the listing's statement
    target: str  # the variable it assigns (W2), or what it computes
    text: str  # the operation with its operand values: "division by zero: JL = 0"

    def __str__(self) -> str:
        # (a surface's description already says its line: "X .LT. 1 at line 9")
        where = f" (line {self.span.line})" if self.span and \
            not self.target.endswith(f" at line {self.span.line}") else ""
        return f"{self.target}{where}: {self.text}"


def line_at(code, lasti: int) -> int | None:
    """The line of the instruction at byte offset `lasti`, from the line table."""
    for start, end, line in code.co_lines():
        if start <= lasti < end:
            return line
    return None


def statement_of(exc: BaseException) -> tuple[Statement | None, str, list] | None:
    """The innermost generated statement in `exc`'s traceback: (statement or None
    for scaffolding, the generated function's name, the statement table)."""
    found = None
    tb = exc.__traceback__
    while tb is not None:
        table = tb.tb_frame.f_globals.get(STATEMENTS)
        if table is not None:
            line = line_at(tb.tb_frame.f_code, tb.tb_lasti)
            stmt = table[line - 1] if line is not None and 1 <= line <= len(table) else None
            found = (stmt, tb.tb_frame.f_code.co_name, table)
        tb = tb.tb_next
    return found


def fault_point(exc: BaseException) -> tuple[float, list, list, list] | None:
    """(t, y, m, z) the innermost generated function in `exc`'s traceback was called
    with, where that was one point (not columns): where the fault happened, which may
    lie past the last instant the run took (a surface evaluated inside a step)."""
    point = None
    tb = exc.__traceback__
    while tb is not None:
        frame, code = tb.tb_frame, tb.tb_frame.f_code
        if frame.f_globals.get(STATEMENTS) is not None:
            point = None
            if code.co_varnames[:code.co_argcount] == ("t", "y", "m", "z"):
                args = tuple(frame.f_locals.get(k) for k in ("t", "y", "m", "z"))
                if isinstance(args[0], float) and isinstance(args[1], list):
                    point = args
        tb = tb.tb_next
    return point


class _Fault(Exception):
    def __init__(self, site: int, values: tuple, exc: BaseException) -> None:
        super().__init__(site)
        self.site = site
        self.values = values
        self.exc = exc


def _check_div(a, b, site):
    try:
        return a / b
    except ArithmeticError as exc:
        raise _Fault(site, (a, b), exc) from None


def _check_pow(a, b, site):
    try:
        return a**b
    except ArithmeticError as exc:
        raise _Fault(site, (a, b), exc) from None


def _check_call(site, f, *args):
    try:
        return f(*args)
    except (ArithmeticError, ValueError) as exc:
        raise _Fault(site, args, exc) from None


_HELPERS = {"_CHECK_DIV": _check_div, "_CHECK_POW": _check_pow, "_CHECK_CALL": _check_call}
_UNCHECKED = {"_WHERE", "_ALL", "_ANY", "_SGN", "_LEVEL", "_LEDGE"}


@dataclass(frozen=True)
class _Site:
    """A checked operation: its node (for the line and the operator) and the source
    of the node and of its operands, taken before the operands were rewritten."""

    node: py.AST
    source: object
    operands: tuple


class _Checking(py.NodeTransformer):
    """Divisions, powers and calls become helpers that report their operands."""

    def __init__(self) -> None:
        self.sites: list[_Site] = []

    def site(self, node: py.AST, operands: list[py.AST]) -> py.Constant:
        self.sites.append(_Site(node, _source(node), tuple(map(_source, operands))))
        return py.Constant(len(self.sites) - 1)

    def visit_BinOp(self, node: py.BinOp) -> py.expr:
        helper = {py.Div: "_CHECK_DIV", py.Pow: "_CHECK_POW"}.get(type(node.op))
        site = self.site(node, [node.left, node.right]) if helper else None
        self.generic_visit(node)
        if helper is None:
            return node
        return py.Call(py.Name(helper, py.Load()), [node.left, node.right, site], [])

    def visit_Call(self, node: py.Call) -> py.expr:
        name = node.func.id if isinstance(node.func, py.Name) else ""
        checked = name.startswith("_") and name not in _UNCHECKED and not any(
            isinstance(a, py.Constant) and isinstance(a.value, str) for a in node.args)
        site = self.site(node, node.args) if checked else None
        self.generic_visit(node)
        if not checked:
            return node
        return py.Call(py.Name("_CHECK_CALL", py.Load()), [site, node.func, *node.args], [])


def _source(node: py.AST) -> object:
    """The IR node an emitted node came from, else its Python text."""
    return getattr(node, "amil_src", None) or py.unparse(node)


def _checking_function(compiled, name: str):
    """The checking copy of one generated function (built once, on the first fault)."""
    if name not in compiled.checking:
        checking = _Checking()
        compiled.checking[name] = (_rebuilt(compiled, name, checking, _HELPERS, "checking"),
                                   checking.sites)
    return compiled.checking[name]


def _rebuilt(compiled, name: str, transformer: py.NodeTransformer, helpers: dict,
             what: str):
    """A copy of the generated function `name`, its tree changed by `transformer`,
    compiled in the model's namespace with `helpers` beside it."""
    # (a tree built for this call: changed in place)
    fn = next(f for f in compiled.module.body if f.name == name)
    tree = py.Module(body=[transformer.visit(fn)], type_ignores=[])
    locate(tree)
    scope = dict(compiled.namespace)
    scope.update(helpers)
    exec(compile(tree, f"<amilpy {what}>", "exec"), scope)  # noqa: S102 - our own tree
    return scope[name]


class _Tolerant(py.NodeTransformer):
    """Each statement of a function's body in a try: one that faults gives NaN to
    what it assigns, and the statements after it go on (NaN flows through them)."""

    def visit_FunctionDef(self, fn: py.FunctionDef) -> py.FunctionDef:
        fn.body = [self._guarded(st) for st in fn.body]
        return fn

    @staticmethod
    def _guarded(st: py.stmt) -> py.stmt:
        if isinstance(st, py.Return):
            return st
        targets = sorted({n.id for n in py.walk(st)
                          if isinstance(n, py.Name) and isinstance(n.ctx, py.Store)})
        if not targets:
            return st
        nan = [py.Assign([py.Name(t, py.Store())], py.Constant(math.nan)) for t in targets]
        faults = py.Tuple([py.Name("ArithmeticError", py.Load()),
                           py.Name("ValueError", py.Load())], py.Load())
        return py.Try(body=[st], handlers=[py.ExceptHandler(faults, None, nan)],
                      orelse=[], finalbody=[])


def tolerant(compiled, name: str):
    """The copy of one generated function in which a statement that faults makes
    its own variables NaN and no others (built once, on the first fault): a row
    whose DN = DELAY(...) cannot be computed still shows X = SIN(TIME)."""
    key = ("tolerant", name)
    if key not in compiled.checking:
        compiled.checking[key] = _rebuilt(compiled, name, _Tolerant(), {
            "ArithmeticError": ArithmeticError, "ValueError": ValueError}, "tolerant")
    return compiled.checking[key]


_SCALAR = {"surf_vec": "surf", "out_vec": "out"}


@deep_enough()
def explain(compiled, exc: BaseException, t: float, y, m, z) -> FaultReport | None:
    """The statement that raised `exc` and the operation that failed (see
    `ModelCode.explain_fault`)."""
    found = statement_of(exc)
    if found is None or found[2] is not compiled.statements:
        return None
    statement, name, table = found
    # (the functions over many rows at once are their scalar ones', statement by
    # statement: the scalar one is re-evaluated at the point given)
    name = _SCALAR.get(name, name)
    if name not in ("rhs", "surf", "out", "mem", "modes", "smp"):
        return None
    fn, sites = _checking_function(compiled, name)
    args = (t, list(y), list(m), list(m), list(z)) if name == "mem" else \
        (t, list(y), list(m), list(z))
    try:
        fn(*args)
    except _Fault as fault:
        site = sites[fault.site]
        line = getattr(site.node, "lineno", 1)
        at = table[line - 1] if 1 <= line <= len(table) else None
        statement = at or statement
        text = _describe(compiled.model, site, fault)
    except (ArithmeticError, ValueError) as again:
        text = str(again)
    else:
        text = str(exc)  # not reproduced with these values: say what was raised
    if statement is None:
        return FaultReport(None, "generated code", text)
    return FaultReport(statement.span, statement.target, text)


def _text(model: ir.Model, source: object) -> str:
    return source if isinstance(source, str) else expr_text(model, source)


def _value(v: float) -> str:
    """An operand as short as %g when that is exact, else every digit it takes:
    ASIN's argument 1.0000000000000002 must not read as 1, which is in range."""
    short = f"{v:g}"
    return short if float(short) == v or not math.isfinite(v) else repr(float(v))


def _describe(model: ir.Model, site: _Site, fault: _Fault) -> str:
    """The failed operation in the listing's notation, with its operand values."""
    if isinstance(fault.exc, HelperFault):
        return str(fault.exc)
    what = {ZeroDivisionError: "division by zero", OverflowError: "overflow"}.get(
        type(fault.exc), "math domain error")
    texts = [_text(model, s) for s in site.operands]
    if isinstance(site.node, py.BinOp):
        (a, b), (left, right) = fault.values, texts
        if isinstance(site.node.op, py.Div):
            return f"{what}: {left}/{right}" if plain_float(right) is not None else \
                f"{what}: {right} = {_value(b)}"
        if isinstance(fault.exc, ZeroDivisionError):
            return f"0 raised to a negative power: {left} = {_value(a)}, {right} = {_value(b)}"
        return f"{what}: {left}**{right} with {left} = {_value(a)}"
    named = [(n, v) for n, v in zip(texts, fault.values, strict=False)
             if plain_float(n) is None and isinstance(v, float)]
    values = ", ".join(f"{n} = {_value(v)}" for n, v in named)
    return f"{what}: {_text(model, site.source)}" + (f" with {values}" if values else "")
