"""Written-order code at run time (ACSL sections, IF/DO units, TERMINAL): what it
reports through `ev` (`Calls`), the words for a fault in it, and the TERMINAL
sections run in file order."""

from __future__ import annotations

from ..codegen.faults import statement_of
from ..codegen.written import SCHEDULE
from ..diagnostics import AmilError
from .cursor import Cursor


class Calls:
    """What written-order code reports through `ev`: SCHEDULE and TERMT."""

    def __init__(self) -> None:
        self.schedules: list[tuple[float, str]] = []
        self.termts: list[int] = []

    def __call__(self, kind: int, what, value: float) -> None:
        if kind == SCHEDULE:
            self.schedules.append((float(value), what))
        else:
            self.termts.append(int(what))


def code_fault(exc: BaseException) -> str:
    """A fault in written-order code: the statement and what went wrong."""
    found = statement_of(exc)
    what = str(exc) or type(exc).__name__
    if isinstance(exc, ZeroDivisionError):
        what = "division by zero"
    if found is None or found[0] is None or found[0].span is None:
        return what
    return f"{found[0].target} (line {found[0].span.line}): {what}"


def run_terminal(c, codes, cur: Cursor) -> dict[str, float]:
    """TERMINAL sections in file order: the values they assign."""
    out: dict[str, float] = {}
    y, z = cur.y.tolist(), list(cur.z)
    for k, code in enumerate(codes):
        _, fn = c.code[f"terminal_{k}"]
        try:
            y, z, values = fn(cur.t, y, cur.m, z, Calls())
        except (ArithmeticError, ValueError) as exc:
            raise AmilError(f"TERMINAL: {code_fault(exc)}") from None
        out.update(zip(code.assigned, values, strict=True))
    return out
