"""The abstract syntax of a listing: small frozen dataclasses that carry source spans.

`parse.py` is the only module that builds these from lark trees; every later
stage reads only these.
"""

from __future__ import annotations

from dataclasses import dataclass

from .diagnostics import Span

# ----------------------------------------------------------------- expressions


@dataclass(frozen=True)
class Num:
    value: float
    span: Span
    text: str = ""


@dataclass(frozen=True)
class Name:
    name: str  # folded to upper case
    span: Span


@dataclass(frozen=True)
class Call:
    func: str  # folded to upper case
    args: tuple[Expr, ...]
    span: Span
    # Where the argument list sits, for the decimal-comma hint.
    arg_spans: tuple[Span, ...] = ()


@dataclass(frozen=True)
class BinOp:
    op: str  # one of + - * / **
    left: Expr
    right: Expr
    span: Span


@dataclass(frozen=True)
class Neg:
    operand: Expr
    span: Span


Expr = Num | Name | Call | BinOp | Neg


def walk(expr: Expr):
    """Every node of an expression, parents before children."""
    stack = [expr]
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, BinOp):
            stack.append(node.right)
            stack.append(node.left)
        elif isinstance(node, Neg):
            stack.append(node.operand)
        elif isinstance(node, Call):
            stack.extend(reversed(node.args))


# ------------------------------------------------------------------ statements


@dataclass(frozen=True)
class Assign:
    targets: tuple[str, ...]
    target_spans: tuple[Span, ...]
    expr: Expr
    span: Span


@dataclass(frozen=True)
class DataItem:
    name: str
    values: tuple[float, ...]  # more than one: one run per value
    span: Span
    is_list: bool = False


@dataclass(frozen=True)
class Data:
    keyword: str  # PARAM, CONST, INCON (aliases folded)
    items: tuple[DataItem, ...]
    span: Span


@dataclass(frozen=True)
class Table:
    name: str
    xs: tuple[float, ...]
    ys: tuple[float, ...]
    span: Span
    odd_count: bool = False


@dataclass(frozen=True)
class Setting:
    name: str
    value: float
    span: Span


@dataclass(frozen=True)
class Timer:
    settings: tuple[Setting, ...]
    span: Span


@dataclass(frozen=True)
class Method:
    name: str
    span: Span


@dataclass(frozen=True)
class Tolerance:
    kind: str  # RELERR or ABSERR
    default: float | None
    settings: tuple[Setting, ...]
    span: Span


@dataclass(frozen=True)
class Finish:
    settings: tuple[Setting, ...]
    span: Span


@dataclass(frozen=True)
class Termt:
    expr: Expr
    span: Span


@dataclass(frozen=True)
class Report:
    kind: str  # PRINT, OUTPUT, PRTPLT, RANGE, PREPARE (PLOT folded into OUTPUT)
    names: tuple[str, ...]
    name_spans: tuple[Span, ...]
    span: Span


@dataclass(frozen=True)
class Label:
    text: str
    span: Span


@dataclass(frozen=True)
class Title:
    text: str
    span: Span


@dataclass(frozen=True)
class Section:
    name: str  # INITIAL, DYNAMIC, TERMINAL
    span: Span


@dataclass(frozen=True)
class End:
    span: Span


@dataclass(frozen=True)
class Stop:
    span: Span


Statement = (
    Assign | Data | Table | Timer | Method | Tolerance | Finish | Termt | Report | Label
    | Title | Section | End | Stop
)


@dataclass(frozen=True)
class Program:
    statements: tuple[Statement, ...]
    path: str | None
    source: str
