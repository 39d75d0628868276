"""The one place that phrases an arithmetic fault in the model's generated code.

Every fault the run meets (a derivative, a surface, an output, TERMINAL, the
start) is written by `fault_text`, from `ModelCode.explain_fault(exc, t, y, m, z)`:
the statement, the variable and the operands ("W2 (line 16): division by zero:
JL = 0"); the caller adds the TIME.
"""

from __future__ import annotations

from dataclasses import dataclass

from .. import ir
from ..codegen import ModelCode


@dataclass(frozen=True)
class Fault:
    """An arithmetic fault met while evaluating the model, where it happened."""

    exc: BaseException
    t: float
    y: list[float]
    m: list[float]
    z: list[float]


def fault_text(model: ir.Model, c: ModelCode, fault: Fault) -> str:
    """"W2 (line 16): division by zero: JL = 0": the statement that faulted (the
    variable it assigns, its line) and the operation with its operand values, as
    the compiled code's own line table and a checking re-evaluation of that one
    statement give them (`ModelCode.explain_fault`). A fault outside the model's
    generated code (a run-time helper, SciPy) keeps Python's own words."""
    report = c.explain_fault(fault.exc, fault.t, fault.y, fault.m, fault.z)
    return str(fault.exc) if report is None else str(report)
