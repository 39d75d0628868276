"""The Jacobian of the frozen-branch vector field, by differentiating the generated
`rhs` (issue 14.3).

The generated `rhs` is straight-line code on floats: the states unpacked, one
assignment per algebraic equation, the derivatives returned. Forward
differentiation of that tree gives, for every assignment v and every state j that
v depends on (the dependency graph: the sparsity), a local `d<j>_v` holding
dv/dy_j, right after v's own assignment; the Jacobian's entries are the
derivatives of the returned expressions. Switches are differentiated in the
branch their frozen modes select (the same `if` on the modes, each branch
differentiated), which is the Jacobian of the field the stepper integrates.

Rules are written out for the arithmetic and the elementary functions; any other
call (a table, DELAY, a function added to the library later) is differentiated
numerically in its own arguments only (`_DIFF`, a central difference scaled to
the argument: about 1e-10 relative), so every model has a Jacobian.

Entries that come out as constants (a linear spring, 1 in X' = V) are computed
once; the generated `jac(t, y, m, z)` returns the others, in the order of
`ModelJacobian.rows, cols`. Its size is linear in the model's: one expression
per nonzero entry of each assignment. A listing is still data: the generated
code reads only the compiler's names (`pytree.assert_closed`).
"""

from __future__ import annotations

import ast as py
import math
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..library.templates import clone
from .pytree import const_value, fold, function, locate, namespace, nodes, place

_ONE = py.Constant(1.0)
_PICKS = {"_AMAX1": py.GtE, "_AMIN1": py.LtE}  # the first argument is taken where this holds


def _diff(f: Callable, k: int, *args: float) -> float:
    """d f / d args[k] by a central difference scaled to the argument."""
    x = args[k]
    h = 6.055454e-6 * max(abs(x), 1.0)  # eps ** (1/3)
    lo, hi = list(args), list(args)
    lo[k], hi[k] = x - h, x + h
    return (f(*hi) - f(*lo)) / (2.0 * h)


def _sgn0(x: float) -> float:
    return 1.0 if x > 0 else -1.0 if x < 0 else 0.0


# d/da of f(a) for one-argument functions, in terms of the argument a (a Python
# expression tree) and the function's value; None: not written out here
def _rule(name: str, a: py.expr) -> py.expr | None:
    def call(fn: str, *args: py.expr) -> py.expr:
        return py.Call(py.Name(fn, py.Load()), list(args), [])

    def c(x: float) -> py.expr:
        return py.Constant(x)

    def mul(x, y):
        return py.BinOp(x, py.Mult(), y)

    def div(x, y):
        return py.BinOp(x, py.Div(), y)

    def sub(x, y):
        return py.BinOp(x, py.Sub(), y)

    a2 = mul(a, clone(a))
    rules = {
        "_SIN": lambda: call("_COS", a),
        "_COS": lambda: py.UnaryOp(py.USub(), call("_SIN", a)),
        "_EXP": lambda: call("_EXP", a),
        "_SINH": lambda: call("_COSH", a),
        "_COSH": lambda: call("_SINH", a),
        "_TANH": lambda: sub(c(1.0), mul(call("_TANH", a), call("_TANH", clone(a)))),
        "_TAN": lambda: py.BinOp(c(1.0), py.Add(), mul(call("_TAN", a),
                                                        call("_TAN", clone(a)))),
        "_ALOG": lambda: div(c(1.0), a),
        "_ALOG10": lambda: div(c(1.0 / math.log(10.0)), a),
        "_SQRT": lambda: div(c(0.5), call("_SQRT", a)),
        "_ABS": lambda: call("_SGN0", a),
        "_ATAN": lambda: div(c(1.0), py.BinOp(c(1.0), py.Add(), a2)),
        "_ASIN": lambda: div(c(1.0), call("_SQRT", sub(c(1.0), a2))),
        "_ACOS": lambda: div(c(-1.0), call("_SQRT", sub(c(1.0), a2))),
        "_SGN": lambda: c(0.0),
        "_LEVEL": lambda: c(0.0),
        "_AINT": lambda: c(0.0),
        "_NINT": lambda: c(0.0),
        "_FLOAT": lambda: c(1.0),
    }
    make = rules.get(name)
    return make() if make else None


class _Deriv:
    """Forward differentiation of the rhs tree: `deps` (which states an expression
    reads, through the locals) and `d(expr, j)` (its derivative in state j, None
    for zero)."""

    def __init__(self, states: dict[str, int]) -> None:
        self.states = states  # local name of a state -> its index
        self.local_deps: dict[str, frozenset[int]] = {}  # assigned local -> states
        self.bound: dict[str, frozenset[int]] = {}  # walrus names -> states
        self.known: dict[str, float] = {}  # derivative locals that are constants

    # dependencies --------------------------------------------------------------
    def deps(self, e: py.AST) -> frozenset[int]:
        out: set[int] = set()
        for node in py.walk(e):
            if isinstance(node, py.Name) and isinstance(node.ctx, py.Load):
                if node.id in self.states:
                    out.add(self.states[node.id])
                out |= self.local_deps.get(node.id, frozenset())
                out |= self.bound.get(node.id, frozenset())
            elif isinstance(node, py.NamedExpr):
                self.bound[node.target.id] = self.deps(node.value)
        # a test reads states too, but a branch is frozen: only the branches count
        return frozenset(out)

    # derivatives ----------------------------------------------------------------
    def d(self, e: py.expr, j: int) -> py.expr | None:
        method = getattr(self, "d_" + type(e).__name__, None)
        if method is None:
            raise NotImplementedError(type(e).__name__)
        return method(e, j)

    def d_Constant(self, e, j):
        return None

    def d_Name(self, e: py.Name, j: int):
        if self.states.get(e.id) == j:
            return _ONE
        name = f"d{j}_{e.id}"
        if name in self.known:
            return py.Constant(self.known[name]) if self.known[name] else None
        if j in self.local_deps.get(e.id, ()) or j in self.bound.get(e.id, ()):
            return py.Name(name, py.Load())
        return None

    def d_Subscript(self, e: py.Subscript, j: int):
        if isinstance(e.value, py.Tuple):  # ((w1 := a), ..., value)[-1]
            parts = [self.d(x, j) for x in e.value.elts]
            if parts[-1] is None and all(p is None for p in parts):
                return None
            parts = [p if p is not None else py.Constant(0.0) for p in parts]
            return py.Subscript(py.Tuple(parts, py.Load()), clone(e.slice), py.Load())
        return None  # z[k]: memory, constant along a step

    def d_NamedExpr(self, e: py.NamedExpr, j: int):
        inner = self.d(e.value, j)
        return py.NamedExpr(py.Name(f"d{j}_{e.target.id}", py.Store()),
                            inner if inner is not None else py.Constant(0.0))

    def d_UnaryOp(self, e: py.UnaryOp, j: int):
        inner = self.d(e.operand, j)
        if inner is None or isinstance(e.op, py.UAdd):
            return inner
        if isinstance(e.op, py.USub):
            return py.UnaryOp(py.USub(), inner)
        return None  # `not`: a condition

    def d_BinOp(self, e: py.BinOp, j: int):
        a, b = e.left, e.right
        da, db = self.d(a, j), self.d(b, j)
        if da is None and db is None:
            return None
        op = e.op

        def cp(x):
            return clone(x)

        def mul(x, y):
            if const_value(x) == 1.0:
                return y
            return x if const_value(y) == 1.0 else py.BinOp(x, py.Mult(), y)

        if isinstance(op, (py.Add, py.Sub)):
            if db is None:
                return da
            if da is None:
                return db if isinstance(op, py.Add) else py.UnaryOp(py.USub(), db)
            return py.BinOp(da, type(op)(), db)
        if isinstance(op, py.Mult):
            left = mul(da, cp(b)) if da is not None else None
            right = mul(cp(a), db) if db is not None else None
            return right if left is None else left if right is None else \
                py.BinOp(left, py.Add(), right)
        if isinstance(op, py.Div):
            first = py.BinOp(da, py.Div(), cp(b)) if da is not None else None
            if db is None:
                return first
            second = py.BinOp(mul(cp(a), db), py.Div(), mul(cp(b), cp(b)))
            return py.UnaryOp(py.USub(), second) if first is None else \
                py.BinOp(first, py.Sub(), second)
        if isinstance(op, py.Pow):
            k = e.right.value if isinstance(e.right, py.Constant) else const_value(e.right)
            if k is not None and db is None:
                return mul(mul(py.Constant(float(k)), py.BinOp(cp(a), py.Pow(),
                                                              py.Constant(k - 1))), da)
            return self._numeric(py.Call(py.Name("_POW", py.Load()), [a, b], []), j)
        raise NotImplementedError(type(op).__name__)

    def d_IfExp(self, e: py.IfExp, j: int):
        body, orelse = self.d(e.body, j), self.d(e.orelse, j)
        if body is None and orelse is None:
            return None
        zero = py.Constant(0.0)
        return py.IfExp(clone(e.test), body or zero, orelse or zero)

    def d_Call(self, e: py.Call, j: int):
        name = e.func.id if isinstance(e.func, py.Name) else ""
        if name in _PICKS and len(e.args) == 2:
            # the larger (smaller) of two: the derivative of the one it is, the first at
            # a tie (a play's clamp, where a difference across the kink gave half)
            a, b = e.args
            da, db = self.d(a, j), self.d(b, j)
            if da is None and db is None:
                return None
            zero = py.Constant(0.0)
            return py.IfExp(py.Compare(clone(a), [_PICKS[name]()], [clone(b)]),
                            da or zero, db or zero)
        if len(e.args) == 1:
            da = self.d(e.args[0], j)
            if da is None:
                return None
            rule = _rule(name, clone(e.args[0]))
            if rule is not None:
                return py.BinOp(rule, py.Mult(), da)
        return self._numeric(e, j)

    def _numeric(self, e: py.Call, j: int):
        """sum over the arguments k that depend on y_j: _DIFF(f, k, args) * d arg_k."""
        total = None
        for k, arg in enumerate(e.args):
            da = self.d(arg, j)
            if da is None:
                continue
            term = py.BinOp(py.Call(py.Name("_DIFF", py.Load()),
                                    [clone(e.func), py.Constant(k),
                                     *[clone(a) for a in e.args]], []), py.Mult(), da)
            total = term if total is None else py.BinOp(total, py.Add(), term)
        return total


@dataclass
class ModelJacobian:
    """d rhs / d y of one run's generated functions, with its sparsity.

    `rows`, `cols`: the structurally nonzero entries (the dependency graph);
    `constant`: the values of those that are constants (NaN where the generated
    `variable(t, y, m, z)` gives them, in order)."""

    n: int
    rows: np.ndarray
    cols: np.ndarray
    constant: np.ndarray
    variable: Callable
    # () -> the tree of `variable`, built again when its text is asked for (`source`):
    # a large model's is as large as its rhs's, and only its code is used
    written: Callable[[], py.Module] | None = None

    @property
    def source(self) -> str:
        """The generated Jacobian as Python text (written when asked for: a large
        model's takes as long to write as to build)."""
        return py.unparse(self.written())

    @property
    def nnz(self) -> int:
        return len(self.rows)

    def values(self, t: float, y, m, z) -> np.ndarray:
        v = self.constant.copy()
        if self._varying.size:
            v[self._varying] = self.variable(t, y, m, z)
        return v

    def __post_init__(self) -> None:
        self._varying = np.flatnonzero(np.isnan(self.constant))

    def dense(self, t: float, y, m, z) -> np.ndarray:
        out = np.zeros((self.n, self.n))
        out[self.rows, self.cols] = self.values(t, y, m, z)
        return out

    def bandwidth(self) -> tuple[int, int]:
        """(lower, upper) diagonals the entries reach."""
        if not self.nnz:
            return 0, 0
        d = self.rows - self.cols
        return int(max(d.max(), 0)), int(max(-d.min(), 0))

    def banded(self, t: float, y, m, z, ml: int, mu: int) -> np.ndarray:
        """In ODEPACK's banded layout: out[mu + i - j, j] = d f_i / d y_j."""
        out = np.zeros((ml + mu + 1, self.n))
        out[mu + self.rows - self.cols, self.cols] = self.values(t, y, m, z)
        return out

    def sparse(self, t: float, y, m, z):
        from scipy.sparse import csc_matrix

        return csc_matrix((self.values(t, y, m, z), (self.rows, self.cols)),
                          shape=(self.n, self.n))


def build(module: py.Module, n: int, tables: dict | None = None,
          values: dict | None = None) -> ModelJacobian:
    """The Jacobian of the `rhs` function in a generated module (`ModelCode.module`);
    `values`: the parameters' globals (p_NAME) it reads."""
    rhs = next(f for f in module.body if isinstance(f, py.FunctionDef) and f.name == "rhs")
    return bind(code(rhs, n), tables, values, lambda: tree(rhs, n)[0])


def bind(built: tuple, tables: dict | None = None, values: dict | None = None,
         written: Callable[[], py.Module] | None = None) -> ModelJacobian:
    """The Jacobian's code (`code`) executed with one run's tables and parameters;
    `written`: its tree, built again (`ModelJacobian.source`)."""
    compiled, n, rows, cols, constant = built
    scope = derivative_scope(tables, values)
    exec(compiled, scope)  # noqa: S102 - compiler-built tree, closed namespace
    return ModelJacobian(n, rows, cols, constant, scope["jac"], written)


def derivative_scope(tables: dict | None, values: dict | None) -> dict[str, object]:
    """The closed namespace generated derivatives run in: the library's functions, the
    rules' helpers, the tables and the parameters' globals they read."""
    return {"__builtins__": {}, **namespace(), "_DIFF": _diff, "_SGN0": _sgn0,
            **(tables or {}), **(values or {})}


def code(rhs: py.FunctionDef, n: int, own: bool = False) -> tuple:
    """The generated Jacobian of a generated `rhs`, compiled: (code, n, rows, cols,
    constant entries). Its tree is not kept: as large as rhs's, for its text only."""
    fn, rows, cols, constant = tree(rhs, n, own)
    return compile(fn, "<jacobian>", "exec"), n, rows, cols, constant


def tree(rhs: py.FunctionDef, n: int, own: bool = False) -> tuple:
    """The generated Jacobian of a generated `rhs`: (its module, rows, cols, constant
    entries). rhs is left as it is, unless `own` (no one else needs it): then its
    statements become the Jacobian's, not copies, and rhs lets go of them at once, so
    that those the Jacobian does not read are freed before it is compiled (a large
    model's rhs is the largest tree its run has). An rhs this cannot differentiate
    (NotImplementedError, raised before any statement is changed) gets them back."""
    if not own:
        return _tree([clone(s) for s in rhs.body])
    body, rhs.body = rhs.body, []
    try:
        return _tree(body)
    except BaseException:
        rhs.body = body
        raise


def _unpacked(stmt: py.stmt) -> dict[str, int] | None:
    """The states' locals an rhs statement unpacks from y (name -> index), if it does."""
    if isinstance(stmt, py.Assign) and isinstance(stmt.value, py.Name) and \
            stmt.value.id == "y":
        target = stmt.targets[0]
        names = target.elts if isinstance(target, py.Tuple) else [target]
        return {t.id: i for i, t in enumerate(names)}
    if isinstance(stmt, py.Assign) and isinstance(stmt.value, py.Subscript) and \
            isinstance(stmt.value.value, py.Name) and stmt.value.value.id == "y":
        return {stmt.targets[0].id: 0}  # one state: v = y[0]
    return None


def _local(stmt: py.stmt) -> str | None:
    """The local an rhs statement assigns (one name), if it does."""
    if isinstance(stmt, py.Assign) and len(stmt.targets) == 1 and \
            isinstance(stmt.targets[0], py.Name):
        return stmt.targets[0].id
    return None


def structure(rhs: py.FunctionDef) -> tuple[np.ndarray, np.ndarray] | None:
    """The entries of the Jacobian of a generated `rhs` that can be nonzero (rows,
    cols), from the dependency graph alone: which states each returned derivative
    reads, through the locals, in any branch (a superset of `tree`'s entries,
    which leaves out a branch's zero derivatives). None for an rhs with statements
    other than assignments (a unit's IF): the caller builds the Jacobian instead.
    A small part of `tree`'s work: no derivative is built."""
    states: dict[str, int] = {}
    deriv = _Deriv(states)
    rows: list[int] = []
    cols: list[int] = []
    for stmt in rhs.body:
        unpacked = _unpacked(stmt)
        if unpacked is not None:
            states.update(unpacked)
        elif isinstance(stmt, py.Return):
            for i, value in enumerate(stmt.value.elts):
                dep = sorted(deriv.deps(value))
                rows += [i] * len(dep)
                cols += dep
        elif _local(stmt) is not None:
            deriv.local_deps[_local(stmt)] = deriv.deps(stmt.value)
        elif not (isinstance(stmt, py.Assign) and isinstance(stmt.value, py.Name)):
            return None  # (m and z unpacked read no state; anything else may)
    return np.array(rows, dtype=int), np.array(cols, dtype=int)


def structure_for(c) -> tuple[np.ndarray, np.ndarray] | None:
    """`structure` of a run's generated `rhs` (`codegen.ModelCode`) if its build made
    it (a large model's: `build.EARLY_FROM`), else None."""
    return None if c.binder is None else c.binder.shared.get("structure")


def _tree(body: list[py.stmt], seed: dict[str, int] | None = None,
          wanted: range | None = None, called: str = "jac") -> tuple:
    """`tree` of rhs's statements (changed: placed on line 1); `seed`: other names
    differentiated in (a parameter's global -> its column), `wanted`: the columns
    built (default every one)."""
    states: dict[str, int] = dict(seed or {})
    deriv = _Deriv(states)
    out: list[py.stmt] = []
    entries: list[tuple[int, int, py.expr]] = []
    for stmt in body:
        if isinstance(stmt, py.Return):
            for i, value in enumerate(stmt.value.elts):
                if any(isinstance(x, py.NamedExpr) for x in py.walk(value)):
                    # its derivatives read the names it binds
                    out.append(py.Assign([py.Name(f"r{i}", py.Store())], value))
                for j in sorted(deriv.deps(value)):
                    if wanted is not None and j not in wanted:
                        continue
                    dv = deriv.d(value, j)
                    if dv is not None:
                        entries.append((i, j, dv))
        else:
            _statement(stmt, deriv, wanted, out)
    folded = [fold(e) for _, _, e in entries]
    constant = np.array([const_value(e) if const_value(e) is not None else math.nan
                         for e in folded], dtype=float)
    varying = [e for e, c in zip(folded, constant, strict=True) if math.isnan(c)]
    out.append(py.Return(py.List(varying, py.Load())))
    fn = function(called, ("t", "y", "m", "z"), _live(out))
    module = py.Module(body=[fn], type_ignores=[])
    # (every node a location, line 1: rhs's lines are not the Jacobian's; checked closed)
    place(module, closed=True, also=_ours, lines=False)
    rows = np.array([i for i, _, _ in entries], dtype=int)
    cols = np.array([j for _, j, _ in entries], dtype=int)
    return module, rows, cols, constant


def _statement(stmt: py.stmt, deriv: _Deriv, wanted: range | None, out: list) -> None:
    """One rhs statement and its derivatives' (in the states `deriv` knows, the
    columns `wanted`) onto `out`: an assignment, the unpacking of y, m or z, or a
    unit's IF (each branch differentiated as it runs: the test is a frozen branch)."""
    unpacked = _unpacked(stmt)
    if unpacked is not None:
        deriv.states.update(unpacked)
        out.append(stmt)
    elif _local(stmt) is not None:
        name = _local(stmt)
        out.append(stmt)
        dep = deriv.deps(stmt.value)
        # (the value's derivatives first: it may read the name's own, as a unit's
        # code assigning a name again does)
        made = {j: deriv.d(stmt.value, j) for j in sorted(dep)
                if wanted is None or j in wanted}
        if name in deriv.local_deps:  # (assigned again: its old constants go)
            _forget(deriv, {name})
        deriv.local_deps[name] = dep
        for j, dv in made.items():
            if dv is None:
                deriv.known[f"d{j}_{name}"] = 0.0
                continue
            dv = fold(dv)
            if const_value(dv) is not None:
                deriv.known[f"d{j}_{name}"] = const_value(dv)  # propagated, not stored
            else:
                out.append(py.Assign([py.Name(f"d{j}_{name}", py.Store())], dv))
    elif isinstance(stmt, py.Assign) and isinstance(stmt.value, py.Name):
        out.append(stmt)  # m and z unpacked
    elif isinstance(stmt, py.If):
        _branches(stmt, deriv, wanted, out)
    else:
        # (a unit's loop assigns locals this does not follow: passed through, their
        # derivatives were silently 0 -- the callers difference instead)
        raise NotImplementedError(type(stmt).__name__)


def _branches(stmt: py.If, deriv: _Deriv, wanted: range | None, out: list) -> None:
    """A unit's IF: each branch's statements with their derivatives, and at each
    branch's end the derivatives of every local either branch assigns stored under
    their names (a constant one too), so that what follows reads them whichever ran."""
    before = (dict(deriv.local_deps), dict(deriv.known))
    ends = []
    for branch in (stmt.body, stmt.orelse):
        deriv.local_deps, deriv.known = dict(before[0]), dict(before[1])
        code: list[py.stmt] = []
        for s in branch:
            _statement(s, deriv, wanted, code)
        ends.append((code, deriv.local_deps, deriv.known))
    assigned = sorted({n.id for s in (*stmt.body, *stmt.orelse) for n in py.walk(s)
                       if isinstance(n, py.Name) and isinstance(n.ctx, py.Store)})
    deps = {name: frozenset().union(*(d.get(name, frozenset()) for _, d, _ in ends))
            for name in assigned}
    for code, local_deps, known in ends:
        deriv.local_deps, deriv.known = local_deps, known
        for name in assigned:
            for j in sorted(deps[name]):
                if wanted is not None and j not in wanted:
                    continue
                dv = deriv.d(py.Name(name, py.Load()), j)
                if isinstance(dv, py.Name) and dv.id == f"d{j}_{name}":
                    continue
                code.append(py.Assign([py.Name(f"d{j}_{name}", py.Store())],
                                      dv if dv is not None else py.Constant(0.0)))
    deriv.local_deps, deriv.known = {**before[0], **deps}, dict(before[1])
    _forget(deriv, set(assigned))
    out.append(py.If(stmt.test, ends[0][0] or [py.Pass()], ends[1][0]))


def _forget(deriv: _Deriv, names: set[str]) -> None:
    """The constant derivatives known of `names` dropped (each `d{j}_{name}`): they
    are assigned again."""
    deriv.known = {k: v for k, v in deriv.known.items() if k.split("_", 1)[1] not in names}


def for_compiled(c) -> ModelJacobian:
    """The Jacobian of a run's generated `rhs` (`codegen.ModelCode`), built once."""
    if "jacobian" not in c.derived:
        n = len(c.state_names)
        # one code for every binding of the module
        built = c.binder.from_rhs("jacobian", lambda rhs, own: code(rhs, n, own))
        values = c.parameter_values
        c.derived["jacobian"] = bind(built, c.tables, values, lambda: _written(c))
    return c.derived["jacobian"]


@dataclass
class ParameterJacobian:
    """d fn / d p of one of a run's generated functions ("rhs" or "surf") in the
    parameters it reads by name (`names`, the globals p_NAME: PARAM and INCON values
    and what INITIAL computes from them), from its equations: each switch in its
    frozen branch, as `ModelJacobian`. `dense(t, y, m, z)`: a row per value the
    function returns, a column per name."""

    size: int
    names: list[str]
    rows: np.ndarray
    cols: np.ndarray
    constant: np.ndarray
    variable: Callable

    def __post_init__(self) -> None:
        fixed = ~np.isnan(self.constant)
        self._base = np.zeros((self.size, len(self.names)))
        self._base[self.rows[fixed], self.cols[fixed]] = self.constant[fixed]
        self._at = (self.rows[~fixed], self.cols[~fixed])

    def dense(self, t: float, y, m, z) -> np.ndarray:
        out = self._base.copy()
        if len(self._at[0]):
            out[self._at] = self.variable(t, y, m, z)
        return out


def parameter_names(c) -> list[str]:
    """The constants a run's generated functions read by name (`ModelCode`), in the
    order of `ParameterJacobian.names`: a row of `ParameterTangent.exact` each."""
    return sorted(c.binder.parameters)


def by_parameter(c, rows: dict[str, np.ndarray], q: int) -> np.ndarray:
    """`rows` (a constant's derivatives in q values, by name; none: 0) as the matrix
    `ParameterTangent.exact` takes, a row per `parameter_names`."""
    zero = np.zeros(q)
    return np.array([rows.get(p, zero) for p in parameter_names(c)]).reshape(-1, q)


def for_parameters(c, fn: str) -> ParameterJacobian:
    """`ParameterJacobian` of a run's generated `fn` (`codegen.ModelCode`), its code
    built once for every binding of the build, bound once per run. Raises
    NotImplementedError where the function has statements the differentiation does
    not take (a unit's IF)."""
    key = ("parameters", fn)
    if key not in c.derived:
        from .pytree import parameter

        if key not in c.shared:
            names = parameter_names(c)
            n = len(c.state_names)
            seed = {parameter(name): n + k for k, name in enumerate(names)}
            source = c.binder.rhs_function() if fn == "rhs" else \
                next(f for f in c.binder.tree().body if f.name == fn)
            size = len(next(s for s in source.body if isinstance(s, py.Return)).value.elts)
            module, rows, cols, constant = _tree([clone(s) for s in source.body], seed,
                                                 range(n, n + len(names)), "jacp")
            c.shared[key] = (compile(module, "<jacobian>", "exec"), size, names, rows,
                             cols - n, constant)
        compiled, size, names, rows, cols, constant = c.shared[key]
        values = c.parameter_values
        scope = derivative_scope(c.tables, values)
        exec(compiled, scope)  # noqa: S102 - compiler-built tree, closed namespace
        c.derived[key] = ParameterJacobian(size, names, rows, cols, constant, scope["jacp"])
    return c.derived[key]


def _written(c) -> py.Module:
    """The tree of a run's Jacobian, built again."""
    return tree(c.binder.rhs_function(), len(c.state_names))[0]


def over_members(c, values: dict[str, object]) -> ModelJacobian:
    """The Jacobian of a run's generated `rhs` over NumPy columns, an element per
    member of an ensemble integrated at once (`batch.stacked`): its conditionals
    made elementwise, the library's functions NumPy's, `values` every parameter's
    value (a column, or one float all members share). `variable` then gives a
    column (or a float) per varying entry."""
    from .pytree import parameter, vector_namespace, vectorised

    n = len(c.state_names)

    def elementwise(rhs: py.FunctionDef, own: bool):
        module, rows, cols, constant = tree(rhs, n, own)
        if "jacobian" not in c.shared:  # (the scalar code from the same tree)
            c.shared["jacobian"] = compile(module, "<jacobian>", "exec"), n, rows, cols, \
                constant
        vector = py.Module(body=[vectorised(module.body[0], "jac")], type_ignores=[])
        return compile(locate(vector), "<jacobian>", "exec")

    compiled = c.binder.from_rhs("jacobian_vec", elementwise)
    _, n, rows, cols, constant = c.binder.from_rhs("jacobian",
                                                   lambda rhs, own: code(rhs, n, own))
    scope: dict[str, object] = {"__builtins__": {}, "_DIFF": _diff_columns,
                                "_SGN0": np.sign, **c.tables, **vector_namespace()}
    scope.update({parameter(name): v for name, v in values.items()})
    exec(compiled, scope)  # noqa: S102 - compiler-built tree, closed namespace
    return ModelJacobian(n, rows, cols, constant, scope["jac"], lambda: _written(c))


def _diff_columns(f: Callable, k: int, *args):
    """`_diff` on columns: each element's central difference."""
    x = np.asarray(args[k], dtype=float)
    h = 6.055454e-6 * np.maximum(np.abs(x), 1.0)
    lo, hi = list(args), list(args)
    lo[k], hi[k] = x - h, x + h
    return (np.asarray(f(*hi), dtype=float) - np.asarray(f(*lo), dtype=float)) / (2.0 * h)


def _live(body: list[py.stmt]) -> list[py.stmt]:
    """The statements whose names are read later (the values the derivatives need),
    the unpacking of y, m and z, and the return."""
    used: set[str] = set()
    kept: list[py.stmt] = []
    for stmt in reversed(body):
        # (a unit's IF: kept whole where a name it assigns is read later)
        targets = [n.id for n in nodes(stmt) if isinstance(n, py.Name) and
                   isinstance(n.ctx, py.Store)] if isinstance(stmt, (py.Assign, py.If)) \
            else []
        reads_args = isinstance(stmt, py.Assign) and isinstance(stmt.value, (py.Name,
                                                                             py.Subscript))
        if isinstance(stmt, py.Return) or reads_args and not targets or \
                any(t in used for t in targets):
            kept.append(stmt)
            used |= {n.id for n in nodes(stmt) if isinstance(n, py.Name) and
                     isinstance(n.ctx, py.Load)}
    return list(reversed(kept))


_OURS = re.compile(r"d\d+_\w+|r\d+|_DIFF|_SGN0")


def _ours(name: str) -> bool:
    """The names the Jacobian adds to the rhs's: derivative locals and helpers."""
    return _OURS.fullmatch(name) is not None


def finite_difference(f: Callable, t: float, y: np.ndarray, eps: float = 1e-7) -> np.ndarray:
    """The Jacobian of f(t, y) by central differences (for tests and checks)."""
    y = np.asarray(y, dtype=float)
    n = len(y)
    out = np.empty((n, n))
    for j in range(n):
        h = eps * max(abs(y[j]), 1.0)
        up, down = y.copy(), y.copy()
        up[j] += h
        down[j] -= h
        out[:, j] = (np.asarray(f(t, up), float) - np.asarray(f(t, down), float)) / (2 * h)
    return out
