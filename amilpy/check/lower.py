"""Lowering: calls of simulation functions become IR, as their library entries say.

A state function gives states (named after the assigned variable, or hidden
names taken from the statement it stands in, so that statement order changes no
name); a switch, a memory function or IMPULS gives an instance and a value node.
Surfaces are interned: two with the same expression (spans aside), kind and
purpose are one `ir.Surface`, so a run has one mode for it wherever it stands.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from .. import ir
from ..diagnostics import Diagnostic, Reporter, Span
from ..language import TIME
from ..library import (
    BEFORE,
    RELATIONS,
    WEATHER_FUNC,
    WEATHER_HOLD,
    WEATHER_TABLE,
    Func,
    Kind,
    lookup,
)
from ..library.surfaces import constant_value
from ..library.templates import ARGUMENTS, instantiate, template_names
from ..parse import syntax as ast
from ..parse.syntax import Visitor
from ..parse.unparse import expr_text

# the longest surface text or argument text a description holds
TEXT_LIMIT = 60


def surface_text(template: str, call: ast.Call, states: tuple[str, ...] = (),
                 start: float = 0.0) -> str:
    """A surface as the listing writes it: the template over the call's own
    arguments ("W1", "TIME - T1", "X - P2")."""
    return expr_text(None, instantiate(template, call.args, call.span, states, start),
                     TEXT_LIMIT)


def describe(call: ast.Call, written: Callable[[Span], str | None] = lambda span: None
             ) -> str:
    """A switch for a reader: `FSW(W1, ...) at line 57` (the function and its first
    argument as written; where a block replaced its names by their values, the
    listing's own text of it, which `written` gives: AINT(W), not AINT(RSW(...)))."""
    first = expr_text(None, call.args[0], TEXT_LIMIT) if call.args else ""
    given = call.arg_spans[0] if call.args and call.arg_spans else None
    text = written(given) if given is not None and call.args[0].span != given else None
    if text:
        text = text.upper()
        first = text if len(text) <= TEXT_LIMIT else text[:TEXT_LIMIT - 3] + "..."
    more = ", ..." if len(call.args) > 1 else ""
    return f"{call.func}({first}{more}) at line {call.span.line}"


def arguments_of(template: str) -> set[int]:
    """The argument positions a template reads."""
    return {ARGUMENTS.index(c) for c in template_names(template) if len(c) == 1
            and c in ARGUMENTS}


class _Shape(Visitor):
    """A number per distinct expression structure (spans ignored; a function by its
    canonical name), memoised per node: shared subtrees are shaped once."""

    complete = ir.EXPRESSIONS

    def __init__(self) -> None:
        self.ids: dict[tuple, int] = {}
        self.memo: dict[int, tuple[ast.Node, int]] = {}

    def shape(self, node: ast.Node) -> int:
        hit = self.memo.get(id(node))
        if hit is not None and hit[0] is node:
            return hit[1]
        key = self.visit(node)
        number = self.ids.setdefault(key, len(self.ids))
        self.memo[id(node)] = (node, number)  # the node is kept: its id stays its own
        return number

    def visit_Num(self, e: ast.Num) -> tuple:
        return ("Num", e.value.hex() if isinstance(e.value, float) else e.value)

    def visit_Name(self, e: ast.Name) -> tuple:
        return ("Name", e.name)

    def visit_Call(self, e: ast.Call) -> tuple:
        func = lookup(e.func)
        return ("Call", func.name if func else e.func, *map(self.shape, e.args))

    def visit_BinOp(self, e: ast.BinOp) -> tuple:
        return ("BinOp", e.op, self.shape(e.left), self.shape(e.right))

    def visit_Neg(self, e: ast.Neg) -> tuple:
        return ("Neg", self.shape(e.operand))

    def visit_Not(self, e: ast.Not) -> tuple:
        return ("Not", self.shape(e.operand))

    def visit_UnitValue(self, e: ir.UnitValue) -> tuple:
        return ("Unit", e.unit, e.name)

    def visit_SwitchValue(self, e: ir.SwitchValue) -> tuple:
        return ("Switch", e.switch, e.output)

    def visit_MemoryValue(self, e: ir.MemoryValue) -> tuple:
        return ("Memory", e.memory)

    def visit_TableLookup(self, e: ir.TableLookup) -> tuple:
        return ("Table", e.table, e.func, self.shape(e.x))

    def visit_Impulse(self, e: ir.Impulse) -> tuple:
        return ("Impulse", self.shape(e.start), self.shape(e.period))


class Lowering:
    """The IR instances of one model, built while its statements are lowered."""

    def __init__(self, rep: Reporter) -> None:
        self.rep = rep
        self.states: list[ir.State] = []
        self.switches: list[ir.Switch] = []
        self.surfaces: list[ir.Surface] = []
        self.memories: list[ir.Memory] = []
        self.nslots = 0
        self.hidden_counts: dict[str, int] = {}
        # expressions needed before the run (initial values, DELAY's P), with what they are
        self.before_run: list[tuple[ast.Node, str]] = []
        self.shapes = _Shape()
        self.interned: dict[tuple, int] = {}
        # the listing's own text of a span (relational switches and TERMTs are
        # described as written: "T >= TSTOP"); None where no single line holds it
        self.written: Callable[[Span], str | None] = lambda span: None
        # the run's start as the listing declares it (ACSL's VARIABLE T = t0): a
        # library template's START (ACSL DELAY's turn from IC at t0 + TDL)
        self.start = 0.0
        self.warnings: list[Diagnostic] = []
        # FST's weather names the listing does not define itself, and those read
        self.weather: frozenset[str] = frozenset()
        self.weather_all: frozenset[str] = frozenset()  # (the listing's own too)
        self.weather_used: dict[str, list[Span]] = {}
        self.weather_memory: dict[str, int] = {}  # the memory holding each name's value
        self.closed: set[int] = set()  # TERMT surfaces true at zero (>=, <=)
        self.ending: set[int] = set()  # TERMT surfaces of a routine's STOP (`Model.ending`)
        # the condition of the IF branches whose code is being lowered (None: none),
        # and each surface's so far: the branches it is read on (`guarded_surfaces`)
        self.guard: ast.Node | None = None
        self.guards: dict[int, ast.Node | None] = {}

    def weather_value(self, name: str, span: Span) -> ir.MemoryValue:
        """A weather name's value: the day's, held from the last restart (library's
        WEATHER_HOLD), one memory per name."""
        self.weather_used.setdefault(name, []).append(span)
        if name not in self.weather_memory:
            day = ast.Call(WEATHER_FUNC, (ast.Name(WEATHER_TABLE + name, span),
                                          ast.Name(TIME, span)), span)
            self.weather_memory[name] = self.memory(ast.Call(WEATHER_HOLD, (day,), span), name)
        return ir.MemoryValue(self.weather_memory[name], span)

    def expr(self, expr: ast.Node, target: str | None, literal: bool = False) -> ast.Node:
        """An expression with its simulation-function calls lowered (`literal`: in
        INITIAL/TERMINAL or an initial value, where a switch is evaluated once)."""
        return _Lowerer(self, target, literal).visit(expr)

    def statement(self, st: ast.Assign) -> list[ir.Equation]:
        """The equations of one DYNAMIC assignment (none when it names a state)."""
        expr = st.expr
        func = lookup(expr.func, len(expr.args)) if isinstance(expr, ast.Call) else None
        if len(st.targets) == 2:
            if func is None or func.outputs != 2:
                self.rep.error("only OUTSW gives two values", st.span,
                               "write one assignment per variable")
                return []
            index = self.switch(expr, st.targets[0])
            return [ir.Equation(t, ir.SwitchValue(index, expr.span, k), st.span)
                    for k, t in enumerate(st.targets)]
        if len(st.targets) > 2:
            self.rep.error("at most two variables can be assigned together (OUTSW)", st.span)
            return []
        target = st.targets[0]
        if func is not None and func.kind == Kind.STATE:
            # a state function as the whole right-hand side: its state carries
            # the user's name where the output is the state (Y = REALPL(...))
            value = self.state_function(expr, target)
            if isinstance(value, ast.Name) and value.name == target:
                return []
            return [ir.Equation(target, value, st.span)]
        if func is not None and func.outputs == 2:
            self.rep.error("OUTSW gives two values: write Y1, Y2 = OUTSW(X, V)", st.span)
            return []
        return [ir.Equation(target, self.expr(expr, target), st.span)]

    def hidden(self, kind: str, owner: str | None) -> str:
        """A name for a state the listing does not name (a nested INTGRL, the
        inside of LEDLAG...): from the statement it sits in, so that the order of
        statements does not change the names (nor the order of the states)."""
        owner = owner or "?"
        self.hidden_counts[owner] = self.hidden_counts.get(owner, 0) + 1
        return f"{kind}#{owner}.{self.hidden_counts[owner]}"

    def args(self, call: ast.Call, owner: str | None, literal: set[int] = frozenset()) -> tuple:
        """The call's arguments lowered once (those in `literal` as initial values)."""
        return tuple(self.expr(a, owner, literal=i in literal) for i, a in enumerate(call.args))

    def note_before_run(self, func: Func, call: ast.Call) -> None:
        """Arguments that must be known before the run are checked like initial values."""
        for i in func.constant_args:
            self.before_run.append((call.args[i], f"{func.arg_names[i]} of {call.func}"))

    def state_function(self, call: ast.Call, target: str | None,
                       owner: str | None = None) -> ast.Node:
        """INTGRL, REALPL, LEDLAG, CMPXPL, MODINT...: the states of the entry, named
        after the assigned variable or hidden, and the call's value over them."""
        func = lookup(call.func, len(call.args))
        sp = call.span
        owner = target or owner or "?"
        in_ic = {i for s in func.states for i in arguments_of(s.ic)}
        others = (*(s.deriv for s in func.states), *func.values, *func.surfaces)
        args = self.args(call, owner, literal=in_ic - {i for t in others
                                                        for i in arguments_of(t)})
        named = [k == 0 and bool(target) and s.named for k, s in enumerate(func.states)]
        names = tuple(target if named[k] else self.hidden(s.tag, owner)
                      for k, s in enumerate(func.states))
        # a state function's surfaces (over its arguments and its own states) are
        # what its states' `runs` read (MODINT's hold and reset, LIMINT's bounds)
        modes = tuple(self.surface(instantiate(t, args, sp, names), func.surface_kind, None,
                                   ir.Purpose.SWITCH, sp, describe(call, self.written),
                                   surface_text(t, call, names))
                      for t in func.surfaces)
        for k, spec in enumerate(func.states):
            if arguments_of(spec.ic):
                self.before_run.append((instantiate(spec.ic, call.args, sp),
                                        "the initial value"))
            self.states.append(ir.State(
                names[k], instantiate(spec.ic, args, sp, names),
                instantiate(spec.deriv, args, sp, names), sp, not named[k],
                reset_surfaces=modes if spec.resets else (),
                modes=modes if spec.runs or spec.onto else (), runs=spec.runs,
                onto=tuple((instantiate(v, args, sp, names), when) for v, when in spec.onto)))
        return instantiate(func.values[0], args, sp, names)

    def surface(self, expr: ast.Node, kind: ir.SurfaceKind, owner: int | None,
                purpose: ir.Purpose, span: Span, description: str, text: str) -> int:
        """The index of the surface `expr` (a new one, or the one it shares);
        `text` is the expression as the listing writes it."""
        key = None
        if purpose in (ir.Purpose.SWITCH, ir.Purpose.MEMORY):
            key = (kind, purpose, self.shapes.shape(expr))
        index = self.interned.get(key) if key is not None else None
        if index is None:
            index = len(self.surfaces)
            self.surfaces.append(ir.Surface(index, expr, kind, owner, purpose,
                                            ir.Depends.STATE, span, description, text))
            if key is not None:
                self.interned[key] = index
            self.guards[index] = self.guard
        else:  # (read on these branches too: on either)
            old = self.guards[index]
            self.guards[index] = None if old is None or self.guard is None else \
                old if old == self.guard else ast.BinOp("OR", old, self.guard, span)
        return index

    def guarded_surfaces(self) -> list[ir.Surface]:
        """The surfaces, each a switch's read only on some branches of IF blocks with
        the condition of those branches (`ir.Surface.guard`) where that condition
        tests modes of surfaces before it alone (so the code that evaluates surfaces
        can test it from the modes, without computing anything else)."""
        relations = set(RELATIONS.values())

        def modes_only(e: ast.Node, k: int) -> bool:
            for n in ast.walk(e):
                if isinstance(n, ir.SwitchValue):
                    sw = self.switches[n.switch]
                    if sw.func not in relations or any(j >= k for j in sw.surfaces):
                        return False
                elif not (isinstance(n, (ast.Not, ast.Num)) or
                          (isinstance(n, ast.BinOp) and n.op in ("AND", "OR"))):
                    return False
            return True

        out = []
        for s in self.surfaces:
            g = self.guards.get(s.index)
            if g is not None and s.purpose is ir.Purpose.SWITCH and \
                    s.kind is ir.SurfaceKind.SIGN and modes_only(g, s.index):
                s = replace(s, guard=g)
            out.append(s)
        return out

    def memory(self, call: ast.Call, target: str | None) -> int:
        func = lookup(call.func, len(call.args))
        self.note_before_run(func, call)
        args = self.args(call, target)
        index = len(self.memories)
        surfaces = tuple(
            self.surface(instantiate(t, args, call.span, start=self.start),
                         func.surface_kind, index, ir.Purpose.MEMORY, call.span,
                         describe(call, self.written),
                         surface_text(t, call, start=self.start))
            for t in func.surfaces)
        nslots = int(constant_value(instantiate(func.memory.slots, call.args, call.span), {}))
        self.memories.append(ir.Memory(index, func.name, args, self.nslots, nslots, surfaces,
                                       call.span, target or "?", call.func))
        self.nslots += nslots
        return index

    def switch(self, call: ast.Call, target: str) -> int:
        func = lookup(call.func, len(call.args))
        description = describe(call, self.written)
        if func.folds and len(call.args) > 2:
            # AMAX1(A, B, C) is AMAX1(AMAX1(A, B), C): a switch per argument after the
            # first, each on the running result and the next argument
            inner = ast.Call(call.func, call.args[:-1], call.span)
            call = ast.Call(call.func, (inner, call.args[-1]), call.span)
        self.note_before_run(func, call)
        args = self.args(call, target)
        index = len(self.switches)
        surfaces = [self.surface(instantiate(t, args, call.span), func.surface_kind, index,
                                 ir.Purpose.SWITCH, call.span, description,
                                 surface_text(t, call))
                    for t in func.surfaces]
        self.switches.append(ir.Switch(index, func.name, args, tuple(surfaces), call.span,
                                       target, call.func))
        return index

    def relational(self, e: ast.BinOp, target: str | None) -> int:
        """A relational test of sorted code (`A > B`): a switch on A - B."""
        func = lookup(RELATIONS[e.op])
        args = (self.expr(e.left, target), self.expr(e.right, target))
        text = self.written(e.span) or expr_text(None, e, TEXT_LIMIT)
        index = len(self.switches)
        description = f"{text} at line {e.span.line}"
        left, right = (self.written(x.span) or expr_text(None, x, TEXT_LIMIT)
                       for x in (e.left, e.right))
        if not isinstance(e.right, (ast.Num, ast.Name, ast.Call)):
            right = f"({right})"
        zero = isinstance(e.right, ast.Num) and e.right.value == 0.0
        surface = self.surface(instantiate(func.surfaces[0], args, e.span), func.surface_kind,
                               index, ir.Purpose.SWITCH, e.span, description,
                               left if zero else f"{left} - {right}")
        self.switches.append(ir.Switch(index, func.name, args, (surface,), e.span,
                                       target or "?", e.op))
        return index

    def warn(self, message: str, span: Span, hint: str | None = None) -> None:
        if not any(w.span == span and w.message == message for w in self.warnings):
            self.warnings.append(Diagnostic(message, span, hint, "warning"))

    def finish(self, s: ast.Setting) -> None:
        """FINISH X = value: the run ends where X - value changes sign."""
        expr = ast.BinOp("-", ast.Name(s.name, s.span), ast.Num(s.value, s.span), s.span)
        self.surface(expr, ir.SurfaceKind.SIGN, None, ir.Purpose.FINISH, s.span,
                     f"FINISH {s.name}={s.value:g}", f"{s.name} - {s.value:g}")

    def termt(self, st: ast.Termt, cond: ast.Node | None = None, finish: bool = False) -> int:
        """TERMT(c [, 'message']): the run ends where c turns true (`cond`: c as the
        surface reads it, when that differs from what the listing wrote). `finish`:
        FST's FINISH c, the same thing."""
        cond = st.expr if cond is None else cond
        text = self.written(st.expr.span) or expr_text(None, st.expr, TEXT_LIMIT)
        where = f"{st.written or ('FINISH ' + text if finish else f'TERMT({text})')} at " \
            f"line {st.span.line}"
        description = f"{st.message} ({where})" if st.message else where
        surface = condition_surface(cond, lambda e: self.expr(e, "TERMT"))
        index = self.surface(surface, ir.SurfaceKind.SIGN, None, ir.Purpose.TERMT, st.span,
                             description, text)
        if isinstance(cond, ast.BinOp) and cond.op in (">=", "<="):
            self.closed.add(index)
        if st.ends_job:
            self.ending.add(index)
        return index


class _Lowerer(Visitor):
    """Lowers one expression: simulation-function calls become IR nodes."""

    complete = ast.EXPRESSIONS

    def __init__(self, lowering: Lowering, target: str | None, literal: bool) -> None:
        self.lowering = lowering
        self.target = target
        self.literal = literal

    def visit_Num(self, expr: ast.Num) -> ast.Node:
        return expr

    def visit_Name(self, expr: ast.Name) -> ast.Node:
        # (literal too: a statement of a routine's DO loop that reads a value the loop
        # assigns is evaluated where it stands, and the day's weather is still the
        # day's: SUCROS's TOTASS reads LAT so)
        if expr.name in self.lowering.weather:
            return self.lowering.weather_value(expr.name, expr.span)
        return expr

    def visit_Neg(self, expr: ast.Neg) -> ast.Node:
        return ast.Neg(self.visit(expr.operand), expr.span)

    def visit_BinOp(self, expr: ast.BinOp) -> ast.Node:
        op = expr.op
        if op in ast.LOGICAL:
            # a number used as a condition is true iff > 0: in sorted code that is
            # a switch on the number itself
            left, right = self.condition(expr.left), self.condition(expr.right)
            return ast.BinOp(op, left, right, expr.span)
        if op in RELATIONS and not self.literal:
            return ir.SwitchValue(self.lowering.relational(expr, self.target), expr.span)
        if op == "/" and all(isinstance(x, ast.Num) and x.text.isdigit()
                             for x in (expr.left, expr.right)) and expr.right.value:
            # (a division by a literal 0 is the fault's to report, where it happens)
            self.lowering.warn(
                f"{expr.left.text}/{expr.right.text} is a division of whole numbers: it is "
                f"{expr.left.value / expr.right.value:g} here (Fortran would give "
                f"{int(expr.left.value / expr.right.value)})",
                expr.span, "write the numbers with a point (1./2.) to say a real division is "
                "meant")
        if op in ("==", "/=") and not self.literal and _reads_names(expr):
            self.lowering.warn(
                f"{self.lowering.written(expr.span) or op} is tested where it is "
                "evaluated, never located", expr.span,
                "equality of values that move is rarely exact; a test with < or > "
                "is a switching surface whose crossing is located")
        return ast.BinOp(op, self.visit(expr.left), self.visit(expr.right), expr.span)

    def visit_Not(self, expr: ast.Not) -> ast.Node:
        return ast.Not(self.condition(expr.operand), expr.span)

    def visit_UnitValue(self, expr: ir.UnitValue) -> ast.Node:
        return expr

    def condition(self, expr: ast.Node) -> ast.Node:
        """A condition lowered: a number that is not a truth by its form becomes
        `number > 0` (a switch in sorted code)."""
        if ast.is_logical(expr) or not _reads_names(expr):
            return self.visit(expr)
        return self.visit(ast.BinOp(">", expr, ast.Num(0.0, expr.span, "0"), expr.span))

    def visit_Call(self, expr: ast.Call) -> ast.Node:
        low, target = self.lowering, self.target
        if expr.func == BEFORE and expr.args[0].name in low.weather_all:
            # (a weather variable a routine after STOP changes: the day's before the CALL)
            return low.weather_value(expr.args[0].name, expr.args[0].span)
        func = lookup(expr.func, len(expr.args))
        if func is None:
            return expr
        kind = func.kind
        if kind == Kind.MATH or (self.literal and kind in (Kind.SWITCH, Kind.TIME)):
            # a function of its arguments; INITIAL/TERMINAL evaluate a switch once
            return ast.Call(expr.func, tuple(self.visit(a) for a in expr.args), expr.span,
                            expr.arg_spans)
        if kind == Kind.TABLE:
            table = expr.args[func.table_at]
            name = table.name if isinstance(table, ast.Name) else "?"
            return ir.TableLookup(name, self.visit(expr.args[func.x_at]), func.lookup,
                                  expr.span, expr.func)
        if self.literal:
            return expr  # refused by the call checks (no states or memory here)
        if kind == Kind.STATE:
            return low.state_function(expr, None, owner=target)
        if kind in (Kind.SWITCH, Kind.TIME):
            if func.outputs == 2:
                low.rep.error("OUTSW gives two values: write Y1, Y2 = OUTSW(X, V)", expr.span)
                return ast.Num(0.0, expr.span)
            return ir.SwitchValue(low.switch(expr, target or "?"), expr.span)
        if kind == Kind.IMPULSE:
            return ir.Impulse(self.visit(expr.args[0]), self.visit(expr.args[1]), expr.span)
        if kind == Kind.MEMORY:
            return ir.MemoryValue(low.memory(expr, target), expr.span)
        raise AssertionError(f"no lowering for {kind} functions")


def _reads_names(expr: ast.Node) -> bool:
    """Whether an expression reads any name (else it is a number once folded)."""
    return any(isinstance(n, ast.Name) for n in ast.walk(expr))


def condition_surface(e: ast.Node, leaf: Callable[[ast.Node], ast.Node] = lambda x: x
                      ) -> ast.Node:
    """A condition as a continuous surface that is positive where the condition
    holds (TERMT, FINISH relations): `A > B` is A - B, `A .AND. B` the smaller of
    the two surfaces, `A .OR. B` the larger, `.NOT. A` its negative, a number
    itself. Where no such surface exists (==, .EQV.), the truth minus 1/2.

    `leaf` lowers the listing's own expressions (A, B); the smaller, larger and
    absolute values this puts around them are the surface's own arithmetic, left
    as plain calls (a surface is located, never integrated: its kinks are harmless)."""
    span = e.span
    if isinstance(e, ast.BinOp):
        if e.op in (">", ">="):
            return ast.BinOp("-", leaf(e.left), leaf(e.right), span)
        if e.op in ("<", "<="):
            return ast.BinOp("-", leaf(e.right), leaf(e.left), span)
        if e.op == "/=":
            return ast.Call("ABS", (ast.BinOp("-", leaf(e.left), leaf(e.right), span),), span)
        if e.op in ("AND", "OR"):
            return ast.Call("AMIN1" if e.op == "AND" else "AMAX1",
                            (condition_surface(e.left, leaf),
                             condition_surface(e.right, leaf)), span)
    if isinstance(e, ast.Not):
        return ast.Neg(condition_surface(e.operand, leaf), span)
    if isinstance(e, ast.Num) and ast.is_logical(e):
        return ast.Num(1.0 if e.value > 0 else -1.0, span, e.text)
    if ast.is_logical(e):
        return ast.BinOp("-", leaf(e), ast.Num(0.5, span, "0.5"), span)
    return leaf(e)
