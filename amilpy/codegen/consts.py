"""Values known before a run: INITIAL, initial conditions, initial memory slots.

Each is emitted like the run's code (in the "literal" context: a switch takes its
branch from the signs on the spot) and evaluated once in the same closed
namespace; a fault is an `AmilError` at the listing's line.
"""

from __future__ import annotations

import ast as py
import math

import numpy as np

from .. import ir
from ..diagnostics import AmilError, Diagnostic, Span
from ..library import templates
from ..library.runtime import Extending
from ..parse.syntax import deep_enough
from .emit import Emitter
from .jacobian import _Deriv, _ours, derivative_scope
from .pytree import assert_closed, namespace, parameter
from .written import user_callable


def _emitter(model: ir.Model, constants: dict[str, float], tables) -> Emitter:
    return Emitter(model, constants, {}, "literal", {}, {}, tables,
                   define_function=user_callable)


# expression -> its code with the constants it reads as names (p_NAME): a run with
# other data evaluates its INITIAL section without compiling it again
_CODE: dict[tuple, tuple] = {}
_CODE_LIMIT = 4096


@deep_enough()
def evaluate_constant(model: ir.Model, expr, constants: dict[str, float], tables,
                      span: Span) -> float:
    """Evaluate an expression of constants (INITIAL, initial conditions)."""
    from ..parse import syntax as syn

    if type(expr) is syn.Num:  # (most initial conditions: no code to make)
        return float(expr.value)
    names = frozenset(n.name for n in syn.walk(expr)
                      if isinstance(n, syn.Name) and n.name in constants)
    key = (id(expr), names, tuple(sorted(tables)))
    entry = _CODE.get(key)
    if entry is None or entry[0] is not expr:
        em = Emitter(model, constants, {}, "literal", {}, {}, tables, parameters=names,
                     define_function=user_callable)
        try:
            tree = em.emit(expr)
        except KeyError as exc:  # a name that is not a constant
            raise AmilError([Diagnostic(f"{exc.args[0]} is not known before the run "
                                        "starts", span)], model.path, model.source) from None
        body = py.Expression(tree)
        py.fix_missing_locations(body)
        assert_closed(py.Module(body=[py.Expr(body.body)], type_ignores=[]))
        if len(_CODE) > _CODE_LIMIT:
            _CODE.clear()
        entry = _CODE[key] = (expr, compile(body, model.path or model.name, "eval"),
                              sorted(em.tables))
    _, code, used = entry
    scope = {"__builtins__": {}, **namespace(),
             **{name: _table(tables, name) for name in used},
             **{parameter(n): constants[n] for n in names}}
    return float(_run(model, lambda: eval(code, scope), span))  # noqa: S307


def _table(tables, name: str):
    if name.startswith("_T__"):  # LINT's own copy, which notes reads outside it
        return Extending(name[len("_T__"):], tables[name[len("_T__"):]])
    return tables[name[len("_T_"):]]


def initial_slots(model: ir.Model, text: str, mem: ir.Memory, constants: dict[str, float],
                  tables) -> list[float]:
    """The initial values a memory template gives (one, or several with `*`)."""
    em = _emitter(model, constants, tables)
    used = templates.template_names(text)  # only these arguments are evaluated
    args = [em.emit(a) if templates.ARGUMENTS[i] in used else None
            for i, a in enumerate(mem.args)]
    value = evaluate(model, em.fill(text, args, memory=mem), em.tables, mem.span)
    return [float(v) for v in value] if templates.spread(text) else [float(value)]


def evaluate(model: ir.Model, body: py.expr, tables: dict[str, tuple], span: Span):
    """The value of a generated expression of constants; a fault is an AmilError at span."""
    tree = py.Expression(body)
    py.fix_missing_locations(tree)
    assert_closed(py.Module(body=[py.Expr(tree.body)], type_ignores=[]))
    scope: dict[str, object] = {"__builtins__": {}}
    scope.update(namespace())
    scope.update(tables)
    return _run(model, lambda: eval(compile(tree, model.path or model.name, "eval"),  # noqa: S307
                                    scope), span)


def _run(model: ir.Model, evaluate_it, span: Span):
    """evaluate_it(), its faults as AmilErrors at span."""
    try:
        return evaluate_it()
    except ZeroDivisionError:
        raise AmilError([Diagnostic("division by zero", span,
                                    "check the data values this expression uses")],
                        model.path, model.source) from None
    except OverflowError:
        raise AmilError([Diagnostic("value too large (overflow)", span)], model.path,
                        model.source) from None
    except (ValueError, TypeError) as exc:
        raise AmilError([Diagnostic(f"cannot be evaluated: {exc}", span,
                                    "check the arguments' ranges (ASIN, ACOS, SQRT, ALOG)")],
                        model.path, model.source) from None
    except NameError as exc:
        name = str(exc).split("'")[1] if "'" in str(exc) else str(exc)
        if name == "t":  # (the generated code's time: the listing's TIME, or ACSL's T)
            time = "T" if model.acsl is not None else "TIME"
            raise AmilError([Diagnostic(
                f"{time} is not known before the run starts", span,
                f"an initial value is taken before {time} runs: write the start's value "
                "(0, unless the listing gives another start)")],
                model.path, model.source) from None
        raise AmilError([Diagnostic(
            f"{name.removeprefix('v_')} is not known before the run starts", span,
            "an initial value or INITIAL statement can use numbers, data values and INITIAL "
            "values only")], model.path, model.source) from None


@deep_enough()
def initial_values(model: ir.Model, data: dict[str, float], tables,
                   reserved: dict[str, float]) -> dict[str, float]:
    """Data values, TIMER values and the INITIAL section, evaluated in sorted order."""
    constants = dict(reserved)
    constants.update(data)
    if not model.own_pi:
        constants["PI"] = math.pi
    for eq in model.initial:
        constants[eq.target] = evaluate_constant(model, eq.expr, constants, tables, eq.span)
    return constants


def parameter_names(model: ir.Model) -> frozenset[str]:
    """The constants generated code reads by name instead of folding in: PARAM and
    INCON values, and the INITIAL values computed from them. A sweep, a value list
    or --set changes those, and the same code serves every run (`Compiler.bind`);
    CONST values, TIMER values and what INITIAL computes from them alone are the
    true constants, folded into the code."""
    from ..parse import syntax as syn

    names = {n for n in model.data_names if model.data_kinds.get(n) != "CONST"}
    for eq in model.initial:  # in sorted order: what an equation reads comes first
        if any(isinstance(x, syn.Name) and x.name in names for x in syn.walk(eq.expr)):
            names.add(eq.target)
    return frozenset(names)


# (expression, the constants it reads by name) -> its derivatives' code, a compiled
# expression or None per name read (`slopes`)
_SLOPES: dict[tuple, tuple] = {}


def slopes(model: ir.Model, free: list[str], constants: dict[str, float],
           parameters: frozenset[str], tables) -> tuple[dict[str, np.ndarray], np.ndarray] | None:
    """d/d `free` of the constants a run's code reads by name (`parameter_names`: the
    data values and what INITIAL computes from them, each a row) and of the states'
    initial values (an array, a row per state), from the equations: INITIAL's
    derivatives in its sorted order, each the sum over the constants it reads of its
    derivative in that constant times that constant's row (a switch in its branch, a
    function with no written rule by a difference in its own arguments, as the
    field's Jacobian). None where a free value is folded into the code (a CONST) or
    an equation cannot be differentiated so: the caller differences the bind."""
    q = len(free)
    if any(name not in parameters for name in free):
        return None
    rows = {name: np.eye(q)[k] for k, name in enumerate(free)}
    try:
        for eq in model.initial:
            if eq.target in parameters and eq.target not in rows:
                rows[eq.target] = _row(model, eq.expr, constants, rows, q, tables)
        start = _starts(model, constants, rows, q, tables)
    except (NotImplementedError, ArithmeticError, ValueError, TypeError, KeyError, NameError):
        return None
    return rows, start


# statements of ACSL INITIAL code that assign no value (`written_slopes`)
_INERT = (ir.ScheduleAt, ir.TermtIf)


def written_slopes(model: ir.Model, free: list[str], start: dict[str, float],
                   constants: dict[str, float], tables
                   ) -> tuple[dict[str, np.ndarray], np.ndarray] | None:
    """`slopes` of a program in ACSL form, whose INITIAL is written-order code run from
    `start` (`run.acsl.initial_start`): each assignment's derivative at the values
    the code has there (a name assigned again takes its last). None where the code
    is more than assignments of REAL values (an IF, a loop, an INTEGER: the caller
    differences the bind), or where following it does not give the run's
    `constants`."""
    q = len(free)
    rows = {name: np.eye(q)[k] for k, name in enumerate(free)}
    values = dict(start)
    try:
        for code in model.acsl.initial:
            for st in code.body:
                if isinstance(st, _INERT):
                    continue
                if not isinstance(st, ir.Let) or st.store != "REAL":
                    return None
                rows[st.target] = _row(model, st.expr, values, rows, q, tables)
                values[st.target] = evaluate_constant(model, st.expr, values, tables,
                                                      st.span)
        if any(name in constants and not math.isclose(values[name], constants[name],
                                                      rel_tol=1e-12)
               for name in rows):
            return None
        ics = _starts(model, constants, rows, q, tables)
    except (NotImplementedError, ArithmeticError, ValueError, TypeError, KeyError, NameError,
            AmilError):  # (NameError: a name INITIAL has no value for, as T)
        return None
    return rows, ics


def _starts(model: ir.Model, constants: dict[str, float], rows: dict[str, np.ndarray],
            q: int, tables) -> np.ndarray:
    """d/d the free values of the states' initial values, a row per state (`_row`)."""
    return np.array([_row(model, s.ic, constants, rows, q, tables)
                     for s in model.states]).reshape(len(model.states), q)


def _row(model: ir.Model, expr, values: dict[str, float], rows: dict[str, np.ndarray],
         q: int, tables) -> np.ndarray:
    """d expr/d the free values at `values`: the sum over the names it reads of its
    derivative in each (`_slope_code`) times that name's row (`rows`; none: 0)."""
    from ..parse import syntax as syn

    out = np.zeros(q)
    if type(expr) is syn.Num:
        return out
    read = sorted({n.name for n in syn.walk(expr)
                   if isinstance(n, syn.Name) and n.name in values})
    moved = [k for k, name in enumerate(read) if name in rows]
    if not moved:
        return out
    made = _slope_code(model, expr, read, values, tables)
    scope = derivative_scope({name: _table(tables, name) for name in made[1]},
                             {parameter(name): values[name] for name in read})
    for k in moved:
        if made[0][k] is not None:
            out += float(eval(made[0][k], scope)) * rows[read[k]]  # noqa: S307
    return out


def _slope_code(model: ir.Model, expr, read: list[str], constants, tables) -> tuple:
    """(d expr/d each of `read`, compiled or None where it is 0; the tables it reads)."""
    key = (id(expr), tuple(read), tuple(sorted(tables)))
    entry = _SLOPES.get(key)
    if entry is None or entry[0] is not expr:
        em = Emitter(model, constants, {}, "literal", {}, {}, tables,
                     parameters=frozenset(read), define_function=user_callable)
        tree = em.emit(expr)
        deriv = _Deriv({parameter(name): k for k, name in enumerate(read)})
        deriv.deps(tree)
        made = []
        for k in range(len(read)):
            d = deriv.d(tree, k)
            if d is None:
                made.append(None)
                continue
            if any(isinstance(n, py.NamedExpr) for n in py.walk(tree)):
                # (the derivative reads the names the expression binds -- an argument
                # a template reads twice, LIMIT's (w1 := ...): the expression first)
                d = py.Subscript(py.Tuple([templates.clone(tree), d], py.Load()),
                                 py.Constant(1), py.Load())
            body = py.Expression(d)
            py.fix_missing_locations(body)
            assert_closed(py.Module(body=[py.Expr(body.body)], type_ignores=[]),
                          also=_ours)
            made.append(compile(body, model.path or model.name, "eval"))
        if len(_SLOPES) > _CODE_LIMIT:
            _SLOPES.clear()
        entry = _SLOPES[key] = (expr, made, sorted(em.tables))
    return entry[1], entry[2]
