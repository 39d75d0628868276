"""A run's generated right-hand side and surfaces, rewritten for numba.

The scalar functions `codegen` builds (`Compiled.module`, a tree the compiler made,
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

from ..codegen import Compiled

# The run-time helpers (`codegen.pytree.namespace`, as _NAME) with a numba spelling:
# the same meaning as `runtime`, faults as NaN or an infinity (numba's NumPy error
# model), which the kernel's step control treats as it treats a NaN from Python.
NUMBA_HELPERS: dict[str, str] = {
    "ABS": "_ABS = abs",
    "SQRT": "@_njit\ndef _SQRT(x):\n    return math.sqrt(x) if x >= 0.0 else math.nan",
    "EXP": "_EXP = math.exp",
    "ALOG": "@_njit\ndef _ALOG(x):\n    if x > 0.0:\n        return math.log(x)\n"
            "    return -math.inf if x == 0.0 else math.nan",
    "ALOG10": "@_njit\ndef _ALOG10(x):\n    if x > 0.0:\n        return math.log10(x)\n"
              "    return -math.inf if x == 0.0 else math.nan",
    "SIN": "_SIN = math.sin", "COS": "_COS = math.cos", "TAN": "_TAN = math.tan",
    "ASIN": "@_njit\ndef _ASIN(x):\n    return math.asin(x) if -1.0 <= x <= 1.0 else math.nan",
    "ACOS": "@_njit\ndef _ACOS(x):\n    return math.acos(x) if -1.0 <= x <= 1.0 else math.nan",
    "ATAN": "_ATAN = math.atan", "TANH": "_TANH = math.tanh", "ATAN2": "_ATAN2 = math.atan2",
    "SINH": "_SINH = math.sinh", "COSH": "_COSH = math.cosh",
    "AINT": "@_njit\ndef _AINT(x):\n    return float(math.trunc(x))",
    "FLOAT": "_FLOAT = float",
    "AMOD": "@_njit\ndef _AMOD(a, b):\n    return math.fmod(a, b) if b != 0.0 else math.nan",
    "SIGN": "@_njit\ndef _SIGN(a, b):\n    return abs(a) if b >= 0.0 else -abs(a)",
    "AMAX1": "_AMAX1 = max", "AMIN1": "_AMIN1 = min",
    "NOTNUL": "@_njit\ndef _NOTNUL(x):\n    return 1.0 if x == 0.0 else x",
    "POW": "@_njit\ndef _POW(a, b):\n    return a ** b",
    "SGN": "@_njit\ndef _SGN(x):\n    return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)",
    "LEVEL": "@_njit\ndef _LEVEL(v):\n    return float(math.ceil(v - 0.5))",
}

_STATE_ARGS = ("y", "m", "z")  # what the generated functions unpack by position


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
    fn.body = body
    rewrite = _Rewrite(parameters, _locals(fn))
    fn = rewrite.visit(fn)
    fn.name = name
    fn.args.args = [py.arg(a) for a in ("t", "y", "m", "z", "p", "out")]
    fn.decorator_list = [py.Name("_model", py.Load())]
    return fn, rewrite.globals


def translate(c: Compiled) -> Translation:
    """The numba module for `c`'s code (raises Unsupported)."""
    if c.module is None:
        raise Unsupported("no scalar functions were generated")
    found = {f.name: f for f in c.module.body if isinstance(f, py.FunctionDef)}
    if "rhs" not in found or "surf" not in found:
        raise Unsupported("no right-hand side was generated")
    names = tuple(sorted(k for k, v in c.namespace.items()
                         if k.startswith("p_") and isinstance(v, float)))
    parameters = {n: i for i, n in enumerate(names)}
    functions, used = [], set()
    for source, target in (("rhs", "model_rhs"), ("surf", "model_surf")):
        fn, reads = _function(found[source], target, parameters)
        functions.append(fn)
        used |= reads
    helpers = []
    for name in sorted(used):
        spelling = NUMBA_HELPERS.get(name[1:]) if name.startswith("_") else None
        if spelling is None:
            what = name[1:] if name.startswith("_") else name
            raise Unsupported(f"{what} has no compiled form")
        helpers.append(spelling)
    model = py.Module(body=functions, type_ignores=[])
    py.fix_missing_locations(model)
    text = "\n\n".join([
        '"""One model\'s functions for amilpy\'s compiled route (amilpy.compiled.translate)."""',
        "import math\n\nfrom numba import cfunc, njit\n\nfrom amilpy.compiled.kernel import MODEL",
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
