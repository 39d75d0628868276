"""IR statements -> Python statements: written-order code and sorting units.

A sorting unit (an IF or PROCEDURAL block of sorted code) is emitted inside the
generated functions where the sort places it: its outputs start from their value
before it (`start`), then its statements run. Written-order code (the ACSL form's
INITIAL, DYNAMIC, DISCRETE and TERMINAL) becomes a function of its own,

    def NAME(t, y, m, z, ev): ... return states, memory, values

which may change states (a reset) and the names it keeps (z), and reports a
SCHEDULE (`ev(0, section, time)`) or a TERMT that holds (`ev(1, index, 0.0)`) to
the run through `ev`. A FUNCTION the listing defines is a plain Python function.
Every statement has its own line (the compiler's `line`), so a fault names it.
"""

from __future__ import annotations

import ast as py
from collections.abc import Callable

from .. import ir
from .emit import Emitter, truth
from .pytree import local, number

SCHEDULE, TERMT = 0, 1  # what a call of `ev` reports


def name(n: str, store: bool = False) -> py.Name:
    return py.Name(local(n), py.Store() if store else py.Load())


class Statements:
    """Emits IR statements with one expression emitter; `line(kind, target, span)`
    gives each statement its line of the generated code."""

    def __init__(self, em: Emitter, line: Callable, fresh: Callable[[], str]) -> None:
        self.em = em
        self.line = line
        self.fresh = fresh

    def block(self, body) -> list[py.stmt]:
        out: list[py.stmt] = []
        for st in body:
            out.extend(self.statement(st))
        return out or [py.Pass()]

    def placed(self, node: py.stmt, target: str, span) -> py.stmt:
        node.amil_line = self.line("code", target, span)
        return node

    def statement(self, st) -> list[py.stmt]:
        em = self.em
        if isinstance(st, ir.Let):
            value = em.emit(st.expr)
            if st.store == "INTEGER":
                value = py.Call(py.Name("_AINT", py.Load()), [value], [])
            elif st.store == "LOGICAL":
                value = py.IfExp(truth(value), py.Constant(1.0), py.Constant(0.0))
            return [self.placed(py.Assign([name(st.target, True)], value), st.target, st.span)]
        if isinstance(st, ir.IfThen):
            orelse: list[py.stmt] = []
            for cond, body in reversed(st.branches):
                if cond is None:
                    orelse = self.block(body)
                    continue
                test = truth(em.emit(cond))
                node = self.placed(py.If(test, self.block(body), orelse), "IF", st.span)
                orelse = [node]
            return orelse
        if isinstance(st, ir.ForLoop):
            a, b, s, n, k = (self.fresh() for _ in range(5))
            head = [py.Assign([py.Name(w, py.Store())], em.emit(e))
                    for w, e in ((a, st.start), (b, st.stop), (s, st.step))]
            head.append(py.Assign([py.Name(n, py.Store())], py.Call(
                py.Name("_NITER", py.Load()), [py.Name(a, py.Load()), py.Name(b, py.Load()),
                                               py.Name(s, py.Load())], [])))

            def value_after(count: str) -> py.expr:
                return py.BinOp(py.Name(a, py.Load()), py.Add(), py.BinOp(
                    py.Name(count, py.Load()), py.Mult(), py.Name(s, py.Load())))

            body = [py.Assign([name(st.var, True)], value_after(k)), *self.block(st.body)]
            loop = py.For(py.Name(k, py.Store()), py.Call(py.Name("_RANGE", py.Load()),
                                                          [py.Name(n, py.Load())], []),
                          body, [])
            # after the loop the variable is one step past the last value (Fortran)
            after = py.Assign([name(st.var, True)], value_after(n))
            return [self.placed(x, st.var, st.span) for x in (*head, loop, after)]
        if isinstance(st, ir.ScheduleAt):
            call = py.Call(py.Name("ev", py.Load()), [py.Constant(SCHEDULE),
                                                      py.Constant(st.section),
                                                      em.emit(st.when)], [])
            return [self.placed(py.Expr(call), f"SCHEDULE {st.section}", st.span)]
        if isinstance(st, ir.TermtIf):
            call = py.Call(py.Name("ev", py.Load()), [py.Constant(TERMT),
                                                      py.Constant(st.index),
                                                      py.Constant(0.0)], [])
            return [self.placed(py.If(truth(em.emit(st.cond)), [py.Expr(call)], []),
                                "TERMT", st.span)]
        if isinstance(st, ir.Solve):
            return self.solve(st)
        raise AssertionError(f"no code for {type(st).__name__}")

    def solve(self, st: ir.Solve) -> list[py.stmt]:
        """IMPL: Y from its last accepted value; the body gives FOFY(Y); converged
        when |FOFY - Y| <= P*max(1, |Y|), else Y = FOFY and again; a fault naming Y,
        TIME and the residual after ir.IMPL_ITERATIONS tries."""
        em = self.em
        r, k, tol = self.fresh(), self.fresh(), self.fresh()

        def call(f: str, *args: py.expr) -> py.expr:
            return py.Call(py.Name(f, py.Load()), list(args), [])

        y = name(st.target)
        converged = py.Compare(call("_ABS", py.Name(r, py.Load())), [py.LtE()], [py.BinOp(
            py.Name(tol, py.Load()), py.Mult(), call("_AMAX1", py.Constant(1.0),
                                                     call("_ABS", y)))])
        loop = py.For(py.Name(k, py.Store()), call("_RANGE", py.Constant(ir.IMPL_ITERATIONS)),
                      [*self.block(st.body),
                       py.Assign([py.Name(r, py.Store())],
                                 py.BinOp(name(st.result), py.Sub(), name(st.target))),
                       py.If(converged, [py.Break()], []),
                       py.Assign([name(st.target, True)], name(st.result))],
                      [py.Expr(call("_IMPL_FAIL", py.Constant(st.target), py.Name("t", py.Load()),
                                    py.Name(r, py.Load())))])
        head = [py.Assign([name(st.target, True)], em.emit(st.start)),
                py.Assign([py.Name(tol, py.Store())], em.emit(st.tol)),
                py.Assign([py.Name(r, py.Store())], py.Constant(0.0))]
        return [self.placed(x, st.target, st.span) for x in (*head, loop)]


def start(outputs, known: set[str], values: dict[str, float]) -> list[py.stmt]:
    """Each output's value before a unit or a section runs: its own local where the
    function has one (`known`: states, kept names), else `values` (INITIAL's), else 0."""
    out = []
    for n in outputs:
        if n in known:
            continue
        value = values.get(n, 0.0)
        out.append(py.Assign([name(n, True)], number(float(value))))
    return out


def compile_code(model: ir.Model, name_: str, codes, constants: dict[str, float], tables,
                 starts: dict[str, float], params: tuple[str, ...] = (),
                 result: str | None = None) -> Callable:
    """Written-order code compiled on its own, before the run's functions exist: the
    ACSL form's INITIAL (`name_(t, y, m, z, ev)` -> values of the names it assigns,
    then of `starts`' names), or a FUNCTION (`name_(*params)` -> its result). Names
    the code assigns or reads that are not constants start at `starts` or 0; a
    constant it assigns starts at its value."""
    from ..parse.syntax import walk
    from .faults import STATEMENTS, Statement
    from .pytree import fold, function, namespace, place

    assigned = list(dict.fromkeys(n for c in codes for n in c.assigned))
    read = [n.name for c in codes for st in c.body for n in walk(st)
            if isinstance(n, syntax_name())]
    # a constant the code assigns (Magnolia's CONSTANT given a new value in INITIAL)
    # is its constant until then
    starts = {**{n: constants[n] for n in assigned if n in constants}, **starts}
    own = set(assigned) | set(starts) | set(params)
    em = Emitter(model, {k: v for k, v in constants.items() if k not in own}, {}, "literal",
                 {}, {}, tables, define_function=user_callable)
    table: list = [None]
    lines: dict = {}

    def line(kind: str, target: str, span) -> int:
        key = (kind, target, span)
        if key not in lines:
            table.append(Statement(kind, target, span))
            lines[key] = len(table)
        return lines[key]

    counter = iter(range(1, 1 << 30))
    locals_ = [n for n in dict.fromkeys([*assigned, *starts, *read])
               if n not in params and (n in own or n not in constants)]
    body = start(locals_, set(), starts)
    for c in codes:
        body += Statements(em, line, lambda: f"w{next(counter)}").block(c.body)
    if result is not None:
        body.append(py.Return(name(result)))
        fn = function(name_, tuple(local(p) for p in params), body)
    else:
        names = [*assigned, *(n for n in starts if n not in assigned)]
        body.append(py.Return(py.List([name(n) for n in names], py.Load())))
        fn = function(name_, ("t", "y", "m", "z", "ev"), body)
    module = fold(py.Module(body=[fn], type_ignores=[]))
    place(module, closed=True)
    scope = {"__builtins__": {}, **namespace(), **em.tables, STATEMENTS: table}
    exec(compile(module, model.path or model.name, "exec"), scope)  # noqa: S102
    fn = scope[name_]
    if result is None:
        fn.amil_names = names  # what the returned values are
    else:
        # the same function on NumPy columns (an ensemble's members at once): its
        # conditional expressions made elementwise, the library's functions NumPy's;
        # a statement that branches on a column raises ValueError there
        from .pytree import locate, vector_namespace, vectorised

        elementwise = py.Module(body=[vectorised(module.body[0], name_)], type_ignores=[])
        vector = {"__builtins__": {}, **vector_namespace(), **em.tables, STATEMENTS: table}
        exec(compile(locate(elementwise), model.path or model.name,  # noqa: S102
                     "exec"), vector)
        fn.elementwise = vector[name_]
    return fn


def syntax_name():
    from ..parse.syntax import Name

    return Name


def user_callable(model: ir.Model, func: str, constants: dict[str, float], tables
                  ) -> Callable:
    """A FUNCTION the listing defines, compiled with the run's constants (once per
    set of constants), callable on floats and, elementwise, on NumPy arrays."""
    key = ("function", func, tuple(sorted(constants.items())))
    if key not in model.memo:
        params, result, code = model.acsl.functions[func]
        scalar = compile_code(model, f"_U_{func}", [code], constants, tables, {}, params,
                              result)

        def call(*args):
            if any(hasattr(a, "shape") for a in args):
                import numpy as np

                try:
                    # (a fault raises, as on floats: element by element below, the
                    # same fault is then the caller's, with its words)
                    with np.errstate(divide="raise", over="raise", invalid="raise"):
                        return scalar.elementwise(*args)
                except (ValueError, TypeError, ArithmeticError):
                    # (it branches on a column's value, or faults on an element)
                    return np.vectorize(scalar, otypes=[float])(*args)
            return scalar(*args)
        model.memo[key] = call
    return model.memo[key]
