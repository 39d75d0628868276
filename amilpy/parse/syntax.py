"""The abstract syntax of a listing: small frozen dataclasses that carry source spans,
and the checked visitor every later stage uses to walk them.

`parse.py` is the only module that builds these from lark trees; every later
stage reads only these (and the IR nodes of `ir.py`, which join the same family).

Every node class registers itself by name (`NODES`). `children()` lists the
sub-nodes a plain walk descends into, so `walk` needs no ladder. A `Visitor`
dispatches on the class name (`visit_Num`, `visit_BinOp`, ...); when a visitor
class is defined, each of its `visit_X` must name a registered node class, and a
visitor that declares `complete = SOME_FAMILY` must handle every class of that
family, so adding a node fails at import wherever it is not handled.
"""

from __future__ import annotations

import dataclasses
import gc
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any, ClassVar

from ..diagnostics import Span

# every node class, by name: what a visit_X method may name
NODES: dict[str, type[Node]] = {}

# The deepest expression a listing may hold (a sum of 1000 terms is 1000 deep):
# the reader refuses deeper ones with a located error, and every stage that walks
# expressions recursively makes room for this depth (`deep_enough`).
MAX_DEPTH = 1500
_FRAMES_PER_LEVEL = 40  # the deepest recursive walk (copying Python trees) with margin


@contextmanager
def deep_enough() -> Iterator[None]:
    """Python's recursion limit raised (for the block) to what walking an expression
    of MAX_DEPTH levels needs."""
    old = sys.getrecursionlimit()
    need = MAX_DEPTH * _FRAMES_PER_LEVEL + 1000
    if old < need:
        sys.setrecursionlimit(need)
    try:
        yield
    finally:
        if old < need:
            sys.setrecursionlimit(old)


@contextmanager
def no_collection() -> Iterator[None]:
    """Python's cyclic garbage collector held off (for the block). The front end
    makes millions of small objects that live on (syntax and Python trees); each
    full collection walks every one, which took a quarter of a large model's
    reading and building. Nothing it makes is garbage in a cycle worth finding."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


class Node:
    """Base of every syntax and IR node."""

    __slots__ = ()
    # the fields that hold sub-nodes (a node or a tuple of nodes), in source order;
    # node classes set it without an annotation, so no dataclass takes it for a field
    child_fields: ClassVar[tuple[str, ...]] = ()
    # a class that says its children itself (`children` overridden): `walk` asks it
    own_children: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        name = cls.__name__
        if name in NODES and NODES[name] is not cls and NODES[name].__module__ != cls.__module__:
            raise TypeError(f"two node classes named {name}: visitors dispatch on the name")
        NODES[name] = cls
        cls.own_children = cls.children is not Node.children

    def children(self) -> tuple[Node, ...]:
        out: list[Node] = []
        for f in self.child_fields:
            value = getattr(self, f)
            if isinstance(value, tuple):
                out.extend(value)
            else:
                out.append(value)
        return tuple(out)


def walk(node: Node) -> Iterator[Node]:
    """Every node under `node`, parents before children, left to right (iterative:
    any depth). IR instances (a switch's arguments) are not entered: they live on
    the instance, not under the node that reads its value."""
    stack = [node]
    pop, push = stack.pop, stack.append
    while stack:
        n = pop()
        yield n
        if n.own_children:
            stack.extend(reversed(n.children()))
            continue
        fields = n.child_fields
        if not fields:  # (a number, a name: most nodes)
            continue
        if len(fields) == 1:
            value = getattr(n, fields[0])
            if value.__class__ is tuple:
                stack.extend(value[::-1])
            else:
                push(value)
            continue
        below: list[Node] = []
        for f in fields:
            value = getattr(n, f)
            if value.__class__ is tuple:
                below.extend(value)
            else:
                below.append(value)
        below.reverse()
        stack.extend(below)


class Visitor:
    """Dispatch on the class name: `visit(node, ...)` calls `visit_<Class>(node, ...)`.

    A class without a `visit_X` for a node goes to `generic(node, ...)`, which
    raises unless the subclass overrides it. Checked when a subclass is defined:
    every `visit_X` names a node class, and `complete` (a tuple of node classes)
    is handled in full.
    """

    complete: ClassVar[tuple[type[Node], ...]] = ()
    _table: ClassVar[dict[type, Any]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        for attr in dir(cls):
            if attr.startswith("visit_") and attr[6:] not in NODES:
                raise TypeError(f"{cls.__qualname__}.{attr} names no node class "
                                f"(known: {', '.join(sorted(NODES))})")
        missing = [c.__name__ for c in cls.complete if not hasattr(cls, "visit_" + c.__name__)]
        if missing:
            raise TypeError(f"{cls.__qualname__} is declared complete but does not visit "
                            + ", ".join(missing))
        cls._table = {}

    def visit(self, node: Node, *args: Any) -> Any:
        table = type(self)._table
        method = table.get(type(node))
        if method is None:
            method = getattr(type(self), "visit_" + type(node).__name__, None) \
                or type(self).generic
            table[type(node)] = method
        # a plain call when there are no extra arguments: CPython runs it without
        # a C stack frame, so deep expressions cost Python frames only
        return method(self, node, *args) if args else method(self, node)

    def generic(self, node: Node, *args: Any) -> Any:
        raise TypeError(f"{type(self).__qualname__} cannot visit {type(node).__name__}")


# ----------------------------------------------------------------- expressions


@dataclass(frozen=True)
class Num(Node):
    value: float
    span: Span
    text: str = ""  # as written ("1.5D-3"), for messages and reports


@dataclass(frozen=True)
class Name(Node):
    name: str  # folded to upper case
    span: Span


@dataclass(frozen=True)
class Call(Node):
    func: str  # as written, folded to upper case (an alias stays an alias)
    args: tuple[Expr, ...]
    span: Span
    # Where the argument list sits, for the decimal-comma hint.
    arg_spans: tuple[Span, ...] = ()
    child_fields = ("args",)


@dataclass(frozen=True)
class Index(Node):
    """An array's element, `X[i]` or `X(i, j)` once X is declared an array: only the
    reader makes one, and `parse.arrays` turns every one into the element's own
    variable (or, for a subscript known only while the run goes, an ELEMENT call)
    before anything else reads the program."""

    name: str
    args: tuple[Expr, ...]
    span: Span
    child_fields = ("args",)


@dataclass(frozen=True)
class BinOp(Node):
    # arithmetic + - * / **; relational < <= > >= == /= (a number 1.0 or 0.0);
    # logical AND OR EQV NEQV (operands true when > 0; a number 1.0 or 0.0)
    op: str
    left: Expr
    right: Expr
    span: Span
    child_fields = ("left", "right")


@dataclass(frozen=True)
class Neg(Node):
    operand: Expr
    span: Span
    child_fields = ("operand",)


@dataclass(frozen=True)
class Not(Node):
    """`.NOT. X` (also `~X`): 1.0 when X is not true (X <= 0), else 0.0."""

    operand: Expr
    span: Span
    child_fields = ("operand",)


# the operators of BinOp by kind (the grammar's spellings fold to these)
RELATIONAL = ("<", "<=", ">", ">=", "==", "/=")
LOGICAL = ("AND", "OR", "EQV", "NEQV")

Expr = Num | Name | Call | BinOp | Neg | Not
# the expression nodes of the syntax: a visitor of syntax expressions declares
# `complete = EXPRESSIONS` (ir.EXPRESSIONS adds the IR's own)
EXPRESSIONS: tuple[type[Node], ...] = (Num, Name, Call, BinOp, Neg, Not)
# the reader's nodes that `parse.arrays` resolves: no stage after the reader sees one
RESOLVED_BY_READER: tuple[type[Node], ...] = (Index,)


_EXPRESSION_CLASSES = frozenset({*EXPRESSIONS, Index})


def walk_statements(node: Node) -> Iterator[Node]:
    """`walk`, but an expression's parts not entered: every node under `node` that is
    no part of an expression (an expression holds expressions only), and the
    expressions those hold. For a search for statements (a GO TO, a MACRO call): on
    a large model, a tenth of the nodes `walk` visits."""
    stack = [node]
    while stack:
        n = stack.pop()
        yield n
        if n.__class__ in _EXPRESSION_CLASSES:
            continue
        stack.extend(reversed(n.children()))


def is_logical(e: Node) -> bool:
    """An expression whose value is a truth (1.0 or 0.0) by its form: a relational
    or logical operation, .NOT., .TRUE./.FALSE. (as written)."""
    if isinstance(e, BinOp):
        return e.op in RELATIONAL or e.op in LOGICAL
    if isinstance(e, Not):
        return True
    return isinstance(e, Num) and e.text.upper() in (".TRUE.", ".FALSE.")


# ------------------------------------------------------------------ statements


@dataclass(frozen=True)
class Assign(Node):
    targets: tuple[str, ...]
    target_spans: tuple[Span, ...]
    expr: Expr
    span: Span
    # X(i, j) = ...: the target's subscripts (the reader's; `parse.arrays` resolves them)
    subscripts: tuple[Expr, ...] = ()
    child_fields = ("expr",)


@dataclass(frozen=True)
class DataItem(Node):
    name: str
    values: tuple[float, ...]  # more than one: one run per value
    span: Span
    is_list: bool = False
    # ACSL's CONSTANT X = 1, 2, 3 (n*v repeats v): the values of the array X's elements
    is_array: bool = False
    # the values as written where a count or a value names a constant, (n, v, span)
    # each, n an int or a name, v a float or a name (`arrays` reads them; values is ())
    pieces: tuple = ()
    text: str | None = None  # a text in quotes (ACSL form), for a CHARACTER name
    # FST's X(2) = v or X(1:N) = v1, v2, ...: the first and last subscript, each a
    # number or a name (`arrays` gives the elements their values)
    element: tuple = ()


@dataclass(frozen=True)
class Data(Node):
    keyword: str  # PARAM, CONST, INCON (aliases folded)
    items: tuple[DataItem, ...]
    span: Span


@dataclass(frozen=True)
class Table(Node):
    name: str
    xs: tuple[float, ...]
    ys: tuple[float, ...]
    span: Span
    odd_count: bool = False
    # ACSL's TABLE of 2 or 3 variables: the others' breakpoints (ys then holds every
    # value, xs's index fastest); `parse.arrays` writes it out as 1-variable tables
    grid: tuple[tuple[float, ...], ...] = ()


@dataclass(frozen=True)
class Setting(Node):
    name: str
    value: float
    span: Span


@dataclass(frozen=True)
class Timer(Node):
    settings: tuple[Setting, ...]
    span: Span


@dataclass(frozen=True)
class Method(Node):
    name: str
    span: Span


@dataclass(frozen=True)
class Tolerance(Node):
    kind: str  # RELERR or ABSERR
    default: float | None
    settings: tuple[Setting, ...]
    span: Span


@dataclass(frozen=True)
class Finish(Node):
    settings: tuple[Setting, ...]  # FINISH X = v: where X crosses v
    span: Span
    # FINISH X > v (FST): where the relation first holds, as TERMT(X > v)
    relations: tuple[Termt, ...] = ()


@dataclass(frozen=True)
class Termt(Node):
    expr: Expr
    span: Span
    message: str | None = None  # TERMT(c, 'message'): said with the time when it stops
    # what the listing wrote, where that is no TERMT: "STOP in SUBROUTINE ASTRO"
    written: str = ""
    # a routine's STOP or FATALERR: Fortran's STOP ends the program, the later runs too
    ends_job: bool = False
    child_fields = ("expr",)


@dataclass(frozen=True)
class Report(Node):
    kind: str  # PRINT, OUTPUT, PRTPLT, RANGE, PREPARE (PLOT folded into OUTPUT)
    names: tuple[str, ...]
    name_spans: tuple[Span, ...]
    span: Span
    x: str | None = None  # OUTPUT Y1, Y2 VS X: the variable on the horizontal axis
    x_span: Span | None = None


@dataclass(frozen=True)
class Label(Node):
    text: str
    span: Span


@dataclass(frozen=True)
class Title(Node):
    text: str
    span: Span


@dataclass(frozen=True)
class Section(Node):
    name: str  # INITIAL, DYNAMIC, TERMINAL
    span: Span
    written: str = ""  # the keyword as written (DERIVATIVE opens DYNAMIC in CSMP form)


@dataclass(frozen=True)
class End(Node):
    span: Span


@dataclass(frozen=True)
class Stop(Node):
    span: Span


# --------------------------------------- procedural code and the ACSL form (8-11)


@dataclass(frozen=True)
class Branch(Node):
    """One branch of an IF: its condition (None: ELSE) and statements."""

    cond: Expr | None
    body: tuple[Statement, ...]
    span: Span

    def children(self) -> tuple[Node, ...]:
        return ((self.cond,) if self.cond is not None else ()) + self.body


@dataclass(frozen=True)
class If(Node):
    """IF (c) THEN ... [ELSE IF (c) THEN ...] [ELSE ...] END IF, Magnolia's IF (c) ...
    END, and the one-line IF (c) statement (one branch of one statement)."""

    branches: tuple[Branch, ...]
    span: Span
    child_fields = ("branches",)


@dataclass(frozen=True)
class Procedural(Node):
    """PROCEDURAL (o1, o2 = i1, i2) ... END: one sorting unit, written order inside."""

    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    body: tuple[Statement, ...]
    span: Span
    child_fields = ("body",)


@dataclass(frozen=True)
class Loop(Node):
    """FOR i = a, b [, s] ... END  or  DO i = a, b [, s] ... END DO."""

    var: str
    start: Expr
    stop: Expr
    step: Expr | None
    body: tuple[Statement, ...]
    span: Span
    keyword: str = "DO"

    def children(self) -> tuple[Node, ...]:
        return (self.start, self.stop) + ((self.step,) if self.step is not None else ()) \
            + self.body


@dataclass(frozen=True)
class FunctionDef(Node):
    """FUNCTION y = f(a, b) ... END (ACSL form): written order, no states."""

    name: str
    result: str
    params: tuple[str, ...]
    body: tuple[Statement, ...]
    span: Span
    child_fields = ("body",)


@dataclass(frozen=True)
class Block(Node):
    """A section of the ACSL form: INITIAL, DYNAMIC, DERIVATIVE, DISCRETE (with its
    name), TERMINAL; `END` closes it."""

    kind: str
    name: str | None
    body: tuple[Statement, ...]
    span: Span
    child_fields = ("body",)


@dataclass(frozen=True)
class Schedule(Node):
    """SCHEDULE s .AT. e (kind AT), or .XP./.XN./.XZ. e (a crossing of e)."""

    section: str
    kind: str  # AT, XP, XN, XZ
    expr: Expr
    span: Span
    child_fields = ("expr",)


@dataclass(frozen=True)
class Interval(Node):
    """INTERVAL v = dt inside a DISCRETE section: it runs at t0 and every v after."""

    name: str
    expr: Expr
    span: Span
    child_fields = ("expr",)


@dataclass(frozen=True)
class Cinterval(Node):
    """CINTERVAL CINT = v: the name and value of the output interval."""

    name: str
    expr: Expr
    span: Span
    child_fields = ("expr",)


@dataclass(frozen=True)
class Variable(Node):
    """VARIABLE X [= t0]: the independent variable's name and start."""

    name: str
    value: float | None
    span: Span


@dataclass(frozen=True)
class Control(Node):
    """ALGORITHM, NSTEPS, MAXTERVAL, MINTERVAL, MERROR, XERROR: NAME = value, ..."""

    keyword: str
    settings: tuple[Setting, ...]
    span: Span


@dataclass(frozen=True)
class Declare(Node):
    """LOGICAL / INTEGER / REAL / DOUBLEPRECISION names (DIMENSION without sizes)."""

    type: str  # LOGICAL, INTEGER or REAL
    names: tuple[str, ...]
    name_spans: tuple[Span, ...]
    span: Span
    # an array's sizes, per name (() for a scalar): `parse.arrays` declares its elements
    sizes: tuple[tuple[Expr, ...], ...] = ()


@dataclass(frozen=True)
class Item(Node):
    """NAME = 'text' or NAME = number in an FST WEATHER or TRANSLATION_* statement."""

    name: str
    value: str | float
    span: Span


@dataclass(frozen=True)
class Translation(Node):
    """TRANSLATION_GENERAL DRIVER = 'EUDRIV', ...; TRANSLATION_FSE (FST, section 13)."""

    kind: str  # TRANSLATION_GENERAL or TRANSLATION_FSE
    items: tuple[Item, ...]
    span: Span


@dataclass(frozen=True)
class Weather(Node):
    """WEATHER WTRDIR = '...'; CNTR = 'NLD'; ISTN = 1; IYEAR = 1990 (FST)."""

    items: tuple[Item, ...]
    span: Span


@dataclass(frozen=True)
class ZeroCondition(Node):
    """ZEROCONDITION e, FIRSTTIME t or NEXTTIME t (`kind`) inside an FST EVENT block
    (the nester puts them in `Event`)."""

    expr: Expr
    span: Span
    kind: str = "ZEROCONDITION"
    child_fields = ("expr",)


@dataclass(frozen=True)
class NewValue(Node):
    """NEWVALUE X = e inside an FST EVENT block: X's value from the event on."""

    target: str
    target_span: Span
    expr: Expr
    span: Span
    child_fields = ("expr",)


@dataclass(frozen=True)
class Event(Node):
    """EVENT ... ENDEVENT (FST 3): a state event (ZEROCONDITION e: where e reaches zero
    from either side) or a time event (FIRSTTIME t1, and NEXTTIME t2: at t1, then at
    each t2 it gives). There its assignments (`helpers`, values of the event's own)
    and then its NEWVALUEs are computed, all from the values before it, and the
    NEWVALUEs given at once: X a state or a SET variable. Its PARAMETERs are the
    listing's (`data`, taken out by the nester)."""

    zero: ZeroCondition | None
    first: ZeroCondition | None
    next: ZeroCondition | None
    helpers: tuple[Assign, ...]
    values: tuple[NewValue, ...]
    span: Span
    data: tuple = ()

    def children(self) -> tuple[Node, ...]:
        return tuple(n for n in (self.zero, self.first, self.next) if n is not None) + \
            self.helpers + self.values


@dataclass(frozen=True)
class SetValue(Node):
    """SET X = e (FST 3, in INITIAL): X's first value; afterwards only an EVENT's
    NEWVALUE changes it."""

    target: str
    target_span: Span
    expr: Expr
    span: Span
    child_fields = ("expr",)


@dataclass(frozen=True)
class Macro(Node):
    """MACRO O1, O2 = NAME(P1, P2) ... ENDMAC (CSMP III), or ACSL's MACRO NAME(A1,
    A2) ... MACRO END (`acsl`: every argument positional, `defaults` from MACRO
    STANDVAL, `local` the names MACRO REDEFINE makes each call's own): expanded at
    each call before checking (parse/macros.py); no later stage sees one."""

    name: str
    outputs: tuple[str, ...]
    params: tuple[str, ...]
    body: tuple[Statement, ...]
    span: Span
    acsl: bool = False
    defaults: tuple[tuple[str, float], ...] = ()
    local: tuple[str, ...] = ()
    child_fields = ("body",)


@dataclass(frozen=True)
class MacroCall(Node):
    """NAME(e1, e2, ...) as a statement: a call of an ACSL MACRO (parse/macros.py)."""

    name: str
    args: tuple[Expr, ...]
    span: Span
    child_fields = ("args",)


@dataclass(frozen=True)
class SubroutineCall(Node):
    """CALL NAME(e1, e2, ...): a subroutine written after STOP, run as a PROCEDURAL
    (parse/fortran.py)."""

    name: str
    args: tuple[Expr, ...]
    span: Span
    child_fields = ("args",)


@dataclass(frozen=True)
class GoTo(Node):
    """GO TO label: a jump forward in written-order code (parse/jumps.py writes it
    out as IF blocks)."""

    label: str  # as written, upper case; a number without its leading zeros
    span: Span


@dataclass(frozen=True)
class Target(Node):
    """`label:` (or a Fortran label) before a statement a GO TO jumps to."""

    label: str
    span: Span


@dataclass(frozen=True)
class MacroDirective(Node):
    """MACRO STANDVAL A = v, ... or MACRO REDEFINE X, Y inside an ACSL MACRO: folded
    into the MACRO when its body is read (parse/blocks.py)."""

    kind: str  # STANDVAL or REDEFINE
    names: tuple[str, ...]
    values: tuple[float, ...]
    span: Span


@dataclass(frozen=True)
class Nosort(Node):
    """NOSORT (sorted=False) or SORT (True): a written-order region of sorted code."""

    sorted: bool
    span: Span


@dataclass(frozen=True)
class DefineCall(Node):
    """DEFINE_CALL NAME(...): a Fortran routine's interface, read and not needed."""

    span: Span


Statement = (
    Assign | Data | Table | Timer | Method | Tolerance | Finish | Termt | Report | Label
    | Title | Section | End | Stop | If | Procedural | Loop | FunctionDef | Block | Schedule
    | Interval | Cinterval | Variable | Control | Declare | Translation | Weather | DefineCall
    | Macro | MacroCall | MacroDirective | SubroutineCall | Nosort
)
STATEMENTS: tuple[type[Node], ...] = (Assign, Data, Table, Timer, Method, Tolerance, Finish,
                                      Termt, Report, Label, Title, Section, End, Stop, If,
                                      Procedural, Loop, FunctionDef, Block, Schedule, Interval,
                                      Cinterval, Variable, Control, Declare, Translation,
                                      Weather, DefineCall, Macro, MacroCall, MacroDirective,
                                      SubroutineCall, Nosort, GoTo, Target, Event,
                                      ZeroCondition, NewValue, SetValue)


@dataclass(frozen=True)
class Program:
    statements: tuple[Statement, ...]
    path: str | None
    source: str
    form: str = "CSMP"  # ACSL when the file starts with PROGRAM or MODEL (section 9)
    name: str = ""  # the ACSL program's name (the rest of its PROGRAM/MODEL line)
    # the MACROs (CSMP III's and ACSL's), expanded before checking: (name, first and
    # last line of the definition, the spans of its calls), so a fault in a body names
    # the calls too
    macros: tuple[tuple[str, int, int, tuple[Span, ...]], ...] = ()
    # constants that size an array or bound a loop written out over one: fixed when
    # the listing is read (a run may not change them)
    fixed: frozenset[str] = frozenset()
    notes: tuple = ()  # the reader's warnings (diagnostics.Diagnostic), kept with the model
    # an FST listing that assigns PI: FST has none, PI is the listing's own variable
    own_pi: bool = False


def with_bodies(st, fix):
    """st with `fix` applied to each statement list it holds (IF branches, blocks,
    PROCEDURAL, loops, an ACSL MACRO's body)."""
    if isinstance(st, If):
        return replace(st, branches=tuple(replace(b, body=tuple(fix(b.body)))
                                          for b in st.branches))
    if isinstance(st, (Block, Procedural, Loop, FunctionDef)):
        return replace(st, body=tuple(fix(st.body)))
    return st


def rebuilt(node, leaf, skip: frozenset[str] = frozenset()):
    """node with `leaf(value)` in place of every value of its fields that is neither a
    node nor a tuple (names, numbers, spans: a dataclass is entered, a Span too), at
    any depth; the fields named in `skip` are kept as they are. Unchanged parts are
    the same objects."""
    if isinstance(node, tuple):
        out = tuple(rebuilt(x, leaf, skip) for x in node)
        return node if all(a is b for a, b in zip(out, node, strict=True)) else out
    if isinstance(node, Span) or not dataclasses.is_dataclass(node) or \
            isinstance(node, type):
        return leaf(node)
    changes = {}
    for f in dataclasses.fields(node):
        if f.name in skip:
            continue
        value = getattr(node, f.name)
        new = rebuilt(value, leaf, skip)
        if new is not value:
            changes[f.name] = new
    return replace(node, **changes) if changes else node


def every_statement(statements) -> list:
    """Every statement, in blocks and loops too, in written order."""
    out, stack = [], list(reversed(statements))
    while stack:
        st = stack.pop()
        out.append(st)
        body = getattr(st, "body", None)
        if isinstance(st, If):
            body = tuple(s for b in st.branches for s in b.body)
        if body:
            stack.extend(reversed(body))
    return out
