"""IR and syntax expressions written back in the listing's notation.

The student's own spelling is kept: a function is printed under the name the
listing wrote (FSW stays FSW, BOUND stays BOUND), numbers as written (1.5D-3),
names folded to upper case as everywhere in amilpy's output. Reports print the
equations with this; surfaces carry their text for events and messages.
"""

from __future__ import annotations

from .. import ir
from ..library import WEATHER_HOLD
from . import syntax as syn
from .syntax import Visitor, deep_enough

_PREC = {"EQV": 1, "NEQV": 1, "OR": 2, "AND": 3, "<": 5, "<=": 5, ">": 5, ">=": 5, "==": 5,
         "/=": 5, "+": 6, "-": 6, "*": 7, "/": 7, "**": 9}
_NOT = 4
_UNARY = 8  # unary minus binds looser than ** and tighter than * /
_WORDS = {"EQV": " .EQV. ", "NEQV": " .NEQV. ", "OR": " .OR. ", "AND": " .AND. "}


class _Text(Visitor):
    """The text of an expression; `parent` is the precedence around it. With a
    `limit`, a part that would run past it is written "..." (and not walked)."""

    complete = ir.EXPRESSIONS

    def __init__(self, model: ir.Model | None, limit: int | None = None) -> None:
        self.model = model
        self.left = limit

    def visit(self, node, *args):
        if self.left is not None:
            if self.left <= 0:
                return "..."
            self.left -= 1  # a node writes at least one character
        return super().visit(node, *args)

    def call(self, func: str, args) -> str:
        return f"{func}({', '.join(self.visit(a, 0) for a in args)})"

    def visit_Num(self, e: syn.Num, parent: int) -> str:
        return e.text or f"{e.value:g}"

    def visit_Name(self, e: syn.Name, parent: int) -> str:
        return e.name

    def visit_Neg(self, e: syn.Neg, parent: int) -> str:
        # unary minus binds tighter than * and / (Fortran reads -A*B as (-A)*B),
        # looser than **: only a power's operand needs it in parentheses
        inner = "-" + self.visit(e.operand, _UNARY)
        return f"({inner})" if parent > _UNARY else inner

    def visit_BinOp(self, e: syn.BinOp, parent: int) -> str:
        p = _PREC[e.op]
        # ** groups to the right, the others to the left; an operand grouped the
        # other way keeps its parentheses (X + (Y + Z) is not X + Y + Z in floats)
        left_p = p + 1 if e.op == "**" or p == _PREC["<"] else p
        right_p = p if e.op == "**" else p + 1
        op = e.op if e.op in ("*", "/", "**") else _WORDS.get(e.op, f" {e.op} ")
        text = f"{self.visit(e.left, left_p)}{op}{self.visit(e.right, right_p)}"
        return f"({text})" if p < parent else text

    def visit_Not(self, e: syn.Not, parent: int) -> str:
        inner = ".NOT. " + self.visit(e.operand, _NOT)
        return f"({inner})" if parent > _NOT else inner

    def visit_Call(self, e: syn.Call, parent: int) -> str:
        return self.call(e.func, e.args)

    def visit_UnitValue(self, e: ir.UnitValue, parent: int) -> str:
        # the value a block computes (an IF, PROCEDURAL/PROCEDURE/NOSORT, an IMPL loop)
        if self.model is None:
            return e.name
        unit = self.model.units[e.unit]
        what = {"IMPL": "the IMPL loop", "IF": "the IF block"}.get(unit.kind,
                                                                   "the written-order block")
        return f"({what} at line {unit.span.line})"

    def visit_SwitchValue(self, e: ir.SwitchValue, parent: int) -> str:
        sw = self.model.switches[e.switch]
        text = self.call(sw.written or sw.func, sw.args)
        return text + (f"[{e.output + 1}]" if sw.func == "OUTSW" else "")

    def visit_MemoryValue(self, e: ir.MemoryValue, parent: int) -> str:
        mem = self.model.memories[e.memory]
        if mem.func == WEATHER_HOLD:
            return mem.target  # FST's weather name, as the listing writes it
        return self.call(mem.written or mem.func, mem.args)

    def visit_TableLookup(self, e: ir.TableLookup, parent: int) -> str:
        name = e.written or e.func
        return f"{name}({e.table}, {self.visit(e.x, 0)})"

    def visit_Impulse(self, e: ir.Impulse, parent: int) -> str:
        return self.call("IMPULS", (e.start, e.period))


@deep_enough()
def expr_text(model: ir.Model | None, e: syn.Node, limit: int | None = None) -> str:
    """An expression (syntax or IR; IR nodes need the model) in the listing's notation;
    with `limit`, about that many characters at most (the rest "...")."""
    text = _Text(model, limit).visit(e, 0)
    if limit is not None and len(text) > limit:
        text = text[:max(limit - 3, 1)] + "..."
    return text
