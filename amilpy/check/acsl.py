"""Syntax of the ACSL form -> IR (contract sections 9-11).

DERIVATIVE is sorted like CSMP's DYNAMIC (an IF or PROCEDURAL block is one unit);
INITIAL, DYNAMIC's own statements, DISCRETE and TERMINAL are written-order code
(`ir.Code`), where a name may be reassigned. The names written-order code assigns
during a run are kept between instants (`Acsl.discrete_vars`, memory slots after
the memory functions'); the names only INITIAL assigns are constants of the run.
TERMT in DERIVATIVE and SCHEDULE .XP./.XN./.XZ. are surfaces, located; TERMT
elsewhere is tested when its code runs.
"""

from __future__ import annotations

from .. import ir
from ..diagnostics import Reporter, Span, did_you_mean
from ..language import DEFAULT_CINT, TIME
from ..library import Kind, lookup
from ..library.surfaces import classify
from ..parse import syntax as ast
from ..parse.syntax import deep_enough
from ..parse.unparse import expr_text
from . import order
from .code import CodeLowering, assigned_names
from .groups import DATA_STATEMENTS, RunGroups
from .lower import TEXT_LIMIT, Lowering
from .names import Names, reserved_names
from .parts import (
    Parts,
    Renamer,
    globals_as_arguments,
    initial_values_from_constants,
    time_names,
)
from .units import declared_stores, stored, unit_equations, written_text

_DIRECTION = {"XP": 1, "XN": -1, "XZ": 0}


@deep_enough()
def check_acsl(program: ast.Program, name: str | None = None) -> ir.Model:
    """The checked model of a program in ACSL form; raises AmilError with every fault."""
    rep = Reporter(program.path, program.source)
    parts = Parts.read(program, rep)
    data_names = {i.name for d in parts.declarations if isinstance(d, ast.Data)
                  for i in d.items}
    parts = Renamer(time_names(parts, data_names)).parts(parts)
    parts = globals_as_arguments(parts, data_names)
    parts = initial_values_from_constants(parts, data_names)
    return _Check(program, parts, rep).model(name or program.name or program.path)


class _Check:
    def __init__(self, program: ast.Program, parts: Parts, rep: Reporter) -> None:
        self.program, self.parts, self.rep = program, parts, rep
        decl = parts.declarations
        self.controls = [d for d in decl if isinstance(d, ast.Control)]
        control_data = [ast.Data("CONST", tuple(ast.DataItem(s.name, (s.value,), s.span)
                                                for s in c.settings), c.span)
                        for c in self.controls if c.keyword not in ("MERROR", "XERROR")]
        group = [d for d in decl if isinstance(d, DATA_STATEMENTS)] + control_data
        self.data = RunGroups(rep, reserved_names(program)).read([group],
                                                                 needs_fintim=False)
        self.names = Names(rep, program, self.data)
        self.names.reserved = (TIME,)
        self.names.functions = {f.name: len(f.params) for f in parts.functions}
        self.low = Lowering(rep)
        self.low.written = written_text(program.source)
        self.low.start = self.t0()
        self.code = CodeLowering(rep, self.low, self.names, declared_stores(decl))

    # ------------------------------------------------------------------ model
    def model(self, name: str | None) -> ir.Model:
        rep, parts, low, data = self.rep, self.parts, self.low, self.data
        dynamic, units, crossings = self.derivative()
        code = self.code
        initial = [code.written(b, "INITIAL", s) for b, s in parts.initial]
        own = code.written(parts.dynamic, "DYNAMIC")
        discretes = {k: self.discrete(k, b, s) for k, (b, s) in parts.discretes.items()}
        terminal = [code.written(b, "TERMINAL", s) for b, s in parts.terminal]
        functions = {f.name: self.function(f) for f in parts.functions}
        self.recursion(functions)
        cint_name, cint = self.cinterval()
        presets = {cint_name} | {iv.name for iv in parts.intervals.values()}
        states = {s.name for s in low.states if not s.hidden}
        initial_names = {n for c in initial for n in c.assigned}
        runtime = [n for c in (own, *(d.code for d in discretes.values()))
                   for n in c.assigned]
        kept = [n for n in dict.fromkeys(runtime) if n not in states]
        self.check_names(initial, own, discretes, terminal, states, initial_names, kept,
                         presets)
        dynamic = order.sort(dynamic, "DERIVATIVE", rep, low.switches, low.memories, units)
        terminations = list(code.terminations)
        for st, cond in self.termts + code.termts:
            if self.names.check_calls(st.expr, None, "DERIVATIVE"):
                low.termt(st, cond)
                terminations.append(ir.Termination("DERIVATIVE", low.written(st.expr.span)
                                                   or "", st.message, st.span))
        surfaces = {}
        for st in crossings:
            index = low.surface(low.expr(st.expr, "SCHEDULE"), ir.SurfaceKind.SIGN, None,
                                ir.Purpose.SCHEDULE, st.span,
                                f"SCHEDULE {st.section} .{st.kind}. at line {st.span.line}",
                                low.written(st.expr.span)
                                or expr_text(None, st.expr, TEXT_LIMIT))
            surfaces[index] = (st.section, _DIRECTION[st.kind])
        self.check_schedules(discretes)
        deriv = set(self.names.defined)
        acsl = ir.Acsl(
            initial=initial, dynamic=own, discretes=discretes, terminal=terminal,
            discrete_vars=kept, cint_name=cint_name, cint=cint, t0=self.t0(),
            termts=terminations, crossings=surfaces,
            priors=(deriv & initial_names) - set(kept), stores=dict(code.stores),
            functions=functions, bounded=bool(terminations) or "FINTIM" in data.runs[0].timer
            if data.runs else False,
            controls={c.keyword: s.name for c in self.controls for s in c.settings
                      if c.keyword not in ("MERROR", "XERROR")},
            control_spans={c.keyword: s.span for c in self.controls for s in c.settings})
        if not acsl.bounded:
            rep.error("nothing ends the run: no TERMT and no TIMER FINTIM", None,
                      "add TERMT(T >= TSTOP, 'time limit') to DERIVATIVE")
        low.states.sort(key=lambda s: (s.hidden, s.name))
        self.tolerances(states)
        for spec in data.runs:
            if not spec.titles and self.program.name:
                spec.titles = [f"{self.program.name}"]
        for spec in data.runs:  # no PRINT or OUTPUT: T and every state
            if not any(r.kind in ("PRINT", "OUTPUT") for r in spec.reports):
                spec.reports.append(ir.Report("PRINT", tuple(s.name for s in low.states
                                                             if not s.hidden), None,
                                              self.program.statements[0].span
                                              if self.program.statements else Span(1, 1)))
        model = ir.Model(
            name=name or "<listing>", path=self.program.path, source=self.program.source,
            initial=[], dynamic=dynamic, terminal=[], states=low.states,
            switches=low.switches, surfaces=low.guarded_surfaces(), memories=low.memories,
            runs=data.runs, data_names=data.names,
            spans={**data.spans, **self.names.defined}, data_kinds=data.kinds, units=units,
            acsl=acsl, warnings=low.warnings + self.warnings(initial, kept, initial_names),
            closed=low.closed, own_pi=self.program.own_pi)
        classify(model)
        rep.raise_if_any()
        return model

    # -------------------------------------------------------------- DERIVATIVE
    def derivative(self):
        dynamic: list[ir.Equation] = []
        units: list[ir.Unit] = []
        crossings: list[ast.Schedule] = []
        self.termts: list[tuple[ast.Termt, ast.Node | None]] = []
        names, low = self.names, self.low
        for st in self.parts.derivative:
            if isinstance(st, ast.Assign):
                st = stored(st, self.code.stores)
                ok = all([names.define(t, s, "DERIVATIVE")
                          for t, s in zip(st.targets, st.target_spans, strict=True)])
                if names.check_calls(st.expr, None, "DERIVATIVE") and ok:
                    dynamic.extend(low.statement(st))
            elif isinstance(st, (ast.If, ast.Procedural)):
                dynamic.extend(unit_equations(self.code, names, st, units, "DERIVATIVE"))
            elif isinstance(st, ast.Termt):
                self.termts.append((st, None))
            elif isinstance(st, ast.Schedule):
                if st.kind == "AT":
                    self.rep.error("SCHEDULE .AT. cannot stand in DERIVATIVE", st.span,
                                   "schedule in INITIAL, DYNAMIC or a DISCRETE section; in "
                                   "DERIVATIVE a crossing: SCHEDULE s .XP. expr")
                else:
                    crossings.append(st)
            elif isinstance(st, ast.Loop):
                self.rep.error("a loop cannot stand in DERIVATIVE", st.span,
                               "put it inside a PROCEDURAL block (one sorting unit)")
        return dynamic, units, crossings

    def discrete(self, name: str, body, span: Span) -> ir.Discrete:
        interval = self.parts.intervals.get(name)
        code = self.code.written(body, f"DISCRETE {name}", span)
        value = None
        if interval is not None:
            self.names.check_calls(interval.expr, (Kind.MATH,), "INTERVAL")
            value = self.low.expr(interval.expr, None, literal=True)
        return ir.Discrete(name, code, interval.name if interval else None, value, span)

    def function(self, f: ast.FunctionDef):
        """A FUNCTION definition: its parameters, result and written-order body."""
        code = self.code.written(f.body, f"FUNCTION {f.name}", f.span)
        allowed = set(f.params) | set(code.assigned) | set(self.data.names) | {"PI"}
        for st in code.body:
            for node in ast.walk(st):
                if isinstance(node, ast.Name) and node.name not in allowed:
                    self.rep.error(f"FUNCTION {f.name} reads {node.name}, which is not one of "
                                   "its arguments, its values or a constant", node.span,
                                   "a FUNCTION sees its arguments, its locals and constants; "
                                   f"pass {node.name} as an argument")
                if isinstance(node, ast.Call) and node.func == f.name:
                    self.rep.error(f"FUNCTION {f.name} calls itself", node.span,
                                   "recursion is not supported: write a loop")
        if f.result not in code.assigned:
            self.rep.error(f"FUNCTION {f.name} never assigns its result {f.result}", f.span)
        return (f.params, f.result, code)

    def recursion(self, functions: dict) -> None:
        """No FUNCTION may call itself through others (direct calls: `function`)."""
        calls = {name: {n.func for st in code.body for n in ast.walk(st)
                        if isinstance(n, ast.Call) and n.func in functions and n.func != name}
                 for name, (_, _, code) in functions.items()}
        for name in calls:
            seen, todo = set(), list(calls[name])
            while todo:
                g = todo.pop()
                if g == name:
                    span = next(f.span for f in self.parts.functions if f.name == name)
                    self.rep.error(f"FUNCTION {name} calls itself through other FUNCTIONs",
                                   span, "recursion is not supported: write a loop")
                    break
                if g not in seen:
                    seen.add(g)
                    todo.extend(calls.get(g, ()))

    def cinterval(self) -> tuple[str, ast.Node]:
        given = [d for d in self.parts.declarations if isinstance(d, ast.Cinterval)]
        if given:
            self.names.check_calls(given[-1].expr, (Kind.MATH,), "CINTERVAL")
            return given[-1].name, self.low.expr(given[-1].expr, None, literal=True)
        name = "CINT"
        if name in self.data.names:
            return name, ast.Name(name, Span(0, 0))
        return name, ast.Num(DEFAULT_CINT, Span(0, 0), str(DEFAULT_CINT))

    def t0(self) -> float:
        variable = next((d for d in self.parts.declarations if isinstance(d, ast.Variable)),
                        None)
        return variable.value if variable is not None and variable.value is not None else 0.0

    # ------------------------------------------------------------------- names
    def check_names(self, initial, own, discretes, terminal, states, initial_names, kept,
                    presets) -> None:
        names = self.names
        deriv = set(names.defined)
        clash = (initial_names | set(kept)) & set(self.data.names)
        for code in (*initial, own, *(d.code for d in discretes.values()), *terminal):
            for st in code.body:
                for node in ast.walk(st):
                    # (in INITIAL a CONSTANT may be given a new value, as Magnolia
                    # allows: the assignment wins from there on)
                    if isinstance(node, ir.Let) and node.target in clash and \
                            not any(code is c for c in initial):
                        self.rep.error(f"{node.target} is a CONSTANT and cannot be assigned",
                                       node.span, "give it its value in CONSTANT only, or "
                                       "rename the computed one")
                    if isinstance(node, ir.Let) and node.target == TIME:
                        names.define(TIME, node.span, "code")
        known = set(self.data.names) | states | deriv | initial_names | set(kept) | presets
        known |= {TIME, "PI"}
        terminal_names = {n for c in terminal for n in c.assigned}
        table_args = {id(n.args[0]) for st in self.parts.statements() for n in ast.walk(st)
                      if isinstance(n, ast.Call) and n.args
                      and getattr(lookup(n.func), "kind", None) == Kind.TABLE}
        for section, body in (("DERIVATIVE", self.parts.derivative),
                              ("DYNAMIC", self.parts.dynamic),
                              *(("INITIAL", b) for b, _ in self.parts.initial),
                              *(("DISCRETE", b) for b, _ in self.parts.discretes.values()),
                              *(("TERMINAL", b) for b, _ in self.parts.terminal),
                              ("INTERVAL", list(self.parts.intervals.values()))):
            here = known | (terminal_names if section == "TERMINAL" else set())
            here |= set(assigned_names(body))
            for st in body:
                for node in ast.walk(st):
                    if isinstance(node, ast.Name) and node.name not in here \
                            and id(node) not in table_args:
                        names.undefined(node, known | terminal_names)
        # a CONSTANT INITIAL gives a new value is its new value from there on; what is
        # computed before INITIAL runs (CINTERVAL) cannot see it: said, not ignored
        reassigned = clash & {n for code in initial for n in code.assigned}
        for d in self.parts.declarations:
            if isinstance(d, ast.Cinterval):
                for node in ast.walk(d.expr):
                    if isinstance(node, ast.Name) and node.name in reassigned:
                        self.rep.error(f"CINTERVAL uses {node.name}, which INITIAL gives a "
                                       "new value", node.span, f"assign {d.name} in INITIAL, "
                                       f"after {node.name}")
        before = set(self.data.names) | initial_names | presets | {"PI", TIME}
        for expr, what in self.low.before_run:
            for node in ast.walk(expr):
                if isinstance(node, ast.Name) and node.name not in before \
                        and node.name in known:
                    self.rep.error(f"{what} uses {node.name}, which changes in time",
                                   node.span, f"{what} must be a number, a constant or a "
                                   "value INITIAL computes")
        names.check_named(known, states)

    def check_schedules(self, discretes: dict[str, ir.Discrete]) -> None:
        for st in self.parts.statements():
            for node in ast.walk(st):
                if isinstance(node, ast.Schedule) and node.section not in discretes:
                    self.rep.error(f"SCHEDULE names {node.section}, which is no DISCRETE "
                                   "section", node.span,
                                   did_you_mean(node.section, discretes) or
                                   f"define it: DISCRETE {node.section} ... END")

    def tolerances(self, states: set[str]) -> None:
        """MERROR/XERROR: per state when a state is named, else for every state."""
        for c in self.controls:
            if c.keyword not in ("MERROR", "XERROR"):
                continue
            kind = "RELERR" if c.keyword == "MERROR" else "ABSERR"
            for s in c.settings:
                if not s.value > 0:
                    self.rep.error(f"{c.keyword} must be positive", s.span)
                for spec in self.data.runs:
                    if s.name in states:
                        (spec.relerr_each if kind == "RELERR" else spec.abserr_each)[
                            s.name] = s.value
                    elif kind == "RELERR":
                        spec.relerr = s.value
                    else:
                        spec.abserr = s.value

    # ---------------------------------------------------------------- warnings
    def warnings(self, initial, kept, initial_names) -> list:
        """INITIAL reading a name before it has a value; DERIVATIVE reading a kept name
        that starts at 0 because only a DISCRETE or DYNAMIC gives it a value."""
        out = []
        first: dict[str, Span] = {}
        for code in initial:
            for st in code.body:
                for node in ast.walk(st):
                    if isinstance(node, ir.Let):
                        first.setdefault(node.target, node.span)
        given = set(self.data.names) | {TIME, "PI", self.cinterval()[0]}
        given |= {iv.name for iv in self.parts.intervals.values()}
        for code in initial:
            for st in code.body:
                reads = [n for n in ast.walk(st) if isinstance(n, ast.Name)]
                # (a loop gives its variable a value before its body reads it)
                given |= {n.var for n in ast.walk(st) if isinstance(n, ir.ForLoop)}
                for node in reads:
                    if node.name not in given and node.name in first \
                            and first[node.name].line > node.span.line:
                        out.append(self.note(
                            f"{node.name} is read at line {node.span.line} before it has a "
                            f"value (first assigned at line {first[node.name].line}): it "
                            "reads 0.0", node.span))
                given |= {n.target for n in ast.walk(st) if isinstance(n, ir.Let)}
        zero = [n for n in kept if n not in initial_names]
        for st in self.parts.derivative:
            for node in ast.walk(st):
                if isinstance(node, ast.Name) and node.name in zero:
                    zero.remove(node.name)
                    out.append(self.note(
                        f"{node.name} starts at 0.0: only DYNAMIC or a DISCRETE section "
                        "gives it a value", node.span,
                        f"give it its starting value in INITIAL ({node.name} = ...)"))
        return out

    @staticmethod
    def note(message: str, span: Span, hint: str | None = None):
        from ..diagnostics import Diagnostic

        return Diagnostic(message, span, hint, "warning")

