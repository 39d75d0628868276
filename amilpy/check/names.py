"""Names and calls: one definition per name, known functions with the right arguments,
and every name a statement, an initial value, a report, FINISH or a per-variable
tolerance reads known where it is read (a misspelt one gets the nearest known name)."""

from __future__ import annotations

import math

from ..diagnostics import Reporter, Span, did_you_mean, nearest
from ..language import (
    KNOWN_BEFORE_RUN,
    REFUSED_FUNCTIONS,
    RESERVED,
    SETTINGS,
    TIME,
    split_lines,
)
from ..library import Kind, callable_names, lookup
from ..library.surfaces import constant_value
from ..library.weather import NAMES as WEATHER_NAMES
from ..parse import syntax as ast
from .groups import Data, check_assignable

# the largest store a function's literal argument may ask for (DELAY's N points)
MAX_STORE = 100_000

# what each section may call
PURE = (Kind.MATH, Kind.TABLE, Kind.SWITCH, Kind.TIME)  # INITIAL, TERMINAL: evaluated once


def reserved_names(program: ast.Program) -> tuple[str, ...]:
    """The names the listing may not assign: an FST or ACSL listing's own PI is a variable of
    it (`Program.own_pi`)."""
    return tuple(n for n in RESERVED if n != "PI") if program.own_pi else RESERVED


class Names:
    """Definitions and references of one listing."""

    def __init__(self, rep: Reporter, program: ast.Program, data: Data) -> None:
        self.rep = rep
        self.program = program
        self.source_lines = split_lines(program.source or "")
        self.data = data
        self.data_names = set(data.names)
        self.table_names = set(data.tables)
        self.defined: dict[str, Span] = {}
        self.where: dict[str, str] = {}  # name -> the section that computes it
        self.form = program.form
        self.reserved: tuple[str, ...] = reserved_names(program)
        self.own_pi = program.own_pi
        self.functions: dict[str, int] = {}  # FUNCTIONs the listing defines -> arity

    # definitions -----------------------------------------------------------------
    def define(self, target: str, span: Span, where: str) -> bool:
        if not check_assignable(target, span, "assigned", self.rep, self.reserved):
            return False
        if target in self.defined:
            first = self.defined[target]
            self.rep.error(
                f"{target} is defined twice",
                span,
                f"first defined at line {first.line}; a name has one definition",
                related=((first, f"{target} first defined here"),),
            )
            return False
        if target in self.data_names:
            self.rep.error(
                f"{target} is both a data value and computed",
                span,
                f"it is given a value at line {self.data.spans[target].line}; drop one of them",
            )
            return False
        self.defined[target] = span
        self.where[target] = where
        return True

    # calls -----------------------------------------------------------------------
    def check_calls(self, expr: ast.Node, allow: tuple[Kind, ...] | None, section: str) -> bool:
        """Report unknown functions, wrong argument counts and misplaced functions;
        False if any."""
        before = self.rep.errors
        for node in ast.walk(expr):
            if isinstance(node, ast.Call):
                self.check_call(node, allow, section)
        return self.rep.errors == before

    def check_call(self, node: ast.Call, allow, section: str) -> None:
        entry = lookup(node.func)
        if entry is None and node.func in self.functions:
            wanted = self.functions[node.func]
            if len(node.args) != wanted:
                self.rep.error(f"FUNCTION {node.func} takes {wanted} "
                               f"argument{'s' if wanted != 1 else ''}, got {len(node.args)}",
                               node.span)
            return
        if entry is None:
            self.unknown_function(node)
            return
        n = len(node.args)
        func = entry.form(n)
        lo, hi = func.nargs
        if n < lo or (hi is not None and n > hi):
            want = entry.counts()
            comma = self.decimal_comma(node)
            if comma:
                hint = f"'{comma}' reads as two arguments; the decimal separator is a " \
                       f"point: write {comma.replace(',', '.')}"
            else:
                notes = "; ".join(f"{f.signature}: {f.note}" if f.note else f.signature
                                  for f in (entry, *entry.variants))
                hint = f"write it as {notes}"
            self.rep.error(f"{node.func} takes {want} argument{'s' if want != '1' else ''}, "
                           f"got {n}", node.span, hint)
            return
        for i in func.literal_args:
            arg = node.args[i]
            if not (isinstance(arg, ast.Num) and float(arg.value).is_integer()
                    and 1 <= arg.value <= MAX_STORE):
                what = func.arg_names[i]
                self.rep.error(f"{what} of {node.func} must be a whole number written out, "
                               f"from 1 to {MAX_STORE}", arg.span,
                               f"e.g. {func.signature.replace(what, '100', 1)}")
        self.check_argument_values(node, func)
        # where only plain functions may stand (INTERVAL), a switch's plain form may too
        # (a name with a dot is the reader's own: a routine's value before its CALL,
        # whose fault is the CALL's, said there)
        if allow is not None and func.kind not in allow and \
                not (func.plain and Kind.MATH in allow) and not node.func.startswith("."):
            self.rep.error(f"{node.func} cannot be used in {section}", node.span,
                           "compute its argument in the block and put the call after it, "
                           "outside" if section.startswith("an IF") else
                           "states, memory functions and IMPULS belong in "
                           + ("DERIVATIVE" if self.form == "ACSL" else "DYNAMIC"))
        if func.kind == Kind.TABLE:
            self.check_table_argument(node)

    def check_argument_values(self, node: ast.Call, func) -> None:
        """Arguments that must be positive (PULSE's P) or not negative, where their
        value is known from the data (else the run checks them)."""
        for i in (*func.positive_args, *func.nonnegative_args):
            for spec in self.data.runs:
                value = constant_value(node.args[i], {**spec.data, "PI": math.pi})
                fault = None if value is None else func.argument_fault(i, value)
                if fault:
                    self.rep.error(fault, node.args[i].span,
                                   f"{func.signature}: {func.doc}")
                    break

    def unknown_function(self, node: ast.Call) -> None:
        if node.func == "IMPL":
            self.rep.error("IMPL stands as a statement of its own in DYNAMIC (CSMP form)",
                           node.span, "write Y = IMPL(IC, P, FOFY) in DYNAMIC, then the "
                           "statements that compute FOFY from Y, ending with FOFY = ...")
            return
        if node.func in REFUSED_FUNCTIONS:
            what, hint = REFUSED_FUNCTIONS[node.func]
            self.rep.error(f"{what} (line {node.span.line}): not supported", node.span, hint)
            return
        if node.func in self.defined or node.func in self.data_names:
            self.rep.error(f"{node.func} is a variable, not a function or an array",
                           node.span, f"to read {node.func} as an array, declare it: "
                           f"DIMENSION {node.func}(n)")
            return
        self.rep.error(f"unknown function {node.func}", node.span,
                       did_you_mean(node.func, callable_names() | set(self.functions)) or
                       "see the function list in docs/language.md")

    def check_table_argument(self, node: ast.Call) -> None:
        first = node.args[0]
        if isinstance(first, ast.Name) and first.name in self.table_names:
            return
        label = first.name if isinstance(first, ast.Name) else "its first argument"
        hint = did_you_mean(label, self.table_names) if isinstance(first, ast.Name) else ""
        self.rep.error(
            f"{node.func} needs a FUNCTION table as first argument; {label} is not one",
            first.span,
            hint or "define it with FUNCTION NAME = x1,y1, x2,y2, ...",
        )

    def decimal_comma(self, node: ast.Call) -> str | None:
        """`1,5` where the listing meant 1.5: two number arguments one comma apart."""
        for a, b in zip(node.args, node.args[1:], strict=False):
            if isinstance(a, ast.Num) and isinstance(b, ast.Num):
                sa, sb = a.span, b.span
                if sa.end_line == sb.line and sa.end_column == sb.column - 1 \
                        and 1 <= sa.line <= len(self.source_lines):
                    line = self.source_lines[sa.line - 1]
                    if line[sa.end_column - 1: sb.column - 1] == ",":
                        return line[sa.column - 1: sb.end_column - 1]
        return None

    # references ------------------------------------------------------------------
    def check_references(self, sections: dict[str, list[ast.Node]],
                         before_run: list[tuple[ast.Node, str]], states: set[str]) -> None:
        """Every name read is known: in DYNAMIC and TERMINAL anything defined; in
        INITIAL and in values needed before the run (`before_run`, with what they are)
        only data and INITIAL values. Then the names of reports, FINISH and tolerances."""
        known = set(self.defined) | self.data_names | set(RESERVED) | self.weather_names
        initial_names = {t for st in sections["INITIAL"] for t in getattr(st, "targets", ())}
        initial_ok = self.data_names | initial_names | KNOWN_BEFORE_RUN
        # a table name as AFGEN's first argument is no value
        table_args = {id(node.args[0]) for section in sections.values() for st in section
                      for node in ast.walk(st)
                      if isinstance(node, ast.Call) and node.args
                      and getattr(lookup(node.func), "kind", None) == Kind.TABLE}

        def names_of(expr):
            return (node for node in ast.walk(expr)
                    if isinstance(node, ast.Name) and id(node) not in table_args)

        for st in sections["INITIAL"]:
            for node in names_of(st):
                if node.name in initial_ok:
                    continue
                if node.name in self.defined:
                    self.rep.error(
                        f"INITIAL uses {node.name}, which is computed in "
                        f"{self.where[node.name]}", node.span,
                        "INITIAL runs once before the dynamics; it can use data values and "
                        "other INITIAL values only")
                else:
                    self.undefined(node, known)
        for st in sections["DYNAMIC"] + sections["TERMINAL"]:
            for node in names_of(st):
                if node.name not in known:
                    self.undefined(node, known)
        weather = self.weather_names - set(self.defined)
        for st in sections["TERMINAL"]:
            for node in names_of(st):
                if node.name in weather:
                    self.undefined(node, known - weather)
        for expr, what in before_run:
            for node in names_of(expr):
                if node.name in initial_ok:
                    continue
                if node.name in self.defined:
                    self.rep.error(f"{what} uses {node.name}, which changes in time", node.span,
                                   f"{what} must be a number, a data value or an INITIAL value")
                else:
                    self.undefined(node, known)
        self.check_named(known, states)

    def check_named(self, known: set[str], states: set[str]) -> None:
        """Reports and FINISH name known quantities; RELERR/ABSERR X=... name states."""
        # (an FST or ACSL listing's own PI is a quantity of it)
        report_known = known - (SETTINGS - ({"PI"} if self.own_pi else set()))
        for st in self.data.reports:
            named = list(zip(st.names, st.name_spans, strict=True))
            if st.x is not None:
                named.append((st.x, st.x_span))
            for n, s in named:
                if n not in report_known and n != TIME and not self.refused_definition(n):
                    self.rep.error(f"{st.kind} names {n}, which the model never defines", s,
                                   did_you_mean(n, report_known - {TIME}) or None)
        for st in self.data.finish_relations:
            for node in ast.walk(st.expr):
                if isinstance(node, ast.Name) and node.name not in known:
                    self.undefined(node, known)
        for s in self.data.finish:
            if s.name not in known:
                self.rep.error(f"FINISH names {s.name}, which the model never defines", s.span,
                               did_you_mean(s.name, known) or None)
        for kind, s in self.data.tolerances:
            if s.name in states:
                continue
            what = "is not a state" if s.name in known else "is not a variable of the model"
            hint = nearest(s.name, states)
            self.rep.error(
                f"{kind} names {s.name}, which {what}", s.span,
                (f"did you mean {hint}? " if hint else "")
                + "a per-variable tolerance applies to a state (an INTGRL output)"
                + ("" if hint or not states else ": " + ", ".join(sorted(states)[:8])))

    def refused_definition(self, name: str) -> bool:
        """Whether a statement the listing writes assigns `name` and a fault has been said
        (that statement refused, or the block around it): "never defines" would follow
        that fault and point at the wrong line."""
        if not self.rep.errors:
            return False
        if not hasattr(self, "_written"):
            self._written = {t for st in self.program.statements for n in ast.walk(st)
                             for t in (n.targets if isinstance(n, ast.Assign) else
                                       n.outputs if isinstance(n, ast.Procedural) else ())}
        return name in self._written

    @property
    def weather_names(self) -> set[str]:
        """FST's weather names, when the listing has a WEATHER statement."""
        return set(WEATHER_NAMES) if self.data.weather is not None else set()

    def undefined(self, node: ast.Name, known: set[str]) -> None:
        if "#" in node.name:
            # (a name the reader made -- a routine's own, a FUNCTION's value, a GO TO's
            # flag -- is defined with what made it, unless that was refused: said there)
            return
        if node.name in WEATHER_NAMES and node.name not in self.defined:
            if self.data.weather is not None:
                self.rep.error(f"{node.name} is the day's weather, which changes in time",
                               node.span, f"read {node.name} in the dynamic statements (assign "
                               "it to a variable there), not in INITIAL, TERMINAL or an "
                               "initial value")
            else:
                self.rep.error(f"{node.name} is used but never defined", node.span,
                               f"{node.name} is an FST weather variable: add a WEATHER "
                               "statement (WEATHER CNTR = 'NLD'; ISTN = 1; IYEAR = 1990), "
                               "or define it")
            return
        if node.name in self.table_names:
            self.rep.error(f"{node.name} is a FUNCTION table, not a value", node.span,
                           f"look it up with AFGEN({node.name}, X)")
            return
        if node.name == "T" and self.form == "CSMP":
            self.rep.error("T is used but never defined", node.span,
                           "time is TIME in this form; a file that starts with PROGRAM or "
                           "MODEL is in ACSL form, where time is T")
            return
        self.rep.error(
            f"{node.name} is used but never defined", node.span,
            " ".join(filter(None, [did_you_mean(node.name, known - {"DELMIN", "DELMAX"}),
                                   "give it a value with PARAM/CONST/INCON or an equation"])),
        )
