"""The right-hand side of a large model as NumPy operations on groups of alike
statements (issue 14.3: a chain of 1000 masses).

The generated `rhs` is one Python statement per equation: about 0.05 us each a
call, cheaper than NumPy for small models and 10-20 times dearer for a model of
thousands of statements whose equations repeat (the N-mass chain: N - 1 coupling
forces of one shape, N accelerations of one shape). Here the statements of the
generated `rhs` (and its returned derivatives) are grouped by their shape (the
expression with every name and float constant taken out) and by their level in
the dependency order (a statement comes after everything it reads), and each
group is evaluated at once on arrays gathered from one value vector: one NumPy
expression per group instead of one Python statement per equation.

Where a group meets a fault (a division by zero, a square root of a negative
number) NumPy gives a non-finite value silently: the call then evaluates the
scalar `rhs` at the same point, which raises the fault at its statement as
usual, or gives the same non-finite value.
"""

from __future__ import annotations

import ast as py
from collections.abc import Callable
from dataclasses import dataclass
from types import FunctionType

import numpy as np

from ..library.templates import clone
from .pytree import function, place, vector_namespace

MIN_STATEMENTS = 400  # below this the scalar code is as fast (measured on the chain)
MIN_PER_GROUP = 12  # statements per group on average, else nothing repeats enough


@dataclass
class _Statement:
    target: int  # slot in the value vector (or -1 - i: derivative i)
    expr: py.expr
    level: int


class _Shape(py.NodeTransformer):
    """Takes the names and float constants out of an expression: `slots` (value
    names), `modes` (mN), `memory` (zN), `floats`, in the order met; walrus names
    become W0, W1, ... (local to the expression)."""

    def __init__(self, values: dict[str, int]) -> None:
        self.values = values
        self.slots: list[int] = []
        self.modes: list[int] = []
        self.memory: list[int] = []
        self.floats: list[float] = []
        self.local: dict[str, str] = {}

    def visit_Name(self, node: py.Name) -> py.expr:
        name = node.id
        if name in self.local:
            return py.Name(self.local[name], node.ctx)
        if isinstance(node.ctx, py.Store):  # a walrus target
            self.local[name] = f"W{len(self.local)}"
            return py.Name(self.local[name], py.Store())
        if name in self.values:
            self.slots.append(self.values[name])
            return py.Name(f"P{len(self.slots) - 1}", py.Load())
        if name[0] in "mz" and name[1:].isdigit():
            table = self.modes if name[0] == "m" else self.memory
            table.append(int(name[1:]))
            return py.Name(f"{name[0].upper()}{len(table) - 1}", py.Load())
        return node

    def visit_Constant(self, node: py.Constant) -> py.expr:
        if isinstance(node.value, float):
            self.floats.append(node.value)
            return py.Name(f"C{len(self.floats) - 1}", py.Load())
        return node


class _Vector(py.NodeTransformer):
    """A shape as NumPy code on the group's gathered arrays."""

    def __init__(self, g: int) -> None:
        self.g = g

    def visit_Name(self, node: py.Name) -> py.expr:
        kind, rest = node.id[0], node.id[1:]
        if not rest.isdigit() or kind not in "PMZCW":
            return node
        if kind == "W":
            return py.Name(f"w_{rest}", node.ctx)
        source = {"P": "V", "M": "M", "Z": "Z"}.get(kind)
        index = py.Name(f"_I{self.g}_{kind}{rest}", py.Load())
        if source is None:  # a float constant: its array
            return index
        return py.Subscript(py.Name(source, py.Load()), index, py.Load())

    def visit_IfExp(self, node: py.IfExp) -> py.expr:
        self.generic_visit(node)
        return py.Call(py.Name("_WHERE", py.Load()), [node.test, node.body, node.orelse], [])

    def visit_BoolOp(self, node: py.BoolOp) -> py.expr:
        self.generic_visit(node)
        fn = "_ALL" if isinstance(node.op, py.And) else "_ANY"
        return py.Call(py.Name(fn, py.Load()), node.values, [])


def build(rhs: py.FunctionDef, n: int) -> Callable | None:
    """The rolled right-hand side `rhs(t, y, m, z) -> array` of a generated `rhs`, or
    None when the model is too small or its statements do not repeat."""
    statements, values = _statements(rhs, n)
    if statements is None or len(statements) < MIN_STATEMENTS:
        return None
    groups: dict[tuple, list[tuple[_Statement, _Shape]]] = {}
    for s in statements:
        shape = _Shape(values)
        # (on a copy: the tree is the Jacobian's to differentiate too)
        key_tree = shape.visit(clone(s.expr))
        key = (s.level, s.target < 0, py.dump(key_tree))
        groups.setdefault(key, []).append((s, shape))
    if len(statements) < MIN_PER_GROUP * len(groups):
        return None
    scope: dict[str, object] = {"__builtins__": {}}
    scope.update(vector_namespace())
    body: list[py.stmt] = [py.parse(f"V = _EMPTY({len(values)})").body[0],
                           py.parse(f"V[:{n}] = y").body[0],
                           py.parse(f"D = _EMPTY({n})").body[0],
                           py.parse("M = _ARRAY(m)").body[0], py.parse("Z = _ARRAY(z)").body[0]]
    scope.update(_EMPTY=np.empty, _ARRAY=lambda v: np.asarray(v, dtype=float))
    for g, (_, members) in enumerate(sorted(groups.items(), key=lambda kv: kv[0][0])):
        first = members[0][1]
        for kind, values_of in (("P", lambda sh: sh.slots), ("M", lambda sh: sh.modes),
                                ("Z", lambda sh: sh.memory)):
            for k in range(len(values_of(first))):
                scope[f"_I{g}_{kind}{k}"] = np.array([values_of(sh)[k] for _, sh in members])
        for k in range(len(first.floats)):
            scope[f"_I{g}_C{k}"] = np.array([sh.floats[k] for _, sh in members])
        expr = _Vector(g).visit(_Shape(values).visit(clone(members[0][0].expr)))
        targets = np.array([s.target for s, _ in members])
        scope[f"_O{g}"] = targets if targets[0] >= 0 else -1 - targets
        out = "V" if targets[0] >= 0 else "D"
        body.append(py.Assign([py.Subscript(py.Name(out, py.Load()),
                                            py.Name(f"_O{g}", py.Load()), py.Store())], expr))
    body.append(py.Return(py.Name("D", py.Load())))
    fn = function("rhs_rolled", ("t", "y", "m", "z"), body)
    tree = py.Module(body=[fn], type_ignores=[])
    place(tree, closed=True, also=lambda name: name in ("V", "D", "M", "Z") or
          name.startswith(("_I", "_O", "w_")) or name in ("_EMPTY", "_ARRAY"))
    exec(compile(tree, "<rolled rhs>", "exec"), scope)  # noqa: S102 - compiler-built tree
    return scope["rhs_rolled"]


def _statements(rhs: py.FunctionDef, n: int):
    """The assignments and returned derivatives of `rhs`, with their levels; None if
    the function has a form this does not roll (more than one state unpacked by
    index, or anything but assignments and the unpacking)."""
    values: dict[str, int] = {}
    level: dict[str, int] = {}
    out: list[_Statement] = []
    for stmt in rhs.body:
        if isinstance(stmt, py.Assign) and isinstance(stmt.value, py.Name) and \
                stmt.value.id == "y" and isinstance(stmt.targets[0], py.Tuple):
            for i, t in enumerate(stmt.targets[0].elts):
                values[t.id] = i
                level[t.id] = 0
        elif isinstance(stmt, py.Assign) and isinstance(stmt.value, py.Name) and \
                stmt.value.id in ("m", "z"):
            continue  # modes and memory are read from M and Z
        elif isinstance(stmt, py.Assign) and isinstance(stmt.value, py.Subscript) and \
                isinstance(stmt.value.value, py.Name) and stmt.value.value.id in ("m", "z"):
            continue
        elif isinstance(stmt, py.Assign) and len(stmt.targets) == 1 and \
                isinstance(stmt.targets[0], py.Name):
            name = stmt.targets[0].id
            lv = 1 + max((level.get(x.id, 0) for x in py.walk(stmt.value)
                          if isinstance(x, py.Name) and x.id in values), default=0)
            values[name] = len(values)
            level[name] = lv
            out.append(_Statement(values[name], stmt.value, lv))
        elif isinstance(stmt, py.Return) and isinstance(stmt.value, py.List):
            for i, e in enumerate(stmt.value.elts):
                lv = 1 + max((level.get(x.id, 0) for x in py.walk(e)
                              if isinstance(x, py.Name) and x.id in values), default=0)
                out.append(_Statement(-1 - i, e, lv))
        else:
            return None, values
    if len(values) < n:
        return None, values
    return out, values


def for_compiled(c) -> Callable | None:
    """The rolled right-hand side of a run's generated functions (`codegen.ModelCode`),
    guarded (see the module docstring), built once; None for a model it does not pay
    for."""
    if "rolled" not in c.derived:
        # one code for every binding of the module
        fn = None if c.binder is None else \
            c.binder.from_rhs("rolled", lambda rhs, _: build(rhs, len(c.state_names)))
        if fn is not None:  # its own globals, with this run's parameters
            values = c.parameter_values
            fn = FunctionType(fn.__code__, {**fn.__globals__, **values})
        c.derived["rolled"] = None if fn is None else _guarded(fn, c.rhs)
    return c.derived["rolled"]


def _guarded(fn: Callable, rhs: Callable) -> Callable:
    def f(t, y, m, z):
        with np.errstate(all="ignore"):
            d = fn(t, y, m, z)
        if not np.isfinite(d).all():
            # the scalar code raises the fault at its statement, or agrees
            return rhs(t, y.tolist(), m, z)
        return d
    return f
