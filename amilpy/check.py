"""Syntax -> IR: names, sections, run groups, lowering of simulation functions,
dependency sorting and algebraic-loop detection.

Every fault found here is collected and reported together (see `Reporter`).
"""

from __future__ import annotations

import math
from dataclasses import replace

from . import ir
from . import syntax as ast
from .diagnostics import Reporter, Span, nearest
from .language import KNOWN_BEFORE_RUN, RESERVED, SETTINGS, TIME, TIMER_KEYS
from .library import ALIASES, FUNCTIONS, Func, Kind, lookup
from .routes import method_names, route_for
from .surfaces import classify, constant_value
from .syntax import Visitor
from .templates import ARGUMENTS, instantiate, template_names

# the largest store a function's literal argument may ask for (DELAY's N points)
MAX_STORE = 100_000

_DATA_STATEMENTS = (ast.Data, ast.Table, ast.Timer, ast.Method, ast.Tolerance, ast.Finish,
                    ast.Report, ast.Label, ast.Title)


def check(program: ast.Program, name: str | None = None) -> ir.Model:
    return _Checker(program, name).run()


class _Checker:
    def __init__(self, program: ast.Program, name: str | None) -> None:
        self.program = program
        self.rep = Reporter(program.path, program.source)
        self.name = name or program.path or "<listing>"

    # ------------------------------------------------------------------ driver
    def run(self) -> ir.Model:
        groups = self.split_groups()
        first = groups[0] if groups else []
        sections = self.sections(first)
        for later in groups[1:]:
            for st in later:
                if not isinstance(st, _DATA_STATEMENTS):
                    self.rep.error(
                        "only data and control statements may follow the first END",
                        st.span,
                        "a later run group may change PARAM, TIMER, METHOD, PRINT ...; "
                        "equations belong before the first END",
                    )
        runs, data_names, data_spans = self.run_specs(groups)
        model = self.lower(sections, runs, data_names, data_spans)
        self.rep.raise_if_any()
        return model

    def split_groups(self) -> list[list[ast.Statement]]:
        groups: list[list[ast.Statement]] = [[]]
        for st in self.program.statements:
            if isinstance(st, ast.Stop):
                break
            if isinstance(st, ast.End):
                groups.append([])
                continue
            groups[-1].append(st)
        if len(groups) > 1 and not any(
            not isinstance(s, (ast.Title,)) for s in groups[-1]
        ):
            groups.pop()  # a final END (or END followed by STOP) opens no new run
        return groups

    def sections(self, group: list[ast.Statement]) -> dict[str, list[ast.Statement]]:
        out: dict[str, list[ast.Statement]] = {"INITIAL": [], "DYNAMIC": [], "TERMINAL": []}
        current = "DYNAMIC"
        for st in group:
            if isinstance(st, ast.Section):
                current = st.name
            elif isinstance(st, (ast.Assign, ast.Termt)):
                if isinstance(st, ast.Termt) and current != "DYNAMIC":
                    self.rep.error("TERMT belongs in DYNAMIC", st.span)
                out[current].append(st)
        return out

    # ------------------------------------------------------------- run groups
    def run_specs(self, groups):
        data: dict[str, float] = {}
        data_spans: dict[str, Span] = {}
        data_kind: dict[str, str] = {}
        tables: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = {}
        table_spans: dict[str, Span] = {}
        timer: dict[str, float] = {}
        method: str | None = None
        relerr = abserr = None
        rel_each: dict[str, float] = {}
        abs_each: dict[str, float] = {}
        reports: list[ir.Report] = []
        titles: list[str] = []
        finish: list[ast.Setting] = []
        runs: list[ir.RunSpec] = []
        base: dict[str, float] | None = None
        self.finish_settings: list[ast.Setting] = []
        for gi, group in enumerate(groups):
            lists: dict[str, tuple[float, ...]] = {}
            new_reports = [] if any(isinstance(s, ast.Report) for s in group) else None
            new_titles = [] if any(isinstance(s, ast.Title) for s in group) else None
            for st in group:
                if isinstance(st, ast.Data):
                    for item in st.items:
                        self.check_assignable(item.name, item.span, "a data value")
                        if gi == 0 and item.name in data_spans and data_kind.get(item.name):
                            self.rep.error(
                                f"{item.name} is given a value twice",
                                item.span,
                                f"first given at line {data_spans[item.name].line}",
                            )
                        data_spans.setdefault(item.name, item.span)
                        data_kind[item.name] = st.keyword
                        data[item.name] = item.values[0]
                        if item.is_list:
                            lists[item.name] = item.values
                elif isinstance(st, ast.Table):
                    self.check_table(st)
                    tables[st.name] = (st.xs, st.ys)
                    table_spans.setdefault(st.name, st.span)
                elif isinstance(st, ast.Timer):
                    for s in st.settings:
                        if s.name not in TIMER_KEYS:
                            hint = nearest(s.name, set(TIMER_KEYS))
                            self.rep.error(
                                f"unknown TIMER setting {s.name}",
                                s.span,
                                f"did you mean {hint}?" if hint else
                                "TIMER takes " + ", ".join(TIMER_KEYS),
                            )
                        elif not math.isfinite(s.value):
                            self.rep.error(f"{s.name} must be a finite number (got {s.value:g})",
                                           s.span)
                        elif s.value <= 0 and s.name != "DELMIN":
                            self.rep.error(f"{s.name} must be positive (got {s.value:g})", s.span)
                        timer[s.name] = s.value
                elif isinstance(st, ast.Method):
                    if route_for(st.name) is None:
                        hint = nearest(st.name, set(method_names()))
                        self.rep.error(
                            f"unknown integration method {st.name}",
                            st.span,
                            (f"did you mean {hint}? " if hint else "")
                            + "known: " + ", ".join(method_names()),
                        )
                    method = st.name
                elif isinstance(st, ast.Tolerance):
                    target_each = rel_each if st.kind == "RELERR" else abs_each
                    if st.default is not None:
                        if st.default <= 0:
                            self.rep.error(f"{st.kind} must be positive", st.span)
                        if st.kind == "RELERR":
                            relerr = st.default
                        else:
                            abserr = st.default
                    for s in st.settings:
                        if s.value <= 0:
                            self.rep.error(f"{st.kind} must be positive", s.span)
                        target_each[s.name] = s.value
                elif isinstance(st, ast.Finish):
                    finish.extend(st.settings)
                elif isinstance(st, ast.Report):
                    kind = "OUTPUT" if st.kind == "PRTPLT" else st.kind
                    (new_reports if new_reports is not None else reports).append(
                        ir.Report(kind, st.names, None, st.span, st.kind == "PRTPLT"))
                    self._all_report_statements = getattr(self, "_all_report_statements", [])
                    self._all_report_statements.append(st)
                elif isinstance(st, ast.Label):
                    target = new_reports if new_reports is not None else reports
                    outs = [i for i, r in enumerate(target) if r.kind == "OUTPUT"]
                    if outs:
                        target[outs[-1]] = replace(target[outs[-1]], label=st.text)
                    else:
                        titles_target = new_titles if new_titles is not None else titles
                        titles_target.append(st.text)
                elif isinstance(st, ast.Title):
                    (new_titles if new_titles is not None else titles).append(st.text)
            if new_reports is not None:
                reports = new_reports
            if new_titles is not None:
                titles = new_titles
            if gi == 0:
                self.finish_settings = list(finish)
                if "FINTIM" not in timer:
                    self.rep.error(
                        "FINTIM is not given",
                        None,
                        "add a TIMER statement, e.g. TIMER FINTIM = 1.0, PRDEL = 0.01",
                    )
            lengths = {len(v) for v in lists.values()}
            if len(lengths) > 1:
                first = next(iter(lists))
                self.rep.error(
                    "value lists in one run group must have the same length",
                    data_spans.get(first),
                    ", ".join(f"{k} has {len(v)}" for k, v in lists.items()),
                )
            count = max(lengths) if lengths else 1
            for k in range(count):
                values = dict(data)
                for lname, lvalues in lists.items():
                    values[lname] = lvalues[min(k, len(lvalues) - 1)]
                if base is None:
                    base = dict(values)
                changed = {n: v for n, v in values.items() if base.get(n) != v}
                if lists:
                    changed.update({n: values[n] for n in lists})
                label = ", ".join(f"{n} = {v:g}" for n, v in changed.items())
                runs.append(ir.RunSpec(
                    label=label or ("RUN 1" if gi == 0 else f"RUN {len(runs) + 1}"),
                    data=values, changed=changed, tables=dict(tables), timer=dict(timer),
                    method=method, relerr=relerr, abserr=abserr, relerr_each=dict(rel_each),
                    abserr_each=dict(abs_each), reports=list(reports), titles=list(titles),
                ))
            # a later group inherits everything, value lists collapse to their first value
            for lname in lists:
                data[lname] = lists[lname][0]
        if not runs:
            self.rep.error("the listing has no statements", None)
        # a value first given after an END exists only for the runs from there on
        for name, span in [*data_spans.items(), *table_spans.items()]:
            if runs and name not in runs[0].data and name not in runs[0].tables:
                self.rep.error(
                    f"{name} has no value in the first run: it is first given after an END",
                    span,
                    f"give {name} a value before the first END; a statement after END "
                    "changes it for the runs that follow",
                )
        self.tables = tables
        self.data_kind = data_kind
        return runs, list(data), data_spans

    def check_table(self, st: ast.Table) -> None:
        if st.odd_count:
            self.rep.error(
                f"FUNCTION {st.name} has an odd number of values",
                st.span,
                "a table is pairs x1,y1, x2,y2, ...; a decimal comma (1,5) splits a number in two",
            )
        for i in range(1, len(st.xs)):
            if not st.xs[i] > st.xs[i - 1]:
                self.rep.error(
                    f"FUNCTION {st.name}: x values must increase strictly "
                    f"(x{i} = {st.xs[i - 1]:g}, x{i + 1} = {st.xs[i]:g})",
                    st.span,
                    "write the points in order of increasing x",
                )
                break
        if len(st.xs) < 2:
            self.rep.error(f"FUNCTION {st.name} needs at least two points", st.span)

    def check_assignable(self, name: str, span: Span, what: str) -> bool:
        if name in RESERVED:
            self.rep.error(
                f"{name} is a reserved name and cannot be {what}",
                span,
                ", ".join(RESERVED[:-1]) + f" and {RESERVED[-1]} are read-only; "
                "set the TIMER values with a TIMER statement",
            )
            return False
        # a variable may be named like a function (CSMP allows it): calls have '('
        return True

    # ---------------------------------------------------------------- lowering
    def lower(self, sections, runs, data_names, data_spans) -> ir.Model:
        self.data_names = set(data_names)
        self.table_names = set(self.tables)
        self.states: list[ir.State] = []
        self.switches: list[ir.Switch] = []
        self.surfaces: list[ir.Surface] = []
        self.memories: list[ir.Memory] = []
        self.nslots = 0
        self.hidden_counts: dict[str, int] = {}
        # expressions that must be known before the run, with what they are
        self.ic_exprs: list[tuple[ast.Expr, str]] = []
        defined: dict[str, Span] = {}
        self.defined_where: dict[str, str] = {}

        def define(target: str, span: Span, where: str) -> bool:
            if not self.check_assignable(target, span, "assigned"):
                return False
            if target in defined:
                self.rep.error(
                    f"{target} is defined twice",
                    span,
                    f"first defined at line {defined[target].line}; a name has one definition",
                    related=((defined[target], f"{target} first defined here"),),
                )
                return False
            if target in self.data_names:
                self.rep.error(
                    f"{target} is both a data value and computed",
                    span,
                    f"it is given a value at line {data_spans[target].line}; drop one of them",
                )
                return False
            defined[target] = span
            self.defined_where[target] = where
            return True

        # INITIAL: plain assignments, evaluated once, sorted.
        initial: list[ir.Equation] = []
        for st in sections["INITIAL"]:
            for target, tspan in zip(st.targets, st.target_spans, strict=True):
                define(target, tspan, "INITIAL")
            if not self.check_calls(st.expr, allow=("math", "table", "switch", "time"),
                                    section="INITIAL"):
                continue
            if len(st.targets) > 1:
                self.rep.error("only OUTSW gives two values, and only in DYNAMIC", st.span)
                continue
            initial.append(ir.Equation(st.targets[0], self.lower_pure(st.expr), st.span))
        self.initial_names = {e.target for e in initial}

        # DYNAMIC
        dyn_eqs: list[ir.Equation] = []
        self.pending_termt: list[ast.Termt] = []
        for st in sections["DYNAMIC"]:
            if isinstance(st, ast.Termt):
                self.pending_termt.append(st)
                continue
            ok = all(define(t, s, "DYNAMIC") for t, s in zip(st.targets, st.target_spans,
                                                            strict=True))
            if not self.check_calls(st.expr, allow=None, section="DYNAMIC") or not ok:
                continue
            dyn_eqs.extend(self.lower_dynamic(st))

        terminal: list[ir.Equation] = []
        for st in sections["TERMINAL"]:
            for target, tspan in zip(st.targets, st.target_spans, strict=True):
                define(target, tspan, "TERMINAL")
            if self.check_calls(st.expr, allow=("math", "table", "switch", "time"),
                                section="TERMINAL") and len(st.targets) == 1:
                terminal.append(ir.Equation(st.targets[0], self.lower_pure(st.expr), st.span))

        self.defined = defined
        known = set(defined) | self.data_names | set(RESERVED)

        # names used but never defined (a table name as AFGEN's first argument is fine)
        table_args: set[int] = set()
        for section in sections.values():
            for st in section:
                for node in ast.walk(st.expr):
                    if isinstance(node, ast.Call) and node.args and \
                            getattr(lookup(node.func), "kind", "") == "table":
                        table_args.add(id(node.args[0]))

        def check_names(expr, where_ok: set[str]):
            for node in ast.walk(expr):
                if isinstance(node, ast.Name) and node.name not in where_ok \
                        and id(node) not in table_args:
                    self.undefined(node, known)

        initial_ok = self.data_names | self.initial_names | KNOWN_BEFORE_RUN
        for st in sections["INITIAL"]:
            for node in ast.walk(st.expr):
                if isinstance(node, ast.Name) and node.name not in initial_ok \
                        and id(node) not in table_args:
                    if node.name in defined:
                        self.rep.error(
                            f"INITIAL uses {node.name}, which is computed in "
                            f"{self.defined_where[node.name]}",
                            node.span,
                            "INITIAL runs once before the dynamics; it can use data values "
                            "and other INITIAL values only",
                        )
                    else:
                        self.undefined(node, known)
        for st in sections["DYNAMIC"] + sections["TERMINAL"]:
            check_names(st.expr, known)
        for expr, what in self.ic_exprs:
            for node in ast.walk(expr):
                if isinstance(node, ast.Name) and node.name not in initial_ok:
                    if node.name in defined:
                        self.rep.error(
                            f"{what} uses {node.name}, which changes in time",
                            node.span,
                            f"{what} must be a number, a data value or an INITIAL value",
                        )
                    else:
                        self.undefined(node, known)

        # reports and FINISH must name known quantities
        report_known = known - SETTINGS
        for st in getattr(self, "_all_report_statements", []):
            for n, s in zip(st.names, st.name_spans, strict=True):
                if n not in report_known and n != TIME:
                    hint = nearest(n, report_known - {TIME})
                    self.rep.error(
                        f"{st.kind} names {n}, which the model never defines",
                        s,
                        f"did you mean {hint}?" if hint else None,
                    )
        for s in self.finish_settings:
            if s.name not in known:
                hint = nearest(s.name, known)
                self.rep.error(f"FINISH names {s.name}, which the model never defines", s.span,
                               f"did you mean {hint}?" if hint else None)

        initial_sorted = self.sort(initial, set(self.initial_names), "INITIAL")
        dyn_sorted = self.sort(dyn_eqs, {e.target for e in dyn_eqs}, "DYNAMIC")

        # FINISH and TERMT surfaces
        for s in self.finish_settings:
            expr = ast.BinOp("-", ast.Name(s.name, s.span), ast.Num(s.value, s.span), s.span)
            self.add_surface(expr, "sign", None, "finish", s.span, f"FINISH {s.name}={s.value:g}")
        for st in self.pending_termt:
            if not self.check_calls(st.expr, allow=None, section="DYNAMIC"):
                continue
            expr = self.lower_expr(st.expr, "TERMT")
            self.add_surface(expr, "sign", None, "termt", st.span, "TERMT")

        # states in a canonical order: the listing's order must not matter
        self.states.sort(key=lambda s: (s.hidden, s.name))
        model = ir.Model(
            name=self.name, path=self.program.path, source=self.program.source,
            initial=initial_sorted, dynamic=dyn_sorted, terminal=terminal,
            states=self.states, switches=self.switches, surfaces=self.surfaces,
            memories=self.memories, runs=runs, data_names=data_names,
            spans={**data_spans, **defined}, data_kinds=dict(self.data_kind),
        )
        classify(model)
        return model

    def undefined(self, node: ast.Name, known: set[str]) -> None:
        if node.name in self.table_names:
            self.rep.error(f"{node.name} is a FUNCTION table, not a value", node.span,
                           f"look it up with AFGEN({node.name}, X)")
            return
        hint = nearest(node.name, known - {"DELMIN", "DELMAX"})
        self.rep.error(
            f"{node.name} is used but never defined",
            node.span,
            (f"did you mean {hint}? " if hint else "")
            + "give it a value with PARAM/CONST/INCON or an equation",
        )

    # ----------------------------------------------------------- call checks
    def check_calls(self, expr: ast.Expr, allow, section: str) -> bool:
        """Report unknown functions and wrong argument counts; False if any."""
        before = len(self.rep.diagnostics)
        self._check_calls(expr, allow, section)
        return len(self.rep.diagnostics) == before

    def _check_calls(self, expr: ast.Expr, allow, section: str) -> None:
        for node in ast.walk(expr):
            if not isinstance(node, ast.Call):
                continue
            func = lookup(node.func)
            if func is None:
                hint = nearest(node.func, set(FUNCTIONS) | set(ALIASES))
                self.rep.error(
                    f"unknown function {node.func}",
                    node.span,
                    f"did you mean {hint}?" if hint else "see the function list in the manual",
                )
                continue
            n = len(node.args)
            func = func.form(n)
            lo, hi = func.nargs
            if n < lo or (hi is not None and n > hi):
                want = f"{lo}" if hi == lo else (f"{lo} to {hi}" if hi else f"at least {lo}")
                comma = self.decimal_comma(node)
                if comma:
                    hint = f"'{comma}' reads as two arguments; the decimal separator is a " \
                           f"point: write {comma.replace(',', '.')}"
                elif n > (hi or n):
                    hint = "a decimal comma (1,5) splits a number into two arguments"
                else:
                    hint = f"write it as {lookup(node.func).signatures()}"
                self.rep.error(
                    f"{node.func} takes {want} argument{'s' if want != '1' else ''}, "
                    f"got {n}",
                    node.span,
                    hint,
                )
                continue
            for i in func.literal_args:
                arg = node.args[i]
                if not (isinstance(arg, ast.Num) and float(arg.value).is_integer()
                        and 1 <= arg.value <= MAX_STORE):
                    what = func.arg_names[i]
                    self.rep.error(
                        f"{what} of {node.func} must be a whole number written out, "
                        f"from 1 to {MAX_STORE}",
                        arg.span, f"e.g. {func.signature.replace(what, '100', 1)}")
            if allow is not None and func.kind not in allow:
                self.rep.error(
                    f"{node.func} cannot be used in {section}",
                    node.span,
                    "states, memory functions and IMPULS belong in DYNAMIC",
                )
            if func.kind == "table":
                first = node.args[0]
                if not isinstance(first, ast.Name) or first.name not in self.table_names:
                    label = first.name if isinstance(first, ast.Name) else "its first argument"
                    hint = nearest(label, self.table_names) if isinstance(first, ast.Name) else None
                    self.rep.error(
                        f"{node.func} needs a FUNCTION table as first argument; "
                        f"{label} is not one",
                        node.args[0].span,
                        f"did you mean {hint}?" if hint else
                        "define it with FUNCTION NAME = x1,y1, x2,y2, ...",
                    )

    def decimal_comma(self, node: ast.Call) -> str | None:
        lines = (self.program.source or "").split("\n")
        for a, b in zip(node.args, node.args[1:], strict=False):
            if isinstance(a, ast.Num) and isinstance(b, ast.Num):
                sa, sb = a.span, b.span
                if sa.end_line == sb.line and sa.end_column == sb.column - 1:
                    line = lines[sa.line - 1]
                    if line[sa.end_column - 1: sb.column - 1] == ",":
                        return line[sa.column - 1: sb.end_column - 1]
        return None

    # -------------------------------------------------------------- lowering
    def lower_pure(self, expr: ast.Expr) -> ast.Expr:
        """INITIAL/TERMINAL: switches evaluate literally; no states or memory."""
        return self.lower_expr(expr, None, literal=True)

    def lower_dynamic(self, st: ast.Assign) -> list[ir.Equation]:
        expr = st.expr
        func = lookup(expr.func, len(expr.args)) if isinstance(expr, ast.Call) else None
        if len(st.targets) == 2:
            if func is None or func.outputs != 2:
                self.rep.error("only OUTSW gives two values", st.span,
                               "write one assignment per variable")
                return []
            index = self.add_switch(expr, st.targets[0])
            return [ir.Equation(t, ir.SwitchValue(index, expr.span, k), st.span)
                    for k, t in enumerate(st.targets)]
        if len(st.targets) > 2:
            self.rep.error("at most two variables can be assigned together (OUTSW)", st.span)
            return []
        target = st.targets[0]
        if func is not None and func.kind == Kind.STATE:
            # a state function as the whole right-hand side: its state carries
            # the user's name where the output is the state (Y = REALPL(...))
            value = self.lower_state_function(expr, target)
            if isinstance(value, ast.Name) and value.name == target:
                return []
            return [ir.Equation(target, value, st.span)]
        if func is not None and func.outputs == 2:
            self.rep.error("OUTSW gives two values: write Y1, Y2 = OUTSW(X, V)", st.span)
            return []
        return [ir.Equation(target, self.lower_expr(expr, target), st.span)]

    def hidden(self, kind: str, owner: str | None) -> str:
        """A name for a state the listing does not name (a nested INTGRL, the
        inside of LEDLAG...): from the statement it sits in, so that the order of
        statements does not change the names (nor the order of the states)."""
        owner = owner or "?"
        self.hidden_counts[owner] = self.hidden_counts.get(owner, 0) + 1
        return f"{kind}#{owner}.{self.hidden_counts[owner]}"

    def lower_args(self, call: ast.Call, owner: str | None, literal: set[int] = frozenset()
                   ) -> tuple:
        """The call's arguments lowered once (those in `literal` as initial values:
        a switch there is evaluated once, at the start)."""
        return tuple(self.lower_expr(a, owner, literal=i in literal)
                     for i, a in enumerate(call.args))

    def note_constants(self, func: Func, call: ast.Call) -> None:
        """Arguments that must be known before the run are checked like initial values."""
        for i in func.constant_args:
            self.ic_exprs.append((call.args[i], f"{func.arg_names[i]} of {call.func}"))

    def lower_state_function(self, call: ast.Call, target: str | None,
                             owner: str | None = None) -> ast.Expr:
        """INTGRL, REALPL, LEDLAG, CMPXPL, MODINT...: the states of the entry, named
        after the assigned variable or hidden, and the call's value over them."""
        func = lookup(call.func, len(call.args))
        sp = call.span
        owner = target or owner or "?"
        in_ic = {i for s in func.states for i in _arguments_of(s.ic)}
        in_rest = {i for s in func.states for i in _arguments_of(s.deriv)}
        in_rest |= {i for t in (*func.values, *func.surfaces) for i in _arguments_of(t)}
        args = self.lower_args(call, owner, literal=in_ic - in_rest)
        resets = tuple(
            self.add_surface(instantiate(t, args, sp), func.surface_kind, None,
                             ir.Purpose.SWITCH, sp, f"{call.func} surface {k + 1} for {owner}")
            for k, t in enumerate(func.surfaces))
        named = [k == 0 and bool(target) and s.named for k, s in enumerate(func.states)]
        names = tuple(target if named[k] else self.hidden(s.tag, owner)
                      for k, s in enumerate(func.states))
        for k, spec in enumerate(func.states):
            if _arguments_of(spec.ic):
                self.ic_exprs.append((instantiate(spec.ic, call.args, sp), "the initial value"))
            self.states.append(ir.State(
                names[k], instantiate(spec.ic, args, sp, names),
                instantiate(spec.deriv, args, sp, names), sp, not named[k],
                reset_surfaces=resets if k == 0 else ()))
        return instantiate(func.values[0], args, sp, names)

    def add_surface(self, expr, kind, owner, purpose, span, description) -> int:
        index = len(self.surfaces)
        self.surfaces.append(ir.Surface(index, expr, ir.SurfaceKind(kind), owner,
                                        ir.Purpose(purpose), ir.Depends.STATE, span,
                                        description))
        return index

    def add_memory(self, call: ast.Call, target: str | None) -> int:
        func = lookup(call.func, len(call.args))
        self.note_constants(func, call)
        args = self.lower_args(call, target)
        index = len(self.memories)
        surfaces = tuple(
            self.add_surface(instantiate(t, args, call.span), func.surface_kind, index,
                             ir.Purpose.MEMORY, call.span,
                             f"{call.func} for {target} (line {call.span.line})")
            for t in func.surfaces)
        nslots = int(constant_value(instantiate(func.memory.slots, call.args, call.span), {}))
        self.memories.append(ir.Memory(index, func.name, args, self.nslots, nslots, surfaces,
                                       call.span, target or "?", call.func))
        self.nslots += nslots
        return index

    def add_switch(self, call: ast.Call, target: str) -> int:
        func = lookup(call.func, len(call.args))
        args = self.lower_args(call, target)
        index = len(self.switches)
        surfaces = []
        for k, template in enumerate(func.surfaces):
            desc = f"{call.func} for {target} (line {call.span.line})"
            if len(func.surfaces) > 1:
                desc += f", surface {k + 1}"
            surfaces.append(self.add_surface(instantiate(template, args, call.span),
                                             func.surface_kind, index, ir.Purpose.SWITCH,
                                             call.span, desc))
        self.switches.append(ir.Switch(index, func.name, args, tuple(surfaces), call.span,
                                       target, call.func))
        return index

    def lower_expr(self, expr: ast.Expr, target: str | None, literal: bool = False):
        """Replace simulation-function calls by IR nodes."""
        return _Lowerer(self, target, literal).visit(expr)

    # ----------------------------------------------------------------- sorting
    def sort(self, equations: list[ir.Equation], targets: set[str], section: str):
        """Order equations so each follows what it reads; report algebraic loops."""
        by_target = {e.target: e for e in equations}
        deps: dict[str, list[str]] = {}
        for e in equations:
            seen: list[str] = []
            for n in names_in(e.expr, self):
                if n in targets and n != e.target and n not in seen:
                    seen.append(n)
                elif n == e.target:
                    seen.append(n)
            deps[e.target] = seen
        order: list[ir.Equation] = []
        state = {t: 0 for t in by_target}  # 0 new, 1 on stack, 2 done
        reported: set[frozenset[str]] = set()
        for root in by_target:
            if state[root]:
                continue
            # iterative DFS, keeping the path to report cycles
            stack = [(root, iter(deps[root]))]
            path = [root]
            state[root] = 1
            while stack:
                node, it = stack[-1]
                nxt = next(it, None)
                if nxt is None:
                    stack.pop()
                    path.pop()
                    state[node] = 2
                    order.append(by_target[node])
                    continue
                if state[nxt] == 1:
                    cycle = path[path.index(nxt):]
                    key = frozenset(cycle)
                    if key not in reported:
                        reported.add(key)
                        self.loop_error(cycle, by_target, section)
                    continue
                if state[nxt] == 0:
                    state[nxt] = 1
                    path.append(nxt)
                    stack.append((nxt, iter(deps[nxt])))
        return order

    def loop_error(self, cycle: list[str], by_target, section: str) -> None:
        first = by_target[cycle[0]]
        chain = " -> ".join(cycle + [cycle[0]])
        related = tuple((by_target[n].span, f"{n} is computed here") for n in cycle[1:])
        self.rep.error(
            f"algebraic loop in {section}: {chain}",
            first.span,
            "every variable of the loop needs the others at the same instant; break it with "
            "a state (INTGRL), e.g. a fast first-order lag REALPL",
            related=related,
        )

def _arguments_of(template: str) -> set[int]:
    """The argument positions a template reads."""
    return {ARGUMENTS.index(c) for c in template_names(template) if len(c) == 1
            and c in ARGUMENTS}


class _Lowerer(Visitor):
    """Lowers one expression: simulation-function calls become IR nodes."""

    complete = ast.EXPRESSIONS

    def __init__(self, checker: _Checker, target: str | None, literal: bool) -> None:
        self.checker = checker
        self.target = target
        self.literal = literal

    def visit_Num(self, expr: ast.Num):
        return expr

    def visit_Name(self, expr: ast.Name):
        return expr

    def visit_Neg(self, expr: ast.Neg):
        return ast.Neg(self.visit(expr.operand), expr.span)

    def visit_BinOp(self, expr: ast.BinOp):
        return ast.BinOp(expr.op, self.visit(expr.left), self.visit(expr.right), expr.span)

    def visit_Call(self, expr: ast.Call):
        checker, target = self.checker, self.target
        func = lookup(expr.func, len(expr.args))
        if func is None:
            return expr
        if func.kind == "math":
            return ast.Call(expr.func, tuple(self.visit(a) for a in expr.args), expr.span,
                            expr.arg_spans)
        if func.kind == "table":
            name = expr.args[0].name if isinstance(expr.args[0], ast.Name) else "?"
            return ir.TableLookup(name, self.visit(expr.args[1]), func.lookup, expr.span,
                                  expr.func)
        if self.literal:
            if func.kind in ("switch", "time"):
                # INITIAL/TERMINAL: a switch is evaluated once, literally
                return ast.Call(expr.func, tuple(self.visit(a) for a in expr.args), expr.span)
            return expr
        if func.kind == "state":
            return checker.lower_state_function(expr, None, owner=target)
        if func.kind in ("switch", "time"):
            if func.outputs == 2:
                checker.rep.error("OUTSW gives two values: write Y1, Y2 = OUTSW(X, V)",
                                  expr.span)
                return ast.Num(0.0, expr.span)
            return ir.SwitchValue(checker.add_switch(expr, target or "?"), expr.span)
        if func.kind == "impulse":
            return ir.Impulse(self.visit(expr.args[0]), self.visit(expr.args[1]), expr.span)
        if func.kind == "memory":
            return ir.MemoryValue(checker.add_memory(expr, target), expr.span)
        return expr


class _Reads(Visitor):
    """Collects the variable names an IR expression reads, through switch and memory
    arguments (each instance entered once)."""

    def __init__(self, checker: _Checker) -> None:
        self.checker = checker
        self.names: list[str] = []
        self.pending: list = []
        self.seen: set[tuple[str, int]] = set()

    def generic(self, node) -> None:
        pass

    def visit_Name(self, node: ast.Name) -> None:
        self.names.append(node.name)

    def visit_SwitchValue(self, node: ir.SwitchValue) -> None:
        if ("s", node.switch) not in self.seen:
            self.seen.add(("s", node.switch))
            self.pending.extend(self.checker.switches[node.switch].args)

    def visit_MemoryValue(self, node: ir.MemoryValue) -> None:
        if ("m", node.memory) not in self.seen:
            self.seen.add(("m", node.memory))
            self.pending.extend(self.checker.memories[node.memory].args)


def names_in(expr, checker) -> list[str]:
    """Variable names an IR expression reads, including through switch/memory args."""
    reads = _Reads(checker)
    reads.pending.append(expr)
    while reads.pending:
        for node in ast.walk(reads.pending.pop()):
            reads.visit(node)
    return reads.names
