"""The template language of the library: small expressions in a Python subset that
say what a function's value, surfaces, states and memory are, over placeholders
for its arguments (see `library` for what each name means).

A template is compiler text, never model text: it is parsed once (cached) and
checked when the library registers its entry, so a wrong template fails at import.
`instantiate` builds a syntax expression from an arithmetic template (surfaces,
states: the IR's own nodes), sharing the argument subtrees it is given; `tree`
gives a fresh copy of the parsed Python tree for the compiler to fill in.
"""

from __future__ import annotations

import ast as py
from functools import cache

from ..diagnostics import Span
from ..parse import syntax

ARGUMENTS = "ABCDEFGH"
# placeholders whose meaning does not depend on the function; START is the run's
# start time as the listing declares it (ACSL's VARIABLE T = t0; 0 elsewhere)
FIXED_NAMES = frozenset({"TIME", "INF", "START"})
# placeholders of memory templates set by the run, not the listing: the random
# streams' seed, how long a draw is held, and the call site's own number
RUN_NAMES = frozenset({"SEED", "HOLD", "SITE"})
_ARITHMETIC = (py.Expression, py.BinOp, py.UnaryOp, py.Name, py.Constant, py.Call, py.Load,
               py.Add, py.Sub, py.Mult, py.Div, py.USub)
_ANY = _ARITHMETIC + (py.IfExp, py.Compare, py.BoolOp, py.And, py.Or, py.Lt, py.Gt, py.LtE,
                      py.GtE, py.Eq, py.NotEq)


def spread(text: str) -> bool:
    """A template that gives several slots at once (`*HELPER(...)`)."""
    return text.startswith("*")


@cache
def _parsed(text: str) -> py.expr:
    return py.parse(text.removeprefix("*"), mode="eval").body


def tree(text: str) -> py.expr:
    """A fresh copy of the template's Python tree (the caller may change it), with no
    positions of its own: the generated code's are those of the statement it stands
    in (`codegen.pytree.place`)."""
    return clone(_parsed(text))


def clone(node):
    """A copy of a syntax tree, its nodes' fields only (no positions, no notes): far
    cheaper than copy.deepcopy, which would also copy the IR each node remembers
    (`amil_src`). An operator or a context (Add, Load: no fields, no position) is
    the same node in both, as the parser shares them (half the nodes of the 1000-mass
    chain's rhs)."""
    if isinstance(node, py.AST):
        kind = type(node)
        if not kind._fields and not kind._attributes:
            return node
        new = kind()
        for name in node._fields:
            setattr(new, name, clone(getattr(node, name, None)))
        return new
    if isinstance(node, list):
        return [clone(x) for x in node]
    return node


def _index(name: str, prefix: str) -> int | None:
    if name.startswith(prefix) and name[len(prefix):].isdigit():
        return int(name[len(prefix):])
    return None


def check_template(text: str, owner: str, *, args: int, calls: frozenset[str],
                   modes: int = 0, states: int = 0, slots: bool = False,
                   update: bool = False, arithmetic: bool = False) -> None:
    """Raise if a template is malformed or reads a placeholder it may not."""
    def bad(why: str) -> None:
        raise ValueError(f"library entry {owner}: template {text!r}: {why}")

    if spread(text) and (arithmetic or not isinstance(_parsed(text), py.Call)):
        bad("only a helper call may give several slots")
    try:
        body = _parsed(text)
    except SyntaxError as exc:
        raise ValueError(f"library entry {owner}: template {text!r}: {exc}") from None
    allowed = _ARITHMETIC if arithmetic else _ANY
    for node in py.walk(body):
        if not isinstance(node, allowed):
            bad(f"{type(node).__name__} is not allowed here")
        if isinstance(node, py.Constant) and not isinstance(node.value, (int, float)):
            bad("constants are numbers")
        if isinstance(node, py.Call):
            if not isinstance(node.func, py.Name) or node.keywords or \
                    node.func.id not in calls:
                bad("calls name a math function or a run-time helper, positionally")
        elif isinstance(node, py.Name) and not _known(node.id, args, modes, states, slots,
                                                       update, calls):
            bad(f"{node.id} means nothing here")


def _known(name: str, args: int, modes: int, states: int, slots: bool, update: bool,
           calls: frozenset[str]) -> bool:
    if name in FIXED_NAMES or name in calls:
        return True
    if len(name) == 1 and name in ARGUMENTS:
        return ARGUMENTS.index(name) < args
    for prefix, limit in (("M", modes), ("N", modes if update else 0), ("Y", states)):
        k = _index(name, prefix)
        if k is not None:
            return k < limit
    if slots and (name in ("Z", "OFFSET") or name in RUN_NAMES
                  or _index(name, "Z") is not None):
        return True
    return update and name == "VALUE"


class _Build(py.NodeVisitor):
    """An arithmetic template as a syntax expression over given subtrees."""

    def __init__(self, args: tuple, states: tuple[str, ...], span: Span, start: float
                 ) -> None:
        self.args = args
        self.states = states
        self.span = span
        self.start = start

    def visit_Name(self, node: py.Name) -> syntax.Expr:
        if node.id == "TIME":
            return syntax.Name("TIME", self.span)
        if node.id == "START":
            return syntax.Num(self.start, self.span, repr(self.start))
        k = _index(node.id, "Y")
        if k is not None:
            return syntax.Name(self.states[k], self.span)
        return self.args[ARGUMENTS.index(node.id)]

    def visit_Constant(self, node: py.Constant) -> syntax.Expr:
        return syntax.Num(float(node.value), self.span, repr(float(node.value)))

    def visit_UnaryOp(self, node: py.UnaryOp) -> syntax.Expr:
        return syntax.Neg(self.visit(node.operand), self.span)

    def visit_BinOp(self, node: py.BinOp) -> syntax.Expr:
        if isinstance(node.right, py.Name) and node.right.id == "START" and \
                isinstance(node.op, (py.Add, py.Sub)) and self.start == 0.0:
            return self.visit(node.left)  # (a run from 0: the surface as it was written)
        op = {py.Sub: "-", py.Add: "+", py.Div: "/", py.Mult: "*"}[type(node.op)]
        return syntax.BinOp(op, self.visit(node.left), self.visit(node.right), self.span)

    def visit_Call(self, node: py.Call) -> syntax.Expr:
        return syntax.Call(node.func.id, tuple(self.visit(a) for a in node.args), self.span)

    def generic_visit(self, node: py.AST) -> syntax.Expr:
        raise AssertionError(f"not an arithmetic template node: {py.dump(node)}")


def instantiate(text: str, args: tuple, span: Span, states: tuple[str, ...] = (),
                start: float = 0.0) -> syntax.Expr:
    """The syntax expression of an arithmetic template over the given arguments
    (shared, not copied) and state names; START is `start`."""
    return _Build(args, states, span, start).visit(_parsed(text))


@cache
def template_names(text: str) -> frozenset[str]:
    """Every name a template reads (placeholders and called helpers)."""
    return frozenset(n.id for n in py.walk(_parsed(text)) if isinstance(n, py.Name))


@cache
def argument_uses(text: str) -> tuple[str, ...]:
    """The argument placeholders of a template, once per use ("C", "C" for DEADSP)."""
    return tuple(n.id for n in py.walk(_parsed(text)) if isinstance(n, py.Name)
                 and len(n.id) == 1 and n.id in ARGUMENTS)
