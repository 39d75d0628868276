"""A run's generated right-hand side and surfaces, rewritten for numba.

The scalar functions `codegen` builds (`ModelCode.module`, a tree the compiler made,
never listing text) become `model_rhs(t, y, m, z, p, out)` and
`model_surf(t, y, m, z, p, out)`: the states, branches and memory read by index,
each parameter read from `p` (so a new PARAM value is an argument, not a new
compilation), the results written into `out`. A helper numba has no spelling for
here (tables, DELAY, random draws, IMPL) makes the model not compilable:
`Unsupported` says which, and the run goes on by the Python route.
"""

from __future__ import annotations

import ast as py
import copy
import hashlib
from dataclasses import dataclass

from ..codegen import ModelCode

# The run-time helpers (`codegen.pytree.namespace`, as _NAME) the compiled route has.
# Faults are NaN or an infinity there (numba's NumPy error model), which the kernel's
# step control treats as it treats a NaN from Python. Most are what the Python route
# calls: `math`'s functions and the builtins as numba has them (its math.asin is NaN
# outside [-1, 1], where Python's raises), amilpy's own helpers compiled as written.
# RESPELLED are those whose Python form catches an exception numba cannot: numba's
# plain operation gives the NaN or infinity they return.
AS_WRITTEN = frozenset({"SQRT", "ALOG", "ALOG10", "AINT", "NINT", "DIM", "SIGN", "NOTNUL", "SGN",
                        "LEVEL", "LEDGE", "AMODAT"})
_BUILTINS = {abs: "abs", max: "max", min: "min", float: "float"}
RESPELLED: dict[str, str] = {
    "EXP": "math.exp", "SINH": "math.sinh", "COSH": "math.cosh",
    "AMOD": "np.fmod",  # (NaN for b = 0, as runtime.fortran_amod)
    "POW": "np.power",  # (NaN for a negative base to a fractional power)
}


def _helper(name: str, obj: object) -> tuple[str, str | None]:
    """The module text binding helper `name` (`_SQRT`) for numba, and the module it
    imports (None: none); raises Unsupported."""
    key = name[1:]
    if key in RESPELLED:
        return f"{name} = {RESPELLED[key]}", None
    if key in AS_WRITTEN:
        return f"{name} = _njit({obj.__module__}.{obj.__name__})", obj.__module__
    if getattr(obj, "__module__", None) == "math":
        return f"{name} = math.{obj.__name__}", None
    if obj in _BUILTINS:
        return f"{name} = {_BUILTINS[obj]}", None
    raise Unsupported(f"{key} has no compiled form")


_STATE_ARGS = ("y", "m", "z")  # what the generated functions unpack by position


# numba's time to compile one function grows faster than the function (the N-mass
# chain's first run in a new process, kernel cached: 5 s at 100 equations, 15 s at
# 400, 315 s at 3,000); past this a run would wait minutes before its first step
MAX_EQUATIONS = 400


def _equations(rhs: py.FunctionDef) -> int:
    """The right side's assignments and returned derivatives."""
    n = sum(isinstance(s, py.Assign) and not isinstance(s.targets[0], py.Tuple)
            for s in rhs.body)
    ret = rhs.body[-1] if rhs.body else None
    if isinstance(ret, py.Return) and isinstance(ret.value, (py.List, py.Tuple)):
        n += len(ret.value.elts)
    return n


class Unsupported(Exception):
    """The model uses something the compiled route has no spelling for."""


@dataclass(frozen=True)
class Translation:
    """One model's numba functions: the module text, its key, and the parameters in
    the order `p` holds them."""

    text: str
    key: str
    parameters: tuple[str, ...]


class _Rewrite(py.NodeTransformer):
    """Parameters to p[i], results to out[i]; records every other global read."""

    def __init__(self, parameters: dict[str, int], local: set[str]) -> None:
        self.parameters = parameters
        self.local = local
        self.globals: set[str] = set()

    def visit_Name(self, node: py.Name) -> py.AST:
        if isinstance(node.ctx, py.Load) and node.id not in self.local:
            if node.id in self.parameters:
                return py.copy_location(py.Subscript(
                    py.Name("p", py.Load()), py.Constant(self.parameters[node.id]), py.Load()),
                    node)
            self.globals.add(node.id)
        return node

    def visit_Return(self, node: py.Return) -> list[py.stmt]:
        if not isinstance(node.value, py.List):
            raise Unsupported("a function that does not return its list")
        out = [py.Assign([py.Subscript(py.Name("out", py.Load()), py.Constant(i), py.Store())],
                         self.visit(v)) for i, v in enumerate(node.value.elts)]
        return [*out, py.Return(None)]


class _Unbind(py.NodeTransformer):
    """An argument the compiler binds once inside an expression, `((w1 := X), ...,
    value)[-1]` (`Emitter.bind`), which numba cannot type, as `w1 = X` before the
    statement: `hoisted`, innermost first. Generated code is pure and numba's faults
    are NaN or an infinity, so a binding made where its branch is not taken changes
    nothing."""

    def __init__(self) -> None:
        self.hoisted: list[py.stmt] = []

    def visit_NamedExpr(self, node: py.NamedExpr) -> py.expr:
        self.generic_visit(node)
        self.hoisted.append(py.Assign([py.Name(node.target.id, py.Store())], node.value))
        return py.Name(node.target.id, py.Load())

    def visit_Subscript(self, node: py.Subscript) -> py.expr:
        bound = isinstance(node.value, py.Tuple) and \
            any(isinstance(e, py.NamedExpr) for e in node.value.elts)
        self.generic_visit(node)
        return node.value.elts[-1] if bound else node


def _unbound(body: list[py.stmt]) -> list[py.stmt]:
    """Statements with their expressions' bindings made statements before them (the
    bodies of `if` and `for` likewise; a `for` reads its range once)."""
    out: list[py.stmt] = []
    for stmt in body:
        unbind = _Unbind()
        for name, value in py.iter_fields(stmt):
            if name in ("body", "orelse"):
                setattr(stmt, name, _unbound(value))
            elif isinstance(value, py.expr):
                setattr(stmt, name, unbind.visit(value))
            elif isinstance(value, list):
                setattr(stmt, name, [unbind.visit(v) if isinstance(v, py.expr) else v
                                     for v in value])
        if unbind.hoisted and isinstance(stmt, py.While):
            raise Unsupported("a loop whose test binds a value")
        out.extend(unbind.hoisted)
        out.append(stmt)
    return out


def _locals(fn: py.FunctionDef) -> set[str]:
    names = {a.arg for a in fn.args.args}
    for node in py.walk(fn):
        if isinstance(node, py.Name) and isinstance(node.ctx, py.Store):
            names.add(node.id)
        elif isinstance(node, py.NamedExpr):
            names.add(node.target.id)
    return names


def _function(fn: py.FunctionDef, name: str, parameters: dict[str, int]
              ) -> tuple[py.FunctionDef, set[str]]:
    fn = copy.deepcopy(fn)
    body: list[py.stmt] = []
    for stmt in fn.body:
        # `v_A, v_B = y`: by index (numba does not unpack an array of unknown length)
        if isinstance(stmt, py.Assign) and isinstance(stmt.targets[0], py.Tuple) and \
                isinstance(stmt.value, py.Name) and stmt.value.id in _STATE_ARGS:
            for i, target in enumerate(stmt.targets[0].elts):
                body.append(py.Assign([target], py.Subscript(
                    py.Name(stmt.value.id, py.Load()), py.Constant(i), py.Load())))
        else:
            body.append(stmt)
    fn.body = _unbound(body)
    rewrite = _Rewrite(parameters, _locals(fn))
    fn = rewrite.visit(fn)
    fn.name = name
    fn.args.args = [py.arg(a) for a in ("t", "y", "m", "z", "p", "out")]
    fn.decorator_list = [py.Name("_model", py.Load())]
    return fn, rewrite.globals


def translate(c: ModelCode) -> Translation:
    """The numba module for `c`'s code (raises Unsupported)."""
    if c.module is None:
        raise Unsupported("no scalar functions were generated")
    found = {f.name: f for f in c.module.body if isinstance(f, py.FunctionDef)}
    if "rhs" not in found or "surf" not in found:
        raise Unsupported("no right-hand side was generated")
    equations = _equations(found["rhs"])
    if equations > MAX_EQUATIONS:
        raise Unsupported(f"its right side has {equations} equations, more than the "
                          f"{MAX_EQUATIONS} numba compiles in 15 s (3,000 take it 5 min)")
    names = tuple(sorted(k for k, v in c.namespace.items()
                         if k.startswith("p_") and isinstance(v, float)))
    parameters = {n: i for i, n in enumerate(names)}
    functions, used = [], set()
    for source, target in (("rhs", "model_rhs"), ("surf", "model_surf")):
        fn, reads = _function(found[source], target, parameters)
        functions.append(fn)
        used |= reads
    helpers, imports = [], {"math", "numpy as np"}
    for name in sorted(used):
        if not name.startswith("_") or name not in c.namespace:
            raise Unsupported(f"{name} has no compiled form")
        line, module = _helper(name, c.namespace[name])
        helpers.append(line)
        imports |= {module} if module else set()
    model = py.Module(body=functions, type_ignores=[])
    py.fix_missing_locations(model)
    text = "\n\n".join([
        '"""One model\'s functions for amilpy\'s compiled route (amilpy.compiled.translate)."""',
        "\n".join(f"import {m}" for m in sorted(imports)) +
        "\n\nfrom numba import cfunc, njit\n\nfrom amilpy.compiled.kernel import MODEL",
        # (the order p holds them in: part of the text, so of the module's key)
        f"PARAMETERS = {names!r}",
        "_njit = njit(cache=True, error_model='numpy')\n"
        "_model = njit(MODEL, cache=True, error_model='numpy')",
        *helpers, py.unparse(model),
        "# as C functions, for the kernel: a pointer passes to it at no cost per call\n"
        "@cfunc(MODEL, cache=True)\ndef model_rhs_c(t, y, m, z, p, out):\n"
        "    model_rhs(t, y, m, z, p, out)",
        "@cfunc(MODEL, cache=True)\ndef model_surf_c(t, y, m, z, p, out):\n"
        "    model_surf(t, y, m, z, p, out)", ""])
    key = hashlib.sha256(text.encode()).hexdigest()[:20]
    return Translation(text, key, names)
