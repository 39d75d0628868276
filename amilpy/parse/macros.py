"""MACROs expanded, the last step of reading: CSMP III's (contract section 13, below)
and ACSL's (`AcslExpander`).

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
    # (an argument read as an array, X(I) or X[I], or as a table, F(X): the call's
    # name stands there; an ACSL MACRO's argument given as a name is in `values`)
    key = "func" if isinstance(expr, ast.Call) else "name" if isinstance(expr, ast.Index) \
        else None
    if key is not None:
        called = getattr(expr, key)
        given = values.get(called)
        if isinstance(given, ast.Name):
            changes[key] = given.name
        elif called in names:
            changes[key] = names[called]
    for field in expr.child_fields:
        value = getattr(expr, field)
        if isinstance(value, tuple):
            changes[field] = tuple(_substitute(v, names, values) for v in value)
        else:
            changes[field] = _substitute(value, names, values)
    return replace(expr, **changes) if changes else expr


class AcslExpander:
    """ACSL's MACROs (`Macro.acsl`): defined anywhere in the program (or before it),
    called as a statement NAME(e1, e2, ...) -- or A1, A2 = NAME(e3, ...), whose names
    before '=' are the first arguments -- wherever a statement may stand. An argument
    the body assigns must be given a name (the call's variable); the others stand for
    the call's expressions (as a whole: an argument A + B is (A + B) wherever the body
    reads it). Arguments left out at the end take their MACRO STANDVAL values. Names
    listed in MACRO REDEFINE are each call's own (`NAME#k.X`); every other name of the
    body is the program's, as ACSL has it."""

    def __init__(self, errors: list[Diagnostic], acsl: bool, csmp: dict[str, ast.Macro]
                 ) -> None:
        self.errors = errors
        self.acsl = acsl  # (the listing's form, for the message of a call of no MACRO)
        self.csmp = csmp  # CSMP III's MACROs by name (called otherwise)
        self.macros: dict[str, ast.Macro] = {}
        self.rejected: set[str] = set()
        self.calls: dict[str, int] = {}
        self.call_spans: dict[str, list] = {}
        self.made = 0

    def collect(self, statements) -> list:
        """The statements without the ACSL MACROs they define (kept in `macros`)."""
        out = []
        for st in statements:
            if isinstance(st, ast.Macro) and st.acsl:
                if st.name in self.macros:
                    self.errors.append(Diagnostic(
                        f"MACRO {st.name} is defined twice", st.span,
                        f"the first definition is at line {self.macros[st.name].span.line}"))
                elif self.well_formed(st):
                    self.macros[st.name] = replace(st, body=tuple(self.collect(st.body)))
                else:
                    self.rejected.add(st.name)  # (its calls: nothing more to say)
                continue
            out.append(ast.with_bodies(st, self.collect))
        return out

    def well_formed(self, macro: ast.Macro) -> bool:
        """A MACRO whose name no built-in function, reserved or refused word has (a call
        would mean two things), with its parameters once each, and STANDVAL values for
        parameters only."""
        from ..language import REFUSED, RESERVED, STATEMENT_KEYWORDS
        from ..library import callable_names

        taken = "a function" if macro.name in callable_names() else \
            "reserved" if macro.name in RESERVED else \
            "a keyword" if macro.name in REFUSED or macro.name in STATEMENT_KEYWORDS else None
        if taken is not None:
            self.errors.append(Diagnostic(
                f"MACRO {macro.name}: {macro.name} is {taken}, which a MACRO of that name "
                "would hide", macro.span, "give the MACRO another name"))
            return False
        seen: set[str] = set()
        for p in macro.params:
            if p in seen:
                self.errors.append(Diagnostic(
                    f"MACRO {macro.name} names its argument {p} twice", macro.span,
                    "give each argument its own name"))
                return False
            seen.add(p)
        for st in macro.body:
            for node in ast.walk(st):
                if isinstance(node, ast.MacroDirective) and node is not st:
                    self.errors.append(Diagnostic(
                        f"MACRO {node.kind} stands in the MACRO's own body, not inside a "
                        "block of it", node.span, f"move it up to the lines after MACRO "
                        f"{macro.name}(...)"))
                    return False
        stray = [n for n, _ in macro.defaults if n not in seen]
        if stray:
            self.errors.append(Diagnostic(
                f"MACRO STANDVAL {', '.join(stray)}: no argument of MACRO {macro.name} "
                f"({', '.join(macro.params)})", macro.span,
                "give STANDVAL values to the MACRO's own arguments"))
            return False
        return True

    def expand(self, statements, calling: tuple[str, ...] = ()) -> list:
        out: list = []
        for st in statements:
            out.extend(self.statement(st, calling))
        return out

    def statement(self, st, calling: tuple[str, ...]) -> list:
        if isinstance(st, ast.MacroDirective):
            self.errors.append(Diagnostic(
                f"MACRO {st.kind} stands inside a MACRO NAME(...) ... MACRO END", st.span,
                "move it into the MACRO it belongs to"))
            return []
        if isinstance(st, ast.MacroCall):
            return self.call(st.name, (), st.args, st.span, calling)
        if isinstance(st, ast.Assign) and isinstance(st.expr, ast.Call) and \
                st.expr.func in self.macros:
            if st.subscripts:
                self.errors.append(Diagnostic(
                    f"MACRO {st.expr.func} gives its values to names, not to an array's "
                    "element", st.span, f"write {st.expr.func}(NAME, ...), then "
                    f"{st.targets[0]}(...) = NAME"))
                return []
            outputs = tuple(ast.Name(t, sp) for t, sp in
                            zip(st.targets, st.target_spans, strict=True))
            return self.call(st.expr.func, outputs, st.expr.args, st.span, calling)
        for node in _expressions(st):
            for inner in ast.walk(node):
                if isinstance(inner, ast.Call) and inner.func in self.macros:
                    self.errors.append(Diagnostic(
                        f"MACRO {inner.func} is called inside an expression", inner.span,
                        f"call it as a statement of its own: {inner.func}(...), or NAME = "
                        f"{inner.func}(...), then use NAME"))
        return [ast.with_bodies(st, lambda body: self.expand(body, calling))]

    def call(self, name: str, outputs: tuple, args: tuple, span, calling) -> list:
        macro = self.macros.get(name)
        if macro is None and name in self.rejected:
            return []
        if macro is None:
            csmp = self.csmp.get(name)
            if csmp is not None:
                signature = f"{', '.join(csmp.outputs)} = {name}({', '.join(csmp.params)})"
                self.errors.append(Diagnostic(
                    f"MACRO {name} is CSMP III's: it is called {signature}", span,
                    f"write {signature} with your names and expressions"))
            elif not self.acsl:
                self.errors.append(Diagnostic(
                    f"{name}(...) is no statement of the CSMP form", span,
                    f"write NAME = {name}(...) to use a function's value"))
            else:
                self.errors.append(Diagnostic(
                    f"{name}(...) as a statement calls an ACSL MACRO, and no MACRO {name} is "
                    "defined", span, f"define MACRO {name}(A1, A2, ...) ... MACRO END, or "
                    f"write NAME = {name}(...) to use a function's value"))
            return []
        if name in calling:
            self.errors.append(Diagnostic(
                f"MACRO {name} calls itself" + (f" (through {', '.join(calling)})"
                                                if calling[-1] != name else ""),
                span, "a MACRO may call other MACROs, not itself"))
            return []
        given = outputs + tuple(args)
        defaults = dict(macro.defaults)
        signature = f"MACRO {name}({', '.join(macro.params)}) (line {macro.span.line})"
        if len(given) > len(macro.params) or any(
                p not in defaults for p in macro.params[len(given):]):
            missing = [p for p in macro.params[len(given):] if p not in defaults]
            self.errors.append(Diagnostic(
                f"{name} takes {len(macro.params)} argument(s), "
                + (f"{len(given)} given" if len(given) > len(macro.params) else
                   f"and {', '.join(missing)} {'has' if len(missing) == 1 else 'have'} no "
                   "MACRO STANDVAL value")
                + f": {signature}", span, f"write {name}({', '.join(macro.params)}) with "
                "your names and expressions"))
            return []
        values = dict(zip(macro.params, given, strict=False))
        values |= {p: ast.Num(defaults[p], span, repr(defaults[p]))
                   for p in macro.params[len(given):]}
        self.calls[name] = k = self.calls.get(name, 0) + 1
        self.call_spans.setdefault(name, []).append(span)
        names = {n: f"{name}#{k}.{n}" for n in macro.local}
        # (each call's labels its own, as MACRO RELABEL would make them: a GO TO in the
        # body jumps within its own call)
        names |= {_LABEL + x.label: f"{name}#{k}.{x.label}" for st in macro.body
                  for x in ast.walk(st) if isinstance(x, ast.Target)}
        for p in sorted(_assigned(macro.body) & set(macro.params)):
            actual = values.pop(p)
            if not isinstance(actual, ast.Name):
                self.errors.append(Diagnostic(
                    f"argument {p} of MACRO {name} is assigned in it: the call must give a "
                    "name there", span, f"{signature}: pass a variable as {p}"))
                return []
            names[p] = actual.name
        body = [_rename(st, names, values) for st in macro.body]
        self.made += len(body)
        if self.made > MAX_EXPANSIONS:
            self.errors.append(Diagnostic(
                f"the MACRO calls expand to more than {MAX_EXPANSIONS} statements", span,
                "call fewer MACROs, or MACROs with fewer statements"))
            return []
        return self.expand(body, calling + (name,))


def _assigned(body) -> set[str]:
    """The names a MACRO body gives values to (assignments, loop variables, PROCEDURAL
    outputs), at any depth."""
    out: set[str] = set()
    for st in body:
        for node in ast.walk(st) if isinstance(st, ast.Node) else ():
            if isinstance(node, ast.Assign):
                out.update(node.targets)
            elif isinstance(node, ast.Loop):
                out.add(node.var)
            elif isinstance(node, ast.Procedural):
                out.update(node.outputs)
    return out


_LABEL = "label "  # (a label's key among a call's names: no name has a blank)


def _rename(st, names: dict[str, str], values: dict[str, ast.Node]):
    """A statement of an ACSL MACRO's body for one call: names renamed, arguments
    replaced by the call's expressions."""
    def expr(e):
        return None if e is None else _substitute(e, names, values)

    def name(n: str) -> str:
        return names.get(n, n)

    def name_of(n: str) -> str:
        """A name the statement holds as text (a section, an INTERVAL, a declared name):
        an argument's name at the call, a REDEFINE'd name the call's own."""
        given = values.get(n)
        return given.name if isinstance(given, ast.Name) else names.get(n, n)

    def reads(n: str) -> tuple[str, ...]:
        if n in values:  # (a PROCEDURAL's input given as an expression: what it reads)
            return tuple(x.name for x in ast.walk(values[n]) if isinstance(x, ast.Name))
        return (name(n),)

    def body(statements):
        return tuple(_rename(s, names, values) for s in statements)

    if isinstance(st, ast.Assign):
        return replace(st, targets=tuple(name(t) for t in st.targets), expr=expr(st.expr),
                       subscripts=tuple(expr(e) for e in st.subscripts))
    if isinstance(st, ast.MacroCall):
        return replace(st, args=tuple(expr(a) for a in st.args))
    if isinstance(st, ast.If):
        return replace(st, branches=tuple(replace(b, cond=expr(b.cond), body=body(b.body))
                                          for b in st.branches))
    if isinstance(st, ast.Procedural):
        return replace(st, outputs=tuple(name(o) for o in st.outputs),
                       inputs=tuple(dict.fromkeys(r for i in st.inputs for r in reads(i))),
                       body=body(st.body))
    if isinstance(st, ast.Loop):
        return replace(st, var=name(st.var), start=expr(st.start), stop=expr(st.stop),
                       step=expr(st.step), body=body(st.body))
    if isinstance(st, ast.Block):
        return replace(st, body=body(st.body))
    if isinstance(st, ast.Schedule):
        return replace(st, section=name_of(st.section), expr=expr(st.expr))
    if isinstance(st, (ast.Interval, ast.Cinterval)):
        return replace(st, name=name_of(st.name), expr=expr(st.expr))
    if isinstance(st, ast.Termt):
        return replace(st, expr=expr(st.expr))
    if isinstance(st, (ast.GoTo, ast.Target)):
        return replace(st, label=names.get(_LABEL + st.label, st.label))
    if isinstance(st, ast.Data):
        return replace(st, items=tuple(replace(i, name=name_of(i.name)) for i in st.items))
    if isinstance(st, ast.Declare):
        return replace(st, names=tuple(name_of(n) for n in st.names),
                       sizes=tuple(tuple(expr(e) for e in dims) for dims in st.sizes))
    return st


def expand(statements: list, errors: list[Diagnostic], acsl_form: bool = False
           ) -> tuple[list, tuple]:
    """The top-level statements with every MACRO call expanded, the MACROs removed;
    and (name, first line, last line, call spans) of each MACRO (`Program.macros`)."""
    expander = Expander(errors)
    csmp = {st.name: st for st in statements if isinstance(st, ast.Macro) and not st.acsl}
    acsl = AcslExpander(errors, acsl_form, csmp)
    with ast.deep_enough():
        out = acsl.expand(acsl.collect(statements)) if _any_acsl(statements) else statements
        out = expander.expand(out)
    # (the last line: of any statement in the body, a block's inner ones too)
    where = tuple((m.name, m.span.line,
                   max(n.span.end_line for st in (m, *m.body) for n in ast.walk(st)
                       if getattr(n, "span", None) is not None),
                   tuple(e.call_spans.get(m.name, ())))
                  for e in (expander, acsl) for m in e.macros.values())
    return out, where


def _expressions(st) -> tuple:
    """The expressions a statement holds itself (not those of the statements in its
    blocks: the expander goes through those one by one)."""
    if isinstance(st, ast.If):
        return tuple(b.cond for b in st.branches if b.cond is not None)
    if isinstance(st, ast.Loop):
        return tuple(e for e in (st.start, st.stop, st.step) if e is not None)
    if isinstance(st, ast.Assign):
        return (st.expr, *st.subscripts)
    if isinstance(st, ast.MacroCall):
        return st.args
    if isinstance(st, (ast.Termt, ast.Schedule, ast.Interval, ast.Cinterval)):
        return (st.expr,)
    return ()


def _any_acsl(statements) -> bool:
    """Whether ACSL MACROs are defined or called (else the statements stay as they
    are, not rebuilt)."""
    return any(isinstance(n, (ast.MacroCall, ast.MacroDirective)) or
               isinstance(n, ast.Macro) and n.acsl
               for st in statements for n in ast.walk_statements(st))


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
