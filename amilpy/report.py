"""The IR written back in the listing's notation (`expr_text`), for the report's
equations. The report itself is `amilpy.output.report`.
"""

from __future__ import annotations

from . import ir
from . import syntax as syn

# ---------------------------------------------------------------- expressions

_PREC = {"+": 1, "-": 1, "*": 2, "/": 2, "**": 4}


def expr_text(model: ir.Model, e, parent: int = 0) -> str:
    """An IR expression written back in the listing's notation."""
    if isinstance(e, syn.Num):
        return e.text or f"{e.value:g}"
    if isinstance(e, syn.Name):
        return e.name
    if isinstance(e, syn.Neg):
        inner = "-" + expr_text(model, e.operand, 3)
        return f"({inner})" if parent > 1 else inner
    if isinstance(e, syn.BinOp):
        p = _PREC[e.op]
        right_p = p + (1 if e.op in "-/" else 0) if e.op != "**" else p
        text = (f"{expr_text(model, e.left, p + (1 if e.op == '**' else 0))}"
                f"{e.op if e.op in '*/**' else ' ' + e.op + ' '}"
                f"{expr_text(model, e.right, right_p)}")
        return f"({text})" if p < parent else text
    if isinstance(e, syn.Call):
        return f"{e.func}({', '.join(expr_text(model, a) for a in e.args)})"
    if isinstance(e, ir.SwitchValue):
        sw = model.switches[e.switch]
        call = f"{sw.func}({', '.join(expr_text(model, a) for a in sw.args)})"
        return call + (f"[{e.output + 1}]" if sw.func == "OUTSW" else "")
    if isinstance(e, ir.MemoryValue):
        mem = model.memories[e.memory]
        return f"{mem.func}({', '.join(expr_text(model, a) for a in mem.args)})"
    if isinstance(e, ir.TableLookup):
        return f"{'NLFGEN' if e.quadratic else 'AFGEN'}({e.table}, {expr_text(model, e.x)})"
    if isinstance(e, ir.Impulse):
        return f"IMPULS({expr_text(model, e.start)}, {expr_text(model, e.period)})"
    return "?"
