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
from ..library import Kind, lookup
from ..parse import syntax as ast
from .code import assigned_names, statement_reads
from .lower import arguments_of

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
                out.append(self.hoisted(st))
            elif isinstance(st, ast.SetValue):
                rep.error("FST's SET belongs to the FST (CSMP) form", st.span,
                          f"in ACSL form assign it in INITIAL ({st.target} = ...) and "
                          "change it in a DISCRETE section")
            else:
                rep.error(f"{type(st).__name__.upper()} cannot stand in the ACSL form",
                          st.span)
        return out

    def hoisted(self, st):
        """st with the declarations inside its blocks (a CONSTANT in a PROCEDURAL, as
        Molly writes them) taken out to the program's: a translator reads them wherever
        they stand."""
        def body(statements) -> list:
            kept = []
            for s in statements:
                if isinstance(s, DECLARATIONS):
                    self.declarations.append(s)
                else:
                    kept.append(self.hoisted(s) if isinstance(s, EXECUTABLE) else s)
            return kept

        return ast.with_bodies(st, body)

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
            if st.name is None and not st.body:
                return  # (an empty one, a template's placeholder: the EPA lead model's)
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


class ImplicitArguments(Renamer):
    """Every call of a FUNCTION in `extra` passes the program's variables that function
    reads as arguments after its own (`globals_as_arguments`)."""

    def __init__(self, extra: dict[str, tuple[str, ...]]) -> None:
        super().__init__({})
        self.extra = extra

    def expr(self, e):
        e = super().expr(e)
        if isinstance(e, ast.Call) and e.func in self.extra:
            return replace(e, args=e.args + tuple(ast.Name(n, e.span)
                                                  for n in self.extra[e.func]))
        return e


def globals_as_arguments(parts: Parts, data: set[str]) -> Parts:
    """A Magnolia FUNCTION sees the program's variables as they are where it is called
    (Peters 2008's `kpu = (Dvow*...)` reads Dvow, which INITIAL computes): each one it
    reads becomes an argument every call passes, so the call's value and, in sorted
    code, its place in the order follow that variable. A data value it reads is an
    argument too: runs that differ in it share one build (a sweep, a Monte Carlo),
    and each call passes the run's own value. Names the program defines nowhere stay
    what the check says of them."""
    if not parts.functions:
        return parts
    defined = assigned_anywhere(parts) | {TIME}
    extra: dict[str, tuple[str, ...]] = {f.name: () for f in parts.functions}
    while True:  # (a function calling another takes the other's too)
        found = {}
        for f in parts.functions:
            own = set(f.params) | set(assigned_names(f.body))
            reads = statement_reads(f.body)
            reads += [n for st in f.body for node in ast.walk(st)
                      if isinstance(node, ast.Call) for n in extra.get(node.func, ())]
            found[f.name] = tuple(dict.fromkeys(
                n for n in reads if (n in defined or n in data) and n not in own))
        if found == extra:
            break
        extra = found
    extra = {k: v for k, v in extra.items() if v}
    if not extra:
        return parts
    calls = ImplicitArguments(extra)
    rebuilt = calls.parts(parts)
    rebuilt.functions = [replace(f, params=f.params + extra.get(f.name, ()),
                                 body=tuple(calls.body(f.body))) for f in parts.functions]
    return rebuilt


def initial_values_from_constants(parts: Parts, data: set[str]) -> Parts:
    """An initial value (INTEG's) that reads a name DERIVATIVE computes from constants
    alone (AALD's `HTOTALDO1 = INTEG(RHDO1, HT0DO1)`, `HT0DO1 = HFREE0*(...)`,
    `HFREE0 = 10**(-PHINIT)`): those equations hold one value for the whole run, so
    they are computed once, at the end of INITIAL, where the initial values are read.
    Only equations of constants (data values no running code assigns, INITIAL's
    values, PI and other such equations) through plain functions move."""
    running = set(assigned_names(parts.dynamic))
    for body, _ in parts.discretes.values():
        running |= set(assigned_names(body))
    fixed = ((data | {n for b, _ in parts.initial for n in assigned_names(b)} | {"PI"})
             - running)
    single = {}  # name -> its one DERIVATIVE equation, when it is a plain one
    count: dict[str, int] = {}
    for st in parts.derivative:
        for n in assigned_names([st]):
            count[n] = count.get(n, 0) + 1
        if isinstance(st, ast.Assign) and len(st.targets) == 1 and all(
                getattr(lookup(c.func, len(c.args)), "kind", None) is Kind.MATH
                for c in ast.walk(st.expr) if isinstance(c, ast.Call)):
            single[st.targets[0]] = st
    single = {n: st for n, st in single.items() if count[n] == 1 and n not in fixed}

    def reads(st) -> set[str]:
        return set(statement_reads([st]))

    constant = set(single)
    while True:  # (those that read only constants, or others of these)
        keep = {n for n in constant if reads(single[n]) <= fixed | constant}
        if keep == constant:
            break
        constant = keep
    wanted: list[str] = []
    # (the arguments the states' initial values read: INTEG's IC, ...)
    todo = [node.name for st in parts.derivative for call in ast.walk(st)
            if isinstance(call, ast.Call)
            for spec in getattr(lookup(call.func, len(call.args)), "states", ())
            for i in arguments_of(spec.ic) if i < len(call.args)
            for node in ast.walk(call.args[i]) if isinstance(node, ast.Name)]
    while todo:
        n = todo.pop()
        if n in constant and n not in wanted:
            wanted.append(n)
            todo.extend(reads(single[n]))
    if not wanted:
        return parts
    order: list[str] = []  # (each after what it reads)
    while len(order) < len(wanted):
        order += [n for n in wanted if n not in order
                  and reads(single[n]) & set(wanted) <= set(order)]
    moved = [single[n] for n in order]
    return replace(parts, derivative=[st for st in parts.derivative if st not in moved],
                   initial=[*parts.initial, (moved, moved[0].span)])
