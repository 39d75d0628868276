"""Helpers on the generated Python syntax tree: numbers, constant folding, placing
statements on their lines, function definitions, the elementwise copy and the
closedness check. Nothing here knows the model."""

from __future__ import annotations

import ast as py
import copy
import math
from collections.abc import Callable

from ..library import math_functions
from ..runtime import HELPERS, safe_pow

# the arguments of every generated function; with the v_/h_ locals of model
# names, the mN/nN/zN/wN locals and the _NAME callables, all generated code reads
ARGS = ("t", "y", "m", "mn", "z", "ev")


def namespace() -> dict[str, object]:
    """Every callable generated code can reach: the language's math functions and
    the run-time helpers, each as _NAME (read from the library at each build, so an
    entry registered later is there too)."""
    out: dict[str, object] = {f"_{k}": v for k, v in math_functions().items()}
    out.update({f"_{k}": v for k, v in HELPERS.items()})
    return out


def local(name: str) -> str:
    """Python identifier for a model variable (hidden ones have '#')."""
    if "#" in name:
        # hidden names hold '#', '.' and "'": spell every non-alphanumeric
        # character as _XX so that no two names meet
        return "h_" + "".join(c if c.isalnum() else f"_{ord(c):02X}" for c in name)
    return "v_" + name


def user_function(name: str) -> str:
    """The Python name of a FUNCTION the listing defines (ACSL form)."""
    return "_U_" + name


def parameter(name: str) -> str:
    """The global a run's parameter is read from in generated code."""
    return "p_" + name


def number(v: float) -> py.expr:
    """A float constant (NaN and infinities through _FLOAT, -0.0 kept)."""
    if v != v:
        return py.Call(py.Name("_FLOAT", py.Load()), [py.Constant("nan")], [])
    if math.isinf(v):
        return py.Call(py.Name("_FLOAT", py.Load()), [py.Constant("inf" if v > 0 else "-inf")],
                       [])
    if v < 0 or (v == 0 and math.copysign(1.0, v) < 0):
        return py.UnaryOp(py.USub(), py.Constant(-float(v)))
    return py.Constant(float(v))


def const_value(node: py.expr) -> float | None:
    """The value of a float constant node (as `number` writes it), else None."""
    if isinstance(node, py.Constant) and isinstance(node.value, float):
        return node.value
    if (isinstance(node, py.UnaryOp) and isinstance(node.op, py.USub)
            and isinstance(node.operand, py.Constant) and isinstance(node.operand.value, float)):
        return -node.operand.value
    return None


class Folder(py.NodeTransformer):
    """Constant folding on the generated tree (keeps float semantics)."""

    def visit(self, node):
        new = super().visit(node)
        # a folded statement root keeps its line (see `on_line`)
        if new is not node and hasattr(node, "amil_line") and new is not None:
            new.amil_line = node.amil_line
        return new

    def visit_BinOp(self, node):
        self.generic_visit(node)
        a, b = const_value(node.left), const_value(node.right)
        if isinstance(node.op, py.Pow) and a is not None and isinstance(node.right, py.Constant):
            v = safe_pow(a, float(node.right.value))
            return py.copy_location(number(v), node) if math.isfinite(v) else node
        if a is not None and b is not None and not isinstance(node.op, py.Pow):
            try:
                if isinstance(node.op, py.Add):
                    v = a + b
                elif isinstance(node.op, py.Sub):
                    v = a - b
                elif isinstance(node.op, py.Mult):
                    v = a * b
                elif isinstance(node.op, py.Div):
                    v = a / b
                else:
                    return node
            except (ArithmeticError, ValueError):
                return node  # left to the run, which reports it where it happens
            return py.copy_location(number(v), node)
        return node

    def visit_UnaryOp(self, node):
        self.generic_visit(node)
        if isinstance(node.op, py.USub):
            inner = node.operand
            if isinstance(inner, py.UnaryOp) and isinstance(inner.op, py.USub):
                return inner.operand
        return node

    def visit_IfExp(self, node):
        self.generic_visit(node)
        test = truth(node.test)
        if test is None:
            return node
        return node.body if test else node.orelse


def truth(node) -> bool | None:
    """The truth of a constant condition, else None."""
    if isinstance(node, py.Constant) and isinstance(node.value, bool):
        return node.value
    if isinstance(node, py.Compare) and len(node.ops) == 1:
        a, b = const_value(node.left), const_value(node.comparators[0])
        if a is None or b is None:
            return None
        op = node.ops[0]
        return {py.Lt: a < b, py.Gt: a > b, py.LtE: a <= b, py.GtE: a >= b, py.Eq: a == b,
                py.NotEq: a != b}[type(op)]
    if isinstance(node, py.BoolOp):
        vals = [truth(v) for v in node.values]
        if isinstance(node.op, py.And):
            if any(v is False for v in vals):
                return False
            return True if all(v is True for v in vals) else None
        if any(v is True for v in vals):
            return True
        return False if all(v is False for v in vals) else None
    return None


def on_line(node: py.AST, line: int) -> py.AST:
    """Mark a statement (or one element of a returned list) as line `line` of the
    generated code: `place` gives it and everything under it that line."""
    node.amil_line = line
    return node


def place(module: py.Module) -> None:
    """Give every node the line of the statement it belongs to (`on_line`; line 1
    for the scaffolding), so the code object's own line table says which statement
    an instruction belongs to."""
    for fn in module.body:
        fn.lineno = fn.end_lineno = 1
        fn.col_offset = fn.end_col_offset = 0
        stack: list[tuple[py.AST, int]] = [(child, 1) for child in py.iter_child_nodes(fn)]
        while stack:
            node, line = stack.pop()
            line = getattr(node, "amil_line", line)
            if isinstance(node, (py.expr, py.stmt, py.excepthandler, py.arg)):
                node.lineno = node.end_lineno = line
                node.col_offset = node.end_col_offset = 0
            stack.extend((child, line) for child in py.iter_child_nodes(node))


def function(name: str, args: tuple[str, ...], body: list[py.stmt]) -> py.FunctionDef:
    return py.FunctionDef(
        name=name,
        args=py.arguments(posonlyargs=[], args=[py.arg(a) for a in args], vararg=None,
                          kwonlyargs=[], kw_defaults=[], kwarg=None, defaults=[]),
        body=body or [py.Pass()],
        decorator_list=[],
        returns=None,
        type_params=[],
    )


def vectorised(fn: py.FunctionDef, name: str) -> py.FunctionDef:
    """A copy of a generated function whose conditionals work elementwise."""

    class Where(py.NodeTransformer):
        def visit_IfExp(self, node):
            self.generic_visit(node)
            return py.Call(py.Name("_WHERE", py.Load()), [node.test, node.body, node.orelse], [])

        def visit_BoolOp(self, node):
            self.generic_visit(node)
            fn = "_ALL" if isinstance(node.op, py.And) else "_ANY"
            return py.Call(py.Name(fn, py.Load()), node.values, [])

    # the IR nodes the tree remembers (emit's `amil_src`) are shared, not copied
    memo = {id(n.amil_src): n.amil_src for n in py.walk(fn) if hasattr(n, "amil_src")}
    new = Where().visit(copy.deepcopy(fn, memo))
    new.name = name
    return new


def assert_closed(module: py.Module, also: Callable[[str], bool] | None = None) -> None:
    """Generated code reads only the compiler's names: no attributes, no builtins.
    `also`: names a later stage adds (the Jacobian's derivative locals)."""
    allowed = set(namespace()) | set(ARGS)
    for node in py.walk(module):
        if isinstance(node, (py.Attribute, py.Import, py.ImportFrom, py.Global, py.Lambda)):
            raise AssertionError(f"generated code contains {type(node).__name__}")
        if isinstance(node, py.Name) and isinstance(node.ctx, py.Load):
            ok = (node.id in allowed or node.id.startswith(("v_", "h_", "_T_", "_U_", "p_"))
                  or (node.id[0] in "mnzw" and node.id[1:].isdigit())
                  or (also is not None and also(node.id)))
            if not ok:
                raise AssertionError(f"generated code reads unknown name {node.id}")
