"""The parts of a program in ACSL form (contract section 9), and its names.

`Parts.read` walks the nested blocks once: INITIAL sections in file order (wherever
they stand, inside DYNAMIC or DERIVATIVE too), DYNAMIC's own statements, every
DERIVATIVE section merged into one sorted block, the DISCRETE sections (in the
program, DYNAMIC or DERIVATIVE) with their INTERVAL, TERMINAL sections, and the
declarations, which are global wherever they stand (a CONSTANT inside DERIVATIVE
is a constant of the program, as ACSL has it). With no section keyword at all,
everything is DERIVATIVE.

`rename` gives time its one internal name: T (or the VARIABLE's name) and TIME
are time; a listing that assigns TIME has a variable of that name, kept as TIME_.
In ACSL form `true` and `false` are the logical literals.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..diagnostics import Reporter, Span
from ..language import ACSL_TIME, TIME
from ..parse import syntax as ast

# declarations and data: global wherever they stand
DECLARATIONS = (ast.Data, ast.Timer, ast.Method, ast.Tolerance, ast.Report, ast.Label,
                ast.Title, ast.Finish, ast.Table, ast.Declare, ast.Cinterval, ast.Control,
                ast.Variable)
EXECUTABLE = (ast.Assign, ast.If, ast.Loop, ast.Procedural, ast.Termt, ast.Schedule)
# a user variable named TIME (ACSL's time is T): kept under this name
USER_TIME = "TIME_"


@dataclass
class Parts:
    initial: list[tuple[list, Span]] = field(default_factory=list)
    dynamic: list = field(default_factory=list)
    derivative: list = field(default_factory=list)
    discretes: dict[str, tuple[list, Span]] = field(default_factory=dict)
    intervals: dict[str, ast.Interval] = field(default_factory=dict)  # DISCRETE -> INTERVAL
    terminal: list[tuple[list, Span]] = field(default_factory=list)
    declarations: list = field(default_factory=list)
    functions: list[ast.FunctionDef] = field(default_factory=list)
    sections: bool = False  # any section keyword at all
    derivatives: int = 0  # DERIVATIVE sections (they merge into one)
    algorithms: list[tuple[ast.Control, str]] = field(default_factory=list)  # and where

    @classmethod
    def read(cls, program: ast.Program, rep: Reporter) -> Parts:
        parts = cls()
        top = parts.walk(program.statements, "PROGRAM", rep)
        if top and parts.sections:
            for st in top:
                rep.error("outside the sections only declarations may stand", st.span,
                          "put it in INITIAL, DYNAMIC, DERIVATIVE, DISCRETE or TERMINAL")
        elif top:
            parts.derivative = top  # no section keyword at all: all is DERIVATIVE
        if len(parts.algorithms) > 1 or (parts.derivatives > 1 and any(
                where == "DERIVATIVE" for _, where in parts.algorithms)):
            st = parts.algorithms[-1][0]
            rep.error(f"a per-section ALGORITHM (line {st.span.line}): not supported",
                      st.span, "every DERIVATIVE section is one sorted block run by one "
                      "method: keep one ALGORITHM statement")
        return parts

    def walk(self, body, where: str, rep: Reporter) -> list:
        """The executable statements of one level; blocks and declarations recorded."""
        out = []
        for st in body:
            if isinstance(st, ast.Block):
                self.block(st, where, rep)
            elif isinstance(st, DECLARATIONS):
                self.declarations.append(st)
                if isinstance(st, ast.Control) and st.keyword == "ALGORITHM":
                    self.algorithms.append((st, where))
            elif isinstance(st, ast.Interval):
                if not where.startswith("DISCRETE "):
                    rep.error("INTERVAL stands in a DISCRETE section", st.span,
                              "DISCRETE name ... INTERVAL v = dt ... END runs every dt")
                else:
                    self.intervals[where[9:]] = st
            elif isinstance(st, ast.FunctionDef):
                if where != "PROGRAM":
                    rep.error("a FUNCTION is defined at the top of the program", st.span,
                              "move FUNCTION ... END out of the section")
                self.functions.append(st)
            elif isinstance(st, EXECUTABLE):
                out.append(st)
            else:
                rep.error(f"{type(st).__name__.upper()} cannot stand in the ACSL form",
                          st.span)
        return out

    def block(self, st: ast.Block, where: str, rep: Reporter) -> None:
        self.sections = True
        kind = st.kind
        allowed = {"DYNAMIC": ("PROGRAM",), "DERIVATIVE": ("PROGRAM", "DYNAMIC"),
                   "DISCRETE": ("PROGRAM", "DYNAMIC", "DERIVATIVE"),
                   "TERMINAL": ("PROGRAM", "DYNAMIC")}.get(kind)
        if allowed is not None and where not in allowed:
            rep.error(f"{kind} cannot stand inside {where.split()[0]}", st.span,
                      f"{kind} stands in " + " or ".join(allowed))
        if kind == "INITIAL":
            self.initial.append((self.walk(st.body, "INITIAL", rep), st.span))
        elif kind == "DYNAMIC":
            self.dynamic.extend(self.walk(st.body, "DYNAMIC", rep))
        elif kind == "DERIVATIVE":
            self.derivatives += 1
            self.derivative.extend(self.walk(st.body, "DERIVATIVE", rep))
        elif kind == "TERMINAL":
            self.terminal.append((self.walk(st.body, "TERMINAL", rep), st.span))
        elif kind == "DISCRETE":
            if st.name is None:
                rep.error("a DISCRETE section needs a name", st.span,
                          "DISCRETE name ... END; SCHEDULE name .AT. t runs it")
                return
            if st.name in self.discretes:
                rep.error(f"DISCRETE {st.name} is defined twice", st.span,
                          f"first at line {self.discretes[st.name][1].line}")
                return
            self.discretes[st.name] = (self.walk(st.body, f"DISCRETE {st.name}", rep), st.span)

    # -------------------------------------------------------------------- names
    def statements(self):
        """Every statement, for the name survey."""
        yield from self.declarations
        yield from self.dynamic
        yield from self.derivative
        yield from self.intervals.values()
        for body, _ in (*self.initial, *self.terminal, *self.discretes.values()):
            yield from body


def assigned_anywhere(parts: Parts) -> set[str]:
    out: set[str] = set()
    for st in parts.statements():
        for node in ast.walk(st):
            if isinstance(node, ast.Assign):
                out.update(node.targets)
            elif isinstance(node, ast.Loop):
                out.add(node.var)
    return out


def time_names(parts: Parts, data: set[str]) -> dict[str, ast.Node | str]:
    """The renaming that gives time its internal name (see the module's docstring)."""
    variable = next((d for d in parts.declarations if isinstance(d, ast.Variable)), None)
    assigned = assigned_anywhere(parts)
    mapping: dict[str, ast.Node | str] = {}
    if TIME in assigned or TIME in data:
        mapping[TIME] = USER_TIME
    name = variable.name if variable is not None else ACSL_TIME
    if name not in assigned and name not in data:
        mapping[name] = TIME
    for word, value in (("TRUE", 1.0), ("FALSE", 0.0)):
        if word not in assigned and word not in data:
            mapping[word] = ast.Num(value, Span(0, 0), f".{word}.")
    return mapping


class Renamer:
    """Rebuilds statements with names mapped (a name -> a name, or an expression)."""

    def __init__(self, mapping: dict[str, ast.Node | str]) -> None:
        self.mapping = mapping

    def name(self, n: str) -> str:
        to = self.mapping.get(n, n)
        return to if isinstance(to, str) else n

    def names(self, ns) -> tuple[str, ...]:
        return tuple(self.name(n) for n in ns)

    def expr(self, e):
        if e is None:
            return None
        if isinstance(e, ast.Name):
            to = self.mapping.get(e.name)
            if to is None:
                return e
            return ast.Name(to, e.span) if isinstance(to, str) else replace(to, span=e.span)
        if isinstance(e, ast.Call):
            return replace(e, args=tuple(self.expr(a) for a in e.args))
        if isinstance(e, ast.BinOp):
            return replace(e, left=self.expr(e.left), right=self.expr(e.right))
        if isinstance(e, (ast.Neg, ast.Not)):
            return replace(e, operand=self.expr(e.operand))
        return e

    def body(self, body) -> list:
        return [self.statement(st) for st in body]

    def settings(self, settings):
        return tuple(replace(s, name=self.name(s.name)) for s in settings)

    def statement(self, st):  # noqa: C901 - one line per statement class
        if isinstance(st, ast.Assign):
            return replace(st, targets=self.names(st.targets), expr=self.expr(st.expr))
        if isinstance(st, ast.If):
            return replace(st, branches=tuple(
                replace(b, cond=self.expr(b.cond), body=tuple(self.body(b.body)))
                for b in st.branches))
        if isinstance(st, ast.Loop):
            return replace(st, var=self.name(st.var), start=self.expr(st.start),
                           stop=self.expr(st.stop), step=self.expr(st.step),
                           body=tuple(self.body(st.body)))
        if isinstance(st, ast.Procedural):
            return replace(st, outputs=self.names(st.outputs), inputs=self.names(st.inputs),
                           body=tuple(self.body(st.body)))
        if isinstance(st, (ast.Termt, ast.Schedule)):
            return replace(st, expr=self.expr(st.expr))
        if isinstance(st, (ast.Interval, ast.Cinterval)):
            return replace(st, name=self.name(st.name), expr=self.expr(st.expr))
        if isinstance(st, ast.Data):
            return replace(st, items=tuple(replace(i, name=self.name(i.name))
                                           for i in st.items))
        if isinstance(st, ast.Report):
            return replace(st, names=self.names(st.names),
                           x=self.name(st.x) if st.x is not None else None)
        if isinstance(st, ast.Declare):
            return replace(st, names=self.names(st.names))
        if isinstance(st, (ast.Control, ast.Finish, ast.Timer)):
            return replace(st, settings=self.settings(st.settings))
        if isinstance(st, ast.Tolerance):
            return replace(st, settings=self.settings(st.settings))
        return st

    def parts(self, parts: Parts) -> Parts:
        return Parts(
            initial=[(self.body(b), s) for b, s in parts.initial],
            dynamic=self.body(parts.dynamic), derivative=self.body(parts.derivative),
            discretes={k: (self.body(b), s) for k, (b, s) in parts.discretes.items()},
            intervals={k: self.statement(v) for k, v in parts.intervals.items()},
            terminal=[(self.body(b), s) for b, s in parts.terminal],
            declarations=self.body(parts.declarations), functions=parts.functions,
            sections=parts.sections)
