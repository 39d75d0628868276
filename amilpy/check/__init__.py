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

from .. import ir
from .. import syntax as ast
from ..diagnostics import Reporter
from ..surfaces import classify
from ..syntax import deep_enough
from . import order
from .groups import RunGroups, reject_late_equations, sections, split_groups
from .lower import Lowering
from .names import PURE, Names

__all__ = ["check"]


@deep_enough()
def check(program: ast.Program, name: str | None = None) -> ir.Model:
    """The checked, sorted model of a parsed listing; raises AmilError with every
    fault found."""
    rep = Reporter(program.path, program.source)
    groups = split_groups(program)
    parts = sections(groups[0] if groups else [], rep)
    reject_late_equations(groups, rep)
    data = RunGroups(rep).read(groups)
    names = Names(rep, program, data)
    low = Lowering(rep)

    # INITIAL: plain assignments, evaluated once, sorted
    initial: list[ir.Equation] = []
    for st in parts["INITIAL"]:
        for target, span in zip(st.targets, st.target_spans, strict=True):
            names.define(target, span, "INITIAL")
        if not names.check_calls(st.expr, PURE, "INITIAL"):
            continue
        if len(st.targets) > 1:
            rep.error("only OUTSW gives two values, and only in DYNAMIC", st.span)
            continue
        initial.append(ir.Equation(st.targets[0], low.expr(st.expr, None, literal=True),
                                   st.span))
    # DYNAMIC: one parallel block, sorted
    dynamic: list[ir.Equation] = []
    termts: list[ast.Termt] = []
    for st in parts["DYNAMIC"]:
        if isinstance(st, ast.Termt):
            termts.append(st)
            continue
        ok = all([names.define(t, s, "DYNAMIC")
                  for t, s in zip(st.targets, st.target_spans, strict=True)])
        if names.check_calls(st.expr, None, "DYNAMIC") and ok:
            dynamic.extend(low.statement(st))
    # TERMINAL: once at the end of a run, in written order
    terminal: list[ir.Equation] = []
    for st in parts["TERMINAL"]:
        for target, span in zip(st.targets, st.target_spans, strict=True):
            names.define(target, span, "TERMINAL")
        if names.check_calls(st.expr, PURE, "TERMINAL") and len(st.targets) == 1:
            terminal.append(ir.Equation(st.targets[0], low.expr(st.expr, None, literal=True),
                                        st.span))

    names.check_references(parts, low.before_run,
                           {s.name for s in low.states if not s.hidden})
    initial = order.sort(initial, "INITIAL", rep, low.switches, low.memories)
    dynamic = order.sort(dynamic, "DYNAMIC", rep, low.switches, low.memories)
    for s in data.finish:
        low.finish(s)
    for st in termts:
        if names.check_calls(st.expr, None, "DYNAMIC"):
            low.termt(st)

    # states in a canonical order: the listing's order must not matter
    low.states.sort(key=lambda s: (s.hidden, s.name))
    model = ir.Model(
        name=name or program.path or "<listing>", path=program.path, source=program.source,
        initial=initial, dynamic=dynamic, terminal=terminal, states=low.states,
        switches=low.switches, surfaces=low.surfaces, memories=low.memories, runs=data.runs,
        data_names=data.names, spans={**data.spans, **names.defined}, data_kinds=data.kinds,
    )
    classify(model)
    rep.raise_if_any()
    return model
