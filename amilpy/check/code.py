"""Procedural code -> IR statements (contract section 10).

Two kinds of code:

- **written order** (ACSL INITIAL, DYNAMIC's own statements, DISCRETE, TERMINAL,
  FUNCTION bodies): names may be reassigned; every test is made where it stands
  (`literal` lowering: no surface, nothing located);
- **a sorting unit** (an IF or PROCEDURAL block of sorted code): one unit for the
  sort, written order inside. Its conditions and switches (FSW, ABS, AINT, ...) are
  switching surfaces, located like FSW; a surface must be a function of what the unit
  reads, so a name the unit assigned before on its straight-line path is replaced by
  the expression it was given (`substitute`), and a name an IF assigned on every path
  by what the IF selects, RSW(condition, value, ...) over the IF's own conditions. A
  test that reads a name assigned inside a loop of the unit (or by an IF on some
  paths only) cannot be written that way: it is made where it stands, with a
  warning.
"""

from __future__ import annotations

from dataclasses import replace

from .. import ir
from ..diagnostics import Reporter, Span
from ..library import Kind, lookup
from ..parse import syntax as ast
from ..parse.syntax import deep_enough
from .lower import Lowering
from .names import PURE, Names

# what a unit in sorted code may call: no states, no memory (section 10)
UNIT_CALLS = PURE


def read_names(expr: ast.Node) -> list[str]:
    """Every name an expression reads, in order, once each."""
    return list(dict.fromkeys(n.name for n in ast.walk(expr) if isinstance(n, ast.Name)))


@deep_enough()
def substitute(expr: ast.Node, env: dict[str, ast.Node]) -> ast.Node:
    """The expression with every name of `env` replaced by its expression."""
    if not env:
        return expr
    if isinstance(expr, ast.Name):
        return env.get(expr.name, expr)
    if isinstance(expr, ast.Call):
        return replace(expr, args=tuple(substitute(a, env) for a in expr.args))
    if isinstance(expr, ast.BinOp):
        return replace(expr, left=substitute(expr.left, env), right=substitute(expr.right, env))
    if isinstance(expr, (ast.Neg, ast.Not)):
        return replace(expr, operand=substitute(expr.operand, env))
    return expr


def assigned_names(body) -> list[str]:
    """The names a block of statements assigns (loop variables too), in order."""
    out: dict[str, None] = {}
    for st in body:
        for node in ast.walk(st):
            if isinstance(node, ast.Assign):
                out.update(dict.fromkeys(node.targets))
            elif isinstance(node, ast.Loop):
                out[node.var] = None
    return list(out)


def statement_reads(body) -> list[str]:
    """Every name a block of statements reads, in order."""
    out: dict[str, None] = {}
    for st in body:
        for node in ast.walk(st):
            if isinstance(node, ast.Name):
                out[node.name] = None
    return list(out)


class CodeLowering:
    """Lowers blocks of statements; shares the model's `Lowering` (switches,
    surfaces) and `Names` (calls)."""

    def __init__(self, rep: Reporter, low: Lowering, names: Names,
                 stores: dict[str, str] | None = None) -> None:
        self.rep = rep
        self.low = low
        self.names = names
        self.stores = stores or {}
        self.termts: list[tuple[ast.Termt, ast.Node]] = []  # DERIVATIVE TERMTs found in units
        # TERMTs of written-order code (TermtIf.index points here)
        self.terminations: list[ir.Termination] = []

    # ---------------------------------------------------------- written order
    def written(self, body, section: str, span: Span | None = None) -> ir.Code:
        """Written-order code of one section."""
        lowered = self.block(body, section)
        return ir.Code(section, tuple(lowered), tuple(assigned_names(body)), span)

    def block(self, body, section: str) -> list[ast.Node]:
        out: list[ast.Node] = []
        for st in body:
            lowered = self.statement(st, section)
            if lowered is not None:
                out.extend(lowered if isinstance(lowered, list) else [lowered])
        return out

    def expr(self, expr: ast.Node, target: str | None, section: str) -> ast.Node:
        self.names.check_calls(expr, PURE, section)
        return self.low.expr(expr, target, literal=True)

    def statement(self, st, section: str):
        if isinstance(st, ast.Assign):
            if len(st.targets) > 1:
                self.rep.error("only OUTSW gives two values, and only in sorted code", st.span)
                return None
            target = st.targets[0]
            return ir.Let(target, self.expr(st.expr, target, section), st.span,
                          self.stores.get(target, "REAL"))
        if isinstance(st, ast.If):
            return ir.IfThen(tuple(
                (None if b.cond is None else self.expr(b.cond, None, section),
                 tuple(self.block(b.body, section))) for b in st.branches), st.span)
        if isinstance(st, ast.Loop):
            step = st.step if st.step is not None else ast.Num(1.0, st.span, "1")
            return ir.ForLoop(st.var, self.expr(st.start, None, section),
                              self.expr(st.stop, None, section), self.expr(step, None, section),
                              tuple(self.block(st.body, section)), st.span)
        if isinstance(st, ast.Procedural):  # in written-order code: a plain group
            return self.block(st.body, section)
        if isinstance(st, (ast.Termt, ast.Schedule)) and section.startswith("FUNCTION"):
            what = "TERMT" if isinstance(st, ast.Termt) else "SCHEDULE"
            self.rep.error(f"{what} cannot stand in {section}", st.span,
                           "a FUNCTION only computes its value: write the TERMT or "
                           "SCHEDULE where the FUNCTION is called")
            return None
        if isinstance(st, ast.Schedule):
            if st.kind != "AT":
                self.rep.error(f"SCHEDULE .{st.kind}. stands only in DERIVATIVE", st.span,
                               "a crossing is located in the sorted code; here write "
                               f"SCHEDULE {st.section} .AT. T + delay")
                return None
            return ir.ScheduleAt(st.section, self.expr(st.expr, None, section), st.span)
        if isinstance(st, ast.Declare):  # a FUNCTION's declarations: scalars
            return None
        if isinstance(st, ast.Termt):
            text = self.low.written(st.expr.span) or ""
            self.terminations.append(ir.Termination(section, text, st.message, st.span))
            return ir.TermtIf(self.expr(st.expr, None, section), len(self.terminations) - 1,
                              st.span)
        self.rep.error(f"{type(st).__name__.upper()} cannot stand in {section}", st.span)
        return None

    # ------------------------------------------------------------ sorting units
    def unit(self, st: ast.If | ast.Procedural, index: int, section: str) -> ir.Unit | None:
        """An IF or PROCEDURAL block of sorted code as one unit."""
        body = st.body if isinstance(st, ast.Procedural) else (st,)
        outputs = assigned_names(body)
        reads = [n for n in statement_reads(body) if n not in outputs]
        if isinstance(st, ast.Procedural):
            self.declared(st, outputs, reads)
            outputs = list(dict.fromkeys([*st.outputs, *outputs]))
            reads = list(dict.fromkeys([*st.inputs, *reads]))
            reads = [n for n in reads if n not in outputs]
        self.read_before_assigned(body, outputs)
        before = self.rep.errors
        lowered = _Unit(self, section, st.span).block(body, {}, set(), ())
        if self.rep.errors > before:
            return None
        return ir.Unit(index, "PROCEDURAL" if isinstance(st, ast.Procedural) else "IF",
                       tuple(outputs), tuple(reads), tuple(lowered), st.span)

    def read_before_assigned(self, body, outputs: list[str]) -> None:
        """A name the block assigns, read (in written order) before the block first
        assigns it: the block's own value is not there yet, and it reads 0.0 at every
        evaluation (a CSMP or ACSL translator kept whatever the last evaluation left,
        which depends on the integrator's stages): said, as INITIAL's are."""
        later = set(outputs)
        first = {}
        for st in body:
            for name in assigned_names([st]):
                first.setdefault(name, st.span.line)
        for st in body:
            own = set() if isinstance(st, ast.Assign) else set(assigned_names([st]))
            for node in ast.walk(st):
                if isinstance(node, ast.Name) and node.name in later and \
                        node.name not in own and first.get(node.name, 0) >= node.span.line:
                    later.discard(node.name)
                    self.low.warn(
                        f"{node.name} is read at line {node.span.line} before the block "
                        f"assigns it (line {first[node.name]}): it reads 0.0 there, at every "
                        "evaluation", node.span,
                        f"assign {node.name} before it is read, or compute it outside the "
                        "block (the sort then puts it first)")
            later -= set(assigned_names([st]))

    def declared(self, st: ast.Procedural, outputs: list[str], reads: list[str]) -> None:
        missing_out = [n for n in outputs if n not in st.outputs]
        # constants and time need no listing: they do not move the unit in the sort
        fixed = self.names.data_names | {"TIME"} | set(self.names.reserved) & {"PI"}
        missing_in = [n for n in reads if n not in st.inputs and n not in outputs
                      and n not in fixed]
        if st.outputs or st.inputs:
            for names, what in ((missing_out, "assigns"), (missing_in, "reads")):
                if names:
                    self.low.warn(f"the PROCEDURAL {what} {', '.join(names)}, not in its "
                                  "list", st.span,
                                  "its outputs and inputs are its lists joined with what "
                                  "the body assigns and reads")


class _Unit:
    """The lowering of one unit's statements: `env` holds the straight-line values
    (name -> expression of what the unit reads), `opaque` the names assigned in a
    nested branch or loop, `path` the conditions around the statement."""

    def __init__(self, code: CodeLowering, section: str, span: Span) -> None:
        self.code = code
        self.section = section
        self.span = span

    def expr(self, expr: ast.Node, target: str | None, env, opaque, condition=False):
        names = self.code.names
        if not names.check_calls(expr, UNIT_CALLS, "an IF or PROCEDURAL block"):
            return ast.Num(0.0, expr.span)  # (reported: lowering it would fail on it)
        value = substitute(expr, env)
        opaque_read = opaque & set(read_names(value))
        literal = bool(opaque_read)
        # (a GO TO's flags, names the reader made, are set by tests of their own, said
        # or located where they stand: a test of the flags alone is no news)
        switch = next((n for n in ast.walk(value) if _switch_in_sorted_code(n)), None) \
            if literal and not all("#" in n for n in opaque_read) else None
        if switch is not None:
            what = "this test" if isinstance(switch, ast.BinOp) else f"{switch.func} here"
            self.code.low.warn(
                f"{what} reads a value assigned inside an IF or a loop before it: it is "
                "made where it stands, never located", expr.span,
                "compute that value before the block, or test it with FSW/INSW")
        if condition and not literal:
            return self.code.low.expr(_as_condition(value), target)
        return self.code.low.expr(value, target, literal=literal)

    def block(self, body, env: dict, opaque: set, path: tuple) -> list[ast.Node]:
        out: list[ast.Node] = []
        for st in body:
            if isinstance(st, ast.Assign):
                target = st.targets[0]
                if len(st.targets) > 1:
                    self.code.rep.error("only OUTSW gives two values, and not inside a "
                                        "block", st.span)
                    continue
                out.append(ir.Let(target, self.expr(st.expr, target, env, opaque), st.span,
                                  self.code.stores.get(target, "REAL")))
                value = substitute(st.expr, env)
                if opaque & set(read_names(value)):
                    opaque.add(target)
                    env.pop(target, None)
                else:
                    env[target] = value
                    opaque.discard(target)
            elif isinstance(st, ast.If):
                branches, after = [], []
                inner: dict[str, None] = {}  # (in written order: one order every run)
                # the program reads a branch's test only where the tests before it are
                # false, and its code only where its own is true: the surfaces made
                # there are guarded so (`Lowering.guarded_surfaces`)
                low, outer, passed = self.code.low, self.code.low.guard, []
                earlier: list = []  # (the tests of the branches before, as written)
                for b in st.branches:
                    low.guard = _all_of(outer, passed)
                    cond = None if b.cond is None else \
                        self.expr(b.cond, None, env, opaque, condition=True)
                    low.guard = _all_of(outer, passed + ([cond] if cond is not None else []))
                    # (a TERMT in this branch: where the tests before are false and its
                    # own is true; an ELSE's where all before are false)
                    here = path + tuple(ast.Not(c, c.span) for c in earlier) + \
                        ((b.cond,) if b.cond is not None else ())
                    if b.cond is not None:
                        earlier.append(b.cond)
                    benv, bopaque = dict(env), set(opaque)
                    branches.append((cond, tuple(self.block(b.body, benv, bopaque, here))))
                    after.append((b.cond, benv, bopaque))
                    inner.update(dict.fromkeys(assigned_names(b.body)))
                    if cond is not None:
                        passed.append(ast.Not(cond, cond.span))
                low.guard = outer
                out.append(ir.IfThen(tuple(branches), st.span))
                # (where the IF starts: a surface over it reads as RSW(...), not as
                # the IF's first line)
                at = Span(st.span.line, st.span.column)
                # (each from the values before the IF, where its tests were read: a
                # name the IF assigns and one of its tests reads, FIRST in IF (FIRST)
                # THEN ... FIRST = .FALSE., is selected by the test's value before)
                before, hidden = dict(env), set(opaque)
                selected = {n: _selected(n, before, hidden, after, at) for n in inner}
                for n, value in selected.items():
                    if value is None:
                        env.pop(n, None)
                        opaque.add(n)
                    else:
                        env[n] = value
                        opaque.discard(n)
            elif isinstance(st, ast.Loop):
                step = st.step if st.step is not None else ast.Num(1.0, st.span, "1")
                changed = set(assigned_names(st.body)) | {st.var}
                inside = {k: v for k, v in env.items() if k not in changed}
                bounds = [self.expr(e, None, env, opaque) for e in (st.start, st.stop, step)]
                body_ir = self.block(st.body, inside, opaque | changed, path)
                out.append(ir.ForLoop(st.var, *bounds, tuple(body_ir), st.span))
                for n in changed:
                    env.pop(n, None)
                opaque |= changed
            elif isinstance(st, ast.Termt):
                if path:  # TERMT(c) inside IF (d): TERMT(d .AND. c)
                    cond = st.expr
                    for d in reversed(path):
                        cond = ast.BinOp("AND", d, cond, st.span)
                    st = replace(st, expr=cond)
                self.code.termts.append((st, substitute(st.expr, env)))
            elif isinstance(st, ast.Procedural):
                out.extend(self.block(st.body, env, opaque, path))
            else:
                what = type(st).__name__.upper()
                self.code.rep.error(f"{what} cannot stand inside an IF or PROCEDURAL block "
                                    f"of {self.section}", st.span)
        return out


def _all_of(outer: ast.Node | None, tests: list) -> ast.Node | None:
    """outer .AND. each of tests (None: no test at all)."""
    out = outer
    for t in tests:
        out = t if out is None else ast.BinOp("AND", out, t, t.span)
    return out


def _selected(name: str, env: dict, opaque: set, after: list, span: Span) -> ast.Node | None:
    """A name an IF assigns, as what the IF selects: RSW(c1, v1, RSW(c2, v2, v)) over
    its conditions and the name's value at the end of each branch (v: the ELSE's, or
    the value from before the IF where a path does not assign it), so that a test
    after the IF is a surface of what the unit reads, switched by the IF's own
    conditions. None where a value is not such an expression (assigned in a loop or
    a nested IF that is not, or not known before the IF on a path that keeps it)."""
    def known(values: dict, hidden: set) -> ast.Node | None:
        return None if name in hidden else values.get(name)

    *tests, (last, last_env, last_opaque) = after
    if last is None:
        value = known(last_env, last_opaque)
    else:
        tests.append((last, last_env, last_opaque))
        value = known(env, opaque)
    for cond, values, hidden in reversed(tests):
        chosen, cond = known(values, hidden), substitute(cond, env)
        if value is None or chosen is None or opaque & set(read_names(cond)):
            return None
        value = ast.Call("RSW", (_as_condition(cond), chosen, value), span)
    return value


def _switch_in_sorted_code(node: ast.Node) -> bool:
    """A relational test (`A > B`) or a switch's call (FSW, ABS, AMAX1, ...): what
    sorted code locates, and a test made where it stands does not."""
    if isinstance(node, ast.BinOp):
        return node.op in ast.RELATIONAL[:4]
    if isinstance(node, ast.Call):
        func = lookup(node.func)
        return func is not None and func.kind in (Kind.SWITCH, Kind.TIME)
    return False


def _as_condition(expr: ast.Node) -> ast.Node:
    """A condition as a truth (a number is true when > 0)."""
    if ast.is_logical(expr):
        return expr
    return ast.BinOp(">", expr, ast.Num(0.0, expr.span, "0"), expr.span)
