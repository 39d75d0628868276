"""CSMP III's MACROs expanded (contract section 13): the last step of reading.

    MACRO Y = LAG2(T, X)          a call   A = LAG2(0.1, U)   becomes
       Y1 = REALPL(0., T, X)         LAG2#1.Y1 = REALPL(0., 0.1, U)
       Y  = REALPL(0., T, Y1)        A = REALPL(0., 0.1, LAG2#1.Y1)
    ENDMAC

A call is a statement `O1, O2 = NAME(e1, e2)` with as many outputs as the MACRO
defines. In the body, the outputs become the call's names, the parameters the
call's expressions, and every other name the body assigns a name of that call
alone, `NAME#k.X` (k counts the calls), which is how diagnostics and --show-python
show it; names the body only reads are the listing's. A body may call other MACROs
(expanded in turn), not itself. The expanded statements keep the spans of the body
lines, so a fault in them points at the MACRO's line, and the call's number in the
local names says which call it came from. No later stage sees a MACRO.
"""

from __future__ import annotations

from dataclasses import replace

from ..diagnostics import Diagnostic
from . import syntax as ast

MAX_EXPANSIONS = 10_000  # statements a listing's MACRO calls may expand to


class Expander:
    def __init__(self, errors: list[Diagnostic]) -> None:
        self.errors = errors
        self.macros: dict[str, ast.Macro] = {}
        self.calls: dict[str, int] = {}
        self.call_spans: dict[str, list] = {}
        self.made = 0

    def expand(self, statements: list) -> list:
        for st in statements:
            if isinstance(st, ast.Macro):
                if st.name in self.macros:
                    self.errors.append(Diagnostic(
                        f"MACRO {st.name} is defined twice", st.span,
                        f"the first definition is at line {self.macros[st.name].span.line}"))
                    continue
                self.check_body(st)
                self.macros[st.name] = st
        if not self.macros:
            return statements
        out: list = []
        for st in statements:
            if not isinstance(st, ast.Macro):
                out.extend(self.statement(st, ()))
        return out

    def check_body(self, macro: ast.Macro) -> None:
        for st in macro.body:
            if not isinstance(st, ast.Assign):
                self.errors.append(Diagnostic(
                    "a MACRO body holds assignments only", st.span,
                    f"end MACRO {macro.name} with ENDMAC before this statement"))
            else:
                for target, span in zip(st.targets, st.target_spans, strict=True):
                    if target in macro.params:
                        self.errors.append(Diagnostic(
                            f"MACRO {macro.name} assigns its parameter {target}", span,
                            "a parameter stands for the caller's expression: give the "
                            "value another name"))
        missing = [o for o in macro.outputs
                   if not any(o in getattr(st, "targets", ()) for st in macro.body)]
        for name in missing:
            self.errors.append(Diagnostic(f"MACRO {macro.name} never assigns its output "
                                          f"{name}", macro.span))

    def statement(self, st, calling: tuple[str, ...]) -> list:
        """The statement, or the statements its MACRO call expands to."""
        if isinstance(st, ast.If):
            return [replace(st, branches=tuple(
                replace(b, body=tuple(x for s in b.body for x in self.statement(s, calling)))
                for b in st.branches))]
        if not isinstance(st, ast.Assign):
            return [st]
        call = st.expr
        if not (isinstance(call, ast.Call) and call.func in self.macros):
            self.nested_call(st)
            return [st]
        macro = self.macros[call.func]
        if macro.name in calling:
            self.errors.append(Diagnostic(
                f"MACRO {macro.name} calls itself" + (f" (through {', '.join(calling)})"
                                                      if calling[-1] != macro.name else ""),
                call.span, "a MACRO may call other MACROs, not itself"))
            return []
        signature = f"{', '.join(macro.outputs)} = {macro.name}({', '.join(macro.params)})"
        if len(call.args) != len(macro.params) or len(st.targets) != len(macro.outputs):
            self.errors.append(Diagnostic(
                f"{macro.name} takes {len(macro.params)} argument(s) and gives "
                f"{len(macro.outputs)} value(s): MACRO {signature} (line {macro.span.line})",
                st.span, f"write {signature} with your names and expressions"))
            return []
        self.calls[macro.name] = k = self.calls.get(macro.name, 0) + 1
        self.call_spans.setdefault(macro.name, []).append(st.span)
        # (a body statement that is not an assignment is already an error: check_body)
        body_assigns = [s for s in macro.body if isinstance(s, ast.Assign)]
        assigned = {t for s in body_assigns for t in s.targets}
        names = {o: t for o, t in zip(macro.outputs, st.targets, strict=True)}
        names |= {n: f"{macro.name}#{k}.{n}" for n in assigned - set(macro.outputs)}
        values = dict(zip(macro.params, call.args, strict=True))
        out = []
        for body in body_assigns:
            self.made += 1
            if self.made > MAX_EXPANSIONS:
                self.errors.append(Diagnostic(
                    f"the MACRO calls expand to more than {MAX_EXPANSIONS} statements",
                    st.span, "call fewer MACROs, or MACROs with fewer statements"))
                return out
            expanded = ast.Assign(tuple(names[t] for t in body.targets), body.target_spans,
                                  _substitute(body.expr, names, values), body.span)
            out.extend(self.statement(expanded, calling + (macro.name,)))
        return out

    def nested_call(self, st: ast.Assign) -> None:
        for node in ast.walk(st.expr):
            if isinstance(node, ast.Call) and node.func in self.macros:
                self.errors.append(Diagnostic(
                    f"MACRO {node.func} is called inside an expression", node.span,
                    f"call it as a statement of its own: NAME = {node.func}(...), then use "
                    "NAME"))


def _substitute(expr: ast.Node, names: dict[str, str], values: dict[str, ast.Node]
                ) -> ast.Node:
    """expr with the parameters replaced by the call's expressions and the body's own
    names by the call's (recursive: `expand` runs with room for MAX_DEPTH levels)."""
    if isinstance(expr, ast.Name):
        if expr.name in values:
            return values[expr.name]
        return replace(expr, name=names[expr.name]) if expr.name in names else expr
    changes = {}
    for field in expr.child_fields:
        value = getattr(expr, field)
        if isinstance(value, tuple):
            changes[field] = tuple(_substitute(v, names, values) for v in value)
        else:
            changes[field] = _substitute(value, names, values)
    return replace(expr, **changes) if changes else expr


def expand(statements: list, errors: list[Diagnostic]) -> tuple[list, tuple]:
    """The top-level statements with every MACRO call expanded, the MACROs removed;
    and (name, first line, last line, call spans) of each MACRO (`Program.macros`)."""
    expander = Expander(errors)
    with ast.deep_enough():
        out = expander.expand(statements)
    where = tuple((m.name, m.span.line,
                   max([m.span.line] + [s.span.end_line for s in m.body]),
                   tuple(expander.call_spans.get(m.name, ())))
                  for m in expander.macros.values())
    return out, where


def in_macros(diagnostics: list[Diagnostic], macros) -> list[Diagnostic]:
    """Faults found in expanded MACRO bodies, once each (not once per call), with the
    calls they came through as related places."""
    out: list[Diagnostic] = []
    seen: set = set()
    for d in diagnostics:
        key = (d.message, d.span, d.hint)
        if key in seen:
            continue
        seen.add(key)
        for name, first, last, calls in macros:
            if d.span is not None and first <= d.span.line <= last and calls:
                d = replace(d, related=d.related + tuple(
                    (call, f"in MACRO {name}, called here") for call in calls))
        out.append(d)
    return out
