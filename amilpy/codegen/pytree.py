"""Helpers on the generated Python syntax tree: numbers, constant folding, placing
statements on their lines, function definitions, the elementwise copy and the
closedness check. Nothing here knows the model."""

from __future__ import annotations

import ast as py
import copy
import math
from collections.abc import Callable
from functools import lru_cache

from ..library import generation, math_functions, vector_functions
from ..library.runtime import HELPERS, safe_pow
from ..parse.syntax import deep_enough

# the arguments of every generated function; with the v_/h_ locals of model
# names, the mN/nN/zN/wN locals and the _NAME callables, all generated code reads
ARGS = ("t", "y", "m", "mn", "z", "ev")


@lru_cache(maxsize=1)
def _built(_registry: tuple[int, int]) -> tuple[dict[str, object], frozenset[str]]:
    """(the namespace, the names generated code may read) of one state of the
    registries (`_current` says which)."""
    out: dict[str, object] = {f"_{k}": v for k, v in math_functions().items()}
    out.update({f"_{k}": v for k, v in HELPERS.items()})
    return out, frozenset(out) | frozenset(ARGS)


def _current() -> tuple[dict[str, object], frozenset[str]]:
    return _built((generation(), len(HELPERS)))


def namespace() -> dict[str, object]:
    """Every callable generated code can reach: the language's math functions and
    the run-time helpers, each as _NAME (as the library stands now: an entry
    registered later is there too). A fresh dictionary, for the caller to fill."""
    return dict(_current()[0])


def vector_namespace() -> dict[str, object]:
    """`namespace`'s functions elementwise on NumPy arrays, each as _NAME: a fresh
    dictionary, for the caller to fill."""
    return {f"_{k}": v for k, v in vector_functions().items()}


def local(name: str) -> str:
    """Python identifier for a model variable (hidden ones have '#')."""
    if "#" in name:
        # hidden names hold '#', '.' and "'": spell every non-alphanumeric
        # character as _XX so that no two names meet
        return "h_" + _spelled(name)
    if not name.replace("_", "").isalnum():  # an array's element, X(1,2)
        return "a_" + _spelled(name)
    return "v_" + name


def _spelled(name: str) -> str:
    return "".join(c if c.isalnum() else f"_{ord(c):02X}" for c in name)


def user_function(name: str) -> str:
    """The Python name of a FUNCTION the listing defines (ACSL form)."""
    return "_U_" + name


def parameter(name: str) -> str:
    """The global a run's parameter is read from in generated code."""
    return "p_" + (name if name.replace("_", "").isalnum() else "a_" + _spelled(name))


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


def fold(node: py.AST) -> py.AST:
    """Constant folding on the generated tree (keeps float semantics), bottom-up, in
    place; the node itself or what replaces it (ast.NodeTransformer's generic walk
    took longer than the rest of a large model's build)."""
    for name in node._fields:
        value = getattr(node, name, None)
        if value.__class__ is list:
            for i, x in enumerate(value):
                if isinstance(x, py.AST):
                    new = fold(x)
                    if new is not x:
                        value[i] = new
        elif isinstance(value, py.AST):
            new = fold(value)
            if new is not value:
                setattr(node, name, new)
    kind = node.__class__
    if kind is py.BinOp:
        new = _fold_binop(node)
    elif kind is py.UnaryOp:
        inner = node.operand
        new = inner.operand if (isinstance(node.op, py.USub) and isinstance(inner, py.UnaryOp)
                                and isinstance(inner.op, py.USub)) else node
    elif kind is py.IfExp:
        test = truth(node.test)
        new = node if test is None else node.body if test else node.orelse
    else:
        return node
    # a folded statement root keeps its line (see `on_line`)
    if new is not node and hasattr(node, "amil_line"):
        new.amil_line = node.amil_line
    return new


def _fold_binop(node: py.BinOp) -> py.expr:
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


def children(node: py.AST) -> list[py.AST]:
    """The nodes right under `node` (as ast.iter_child_nodes, at twice its speed: a
    large model's module has hundreds of thousands of nodes)."""
    out: list[py.AST] = []
    for name in node._fields:
        value = getattr(node, name, None)
        if value.__class__ is list:
            out.extend(x for x in value if isinstance(x, py.AST))
        elif isinstance(value, py.AST):
            out.append(value)
    return out


def nodes(root: py.AST) -> list[py.AST]:
    """Every node under `root`, root included (as ast.walk, faster)."""
    out, stack = [root], [root]
    while stack:
        below = children(stack.pop())
        out.extend(below)
        stack.extend(below)
    return out


_LOCATED: dict[type, bool] = {}  # node type -> whether it has a source location


def place(module: py.Module, closed: bool = False,
          also: Callable[[str], bool] | None = None, lines: bool = True) -> None:
    """Give every node the line of the statement it belongs to (`on_line`; line 1
    for the scaffolding; `lines` False: line 1 for all), so the code object's own
    line table says which statement an instruction belongs to; every node gets a
    location (no `ast.fix_missing_locations` needed after). `closed`: check on the
    way what `assert_closed` checks, `also` as there (one walk of a large module
    instead of two).

    Only the start (lineno, col_offset) is set, and an end a node has (a template's,
    parsed) taken away: compile() takes a node's missing end for its start, which is
    what this would set (the code is the same byte for byte), and the two more
    attributes took a quarter of a large tree's memory. A change to a placed tree is
    located with `locate`, not ast.fix_missing_locations (which would give each node
    the end of the node above it)."""
    located = _LOCATED
    allowed = _current()[1]
    for fn in module.body:
        fn.lineno = 1
        fn.col_offset = 0
        if closed:
            _assert_node(fn, allowed, also)
        stack: list[tuple[py.AST, int]] = [(child, 1) for child in children(fn)]
        while stack:
            node, line = stack.pop()
            if lines:
                line = getattr(node, "amil_line", line)
            kind = node.__class__
            has = located.get(kind)
            if has is None:
                has = located[kind] = "lineno" in kind._attributes
            if has:
                node.lineno = line
                node.col_offset = 0
                if "end_lineno" in node.__dict__:  # (a library template's node, parsed)
                    del node.end_lineno, node.end_col_offset
            if closed:
                _assert_node(node, allowed, also)
            stack.extend((child, line) for child in children(node))


def locate(tree: py.AST) -> py.AST:
    """A placed tree (`place`) with nodes added: each new node the start of the
    node above it, as ast.fix_missing_locations gives, and no end (see `place`)."""
    stack: list[tuple[py.AST, int, int]] = [(tree, 1, 0)]
    while stack:
        node, line, col = stack.pop()
        if "lineno" in node._attributes:
            if getattr(node, "lineno", None) is None:
                node.lineno = line
            else:
                line = node.lineno
            if getattr(node, "col_offset", None) is None:
                node.col_offset = col
            else:
                col = node.col_offset
        stack.extend((child, line, col) for child in children(node))
    return tree


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


@deep_enough()
def vectorised(fn: py.FunctionDef, name: str) -> py.FunctionDef:
    """A copy of a generated function whose conditionals work elementwise. Only the
    nodes above a conditional are copied; the rest (most of a large model) is
    shared with `fn`, as are the IR nodes the tree remembers (emit's `amil_src`)."""
    new = column_copy(fn, name)
    if new is None:  # (nothing elementwise in it: a copy under another name)
        new = copy.copy(fn)
        new.name = name
    return new


@deep_enough()
def column_copy(fn: py.FunctionDef, name: str) -> py.FunctionDef | None:
    """`vectorised`'s copy where it differs from `fn`, else None: with nothing to make
    elementwise, fn itself works on NumPy columns among NumPy's functions (the
    vector namespace), and a second copy of a large model's code would cost its
    compile time and memory again."""
    new = _elementwise(fn)
    if new is fn:
        return None
    new.name = name
    return new


def _elementwise(node: py.AST) -> py.AST:
    """`node` with IfExp as _WHERE(...) and and/or as _ALL/_ANY(...) calls; the
    same node when nothing under it changes."""
    changed: dict[str, object] = {}
    for field in node._fields:
        value = getattr(node, field, None)
        if value.__class__ is list:
            new = [_elementwise(v) if isinstance(v, py.AST) else v for v in value]
            if any(a is not b for a, b in zip(new, value, strict=True)):
                changed[field] = new
        elif isinstance(value, py.AST):
            new = _elementwise(value)
            if new is not value:
                changed[field] = new
    if isinstance(node, py.IfExp):
        parts = [changed.get(f, getattr(node, f)) for f in ("test", "body", "orelse")]
        out = py.Call(py.Name("_WHERE", py.Load()), parts, [])
    elif isinstance(node, py.BoolOp):
        fn = "_ALL" if isinstance(node.op, py.And) else "_ANY"
        out = py.Call(py.Name(fn, py.Load()), changed.get("values", node.values), [])
    elif not changed:
        return node
    else:
        out = copy.copy(node)
        for field, value in changed.items():
            setattr(out, field, value)
        return out
    if hasattr(node, "amil_line"):
        out.amil_line = node.amil_line
    return out


_FORBIDDEN = (py.Attribute, py.Import, py.ImportFrom, py.Global, py.Lambda)


def _compiler_name(name: str, allowed: frozenset, also: Callable[[str], bool] | None) -> bool:
    return (name in allowed or name.startswith(("v_", "h_", "a_", "_T_", "_U_", "p_"))
            or (name[0] in "mnzw" and name[1:].isdigit())
            or (also is not None and also(name)))


def _assert_node(node: py.AST, allowed: frozenset, also=None) -> None:
    if isinstance(node, _FORBIDDEN):
        raise AssertionError(f"generated code contains {type(node).__name__}")
    if node.__class__ is py.Name and isinstance(node.ctx, py.Load) and \
            not _compiler_name(node.id, allowed, also):
        raise AssertionError(f"generated code reads unknown name {node.id}")


def assert_closed(module: py.Module, also: Callable[[str], bool] | None = None) -> None:
    """Generated code reads only the compiler's names: no attributes, no builtins.
    `also`: names a later stage adds (the Jacobian's derivative locals)."""
    allowed = _current()[1]
    for node in nodes(module):
        _assert_node(node, allowed, also)
