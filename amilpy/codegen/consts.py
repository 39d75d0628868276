"""Values known before a run: INITIAL, initial conditions, initial memory slots.

Each is emitted like the run's code (in the "literal" context: a switch takes its
branch from the signs on the spot) and evaluated once in the same closed
namespace; a fault is an `AmilError` at the listing's line.
"""

from __future__ import annotations

import ast as py
import math

from .. import ir, templates
from ..diagnostics import AmilError, Diagnostic, Span
from ..syntax import deep_enough
from .emit import Emitter
from .pytree import assert_closed, namespace


def _emitter(model: ir.Model, constants: dict[str, float], tables) -> Emitter:
    return Emitter(model, constants, {}, "literal", {}, {}, tables)


@deep_enough()
def evaluate_constant(model: ir.Model, expr, constants: dict[str, float], tables,
                      span: Span) -> float:
    """Evaluate an expression of constants (INITIAL, initial conditions)."""
    em = _emitter(model, constants, tables)
    try:
        tree = em.emit(expr)
    except KeyError as exc:  # a name that is not a constant
        raise AmilError([Diagnostic(f"{exc.args[0]} is not known before the run starts",
                                    span)], model.path, model.source) from None
    return float(evaluate(model, tree, em.tables, span))


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
    try:
        return eval(compile(tree, model.path or model.name, "eval"), scope)  # noqa: S307
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
    constants["PI"] = math.pi
    for eq in model.initial:
        constants[eq.target] = evaluate_constant(model, eq.expr, constants, tables, eq.span)
    return constants
