"""Run groups and data: END splits a listing into groups, each giving one or more runs
(a value list gives one run per value); data and control statements become the
`RunSpec`s. Every TIMER key, METHOD and tolerance value is checked here; the names
that reports, FINISH and per-variable tolerances mention are kept for `names`,
which knows the model's variables.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from .. import ir
from ..diagnostics import Reporter, Span, did_you_mean
from ..language import (
    DRIVERS,
    IGNORED_TIMER_KEYS,
    RESERVED,
    START_KEY,
    TIME,
    TIMER_KEYS,
    TRANSLATION_FSE_DRIVER,
    TRANSLATION_KEYS,
    WEATHER_KEYS,
)
from ..library.weather import WeatherSpec
from ..parse import syntax as ast
from ..parse.syntax import Visitor
from ..routes import method_names, route_for

# what may stand in a run group after the first END
DATA_STATEMENTS = (ast.Data, ast.Table, ast.Timer, ast.Method, ast.Tolerance, ast.Finish,
                   ast.Report, ast.Label, ast.Title, ast.Translation, ast.Weather,
                   ast.DefineCall)

Table = tuple[tuple[float, ...], tuple[float, ...]]


@dataclass
class Data:
    """What the data and control statements of all run groups give."""

    runs: list[ir.RunSpec]
    names: list[str]  # PARAM/CONST/INCON names, in the order first given
    spans: dict[str, Span]
    kinds: dict[str, str]
    tables: dict[str, Table]
    finish: list[ast.Setting]  # FINISH items of the first group
    reports: list[ast.Report]  # every report statement, for the name checks
    tolerances: list[tuple[str, ast.Setting]]  # (RELERR or ABSERR, NAME = value)
    finish_relations: list[ast.Termt] = field(default_factory=list)  # FINISH X > v
    weather: WeatherSpec | None = None  # the WEATHER statements' station and year


def split_groups(program: ast.Program) -> list[list[ast.Node]]:
    """The statements of each run group (END ends one, STOP the file)."""
    groups: list[list[ast.Node]] = [[]]
    for st in program.statements:
        if isinstance(st, ast.Stop):
            break
        if isinstance(st, ast.End):
            groups.append([])
            continue
        groups[-1].append(st)
    if len(groups) > 1 and all(isinstance(s, ast.Title) for s in groups[-1]):
        groups.pop()  # a final END (or END followed by STOP) opens no new run
    return groups


# statements of the ACSL form: in a CSMP-form file, an error that says so
# (a Procedural in a CSMP-form file is CSMP III's PROCEDURE ... ENDPRO: the reader
# refuses ACSL's PROCEDURAL there)
ACSL_STATEMENTS = (ast.Schedule, ast.Interval, ast.Cinterval, ast.Variable, ast.Control,
                   ast.Block, ast.FunctionDef)


def sections(group: list[ast.Node], rep: Reporter) -> dict[str, list[ast.Node]]:
    """The equations of the first group by section (none: DYNAMIC); TERMT stands in
    DYNAMIC only. IF blocks stand in DYNAMIC (a sorting unit) and TERMINAL, DO loops
    in TERMINAL (written order). FST's EVENT blocks (under "EVENT") stand anywhere but
    in TERMINAL, its SET statements (under "SET", and as INITIAL's assignments) in
    INITIAL."""
    out: dict[str, list[ast.Node]] = {"INITIAL": [], "DYNAMIC": [], "TERMINAL": [],
                                      "EVENT": [], "SET": []}
    current = "DYNAMIC"
    for st in group:
        if isinstance(st, ast.Section):
            current = st.name
        elif isinstance(st, ast.SetValue):
            if current != "INITIAL":
                rep.error(f"SET cannot stand in {current}", st.span,
                          "SET X = value gives a variable its first value: write it in "
                          "INITIAL; an EVENT's NEWVALUE X = value changes it later")
                continue
            out["SET"].append(st)
            out["INITIAL"].append(ast.Assign((st.target,), (st.target_span,), st.expr,
                                             st.span))
        elif isinstance(st, ast.Event):
            if current == "TERMINAL":
                rep.error("an EVENT cannot stand in TERMINAL", st.span,
                          "TERMINAL runs once, after the run: put the EVENT in DYNAMIC")
                continue
            out["EVENT"].append(st)
        elif isinstance(st, ast.Termt) and current != "DYNAMIC":
            rep.error(f"TERMT cannot stand in {current}", st.span,
                      "TERMT(expr) ends the run when expr turns positive: put it in DYNAMIC")
        elif isinstance(st, ast.If) and current == "INITIAL":
            rep.error("an IF block cannot stand in INITIAL in CSMP form", st.span,
                      "compute the value with FSW or INSW, or write the listing in ACSL "
                      "form (PROGRAM ... END), whose INITIAL runs in written order")
        elif isinstance(st, ast.Loop) and current != "TERMINAL":
            rep.error(f"a DO loop cannot stand in {current}", st.span,
                      "loops run in written-order code: TERMINAL, or a PROCEDURAL block "
                      "of the ACSL form")
        elif isinstance(st, ACSL_STATEMENTS):
            rep.error(f"{type(st).__name__.upper()} belongs to the ACSL form", st.span,
                      "start the file with PROGRAM or MODEL (ACSL form)")
        elif isinstance(st, ast.Procedural):  # CSMP III's PROCEDURE ... ENDPRO
            if current == "INITIAL":
                rep.error("a PROCEDURE block (or a CALL of a subroutine, or a reference to "
                          "a FUNCTION written after STOP) cannot stand in INITIAL", st.span,
                          "INITIAL is sorted: write the statements out there, or put the "
                          "PROCEDURE, the CALL or the reference in DYNAMIC")
            elif current == "TERMINAL":
                out[current].extend(st.body)  # written order there anyway
            else:
                out[current].append(st)
        elif isinstance(st, (ast.Assign, ast.Termt, ast.If, ast.Loop, ast.Nosort)):
            out[current].append(st)
    return out


def reject_late_equations(groups: list[list[ast.Node]], rep: Reporter) -> None:
    for later in groups[1:]:
        for st in later:
            if not isinstance(st, DATA_STATEMENTS):
                rep.error(
                    "only data and control statements may follow the first END",
                    st.span,
                    "a later run group may change PARAM, TIMER, METHOD, PRINT ...; "
                    "equations belong before the first END",
                )


def check_assignable(name: str, span: Span, what: str, rep: Reporter,
                     reserved: tuple[str, ...] = RESERVED) -> bool:
    if name in reserved:
        if reserved == (TIME,):  # (the ACSL form's, where only time is reserved)
            rep.error(f"{name} is time and cannot be {what}", span,
                      "time is T (its name may be changed with VARIABLE)")
            return False
        rep.error(
            f"{name} is a reserved name and cannot be {what}",
            span,
            ", ".join(RESERVED[:-1]) + f" and {RESERVED[-1]} are read-only; "
            "set the TIMER values with a TIMER statement",
        )
        return False
    # a variable may be named like a function (CSMP allows it): calls have '('
    return True


@dataclass
class _Group:
    """What one run group changes; reports and titles replace the inherited ones
    when the group has any."""

    index: int
    lists: dict[str, tuple[float, ...]] = field(default_factory=dict)
    reports: list[ir.Report] | None = None
    titles: list[str] | None = None
    weather: bool = False  # it has a WEATHER statement


class RunGroups(Visitor):
    """Reads every run group's data and control statements into RunSpecs."""

    complete = DATA_STATEMENTS

    def __init__(self, rep: Reporter, reserved: tuple[str, ...] = RESERVED) -> None:
        self.rep = rep
        self.reserved = reserved  # (an FST or ACSL listing's own PI is no reserved name)
        self.data: dict[str, float] = {}
        self.spans: dict[str, Span] = {}
        self.kinds: dict[str, str] = {}
        self.tables: dict[str, Table] = {}
        self.table_spans: dict[str, Span] = {}
        self.timer: dict[str, float] = {}
        self.timer_spans: dict[str, Span] = {}
        self.timer_span: Span | None = None  # the first group's first TIMER statement
        self.method: str | None = None
        self.driven: str | None = None  # the METHOD a DRIVER set (not the listing's own)
        self.tolerance: dict[str, float | None] = {"RELERR": None, "ABSERR": None}
        self.each: dict[str, dict[str, float]] = {"RELERR": {}, "ABSERR": {}}
        self.reports: list[ir.Report] = []
        self.titles: list[str] = []
        self.finish: list[ast.Setting] = []
        self.finish_relations: list[ast.Termt] = []
        self.driver: tuple[str, Span] | None = None  # FST's DRIVER and where
        self.weather_items: dict[str, ast.Item] = {}
        self.weather_span: Span | None = None
        self.weather: WeatherSpec | None = None  # the runs' of the group being read
        self.all_reports: list[ast.Report] = []
        self.all_tolerances: list[tuple[str, ast.Setting]] = []
        self.runs: list[ir.RunSpec] = []
        self.base: dict[str, float] | None = None
        self.group = _Group(0)

    def read(self, groups: list[list[ast.Node]], needs_fintim: bool = True) -> Data:
        """`needs_fintim`: CSMP form; in ACSL form a TERMT may bound the run instead."""
        finish_first: list[ast.Setting] = []
        relations_first: list[ast.Termt] = []
        for gi, group in enumerate(groups):
            self.group = _Group(
                gi, reports=[] if any(isinstance(s, ast.Report) for s in group) else None,
                titles=[] if any(isinstance(s, ast.Title) for s in group) else None)
            for st in group:
                if isinstance(st, DATA_STATEMENTS):
                    self.visit(st)
            if self.group.reports is not None:
                self.reports = self.group.reports
            if self.group.titles is not None:
                self.titles = self.group.titles
            self.check_driver()  # a driver given here holds from this group on
            if gi == 0:
                finish_first = list(self.finish)
                relations_first = list(self.finish_relations)
                start, end = self.timer.get(START_KEY), self.timer.get("FINTIM")
                if start is not None and end is not None and not end > start:
                    self.rep.error(f"FINTIM = {end:g} is not after STTIME = {start:g}",
                                   self.timer_spans.get("FINTIM"),
                                   "with STTIME (FST), FINTIM is the end time, not a length")
                if "FINTIM" not in self.timer and needs_fintim:
                    self.rep.error(
                        "FINTIM is not given", self.timer_span,
                        "add FINTIM to this TIMER statement, e.g. FINTIM = 1.0"
                        if self.timer_span else
                        "add a TIMER statement, e.g. TIMER FINTIM = 1.0, PRDEL = 0.01")
            self.add_runs()
        if not self.runs:
            self.rep.error("the listing has no statements", None)
        # a value first given after an END exists only for the runs from there on
        for name, span in [*self.spans.items(), *self.table_spans.items()]:
            if self.runs and name not in self.runs[0].data and name not in self.runs[0].tables:
                self.rep.error(
                    f"{name} has no value in the first run: it is first given after an END",
                    span,
                    f"give {name} a value before the first END; a statement after END "
                    "changes it for the runs that follow",
                )
        return Data(self.runs, list(self.data), self.spans, dict(self.kinds), self.tables,
                    finish_first, self.all_reports, self.all_tolerances, relations_first,
                    self.runs[0].weather if self.runs else None)

    def add_runs(self) -> None:
        """The runs of the group just read: one per value of its value lists."""
        lists = self.group.lists
        lengths = {len(v) for v in lists.values()}
        if len(lengths) > 1:
            first = next(iter(lists))
            self.rep.error(
                "value lists in one run group must have the same length",
                self.spans.get(first),
                ", ".join(f"{k} has {len(v)}" for k, v in lists.items()),
            )
        # (FST's reruns: a WEATHER after an END, IYEAR = 2011 say, is that run's)
        if self.group.index == 0 or self.group.weather:
            self.weather = self.weather_spec()
        for k in range(max(lengths) if lengths else 1):
            values = dict(self.data)
            for lname, lvalues in lists.items():
                values[lname] = lvalues[min(k, len(lvalues) - 1)]
            if self.base is None:
                self.base = dict(values)
            changed = {n: v for n, v in values.items() if self.base.get(n) != v}
            if lists:
                changed.update({n: values[n] for n in lists})
            label = ", ".join(f"{n} = {v:g}" for n, v in changed.items())
            first = self.runs[0].weather if self.runs else self.weather
            if self.weather is not None and first is not None and self.weather.what != first.what:
                label = ", ".join(filter(None, [label, self.weather.what]))
            self.runs.append(ir.RunSpec(
                label=label or ("RUN 1" if self.group.index == 0 else f"RUN {len(self.runs) + 1}"),
                data=values, changed=changed, tables=dict(self.tables), timer=dict(self.timer),
                method=self.method, relerr=self.tolerance["RELERR"],
                abserr=self.tolerance["ABSERR"], relerr_each=dict(self.each["RELERR"]),
                abserr_each=dict(self.each["ABSERR"]), reports=list(self.reports),
                titles=list(self.titles), timer_spans=dict(self.timer_spans),
                step_point=DRIVERS[self.driver[0]][1] if self.driver else None,
                weather=self.weather,
            ))
        # a later group inherits everything; value lists collapse to their first value
        for lname in lists:
            self.data[lname] = lists[lname][0]

    # statements ----------------------------------------------------------------
    def visit_Data(self, st: ast.Data) -> None:
        for item in st.items:
            check_assignable(item.name, item.span, "a data value", self.rep, self.reserved)
            again = item.name in self.spans and self.kinds.get(item.name)
            if again and st.keyword == "CONST" == self.kinds[item.name] and \
                    not item.is_list and item.name not in self.group.lists and \
                    self.data.get(item.name) == item.values[0]:
                continue  # (the same value again: Magnolia listings repeat a CONSTANT)
            if self.group.index == 0 and again:
                self.rep.error(
                    f"{item.name} is given a value twice",
                    item.span,
                    f"first given at line {self.spans[item.name].line}",
                )
            self.spans.setdefault(item.name, item.span)
            self.kinds[item.name] = st.keyword
            self.data[item.name] = item.values[0]
            if item.is_list:
                self.group.lists[item.name] = item.values

    def visit_Table(self, st: ast.Table) -> None:
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
        self.tables[st.name] = (st.xs, st.ys)
        self.table_spans.setdefault(st.name, st.span)

    def visit_Timer(self, st: ast.Timer) -> None:
        if self.group.index == 0 and self.timer_span is None:
            self.timer_span = st.span
        for s in st.settings:
            if s.name in IGNORED_TIMER_KEYS:
                continue  # FST's output and translator settings: nothing to do here
            if s.name == START_KEY:
                if not math.isfinite(s.value):
                    self.rep.error(f"{s.name} must be a finite number (got {s.value:g})",
                                   s.span)
                self.timer[s.name] = s.value
                self.timer_spans[s.name] = s.span
                continue
            if s.name not in TIMER_KEYS:
                self.rep.error(
                    f"unknown TIMER setting {s.name}",
                    s.span,
                    did_you_mean(s.name, {*TIMER_KEYS, START_KEY})
                    or "TIMER takes " + ", ".join(TIMER_KEYS),
                )
            elif not math.isfinite(s.value):
                self.rep.error(f"{s.name} must be a finite number (got {s.value:g})", s.span)
            elif s.value <= 0 and s.name != "DELMIN":
                self.rep.error(f"{s.name} must be positive (got {s.value:g})", s.span)
            self.timer[s.name] = s.value
            self.timer_spans[s.name] = s.span

    def visit_Method(self, st: ast.Method) -> None:
        if route_for(st.name) is None:
            self.rep.error(
                f"unknown integration method {st.name}",
                st.span,
                " ".join(filter(None, [did_you_mean(st.name, method_names()),
                                       "known: " + ", ".join(method_names())])),
            )
        self.method = st.name

    def visit_Tolerance(self, st: ast.Tolerance) -> None:
        if st.default is not None:
            if not st.default > 0:
                self.rep.error(f"{st.kind} must be positive", st.span)
            self.tolerance[st.kind] = st.default
        for s in st.settings:
            if not s.value > 0:
                self.rep.error(f"{st.kind} must be positive", s.span)
            self.each[st.kind][s.name] = s.value
            self.all_tolerances.append((st.kind, s))

    def visit_Finish(self, st: ast.Finish) -> None:
        self.finish.extend(st.settings)
        self.finish_relations.extend(st.relations)

    def visit_Translation(self, st: ast.Translation) -> None:
        """FST's translator settings (section 13): the driver is a METHOD."""
        if st.kind == "TRANSLATION_FSE":
            self.driver = (TRANSLATION_FSE_DRIVER, st.span)
        for item in st.items:
            meaning = TRANSLATION_KEYS.get(item.name, "?")
            if st.kind == "TRANSLATION_FSE":
                self.rep.error(f"TRANSLATION_FSE has no setting {item.name}", item.span,
                               "TRANSLATION_FSE takes no settings: it is the Euler driver")
            elif meaning == "?":
                self.rep.error(f"TRANSLATION_GENERAL has no setting {item.name}", item.span,
                               "TRANSLATION_GENERAL takes " + ", ".join(TRANSLATION_KEYS))
            elif meaning == "METHOD":
                driver = str(item.value).upper()
                if driver not in DRIVERS:
                    self.rep.error(f"unknown DRIVER '{item.value}'", item.span,
                                   "DRIVER is " + " or ".join(f"'{d}'" for d in DRIVERS))
                else:
                    self.driver = (driver, item.span)
            elif meaning is not None:
                if isinstance(item.value, str) or not item.value > 0:
                    self.rep.error(f"{item.name} must be a positive number", item.span)
                elif meaning == "RELERR":
                    self.tolerance["RELERR"] = float(item.value)
                else:
                    self.timer[meaning] = float(item.value)
                    self.timer_spans[meaning] = item.span

    def check_driver(self) -> None:
        """The METHOD a DRIVER means, or an error where METHOD says otherwise."""
        if self.driver is None:
            return
        name, span = self.driver
        method = DRIVERS[name][0]
        if self.method is None or self.method == self.driven:
            self.method = self.driven = method
        elif route_for(self.method) is not route_for(method):
            self.rep.error(f"METHOD {self.method} contradicts DRIVER = '{name}', which is "
                           f"METHOD {method}" + (" in step-point mode" if DRIVERS[name][1]
                                                else ""), span,
                           "remove one of them")

    def visit_Weather(self, st: ast.Weather) -> None:
        """WEATHER items, gathered over every WEATHER statement (FST splits them); the
        last one is where a run's weather is said to come from."""
        self.weather_span = st.span
        self.group.weather = True
        for item in st.items:
            if item.name not in WEATHER_KEYS:
                self.rep.error(f"WEATHER has no setting {item.name}", item.span,
                               "WEATHER takes " + ", ".join(WEATHER_KEYS))
            self.weather_items[item.name] = item

    def weather_spec(self) -> WeatherSpec | None:
        items = self.weather_items
        if not items:
            return None
        missing = [k for k in ("CNTR", "ISTN", "IYEAR") if k not in items]
        if missing:
            self.rep.error(f"WEATHER needs {', '.join(missing)}", self.weather_span,
                           "e.g. WEATHER CNTR = 'NLD'; ISTN = 1; IYEAR = 1990")
            return None
        for key, low, high in (("ISTN", 0, 1e9), ("IYEAR", 1, 9999)):
            value = items[key].value
            if isinstance(value, str) or not (low <= value <= high) or value != int(value):
                self.rep.error(f"{key} must be a whole number from {low} to {high:g}",
                               items[key].span)
                return None
        wtrdir = items.get("WTRDIR")
        return WeatherSpec(str(items["CNTR"].value).strip().upper(), int(items["ISTN"].value),
                           int(items["IYEAR"].value),
                           str(wtrdir.value) if wtrdir is not None else None,
                           self.weather_span)

    def visit_DefineCall(self, st: ast.DefineCall) -> None:
        pass  # a routine's interface: its CALL is what amilpy refuses

    def visit_Report(self, st: ast.Report) -> None:
        kind = "OUTPUT" if st.kind == "PRTPLT" else st.kind
        if st.x is not None and kind != "OUTPUT":
            self.rep.error(f"{st.kind} has no horizontal axis: VS {st.x} belongs to a figure",
                           st.x_span, f"write OUTPUT {', '.join(st.names)} VS {st.x}")
        # VS TIME is the default axis
        x = st.x if st.x != TIME and kind == "OUTPUT" else None
        target = self.group.reports if self.group.reports is not None else self.reports
        target.append(ir.Report(kind, st.names, None, st.span, st.kind == "PRTPLT", x))
        self.all_reports.append(st)

    def visit_Label(self, st: ast.Label) -> None:
        # the title of the latest OUTPUT figure; with none yet, a title
        target = self.group.reports if self.group.reports is not None else self.reports
        outs = [i for i, r in enumerate(target) if r.kind == "OUTPUT"]
        if outs:
            target[outs[-1]] = replace(target[outs[-1]], label=st.text)
        else:
            self.visit_Title(st)

    def visit_Title(self, st: ast.Title | ast.Label) -> None:
        (self.group.titles if self.group.titles is not None else self.titles).append(st.text)
