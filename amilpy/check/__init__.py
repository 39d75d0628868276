"""Syntax -> IR in four passes that share one `Reporter` (pylox's context), so every
fault of the stage is reported together:

- `groups`: run groups and data statements -> RunSpecs (every TIMER key, METHOD
  and tolerance checked);
- `names`: one definition per name, the calls, and every name read, reported,
  FINISHed or given a tolerance;
- `lower`: simulation functions -> states, switches, memory and surfaces, as the
  library's entries say (surfaces interned);
- `order`: dependency sorting and algebraic loops.
Surface classification (const / time / state) is `surfaces.classify`.
"""

from __future__ import annotations

from dataclasses import replace

from .. import ir
from ..diagnostics import AmilError, Reporter
from ..language import RESERVED
from ..library.surfaces import classify
from ..parse import syntax as ast
from ..parse.syntax import deep_enough, no_collection
from ..parse.unparse import expr_text
from . import order
from .code import CodeLowering, assigned_names, substitute
from .groups import RunGroups, reject_late_equations, sections, split_groups
from .lower import TEXT_LIMIT, Lowering
from .names import PURE, Names, reserved_names
from .units import (
    ImplGroup,
    declared_stores,
    impl_equations,
    impl_groups,
    nosort_regions,
    stored,
    unit_equations,
    written_text,
)

__all__ = ["check"]


def _dynamic_in_initial(statements: list, rep: Reporter) -> list:
    """The INITIAL statements that call INTGRL (or another function of DYNAMIC),
    said once: several of them are most often the model's equations under an
    INITIAL whose DYNAMIC line was forgotten (four errors, one per INTGRL, hid that)."""
    from ..library import lookup

    def dynamic_call(st) -> ast.Call | None:
        for n in ast.walk(st.expr):
            if isinstance(n, ast.Call):
                f = lookup(n.func)
                # (a name with a dot is the reader's own: a routine's value before its
                # CALL, whose fault is the CALL's, said there)
                if f is not None and f.kind not in PURE and not n.func.startswith("."):
                    return n
        return None

    found = [(st, call) for st in statements if isinstance(st, ast.Assign)
             and (call := dynamic_call(st)) is not None]
    if found:
        (_, first), rest = found[0], found[1:]
        rep.error(f"{first.func} cannot be used in INITIAL" + (
            f" (nor can {len(rest)} more statement{'s' if len(rest) > 1 else ''} here)"
            if rest else ""), first.span,
            "states, memory functions and IMPULS belong in DYNAMIC: if the model's "
            "equations follow its data, write DYNAMIC on a line before them"
            + (f" (before line {found[0][0].span.line})" if found[0][0].span else ""),
            tuple((call.span, f"{call.func} in INITIAL too") for _, call in rest))
    return [st for st, _ in found]


@deep_enough()
@no_collection()
def check(program: ast.Program, name: str | None = None) -> ir.Model:
    """The checked, sorted model of a parsed listing; raises AmilError with every
    fault found."""
    try:
        if program.form == "ACSL":
            from .acsl import check_acsl

            return _carried(check_acsl(program, name), program)
        return _carried(_check_csmp(program, name), program)
    except AmilError as exc:
        if program.macros:
            from ..parse.macros import in_macros

            exc.diagnostics = in_macros(exc.diagnostics, program.macros)
        raise


def _carried(model: ir.Model, program: ast.Program) -> ir.Model:
    """What the reader found that the checked model carries: the constants an array's
    size or a written-out loop's bounds read (parse.arrays), which no run may change,
    and the reader's warnings, before the model's."""
    if program.fixed:
        model.runs = [replace(r, fixed=program.fixed) for r in model.runs]
    model.warnings = [*program.notes, *model.warnings]
    return model


def _fst_events(blocks: list[ast.Event], sets: set[str], low: Lowering, code: CodeLowering,
                names: Names, rep: Reporter) -> tuple[list[ir.FstEvent], list[ast.Node]]:
    """FST's EVENT blocks, and the expressions they read (for the names check): a
    ZEROCONDITION a surface the run watches, a FIRSTTIME a value before the run; the
    event's own values (EVENT#k.NAME), its NEWVALUEs and its NEXTTIME written-order
    code, every one computed from the values before the event, then the NEWVALUEs
    given at once (FST's statements have no order, so neither may their effect)."""
    states = {s.name for s in low.states if not s.hidden}
    out, reads = [], []
    for k, ev in enumerate(blocks, start=1):
        ok = True
        for nv in ev.values:
            if nv.target not in states and nv.target not in sets:
                ok = False
                what = ("is time, which no EVENT can set" if nv.target in RESERVED else
                        "is a data value (PARAM, INCON)" if nv.target in names.data_names
                        else f"is computed at line {names.defined[nv.target].line}"
                        if nv.target in names.defined else "is never defined")
                rep.error(f"NEWVALUE {nv.target}: {nv.target} is neither a state nor a SET "
                          "variable", nv.target_span,
                          f"{nv.target} {what}; an EVENT changes states (X = INTGRL(...)) "
                          "and SET variables (SET X = value in INITIAL, X then read in "
                          "DYNAMIC)")
        own = {h.targets[0]: ast.Name(f"EVENT#{k}.{h.targets[0]}", h.span) for h in ev.helpers}
        for h in ev.helpers:
            if h.targets[0] in names.defined or h.targets[0] in names.data_names:
                ok = False
                rep.error(f"{h.targets[0]} is the EVENT's own value and a variable of the "
                          "model", h.target_spans[0], "give the EVENT's own value another name")
        body = [replace(h, targets=(own[h.targets[0]].name,), expr=substitute(h.expr, own))
                for h in ev.helpers]
        new = [ast.Assign((f"EVENT#{k}.NEW.{nv.target}",), (nv.target_span,),
                          substitute(nv.expr, own), nv.span) for nv in ev.values]
        after = None
        if ev.next is not None:
            after = f"EVENT#{k}.NEXTTIME"
            new.append(ast.Assign((after,), (ev.next.span,), substitute(ev.next.expr, own),
                                  ev.next.span))
        given = [ast.Assign((nv.target,), (nv.target_span,), ast.Name(t.targets[0], nv.span),
                            nv.span) for nv, t in zip(ev.values, new, strict=False)]
        reads += [st.expr for st in body + new]
        surface = first = None
        if ev.zero is not None:
            reads.append(ev.zero.expr)
            if names.check_calls(ev.zero.expr, PURE, "EVENT"):
                surface = low.surface(
                    low.expr(ev.zero.expr, "ZEROCONDITION"), ir.SurfaceKind.SIGN, None,
                    ir.Purpose.SCHEDULE, ev.zero.span, f"EVENT at line {ev.span.line}",
                    low.written(ev.zero.expr.span) or expr_text(None, ev.zero.expr, TEXT_LIMIT))
            else:
                ok = False
        else:
            low.before_run.append((ev.first.expr, "FIRSTTIME"))
            if names.check_calls(ev.first.expr, PURE, "FIRSTTIME"):
                first = low.expr(ev.first.expr, None, literal=True)
            else:
                ok = False
        if ok:
            out.append(ir.FstEvent(surface, first, after,
                                   code.written(body + new + given, "EVENT", ev.span), ev.span))
    return out, reads


def _check_csmp(program: ast.Program, name: str | None) -> ir.Model:
    rep = Reporter(program.path, program.source)
    groups = split_groups(program)
    parts = sections(groups[0] if groups else [], rep)
    for section in ("INITIAL", "TERMINAL"):  # sorted INITIAL keeps no order to keep;
        # TERMINAL runs in written order anyway: NOSORT/SORT change nothing there
        parts[section] = [s for s in parts[section] if not isinstance(s, ast.Nosort)]
    reject_late_equations(groups, rep)
    data = RunGroups(rep, reserved_names(program)).read(groups)
    names = Names(rep, program, data)
    low = Lowering(rep)
    if data.weather is not None:
        # FST's weather names, where the listing does not define them itself
        own = set(data.names) | set(assigned_names([st for section in parts.values()
                                                    for st in section]))
        low.weather = frozenset(names.weather_names - own)
        low.weather_all = frozenset(names.weather_names)

    # INITIAL: plain assignments, evaluated once, sorted
    stores = declared_stores(program.statements)  # INTEGER (FIXED), LOGICAL names
    initial: list[ir.Equation] = []
    misplaced = {id(st) for st in _dynamic_in_initial(parts["INITIAL"], rep)}
    for st in parts["INITIAL"]:
        said = id(st) in misplaced  # (said once, above)
        st = stored(st, stores)
        for target, span in zip(st.targets, st.target_spans, strict=True):
            names.define(target, span, "INITIAL")
        if said:
            continue
        if not names.check_calls(st.expr, PURE, "INITIAL"):
            continue
        if len(st.targets) > 1:
            rep.error("only OUTSW gives two values, and only in DYNAMIC", st.span)
            continue
        initial.append(ir.Equation(st.targets[0], low.expr(st.expr, None, literal=True),
                                   st.span))
    low.written = written_text(program.source)
    code = CodeLowering(rep, low, names, stores)
    # DYNAMIC: one parallel block, sorted (an IF block is one unit)
    dynamic: list[ir.Equation] = []
    units: list[ir.Unit] = []
    termts: list[tuple[ast.Termt, ast.Node | None]] = []
    for st in impl_groups(nosort_regions(parts["DYNAMIC"], rep), rep):
        if isinstance(st, ImplGroup):
            dynamic.extend(impl_equations(code, names, st, units))
            continue
        if isinstance(st, ast.Termt):
            termts.append((st, None))
            continue
        if isinstance(st, (ast.If, ast.Procedural)):
            dynamic.extend(unit_equations(code, names, st, units, "DYNAMIC"))
            continue
        st = stored(st, stores)
        ok = all([names.define(t, s, "DYNAMIC")
                  for t, s in zip(st.targets, st.target_spans, strict=True)])
        if names.check_calls(st.expr, None, "DYNAMIC") and ok:
            dynamic.extend(low.statement(st))
    termts += code.termts
    # TERMINAL: once at the end of a run, in written order
    terminal: list[ir.Equation] = []
    terminal_code: list[ir.Code] = []
    if any(isinstance(st, (ast.If, ast.Loop)) for st in parts["TERMINAL"]):
        for target in assigned_names(parts["TERMINAL"]):
            names.define(target, parts["TERMINAL"][0].span, "TERMINAL")
        terminal_code.append(code.written(parts["TERMINAL"], "TERMINAL"))
    for st in parts["TERMINAL"] if not terminal_code else ():
        for target, span in zip(st.targets, st.target_spans, strict=True):
            names.define(target, span, "TERMINAL")
        if names.check_calls(st.expr, PURE, "TERMINAL") and len(st.targets) == 1:
            terminal.append(ir.Equation(st.targets[0], low.expr(st.expr, None, literal=True),
                                        st.span))

    sets = {st.target for st in parts["SET"]}
    events, reads = _fst_events(parts["EVENT"], sets, low, code, names, rep)
    names.check_references({**parts, "DYNAMIC": parts["DYNAMIC"] + reads},
                           low.before_run, {s.name for s in low.states if not s.hidden})
    # a weather name a report asks for is a variable of the run (PRINT RDD)
    reported = {n: st.span for st in data.reports for n in st.names if n in low.weather}
    dynamic += [ir.Equation(n, low.expr(ast.Name(n, span), n), span)
                for n, span in reported.items()]
    initial = order.sort(initial, "INITIAL", rep, low.switches, low.memories)
    dynamic = order.sort(dynamic, "DYNAMIC", rep, low.switches, low.memories, units)
    for s in data.finish:
        low.finish(s)
    for st in data.finish_relations:
        if names.check_calls(st.expr, None, "DYNAMIC"):
            low.termt(st, finish=True)
    for st, cond in termts:
        if names.check_calls(st.expr, None, "DYNAMIC"):
            low.termt(st, cond)

    # states in a canonical order: the listing's order must not matter
    low.states.sort(key=lambda s: (s.hidden, s.name))
    model = ir.Model(
        name=name or program.path or "<listing>", path=program.path, source=program.source,
        initial=initial, dynamic=dynamic, terminal=terminal, states=low.states,
        switches=low.switches, surfaces=low.guarded_surfaces(), memories=low.memories,
        runs=data.runs,
        data_names=data.names, spans={**data.spans, **names.defined}, data_kinds=data.kinds,
        units=units, warnings=low.warnings, terminal_code=terminal_code,
        events=events, sets=sorted(sets), own_pi=program.own_pi,
        ending=frozenset(low.ending),
        weather=sorted(low.weather_used), closed=low.closed,
        weather_lines=sorted({s for spans in low.weather_used.values() for s in spans},
                             key=lambda s: (s.line, s.column)),
    )
    classify(model)
    rep.raise_if_any()
    return model
